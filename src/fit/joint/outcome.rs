//! What a joint fit found ([`JointReport`]) and each release's row of its table
//! ([`ReleaseRow`]).

use crate::fit::estimate::Estimate;
use crate::fit::problem::{Param, TrajectoryProblem};
use crate::fit::select::{ModelRow, Nuisance};
use nalgebra::DMatrix;
use serde::Serialize;

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

impl ReleaseRow {
    /// Chi-square per residual row under the model the row is of.
    pub fn chi2_per_residual(&self) -> f64 {
        self.chi2 / self.n_residuals.max(1) as f64
    }
}

/// The result of a joint fit. Its values are those of the releases kept: a release set aside
/// is listed apart ([`JointReport::set_aside`]) with its own values and the evidence.
#[derive(Debug, Clone)]
pub struct JointReport {
    /// mu_kinetic of the rail from the releases kept, with its interval.
    pub mu_kinetic: Estimate,
    /// Why the result is no measurement (`None` when it is one): a joint interval wider than
    /// a single release's, or mu at its bound 0. The values are then not an answer.
    pub failed: Option<String>,
    /// Every shared parameter with its estimate (mu_kinetic first).
    pub shared: Vec<(Param, Estimate)>,
    /// Covariance of the shared parameters (the releases' own parameters marginalised):
    /// its inverse is what the releases know of them.
    pub shared_covariance: DMatrix<f64>,
    /// The releases kept (those the result is of).
    pub releases: Vec<ReleaseRow>,
    /// The releases set aside: each one's own mu and z under the kept releases' model (a
    /// model chosen without it), more than 3 standard errors off.
    pub set_aside: Vec<ReleaseRow>,
    /// Releases that failed and were left out (name, why), with `keep_going`.
    pub left_out: Vec<(String, String)>,
    /// p-value of the kept releases' own mu agreeing (chi-square of their spread), with two
    /// or more releases.
    pub consistency_p: Option<f64>,
    /// p-value of every release's own mu agreeing under the model chosen on all of them.
    pub consistency_p_all: Option<f64>,
    /// The releases set aside, by name.
    pub disagreeing: Vec<String>,
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
    /// The releases disagree and no few of them, set aside, leave releases that agree: the
    /// interval is widened by their spread (`report::joint::agreement_sentence` says so).
    pub unresolved: bool,
    /// Warnings.
    pub warnings: Vec<String>,
    /// Levenberg-Marquardt iterations of the joint stages (the single fits not counted).
    pub iterations: u64,
    /// The friction law the releases share, its parameters and every law's evidence.
    pub friction: crate::fit::law::FrictionLawResult,
    /// Each release's problem at the joint optimum, in the order of `releases`: what the
    /// friction figure cuts into slides.
    pub parts: Vec<TrajectoryProblem>,
    /// The joint model's values no real rig has (a tilt on a levelled rail, ...), a sentence
    /// each: the result is then limited by the model, as a single fit's would be.
    pub implausible: Vec<String>,
    /// The rig file's measured keys: key, value, standard deviation, where it came from
    /// (`"stated"`, `"default"` or `"--latitude"`), as a single fit's report lists them.
    pub rig_keys: Vec<(&'static str, f64, f64, &'static str)>,
}
