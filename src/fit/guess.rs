//! Starting values from the data, because the cost is only piecewise smooth in mu: the angle
//! and its rate from the first frames' geometry, the slider's state from its track, and mu
//! from the accelerations of a sliding stretch through the sliding equation.

use super::priors::RigMeasurement;
use super::problem::Observations;
use crate::model::{sign, Rig, Shorthands};

/// Least-squares quadratic through (t, y): value and first two derivatives at `t0`, and the
/// standard error of the slope from the fit's own residuals.
fn quadratic_fit(t: &[f64], y: &[f64], t0: f64) -> Option<([f64; 3], f64)> {
    if t.len() < 3 {
        return None;
    }
    // Normal equations of y = c0 + c1 (t - t0) + c2 (t - t0)^2.
    let mut a = nalgebra::Matrix3::zeros();
    let mut b = nalgebra::Vector3::zeros();
    for (&ti, &yi) in t.iter().zip(y) {
        let d = ti - t0;
        let phi = nalgebra::Vector3::new(1.0, d, d * d);
        a += phi * phi.transpose();
        b += phi * yi;
    }
    let cov = a.try_inverse()?;
    let c = cov * b;
    let ss: f64 = t
        .iter()
        .zip(y)
        .map(|(&ti, &yi)| {
            let d = ti - t0;
            (yi - c[0] - c[1] * d - c[2] * d * d).powi(2)
        })
        .sum();
    let s2 = ss / (t.len() as f64 - 3.0).max(1.0);
    Some(([c[0], c[1], 2.0 * c[2]], (s2 * cov[(1, 1)]).sqrt()))
}

/// Value and first two derivatives at `t0` of the least-squares quadratic.
fn quadratic_at(t: &[f64], y: &[f64], t0: f64) -> Option<[f64; 3]> {
    quadratic_fit(t, y, t0).map(|(c, _)| c)
}

/// Rod angle in the model convention (y down) from rail-frame markers with y up.
pub fn angle(slider: [f64; 2], bob: [f64; 2]) -> f64 {
    (-(bob[1] - slider[1])).atan2(bob[0] - slider[0])
}

/// The frames with both markers: their times, the slider's x and the rod angle (unwrapped to
/// be continuous), read off the recording once for every guess. A million frames make 24 MB
/// of these; each guess reading its own copy, side by side, took the fit's peak memory from
/// 131 to 168 MB.
pub struct Tracks {
    t: Vec<f64>,
    x: Vec<f64>,
    theta: Vec<f64>,
    /// The recording's first frame time.
    t0: Option<f64>,
}

impl Tracks {
    /// The tracks of `obs`.
    pub fn new(obs: &Observations) -> Tracks {
        let n = obs.times.len();
        let mut tracks = Tracks {
            t: Vec::with_capacity(n),
            x: Vec::with_capacity(n),
            theta: Vec::with_capacity(n),
            t0: obs.times.first().copied(),
        };
        for ((ti, s), b) in obs.times.iter().zip(&obs.slider).zip(&obs.bob) {
            if let (Some(s), Some(b)) = (s, b) {
                let mut a = angle(*s, *b);
                if let Some(prev) = tracks.theta.last() {
                    a += (2.0 * std::f64::consts::PI)
                        * ((prev - a) / (2.0 * std::f64::consts::PI)).round();
                }
                tracks.t.push(*ti);
                tracks.x.push(s[0]);
                tracks.theta.push(a);
            }
        }
        tracks
    }
}

/// Initial state (x, theta, x', theta') from a quadratic fit over the first `window` frames,
/// with the standard error of x' (to tell a release from rest).
pub fn initial_state(tracks: &Tracks, window: usize) -> Option<([f64; 4], f64)> {
    let t0 = tracks.t0?;
    let (ts, xs, th) = (&tracks.t, &tracks.x, &tracks.theta);
    let n = window.max(3).min(ts.len());
    let (x, x_dot_se) = quadratic_fit(&ts[..n], &xs[..n], t0)?;
    let a = quadratic_at(&ts[..n], &th[..n], t0)?;
    Some(([x[0], a[0], x[1], a[1]], x_dot_se))
}

/// The markers' distance (the rod as the camera sees it) in each frame with both markers.
pub fn marker_distances(obs: &Observations) -> Vec<f64> {
    obs.slider
        .iter()
        .zip(&obs.bob)
        .filter_map(|(s, b)| {
            let (s, b) = ((*s)?, (*b)?);
            Some(((b[0] - s[0]).powi(2) + (b[1] - s[1]).powi(2)).sqrt())
        })
        .collect()
}

/// Median rod length seen in the frames with both markers.
pub fn rod_length(obs: &Observations) -> Option<f64> {
    let mut d = marker_distances(obs);
    if d.is_empty() {
        return None;
    }
    let mid = d.len() / 2;
    Some(*d.select_nth_unstable_by(mid, f64::total_cmp).1)
}

/// mu_kinetic from the sliding equation solved for mu at frames where the slider clearly
/// moves: x'' (D + mu s sigma a) = c - mu s sigma b, with x', x'', theta, theta' from local
/// quadratic fits; the median over the frames. `None` when the slider never clearly slides.
pub fn mu_from_sliding(tracks: &Tracks, rig: &Rig<f64>, half_window: usize) -> Option<f64> {
    let (ts, xs, th) = (&tracks.t, &tracks.x, &tracks.theta);
    if ts.len() < 2 * half_window + 1 {
        return None;
    }
    let h = half_window;
    let mut est = Vec::new();
    let mut speeds = Vec::new();
    // Every few frames is enough for a median, and the window is wide.
    for i in (h..ts.len() - h).step_by((h / 4).max(1)) {
        let Some(x) = quadratic_at(&ts[i - h..=i + h], &xs[i - h..=i + h], ts[i]) else {
            continue;
        };
        speeds.push(x[1].abs());
        let Some(a) = quadratic_at(&ts[i - h..=i + h], &th[i - h..=i + h], ts[i]) else {
            continue;
        };
        est.push((x, a));
    }
    // "Clearly sliding": faster than a fifth of the fastest slide seen.
    let vmax = speeds.iter().cloned().fold(0.0, f64::max);
    if vmax < 1e-3 {
        return None;
    }
    let mut mus: Vec<f64> = est
        .iter()
        .filter(|(x, _)| x[1].abs() > 0.2 * vmax)
        .filter_map(|(x, a)| {
            let sh = Shorthands::new(rig, a[0], a[1]);
            let s = sign(x[1]);
            let sigma = sign(sh.q);
            let den = s * sigma * (x[2] * sh.a + sh.b);
            let mu = (sh.c - x[2] * sh.d) / den;
            (den.abs() > 1e-12 && mu.is_finite() && mu >= 0.0).then_some(mu)
        })
        .collect();
    if mus.len() < 5 {
        return None;
    }
    let mid = mus.len() / 2;
    Some(*mus.select_nth_unstable_by(mid, f64::total_cmp).1)
}

/// mu_static from the stick-to-slide onsets seen in the data: where a stretch with the slider
/// at rest ends, static friction was just exhausted, so mu_static ~ |c| / |b| there (the
/// needed ratio of the pendulum model, from the smoothed angle and rate at the last stuck
/// frame). The median over onsets; `None` when the data show no onset after a stuck stretch.
pub fn mu_static_from_onsets(tracks: &Tracks, rig: &Rig<f64>, half_window: usize) -> Option<f64> {
    let (ts, xs, th) = (&tracks.t, &tracks.x, &tracks.theta);
    let h = half_window;
    if ts.len() < 2 * h + 1 {
        return None;
    }
    // Rates every few frames are enough to find the stuck stretches; the onset time itself is
    // refined on the raw track below.
    let stride = (h / 4).max(1);
    let fits: Vec<(usize, f64, f64)> = (h..ts.len() - h)
        .step_by(stride)
        .filter_map(|i| {
            let (x, se) = quadratic_fit(&ts[i - h..=i + h], &xs[i - h..=i + h], ts[i])?;
            Some((i, x[1], se))
        })
        .collect();
    let vmax = fits.iter().map(|f| f.1.abs()).fold(0.0, f64::max);
    let mut ratios = Vec::new();
    let mut run = 0;
    for &(first_moving, v, se) in &fits {
        if v.abs() < (3.0 * se).max(0.02 * vmax) {
            run += stride;
            continue;
        }
        // An onset: a stuck stretch of at least a window, then motion. The smoothed rate
        // crosses its threshold late; the onset time itself comes from a hinge fit of the raw
        // track (at rest, then a quadratic-and-cubic start), and the needed ratio is read there.
        if run >= h {
            let lo = first_moving.saturating_sub(4 * h);
            let hi = (first_moving + 2 * h).min(ts.len() - 1);
            let onset = (lo + 1..hi)
                .map(|j| (j, hinge_sse(&ts[lo..=hi], &xs[lo..=hi], ts[j])))
                .min_by(|a, b| a.1.total_cmp(&b.1))
                .map(|(j, _)| j);
            if let Some(j) = onset {
                let (a0, a1) = (j.saturating_sub(h), (j + h).min(ts.len() - 1));
                if let Some(a) = quadratic_at(&ts[a0..=a1], &th[a0..=a1], ts[j]) {
                    ratios.push(Shorthands::new(rig, a[0], a[1]).pull());
                }
            }
        }
        run = 0;
    }
    if ratios.is_empty() {
        return None;
    }
    let mid = ratios.len() / 2;
    Some(*ratios.select_nth_unstable_by(mid, f64::total_cmp).1)
}

/// Residual sum of squares of the hinge x = x0 (t <= t*), x0 + c2 u^2 + c3 u^3 (u = t - t*,
/// for t > t*) fitted by linear least squares: a slip starts with a jump in x'' when
/// mu_s > mu_k (the u^2 term) and smoothly when they are equal (the u^3 term).
fn hinge_sse(t: &[f64], x: &[f64], t_star: f64) -> f64 {
    let basis = |ti: f64| {
        let u = (ti - t_star).max(0.0);
        nalgebra::Vector3::new(1.0, u * u, u * u * u)
    };
    // The frames up to t* (the times increase) have the basis (1, 0, 0): each adds one to the
    // count and its position to the sum, and the fit's value there is x0. Written out, the
    // same numbers in the same order as the general terms give (their other products are
    // zeros added to sums that start at +0): the onset search calls this for every frame of
    // a window, a million frames' recording for every onset.
    let rest = t.partition_point(|&ti| ti <= t_star);
    let mut a = nalgebra::Matrix3::zeros();
    let mut b = nalgebra::Vector3::zeros();
    for &xi in &x[..rest] {
        a[(0, 0)] += 1.0;
        b[0] += xi;
    }
    for (&ti, &xi) in t[rest..].iter().zip(&x[rest..]) {
        let phi = basis(ti);
        a += phi * phi.transpose();
        b += phi * xi;
    }
    let Some(c) = a.lu().solve(&b) else {
        return f64::INFINITY;
    };
    // A coefficient that is not finite makes the zeros' products NaN in the full terms: take
    // those, so that the sum stays the one the full terms give.
    if !c.iter().all(|v| v.is_finite()) {
        return t
            .iter()
            .zip(x)
            .map(|(&ti, &xi)| (xi - basis(ti).dot(&c)).powi(2))
            .sum();
    }
    x[..rest]
        .iter()
        .map(|&xi| (xi - c[0]).powi(2))
        .chain(
            t[rest..]
                .iter()
                .zip(&x[rest..])
                .map(|(&ti, &xi)| (xi - basis(ti).dot(&c)).powi(2)),
        )
        .sum()
}

/// The rig to start from: with a measured rod, its length at the recording's median
/// slider-bob marker distance when that lies within 5 of the measurement's deviations of the
/// file's value (the markers measure the rod to micrometres; a base model fitted on a rod a
/// ruler's error off takes friction nuisances for the wrong geometry and can end in another
/// optimum). A rigid pendulum's equivalent length moves in proportion. Only the start: the
/// prior stays centred on the file's value.
pub fn start_from_markers(
    obs: &Observations,
    rig: &Rig<f64>,
    measured: Option<&RigMeasurement>,
) -> Rig<f64> {
    let Some((file, sd)) = measured.map(|m| m.rod_length).filter(|(_, sd)| *sd > 0.0) else {
        return *rig;
    };
    let mut d: Vec<f64> = obs
        .slider
        .iter()
        .zip(&obs.bob)
        .filter_map(|(s, b)| {
            let (s, b) = ((*s)?, (*b)?);
            Some((b[0] - s[0]).hypot(b[1] - s[1]))
        })
        .filter(|d| d.is_finite())
        .collect();
    if d.len() < 10 {
        return *rig;
    }
    let median = crate::data::calibrate::median(&mut d);
    if (median - file).abs() > 5.0 * sd {
        return *rig;
    }
    let mut out = *rig;
    let ratio = rig.rod_length / rig.marker_length;
    out.marker_length = median;
    out.rod_length = median * ratio;
    out
}

#[cfg(test)]
mod tests {
    use super::hinge_sse;

    /// The hinge's sum of squares with every frame's terms written in full, as it was before
    /// the frames up to t* were summed apart.
    fn hinge_sse_in_full(t: &[f64], x: &[f64], t_star: f64) -> f64 {
        let basis = |ti: f64| {
            let u = (ti - t_star).max(0.0);
            nalgebra::Vector3::new(1.0, u * u, u * u * u)
        };
        let mut a = nalgebra::Matrix3::zeros();
        let mut b = nalgebra::Vector3::zeros();
        for (&ti, &xi) in t.iter().zip(x) {
            let phi = basis(ti);
            a += phi * phi.transpose();
            b += phi * xi;
        }
        let Some(c) = a.lu().solve(&b) else {
            return f64::INFINITY;
        };
        t.iter()
            .zip(x)
            .map(|(&ti, &xi)| (xi - basis(ti).dot(&c)).powi(2))
            .sum()
    }

    /// The onset search picks the smallest sum: the frames summed apart must give the same
    /// number to the bit, at every frame time and between them, on a slider at rest (with
    /// signed noise) that then starts to slide.
    #[test]
    fn the_hinge_sum_is_the_full_sum_to_the_bit() {
        let n = 301;
        let t: Vec<f64> = (0..n).map(|i| 12.3 + i as f64 * 1e-4).collect();
        let x: Vec<f64> = t
            .iter()
            .enumerate()
            .map(|(i, &ti)| {
                let u = (ti - t[200]).max(0.0);
                let noise = 1e-4 * ((i as f64 * 12.9898).sin() * 43758.5453).fract();
                -0.01 + 3.0 * u * u + noise
            })
            .collect();
        let mut stars: Vec<f64> = t.clone();
        stars.extend(t.windows(2).map(|w| 0.5 * (w[0] + w[1])));
        stars.extend([t[0] - 1.0, t[n - 1] + 1.0]);
        for s in stars {
            let (fast, full) = (hinge_sse(&t, &x, s), hinge_sse_in_full(&t, &x, s));
            assert!(
                fast.to_bits() == full.to_bits() || (fast.is_nan() && full.is_nan()),
                "t* = {s}: {fast} against {full}"
            );
        }
    }
}
