//! `appell fit` as a user runs it: the shared example recordings (mu = 0.12, docs/formats.md) in
//! every encoding, a directory of recordings, a figure, and bad input.

use std::process::Command;

fn appell(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_appell"))
        .args(args)
        .output()
        .expect("runs")
}

fn path(rel: &str) -> String {
    format!("{}/{rel}", env!("CARGO_MANIFEST_DIR"))
}

/// The example recordings were made with mu = 0.12: every encoding fits to an interval that
/// contains it, with residuals at the documented 0.2 mm noise.
#[test]
fn example_recordings_fit_to_their_true_mu() {
    for file in [
        "tests/data/markers_json_zstd.mcap",
        "tests/data/markers_ros2_pointstamped.mcap",
        "tests/data/markers_reference.csv",
    ] {
        let out = appell(&[
            "fit",
            &path(file),
            "--rig",
            &path("configs/rig_example.toml"),
            "--json",
        ]);
        assert!(
            out.status.success(),
            "{file}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        let mu = &v["mu_kinetic"];
        let (lo, hi) = (
            mu["ci95"][0].as_f64().unwrap(),
            mu["ci95"][1].as_f64().unwrap(),
        );
        assert!(lo < 0.12 && 0.12 < hi, "{file}: {mu}");
        assert!(mu["stderr"].as_f64().unwrap() > 0.0);
        assert_eq!(v["identifiable"], true);
        let rms = v["rms_residual_m"].as_f64().unwrap();
        assert!((rms - 2e-4).abs() < 2e-5, "{file}: rms {rms}");
        for key in ["x", "theta", "x_dot", "theta_dot"] {
            assert!(v["initial"][key].is_f64(), "{file}: initial.{key}");
        }
        // Released from rest 0.9 rad from the downward vertical: theta = pi/2 - 0.9.
        assert!(
            (v["initial"]["theta"].as_f64().unwrap() - (std::f64::consts::FRAC_PI_2 - 0.9)).abs()
                < 1e-3
        );
    }
}

#[test]
fn directory_gives_one_json_line_per_recording_and_a_figure() {
    // Removed with everything in it at the end of the test.
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().to_path_buf();
    for f in ["markers_json_zstd.mcap", "markers_reference.csv"] {
        std::fs::copy(path(&format!("tests/data/{f}")), dir.join(f)).unwrap();
    }
    let out = appell(&[
        "fit",
        dir.to_str().unwrap(),
        "--rig",
        &path("configs/rig_example.toml"),
        "--json",
        "--no-profile",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let lines: Vec<serde_json::Value> = String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines.len(), 2);
    for v in &lines {
        assert!(
            (v["mu_kinetic"]["value"].as_f64().unwrap() - 0.12).abs() < 1e-4,
            "{v}"
        );
        assert!(v["recording"].as_str().unwrap().contains("markers_"));
        // Where the result came from: the recording, the rig file and the tool's version.
        assert_eq!(v["inputs"][0], v["recording"], "{v}");
        assert!(v["rig_file"]
            .as_str()
            .unwrap()
            .ends_with("rig_example.toml"));
        assert!(v["version"].as_str().unwrap().starts_with("appell "));
    }
    // Without --json each recording's line is its answer, with the verdict.
    let out = appell(&[
        "fit",
        dir.to_str().unwrap(),
        "--rig",
        &path("configs/rig_example.toml"),
        "--no-profile",
    ]);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert_eq!(text.lines().count(), 2, "{text}");
    for l in text.lines() {
        assert!(
            l.contains(": mu_kinetic = 0.1") && l.ends_with("model adequate"),
            "{l}"
        );
    }
    // A figure is one recording's: for a directory --plot is refused, not ignored.
    let out = appell(&[
        "fit",
        dir.to_str().unwrap(),
        "--rig",
        &path("configs/rig_example.toml"),
        "--plot",
        dir.join("d.svg").to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--plot draws one recording's fit"));
    assert!(!dir.join("d.svg").exists());
    let svg = dir.join("fit.svg");
    let out = appell(&[
        "fit",
        &path("tests/data/markers_reference.csv"),
        "--rig",
        &path("configs/rig_example.toml"),
        "--no-profile",
        "--plot",
        svg.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(text.starts_with("<svg") && text.contains("fitted - observed"));
    // The key numbers are on the figure: the fitted mu (the report's value) and the model.
    let report = String::from_utf8_lossy(&out.stdout);
    // The variables table's row (the one-line answer above it rounds the value).
    let mu: f64 = report
        .lines()
        .filter_map(|l| l.trim().strip_prefix("mu_kinetic"))
        .find_map(|rest| rest.split_whitespace().next()?.parse().ok())
        .expect("mu_kinetic row in the report");
    assert!(
        text.contains(&format!("mu_kinetic = {mu:.6}")),
        "figure lacks mu_kinetic = {mu:.6}"
    );
    assert!(text.contains("model: "));
}

#[test]
fn bad_rig_or_recording_exits_2_with_the_cause() {
    // Removed with everything in it at the end of the test.
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().to_path_buf();
    let rig = dir.join("rig.toml");
    std::fs::write(&rig, "[rig]\nslider_mass = 0.5\nbob_mass = 0.2\nrod_length = 0.3\ngravity = 9.81\nfriction = 0.1\n").unwrap();
    let out = appell(&[
        "fit",
        &path("tests/data/markers_reference.csv"),
        "--rig",
        rig.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("friction"));
    let empty = dir.join("empty.csv");
    std::fs::write(&empty, "").unwrap();
    let out = appell(&[
        "fit",
        empty.to_str().unwrap(),
        "--rig",
        &path("configs/rig_example.toml"),
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("empty.csv"));
}

/// A directory's HDF5 recordings (DeepLabCut, SLEAP) are read like its CSVs, not passed over:
/// with only a SLEAP analysis file in it, the directory is not "without recordings", and the
/// file is named in what the fit reports.
#[test]
fn directory_reads_hdf5_recordings_too() {
    let dir = tempfile::tempdir().unwrap();
    let name = "sleap_three-mice_Aeon.analysis.h5";
    std::fs::copy(path(&format!("tests/data/{name}")), dir.path().join(name)).unwrap();
    let out = appell(&[
        "fit",
        dir.path().to_str().unwrap(),
        "--rig",
        &path("configs/rig_example.toml"),
        "--json",
        "--no-profile",
    ]);
    let all = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(!all.contains("no recordings"), "{all}");
    assert!(all.contains(name), "{all}");
}

/// The report opens with its answer in one line: mu with the digits its uncertainty carries and
/// the verdict; the JSON's `answer` is the same line. A well-specified recording reads "model
/// adequate", one with four effects at once "limited by the model" naming the implausible
/// nuisances, and neither line may claim what the other does.
#[test]
fn the_report_opens_with_a_one_line_answer() {
    let cases = [
        (
            "data/example_recording.mcap",
            "configs/rig_example.toml",
            true,
        ),
        (
            "tests/data/misspec/four_paper.csv",
            "tests/data/misspec/paper_measured.toml",
            false,
        ),
    ];
    for (file, rig, adequate) in cases {
        let text = appell(&["fit", &path(file), "--rig", &path(rig)]);
        assert!(text.status.success(), "{file}");
        let text = String::from_utf8(text.stdout).unwrap();
        let first = text.lines().next().unwrap();
        let json = appell(&["fit", &path(file), "--rig", &path(rig), "--json"]);
        let v: serde_json::Value = serde_json::from_slice(&json.stdout).unwrap();
        assert_eq!(v["answer"], first, "{file}");
        assert!(first.starts_with("mu_kinetic = "), "{file}: {first}");
        // The value printed is the fitted one, rounded where its standard error puts it.
        let printed: f64 = first["mu_kinetic = ".len()..]
            .split(' ')
            .next()
            .unwrap()
            .parse()
            .unwrap();
        let mu = v["mu_kinetic"]["value"].as_f64().unwrap();
        let se = v["mu_kinetic"]["stderr"].as_f64().unwrap();
        assert!((printed - mu).abs() <= 0.1 * se, "{file}: {first} vs {mu}");
        assert_eq!(
            first.ends_with("model adequate"),
            adequate,
            "{file}: {first}"
        );
        assert_eq!(first.contains("limited by the model"), !adequate, "{file}");
        assert_eq!(
            v["limited_by_model"].is_null(),
            adequate,
            "{file}: the line and the verdict disagree"
        );
        if !adequate {
            assert!(first.contains("needs rail_tilt"), "{file}: {first}");
        }
        // theta is said from hanging (docs/physics.md: theta = pi/2 hangs), at the value the
        // JSON gives and on the side the bob is.
        let theta = v["initial"]["theta"].as_f64().unwrap();
        let line = text
            .lines()
            .find(|l| l.trim_start().starts_with("theta "))
            .unwrap();
        let said = line.rsplit(" (").next().unwrap();
        let (from_hanging, rest) = said
            .split_once(" rad from hanging, toward ")
            .unwrap_or_else(|| panic!("{file}: {line}"));
        let from_hanging: f64 = from_hanging.parse().unwrap();
        assert!(
            (from_hanging - (theta - std::f64::consts::FRAC_PI_2).abs()).abs() < 1e-3,
            "{file}: {line}"
        );
        let side = if theta < std::f64::consts::FRAC_PI_2 {
            "+x"
        } else {
            "-x"
        };
        assert!(
            rest.starts_with(&format!("{side}; theta = pi/2 hangs)")),
            "{file}: {line}"
        );
        // The report ends by saying where its words are explained, a file the repository has.
        let last = text.lines().rev().find(|l| !l.trim().is_empty()).unwrap();
        assert!(
            last.starts_with("terms: docs/glossary.md"),
            "{file}: {last}"
        );
        assert!(std::path::Path::new(&path("docs/glossary.md")).is_file());
    }
}

/// `--friction-plot` draws the friction figure of a direction-dependent rail (an SVG with its
/// axes and both directions) next to the report, which names the law; with `--joint`, one
/// colour per release.
#[test]
fn friction_plot_draws_the_slides_and_the_law() {
    let tmp = tempfile::tempdir().unwrap();
    let svg = tmp.path().join("friction.svg");
    let rec = path("tests/data/friction/direction_equal_s1.csv");
    let rig = path("tests/data/friction/rigs/equal.toml");
    let out = appell(&[
        "fit",
        &rec,
        "--rig",
        &rig,
        "--friction-plot",
        svg.to_str().unwrap(),
    ]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("(direction law)") && text.contains("[[Friction law]] direction"));
    let figure = std::fs::read_to_string(&svg).unwrap();
    for want in ["<svg", "sliding speed", "friction coefficient", "toward -x"] {
        assert!(figure.contains(want), "{want}");
    }
    // The joint fit's figure: one colour per release.
    let joint = tmp.path().join("joint.svg");
    let releases = tmp.path().join("releases");
    std::fs::create_dir(&releases).unwrap();
    for r in ["std", "mirror"] {
        let name = format!("campaign_direction_heavy_{r}_s1.csv");
        std::fs::copy(
            path(&format!("tests/data/friction/{name}")),
            releases.join(name),
        )
        .unwrap();
    }
    let out = appell(&[
        "fit",
        releases.to_str().unwrap(),
        "--joint",
        "--rig",
        &path("tests/data/friction/rigs/heavy.toml"),
        "--friction-plot",
        joint.to_str().unwrap(),
    ]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let figure = std::fs::read_to_string(&joint).unwrap();
    assert!(figure.contains("campaign_direction_heavy_mirror_s1.csv"));
}

/// A figure that cannot be written does not cost the result: the whole report is printed
/// (text and JSON), then the error names the path and the command exits 1. It used to exit 1
/// with nothing but the error.
#[test]
fn a_plot_that_cannot_be_written_keeps_the_report() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("no_such_dir").join("fit.svg");
    let bad = bad.to_str().unwrap();
    let rec = path("data/example_recording.mcap");
    let rig = path("configs/rig_example.toml");
    for json in [false, true] {
        let mut args = vec!["fit", &rec, "--rig", &rig, "--no-profile", "--plot", bad];
        if json {
            args.push("--json");
        }
        let out = appell(&args);
        let (stdout, stderr) = (
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr),
        );
        assert_eq!(out.status.code(), Some(1), "{stderr}");
        assert!(
            stderr.contains("no_such_dir") && stderr.contains("report above"),
            "{stderr}"
        );
        if json {
            let v: serde_json::Value = serde_json::from_str(stdout.trim()).unwrap();
            assert!(v["mu_kinetic"]["value"].is_f64(), "{v}");
        } else {
            assert!(stdout.starts_with("mu_kinetic = "), "{stdout}");
            assert!(stdout.contains("[[Fit statistics]]"), "{stdout}");
            assert!(!stdout.contains("figure written"), "{stdout}");
        }
    }
}
