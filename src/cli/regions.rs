//! `appell regions RIG.toml [--json] [--plot FILE.svg|FILE.png] [--trajectories N]`.

use super::Failure;
use anyhow::anyhow;
use appell::model::regions::RegionMap;
use appell::report::plot::{render, ImageFormat};
use appell::report::regions::{
    figure_window, phase_portrait, regions_json, regions_summary, PortraitOptions, RegionFigure,
};
use appell::scene::RigFile;
use std::path::PathBuf;

/// Arguments of `appell regions`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Rig file (TOML with a [rig] section, as in a scene).
    rig: PathBuf,
    /// Print one JSON object instead of the summary.
    #[arg(long)]
    json: bool,
    /// Draw the regions and phase portraits in the (theta, theta') plane (.svg or .png).
    #[arg(long, value_name = "FILE.svg|FILE.png")]
    plot: Option<PathBuf>,
    /// Number of phase-portrait trajectories to simulate (0: none).
    #[arg(long, value_name = "N", default_value_t = 8)]
    trajectories: usize,
    /// Duration of each trajectory (s).
    #[arg(long, value_name = "SECONDS", default_value_t = 3.0)]
    duration: f64,
}

/// The most phase-portrait trajectories one run draws.
const MAX_TRAJECTORIES: usize = 1000;

/// The most simulated seconds one run's portraits hold (trajectories x duration): each keeps
/// 1000 samples a second (4.0e7 bytes here at most), and the integration's work is this times
/// the rig's rate, at most 100 /s (`scene::check_time_scale`). Measured at the bound: the
/// paper rig about 0.7 s; a rig damped at 95 /s about 5 s (1000 runs of 600 s took 40 s and
/// 300 s).
const MAX_PORTRAIT_SECONDS: f64 = 1e4;

pub fn run(args: Args) -> Result<(), Failure> {
    // Validate every value before any work.
    super::refuse_input(args.plot.as_deref(), &[&args.rig])?;
    if let Some(path) = &args.plot {
        ImageFormat::from_path(path).map_err(|e| Failure::Input(e.into()))?;
    }
    if !(args.duration.is_finite() && args.duration > 0.0 && args.duration <= 600.0) {
        return Err(Failure::Input(anyhow!(
            "--duration must be in (0, 600] s, got {}",
            args.duration
        )));
    }
    if args.trajectories > MAX_TRAJECTORIES {
        return Err(Failure::Input(anyhow!(
            "--trajectories must be at most {MAX_TRAJECTORIES}, got {}",
            args.trajectories
        )));
    }
    let seconds = args.trajectories as f64 * args.duration;
    if seconds > MAX_PORTRAIT_SECONDS {
        return Err(Failure::Input(anyhow!(
            "--trajectories {} x --duration {} s is {seconds:e} simulated seconds, more than the {MAX_PORTRAIT_SECONDS:e} one run draws (1000 samples a second each): lower either",
            args.trajectories,
            args.duration
        )));
    }
    let rig = RigFile::load(&args.rig).map_err(|e| Failure::Input(e.into()))?;
    let window = figure_window(&rig);
    let map = RegionMap::new(&rig, &window);
    let trajectories = phase_portrait(
        &rig,
        &PortraitOptions {
            trajectories: args.trajectories,
            duration: args.duration,
            ..PortraitOptions::default()
        },
    );
    if let Some(path) = &args.plot {
        let figure = RegionFigure::new(&rig, &map, &trajectories);
        render(path, &figure).map_err(|e| {
            Failure::Run(anyhow!(e).context(format!("plotting {}", path.display())))
        })?;
    }
    if args.json {
        outln!("{}", regions_json(&map, &trajectories));
    } else {
        out!("{}", regions_summary(&rig, &map, &trajectories));
        if let Some(path) = &args.plot {
            outln!("figure written to {}", path.display());
        }
    }
    Ok(())
}
