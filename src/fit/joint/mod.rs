//! One rig, many releases: the releases fitted together. The rail and the pendulum are the
//! same in every release, so the friction law, the tilt, the viscous terms and the pendulum's
//! build are shared; each release keeps its initial state and marker lag, and its camera
//! unless the camera is the same. The releases' problems are the single fit's
//! ([`TrajectoryProblem`]); the joint problem sums their normal equations into the shared and
//! per-release blocks, so its cost grows linearly with the releases, and its nuisances are
//! chosen by the single fit's selection ([`select::forward`] over [`Candidate`]).
//!
//! The folder's files, in the order [`fit_joint`] runs them: `rigs.rs` releases of another
//! rig; `singles.rs` the single fits and the joint start; `problem.rs` the joint problem;
//! `model.rs` the joint model (its fit, nuisances and polish); `shared.rs` the shared
//! parameters' covariance; `releases.rs` each release under the joint model; `agreement.rs`
//! the releases' own mu and their agreement; `set_aside.rs` the releases that disagree; this
//! file the joint fit's settings, report and driver.

mod agreement;
mod model;
mod problem;
mod releases;
mod rigs;
mod set_aside;
mod shared;
mod singles;

pub use problem::JointProblem;
pub use rigs::other_rigs;

use super::intervals::model_uncertainty;
use super::problem::{Observations, Param};
use super::select::{self, ModelRow, Nuisance};
use super::{Estimate, FitError, FitSettings};
use crate::model::Rig;
use nalgebra::DMatrix;
use serde::Serialize;

/// One release of a joint fit: its name and its tracks.
#[derive(Debug, Clone)]
pub struct Release {
    /// The recording's name (its file, for messages and the table).
    pub name: String,
    /// Its tracks.
    pub obs: Observations,
}

/// Settings of a joint fit beyond the single fit's.
#[derive(Debug, Clone, Default)]
pub struct JointSettings {
    /// One camera for every release: its scale and marker offsets shared.
    pub same_camera: bool,
    /// Fit the other releases when one fails (it is named); otherwise a failure ends the fit.
    pub keep_going: bool,
}

/// A release in the joint fit's table.
#[derive(Debug, Clone, Serialize)]
pub struct ReleaseRow {
    /// The recording's name.
    pub name: String,
    /// Frames with a marker.
    pub frames: usize,
    /// Mode transitions of the joint model in this release.
    pub transitions: usize,
    /// mu_kinetic of this release alone, with the shared nuisances held at the joint values.
    pub own_mu: Option<Estimate>,
    /// mu_kinetic of the release's single fit (its own nuisances, chosen from it alone).
    pub single_mu: Option<Estimate>,
    /// Nuisances its single fit chose.
    pub single_nuisances: Vec<&'static str>,
    /// RMS residual under the joint model (m).
    pub rms_residual_m: f64,
    /// Chi-square of its residuals under the joint model.
    pub chi2: f64,
    /// Its residual rows.
    pub n_residuals: usize,
    /// (own mu - the others' joint mu) / combined standard error.
    pub z: f64,
    /// Whether its own mu agrees with the other releases' (|z| below 3, or the releases agree).
    pub agrees: bool,
}

/// The result of a joint fit.
#[derive(Debug, Clone)]
pub struct JointReport {
    /// mu_kinetic of the rail, with its interval.
    pub mu_kinetic: Estimate,
    /// Every shared parameter with its estimate (mu_kinetic first).
    pub shared: Vec<(Param, Estimate)>,
    /// Covariance of the shared parameters (the releases' own parameters marginalised):
    /// its inverse is what the releases know of them.
    pub shared_covariance: DMatrix<f64>,
    /// The releases.
    pub releases: Vec<ReleaseRow>,
    /// Releases that failed and were left out (name, why), with `keep_going`.
    pub left_out: Vec<(String, String)>,
    /// p-value of the releases' own mu agreeing (chi-square of their spread), with two or
    /// more releases.
    pub consistency_p: Option<f64>,
    /// The releases whose own mu disagrees with the others'.
    pub disagreeing: Vec<String>,
    /// mu_kinetic of the other releases fitted jointly without those (Wald interval).
    pub mu_without_disagreeing: Option<Estimate>,
    /// Nuisances in the joint model.
    pub nuisances: Vec<Nuisance>,
    /// Every joint model compared.
    pub models: Vec<ModelRow>,
    /// Chi-square of the joint model.
    pub chi2: f64,
    /// Residual rows minus free parameters.
    pub dof: f64,
    /// chi2 / dof.
    pub reduced_chi2: f64,
    /// Free parameters in all.
    pub n_params: usize,
    /// One plain sentence on what the interval holds.
    pub sentence: String,
    /// Warnings.
    pub warnings: Vec<String>,
    /// Levenberg-Marquardt iterations of the joint stages (the single fits not counted).
    pub iterations: u64,
    /// The friction law the releases share, its parameters and every law's evidence.
    pub friction: crate::fit::law::FrictionLawResult,
    /// Each release's problem at the joint optimum, in the order of `releases`: what the
    /// friction figure cuts into slides.
    pub parts: Vec<crate::fit::TrajectoryProblem>,
    /// The joint model's values no real rig has (a tilt on a levelled rail, ...), a sentence
    /// each: the result is then limited by the model, as a single fit's would be.
    pub implausible: Vec<String>,
}

/// Why a joint fit could not run.
#[derive(Debug, thiserror::Error)]
pub enum JointError {
    /// Fewer than two releases to fit.
    #[error("a joint fit needs two or more recordings, got {0}")]
    TooFew(usize),
    /// Releases of different rigs.
    #[error("{0}")]
    OtherRig(String),
    /// A release's own fit failed.
    #[error("{name}: {error}")]
    Release {
        /// The release.
        name: String,
        /// Its failure.
        error: FitError,
    },
    /// The joint fit failed.
    #[error("the joint fit failed: {0}")]
    Joint(String),
}

/// Fit the releases jointly: each alone first (its start, noise, outliers and own mu), then
/// all together with the shared parameters tied, the nuisances chosen by the data, and the
/// releases' agreement tested.
pub fn fit_joint(
    releases: &[Release],
    rig_guess: &Rig<f64>,
    settings: &FitSettings,
    joint: &JointSettings,
) -> Result<JointReport, JointError> {
    singles::check_releases(releases)?;
    let singles::Singles {
        kept,
        left_out,
        mut warnings,
    } = singles::fit_singles(releases, rig_guess, settings, joint)?;
    let start = singles::start(&kept, rig_guess, settings, joint);
    let model = model::fit_model(start, &kept, settings)?;
    let mut shared = shared::shared_fit(&model.problem, &model.p, &kept)?;
    let mut rows = releases::release_rows(&model.problem, &kept, settings);
    let mut mu = shared.estimates[shared.mu_index].1;
    model_uncertainty(
        &mut mu,
        &model.models,
        shared.reduced_chi2.max(1.0),
        &mut warnings,
    );
    let agreed = agreement::agreement(&model.problem, &mut rows, &mut mu, settings);
    if select::misfits(&model.problem, shared.chi2) {
        warnings.push(format!(
            "the joint model misfits the releases (reduced chi-square {:.2}): the interval is the Jacobian's scaled by it",
            shared.reduced_chi2
        ));
    }
    let mu = shared::carry_mu(&mut shared, mu);
    // The shared parameters' correlation from their covariance, for the law's section.
    let k = shared.estimates.len();
    let correlation = DMatrix::from_fn(k, k, |i, j| {
        let d = (shared.covariance[(i, i)] * shared.covariance[(j, j)]).sqrt();
        if d > 0.0 {
            shared.covariance[(i, j)] / d
        } else {
            f64::from(u8::from(i == j))
        }
    });
    let friction = crate::fit::law::friction_law(&crate::fit::law::LawInputs {
        params: &shared.estimates,
        correlation: &correlation,
        models: &model.models,
        chosen: &model.nuisances,
        screening: &[],
        n_rows: 0,
        forced: settings.friction.is_some(),
    });
    // A shared value (a tilt) is the same in every release: each sentence once.
    let mut implausible: Vec<String> = Vec::new();
    for part in &model.problem.parts {
        for sentence in crate::fit::priors::implausible(part) {
            if !implausible.contains(&sentence) {
                implausible.push(sentence);
            }
        }
    }
    for sentence in &implausible {
        warnings.push(format!(
            "the joint model needs what no real rig has, so the result is limited by the model: {sentence}"
        ));
    }
    Ok(JointReport {
        implausible,
        parts: model.problem.parts.clone(),
        friction,
        mu_kinetic: mu,
        shared: shared.estimates,
        shared_covariance: shared.covariance,
        releases: rows,
        left_out,
        consistency_p: agreed.consistency_p,
        disagreeing: agreed.disagreeing,
        mu_without_disagreeing: agreed.others,
        nuisances: model.nuisances,
        models: model.models,
        chi2: shared.chi2,
        dof: shared.dof,
        reduced_chi2: shared.reduced_chi2,
        n_params: model.p.len(),
        sentence: agreed.sentence,
        warnings,
        iterations: model.iterations,
    })
}
