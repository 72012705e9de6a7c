//! Fit mu and the initial state to a recording by least squares on the hybrid model, and say
//! how far to trust it. The driver [`fit`] reads as its steps: check the data; measure each
//! marker's noise from the tracks and drop mis-tracked frames; fit the base model from starts
//! that cannot miss; let the data choose physics and camera nuisances (forward selection by
//! BIC); settle mu_static; then the uncertainty (Jacobian, block covariance, profile) and
//! the adequacy checks (chi-square against the measured noise, fits of the windows) that widen
//! the interval when the model does not describe the recording.
//!
//! The folder's files, the vocabulary first (no file imports one that imports it; the face,
//! this file, only lists the modules, re-exports what the fit offers and holds [`fit`]):
//! - `settings.rs`: how to fit ([`FitSettings`]); `estimate.rs`: an estimate and its interval,
//!   mu's error in parts, a rig value as measured; `outcome.rs`: what a fit found
//!   ([`FitReport`]) and its parts; `error.rs`: why a recording cannot be fitted;
//! - `implausible.rs`: a fitted value no real rig has, said as such;
//! - `rig_priors.rs`: the rig file's measurements and the nuisances' ranges set as priors;
//! - `checks.rs`: what was recorded, before fitting: the slider and the bob not swapped, their
//!   distance a rod's;
//! - `plausible.rs`: the rig file's rod length compared with the recording's markers;
//! - `prepare.rs`: the recording checked, each marker's noise, mis-tracked frames dropped;
//! - `priors.rs`: the rig file as a measurement, the nuisances' plausible ranges;
//! - `guess.rs`: starting values from the data;
//! - `base.rs`: the base model from several starts;
//! - `problem/`: the residual function and its exact normal equations;
//! - `lm.rs`, `solve.rs`: the Levenberg-Marquardt solver and the ways the fit runs it;
//! - `select/`: the nuisances chosen by the data (forward selection by BIC);
//! - `outliers.rs`: mis-tracked positions, from the tracks and from the residuals;
//! - `motion.rs`: what the fitted motion does at the frames;
//! - `stages.rs`: the stages of [`fit`] after the base model;
//! - `uncertainty.rs`: covariances, the windows and the profile interval;
//! - `intervals.rs`: intervals widened and cut at physical bounds;
//! - `adequacy.rs`: residual RMS, noise-free recordings and the adequacy sentence;
//! - `pendulum.rs`: the rigid pendulum the data found;
//! - `noise.rs`: each marker's noise from its track;
//! - `joint/`: many releases of one rig fitted together.

mod adequacy;
mod base;
pub mod checks;
mod error;
mod estimate;
pub mod guess;
mod implausible;
mod intervals;
pub mod joint;
pub mod law;
pub mod lm;
mod motion;
pub mod noise;
mod outcome;
mod outliers;
mod pendulum;
mod plausible;
mod prepare;
pub mod priors;
mod problem;
mod rig_priors;
mod select;
mod settings;
pub mod solve;
mod stages;
mod uncertainty;

pub use adequacy::{
    failed_tests, is_noise_free, FailedTest, FailedTests, LimitPart, RUNS_P, WINDOWS_P,
};
pub use checks::{check_frame_rate, check_recording, RecordingCheck};
pub use error::FitError;
pub use estimate::{Estimate, MuParts, RigValue};
pub use noise::NoiseEstimate;
pub use outcome::{Adequacy, FitReport, StartOutcome, StaticResult, Work};
pub use pendulum::{PendulumFound, ValueSe};
pub use plausible::{
    check_masses, check_rod_length, check_tilt, MASS_MAX_KG, ROD_LENGTH_TOLERANCE,
};
pub use problem::{Counters, Observations, Param, TrajectoryProblem, MAX_FREE};
pub use select::{ModelRow, Nuisance};
pub use settings::{FitSettings, Loss, StaticMode, PREFIX_FRAMES};
pub use uncertainty::{WindowCut, WindowFit};

use crate::model::Rig;
use outliers::residual_outliers;

/// Fit the free parameters to `obs` starting from `rig_guess` (its mu values are guesses):
/// the data prepared ([`prepare`]), the base model ([`base`]), then the stages of [`stages`], in
/// order.
pub fn fit(
    obs: Observations,
    rig_guess: &Rig<f64>,
    settings: &FitSettings,
) -> Result<FitReport, FitError> {
    let data = prepare::prepare(obs, settings)?;
    let mut warnings: Vec<String> = settings
        .measured
        .iter()
        .flat_map(|m| m.notes.clone())
        .collect();
    let started = guess::start_from_markers(&data.obs, rig_guess, settings.measured.as_ref());
    let rig_guess = &started;
    let base = base::fit(
        &data.obs,
        rig_guess,
        data.sigma,
        data.frame,
        settings,
        &mut warnings,
    )?;
    let mut f = stages::Fitting {
        problem: base.problem.clone(),
        p: base.p.clone(),
        iterations: base.iterations,
        warnings,
        moved: false,
    };
    stages::measured_rig(&mut f, data.frame, settings);
    let late = residual_outliers(&mut f.problem, &mut f.p, settings, &mut f.iterations, false);
    let seen = stages::seen(&f, &data.obs)?;
    let (models, nuisances, screening) =
        stages::nuisances(&mut f, &seen, &base, data.n_frames, settings);
    let (outliers, late) = stages::late_outliers(&mut f, late, data.dropped, settings);
    if !seen.slides {
        stages::hold_stuck(&mut f, seen.raw_moves, settings);
    }
    let static_state = stages::static_bound(&mut f, seen.slides);
    let slides = seen.slides;
    let motion = if f.moved {
        motion::motion(&f.problem)?
    } else {
        seen.motion
    };
    let settled = base.settled.clone().filter(|_| late.dropped == [0, 0]);
    let stop_reason = stages::polish(&mut f, settled, settings);
    let mut est = stages::estimates(&mut f, data.noise_dof, slides)?;
    let case = stages::static_case(&f, static_state, slides, &motion, &base);
    // mu_kinetic's profile, the windows and mu_static's one-sided profile only read the fit
    // and its covariances: side by side (each profile's search is sequential).
    let ((profile, windows), upper) = rayon::join(
        || {
            rayon::join(
                || stages::mu_profile(&f, &est, settings),
                || stages::windows(&f.problem, est.mu_index, &motion.sol.events, settings),
            )
        },
        || stages::upper_limit(&case, &f, &est, &data.obs, settings),
    );
    stages::mu_profile_taken(&mut f, &mut est, profile);
    let verdict = stages::adequacy(&mut f, &mut est, &models, windows, settings);
    let mu_static = stages::mu_static(&mut f, &mut est, case, &motion, &data.obs, settings, upper);
    stages::starts_agree(&mut f, &base, &est);
    let identifiable = slides;
    let not_identifiable = (!slides && seen.raw_moves.is_none())
        .then(|| checks::never_slides(&data.obs, data.sigma[0], &mu_static));
    let mut report = stages::report(
        f,
        stages::Parts {
            data,
            base,
            rig_guess,
            settings,
            est,
            verdict,
            models,
            nuisances,
            screening,
            outliers,
            motion,
            mu_static,
            identifiable,
            stop_reason,
        },
    );
    report.not_identifiable = not_identifiable;
    Ok(report)
}

/// What the fit's unit tests share.
#[cfg(test)]
pub(crate) mod test_support {
    use super::problem::{Observations, Param, TrajectoryProblem};
    use crate::data::synth::{synthesize, SynthOptions};
    use crate::scene::Scene;
    use std::sync::Arc;

    /// The paper scene (`configs/paper_rest_horizontal.toml`, mu = 0.35) recorded for 1.5 s at
    /// 200 frames/s with 0.5 mm of noise (`seed`), as a problem with mu and the initial state
    /// free, weighted by that noise.
    pub(crate) fn paper_problem(seed: u64) -> TrajectoryProblem {
        paper_problem_on(seed, |rig| rig)
    }

    /// [`paper_problem`] recorded on the paper's rig changed by `rig` (a friction law, say),
    /// the problem on the paper's own rig (Coulomb's law).
    pub(crate) fn paper_problem_on(
        seed: u64,
        rig: impl Fn(crate::model::Rig<f64>) -> crate::model::Rig<f64>,
    ) -> TrajectoryProblem {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("configs/paper_rest_horizontal.toml");
        let mut scene = Scene::from_toml(&std::fs::read_to_string(&path).unwrap(), &path).unwrap();
        let paper_rig = scene.rig;
        scene.rig = rig(scene.rig);
        let syn = synthesize(
            &scene,
            &SynthOptions {
                fps: 200.0,
                duration: Some(1.5),
                noise: 5e-4,
                seed,
                ..SynthOptions::default()
            },
        )
        .unwrap();
        let obs = Arc::new(Observations::from(&syn.recording));
        let free = vec![Param::MuKinetic, Param::X, Param::Theta, Param::ThetaDot];
        let options = super::FitSettings::default().options;
        let mut problem = TrajectoryProblem::new(obs, paper_rig, scene.initial, free, options);
        problem.sigma = [5e-4, 5e-4];
        problem
    }
}
