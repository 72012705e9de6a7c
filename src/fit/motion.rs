//! What the fitted motion does at the frame times (its range, slides, sticks and the
//! friction it needs), summed as it runs, and whether the raw slider track moves at all.

use super::error::FitError;
use super::problem::{Observations, TrajectoryProblem};
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
    /// Lowest and highest normal force over the static load at the frames that slide.
    pub(super) slide_loads: Option<[f64; 2]>,
}

/// The fitted motion at the frame times.
pub(super) fn motion(problem: &TrajectoryProblem) -> Result<Motion, FitError> {
    let mut range = (f64::INFINITY, f64::NEG_INFINITY);
    let (mut slides, mut sticks) = (false, false);
    let mut needed_ratio: f64 = 0.0;
    let mut slide_speeds: Option<[f64; 2]> = None;
    let mut slide_loads: Option<[f64; 2]> = None;
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
            if let Mode::Slide(d) = s.mode {
                slides = true;
                let v = s.state[2].abs();
                let r = slide_speeds.get_or_insert([v, v]);
                *r = [r[0].min(v), r[1].max(v)];
                if let Some(n) = problem.rig.slide_load(&s.state, d.sign()) {
                    let r = slide_loads.get_or_insert([n, n]);
                    *r = [r[0].min(n), r[1].max(n)];
                }
            }
            sticks |= s.mode == Mode::Stick;
            needed_ratio = needed_ratio.max(Shorthands::at(&problem.rig, &s.state).pull());
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
        slide_loads,
    })
}

/// Noise deviations a track's span ([`track_span`]) must exceed for its marker to count as
/// moving.
pub(super) const STILL_NOISES: f64 = 10.0;

/// The span of coordinate `k` of a track's seen positions from its 2nd to its 98th
/// percentile (a few mis-tracked frames do not widen it); `None` for a track never seen.
pub(super) fn track_span(track: &[Option<[f64; 2]>], k: usize) -> Option<f64> {
    let mut v: Vec<f64> = track.iter().flatten().map(|p| p[k]).collect();
    let n = v.len();
    if n == 0 {
        return None;
    }
    let lo = *v.select_nth_unstable_by(n * 2 / 100, f64::total_cmp).1;
    let hi = *v.select_nth_unstable_by(n * 98 / 100, f64::total_cmp).1;
    Some(hi - lo)
}

/// Whether the raw slider track moves by more than its noise can explain: its span along
/// the rail ([`track_span`]) beyond [`STILL_NOISES`] noise deviations.
pub(super) fn slider_moves(obs: &Observations, sigma: f64) -> Option<f64> {
    if obs.slider.iter().flatten().count() < 10 {
        return None;
    }
    let range = track_span(&obs.slider, 0)?;
    (range > STILL_NOISES * sigma).then_some(range)
}
