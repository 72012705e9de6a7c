//! What was recorded, checked before any fitting work: the slider and the bob the right way
//! round, and their distance as constant as a rod's. A swapped or foreign recording is
//! otherwise fitted to a meaningless mu (or fails after minutes) instead of being named.

use crate::data::Recording;
use thiserror::Error;

/// How many times farther from its own best straight line the track read as the slider must
/// lie than the bob's for the two to be taken as swapped. A slider runs along the rail (off a
/// line by its noise, the rail's straightness of 0.1-0.5 mm per metre and the lens'
/// distortion); the bob swings on a circle about it. On the shipped recordings the slider's
/// spread is at most 0.72 times the bob's (a release that hardly swings), usually below 0.01.
pub const SWAP_RATIO: f64 = 4.0;

/// The share of the median slider-bob distance the track read as the slider must also lie off
/// its line for a swap to be named: a slider on a straight rail filmed through a lens that
/// distorts by up to 2 % at the frame's edge stays well within it (the shipped slider tracks:
/// 0.2 mm, the noise, on 0.3 m rods), and a pendulum that hardly swings says nothing either way.
pub const SWAP_SHARE: f64 = 0.01;

/// The share of frames (with both markers) in which the bob must sit above the slider by more
/// than half the median distance (more than 30 degrees above the rail's horizontal) for the
/// recording to be called upside down or swapped: a pendulum hangs below its pivot, passes below
/// it on every swing, and can stay above it only for a moment (the shipped recordings: the bob
/// above the slider's height at all in at most 5.4 % of the frames, at most 0.1435 m above it on
/// a 0.30 m rod, so more than half the distance in none). This is what tells a pendulum at rest,
/// whose tracks are two points, the right way up.
pub const ABOVE_SHARE: f64 = 0.98;

/// A recording that is not what the fit needs, found before fitting.
#[derive(Debug, Error)]
#[error("{files}: {message}")]
pub struct RecordingCheck {
    /// The file(s) read.
    pub files: String,
    /// What was found, with the figures behind it and the fix.
    pub message: String,
}

pub use crate::data::calibrate::off_line_spread;

/// The files of a recording, as its messages name them.
fn files(rec: &Recording) -> String {
    rec.provenance
        .sources
        .iter()
        .map(|p| p.display().to_string())
        .collect::<Vec<_>>()
        .join(" + ")
}

/// The slider and the bob the right way round: refused when the track read as the slider lies
/// off its own best line by more than [`SWAP_RATIO`] times the bob's and by more than
/// [`SWAP_SHARE`] of the median marker distance (the bob then runs along a line while the
/// "slider" swings: they are swapped). Also refused: the bob above the slider by more than half
/// their distance in over [`ABOVE_SHARE`] of the frames (a pendulum hangs below its pivot), as
/// upside down (the slider on its line, the bob swinging) or, when the tracks cannot tell (a
/// pendulum at rest), as upside down or swapped. The message names the flags that fix it. A
/// recording that cannot tell either way (too few positions) passes.
pub fn check_labels(rec: &Recording) -> Result<(), RecordingCheck> {
    let (Some(slider), Some(bob), Some(g)) = (
        off_line_spread(&rec.slider),
        off_line_spread(&rec.bob),
        rec.provenance.geometry.as_ref(),
    ) else {
        return Ok(());
    };
    let swapped = slider > SWAP_RATIO * bob && slider > SWAP_SHARE * g.median;
    let labelled = bob > SWAP_RATIO * slider && bob > SWAP_SHARE * g.median;
    let above = bob_above(rec, g.median);
    if !swapped && !above {
        return Ok(());
    }
    let p = &rec.provenance;
    let flip = if from_arrays(rec) {
        "y up: negate the y columns of slider and bob"
    } else if p.calibration.y_flipped {
        "--y-up (the file's y points up)"
    } else {
        "--y-down (the file's y points down)"
    };
    if !swapped {
        let share = 100.0 * ABOVE_SHARE;
        let (what, fix) = if labelled {
            (
                "the recording is upside down",
                format!("read it with {flip}"),
            )
        } else {
            (
                "the recording is upside down or its slider and bob are swapped",
                format!(
                    "read it with {flip}, or the markers the other way round ({})",
                    swap_fix(rec)
                ),
            )
        };
        return Err(RecordingCheck {
            files: files(rec),
            message: format!(
                "{what}: the bob ({:?}) sits more than half the marker distance ({:.4} m) above the slider ({:?}) in over {share} % of the frames, where a pendulum hangs below its pivot; {fix}",
                p.bob_name, g.median, p.slider_name
            ),
        });
    }
    let fix = swap_fix(rec);
    Err(RecordingCheck {
        files: files(rec),
        message: format!(
            "the slider and the bob look swapped: the track read as the slider ({:?}) lies off its best straight line by {slider:.3e} m (robust spread) and the bob's ({:?}) by {bob:.3e} m, but a slider runs along the rail and the bob swings on a circle of {:.4} m about it; {fix}",
            p.slider_name, p.bob_name, g.median
        ),
    })
}

/// Whether the bob sits above the slider by more than half the median distance in more than
/// [`ABOVE_SHARE`] of the frames with both markers.
fn bob_above(rec: &Recording, median: f64) -> bool {
    let (mut above, mut both) = (0usize, 0usize);
    for (s, b) in rec.slider.iter().zip(&rec.bob) {
        if let (Some(s), Some(b)) = (s, b) {
            both += 1;
            above += usize::from(b[1] - s[1] > 0.5 * median);
        }
    }
    both >= 10 && above as f64 > ABOVE_SHARE * both as f64
}

/// Whether a recording was made from arrays (the Python package's `Recording`), not read from
/// a file: its fixes are to the arrays, not to a reader's flags.
fn from_arrays(rec: &Recording) -> bool {
    rec.provenance.format.is_none()
}

/// The flags (or the file order, or the arrays' order) that read a recording's two markers the
/// other way round.
fn swap_fix(rec: &Recording) -> String {
    let p = &rec.provenance;
    if from_arrays(rec) {
        return format!(
            "give them the other way round: {}",
            crate::data::arrays::ARRAYS.replace("slider, bob", "bob, slider")
        );
    }
    let by_file_order = p.sources.len() == 2
        && p.notes
            .iter()
            .any(|n| n.contains(crate::data::FILE_ORDER_NOTE));
    if by_file_order {
        format!(
            "give the two files the other way round, the slider's first: {} {} (as a release of fit --joint: --release {},{})",
            p.sources[1].display(),
            p.sources[0].display(),
            p.sources[1].display(),
            p.sources[0].display()
        )
    } else {
        format!(
            "read them the other way round with --slider {:?} --bob {:?}",
            p.bob_name, p.slider_name
        )
    }
}

/// The slider-bob distance as constant as a rod's ([`crate::data::Geometry::rigid`]: a robust
/// spread within five noise deviations plus 5 % of the median): otherwise the recording is not
/// of this rig, or its markers are not the slider and the bob, and it is refused with the
/// median and the spread.
pub fn check_rigid(rec: &Recording) -> Result<(), RecordingCheck> {
    let Some(g) = rec.provenance.geometry.as_ref() else {
        return Ok(());
    };
    if g.rigid() {
        return Ok(());
    }
    let p = &rec.provenance;
    let check = if from_arrays(rec) {
        "check that slider and bob are the slider's and the bob's tracks, in metres".to_owned()
    } else {
        format!(
            "check that {:?} and {:?} are the slider's and the bob's markers (--slider NAME --bob NAME)",
            p.slider_name, p.bob_name
        )
    };
    Err(RecordingCheck {
        files: files(rec),
        message: format!(
            "not a recording of a pendulum on a slider: the slider-bob marker distance is not constant, median {:.4} m with a robust spread of {:.3e} m (1.4826 MAD over {} frames), beyond the {:.3e} m a rod's markers show (5 noise deviations of {:.2e} m plus 5 % of the median); {check}",
            g.median,
            g.spread,
            g.frames,
            g.rigid_limit(),
            g.noise,
        ),
    })
}

/// Every check of what was recorded, in order: the markers the right way round, then their
/// distance a rod's.
pub fn check_recording(rec: &Recording) -> Result<(), RecordingCheck> {
    check_labels(rec)?;
    check_rigid(rec)
}

pub use crate::data::MIN_FRAMES_PER_SWING;

/// The frames dense enough to follow the rig's pendulum: the median frame step at most a
/// [`MIN_FRAMES_PER_SWING`]th of the stuck pendulum's small-swing period (the slowest motion
/// the rig makes; a sliding pivot swings faster). Refused otherwise, naming the step, the
/// period and the likely slip: times in milliseconds where seconds are read.
pub fn check_frame_rate(
    rec: &Recording,
    rig: &crate::model::Rig<f64>,
) -> Result<(), RecordingCheck> {
    if rec.times.len() < 2 {
        return Ok(());
    }
    let step = super::problem::frame_step(&rec.times);
    let period = crate::model::pendulum::stuck_period(rig, 0.0);
    let per_swing = period / step;
    if per_swing.is_nan() || per_swing >= MIN_FRAMES_PER_SWING {
        return Ok(());
    }
    let fix = if from_arrays(rec) {
        "t is in seconds: times in milliseconds are t / 1000"
    } else {
        "the times are read as seconds: a column of milliseconds is headed t_ms (or time_ms)"
    };
    Err(RecordingCheck {
        files: files(rec),
        message: format!(
            "the frames are {step:.4} s apart (the median step), {per_swing:.2} a swing of the rig's pendulum (a period of {period:.3} s), where a fit needs at least {MIN_FRAMES_PER_SWING} to follow the motion: are the times in milliseconds? {fix}"
        ),
    })
}

/// The plain sentence for a recording whose slider never moves beyond its noise: mu_kinetic
/// is not identifiable (no slide shows it); what the stuck motion says is that the rail held
/// the slider against the largest friction ratio |F/N| the fitted stuck pendulum demanded, a
/// lower bound on mu_static.
pub(super) fn never_slides(
    obs: &super::problem::Observations,
    slider_noise: f64,
    mu_static: &super::outcome::StaticResult,
) -> String {
    let mut x: Vec<f64> = obs.slider.iter().flatten().map(|p| p[0]).collect();
    let range = if x.len() >= 10 {
        x.sort_by(f64::total_cmp);
        format!(
            "its track spans {:.2e} m along the rail between the 2nd and 98th percentiles, within ten noise deviations of {slider_noise:.2e} m",
            x[x.len() * 98 / 100] - x[x.len() * 2 / 100]
        )
    } else {
        format!("within ten noise deviations of {slider_noise:.2e} m")
    };
    let bound = match mu_static {
        super::outcome::StaticResult::LowerBound(r) => format!(
            "; while it stuck, the rail held it against a friction force of up to {r:.4} times the normal force (the stuck pendulum fitted to the bob's track), so mu_static >= {r:.4}"
        ),
        _ => String::new(),
    };
    format!(
        "mu is not identifiable from this recording: the slider never slides ({range}), so no slide shows mu_kinetic{bound}."
    )
}

#[cfg(test)]
mod tests {
    use super::off_line_spread;

    /// Points on a line at any angle have no spread across it; on a circle's arc, the arc's.
    #[test]
    fn a_line_has_no_spread_and_an_arc_its_sagitta() {
        let line: Vec<Option<[f64; 2]>> = (0..100)
            .map(|i| {
                let s = i as f64 * 1e-3;
                Some([0.1 + s * 0.8, -0.2 + s * 0.6])
            })
            .collect();
        assert!(off_line_spread(&line).unwrap() < 1e-12);
        let arc: Vec<Option<[f64; 2]>> = (0..=200)
            .map(|i| {
                let a = -0.9 + 1.8 * i as f64 / 200.0;
                Some([0.3 * a.sin(), -0.3 * a.cos()])
            })
            .collect();
        let s = off_line_spread(&arc).unwrap();
        assert!(s > 0.01 && s < 0.3 * (1.0 - 0.9f64.cos()), "{s}");
    }
}
