//! What a user sees on the command line (issue 13): a scene accepted as a rig file, files that
//! are not recordings skipped in a directory, each error said once, help and usage lines that
//! match what the commands do.

use std::path::Path;
use std::process::{Command, Output};

fn appell(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_appell"))
        .args(args)
        .output()
        .expect("run appell")
}

fn path(rel: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join(rel)
        .display()
        .to_string()
}

/// A scratch directory, removed with everything in it when dropped (the tests left 60 of them
/// in /tmp before).
struct Scratch(tempfile::TempDir);

impl std::ops::Deref for Scratch {
    type Target = Path;
    fn deref(&self) -> &Path {
        self.0.path()
    }
}

fn scratch(name: &str) -> Scratch {
    Scratch(
        tempfile::Builder::new()
            .prefix(&format!("appell-cli-msg-{name}-"))
            .tempdir()
            .unwrap(),
    )
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// Every `caused by:` line says something its predecessor did not already say.
fn assert_no_repeated_cause(err: &str) {
    let lines: Vec<&str> = err.lines().collect();
    for pair in lines.windows(2) {
        if let Some(cause) = pair[1].trim_start().strip_prefix("caused by: ") {
            assert!(!pair[0].contains(cause), "repeated cause:\n{err}");
        }
    }
}

#[test]
fn a_scene_file_is_accepted_as_the_rig() {
    let out = appell(&[
        "regions",
        &path("configs/paper_rest_horizontal.toml"),
        "--trajectories",
        "0",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(String::from_utf8_lossy(&out.stdout).contains("mu* = 2.8284"));
    let out = appell(&[
        "fit",
        &path("tests/data/markers_reference.csv"),
        "--rig",
        &path("configs/markers_example.toml"),
        "--json",
        "--no-profile",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    // Sections that belong to no scene are still refused, by name.
    let dir = scratch("rig");
    let bad = dir.join("typo.toml");
    std::fs::write(
        &bad,
        "[rig]\nslider_mass = 0.1\nbob_mass = 0.1\nrod_length = 0.3\ngravity = 9.81\nmu_kinetic = 0.3\n[rgi]\nx = 1\n",
    )
    .unwrap();
    let out = appell(&["regions", bad.to_str().unwrap(), "--trajectories", "0"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("rgi"), "{}", stderr(&out));
}

/// Fit a directory holding the shipped canonical CSV (as `good.csv`) and `extra` files (name,
/// content), without profile intervals.
fn fit_directory(name: &str, extra: &[(&str, &str)], json: bool) -> (Scratch, Output) {
    let dir = scratch(name);
    std::fs::copy(
        path("tests/data/markers_reference.csv"),
        dir.join("good.csv"),
    )
    .unwrap();
    for (file, content) in extra {
        std::fs::write(dir.join(file), content).unwrap();
    }
    let rig = path("configs/rig_example.toml");
    let mut args = vec![
        "fit",
        dir.to_str().unwrap(),
        "--rig",
        rig.as_str(),
        "--no-profile",
    ];
    if json {
        args.push("--json");
    }
    let out = appell(&args);
    (dir, out)
}

#[test]
fn directory_fit_skips_files_that_are_not_recordings() {
    let notes = ("notes.txt", "Tuesday: rail cleaned, camera refocused\n");
    let (_, out) = fit_directory("notes", &[notes], true);
    assert!(out.status.success(), "{}", stderr(&out));
    let err = stderr(&out);
    assert!(
        err.contains("note: skipped, not a recording") && err.contains("notes.txt"),
        "{err}"
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(stdout.lines().count(), 1, "{stdout}");
    assert!(stdout.contains("good.csv"));
}

#[test]
fn directory_fit_failures_are_each_said_once() {
    // Recognised as the canonical CSV, but broken in its second row.
    let broken = (
        "broken.csv",
        "t,slider_x,slider_y,bob_x,bob_y\n0,0,0,0.3,0\nzero,0,0,0.3,0\n",
    );
    let (dir, out) = fit_directory("fail", &[broken], false);
    assert_eq!(out.status.code(), Some(1));
    let err = stderr(&out);
    assert_eq!(err.matches("could not be fitted").count(), 1, "{err}");
    let broken = dir.join("broken.csv").display().to_string();
    let lines: Vec<&str> = err.lines().filter(|l| l.contains(&broken)).collect();
    assert_eq!(lines.len(), 1, "{err}");
    assert_eq!(lines[0].matches(&broken).count(), 1, "{err}");
    assert_no_repeated_cause(&err);
}

#[test]
fn error_causes_are_not_repeated() {
    let missing = path("configs/no_such_rig.toml");
    for args in [
        vec!["regions", missing.as_str()],
        vec![
            "fit",
            "/nonexistent/recording.csv",
            "--rig",
            missing.as_str(),
        ],
    ] {
        let out = appell(&args);
        assert_eq!(out.status.code(), Some(2));
        let err = stderr(&out);
        assert!(err.contains("no_such_rig.toml"), "{err}");
        assert_eq!(err.matches("no_such_rig.toml").count(), 1, "{err}");
        assert_no_repeated_cause(&err);
    }
}

#[test]
fn simulate_out_help_says_the_default_frame_rate() {
    let out = appell(&["simulate", "--help"]);
    let help = String::from_utf8_lossy(&out.stdout);
    assert!(!help.contains("needs output.frame_rate"), "{help}");
    assert!(
        help.contains("else 1000 Hz") || help.contains("else\n"),
        "{help}"
    );
    // And it does: a scene without [output] writes a 1000 Hz trajectory.
    let dir = scratch("simulate");
    let csv = dir.join("traj.csv");
    let out = appell(&[
        "simulate",
        &path("configs/paper_rest_horizontal.toml"),
        "--out",
        csv.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = std::fs::read_to_string(&csv).unwrap();
    assert!(text.lines().count() > 1000);
}

#[test]
fn convert_usage_names_inputs_then_the_output() {
    let out = appell(&["convert", "--help"]);
    let help = String::from_utf8_lossy(&out.stdout);
    let usage = help
        .lines()
        .find(|l| l.starts_with("Usage:"))
        .expect("a usage line");
    assert!(usage.contains("<INPUT>... <OUTPUT.csv>"), "{usage}");
    assert!(!usage.contains("<INPUT... OUTPUT.csv>"), "{usage}");
    // Two inputs and the output, as the README's Tracker example.
    let dir = scratch("convert");
    let csv = dir.join("out.csv");
    let out = appell(&[
        "convert",
        &path("tests/data/tracker_slider.txt"),
        &path("tests/data/tracker_bob.txt"),
        csv.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(csv.exists());
    let out = appell(&["convert", csv.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2), "one path is not enough");
}

/// A rod typed in centimetres (30 for the example's 0.30 m) is refused with exit code 2, the
/// range at the precision the markers give it (no 0.20080000000000006), and the slip named.
#[test]
fn a_rod_length_in_centimetres_is_named_as_such() {
    let d = scratch("rod-cm");
    let text = std::fs::read_to_string(path("configs/rig_example.toml")).unwrap();
    let rig = d.join("rig.toml");
    std::fs::write(&rig, text.replace("rod_length = 0.30 ", "rod_length = 30 ")).unwrap();
    let out = appell(&[
        "fit",
        &path("data/example_recording.mcap"),
        "--rig",
        &rig.display().to_string(),
    ]);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("a length in centimetres? the rig file takes metres: 0.3000 m"),
        "{err}"
    );
    // Every number of the range at four significant digits.
    let range = err
        .split("from ")
        .nth(1)
        .unwrap()
        .split(" m:")
        .next()
        .unwrap();
    for v in range.split(" to ") {
        let digits = v.trim_start_matches("0.").len();
        assert!(digits <= 4 && v.parse::<f64>().is_ok(), "{range}: {err}");
    }
}

/// A rig file's mistakes of a first hour each get one error naming the fix, exit code 2: the
/// `[rig]` line left out (the parser would call the first key an unknown section), masses
/// typed in grams (the dynamics see only their ratio, so grams for both would fit the same mu
/// with every force a thousand times off), and a rig file that does not exist yet.
#[test]
fn a_first_hour_rig_file_gets_errors_naming_the_fix() {
    let d = scratch("rig-first-hour");
    let text = std::fs::read_to_string(path("configs/rig_example.toml")).unwrap();
    let fit = |rig: &std::path::Path| {
        appell(&[
            "fit",
            &path("data/example_recording.mcap"),
            "--rig",
            &rig.display().to_string(),
        ])
    };
    let headless = d.join("headless.toml");
    std::fs::write(&headless, text.replace("[rig]\n", "")).unwrap();
    let out = fit(&headless);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("comes before any section") && err.contains("[rig] line"),
        "{err}"
    );
    let grams = d.join("grams.toml");
    let heavy = text.replace("slider_mass = 0.5", "slider_mass = 500");
    assert_ne!(
        heavy, text,
        "the example's slider mass moved: update this test"
    );
    std::fs::write(&grams, heavy).unwrap();
    let out = fit(&grams);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("rig.slider_mass = 500.0 kg")
            && err.contains("a mass in grams? the rig file takes kilograms: 0.5000 kg"),
        "{err}"
    );
    let out = fit(&d.join("missing.toml"));
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("--rig-template"), "{err}");
}

/// Issue 59, class I: gravity the rig file leaves out is reported as where it came from, the
/// default or `--latitude`, never as stated by the file (text and JSON).
#[test]
fn gravity_left_out_is_not_reported_as_stated() {
    let dir = scratch("gravity");
    let measured = path("tests/data/rigid/rigid_paper_measured.toml");
    let text = std::fs::read_to_string(measured).unwrap();
    let left_out: String = text
        .lines()
        .filter(|l| !l.trim_start().starts_with("gravity"))
        .map(|l| format!("{l}\n"))
        .collect();
    let rig = dir.join("no_gravity.toml").display().to_string();
    std::fs::write(&rig, left_out).unwrap();
    let rec = path("tests/data/rigid/rigid_paper.csv");
    for (extra, source) in [
        (&[][..], "default"),
        (&["--latitude", "45"][..], "--latitude"),
    ] {
        let mut args = vec!["fit", &rec, "--rig", &rig];
        args.extend_from_slice(extra);
        let out = appell(&args);
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        // The rig-as-measured line: "gravity  value +- sd (source)".
        let line = stdout
            .lines()
            .find(|l| l.trim_start().starts_with("gravity") && l.trim_end().ends_with(')'))
            .unwrap_or_else(|| panic!("no gravity line in {stdout}"));
        assert!(line.ends_with(&format!("({source})")), "{line}");
        args.push("--json");
        let out = appell(&args);
        assert!(out.status.success());
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        let mut keys = Vec::new();
        find_keys(&v, &mut keys);
        let g = keys
            .iter()
            .find(|k| k["key"] == "gravity")
            .unwrap_or_else(|| panic!("no gravity key in {v}"));
        assert_eq!(g["source"], source, "{g}");
        assert_eq!(g["stated"], false, "{g}");
    }
}

/// Every object with a `key` and a `stated` field in `v`, wherever the JSON nests them.
fn find_keys(v: &serde_json::Value, out: &mut Vec<serde_json::Value>) {
    match v {
        serde_json::Value::Object(m) => {
            if m.contains_key("key") && m.contains_key("stated") {
                out.push(v.clone());
            }
            m.values().for_each(|x| find_keys(x, out));
        }
        serde_json::Value::Array(a) => a.iter().for_each(|x| find_keys(x, out)),
        _ => {}
    }
}
