//! Benchmarks a user can run on their own machine: run time of a scene (median of repeats).

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
    let t0 = Instant::now();
    let mut warm = 0;
    while t0.elapsed().as_secs_f64() < 0.2 || warm < 3 {
        std::hint::black_box(run()?);
        warm += 1;
    }
    let per_run = t0.elapsed().as_secs_f64() / warm as f64;
    let batch = ((0.02 / per_run).ceil() as usize).max(1);
    let mut times = Vec::with_capacity(batches);
    for _ in 0..batches.max(1) {
        let t = Instant::now();
        for _ in 0..batch {
            std::hint::black_box(run()?);
        }
        times.push(t.elapsed().as_secs_f64() / batch as f64);
    }
    times.sort_by(f64::total_cmp);
    Ok(SceneTiming {
        median_s: times[times.len() / 2],
        min_s: times[0],
        runs: batch * times.len(),
        stats,
    })
}
