//! An estimate's interval widened by a further source of error (the models in play, the
//! windows, the releases) and cut at the physical bounds, and a mu pinned at its bound said
//! as a failed fit.

use super::estimate::Estimate;
use super::problem::{Param, TrajectoryProblem};
use super::select::{self, ModelRow};

/// `e` widened by a further standard deviation `s` (a source of error its interval did not
/// hold), named `tag` in its interval's method: the standard error becomes sqrt(se^2 + s^2) and
/// each half-width h becomes sqrt(h^2 + (1.96 s)^2), about the same value.
pub(super) fn widen(e: &mut Estimate, s: f64, tag: &str) {
    if s.is_nan() || s <= 0.0 {
        return;
    }
    let wider = |h: f64| (h * h + 1.96 * 1.96 * s * s).sqrt();
    e.ci95 = [
        e.value - wider(e.value - e.ci95[0]),
        e.value + wider(e.ci95[1] - e.value),
    ];
    e.stderr = (e.stderr * e.stderr + s * s).sqrt();
    e.interval = intern(format!("{}+{tag}", e.interval));
}

/// A method label as a `&'static str`: the labels are few (a base method and a handful of
/// widenings in a fixed order), so each distinct one is leaked once and reused.
fn intern(label: String) -> &'static str {
    static LABELS: std::sync::Mutex<Vec<&'static str>> = std::sync::Mutex::new(Vec::new());
    let mut labels = LABELS.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(l) = labels.iter().find(|l| **l == label) {
        return l;
    }
    let l: &'static str = Box::leak(label.into_boxed_str());
    labels.push(l);
    l
}

/// Widen mu_kinetic's estimate `e` by the models' uncertainty, the larger of two: the spread
/// of the models the weights leave in play ([`select::model_spread`]), and the adequate
/// alternatives ([`select::adequate_spread`], chi-squares scaled by `c`), whose farthest mu
/// the widened interval reaches (a standard deviation of a 1.96th of that distance). Only
/// when worth a tenth of the standard error.
pub(super) fn model_uncertainty(
    e: &mut Estimate,
    models: &[ModelRow],
    c: f64,
    warnings: &mut Vec<String>,
) {
    let (var, names) = select::model_spread(models, e.value);
    let (far, adequate) = select::adequate_spread(models, e.value, c);
    let by_weight = if var.is_nan() || names.len() < 2 {
        0.0
    } else {
        var.sqrt()
    };
    let by_adequacy = far / 1.96;
    let s = by_weight.max(by_adequacy);
    if s <= 0.1 * e.stderr {
        return;
    }
    widen(e, s, "models");
    if by_adequacy > by_weight {
        warnings.push(format!(
            "other models describe the recording as well as the chosen one and give other mu_kinetic; the interval reaches the farthest ({:.2e} away): {}",
            far,
            adequate.join(", ")
        ));
    } else {
        warnings.push(format!(
            "models close in the criterion give different mu_kinetic, and the interval carries their spread (standard deviation {:.2e}): {}",
            s,
            names.join(", ")
        ));
    }
}

/// `e` with its 95% interval cut at the physical bound of `q`: mu_kinetic, pivot damping and
/// viscous rail friction are at least 0, and mu_static at least `mu_k_low` (the lower end of
/// mu_kinetic's interval). The part of an interval beyond a bound holds no rig, so cutting it
/// never loses the truth; the value and standard error are left as fitted.
pub(super) fn within_bounds(q: Param, mut e: Estimate, mu_k_low: f64) -> Estimate {
    let low = match q {
        Param::MuKinetic
        | Param::PivotDamping
        | Param::ViscousFriction
        | Param::StribeckVelocity => 0.0,
        Param::MuStatic => mu_k_low,
        _ => return e,
    };
    e.ci95[0] = e.ci95[0].max(low);
    e.ci95[1] = e.ci95[1].max(e.ci95[0]);
    e
}

/// The fit failed although it ran when mu_kinetic sits at its bound 0 (within two standard
/// errors of it, and below 1e-3) while Stribeck's law or viscous rail friction carries the
/// friction (mu_static measured at 1e-3 or more, clear of 0 by two standard errors, or
/// viscous friction worth 1e-3 of the static load at 0.1 m/s): no Coulomb coefficient was
/// measured, whatever its interval says. Said as such.
pub(super) fn pinned_friction(
    problem: &TrajectoryProblem,
    mu: Option<&Estimate>,
    mu_static: Option<&Estimate>,
) -> Option<String> {
    let mu = mu?;
    // Only a term that does carry friction: on a frictionless rail the law's terms sit at 0
    // with mu_kinetic, and mu_kinetic = 0 is then the measurement (a tenth of a per mille of
    // the static load, at a slide's 0.1 m/s for viscous friction). A mu_static the recording
    // does not pin (its value anywhere within its error) carries nothing measured either.
    let rig = &problem.rig;
    let load = (rig.slider_mass + rig.bob_mass) * rig.gravity;
    let static_measured = mu_static.map_or(rig.mu_static >= 1e-3, |e| {
        e.value >= 1e-3 && e.value > 2.0 * e.stderr
    });
    let carried = if problem.free.contains(&Param::StribeckVelocity) && static_measured {
        "Stribeck's law (mu_static and the Stribeck speed)"
    } else if problem.free.contains(&Param::ViscousFriction)
        && rig.viscous_friction * 0.1 >= 1e-3 * load
    {
        "viscous rail friction"
    } else {
        return None;
    };
    (mu.value < select::MU_PINNED && mu.value < 2.0 * mu.stderr).then(|| {
        format!(
            "The fit failed: mu_kinetic is pinned at {:.2e} while {carried} carries the friction, so no friction coefficient was measured; the rig's description is likely wrong (a rigid pendulum: try --with rigid_pendulum, or give rod_mass and bob_radius).",
            mu.value
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::problem::Observations;
    use crate::model::Rig;
    use crate::sim::Options;
    use std::sync::Arc;

    fn problem(free: Vec<Param>) -> TrajectoryProblem {
        let obs = Arc::new(Observations {
            times: vec![0.0, 0.001],
            slider: vec![Some([0.0, 0.0]); 2],
            bob: vec![Some([0.3, 0.0]); 2],
        });
        TrajectoryProblem::new(obs, Rig::paper(0.3), [0.0; 4], free, Options::default())
    }

    fn estimate(value: f64, stderr: f64) -> Estimate {
        Estimate::wald(value, stderr)
    }

    /// The solver's steps stay inside the time-scale bound the commands check: damping,
    /// viscous friction and a mass ratio pushed far beyond it come back to a rig the
    /// integrator runs at its bound, not beyond.
    #[test]
    fn steps_stay_inside_the_time_scale_bound() {
        use crate::fit::lm::LeastSquares;
        for (q, wild) in [
            (Param::PivotDamping, 1e3),
            (Param::ViscousFriction, 1e4),
            (Param::MassRatio, 1e-6),
        ] {
            let m = problem(vec![Param::MuKinetic, q]);
            let mut p = nalgebra::DVector::from_vec(vec![0.3, wild]);
            m.project(&mut p);
            let mut at = m.clone();
            at.set_values(&p);
            let rate = crate::scene::rig_time_rate(&at.rig);
            assert!(
                rate <= crate::scene::MAX_RIG_RATE * (1.0 + 1e-9),
                "{q:?} {wild} -> {} gives a rate {rate}",
                p[1]
            );
            assert!(rate > 0.5 * crate::scene::MAX_RIG_RATE, "{q:?}: {rate}");
        }
    }

    /// Intervals stop at the physical bounds and nowhere else.
    #[test]
    fn intervals_stop_at_the_physical_bounds() {
        let e = within_bounds(Param::MuKinetic, estimate(0.0, 20.0), 0.0);
        assert_eq!(e.ci95, [0.0, 39.2]);
        assert_eq!((e.value, e.stderr), (0.0, 20.0));
        let e = within_bounds(Param::PivotDamping, estimate(1e-4, 1e-4), 0.0);
        assert_eq!(e.ci95[0], 0.0);
        // mu_static from the lower end of mu_kinetic's interval.
        let e = within_bounds(Param::MuStatic, estimate(0.30, 0.05), 0.26);
        assert_eq!(e.ci95[0], 0.26);
        // Away from a bound, or without one, nothing changes.
        let far = estimate(0.25, 0.01);
        assert_eq!(within_bounds(Param::MuKinetic, far, 0.0), far);
        let tilt = estimate(-0.01, 0.02);
        assert_eq!(within_bounds(Param::RailTilt, tilt, 0.0), tilt);
    }

    /// mu pinned at 0 while Stribeck's law or viscous friction carries the friction is a
    /// failed fit; the same mu with Coulomb's law alone, or a mu clear of 0, is not.
    #[test]
    fn mu_pinned_at_zero_with_friction_elsewhere_is_a_failed_fit() {
        let stribeck = problem(vec![
            Param::MuKinetic,
            Param::MuStatic,
            Param::StribeckVelocity,
        ]);
        let mut viscous = problem(vec![Param::MuKinetic, Param::ViscousFriction]);
        let coulomb = problem(vec![Param::MuKinetic, Param::X]);
        let pinned = estimate(0.0, 0.26);
        assert!(pinned_friction(&stribeck, Some(&pinned), None).is_some());
        // A mu_static the recording does not pin carries nothing measured (issue 59, class
        // F: a frictionless rail forced to Stribeck's law was "failed ... likely wrong"); the
        // same value pinned does carry the friction.
        let mut loose = stribeck.clone();
        loose.rig.mu_static = 0.01;
        assert!(pinned_friction(&loose, Some(&pinned), Some(&estimate(0.01, 0.05))).is_none());
        assert!(pinned_friction(&loose, Some(&pinned), Some(&estimate(0.01, 0.001))).is_some());
        // A frictionless rail: viscous friction at 0 with mu_kinetic carries nothing, and
        // mu_kinetic = 0 is the measurement; at 0.1 N s/m it carries the friction.
        assert!(pinned_friction(&viscous, Some(&pinned), None).is_none());
        viscous.rig.viscous_friction = 0.1;
        assert!(pinned_friction(&viscous, Some(&pinned), None).is_some());
        let mut frictionless = stribeck.clone();
        frictionless.rig.mu_static = 2e-4;
        assert!(pinned_friction(&frictionless, Some(&pinned), None).is_none());
        assert!(pinned_friction(&coulomb, Some(&pinned), None).is_none());
        assert!(pinned_friction(&stribeck, Some(&estimate(0.25, 0.01)), None).is_none());
        // Clear of zero by many standard errors: a small but measured coefficient.
        assert!(pinned_friction(&stribeck, Some(&estimate(5e-4, 1e-5)), None).is_none());
    }
}
