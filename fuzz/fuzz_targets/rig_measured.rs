//! Fuzz the rig file as a fit reads it, structure-aware (issue 59): the input builds a rig
//! file from every key a `[rig]` may hold (the masses, the rod, a rigid pendulum's keys,
//! gravity, the friction law and its keys, the tilt, the damping and every `*_sd`), each
//! absent, a number from the edges (zero, subnormal, huge, negative, NaN written as text) or a
//! wrong type, so most inputs pass the TOML parser and reach the range checks. Each is read as
//! `appell fit` reads it (`RigFile::parse_on_earth`, then the measurement and its priors, then
//! the fit's pre-checks of the rig); whatever passes must leave priors the solve can use (a
//! finite centre, a deviation above `RESOLVABLE_REL` of it) and a rig every command accepts.
//! Nothing is simulated, so an input takes microseconds.
#![no_main]

use appell::fit::priors::{RigMeasurement, RESOLVABLE_REL};
use appell::fit::{check_masses, check_tilt};
use appell::scene::{check_rig, check_time_scale, RigFile, RigOrigin};
use arbitrary::Arbitrary;
use libfuzzer_sys::fuzz_target;
use std::fmt::Write;
use std::path::Path;

/// A value for one key.
#[derive(Debug, Arbitrary)]
enum Val {
    Absent,
    Any(f64),
    Edge(u8),
    /// A plausible value times 10^k.
    Scaled(u8, i8),
    /// Not a number: a string, a boolean, a list.
    Wrong(u8),
}

const EDGES: [f64; 16] = [
    0.0, -0.0, 5e-324, 2.2e-308, 1e-300, 1e-20, 1e-9, 1e-3, 0.5, 1.0, 1e9, 1.9e9, 1e300,
    1.7e308, -1.0, 89.99999,
];
const PLAUSIBLE: [f64; 6] = [0.1, 0.3, 9.81, 0.25, 0.02, 1e-3];
const LAWS: [&str; 6] = ["coulomb", "static", "stribeck", "direction", "load", "viscous"];
const KEYS: [&str; 28] = [
    "slider_mass",
    "bob_mass",
    "rod_length",
    "rod_mass",
    "bob_radius",
    "pendulum_mass",
    "pendulum_com",
    "pendulum_inertia",
    "gravity",
    "mu_kinetic",
    "mu_static",
    "rail_tilt_deg",
    "pivot_damping",
    "mu_kinetic_positive",
    "mu_kinetic_negative",
    "mu_static_positive",
    "mu_static_negative",
    "load_exponent",
    "stribeck_velocity",
    "viscous_friction",
    "rod_length_sd",
    "slider_mass_sd",
    "bob_mass_sd",
    "rod_mass_sd",
    "bob_radius_sd",
    "gravity_sd",
    "slider_mass",
    "rod_length",
];

#[derive(Debug, Arbitrary)]
struct Input {
    values: [Val; 28],
    law: Option<u8>,
    site: Option<(f64, f64)>,
}

fn toml_value(v: &Val) -> Option<String> {
    let f = match v {
        Val::Absent => return None,
        Val::Any(x) => *x,
        Val::Edge(i) => EDGES[*i as usize % EDGES.len()],
        Val::Scaled(i, k) => PLAUSIBLE[*i as usize % PLAUSIBLE.len()] * 10f64.powi(*k as i32 % 40),
        Val::Wrong(i) => {
            return Some(["\"0.3\"", "true", "[0.3]", "nan", "inf", "-inf"][*i as usize % 6].into())
        }
    };
    Some(if f.is_nan() {
        "nan".into()
    } else if f.is_infinite() {
        if f > 0.0 { "inf" } else { "-inf" }.into()
    } else {
        format!("{f:e}")
    })
}

fuzz_target!(|input: Input| {
    let mut text = String::from("[rig]\n");
    // The first 26 keys once each; the last two repeat a key (a duplicate key is a TOML error).
    for (key, v) in KEYS.iter().zip(&input.values) {
        if let Some(v) = toml_value(v) {
            let _ = writeln!(text, "{key} = {v}");
        }
    }
    if let Some(l) = input.law {
        let _ = writeln!(text, "friction_law = \"{}\"", LAWS[l as usize % LAWS.len()]);
    }
    let path = Path::new("rig.toml");
    // RIG_MEASURED_STAGES=1 with `-runs=0` over a corpus says where each input ends.
    let stages = std::env::var_os("RIG_MEASURED_STAGES").is_some();
    let (rig, spec, _) = match RigFile::parse_on_earth(&text, path, 0.3, input.site) {
        Ok(parsed) => parsed,
        Err(e) => {
            if stages {
                let e = e.to_string();
                let kind = if e.contains("duplicate key") {
                    "duplicate key"
                } else if e.contains("TOML") || e.contains("invalid type") {
                    "not TOML / wrong type"
                } else {
                    "refused by a range check"
                };
                eprintln!("STAGE {kind}");
            }
            return;
        }
    };
    // What passes is a rig every command accepts, and a measurement whose priors the solve can
    // use: a tiny deviation is the exact value, never a weight that swamps the data.
    check_rig(path, &rig, RigOrigin::File { friction: "rig" }).expect("a parsed rig is valid");
    let m = RigMeasurement::from_spec(&spec);
    for p in m.priors() {
        assert!(p.centre.is_finite(), "{text}: {p:?}");
        assert!(
            p.sd.is_finite() && p.sd > RESOLVABLE_REL * p.centre.abs(),
            "{text}: {p:?}"
        );
    }
    for (name, v, sd, _) in &m.keys {
        assert!(v.is_finite() && sd.is_finite() && *sd >= 0.0, "{text}: {name} {v} {sd}");
    }
    let masses = check_masses(path, &rig).is_ok();
    let tilt = check_tilt(path, &rig).is_ok();
    let scale = check_time_scale(path, &rig, RigOrigin::File { friction: "rig" }).is_ok();
    if stages {
        let held = m.notes.iter().any(|n| n.contains("held exact"));
        eprintln!(
            "STAGE read, {} priors{}, fit pre-checks {}",
            m.priors().len(),
            if held { ", a tiny sd held exact" } else { "" },
            if masses && tilt && scale { "pass" } else { "refuse" }
        );
    }
});
