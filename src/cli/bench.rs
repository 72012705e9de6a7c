//! `appell bench [SCENE.toml]`: time a scene on this machine.

use super::Failure;
use anyhow::anyhow;
use appell::bench::time_scene;
use appell::scene::Scene;
use std::path::PathBuf;

/// The paper's rig released from rest with the rod horizontal, 2 s at rtol 1e-10: the
/// reference scene of the simulator's performance target.
const REFERENCE_SCENE: &str = include_str!("../../configs/paper_rest_horizontal.toml");

/// Arguments of `appell bench`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Scene to time (default: the shipped paper scene, configs/paper_rest_horizontal.toml).
    scene: Option<PathBuf>,
    /// Timed batches (the median is reported).
    #[arg(long, default_value_t = 31)]
    batches: usize,
    /// Print JSON.
    #[arg(long)]
    json: bool,
}

pub fn run(args: Args) -> Result<(), Failure> {
    let (scene, name) = match &args.scene {
        Some(p) => (
            Scene::from_path(p).map_err(|e| Failure::Input(e.into()))?,
            p.display().to_string(),
        ),
        None => (
            Scene::from_toml(
                REFERENCE_SCENE,
                "configs/paper_rest_horizontal.toml".as_ref(),
            )
            .map_err(|e| Failure::Input(e.into()))?,
            "configs/paper_rest_horizontal.toml (built in)".to_owned(),
        ),
    };
    let timing = time_scene(&scene, args.batches).map_err(|e| Failure::Run(anyhow!(e)))?;
    if args.json {
        outln!(
            "{}",
            serde_json::json!({"scene": name, "method": scene.options.method.name(), "rtol": scene.options.rtol, "timing": timing})
        );
    } else {
        outln!(
            "{name}: {} rtol {:e}: median {:.1} us per simulation (fastest {:.1} us, {} runs); {} steps, {} rejected, {} rhs evaluations, {} events",
            scene.options.method.name(),
            scene.options.rtol,
            timing.median_s * 1e6,
            timing.min_s * 1e6,
            timing.runs,
            timing.stats.steps,
            timing.stats.rejected,
            timing.stats.rhs_evals,
            timing.stats.events
        );
    }
    Ok(())
}
