//! Benchmarks a user can run on their own machine: run time of a scene (median of repeats),
//! the work-precision diagram (run time against error for each integrator), and the fit, the
//! planner and the recording readers (`read`).

pub use crate::model::pendulum as exact;
pub mod fit;
pub mod plan;
pub mod plot;
pub mod read;
pub mod skips;
pub mod work_precision;

use crate::scene::Scene;
use crate::sim::{simulate, SimError, Stats};
use std::time::Instant;

/// Timing of one scene.
#[derive(Debug, Clone, serde::Serialize)]
pub struct SceneTiming {
    /// Median wall time of one whole simulation (s).
    pub median_s: f64,
    /// Fastest batch, per simulation (s).
    pub min_s: f64,
    /// Simulations timed.
    pub runs: usize,
    /// Counters of one run.
    pub stats: Stats,
}

/// Batch timings of `run`, per call, sorted: a warm-up of at least `budget_s / 10` (and three
/// calls), then `batches` batches sized to take about `budget_s / batches` each, so that
/// runs of a few microseconds are not dominated by the clock.
pub fn batch_seconds<T, E>(
    mut run: impl FnMut() -> Result<T, E>,
    batches: usize,
    budget_s: f64,
) -> Result<(Vec<f64>, usize), E> {
    let t0 = Instant::now();
    let mut warm = 0;
    while t0.elapsed().as_secs_f64() < budget_s / 10.0 || warm < 3 {
        std::hint::black_box(run()?);
        warm += 1;
    }
    let per_run = t0.elapsed().as_secs_f64() / warm as f64;
    let batches = batches.max(1);
    let batch = ((budget_s / batches as f64 / per_run).ceil() as usize).max(1);
    let mut times = Vec::with_capacity(batches);
    for _ in 0..batches {
        let t = Instant::now();
        for _ in 0..batch {
            std::hint::black_box(run()?);
        }
        times.push(t.elapsed().as_secs_f64() / batch as f64);
    }
    times.sort_by(f64::total_cmp);
    Ok((times, batch * batches))
}

/// Median wall time (s) of one call of `run`, by [`batch_seconds`].
pub fn median_seconds<T, E>(
    run: impl FnMut() -> Result<T, E>,
    batches: usize,
    budget_s: f64,
) -> Result<f64, E> {
    let (times, _) = batch_seconds(run, batches, budget_s)?;
    Ok(times[times.len() / 2])
}

/// Time `scene` (events and everything it asks for) over `batches` batches sized to take
/// about 20 ms each, after a warm-up; reports the median per simulation.
pub fn time_scene(scene: &Scene, batches: usize) -> Result<SceneTiming, SimError> {
    let request = scene.request();
    let run = || {
        simulate(
            &scene.rig,
            &scene.initial,
            scene.duration,
            &scene.options,
            &request,
        )
    };
    let stats = run()?.stats;
    let budget = 0.02 * batches.max(1) as f64;
    let (times, runs) = batch_seconds(run, batches, budget.max(2.0 * 0.02))?;
    Ok(SceneTiming {
        median_s: times[times.len() / 2],
        min_s: times[0],
        runs,
        stats,
    })
}
