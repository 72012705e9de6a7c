//! What the fitted motion does at the frame times (its range, slides, sticks and the
//! friction it needs), summed as it runs, and whether the raw slider track moves at all.

use super::problem::{Observations, TrajectoryProblem};
use super::FitError;
use crate::model::{Mode, Shorthands};
use crate::sim::{simulate_each, Request, Sample, Solution};

/// What the fitted motion does at the frame times, summed as it runs (no samples kept).
pub(super) struct Motion {
    /// The run (events, final state; no samples).
    pub(super) sol: Solution<f64>,
    /// Lowest and highest slider position at the frames (m).
    pub(super) range: (f64, f64),
    /// Whether it slides at some frame.
    pub(super) slides: bool,
    /// Whether it sticks at some frame.
    pub(super) sticks: bool,
    /// The largest friction ratio |c|/|b| the motion needs at a frame: while it never
    /// slides, mu_static is at least this.
    pub(super) needed_ratio: f64,
    /// Lowest and highest sliding speed |x'| at the frames that slide.
    pub(super) slide_speeds: Option<[f64; 2]>,
}

/// The fitted motion at the frame times.
pub(super) fn motion(problem: &TrajectoryProblem) -> Result<Motion, FitError> {
    let mut range = (f64::INFINITY, f64::NEG_INFINITY);
    let (mut slides, mut sticks) = (false, false);
    let mut needed_ratio: f64 = 0.0;
    let mut slide_speeds: Option<[f64; 2]> = None;
    let sol = simulate_each(
        &problem.rig,
        &problem.initial,
        problem.frame_times().last().copied().unwrap_or(0.0),
        &problem.options,
        &Request {
            sample_times: problem.frame_times().to_vec(),
            friction_work: false,
            positions_only: false,
        },
        &mut |s: Sample<f64>| {
            range = (range.0.min(s.state[0]), range.1.max(s.state[0]));
            if matches!(s.mode, Mode::Slide(_)) {
                slides = true;
                let v = s.state[2].abs();
                let r = slide_speeds.get_or_insert([v, v]);
                *r = [r[0].min(v), r[1].max(v)];
            }
            sticks |= s.mode == Mode::Stick;
            let sh = Shorthands::at(&problem.rig, &s.state);
            needed_ratio = needed_ratio.max(sh.c.abs() / sh.b.abs());
        },
    )
    .map_err(|e| FitError::NoStart(e.to_string()))?;
    Ok(Motion {
        sol,
        range,
        slides,
        sticks,
        needed_ratio,
        slide_speeds,
    })
}

/// Whether the raw slider track moves by more than its noise can explain: its range along
/// the rail (2nd to 98th percentile) beyond ten noise deviations.
pub(super) fn slider_moves(obs: &Observations, sigma: f64) -> Option<f64> {
    let mut x: Vec<f64> = obs.slider.iter().flatten().map(|p| p[0]).collect();
    if x.len() < 10 {
        return None;
    }
    x.sort_by(f64::total_cmp);
    let range = x[x.len() * 98 / 100] - x[x.len() * 2 / 100];
    (range > 10.0 * sigma).then_some(range)
}
