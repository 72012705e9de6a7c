//! Fit mu and the initial state to a recording by least squares on the hybrid model, with
//! honest uncertainty: standard errors from the exact Jacobian, a profile interval for mu,
//! identifiability checks, and goodness-of-fit diagnostics.

pub mod guess;
pub mod lm;
mod problem;

pub use problem::{Observations, Param, TrajectoryProblem};

use crate::model::{Mode, Rig, Shorthands, State};
use crate::sim::{simulate, Event, EventKind, Options, Request};
use argmin::core::{Executor, State as _};
use lm::{LeastSquares, LevenbergMarquardt};
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;
use std::sync::Arc;
use thiserror::Error;

/// Loss applied to the standardised residuals.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Loss {
    /// Plain least squares.
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
    /// Free it when the fitted motion shows a stick-to-slide onset, else tie it to mu_kinetic.
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
    /// Extra starting values of mu_kinetic (besides the data's and the rig's guesses).
    pub extra_starts: Vec<f64>,
    /// Compute the profile-likelihood interval for mu_kinetic.
    pub profile: bool,
    /// Integrator settings for predictions.
    pub options: Options,
    /// Most Levenberg-Marquardt iterations per fit.
    pub max_iters: u64,
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
        }
    }
}

/// An estimated parameter.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Estimate {
    /// Best-fit value.
    pub value: f64,
    /// Standard error from the Jacobian at the optimum, scaled by the residual variance.
    pub stderr: f64,
    /// 95% interval: from the profile for mu (the cost is not quadratic near mode changes),
    /// value +- 1.96 stderr otherwise.
    pub ci95: [f64; 2],
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
    /// Final cost 1/2 sum of squared standardised residuals.
    pub cost: f64,
}

/// The result of a fit.
#[derive(Debug, Clone)]
pub struct FitReport {
    /// Every free parameter with its estimate.
    pub params: Vec<(Param, Estimate)>,
    /// mu_kinetic, or `None` when the recording never slides (not identifiable).
    pub mu_kinetic: Option<Estimate>,
    /// mu_static.
    pub mu_static: StaticResult,
    /// Fitted rig (fixed values kept).
    pub rig: Rig<f64>,
    /// Fitted initial state.
    pub initial: State<f64>,
    /// Correlation matrix of the free parameters (order of `params`).
    pub correlation: DMatrix<f64>,
    /// RMS residual over all coordinates (m).
    pub rms_residual_m: f64,
    /// RMS residual per marker (slider, bob) (m).
    pub rms_per_marker_m: [f64; 2],
    /// Noise scale per marker estimated from the residuals (m).
    pub noise_m: [f64; 2],
    /// Sum of squared standardised residuals over degrees of freedom.
    pub reduced_chi2: f64,
    /// Lag-1 autocorrelation of the residuals (0 for white noise).
    pub residual_autocorrelation: f64,
    /// Events of the fitted motion.
    pub events: Vec<Event>,
    /// Whether mu_kinetic is identifiable from the recording.
    pub identifiable: bool,
    /// Multi-start outcomes.
    pub starts: Vec<StartOutcome>,
    /// Residual rows used.
    pub n_residuals: usize,
    /// Notes on identifiability and warnings on the fit's quality.
    pub warnings: Vec<String>,
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
}

/// The optimum and its cost, or why the solver failed.
type Solved = Result<(DVector<f64>, f64), String>;

/// Run Levenberg-Marquardt from `p0` on `problem`; returns the optimum and its cost.
fn solve(
    problem: &TrajectoryProblem,
    p0: DVector<f64>,
    max_iters: u64,
) -> Result<(DVector<f64>, f64), String> {
    let res = Executor::new(problem.clone(), LevenbergMarquardt::default())
        .configure(|s| s.param(p0).max_iters(max_iters))
        .run()
        .map_err(|e| e.to_string())?;
    let cost = res.state.get_best_cost();
    if std::env::var_os("APPELL_TRACE_FIT").is_some() {
        eprintln!(
            "lm: {} iterations, cost {cost:.6e}, {:?}",
            res.state.get_iter(),
            res.state.get_termination_reason()
        );
    }
    let p = res.state.best_param.ok_or("no parameters")?;
    Ok((p, cost))
}

fn idx(problem: &TrajectoryProblem, p: Param) -> Option<usize> {
    problem.free.iter().position(|&f| f == p)
}

/// Per-marker RMS of raw residuals, with a degrees-of-freedom correction.
fn marker_rms(raw: &[(usize, f64)], n_params: usize) -> ([f64; 2], f64) {
    let mut ss = [0.0; 2];
    let mut n = [0usize; 2];
    for &(m, r) in raw {
        ss[m] += r * r;
        n[m] += 1;
    }
    let total = raw.len().max(1);
    let dof_frac = 1.0 - n_params as f64 / total as f64;
    let rms = [0, 1].map(|m| {
        if n[m] > 0 {
            (ss[m] / n[m] as f64 / dof_frac).sqrt()
        } else {
            f64::NAN
        }
    });
    (rms, ((ss[0] + ss[1]) / total as f64).sqrt())
}

/// Fit the free parameters to `obs` starting from `rig_guess` (its mu values are guesses).
pub fn fit(
    obs: Observations,
    rig_guess: &Rig<f64>,
    settings: &FitSettings,
) -> Result<FitReport, FitError> {
    let both = obs
        .slider
        .iter()
        .zip(&obs.bob)
        .filter(|(s, b)| s.is_some() && b.is_some())
        .count();
    if both < 10 {
        return Err(FitError::TooFewFrames(both));
    }
    let mut obs = obs;
    let t0 = obs.times[0];
    obs.times.iter_mut().for_each(|t| *t -= t0);
    let obs = Arc::new(obs);
    let mut warnings = Vec::new();

    // Starting values from the data.
    let n = obs.times.len();
    let dt = (obs.times[n - 1] / (n - 1) as f64).max(1e-6);
    let window = ((0.012 / dt).round() as usize).clamp(5, 40);
    let (y0, x_dot_se) = guess::initial_state(&obs, window).unwrap_or(([0.0; 4], f64::INFINITY));
    let at_rest = y0[2].abs() < 3.0 * x_dot_se;
    let rig = *rig_guess;
    if let Some(l) = guess::rod_length(&obs) {
        if (l - rig.rod_length).abs() > 0.05 * rig.rod_length {
            warnings.push(format!(
                "the markers are {l:.4} m apart (median) but the rig says rod_length = {:.4} m: check the scale or the rig",
                rig.rod_length
            ));
        }
    }
    // Second derivatives need a wider window than the initial slope: about 40 ms each side.
    let mu_data = guess::mu_from_sliding(&obs, &rig, ((0.04 / dt).round() as usize).clamp(4, 200));
    let mut free = vec![
        Param::MuKinetic,
        Param::X,
        Param::Theta,
        Param::XDot,
        Param::ThetaDot,
    ];
    if settings.fit_rod_length {
        free.push(Param::RodLength);
    }
    let mut problem = TrajectoryProblem::new(obs.clone(), rig, y0, free, settings.options);
    problem.tie_static = settings.mu_static != StaticMode::Fixed;

    // Candidate models. Released from rest, x'(0) = 0 exactly: the motion may start stuck,
    // which no small nonzero x'(0) reproduces (the mode at t = 0 jumps there). And a stuck
    // start lasts as long as mu_static allows, which mu_static = mu_kinetic cannot reproduce
    // when they differ: onsets seen in the data give mu_static a start of its own.
    // The onset estimate runs about 20% high when mu_static = mu_kinetic (the slip then starts
    // smoothly, x'' from zero); only an estimate above 1.25 times mu_kinetic counts as
    // evidence that mu_static exceeds it.
    let mu_s_data = (settings.mu_static == StaticMode::Auto)
        .then(|| {
            guess::mu_static_from_onsets(&obs, &rig, ((0.01 / dt).round() as usize).clamp(3, 50))
        })
        .flatten();
    let static_evidence =
        mu_s_data.map(|m| m > 1.25 * rig.mu_kinetic.min(mu_data.unwrap_or(f64::INFINITY)));
    let free_model = problem.clone();
    let mut candidates = Vec::new();
    if at_rest {
        let mut rest = problem.clone();
        rest.free.retain(|&q| q != Param::XDot);
        rest.initial[2] = 0.0;
        candidates.push(rest.clone());
        if let (Some(mu_s), Some(true)) = (mu_s_data, static_evidence) {
            let mut m = rest;
            m.free.push(Param::MuStatic);
            m.tie_static = false;
            m.rig.mu_static = mu_s;
            candidates.push(m);
        }
    } else {
        candidates.push(free_model.clone());
    }
    let mu0 = mu_data.unwrap_or(rig.mu_kinetic);
    let start_values = |m: &TrajectoryProblem, mu: f64| {
        let mut p0 = m.values();
        p0[0] = mu;
        if let Some(i) = m.free.iter().position(|&q| q == Param::MuStatic) {
            p0[i] = p0[i].max(mu);
        }
        p0
    };
    // One parallel batch: every candidate from the data's mu, and the first candidate from
    // the other starts over mu (the cost is only piecewise smooth in mu).
    // The farther starts go first: they take the most iterations, and with one job per
    // thread the batch then ends with the quick ones.
    let mut jobs: Vec<(usize, f64)> = Vec::new();
    for mu in [rig.mu_kinetic]
        .into_iter()
        .chain(settings.extra_starts.iter().copied())
    {
        if (mu - mu0).abs() > 1e-3 * mu0.abs().max(1e-3) {
            jobs.push((0, mu));
        }
    }
    jobs.extend((0..candidates.len()).map(|m| (m, mu0)));
    let solved: Vec<(usize, f64, Solved)> = jobs
        .par_iter()
        .with_max_len(1)
        .map(|&(m, mu)| {
            (
                m,
                mu,
                solve(
                    &candidates[m],
                    start_values(&candidates[m], mu),
                    settings.max_iters,
                ),
            )
        })
        .collect();
    // Model choice by an information criterion: residual sum of squares times (1 + 2k/n),
    // so a parameter must pay for itself (Akaike's criterion for Gaussian noise).
    let n_rows = problem.n_rows() as f64;
    let score = |p: &DVector<f64>, c: f64| c * (1.0 + 2.0 * p.len() as f64 / n_rows);
    let mut starts = Vec::new();
    let mut last_err = String::new();
    let mut best: Option<(usize, DVector<f64>, f64)> = None;
    for (m, mu, r) in solved {
        match r {
            Ok((p, c)) => {
                starts.push(StartOutcome {
                    mu_start: mu,
                    mu_end: p[0],
                    cost: c,
                });
                if best
                    .as_ref()
                    .is_none_or(|(_, bp, bc)| score(&p, c) < score(bp, *bc))
                {
                    best = Some((m, p, c));
                }
            }
            Err(e) => last_err = e,
        }
    }
    let (choice, mut p, cost) = best.ok_or(FitError::NoStart(last_err))?;
    let tried_static = candidates.iter().any(|m| m.free.contains(&Param::MuStatic));
    problem = candidates.swap_remove(choice);
    // A release judged "from rest" whose fit leaves structured residuals may have had a small
    // push: then the model with x'(0) free competes too.
    if at_rest {
        let structured = problem.raw_residuals(&p).map(|raw| {
            let r: Vec<f64> = raw.iter().map(|x| x.1).collect();
            lag1(&problem, &r)
        });
        if structured.is_ok_and(|rho| rho > 0.3) {
            let mut p0 = free_model.values();
            p0[0] = p[0];
            if let Ok((q, c)) = solve(&free_model, p0, settings.max_iters) {
                starts.push(StartOutcome {
                    mu_start: p[0],
                    mu_end: q[0],
                    cost: c,
                });
                if score(&q, c) < score(&p, cost) {
                    problem = free_model;
                    p = q;
                }
            }
        }
    }
    problem.set_values(&p);

    // Noise per marker from the residuals, then refit with those weights (and robust weights).
    let refit = |problem: &TrajectoryProblem, p: &DVector<f64>| {
        solve(problem, p.clone(), settings.max_iters).map(|(p, _)| p)
    };
    let rounds = if settings.loss == Loss::Squares { 1 } else { 3 };
    for _ in 0..rounds {
        let Ok(raw) = problem.raw_residuals(&p) else {
            break;
        };
        let (rms, _) = marker_rms(&raw, problem.free.len());
        problem.sigma = rms.map(|s| if s.is_finite() && s > 0.0 { s } else { 1e-3 });
        problem.row_weights = raw
            .iter()
            .map(|&(m, r)| {
                let z = (r / problem.sigma[m]).abs();
                match settings.loss {
                    Loss::Squares => 1.0,
                    Loss::Huber(k) => {
                        if z <= k {
                            1.0
                        } else {
                            (k / z).sqrt()
                        }
                    }
                    Loss::Cauchy(k) => (1.0 / (1.0 + (z / k).powi(2))).sqrt(),
                }
            })
            .collect();
        // Equal noise on both markers only rescales the cost: the optimum does not move.
        let ratio = problem.sigma[0].max(problem.sigma[1]) / problem.sigma[0].min(problem.sigma[1]);
        if settings.loss == Loss::Squares && ratio < 1.25 {
            break;
        }
        if let Ok(q) = refit(&problem, &p) {
            p = q;
            problem.set_values(&p);
        }
    }

    // The fitted motion: does it slide, does it stick, does a stick end in a slip?
    let motion = |problem: &TrajectoryProblem| {
        simulate(
            &problem.rig,
            &problem.initial,
            obs.times[obs.times.len() - 1],
            &settings.options,
            &Request {
                sample_times: problem.frame_times().to_vec(),
                friction_work: false,
            },
        )
    };
    let sol = motion(&problem).map_err(|e| FitError::NoStart(e.to_string()))?;
    // Whether the parameters change below (the fitted motion is then simulated again).
    let mut moved = false;
    // A slide shorter than the slider's noise is not seen by the camera: the data then only
    // say the slider held, so refit the stuck pendulum (mu at 0.999 mu*, where it never slips
    // and no paradox arises) and report a lower bound for mu_static.
    let (x_lo, x_hi) = sol
        .samples
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), s| {
            (lo.min(s.state[0]), hi.max(s.state[0]))
        });
    let slides = sol.samples.iter().any(|s| matches!(s.mode, Mode::Slide(_)))
        && x_hi - x_lo > 3.0 * problem.sigma[0];
    let sticks = sol.samples.iter().any(|s| s.mode == Mode::Stick);
    let onset = sol
        .events
        .iter()
        .any(|e| e.kind == EventKind::Slip && e.t > 0.0);
    if !slides {
        let mu_hold = 0.999 * crate::model::regions::mu_critical(problem.rig.mass_ratio());
        problem.rig.mu_kinetic = mu_hold;
        problem.rig.mu_static = mu_hold;
        problem.initial[2] = 0.0;
        problem.free = vec![Param::X, Param::Theta, Param::ThetaDot];
        p = problem.values();
        if let Ok(q) = refit(&problem, &p) {
            p = q;
            problem.set_values(&p);
        }
        moved = true;
        warnings.push("the slider never slides in the recording: mu_kinetic is not identifiable from it; mu_static is only bounded from below".into());
    }
    // mu_static is freed when the motion shows a stick-to-slide onset. If it ends on its bound
    // mu_static = mu_kinetic, the onset is smooth (x'' starts at zero), its first-order
    // sensitivity vanishes, and the errors of the others come from the tied model; mu_static
    // then gets a one-sided profile interval.
    let mut static_at_bound = false;
    let mut mu_static_free = false;
    if !slides {
        // handled above: the stuck pendulum has no friction parameter left
    } else if let Some(i) = idx(&problem, Param::MuStatic) {
        if p[i] - p[0] <= 1e-9 * p[0].max(1e-9) {
            problem.free.remove(i);
            problem.tie_static = true;
            p = problem.values();
            static_at_bound = true;
        } else {
            mu_static_free = true;
        }
    } else if settings.mu_static == StaticMode::Auto
        && onset
        && !tried_static
        && static_evidence != Some(false)
    {
        let mut free_static = problem.clone();
        free_static.free.push(Param::MuStatic);
        free_static.tie_static = false;
        if let Ok(q) = refit(&free_static, &free_static.values()) {
            let at_bound = q[q.len() - 1] - q[0] <= 1e-9 * q[0].max(1e-9);
            if at_bound {
                static_at_bound = true;
            } else {
                problem = free_static;
                p = q;
                problem.set_values(&p);
                mu_static_free = true;
                moved = true;
            }
        }
    }
    let sol = if moved {
        motion(&problem).map_err(|e| FitError::NoStart(e.to_string()))?
    } else {
        sol
    };

    // Uncertainty from the exact Jacobian at the optimum.
    let (r, j) = problem
        .residuals_jacobian(&p)
        .map_err(|e| FitError::NoStart(e.to_string()))?;
    let n_res = r.len();
    let dof = (n_res - p.len()).max(1) as f64;
    let s2 = r.norm_squared() / dof;
    let jtj = j.tr_mul(&j);
    let cov = jtj.clone().try_inverse().unwrap_or_else(|| {
        jtj.pseudo_inverse(1e-14)
            .unwrap_or(DMatrix::from_element(p.len(), p.len(), f64::NAN))
    }) * s2;
    let se: Vec<f64> = (0..p.len()).map(|i| cov[(i, i)].max(0.0).sqrt()).collect();
    let correlation = DMatrix::from_fn(p.len(), p.len(), |a, b| cov[(a, b)] / (se[a] * se[b]));
    let mut params: Vec<(Param, Estimate)> = problem
        .free
        .iter()
        .enumerate()
        .map(|(i, &q)| {
            (
                q,
                Estimate {
                    value: p[i],
                    stderr: se[i],
                    ci95: [p[i] - 1.96 * se[i], p[i] + 1.96 * se[i]],
                },
            )
        })
        .collect();

    let identifiable = slides;
    if settings.profile && identifiable {
        if let Some(ci) = profile_interval(&problem, &p, 0, se[0], s2, settings, 0.0) {
            params[0].1.ci95 = ci;
        } else {
            warnings.push("the profile interval for mu_kinetic did not close; the interval shown is value +- 1.96 stderr".into());
        }
    }
    let mu_kinetic = identifiable.then(|| params[0].1);
    let static_index = idx(&problem, Param::MuStatic).filter(|_| mu_static_free);
    let mu_static = if let Some(i) = static_index {
        if settings.profile {
            match profile_interval(&problem, &p, i, se[i], s2, settings, p[0]) {
                Some(ci) => params[i].1.ci95 = ci,
                None => warnings.push("the profile interval for mu_static did not close".into()),
            }
        }
        StaticResult::Estimated(params[i].1)
    } else if static_at_bound || (slides && onset && static_evidence == Some(false)) {
        let mut upper = f64::NAN;
        if settings.profile {
            let mut free_static = problem.clone();
            free_static.free.push(Param::MuStatic);
            free_static.tie_static = false;
            let q = free_static.values();
            if let Some(ci) =
                profile_interval(&free_static, &q, q.len() - 1, f64::NAN, s2, settings, q[0])
            {
                upper = ci[1];
            }
        }
        warnings.push(format!(
            "mu_static fits at its bound mu_static = mu_kinetic; the data allow up to {upper:.5}"
        ));
        let mu = p[0];
        StaticResult::Estimated(Estimate {
            value: mu,
            stderr: (upper - mu) / 1.96,
            ci95: [mu, upper],
        })
    } else if !slides {
        let bound = sol
            .samples
            .iter()
            .map(|s| {
                let sh = Shorthands::at(&problem.rig, &s.state);
                sh.c.abs() / sh.b.abs()
            })
            .fold(0.0, f64::max);
        StaticResult::LowerBound(bound)
    } else {
        if !sticks {
            warnings
                .push("the slider never sticks: the recording says nothing about mu_static".into());
        }
        StaticResult::NotIdentifiable
    };

    // Goodness of fit.
    let raw = problem.unweighted(r.as_slice());
    let (rms_per_marker_m, rms_residual_m) = marker_rms(&raw, p.len());
    let rho = lag1(&problem, r.as_slice());
    if rho.abs() * (n_res as f64).sqrt() > 8.0 && rho.abs() > 0.3 {
        warnings.push(format!("residuals show structure (lag-1 autocorrelation {rho:.2}): the model may not describe this recording (rod length, rail tilt, time offset, a marker mix-up)"));
    }
    // Starts that ended statistically as good as the best (cost within the 1-dof likelihood
    // ratio, 2 / n relative) but at a different mu are a real ambiguity; a start that stalled
    // at a worse cost is only a failed start.
    let best_cost = starts.iter().map(|s| s.cost).fold(f64::INFINITY, f64::min);
    let tied: Vec<f64> = starts
        .iter()
        .filter(|s| s.cost <= best_cost * (1.0 + 2.0 / n_rows))
        .map(|s| s.mu_end)
        .collect();
    if let (Some(lo), Some(hi), true) = (
        tied.iter().cloned().reduce(f64::min),
        tied.iter().cloned().reduce(f64::max),
        identifiable,
    ) {
        if hi - lo > 3.0 * se[0].max(1e-6) {
            warnings.push(format!("starts disagree: equally good fits have mu_kinetic from {lo:.5} to {hi:.5}; the best was kept"));
        }
    }
    Ok(FitReport {
        params,
        mu_kinetic,
        mu_static,
        rig: problem.rig,
        initial: problem.initial,
        correlation,
        rms_residual_m,
        rms_per_marker_m,
        noise_m: problem.sigma,
        reduced_chi2: s2,
        residual_autocorrelation: rho,
        events: sol.events,
        identifiable,
        starts,
        n_residuals: n_res,
        warnings,
    })
}

/// Lag-1 autocorrelation of the residual series, per coordinate stream, pooled.
fn lag1(problem: &TrajectoryProblem, r: &[f64]) -> f64 {
    let markers = problem.row_markers();
    // Rows come as frame-major (slider x, y, bob x, y); pair each row with the next row of
    // the same stream, 2 or 4 rows later depending on which markers the frames have.
    let mut num = 0.0;
    let mut den = 0.0;
    for (i, &ri) in r.iter().enumerate() {
        den += ri * ri;
        if let Some(k) =
            (i + 1..r.len().min(i + 6)).find(|&k| markers[k] == markers[i] && (k - i) % 2 == 0)
        {
            num += ri * r[k];
        }
    }
    if den > 0.0 {
        num / den
    } else {
        0.0
    }
}

/// 95% profile-likelihood interval for parameter `k`: where the best cost with that parameter
/// fixed rises by chi2(1, 0.95) = 3.84 times the residual variance.
fn profile_interval(
    problem: &TrajectoryProblem,
    p: &DVector<f64>,
    k: usize,
    se: f64,
    s2: f64,
    settings: &FitSettings,
    lower_limit: f64,
) -> Option<[f64; 2]> {
    let target = 3.84 * s2;
    let base = p.clone();
    let s_min = problem.residuals(p).ok()?.norm_squared();
    let mut fixed = problem.clone();
    fixed.free.remove(k);
    let others: Vec<usize> = (0..p.len()).filter(|&i| i != k).collect();
    let profile = |v: f64, warm: &DVector<f64>| -> Option<(f64, DVector<f64>)> {
        let mut pr = fixed.clone();
        let mut full = base.clone();
        full[k] = v;
        let mut tmp = problem.clone();
        tmp.set_values(&full);
        pr.rig = tmp.rig;
        pr.initial = tmp.initial;
        let (opt, cost) = solve(&pr, warm.clone(), settings.max_iters).ok()?;
        Some((2.0 * cost - s_min, opt))
    };
    let start: DVector<f64> = DVector::from_iterator(others.len(), others.iter().map(|&i| p[i]));
    let mut ends = [0.0; 2];
    for (side, dir) in [-1.0f64, 1.0].iter().enumerate() {
        // A standard error larger than half the value means the linearisation says nothing
        // (a bound is active): start from a step relative to the value instead.
        let scale = p[k].abs().max(1e-3);
        let step0 = if se.is_finite() && se < 0.5 * scale {
            se.max(1e-6 * scale)
        } else {
            0.01 * scale
        };
        let mut lo = (p[k], 0.0);
        let mut warm = start.clone();
        let mut step = 2.0 * step0;
        let mut hi = None;
        for _ in 0..12 {
            let v = (p[k] + dir * step).max(lower_limit);
            let (d, opt) = profile(v, &warm)?;
            if d >= target {
                hi = Some((v, d));
                break;
            }
            lo = (v, d);
            warm = opt;
            if v == lower_limit {
                break;
            }
            step *= 2.0;
        }
        let Some(mut hi) = hi else {
            if lo.0 == lower_limit {
                ends[side] = lower_limit;
                continue;
            }
            return None;
        };
        for _ in 0..8 {
            // Interpolate on the square root of the rise, which is nearly linear in the value.
            let (a, b) = (lo.1.max(0.0).sqrt(), hi.1.sqrt());
            let frac = ((target.sqrt() - a) / (b - a)).clamp(0.05, 0.95);
            let v = lo.0 + frac * (hi.0 - lo.0);
            let (d, opt) = profile(v, &warm)?;
            if d >= target {
                hi = (v, d);
            } else {
                lo = (v, d);
                warm = opt;
            }
            if (hi.0 - lo.0).abs() < 0.02 * step0 {
                break;
            }
        }
        ends[side] = 0.5 * (lo.0 + hi.0);
    }
    Some(ends)
}
