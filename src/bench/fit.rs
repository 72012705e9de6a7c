//! The fit benchmark: a 2 s, 1000 Hz, two-marker synthetic recording of the example rig
//! (mu = 0.12, 0.2 mm noise), fitted from a start 30% off in mu; run time against mu error over
//! a ladder of integration tolerances.

use super::median_seconds;
use crate::data::synth::{synthesize, SynthOptions};
use crate::fit::{fit, FitSettings, Observations};
use crate::scene::Scene;
use crate::sim::Options;
use serde::Serialize;

/// The example rig's scene (FORMATS.md): m1 = 0.5, m2 = 0.2, l = 0.30, mu = 0.12, from rest.
const SCENE: &str = include_str!("../../configs/markers_example.toml");

/// One point of the fit's run time against its error.
#[derive(Debug, Clone, Serialize)]
pub struct FitPoint {
    /// Integration tolerance used inside the fit.
    pub rtol: f64,
    /// Whether the profile intervals were computed.
    pub profile: bool,
    /// The plain model only (`--plain`: no nuisance search, no thirds).
    pub plain: bool,
    /// Median wall time of one whole fit (s).
    pub seconds: f64,
    /// Estimated mu_kinetic.
    pub mu: f64,
    /// Its reported standard error.
    pub stderr: f64,
    /// |mu - truth|.
    pub mu_error: f64,
    /// |mu - mu at the tightest tolerance|: the part of the error the integrator causes.
    pub integration_error: f64,
}

/// The benchmark's recording and the start rig (mu 30% off).
pub fn recording() -> (Observations, crate::model::Rig<f64>, f64) {
    let scene = Scene::from_toml(SCENE, "configs/markers_example.toml".as_ref())
        .expect("shipped scene parses");
    let opts = SynthOptions {
        fps: 1000.0,
        duration: Some(2.0),
        noise: 2e-4,
        seed: 7,
        ..SynthOptions::default()
    };
    let syn = synthesize(&scene, &opts).expect("the example scene simulates");
    let mut start = scene.rig;
    start.mu_kinetic *= 1.3;
    start.mu_static = start.mu_kinetic;
    (
        Observations::from(&syn.recording),
        start,
        scene.rig.mu_kinetic,
    )
}

/// Time the fit over `rtols` (and with/without profile at the default tolerance).
pub fn fit_benchmark(rtols: &[f64], batches: usize) -> Result<Vec<FitPoint>, String> {
    let (obs, start, truth) = recording();
    let settings = |rtol: f64, profile: bool, plain: bool| FitSettings {
        profile,
        nuisances: !plain,
        windows: !plain,
        options: Options {
            rtol,
            atol: rtol * 1e-2,
            ..Options::default()
        },
        ..FitSettings::default()
    };
    let reference =
        fit(obs.clone(), &start, &settings(1e-12, false, false)).map_err(|e| e.to_string())?;
    let mu_ref = reference
        .mu_kinetic
        .ok_or("reference fit: mu not identifiable")?
        .value;
    let default_rtol = FitSettings::default().options.rtol;
    let mut points = Vec::new();
    // The rtol ladder with every step but the profiles, then the defaults, then the plain
    // model (the speed a user keeps with --plain).
    let mut cases: Vec<(f64, bool, bool)> = rtols.iter().map(|&r| (r, false, false)).collect();
    cases.push((default_rtol, true, false));
    cases.push((default_rtol, false, true));
    cases.push((default_rtol, true, true));
    for (rtol, profile, plain) in cases {
        let s = settings(rtol, profile, plain);
        let rep = fit(obs.clone(), &start, &s).map_err(|e| e.to_string())?;
        let mu = rep.mu_kinetic.ok_or("mu not identifiable")?;
        let seconds = median_seconds(
            || fit(obs.clone(), &start, &s),
            batches,
            if profile { 2.0 } else { 1.0 },
        )
        .map_err(|e| e.to_string())?;
        points.push(FitPoint {
            rtol,
            profile,
            plain,
            seconds,
            mu: mu.value,
            stderr: mu.stderr,
            mu_error: (mu.value - truth).abs(),
            integration_error: (mu.value - mu_ref).abs(),
        });
    }
    Ok(points)
}
