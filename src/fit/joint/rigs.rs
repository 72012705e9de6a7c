//! Releases of another rig told apart before a joint fit: the marker distance (the rod, as the
//! camera sees it) of each release against the releases' median.

use super::settings::Release;
use crate::fit::problem::Observations;

/// Marker distance per release: the median slider-to-bob distance and the spread of one
/// frame's distance (a robust standard deviation).
fn marker_distance(obs: &Observations) -> Option<(f64, f64)> {
    let mut d: Vec<f64> = crate::fit::guess::marker_distances(obs)
        .into_iter()
        .filter(|d| d.is_finite())
        .collect();
    if d.len() < 10 {
        return None;
    }
    d.sort_by(f64::total_cmp);
    let med = d[d.len() / 2];
    let mut dev: Vec<f64> = d.iter().map(|x| (x - med).abs()).collect();
    dev.sort_by(f64::total_cmp);
    Some((med, 1.4826 * dev[dev.len() / 2]))
}

/// Releases of another rig: their marker distance (the rod, as the camera sees it) differs
/// from the releases' median by more than five times the frames' spread plus 2 % (what a
/// camera's scale may differ by between releases). The names of those releases.
pub fn other_rigs(releases: &[Release]) -> Vec<(String, f64, f64)> {
    let d: Vec<Option<(f64, f64)>> = releases.iter().map(|r| marker_distance(&r.obs)).collect();
    let mut meds: Vec<f64> = d.iter().flatten().map(|x| x.0).collect();
    if meds.len() < 2 {
        return Vec::new();
    }
    meds.sort_by(f64::total_cmp);
    let median = meds[meds.len() / 2];
    releases
        .iter()
        .zip(&d)
        .filter_map(|(r, d)| {
            let (m, s) = (*d)?;
            ((m - median).abs() > 5.0 * s + 0.02 * median).then(|| (r.name.clone(), m, median))
        })
        .collect()
}
