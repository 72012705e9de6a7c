//! `appell plan PLAN.toml [--json] [--plot FILE.svg|FILE.png] [--after FIT.json]`: releases
//! that make the wanted transitions observable, ranked by the predicted standard error of mu
//! or, when friction laws are weighed, by how surely a fit would tell them apart.

use super::Failure;
use anyhow::anyhow;
use appell::plan::prior::{self, Prior};
use appell::plan::rig_match;
use appell::plan::{plan_with_progress, PlanSpec};
use appell::report::plan::{plan_json, plan_table, PlanFigure};
use appell::report::plot::{render, ImageFormat};
use indicatif::{ProgressBar, ProgressStyle};
use std::path::PathBuf;

/// Arguments of `appell plan`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Plan file (TOML: [rig], [friction], [camera], [release], [goal], optional [search]).
    plan: PathBuf,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    json: bool,
    /// Draw the proposals in the (theta, theta') plane over the stick region (.svg or .png).
    #[arg(long, value_name = "FILE.svg|FILE.png")]
    plot: Option<PathBuf>,
    /// Plan the next release after a fit (`appell fit --json`, single or `--joint`): its mu
    /// and standard error for the robustness draws, its chosen nuisances in the simulated
    /// rig, and its covariance as what is already known. When the fit left friction laws
    /// open (its law table), releases are ranked by how many pairs of those laws a joint fit
    /// of both recordings is expected to tell apart; otherwise by mu's standard error after
    /// adding them (docs/plan.md, "Telling laws apart").
    #[arg(long, value_name = "FIT.json")]
    after: Option<PathBuf>,
}

pub fn run(args: Args) -> Result<(), Failure> {
    let inputs: Vec<&std::path::Path> = std::iter::once(args.plan.as_path())
        .chain(args.after.as_deref())
        .collect();
    super::refuse_input(args.plot.as_deref(), &inputs)?;
    if let Some(path) = &args.plot {
        ImageFormat::from_path(path).map_err(|e| Failure::Input(e.into()))?;
    }
    let mut spec = PlanSpec::from_path(&args.plan).map_err(|e| Failure::Input(e.into()))?;
    if let Some(fit) = &args.after {
        let json = prior::read_json(fit).map_err(|e| Failure::Input(e.into()))?;
        // A fit of another rig is refused before its values enter the plan's rig.
        let notes = rig_match::check(&json, fit, &spec.rig_file, &args.plan)
            .map_err(|e| Failure::Input(e.into()))?;
        for n in notes {
            note!("note: {n}");
        }
        let prior = Prior::from_json(&json, fit).map_err(|e| Failure::Input(e.into()))?;
        prior
            .apply(&mut spec)
            .map_err(|e| Failure::Input(e.into()))?;
        spec.check_work(&args.plan, Some(fit))
            .map_err(|e| Failure::Input(e.into()))?;
        spec.prior = Some(prior);
    }
    // Drawn only when stderr is a terminal (indicatif hides it otherwise).
    let bar = ProgressBar::new(0);
    bar.set_style(
        ProgressStyle::with_template("{bar:40} {pos}/{len} releases screened ({elapsed})")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let report = plan_with_progress(&spec, &bar).map_err(|e| Failure::Run(e.into()))?;
    if let Some(path) = &args.plot {
        render(path, &PlanFigure { report: &report }).map_err(|e| {
            Failure::Run(anyhow!(e).context(format!("plotting {}", path.display())))
        })?;
    }
    if args.json {
        outln!("{}", plan_json(&report));
    } else {
        out!("{}", plan_table(&report));
        if let Some(path) = &args.plot {
            outln!("figure written to {}", path.display());
        }
    }
    Ok(())
}
