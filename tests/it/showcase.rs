//! The showcase recordings (`tests/data/showcase/`): one release of a point-pendulum rig made by
//! an independent generator (`scripts/showcase_generator.py`) and written as DeepLabCut, SLEAP,
//! OptiTrack Motive and Tracker write their files, with camera noise, dropped frames and planted
//! mis-tracks. Each is fitted as the README shows it, with the flags its tool needs, and the
//! rig file a lab would type (rod 1 mm long, masses 2 % off). The oracle is the generator's
//! truth file: mu inside the 95 % interval, the model adequate, and no position left out
//! beyond the planted mis-tracks (give or take a few noise draws past the filter's threshold).

use std::path::PathBuf;
use std::process::Command;

fn dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/showcase")
}

fn truth() -> serde_json::Value {
    let text = std::fs::read_to_string(dir().join("truth.json")).expect("truth.json");
    serde_json::from_str(&text).expect("truth.json is JSON")
}

/// `appell fit FILES --rig showcase_rig.toml ARGS --json`, parsed.
fn fit(files: &[&str], args: &[&str]) -> serde_json::Value {
    let out = Command::new(env!("CARGO_BIN_EXE_appell"))
        .arg("fit")
        .args(files.iter().map(|f| dir().join(f)))
        .arg("--rig")
        .arg(dir().join("showcase_rig.toml"))
        .args(args)
        .arg("--json")
        .output()
        .expect("runs");
    assert!(
        out.status.success(),
        "{files:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("one JSON object")
}

/// The planted mis-tracks of one tool (high-confidence positions off the marker), per marker.
fn planted(tool: &str) -> [usize; 2] {
    let t = truth();
    let m = &t["files"][tool]["planted"]["mistracked"];
    ["slider", "bob"].map(|k| m[k].as_array().expect("a list of frames").len())
}

fn check(tool: &str, files: &[&str], args: &[&str]) {
    let t = truth();
    let mu_true = t["rig"]["mu_kinetic"].as_f64().unwrap();
    let v = fit(files, args);
    let mu = &v["mu_kinetic"];
    let (lo, hi) = (
        mu["ci95"][0].as_f64().unwrap(),
        mu["ci95"][1].as_f64().unwrap(),
    );
    assert!(
        lo < mu_true && mu_true < hi,
        "{tool}: mu {mu} misses {mu_true}"
    );
    // An interval that says something: at most 1 % of mu wide.
    assert!(hi - lo < 0.01 * mu_true, "{tool}: {mu}");
    assert!(v["failed"].is_null(), "{tool}: {}", v["failed"]);
    assert!(
        v["limited_by_model"].is_null(),
        "{tool}: {}",
        v["limited_by_model"]
    );
    let out = [
        v["outliers"]["slider"].as_u64(),
        v["outliers"]["bob"].as_u64(),
    ]
    .map(|c| c.expect("outlier count") as usize);
    let want = planted(tool);
    for m in 0..2 {
        assert!(
            out[m] >= want[m] && out[m] <= want[m] + 2,
            "{tool}: {out:?} positions left out, {want:?} planted"
        );
    }
    // The frames the fit used: every frame with both markers seen.
    assert!(
        v["n_frames"].as_u64().unwrap() > 200,
        "{tool}: {}",
        v["n_frames"]
    );
}

/// DeepLabCut: pixels, y down, a rolled camera, 100 fps, the scale from the measured rod
/// (1 mm long); low-likelihood garbage is read as missing, the two bob jumps and the slider's
/// slip are left out.
#[test]
fn showcase_deeplabcut_fits_to_the_truth() {
    check(
        "dlc",
        &["showcase_dlc.csv"],
        &["--fps", "100", "--rod-length", "0.251", "--rail-frame"],
    );
}

/// SLEAP: frames without a prediction left out of the file, nodes not found as empty cells,
/// 200 fps, the scale from a calibration (0.16 % off).
#[test]
fn showcase_sleap_fits_to_the_truth() {
    check(
        "sleap",
        &["showcase_sleap.csv"],
        &["--fps", "200", "--scale", "0.00104", "--rail-frame"],
    );
}

/// OptiTrack Motive: millimetres, Y up, the rig in the XY plane (the default plane), unlabeled
/// markers chosen by name, the bob's gap joined across Motive's renaming.
#[test]
fn showcase_motive_fits_to_the_truth() {
    check(
        "motive",
        &["showcase_motive.csv"],
        &[
            "--slider",
            "Unlabeled 1001",
            "--bob",
            "Unlabeled 1002",
            "--rail-frame",
        ],
    );
}

/// Tracker: a pair of exports named mass_A and mass_B (read in file order), axes set by hand
/// 0.3 deg off the rail.
#[test]
fn showcase_tracker_pair_fits_to_the_truth() {
    check(
        "tracker",
        &["showcase_tracker_slider.txt", "showcase_tracker_bob.txt"],
        &["--rail-frame"],
    );
}
