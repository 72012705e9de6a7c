//! The rigid pendulum (docs/physics.md, "The rigid pendulum") against physics the library does not
//! compute: the rigid body's mass, centre of mass and inertia summed here from the rod and the
//! sphere, Newton-Euler's forces and torque from the simulated accelerations, the conserved
//! momentum, the energy with J, the impulse law from the pivot's angular momentum, the period of
//! small swings; and fits of recordings made by an independent Newton-Euler generator
//! (`scripts/generators/rigid_generator.py`, `tests/data/rigid/`).

use crate::helpers::*;
use appell::data::{read_recording, ReadOptions};
use appell::fit::{fit, Estimate, FitReport, FitSettings, Nuisance, Observations};
use appell::model::{markers, regions, Mode, PendulumKeys, Rig};
use appell::scene::RigFile;
use appell::sim::{impulsive_stop, simulate, Method, Options, Request};
use std::f64::consts::{FRAC_PI_2, PI};
use std::path::{Path, PathBuf};
use std::process::Command;

/// A rig's rigid body summed here, part by part: a uniform rod of mass m_r from the pivot to
/// the bob's centre at l, and a solid sphere of mass m2 and radius R centred at l.
struct Body {
    m1: f64,
    m_p: f64,
    d: f64,
    /// About the pivot.
    j: f64,
    /// About the centre of mass.
    j_cm: f64,
    g: f64,
}

fn body(m1: f64, m2: f64, m_r: f64, radius: f64, l: f64) -> Body {
    let m_p = m2 + m_r;
    let d = (m2 * l + m_r * l / 2.0) / m_p;
    // Each part about its own centre, then moved to the common centre of mass.
    let rod_cm = m_r * l * l / 12.0 + m_r * (l / 2.0 - d).powi(2);
    let sphere_cm = 0.4 * m2 * radius * radius + m2 * (l - d).powi(2);
    let j_cm = rod_cm + sphere_cm;
    Body {
        m1,
        m_p,
        d,
        j: j_cm + m_p * d * d,
        j_cm,
        g: 9.81,
    }
}

/// The library's rig for the same build, from the rig-file keys.
fn rig_of(m1: f64, m2: f64, m_r: f64, radius: f64, l: f64, mu: f64) -> Rig<f64> {
    PendulumKeys {
        bob_mass: Some(m2),
        rod_mass: Some(m_r),
        bob_radius: Some(radius),
        ..PendulumKeys::default()
    }
    .rig(m1, l, 9.81, mu, None)
    .expect("a valid rig")
}

/// The rigs of the tests: docs/physics.md's example (paper rig, 20 g rod, 2 cm sphere) and a
/// light slider under a heavy bob with a heavy rod.
fn cases() -> Vec<(Body, Rig<f64>)> {
    [
        (0.1, 0.1, 0.02, 0.02, 0.3),
        (0.05, 0.15, 0.03, 0.025, 0.25),
        (0.4, 0.2, 0.03, 0.02, 0.3),
    ]
    .into_iter()
    .map(|(m1, m2, mr, r, l)| (body(m1, m2, mr, r, l), rig_of(m1, m2, mr, r, l, 0.25)))
    .collect()
}

fn request(times: Vec<f64>, work: bool) -> Request {
    Request {
        sample_times: times,
        friction_work: work,
        positions_only: false,
    }
}

/// docs/physics.md's worked example, from the sums above: L = 0.29139 m, m_e = 0.11325 kg,
/// equivalent slider 0.10675 kg.
#[test]
fn the_worked_example_of_physics_md() {
    let b = body(0.1, 0.1, 0.02, 0.02, 0.3);
    let rig = rig_of(0.1, 0.1, 0.02, 0.02, 0.3, 0.3);
    let l_eq = b.j / (b.m_p * b.d);
    assert!((l_eq - 0.29139).abs() < 5e-6);
    assert!((rig.rod_length - l_eq).abs() < 1e-15);
    assert!((rig.bob_mass - 0.11325).abs() < 5e-6);
    assert!((rig.slider_mass - 0.10675).abs() < 5e-6);
    assert_eq!(rig.marker_length, 0.3);
    let period = 2.0 * PI * (b.j / (b.m_p * b.g * b.d)).sqrt();
    assert!((period - 1.0829).abs() < 5e-5);
}

/// Small swings of the stuck pendulum have the rigid body's period 2 pi sqrt(J / (m_p g d))
/// (times the finite-amplitude factor 1 + theta0^2 / 16), not the point rig's.
#[test]
fn small_swings_have_the_rigid_bodys_period() {
    for (b, rig) in cases() {
        let amp = 1e-3;
        let expected = 2.0 * PI * (b.j / (b.m_p * b.g * b.d)).sqrt() * (1.0 + amp * amp / 16.0);
        let dt = 1e-4;
        let times: Vec<f64> = (0..=35_000).map(|k| k as f64 * dt).collect();
        let sol = run(
            &rig,
            [0.0, FRAC_PI_2 + amp, 0.0, 0.0],
            3.5,
            1e-12,
            Method::Dop853,
            &request(times, false),
        );
        assert!(sol.events.is_empty(), "stays stuck: {:?}", sol.events);
        // Downward crossings of theta = pi/2, by linear interpolation between samples.
        let mut crossings = Vec::new();
        for w in sol.samples.windows(2) {
            let (a, c) = (w[0].state[1] - FRAC_PI_2, w[1].state[1] - FRAC_PI_2);
            if a > 0.0 && c <= 0.0 {
                crossings.push(w[0].t + dt * a / (a - c));
            }
        }
        assert!(crossings.len() >= 3);
        let period = (crossings[crossings.len() - 1] - crossings[0]) / (crossings.len() - 1) as f64;
        let point = 2.0 * PI * (rig.marker_length / b.g).sqrt();
        assert!(
            (period / expected - 1.0).abs() < 1e-6,
            "period {period} expected {expected} (the point rig's {point})"
        );
        assert!((period / point - 1.0).abs() > 1e-3);
    }
}

/// At mu = 0 the rigid rig's horizontal momentum (m1 + m_p) x' - m_p d w sin(theta) is conserved
/// and its energy with J is constant.
#[test]
fn frictionless_conserves_the_rigid_bodys_momentum_and_energy() {
    for (b, rig) in cases() {
        let rig = Rig {
            mu_kinetic: 0.0,
            mu_static: 0.0,
            ..rig
        };
        let y0 = [0.0, 0.2, 0.3, -2.0];
        let times: Vec<f64> = (0..=200).map(|k| k as f64 * 0.01).collect();
        let sol = run(&rig, y0, 2.0, 1e-12, Method::Dop853, &request(times, false));
        let p = |y: &[f64; 4]| (b.m1 + b.m_p) * y[2] - b.m_p * b.d * y[3] * y[1].sin();
        let e = |y: &[f64; 4]| energy_rigid(&b, y);
        for s in &sol.samples {
            assert!((p(&s.state) - p(&y0)).abs() < 1e-10, "t={}", s.t);
            assert!((e(&s.state) - e(&y0)).abs() < 1e-10, "t={}", s.t);
        }
    }
}

/// E = 1/2 (m1 + m_p) x'^2 - m_p d x' w sin(theta) + 1/2 J w^2 - m_p g d sin(theta) (level).
fn energy_rigid(b: &Body, y: &[f64; 4]) -> f64 {
    let (x_dot, th, w) = (y[2], y[1], y[3]);
    0.5 * (b.m1 + b.m_p) * x_dot * x_dot - b.m_p * b.d * x_dot * w * th.sin() + 0.5 * b.j * w * w
        - b.m_p * b.g * b.d * th.sin()
}

/// With friction, the rigid body's energy falls by exactly the friction work, through every
/// stick-slip transition; and the library's energy output is that energy.
#[test]
fn energy_with_j_balances_the_friction_work() {
    for (b, rig) in cases() {
        let y0 = [0.0, 0.0, 0.0, 0.0];
        let times: Vec<f64> = (0..=40).map(|k| k as f64 * 0.05).collect();
        let sol = run(&rig, y0, 2.0, 1e-12, Method::Dop853, &request(times, true));
        assert!(sol.events.len() >= 2, "sticks and slips: {:?}", sol.events);
        let work = sol.friction_work.unwrap();
        assert!(work < -1e-3);
        for s in &sol.samples {
            let de = energy_rigid(&b, &s.state) - energy_rigid(&b, &y0);
            let w = s.friction_work.unwrap();
            assert!(
                (de - w).abs() < 1e-9 * work.abs(),
                "t={} dE={de} W={w}",
                s.t
            );
            let lib = appell::model::energy(&rig, &s.state);
            assert!((lib - energy_rigid(&b, &s.state)).abs() < 1e-12);
        }
    }
}

/// Newton-Euler on `rig`'s sampled trajectories (the rigid body `b` summed here), with the
/// real-rig terms written out here: gravity (g_x, g_y) in the rail frame, the pivot's damping
/// torque -c_p w on the pendulum, and while sliding the friction law mu(v) = mu_k + (mu_s -
/// mu_k) exp(-(v/v_s)^2) (Coulomb when v_s is `None`) plus viscous rail friction -c_v x'.
/// From the simulated accelerations the pivot force on the pendulum is
/// H = m_p a_cm - m_p (g_x, g_y); it must give the angular acceleration about the centre of
/// mass, J_cm theta'' = torque of H - c_p w; the slider obeys m1 x'' = F - H_x + m1 g_x with
/// the law's F on N = H_y - m1 g_y while sliding, and while stuck |F| <= mu_s |N|. Nothing here
/// uses the equivalent rig.
fn check_newton_euler(b: &Body, rig: &Rig<f64>, v_s: Option<f64>) {
    let (gx, gy) = (b.g * rig.rail_tilt.sin(), b.g * rig.rail_tilt.cos());
    for y0 in [[0.0, 0.0, 0.0, 0.0], [0.0, -0.4, 0.0, 3.0]] {
        let times: Vec<f64> = (0..=400).map(|k| k as f64 * 0.005).collect();
        let sol = run(rig, y0, 2.0, 1e-11, Method::Dop853, &request(times, false));
        let (mut slides, mut sticks) = (0, 0);
        for s in &sol.samples {
            let y = s.state;
            let (xdd, tdd) = rig.accelerations(s.mode, &y);
            let (sn, cs, w) = (y[1].sin(), y[1].cos(), y[3]);
            // Centre of mass at (x + d cos, d sin), y down.
            let a_cm = [
                xdd - b.d * (sn * tdd + cs * w * w),
                b.d * (cs * tdd - sn * w * w),
            ];
            let h = [b.m_p * (a_cm[0] - gx), b.m_p * (a_cm[1] - gy)];
            // From the centre of mass to the pivot: -d (cos, sin).
            let r = [-b.d * cs, -b.d * sn];
            let torque = r[0] * h[1] - r[1] * h[0] - rig.pivot_damping * w;
            let scale = b.m_p * b.g * b.d;
            assert!(
                (b.j_cm * tdd - torque).abs() < 1e-9 * scale,
                "t={} torque {torque} vs {}",
                s.t,
                b.j_cm * tdd
            );
            let normal = h[1] - b.m1 * gy;
            let f = b.m1 * xdd + h[0] - b.m1 * gx;
            let force = (b.m1 + b.m_p) * b.g;
            match s.mode {
                Mode::Slide(dir) => {
                    slides += 1;
                    let v = y[2].abs();
                    let mu = match v_s {
                        None => rig.mu_kinetic,
                        Some(v_s) => {
                            rig.mu_kinetic
                                + (rig.mu_static - rig.mu_kinetic) * (-(v / v_s).powi(2)).exp()
                        }
                    };
                    let law = -mu * dir.sign() * normal.abs() - rig.viscous_friction * y[2];
                    assert!((f - law).abs() < 1e-9 * force, "t={} F={f} law {law}", s.t);
                }
                Mode::Stick => {
                    sticks += 1;
                    assert!(xdd == 0.0);
                    assert!(f.abs() <= rig.mu_static * normal.abs() + 1e-9 * force);
                }
            }
        }
        assert!(
            slides > 10 && sticks > 10,
            "{slides} slides, {sticks} sticks"
        );
    }
}

/// Newton-Euler on the plain rigid rigs (level rail, Coulomb friction, no damping).
#[test]
fn newton_euler_holds_on_sampled_trajectories() {
    for (b, rig) in cases() {
        check_newton_euler(&b, &rig, None);
    }
}

/// The real-rig terms compose with the rigid pendulum: Newton-Euler with a tilted rail, pivot
/// damping, Stribeck friction and viscous rail friction, all at once.
#[test]
fn newton_euler_holds_with_tilt_damping_and_stribeck() {
    for (b, rig) in cases() {
        let rig = Rig {
            mu_static: 0.3,
            ..rig
        }
        .with_rail_tilt(0.5_f64.to_radians())
        .with_pivot_damping(2e-3)
        .with_viscous_friction(0.05)
        .with_stribeck(0.05);
        check_newton_euler(&b, &rig, Some(0.05));
    }
}

/// An impulsive stop keeps the pendulum's angular momentum about the pivot,
/// J w - m_p d sin(theta) x', and its impulses are the changes of the whole rig's momentum.
#[test]
fn impulsive_stop_keeps_the_angular_momentum_about_the_pivot() {
    for (b, rig) in cases() {
        for y in [[0.0, 0.7, 0.4, -1.5], [0.1, -1.2, -0.8, 2.0]] {
            let (after, imp) = impulsive_stop(&rig, &y);
            assert_eq!(after[2], 0.0);
            let h = |y: &[f64; 4]| b.j * y[3] - b.m_p * b.d * y[1].sin() * y[2];
            assert!((h(&after) - h(&y)).abs() < 1e-14);
            let px = |y: &[f64; 4]| (b.m1 + b.m_p) * y[2] - b.m_p * b.d * y[3] * y[1].sin();
            let py = |y: &[f64; 4]| b.m_p * b.d * y[3] * y[1].cos();
            assert!((imp.friction - (px(&after) - px(&y))).abs() < 1e-14);
            assert!((imp.normal - (py(&after) - py(&y))).abs() < 1e-14);
            let lost = energy_rigid(&b, &y) - energy_rigid(&b, &after);
            assert!((imp.energy_lost - lost).abs() < 1e-14);
        }
    }
}

/// Zero rod mass and zero radius are the point rig bit for bit: the same events and final
/// state, to the last bit, as a rig file without the keys.
#[test]
fn zero_rod_mass_and_radius_are_the_point_rig_bit_for_bit() {
    let point = Rig::new(0.1, 0.1, 0.3, 9.81, 0.35, None).unwrap();
    let zeros = rig_of(0.1, 0.1, 0.0, 0.0, 0.3, 0.35);
    assert_eq!(zeros.slider_mass, point.slider_mass);
    assert_eq!(zeros.bob_mass, point.bob_mass);
    assert_eq!(zeros.rod_length, point.rod_length);
    assert_eq!(zeros.marker_length, point.marker_length);
    let options = Options::default();
    let req = request((0..=20).map(|k| k as f64 * 0.1).collect(), true);
    let a = simulate(&point, &[0.0; 4], 2.0, &options, &req).unwrap();
    let b = simulate(&zeros, &[0.0; 4], 2.0, &options, &req).unwrap();
    assert_eq!(a.final_state, b.final_state);
    assert_eq!(a.events.len(), b.events.len());
    for (e, f) in a.events.iter().zip(&b.events) {
        assert_eq!(e.t, f.t);
        assert_eq!(e.state, f.state);
    }
}

/// The bob's marker stays at the bob's centre (l from the slider), while the motion follows L.
#[test]
fn the_bob_marker_sits_at_the_rod_length() {
    let rig = rig_of(0.1, 0.1, 0.02, 0.02, 0.3, 0.35);
    assert!((rig.rod_length - 0.3).abs() > 5e-3);
    let m = markers(&rig, &[0.01, 0.7, 0.0, 0.0]);
    let dist = ((m[2] - m[0]).powi(2) + (m[3] - m[1]).powi(2)).sqrt();
    assert!((dist - 0.3).abs() < 1e-15);
}

/// mu* and the paradox band from r' = (m1 + m_p - m_e) / m_e: a rigid pendulum's mu* is above
/// the point rig's with the same masses.
#[test]
fn critical_friction_uses_the_equivalent_mass_ratio() {
    for (b, rig) in cases() {
        let m_e = (b.m_p * b.d).powi(2) / b.j;
        let r_eq = (b.m1 + b.m_p - m_e) / m_e;
        let mu_star = 2.0 * (r_eq * (1.0 + r_eq)).sqrt();
        let summary = regions::RegionSummary::of(&rig);
        assert!((summary.mu_critical - mu_star).abs() < 1e-12 * mu_star);
        let point = 2.0 * (b.m1 / b.m_p * (1.0 + b.m1 / b.m_p)).sqrt();
        assert!((summary.point_rig_mu_critical.unwrap() - point).abs() < 1e-12 * point);
        assert!(mu_star > point);
    }
}

fn appell(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_appell"))
        .args(args)
        .output()
        .expect("run appell")
}

fn repo(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

/// `appell regions` prints the rigid rig's mu* and the point rig's beside it.
#[test]
fn regions_prints_both_critical_frictions() {
    let out = appell(&[
        "regions",
        repo("configs/rigid_rig.toml").to_str().unwrap(),
        "--trajectories",
        "0",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    let b = body(0.1, 0.1, 0.02, 0.02, 0.3);
    let m_e = (b.m_p * b.d).powi(2) / b.j;
    let r_eq = (b.m1 + b.m_p - m_e) / m_e;
    let rigid = format!("mu* = {:.4}", 2.0 * (r_eq * (1.0 + r_eq)).sqrt());
    let r = b.m1 / b.m_p;
    let point = format!("has mu* = {:.4}", 2.0 * (r * (1.0 + r)).sqrt());
    assert!(text.contains(&rigid), "{rigid} not in:\n{text}");
    assert!(text.contains(&point), "{point} not in:\n{text}");
}

/// Pendulum keys no body can have are refused with exit 2, naming the file and the key.
#[test]
fn impossible_pendulums_exit_2_naming_the_key() {
    // Removed with everything in it at the end of the test.
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().to_path_buf();
    let head = "[rig]\nslider_mass = 0.1\nrod_length = 0.3\ngravity = 9.81\nmu_kinetic = 0.3\n";
    for (name, keys, key) in [
        ("neg_rod", "bob_mass = 0.1\nrod_mass = -0.01\n", "rod_mass"),
        (
            "neg_radius",
            "bob_mass = 0.1\nbob_radius = -0.01\n",
            "bob_radius",
        ),
        (
            "big_radius",
            "bob_mass = 0.1\nbob_radius = 0.3\n",
            "bob_radius",
        ),
        (
            "mixed",
            "bob_mass = 0.1\npendulum_mass = 0.12\npendulum_com = 0.28\npendulum_inertia = 0.01\n",
            "pendulum_mass",
        ),
        (
            "low_inertia",
            "pendulum_mass = 0.12\npendulum_com = 0.28\npendulum_inertia = 0.009\n",
            "pendulum_inertia",
        ),
        (
            "far_com",
            "pendulum_mass = 0.12\npendulum_com = 0.7\npendulum_inertia = 0.1\n",
            "pendulum_com",
        ),
        (
            "no_com",
            "pendulum_mass = 0.12\npendulum_inertia = 0.01\n",
            "pendulum_com",
        ),
        ("no_bob", "", "bob_mass"),
    ] {
        let path = dir.join(format!("{name}.toml"));
        std::fs::write(&path, format!("{head}{keys}")).unwrap();
        let out = appell(&["regions", path.to_str().unwrap(), "--trajectories", "0"]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{name}: {err}");
        assert!(err.contains(&format!("{name}.toml")), "{name}: {err}");
        assert!(err.contains(key), "{name}: {err}");
    }
}

/// The general form (mass, centre of mass, inertia) gives the same rig as the rod and sphere
/// it describes.
#[test]
fn the_general_form_matches_the_rod_and_sphere() {
    let b = body(0.1, 0.1, 0.02, 0.02, 0.3);
    let general = PendulumKeys {
        pendulum_mass: Some(b.m_p),
        pendulum_com: Some(b.d),
        pendulum_inertia: Some(b.j),
        ..PendulumKeys::default()
    }
    .rig(0.1, 0.3, 9.81, 0.3, None)
    .unwrap();
    let rod = rig_of(0.1, 0.1, 0.02, 0.02, 0.3, 0.3);
    for (a, c) in [
        (general.slider_mass, rod.slider_mass),
        (general.bob_mass, rod.bob_mass),
        (general.rod_length, rod.rod_length),
    ] {
        assert!((a - c).abs() < 1e-14 * c);
    }
}

/// The truth of the independent generator's recordings.
fn truth() -> serde_json::Value {
    let text = std::fs::read_to_string(repo("tests/data/rigid/rigid_truth.json")).unwrap();
    serde_json::from_str(&text).unwrap()
}

fn observations(rig: &str) -> Observations {
    let path = repo(&format!("tests/data/rigid/rigid_{rig}.csv"));
    let rec = read_recording(&[path], &ReadOptions::default()).expect("reads");
    Observations::from(&rec)
}

/// The fit's mu_kinetic, asserted within 3 standard errors of the truth `mu`.
fn mu_within_three_se(rig: &str, rep: &FitReport, mu: f64) -> Estimate {
    let e = rep.mu_kinetic.expect("mu_kinetic identifiable");
    let z = (e.value - mu) / e.stderr;
    assert!(
        z.abs() < 3.0,
        "{rig}: mu {} +- {} (z = {z})",
        e.value,
        e.stderr
    );
    e
}

/// Recordings of rigid pendulums made by the independent Newton-Euler generator, three rigs
/// from light to heavy slider: with the measured pendulum in the rig file, mu within 3
/// standard errors and not flagged.
#[test]
fn rigid_recordings_fit_with_the_measured_pendulum() {
    let t = truth();
    for rig in ["light", "paper", "heavy"] {
        let mu = t["rigs"][rig]["mu"].as_f64().unwrap();
        let file = repo(&format!("tests/data/rigid/rigid_{rig}_measured.toml"));
        let r = RigFile::load_for_fit(&file, 0.3).unwrap();
        assert!(r.pendulum.is_some());
        let rep = fit(observations(rig), &r, &FitSettings::default()).unwrap();
        mu_within_three_se(rig, &rep, mu);
        assert!(
            rep.adequacy.limited_by_model.is_empty(),
            "{rig}: {:?}",
            rep.adequacy
        );
        assert!(!rep.nuisances.contains(&Nuisance::RigidPendulum));
    }
}

/// The same recordings with the lab's masses only (no rod mass, no radius): the data choose the
/// rigid pendulum, and mu is within 3 standard errors with a 95% half-width of at most 2% of
/// mu; the equivalent length found is the true L within 3 standard errors.
#[test]
fn rigid_recordings_fit_with_the_labs_masses_only() {
    let t = truth();
    for rig in ["light", "paper", "heavy"] {
        let mu = t["rigs"][rig]["mu"].as_f64().unwrap();
        let l_true = t["rigs"][rig]["L"].as_f64().unwrap();
        let file = repo(&format!("tests/data/rigid/rigid_{rig}_lab.toml"));
        let r = RigFile::load_for_fit(&file, 0.3).unwrap();
        assert!(r.pendulum.is_none());
        let rep = fit(observations(rig), &r, &FitSettings::default()).unwrap();
        assert!(rep.failed.is_none(), "{rig}: {:?}", rep.failed);
        assert!(
            rep.nuisances.contains(&Nuisance::RigidPendulum),
            "{rig}: {:?}",
            rep.nuisances
        );
        let e = mu_within_three_se(rig, &rep, mu);
        let half = 0.5 * (e.ci95[1] - e.ci95[0]);
        assert!(half <= 0.02 * mu, "{rig}: half-width {half}");
        let p = rep.pendulum.unwrap();
        let zl = (p.equivalent_length.value - l_true) / p.equivalent_length.stderr;
        assert!(
            zl.abs() < 3.0,
            "{rig}: L {:?} (z = {zl})",
            p.equivalent_length
        );
    }
}

/// A plan file takes the rigid keys: the planner's rig is the rigid body's equivalent rig (its
/// stuck pendulum swings with L from the sums here), and the plan's note names r'.
#[test]
fn plans_take_the_rigid_pendulum() {
    let text = std::fs::read_to_string(repo("configs/plan_example.toml"))
        .unwrap()
        .replace(
            "bob_mass = 0.10      # kg\n",
            "bob_mass = 0.10      # kg\nrod_mass = 0.02\nbob_radius = 0.02\n",
        );
    assert!(text.contains("rod_mass"));
    let spec = appell::plan::PlanSpec::from_toml(&text, Path::new("rigid_plan.toml")).unwrap();
    let b = body(0.1, 0.1, 0.02, 0.02, 0.3);
    assert!((spec.rig.rod_length - b.j / (b.m_p * b.d)).abs() < 1e-14);
    assert_eq!(spec.rig.marker_length, 0.3);
    let m_e = (b.m_p * b.d).powi(2) / b.j;
    assert!((spec.rig.mass_ratio() - (b.m1 + b.m_p - m_e) / m_e).abs() < 1e-12);
}

/// The failure, made on purpose: the heavy rig's recording fitted with point masses and
/// Stribeck friction forced in (no rigid pendulum allowed) ends with mu_kinetic pinned at 0 and
/// the friction carried by Stribeck's law. The fit must say it failed, never report mu = 0.
#[test]
fn mu_pinned_at_zero_by_stribeck_is_reported_as_a_failed_fit() {
    let file = repo("tests/data/rigid/rigid_heavy_lab.toml");
    let r = RigFile::load_for_fit(&file, 0.3).unwrap();
    let settings = FitSettings {
        nuisances: false,
        windows: false,
        with: vec![Nuisance::Stribeck],
        ..FitSettings::default()
    };
    let rep = fit(observations("heavy"), &r, &settings).unwrap();
    // The scenario: Stribeck's law takes the friction and mu_kinetic sits at its bound.
    let e = rep.mu_kinetic.unwrap();
    assert!(
        e.value < 1e-3,
        "mu {} is no longer pinned: {:?}",
        e.value,
        rep.nuisances
    );
    // Its interval stops at mu_kinetic = 0 (it was [-40, 40] before the bound).
    assert!(e.ci95[0] >= 0.0, "{:?}", e.ci95);
    let why = rep.failed.expect("a pinned mu is a failed fit");
    assert!(why.starts_with("The fit failed"), "{why}");
    let limited = appell::report::fit::limited_sentence(&rep.adequacy).unwrap();
    assert!(limited.starts_with("The fit failed"), "{limited}");
}

/// The same failure from the command line is no answer: exit 1 with the reason, mu_kinetic
/// null in the JSON (the report still printed in full), alone and in a directory of
/// recordings.
#[test]
fn a_failed_fit_exits_1_with_mu_null() {
    let rig = repo("tests/data/rigid/rigid_heavy_lab.toml");
    let rec = repo("tests/data/rigid/rigid_heavy.csv");
    let run = |input: &Path| {
        Command::new(env!("CARGO_BIN_EXE_appell"))
            .args([
                "fit",
                "--json",
                "--plain",
                "--no-profile",
                "--with",
                "stribeck",
                "--rig",
            ])
            .arg(&rig)
            .arg(input)
            .output()
            .unwrap()
    };
    let out = run(&rec);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("The fit failed"), "{err}");
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(
        v["failed"].is_string() && v["mu_kinetic"].is_null(),
        "{}",
        v["mu_kinetic"]
    );
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(&rec, dir.path().join("rigid_heavy.csv")).unwrap();
    let out = run(dir.path());
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    let line = String::from_utf8_lossy(&out.stdout);
    let v: serde_json::Value = serde_json::from_str(line.trim()).unwrap();
    assert!(
        v["failed"].is_string() && v["mu_kinetic"].is_null(),
        "{line}"
    );
}

/// With a tilted rail and pivot damping the rigid body's energy (docs/physics.md, "The rigid pendulum":
/// E = 1/2 (m1 + m_p) x'^2 - m_p d x' w sin + 1/2 J w^2 - (m1 + m_p) g_x x - m_p g_x d cos
/// - m_p g_y d sin) changes by the friction work plus the damping work.
#[test]
fn tilted_damped_energy_with_j_balances_the_work() {
    for (b, rig) in cases() {
        let rig = rig
            .with_rail_tilt(1.0_f64.to_radians())
            .with_pivot_damping(1e-3)
            .with_viscous_friction(0.02);
        let (gx, gy) = (b.g * rig.rail_tilt.sin(), b.g * rig.rail_tilt.cos());
        let e = |y: &[f64; 4]| {
            let (x, th, x_dot, w) = (y[0], y[1], y[2], y[3]);
            0.5 * (b.m1 + b.m_p) * x_dot * x_dot - b.m_p * b.d * x_dot * w * th.sin()
                + 0.5 * b.j * w * w
                - (b.m1 + b.m_p) * gx * x
                - b.m_p * gx * b.d * th.cos()
                - b.m_p * gy * b.d * th.sin()
        };
        let y0 = [0.0, 0.0, 0.0, 0.0];
        let times: Vec<f64> = (0..=40).map(|k| k as f64 * 0.05).collect();
        let sol = run(&rig, y0, 2.0, 1e-12, Method::Dop853, &request(times, true));
        assert!(sol.events.len() >= 2, "sticks and slips: {:?}", sol.events);
        for s in &sol.samples {
            let work = s.friction_work.unwrap() + s.damping_work.unwrap();
            let de = e(&s.state) - e(&y0);
            assert!(
                (de - work).abs() < 1e-9 * (b.m_p * b.g * b.d),
                "t={} dE={de} W={work}",
                s.t
            );
        }
    }
}

/// What the fit reports of a pendulum it found: given the true L and r' and the true masses,
/// m_e, J, d and the radius of gyration are the rigid body's (summed here); the standard errors
/// follow the delta method, checked by finite differences with a correlated covariance.
#[test]
fn the_pendulum_found_is_reported_in_the_bodys_quantities() {
    use appell::fit::PendulumFound;
    let b = body(0.1, 0.1, 0.02, 0.02, 0.3);
    let l_eq = b.j / (b.m_p * b.d);
    let m_e = (b.m_p * b.d).powi(2) / b.j;
    let r_eq = (b.m1 + b.m_p - m_e) / m_e;
    let cov = [[4e-10, -3e-9], [-3e-9, 9e-8]];
    let found = PendulumFound::new(l_eq, r_eq, cov, b.m1 + b.m_p, b.m_p);
    let close = |a: f64, c: f64| (a - c).abs() < 1e-12 * c.abs();
    assert!(close(found.equivalent_bob_mass.value, m_e));
    assert!(close(found.inertia.value, b.j));
    assert!(close(found.com.value, b.d));
    assert!(close(found.radius_of_gyration.value, (b.j / b.m_p).sqrt()));
    // Delta method by central differences of J(L, r') = total / (1 + r') L^2.
    let j = |l: f64, r: f64| (b.m1 + b.m_p) / (1.0 + r) * l * l;
    let (hl, hr) = (1e-7, 1e-6);
    let g = [
        (j(l_eq + hl, r_eq) - j(l_eq - hl, r_eq)) / (2.0 * hl),
        (j(l_eq, r_eq + hr) - j(l_eq, r_eq - hr)) / (2.0 * hr),
    ];
    let var = g[0] * g[0] * cov[0][0] + 2.0 * g[0] * g[1] * cov[0][1] + g[1] * g[1] * cov[1][1];
    assert!((found.inertia.stderr / var.sqrt() - 1.0).abs() < 1e-5);
    assert!((found.equivalent_length.stderr - 2e-5).abs() < 1e-15);
}

/// A rod and sphere of zero mass and size is a point bob (a rig file that writes the zeros
/// out), and any rod mass or radius makes it rigid: reports call only the latter a rigid
/// pendulum.
#[test]
fn zero_rod_and_radius_are_a_point_pendulum() {
    use appell::model::RigidPendulum;
    assert!(RigidPendulum::rod_and_sphere(0.045, 0.15, 0.0, 0.0, 0.3).is_point());
    assert!(!RigidPendulum::rod_and_sphere(0.045, 0.15, 1e-3, 0.0, 0.3).is_point());
    assert!(!RigidPendulum::rod_and_sphere(0.045, 0.15, 0.0, 0.01, 0.3).is_point());
    // The point rig's plan prints the point mass ratio, not an equivalent one.
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_appell"))
        .args(["plan", "--json"])
        .arg(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/plan_law_suspect.toml"))
        .output()
        .unwrap();
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let notes = v["notes"].to_string();
    assert!(notes.contains("mass ratio r = m1/m2 = 0.300"), "{notes}");
    assert!(!notes.contains("rigid"), "{notes}");
}
