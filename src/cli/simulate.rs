//! `appell simulate SCENE.toml [--json] [--out FILE.csv]`.

use super::Failure;
use anyhow::anyhow;
use appell::report;
use appell::scene::Scene;
use appell::sim::simulate;
use std::path::PathBuf;

/// Arguments of `appell simulate`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Scene file (TOML with [rig], [initial], [run] and optional [output]).
    scene: PathBuf,
    /// Print one JSON object instead of the timeline.
    #[arg(long)]
    json: bool,
    /// Write the sampled trajectory to this CSV (at the scene's output.frame_rate, else
    /// 1000 Hz); a `.mcap` file holds the overlay's topics for Foxglove instead
    /// (docs/overlay.md).
    #[arg(long, value_name = "FILE.csv")]
    out: Option<PathBuf>,
}

pub fn run(args: Args) -> Result<(), Failure> {
    super::refuse_input(args.out.as_deref(), &[&args.scene])?;
    let mut scene = Scene::from_path(&args.scene).map_err(|e| Failure::Input(e.into()))?;
    if args.out.is_some() && scene.output.frame_rate.is_none() {
        // A trajectory was asked for on the command line: sample at a sensible default.
        scene.output.frame_rate = Some(1000.0);
        appell::scene::check_frames(&args.scene, scene.duration, 1000.0, "--out's 1000 Hz")
            .map_err(|e| Failure::Input(e.into()))?;
    }
    let sol = simulate(
        &scene.rig,
        &scene.initial,
        scene.duration,
        &scene.options,
        &scene.request(),
    )
    .map_err(|e| {
        Failure::Run(anyhow!(e).context(format!("simulating {}", args.scene.display())))
    })?;
    if let Some(path) = &args.out {
        appell::output::write_atomic(path, |w| {
            if appell::data::synth::output_format(path) == appell::data::Format::Mcap {
                Ok(report::overlay::write_simulation_overlay(w, &scene, &sol)?)
            } else {
                report::write_trajectory_csv(w, &scene.rig, &scene, &sol)
            }
        })
        .map_err(|e| Failure::Run(anyhow!(e).context(format!("writing {}", path.display()))))?;
    }
    // With the trajectory on stdout, the timeline and the JSON go to stderr.
    let quiet = args
        .out
        .as_deref()
        .is_some_and(appell::output::names_stdout);
    if args.json {
        status!(quiet, "{}", report::simulation_json(&scene, &sol));
    } else {
        let timeline = report::timeline(&scene, &sol);
        if quiet {
            note!("{}", timeline.trim_end());
        } else {
            out!("{timeline}");
        }
        if let Some(path) = &args.out {
            status!(
                quiet,
                "trajectory: {} samples written to {}",
                sol.samples.len(),
                path.display()
            );
        }
    }
    Ok(())
}
