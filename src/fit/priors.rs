//! The rig file as a measurement and the nuisances' plausible ranges.
//!
//! A lab measures its rod with a ruler and its masses with a scale: the fit treats the rod
//! length and the mass ratio as parameters with Gaussian priors from those measurements
//! (errors in variables), so the data correct what they can (the marker distance measures the
//! rod) and mu's interval carries what they leave (a heavy slider cannot tell the mass ratio
//! from mu). Each camera and rig nuisance has a plausible range a lab would recognise (a
//! levelled rail, a marker on the bob, a lag below a frame); its prior has a standard deviation
//! of half that range, so a nuisance pays in the criterion for leaving it, and a chosen value
//! beyond it is evidence that the model misses something: the fit says so and names it.
//! `docs/fit.md` ("The rig file is a measurement") gives every default and range with its
//! reason.

use crate::model::Param;
use crate::model::{PendulumKeys, Rig};
use crate::scene::RigSpec;

/// A Gaussian prior on a free parameter: `((value - centre) / sd)^2` joins the chi-square as
/// one pseudo-observation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Prior {
    /// The parameter it is on.
    pub param: Param,
    /// Its centre (the measured value, or a nuisance's neutral value).
    pub centre: f64,
    /// Its standard deviation (> 0).
    pub sd: f64,
}

/// Default standard deviation of a rod length measured with a ruler (m): 0.5 mm divisions,
/// and the pivot axis and the bob's centre are not marked (0.5-1 mm between them).
pub const DEFAULT_ROD_LENGTH_SD: f64 = 1e-3;
/// Default relative standard deviation of the slider's mass: a kitchen scale's 1-2 % of a
/// 50-100 g part, and screws, bearings or a pivot pin weighed apart or forgotten (2-10 %).
pub const DEFAULT_SLIDER_MASS_REL: f64 = 0.03;
/// Default relative standard deviation of the bob's and the rod's mass: a kitchen scale's
/// 0.5-1 g, 1-2 % of a 50-100 g part.
pub const DEFAULT_BOB_MASS_REL: f64 = 0.02;
/// The smallest default mass standard deviation (kg): half a kitchen scale's 1 g step.
pub const DEFAULT_MASS_FLOOR: f64 = 5e-4;
/// Default standard deviation of a bob radius (m): calipers, or a nominal size typed in.
pub const DEFAULT_BOB_RADIUS_SD: f64 = 5e-4;
/// Default standard deviation of a rig file's typed gravity (m/s^2): 0, held as typed. Fitted
/// (a `gravity_sd`, or no `gravity`), a recording's swings pin gravity to about 0.003 %, and
/// 0.04 % held wrong moved mu by 3.5 standard errors on the shipped example; but freed by
/// default on recordings the model misfits (a tilted rail with a damped pivot) it opened
/// another path through the nuisances (a direction law and a gravity no lab has in place of
/// the tilt, an interval 600 times narrower), so a lab asks for it.
pub const DEFAULT_GRAVITY_SD: f64 = 0.0;
/// A stated deviation below this fraction of its value is held exact, as `_sd = 0` is: a
/// nanometre on a metre, finer than any ruler, scale or gravimeter a lab types and a thousand
/// times below what a recording pins (a rod to about a micrometre). A prior that much tighter
/// than the data adds nothing but ruins the solve's conditioning (`rod_length_sd = 1e-300`
/// stopped the fit at its start with every standard error 0).
pub const RESOLVABLE_REL: f64 = 1e-9;

/// Whether a deviation `sd` of a value `v` is one the fit can use as a prior (finite, above
/// [`RESOLVABLE_REL`] of the value); otherwise the value is held exact.
fn resolvable(v: f64, sd: f64) -> bool {
    v.is_finite() && sd.is_finite() && sd > RESOLVABLE_REL * v.abs()
}

/// The measured rig: the standard deviation of each measured value (stated in the rig file or
/// the default), and the priors they give the fit.
#[derive(Debug, Clone, PartialEq)]
pub struct RigMeasurement {
    /// Rod length (m) and its standard deviation.
    pub rod_length: (f64, f64),
    /// The mass ratio the dynamics use (m1 / m2, or a given rigid pendulum's r') and its
    /// standard deviation propagated from the masses'.
    pub mass_ratio: (f64, f64),
    /// Gravity (m/s^2) and its standard deviation.
    pub gravity: (f64, f64),
    /// Each measured key with its value, standard deviation and where the deviation came from
    /// (`"stated"` in the file, `"default"`, or `"--latitude"` for gravity), for the report.
    pub keys: Vec<(&'static str, f64, f64, &'static str)>,
    /// What the fit reports about the rig file besides its values (a gravity it did not give).
    pub notes: Vec<String>,
}

/// Where a measured value's deviation came from: the file (`Some`), or the default.
fn stated_or_default(sd: Option<f64>) -> &'static str {
    if sd.is_some() {
        "stated"
    } else {
        "default"
    }
}

impl RigMeasurement {
    /// Record that gravity came from `source` (`"--latitude"` or `"default"`), not the rig
    /// file: the file left it out and the fit filled it in.
    pub fn gravity_from(&mut self, source: &'static str) {
        for k in self.keys.iter_mut().filter(|k| k.0 == "gravity") {
            k.3 = source;
        }
    }

    /// The measurement a rig file's `[rig]` describes: its `*_sd` keys, or the defaults of a
    /// ruler and a kitchen scale.
    pub fn from_spec(spec: &RigSpec) -> RigMeasurement {
        let mass_sd = |v: f64, rel: f64| (v * rel).max(DEFAULT_MASS_FLOOR.min(0.5 * v));
        let mut keys = Vec::new();
        let mut notes = Vec::new();
        // A stated deviation too small to resolve is the exact value (one rule for every key,
        // gravity's too): held as `_sd = 0` holds it, and said so.
        let mut exact_below = |name: &str, v: f64, sd: Option<f64>| {
            sd.map(|sd| {
                if sd > 0.0 && !resolvable(v, sd) {
                    notes.push(format!(
                        "rig.{name}_sd = {sd:e} is below {RESOLVABLE_REL:e} of the value \
                         ({v}), finer than any measurement: the value is held exact, as \
                         {name}_sd = 0 holds it"
                    ));
                    0.0
                } else {
                    sd
                }
            })
        };
        let rod_length_sd = exact_below("rod_length", spec.rod_length, spec.rod_length_sd);
        let slider_mass_sd = exact_below("slider_mass", spec.slider_mass, spec.slider_mass_sd);
        let bob_mass_sd = exact_below("bob_mass", spec.bob_mass.unwrap_or(0.0), spec.bob_mass_sd);
        let rod_mass_sd = exact_below("rod_mass", spec.rod_mass.unwrap_or(0.0), spec.rod_mass_sd);
        let bob_radius_sd = exact_below(
            "bob_radius",
            spec.bob_radius.unwrap_or(0.0),
            spec.bob_radius_sd,
        );
        let gravity_sd = exact_below("gravity", spec.gravity(), spec.gravity_sd);
        let mut key = |name: &'static str, v: Option<f64>, sd: Option<f64>, default: f64| {
            let v = v?;
            keys.push((name, v, sd.unwrap_or(default), stated_or_default(sd)));
            Some(sd.unwrap_or(default))
        };
        let rod_sd = key(
            "rod_length",
            Some(spec.rod_length),
            rod_length_sd,
            DEFAULT_ROD_LENGTH_SD,
        )
        .unwrap_or(DEFAULT_ROD_LENGTH_SD);
        let m1_sd = key(
            "slider_mass",
            Some(spec.slider_mass),
            slider_mass_sd,
            mass_sd(spec.slider_mass, DEFAULT_SLIDER_MASS_REL),
        )
        .unwrap_or(0.0);
        let m2_sd = spec.bob_mass.and_then(|m| {
            key(
                "bob_mass",
                Some(m),
                bob_mass_sd,
                mass_sd(m, DEFAULT_BOB_MASS_REL),
            )
        });
        let rod_mass_sd = spec.rod_mass.filter(|&m| m > 0.0).and_then(|m| {
            key(
                "rod_mass",
                Some(m),
                rod_mass_sd,
                mass_sd(m, DEFAULT_BOB_MASS_REL),
            )
        });
        let radius_sd = spec
            .bob_radius
            .filter(|&a| a > 0.0)
            .and_then(|a| key("bob_radius", Some(a), bob_radius_sd, DEFAULT_BOB_RADIUS_SD));
        // Gravity is listed only when it is fitted (held as typed by default).
        // Stated only when the file gives both the value and its deviation: gravity left out
        // is the default 9.81 +- 0.015 it is, not a measurement the file states.
        let gravity_sd = gravity_sd.unwrap_or(DEFAULT_GRAVITY_SD);
        if gravity_sd > 0.0 {
            let source = stated_or_default(spec.gravity.and(spec.gravity_sd));
            keys.push(("gravity", spec.gravity(), gravity_sd, source));
        }
        // The mass ratio the dynamics use, and its deviation by the delta method (central
        // differences through the same rig builder the fit's rig came from).
        let ratio = |m1: f64, m2: Option<f64>, m_r: Option<f64>, a: Option<f64>| -> f64 {
            let keys = PendulumKeys {
                bob_mass: m2,
                rod_mass: m_r,
                bob_radius: a,
                ..spec.pendulum_keys()
            };
            keys.rig(m1, spec.rod_length, spec.gravity(), 0.3, None)
                .map_or(f64::NAN, |r| r.mass_ratio())
        };
        let (m1, m2, m_r, a) = (
            spec.slider_mass,
            spec.bob_mass,
            spec.rod_mass,
            spec.bob_radius,
        );
        let centre = ratio(m1, m2, m_r, a);
        let mut var = 0.0;
        let mut term = |plus: f64, minus: f64| {
            if plus.is_finite() && minus.is_finite() {
                var += (0.5 * (plus - minus)).powi(2);
            }
        };
        term(ratio(m1 + m1_sd, m2, m_r, a), ratio(m1 - m1_sd, m2, m_r, a));
        if let (Some(m2), Some(sd)) = (m2, m2_sd) {
            term(
                ratio(m1, Some(m2 + sd), m_r, a),
                ratio(m1, Some(m2 - sd), m_r, a),
            );
        }
        if let (Some(m), Some(sd)) = (m_r, rod_mass_sd) {
            term(
                ratio(m1, m2, Some(m + sd), a),
                ratio(m1, m2, Some((m - sd).max(0.0)), a),
            );
        }
        if let (Some(r), Some(sd)) = (a, radius_sd) {
            term(
                ratio(m1, m2, m_r, Some(r + sd)),
                ratio(m1, m2, m_r, Some((r - sd).max(0.0))),
            );
        }
        RigMeasurement {
            rod_length: (spec.rod_length, rod_sd),
            mass_ratio: (centre, var.sqrt()),
            gravity: (spec.gravity(), gravity_sd),
            keys,
            notes,
        }
    }

    /// An exact rig: no prior, nothing freed (the rig file's values taken as they are).
    pub fn exact(rig: &Rig<f64>) -> RigMeasurement {
        RigMeasurement {
            rod_length: (rig.marker_length, 0.0),
            mass_ratio: (rig.mass_ratio(), 0.0),
            gravity: (rig.gravity, 0.0),
            keys: Vec::new(),
            notes: Vec::new(),
        }
    }

    /// The priors of the rig's measured values: the rod length, the mass ratio and gravity,
    /// each only when its deviation is one the data can use ([`RESOLVABLE_REL`]; a value stated
    /// exact, or the mass ratio of masses stated exact, stays fixed).
    pub fn priors(&self) -> Vec<Prior> {
        [
            (Param::RodLength, self.rod_length),
            (Param::MassRatio, self.mass_ratio),
            (Param::Gravity, self.gravity),
        ]
        .into_iter()
        .filter(|(_, (c, sd))| resolvable(*c, *sd))
        .map(|(param, (centre, sd))| Prior { param, centre, sd })
        .collect()
    }
}

/// A nuisance parameter's plausible range: within `bound` of its neutral value, with the
/// reason a lab would give and what to check when a fit needs more.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Plausible {
    /// The parameter.
    pub param: Param,
    /// Its neutral value (the rig file's, or zero).
    pub centre: f64,
    /// How far from it a real rig goes.
    pub bound: f64,
    /// What to check when the fit needs more (one phrase).
    pub check: &'static str,
}

/// Plausible rail tilt (rad): 0.6 deg, 10 mm/m, over three times an unlevelled table top's
/// 1-3 mm/m; a 1 deg tilt is visible by eye (docs/fit.md, "The nuisances' plausible ranges").
pub const TILT_BOUND: f64 = 0.6 * std::f64::consts::PI / 180.0;
/// The widest rail tilt (rad) a fit's solver searches, about 17 degrees: a tilt nuisance
/// stepped beyond it simulates a rail no rig levelled by eye has; and a rig file's tilt
/// beyond it is refused before a fit (`plausible::check_tilt`): a rail near vertical fitted
/// for a minute to nonsense (89.9 degrees: 51 s, mu 3073 +- 17000).
pub const TILT_SEARCH: f64 = 0.3;
/// Plausible camera scale error: 2 % (a scale from a ruler in view or the rod is good to
/// 0.1-0.3 %; a pixel scale typed from a short reference, to a percent or two).
pub const SCALE_BOUND: f64 = 0.02;
/// Plausible marker offset (m): a marker stuck beside the rod axis or the pivot is off by at
/// most its own size, 5-15 mm across.
pub const MARKER_BOUND: f64 = 0.008;
/// Plausible pivot damping as a logarithmic decrement of small swings: 0.05 (10 % of the
/// energy per period; a bearing loses 0.1-3 %).
pub const DAMPING_DECREMENT_BOUND: f64 = 0.05;

/// The plausible ranges of the camera and rig nuisances for `rig` over frames `frame` seconds
/// apart. The friction law's own parameters (mu_static, Stribeck, viscous friction) have none:
/// the rail's friction is what the lab measures.
pub fn plausible_ranges(rig: &Rig<f64>, frame: f64) -> Vec<Plausible> {
    // The damping coefficient of the bound's decrement: c = 2 J delta / T for small swings,
    // J = m_e L^2 the equivalent pendulum's inertia, T = 2 pi sqrt(L / g).
    let l = rig.rod_length;
    let period = 2.0 * std::f64::consts::PI * (l / rig.gravity).sqrt();
    let damping = 2.0 * rig.bob_mass * l * l * DAMPING_DECREMENT_BOUND / period;
    let p = |param, centre, bound, check| Plausible {
        param,
        centre,
        bound,
        check,
    };
    vec![
        p(
            Param::RailTilt,
            rig.rail_tilt,
            TILT_BOUND,
            "level the rail (or state its tilt as rail_tilt_deg), or the friction may differ by direction",
        ),
        p(
            Param::ScaleError,
            0.0,
            SCALE_BOUND,
            "check the camera's scale (--scale) and the rod length, or lens distortion",
        ),
        p(
            Param::BobAlong,
            0.0,
            MARKER_BOUND,
            "check where the bob's marker sits and the rod length",
        ),
        p(
            Param::BobAcross,
            0.0,
            MARKER_BOUND,
            "check where the bob's marker sits, or the rail's tilt",
        ),
        p(
            Param::SliderDx,
            0.0,
            MARKER_BOUND,
            "check where the slider's marker sits",
        ),
        p(
            Param::SliderDy,
            0.0,
            MARKER_BOUND,
            "check where the slider's marker sits",
        ),
        p(
            Param::Lag,
            0.0,
            frame.max(1e-6),
            "check the two tracks' frame times (a lag beyond a frame is no rounding)",
        ),
        p(
            Param::PivotDamping,
            rig.pivot_damping,
            damping.max(1e-12),
            "check the pivot (a bearing loses a few percent per swing), or air drag on the bob",
        ),
    ]
}

/// The priors of the plausible ranges: each a Gaussian of standard deviation half its bound.
pub fn nuisance_priors(ranges: &[Plausible]) -> Vec<Prior> {
    ranges
        .iter()
        .map(|r| Prior {
            param: r.param,
            centre: r.centre,
            sd: 0.5 * r.bound,
        })
        .collect()
}

/// What a fitted model's values are judged against: the nuisances' plausible ranges and the
/// rig file's mass ratio m1 / m2 (a rigid correction's implied rod mass reads the masses from
/// it). Empty: nothing is judged.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Plausibility {
    /// The ranges.
    pub ranges: Vec<Plausible>,
    /// The rig file's mass ratio (NaN: not known, no rod mass implied).
    pub file_ratio: f64,
}

/// Earth's gravity from the equator at 6 km to the poles below sea level (m/s^2): no lab on
/// Earth has gravity outside it.
pub const EARTH_GRAVITY_RANGE: [f64; 2] = [9.76, 9.84];

/// The largest bob radius a rigid correction may imply (m): bob spheres are 1-3 cm.
pub const BOB_RADIUS_BOUND: f64 = 0.05;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::guess::start_from_markers;
    use crate::fit::implausible::implausible;
    use crate::fit::problem::{Observations, TrajectoryProblem};
    use crate::sim::Options;
    use std::sync::Arc;

    fn spec(text: &str) -> RigSpec {
        let file: crate::scene::RigFile = toml::from_str(text).unwrap();
        file.rig
    }

    /// A point rig's mass ratio r = m1 / m2 carries (sd_r / r)^2 = (sd1 / m1)^2 + (sd2 / m2)^2
    /// (first order), the defaults are the documented ones, and a stated 0 is no prior.
    #[test]
    fn the_mass_ratio_carries_both_masses_errors() {
        let s = spec("[rig]\nslider_mass = 0.35\nslider_mass_sd = 0.007\nbob_mass = 0.1\nbob_mass_sd = 0.003\nrod_length = 0.3\ngravity = 9.81\n");
        let m = RigMeasurement::from_spec(&s);
        let (r, sd) = m.mass_ratio;
        assert!((r - 3.5).abs() < 1e-12);
        let want = 3.5 * (0.02f64.powi(2) + 0.03f64.powi(2)).sqrt();
        assert!((sd - want).abs() < 2e-3 * want, "{sd} against {want}");
        let d = RigMeasurement::from_spec(&spec(
            "[rig]\nslider_mass = 0.35\nbob_mass = 0.1\nrod_length = 0.3\ngravity = 9.81\n",
        ));
        assert_eq!(d.rod_length, (0.3, DEFAULT_ROD_LENGTH_SD));
        let want = 3.5 * (DEFAULT_SLIDER_MASS_REL.powi(2) + DEFAULT_BOB_MASS_REL.powi(2)).sqrt();
        assert!((d.mass_ratio.1 - want).abs() < 2e-3 * want);
        assert!(d.keys.iter().all(|k| k.3 == "default"));
        let exact = RigMeasurement::from_spec(&spec("[rig]\nslider_mass = 0.35\nslider_mass_sd = 0\nbob_mass = 0.1\nbob_mass_sd = 0\nrod_length = 0.3\nrod_length_sd = 0\ngravity = 9.81\ngravity_sd = 0\n"));
        assert!(exact.priors().is_empty());
    }

    fn problem(free: Vec<Param>) -> TrajectoryProblem {
        let obs = Arc::new(Observations {
            times: vec![0.0, 0.001],
            slider: vec![Some([0.0, 0.0]); 2],
            bob: vec![Some([0.3, 0.0]); 2],
        });
        let rig = Rig::new(0.35, 0.1, 0.3, 9.81, 0.25, None).unwrap();
        let mut p = TrajectoryProblem::new(obs, rig, [0.0; 4], free, Options::default());
        p.plausible = Arc::new(Plausibility {
            ranges: plausible_ranges(&rig, 1e-3),
            file_ratio: 3.5,
        });
        p
    }

    /// A tilt beyond 0.6 deg, a lag beyond a frame and an equivalent length no rod and bob
    /// give are named; values inside their ranges, and parameters not free, are not.
    #[test]
    fn values_beyond_their_ranges_are_named() {
        let mut p = problem(vec![Param::MuKinetic, Param::RailTilt, Param::Lag]);
        p.rig.rail_tilt = 0.3f64.to_radians();
        p.camera.lag = 5e-4;
        assert!(implausible(&p).is_empty());
        p.rig.rail_tilt = 1.0f64.to_radians();
        p.camera.lag = 2e-3;
        let said = implausible(&p);
        assert_eq!(said.len(), 2, "{said:?}");
        assert!(said[0].starts_with("rail_tilt = 1.00 deg"));
        assert!(said[1].starts_with("marker_lag"));
        p.free = vec![Param::MuKinetic];
        assert!(implausible(&p).is_empty());
        let mut rigid = problem(vec![Param::PendulumLength, Param::MassRatio]);
        rigid.rig.rod_length = 0.5 * 0.3;
        assert!(implausible(&rigid)[0].starts_with("rigid_pendulum"));
        // A uniform rod of 22.2 g on the 100 g bob: L = 0.29 m and r' = 3.108 (the same
        // total mass of rig file parts, 0.45 kg, split at r').
        rigid.rig.rod_length = 0.29;
        rigid.rig.bob_mass = 0.45 / (1.0 + 3.108);
        rigid.rig.slider_mass = 0.45 - rigid.rig.bob_mass;
        assert!(implausible(&rigid).is_empty(), "{:?}", implausible(&rigid));
        // The same length with the point rig's r' = 3.5 needs a rod of negative mass.
        rigid.rig.bob_mass = 0.1;
        rigid.rig.slider_mass = 0.35;
        assert!(implausible(&rigid)[0].contains("imply a rod of -11.7 g"));
    }

    /// The rod starts at the markers' median distance when it lies within 5 deviations of the
    /// file's value, and at the file's value otherwise or without a measurement.
    #[test]
    fn the_rod_starts_where_the_markers_put_it() {
        let obs = Observations {
            times: (0..20).map(|k| k as f64 * 1e-3).collect(),
            slider: vec![Some([0.0, 0.0]); 20],
            bob: (0..20)
                .map(|k| Some([0.0, -0.302 - 1e-5 * k as f64]))
                .collect(),
        };
        let rig = Rig::new(0.35, 0.1, 0.3, 9.81, 0.25, None).unwrap();
        let m = RigMeasurement::exact(&rig);
        assert_eq!(start_from_markers(&obs, &rig, Some(&m)).marker_length, 0.3);
        let measured = RigMeasurement {
            rod_length: (0.3, 1e-3),
            ..m.clone()
        };
        let started = start_from_markers(&obs, &rig, Some(&measured));
        // The median of 0.302 + 1e-5 k, k = 0..19: the mean of k = 9 and 10.
        assert!((started.marker_length - 0.302095).abs() < 1e-12);
        assert_eq!(started.rod_length, started.marker_length);
        let narrow = RigMeasurement {
            rod_length: (0.3, 1e-4),
            ..m
        };
        assert_eq!(
            start_from_markers(&obs, &rig, Some(&narrow)).marker_length,
            0.3
        );
        assert_eq!(start_from_markers(&obs, &rig, None).marker_length, 0.3);
    }
}
