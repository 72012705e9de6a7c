//! Fit mu and the initial state to a recording by least squares on the hybrid model, and say
//! how far to trust it. The driver [`fit`] reads as its steps: check the data; measure each
//! marker's noise from the tracks and drop mis-tracked frames; fit the base model from starts
//! that cannot miss; let the data choose physics and camera nuisances (forward selection by
//! BIC); settle mu_static; then the uncertainty (Jacobian, block covariance, profile) and
//! the adequacy checks (chi-square against the measured noise, fits of the windows) that widen
//! the interval when the model does not describe the recording.

mod base;
pub mod guess;
pub mod joint;
pub mod lm;
pub mod noise;
mod outliers;
mod problem;
mod select;
mod stages;
mod uncertainty;

pub use noise::NoiseEstimate;
pub use problem::{Counters, Observations, Param, TrajectoryProblem, MAX_FREE};
pub use select::{ModelRow, Nuisance};
pub use uncertainty::WindowFit;

use crate::model::{Camera, Mode, Rig, Shorthands, State};
use crate::sim::{simulate_each, Event, Options, Request, Sample, Solution};
use argmin::core::{Executor, State as _};
use lm::LevenbergMarquardt;
use nalgebra::{DMatrix, DVector};
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
    /// A recording with more than twice this many frames is long: its starts and candidate
    /// models are fitted on these first frames and the winner carried over the rest by
    /// doubling the length; its profile intervals are checked at the Wald ends first.
    pub long_prefix: usize,
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
            noise: None,
            nuisances: true,
            windows: true,
            with: Vec::new(),
            long_prefix: PREFIX_FRAMES,
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

/// A value with its standard error.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct ValueSe {
    /// The value.
    pub value: f64,
    /// Its standard error (delta method from the fitted parameters' covariance).
    pub stderr: f64,
}

/// What the fit found of a rigid pendulum the rig file did not give (the `rigid_pendulum`
/// nuisance), in quantities a lab can check against its pendulum. The data fix L and r'; the
/// masses follow from the rig file's total mass, taken as slider_mass + bob_mass (a rod's
/// mass missing there scales m_e, J and d by the same factor).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct PendulumFound {
    /// Equivalent length L = J / (m_p d) (m): the simple pendulum with the same period.
    pub equivalent_length: ValueSe,
    /// Equivalent mass ratio r' = (m1 + m_p - m_e) / m_e.
    pub mass_ratio: ValueSe,
    /// Equivalent bob mass m_e = (m_p d)^2 / J (kg), from the total mass.
    pub equivalent_bob_mass: ValueSe,
    /// Moment of inertia about the pivot J = m_e L^2 (kg m^2).
    pub inertia: ValueSe,
    /// Radius of gyration about the pivot sqrt(J / m_p) (m), m_p taken as the rig's bob_mass.
    pub radius_of_gyration: ValueSe,
    /// Pivot to the centre of mass d = m_e L / m_p (m), m_p taken as the rig's bob_mass.
    pub com: ValueSe,
    /// The total mass m1 + m_p assumed (kg): the rig file's slider_mass + bob_mass.
    pub total_mass: f64,
    /// The swinging mass m_p assumed (kg): the rig file's bob_mass.
    pub swinging_mass: f64,
}

impl PendulumFound {
    /// From L and r' with their covariance `cov` ([[var L, cov], [cov, var r']]), the total
    /// mass `total` and the swinging mass `m_p`.
    pub fn new(l: f64, r: f64, cov: [[f64; 2]; 2], total: f64, m_p: f64) -> Self {
        // Each derived quantity with its gradient in (L, r'): the delta method.
        let se = |g: [f64; 2]| {
            (g[0] * g[0] * cov[0][0] + 2.0 * g[0] * g[1] * cov[0][1] + g[1] * g[1] * cov[1][1])
                .max(0.0)
                .sqrt()
        };
        let m_e = total / (1.0 + r);
        let dm_e = -total / ((1.0 + r) * (1.0 + r));
        let j = m_e * l * l;
        let dj = [2.0 * m_e * l, dm_e * l * l];
        let k = (j / m_p).sqrt();
        let dk = [dj[0] / (2.0 * k * m_p), dj[1] / (2.0 * k * m_p)];
        let d = m_e * l / m_p;
        let dd = [m_e / m_p, dm_e * l / m_p];
        PendulumFound {
            equivalent_length: ValueSe {
                value: l,
                stderr: se([1.0, 0.0]),
            },
            mass_ratio: ValueSe {
                value: r,
                stderr: se([0.0, 1.0]),
            },
            equivalent_bob_mass: ValueSe {
                value: m_e,
                stderr: se([0.0, dm_e]),
            },
            inertia: ValueSe {
                value: j,
                stderr: se(dj),
            },
            radius_of_gyration: ValueSe {
                value: k,
                stderr: se(dk),
            },
            com: ValueSe {
                value: d,
                stderr: se(dd),
            },
            total_mass: total,
            swinging_mass: m_p,
        }
    }
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
    /// The chosen model at its optimum, with its noise scales and row weights (outliers at
    /// zero): what a fit built on this one (the joint fit) starts from.
    pub problem: TrajectoryProblem,
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
}

/// The optimum, its cost (1/2 chi-square) and the iterations, or why the solver failed.
type Solved = Result<(DVector<f64>, f64, u64), String>;

/// Run Levenberg-Marquardt from `p0` on `problem`.
fn solve(problem: &TrajectoryProblem, p0: DVector<f64>, max_iters: u64) -> Solved {
    solve_traced(problem, p0, max_iters).map(|(p, c, i, _)| (p, c, i))
}

/// [`solve`] stopping at a relative cost decrease of `ftol` (and a relative step of the
/// same size) when given.
fn solve_loose<P: lm::LeastSquares + Clone>(
    problem: &P,
    p0: DVector<f64>,
    max_iters: u64,
    ftol: Option<f64>,
) -> Solved {
    let mut lm = LevenbergMarquardt::default();
    if let Some(tol) = ftol {
        lm.ftol = tol;
        lm.xtol = tol;
    }
    run_lm(problem, p0, max_iters, lm).map(|(p, c, i, _)| (p, c, i))
}

/// [`solve`] with the solver's termination reason.
fn solve_traced(
    problem: &TrajectoryProblem,
    p0: DVector<f64>,
    max_iters: u64,
) -> Result<(DVector<f64>, f64, u64, String), String> {
    run_lm(problem, p0, max_iters, LevenbergMarquardt::default())
}

/// Run `lm` on `problem` from `p0`: optimum, cost, iterations and termination reason.
fn run_lm<P: lm::LeastSquares + Clone>(
    problem: &P,
    p0: DVector<f64>,
    max_iters: u64,
    lm: LevenbergMarquardt,
) -> Result<(DVector<f64>, f64, u64, String), String> {
    let res = Executor::new(problem.clone(), lm)
        .configure(|s| s.param(p0).max_iters(max_iters))
        .run()
        .map_err(|e| e.to_string())?;
    let cost = res.state.get_best_cost();
    let iters = res.state.get_iter();
    let reason = res
        .state
        .get_termination_reason()
        .map_or_else(|| "not terminated".to_owned(), |r| r.to_string());
    let p = res.state.best_param.ok_or("no parameters")?;
    Ok((p, cost, iters, reason))
}

fn idx(problem: &TrajectoryProblem, p: Param) -> Option<usize> {
    problem.free.iter().position(|&f| f == p)
}

/// Per-marker RMS of raw residuals (weight-zero rows left out), with a degrees-of-freedom
/// correction, and the overall RMS.
fn marker_rms(problem: &TrajectoryProblem, weighted: &[f64], n_params: usize) -> ([f64; 2], f64) {
    let mut ss = [0.0; 2];
    let mut n = [0usize; 2];
    for (i, (row, v)) in problem.rows().zip(weighted).enumerate() {
        let (m, w) = (row.marker, problem.row_weight(i));
        if w > 0.0 {
            // Back in metres from the solver's weighted residual.
            let r = v * problem.sigma[m] / w;
            ss[m] += r * r;
            n[m] += 1;
        }
    }
    let total = (n[0] + n[1]).max(1);
    let dof_frac = (1.0 - n_params as f64 / total as f64).max(1e-3);
    let rms = [0, 1].map(|m| {
        if n[m] > 0 {
            (ss[m] / n[m] as f64 / dof_frac).sqrt()
        } else {
            f64::NAN
        }
    });
    (rms, ((ss[0] + ss[1]) / total as f64).sqrt())
}

/// The recording is usable: enough frames with both markers; times from zero.
fn check_data(mut obs: Observations) -> Result<Observations, FitError> {
    enough_frames(&obs)?;
    let t0 = obs.times[0];
    obs.times.iter_mut().for_each(|t| *t -= t0);
    Ok(obs)
}

/// At least ten frames with both markers.
fn enough_frames(obs: &Observations) -> Result<(), FitError> {
    let both = obs
        .slider
        .iter()
        .zip(&obs.bob)
        .filter(|(s, b)| s.is_some() && b.is_some())
        .count();
    if both < 10 {
        return Err(FitError::TooFewFrames(both));
    }
    Ok(())
}

/// The noise used as weights (m), the measurements behind it, and the positions dropped.
type NoiseAndOutliers = ([f64; 2], [Option<NoiseEstimate>; 2], [usize; 2]);

/// Each marker's noise, measured from its track (or given), and the mis-tracked
/// positions dropped. Returns the noise used as weights, the measurements and the drops.
fn noise_and_outliers(
    obs: &mut Observations,
    settings: &FitSettings,
) -> Result<NoiseAndOutliers, FitError> {
    if let Some(given) = settings.noise {
        if !given.iter().all(|s| s.is_finite() && *s > 0.0) {
            return Err(FitError::Settings(format!(
                "noise must be finite and positive (m), got {given:?}"
            )));
        }
    }
    let measured = noise::from_tracks(obs);
    let pick = |m: usize, est: &[Option<NoiseEstimate>; 2]| -> f64 {
        match (settings.noise, est[m], est[1 - m]) {
            (Some(g), _, _) => g[m],
            (None, Some(e), _) if e.sigma > 0.0 => e.sigma,
            (None, _, Some(o)) if o.sigma > 0.0 => o.sigma,
            // Noiseless tracks: a floor far below any camera, so the weights stay finite.
            _ => 1e-7,
        }
    };
    let first = [pick(0, &measured), pick(1, &measured)];
    let dropped = outliers::drop_from_tracks(obs, first);
    // The trimmed measurement is robust already; measure again without the dropped frames.
    let measured = if dropped.iter().any(|&d| d > 0) {
        noise::from_tracks(obs)
    } else {
        measured
    };
    let sigma = [pick(0, &measured), pick(1, &measured)];
    let reported = match settings.noise {
        Some(g) => [0, 1].map(|m| {
            Some(NoiseEstimate {
                sigma: g[m],
                dof: f64::INFINITY,
                source: "given",
            })
        }),
        None => measured,
    };
    Ok((sigma, reported, dropped))
}

/// What the base fit found, for the steps after it.
struct Base {
    problem: TrajectoryProblem,
    p: DVector<f64>,
    starts: Vec<StartOutcome>,
    iterations: u64,
    /// mu_static estimated from the data's stick-to-slide onsets.
    mu_s_data: Option<f64>,
    /// Whether the onset estimate says mu_static exceeds mu_kinetic (`None`: no onset seen).
    static_evidence: Option<bool>,
    /// The initial state guessed from the first frames (the start of every fit).
    y0_guess: State<f64>,
    /// mu_kinetic from the data (the main start).
    mu0: f64,
    /// How the last fit over the whole of a long recording stopped, when nothing changed
    /// after it (it need not be polished again).
    settled: Option<String>,
}

/// Relative cost decrease (and step) at which a long recording's fits short of the whole
/// recording stop: they only start the next fit well.
pub(crate) const STAGE_FTOL: f64 = 1e-6;

/// The default [`FitSettings::long_prefix`]: frames a long recording's starts and candidate
/// models are fitted on (recordings up to twice this are fitted whole from every start).
pub const PREFIX_FRAMES: usize = 8000;

/// Residuals this many noise deviations out are mis-tracked frames the track check missed.
const RESIDUAL_OUTLIER: f64 = 6.0;

/// What the residual outlier step did.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct ResidualOutliers {
    /// Positions dropped (slider, bob): the model describes the rest of the recording.
    dropped: [usize; 2],
    /// Positions down-weighted, not dropped (slider, bob): the model does not describe the
    /// rest either, so their residuals may be the model's error, not mis-tracking.
    weighted: [usize; 2],
    /// Nothing done yet: the current model misfits the rest; the chosen model decides.
    deferred: bool,
}

/// Positions whose residual is beyond [`RESIDUAL_OUTLIER`] deviations. Dropped (weight
/// zero, and the fit redone) only when the model describes the rest of the recording (its
/// chi-square passes [`select::misfits`]): a model that misfits leaves large residuals where it
/// is wrong, and dropping those would throw real positions away to fit a wrong model. Then the
/// step is deferred to the chosen model (`last` false), or, on that model (`last` true), the
/// positions are down-weighted by Huber's weight (their residual counts as if it were
/// [`RESIDUAL_OUTLIER`] deviations), which keeps them in the fit.
fn residual_outliers(
    problem: &mut TrajectoryProblem,
    p: &mut DVector<f64>,
    settings: &FitSettings,
    iterations: &mut u64,
    last: bool,
) -> ResidualOutliers {
    let mut out = ResidualOutliers::default();
    let Ok(raw) = problem.raw_residuals(p) else {
        return out;
    };
    // The scale: the measured noise, or the residuals' own robust spread when larger (a fit
    // that misses the motion has large residuals everywhere, and those are not outliers).
    let scale = [0, 1].map(|m| {
        let mut a: Vec<f64> = problem
            .rows()
            .zip(&raw)
            .filter(|(row, _)| row.marker == m)
            .map(|(_, r)| r.abs())
            .collect();
        // The median by selection, not a sort: linear in a million frames.
        let mid = a.len() / 2;
        let median = if a.is_empty() {
            0.0
        } else {
            *a.select_nth_unstable_by(mid, f64::total_cmp).1
        };
        problem.sigma[m].max(median / 0.6745)
    });
    // A position is one frame's marker: both its coordinates go together.
    let mut bad = std::collections::HashSet::new();
    for (i, (row, &r)) in problem.rows().zip(&raw).enumerate() {
        if problem.row_weight(i) > 0.0 && (r / scale[row.marker]).abs() > RESIDUAL_OUTLIER {
            bad.insert((row.frame, row.marker));
        }
    }
    // More than 2% of the positions flagged is a misfit, not mis-tracking.
    if bad.is_empty() || bad.len() * 2 * 50 > raw.len() {
        return out;
    }
    let flagged: Vec<usize> = problem
        .rows()
        .enumerate()
        .filter(|(_, row)| bad.contains(&(row.frame, row.marker)))
        .map(|(i, _)| i)
        .collect();
    // The rest: its chi-square against the measured noise.
    let (mut chi2_rest, mut n_rest) = (0.0, 0usize);
    for (i, (row, &r)) in problem.rows().zip(&raw).enumerate() {
        let w = problem.row_weight(i);
        if w > 0.0 && !bad.contains(&(row.frame, row.marker)) {
            chi2_rest += w * w * (r / problem.sigma[row.marker]).powi(2);
            n_rest += 1;
        }
    }
    let dof = (n_rest.saturating_sub(problem.free.len()) as f64).max(1.0);
    let fits_rest = chi2_rest <= dof + 5.0 * (2.0 * dof).sqrt();
    let counts = |out: &mut [usize; 2]| {
        for &(_, m) in &bad {
            out[m] += 1;
        }
    };
    if fits_rest {
        problem.drop_rows(flagged);
        counts(&mut out.dropped);
    } else if !last {
        out.deferred = true;
        return out;
    } else {
        let mut weights: Vec<f64> = (0..problem.n_rows())
            .map(|i| problem.row_weight(i))
            .collect();
        let markers: Vec<usize> = problem.rows().map(|row| row.marker).collect();
        for i in flagged {
            let z = (raw[i] / scale[markers[i]]).abs();
            weights[i] *= (RESIDUAL_OUTLIER / z).sqrt();
        }
        problem.set_row_weights(weights);
        counts(&mut out.weighted);
    }
    if let Ok((q, _, it)) = solve(problem, p.clone(), settings.max_iters) {
        *iterations += it;
        *p = q;
        problem.set_values(p);
    }
    out
}

/// What the fitted motion does at the frame times, summed as it runs (no samples kept).
struct Motion {
    /// The run (events, final state; no samples).
    sol: Solution<f64>,
    /// Lowest and highest slider position at the frames (m).
    range: (f64, f64),
    /// Whether it slides at some frame.
    slides: bool,
    /// Whether it sticks at some frame.
    sticks: bool,
    /// The largest friction ratio |c|/|b| the motion needs at a frame: while it never
    /// slides, mu_static is at least this.
    needed_ratio: f64,
    /// Lowest and highest sliding speed |x'| at the frames that slide.
    slide_speeds: Option<[f64; 2]>,
}

/// The fitted motion at the frame times.
fn motion(problem: &TrajectoryProblem) -> Result<Motion, FitError> {
    let mut range = (f64::INFINITY, f64::NEG_INFINITY);
    let (mut slides, mut sticks) = (false, false);
    let mut needed_ratio: f64 = 0.0;
    let mut slide_speeds: Option<[f64; 2]> = None;
    let sol = simulate_each(
        &problem.rig,
        &problem.initial,
        problem.frame_times().last().copied().unwrap_or(0.0),
        &problem.options,
        &Request {
            sample_times: problem.frame_times().to_vec(),
            friction_work: false,
            positions_only: false,
        },
        &mut |s: Sample<f64>| {
            range = (range.0.min(s.state[0]), range.1.max(s.state[0]));
            if matches!(s.mode, Mode::Slide(_)) {
                slides = true;
                let v = s.state[2].abs();
                let r = slide_speeds.get_or_insert([v, v]);
                *r = [r[0].min(v), r[1].max(v)];
            }
            sticks |= s.mode == Mode::Stick;
            let sh = Shorthands::at(&problem.rig, &s.state);
            needed_ratio = needed_ratio.max(sh.c.abs() / sh.b.abs());
        },
    )
    .map_err(|e| FitError::NoStart(e.to_string()))?;
    Ok(Motion {
        sol,
        range,
        slides,
        sticks,
        needed_ratio,
        slide_speeds,
    })
}

/// Whether the raw slider track moves by more than its noise can explain: its range along
/// the rail (2nd to 98th percentile) beyond ten noise deviations.
fn slider_moves(obs: &Observations, sigma: f64) -> Option<f64> {
    let mut x: Vec<f64> = obs.slider.iter().flatten().map(|p| p[0]).collect();
    if x.len() < 10 {
        return None;
    }
    x.sort_by(f64::total_cmp);
    let range = x[x.len() * 98 / 100] - x[x.len() * 2 / 100];
    (range > 10.0 * sigma).then_some(range)
}

/// Fit the free parameters to `obs` starting from `rig_guess` (its mu values are guesses):
/// the stages of [`stages`], in order.
pub fn fit(
    obs: Observations,
    rig_guess: &Rig<f64>,
    settings: &FitSettings,
) -> Result<FitReport, FitError> {
    let data = stages::prepare(obs, settings)?;
    let mut warnings = Vec::new();
    let base = base::fit(&data.obs, rig_guess, data.sigma, settings, &mut warnings)?;
    let mut f = stages::Fitting {
        problem: base.problem.clone(),
        p: base.p.clone(),
        iterations: base.iterations,
        warnings,
        moved: false,
    };
    let late = residual_outliers(&mut f.problem, &mut f.p, settings, &mut f.iterations, false);
    let seen = stages::seen(&f, &data.obs, &base)?;
    let (models, nuisances) = stages::nuisances(&mut f, &seen, &base, data.n_frames, settings);
    let (outliers, late) = stages::late_outliers(&mut f, late, data.dropped, settings);
    if !seen.slides {
        stages::hold_stuck(&mut f, seen.raw_moves, settings);
    }
    let static_state = stages::static_bound(&mut f, seen.slides);
    let slides = seen.slides;
    let motion = if f.moved {
        motion(&f.problem)?
    } else {
        seen.motion
    };
    let settled = base.settled.clone().filter(|_| late.dropped == [0, 0]);
    let stop_reason = stages::polish(&mut f, settled, settings);
    let mut est = stages::estimates(&mut f, data.noise_dof, slides, settings)?;
    let verdict = stages::adequacy(&mut f, &mut est, &models, &motion.sol.events, settings);
    let mu_static = stages::mu_static(
        &mut f,
        &mut est,
        static_state,
        slides,
        &motion,
        &base,
        &data.obs,
        settings,
    );
    stages::starts_agree(&mut f, &base, &est);
    let identifiable = slides;
    Ok(stages::report(
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
            outliers,
            motion,
            mu_static,
            identifiable,
            stop_reason,
        },
    ))
}

/// Below this many times the fit's relative tolerance times the rod length, a measured noise
/// and the residuals are below what the model's own positions resolve: the integrator's global
/// error over a recording's thousands of steps grows to hundreds of its local tolerance (a
/// noise-free 10 kHz recording leaves residuals of 1e-8 m at rtol 1e-9). At the default
/// tolerance this is 0.3 um on a 0.3 m rod, far below any camera's noise.
const NOISE_FREE_TOLERANCES: f64 = 1000.0;

/// Below this reduced chi-square the residuals are far smaller than the noise measured from the
/// tracks (no real noise gives it over the thousands of rows of a recording): the "noise" was
/// the smooth motion's leftover in the third differences, not noise.
const NOISE_FREE_CHI2: f64 = 0.01;

/// Whether a recording is noise-free for the fit (a synthetic recording written without
/// noise): its measured noise `sigma` and the residuals' RMS `rms` (m) both below [`NOISE_FREE_TOLERANCES`] x `rtol` x `scale` (the model's
/// numerical accuracy at the markers' distance), or the reduced chi-square below
/// [`NOISE_FREE_CHI2`]. Then the residuals are the integrator's and the data's rounding, and
/// the chi-square, block and window tests, which compare them with the noise, say nothing. A
/// model that misfits a noise-free recording leaves residuals far above the model's accuracy:
/// it is not noise-free and keeps its flag.
pub fn is_noise_free(sigma: [f64; 2], rms: f64, scale: f64, rtol: f64, reduced_chi2: f64) -> bool {
    sigma[0].max(sigma[1]).max(rms) < NOISE_FREE_TOLERANCES * rtol * scale
        || reduced_chi2 < NOISE_FREE_CHI2
}

/// `e` widened by a further standard deviation `s` (a source of error its interval did not
/// hold), named `tag` in its interval's method: the standard error becomes sqrt(se^2 + s^2) and
/// each half-width h becomes sqrt(h^2 + (1.96 s)^2), about the same value.
fn widen(e: &mut Estimate, s: f64, tag: &str) {
    if s.is_nan() || s <= 0.0 {
        return;
    }
    let wider = |h: f64| (h * h + 1.96 * 1.96 * s * s).sqrt();
    e.ci95 = [
        e.value - wider(e.value - e.ci95[0]),
        e.value + wider(e.ci95[1] - e.value),
    ];
    e.stderr = (e.stderr * e.stderr + s * s).sqrt();
    e.interval = intern(format!("{}+{tag}", e.interval));
}

/// A method label as a `&'static str`: the labels are few (a base method and a handful of
/// widenings in a fixed order), so each distinct one is leaked once and reused.
fn intern(label: String) -> &'static str {
    static LABELS: std::sync::Mutex<Vec<&'static str>> = std::sync::Mutex::new(Vec::new());
    let mut labels = LABELS.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(l) = labels.iter().find(|l| **l == label) {
        return l;
    }
    let l: &'static str = Box::leak(label.into_boxed_str());
    labels.push(l);
    l
}

/// Widen mu_kinetic's estimate `e` by the spread of the models in play ([`select::model_spread`])
/// when that spread is worth a tenth of its standard error: the standard error becomes
/// sqrt(se^2 + spread) and each half-width sqrt(h^2 + 1.96^2 spread).
fn model_uncertainty(e: &mut Estimate, models: &[ModelRow], warnings: &mut Vec<String>) {
    let (var, names) = select::model_spread(models, e.value);
    if var.is_nan() || var.sqrt() <= 0.1 * e.stderr || names.len() < 2 {
        return;
    }
    widen(e, var.sqrt(), "models");
    warnings.push(format!(
        "models close in the criterion give different mu_kinetic, and the interval carries their spread (standard deviation {:.2e}): {}",
        var.sqrt(),
        names.join(", ")
    ));
}

/// `e` with its 95% interval cut at the physical bound of `q`: mu_kinetic, pivot damping and
/// viscous rail friction are at least 0, and mu_static at least `mu_k_low` (the lower end of
/// mu_kinetic's interval). The part of an interval beyond a bound holds no rig, so cutting it
/// never loses the truth; the value and standard error are left as fitted.
fn within_bounds(q: Param, mut e: Estimate, mu_k_low: f64) -> Estimate {
    let low = match q {
        Param::MuKinetic | Param::PivotDamping | Param::ViscousFriction => 0.0,
        Param::MuStatic => mu_k_low,
        _ => return e,
    };
    e.ci95[0] = e.ci95[0].max(low);
    e.ci95[1] = e.ci95[1].max(e.ci95[0]);
    e
}

/// The fit failed although it ran when mu_kinetic sits at its bound 0 (within two standard
/// errors of it, and below 1e-3) while Stribeck's law or viscous rail friction carries the
/// friction: no Coulomb coefficient was measured, whatever its interval says. Said as such.
fn pinned_friction(problem: &TrajectoryProblem, mu: Option<&Estimate>) -> Option<String> {
    let mu = mu?;
    let carried = if problem.free.contains(&Param::StribeckVelocity) {
        "Stribeck's law (mu_static and the Stribeck speed)"
    } else if problem.free.contains(&Param::ViscousFriction) {
        "viscous rail friction"
    } else {
        return None;
    };
    (mu.value < 1e-3 && mu.value < 2.0 * mu.stderr).then(|| {
        format!(
            "The fit failed: mu_kinetic is pinned at {:.2e} while {carried} carries the friction, so no friction coefficient was measured; the rig's description is likely wrong (a rigid pendulum: try --with rigid_pendulum, or give rod_mass and bob_radius).",
            mu.value
        )
    })
}

/// What the `rigid_pendulum` nuisance found, when the chosen model frees it.
fn pendulum_found(
    problem: &TrajectoryProblem,
    params: &[(Param, Estimate)],
    correlation: &DMatrix<f64>,
    rig_guess: &Rig<f64>,
) -> Option<PendulumFound> {
    let i = idx(problem, Param::PendulumLength)?;
    let j = idx(problem, Param::MassRatio)?;
    let (l, r) = (params[i].1, params[j].1);
    let c = correlation[(i, j)] * l.stderr * r.stderr;
    let cov = [[l.stderr * l.stderr, c], [c, r.stderr * r.stderr]];
    let (total, m_p) = match rig_guess.pendulum {
        Some(p) => (p.slider_mass + p.mass, p.mass),
        None => (
            rig_guess.slider_mass + rig_guess.bob_mass,
            rig_guess.bob_mass,
        ),
    };
    Some(PendulumFound::new(l.value, r.value, cov, total, m_p))
}

/// Below this p-value the runs test says the residuals are not noise (four streams of
/// thousands of signs: a smooth miss of 3/4 of the noise is enough, whatever noise was measured).
const RUNS_P: f64 = 1e-4;

/// The one plain sentence when the model limits the result: chi-square fails against the
/// measured noise (p < 0.001), the residuals are correlated enough to widen the errors by half,
/// the windows (a slide each) disagree (p < 0.01), or the residuals' signs run in long
/// stretches (runs test p < [`RUNS_P`]).
fn adequacy_sentence(
    a: &uncertainty::Assessment,
    block_ratio: f64,
    windows_p: Option<f64>,
    runs_p: f64,
    mu: Option<&Estimate>,
) -> Option<String> {
    let mut why = Vec::new();
    if a.p_value < 1e-3 {
        why.push(format!(
            "chi-square is {:.0} for {:.0} degrees of freedom against the noise measured from the tracks (reduced {:.2}, p = {:.1e})",
            a.chi2, a.dof, a.reduced_chi2, a.p_value
        ));
    }
    if block_ratio > 1.5 {
        why.push(format!(
            "the residuals are correlated in time (block standard error {block_ratio:.1} times the plain one)"
        ));
    }
    if runs_p < RUNS_P {
        why.push(format!(
            "the residuals keep their sign over long stretches (runs test p = {runs_p:.1e})"
        ));
    }
    if let Some(pw) = windows_p.filter(|p| *p < 0.01) {
        why.push(format!(
            "the recording's slides, fitted one by one, disagree on mu_kinetic (p = {pw:.1e})"
        ));
    }
    if why.is_empty() {
        return None;
    }
    let interval = mu.map_or(String::new(), |e| {
        let what: Vec<&str> = e
            .interval
            .split('+')
            .filter_map(|tag| match tag {
                "block" => Some("the residuals' correlation"),
                "windows" => Some("the spread of the slides' values"),
                "models" => Some("the spread of close models"),
                "path" => Some("as much as mu moved while nuisances were added"),
                _ => None,
            })
            .collect();
        let held = if what.is_empty() {
            String::new()
        } else {
            format!(" to hold {}", what.join(", "))
        };
        format!(
            "; the interval for mu_kinetic was widened{held}: [{:.5}, {:.5}] ({})",
            e.ci95[0], e.ci95[1], e.interval
        )
    });
    Some(format!(
        "The result is limited by the model, not by the noise: {}{interval}.",
        why.join("; ")
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Arc;

    fn problem(free: Vec<Param>) -> TrajectoryProblem {
        let obs = Arc::new(Observations {
            times: vec![0.0, 0.001],
            slider: vec![Some([0.0, 0.0]); 2],
            bob: vec![Some([0.3, 0.0]); 2],
        });
        TrajectoryProblem::new(obs, Rig::paper(0.3), [0.0; 4], free, Options::default())
    }

    fn estimate(value: f64, stderr: f64) -> Estimate {
        Estimate {
            value,
            stderr,
            ci95: [value - 1.96 * stderr, value + 1.96 * stderr],
            interval: "wald",
        }
    }

    /// Intervals stop at the physical bounds and nowhere else.
    #[test]
    fn intervals_stop_at_the_physical_bounds() {
        let e = within_bounds(Param::MuKinetic, estimate(0.0, 20.0), 0.0);
        assert_eq!(e.ci95, [0.0, 39.2]);
        assert_eq!((e.value, e.stderr), (0.0, 20.0));
        let e = within_bounds(Param::PivotDamping, estimate(1e-4, 1e-4), 0.0);
        assert_eq!(e.ci95[0], 0.0);
        // mu_static from the lower end of mu_kinetic's interval.
        let e = within_bounds(Param::MuStatic, estimate(0.30, 0.05), 0.26);
        assert_eq!(e.ci95[0], 0.26);
        // Away from a bound, or without one, nothing changes.
        let far = estimate(0.25, 0.01);
        assert_eq!(within_bounds(Param::MuKinetic, far, 0.0), far);
        let tilt = estimate(-0.01, 0.02);
        assert_eq!(within_bounds(Param::RailTilt, tilt, 0.0), tilt);
    }

    /// mu pinned at 0 while Stribeck's law or viscous friction carries the friction is a
    /// failed fit; the same mu with Coulomb's law alone, or a mu clear of 0, is not.
    #[test]
    fn mu_pinned_at_zero_with_friction_elsewhere_is_a_failed_fit() {
        let stribeck = problem(vec![
            Param::MuKinetic,
            Param::MuStatic,
            Param::StribeckVelocity,
        ]);
        let viscous = problem(vec![Param::MuKinetic, Param::ViscousFriction]);
        let coulomb = problem(vec![Param::MuKinetic, Param::X]);
        let pinned = estimate(0.0, 0.26);
        assert!(pinned_friction(&stribeck, Some(&pinned)).is_some());
        assert!(pinned_friction(&viscous, Some(&pinned)).is_some());
        assert!(pinned_friction(&coulomb, Some(&pinned)).is_none());
        assert!(pinned_friction(&stribeck, Some(&estimate(0.25, 0.01))).is_none());
        // Clear of zero by many standard errors: a small but measured coefficient.
        assert!(pinned_friction(&stribeck, Some(&estimate(5e-4, 1e-5))).is_none());
    }
}
