//! Fit mu and the initial state to a recording by least squares on the hybrid model, and say
//! how far to trust it. The driver [`fit`] reads as its steps: check the data; measure each
//! marker's noise from the tracks and drop mis-tracked frames; fit the base model from starts
//! that cannot miss; let the data choose physics and camera nuisances (forward selection by
//! BIC); settle mu_static; then the uncertainty (Jacobian, block covariance, profile) and
//! the adequacy checks (chi-square against the measured noise, fits of the windows) that widen
//! the interval when the model does not describe the recording.
//!
//! The folder's files:
//! - `mod.rs`: the settings, the report's types and the driver [`fit`];
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
pub mod guess;
mod intervals;
pub mod joint;
pub mod law;
pub mod lm;
mod motion;
pub mod noise;
mod outliers;
mod pendulum;
mod plausible;
mod prepare;
pub mod priors;
mod problem;
mod select;
pub mod solve;
mod stages;
mod uncertainty;

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

pub use adequacy::{failed_tests, is_noise_free, FailedTest, RUNS_P, WINDOWS_P};
pub use checks::{check_recording, RecordingCheck};
pub use noise::NoiseEstimate;
pub use pendulum::{PendulumFound, ValueSe};
pub use plausible::{check_rod_length, ROD_LENGTH_TOLERANCE};
pub use problem::{Counters, Observations, Param, TrajectoryProblem, MAX_FREE};
pub use select::{ModelRow, Nuisance};
pub use uncertainty::{WindowCut, WindowFit};

use crate::model::{Camera, FrictionLaw, Rig, State};
use crate::sim::{Event, Options};
use nalgebra::DMatrix;
use outliers::residual_outliers;
use thiserror::Error;

/// Loss applied to the standardised residuals.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Loss {
    /// Plain least squares (mis-tracked frames are dropped before the fit and after it).
    #[default]
    Squares,
    /// Huber loss with threshold k (in noise standard deviations): mis-tracked frames count
    /// linearly, not quadratically.
    Huber(f64),
    /// Cauchy loss with scale k: outliers are down-weighted further.
    Cauchy(f64),
}

/// Whether mu_static is estimated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum StaticMode {
    /// A candidate model when the recording shows a stick-to-slide onset; the data choose.
    #[default]
    Auto,
    /// Always equal to mu_kinetic.
    Tied,
    /// Fixed at the rig's value.
    Fixed,
}

/// How to fit.
#[derive(Debug, Clone, PartialEq)]
pub struct FitSettings {
    /// Also estimate the rod length.
    pub fit_rod_length: bool,
    /// Treatment of mu_static.
    pub mu_static: StaticMode,
    /// Loss on standardised residuals.
    pub loss: Loss,
    /// Extra starting values of mu_kinetic (besides the data's, the rig's and a low one).
    pub extra_starts: Vec<f64>,
    /// Compute the profile-likelihood interval for mu_kinetic.
    pub profile: bool,
    /// Integrator settings for predictions.
    pub options: Options,
    /// Most Levenberg-Marquardt iterations per fit.
    pub max_iters: u64,
    /// Iterations a start of a candidate model gets before those far behind the round's best
    /// are left where they stopped (0: every candidate fitted to the end, the laws too, with
    /// no out-of-reach stop; see the selection).
    pub first_iters: u64,
    /// Known noise per marker (slider, bob), m; `None`: measured from the tracks.
    pub noise: Option<[f64; 2]>,
    /// Let the data add physics and camera nuisances (tilt, damping, friction laws, scale,
    /// marker offsets, lag); off: the plain model only (faster).
    pub nuisances: bool,
    /// Fit the recording's windows (cut by the motion, a slide each) and widen the interval
    /// when they disagree.
    pub windows: bool,
    /// Nuisances put in the model whatever the data say (a rail known to be tilted); the
    /// selection adds others on top.
    pub with: Vec<Nuisance>,
    /// The friction law the user forces (`--friction LAW`): the other laws are not offered.
    /// `None`: the data choose among Coulomb's, static above kinetic, Stribeck's, the
    /// direction and the load law.
    pub friction: Option<FrictionLaw>,
    /// A recording with more than twice this many frames is long: its starts and candidate
    /// models are fitted on these first frames and the winner carried over the rest by
    /// doubling the length; its profile intervals are checked at the Wald ends first.
    pub long_prefix: usize,
    /// The rig file as a measurement: its rod length and mass ratio are fitted with these
    /// priors (errors in variables). `None`: the rig is taken as exact.
    pub measured: Option<priors::RigMeasurement>,
    /// The camera scale set from a length the lab measured (`--rod-length`, a ruler in view),
    /// as the relative standard deviation of that measurement: the camera scale is then
    /// fitted with this prior, so the ruler's millimetre reaches mu's interval. `None`: the
    /// scale is taken as the file or `--scale` gives it.
    pub scale_sd: Option<f64>,
}

impl FitSettings {
    /// The nuisances forced: `--with`'s, the law of `--friction`, and the camera scale when
    /// it was set from a measured length ([`FitSettings::scale_sd`]).
    pub fn forced(&self) -> Vec<Nuisance> {
        let mut forced = self.with.clone();
        if self.scale_sd.is_some() && !forced.contains(&Nuisance::CameraScale) {
            forced.push(Nuisance::CameraScale);
        }
        if let Some(nu) = self
            .friction
            .and_then(|law| Nuisance::ALL.into_iter().find(|n| n.law() == Some(law)))
        {
            if !forced.contains(&nu) {
                forced.push(nu);
            }
        }
        forced
    }

    /// The nuisances never offered: with `--friction`, every other law.
    pub fn excluded(&self) -> Vec<Nuisance> {
        match self.friction {
            None => Vec::new(),
            Some(law) => Nuisance::ALL
                .into_iter()
                .filter(|n| n.law().is_some_and(|l| l != law))
                .collect(),
        }
    }
}

impl Default for FitSettings {
    fn default() -> Self {
        FitSettings {
            fit_rod_length: false,
            mu_static: StaticMode::Auto,
            loss: Loss::Squares,
            extra_starts: Vec::new(),
            profile: true,
            options: Options {
                rtol: 1e-9,
                atol: 1e-11,
                ..Options::default()
            },
            max_iters: 60,
            first_iters: 15,
            noise: None,
            nuisances: true,
            windows: true,
            with: Vec::new(),
            friction: None,
            long_prefix: PREFIX_FRAMES,
            measured: None,
            scale_sd: None,
        }
    }
}

/// An estimated parameter.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Estimate {
    /// Best-fit value.
    pub value: f64,
    /// Standard error: from the Jacobian scaled by max(1, reduced chi-square), or from the
    /// block covariance when that is larger.
    pub stderr: f64,
    /// 95% interval (how it was computed: [`Estimate::interval`]).
    pub ci95: [f64; 2],
    /// How the interval was computed: `profile`, `wald` (value +- 1.96 stderr), with
    /// `+block` when widened for correlated residuals and `+windows` when widened to cover
    /// the windows' values, and `+models` when it carries the spread of close models.
    pub interval: &'static str,
}

impl Estimate {
    /// A Wald estimate: `value` +- 1.96 `stderr`.
    pub fn wald(value: f64, stderr: f64) -> Estimate {
        Estimate {
            value,
            stderr,
            ci95: [value - 1.96 * stderr, value + 1.96 * stderr],
            interval: "wald",
        }
    }
}

/// mu_kinetic's standard error in its parts, each a standard deviation; the total is their
/// root sum of squares (the reported standard error).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct MuParts {
    /// From the recording's noise, the rig's measured values held (its correlation in time
    /// included).
    pub noise: f64,
    /// From the rig file's measurement errors the recording cannot correct.
    pub rig: f64,
    /// From the model: the spread of adequate and close models, the windows, the path.
    pub model: f64,
    /// The whole standard error.
    pub total: f64,
}

/// A rig value the fit took as a measurement: what the file says and what the fit found.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct RigValue {
    /// The parameter (`rod_length`, `equivalent_mass_ratio`).
    pub param: &'static str,
    /// The rig file's value.
    pub file: f64,
    /// Its standard deviation (stated, or the default).
    pub sd: f64,
    /// The fitted value.
    pub value: f64,
    /// Its standard error.
    pub stderr: f64,
    /// (value - file) / sd: how far the recording moved it, in the file's deviations.
    pub z: f64,
}

impl RigValue {
    /// The rig file's measured values among fitted `params` (the rod length and the mass
    /// ratio), `prior_on` giving the file's prior on each.
    pub(crate) fn of<'a>(
        params: &[(Param, Estimate)],
        prior_on: impl Fn(Param) -> Option<&'a priors::Prior>,
    ) -> Vec<RigValue> {
        params
            .iter()
            .filter(|(q, _)| q.is_measured())
            .filter_map(|(q, e)| {
                let pr = prior_on(*q)?;
                Some(RigValue {
                    param: q.name(),
                    file: pr.centre,
                    sd: pr.sd,
                    value: e.value,
                    stderr: e.stderr,
                    z: (e.value - pr.centre) / pr.sd,
                })
            })
            .collect()
    }

    /// Whether the data moved it beyond 3 of the file's deviations: worth a warning.
    pub(crate) fn off(&self) -> bool {
        self.z.abs() > 3.0
    }

    /// What `who` ("the recording puts") says of it, for warnings.
    pub(crate) fn said(&self, who: &str) -> String {
        format!(
            "{who} {} at {:.6} +- {:.1e}, {:.1} of the rig file's deviations from its {:.6} +- {:.1e}",
            self.param, self.value, self.stderr, self.z, self.file, self.sd
        )
    }
}

/// What the recording says about mu_static.
#[derive(Debug, Clone, PartialEq)]
pub enum StaticResult {
    /// Estimated from a stick-to-slide onset.
    Estimated(Estimate),
    /// The slider stayed stuck: mu_static is at least the largest friction ratio |F|/|N|
    /// needed along the fit.
    LowerBound(f64),
    /// The recording shows no onset of slip after a stick: it says nothing about mu_static
    /// (it was tied to mu_kinetic for the fit).
    NotIdentifiable,
}

/// One start of the multi-start search.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct StartOutcome {
    /// mu_kinetic at the start.
    pub mu_start: f64,
    /// mu_kinetic where it converged.
    pub mu_end: f64,
    /// Final cost: 1/2 sum of squared standardised residuals.
    pub cost: f64,
}

/// Goodness of fit against the noise measured independently of the model.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Adequacy {
    /// Sum of squared residuals standardised by the measured noise.
    pub chi2: f64,
    /// Residual rows used minus free parameters.
    pub dof: f64,
    /// chi2 / dof.
    pub reduced_chi2: f64,
    /// Probability of so large a chi-square if model and noise were right (F test, since the
    /// noise is itself measured).
    pub p_value: f64,
    /// Akaike's criterion chi2 + 2k.
    pub aic: f64,
    /// Bayesian information criterion chi2 + k ln(n).
    pub bic: f64,
    /// Lag-1 autocorrelation of the residuals (0 for white noise).
    pub lag1: f64,
    /// Block standard error of mu_kinetic over the Jacobian's.
    pub block_se_ratio: f64,
    /// Frames per block of the block covariance.
    pub block_frames: usize,
    /// One-sided p-value of the runs test on the residuals' signs (small: long runs, a smooth
    /// misfit even below the chi-square's threshold).
    pub runs_p_value: f64,
    /// p-value of the windows' agreement (`None` with fewer than two sliding windows).
    pub windows_p_value: Option<f64>,
    /// One plain sentence when the result is limited by the model; `None` when it is not.
    pub limited_by_model: Option<String>,
    /// The recording is noise-free to the model's numerical accuracy ([`is_noise_free`]):
    /// mu is recovered to rounding, the intervals are not meaningful, and no adequacy test
    /// (all of which compare the residuals with the noise) applies.
    pub noise_free: bool,
}

/// The work a fit did.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Work {
    /// Levenberg-Marquardt iterations, every fit included.
    pub iterations: u64,
    /// Residual evaluations (simulations in f64).
    pub residual_evals: u64,
    /// Jacobian evaluations (simulations in dual numbers).
    pub jacobian_evals: u64,
}

/// The result of a fit.
#[derive(Debug, Clone)]
pub struct FitReport {
    /// Every free parameter with its estimate.
    pub params: Vec<(Param, Estimate)>,
    /// Start value of each free parameter.
    pub start_values: Vec<(Param, f64)>,
    /// Parameters held fixed, with their values.
    pub fixed: Vec<(Param, f64)>,
    /// mu_kinetic, or `None` when the recording never slides (not identifiable).
    pub mu_kinetic: Option<Estimate>,
    /// mu_static.
    pub mu_static: StaticResult,
    /// Fitted rig (fixed values kept).
    pub rig: Rig<f64>,
    /// Fitted initial state.
    pub initial: State<f64>,
    /// Fitted camera and marker model (the ideal camera unless the data chose otherwise).
    pub camera: Camera<f64>,
    /// Correlation matrix of the free parameters (order of `params`).
    pub correlation: DMatrix<f64>,
    /// RMS residual over all coordinates (m).
    pub rms_residual_m: f64,
    /// RMS residual per marker (slider, bob) (m).
    pub rms_per_marker_m: [f64; 2],
    /// Noise per marker used as weights (m).
    pub noise_m: [f64; 2],
    /// The noise measurement per marker (`None` where it could not be measured).
    pub noise: [Option<NoiseEstimate>; 2],
    /// Goodness of fit and whether the model limits the result.
    pub adequacy: Adequacy,
    /// Same as `adequacy.reduced_chi2` (kept for readers of earlier reports).
    pub reduced_chi2: f64,
    /// Same as `adequacy.lag1`.
    pub residual_autocorrelation: f64,
    /// Candidate models compared, the chosen one marked.
    pub models: Vec<ModelRow>,
    /// Nuisances in the chosen model.
    pub nuisances: Vec<Nuisance>,
    /// mu_kinetic fitted on each window of the recording (cut by the motion).
    pub windows: Vec<WindowFit>,
    /// How the windows were cut: a slide each, a slide or more, or the thirds (`None` when
    /// no window was fitted).
    pub window_cut: Option<WindowCut>,
    /// Mis-tracked positions dropped (slider, bob): before the fit from the tracks, and
    /// after it from the residuals.
    pub outliers: [usize; 2],
    /// Sliding speeds behind mu_kinetic, m/s: the smallest and largest |x'| of the fitted
    /// slides at frame times.
    pub sliding_speed_range: Option<[f64; 2]>,
    /// Events of the fitted motion.
    pub events: Vec<Event>,
    /// Whether mu_kinetic is identifiable from the recording.
    pub identifiable: bool,
    /// Multi-start outcomes.
    pub starts: Vec<StartOutcome>,
    /// Residual rows used.
    pub n_residuals: usize,
    /// Frames in the recording.
    pub n_frames: usize,
    /// What the fit cost.
    pub work: Work,
    /// Why the last solve stopped.
    pub stop_reason: String,
    /// Notes on identifiability and warnings on the fit's quality.
    pub warnings: Vec<String>,
    /// The rigid pendulum the data found, when the `rigid_pendulum` nuisance was chosen.
    pub pendulum: Option<PendulumFound>,
    /// Why the fit failed although it ran (mu_kinetic pinned at zero with the friction
    /// carried by another term): the value is then not a friction coefficient.
    pub failed: Option<String>,
    /// Why mu was not measured although the fit ran: the slider never moves beyond its noise
    /// (one plain sentence, with the lower bound on mu_static the stuck motion needs).
    pub not_identifiable: Option<String>,
    /// The chosen model at its optimum, with its noise scales and row weights (outliers at
    /// zero): what a fit built on this one (the joint fit) starts from.
    pub problem: TrajectoryProblem,
    /// mu_kinetic's standard error in parts (noise, rig, model).
    pub mu_parts: Option<MuParts>,
    /// The rig file's measured keys: key, value, standard deviation, whether the file stated
    /// it (`false`: the default).
    pub rig_keys: Vec<(&'static str, f64, f64, bool)>,
    /// The rig values fitted as measurements.
    pub rig_values: Vec<RigValue>,
    /// The chosen model's values no real rig has, a sentence each (the fit is then flagged).
    pub implausible: Vec<String>,
    /// The friction law the data chose, every law's evidence and the law's parameters
    /// (`None` when the recording never slides).
    pub friction: Option<law::FrictionLawResult>,
}

/// A recording that cannot be fitted.
#[derive(Debug, Error)]
pub enum FitError {
    /// Too little data.
    #[error("too few frames with both markers ({0}); need at least 10")]
    TooFewFrames(usize),
    /// No start produced a usable model prediction.
    #[error("no start could be fitted: {0}")]
    NoStart(String),
    /// A setting out of range.
    #[error("{0}")]
    Settings(String),
    /// The mis-tracked filter dropped so many positions that too few frames with both
    /// markers are left: the sentence says how many, against which noise, and the fix.
    #[error("{0}")]
    AllDropped(String),
    /// Neither marker moves beyond its noise: nothing in the recording shows mu.
    #[error("{0}")]
    NoMotion(String),
}

/// The default [`FitSettings::long_prefix`]: frames a long recording's starts and candidate
/// models are fitted on (recordings up to twice this are fitted whole from every start).
pub const PREFIX_FRAMES: usize = 8000;

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
    let started = priors::start_from_markers(&data.obs, rig_guess, settings.measured.as_ref());
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
    let mut est = stages::estimates(&f, data.noise_dof, slides)?;
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
