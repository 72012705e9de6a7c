//! The commands' work as library calls: what `appell fit` does between its flags and its
//! output (read and check the recordings, load the rig file as a measurement, fit, say where
//! the answer came from), so the binary and the Python package run the same steps and give
//! the same numbers.

mod files;
mod fit_args;
mod recording_args;

pub use files::{directory_files, once_each, release_name, RECORDING_EXTENSIONS};
pub use fit_args::{friction_law, nuisance, FitArgs, MAX_STARTS};
pub use recording_args::{RecordingArgs, FORMAT_NAMES};

use crate::data::{read_recording, ReadOptions, Recording};
use crate::fit::joint::{fit_joint, JointError, JointReport, JointSettings, Release};
use crate::fit::{
    check_frame_rate, check_masses, check_recording, check_rod_length, check_tilt, fit, FitReport,
    FitSettings, Observations,
};
use crate::model::Rig;
use crate::scene::RigFile;
use std::path::{Path, PathBuf};

/// A rig file loaded for fitting: the rig (mu values only starting guesses), the settings with
/// the file's measurement as priors (docs/fit.md, "The rig file is a measurement"), and the
/// file's path for messages and provenance.
#[derive(Debug, Clone)]
pub struct FitSetup {
    /// The rig file (or the label of a rig given as text).
    pub rig_path: PathBuf,
    /// The rig at the file's values.
    pub rig: Rig<f64>,
    /// The fit's settings, the measurement included.
    pub settings: FitSettings,
}

/// The starting guess of mu where a rig file gives none (the CLI's).
pub const MU_GUESS: f64 = 0.3;

impl FitSetup {
    /// Load the rig file at `rig_path` and check `args` (bad input: the file and key, or the
    /// flag, at fault). `scale` is the recording's `--scale`, for noise given in pixels.
    pub fn new(rig_path: &Path, args: &FitArgs, scale: Option<f64>) -> anyhow::Result<FitSetup> {
        let text = match crate::scene::read_text(rig_path, crate::scene::MAX_TOML_BYTES) {
            // A lab's first fit: say where a rig file comes from.
            Err(crate::scene::SceneError::Io { source, .. })
                if source.kind() == std::io::ErrorKind::NotFound =>
            {
                anyhow::bail!(
                    "{}: no such rig file: `appell inspect RECORDING --rig-template RIG.toml` writes one for the recording, to fill in with the rig's masses and rod length as measured",
                    rig_path.display()
                )
            }
            r => r?,
        };
        Self::from_text(&text, rig_path, args, scale)
    }

    /// [`FitSetup::new`] on a rig file's text; `rig_path` labels messages and the JSON.
    pub fn from_text(
        text: &str,
        rig_path: &Path,
        args: &FitArgs,
        scale: Option<f64>,
    ) -> anyhow::Result<FitSetup> {
        let site = args.site().map_err(anyhow::Error::msg)?;
        let (rig, spec, gravity_note) = RigFile::parse_on_earth(text, rig_path, MU_GUESS, site)?;
        let mut settings = args.settings(scale).map_err(anyhow::Error::msg)?;
        let mut measured = crate::fit::priors::RigMeasurement::from_spec(&spec);
        if gravity_note.is_some() {
            measured.gravity_from(if site.is_some() {
                "--latitude"
            } else {
                "default"
            });
        }
        measured.notes.extend(gravity_note);
        settings.measured = Some(measured);
        Ok(FitSetup {
            rig_path: rig_path.to_owned(),
            rig,
            settings,
        })
    }
}

/// A recording read and checked before any fitting work: its slider and bob swapped, a
/// distance no rod keeps (not this rig), a rod length its markers contradict, frames too
/// sparse to follow the pendulum (times in milliseconds) and a rig too stiff to fit in
/// minutes are bad input naming the file and the fix. The second value holds
/// the notes worth showing (frame times of two files joined).
pub fn read_for_rig(
    paths: &[PathBuf],
    opts: &ReadOptions,
    rig_path: &Path,
    rig: &Rig<f64>,
) -> anyhow::Result<(Observations, Vec<String>)> {
    read_calibrated(paths, opts, rig_path, rig).map(|(obs, notes, _)| (obs, notes))
}

/// [`read_for_rig`] with the recording's provenance (its calibration, where its scale came
/// from, and its clock).
fn read_calibrated(
    paths: &[PathBuf],
    opts: &ReadOptions,
    rig_path: &Path,
    rig: &Rig<f64>,
) -> anyhow::Result<(Observations, Vec<String>, crate::data::Provenance)> {
    let rec = read_recording(paths, opts)?;
    let files: Vec<String> = paths.iter().map(|p| p.display().to_string()).collect();
    let notes = rec
        .provenance
        .notes
        .iter()
        .filter(|n| n.starts_with(crate::data::TIMES_JOINED_NOTE))
        .map(|n| format!("{}: {n}", files.join(" + ")))
        .collect();
    check_for_rig(&rec, rig_path, rig)?;
    let provenance = rec.provenance.clone();
    Ok((Observations::from(rec), notes, provenance))
}

/// The relative standard deviation of a camera scale set from `--rod-length` (`None` for a
/// scale from the file or `--scale`): the rod measured with the rig file's ruler
/// (`rod_length_sd`, 1 mm by default) over the length given.
fn scale_sd(
    calibration: &crate::data::Calibration,
    opts: &ReadOptions,
    setup: &FitSetup,
) -> Option<f64> {
    let length = opts.rod_length?;
    if !calibration
        .scale_source
        .starts_with(crate::data::calibrate::ROD_LENGTH_SCALE)
    {
        return None;
    }
    let ruler = setup
        .settings
        .measured
        .as_ref()
        .map_or(crate::fit::priors::DEFAULT_ROD_LENGTH_SD, |m| {
            m.rod_length.1
        });
    Some(ruler / length).filter(|sd| sd.is_finite() && *sd > 0.0)
}

/// A recording (read, or made from arrays) checked for the rig as [`read_for_rig`] checks
/// it, as the fit's observations.
pub fn observations_for_rig(
    rec: &Recording,
    rig_path: &Path,
    rig: &Rig<f64>,
) -> anyhow::Result<Observations> {
    check_for_rig(rec, rig_path, rig)?;
    Ok(Observations::from(rec))
}

/// The checks of [`read_for_rig`].
fn check_for_rig(rec: &Recording, rig_path: &Path, rig: &Rig<f64>) -> anyhow::Result<()> {
    check_recording(rec)?;
    check_masses(rig_path, rig)?;
    check_tilt(rig_path, rig)?;
    check_rod_length(rig_path, rig, rec)?;
    check_frame_rate(rec, rig)?;
    // Before any integration: a rig too stiff to fit in minutes is refused, naming its key.
    crate::scene::check_time_scale(
        rig_path,
        rig,
        crate::scene::RigOrigin::File { friction: "rig" },
    )?;
    Ok(())
}

/// Why a fit gave no report: its input (exit code 2 on the command line, `ValueError` in
/// Python) or the run.
#[derive(Debug)]
pub enum FitFailure {
    /// The recordings or the rig cannot be fitted as given.
    Input(anyhow::Error),
    /// The fit itself failed.
    Run(anyhow::Error),
}

/// Fit one recording (a Tracker pair is two files) as `appell fit` does. `keep` returns the
/// observations too (the figure needs them; otherwise a long recording is held once).
pub fn fit_files(
    paths: &[PathBuf],
    opts: &ReadOptions,
    setup: &FitSetup,
    keep: bool,
) -> Result<(Observations, FitReport, Vec<String>), FitFailure> {
    fit_recording(paths, opts, setup, keep).map(|(obs, _, report, notes)| (obs, report, notes))
}

/// [`fit_files`] with the recording's provenance: its calibration and its clock, which an
/// overlay writes the model back in.
pub fn fit_recording(
    paths: &[PathBuf],
    opts: &ReadOptions,
    setup: &FitSetup,
    keep: bool,
) -> Result<
    (
        Observations,
        crate::data::Provenance,
        FitReport,
        Vec<String>,
    ),
    FitFailure,
> {
    let (obs, notes, provenance) =
        read_calibrated(paths, opts, &setup.rig_path, &setup.rig).map_err(FitFailure::Input)?;
    let calibration = &provenance.calibration;
    let (kept, given) = if keep {
        (obs.clone(), obs)
    } else {
        (Observations::default(), obs)
    };
    let name = paths[0].display().to_string();
    let report = match scale_sd(calibration, opts, setup) {
        Some(sd) => {
            let mut scaled = setup.clone();
            scaled.settings.scale_sd = Some(sd);
            fit_observations(given, &scaled, &name)?
        }
        None => fit_observations(given, setup, &name)?,
    };
    Ok((kept, provenance, report, notes))
}

/// Fit observations already read (from arrays, in Python) with a setup; `name` labels the
/// error.
pub fn fit_observations(
    obs: Observations,
    setup: &FitSetup,
    name: &str,
) -> Result<FitReport, FitFailure> {
    fit(obs, &setup.rig, &setup.settings)
        .map_err(|e| FitFailure::Run(anyhow::anyhow!(e).context(format!("fitting {name}"))))
}

/// The first frame's stamp in a recording's own clock (ns, [`crate::data::Provenance::origin_ns`]),
/// read again: an overlay of a joint fit's release is stamped from it.
pub fn origin_ns(paths: &[PathBuf], opts: &ReadOptions) -> anyhow::Result<u64> {
    Ok(read_provenance(paths, opts)?.origin_ns())
}

/// A recording's provenance (its calibration, format, marker names and clock), read again: a
/// joint fit's release overlay in the release's own units is written through it.
pub fn read_provenance(
    paths: &[PathBuf],
    opts: &ReadOptions,
) -> anyhow::Result<crate::data::Provenance> {
    Ok(read_recording(paths, opts)?.provenance)
}

/// What a fit's JSON was made from: the recordings read, the rig file, and this tool's
/// version, so that a result kept in a lab's archive says where it came from.
pub fn provenance(v: &mut serde_json::Value, inputs: &[PathBuf], rig: &Path) {
    v["inputs"] = serde_json::json!(inputs
        .iter()
        .map(|p| p.display().to_string())
        .collect::<Vec<_>>());
    v["rig_file"] = serde_json::json!(rig.display().to_string());
    v["version"] = serde_json::json!(concat!("appell ", env!("CARGO_PKG_VERSION")));
}

/// A recording read for a rig, with its notes ([`read_for_rig`]).
type Read = (Observations, Vec<String>);

/// Read the releases (in parallel) and fit them together as `appell fit --joint` does. With
/// `keep_going`, a release that cannot be read is named in the report's `left_out` and the
/// others are fitted. The second value holds the notes worth showing.
pub fn fit_joint_files(
    paths: &[Vec<PathBuf>],
    opts: &ReadOptions,
    setup: &FitSetup,
    joint: &JointSettings,
) -> Result<(JointReport, Vec<String>), FitFailure> {
    use rayon::prelude::*;
    let read: Vec<(String, anyhow::Result<Read>)> = paths
        .par_iter()
        .map(|p| {
            let name = release_name(p);
            (name, read_for_rig(p, opts, &setup.rig_path, &setup.rig))
        })
        .collect();
    let mut releases = Vec::new();
    let mut unread = Vec::new();
    let mut notes = Vec::new();
    for (name, obs) in read {
        match obs {
            Ok((obs, read_notes)) => {
                notes.extend(read_notes.into_iter().map(|n| format!("note: {n}")));
                releases.push(Release { name, obs });
            }
            Err(e) if joint.keep_going => {
                let message = messages(&e).join(": ");
                notes.push(format!("error: {message} (left out)"));
                unread.push((name, message));
            }
            Err(e) => return Err(FitFailure::Input(e)),
        }
    }
    let mut rep =
        fit_joint(&releases, &setup.rig, &setup.settings, joint).map_err(|e| match e {
            JointError::OtherRig(_) | JointError::TooFew(_) => FitFailure::Input(e.into()),
            e => FitFailure::Run(e.into()),
        })?;
    rep.left_out.extend(unread);
    Ok((rep, notes))
}

/// The messages of an error and its causes, leaving out a cause whose message the one before
/// it already contains (errors that print their source, as most of the library's do), so
/// nothing is said twice. Never empty.
pub fn messages(e: &anyhow::Error) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for cause in e.chain() {
        let m = cause.to_string();
        if !out.last().is_some_and(|prev| prev.contains(&m)) {
            out.push(m);
        }
    }
    out
}

/// The most phase-portrait trajectories `appell regions` draws.
pub const MAX_TRAJECTORIES: usize = 1000;

/// The most simulated seconds a phase portrait runs (trajectories x duration).
pub const MAX_PORTRAIT_SECONDS: f64 = 1e4;

/// Check `--trajectories` and `--duration` of `appell regions` before any work: bounded, so no
/// number makes the portrait run without end.
pub fn check_portrait(trajectories: usize, duration: f64) -> Result<(), String> {
    if !(duration.is_finite() && duration > 0.0 && duration <= 600.0) {
        return Err(format!("--duration must be in (0, 600] s, got {duration}"));
    }
    if trajectories > MAX_TRAJECTORIES {
        return Err(format!(
            "--trajectories must be at most {MAX_TRAJECTORIES}, got {trajectories}"
        ));
    }
    let seconds = trajectories as f64 * duration;
    if seconds > MAX_PORTRAIT_SECONDS {
        return Err(format!(
            "--trajectories {trajectories} x --duration {duration} s is {seconds:e} simulated seconds, more than the {MAX_PORTRAIT_SECONDS:e} one run draws (1000 samples a second each): lower either"
        ));
    }
    Ok(())
}
