//! `appell regions` end to end: the shipped rigs give a valid SVG, PNG and JSON; bad rig files
//! exit with code 2 and name the key.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn appell(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_appell"))
        .args(args)
        .output()
        .expect("run appell")
}

fn config(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("configs")
        .join(name)
        .display()
        .to_string()
}

/// A file name in a directory of its own, removed with it when dropped.
struct Scratch {
    _dir: tempfile::TempDir,
    path: PathBuf,
}

impl std::ops::Deref for Scratch {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.path
    }
}

impl AsRef<Path> for Scratch {
    fn as_ref(&self) -> &Path {
        &self.path
    }
}

fn scratch(name: &str) -> Scratch {
    let dir = tempfile::Builder::new()
        .prefix("appell-cli-regions-")
        .tempdir()
        .unwrap();
    let path = dir.path().join(name);
    Scratch { _dir: dir, path }
}

fn json_of(out: &Output) -> serde_json::Value {
    assert!(
        out.status.success(),
        "stderr: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("stdout is JSON")
}

fn png_size(bytes: &[u8]) -> (u32, u32) {
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "PNG signature");
    assert_eq!(&bytes[12..16], b"IHDR");
    let be = |i: usize| u32::from_be_bytes(bytes[i..i + 4].try_into().unwrap());
    (be(16), be(20))
}

fn check_svg(path: &Path) {
    let svg = std::fs::read_to_string(path).unwrap();
    assert!(
        svg.trim_start().starts_with("<svg"),
        "{}",
        &svg[..60.min(svg.len())]
    );
    assert!(svg.trim_end().ends_with("</svg>"));
    assert!(svg.contains("<text"), "axis labels are drawn");
    assert!(svg.contains("theta [deg]"));
    assert_eq!(svg.matches("<svg").count(), 1);
}

#[test]
fn paper_rig_json_svg_and_png() {
    let svg = scratch("paper.svg");
    let out = appell(&[
        "regions",
        &config("rig_paper.toml"),
        "--json",
        "--plot",
        svg.to_str().unwrap(),
        "--trajectories",
        "4",
    ]);
    let v = json_of(&out);
    assert!((v["mu_critical"].as_f64().unwrap() - 2.0 * 2f64.sqrt()).abs() < 1e-9);
    assert!((v["theta_critical_deg"].as_f64().unwrap() - 54.7356).abs() < 1e-3);
    assert_eq!(v["paradox_band_deg"].as_array().unwrap().len(), 0);
    let r_max = v["max_mass_ratio_for_paradox"].as_f64().unwrap();
    assert!((r_max - ((1.0f64 + 0.35 * 0.35).sqrt() - 1.0) / 2.0).abs() < 1e-12);
    let curves = v["stick_boundary"].as_array().unwrap();
    assert!(!curves.is_empty());
    assert!(curves[0]["points"][0].as_array().unwrap().len() == 2);
    assert_eq!(v["trajectories"].as_array().unwrap().len(), 4);
    check_svg(&svg);
    // No band: nothing depends on the slide direction, one panel says so (issue 13: the two
    // panels were identical); the key numbers are on the figure.
    let text = crate::helpers::svg_text(&std::fs::read_to_string(&svg).unwrap());
    assert!(text.contains("one panel serves s = +1 and s = -1"));
    assert!(!text.contains("slide direction s = -1"));
    assert!(text.contains("mu* = 2 sqrt(r (1 + r)) = 2.828"));

    let png = scratch("paper.png");
    let out = appell(&[
        "regions",
        &config("rig_paper.toml"),
        "--plot",
        png.to_str().unwrap(),
        "--trajectories",
        "2",
    ]);
    assert!(out.status.success());
    assert!(String::from_utf8_lossy(&out.stdout).contains("mu* = 2.8284"));
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(png_size(&bytes), (1400, 650));
    assert!(bytes.len() > 20_000);
}

#[test]
fn paradox_rig_json_svg_and_png() {
    let svg = scratch("paradox.svg");
    let png = scratch("paradox.png");
    for plot in [&svg, &png] {
        let out = appell(&[
            "regions",
            &config("rig_paradox.toml"),
            "--json",
            "--plot",
            plot.to_str().unwrap(),
        ]);
        let v = json_of(&out);
        assert!((v["mu_critical"].as_f64().unwrap() - 0.458).abs() < 1e-3);
        let band = v["paradox_band_deg"].as_array().unwrap();
        assert_eq!(band.len(), 2);
        let (lo, hi) = (band[0][0].as_f64().unwrap(), band[0][1].as_f64().unwrap());
        assert!(lo < 77.7 && 77.7 < hi, "{lo}..{hi}");
        assert!(!v["q_zero"].as_array().unwrap().is_empty());
        assert_eq!(v["band_edges_deg"].as_array().unwrap().len(), 8);
    }
    check_svg(&svg);
    // A band: one panel per direction, which on this level rig are mirror images, as stated.
    let text = crate::helpers::svg_text(&std::fs::read_to_string(&svg).unwrap());
    assert!(text.contains("slide direction s = +1") && text.contains("slide direction s = -1"));
    assert!(text.contains("level rig: the s = -1 panel is the s = +1 panel mirrored"));
    assert!(text.contains("64.8..84.2"));
    assert_eq!(png_size(&std::fs::read(&png).unwrap()), (1400, 1100));
}

fn bad_rig(name: &str, body: &str) -> Output {
    let path = scratch(name);
    std::fs::write(&path, body).unwrap();
    appell(&["regions", path.to_str().unwrap(), "--trajectories", "0"])
}

#[test]
fn negative_mass_exits_2_naming_the_key() {
    let out = bad_rig(
        "negative.toml",
        "[rig]\nslider_mass = -0.1\nbob_mass = 0.1\nrod_length = 0.3\ngravity = 9.81\nmu_kinetic = 0.3\n",
    );
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("slider_mass"));
}

#[test]
fn unknown_key_exits_2_naming_the_key() {
    let out = bad_rig(
        "unknown.toml",
        "[rig]\nslider_mass = 0.1\nbob_mass = 0.1\nrod_length = 0.3\ngravity = 9.81\nmu_kinetic = 0.3\nmu_kinetc = 0.3\n",
    );
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("mu_kinetc"));
}

#[test]
fn unsupported_plot_format_exits_2_and_writes_nothing() {
    let path = scratch("figure.jpg");
    let out = appell(&[
        "regions",
        &config("rig_paper.toml"),
        "--plot",
        path.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(!path.exists());
}

/// A rig file written to a scratch directory.
fn rig_file(name: &str, body: &str) -> Scratch {
    let path = scratch(name);
    std::fs::write(
        &path,
        format!(
            "[rig]\nslider_mass = 0.01\nbob_mass = 0.20\nrod_length = 0.30\ngravity = 9.81\n{body}"
        ),
    )
    .unwrap();
    path
}

fn bands(v: &serde_json::Value, field: &str) -> Vec<[f64; 2]> {
    serde_json::from_value(v[field].clone()).unwrap()
}

/// Issue 60, item 4: each direction's band is the Coulomb rig's at that direction's
/// coefficient, drawn in its own panel, and the numbers print at seven digits at most.
#[test]
fn direction_rig_draws_each_directions_coulomb_band() {
    let svg = scratch("direction.svg");
    let v = json_of(&appell(&[
        "regions",
        &config("rig_direction.toml"),
        "--json",
        "--plot",
        svg.to_str().unwrap(),
        "--trajectories",
        "0",
    ]));
    let law = v["law_bands"].as_array().unwrap();
    assert_eq!(law.len(), 2);
    for (b, (dir, mu)) in law.iter().zip([("+x", 0.65), ("-x", 0.5)]) {
        assert_eq!(b["direction"], dir);
        let coulomb = rig_file("c.toml", &format!("mu_kinetic = {mu}\n"));
        let c = json_of(&appell(&[
            "regions",
            coulomb.to_str().unwrap(),
            "--json",
            "--trajectories",
            "0",
        ]));
        let (a, b) = (bands(b, "paradox_band_deg"), bands(&c, "paradox_band_deg"));
        assert_eq!(a.len(), 2, "{dir}");
        for (x, y) in a.iter().zip(&b) {
            assert!(
                (x[0] - y[0]).abs() < 1e-9 && (x[1] - y[1]).abs() < 1e-9,
                "{dir}: {a:?} {b:?}"
            );
        }
    }
    check_svg(&svg);
    let text = crate::helpers::svg_text(&std::fs::read_to_string(&svg).unwrap());
    assert!(
        text.contains("sliding toward +x: mu_k+ = 0.65: paradox band 62.1..84.9"),
        "{text}"
    );
    assert!(
        text.contains("sliding toward -x: mu_k- = 0.5: paradox band 71.6..81.9"),
        "{text}"
    );
    // The means of 0.47 and 0.43 are 0.45, not the 0.44999999999999996 of an f64.
    let split = rig_file(
        "d.toml",
        "friction_law = \"direction\"\nmu_kinetic_positive = 0.47\nmu_kinetic_negative = 0.43\n",
    );
    let out = appell(&["regions", split.to_str().unwrap(), "--trajectories", "0"]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("(means 0.45 and 0.45)"), "{text}");
    assert!(!text.contains("999999"), "{text}");
}

/// Issue 60, item 4: the load law's bands at the smallest, static and largest load a swing
/// meets; the shipped rig opens one at the light load only.
#[test]
fn load_rig_draws_the_band_of_each_load() {
    let png = scratch("load.png");
    let v = json_of(&appell(&[
        "regions",
        &config("rig_load.toml"),
        "--json",
        "--plot",
        png.to_str().unwrap(),
        "--trajectories",
        "2",
    ]));
    let law = v["law_bands"].as_array().unwrap();
    let labels: Vec<&str> = law.iter().map(|b| b["label"].as_str().unwrap()).collect();
    assert_eq!(labels, ["smallest load", "static load", "largest load"]);
    let n0 = 0.21 * 9.81;
    for b in law {
        let (n, mu) = (
            b["normal_load"].as_f64().unwrap(),
            b["mu"].as_f64().unwrap(),
        );
        assert!((mu - 0.42 * (n / n0).powf(-0.2)).abs() < 1e-12, "{b}");
    }
    assert!((law[0]["normal_load"].as_f64().unwrap() - 0.01 * 9.81).abs() < 1e-12);
    assert!(!bands(&law[0], "paradox_band_deg").is_empty());
    assert!(bands(&law[1], "paradox_band_deg").is_empty());
    // Two panels: a band opens at some load a swing meets.
    assert_eq!(png_size(&std::fs::read(&png).unwrap()), (1400, 1100));
}
