//! Levenberg-Marquardt as an argmin `Solver`: argmin's Gauss-Newton inverts J^T J outright,
//! which fails when the fit is nearly degenerate (mu barely constrained, strong correlations);
//! the damped step survives that. The problem says what to compute ([`LeastSquares`]); this
//! solver only says how to step; argmin's `Executor` owns the loop, limits and observers.
//!
//! The cost is reported as 1/2 ||r||^2 (argmin's own Gauss-Newton reports ||r||).

use argmin::core::{Error, IterState, Problem, Solver, TerminationReason, TerminationStatus, KV};
use nalgebra::{DMatrix, DVector};

/// The Gauss-Newton normal equations at a point, summed frame by frame as the simulation
/// passes each frame: the Jacobian itself is never stored, so memory does not grow with the
/// recording.
#[derive(Debug, Clone)]
pub struct Normal {
    /// Half the weighted sum of squares, 1/2 r'r.
    pub cost: f64,
    /// J'J.
    pub jtj: DMatrix<f64>,
    /// J'r.
    pub jtr: DVector<f64>,
    /// Sum over blocks of frames of (J_b'r_b)(J_b'r_b)', when blocks were asked for (the
    /// middle of the block covariance).
    pub meat: Option<DMatrix<f64>>,
}

impl Normal {
    /// The normal equations of residuals `r` with Jacobian `j` held in full (small problems).
    pub fn from_dense(r: &DVector<f64>, j: &DMatrix<f64>) -> Self {
        Normal {
            cost: half_sq(r),
            jtj: j.tr_mul(j),
            jtr: j.tr_mul(r),
            meat: None,
        }
    }

    /// Whether every number in it is finite (a simulation that blew up is not a step).
    pub fn is_finite(&self) -> bool {
        self.cost.is_finite()
            && self
                .jtr
                .iter()
                .chain(self.jtj.iter())
                .all(|v| v.is_finite())
    }
}

/// A nonlinear least-squares problem, seen by the solver only through its normal equations:
/// a problem can then sum them as it goes and never hold the Jacobian.
pub trait LeastSquares {
    /// Cost 1/2 r'r, J'J and J'r at `p`; an error marks `p` as unusable (the solver then
    /// damps harder).
    fn normal_equations(&self, p: &DVector<f64>) -> Result<Normal, Error>;
    /// Map `p` into the feasible set (bounds such as mu >= 0); the identity by default.
    fn project(&self, _p: &mut DVector<f64>) {}
    /// The cost 1/2 r'r at `p` alone, the same number [`Self::normal_equations`] gives, when
    /// it comes cheaper than they do; `None` (the default) when it does not, and the solver
    /// then asks for both at once.
    fn cost(&self, _p: &DVector<f64>) -> Option<Result<f64, Error>> {
        None
    }
}

/// argmin's iteration state for this solver: the gradient slot holds J'r and the Hessian
/// slot the Gauss-Newton J'J.
pub type LmState = IterState<DVector<f64>, DVector<f64>, (), DMatrix<f64>, (), f64>;

/// Levenberg-Marquardt with Marquardt's diagonal scaling and Nielsen's damping update.
#[derive(Debug, Clone)]
pub struct LevenbergMarquardt {
    lambda: f64,
    nu: f64,
    /// Stop when the relative cost decrease of an accepted step falls below this.
    pub ftol: f64,
    /// ... and, with it, when that decrease is below this in cost units (half a chi-square):
    /// a relative tolerance alone lets a million frames' optimum (cost ~2e6) stop 0.06
    /// standard errors short; 1e-4 keeps it within about 0.015, and binds only above a cost
    /// of 1e5 (tens of thousands of frames).
    pub fatol: f64,
    /// Stop when the step is this small relative to the parameters.
    pub xtol: f64,
    /// Stop, whatever the relative tolerances say, when even the full Gauss-Newton step is
    /// predicted to lower the cost by less than this (cost units): a comparison of models
    /// that differ by units of chi-square needs no more (0: never).
    pub gn_tol: f64,
    /// Stop, out of reach, when even [`REACH_SAFETY`] times the full Gauss-Newton step's
    /// predicted decrease leaves the cost above this (cost units; +inf: never): a model
    /// weighed against a better one needs no optimum once it cannot come within the
    /// comparison's window. The point one undamped Gauss-Newton step away is then kept when its
    /// cost (evaluated alone) is lower, so the cost returned is a true one, and an upper bound.
    pub reach_floor: f64,
    /// Most trial steps per iteration before giving up.
    pub max_trials: usize,
    /// Leave the start where it is when this parameter has no gradient there (its column of
    /// the Jacobian is zero): a start of mu above the truth, where the model never slides,
    /// cannot learn mu, and fitting the other parameters to a motion that never slides only
    /// spends runs on a start that loses.
    pub flat_exit: Option<usize>,
    last_rel_decrease: f64,
    last_decrease: f64,
    last_step: f64,
    stalled: bool,
    /// The Gauss-Newton step's predicted decrease fell below the tolerances.
    converged: bool,
    /// The start left [`Self::flat_exit`]'s parameter without a gradient.
    flat: bool,
    /// The model could not come within [`Self::reach_floor`].
    out_of_reach: bool,
    /// The last iteration rejected a trial before it kept one.
    retried: bool,
}

impl Default for LevenbergMarquardt {
    fn default() -> Self {
        LevenbergMarquardt {
            lambda: 1e-3,
            nu: 2.0,
            ftol: 1e-9,
            fatol: 1e-4,
            xtol: 1e-9,
            gn_tol: 0.0,
            reach_floor: f64::INFINITY,
            max_trials: 30,
            flat_exit: None,
            last_rel_decrease: f64::INFINITY,
            last_decrease: f64::INFINITY,
            last_step: f64::INFINITY,
            stalled: false,
            converged: false,
            flat: false,
            out_of_reach: false,
            retried: false,
        }
    }
}

impl LevenbergMarquardt {
    /// After a trial that failed or was rejected: Nielsen's damping increase, faster with each
    /// failure in a row (reset to doubling when a step is kept).
    fn raise_damping(&mut self) {
        self.lambda *= self.nu;
        self.nu *= 2.0;
    }

    /// Before any trial, what the full Gauss-Newton step predicts: the point to stop at and
    /// its cost when the predicted decrease is below both tolerances (MINPACK's
    /// predicted-reduction test: a start at a minimum, as a final polish often is, ends here
    /// rather than spending trial simulations that cannot decrease the cost), or when even
    /// [`REACH_SAFETY`] times it leaves the cost above [`Self::reach_floor`] (then the point
    /// one undamped step away when its cost, evaluated alone, is lower); `None` otherwise.
    fn gauss_newton_stop<O: LeastSquares>(
        &mut self,
        problem: &mut Problem<O>,
        p: &DVector<f64>,
        g: &DVector<f64>,
        a: &DMatrix<f64>,
        cost: f64,
    ) -> Result<Option<(DVector<f64>, f64)>, Error> {
        let Some(chol) = a.clone().cholesky() else {
            return Ok(None);
        };
        let predicted = 0.5 * g.dot(&chol.solve(g));
        let within = predicted <= self.ftol * cost && predicted <= self.fatol;
        if predicted.is_finite() && (within || predicted < self.gn_tol) {
            self.converged = true;
            return Ok(Some((p.clone(), cost)));
        }
        if predicted.is_finite() && cost - REACH_SAFETY * predicted > self.reach_floor {
            self.out_of_reach = true;
            let mut trial = p - chol.solve(g);
            problem.problem("operator_count", |o| {
                o.project(&mut trial);
                Ok(())
            })?;
            let alone = problem.problem("cost_count", |o| Ok(o.cost(&trial)))?;
            if let Some(Ok(c)) = alone.filter(|c| c.as_ref().is_ok_and(|c| *c < cost)) {
                return Ok(Some((trial, c)));
            }
            return Ok(Some((p.clone(), cost)));
        }
        Ok(None)
    }

    /// The trial point of the step damped by the current `lambda` (each parameter by its own
    /// curvature `diag`), projected onto the bounds; `None` when the damped matrix is not
    /// positive definite.
    fn damped_trial<O: LeastSquares>(
        &self,
        problem: &mut Problem<O>,
        p: &DVector<f64>,
        g: &DVector<f64>,
        a: &DMatrix<f64>,
        diag: &DVector<f64>,
    ) -> Result<Option<DVector<f64>>, Error> {
        let mut m = a.clone();
        for i in 0..m.nrows() {
            m[(i, i)] += self.lambda * diag[i];
        }
        let Some(chol) = m.cholesky() else {
            return Ok(None);
        };
        let step = -chol.solve(g);
        let mut trial = p + &step;
        problem.problem("operator_count", |o| {
            o.project(&mut trial);
            Ok(())
        })?;
        Ok(Some(trial))
    }

    /// A trial kept (`rho` its decrease over the predicted one, from `cost` to `trial_cost`,
    /// a relative step `rel_step`): the damping eased by Nielsen's rule, and the decrease and
    /// the step kept for the convergence tests.
    fn keep(&mut self, rho: f64, rejected: bool, cost: f64, trial_cost: f64, rel_step: f64) {
        self.retried = rejected;
        self.lambda *= (1.0 - (2.0 * rho - 1.0).powi(3)).max(1.0 / 3.0);
        self.nu = 2.0;
        self.last_rel_decrease = (cost - trial_cost) / cost.max(f64::MIN_POSITIVE);
        self.last_decrease = cost - trial_cost;
        self.last_step = rel_step;
    }

    /// The damping the solver holds now (after a run: where it ended).
    pub fn damping(&self) -> f64 {
        self.lambda
    }

    /// Start from damping `lambda` instead of the default 1e-3: a fit that continues another
    /// of nearly the same problem (a long recording's next stage) starts from where that one's
    /// damping ended. From 1e-3, Nielsen's update lowers it threefold per accepted step, and
    /// along a narrow valley (mu against the mass ratio) each of those steps is cut short:
    /// a million frames' last stage took nine passes to cross what one undamped step does.
    pub fn with_damping(mut self, lambda: f64) -> Self {
        self.lambda = lambda;
        self
    }
}

/// How far the decrease a full Gauss-Newton step predicts may fall short of the one a model's
/// fit reaches before [`LevenbergMarquardt::reach_floor`] stops it: at an optimum of the model
/// it extends, a smooth term's quadratic prediction (the score test's) was within 0.1 % of its
/// fitted drop on direction- and load-law recordings (815.4 against 815.3).
pub const REACH_SAFETY: f64 = 1.5;

/// The termination reason of a model stopped out of reach ([`LevenbergMarquardt::reach_floor`]).
pub const OUT_OF_REACH: &str = "out of reach of the best model";

/// The termination reason of a start left where it was ([`LevenbergMarquardt::flat_exit`]).
pub const FLAT_START: &str = "the start leaves the parameter without a gradient";

fn half_sq(r: &DVector<f64>) -> f64 {
    0.5 * r.norm_squared()
}

impl<O: LeastSquares> Solver<O, LmState> for LevenbergMarquardt {
    fn name(&self) -> &str {
        "Levenberg-Marquardt"
    }

    fn init(
        &mut self,
        problem: &mut Problem<O>,
        mut state: LmState,
    ) -> Result<(LmState, Option<KV>), Error> {
        let mut p = state
            .take_param()
            .ok_or_else(|| Error::msg("Levenberg-Marquardt needs an initial parameter vector"))?;
        problem.problem("operator_count", |o| {
            o.project(&mut p);
            Ok(())
        })?;
        let n = problem.problem("jacobian_count", |o| o.normal_equations(&p))?;
        self.flat = self.flat_exit.is_some_and(|i| n.jtj[(i, i)] == 0.0);
        Ok((
            state.param(p).gradient(n.jtr).hessian(n.jtj).cost(n.cost),
            None,
        ))
    }

    fn next_iter(
        &mut self,
        problem: &mut Problem<O>,
        mut state: LmState,
    ) -> Result<(LmState, Option<KV>), Error> {
        let p = state
            .take_param()
            .ok_or_else(|| Error::msg("no parameters"))?;
        let g = state
            .take_gradient()
            .ok_or_else(|| Error::msg("no gradient J'r"))?;
        let a = state.take_hessian().ok_or_else(|| Error::msg("no J'J"))?;
        let cost = state.get_cost();
        // Converged already when even the full Gauss-Newton step is predicted to lower the
        // cost by less than both tolerances (MINPACK's predicted-reduction test, taken before
        // any trial run): a start at a minimum, as a final polish often is, ends here rather
        // than spending trial simulations that cannot decrease the cost.
        if let Some((q, c)) = self.gauss_newton_stop(problem, &p, &g, &a, cost)? {
            return Ok((state.param(q).gradient(g).hessian(a).cost(c), None));
        }
        // Marquardt scaling: damp each parameter by its own curvature, floored so a parameter
        // the data do not constrain still gets a finite step.
        let max_diag = a.diagonal().max().max(1e-300);
        let diag = a.diagonal().map(|d| d.max(1e-12 * max_diag));
        // A trial after a rejected one (in this iteration or the last) is tried on its cost
        // first, and the normal equations are computed only where the step is kept: there a
        // trial is about as likely to be rejected as kept (a misfitting recording's fits reject
        // a third of their trials), and the cost alone takes a fraction of the run in dual
        // numbers. The first trial of an iteration after one that kept its first gets both at
        // once: near an optimum almost every such trial is kept. Every decision is the one
        // taken on the normal equations' own cost, so the path is the same.
        let mut rejected = false;
        for _ in 0..self.max_trials {
            let Some(trial) = self.damped_trial(problem, &p, &g, &a, &diag)? else {
                self.raise_damping();
                continue;
            };
            let actual_step = &trial - &p;
            // A step the bounds cut to nothing: the optimum sits on a bound to working accuracy.
            if actual_step.norm() <= self.xtol * (p.norm() + self.xtol) {
                break;
            }
            let predicted = -(actual_step.dot(&g) + 0.5 * actual_step.dot(&(&a * &actual_step)));
            if rejected || self.retried {
                let alone = problem.problem("cost_count", |o| Ok(o.cost(&trial)))?;
                // The test below, on the cost alone (a failed or non-finite run is rejected).
                let kept = |c: f64| predicted > 0.0 && c < cost;
                if alone.is_some_and(|c| !c.is_ok_and(kept)) {
                    self.raise_damping();
                    rejected = true;
                    continue;
                }
            }
            // Cost and normal equations together: near the optimum almost every trial is
            // accepted, and the dual-number run gives both for about the price of one.
            let trial_n =
                problem.problem("jacobian_count", |o| Ok(o.normal_equations(&trial).ok()))?;
            let Some(trial_n) = trial_n.filter(Normal::is_finite) else {
                self.raise_damping();
                rejected = true;
                continue;
            };
            let trial_cost = trial_n.cost;
            let rho = if predicted > 0.0 {
                (cost - trial_cost) / predicted
            } else {
                -1.0
            };
            if rho > 0.0 && trial_cost <= cost {
                self.keep(
                    rho,
                    rejected,
                    cost,
                    trial_cost,
                    actual_step.norm() / (p.norm() + self.xtol),
                );
                return Ok((
                    state
                        .param(trial)
                        .gradient(trial_n.jtr)
                        .hessian(trial_n.jtj)
                        .cost(trial_cost),
                    None,
                ));
            }
            self.raise_damping();
            rejected = true;
        }
        // No trial step decreased the cost: the current point is a minimum to working accuracy.
        self.stalled = true;
        Ok((state.param(p).gradient(g).hessian(a).cost(cost), None))
    }

    fn terminate(&mut self, _state: &LmState) -> TerminationStatus {
        if self.flat {
            return TerminationStatus::Terminated(TerminationReason::SolverExit(FLAT_START.into()));
        }
        if self.stalled {
            return TerminationStatus::Terminated(TerminationReason::SolverExit(
                "no decreasing step".into(),
            ));
        }
        if self.out_of_reach {
            return TerminationStatus::Terminated(TerminationReason::SolverExit(
                OUT_OF_REACH.into(),
            ));
        }
        if self.converged {
            return TerminationStatus::Terminated(TerminationReason::SolverConverged);
        }
        let small = self.last_rel_decrease < self.ftol && self.last_decrease < self.fatol;
        if small || self.last_step < self.xtol {
            return TerminationStatus::Terminated(TerminationReason::SolverConverged);
        }
        TerminationStatus::NotTerminated
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use argmin::core::{Executor, State as _};

    /// Fit y = a exp(b t) to exact data; the Jacobian is analytic.
    struct Exponential {
        t: Vec<f64>,
        y: Vec<f64>,
    }

    impl Exponential {
        fn residuals(&self, p: &DVector<f64>) -> Result<DVector<f64>, Error> {
            Ok(DVector::from_iterator(
                self.t.len(),
                self.t
                    .iter()
                    .zip(&self.y)
                    .map(|(t, y)| p[0] * (p[1] * t).exp() - y),
            ))
        }
    }

    impl LeastSquares for Exponential {
        fn normal_equations(&self, p: &DVector<f64>) -> Result<Normal, Error> {
            let j = DMatrix::from_fn(self.t.len(), 2, |i, k| {
                let e = (p[1] * self.t[i]).exp();
                if k == 0 {
                    e
                } else {
                    p[0] * self.t[i] * e
                }
            });
            Ok(Normal::from_dense(&self.residuals(p)?, &j))
        }
    }

    #[test]
    fn recovers_exponential_from_far_start() {
        let t: Vec<f64> = (0..30).map(|i| i as f64 * 0.1).collect();
        let y = t.iter().map(|t| 2.5 * (-1.3 * t).exp()).collect();
        let res = Executor::new(Exponential { t, y }, LevenbergMarquardt::default())
            .configure(|s| s.param(DVector::from_vec(vec![0.5, 0.8])).max_iters(200))
            .run()
            .unwrap();
        let p = res.state.best_param.unwrap();
        assert!(
            (p[0] - 2.5).abs() < 1e-8 && (p[1] + 1.3).abs() < 1e-8,
            "{p}"
        );
    }

    /// A finished run's best parameters and why it stopped.
    fn ended(state: LmState) -> (DVector<f64>, Option<String>) {
        let reason = state.get_termination_reason().map(|r| r.text().to_owned());
        (state.best_param.unwrap(), reason)
    }

    /// y = b + a max(0, t - 5) on t < 3: a's column is zero everywhere the data are.
    struct Hinge(Vec<f64>);
    impl LeastSquares for Hinge {
        fn normal_equations(&self, p: &DVector<f64>) -> Result<Normal, Error> {
            let n = self.0.len();
            let r = DVector::from_fn(n, |i, _| {
                p[1] + p[0] * (self.0[i] - 5.0).max(0.0) - (1.0 + 0.1 * i as f64)
            });
            let j = DMatrix::from_fn(n, 2, |i, k| {
                if k == 0 {
                    (self.0[i] - 5.0).max(0.0)
                } else {
                    1.0
                }
            });
            Ok(Normal::from_dense(&r, &j))
        }
    }

    /// A start that leaves the watched parameter without a gradient ends at once, where it
    /// started, with its own reason; without the watch, the other parameter is fitted.
    #[test]
    fn a_start_without_a_gradient_in_the_watched_parameter_is_left() {
        let run = |flat_exit| {
            let lm = LevenbergMarquardt {
                flat_exit,
                ..Default::default()
            };
            let t: Vec<f64> = (0..30).map(|i| i as f64 * 0.1).collect();
            let res = Executor::new(Hinge(t), lm)
                .configure(|s| s.param(DVector::from_vec(vec![0.3, 0.0])).max_iters(50))
                .run()
                .unwrap();
            (res.state.get_iter(), ended(res.state))
        };
        let (iters, (p, reason)) = run(Some(0));
        assert_eq!((p[0], p[1], iters), (0.3, 0.0, 0));
        assert_eq!(reason.as_deref(), Some(FLAT_START));
        let (_, (q, _)) = run(None);
        // b fitted to the data's mean, 1 + 0.1 * 14.5; a untouched.
        assert!((q[1] - 2.45).abs() < 1e-9 && q[0] == 0.3, "{q}");
    }

    /// The exponential problem counting its evaluations.
    struct Counted(Exponential, std::cell::Cell<usize>);
    impl LeastSquares for Counted {
        fn normal_equations(&self, p: &DVector<f64>) -> Result<Normal, Error> {
            self.1.set(self.1.get() + 1);
            self.0.normal_equations(p)
        }
    }

    /// A start at the minimum ends after the one evaluation at the start: the Gauss-Newton
    /// step's predicted decrease is below the tolerances, and no trial run can lower the
    /// cost. A start a little off still moves to the minimum.
    #[test]
    fn a_start_at_the_minimum_costs_no_trial_run() {
        let run = |p0: Vec<f64>| {
            let t: Vec<f64> = (0..30).map(|i| i as f64 * 0.1).collect();
            // Noisy data: the minimum has a positive cost, as a real fit's does.
            let y = t
                .iter()
                .enumerate()
                .map(|(i, t)| 2.5 * (-1.3 * t).exp() + 0.01 * ((i * 7 % 5) as f64 - 2.0))
                .collect();
            let problem = Counted(Exponential { t, y }, std::cell::Cell::new(0));
            let res = Executor::new(problem, LevenbergMarquardt::default())
                .configure(|s| s.param(DVector::from_vec(p0)).max_iters(200))
                .run()
                .unwrap();
            let evals = res.problem.problem.as_ref().map(|p| p.1.get());
            let (p, reason) = ended(res.state);
            (p, evals, reason)
        };
        let (opt, _, _) = run(vec![0.5, 0.8]);
        let (p, evals, reason) = run(opt.as_slice().to_vec());
        assert_eq!(evals, Some(1), "{reason:?}");
        assert_eq!(reason.as_deref(), Some("Solver converged"));
        assert!((&p - &opt).norm() == 0.0);
        let (q, evals, _) = run(vec![opt[0], opt[1] + 1e-3]);
        assert!(evals.unwrap() > 1 && (&q - &opt).norm() < 1e-6, "{q} {opt}");
    }

    /// The exponential problem with its cost alone on offer (`costed`), counting the runs of
    /// either kind.
    struct Costed {
        inner: Exponential,
        costed: bool,
        normals: std::cell::Cell<usize>,
        costs: std::cell::Cell<usize>,
    }
    impl LeastSquares for Costed {
        fn normal_equations(&self, p: &DVector<f64>) -> Result<Normal, Error> {
            self.normals.set(self.normals.get() + 1);
            self.inner.normal_equations(p)
        }
        fn cost(&self, p: &DVector<f64>) -> Option<Result<f64, Error>> {
            self.costed.then(|| {
                self.costs.set(self.costs.get() + 1);
                self.inner.normal_equations(p).map(|n| n.cost)
            })
        }
    }

    /// With the cost on offer, a trial after a rejected one is tried on its cost first: the
    /// solver takes the same path to the same optimum, bit for bit, and computes the normal
    /// equations once less for every such trial it rejects.
    #[test]
    fn a_trial_tried_on_its_cost_first_keeps_the_path() {
        let run = |costed: bool| {
            let t: Vec<f64> = (0..30).map(|i| i as f64 * 0.1).collect();
            let y = t.iter().map(|t| 2.5 * (-1.3 * t).exp()).collect();
            let problem = Costed {
                inner: Exponential { t, y },
                costed,
                normals: std::cell::Cell::new(0),
                costs: std::cell::Cell::new(0),
            };
            // Far enough that trials are rejected on the way.
            let res = Executor::new(problem, LevenbergMarquardt::default())
                .configure(|s| s.param(DVector::from_vec(vec![0.1, 3.0])).max_iters(200))
                .run()
                .unwrap();
            let counts = res
                .problem
                .problem
                .as_ref()
                .map(|c| (c.normals.get(), c.costs.get()))
                .unwrap();
            (res.state.get_iter(), ended(res.state), counts)
        };
        let (iters, (p, reason), (normals, _)) = run(false);
        let (iters_c, (p_c, reason_c), (normals_c, costs_c)) = run(true);
        // Trials were rejected: more runs than the start and one per iteration.
        assert!(
            normals > iters as usize + 1,
            "{normals} runs, {iters} iterations"
        );
        assert_eq!((iters_c, reason_c), (iters, reason));
        assert!(p
            .iter()
            .zip(p_c.iter())
            .all(|(a, b)| a.to_bits() == b.to_bits()));
        assert!(
            (p[0] - 2.5).abs() < 1e-8 && (p[1] + 1.3).abs() < 1e-8,
            "{p}"
        );
        // Each cost tried first either ends a rejected trial (a run saved) or is followed by
        // the normal equations of the trial kept.
        assert!(
            costs_c > 0 && normals_c < normals,
            "{normals_c} against {normals}"
        );
    }

    /// A degenerate problem (two parameters entering only as their sum) where J^T J is
    /// singular: the damped step still converges to a minimiser.
    struct Degenerate;
    impl LeastSquares for Degenerate {
        fn normal_equations(&self, p: &DVector<f64>) -> Result<Normal, Error> {
            let r = DVector::from_vec(vec![p[0] + p[1] - 3.0, 2.0 * (p[0] + p[1]) - 6.0]);
            Ok(Normal::from_dense(
                &r,
                &DMatrix::from_row_slice(2, 2, &[1.0, 1.0, 2.0, 2.0]),
            ))
        }
    }

    #[test]
    fn survives_singular_normal_matrix() {
        let res = Executor::new(Degenerate, LevenbergMarquardt::default())
            .configure(|s| s.param(DVector::from_vec(vec![0.0, 0.0])).max_iters(100))
            .run()
            .unwrap();
        let p = res.state.best_param.unwrap();
        assert!((p[0] + p[1] - 3.0).abs() < 1e-8, "{p}");
    }

    /// A straight line fitted far from the origin, y = a + b t on t in [1000, 1001]: the
    /// columns are nearly parallel (the valley mu and the mass ratio make in a long
    /// recording). From near the optimum the default damping crawls along the valley, a
    /// threefold cut per step; started undamped ([`LevenbergMarquardt::with_damping`]), one
    /// step reaches the exact least-squares line (one or two more confirm it). Both end there.
    struct Valley {
        t: Vec<f64>,
        y: Vec<f64>,
    }
    impl LeastSquares for Valley {
        fn normal_equations(&self, p: &DVector<f64>) -> Result<Normal, Error> {
            let n = self.t.len();
            let r = DVector::from_fn(n, |i, _| p[0] + p[1] * self.t[i] - self.y[i]);
            let j = DMatrix::from_fn(n, 2, |i, k| if k == 0 { 1.0 } else { self.t[i] });
            Ok(Normal::from_dense(&r, &j))
        }
    }

    #[test]
    fn a_warm_damping_crosses_a_narrow_valley_at_once() {
        let t: Vec<f64> = (0..21).map(|i| 1000.0 + 0.05 * i as f64).collect();
        // A line with a wiggle, so the optimum leaves residuals.
        let y: Vec<f64> = t
            .iter()
            .enumerate()
            .map(|(i, &t)| 2.0 - 0.5 * (t - 1000.0) + 0.01 * (-1f64).powi(i as i32))
            .collect();
        // The least-squares line in closed form.
        let n = t.len() as f64;
        let (tm, ym) = (t.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
        let sxy: f64 = t.iter().zip(&y).map(|(t, y)| (t - tm) * (y - ym)).sum();
        let sxx: f64 = t.iter().map(|t| (t - tm).powi(2)).sum();
        let b = sxy / sxx;
        let opt = [ym - b * tm, b];
        // Off the optimum along the valley's floor (a and b move together).
        let start = DVector::from_vec(vec![opt[0] + 0.05 * 1000.0, opt[1] - 0.05]);
        let run = |lm: LevenbergMarquardt| {
            let res = Executor::new(
                Valley {
                    t: t.clone(),
                    y: y.clone(),
                },
                lm,
            )
            .configure(|s| s.param(start.clone()).max_iters(200))
            .run()
            .unwrap();
            (res.state.best_param.clone().unwrap(), res.state.get_iter())
        };
        let (cold, cold_iters) = run(LevenbergMarquardt::default());
        let (warm, warm_iters) = run(LevenbergMarquardt::default().with_damping(1e-12));
        for p in [&cold, &warm] {
            assert!(
                (p[1] - opt[1]).abs() < 1e-6 * opt[1].abs(),
                "{p} against {opt:?}"
            );
        }
        assert!(warm_iters <= 3, "{warm_iters} iterations");
        assert!(
            cold_iters > warm_iters + 2,
            "{cold_iters} against {warm_iters}"
        );
    }
}
