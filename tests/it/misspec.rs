//! Recordings with effects the fit's model does not describe, made by an independent
//! Newton-Euler generator (`scripts/generators/misspec_generator.py`, `tests/data/misspec/`):
//! air drag, barrel lens distortion, four effects at once, friction that varies along the rail,
//! frame-time jitter and occlusion bursts, on three rigs from light to heavy slider (seed 1 of
//! each; the 10-seed sweep is `scripts/sweeps/misspec_sweep.py`, outside CI). The rule checked:
//! mu within 3 standard errors of the truth, or the report says the model limits the result;
//! never a confident wrong answer.

use appell::data::{read_recording, ReadOptions};
use appell::fit::{fit, FitReport, FitSettings, Observations};
use appell::scene::RigFile;
use rayon::prelude::*;
use std::path::PathBuf;

fn repo(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(rel)
}

const EFFECTS: [&str; 7] = [
    "none",
    "drag",
    "lens",
    "four",
    "friction_ramp",
    "jitter",
    "occlusion",
];
const RIGS: [&str; 3] = ["light", "paper", "heavy"];

/// One fitted file: its effect, rig, true mu (`None` where mu varies along the rail), the
/// positions the generator made gross errors of, and the report.
struct Fitted {
    effect: &'static str,
    rig: &'static str,
    truth: Option<f64>,
    gross: usize,
    rep: FitReport,
}

/// Every seed-1 file fitted with the measured rig and the default settings, once for the
/// tests that read them.
fn fitted() -> &'static [Fitted] {
    static FITTED: std::sync::OnceLock<Vec<Fitted>> = std::sync::OnceLock::new();
    FITTED.get_or_init(fit_all)
}

fn fit_all() -> Vec<Fitted> {
    let text = std::fs::read_to_string(repo("tests/data/misspec/misspec_truth.json")).unwrap();
    let t: serde_json::Value = serde_json::from_str(&text).unwrap();
    let jobs: Vec<(&str, &str)> = EFFECTS
        .iter()
        .flat_map(|e| RIGS.iter().map(move |r| (*e, *r)))
        .collect();
    jobs.into_par_iter()
        .with_max_len(1)
        .map(|(effect, rig)| {
            let case = &t["effects"][effect][rig];
            let truth = case["mu_defined"]
                .as_bool()
                .unwrap()
                .then(|| case["mu_kinetic"].as_f64().unwrap());
            let gross = case["effect_parameters"]["per_seed"]["1"]
                .as_array()
                .map_or(0, |bursts| {
                    bursts
                        .iter()
                        .map(|b| b["gross_error_m"].as_object().unwrap().len())
                        .sum()
                });
            let path = repo(&format!("tests/data/misspec/{effect}_{rig}.csv"));
            let rec = read_recording(&[path], &ReadOptions::default()).expect("reads");
            let r = RigFile::load_for_fit(
                &repo(&format!("tests/data/misspec/{rig}_measured.toml")),
                0.3,
            )
            .unwrap();
            let rep = fit(Observations::from(&rec), &r, &FitSettings::default()).unwrap();
            Fitted {
                effect,
                rig,
                truth,
                gross,
                rep,
            }
        })
        .collect()
}

fn flagged(rep: &FitReport) -> bool {
    !rep.adequacy.limited_by_model.is_empty() || rep.failed.is_some()
}

/// The acceptance rule on every file, the coverage of the 95% intervals, and what the effects
/// the model cannot describe must be reported as.
#[test]
fn effects_outside_the_model_are_never_a_confident_wrong_answer() {
    let all = fitted();
    let (mut defined, mut covered) = (0, 0);
    for f in all {
        let mu = f.rep.mu_kinetic.expect("mu_kinetic identifiable");
        let line = format!(
            "{} {}: mu {} +- {} [{}, {}] {} nuisances {:?} limited {:?}",
            f.effect,
            f.rig,
            mu.value,
            mu.stderr,
            mu.ci95[0],
            mu.ci95[1],
            mu.interval,
            f.rep.nuisances,
            f.rep.adequacy.limited_by_model
        );
        eprintln!("{line}");
        match f.truth {
            Some(truth) => {
                let z = (mu.value - truth) / mu.stderr;
                assert!(
                    z.abs() < 3.0 || flagged(&f.rep),
                    "confident and wrong: {line}"
                );
                defined += 1;
                covered += usize::from(mu.ci95[0] <= truth && truth <= mu.ci95[1]);
            }
            // mu varies along the rail by 20 % per 10 cm: no single mu describes the
            // recording, and the report must say the model limits the result.
            None => assert!(flagged(&f.rep), "a friction ramp unflagged: {line}"),
        }
        // The dynamic and optical effects leave structure no nuisance removes.
        if matches!(f.effect, "drag" | "lens" | "four") {
            assert!(flagged(&f.rep), "unflagged: {line}");
        }
    }
    eprintln!("covered {covered} of {defined}");
    assert!(
        covered * 10 >= defined * 9,
        "covered {covered} of {defined}"
    );
}

/// While the model misfits, no real position is thrown away as "mis-tracked" (the residuals
/// are the model's error); the occlusion bursts' gross errors (5 to 20 mm, one per marker about
/// to vanish) are found, with at most two real positions beside them (a real position next to
/// a burst has no neighbour on one side to be checked against).
#[test]
fn only_mis_tracked_positions_are_left_out() {
    for f in fitted() {
        let dropped: usize = f.rep.outliers.iter().sum();
        match f.effect {
            "occlusion" => assert!(
                f.gross > 0 && (f.gross..=f.gross + 2).contains(&dropped),
                "{} {}: {dropped} dropped of {} gross errors",
                f.effect,
                f.rig,
                f.gross
            ),
            _ => assert_eq!(dropped, 0, "{} {}: {dropped} dropped", f.effect, f.rig),
        }
        // A candidate whose fit failed is listed as failed, takes no weight and is never
        // the chosen model.
        for m in &f.rep.models {
            if m.failed.is_some() {
                assert!(!m.chosen && m.weight == 0.0, "{}: {m:?}", f.effect);
            }
        }
        let total: f64 = f.rep.models.iter().map(|m| m.weight).sum();
        assert!(
            f.rep.models.is_empty() || (total - 1.0).abs() < 1e-9,
            "weights sum to {total}"
        );
    }
}

/// One release that slides once, on a damped rig on a rail tilted by 0.3 deg
/// (`tests/data/campaign37/c14_one_slide`, independent generator). The greedy selection took
/// pivot damping, then a bob marker off the rod's line for the tilt (both move where the
/// pendulum hangs) and never tried the tilt with the damping: mu 46.6 standard errors off,
/// unflagged. The selection now also fits the path it did not take (the marker swapped for
/// the tilt): the table holds both, the better is chosen, and mu is within 3 standard errors.
#[test]
fn one_slide_on_a_damped_tilted_rig_tries_the_tilt_with_the_damping() {
    let dir = repo("tests/data/campaign37/c14_one_slide");
    let text = std::fs::read_to_string(dir.join("truth.json")).unwrap();
    let t: serde_json::Value = serde_json::from_str(&text).unwrap();
    let mu_true = t["mu_per_release"][4].as_f64().unwrap();
    let rec = read_recording(&[dir.join("release_05.csv")], &ReadOptions::default()).unwrap();
    let rig = RigFile::load_for_fit(&dir.join("rig_measured.toml"), 0.3).unwrap();
    let rep = fit(Observations::from(&rec), &rig, &FitSettings::default()).unwrap();
    let names: Vec<&str> = rep.models.iter().map(|m| m.name.as_str()).collect();
    assert!(
        names.contains(&"rail_tilt+pivot_damping") || names.contains(&"pivot_damping+rail_tilt"),
        "{names:?}"
    );
    let mu = rep.mu_kinetic.unwrap();
    assert!(
        ((mu.value - mu_true) / mu.stderr).abs() < 3.0,
        "{mu:?} against {mu_true} ({:?})",
        rep.nuisances
    );
}

/// The selection's first pass leaves a candidate where it stopped after 15 iterations only
/// when it lies far behind the round's best, and the law weighing leaves a law once even its
/// predicted drop cannot bring it within Occam's window: fitting every candidate to the end
/// (`first_iters` 0) gives the same chosen model, mu and interval, with more iterations; a
/// row left after its first iterations is more than a quarter of the best chi-square behind
/// and carries no weight, and a law left out of reach stays outside the window fitted to the
/// end. Release 4 of a light rigid rig on a 0.8 deg tilt, where mu_static and Stribeck
/// friction crawl (233 iterations against 517).
#[test]
fn candidates_left_far_behind_change_no_answer() {
    let dir = repo("tests/data/campaign37/c16_rigid_light_odd_tilt");
    let rec = read_recording(&[dir.join("release_04.csv")], &ReadOptions::default()).unwrap();
    let rig = RigFile::load_for_fit(&dir.join("rig_measured.toml"), 0.3).unwrap();
    let quick = FitSettings {
        profile: false,
        ..FitSettings::default()
    };
    let whole = FitSettings {
        first_iters: 0,
        ..quick.clone()
    };
    let a = fit(Observations::from(&rec), &rig, &quick).unwrap();
    let b = fit(Observations::from(&rec), &rig, &whole).unwrap();
    assert_eq!(a.nuisances, b.nuisances);
    let (ma, mb) = (a.mu_kinetic.unwrap(), b.mu_kinetic.unwrap());
    // The same optimum to the solver's tolerance (a candidate near the best goes on from
    // where it stopped, so its last digits may differ).
    assert!(
        (ma.value - mb.value).abs() < 1e-3 * mb.stderr,
        "{ma:?} {mb:?}"
    );
    assert!((ma.stderr / mb.stderr - 1.0).abs() < 1e-3, "{ma:?} {mb:?}");
    assert!(
        a.work.iterations < b.work.iterations,
        "{:?} {:?}",
        a.work,
        b.work
    );
    let stopped: Vec<_> = a.models.iter().filter(|m| m.stopped_early).collect();
    assert!(!stopped.is_empty(), "no candidate was left early");
    assert!(b.models.iter().all(|m| !m.stopped_early));
    let best = a
        .models
        .iter()
        .filter(|m| m.failed.is_none())
        .map(|m| m.chi2)
        .fold(f64::INFINITY, f64::min);
    for m in stopped {
        let full = b.models.iter().find(|r| r.name == m.name).unwrap();
        // No better where it stopped than fitted to the end, up to the laws' tolerance (a
        // Gauss-Newton step predicted to gain less than 0.1 chi-square units is not taken).
        assert!(full.chi2 <= m.chi2 + 0.5, "{m:?} {full:?}");
        if m.chi2 > 1.25 * best {
            // Left after its first iterations: fitted to the end it is no better than a
            // quarter behind either.
            assert!(m.weight == 0.0 && full.chi2 > 1.25 * best, "{m:?} {full:?}");
        } else {
            // A law stopped out of reach: outside Occam's window (a BIC 6 behind) where it
            // stopped, and fitted to the end too.
            assert!(m.delta_bic > 6.0 && full.delta_bic > 6.0, "{m:?} {full:?}");
        }
    }
}
