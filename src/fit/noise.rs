//! Each marker's measurement noise from the data alone, before any model is fitted: the third
//! differences of a track sampled at consecutive frames cancel any smooth motion (a quadratic
//! exactly; a pendulum at camera rates to far below a pixel) and leave 20 times the noise
//! variance. A fit that does not describe the data cannot hide behind this estimate, unlike a
//! noise level read from its own residuals.

use super::problem::Observations;

/// Variance factor of a third difference of white noise: 1 + 9 + 9 + 1.
const THIRD_DIFF_VAR: f64 = 20.0;

/// Sum over lags of the squared correlations of overlapping third differences
/// (1 + 2 (0.75^2 + 0.3^2 + 0.05^2)): how many of them make one independent square.
const OVERLAP: f64 = 2.31;

/// Third differences beyond this many noise deviations are mis-tracked frames, not noise.
const TRIM: f64 = 4.5;

/// One marker's noise estimate.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct NoiseEstimate {
    /// Standard deviation per coordinate (m).
    pub sigma: f64,
    /// Effective number of independent squares behind it (the estimate's degrees of freedom).
    pub dof: f64,
    /// Where the value comes from: `"data"` (third differences) or `"given"`.
    pub source: &'static str,
}

/// Noise of each marker (slider, bob) from its third differences; `None` for a marker with
/// fewer than 20 runs of four consecutive frames.
pub fn from_tracks(obs: &Observations) -> [Option<NoiseEstimate>; 2] {
    [0, 1].map(|m| estimate(if m == 0 { &obs.slider } else { &obs.bob }))
}

/// Frame times scattering less than this share of a frame about their uniform grid are
/// exact for the fit (a CSV's microsecond digits); more than a quarter frame is a variable
/// frame rate, whose times are the camera's own, not a clock's error.
const TIME_NOISE_RANGE: [f64; 2] = [1e-3, 0.25];

/// The frame times' noise (s): the RMS deviation of `times` from the uniform grid that fits
/// them best (least squares on the frame numbers the median step gives, so a dropped frame is
/// a gap, not an error). A phone writes its timestamps rounded to the millisecond (at 240
/// frames/s they scatter 0.29 ms about the grid) or jittered by its clock; a marker moving at
/// v is then off by v times it. 0 when the scatter is below a thousandth of a frame, or above
/// a quarter of one (a variable frame rate: the times are then the frames' own).
pub fn frame_time_noise(times: &[f64]) -> f64 {
    let n = times.len();
    if n < 10 {
        return 0.0;
    }
    let mut steps: Vec<f64> = times.windows(2).map(|w| w[1] - w[0]).collect();
    let mid = steps.len() / 2;
    let median = *steps.select_nth_unstable_by(mid, f64::total_cmp).1;
    // The mean of the steps near the median, not the median: 240 frames/s written in whole
    // milliseconds steps by 4, 4, 4, 5, 4, 4, 5 ms, whose median is 4 and mean 4.167 (a
    // dropped frame's double step is left out).
    let near: Vec<f64> = steps
        .iter()
        .copied()
        .filter(|d| *d > 0.5 * median && *d < 1.5 * median)
        .collect();
    let step = near.iter().sum::<f64>() / near.len().max(1) as f64;
    if !(step.is_finite() && step > 0.0) {
        return 0.0;
    }
    let k: Vec<f64> = times
        .iter()
        .map(|t| ((t - times[0]) / step).round())
        .collect();
    let (mk, mt) = (
        k.iter().sum::<f64>() / n as f64,
        times.iter().sum::<f64>() / n as f64,
    );
    let (mut skk, mut skt) = (0.0, 0.0);
    for (ki, ti) in k.iter().zip(times) {
        skk += (ki - mk) * (ki - mk);
        skt += (ki - mk) * (ti - mt);
    }
    if skk <= 0.0 {
        return 0.0;
    }
    let slope = skt / skk;
    let ss: f64 = k
        .iter()
        .zip(times)
        .map(|(ki, ti)| (ti - mt - slope * (ki - mk)).powi(2))
        .sum();
    let rms = (ss / (n - 2) as f64).sqrt();
    if rms < TIME_NOISE_RANGE[0] * step || rms > TIME_NOISE_RANGE[1] * step {
        0.0
    } else {
        rms
    }
}

/// A track's third differences, both coordinates of each run of four consecutive frames, in
/// frame order.
fn third_differences(track: &[Option<[f64; 2]>]) -> impl Iterator<Item = f64> + '_ {
    track
        .windows(4)
        .flat_map(|w| match w {
            [Some(a), Some(b), Some(c), Some(d)] => {
                [0, 1].map(|k| Some(d[k] - 3.0 * c[k] + 3.0 * b[k] - a[k]))
            }
            _ => [None, None],
        })
        .flatten()
}

/// Trimmed mean of squares of a track's third differences, starting from their median
/// absolute value (robust to mis-tracked frames) and keeping those within [`TRIM`]
/// deviations. One vector of absolute values is held (the median needs it), sized once: the
/// trimmed sum takes the differences again, in the same order, rather than a copy (a million
/// frames' track would otherwise hold and page in three 16 MB vectors).
fn estimate(track: &[Option<[f64; 2]>]) -> Option<NoiseEstimate> {
    let mut abs = Vec::with_capacity(2 * track.len().saturating_sub(3));
    abs.extend(third_differences(track).map(f64::abs));
    let n = abs.len();
    if n < 40 {
        return None;
    }
    // The median by selection, not a sort: linear in a million frames.
    let mid = n / 2;
    let robust = *abs.select_nth_unstable_by(mid, f64::total_cmp).1 / 0.674_489_750_196_081_7;
    drop(abs);
    if !(robust.is_finite() && robust > 0.0) {
        // Noiseless (or quantised to zero steps) data: no noise level to speak of.
        return Some(NoiseEstimate {
            sigma: 0.0,
            dof: n as f64 / OVERLAP,
            source: "data",
        });
    }
    let (sum, kept) = third_differences(track)
        .filter(|v| v.abs() <= TRIM * robust)
        .fold((0.0, 0usize), |(s, k), v| (s + v * v, k + 1));
    let var = sum / kept as f64;
    Some(NoiseEstimate {
        sigma: (var / THIRD_DIFF_VAR).sqrt(),
        dof: kept as f64 / OVERLAP,
        source: "data",
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// White noise on a fast pendulum-like motion: the estimate recovers the noise, not the
    /// motion, within its own statistical error.
    #[test]
    fn recovers_white_noise_under_smooth_motion() {
        let mut state = 12345u64;
        let mut gauss = || {
            let mut u = || {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                (state >> 11) as f64 / (1u64 << 53) as f64
            };
            let (a, b) = (u().max(1e-300), u());
            (-2.0 * a.ln()).sqrt() * (std::f64::consts::TAU * b).cos()
        };
        let n = 4000;
        let sigma = 2e-4;
        let times: Vec<f64> = (0..n).map(|k| k as f64 * 1e-3).collect();
        let track = |amp: f64, w: f64, noise: &mut dyn FnMut() -> f64| -> Vec<Option<[f64; 2]>> {
            times
                .iter()
                .map(|t| {
                    Some([
                        amp * (w * t).sin() + sigma * noise(),
                        -amp * (w * t).cos() + sigma * noise(),
                    ])
                })
                .collect()
        };
        let slider = track(0.05, 6.0, &mut gauss);
        let mut bob = track(0.3, 9.0, &mut gauss);
        bob[100] = Some([5.0, 5.0]); // a mis-tracked frame
        bob[2000] = None; // a gap
        let obs = Observations {
            times: times.clone(),
            slider,
            bob,
        };
        for est in from_tracks(&obs) {
            let est = est.unwrap();
            let rel = 1.0 / est.dof.sqrt();
            assert!(
                (est.sigma / sigma - 1.0).abs() < 4.0 * rel,
                "{} vs {sigma}",
                est.sigma
            );
        }
    }
}

#[cfg(test)]
mod time_tests {
    use super::frame_time_noise;

    /// Times rounded to the millisecond at 240 frames/s scatter by 1 ms / sqrt(12) about their
    /// grid (uniform rounding errors); exact times, and times with a dropped frame, have none;
    /// a frame rate that changes by half has its own times.
    #[test]
    fn rounded_times_have_the_rounding_noise_and_exact_ones_none() {
        let exact: Vec<f64> = (0..480).map(|k| k as f64 / 240.0).collect();
        assert_eq!(frame_time_noise(&exact), 0.0);
        let gap: Vec<f64> = exact.iter().copied().filter(|t| *t != 0.5).collect();
        assert_eq!(frame_time_noise(&gap), 0.0);
        let rounded: Vec<f64> = exact
            .iter()
            .map(|t| (t * 1000.0).round() / 1000.0)
            .collect();
        let s = frame_time_noise(&rounded);
        let uniform = 1e-3 / 12f64.sqrt();
        assert!((s / uniform - 1.0).abs() < 0.1, "{s} against {uniform}");
        let mut variable = exact[..240].to_vec();
        variable.extend((0..240).map(|k| 1.0 + k as f64 / 160.0));
        assert_eq!(frame_time_noise(&variable), 0.0);
    }
}
