//! The rig file as a measurement (issue 34): recordings of point-pendulum rigs made by an
//! independent Newton-Euler generator (`scripts/generators/measured_rig_generator.py`,
//! `tests/data/measured/`), fitted with rig files whose rod length or masses are off by what a
//! ruler and a kitchen scale allow, and recordings with effects no nuisance describes (a
//! pin's Coulomb torque at the pivot, a rolling shutter, a sagging rail, load-dependent
//! friction). The rules checked: within 3 standard errors of the truth or flagged; the marker
//! distance corrects the rod length; the rig's part of mu's error is what the mass ratio's
//! error implies through mu's dependence on it; a value stated exact stays fixed; the friction
//! candidates are tried on a release from rest.

use super::fit_real::{example_rig, record, Y0};
use appell::data::{read_recording, ReadOptions};
use appell::fit::priors::RigMeasurement;
use appell::fit::{fit, FitReport, FitSettings, Nuisance, Observations, Param};
use appell::model::{Camera, Rig};
use appell::scene::RigFile;
use rayon::prelude::*;
use std::path::{Path, PathBuf};

pub(crate) fn repo(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(rel)
}

/// `recording` fitted with the rig file `rig` read as a measurement (what `appell fit` does).
pub(crate) fn fit_measured(recording: &Path, rig: &Path) -> FitReport {
    let rec = read_recording(&[recording.to_owned()], &ReadOptions::default()).expect("reads");
    let (r, spec, note) = RigFile::load_on_earth(rig, 0.3, None).expect("rig file");
    let mut measured = RigMeasurement::from_spec(&spec);
    measured.notes.extend(note);
    let settings = FitSettings {
        measured: Some(measured),
        ..FitSettings::default()
    };
    fit(Observations::from(&rec), &r, &settings).expect("fits")
}

/// `recording` fitted with `rig` taken as exact.
fn fit_exact(recording: &Path, rig: &Rig<f64>) -> FitReport {
    let rec = read_recording(&[recording.to_owned()], &ReadOptions::default()).expect("reads");
    fit(Observations::from(&rec), rig, &FitSettings::default()).expect("fits")
}

pub(crate) fn flagged(rep: &FitReport) -> bool {
    !rep.adequacy.limited_by_model.is_empty() || rep.failed.is_some()
}

fn manifest() -> serde_json::Value {
    let text = std::fs::read_to_string(repo("tests/data/measured/manifest.json")).unwrap();
    serde_json::from_str(&text).unwrap()
}

/// Every rig-file case shipped (rod 2 mm long, a mass 3 % off, with and without a stated
/// deviation, and the true rig): mu within 3 standard errors or flagged; the parts of its
/// standard error add up in quadrature; the recording's marker distance puts the rod within
/// a tenth of a millimetre of the truth, whatever the file said; and no nuisance taken: the
/// recordings are point pendulums on a level rail, so what the file gets wrong belongs to its
/// measured values (a viscous drag or camera scale taken for a 3 % mass error is the model
/// absorbing the file's error elsewhere).
#[test]
fn rig_file_errors_are_corrected_or_carried() {
    let m = manifest();
    let cases: Vec<&serde_json::Value> = m["cases"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|c| c["kind"] != "effect")
        .collect();
    assert!(cases.len() >= 20, "{} cases", cases.len());
    let bad: Vec<String> = cases
        .par_iter()
        .with_max_len(1)
        .filter_map(|c| {
            let dir = repo("tests/data/measured");
            let rep = fit_measured(
                &dir.join(c["recording"].as_str().unwrap()),
                &dir.join(c["rig_file"].as_str().unwrap()),
            );
            let truth = c["truth_mu"].as_f64().unwrap();
            let mu = rep.mu_kinetic.expect("identifiable");
            let z = (mu.value - truth) / mu.stderr;
            let parts = rep.mu_parts.expect("parts");
            let sum = (parts.noise.powi(2) + parts.rig.powi(2) + parts.model.powi(2)).sqrt();
            assert!(
                (sum - parts.total).abs() <= 1e-9 * parts.total,
                "{}: {parts:?}",
                c["id"]
            );
            assert!((parts.total - mu.stderr).abs() <= 1e-12 * mu.stderr);
            let rod = rep.rig_values.iter().find(|v| v.param == "rod_length");
            let rod_ok =
                c["flavour"] == "tight" || rod.is_some_and(|r| (r.value - 0.3).abs() < 1e-4);
            let line = format!(
                "{}: mu {:.6} +- {:.2e} (z {z:.2}) parts {parts:?} rod {rod:?} flagged {} nuisances {:?}",
                c["id"],
                mu.value,
                mu.stderr,
                flagged(&rep),
                rep.nuisances
            );
            eprintln!("{line}");
            ((z.abs() >= 3.0 && !flagged(&rep)) || !rod_ok || !rep.nuisances.is_empty())
                .then_some(line)
        })
        .collect();
    assert!(bad.is_empty(), "{bad:#?}");
}

/// Four effects no nuisance describes, on the equal-mass rig, and the two recordings of the
/// full sweep that a 1 % gate on the slides' agreement let through 9.3 and 5.4 standard errors
/// off (a pin's friction on the equal rig, load-dependent friction on the heavy one; their
/// slides disagree at p = 0.017 and 0.016): within 3 standard errors of the truth (the
/// slid-weighted friction ratio for load-dependent friction) or flagged.
#[test]
fn effects_no_nuisance_describes_are_flagged_or_right() {
    let m = manifest();
    let cases: Vec<&serde_json::Value> = m["cases"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|c| c["kind"] == "effect")
        .collect();
    assert_eq!(cases.len(), 6);
    for c in cases {
        let dir = repo("tests/data/measured");
        let rep = fit_measured(
            &dir.join(c["recording"].as_str().unwrap()),
            &dir.join(c["rig_file"].as_str().unwrap()),
        );
        let mu = rep.mu_kinetic.expect("identifiable");
        // Load-dependent friction is no longer an effect no nuisance describes: when the fit
        // finds the load law, its mu_kinetic is the coefficient at the static load, 0.25 by
        // the generator's construction (c = 0.25 ((m1 + m2) g)^0.15), and its exponent 0.85.
        let load_law = c["flavour"] == "load" && rep.nuisances.contains(&Nuisance::Load);
        let truth = if load_law {
            0.25
        } else {
            c["truth_mu"].as_f64().unwrap()
        };
        let z = (mu.value - truth) / mu.stderr;
        assert!(
            z.abs() < 3.0 || flagged(&rep),
            "{}: mu {mu:?} z {z:.2} nuisances {:?}",
            c["id"],
            rep.nuisances
        );
        if load_law {
            let (_, n) = rep
                .params
                .iter()
                .find(|(p, _)| *p == Param::LoadExponent)
                .expect("the load law's exponent");
            let zn = (n.value - 0.85) / n.stderr;
            assert!(zn.abs() < 3.0 || flagged(&rep), "{}: n {n:?}", c["id"]);
        }
    }
}

/// The rig's part of mu's standard error against an oracle outside the fit: in a linear model
/// it is |d mu / d r| times the mass ratio's posterior standard error, with the slope measured
/// by refitting the recording with the rig taken as exact at r (1 +- 1 %). On the heavy rig,
/// whose short slides tell r from mu only partly, the posterior keeps a good part of the
/// scale's 2.2 %, so the rig's part is most of mu's error.
#[test]
fn rig_part_is_what_the_mass_ratio_error_implies() {
    let dir = repo("tests/data/measured");
    let recording = dir.join("heavy_s1.csv");
    let rep = fit_measured(&recording, &dir.join("rigs/heavy_true_nosd.toml"));
    let parts = rep.mu_parts.unwrap();
    let r = rep
        .rig_values
        .iter()
        .find(|v| v.param == Param::MassRatio.name())
        .expect("mass ratio fitted");
    let mu_at = |scale: f64| {
        let rig = Rig::new(0.35 * scale, 0.1, 0.3, 9.81, 0.25, None).unwrap();
        fit_exact(&recording, &rig).mu_kinetic.unwrap().value
    };
    let slope = (mu_at(1.01) - mu_at(0.99)) / (0.02 * 3.5);
    let want = slope.abs() * r.stderr;
    eprintln!(
        "rig part {:.3e}, slope {slope:.4} x se_r {:.3e} = {want:.3e}; r {r:?}",
        parts.rig, r.stderr
    );
    assert!(
        (parts.rig - want).abs() < 0.2 * want,
        "rig part {} against {want}",
        parts.rig
    );
    // The data narrow r here, but only partly.
    assert!(r.stderr < r.sd && r.stderr > 0.2 * r.sd, "{r:?}");
    assert!(parts.rig > parts.noise, "{parts:?}");
}

/// A value stated exact (`_sd = 0`) is held, not fitted; with every value stated to a
/// micrometre or a microgram the interval is the exact rig's, within 1.3 times.
#[test]
fn a_value_stated_exact_is_held() {
    let dir = repo("tests/data/measured");
    let recording = dir.join("equal_s1.csv");
    let tmp = std::env::temp_dir().join(format!("appell-measured-{}", std::process::id()));
    std::fs::create_dir_all(&tmp).unwrap();
    let exact = tmp.join("exact.toml");
    std::fs::write(
        &exact,
        "[rig]\nslider_mass = 0.2\nbob_mass = 0.2\nrod_mass = 0.0\nbob_radius = 0.0\nrod_length = 0.3\ngravity = 9.81\nrod_length_sd = 0\nslider_mass_sd = 0\nbob_mass_sd = 0\ngravity_sd = 0\n",
    )
    .unwrap();
    let held = fit_measured(&recording, &exact);
    assert!(held.rig_values.is_empty());
    assert!(!held.params.iter().any(|(q, _)| *q == Param::RodLength));
    let tight = fit_measured(&recording, &dir.join("rigs/equal_true_tight.toml"));
    let (a, b) = (
        held.mu_kinetic.unwrap().stderr,
        tight.mu_kinetic.unwrap().stderr,
    );
    assert!(b <= 1.3 * a, "tight {b} against exact {a}");
    std::fs::remove_dir_all(&tmp).ok();
}

/// A deviation far below what any measurement resolves (`rod_length_sd = 1e-300`, the masses'
/// at 5e-324, `gravity_sd = 1e-20`) is the exact value: held as `_sd = 0` holds it, with a
/// note, so the fit is the exact rig's to the last digits (issue 59, class A: the prior's
/// weight swamped the solve, which stopped at its start with every standard error 0).
#[test]
fn a_deviation_below_any_measurement_is_held_exact() {
    let dir = repo("tests/data/measured");
    let recording = dir.join("equal_s1.csv");
    let tmp = std::env::temp_dir().join(format!("appell-tiny-sd-{}", std::process::id()));
    std::fs::create_dir_all(&tmp).unwrap();
    let rig = "[rig]\nslider_mass = 0.2\nbob_mass = 0.2\nrod_mass = 0.0\nbob_radius = 0.0\nrod_length = 0.3\ngravity = 9.81\n";
    let (exact, tiny) = (tmp.join("exact.toml"), tmp.join("tiny.toml"));
    let zero = "rod_length_sd = 0\nslider_mass_sd = 0\nbob_mass_sd = 0\ngravity_sd = 0\n";
    std::fs::write(&exact, format!("{rig}{zero}")).unwrap();
    let tiny_sds =
        "rod_length_sd = 1e-300\nslider_mass_sd = 5e-324\nbob_mass_sd = 1e-12\ngravity_sd = 1e-20\n";
    std::fs::write(&tiny, format!("{rig}{tiny_sds}")).unwrap();
    let held = fit_measured(&recording, &exact);
    let rep = fit_measured(&recording, &tiny);
    for q in [Param::RodLength, Param::MassRatio, Param::Gravity] {
        assert!(!rep.params.iter().any(|(p, _)| *p == q), "{q:?} fitted");
    }
    let (a, b) = (held.mu_kinetic.unwrap(), rep.mu_kinetic.unwrap());
    assert!(b.stderr > 0.0, "{b:?}");
    assert!((a.value - b.value).abs() <= 1e-9 * a.value, "{a:?} {b:?}");
    assert!(
        (a.stderr - b.stderr).abs() <= 1e-6 * a.stderr,
        "{a:?} {b:?}"
    );
    for key in [
        "rod_length_sd",
        "slider_mass_sd",
        "bob_mass_sd",
        "gravity_sd",
    ] {
        assert!(
            rep.warnings
                .iter()
                .any(|w| w.contains(key) && w.contains("held exact")),
            "{key}: {:?}",
            rep.warnings
        );
    }
    std::fs::remove_dir_all(&tmp).ok();
}

/// The regression of issue 34: equal masses released from rest on a rail with mu_static 0.28
/// above mu_kinetic 0.22 (0.3 mm noise, 1 kHz). The base model (one coefficient) misfits, so
/// the friction candidates are tried although no onset after a stick shows them; mu_static
/// is chosen and both coefficients are found.
#[test]
fn mu_static_is_tried_on_a_release_from_rest() {
    let rig = Rig::new(0.2, 0.2, 0.3, 9.81, 0.22, Some(0.28)).unwrap();
    let obs = record(&rig, &Camera::default(), Y0, 1000.0, 2.0, 3e-4, 1);
    let rep = fit(obs, &example_rig(0.3), &FitSettings::default()).unwrap();
    let mu = rep.mu_kinetic.unwrap();
    eprintln!("{mu:?} {:?} {:?}", rep.nuisances, rep.mu_static);
    assert!(
        rep.nuisances.contains(&Nuisance::StaticFriction)
            || rep.nuisances.contains(&Nuisance::Stribeck),
        "{:?}",
        rep.nuisances
    );
    assert!((mu.value - 0.22).abs() < 3.0 * mu.stderr, "{mu:?}");
    match rep.mu_static {
        appell::fit::StaticResult::Estimated(e) => {
            assert!((e.value - 0.28).abs() < 3.0 * e.stderr.max(1e-4), "{e:?}")
        }
        other => panic!("mu_static {other:?}"),
    }
}

/// A campaign of three releases of the heavy rig (r = 3.5) fitted jointly with a rig file whose
/// slider mass is 3 % high and no stated deviation: the rig taken as exact put mu 0.2437 +-
/// 1.2e-5 (517 standard errors off); as a measurement, mu is within 3 standard errors of 0.25
/// and the mass ratio's error is most of its interval.
#[test]
fn a_joint_fit_takes_the_rig_file_as_a_measurement() {
    let dir = repo("tests/data/measured");
    let mut args: Vec<String> = vec![
        "fit".into(),
        "--joint".into(),
        "--json".into(),
        "--rig".into(),
        dir.join("rigs/heavy_slider+3pct_nosd.toml")
            .display()
            .to_string(),
    ];
    for s in 1..=3 {
        args.push("--release".into());
        args.push(dir.join(format!("heavy_s{s}.csv")).display().to_string());
    }
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_appell"))
        .args(&args)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let j: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let (mu, se) = (
        j["mu_kinetic"]["value"].as_f64().unwrap(),
        j["mu_kinetic"]["stderr"].as_f64().unwrap(),
    );
    assert!((mu - 0.25).abs() < 3.0 * se, "mu {mu} +- {se}");
    // The mass ratio is shared, fitted once with the file's prior (3.605 +- 3.6 %).
    let names = j["shared_covariance"]["names"].as_array().unwrap();
    assert!(
        names.iter().any(|n| n == "equivalent_mass_ratio"),
        "{names:?}"
    );
    assert!(se > 1e-4, "the mass ratio's error is in the interval: {se}");
}

/// Gravity is a measured value too, fitted when the rig file gives `gravity_sd` or leaves
/// gravity out. On the independent recordings of the equal and light rigs, a rig file typing
/// gravity 0.3 % off (the equator's 9.780 or the poles' 9.832 for the generator's 9.81) with
/// `gravity_sd = 0.01` leaves mu within 3 standard errors of the truth and puts the fitted
/// gravity within 0.05 % of the generator's. On the shipped example (made with g = 9.81 and
/// mu = 0.12; its heavy slider pins the mass ratio), gravity typed 0.04 % off (9.806): fitted,
/// mu is within 3; held as typed, the camera's scale error takes the mismatch (0.04 %) and mu is
/// within 3 too. Leaving gravity out takes 9.81 +- 0.015 with a note.
#[test]
fn gravity_is_fitted_with_the_rig_file_as_its_prior() {
    let tmp = tempfile::tempdir().unwrap();
    let point = "rod_mass = 0.0\nbob_radius = 0.0\nrod_length = 0.3\n";
    let equal = format!("[rig]\nslider_mass = 0.1\nbob_mass = 0.1\n{point}");
    let light = format!("[rig]\nslider_mass = 0.05\nbob_mass = 0.15\n{point}");
    let example = "[rig]\nslider_mass = 0.5\nbob_mass = 0.2\nrod_length = 0.3\n".to_owned();
    let measured = repo("tests/data/measured");
    let shipped = repo("data/example_recording.mcap");
    // (name, recording, rig, gravity keys, true mu, whether gravity is fitted)
    let cases = [
        (
            "equal_low",
            measured.join("equal_s1.csv"),
            &equal,
            "gravity = 9.780\ngravity_sd = 0.01\n",
            0.25,
            true,
        ),
        (
            "equal_high",
            measured.join("equal_s1.csv"),
            &equal,
            "gravity = 9.832\ngravity_sd = 0.01\n",
            0.25,
            true,
        ),
        (
            "light_low",
            measured.join("light_s1.csv"),
            &light,
            "gravity = 9.780\ngravity_sd = 0.01\n",
            0.25,
            true,
        ),
        (
            "equal_omitted",
            measured.join("equal_s1.csv"),
            &equal,
            "",
            0.25,
            true,
        ),
        (
            "example_free",
            shipped.clone(),
            &example,
            "gravity = 9.806\ngravity_sd = 0.01\n",
            0.12,
            true,
        ),
        (
            "example_held",
            shipped,
            &example,
            "gravity = 9.806\n",
            0.12,
            false,
        ),
    ];
    let fitted: Vec<(&str, bool, f64, FitReport)> = cases
        .par_iter()
        .with_max_len(1)
        .map(|(name, rec, rig, g, truth, free)| {
            let path = tmp.path().join(format!("{name}.toml"));
            std::fs::write(&path, format!("{rig}{g}")).unwrap();
            (*name, *free, *truth, fit_measured(rec, &path))
        })
        .collect();
    for (name, free, truth, rep) in &fitted {
        let mu = rep.mu_kinetic.expect("identifiable");
        let z = (mu.value - truth) / mu.stderr;
        let g = rep.params.iter().find(|(q, _)| *q == Param::Gravity);
        if *free {
            assert!(z.abs() < 3.0, "{name}: mu {mu:?}, z {z:.1}");
            let g = g.expect("gravity fitted").1;
            assert!((g.value / 9.81 - 1.0).abs() < 5e-4, "{name}: gravity {g:?}");
        } else {
            assert!(g.is_none(), "{name}: gravity held");
            // Held 0.04 % low, the swings ask for a common scale of lengths against gravity,
            // under which mu is invariant: the camera's scale error takes it, as much as the
            // typed gravity is off (9.81 / 9.806 - 1), and mu stays within 3. (Before the
            // score test offered the camera's candidates on this rig, mu moved 3.5 SE
            // unflagged.)
            assert!(z.abs() < 3.0, "{name}: mu {mu:?}, z {z:.1}");
            let s = rep
                .params
                .iter()
                .find(|(q, _)| *q == Param::ScaleError)
                .expect("the camera's scale fitted")
                .1;
            let off = 9.81 / 9.806 - 1.0;
            assert!(
                (s.value - off).abs() < 3.0 * s.stderr,
                "{name}: scale error {s:?}, gravity off by {off:e}"
            );
        }
    }
    let omitted = &fitted.iter().find(|f| f.0 == "equal_omitted").unwrap().3;
    assert!(
        omitted
            .warnings
            .iter()
            .any(|w| w.contains("rig.gravity not given")),
        "{:?}",
        omitted.warnings
    );
}
