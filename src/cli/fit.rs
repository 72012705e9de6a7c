//! `appell fit RECORDING... --rig RIG.toml`: estimate mu and the initial state; a directory of
//! recordings is fitted in parallel, one JSON line per recording.

use super::Failure;
use anyhow::anyhow;
use appell::data::Provenance;
use appell::data::ReadOptions;
use appell::fit::joint::JointSettings;
use appell::fit::{FitReport, Observations};
use appell::model::Rig;
use appell::pipeline::{self, provenance, FitArgs, FitFailure, FitSetup, RecordingArgs};
use appell::report::fit::{answer, fit_json, fit_text, FitFigure, FrictionFigure};
use appell::report::joint::{joint_json, joint_text, JointFigure};
use appell::report::overlay::{self, OverlayFormat};
use appell::report::plot::render;
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;
use std::path::{Path, PathBuf};

/// Arguments of `appell fit`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Recording file(s) (Tracker: one file per marker), or one directory of recordings.
    #[arg(required_unless_present = "release", value_name = "RECORDING")]
    inputs: Vec<PathBuf>,
    /// Fit the recordings together as releases of one rig: the friction law, tilt, viscous
    /// terms and the pendulum shared, each release's state (and camera) its own. Give a
    /// directory, or the releases with --release.
    #[arg(long)]
    joint: bool,
    /// One release of a joint fit (repeat it): a recording file, or a Tracker pair as
    /// `SLIDER.txt,BOB.txt`.
    #[arg(
        long,
        value_name = "FILE[,FILE]",
        requires = "joint",
        conflicts_with = "inputs"
    )]
    release: Vec<String>,
    /// Joint fit: one camera for every release (its scale and marker offsets shared).
    #[arg(long, requires = "joint")]
    same_camera: bool,
    /// Joint fit: a release that cannot be read or fitted is named and left out, and the
    /// others are fitted.
    #[arg(long, requires = "joint")]
    keep_going: bool,
    /// Rig file: the [rig] section of a scene; mu values there are only starting guesses.
    #[arg(long, value_name = "RIG.toml")]
    rig: PathBuf,
    /// Print JSON (one object; one line per recording for a directory).
    #[arg(long)]
    json: bool,
    /// Draw data, fit, residuals and mode bands (SVG or PNG by extension).
    #[arg(long, value_name = "FILE.svg")]
    plot: Option<PathBuf>,
    /// Draw the friction figure: each slide's friction coefficient |F| / |N| against its
    /// sliding speed, both directions, with the chosen and the compared laws (SVG or PNG).
    #[arg(long, value_name = "FILE.svg")]
    friction_plot: Option<PathBuf>,
    /// Write the fit back beside the recording: `.mcap` for Foxglove (recorded and fitted
    /// markers, residuals, modes, forces, events and the answer in the recording's clock), or
    /// `.csv`, the model's markers in the recording's own units, axes and time column, as its
    /// tool's table (Tracker, DeepLabCut, Motive; docs/overlay.md).
    #[arg(long, value_name = "FILE.mcap|FILE.csv")]
    overlay: Option<PathBuf>,
    /// With an `.mcap` overlay of a recording read from MCAP: copy the recording's own topics
    /// (channels, schemas and messages as they are) into the overlay beside its own.
    #[arg(long, requires = "overlay")]
    overlay_with_input: bool,
    #[command(flatten)]
    fit: FitArgs,
    #[command(flatten)]
    recording: RecordingArgs,
}

/// A recording's observations, provenance and fit, or why not.
type Fitted = Result<(Observations, Provenance, FitReport), Failure>;

/// A recording read and checked before any fitting work ([`pipeline::read_for_rig`]), its
/// notes on stderr (`fit`, `fit --joint`, `bench --joint`).
pub(super) fn read_for_rig(
    paths: &[PathBuf],
    opts: &ReadOptions,
    rig_path: &Path,
    rig: &Rig<f64>,
) -> Result<Observations, Failure> {
    let (obs, notes) =
        pipeline::read_for_rig(paths, opts, rig_path, rig).map_err(Failure::Input)?;
    for n in notes {
        note!("note: {n}");
    }
    Ok(obs)
}

/// The library's failure as the command's (exit code 2 for input, 1 for the run).
fn failure(e: FitFailure) -> Failure {
    match e {
        FitFailure::Input(e) => Failure::Input(e),
        FitFailure::Run(e) => Failure::Run(e),
    }
}

/// A directory's recordings ([`pipeline::directory_files`]), the skipped files noted on stderr.
pub(super) fn directory_files(dir: &Path, format_given: bool) -> Result<Vec<PathBuf>, Failure> {
    let (files, notes) = pipeline::directory_files(dir, format_given).map_err(Failure::Input)?;
    for n in notes {
        note!("note: {n}");
    }
    Ok(files)
}

fn fit_one(paths: &[PathBuf], opts: &ReadOptions, setup: &FitSetup, keep: bool) -> Fitted {
    let (obs, provenance, report, notes) =
        pipeline::fit_recording(paths, opts, setup, keep).map_err(failure)?;
    for n in notes {
        note!("note: {n}");
    }
    Ok((obs, provenance, report))
}

/// Every file the fit reads: the rig, the recordings (a directory's entries), the releases.
fn fit_inputs(args: &Args) -> Vec<PathBuf> {
    let mut files = vec![args.rig.clone()];
    for input in &args.inputs {
        match std::fs::read_dir(input) {
            Ok(dir) => files.extend(dir.filter_map(|e| e.ok()).map(|e| e.path())),
            Err(_) => files.push(input.clone()),
        }
    }
    files.extend(
        args.release
            .iter()
            .flat_map(|r| r.split(',').map(PathBuf::from)),
    );
    files
}

pub fn run(args: Args) -> Result<(), Failure> {
    // Every file the command writes: none may be an input, and two naming one file would leave
    // one of them, both said written.
    let outputs: Vec<(&str, &Path)> = [
        ("--plot", &args.plot),
        ("--friction-plot", &args.friction_plot),
        ("--overlay", &args.overlay),
    ]
    .into_iter()
    .filter_map(|(flag, p)| Some((flag, p.as_deref()?)))
    .collect();
    let inputs = fit_inputs(&args);
    for (_, out) in &outputs {
        super::refuse_input(Some(out), &inputs)?;
    }
    appell::output::refuse_same_output(&outputs).map_err(|e| Failure::Input(e.into()))?;
    let opts = args
        .recording
        .resolve()
        .map_err(|e| Failure::Input(anyhow!(e)))?;
    let setup =
        FitSetup::new(&args.rig, &args.fit, args.recording.scale).map_err(Failure::Input)?;
    for p in [&args.plot, &args.friction_plot].into_iter().flatten() {
        appell::report::plot::ImageFormat::from_path(p).map_err(|e| Failure::Input(e.into()))?;
    }
    if let Some(p) = &args.overlay {
        let format = OverlayFormat::from_path(p).map_err(|e| Failure::Input(e.into()))?;
        if args.overlay_with_input {
            with_input_allowed(&args, p, format, &opts)?;
        }
    }
    let settings = &setup.settings;
    if args.joint {
        return run_joint(&args, &opts, &setup);
    }
    if args.inputs.len() == 1 && args.inputs[0].is_dir() {
        if let Some(flag) = [
            (args.plot.is_some(), "--plot"),
            (args.friction_plot.is_some(), "--friction-plot"),
            (args.overlay.is_some(), "--overlay"),
        ]
        .iter()
        .find_map(|(given, flag)| given.then_some(flag))
        {
            return Err(Failure::Input(anyhow!(
                "{flag} draws one recording's fit, and {} is a directory: give one recording, or --joint for the releases' joint figure",
                args.inputs[0].display()
            )));
        }
        let files = directory_files(&args.inputs[0], opts.format.is_some())?;
        let bar = ProgressBar::new(files.len() as u64);
        bar.set_style(
            ProgressStyle::with_template("{bar:40} {pos}/{len} recordings fitted ({elapsed})")
                .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        let results: Vec<(PathBuf, Fitted)> = files
            .par_iter()
            .map(|f| {
                let r = fit_one(std::slice::from_ref(f), &opts, &setup, false);
                bar.inc(1);
                (f.clone(), r)
            })
            .collect();
        bar.finish_and_clear();
        let mut failed = 0;
        for (file, r) in results {
            match r {
                Ok((_, _, rep)) => {
                    // A failed result is reported, and is no answer: it counts toward exit 1.
                    failed += usize::from(rep.failed.is_some());
                    let mut v = fit_json(&rep);
                    v["recording"] = serde_json::json!(file.display().to_string());
                    provenance(&mut v, std::slice::from_ref(&file), &args.rig);
                    if args.json {
                        outln!("{v}");
                    } else {
                        // The answer line keeps the verdict (adequate or limited, and why).
                        outln!("{}: {}", file.display(), answer(&rep));
                    }
                }
                Err(Failure::Input(e) | Failure::Run(e)) => {
                    failed += 1;
                    // The messages name the file already (once).
                    let message = super::messages(&e).join(": ");
                    if args.json {
                        outln!(
                            "{}",
                            serde_json::json!({"recording": file.display().to_string(), "error": message})
                        );
                    } else if message.contains(&file.display().to_string()) {
                        note!("error: {message}");
                    } else {
                        note!("error: {}: {message}", file.display());
                    }
                }
            }
        }
        if failed > 0 {
            return Err(Failure::Run(anyhow!(
                "{failed} recording(s) could not be fitted or their fit failed"
            )));
        }
        return Ok(());
    }
    let keep = args.plot.is_some() || args.overlay.is_some();
    let (obs, recording, rep) = fit_one(&args.inputs, &opts, &setup, keep)?;
    // The report first: a figure that cannot be written must not cost the result.
    if args.json {
        let mut v = fit_json(&rep);
        provenance(&mut v, &args.inputs, &args.rig);
        outln!("{v}");
    } else {
        out!("{}", fit_text(&rep));
    }
    if let Some(p) = &args.plot {
        let figure = FitFigure {
            obs: &obs,
            report: &rep,
        };
        written(p, render(p, &figure), args.json)?;
    }
    if let Some(p) = &args.friction_plot {
        let Some(law) = &rep.friction else {
            return Err(Failure::Run(anyhow!(
                "--friction-plot: the recording never slides, so it shows no friction law"
            )));
        };
        let figure = FrictionFigure {
            rig: &rep.rig,
            law,
            releases: vec![(
                args.inputs[0].display().to_string(),
                appell::fit::law::slide_points_of(&rep.problem, settings),
            )],
        };
        written(p, render(p, &figure), args.json)?;
    }
    if let Some(p) = &args.overlay {
        let origin = recording.origin_ns();
        // The recording's own file, copied into the overlay (checked to be one MCAP file).
        let input = match args.overlay_with_input {
            true => Some(std::fs::read(&args.inputs[0]).map_err(|e| {
                Failure::Run(anyhow!(
                    "--overlay-with-input: reading {} again: {e} (the report above is complete; only the overlay is missing)",
                    args.inputs[0].display()
                ))
            })?),
            false => None,
        };
        let r = appell::output::write_atomic(p, |w| match OverlayFormat::from_path(p) {
            Ok(OverlayFormat::Csv) => {
                Ok(overlay::write_fit_overlay_csv(w, &obs, &rep, &recording)?)
            }
            _ => Ok(overlay::write_fit_overlay_with_input(
                w,
                &obs,
                &rep,
                origin,
                input.as_deref(),
            )?),
        });
        let r = r.map_err(|e| format!("writing {}: {e}", p.display()));
        saved(p, r, args.json, "overlay")?;
    }
    // A failed result is reported in full, and is no answer: exit 1 with the reason.
    if let Some(why) = &rep.failed {
        return Err(Failure::Run(anyhow!("{why}")));
    }
    Ok(())
}

/// `--overlay-with-input` before any work: it copies one MCAP recording's topics into an
/// `.mcap` overlay, so a table overlay, a recording in another format, several files or a
/// joint fit's releases are refused (exit 2) saying why.
fn with_input_allowed(
    args: &Args,
    overlay: &Path,
    format: OverlayFormat,
    opts: &ReadOptions,
) -> Result<(), Failure> {
    let refuse = |why: String| Err(Failure::Input(anyhow!("--overlay-with-input: {why}")));
    if format != OverlayFormat::Mcap {
        return refuse(format!(
            "{} is a table (.csv), which holds the model's markers only: give an .mcap overlay to keep the recording's topics beside it",
            overlay.display()
        ));
    }
    if args.joint {
        return refuse(
            "a joint fit writes one overlay a release: the flag takes one recording".into(),
        );
    }
    let [input] = args.inputs.as_slice() else {
        return refuse(format!(
            "{} files given: the flag copies one MCAP recording's topics",
            args.inputs.len()
        ));
    };
    if input.is_dir() {
        return refuse(format!(
            "{} is a directory: the flag copies one MCAP recording's topics",
            input.display()
        ));
    }
    let format = match opts.format {
        Some(f) => f,
        None => appell::data::detect(input).map_err(|e| Failure::Input(e.into()))?,
    };
    if format != appell::data::Format::Mcap {
        return refuse(format!(
            "{} is a {format} recording, not MCAP: only an MCAP recording's topics can be copied into the overlay",
            input.display()
        ));
    }
    Ok(())
}

/// A figure's outcome after the report: a line saying where it went (text reports), or the
/// error, exit 1, the report already printed.
fn written<E: std::fmt::Display>(p: &Path, r: Result<(), E>, json: bool) -> Result<(), Failure> {
    saved(p, r, json, "figure")
}

/// An output's outcome after the report ([`written`] for any output, named `what`).
fn saved<E: std::fmt::Display>(
    p: &Path,
    r: Result<(), E>,
    json: bool,
    what: &str,
) -> Result<(), Failure> {
    match r {
        Ok(()) => {
            if !json {
                outln!("{what} written to {}", p.display());
            }
            Ok(())
        }
        Err(e) => Err(Failure::Run(anyhow!(
            "{e} (the report above is complete; only the {what} is missing)"
        ))),
    }
}

/// The releases of a joint fit: a directory's recordings, or each `--release`.
fn release_paths(args: &Args, format_given: bool) -> Result<Vec<Vec<PathBuf>>, Failure> {
    if !args.release.is_empty() {
        return Ok(args
            .release
            .iter()
            .map(|r| r.split(',').map(PathBuf::from).collect())
            .collect());
    }
    match args.inputs.as_slice() {
        [dir] if dir.is_dir() => Ok(directory_files(dir, format_given)?
            .into_iter()
            .map(|f| vec![f])
            .collect()),
        _ => Err(Failure::Input(anyhow!(
            "--joint takes one directory of recordings, or each release with --release FILE (a Tracker pair as --release SLIDER.txt,BOB.txt)"
        ))),
    }
}

/// `appell fit --joint`: the releases read (in parallel), fitted together and reported.
fn run_joint(args: &Args, opts: &ReadOptions, setup: &FitSetup) -> Result<(), Failure> {
    let (rig, settings) = (&setup.rig, &setup.settings);
    let (paths, notes) = pipeline::once_each(release_paths(args, opts.format.is_some())?);
    for n in notes {
        note!("note: {n}");
    }
    // One overlay a release, beside --overlay's path: each checked as every output is, before
    // the fit.
    let overlays: Vec<PathBuf> = match &args.overlay {
        Some(out) => paths
            .iter()
            .map(|p| overlay::release_overlay_path(out, p))
            .collect(),
        None => Vec::new(),
    };
    if !overlays.is_empty() {
        let inputs = fit_inputs(args);
        let mut outputs: Vec<(&str, &Path)> = [
            ("--plot", &args.plot),
            ("--friction-plot", &args.friction_plot),
        ]
        .into_iter()
        .filter_map(|(flag, p)| Some((flag, p.as_deref()?)))
        .collect();
        for o in &overlays {
            super::refuse_input(Some(o), &inputs)?;
            outputs.push(("--overlay", o));
        }
        appell::output::refuse_same_output(&outputs).map_err(|e| Failure::Input(e.into()))?;
    }
    let joint = JointSettings {
        same_camera: args.same_camera,
        keep_going: args.keep_going,
    };
    let (rep, notes) = pipeline::fit_joint_files(&paths, opts, setup, &joint).map_err(failure)?;
    for n in notes {
        note!("{n}");
    }
    // The report first: a figure that cannot be written must not cost the result.
    if args.json {
        let mut v = joint_json(&rep);
        let inputs: Vec<PathBuf> = paths.iter().flatten().cloned().collect();
        provenance(&mut v, &inputs, &args.rig);
        outln!("{v}");
    } else {
        out!("{}", joint_text(&rep));
    }
    if let Some(p) = &args.plot {
        written(p, render(p, &JointFigure { report: &rep }), args.json)?;
    }
    if let Some(p) = &args.friction_plot {
        // One colour per release: each release cut into its slides at the joint optimum.
        let releases = rep
            .releases
            .iter()
            .zip(&rep.parts)
            .map(|(row, part)| {
                let name = Path::new(&row.name)
                    .file_name()
                    .map_or(row.name.clone(), |n| n.to_string_lossy().into_owned());
                (name, appell::fit::law::slide_points_of(part, settings))
            })
            .collect();
        let rig = rep.parts.first().map_or(*rig, |p| p.rig);
        let figure = FrictionFigure {
            rig: &rig,
            law: &rep.friction,
            releases,
        };
        written(p, render(p, &figure), args.json)?;
    }
    if !overlays.is_empty() {
        let answer = appell::report::joint::joint_answer(&rep);
        for (row, part) in rep.releases.iter().zip(&rep.parts) {
            let Some(k) = paths
                .iter()
                .position(|p| pipeline::release_name(p) == row.name)
            else {
                continue;
            };
            let out = &overlays[k];
            let r = pipeline::read_provenance(&paths[k], opts).and_then(|prov| {
                appell::output::write_atomic(out, |w| match OverlayFormat::from_path(out) {
                    Ok(OverlayFormat::Csv) => {
                        Ok(overlay::write_release_overlay_csv(w, part, &prov)?)
                    }
                    _ => Ok(overlay::write_release_overlay(
                        w,
                        part,
                        answer.clone(),
                        prov.origin_ns(),
                    )?),
                })
                .map_err(anyhow::Error::from)
            });
            let r = r.map_err(|e| format!("writing {}: {e:#}", out.display()));
            saved(out, r, args.json, "overlay")?;
        }
    }
    // A failed result is reported in full, and is no answer: exit 1 with the reason.
    if let Some(why) = &rep.failed {
        return Err(Failure::Run(anyhow!("the joint fit failed: {why}")));
    }
    Ok(())
}
