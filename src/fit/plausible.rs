//! The rig file compared with the recording before any fitting work: a rod length the markers
//! contradict (a unit slip, a typo such as 1e-9) is otherwise fitted for minutes to a
//! meaningless answer.

use crate::data::Recording;
use crate::model::Rig;
use crate::scene::SceneError;
use std::path::Path;

/// How far, as a factor either way, the rig's `rod_length` may be from the recording's median
/// slider-bob marker distance. `rod_length` runs from the pivot to the bob's centre, where the
/// bob's marker is, so the two differ only by the camera's scale error (a few percent) and
/// the markers' offsets from the pivot and the bob's centre (millimetres to centimetres on a
/// rod of tens of centimetres). A factor 2 leaves room for all of these and still catches a
/// unit slip (centimetres for metres is a factor 100, inches 39) or a typo.
pub const ROD_LENGTH_FACTOR: f64 = 2.0;

/// Refuse a rig whose rod length is more than [`ROD_LENGTH_FACTOR`] from the recording's
/// median slider-bob marker distance (the rod check every reader makes, which `convert`
/// reports); the error names the rig file, the key, its value and the median. A recording with
/// no frame showing both markers has nothing to compare (the fit says what it lacks).
pub fn check_rod_length(
    rig_path: &Path,
    rig: &Rig<f64>,
    rec: &Recording,
) -> Result<(), SceneError> {
    let Some(geometry) = &rec.provenance.geometry else {
        return Ok(());
    };
    // The rig file's rod_length: for a rigid pendulum the dynamics' rod_length is the
    // equivalent length, but the marker stays at the bob's centre.
    let (rod, median) = (rig.marker_length, geometry.median);
    let (lo, hi) = (median / ROD_LENGTH_FACTOR, median * ROD_LENGTH_FACTOR);
    if (lo..=hi).contains(&rod) {
        return Ok(());
    }
    let sources: Vec<String> = rec
        .provenance
        .sources
        .iter()
        .map(|p| p.display().to_string())
        .collect();
    Err(SceneError::Invalid {
        path: rig_path.to_owned(),
        message: format!(
            "rig.rod_length must be within a factor {ROD_LENGTH_FACTOR} of the median slider-bob marker distance of {} ({median} m over {} frames), from {lo} to {hi} m: the rod runs from the pivot to the bob's centre, where its marker is; got {rod:?}",
            sources.join(" + "),
            geometry.frames,
        ),
    })
}
