//! Recordings made from arrays (the Python package's `Recording(t, slider, bob)`): held to
//! the bounds a file's frames are, and given the slider-bob geometry every reader computes,
//! so that the fit's checks of what was recorded see them as they see a file.

use super::budget::{Budget, Resource};
use super::calibrate::{check_geometry, MAX_METRES};
use super::table::rows::Clock;
use super::{DataError, Provenance, Recording, Track};
use std::path::{Path, PathBuf};

/// What names a recording made from arrays in messages, where a file's path would be.
pub const ARRAYS: &str = "Recording(t, slider, bob)";

/// Refuse arrays of `frames` frames where a file of as many would be refused: more marker
/// positions (two a frame) than a reader keeps ([`Resource::Samples`]). Checked before the
/// arrays are copied, so that no length makes the copy fail.
pub fn check_frames(frames: usize) -> Result<(), DataError> {
    let mut budget = Budget::capped(Path::new(ARRAYS));
    let limit = budget.limit(Resource::Samples);
    budget
        .charge(Resource::Samples, (frames as u64).saturating_mul(2))
        .map_err(|_| DataError::Options {
            path: PathBuf::from(ARRAYS),
            message: format!(
                "{frames} frames are more than the {} a recording may hold ({limit} marker positions, as a file's): fit a time window, or every k-th frame",
                limit / 2
            ),
        })
}

/// A recording from arrays in the rail frame: `times` in seconds, `slider` and `bob` as x, y
/// pairs one after the other (metres, y up; both NaN where the marker was not seen). Refused
/// as a file's frames are, naming the array and the index: more frames than
/// [`check_frames`] allows, tracks of another length than `times`, times not finite or not
/// increasing, a point with one coordinate missing, a coordinate beyond [`MAX_METRES`]. The
/// times count from the first frame, as a file's do.
pub fn recording_from_arrays(
    times: &[f64],
    slider: &[f64],
    bob: &[f64],
) -> Result<Recording, DataError> {
    check_frames(times.len())?;
    let path = Path::new(ARRAYS);
    let t0 = times.first().copied().unwrap_or(0.0);
    let mut clock = Clock::default();
    for (i, &t) in times.iter().enumerate() {
        clock.check(path, || format!("t[{i}] = {t}"), t - t0)?;
    }
    let relative: Vec<f64> = times.iter().map(|t| t - t0).collect();
    super::check_frame_spacing(path, "t", &relative)?;
    let mut rec = Recording {
        times: relative,
        slider: track(slider, "slider", times.len())?,
        bob: track(bob, "bob", times.len())?,
        provenance: Provenance {
            sources: vec![PathBuf::from(ARRAYS)],
            slider_name: "slider".into(),
            bob_name: "bob".into(),
            time_origin: t0,
            ..Provenance::default()
        },
    };
    rec.provenance.geometry = check_geometry(&rec, None);
    Ok(rec)
}

/// `n` points of x, y pairs as a track: both NaN is a marker not seen.
fn track(xy: &[f64], role: &str, n: usize) -> Result<Track, DataError> {
    let path = Path::new(ARRAYS);
    if xy.len() != 2 * n {
        return Err(DataError::Options {
            path: path.to_owned(),
            message: format!(
                "{role} holds {} values: expected {n} rows of (x, y), one per time in t",
                xy.len()
            ),
        });
    }
    xy.chunks_exact(2)
        .enumerate()
        .map(|(i, p)| match (p[0].is_nan(), p[1].is_nan()) {
            (true, true) => Ok(None),
            (false, false) if p.iter().all(|v| v.abs() <= MAX_METRES) => Ok(Some([p[0], p[1]])),
            _ => Err(DataError::parse(
                path,
                format!("{role}[{i}]"),
                "(x, y)",
                format!("both finite within +-{MAX_METRES:e} m, or both NaN where the marker was not seen"),
                format!("({}, {})", p[0], p[1]),
            )),
        })
        .collect()
}
