//! Levenberg-Marquardt as an argmin `Solver`: argmin's Gauss-Newton inverts J^T J outright,
//! which fails when the fit is nearly degenerate (mu barely constrained, strong correlations);
//! the damped step survives that. The problem says what to compute ([`LeastSquares`]); this
//! solver only says how to step; argmin's `Executor` owns the loop, limits and observers.
//!
//! The cost is reported as 1/2 ||r||^2 (argmin's own Gauss-Newton reports ||r||).

use argmin::core::{Error, IterState, Problem, Solver, TerminationReason, TerminationStatus, KV};
use nalgebra::{DMatrix, DVector};

/// A nonlinear least-squares problem: residuals r(p), and residuals with their Jacobian.
pub trait LeastSquares {
    /// Residuals at `p`; an error marks `p` as unusable (the solver then damps harder).
    fn residuals(&self, p: &DVector<f64>) -> Result<DVector<f64>, Error>;
    /// Residuals and Jacobian dr/dp at `p`.
    fn residuals_jacobian(&self, p: &DVector<f64>) -> Result<(DVector<f64>, DMatrix<f64>), Error>;
    /// Map `p` into the feasible set (bounds such as mu >= 0); the identity by default.
    fn project(&self, _p: &mut DVector<f64>) {}
}

/// argmin's iteration state for this solver.
pub type LmState = IterState<DVector<f64>, (), DMatrix<f64>, (), DVector<f64>, f64>;

/// Levenberg-Marquardt with Marquardt's diagonal scaling and Nielsen's damping update.
#[derive(Debug, Clone)]
pub struct LevenbergMarquardt {
    lambda: f64,
    nu: f64,
    /// Stop when the relative cost decrease of an accepted step falls below this.
    pub ftol: f64,
    /// Stop when the step is this small relative to the parameters.
    pub xtol: f64,
    /// Most trial steps per iteration before giving up.
    pub max_trials: usize,
    last_rel_decrease: f64,
    last_step: f64,
    stalled: bool,
}

impl Default for LevenbergMarquardt {
    fn default() -> Self {
        LevenbergMarquardt {
            lambda: 1e-3,
            nu: 2.0,
            ftol: 1e-9,
            xtol: 1e-9,
            max_trials: 30,
            last_rel_decrease: f64::INFINITY,
            last_step: f64::INFINITY,
            stalled: false,
        }
    }
}

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
        let (r, j) = problem.problem("jacobian_count", |o| o.residuals_jacobian(&p))?;
        let cost = half_sq(&r);
        Ok((state.param(p).residuals(r).jacobian(j).cost(cost), None))
    }

    fn next_iter(
        &mut self,
        problem: &mut Problem<O>,
        mut state: LmState,
    ) -> Result<(LmState, Option<KV>), Error> {
        let p = state
            .take_param()
            .ok_or_else(|| Error::msg("no parameters"))?;
        let r = state
            .take_residuals()
            .ok_or_else(|| Error::msg("no residuals"))?;
        let j = state
            .take_jacobian()
            .ok_or_else(|| Error::msg("no Jacobian"))?;
        let cost = state.get_cost();
        let a = j.tr_mul(&j);
        let g = j.tr_mul(&r);
        // Marquardt scaling: damp each parameter by its own curvature, floored so a parameter
        // the data do not constrain still gets a finite step.
        let max_diag = a.diagonal().max().max(1e-300);
        let diag = a.diagonal().map(|d| d.max(1e-12 * max_diag));
        for _ in 0..self.max_trials {
            let mut m = a.clone();
            for i in 0..m.nrows() {
                m[(i, i)] += self.lambda * diag[i];
            }
            let Some(chol) = m.cholesky() else {
                self.lambda *= self.nu;
                self.nu *= 2.0;
                continue;
            };
            let step = -chol.solve(&g);
            let mut trial = &p + &step;
            problem.problem("operator_count", |o| {
                o.project(&mut trial);
                Ok(())
            })?;
            let actual_step = &trial - &p;
            // A step the bounds cut to nothing: the optimum sits on a bound to working accuracy.
            if actual_step.norm() <= self.xtol * (p.norm() + self.xtol) {
                break;
            }
            let predicted = -(actual_step.dot(&g) + 0.5 * actual_step.dot(&(&a * &actual_step)));
            // Residuals and Jacobian together: near the optimum almost every trial is accepted,
            // and the dual-number run gives both for about the price of the Jacobian alone.
            let trial_rj =
                problem.problem("jacobian_count", |o| Ok(o.residuals_jacobian(&trial).ok()))?;
            let Some((trial_r, trial_j)) =
                trial_rj.filter(|(r, _)| r.iter().all(|v| v.is_finite()))
            else {
                self.lambda *= self.nu;
                self.nu *= 2.0;
                continue;
            };
            let trial_cost = half_sq(&trial_r);
            let rho = if predicted > 0.0 {
                (cost - trial_cost) / predicted
            } else {
                -1.0
            };
            if rho > 0.0 && trial_cost <= cost {
                self.lambda *= (1.0 - (2.0 * rho - 1.0).powi(3)).max(1.0 / 3.0);
                self.nu = 2.0;
                self.last_rel_decrease = (cost - trial_cost) / cost.max(f64::MIN_POSITIVE);
                self.last_step = actual_step.norm() / (p.norm() + self.xtol);
                return Ok((
                    state
                        .param(trial)
                        .residuals(trial_r)
                        .jacobian(trial_j)
                        .cost(trial_cost),
                    None,
                ));
            }
            self.lambda *= self.nu;
            self.nu *= 2.0;
        }
        // No trial step decreased the cost: the current point is a minimum to working accuracy.
        self.stalled = true;
        Ok((state.param(p).residuals(r).jacobian(j).cost(cost), None))
    }

    fn terminate(&mut self, _state: &LmState) -> TerminationStatus {
        if self.stalled {
            return TerminationStatus::Terminated(TerminationReason::SolverExit(
                "no decreasing step".into(),
            ));
        }
        if self.last_rel_decrease < self.ftol || self.last_step < self.xtol {
            return TerminationStatus::Terminated(TerminationReason::SolverConverged);
        }
        TerminationStatus::NotTerminated
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use argmin::core::Executor;

    /// Fit y = a exp(b t) to exact data; the Jacobian is analytic.
    struct Exponential {
        t: Vec<f64>,
        y: Vec<f64>,
    }

    impl LeastSquares for Exponential {
        fn residuals(&self, p: &DVector<f64>) -> Result<DVector<f64>, Error> {
            Ok(DVector::from_iterator(
                self.t.len(),
                self.t
                    .iter()
                    .zip(&self.y)
                    .map(|(t, y)| p[0] * (p[1] * t).exp() - y),
            ))
        }
        fn residuals_jacobian(
            &self,
            p: &DVector<f64>,
        ) -> Result<(DVector<f64>, DMatrix<f64>), Error> {
            let j = DMatrix::from_fn(self.t.len(), 2, |i, k| {
                let e = (p[1] * self.t[i]).exp();
                if k == 0 {
                    e
                } else {
                    p[0] * self.t[i] * e
                }
            });
            Ok((self.residuals(p)?, j))
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

    /// A degenerate problem (two parameters entering only as their sum) where J^T J is
    /// singular: the damped step still converges to a minimiser.
    struct Degenerate;
    impl LeastSquares for Degenerate {
        fn residuals(&self, p: &DVector<f64>) -> Result<DVector<f64>, Error> {
            Ok(DVector::from_vec(vec![
                p[0] + p[1] - 3.0,
                2.0 * (p[0] + p[1]) - 6.0,
            ]))
        }
        fn residuals_jacobian(
            &self,
            p: &DVector<f64>,
        ) -> Result<(DVector<f64>, DMatrix<f64>), Error> {
            Ok((
                self.residuals(p)?,
                DMatrix::from_row_slice(2, 2, &[1.0, 1.0, 2.0, 2.0]),
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
}
