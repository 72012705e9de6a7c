//! What a fit found ([`FitReport`]) and its parts: mu_static's verdict, the starts, the
//! adequacy against the noise and the work done.

use super::adequacy::LimitPart;
use super::estimate::{Estimate, MuParts, RigValue};
use super::law;
use super::noise::NoiseEstimate;
use super::pendulum::PendulumFound;
use super::problem::{Param, TrajectoryProblem};
use super::select::{ModelRow, Nuisance};
use super::uncertainty::{WindowCut, WindowFit};
use crate::model::{Camera, Rig, State};
use crate::sim::Event;
use nalgebra::DMatrix;

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
    /// Why the result is limited by the model (empty when it is not), worded by the report
    /// as one plain sentence (`report::fit::limited_sentence`).
    #[serde(skip)]
    pub limited_by_model: Vec<LimitPart>,
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
    /// The rig file's measured keys: key, value, standard deviation, where it came from
    /// (`"stated"`, `"default"` or `"--latitude"`).
    pub rig_keys: Vec<(&'static str, f64, f64, &'static str)>,
    /// The rig values fitted as measurements.
    pub rig_values: Vec<RigValue>,
    /// The chosen model's values no real rig has, a sentence each (the fit is then flagged).
    pub implausible: Vec<String>,
    /// The friction law the data chose, every law's evidence and the law's parameters
    /// (`None` when the recording never slides).
    pub friction: Option<law::FrictionLawResult>,
}
