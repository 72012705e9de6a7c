//! One candidate model fitted: from its own start and the data's, retried when a nested model
//! ends worse than the model it extends, and marked failed when it still does.

use super::candidate::Candidate;
use super::selection::{chi2_of, ModelRow, SelectOptions};
use crate::fit::problem::Param;
use crate::fit::solve::{solve_loose, Solved, STAGE_FTOL};
use nalgebra::DVector;
use std::cell::Cell;

/// A candidate's fit: to a relative cost decrease of [`STAGE_FTOL`], which settles its
/// chi-square to far below a unit (the criterion's differences that matter are units), while
/// the last digits cost as many iterations again. The chosen model is polished after the
/// selection.
fn solve_candidate<M: Candidate>(m: &M, p0: DVector<f64>, max_iters: u64) -> Solved {
    solve_loose(m, p0, max_iters, Some(STAGE_FTOL))
}

/// The cost (half the chi-square) within which a law weighed on the chosen model's other
/// nuisances is converged for the comparison: a full Gauss-Newton step predicted to lower its
/// chi-square by less than a tenth of a unit cannot move it across any of
/// the criterion's lines (2 to take a law, 6 to call two laws a tie). Stribeck's law on a
/// recording without it crawled 38-45 iterations along a flat valley to a relative 1e-6 for
/// no change of its criterion.
const LAW_COST_TOL: f64 = 0.05;

/// Solve `m` as the laws are weighed: as a candidate, stopped once the full Gauss-Newton step
/// is predicted to lower the cost by less than [`LAW_COST_TOL`], or once the law cannot come
/// within reach (`reach`: the chi-square the law must reach to matter; +inf: no such stop).
/// Whether it stopped out of reach is returned too (its chi-square is then an upper bound).
fn solve_law<M: Candidate>(m: &M, p0: DVector<f64>, max_iters: u64, reach: f64) -> (Solved, bool) {
    let mut lm = crate::fit::solve::loose(Some(STAGE_FTOL));
    lm.gn_tol = LAW_COST_TOL;
    lm.reach_floor = 0.5 * reach;
    match crate::fit::solve::run_lm(m, p0, max_iters, lm) {
        Ok((p, c, i, why)) => (Ok((p, c, i)), why == crate::fit::lm::OUT_OF_REACH),
        Err(e) => (Err(e), false),
    }
}

/// How a candidate's solves stop: to the selection's relative tolerance, or to the laws'
/// absolute one (and out of reach below the chi-square given).
#[derive(Clone, Copy)]
enum Tol {
    Stage,
    Law(f64),
}

impl Tol {
    /// The solve, and whether it stopped short of an optimum (out of reach).
    fn solve<M: Candidate>(self, m: &M, p0: DVector<f64>, max_iters: u64) -> (Solved, bool) {
        match self {
            Tol::Stage => (solve_candidate(m, p0, max_iters), false),
            Tol::Law(reach) => solve_law(m, p0, max_iters, reach),
        }
    }
}

/// Solve `m` from its values and, when `fresh` is given, also from a restart; the lower
/// cost wins. Iterations of both count. `capped` is set when a solve used all `max_iters`.
fn solve_starts<M: Candidate>(
    m: &M,
    fresh: Option<&M::Start>,
    max_iters: u64,
    capped: &Cell<bool>,
    tol: Tol,
) -> Solved {
    let solve = |m: &M| {
        let (got, short) = tol.solve(m, m.values(), max_iters);
        if short || got.as_ref().is_ok_and(|g| g.2 >= max_iters) {
            capped.set(true);
        }
        got
    };
    let a = solve(m);
    let Some(start) = fresh else {
        return a;
    };
    better(a, solve(&m.restarted(start)))
}

/// Under misfit, when a candidate's best fit `got` moved a measured rig value beyond 3 of its
/// deviations, one more start: the restart from `fresh` with the rig's values held until the
/// nuisance has settled, then released (freed from the first, they can take up the misfit on
/// the way: a one-slide release on a tilted rail put its mass ratio 11 % off the scale's
/// value, a local optimum 16 chi-square units above this one). The lower cost wins.
pub(super) fn held_rig_start<M: Candidate>(
    m: &M,
    fresh: &M::Start,
    got: (DVector<f64>, f64, u64),
    max_iters: u64,
) -> (DVector<f64>, f64, u64) {
    if !m.rig_moved(&got.0) {
        return got;
    }
    let Some(held) = m.restarted(fresh).rig_held() else {
        return got;
    };
    let Ok((q, _, it)) = solve_candidate(&held, held.values(), max_iters) else {
        return got;
    };
    let mut settled = held.clone();
    settled.set_values(&q);
    let full = m.adopt(&settled);
    let (p, cost, iters) = got;
    match solve_candidate(&full, full.values(), max_iters) {
        Ok((q, c, i)) if c < cost => (q, c, iters + it + i),
        Ok((_, _, i)) => (p, cost, iters + it + i),
        Err(_) => (p, cost, iters + it),
    }
}

/// The lower-cost of two solves (the iterations of both counted).
fn better(a: Solved, b: Solved) -> Solved {
    match (a, b) {
        (Ok(x), Ok(y)) => {
            let iters = x.2 + y.2;
            let (p, c) = if y.1 < x.1 { (y.0, y.1) } else { (x.0, x.1) };
            Ok((p, c, iters))
        }
        (Ok(x), Err(_)) => Ok(x),
        (Err(_), b) => b,
    }
}

/// Chi-square a candidate may end above the model it nests and still count as converged:
/// the solvers' stopping tolerance, with a floor of one unit.
fn nested_slack(parent_chi2: f64) -> f64 {
    (1e-4 * parent_chi2).max(1.0)
}

/// A failed candidate: why, the chi-square it reached (NaN when none) and the iterations.
pub(super) type Failure = (String, f64, u64);

/// A candidate's fit: its optimum, cost and iterations, or why it failed.
pub(super) type Outcome = Result<(DVector<f64>, f64, u64), Failure>;

/// Fit candidate `m` from its own start (and `fresh` when given). A candidate that nests the
/// current model (`parent`: that model's chi-square) yet ends worse than it has not converged:
/// it is retried, longer and from the data's start, and is a failure when it still ends
/// worse (it is then no evidence about the nuisance, and must not be compared as if it were).
pub(super) fn fit_candidate<M: Candidate>(
    m: &M,
    fresh: Option<&M::Start>,
    opts: &SelectOptions<M::Start>,
    parent: Option<f64>,
) -> Outcome {
    fit_candidate_within(m, fresh, opts, parent, opts.max_iters).0
}

/// [`fit_candidate`] with at most `max_iters` iterations a start (twice that for a retry),
/// and whether a start used them all (its chi-square is then only an upper bound).
pub(super) fn fit_candidate_within<M: Candidate>(
    m: &M,
    fresh: Option<&M::Start>,
    opts: &SelectOptions<M::Start>,
    parent: Option<f64>,
    max_iters: u64,
) -> (Outcome, bool) {
    let capped = Cell::new(false);
    let got = fit_capped(m, fresh, opts, parent, max_iters, &capped, Tol::Stage);
    (got, capped.get())
}

/// [`fit_candidate`] for a law weighed on the chosen model's other nuisances: its solves stop
/// at [`LAW_COST_TOL`], or out of reach above the chi-square `reach` ([`solve_law`]); whether
/// a start used every iteration or stopped out of reach is returned too.
pub(super) fn fit_law<M: Candidate>(
    m: &M,
    opts: &SelectOptions<M::Start>,
    parent: Option<f64>,
    reach: f64,
) -> (Outcome, bool) {
    let capped = Cell::new(false);
    let got = fit_capped(
        m,
        None,
        opts,
        parent,
        opts.max_iters,
        &capped,
        Tol::Law(reach),
    );
    (got, capped.get())
}

fn fit_capped<M: Candidate>(
    m: &M,
    fresh: Option<&M::Start>,
    opts: &SelectOptions<M::Start>,
    parent: Option<f64>,
    max_iters: u64,
    capped: &Cell<bool>,
    tol: Tol,
) -> Outcome {
    let worse = |cost: f64| parent.is_some_and(|c| chi2_of(cost) > c + nested_slack(c));
    let first = solve_starts(m, fresh, max_iters, capped, tol);
    // A law that used every iteration or stopped out of reach is left where it stopped (its
    // chi-square an upper bound, marked so by the weighing, which does not let it take the
    // model).
    if matches!(tol, Tol::Law(_)) && capped.get() {
        return first.map_err(|e| (e, f64::NAN, max_iters));
    }
    let (mut best, mut iters) = match first {
        Ok((q, cost, it)) if !worse(cost) => return Ok((q, cost, it)),
        Ok((q, cost, it)) => (Some((q, cost)), it),
        Err(e) if parent.is_none() => return Err((e, f64::NAN, 0)),
        Err(_) => (None, 0),
    };
    // The retries: on from where the first fit stopped with twice the iterations, and from
    // the data's start when the first fit did not use it.
    let mut retries: Vec<(M, DVector<f64>)> = Vec::new();
    if let Some((q, _)) = &best {
        retries.push((m.clone(), q.clone()));
    }
    if m.frees(Param::MuStatic) && m.mu_static() > m.mu_kinetic() {
        // From the current model itself: mu_static just above mu_kinetic.
        let tied = m.static_near_tie();
        let v = tied.values();
        retries.push((tied, v));
    }
    if let (None, Some(start)) = (fresh, opts.fresh_start.as_ref()) {
        let f = m.restarted(start);
        let v = f.values();
        retries.push((f, v));
    }
    let mut last_err = String::from("no start converged");
    for (r, p0) in retries {
        let (got, short) = tol.solve(&r, p0, 2 * max_iters);
        match got {
            Ok((q, cost, it)) => {
                if short || it >= 2 * max_iters {
                    capped.set(true);
                }
                iters += it;
                if best.as_ref().is_none_or(|b| cost < b.1) {
                    best = Some((q, cost));
                }
            }
            Err(e) => last_err = e,
        }
    }
    match best {
        Some((q, cost)) if !worse(cost) => Ok((q, cost, iters)),
        Some((_, cost)) => Err((
            format!(
                "did not converge: its chi-square {:.1} stayed above the {:.1} of the model it extends",
                chi2_of(cost),
                parent.unwrap_or(f64::NAN)
            ),
            chi2_of(cost),
            iters,
        )),
        None => Err((last_err, f64::NAN, iters)),
    }
}

/// `r` marked as a failed fit.
pub(super) fn failed_row(mut r: ModelRow, why: String) -> ModelRow {
    r.failed = Some(why);
    r.mu_kinetic = f64::NAN;
    r.bic = f64::NAN;
    r
}
