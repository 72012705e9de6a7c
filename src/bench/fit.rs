//! The fit benchmark: a 2 s, 1000 Hz, two-marker synthetic recording of the example rig
//! (mu = 0.12, 0.2 mm noise), fitted from a start 30% off in mu; run time against mu error over
//! a ladder of integration tolerances.

use super::median_seconds;
use crate::data::synth::{synthesize, SynthOptions};
use crate::fit::{fit, FitSettings, Observations};
use crate::scene::Scene;
use crate::sim::Options;
use serde::Serialize;

/// The example rig's scene (docs/formats.md): m1 = 0.5, m2 = 0.2, l = 0.30, mu = 0.12, from rest.
const SCENE: &str = include_str!("../../configs/markers_example.toml");

/// One point of the fit's run time against its error.
#[derive(Debug, Clone, Serialize)]
pub struct FitPoint {
    /// Integration tolerance used inside the fit.
    pub rtol: f64,
    /// Whether the profile intervals were computed.
    pub profile: bool,
    /// The plain model only (`--plain`: no nuisance search, no windows).
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

/// The length ladder's scene: the paper rig released from rest with the rod horizontal, whose
/// stick-slip goes on for minutes (a noise of 0.5 mm).
const LADDER_SCENE: &str = include_str!("../../configs/paper_rest_horizontal.toml");

/// One rung of the length ladder: a whole fit (default settings) of a recording this long.
#[derive(Debug, Clone, Serialize)]
pub struct LengthPoint {
    /// Recording length (s).
    pub duration: f64,
    /// Frame rate (Hz).
    pub fps: f64,
    /// Frames in the recording.
    pub frames: usize,
    /// Whether the profile intervals were computed.
    pub profile: bool,
    /// CPU time of the fit, every thread (s).
    pub cpu_seconds: f64,
    /// Wall time of the fit (s).
    pub wall_seconds: f64,
    /// Peak resident memory while the recording was held and fitted (MB), where the system
    /// reports it (Linux).
    pub peak_mb: Option<f64>,
    /// Estimated mu_kinetic.
    pub mu: f64,
    /// Its reported standard error.
    pub stderr: f64,
    /// mu - truth.
    pub mu_error: f64,
}

/// CPU time of this process so far, every thread (s).
fn cpu_seconds() -> f64 {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: clock_gettime writes one timespec through a valid pointer.
    let rc = unsafe { libc::clock_gettime(libc::CLOCK_PROCESS_CPUTIME_ID, &mut ts) };
    if rc == 0 {
        ts.tv_sec as f64 + ts.tv_nsec as f64 * 1e-9
    } else {
        f64::NAN
    }
}

/// Reset the peak resident set size the kernel keeps for this process (Linux's clear_refs
/// with 5), so the next reading is the peak of what follows.
fn reset_peak() -> bool {
    std::fs::write("/proc/self/clear_refs", "5").is_ok()
}

/// Peak resident set size since the last reset (MB), from /proc/self/status.
fn peak_mb() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb / 1024.0)
}

/// Fit synthetic recordings of the paper scene of each `(duration s, frame rate Hz)` with the
/// default settings (`profile` on or off), one fit per rung (each takes long enough to time
/// on its own); reports CPU time, wall time, peak memory and the error in mu.
pub fn length_ladder(lengths: &[(f64, f64)], profile: bool) -> Result<Vec<LengthPoint>, String> {
    let scene = Scene::from_toml(LADDER_SCENE, "configs/paper_rest_horizontal.toml".as_ref())
        .map_err(|e| e.to_string())?;
    let settings = FitSettings {
        profile,
        ..FitSettings::default()
    };
    let mut out = Vec::new();
    for &(duration, fps) in lengths {
        if !(duration > 0.0 && fps > 0.0 && duration * fps <= 1e7) {
            return Err(format!(
                "a ladder length needs duration > 0 and fps > 0 with at most 1e7 frames, got {duration} s at {fps} Hz"
            ));
        }
        let opts = SynthOptions {
            fps,
            duration: Some(duration),
            noise: 5e-4,
            seed: 1,
            ..SynthOptions::default()
        };
        let syn = synthesize(&scene, &opts).map_err(|e| e.to_string())?;
        let obs = Observations::from(&syn.recording);
        drop(syn);
        let frames = obs.times.len();
        let measured = reset_peak();
        let (cpu0, wall0) = (cpu_seconds(), std::time::Instant::now());
        let rep = fit(obs, &scene.rig, &settings).map_err(|e| e.to_string())?;
        let (cpu, wall) = (cpu_seconds() - cpu0, wall0.elapsed().as_secs_f64());
        let mu = rep.mu_kinetic.ok_or("mu not identifiable")?;
        out.push(LengthPoint {
            duration,
            fps,
            frames,
            profile,
            cpu_seconds: cpu,
            wall_seconds: wall,
            peak_mb: if measured { peak_mb() } else { None },
            mu: mu.value,
            stderr: mu.stderr,
            mu_error: mu.value - scene.rig.mu_kinetic,
        });
    }
    Ok(out)
}

/// One point of the joint fit's cost against the number of releases.
#[derive(Debug, Clone, Serialize)]
pub struct JointPoint {
    /// Releases fitted together.
    pub releases: usize,
    /// Median CPU time of one joint fit, every thread (s).
    pub cpu_seconds: f64,
    /// Median wall time (s).
    pub wall_seconds: f64,
    /// The joint mu_kinetic and its standard error.
    pub mu: f64,
    /// Its standard error.
    pub stderr: f64,
}

/// Time the joint fit (default settings) of the first `n` of `releases` for each `n` in
/// `counts`: the median over `batches` runs of CPU and wall time, which should grow linearly.
pub fn joint_benchmark(
    releases: &[crate::fit::joint::Release],
    rig: &crate::model::Rig<f64>,
    counts: &[usize],
    batches: usize,
) -> Result<Vec<JointPoint>, String> {
    use crate::fit::joint::{fit_joint, JointSettings};
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    counts
        .iter()
        .map(|&n| {
            let set = &releases[..n.min(releases.len())];
            let (mut cpu, mut wall) = (Vec::new(), Vec::new());
            let mut last = None;
            for _ in 0..batches.max(1) {
                let (cpu0, wall0) = (cpu_seconds(), std::time::Instant::now());
                let rep = fit_joint(set, rig, &FitSettings::default(), &JointSettings::default())
                    .map_err(|e| e.to_string())?;
                cpu.push(cpu_seconds() - cpu0);
                wall.push(wall0.elapsed().as_secs_f64());
                last = Some(rep.mu_kinetic);
            }
            let mu = last.expect("at least one batch");
            Ok(JointPoint {
                releases: set.len(),
                cpu_seconds: median(cpu),
                wall_seconds: median(wall),
                mu: mu.value,
                stderr: mu.stderr,
            })
        })
        .collect()
}
