//! `appell simulate` as a user runs it: output shape and clear errors for bad scenes.

use std::process::Command;

fn appell(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_appell"))
        .args(args)
        .output()
        .expect("runs")
}

/// A file in a directory of its own, removed with everything beside it (the outputs a test
/// writes next to it) when dropped.
struct Scratch {
    _dir: tempfile::TempDir,
    path: std::path::PathBuf,
}

impl std::ops::Deref for Scratch {
    type Target = std::path::Path;
    fn deref(&self) -> &std::path::Path {
        &self.path
    }
}

fn scene_with(replace: &str, with: &str) -> Scratch {
    let base = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/configs/paper_rest_horizontal.toml"
    ))
    .unwrap();
    assert!(base.contains(replace), "fixture lacks {replace}");
    let text = base.replacen(replace, with, 1);
    let dir = tempfile::Builder::new()
        .prefix("appell-test-")
        .tempdir()
        .unwrap();
    let path = dir
        .path()
        .join(format!("scene-{:x}.toml", text.len() * 31 + with.len()));
    std::fs::write(&path, text).unwrap();
    Scratch { _dir: dir, path }
}

#[test]
fn json_has_events_final_and_stats() {
    let out = appell(&[
        "simulate",
        concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/configs/paper_rest_horizontal.toml"
        ),
        "--json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let ev = v["events"].as_array().unwrap();
    assert_eq!(ev[0]["from"], "stick");
    assert_eq!(ev[0]["to"], "slide+");
    assert!((ev[0]["t"].as_f64().unwrap() - 0.0868).abs() < 1e-4);
    for key in ["x", "theta", "x_dot", "theta_dot"] {
        assert!(v["final"][key].is_f64());
    }
    for key in ["steps", "rejected", "rhs_evals"] {
        assert!(v["stats"][key].as_u64().unwrap() > 0 || key == "rejected");
    }
}

#[test]
fn trajectory_csv_has_markers_at_rod_length() {
    let scene = scene_with(
        "[run]",
        "[output]\nframe_rate = 100.0\nmarkers = true\nenergy = true\n\n[run]",
    );
    let out_csv = scene.with_extension("csv");
    let out = appell(&[
        "simulate",
        scene.to_str().unwrap(),
        "--out",
        out_csv.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let mut rd = csv::Reader::from_path(&out_csv).unwrap();
    let headers = rd.headers().unwrap().clone();
    let col = |name: &str| headers.iter().position(|h| h == name).unwrap();
    let mut rows = 0;
    for rec in rd.records() {
        let rec = rec.unwrap();
        let f = |name: &str| rec[col(name)].parse::<f64>().unwrap();
        let d =
            ((f("bob_x") - f("slider_x")).powi(2) + (f("bob_y") - f("slider_y")).powi(2)).sqrt();
        assert!((d - 0.3).abs() < 1e-12);
        assert!(f("bob_y") <= 1e-12, "bob below the rail in a y-up frame");
        rows += 1;
    }
    assert_eq!(rows, 201);
}

/// The `[rig]` line the real-rig cases append their keys after.
const R: &str = "mu_static = 0.35";

#[test]
fn bad_scenes_name_the_key_and_exit_2() {
    let cases = [
        ("slider_mass = 0.10", "slider_mass = -0.10", "slider_mass"),
        ("mu_static = 0.35", "mu_static = 0.2", "mu_static"),
        ("duration = 2.0", "", "duration"),
        ("theta = 0.0", "theta = 0.0\nphi = 1.0", "phi"),
        ("x_dot = 0.0", "x_dot = nan", "x_dot"),
        ("rtol = 1e-10", "rtol = \"tight\"", "rtol"),
        // The real-rig keys get the same checks.
        (
            R,
            "mu_static = 0.35\npivot_damping = -1e-3",
            "pivot_damping",
        ),
        (
            R,
            "mu_static = 0.35\nviscous_friction = inf",
            "viscous_friction",
        ),
        (R, "mu_static = 0.35\nrail_tilt_deg = nan", "rail_tilt_deg"),
        (R, "mu_static = 0.35\nrail_tilt_deg = 90.0", "rail_tilt_deg"),
        (R, "mu_static = 0.35\nrail_tilt = 1.0", "rail_tilt"),
        (
            R,
            "mu_static = 0.35\nfriction_law = \"dahl\"",
            "friction_law",
        ),
        (
            R,
            "mu_static = 0.35\nfriction_law = \"stribeck\"",
            "stribeck_velocity",
        ),
        (
            R,
            "mu_static = 0.35\nstribeck_velocity = 0.1",
            "stribeck_velocity",
        ),
        (
            R,
            "mu_static = 0.35\nfriction_law = \"stribeck\"\nstribeck_velocity = 0.0",
            "stribeck_velocity",
        ),
    ];
    for (from, to, key) in cases {
        let path = scene_with(from, to);
        let out = appell(&["simulate", path.to_str().unwrap()]);
        assert_eq!(
            out.status.code(),
            Some(2),
            "{to}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            err.contains(key),
            "error for `{to}` should name `{key}`: {err}"
        );
        assert!(
            err.contains(path.file_name().unwrap().to_str().unwrap()),
            "names the file: {err}"
        );
    }
    let out = appell(&["simulate", "/nonexistent/scene.toml"]);
    assert_eq!(out.status.code(), Some(2));
}

/// The shipped light-slider scene above mu* shows a sudden stop in the JSON, with its peak
/// normal force, and closes the energy balance with the impulsive losses.
#[test]
fn paradox_scene_json_reports_sudden_stop() {
    let out = appell(&[
        "simulate",
        concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/configs/paradox_light_slider.toml"
        ),
        "--json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let stop = v["events"]
        .as_array()
        .unwrap()
        .iter()
        .find(|e| e["kind"] == "sudden_stop")
        .expect("a sudden stop");
    assert_eq!(
        (stop["from"].as_str(), stop["to"].as_str()),
        (Some("slide+"), Some("stick"))
    );
    assert!(stop["t"].as_f64().unwrap() > 0.2 && stop["peak_normal"].as_f64().unwrap() > 50.0);
    let balance = v["energy_change"].as_f64().unwrap() - v["friction_work"].as_f64().unwrap()
        + v["impulsive_losses"].as_f64().unwrap();
    assert!(balance.abs() < 1e-8, "{balance}");
    assert_eq!(v["completed"], true);
}

/// A scene with every real-rig term runs from the command line, and its trajectory CSV closes
/// the energy balance with the damping work column.
#[test]
fn real_rig_scene_writes_energy_friction_and_damping_work() {
    let scene = scene_with(
        "mu_static = 0.35",
        "mu_static = 0.45\nrail_tilt_deg = 1.5\npivot_damping = 1e-3\nfriction_law = \"stribeck\"\nstribeck_velocity = 0.05\nviscous_friction = 0.02\n\n[output]\nframe_rate = 50.0\nenergy = true",
    );
    let out_csv = scene.with_extension("real.csv");
    let out = appell(&[
        "simulate",
        scene.to_str().unwrap(),
        "--out",
        out_csv.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let mut rd = csv::Reader::from_path(&out_csv).unwrap();
    let headers = rd.headers().unwrap().clone();
    let col = |name: &str| headers.iter().position(|h| h == name).unwrap();
    let rows: Vec<csv::StringRecord> = rd.records().map(|r| r.unwrap()).collect();
    let f = |r: &csv::StringRecord, name: &str| r[col(name)].parse::<f64>().unwrap();
    let e0 = f(&rows[0], "energy");
    let last = rows.last().unwrap();
    let balance = f(last, "energy") - e0 - f(last, "friction_work") - f(last, "damping_work");
    assert!(balance.abs() < 1e-8, "balance {balance}");
    assert!(f(last, "damping_work") < 0.0);
}
