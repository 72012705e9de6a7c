//! The fit on recordings its plain model does not describe: real-rig physics (tilt, damping,
//! Stribeck friction), camera effects (scale, marker offsets, lag), gaps, bad cells and
//! mu_static above mu_kinetic. Recordings are made by the project's simulator with the real
//! terms and the camera's observation model, then Gaussian noise; the fit never sees the
//! truth. The sweeps over many seeds are `#[ignore]`d (run with `--ignored`); CI runs one seed
//! of each case.

use super::helpers::Normal;
use appell::fit::{fit, FitReport, FitSettings, Nuisance, Observations};
use appell::model::{observed_markers, Camera, Rig, State};
use appell::sim::{simulate, Options, Request};

/// The shared example's rig (docs/formats.md): m1 = 0.5, m2 = 0.2, l = 0.3, mu = 0.12.
pub(crate) fn example_rig(mu: f64) -> Rig<f64> {
    Rig::new(0.5, 0.2, 0.3, 9.81, mu, None).unwrap()
}

/// Released from rest 0.9 rad from the downward vertical, like the shipped example.
pub(crate) const Y0: State<f64> = [0.0, std::f64::consts::FRAC_PI_2 - 0.9, 0.0, 0.0];

/// A recording of `rig` seen through `camera`: `rate` Hz for `duration` s, noise `sigma` m.
pub(crate) fn record(
    rig: &Rig<f64>,
    camera: &Camera<f64>,
    y0: State<f64>,
    rate: f64,
    duration: f64,
    sigma: f64,
    seed: u64,
) -> Observations {
    let times: Vec<f64> = (0..=(duration * rate).round() as usize)
        .map(|k| k as f64 / rate)
        .collect();
    let opts = Options {
        rtol: 1e-12,
        atol: 1e-14,
        ..Options::default()
    };
    let sol = simulate(
        rig,
        &y0,
        duration,
        &opts,
        &Request {
            sample_times: times.clone(),
            friction_work: false,
            positions_only: false,
        },
    )
    .unwrap();
    let mut rng = Normal::new(seed * 7919 + 17);
    let mut obs = Observations {
        times,
        slider: vec![],
        bob: vec![],
    };
    for s in &sol.samples {
        let m = observed_markers(rig, camera, s.mode, &s.state);
        let mut n = || sigma * rng.sample();
        obs.slider.push(Some([m[0] + n(), m[1] + n()]));
        obs.bob.push(Some([m[2] + n(), m[3] + n()]));
    }
    obs
}

/// A case: what the recording has that the plain model lacks.
struct Case {
    name: &'static str,
    rig: Rig<f64>,
    camera: Camera<f64>,
    /// The nuisance that describes it (none for the well-specified case).
    right: Option<Nuisance>,
}

fn cases() -> Vec<Case> {
    let base = example_rig(0.12);
    let cam = Camera::default();
    vec![
        Case {
            name: "well-specified",
            rig: base,
            camera: cam,
            right: None,
        },
        Case {
            name: "tilt 0.5 deg",
            rig: base.with_rail_tilt(0.5f64.to_radians()),
            camera: cam,
            right: Some(Nuisance::RailTilt),
        },
        Case {
            name: "pivot damping",
            rig: base.with_pivot_damping(2e-3),
            camera: cam,
            right: Some(Nuisance::PivotDamping),
        },
        Case {
            name: "stribeck",
            rig: Rig::new(0.5, 0.2, 0.3, 9.81, 0.12, Some(0.16))
                .unwrap()
                .with_stribeck(0.05),
            camera: cam,
            right: Some(Nuisance::Stribeck),
        },
        Case {
            name: "mu_static 0.16 > mu_kinetic",
            rig: Rig::new(0.5, 0.2, 0.3, 9.81, 0.12, Some(0.16)).unwrap(),
            camera: cam,
            right: Some(Nuisance::StaticFriction),
        },
        Case {
            name: "camera scale 2% off",
            rig: base,
            camera: Camera {
                scale_error: 0.02,
                ..cam
            },
            right: Some(Nuisance::CameraScale),
        },
        Case {
            name: "bob marker 1 cm off the axis",
            rig: base,
            camera: Camera {
                bob_across: 0.01,
                ..cam
            },
            right: Some(Nuisance::BobOffset),
        },
        Case {
            name: "3 ms lag between markers",
            rig: base,
            camera: Camera { lag: 0.003, ..cam },
            right: Some(Nuisance::Lag),
        },
    ]
}

/// Whether the report's 95% interval covers `truth`, and its half-width relative to it.
fn covers(rep: &FitReport, truth: f64) -> (bool, f64, f64) {
    let mu = rep.mu_kinetic.expect("mu_kinetic identifiable");
    let ok = mu.ci95[0] <= truth && truth <= mu.ci95[1];
    let half = 0.5 * (mu.ci95[1] - mu.ci95[0]) / truth;
    (ok, half, (mu.value - truth) / mu.stderr)
}

/// Fit each case on `seeds` seeds; per case: covered count, median half-width, worst |z|.
/// With `right`, the case's own nuisance is put in the model (`--with`), the rest chosen.
fn sweep(seeds: u64, rate: f64, right: bool) -> Vec<(&'static str, usize, usize, f64, f64)> {
    cases()
        .into_iter()
        .map(|c| {
            let settings = FitSettings {
                with: c.right.filter(|_| right).into_iter().collect(),
                ..FitSettings::default()
            };
            let mut hits = 0;
            let mut halves = Vec::new();
            let mut worst: f64 = 0.0;
            for seed in 0..seeds {
                let obs = record(&c.rig, &c.camera, Y0, rate, 2.0, 2e-4, seed + 1);
                let rep = fit(obs, &example_rig(0.3), &settings).unwrap();
                let (ok, half, z) = covers(&rep, c.rig.mu_kinetic);
                hits += usize::from(ok);
                halves.push(half);
                worst = worst.max(z.abs());
                if !ok {
                    eprintln!(
                        "{} seed {seed}: {:?} nuisances {:?} limited {:?}",
                        c.name, rep.mu_kinetic, rep.nuisances, rep.adequacy.limited_by_model
                    );
                }
            }
            halves.sort_by(f64::total_cmp);
            let line = (
                c.name,
                hits,
                seeds as usize,
                halves[halves.len() / 2],
                worst,
            );
            eprintln!("{line:?}");
            line
        })
        .collect()
}

/// One seed of every case, at 500 Hz: each estimate is within 3.5 standard errors of the
/// truth (a confident wrong answer is tens of them off) with an interval under 2% of mu. The
/// 95% coverage itself is a rate: the ignored sweeps measure it.
#[test]
fn every_misspecification_is_caught_on_one_seed() {
    for (name, _, _, half, worst) in sweep(1, 500.0, false) {
        assert!(worst < 3.5, "{name}: |z| = {worst}");
        assert!(half < 0.02, "{name}: half-width {half}");
    }
}

/// The sweep behind the closing note's coverage figures: 10 seeds of every case at 1 kHz.
#[test]
#[ignore]
fn misspecification_sweep_ten_seeds() {
    for (name, hits, n, half, worst) in sweep(10, 1000.0, false) {
        eprintln!(
            "SWEEP {name}: {hits}/{n} covered, median half-width {half:.4}, worst |z| {worst:.1}"
        );
    }
}

/// With the right nuisance in the model, mu_kinetic is within 3 standard errors of the truth
/// (one seed per case; the ten-seed sweep is ignored).
#[test]
fn the_right_nuisance_brings_mu_within_three_standard_errors() {
    for (name, _, _, _, worst) in sweep(1, 500.0, true) {
        assert!(worst < 3.0, "{name}: |z| = {worst}");
    }
}

/// The ten-seed sweep with the right nuisance in the model.
#[test]
#[ignore]
fn right_nuisance_sweep_ten_seeds() {
    for (name, hits, n, half, worst) in sweep(10, 1000.0, true) {
        eprintln!(
            "RIGHT {name}: {hits}/{n} covered, median half-width {half:.4}, worst |z| {worst:.1}"
        );
    }
}

/// Coverage of the 95% interval over 100 well-specified recordings (different seeds and
/// releases): between 92 and 98 covered is honest. And the friction law stays Coulomb's: a
/// fit that takes another law (static above kinetic, Stribeck, viscous, direction, load) for
/// these Coulomb recordings does so in at most 5 of 100.
#[test]
#[ignore]
fn well_specified_coverage_over_100_recordings() {
    let settings = FitSettings::default();
    let mut hits = 0;
    let mut other_law = 0;
    for seed in 0..100u64 {
        let theta0 = std::f64::consts::FRAC_PI_2 - 0.7 - 0.004 * seed as f64;
        let y0 = [0.0, theta0, 0.0, 0.0];
        let rig = example_rig(0.12);
        let obs = record(&rig, &Camera::default(), y0, 500.0, 2.0, 2e-4, seed + 100);
        let rep = fit(obs, &example_rig(0.3), &settings).unwrap();
        let (ok, _, z) = covers(&rep, 0.12);
        hits += usize::from(ok);
        let law = rep.friction.as_ref().map_or("none", |f| f.chosen.as_str());
        other_law += usize::from(law != "coulomb");
        if !ok || law != "coulomb" {
            eprintln!(
                "seed {seed}: z {z:.2} law {law} nuisances {:?}",
                rep.nuisances
            );
        }
    }
    eprintln!("COVERAGE {hits}/100, another law than Coulomb's {other_law}/100");
    assert!((92..=98).contains(&hits), "{hits}/100 covered");
    assert!(other_law <= 5, "{other_law}/100 took another law");
}

/// A dropped bob frame and 20% of one marker's frames missing: the slider still slides, and
/// mu is found (the starts survive gaps).
#[test]
fn gaps_in_either_marker_do_not_lose_the_slide() {
    let rig = example_rig(0.12);
    let mut obs = record(&rig, &Camera::default(), Y0, 500.0, 2.0, 2e-4, 5);
    obs.bob[3] = None;
    let rep = fit(obs.clone(), &example_rig(0.3), &FitSettings::default()).unwrap();
    let (ok, _, _) = covers(&rep, 0.12);
    assert!(ok, "{:?}", rep.mu_kinetic);
    for (k, s) in obs.slider.iter_mut().enumerate() {
        if k % 5 == 2 {
            *s = None;
        }
    }
    let rep = fit(obs, &example_rig(0.3), &FitSettings::default()).unwrap();
    let (ok, _, _) = covers(&rep, 0.12);
    assert!(ok, "{:?}", rep.mu_kinetic);
}

/// One bad cell (bob x = -0.0 in an early frame) and 1% gross outliers: detected without a
/// flag, counted, and the fit still covers the truth.
#[test]
fn bad_cells_and_gross_outliers_are_found_without_a_flag() {
    let rig = example_rig(0.12);
    let mut obs = record(&rig, &Camera::default(), Y0, 500.0, 2.0, 2e-4, 9);
    if let Some(b) = obs.bob[4].as_mut() {
        b[0] = -0.0;
    }
    let mut rng = Normal::new(3);
    for k in (10..obs.times.len()).step_by(97) {
        if let Some(b) = obs.bob[k].as_mut() {
            b[1] += 0.03 * rng.sample().signum();
        }
    }
    let rep = fit(obs, &example_rig(0.3), &FitSettings::default()).unwrap();
    assert!(rep.outliers[1] >= 10, "outliers {:?}", rep.outliers);
    let (ok, half, _) = covers(&rep, 0.12);
    assert!(ok && half < 0.02, "{:?}", rep.mu_kinetic);
}

/// The chi-square against the measured noise reveals a misfit that a noise read from the
/// residuals would hide: the plain model on a tilted rig fails the test.
#[test]
fn chi_square_against_measured_noise_reveals_a_misfit() {
    let tilted = example_rig(0.12).with_rail_tilt(1f64.to_radians());
    let obs = record(&tilted, &Camera::default(), Y0, 500.0, 2.0, 2e-4, 11);
    let plain = FitSettings {
        nuisances: false,
        windows: false,
        profile: false,
        ..FitSettings::default()
    };
    let rep = fit(obs.clone(), &example_rig(0.3), &plain).unwrap();
    assert!(rep.adequacy.p_value < 1e-3, "p {}", rep.adequacy.p_value);
    assert!(!rep.adequacy.limited_by_model.is_empty());
    // With the nuisance search on, tilt is chosen and the chi-square passes.
    let rep = fit(obs, &example_rig(0.3), &FitSettings::default()).unwrap();
    assert!(
        rep.nuisances.contains(&appell::fit::Nuisance::RailTilt),
        "{:?}",
        rep.nuisances
    );
    assert!(rep.adequacy.p_value > 1e-3, "p {}", rep.adequacy.p_value);
    let (ok, _, z) = covers(&rep, 0.12);
    assert!(ok && z.abs() < 3.0, "z {z}");
}

/// A noise-free recording (regression tests on synthetic data) is recognised, by the fit's
/// chi-square far below the noise measured from the tracks at 1 kHz and by a measured noise
/// below the model's numerical accuracy at 10 kHz: mu is recovered to rounding, no adequacy
/// flag is raised (they compare residuals with a noise that is not there), and the report says
/// the intervals are not meaningful. The same recording with 0.1 mm of noise is not noise-free.
#[test]
fn noise_free_recordings_are_recognised_and_recovered_exactly() {
    let rig = example_rig(0.12);
    let camera = Camera::default();
    for (rate, duration) in [(1000.0, 2.0), (10_000.0, 0.5)] {
        let obs = record(&rig, &camera, Y0, rate, duration, 0.0, 1);
        let rep = fit(obs, &example_rig(0.3), &FitSettings::default()).unwrap();
        assert!(
            rep.adequacy.noise_free,
            "{rate} Hz: noise {:?}, residual RMS {}, {:?}",
            rep.noise_m, rep.rms_residual_m, rep.adequacy
        );
        assert!(
            rep.adequacy.limited_by_model.is_empty(),
            "{:?}",
            rep.adequacy
        );
        let mu = rep.mu_kinetic.unwrap().value;
        assert!((mu - 0.12).abs() < 1e-8, "{rate} Hz: mu {mu}");
        assert!(rep.warnings.iter().any(|w| w.contains("not meaningful")));
        assert_eq!(
            rep.outliers,
            [0, 0],
            "{rate} Hz: noise-free positions left out"
        );
    }
    let noisy = record(&rig, &camera, Y0, 1000.0, 2.0, 1e-4, 1);
    let rep = fit(noisy, &example_rig(0.3), &FitSettings::default()).unwrap();
    assert!(!rep.adequacy.noise_free);
}

/// A noise-free recording that the model does not describe (a rigid pendulum fitted as point
/// masses, no nuisance allowed) is not "noise-free" for the fit: its residuals are far above
/// the model's accuracy, and the model's limit is still said.
#[test]
fn a_misfit_of_a_noise_free_recording_keeps_its_flag() {
    let rigid = appell::model::PendulumKeys {
        bob_mass: Some(0.2),
        rod_mass: Some(0.03),
        bob_radius: Some(0.02),
        ..Default::default()
    }
    .rig(0.5, 0.3, 9.81, 0.12, None)
    .unwrap();
    let obs = record(&rigid, &Camera::default(), Y0, 1000.0, 2.0, 0.0, 1);
    let settings = FitSettings {
        nuisances: false,
        ..FitSettings::default()
    };
    let rep = fit(obs, &example_rig(0.3), &settings).unwrap();
    assert!(!rep.adequacy.noise_free, "{:?}", rep.adequacy);
    assert!(!rep.adequacy.limited_by_model.is_empty());
}
