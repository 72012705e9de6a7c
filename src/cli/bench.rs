//! `appell bench [SCENE.toml]`: time a scene on this machine; `appell bench --work-precision`:
//! run time against error for each integrator over a ladder of tolerances; `--fit`, `--skips`,
//! `--plan`, `--read`: the fit, skipped work, the planner, the recording readers.

use super::Failure;
use anyhow::anyhow;
use appell::bench::plot::WorkPrecisionPlot;
use appell::bench::time_scene;
use appell::bench::work_precision::{self, WorkPrecision, WpConfig, WpPoint};
use appell::report::plot::render;
use appell::scene::Scene;
use appell::sim::Method;
use std::path::PathBuf;

/// The paper's rig released from rest with the rod horizontal, 2 s at rtol 1e-10: the
/// reference scene of the simulator's performance target.
const REFERENCE_SCENE: &str = include_str!("../../configs/paper_rest_horizontal.toml");

/// Arguments of `appell bench`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Scene to time (default: the shipped paper scene, configs/paper_rest_horizontal.toml).
    #[arg(conflicts_with = "work_precision")]
    scene: Option<PathBuf>,
    /// Timed batches, 1 to 1000 (the median is reported; work-precision default 7).
    #[arg(long)]
    batches: Option<usize>,
    /// Print JSON.
    #[arg(long)]
    json: bool,
    /// Run the work-precision benchmark on the built-in reference scenes instead.
    #[arg(long)]
    work_precision: bool,
    /// Time the fit instead: a 2 s, 1000 Hz recording from a start 30% off in mu, over a
    /// ladder of integration tolerances (run time against mu error).
    #[arg(long, conflicts_with_all = ["work_precision", "scene"])]
    fit: bool,
    /// With --fit: the length ladder instead of the tolerance ladder, a whole fit of the
    /// paper scene per length (CPU time, peak memory, mu error): DURATION@FPS,... (default
    /// 2@1000,10@1000,60@1000,100@10000,1000@1000).
    #[arg(long, value_delimiter = ',', value_name = "S@HZ", num_args = 0.., requires = "fit")]
    lengths: Option<Vec<String>>,
    /// With --lengths: skip the profile intervals (--no-profile).
    #[arg(long, requires = "lengths")]
    no_profile: bool,
    /// Time what skipping unrequested work saves (slip monitoring on proven stick phases,
    /// dense samples, friction work, sensitivities).
    #[arg(long, conflicts_with_all = ["work_precision", "scene", "fit"])]
    skips: bool,
    /// Time the planner against its robustness estimate (the example plan with growing Monte
    /// Carlo draws).
    #[arg(long, conflicts_with_all = ["work_precision", "scene", "fit", "skips"])]
    plan: bool,
    /// Time reading a long recording (wide CSV, long CSV, MCAP) with the readers every command
    /// uses: median seconds and frames per second per format.
    #[arg(long, conflicts_with_all = ["work_precision", "scene", "fit", "skips", "plan"])]
    read: bool,
    /// Time the joint fit of a directory's recordings (`fit --joint DIR`) against their number:
    /// the first 5, 10 and 20 (or --counts), median CPU and wall time of --batches runs (3).
    #[arg(long, value_name = "DIR", requires = "rig", conflicts_with_all = ["work_precision", "scene", "fit", "skips", "plan", "read"])]
    joint: Option<PathBuf>,
    /// Joint benchmark: the rig file of its recordings.
    #[arg(long, value_name = "RIG.toml", requires = "joint")]
    rig: Option<PathBuf>,
    /// Joint benchmark: how many releases to fit together, e.g. 5,10,20.
    #[arg(long, value_delimiter = ',', requires = "joint")]
    counts: Vec<usize>,
    /// Read benchmark: frames in the recording (10 kHz), 2 to 10^7.
    #[arg(long, default_value_t = appell::bench::read::DEFAULT_FRAMES, requires = "read")]
    frames: usize,
    /// Work-precision: draw run time against error (log axes) to this SVG or PNG.
    #[arg(long, value_name = "FILE.svg", requires = "work_precision")]
    plot: Option<PathBuf>,
    /// Work-precision: comma-separated tolerance ladder, each in [1e-14, 0.1], at most 32
    /// (default 1e-4,1e-5,...,1e-12).
    #[arg(long, value_delimiter = ',')]
    rtols: Vec<f64>,
    /// Work-precision: comma-separated scene names (default all: paper, unequal, rotation,
    /// near_critical, stuck, frictionless).
    #[arg(long, value_delimiter = ',', requires = "work_precision")]
    scenes: Vec<String>,
    /// Work-precision: wall time spent timing each point (s), 0 to 10.
    #[arg(long, default_value_t = 0.03, requires = "work_precision")]
    seconds_per_point: f64,
}

/// The most timed batches any benchmark takes (`--batches`).
const MAX_BATCHES: usize = 1000;

/// The most frames the read benchmark writes and reads (`--frames`): about 1.5 GB of files.
const MAX_FRAMES: usize = 10_000_000;

/// The longest wall time a work-precision point may be timed for (`--seconds-per-point`, s).
const MAX_SECONDS_PER_POINT: f64 = 10.0;

/// The tolerances the work-precision ladder may hold (`--rtols`), and how many.
const RTOL_RANGE: (f64, f64) = (1e-14, 0.1);

/// The most tolerances in the work-precision ladder.
const MAX_RTOLS: usize = 32;

/// Every bench flag bounded like any other input, before any work: bad input (exit 2) naming
/// the flag, the value and the range.
fn check_flags(args: &Args) -> Result<(), Failure> {
    let bad = |m: String| Err(Failure::Input(anyhow!(m)));
    if let Some(b) = args.batches {
        if !(1..=MAX_BATCHES).contains(&b) {
            return bad(format!(
                "--batches {b}: expected a whole number from 1 to {MAX_BATCHES}"
            ));
        }
    }
    if args.read && !(2..=MAX_FRAMES).contains(&args.frames) {
        return bad(format!(
            "--frames {}: expected a whole number from 2 to {MAX_FRAMES} (10 kHz, about 150 bytes a frame over the three files)",
            args.frames
        ));
    }
    let s = args.seconds_per_point;
    if !(s.is_finite() && (0.0..=MAX_SECONDS_PER_POINT).contains(&s)) {
        // 1e300 as 1e300, not three hundred digits.
        let shown = if s.is_finite() && s.abs() >= 1e6 {
            format!("{s:e}")
        } else {
            format!("{s}")
        };
        return bad(format!(
            "--seconds-per-point {shown}: expected seconds from 0 to {MAX_SECONDS_PER_POINT}"
        ));
    }
    if args.rtols.len() > MAX_RTOLS {
        return bad(format!(
            "--rtols: {} tolerances, expected at most {MAX_RTOLS}",
            args.rtols.len()
        ));
    }
    let (lo, hi) = RTOL_RANGE;
    if let Some(r) = args.rtols.iter().find(|r| !(lo..=hi).contains(*r)) {
        return bad(format!("--rtols: {r:e} is not in [{lo:e}, {hi:e}]"));
    }
    if args.counts.len() > MAX_RTOLS {
        return bad(format!(
            "--counts: {} counts, expected at most {MAX_RTOLS}",
            args.counts.len()
        ));
    }
    Ok(())
}

/// A validated work-precision run, from the parsed arguments.
fn wp_config(args: &Args) -> Result<WpConfig, Failure> {
    let mut config = WpConfig::default();
    if !args.rtols.is_empty() {
        if let Some(bad) = args.rtols.iter().find(|r| !(**r > 0.0 && **r < 1.0)) {
            return Err(Failure::Input(anyhow!("--rtols: {bad} is not in (0, 1)")));
        }
        config.rtols = args.rtols.clone();
    }
    if !args.scenes.is_empty() {
        let known: Vec<_> = config.scenes.iter().map(|s| s.name).collect();
        if let Some(bad) = args.scenes.iter().find(|s| !known.contains(&s.as_str())) {
            return Err(Failure::Input(anyhow!(
                "--scenes: unknown scene {bad:?} (known: {})",
                known.join(", ")
            )));
        }
        config
            .scenes
            .retain(|s| args.scenes.iter().any(|n| n == s.name));
    }
    if !(args.seconds_per_point.is_finite() && args.seconds_per_point >= 0.0) {
        return Err(Failure::Input(anyhow!(
            "--seconds-per-point must be a finite number >= 0"
        )));
    }
    config.seconds_per_point = args.seconds_per_point;
    if let Some(b) = args.batches {
        config.batches = b.max(1);
    }
    config.methods = Method::ALL.to_vec();
    Ok(config)
}

fn fmt_opt(v: Option<f64>) -> String {
    v.map_or_else(|| "-".to_owned(), |v| format!("{v:.1e}"))
}

fn row(p: &WpPoint) -> String {
    format!(
        "{:<13} {:<7} {:>7.0e} {:>11} {:>10} {:>10} {:>10} {:>10} {:>9} {:>7} {:>8}{}",
        p.scene,
        p.method,
        p.rtol,
        p.seconds
            .map_or_else(|| "-".to_owned(), |s| format!("{:.1}", s * 1e6)),
        fmt_opt(p.event_time_error_s),
        fmt_opt(p.state_error),
        fmt_opt(p.marker_error_m),
        fmt_opt(p.energy_defect),
        fmt_opt(p.momentum_defect),
        p.steps,
        p.rhs_evals,
        p.failure
            .as_ref()
            .map_or_else(String::new, |f| format!("  FAILED: {f}"))
    )
}

fn print_summary(wp: &WorkPrecision) {
    outln!(
        "\nreferences (DP5 vs DOP853 at rtol {:e}; the floor of the errors above):",
        work_precision::REFERENCE_RTOL
    );
    for r in &wp.references {
        outln!(
            "  {:<13} {} events, event times agree to {}, final state to {:.1e}{}  ({})",
            r.scene,
            r.events,
            fmt_opt(r.event_time_disagreement_s),
            r.state_disagreement,
            r.closed_form_error
                .map_or_else(String::new, |e| format!(", closed form to {e:.1e}")),
            r.about
        );
    }
    outln!("\ngoals:");
    for g in &wp.goals {
        let verdict = match g.met {
            Some(true) => "met",
            Some(false) => "NOT met",
            None => "undecided",
        };
        outln!("  {verdict:<9} {:<13} {}", g.scene, g.detail);
    }
}

fn run_work_precision(args: &Args) -> Result<(), Failure> {
    let config = wp_config(args)?;
    if !args.json {
        outln!(
            "{:<13} {:<7} {:>7} {:>11} {:>10} {:>10} {:>10} {:>10} {:>9} {:>7} {:>8}",
            "scene",
            "method",
            "rtol",
            "median us",
            "event [s]",
            "state",
            "marker [m]",
            "energy",
            "momentum",
            "steps",
            "rhs"
        );
    }
    let json = args.json;
    let wp = work_precision::run(&config, |p| {
        if !json {
            outln!("{}", row(p));
        }
    });
    if let Some(path) = &args.plot {
        render(path, &WorkPrecisionPlot { result: &wp })
            .map_err(|e| Failure::Run(anyhow!(e).context("drawing the work-precision plot")))?;
    }
    if json {
        outln!(
            "{}",
            serde_json::to_string(&wp).map_err(|e| Failure::Run(e.into()))?
        );
    } else {
        print_summary(&wp);
        if let Some(path) = &args.plot {
            outln!("\nplot written to {}", path.display());
        }
    }
    Ok(())
}

/// `appell bench --fit --lengths`: a whole fit per recording length.
fn run_lengths(args: &Args, lengths: &[String]) -> Result<(), Failure> {
    let parse = |s: &str| -> Option<(f64, f64)> {
        let (d, f) = s.split_once('@')?;
        Some((d.trim().parse().ok()?, f.trim().parse().ok()?))
    };
    let ladder: Vec<(f64, f64)> = if lengths.is_empty() {
        vec![
            (2.0, 1000.0),
            (10.0, 1000.0),
            (60.0, 1000.0),
            (100.0, 10000.0),
            (1000.0, 1000.0),
        ]
    } else {
        lengths
            .iter()
            .map(|s| {
                parse(s).ok_or_else(|| {
                    Failure::Input(anyhow!(
                        "--lengths: expected DURATION@FPS such as 60@1000, got {s:?}"
                    ))
                })
            })
            .collect::<Result<_, _>>()?
    };
    if let Some((d, f)) = ladder
        .iter()
        .find(|(d, f)| !(*d > 0.0 && *f > 0.0 && d * f <= 1e7))
    {
        return Err(Failure::Input(anyhow!(
            "--lengths: each length needs a duration and a frame rate above 0 and at most 1e7 frames, got {d} s at {f} Hz"
        )));
    }
    let points = appell::bench::fit::length_ladder(&ladder, !args.no_profile)
        .map_err(|e| Failure::Run(anyhow!(e)))?;
    if args.json {
        outln!("{}", serde_json::json!({"fit_lengths": points}));
        return Ok(());
    }
    outln!(
        "whole fits (default settings{}) of the paper scene, 0.5 mm noise, mu = 0.35:",
        if args.no_profile {
            ", --no-profile"
        } else {
            ""
        }
    );
    outln!(
        "{:>9} {:>7} {:>9} {:>8} {:>8} {:>9} {:>12} {:>10} {:>11}",
        "length s",
        "Hz",
        "frames",
        "CPU s",
        "wall s",
        "peak MB",
        "mu",
        "stderr",
        "mu - 0.35"
    );
    for p in points {
        outln!(
            "{:>9} {:>7} {:>9} {:>8.2} {:>8.2} {:>9} {:>12.8} {:>10.2e} {:>11.2e}",
            p.duration,
            p.fps,
            p.frames,
            p.cpu_seconds,
            p.wall_seconds,
            p.peak_mb.map_or("-".into(), |m| format!("{m:.0}")),
            p.mu,
            p.stderr,
            p.mu_error
        );
    }
    Ok(())
}

/// `appell bench --fit`: the fit's run time against its mu error.
fn run_fit(args: &Args) -> Result<(), Failure> {
    if let Some(lengths) = &args.lengths {
        return run_lengths(args, lengths);
    }
    let rtols = if args.rtols.is_empty() {
        vec![1e-5, 1e-6, 1e-7, 1e-8, 1e-10]
    } else {
        args.rtols.clone()
    };
    let points = appell::bench::fit::fit_benchmark(&rtols, args.batches.unwrap_or(7))
        .map_err(|e| Failure::Run(anyhow!(e)))?;
    if args.json {
        outln!("{}", serde_json::json!({"fit": points}));
        return Ok(());
    }
    outln!("fit of a 2 s, 1000 Hz two-marker recording (example rig, mu = 0.12, 0.2 mm noise), start 30% off in mu:");
    outln!(
        "{:>8} {:>6} {:>8} {:>11} {:>12} {:>10} {:>12} {:>18}",
        "rtol",
        "model",
        "profile",
        "median ms",
        "mu",
        "stderr",
        "|mu - 0.12|",
        "integration error"
    );
    for p in points {
        outln!(
            "{:>8.0e} {:>6} {:>8} {:>11.2} {:>12.8} {:>10.2e} {:>12.2e} {:>18.2e}",
            p.rtol,
            if p.plain { "plain" } else { "full" },
            p.profile,
            p.seconds * 1e3,
            p.mu,
            p.stderr,
            p.mu_error,
            p.integration_error
        );
    }
    Ok(())
}

/// `appell bench --skips`: each skip, timed with and without it.
fn run_skips(args: &Args) -> Result<(), Failure> {
    let cases = appell::bench::skips::skip_benchmark(args.batches.unwrap_or(7));
    if args.json {
        outln!("{}", serde_json::json!({"skips": cases}));
        return Ok(());
    }
    outln!(
        "{:>12} {:>12} {:>7}  skipped work",
        "with skip",
        "without",
        "saved"
    );
    for c in cases {
        outln!(
            "{:>9.1} us {:>9.1} us {:>6.0}%  {}",
            c.with_skip_s * 1e6,
            c.without_skip_s * 1e6,
            100.0 * (1.0 - c.with_skip_s / c.without_skip_s),
            c.case
        );
    }
    Ok(())
}

/// `appell bench --plan`: run time against robustness.
fn run_plan(args: &Args) -> Result<(), Failure> {
    let ladder = [(8, 50), (16, 100), (32, 400), (64, 1600)];
    let points =
        appell::bench::plan::plan_benchmark(&ladder).map_err(|e| Failure::Run(anyhow!(e)))?;
    if args.json {
        outln!("{}", serde_json::json!({"plan": points}));
        return Ok(());
    }
    outln!("example plan (configs/plan_example.toml), top proposal:");
    outln!(
        "{:>6} {:>8} {:>9} {:>11} {:>9} {:>14}",
        "draws",
        "verify",
        "seconds",
        "robustness",
        "observed",
        "pred. stderr"
    );
    for p in points {
        outln!(
            "{:>6} {:>8} {:>9.3} {:>11.4} {:>9.4} {:>14.3e}",
            p.draws,
            p.verify_draws,
            p.seconds,
            p.robustness,
            p.robustness_observed,
            p.predicted_mu_stderr
        );
    }
    Ok(())
}

/// `appell bench --read`: reading time per format.
fn run_read(args: &Args) -> Result<(), Failure> {
    let timings = appell::bench::read::read_benchmark(args.frames, args.batches.unwrap_or(5))
        .map_err(|e| Failure::Run(anyhow!(e)))?;
    if args.json {
        outln!("{}", serde_json::json!({"read": timings}));
        return Ok(());
    }
    outln!(
        "reading a {}-frame recording (paper scene, {} Hz, 0.5 mm noise), median of {} reads:",
        args.frames,
        appell::bench::read::FPS,
        timings.first().map_or(0, |t| t.runs)
    );
    outln!(
        "{:>6} {:>10} {:>10} {:>10} {:>13}",
        "format",
        "MB",
        "median s",
        "fastest s",
        "M frames/s"
    );
    for t in timings {
        outln!(
            "{:>6} {:>10.1} {:>10.3} {:>10.3} {:>13.2}",
            t.format,
            t.bytes as f64 / 1e6,
            t.median_s,
            t.min_s,
            t.frames_per_s / 1e6
        );
    }
    Ok(())
}

pub fn run(args: Args) -> Result<(), Failure> {
    check_flags(&args)?;
    if let Some(dir) = &args.joint {
        return run_joint(&args, dir);
    }
    if args.read {
        return run_read(&args);
    }
    if args.plan {
        return run_plan(&args);
    }
    if args.skips {
        return run_skips(&args);
    }
    if args.fit {
        return run_fit(&args);
    }
    if args.work_precision {
        return run_work_precision(&args);
    }
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
    let timing =
        time_scene(&scene, args.batches.unwrap_or(31)).map_err(|e| Failure::Run(anyhow!(e)))?;
    if args.json {
        outln!(
            "{}",
            serde_json::json!({"scene": name, "method": scene.options.method.name(), "rtol": scene.options.rtol, "timing": timing})
        );
    } else {
        outln!(
            "{name}: {} rtol {:e}: median {:.1} us per simulation (fastest {:.1} us, {} runs); {} steps, {} rejected, {} rhs evaluations, {} events{}",
            scene.options.method.name(),
            scene.options.rtol,
            timing.median_s * 1e6,
            timing.min_s * 1e6,
            timing.runs,
            timing.stats.steps,
            timing.stats.rejected,
            timing.stats.rhs_evals,
            timing.stats.events,
            appell::report::closed_form_note(&timing.stats)
        );
    }
    Ok(())
}

/// `--joint DIR`: the joint fit's cost against the number of releases.
fn run_joint(args: &Args, dir: &std::path::Path) -> Result<(), Failure> {
    use appell::data::ReadOptions;
    use appell::fit::joint::Release;
    let rig_path = args
        .rig
        .as_ref()
        .ok_or_else(|| Failure::Input(anyhow!("--joint needs --rig")))?;
    let rig = appell::scene::RigFile::load_for_fit(rig_path, 0.3)
        .map_err(|e| Failure::Input(e.into()))?;
    // The recordings `fit --joint DIR` would take, in the same order.
    let files = super::fit::directory_files(dir, false)?;
    let counts = if args.counts.is_empty() {
        vec![5, 10, 20]
    } else {
        args.counts.clone()
    };
    let need = counts.iter().copied().max().unwrap_or(0);
    if counts.iter().any(|&n| n < 2) || files.len() < need {
        return Err(Failure::Input(anyhow!(
            "{}: --counts {:?}: each count must be from 2 to the directory's {} recordings",
            dir.display(),
            counts,
            files.len()
        )));
    }
    let releases = files[..need]
        .iter()
        .map(|f| {
            let obs = super::fit::read_for_rig(
                std::slice::from_ref(f),
                &ReadOptions::default(),
                rig_path,
                &rig,
            )?;
            Ok(Release {
                name: f.display().to_string(),
                obs,
            })
        })
        .collect::<Result<Vec<_>, Failure>>()?;
    let points =
        appell::bench::fit::joint_benchmark(&releases, &rig, &counts, args.batches.unwrap_or(3))
            .map_err(|e| Failure::Run(anyhow!(e)))?;
    if args.json {
        outln!("{}", serde_json::json!({"joint": points}));
        return Ok(());
    }
    outln!(
        "joint fit (fit --joint, default settings) of the first N recordings of {}:",
        dir.display()
    );
    outln!(
        "{:>9} {:>12} {:>13} {:>12} {:>10}",
        "releases",
        "median CPU s",
        "median wall s",
        "mu",
        "stderr"
    );
    for p in points {
        outln!(
            "{:>9} {:>12.2} {:>13.2} {:>12.8} {:>10.2e}",
            p.releases,
            p.cpu_seconds,
            p.wall_seconds,
            p.mu,
            p.stderr
        );
    }
    Ok(())
}
