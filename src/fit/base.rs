//! The base model (mu_kinetic and the initial state; released from rest or moving; mu_static
//! when the onsets demand it), fitted from several starts in mu, the best by AIC: what the
//! data say before any fit ([`guesses`]), the candidate models ([`candidates`]), the starts
//! ([`starts`]) and their best ([`best_start`]), a release from rest that had a push
//! ([`push_check`]), a long recording carried over by doubling ([`carry_over`]) and a robust
//! loss's reweighting ([`reweight`]).

use super::error::FitError;
use super::outcome::StartOutcome;
use super::problem::{Observations, Param, TrajectoryProblem};
use super::settings::{FitSettings, Loss, StaticMode};
use super::solve::{at_iteration_limit, loose, run_lm, run_lm_damped, solve, Traced, STAGE_FTOL};
use super::{guess, uncertainty};
use crate::fit::lm::LevenbergMarquardt;
use crate::model::{Rig, State};
use nalgebra::DVector;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

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
    let tracks = guess::Tracks::new(obs);
    let (y0, x_dot_se) = guess::initial_state(&tracks, window).unwrap_or(([0.0; 4], f64::INFINITY));
    if let Some(l) = guess::rod_length(obs) {
        if (l - rig.marker_length).abs() > 0.05 * rig.marker_length {
            warnings.push(format!(
                "the markers are {l:.4} m apart (median) but the rig says rod_length = {:.4} m: check the scale or the rig",
                rig.marker_length
            ));
        }
    }
    // Second derivatives need a wider window than the initial slope: about 40 ms each side.
    // The two reads of the tracks are independent: side by side on the pool.
    let (mu_data, mu_s_data) = rayon::join(
        || guess::mu_from_sliding(&tracks, rig, ((0.04 / dt).round() as usize).clamp(4, 200)),
        || {
            (settings.mu_static == StaticMode::Auto)
                .then(|| {
                    let h = ((0.01 / dt).round() as usize).clamp(3, 50);
                    guess::mu_static_from_onsets(&tracks, rig, h)
                })
                .flatten()
        },
    );
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

/// The starts (model, mu): the data's mu for every candidate, and probes of the first
/// candidate at the rig's mu, a low one (a start above the truth can stall in a motion that
/// never slides, where mu has no gradient) and the user's. The costliest go first (the
/// candidate with the most parameters free, then the others, then the probes), so that the
/// queue ([`queue`]) ends with the cheap ones.
fn starts(
    rig: &Rig<f64>,
    mu0: f64,
    settings: &FitSettings,
    candidates: &[TrajectoryProblem],
) -> Vec<Job> {
    let mut order: Vec<usize> = (0..candidates.len()).collect();
    order.sort_by_key(|&i| std::cmp::Reverse(candidates[i].free.len()));
    let mut jobs: Vec<Job> = order
        .into_iter()
        .map(|i| (Model::Candidate(i), mu0))
        .collect();
    let mut far: Vec<f64> = Vec::new();
    for mu in [0.4 * mu0, rig.mu_kinetic]
        .into_iter()
        .chain(settings.extra_starts.iter().copied())
    {
        if (mu - mu0).abs() > 1e-3 * mu0.abs().max(1e-3)
            && !far
                .iter()
                .any(|f| (f - mu).abs() < 1e-3 * mu.abs().max(1e-3))
        {
            far.push(mu);
        }
    }
    jobs.extend(far.into_iter().map(|mu| (Model::Probe, mu)));
    jobs
}

/// `f` of every job, the jobs handed out in order to whichever thread is free (a queue), the
/// results in the jobs' order. rayon's halving of a slice would pair the first two jobs on one
/// thread and the last two on the other: with the costliest first, a queue balances better.
fn queue<J: Sync, R: Send>(jobs: &[J], f: impl Fn(&J) -> R + Sync) -> Vec<R> {
    let next = AtomicUsize::new(0);
    let done = Mutex::new(Vec::with_capacity(jobs.len()));
    rayon::scope(|s| {
        for _ in 0..rayon::current_num_threads().min(jobs.len()) {
            s.spawn(|_| loop {
                let i = next.fetch_add(1, Ordering::Relaxed);
                let Some(job) = jobs.get(i) else { break };
                let r = f(job);
                done.lock().unwrap_or_else(|e| e.into_inner()).push((i, r));
            });
        }
    });
    let mut done = done.into_inner().unwrap_or_else(|e| e.into_inner());
    done.sort_by_key(|d| d.0);
    done.into_iter().map(|d| d.1).collect()
}

/// Akaike's criterion chi2 + 2k of an optimum `p` with cost `c` (half the chi-square).
fn aic(p: &DVector<f64>, c: f64) -> f64 {
    2.0 * c + 2.0 * p.len() as f64
}

/// The best start by AIC.
struct Best {
    choice: usize,
    p: DVector<f64>,
    /// Infinite when no candidate's start converged (a probe's basin is then refitted).
    cost: f64,
    outcomes: Vec<StartOutcome>,
    iterations: u64,
    /// The probes' lowest-cost optimum and its cost ([`refit_probe`]).
    probe: Option<(DVector<f64>, f64)>,
    /// Why the best start's solve stopped.
    reason: String,
}

/// The model a start fits.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Model {
    /// A candidate model (its index).
    Candidate(usize),
    /// The first candidate without the rig file's freed measurements: a start far from the
    /// data's mu only probes for another basin, and converges there in fewer runs with fewer
    /// parameters free (the same as the first candidate when the rig file frees none).
    Probe,
}

/// A start: its model and mu.
type Job = (Model, f64);

/// Every start solved (in parallel), stopping at `ftol` when given; the best by AIC among
/// the candidates' starts, and the probes' best ([`Best::probe`]) apart. When the recording's
/// slider clearly `moves`, a probe that leaves mu without a gradient (the model never slides
/// there) is left where it is: it cannot learn mu, and a motion that never slides loses to
/// one that does.
fn best_start(
    candidates: &[TrajectoryProblem],
    probe: Option<&TrajectoryProblem>,
    jobs: &[Job],
    settings: &FitSettings,
    ftol: Option<f64>,
    moves: bool,
) -> Result<Best, FitError> {
    let start_values = |m: &TrajectoryProblem, mu: f64| {
        let mut p0 = m.values();
        p0[0] = mu;
        if let Some(i) = m.free.iter().position(|&q| q == Param::MuStatic) {
            p0[i] = p0[i].max(mu);
        }
        p0
    };
    let solved: Vec<(Model, f64, Traced)> = queue(jobs, |&(m, mu)| {
        let c = match m {
            Model::Candidate(i) => &candidates[i],
            Model::Probe => probe.unwrap_or(&candidates[0]),
        };
        // A probe apart from the candidates only looks for another basin: it stops where a
        // stage before the last does (a probe refitted is solved to the end then).
        let probing = m == Model::Probe && probe.is_some();
        let mut lm = loose(if probing { Some(STAGE_FTOL) } else { ftol });
        if moves && m == Model::Probe {
            lm.flat_exit = Some(0);
        }
        (
            m,
            mu,
            run_lm(c, start_values(c, mu), settings.max_iters, lm),
        )
    });
    let mut outcomes = Vec::new();
    let mut last_err = String::new();
    let mut iterations = 0;
    let mut best: Option<(usize, DVector<f64>, f64, String)> = None;
    let mut probe_best: Option<(DVector<f64>, f64)> = None;
    for (m, mu, r) in solved {
        match r {
            Ok((p, c, it, why)) => {
                iterations += it;
                outcomes.push(StartOutcome {
                    mu_start: mu,
                    mu_end: p[0],
                    cost: c,
                });
                let choice = match m {
                    Model::Candidate(i) => i,
                    Model::Probe if probe.is_none() => 0,
                    Model::Probe => {
                        if probe_best.as_ref().is_none_or(|(_, bc)| c < *bc) {
                            probe_best = Some((p, c));
                        }
                        continue;
                    }
                };
                if best
                    .as_ref()
                    .is_none_or(|(_, bp, bc, _)| aic(&p, c) < aic(bp, *bc))
                {
                    best = Some((choice, p, c, why));
                }
            }
            Err(e) => last_err = e,
        }
    }
    let (choice, p, cost, reason) = match best {
        Some(b) => b,
        // Only a probe converged: no candidate's optimum yet, the probe's refit decides.
        None if probe_best.is_some() => (0, DVector::zeros(0), f64::INFINITY, String::new()),
        None => return Err(FitError::NoStart(last_err)),
    };
    Ok(Best {
        choice,
        p,
        cost,
        outcomes,
        iterations,
        probe: probe_best,
        reason,
    })
}

/// A probe's optimum (`p` on `probe`) clearly lower in cost than the best start's: its basin refitted
/// on the first candidate, the rig file's measurements freed again, and kept when it wins by
/// AIC. The measured model nests the probe's (its measurements at the file's values), so in
/// the same basin its optimum is never higher: a probe below the best start found another
/// basin.
fn refit_probe(
    candidate: &TrajectoryProblem,
    probe: &TrajectoryProblem,
    best: &mut Best,
    settings: &FitSettings,
    ftol: Option<f64>,
) {
    let Some((p, c)) = best.probe.take() else {
        return;
    };
    // Lower by a chi-square of 2 at least: less is the candidates' stopping tolerance, or a
    // basin no better than theirs (its outcome still counts where the starts are compared).
    if c + 1.0 >= best.cost {
        return;
    }
    let mut at = probe.clone();
    at.set_values(&p);
    let mut m = candidate.clone();
    (m.rig, m.initial) = (at.rig, at.initial);
    if compete(best, &m, m.values(), settings, ftol) {
        best.choice = 0;
    }
}

/// `model` solved from `p0`, its outcome recorded, and kept as the best when it wins by AIC
/// (always, when no start has converged: the best's cost is then infinite). Returns whether
/// it won.
fn compete(
    best: &mut Best,
    model: &TrajectoryProblem,
    p0: DVector<f64>,
    settings: &FitSettings,
    ftol: Option<f64>,
) -> bool {
    let mu_start = p0[0];
    let Ok((q, c, it, why)) = run_lm(model, p0, settings.max_iters, loose(ftol)) else {
        return false;
    };
    best.iterations += it;
    best.outcomes.push(StartOutcome {
        mu_start,
        mu_end: q[0],
        cost: c,
    });
    let wins = aic(&q, c) < aic(&best.p, best.cost);
    if wins {
        (best.p, best.cost, best.reason) = (q, c, why);
    }
    wins
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
    if compete(best, &free_model, p0, settings, ftol) {
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
    let mut damping: Option<f64> = None;
    while len < n {
        // Doubling, without a last stage much shorter than the one before it.
        len = if 3 * len >= n { n } else { 2 * len };
        let stage = problem.on_prefix(obs.clone(), len);
        let mut lm = LevenbergMarquardt::default();
        if len < n {
            (lm.ftol, lm.fatol, lm.xtol) = (STAGE_FTOL, f64::INFINITY, STAGE_FTOL);
        }
        // Each stage fits nearly the problem the last one did: it starts from that one's
        // damping, never above the default (a stage that stalled ends heavily damped) nor
        // below 1e-9, which leaves any step a fit can take undamped (a curvature that small
        // relative to the diagonal is a parameter the data do not fix) and, should the
        // next stage's first step fail, is undone in a few trials (each doubles the factor).
        if let Some(d) = damping {
            let cold = LevenbergMarquardt::default().damping();
            // max and min, not clamp: clamp's panic path alone moved the one-unit build's
            // inlining (3 % more instructions in the example's plain fit, in the simulator).
            lm = lm.with_damping(d.max(1e-9).min(cold));
        }
        let ((q, _, it, why), d) =
            run_lm_damped(&stage, p, settings.max_iters, lm).map_err(|e| {
                FitError::NoStart(format!(
                    "carrying the fit of the first {} frames over {len}: {e}",
                    problem.frame_times().len()
                ))
            })?;
        iterations += it;
        reason = why;
        damping = Some(d);
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
    // The starts' data move: a start whose model never slides there is hopeless.
    let moves = super::motion::slider_moves(&fit_obs, sigma[0]).is_some();
    let mut problem = TrajectoryProblem::new(fit_obs, *rig, g.y0, free, settings.options);
    problem.tie_static = settings.mu_static != StaticMode::Fixed;
    problem.sigma = sigma;
    // Frame times are a measurement too: their scatter about a uniform grid weighs each row.
    let sigma_t = super::noise::frame_time_noise(&obs.times);
    if problem.set_time_noise(sigma_t) {
        warnings.push(format!(
            "the frame times scatter by {:.3} ms about their frame rate's uniform grid (timestamps rounded or jittered): a marker moving at v is off by v times that, and each position is weighted for it",
            1e3 * sigma_t
        ));
    }
    // A short recording's candidates take the rig file's priors and freed measurements now,
    // so the measured-rig stage has nothing left to refit; its probes go without them.
    let plain = problem.clone();
    let freed = !long && super::rig_priors::apply_measured(&mut problem, frame, settings);
    let (mut models, free_model) = candidates(&problem, &g);
    let probe = freed.then(|| candidates(&plain, &g).0.swap_remove(0));
    let jobs = starts(rig, g.mu0, settings, &models);
    // A long recording's starts only pick the model and basin the doubling stages refine:
    // they stop where a stage before the last does.
    let ftol = long.then_some(STAGE_FTOL);
    let mut best = best_start(&models, probe.as_ref(), &jobs, settings, ftol, moves)?;
    if let Some(probe) = &probe {
        refit_probe(&models[0], probe, &mut best, settings, ftol);
    }
    if !best.cost.is_finite() {
        return Err(FitError::NoStart("no start converged".into()));
    }
    problem = models.swap_remove(best.choice);
    if g.at_rest {
        problem = push_check(problem, &mut best, free_model, settings, ftol);
    }
    let mut p = best.p.clone();
    let mut iterations = best.iterations;
    // The whole recording's fit, converged: nothing to polish unless the model or the
    // weights change after it. A short recording's best start was solved to the full
    // tolerance on it already.
    let mut settled = (!long && !at_iteration_limit(&best.reason)).then(|| best.reason.clone());
    if long {
        // The rig file's priors and freed measurements taken now, so that the doubling stages
        // fit them on the way: the measured-rig stage then has nothing left to refit over
        // the whole recording.
        problem.set_values(&p);
        if super::rig_priors::apply_measured(&mut problem, frame, settings) {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::lm::LeastSquares;

    /// The paper scene's recording (the truth: mu = 0.35) as a probe's model (mu and the
    /// initial state free) and a candidate's (the rod length and mass ratio too).
    fn models() -> (TrajectoryProblem, TrajectoryProblem) {
        let probe = crate::fit::test_support::paper_problem(5);
        let mut candidate = probe.clone();
        candidate.free.extend([Param::RodLength, Param::MassRatio]);
        // A ruler's and a scale's deviations, as a rig file's defaults are.
        let (l, r) = (
            candidate.get(Param::RodLength),
            candidate.get(Param::MassRatio),
        );
        candidate.priors = Arc::new(vec![
            crate::fit::priors::Prior {
                param: Param::RodLength,
                centre: l,
                sd: 1e-3,
            },
            crate::fit::priors::Prior {
                param: Param::MassRatio,
                centre: r,
                sd: 0.03 * r,
            },
        ]);
        (probe, candidate)
    }

    /// The queue gives every job's result in the jobs' order, whichever thread finished
    /// first (the first job here takes longest).
    #[test]
    fn the_queue_keeps_the_jobs_order() {
        let jobs = [30u64, 1, 5, 0, 2];
        let out = queue(&jobs, |&ms| {
            std::thread::sleep(std::time::Duration::from_millis(ms));
            ms * 10
        });
        assert_eq!(out, vec![300, 10, 50, 0, 20]);
        assert!(queue(&[] as &[u64], |&x| x).is_empty());
    }

    /// A probe ending clearly below the best candidate start (here a start left far off, at
    /// mu = 0.05) is refitted on the candidate from the probe's optimum, with the
    /// measurements free, and wins: the candidate's model nests the probe's, so its optimum
    /// is no higher. A probe not clearly lower (less than a chi-square of 2) changes nothing.
    #[test]
    fn a_probe_below_the_candidates_is_refitted_and_wins() {
        let (probe, candidate) = models();
        let settings = FitSettings::default();
        let (pp, pc, _) = solve(&probe, probe.values(), settings.max_iters).unwrap();
        let mut far = candidate.values();
        far[0] = 0.05;
        let far_cost = candidate.normal_equations(&far).unwrap().cost;
        let best = |cost: f64| Best {
            choice: 1,
            p: far.clone(),
            cost,
            outcomes: Vec::new(),
            iterations: 0,
            probe: Some((pp.clone(), pc)),
            reason: "far".into(),
        };
        assert!(far_cost > pc + 1.0, "{far_cost} {pc}");
        let mut b = best(far_cost);
        refit_probe(&candidate, &probe, &mut b, &settings, None);
        assert_eq!((b.choice, b.p.len(), b.outcomes.len()), (0, 6, 1));
        assert!(b.cost <= pc + 1e-6, "{} above the probe's {pc}", b.cost);
        assert!((b.p[0] - 0.35).abs() < 0.005, "mu {}", b.p[0]);
        assert!(!at_iteration_limit(&b.reason) && b.reason != "far");
        let mut tied = best(pc + 0.5);
        refit_probe(&candidate, &probe, &mut tied, &settings, None);
        assert_eq!((tied.choice, tied.outcomes.len()), (1, 0));
        assert!(tied.p == far && tied.probe.is_none());
    }
}
