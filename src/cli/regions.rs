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

pub fn run(args: Args) -> Result<(), Failure> {
    // Validate every value before any work.
    super::refuse_input(args.plot.as_deref(), &[&args.rig])?;
    if let Some(path) = &args.plot {
        ImageFormat::from_path(path).map_err(|e| Failure::Input(e.into()))?;
    }
    appell::pipeline::check_portrait(args.trajectories, args.duration)
        .map_err(|e| Failure::Input(anyhow!(e)))?;
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
