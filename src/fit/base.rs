//! The base model (mu_kinetic and the initial state; released from rest or moving; mu_static
//! when the onsets demand it), fitted from several starts in mu, the best by AIC: what the
//! data say before any fit ([`guesses`]), the candidate models ([`candidates`]), the starts
//! ([`starts`]) and their best ([`best_start`]), a release from rest that had a push
//! ([`push_check`]), a long recording carried over by doubling ([`carry_over`]) and a robust
//! loss's reweighting ([`reweight`]).

use super::problem::{Observations, Param, TrajectoryProblem};
use super::solve::{run_lm, solve, solve_loose, Solved, STAGE_FTOL};
use super::{guess, uncertainty, FitError, FitSettings, Loss, StartOutcome, StaticMode};
use crate::fit::lm::LevenbergMarquardt;
use crate::model::{Rig, State};
use nalgebra::DVector;
use rayon::prelude::*;
use std::sync::Arc;

/// What the base fit found, for the steps after it.
pub(super) struct Base {
    pub(super) problem: TrajectoryProblem,
    pub(super) p: DVector<f64>,
    pub(super) starts: Vec<StartOutcome>,
    pub(super) iterations: u64,
    /// mu_static estimated from the data's stick-to-slide onsets.
    pub(super) mu_s_data: Option<f64>,
    /// Whether the onset estimate says mu_static exceeds mu_kinetic (`None`: no onset seen).
    pub(super) static_evidence: Option<bool>,
    /// The initial state guessed from the first frames (the start of every fit).
    pub(super) y0_guess: State<f64>,
    /// mu_kinetic from the data (the main start).
    pub(super) mu0: f64,
    /// How the last fit over the whole of a long recording stopped, when nothing changed
    /// after it (it need not be polished again).
    pub(super) settled: Option<String>,
}

/// What the recording says before any fit.
struct Guesses {
    /// The initial state from the first frames.
    y0: State<f64>,
    /// x'(0) is within 3 standard errors of 0.
    at_rest: bool,
    /// mu_kinetic from the sliding accelerations, or the rig's guess.
    mu0: f64,
    /// mu_static from the stick-to-slide onsets (`--mu-static auto` only).
    mu_s_data: Option<f64>,
    /// Whether the onsets say mu_static exceeds mu_kinetic (`None`: no onset seen).
    static_evidence: Option<bool>,
}

/// The initial state, mu and mu_static from the data; a warning when the markers' distance
/// disagrees with the rig's rod length.
fn guesses(
    obs: &Observations,
    rig: &Rig<f64>,
    settings: &FitSettings,
    warnings: &mut Vec<String>,
) -> Guesses {
    let n = obs.times.len();
    let dt = (obs.times[n - 1] / (n - 1) as f64).max(1e-6);
    let window = ((0.012 / dt).round() as usize).clamp(5, 40);
    let (y0, x_dot_se) = guess::initial_state(obs, window).unwrap_or(([0.0; 4], f64::INFINITY));
    if let Some(l) = guess::rod_length(obs) {
        if (l - rig.marker_length).abs() > 0.05 * rig.marker_length {
            warnings.push(format!(
                "the markers are {l:.4} m apart (median) but the rig says rod_length = {:.4} m: check the scale or the rig",
                rig.marker_length
            ));
        }
    }
    // Second derivatives need a wider window than the initial slope: about 40 ms each side.
    let mu_data = guess::mu_from_sliding(obs, rig, ((0.04 / dt).round() as usize).clamp(4, 200));
    let mu_s_data = (settings.mu_static == StaticMode::Auto)
        .then(|| {
            guess::mu_static_from_onsets(obs, rig, ((0.01 / dt).round() as usize).clamp(3, 50))
        })
        .flatten();
    let static_evidence =
        mu_s_data.map(|m| m > 1.25 * rig.mu_kinetic.min(mu_data.unwrap_or(f64::INFINITY)));
    Guesses {
        y0,
        at_rest: y0[2].abs() < 3.0 * x_dot_se,
        mu0: mu_data.unwrap_or(rig.mu_kinetic),
        mu_s_data,
        static_evidence,
    }
}

/// The candidate models, in order, and the one with x'(0) free. Released from rest, x'(0) = 0
/// exactly: the motion may start stuck, which no small nonzero x'(0) reproduces. Both starts
/// compete: a release from rest looks like a moving start within a few noisy frames (the
/// slider accelerates at once), and a wrong x'(0) is a deep local minimum. mu_static joins
/// when the onsets demand it.
fn candidates(
    problem: &TrajectoryProblem,
    g: &Guesses,
) -> (Vec<TrajectoryProblem>, TrajectoryProblem) {
    let free_model = problem.clone();
    let mut rest = problem.clone();
    rest.free.retain(|&q| q != Param::XDot);
    rest.initial[2] = 0.0;
    let mut out = Vec::new();
    if g.at_rest {
        out.push(rest.clone());
        if let (Some(mu_s), Some(true)) = (g.mu_s_data, g.static_evidence) {
            let mut m = rest.clone();
            m.free.push(Param::MuStatic);
            m.tie_static = false;
            m.rig.mu_static = mu_s;
            out.push(m);
        }
        out.push(free_model.clone());
    } else {
        out.push(free_model.clone());
        out.push(rest);
    }
    (out, free_model)
}

/// The starts (candidate, mu): the data's mu for every candidate, and for the first the rig's,
/// a low one (a start above the truth can stall in a motion that never slides, where mu has no
/// gradient) and the user's. The far starts go first: they take the most iterations.
fn starts(
    rig: &Rig<f64>,
    mu0: f64,
    settings: &FitSettings,
    n_candidates: usize,
) -> Vec<(usize, f64)> {
    let mut jobs: Vec<(usize, f64)> = Vec::new();
    for mu in [rig.mu_kinetic, 0.4 * mu0]
        .into_iter()
        .chain(settings.extra_starts.iter().copied())
    {
        if (mu - mu0).abs() > 1e-3 * mu0.abs().max(1e-3)
            && !jobs
                .iter()
                .any(|j| (j.1 - mu).abs() < 1e-3 * mu.abs().max(1e-3))
        {
            jobs.push((0, mu));
        }
    }
    jobs.extend((0..n_candidates).map(|m| (m, mu0)));
    jobs
}

/// Akaike's criterion chi2 + 2k of an optimum `p` with cost `c` (half the chi-square).
fn aic(p: &DVector<f64>, c: f64) -> f64 {
    2.0 * c + 2.0 * p.len() as f64
}

/// The best start by AIC.
struct Best {
    choice: usize,
    p: DVector<f64>,
    cost: f64,
    outcomes: Vec<StartOutcome>,
    iterations: u64,
}

/// Every start solved (in parallel), stopping at `ftol` when given; the best by AIC.
fn best_start(
    candidates: &[TrajectoryProblem],
    jobs: &[(usize, f64)],
    settings: &FitSettings,
    ftol: Option<f64>,
) -> Result<Best, FitError> {
    let start_values = |m: &TrajectoryProblem, mu: f64| {
        let mut p0 = m.values();
        p0[0] = mu;
        if let Some(i) = m.free.iter().position(|&q| q == Param::MuStatic) {
            p0[i] = p0[i].max(mu);
        }
        p0
    };
    let solved: Vec<(usize, f64, Solved)> = jobs
        .par_iter()
        .with_max_len(1)
        .map(|&(m, mu)| {
            let c = &candidates[m];
            (
                m,
                mu,
                solve_loose(c, start_values(c, mu), settings.max_iters, ftol),
            )
        })
        .collect();
    let mut outcomes = Vec::new();
    let mut last_err = String::new();
    let mut iterations = 0;
    let mut best: Option<(usize, DVector<f64>, f64)> = None;
    for (m, mu, r) in solved {
        match r {
            Ok((p, c, it)) => {
                iterations += it;
                outcomes.push(StartOutcome {
                    mu_start: mu,
                    mu_end: p[0],
                    cost: c,
                });
                if best
                    .as_ref()
                    .is_none_or(|(_, bp, bc)| aic(&p, c) < aic(bp, *bc))
                {
                    best = Some((m, p, c));
                }
            }
            Err(e) => last_err = e,
        }
    }
    let (choice, p, cost) = best.ok_or(FitError::NoStart(last_err))?;
    Ok(Best {
        choice,
        p,
        cost,
        outcomes,
        iterations,
    })
}

/// A release judged "from rest" whose fit leaves structured residuals (lag-1 autocorrelation
/// above 0.3) may have had a small push: then the model with x'(0) free competes too. Returns
/// the model and optimum kept.
fn push_check(
    problem: TrajectoryProblem,
    best: &mut Best,
    free_model: TrajectoryProblem,
    settings: &FitSettings,
    ftol: Option<f64>,
) -> TrajectoryProblem {
    let rho = problem
        .residuals(&best.p)
        .map(|r| uncertainty::lag1(&problem, r.as_slice()));
    if !rho.is_ok_and(|rho| rho > 0.3) {
        return problem;
    }
    let mut p0 = free_model.values();
    p0[0] = best.p[0];
    let Ok((q, c, it)) = solve_loose(&free_model, p0, settings.max_iters, ftol) else {
        return problem;
    };
    best.iterations += it;
    best.outcomes.push(StartOutcome {
        mu_start: best.p[0],
        mu_end: q[0],
        cost: c,
    });
    if aic(&q, c) < aic(&best.p, best.cost) {
        best.p = q;
        best.cost = c;
        return free_model;
    }
    problem
}

/// A long recording's fit of its first frames carried over the whole recording by doubling
/// the length, each fit starting where the shorter one ended (a stage before the last only has
/// to start the next one well). Returns the whole recording's problem, its optimum, the
/// iterations and how the last fit stopped.
fn carry_over(
    mut problem: TrajectoryProblem,
    mut p: DVector<f64>,
    obs: &Arc<Observations>,
    prefix: usize,
    settings: &FitSettings,
) -> Result<(TrajectoryProblem, DVector<f64>, u64, String), FitError> {
    let n = obs.times.len();
    let mut len = prefix;
    let mut iterations = 0;
    let mut reason = String::new();
    while len < n {
        // Doubling, without a last stage much shorter than the one before it.
        len = if 3 * len >= n { n } else { 2 * len };
        let stage = problem.on_prefix(obs.clone(), len);
        let mut lm = LevenbergMarquardt::default();
        if len < n {
            (lm.ftol, lm.fatol, lm.xtol) = (STAGE_FTOL, f64::INFINITY, STAGE_FTOL);
        }
        let (q, _, it, why) = run_lm(&stage, p, settings.max_iters, lm).map_err(|e| {
            FitError::NoStart(format!(
                "carrying the fit of the first {} frames over {len}: {e}",
                problem.frame_times().len()
            ))
        })?;
        iterations += it;
        reason = why;
        p = q;
        problem = stage;
    }
    Ok((problem, p, iterations, reason))
}

/// A robust loss reweights the rows by their standardised residuals, a few rounds. Returns
/// the iterations.
fn reweight(problem: &mut TrajectoryProblem, p: &mut DVector<f64>, settings: &FitSettings) -> u64 {
    let mut iterations = 0;
    for _ in 0..3 {
        let Ok(raw) = problem.raw_residuals(p) else {
            break;
        };
        let weights = problem
            .rows()
            .zip(&raw)
            .map(|(row, &r)| {
                let z = (r / problem.sigma[row.marker]).abs();
                match settings.loss {
                    Loss::Squares => 1.0,
                    Loss::Huber(k) if z > k => (k / z).sqrt(),
                    Loss::Huber(_) => 1.0,
                    Loss::Cauchy(k) => (1.0 / (1.0 + (z / k).powi(2))).sqrt(),
                }
            })
            .collect();
        problem.set_row_weights(weights);
        if let Ok((q, _, it)) = solve(problem, p.clone(), settings.max_iters) {
            iterations += it;
            *p = q;
            problem.set_values(p);
        }
    }
    iterations
}

/// The base model of [`super::fit`] from several starts, the best by AIC. A long
/// recording's starts and candidates are fitted on its first frames, and the winner carried
/// over the whole recording ([`carry_over`]): a few full-length fits instead of one per
/// start, and a start that never meets a far-off part of the recording whose events it cannot
/// yet match.
pub(super) fn fit(
    obs: &Arc<Observations>,
    rig: &Rig<f64>,
    sigma: [f64; 2],
    frame: f64,
    settings: &FitSettings,
    warnings: &mut Vec<String>,
) -> Result<Base, FitError> {
    let n = obs.times.len();
    let g = guesses(obs, rig, settings, warnings);
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
    let prefix = settings.long_prefix.max(1);
    let long = n > prefix.saturating_mul(2);
    let fit_obs = if long {
        Arc::new(obs.prefix(prefix))
    } else {
        obs.clone()
    };
    let mut problem = TrajectoryProblem::new(fit_obs, *rig, g.y0, free, settings.options);
    problem.tie_static = settings.mu_static != StaticMode::Fixed;
    problem.sigma = sigma;
    let (mut models, free_model) = candidates(&problem, &g);
    let jobs = starts(rig, g.mu0, settings, models.len());
    // A long recording's starts only pick the model and basin the doubling stages refine:
    // they stop where a stage before the last does.
    let ftol = long.then_some(STAGE_FTOL);
    let mut best = best_start(&models, &jobs, settings, ftol)?;
    problem = models.swap_remove(best.choice);
    if g.at_rest {
        problem = push_check(problem, &mut best, free_model, settings, ftol);
    }
    let mut p = best.p.clone();
    let mut iterations = best.iterations;
    // The whole recording's fit, converged: nothing to polish unless the model or the
    // weights change after it.
    let mut settled = None;
    if long {
        // The rig file's priors and freed measurements taken now, so that the doubling stages
        // fit them on the way: the measured-rig stage then has nothing left to refit over
        // the whole recording.
        problem.set_values(&p);
        if super::stages::apply_measured(&mut problem, frame, settings) {
            p = problem.values();
        }
        let (whole, q, it, reason) = carry_over(problem, p, obs, prefix, settings)?;
        (problem, p, settled) = (whole, q, Some(reason));
        iterations += it;
    }
    problem.set_values(&p);
    if settings.loss != Loss::Squares {
        settled = None;
        iterations += reweight(&mut problem, &mut p, settings);
    }
    Ok(Base {
        problem,
        p,
        starts: best.outcomes,
        iterations,
        mu_s_data: g.mu_s_data,
        static_evidence: g.static_evidence,
        y0_guess: g.y0,
        mu0: g.mu0,
        settled,
    })
}
