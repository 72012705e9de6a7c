//! `appell synth SCENE.toml OUTPUT`: a synthetic recording with a known mu, CSV or MCAP by the
//! output's extension.

use super::Failure;
use anyhow::anyhow;
use appell::data::synth::{self, SynthOptions};
use appell::scene::Scene;
use std::path::PathBuf;

/// Arguments of `appell synth`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Scene file (TOML with [rig], [initial], [run]).
    scene: PathBuf,
    /// Output: `.mcap` writes MCAP (JSON, zstd, truth metadata), anything else canonical CSV.
    output: PathBuf,
    /// Frame rate (Hz).
    #[arg(long, default_value_t = 1000.0, value_name = "HZ")]
    fps: f64,
    /// Duration (s; default: the scene's run.duration).
    #[arg(long, value_name = "S")]
    duration: Option<f64>,
    /// Gaussian noise, standard deviation per coordinate (m).
    #[arg(long, default_value_t = 0.0, value_name = "M")]
    noise: f64,
    /// Probability that a marker is missing in a frame.
    #[arg(long, default_value_t = 0.0, value_name = "P")]
    dropout: f64,
    /// Probability that a marker is mis-tracked in a frame.
    #[arg(long, default_value_t = 0.0, value_name = "P")]
    outliers: f64,
    /// Distance of a mis-tracked marker from the truth (m).
    #[arg(long, default_value_t = 0.05, value_name = "M")]
    outlier_size: f64,
    /// Random seed: the same seed writes the same recording.
    #[arg(long, default_value_t = 0)]
    seed: u64,
}

pub fn run(args: Args) -> Result<(), Failure> {
    let opts = SynthOptions {
        fps: args.fps,
        duration: args.duration,
        noise: args.noise,
        dropout: args.dropout,
        outliers: args.outliers,
        outlier_size: args.outlier_size,
        seed: args.seed,
    };
    opts.validate().map_err(|e| Failure::Input(anyhow!(e)))?;
    super::refuse_input(Some(&args.output), &[&args.scene])?;
    let scene = Scene::from_path(&args.scene).map_err(|e| Failure::Input(e.into()))?;
    appell::scene::check_frames(
        &args.scene,
        opts.duration.unwrap_or(scene.duration),
        opts.fps,
        "--fps",
    )
    .map_err(|e| Failure::Input(e.into()))?;
    let syn = synth::synthesize(&scene, &opts).map_err(|e| {
        Failure::Run(anyhow!(e).context(format!("simulating {}", args.scene.display())))
    })?;
    synth::write_synthetic(&args.output, &syn, &scene).map_err(|e| Failure::Run(e.into()))?;
    let (ns, nb) = syn.recording.seen();
    let quiet = appell::output::names_stdout(&args.output);
    status!(
        quiet,
        "wrote {} frames at {} Hz to {} ({}); slider seen in {ns}, bob in {nb}; mu_kinetic {}, seed {}",
        syn.recording.len(),
        opts.fps,
        args.output.display(),
        synth::output_format(&args.output),
        scene.rig.mu_kinetic,
        opts.seed
    );
    if let Some(t) = syn.stopped_at {
        status!(
            quiet,
            "note: the run stopped at t = {t} s (a paradox it does not resolve); frames end there"
        );
    }
    Ok(())
}
