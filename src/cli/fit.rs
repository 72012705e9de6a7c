//! `appell fit RECORDING... --rig RIG.toml`: estimate mu and the initial state; a directory of
//! recordings is fitted in parallel, one JSON line per recording.

use super::recording_args::RecordingArgs;
use super::Failure;
use anyhow::anyhow;
use appell::data::{read_recording, ReadOptions};
use appell::fit::joint::{fit_joint, JointError, JointSettings, Release};
use appell::fit::{
    check_recording, check_rod_length, fit, FitReport, FitSettings, Loss, Nuisance, Observations,
    StaticMode,
};
use appell::model::{FrictionLaw, Rig};
use appell::report::fit::{answer, fit_json, fit_text, FitFigure, FrictionFigure};
use appell::report::joint::{joint_json, joint_text, JointFigure};
use appell::report::plot::render;
use appell::scene::RigFile;
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
    /// The lab's latitude (deg, -90 to 90): a rig file without `gravity` takes Earth's normal
    /// gravity there instead of 9.81 m/s^2 (a file's `gravity` is used as written).
    #[arg(long, value_name = "DEG", allow_negative_numbers = true, value_parser = latitude)]
    latitude: Option<f64>,
    /// The lab's altitude (m) with --latitude (default 0, sea level).
    #[arg(long, value_name = "M", requires = "latitude", allow_negative_numbers = true, value_parser = altitude)]
    altitude: Option<f64>,
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
    /// Robust loss for mis-tracked frames.
    #[arg(long, value_parser = ["huber", "cauchy"])]
    robust: Option<String>,
    /// Also fit the rod length.
    #[arg(long)]
    fit_rod_length: bool,
    /// mu_static: freed when the recording shows a stick-to-slide onset (auto), always equal
    /// to mu_kinetic (tied), or held at the rig's value (fixed).
    #[arg(long, default_value = "auto", value_parser = ["auto", "tied", "fixed"])]
    mu_static: String,
    /// Skip the profile intervals (faster; intervals are then value +- 1.96 stderr).
    #[arg(long)]
    no_profile: bool,
    /// Extra starting values of mu_kinetic for the multi-start search.
    #[arg(long, value_delimiter = ',', value_name = "MU,...")]
    starts: Vec<f64>,
    /// Known measurement noise per coordinate instead of the one measured from the tracks:
    /// one value for both markers or `SLIDER,BOB`, in metres, or in pixels with a `px` suffix
    /// (with --scale), e.g. `0.0002` or `0.5px,0.8px`.
    #[arg(long, value_delimiter = ',', value_name = "NOISE[,NOISE]")]
    noise: Vec<String>,
    /// The plain model only: no physics or camera nuisances and no check of the windows
    /// (faster; the chi-square against the measured noise still shows a misfit).
    #[arg(long)]
    plain: bool,
    /// Put these nuisances in the model whatever the data say (e.g. a rail known to be
    /// tilted): mu_static, stribeck, direction, load, rail_tilt, pivot_damping, viscous_friction, camera_scale,
    /// bob_marker_offset, bob_marker_across, slider_marker_offset, marker_lag, rigid_pendulum. With --plain, only these.
    #[arg(long, value_delimiter = ',', value_name = "NUISANCE,...", value_parser = nuisance)]
    with: Vec<Nuisance>,
    /// Force the rail's friction law instead of letting the data choose: coulomb, stribeck,
    /// direction (coefficients differ by sliding direction) or load (friction a power of the
    /// normal force). Static above kinetic is --mu-static.
    #[arg(long, value_name = "LAW", value_parser = friction_law)]
    friction: Option<FrictionLaw>,
    #[command(flatten)]
    recording: RecordingArgs,
}

/// Parse a `--friction` law name.
fn friction_law(name: &str) -> Result<FrictionLaw, String> {
    FrictionLaw::ALL
        .into_iter()
        .find(|l| l.name() == name)
        .ok_or_else(|| {
            let names: Vec<&str> = FrictionLaw::ALL.iter().map(|l| l.name()).collect();
            format!("expected one of {}", names.join(", "))
        })
}

/// Parse one `--with` name.
fn nuisance(name: &str) -> Result<Nuisance, String> {
    Nuisance::ALL
        .into_iter()
        .find(|n| n.name() == name)
        .ok_or_else(|| {
            let names: Vec<&str> = Nuisance::ALL.iter().map(|n| n.name()).collect();
            format!("expected one of {}", names.join(", "))
        })
}

/// A number within `[lo, hi]`, for `--latitude` and `--altitude`.
fn within(text: &str, [lo, hi]: [f64; 2], unit: &str) -> Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(v) if (lo..=hi).contains(&v) => Ok(v),
        _ => Err(format!("expected a number of {unit} from {lo} to {hi}")),
    }
}

/// Parse `--latitude` (deg).
fn latitude(text: &str) -> Result<f64, String> {
    within(text, appell::scene::LATITUDE_RANGE, "degrees")
}

/// Parse `--altitude` (m).
fn altitude(text: &str) -> Result<f64, String> {
    within(text, appell::scene::ALTITUDE_RANGE, "metres")
}

/// Parse `--noise`: metres, or pixels (`px` suffix) times the recording's --scale.
fn noise(args: &Args) -> Result<Option<[f64; 2]>, String> {
    if args.noise.is_empty() {
        return Ok(None);
    }
    if args.noise.len() > 2 {
        return Err(format!(
            "--noise takes one value or SLIDER,BOB, got {} values",
            args.noise.len()
        ));
    }
    let one = |text: &str| -> Result<f64, String> {
        let (num, px) = match text.trim().strip_suffix("px") {
            Some(n) => (n, true),
            None => (text.trim().strip_suffix('m').unwrap_or(text.trim()), false),
        };
        let v: f64 = num
            .trim()
            .parse()
            .map_err(|_| format!("--noise: expected a number of metres or pixels (e.g. 0.0002 or 0.5px), got {text:?}"))?;
        let v = if px {
            let scale = args
                .recording
                .scale
                .ok_or_else(|| format!("--noise {text}: pixels need --scale (metres per pixel)"))?;
            v * scale
        } else {
            v
        };
        if v.is_finite() && v > 0.0 {
            Ok(v)
        } else {
            Err(format!("--noise must be positive and finite, got {text:?}"))
        }
    };
    let slider = one(&args.noise[0])?;
    let bob = match args.noise.get(1) {
        Some(b) => one(b)?,
        None => slider,
    };
    Ok(Some([slider, bob]))
}

fn settings(args: &Args) -> Result<FitSettings, String> {
    Ok(FitSettings {
        fit_rod_length: args.fit_rod_length,
        mu_static: match args.mu_static.as_str() {
            "tied" => StaticMode::Tied,
            "fixed" => StaticMode::Fixed,
            _ => StaticMode::Auto,
        },
        loss: match args.robust.as_deref() {
            Some("huber") => Loss::Huber(3.0),
            Some("cauchy") => Loss::Cauchy(3.0),
            _ => Loss::Squares,
        },
        extra_starts: args.starts.clone(),
        profile: !args.no_profile,
        noise: noise(args)?,
        nuisances: !args.plain,
        windows: !args.plain,
        with: args.with.clone(),
        friction: args.friction,
        ..FitSettings::default()
    })
}

/// The file endings a directory's recordings may have: the CSV family, MCAP, HDF5 (DeepLabCut,
/// SLEAP), Tracker projects and Kinovea XML; the content decides the format.
const RECORDING_EXTENSIONS: [&str; 8] = ["csv", "mcap", "txt", "tsv", "h5", "hdf5", "trk", "xml"];

/// Recordings in a directory: files with a recording extension, sorted. Without `--format`,
/// a file whose format cannot be told from its start (a `notes.txt`) is not a recording: it
/// is skipped with a note on stderr and the rest are fitted.
pub(super) fn directory_files(dir: &Path, format_given: bool) -> Result<Vec<PathBuf>, Failure> {
    let entries = std::fs::read_dir(dir)
        .map_err(|e| Failure::Input(anyhow!("{}: cannot list: {e}", dir.display())))?;
    let mut files: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_file())
        .filter(|p| {
            !p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.starts_with('.'))
        })
        .filter(|p| {
            p.extension()
                .and_then(|e| e.to_str())
                .is_some_and(|e| RECORDING_EXTENSIONS.contains(&e.to_ascii_lowercase().as_str()))
        })
        .collect();
    files.sort();
    if !format_given {
        files.retain(|f| match appell::data::detect(f) {
            Err(e @ appell::data::DataError::UnknownFormat { .. }) => {
                note!("note: skipped, not a recording: {e}");
                false
            }
            _ => true,
        });
    }
    if files.is_empty() {
        return Err(Failure::Input(anyhow!(
            "{}: no recordings (.{}) in this directory",
            dir.display(),
            RECORDING_EXTENSIONS.join(", .")
        )));
    }
    Ok(files)
}

/// A recording's observations and fit, or why not.
type Fitted = Result<(Observations, FitReport), Failure>;

/// A recording read and checked before any fitting work: its slider and bob swapped, a
/// distance no rod keeps (not this rig) and a rod length its markers contradict are bad input
/// naming the file and the fix (`fit`, `fit --joint`, `bench --joint`).
pub(super) fn read_for_rig(
    paths: &[PathBuf],
    opts: &ReadOptions,
    rig_path: &Path,
    rig: &Rig<f64>,
) -> Result<Observations, Failure> {
    let rec = read_recording(paths, opts).map_err(|e| Failure::Input(e.into()))?;
    for note in &rec.provenance.notes {
        if note.starts_with(appell::data::TIMES_JOINED_NOTE) {
            let files: Vec<String> = paths.iter().map(|p| p.display().to_string()).collect();
            note!("note: {}: {note}", files.join(" + "));
        }
    }
    check_recording(&rec).map_err(|e| Failure::Input(e.into()))?;
    check_rod_length(rig_path, rig, &rec).map_err(|e| Failure::Input(e.into()))?;
    // Before any integration: a rig too stiff to fit in minutes is refused, naming its key.
    appell::scene::check_time_scale(
        rig_path,
        rig,
        appell::scene::RigOrigin::File { friction: "rig" },
    )
    .map_err(|e| Failure::Input(e.into()))?;
    Ok(Observations::from(&rec))
}

fn fit_one(
    paths: &[PathBuf],
    opts: &ReadOptions,
    (rig_path, rig): (&Path, &Rig<f64>),
    settings: &FitSettings,
    keep: bool,
) -> Fitted {
    let obs = read_for_rig(paths, opts, rig_path, rig)?;
    // Only the figure needs the observations after the fit: a long recording is held once.
    let (kept, given) = if keep {
        (obs.clone(), obs)
    } else {
        (Observations::default(), obs)
    };
    let report = fit(given, rig, settings)
        .map_err(|e| Failure::Run(anyhow!(e).context(format!("fitting {}", paths[0].display()))))?;
    Ok((kept, report))
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
    super::refuse_input(args.plot.as_deref(), &fit_inputs(&args))?;
    super::refuse_input(args.friction_plot.as_deref(), &fit_inputs(&args))?;
    let opts = args
        .recording
        .resolve()
        .map_err(|e| Failure::Input(anyhow!(e)))?;
    let site = args.latitude.map(|lat| (lat, args.altitude.unwrap_or(0.0)));
    let (rig, spec, gravity_note) =
        RigFile::load_on_earth(&args.rig, 0.3, site).map_err(|e| Failure::Input(e.into()))?;
    let mut settings = settings(&args).map_err(|e| Failure::Input(anyhow!(e)))?;
    for p in [&args.plot, &args.friction_plot].into_iter().flatten() {
        appell::report::plot::ImageFormat::from_path(p).map_err(|e| Failure::Input(e.into()))?;
    }
    // The rig file is the measurement it is: its rod length and mass ratio are fitted with
    // its deviations as priors (docs/fit.md, "The rig file is a measurement").
    let mut measured = appell::fit::priors::RigMeasurement::from_spec(&spec);
    measured.notes.extend(gravity_note);
    settings.measured = Some(measured);
    if args.joint {
        return run_joint(&args, &opts, &rig, &settings);
    }
    if args.inputs.len() == 1 && args.inputs[0].is_dir() {
        if let Some(flag) = [
            (args.plot.is_some(), "--plot"),
            (args.friction_plot.is_some(), "--friction-plot"),
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
                let r = fit_one(
                    std::slice::from_ref(f),
                    &opts,
                    (&args.rig, &rig),
                    &settings,
                    false,
                );
                bar.inc(1);
                (f.clone(), r)
            })
            .collect();
        bar.finish_and_clear();
        let mut failed = 0;
        for (file, r) in results {
            match r {
                Ok((_, rep)) => {
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
                "{failed} recording(s) could not be fitted"
            )));
        }
        return Ok(());
    }
    let (obs, rep) = fit_one(
        &args.inputs,
        &opts,
        (&args.rig, &rig),
        &settings,
        args.plot.is_some(),
    )?;
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
                appell::fit::law::slide_points(&rep, &settings),
            )],
        };
        written(p, render(p, &figure), args.json)?;
    }
    Ok(())
}

/// A figure's outcome after the report: a line saying where it went (text reports), or the
/// error, exit 1, the report already printed.
fn written<E: std::fmt::Display>(p: &Path, r: Result<(), E>, json: bool) -> Result<(), Failure> {
    match r {
        Ok(()) => {
            if !json {
                outln!("figure written to {}", p.display());
            }
            Ok(())
        }
        Err(e) => Err(Failure::Run(anyhow!(
            "{e} (the report above is complete; only the figure is missing)"
        ))),
    }
}

/// What a fit's JSON was made from: the recordings read, the rig file, and this tool's
/// version, so that a result kept in a lab's archive says where it came from.
fn provenance(v: &mut serde_json::Value, inputs: &[PathBuf], rig: &Path) {
    v["inputs"] = serde_json::json!(inputs
        .iter()
        .map(|p| p.display().to_string())
        .collect::<Vec<_>>());
    v["rig_file"] = serde_json::json!(rig.display().to_string());
    v["version"] = serde_json::json!(concat!("appell ", env!("CARGO_PKG_VERSION")));
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

/// A file's device and inode, or its path as given where it cannot be looked at.
type FileId = Result<(u64, u64), PathBuf>;

/// The identity of a file: its device and inode (any spelling, link or `..` of one file gives
/// the same), or, where the file cannot be opened, its path as given (the read names it).
fn file_id(path: &Path) -> FileId {
    use std::os::unix::fs::MetadataExt;
    std::fs::metadata(path)
        .map(|m| (m.dev(), m.ino()))
        .map_err(|_| path.to_owned())
}

/// One release per file: a release whose files are those of an earlier one (`A` and
/// `DIR/./A`, a link to `A` in the directory, the same Tracker pair twice) is dropped with a
/// note on stderr, so no recording is counted twice.
fn once_each(paths: Vec<Vec<PathBuf>>) -> Vec<Vec<PathBuf>> {
    let mut seen: Vec<(Vec<FileId>, String)> = Vec::new();
    let mut kept = Vec::new();
    for p in paths {
        let id: Vec<_> = p.iter().map(|f| file_id(f)).collect();
        let name = release_name(&p);
        match seen.iter().find(|(other, _)| *other == id) {
            Some((_, first)) => {
                note!("note: {name} is {first} again (the same file): counted once");
            }
            None => {
                seen.push((id, name));
                kept.push(p);
            }
        }
    }
    kept
}

/// A release's name in messages and the table: its files joined by commas.
fn release_name(files: &[PathBuf]) -> String {
    files
        .iter()
        .map(|f| f.display().to_string())
        .collect::<Vec<_>>()
        .join(",")
}

/// `appell fit --joint`: the releases read (in parallel), fitted together and reported.
fn run_joint(
    args: &Args,
    opts: &ReadOptions,
    rig: &Rig<f64>,
    settings: &FitSettings,
) -> Result<(), Failure> {
    let paths = once_each(release_paths(args, opts.format.is_some())?);
    let read: Vec<(String, Result<Observations, Failure>)> = paths
        .par_iter()
        .map(|p| {
            let name = release_name(p);
            let obs = read_for_rig(p, opts, &args.rig, rig);
            (name, obs)
        })
        .collect();
    let mut releases = Vec::new();
    let mut unread = Vec::new();
    for (name, obs) in read {
        match obs {
            Ok(obs) => releases.push(Release { name, obs }),
            Err(Failure::Input(e) | Failure::Run(e)) if args.keep_going => {
                let message = super::messages(&e).join(": ");
                note!("error: {message} (left out)");
                unread.push((name, message));
            }
            Err(e) => return Err(e),
        }
    }
    let joint = JointSettings {
        same_camera: args.same_camera,
        keep_going: args.keep_going,
    };
    let mut rep = fit_joint(&releases, rig, settings, &joint).map_err(|e| match e {
        JointError::OtherRig(_) | JointError::TooFew(_) => Failure::Input(anyhow!(e)),
        e => Failure::Run(anyhow!(e)),
    })?;
    rep.left_out.extend(unread);
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
    // A failed result is reported in full, and is no answer: exit 1 with the reason.
    if let Some(why) = &rep.failed {
        return Err(Failure::Run(anyhow!("the joint fit failed: {why}")));
    }
    Ok(())
}
