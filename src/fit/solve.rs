//! The ways the fit runs the Levenberg-Marquardt solver ([`super::lm`]): to its full
//! tolerance, loosely (a stage that only starts the next fit) and with its stop reason.

use super::lm::{self, LevenbergMarquardt};
use super::problem::TrajectoryProblem;
use argmin::core::{Executor, State as _};
use nalgebra::DVector;

/// Relative cost decrease (and step) at which a long recording's fits short of the whole
/// recording stop: they only start the next fit well.
pub(crate) const STAGE_FTOL: f64 = 1e-6;

/// The optimum, its cost (1/2 chi-square) and the iterations, or why the solver failed.
pub(super) type Solved = Result<(DVector<f64>, f64, u64), String>;

/// The optimum, its cost, the iterations and why the solver stopped.
pub(super) type Stopped = (DVector<f64>, f64, u64, String);

/// A solve's [`Stopped`], or why the solver failed.
pub(super) type Traced = Result<Stopped, String>;

/// Run Levenberg-Marquardt from `p0` on `problem`.
pub(super) fn solve(problem: &TrajectoryProblem, p0: DVector<f64>, max_iters: u64) -> Solved {
    solve_traced(problem, p0, max_iters).map(|(p, c, i, _)| (p, c, i))
}

/// [`solve`] stopping at a relative cost decrease of `ftol` (and a relative step of the
/// same size) when given.
pub(super) fn solve_loose<P: lm::LeastSquares + Clone>(
    problem: &P,
    p0: DVector<f64>,
    max_iters: u64,
    ftol: Option<f64>,
) -> Solved {
    run_lm(problem, p0, max_iters, loose(ftol)).map(|(p, c, i, _)| (p, c, i))
}

/// Levenberg-Marquardt stopping at `ftol` when given (relative cost and step, no absolute
/// tolerance), else at its defaults.
pub(crate) fn loose(ftol: Option<f64>) -> LevenbergMarquardt {
    let mut lm = LevenbergMarquardt::default();
    if let Some(tol) = ftol {
        // Only the next fit's start: no absolute tolerance.
        (lm.ftol, lm.fatol) = (tol, f64::INFINITY);
        lm.xtol = tol;
    }
    lm
}

/// [`solve`] with the solver's termination reason.
pub(super) fn solve_traced(
    problem: &TrajectoryProblem,
    p0: DVector<f64>,
    max_iters: u64,
) -> Traced {
    run_lm(problem, p0, max_iters, LevenbergMarquardt::default())
}

/// Whether a solve's termination reason says it stopped at its iteration limit, not at a
/// minimum (its values and their covariance then describe no optimum).
pub fn at_iteration_limit(reason: &str) -> bool {
    reason == argmin::core::TerminationReason::MaxItersReached.text()
}

/// Run `lm` on `problem` from `p0`: optimum, cost, iterations and termination reason.
pub(crate) fn run_lm<P: lm::LeastSquares + Clone>(
    problem: &P,
    p0: DVector<f64>,
    max_iters: u64,
    lm: LevenbergMarquardt,
) -> Traced {
    run_lm_damped(problem, p0, max_iters, lm).map(|(solved, _)| solved)
}

/// [`run_lm`] with the damping the solver ended at ([`LevenbergMarquardt::damping`]).
pub(super) fn run_lm_damped<P: lm::LeastSquares + Clone>(
    problem: &P,
    p0: DVector<f64>,
    max_iters: u64,
    lm: LevenbergMarquardt,
) -> Result<(Stopped, f64), String> {
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
    Ok(((p, cost, iters, reason), res.solver.damping()))
}
