//! Mis-tracked frames found before any model is fitted: a frame whose marker lies far from
//! the quadratic through its neighbours (which any smooth motion follows to far below the
//! noise at camera rates) is dropped from the fit and counted.

use super::problem::Observations;

/// Neighbours on each side of the local quadratic.
const HALF: usize = 6;

/// A deviation beyond this many noise deviations marks a frame as mis-tracked.
const THRESHOLD: f64 = 8.0;

/// Drop (set to missing) every marker position that sits more than [`THRESHOLD`] noise
/// deviations (`sigma`, per marker) from the quadratic through its neighbours; returns how
/// many positions were dropped per marker (slider, bob).
pub fn drop_from_tracks(obs: &mut Observations, sigma: [f64; 2]) -> [usize; 2] {
    let mut dropped = [0; 2];
    for (m, count) in dropped.iter_mut().enumerate() {
        let track = if m == 0 { &obs.slider } else { &obs.bob };
        // Below a micrometre the quadratic's own error on fast motion would count.
        let limit = THRESHOLD * sigma[m].max(1e-6);
        let bad: Vec<usize> = (0..track.len())
            .filter(|&i| {
                let Some(here) = track[i] else {
                    return false;
                };
                let lo = i.saturating_sub(HALF);
                let hi = (i + HALF).min(track.len() - 1);
                let near: Vec<(f64, [f64; 2])> = (lo..=hi)
                    .filter(|&j| j != i)
                    .filter_map(|j| track[j].map(|p| (obs.times[j] - obs.times[i], p)))
                    .collect();
                if near.len() < 6 {
                    return false;
                }
                (0..2).any(|k| {
                    predict(&near, k).is_some_and(|v| (here[k] - v).abs() > limit)
                        && median_predict(&near, k).is_some_and(|v| (here[k] - v).abs() > limit)
                })
            })
            .collect();
        let track = if m == 0 {
            &mut obs.slider
        } else {
            &mut obs.bob
        };
        for i in bad {
            track[i] = None;
            *count += 1;
        }
    }
    dropped
}

/// The least-squares quadratic through the neighbours (times relative to the frame), at 0.
fn predict(near: &[(f64, [f64; 2])], k: usize) -> Option<f64> {
    let mut a = nalgebra::Matrix3::zeros();
    let mut b = nalgebra::Vector3::zeros();
    let scale = near
        .iter()
        .map(|(t, _)| t.abs())
        .fold(0.0, f64::max)
        .max(1e-12);
    for (t, p) in near {
        let u = t / scale;
        let phi = nalgebra::Vector3::new(1.0, u, u * u);
        a += phi * phi.transpose();
        b += phi * p[k];
    }
    a.lu().solve(&b).map(|c| c[0])
}

/// The same prediction from the neighbours without the one farthest from it: a second
/// mis-tracked frame among the neighbours must not make a good frame look bad.
fn median_predict(near: &[(f64, [f64; 2])], k: usize) -> Option<f64> {
    let first = predict(near, k)?;
    let worst = near
        .iter()
        .enumerate()
        .map(|(i, (t, p))| {
            let others: Vec<(f64, [f64; 2])> = near
                .iter()
                .enumerate()
                .filter(|(j, _)| *j != i)
                .map(|(_, q)| *q)
                .collect();
            let v = predict(&others, k).unwrap_or(first);
            let _ = t;
            (i, (p[k] - v).abs())
        })
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(i, _)| i)?;
    let kept: Vec<(f64, [f64; 2])> = near
        .iter()
        .enumerate()
        .filter(|(j, _)| *j != worst)
        .map(|(_, q)| *q)
        .collect();
    predict(&kept, k)
}
