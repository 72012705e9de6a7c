//! Synthetic recordings of a scene with a known mu: simulated marker tracks plus seeded
//! Gaussian noise, dropouts and outliers, written as canonical CSV or MCAP.

use super::{DataError, Format, Provenance, Recording};
use crate::scene::Scene;
use crate::sim::{simulate, Request, SimError};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use std::collections::BTreeMap;
use std::path::Path;

/// What to add to the simulated markers. Every option is checked by [`SynthOptions::validate`].
#[derive(Debug, Clone, PartialEq)]
pub struct SynthOptions {
    /// Frame rate (Hz).
    pub fps: f64,
    /// Duration (s); `None` takes the scene's.
    pub duration: Option<f64>,
    /// Standard deviation of the Gaussian noise on each coordinate (m).
    pub noise: f64,
    /// Probability that a marker is missing in a frame.
    pub dropout: f64,
    /// Probability that a marker is mis-tracked in a frame.
    pub outliers: f64,
    /// How far a mis-tracked marker lands from the truth (m, random direction).
    pub outlier_size: f64,
    /// Seed of the random generator (ChaCha8): the same seed gives the same recording.
    pub seed: u64,
}

impl Default for SynthOptions {
    fn default() -> Self {
        SynthOptions {
            fps: 1000.0,
            duration: None,
            noise: 0.0,
            dropout: 0.0,
            outliers: 0.0,
            outlier_size: 0.05,
            seed: 0,
        }
    }
}

impl SynthOptions {
    /// Check the ranges, naming the option at fault.
    pub fn validate(&self) -> Result<(), String> {
        let pos = |name: &str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(format!("{name} must be a finite number > 0, got {v}"))
            }
        };
        // A length far beyond any rig and camera, yet small enough that the recording's
        // coordinates stay ones every reader takes (1e300 wrote a file no command would read).
        let nonneg = |name: &str, v: f64| {
            if v.is_finite() && (0.0..=MAX_SYNTH_LENGTH).contains(&v) {
                Ok(())
            } else {
                Err(format!(
                    "{name} must be a length from 0 to {MAX_SYNTH_LENGTH} m, got {v:?}"
                ))
            }
        };
        let prob = |name: &str, v: f64| {
            if (0.0..=1.0).contains(&v) {
                Ok(())
            } else {
                Err(format!("{name} must be a probability in [0, 1], got {v}"))
            }
        };
        pos("--fps", self.fps)?;
        if let Some(d) = self.duration {
            pos("--duration", d)?;
        }
        nonneg("--noise", self.noise)?;
        prob("--dropout", self.dropout)?;
        prob("--outliers", self.outliers)?;
        nonneg("--outlier-size", self.outlier_size)
    }
}

/// The largest noise or outlier distance (m) `synth` adds: a thousand metres, beyond any
/// rig and camera.
pub const MAX_SYNTH_LENGTH: f64 = 1e3;

/// A synthetic recording and the truth it was made with.
#[derive(Debug, Clone)]
pub struct Synthetic {
    /// The recording (rail frame, metres, y up).
    pub recording: Recording,
    /// The true parameters and options: rig, initial state, noise, seed.
    pub truth: BTreeMap<String, String>,
    /// When the simulation ended before the duration (a paradox it does not resolve).
    pub stopped_at: Option<f64>,
    /// The simulation's events (the true mode switches).
    pub events: Vec<crate::sim::Event>,
}

/// Simulate `scene` and turn its markers into a recording with noise, dropouts and outliers.
pub fn synthesize(scene: &Scene, opts: &SynthOptions) -> Result<Synthetic, SimError> {
    let duration = opts.duration.unwrap_or(scene.duration);
    let n = (duration * opts.fps + 1e-9).floor() as usize;
    let sample_times: Vec<f64> = (0..=n).map(|k| k as f64 / opts.fps).collect();
    let sol = simulate(
        &scene.rig,
        &scene.initial,
        duration,
        &scene.options,
        &Request {
            sample_times,
            friction_work: false,
            positions_only: false,
        },
    )?;
    let mut rng = ChaCha8Rng::seed_from_u64(opts.seed);
    let normal = Normal::new(0.0, opts.noise).expect("noise checked by validate");
    let mut rec = Recording {
        provenance: Provenance {
            format: None,
            slider_name: "slider".into(),
            bob_name: "bob".into(),
            ..Provenance::default()
        },
        ..Recording::default()
    };
    for s in &sol.samples {
        let m = crate::model::markers(&scene.rig, &s.state);
        rec.times.push(s.t);
        for (track, truth) in [
            (&mut rec.slider, [m[0], m[1]]),
            (&mut rec.bob, [m[2], m[3]]),
        ] {
            // Draw every random number for every marker and frame, so options change values
            // but not the stream.
            let noise = [normal.sample(&mut rng), normal.sample(&mut rng)];
            let drop = rng.random::<f64>() < opts.dropout;
            let outlier = rng.random::<f64>() < opts.outliers;
            let dir = rng.random::<f64>() * std::f64::consts::TAU;
            let mut p = [truth[0] + noise[0], truth[1] + noise[1]];
            if outlier {
                p[0] += opts.outlier_size * dir.cos();
                p[1] += opts.outlier_size * dir.sin();
            }
            track.push((!drop).then_some(p));
        }
    }
    let r = &scene.rig;
    let mut truth = BTreeMap::new();
    let mut put = |k: &str, v: f64| {
        truth.insert(k.to_string(), v.to_string());
    };
    match r.pendulum {
        // The rig as built (a fit's rig file takes these keys) and the equivalent point rig
        // its motion follows.
        Some(p) => {
            put("slider_mass", p.slider_mass);
            put("pendulum_mass", p.mass);
            put("pendulum_com", p.com);
            put("pendulum_inertia", p.inertia);
            put("equivalent_length", r.rod_length);
            put("equivalent_mass_ratio", r.slider_mass / r.bob_mass);
        }
        None => {
            put("slider_mass", r.slider_mass);
            put("bob_mass", r.bob_mass);
        }
    }
    put("rod_length", r.marker_length);
    put("gravity", r.gravity);
    put("mu_kinetic", r.mu_kinetic);
    put("mu_static", r.mu_static);
    // The law's own values, so that a recording's truth names everything the fit estimates.
    match r.friction_law {
        crate::model::FrictionLaw::Direction => {
            put("mu_kinetic_positive", r.mu_kinetic + r.kinetic_split);
            put("mu_kinetic_negative", r.mu_kinetic - r.kinetic_split);
            put("mu_kinetic_split", r.kinetic_split);
        }
        crate::model::FrictionLaw::Load => put("load_exponent", r.load_exponent),
        _ => {}
    }
    put("x0", scene.initial[0]);
    put("theta0", scene.initial[1]);
    put("x_dot0", scene.initial[2]);
    put("theta_dot0", scene.initial[3]);
    put("fps", opts.fps);
    put("duration", duration);
    put("noise_std", opts.noise);
    put("dropout", opts.dropout);
    put("outliers", opts.outliers);
    put("outlier_size", opts.outlier_size);
    truth.insert("seed".into(), opts.seed.to_string());
    truth.insert(
        "convention".into(),
        "theta0 from the rail's +x, y down (docs/physics.md); positions rail frame, metres, y up"
            .into(),
    );
    let stopped_at = (sol.final_time < duration - 1e-12).then_some(sol.final_time);
    if let Some(t) = stopped_at {
        truth.insert("stopped_at".into(), t.to_string());
    }
    Ok(Synthetic {
        recording: rec,
        truth,
        stopped_at,
        events: sol.events,
    })
}

/// The output format for a path's extension: `.mcap` is MCAP, anything else canonical CSV.
pub fn output_format(path: &Path) -> Format {
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("mcap"))
    {
        Format::Mcap
    } else {
        Format::Wide
    }
}

/// Stamp of the first frame in synthetic MCAP files (2023-11-14, as in the example files).
pub const START_NS: i64 = 1_700_000_000_000_000_000;

/// Write a synthetic recording of `scene` to `path` atomically: canonical CSV as [`write`];
/// MCAP with appell's recording topic (`/markers`, read back by its reader) and the overlay's
/// topics besides (docs/overlay.md): the noisy markers as recorded, the scene's true motion as
/// the model (its markers, modes, forces and events), so a planned release can be looked at in
/// Foxglove before it is recorded.
pub fn write_synthetic(path: &Path, syn: &Synthetic, scene: &Scene) -> Result<(), DataError> {
    use super::mcap::overlay::{write_overlay, ModelRun, OverlayInput};
    if output_format(path) != Format::Mcap {
        return write(path, &syn.recording, &syn.truth);
    }
    let rec = &syn.recording;
    let last = rec.times.last().copied().unwrap_or(0.0);
    let events: Vec<_> = syn.events.iter().filter(|e| e.t <= last).cloned().collect();
    let input = OverlayInput {
        times: &rec.times,
        recorded: Some([&rec.slider, &rec.bob]),
        events: &events,
        answer: None,
        origin_ns: START_NS as u64,
        lab_markers: true,
        metadata: BTreeMap::from([("truth".to_string(), syn.truth.clone())]),
        with_input: None,
    };
    let run = ModelRun {
        rig: &scene.rig,
        initial: &scene.initial,
        camera: &crate::model::Camera::default(),
        options: &scene.options,
    };
    crate::output::write_atomic(path, |w| Ok(write_overlay(w, &input, Some(&run))?)).map_err(
        |source| DataError::Write {
            path: path.to_owned(),
            source,
        },
    )
}

/// Write a recording to `path` atomically: canonical CSV, or MCAP (JSON frames, zstd, the
/// `truth` map as a metadata record named `truth`) when the extension is `.mcap`.
pub fn write(
    path: &Path,
    rec: &Recording,
    truth: &BTreeMap<String, String>,
) -> Result<(), DataError> {
    let result = match output_format(path) {
        Format::Mcap => {
            let meta = BTreeMap::from([("truth".to_string(), truth.clone())]);
            crate::output::write_atomic(path, |w| {
                super::mcap::write_json(w, rec, START_NS, &meta).map_err(|e| match e {
                    ::mcap::McapError::Io(io) => io,
                    other => std::io::Error::other(other),
                })
            })
        }
        _ => crate::output::write_atomic(path, |w| rec.write_csv(w)),
    };
    result.map_err(|source| DataError::Write {
        path: path.to_owned(),
        source,
    })
}
