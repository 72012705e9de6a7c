//! The values of a fitted model no real rig has ([`implausible`]): a nuisance beyond its
//! plausible range ([`crate::fit::priors`]), a rigid pendulum no rod and bob give, a gravity no
//! lab on Earth has. Each is a sentence that names the value and what to check.

use crate::fit::priors::{BOB_RADIUS_BOUND, DAMPING_DECREMENT_BOUND, EARTH_GRAVITY_RANGE};
use crate::fit::problem::TrajectoryProblem;
use crate::model::Param;

/// The values of `problem`'s model no real rig has: a sentence each that names it and what
/// to check.
pub fn implausible(problem: &TrajectoryProblem) -> Vec<String> {
    let mut out = Vec::new();
    let file_ratio = problem.plausible.file_ratio;
    for r in &problem.plausible.ranges {
        if !problem.free.contains(&r.param) {
            continue;
        }
        let v = problem.get(r.param);
        if (v - r.centre).abs() > r.bound {
            let (shown, bound) = match r.param {
                Param::RailTilt => (
                    format!("{:.2} deg", v.to_degrees()),
                    format!("{:.1} deg", r.bound.to_degrees()),
                ),
                Param::ScaleError => (
                    format!("{:.2} %", 100.0 * v),
                    format!("{:.0} %", 100.0 * r.bound),
                ),
                Param::Lag => (
                    format!("{:.2} ms", 1e3 * v),
                    format!("one frame, {:.2} ms", 1e3 * r.bound),
                ),
                Param::PivotDamping => (
                    format!("{v:.2e} N m s"),
                    format!(
                        "{:.2e} N m s, a decrement of {DAMPING_DECREMENT_BOUND}",
                        r.bound
                    ),
                ),
                _ => (
                    format!("{:.1} mm", 1e3 * v),
                    format!("{:.0} mm", 1e3 * r.bound),
                ),
            };
            out.push(format!(
                "{} = {shown} is beyond what a real rig has ({bound}): {}",
                r.param.name(),
                r.check
            ));
        }
    }
    if let Some(s) = rigid_implausible(problem, file_ratio) {
        out.push(s);
    }
    out.extend(gravity_implausible(problem));
    out
}

/// A fitted gravity no lab on Earth has, when the rig file's is an Earth value: the recording's
/// time or length scale is not what the fit was told, or an effect the model lacks bends it.
fn gravity_implausible(problem: &TrajectoryProblem) -> Option<String> {
    let [lo, hi] = EARTH_GRAVITY_RANGE;
    let on_earth = |g: f64| (lo..=hi).contains(&g);
    let file = problem.prior_on(Param::Gravity)?.centre;
    let g = problem.get(Param::Gravity);
    (problem.free.contains(&Param::Gravity) && on_earth(file) && !on_earth(g)).then(|| {
        format!(
            "gravity = {g:.3} m/s^2 is beyond what a lab on Earth has ({lo} to {hi} m/s^2): check the frame rate (times) and the scale (lengths), or an effect the model lacks (drag, a worn pivot) bends the swing"
        )
    })
}

/// A rigid pendulum found by the data (`rigid_pendulum`) that no rod and bob give: its
/// equivalent length L outside [0.64 l, l + 0.4 a_max^2 / l] (a bare uniform rod has 2l/3, a
/// sphere of radius a adds 0.4 a^2 / l), or, where the mass ratio tells it, an implied rod mass
/// below zero or above the bob's.
fn rigid_implausible(problem: &TrajectoryProblem, file_ratio: f64) -> Option<String> {
    if !problem.free.contains(&Param::PendulumLength) || problem.rig.pendulum.is_some() {
        return None;
    }
    let l = problem.rig.marker_length;
    let big_l = problem.get(Param::PendulumLength);
    let r = problem.get(Param::MassRatio);
    let a_max = BOB_RADIUS_BOUND.min(0.5 * l);
    let (lo, hi) = (0.64 * l, l + 0.4 * a_max * a_max / l);
    let what = "the pendulum: state it (rod_mass = 0 and bob_radius = 0 for a thread, or the rod's mass and the bob's radius)";
    if big_l < lo || big_l > hi {
        return Some(format!(
            "rigid_pendulum: an equivalent length of {:.1} mm on a {:.1} mm rod is no rod and bob a lab builds ({:.1}-{:.1} mm): check {what}",
            1e3 * big_l,
            1e3 * l,
            1e3 * lo,
            1e3 * hi
        ));
    }
    // The rod mass behind (L, r') with the rig file's masses (total m1 + m2 + m_r, a uniform
    // rod to the bob's centre): (m1 + m2 + m_r) L = (1 + r') (m2 + m_r / 2) l.
    let total = problem.rig.slider_mass + problem.rig.bob_mass;
    let m2 = total / (1.0 + file_ratio);
    let m1 = total - m2;
    let den = big_l - 0.5 * (1.0 + r) * l;
    if file_ratio.is_finite() && den.abs() > 0.05 * l {
        let m_r = ((1.0 + r) * m2 * l - (m1 + m2) * big_l) / den;
        if m_r < -0.05 * m2 || m_r > m2 {
            return Some(format!(
                "rigid_pendulum: its length and mass ratio imply a rod of {:.1} g on a {:.1} g bob, which no pendulum has: check {what}, and the masses",
                1e3 * m_r,
                1e3 * m2
            ));
        }
    }
    None
}
