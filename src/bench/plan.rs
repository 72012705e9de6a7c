//! The planner's run time against its robustness estimate: the example plan with more and
//! more Monte Carlo draws, reporting the top proposal's robustness (a 95% lower bound, which
//! tightens as draws grow) and the observed fraction.

use crate::plan::{plan, PlanSpec};
use serde::Serialize;
use std::time::Instant;

/// The shipped example plan (paper rig, mu 0.35 +- 0.05, 500 Hz camera).
const PLAN: &str = include_str!("../../configs/plan_example.toml");

/// One point: draws, run time, the top proposal's robustness.
#[derive(Debug, Clone, Serialize)]
pub struct PlanPoint {
    /// Draws per candidate while searching.
    pub draws: usize,
    /// Draws of the final check.
    pub verify_draws: usize,
    /// Wall time of the whole plan (s, best of three).
    pub seconds: f64,
    /// Top proposal's robustness (one-sided 95% lower bound).
    pub robustness: f64,
    /// Top proposal's observed fraction of draws showing the targets.
    pub robustness_observed: f64,
    /// Top proposal's predicted standard error of mu.
    pub predicted_mu_stderr: f64,
}

/// Run the example plan at each (search draws, final draws) pair.
pub fn plan_benchmark(ladder: &[(usize, usize)]) -> Result<Vec<PlanPoint>, String> {
    let base = PlanSpec::from_toml(PLAN, "configs/plan_example.toml".as_ref())
        .map_err(|e| e.to_string())?;
    let mut out = Vec::new();
    for &(draws, verify) in ladder {
        let mut spec = base.clone();
        spec.search.draws = draws;
        spec.search.verify_draws = verify;
        let mut best = f64::INFINITY;
        let mut report = None;
        for _ in 0..3 {
            let t0 = Instant::now();
            let r = plan(&spec).map_err(|e| e.to_string())?;
            best = best.min(t0.elapsed().as_secs_f64());
            report = Some(r);
        }
        let r = report.expect("three runs");
        let top = r
            .proposals
            .first()
            .ok_or("the example plan found no proposal")?;
        out.push(PlanPoint {
            draws,
            verify_draws: verify,
            seconds: best,
            robustness: top.robustness,
            robustness_observed: top.robustness_observed,
            predicted_mu_stderr: top.predicted_mu_stderr,
        });
    }
    Ok(out)
}
