//! Mis-tracked frames found before any model is fitted: a frame whose marker lies far from
//! the quadratic through its neighbours (which any smooth motion follows to far below the
//! noise at camera rates) is dropped from the fit and counted. After a fit, the positions whose
//! residual the model cannot explain ([`residual_outliers`]) are dropped or down-weighted.

use super::adequacy::numerical_accuracy_m;
use super::problem::{Observations, TrajectoryProblem};
use super::settings::FitSettings;
use super::solve::solve;
use nalgebra::DVector;

/// Neighbours on each side of the local quadratic.
const HALF: usize = 6;

/// A deviation beyond this many noise deviations marks a frame as mis-tracked.
pub(super) const THRESHOLD: f64 = 8.0;

/// Drop (set to missing) every marker position that sits more than [`THRESHOLD`] noise
/// deviations (`sigma`, per marker) from the quadratic through its neighbours; returns how
/// many positions were dropped per marker (slider, bob).
pub fn drop_from_tracks(obs: &mut Observations, sigma: [f64; 2]) -> [usize; 2] {
    let mut dropped = [0; 2];
    let n = obs.times.len();
    // Frames at a constant rate: at an interior frame with all its neighbours the quadratic's
    // prediction is a fixed weighted sum of them (linear in a million frames, no solve).
    let uniform = n > 2 * HALF && {
        let dt = (obs.times[n - 1] - obs.times[0]) / (n - 1) as f64;
        dt > 0.0
            && obs
                .times
                .iter()
                .enumerate()
                .all(|(k, t)| (t - obs.times[0] - k as f64 * dt).abs() <= 1e-6 * dt)
    };
    // The two markers' tracks are read apart: side by side.
    let bad_in = |track: &[Option<[f64; 2]>], m: usize| {
        // Below a micrometre the quadratic's own error on fast motion would count.
        let limit = THRESHOLD * sigma[m].max(1e-6);
        (0..n)
            .filter(|&i| {
                let Some(here) = track[i] else {
                    return false;
                };
                let lo = i.saturating_sub(HALF);
                let hi = (i + HALF).min(n - 1);
                // The neighbours with data, times relative to this frame, on the stack.
                let mut buf = [(0.0, [0.0; 2]); 2 * HALF];
                let mut len = 0;
                for j in (lo..=hi).filter(|&j| j != i) {
                    if let Some(p) = track[j] {
                        buf[len] = (obs.times[j] - obs.times[i], p);
                        len += 1;
                    }
                }
                let near = &buf[..len];
                if len < 6 {
                    return false;
                }
                let full = uniform && len == 2 * HALF;
                (0..2).any(|k| {
                    let first = if full {
                        Some(centred_prediction(near, k))
                    } else {
                        predict(near, k)
                    };
                    first.is_some_and(|v| (here[k] - v).abs() > limit)
                        && median_predict(near, k).is_some_and(|v| (here[k] - v).abs() > limit)
                })
            })
            .collect::<Vec<usize>>()
    };
    let (slider, bob) = rayon::join(|| bad_in(&obs.slider, 0), || bad_in(&obs.bob, 1));
    for (m, (track, bad)) in [(&mut obs.slider, slider), (&mut obs.bob, bob)]
        .into_iter()
        .enumerate()
    {
        for i in bad {
            track[i] = None;
            dropped[m] += 1;
        }
    }
    dropped
}

/// [`predict`] for the [`HALF`] neighbours on each side at equal steps, in closed form: with
/// offsets o = +-1..+-HALF the odd moments vanish, and the quadratic's value at 0 is
/// sum (S4 - S2 o^2) p_o / (n S4 - S2^2), S2 and S4 the sums of o^2 and o^4.
fn centred_prediction(near: &[(f64, [f64; 2])], k: usize) -> f64 {
    let h = HALF as f64;
    let s2 = h * (h + 1.0) * (2.0 * h + 1.0) / 3.0;
    let s4 = h * (h + 1.0) * (2.0 * h + 1.0) * (3.0 * h * h + 3.0 * h - 1.0) / 15.0;
    let den = 2.0 * h * s4 - s2 * s2;
    // In frame order: offsets -HALF..-1, then 1..HALF.
    let offset = |j: usize| {
        if j < HALF {
            j as f64 - h
        } else {
            (j - HALF) as f64 + 1.0
        }
    };
    near.iter()
        .enumerate()
        .map(|(j, (_, p))| (s4 - s2 * offset(j).powi(2)) * p[k])
        .sum::<f64>()
        / den
}

/// The least-squares quadratic through the neighbours (times relative to the frame), at 0.
fn predict(near: &[(f64, [f64; 2])], k: usize) -> Option<f64> {
    predict_at(near, k, 0.0)
}

/// The least-squares quadratic through the neighbours (times relative to the frame), at
/// time `at` (relative to the frame, like theirs).
fn predict_at(near: &[(f64, [f64; 2])], k: usize, at: f64) -> Option<f64> {
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
    let u = at / scale;
    a.lu().solve(&b).map(|c| c[0] + c[1] * u + c[2] * u * u)
}

/// The same prediction from the neighbours without the one that lies farthest from the
/// quadratic through the others, at its own time: a mis-tracked frame among the neighbours
/// must not make a good frame look bad. (Measured against the prediction at the frame's own
/// time instead, the farthest neighbour is the one the motion carried farthest, and the
/// mis-tracked one stays in.)
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
            let v = predict_at(&others, k, *t).unwrap_or(first);
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

/// Residuals this many noise deviations out are mis-tracked frames the track check missed.
pub(super) const RESIDUAL_OUTLIER: f64 = 6.0;

/// What the residual outlier step did.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(super) struct ResidualOutliers {
    /// Positions dropped (slider, bob): the model describes the rest of the recording.
    pub(super) dropped: [usize; 2],
    /// Positions down-weighted, not dropped (slider, bob): the model does not describe the
    /// rest either, so their residuals may be the model's error, not mis-tracking.
    pub(super) weighted: [usize; 2],
    /// Nothing done yet: the current model misfits the rest; the chosen model decides.
    pub(super) deferred: bool,
}

/// Positions whose residual is beyond [`RESIDUAL_OUTLIER`] deviations. Dropped (weight
/// zero, and the fit redone) only when the model describes the rest of the recording (its
/// chi-square passes [`super::select::misfits`]): a model that misfits leaves large residuals
/// where it is wrong, and dropping those would throw real positions away to fit a wrong model.
/// Then the step is deferred to the chosen model (`last` false), or, on that model (`last` true), the
/// positions are down-weighted by Huber's weight (their residual counts as if it were
/// [`RESIDUAL_OUTLIER`] deviations), which keeps them in the fit.
pub(super) fn residual_outliers(
    problem: &mut TrajectoryProblem,
    p: &mut DVector<f64>,
    settings: &FitSettings,
    iterations: &mut u64,
    last: bool,
) -> ResidualOutliers {
    let mut out = ResidualOutliers::default();
    let Ok(raw) = problem.raw_residuals(p) else {
        return out;
    };
    // The scale: the measured noise, or the residuals' own robust spread when larger (a fit
    // that misses the motion has large residuals everywhere, and those are not outliers).
    let scale = [0, 1].map(|m| {
        // Sized once: grown by doubling, a million frames' worth holds up to twice itself.
        let mut a = Vec::with_capacity(problem.rows().filter(|row| row.marker == m).count());
        a.extend(
            problem
                .rows()
                .zip(&raw)
                .filter(|(row, _)| row.marker == m)
                .map(|(_, r)| r.abs()),
        );
        // The median by selection, not a sort: linear in a million frames.
        let mid = a.len() / 2;
        let median = if a.is_empty() {
            0.0
        } else {
            *a.select_nth_unstable_by(mid, f64::total_cmp).1
        };
        problem.sigma[m].max(median / 0.6745)
    });
    // A residual the model's own positions do not resolve is no evidence of mis-tracking: on
    // a noise-free recording the scale is the integrator's error, whose peaks (near events)
    // are many times its median.
    let floor = numerical_accuracy_m(settings.options.rtol, problem.rig.marker_length);
    // A position is one frame's marker: both its coordinates go together.
    let mut bad = std::collections::HashSet::new();
    for (i, (row, &r)) in problem.rows().zip(&raw).enumerate() {
        if problem.row_weight(i) > 0.0
            && (r / scale[row.marker]).abs() > RESIDUAL_OUTLIER
            && r.abs() > floor
        {
            bad.insert((row.frame, row.marker));
        }
    }
    // More than 2% of the positions flagged is a misfit, not mis-tracking.
    if bad.is_empty() || bad.len() * 2 * 50 > raw.len() {
        return out;
    }
    let flagged: Vec<usize> = problem
        .rows()
        .enumerate()
        .filter(|(_, row)| bad.contains(&(row.frame, row.marker)))
        .map(|(i, _)| i)
        .collect();
    // The rest: its chi-square against the measured noise.
    let (mut chi2_rest, mut n_rest) = (0.0, 0usize);
    for (i, (row, &r)) in problem.rows().zip(&raw).enumerate() {
        let w = problem.row_weight(i);
        if w > 0.0 && !bad.contains(&(row.frame, row.marker)) {
            chi2_rest += w * w * (r / problem.sigma[row.marker]).powi(2);
            n_rest += 1;
        }
    }
    let dof = (n_rest.saturating_sub(problem.free.len()) as f64).max(1.0);
    let fits_rest = chi2_rest <= dof + 5.0 * (2.0 * dof).sqrt();
    let counts = |out: &mut [usize; 2]| {
        for &(_, m) in &bad {
            out[m] += 1;
        }
    };
    if fits_rest {
        problem.drop_rows(flagged);
        counts(&mut out.dropped);
    } else if !last {
        out.deferred = true;
        return out;
    } else {
        let mut weights: Vec<f64> = (0..problem.n_rows())
            .map(|i| problem.row_weight(i))
            .collect();
        let markers: Vec<usize> = problem.rows().map(|row| row.marker).collect();
        for i in flagged {
            let z = (raw[i] / scale[markers[i]]).abs();
            weights[i] *= (RESIDUAL_OUTLIER / z).sqrt();
        }
        problem.set_row_weights(weights);
        counts(&mut out.weighted);
    }
    if let Ok((q, _, it)) = solve(problem, p.clone(), settings.max_iters) {
        *iterations += it;
        *p = q;
        problem.set_values(p);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::Distribution;

    /// A swinging bob filmed at 100 fps (a centimetre a frame) with 0.3 mm noise and one
    /// position 15 mm off: that one is dropped and none of its neighbours, whose quadratics
    /// it sits in. The neighbour left out of the second prediction must be the one off the
    /// others' quadratic at its own time, not the one the motion carried farthest.
    #[test]
    fn a_mis_tracked_frame_does_not_drop_its_neighbours() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let normal = rand_distr::Normal::new(0.0, 3e-4).unwrap();
        let times: Vec<f64> = (0..200).map(|k| k as f64 / 100.0).collect();
        let mut bob: Vec<Option<[f64; 2]>> = times
            .iter()
            .map(|t| {
                let th = 1.0 * (6.0 * t).cos();
                Some([
                    0.25 * th.sin() + normal.sample(&mut rng),
                    -0.25 * th.cos() + normal.sample(&mut rng),
                ])
            })
            .collect();
        let bad = 60;
        // At t = 0.6 s the bob moves at about 1.2 m/s: 15 mm is 50 noise deviations.
        bob[bad] = bob[bad].map(|p| [p[0] + 0.015, p[1]]);
        let slider = times.iter().map(|_| Some([0.0, 0.0])).collect();
        let mut obs = Observations { times, slider, bob };
        let dropped = drop_from_tracks(&mut obs, [3e-4, 3e-4]);
        let gone: Vec<usize> = (0..obs.bob.len())
            .filter(|&i| obs.bob[i].is_none())
            .collect();
        assert_eq!(gone, vec![bad], "dropped {dropped:?}");
    }

    /// The closed form at equal steps is the least-squares quadratic's value, on a cubic
    /// (which the quadratic does not fit exactly) at an uneven scale.
    #[test]
    fn centred_prediction_is_the_least_squares_quadratic() {
        let dt = 1e-3;
        let near: Vec<(f64, [f64; 2])> = (1..=HALF)
            .map(|o| -(o as f64))
            .rev()
            .chain((1..=HALF).map(|o| o as f64))
            .map(|o| {
                let t = o * dt;
                (
                    t,
                    [
                        0.3 + 2.0 * t - 40.0 * t * t + 5e3 * t.powi(3),
                        (90.0 * t).sin(),
                    ],
                )
            })
            .collect();
        for k in 0..2 {
            let general = predict(&near, k).unwrap();
            let closed = centred_prediction(&near, k);
            assert!((general - closed).abs() < 1e-12, "{general} vs {closed}");
        }
    }
}
