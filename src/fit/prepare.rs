//! The recording made ready to fit: enough frames with both markers, times from zero, each
//! marker's noise measured from its track (or given) and the mis-tracked positions dropped.

use super::error::FitError;
use super::motion::{track_span, STILL_NOISES};
use super::noise::{self, NoiseEstimate};
use super::outliers;
use super::problem::Observations;
use super::settings::FitSettings;
use std::sync::Arc;

/// The recording ready to fit: times from zero, mis-tracked positions out, each marker's noise.
pub(super) struct Prepared {
    pub obs: Arc<Observations>,
    /// Frames in the recording as read.
    pub n_frames: usize,
    /// Noise per marker used as weights (m).
    pub sigma: [f64; 2],
    /// The noise measurements (or the given noise).
    pub noise: [Option<NoiseEstimate>; 2],
    /// Degrees of freedom of the noise measurement (the chi-square's F test).
    pub noise_dof: f64,
    /// Positions dropped from the tracks (slider, bob).
    pub dropped: [usize; 2],
    /// The median step between frame times (s), for the nuisances' plausible ranges.
    pub frame: f64,
}

/// The data checked, the noise measured, the mis-tracked positions dropped.
pub(super) fn prepare(obs: Observations, settings: &FitSettings) -> Result<Prepared, FitError> {
    let mut obs = check_data(obs)?;
    let n_frames = obs.times.len();
    let (sigma, noise, dropped) = noise_and_outliers(&mut obs, settings)?;
    match enough_frames(&obs) {
        Err(FitError::TooFewFrames(left)) => {
            return Err(all_dropped(&obs, left, dropped, sigma, settings))
        }
        // Mis-tracked frames are a few of a track; most of one is a noise that is not the
        // track's (a bob noise of 1e-10 m dropped 1991 of 2001 positions and the rest was
        // fitted to a misfit with exit 0).
        _ if most_dropped(&obs, dropped) => {
            let left = both_seen(&obs);
            return Err(all_dropped(&obs, left, dropped, sigma, settings));
        }
        _ => {}
    }
    if let Some(message) = nothing_moves(&obs, sigma) {
        return Err(FitError::NoMotion(message));
    }
    let noise_dof = noise.iter().flatten().map(|e| e.dof).sum::<f64>().max(2.0);
    Ok(Prepared {
        frame: super::problem::frame_step(&obs.times),
        obs: Arc::new(obs),
        n_frames,
        sigma,
        noise,
        noise_dof,
        dropped,
    })
}

/// The recording is usable: enough frames with both markers; times from zero.
fn check_data(mut obs: Observations) -> Result<Observations, FitError> {
    enough_frames(&obs)?;
    let t0 = obs.times[0];
    obs.times.iter_mut().for_each(|t| *t -= t0);
    Ok(obs)
}

/// Frames with both markers.
fn both_seen(obs: &Observations) -> usize {
    obs.slider
        .iter()
        .zip(&obs.bob)
        .filter(|(s, b)| s.is_some() && b.is_some())
        .count()
}

/// Whether the filter dropped more than half of either marker's positions.
fn most_dropped(obs: &Observations, dropped: [usize; 2]) -> bool {
    let seen = [&obs.slider, &obs.bob].map(|t| t.iter().flatten().count());
    (0..2).any(|m| dropped[m] > seen[m])
}

/// At least ten frames with both markers.
pub(super) fn enough_frames(obs: &Observations) -> Result<(), FitError> {
    let both = both_seen(obs);
    if both < 10 {
        return Err(FitError::TooFewFrames(both));
    }
    Ok(())
}

/// Why the filtered recording cannot be fitted (there were ten or more frames with both
/// markers before it ran): too few frames left, or more than half of a track dropped; how many
/// positions of each marker it dropped, the noise it measured them against and where that
/// noise came from, and the fix.
fn all_dropped(
    obs: &Observations,
    left: usize,
    dropped: [usize; 2],
    sigma: [f64; 2],
    settings: &FitSettings,
) -> FitError {
    let seen = [&obs.slider, &obs.bob].map(|t| t.iter().flatten().count());
    let (source, fix) = if settings.noise.is_some() {
        (
            "given with --noise",
            "give the noise the tracks have with --noise, or leave it out to measure it",
        )
    } else {
        (
            "measured from the tracks",
            "the tracks jump from frame to frame far beyond their measured noise; check the frame times and the markers (--noise sets the noise)",
        )
    };
    let leaving = if left < 10 {
        format!("leaving {left} frames with both markers where the fit needs at least 10")
    } else {
        "more than half of a track, which is no longer a few mis-tracked frames".to_string()
    };
    FitError::AllDropped(format!(
        "the mis-tracked filter dropped {} of {} slider and {} of {} bob positions (each more than {} noise deviations from the quadratic through its neighbours, with the noise {source}: slider {:.3e} m, bob {:.3e} m), {leaving}: {fix}",
        dropped[0],
        dropped[0] + seen[0],
        dropped[1],
        dropped[1] + seen[1],
        outliers::THRESHOLD,
        sigma[0],
        sigma[1],
    ))
}

/// The sentence for a recording in which neither marker moves beyond [`STILL_NOISES`] noise
/// deviations (`sigma`, per marker) in either coordinate ([`track_span`]): no slide shows
/// mu_kinetic and no swing bounds mu_static, so there is nothing to fit. `None` when either
/// marker moves.
fn nothing_moves(obs: &Observations, sigma: [f64; 2]) -> Option<String> {
    let mut spans = [0.0; 2];
    for (m, track) in [&obs.slider, &obs.bob].into_iter().enumerate() {
        for k in 0..2 {
            spans[m] = f64::max(spans[m], track_span(track, k)?);
        }
        if spans[m] > STILL_NOISES * sigma[m] {
            return None;
        }
    }
    Some(format!(
        "nothing moves in this recording: the slider's track spans {:.2e} m and the bob's {:.2e} m (2nd to 98th percentile, the wider coordinate), within {STILL_NOISES} noise deviations ({:.2e} m, {:.2e} m); mu is not identifiable without motion (no slide shows mu_kinetic, no swing bounds mu_static): fit a recording of a release",
        spans[0], spans[1], sigma[0], sigma[1]
    ))
}

/// The noise used as weights (m), the measurements behind it, and the positions dropped.
type NoiseAndOutliers = ([f64; 2], [Option<NoiseEstimate>; 2], [usize; 2]);

/// Each marker's noise, measured from its track (or given), and the mis-tracked
/// positions dropped. Returns the noise used as weights, the measurements and the drops.
fn noise_and_outliers(
    obs: &mut Observations,
    settings: &FitSettings,
) -> Result<NoiseAndOutliers, FitError> {
    if let Some(given) = settings.noise {
        if !given.iter().all(|s| s.is_finite() && *s > 0.0) {
            return Err(FitError::Settings(format!(
                "noise must be finite and positive (m), got {given:?}"
            )));
        }
    }
    let measured = noise::from_tracks(obs);
    let pick = |m: usize, est: &[Option<NoiseEstimate>; 2]| -> f64 {
        match (settings.noise, est[m], est[1 - m]) {
            (Some(g), _, _) => g[m],
            (None, Some(e), _) if e.sigma > 0.0 => e.sigma,
            (None, _, Some(o)) if o.sigma > 0.0 => o.sigma,
            // Noiseless tracks: a floor far below any camera, so the weights stay finite.
            _ => 1e-7,
        }
    };
    let first = [pick(0, &measured), pick(1, &measured)];
    let dropped = outliers::drop_from_tracks(obs, first);
    // The trimmed measurement is robust already; measure again without the dropped frames.
    let measured = if dropped.iter().any(|&d| d > 0) {
        noise::from_tracks(obs)
    } else {
        measured
    };
    let sigma = [pick(0, &measured), pick(1, &measured)];
    let reported = match settings.noise {
        Some(g) => [0, 1].map(|m| {
            Some(NoiseEstimate {
                sigma: g[m],
                dof: f64::INFINITY,
                source: "given",
            })
        }),
        None => measured,
    };
    Ok((sigma, reported, dropped))
}
