//! What a release box can do at all, whatever the friction: the most energetic release it allows
//! bounds the pendulum's pull on a stuck slider for the whole recording (friction and damping
//! only take energy out). When that pull stays below mu_kinetic, no release in the box makes a
//! stuck slider slip, so static friction and a Stribeck hump (both act only at that moment)
//! cannot show, however the search ranks its releases.

use super::spec::{PlanSpec, Release};
use crate::model::regions::largest_stuck_pull;
use crate::model::{energy, Rig};
use crate::numbers::significant;

/// The highest energy level ([`crate::model::regions::stuck_level`] units,
/// w^2 - 2 (g/l) sin(theta)) of any release in the box, execution errors included. The energy is convex in the two velocities, so their
/// corners bound it; the angle is scanned (257 points and the ends).
pub fn box_level(rig: &Rig<f64>, release: &Release) -> f64 {
    let [e_th, e_w, e_v] = release.error;
    let [th0, th1] = [release.theta[0] - e_th, release.theta[1] + e_th];
    let ws = [release.theta_dot[0] - e_w, release.theta_dot[1] + e_w];
    let vs = [release.x_dot[0] - e_v, release.x_dot[1] + e_v];
    let n = 256;
    let scale = 2.0 / (rig.bob_mass * rig.rod_length * rig.rod_length);
    let mut top = f64::NEG_INFINITY;
    for k in 0..=n {
        let th = th0 + (th1 - th0) * k as f64 / n as f64;
        for w in ws {
            for v in vs {
                top = top.max(scale * energy(rig, &[release.x, th, v, w]));
            }
        }
    }
    top
}

/// The least energetic release that pulls a stuck slider as hard as friction `mu`: from rest at
/// `from_hanging_deg` from hanging (`None` when even the rod upright at rest pulls less), or a
/// swing through hanging at `swing` rad/s.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Restart {
    /// Angle from hanging of a release from rest (degrees).
    pub from_hanging_deg: Option<f64>,
    /// Angular velocity of a swing through hanging (rad/s).
    pub swing: f64,
}

/// [`Restart`] for friction `mu` on `rig` (level, undamped; `None` otherwise, or when no
/// swing up to 20 sqrt(g/l) pulls that hard). Bisection on the energy level: the largest pull
/// over all levels up to one never falls as the level rises.
pub fn restart_release(rig: &Rig<f64>, mu: f64) -> Option<Restart> {
    let g_l = rig.gravity / rig.rod_length;
    let pulls = |level: f64| largest_stuck_pull(rig, level).map(|p| p >= mu);
    let (mut lo, mut hi) = (-2.0 * g_l, 400.0 * g_l);
    if pulls(lo)? || !pulls(hi)? {
        return None;
    }
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if pulls(mid)? {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    // From rest at theta: hi = -2 (g/l) sin(theta); hanging is theta = 90 deg.
    let sin = -hi / (2.0 * g_l);
    let from_hanging_deg = (sin >= -1.0).then(|| 90.0 - sin.asin().to_degrees());
    Some(Restart {
        from_hanging_deg,
        swing: (hi + 2.0 * g_l).sqrt(),
    })
}

/// The note for a plan whose box cannot make a stuck slider slip under the lowest plausible
/// mu_kinetic (mean - 2 sd; static friction is no lower): the pull the box reaches and the
/// release that would restart the slider. `None` when the box can, or on a tilted rail or a
/// damped pivot, where the bound is not proven.
pub fn no_restart_note(spec: &PlanSpec) -> Option<String> {
    let rig = &spec.rig;
    let level = box_level(rig, &spec.release);
    let pull = largest_stuck_pull(rig, level)?;
    let mu_lo = spec.mu_kinetic.span()[0];
    if pull.is_nan() || pull >= mu_lo {
        return None;
    }
    let need = restart_release(rig, spec.rig.mu_kinetic).map_or_else(
        String::new,
        |r| {
            let rest = r.from_hanging_deg.map_or_else(String::new, |d| {
                format!(
                    "a release from rest at least {} deg from hanging, or ",
                    significant(d, 2)
                )
            });
            format!(
                "; {rest}a swing through hanging at {} rad/s, would pull as hard as mu_kinetic (static friction needs more)",
                significant(r.swing, 2)
            )
        },
    );
    // A bound, so rounded up, to three digits: it stays visibly below mu_kinetic.
    let shown = if pull > 0.0 {
        let scale = 10f64.powi(2 - pull.log10().floor() as i32);
        significant((pull * scale).ceil() / scale, 3)
    } else {
        "0".to_owned()
    };
    Some(format!(
        "no release in the box can make a stuck slider slip: the most energetic one (execution errors included) lets the pendulum pull at most {shown} of the normal force, below mu_kinetic ({}) and so below any static friction; static friction and a Stribeck hump act only when a stuck slider starts to slip, so no release here shows them{need}",
        spec.mu_kinetic
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::regions::stuck_level;
    use crate::plan::spec::Release;

    /// The heavy rig of configs/plan_law_heavy.toml (slider 0.3 kg, bob 0.1 kg, rod 0.3 m).
    fn heavy() -> Rig<f64> {
        Rig::new(0.3, 0.1, 0.3, 9.81, 0.22, None).unwrap()
    }

    /// A box of one release from rest at `deg` from hanging: its level is the release's own.
    #[test]
    fn a_single_release_from_rest_has_its_own_level() {
        let rig = heavy();
        let th = 50f64.to_radians();
        let r = Release {
            x: 0.0,
            theta: [th, th],
            theta_dot: [0.0, 0.0],
            x_dot: [0.0, 0.0],
            rail: [-0.25, 0.25],
            error: [0.0; 3],
        };
        let want = stuck_level(&rig, th, 0.0);
        assert!((box_level(&rig, &r) - want).abs() < 1e-12 * want.abs().max(1.0));
    }
}
