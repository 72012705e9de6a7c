//! The rig file compared with the recording before any fitting work: a rod length the markers
//! contradict (a unit slip, a typo such as 1e-9) is otherwise fitted for minutes to a
//! meaningless answer.

use super::priors::TILT_SEARCH;
use crate::data::inspect::sig;
use crate::data::Recording;
use crate::model::Rig;
use crate::scene::SceneError;
use std::path::Path;

/// How far, as a share of the recording's median slider-bob marker distance, the rig's
/// `rod_length` may be from it. `rod_length` runs from the pivot to the bob's centre, where the
/// bob's marker is, so the two differ only by the camera's scale error (0.1-0.3 % from a
/// reference in view, a few percent at worst) and the markers' offsets from the pivot and the
/// bob's centre (a few millimetres on a rod of tens of centimetres); a ruler reads the rod to a
/// millimetre. 20 % is more than all of these together and still catches a rod measured to the
/// wrong point, a unit slip (centimetres for metres is a factor 100, inches 39) or a typo. The
/// shipped recordings' medians are within 1.6 % of their rig files' 0.30 m.
pub const ROD_LENGTH_TOLERANCE: f64 = 0.2;

/// Refuse a rig whose rod length is more than [`ROD_LENGTH_TOLERANCE`] off the recording's
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
    let (lo, hi) = (
        median * (1.0 - ROD_LENGTH_TOLERANCE),
        median * (1.0 + ROD_LENGTH_TOLERANCE),
    );
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
            "rig.rod_length must be within {} % of the median slider-bob marker distance of {} ({} m over {} frames), from {} to {} m: the rod runs from the pivot to the bob's centre, where its marker is, and a camera's scale and the markers' offsets explain a few percent, not more; got {rod:?}{}",
            ROD_LENGTH_TOLERANCE * 100.0,
            sources.join(" + "),
            sig4(median),
            geometry.frames,
            sig4(lo),
            sig4(hi),
            unit_slip(rod, median),
        ),
    })
}

/// The most a bench rig's slider or bob weighs here, in kg: a Painleve-Appell rig's parts weigh
/// grams to a few kilograms (a cart of 0.05-2 kg, a bob of 0.02-1 kg), so a mass above this
/// is a mass in grams far more often than a rig this heavy. The dynamics see only the masses'
/// ratio, so grams for both would fit the same mu while every force the report gives came out
/// a thousand times too large; grams for one would fit nonsense.
pub const MASS_MAX_KG: f64 = 20.0;

/// Refuse a rig file whose slider or bob weighs more than [`MASS_MAX_KG`], naming the key, its
/// value and, when it reads as grams, the value in kilograms.
pub fn check_masses(rig_path: &Path, rig: &Rig<f64>) -> Result<(), SceneError> {
    for (key, mass) in [
        ("rig.slider_mass", rig.slider_mass),
        ("rig.bob_mass", rig.bob_mass),
    ] {
        if mass > MASS_MAX_KG {
            let grams = if mass / 1000.0 >= 1e-3 {
                format!(
                    ": a mass in grams? the rig file takes kilograms: {} kg",
                    sig4(mass / 1000.0)
                )
            } else {
                String::new()
            };
            return Err(SceneError::Invalid {
                path: rig_path.to_owned(),
                message: format!(
                    "{key} = {} kg is more than a bench rig's slider or bob weighs (at most {MASS_MAX_KG} kg){grams}",
                    sig4(mass)
                ),
            });
        }
    }
    Ok(())
}

/// Refuse a rig file whose rail is tilted beyond [`TILT_SEARCH`] (about 17 degrees) for a
/// fit: the fit's tilt nuisance searches only that far, so a steeper rail would be stepped
/// back to it, and a rail near vertical took the fit minutes (issue 59, class C). A lab's rail
/// is levelled to a fraction of a degree (docs/fit.md); a steep incline is for `simulate`.
pub fn check_tilt(rig_path: &Path, rig: &Rig<f64>) -> Result<(), SceneError> {
    if rig.rail_tilt.abs() <= TILT_SEARCH {
        return Ok(());
    }
    let max = TILT_SEARCH.to_degrees();
    Err(SceneError::Invalid {
        path: rig_path.to_owned(),
        message: format!(
            "rig.rail_tilt_deg must be within {} degrees of level for a fit (the widest tilt the fit searches; a lab's rail is levelled to a fraction of a degree), got {}",
            sig4(max),
            sig4(rig.rail_tilt.to_degrees())
        ),
    })
}

/// A hint when `rod` is the markers' `median` in another unit: the rig file takes metres, and
/// a rod typed in centimetres, millimetres or inches is the commonest slip.
fn unit_slip(rod: f64, median: f64) -> String {
    let ratio = rod / median;
    [
        ("centimetres", 100.0),
        ("millimetres", 1000.0),
        ("inches", 1.0 / 0.0254),
    ]
    .into_iter()
    .find(|(_, f)| (ratio / f - 1.0).abs() < ROD_LENGTH_TOLERANCE)
    .map_or(String::new(), |(unit, f)| {
        format!(
            " (a length in {unit}? the rig file takes metres: {} m)",
            sig4(rod / f)
        )
    })
}

/// `v` to four significant digits ([`sig`]): the median is a measurement, and the range's ends
/// carry no more digits than it does (0.2008, not 0.20080000000000006).
fn sig4(v: f64) -> String {
    sig(v, 4)
}
