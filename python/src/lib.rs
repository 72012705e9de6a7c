//! `appell._appell`: the Rust side of the Python package. A thin layer over the library's
//! `pipeline`, so a fit from Python runs the steps `appell fit` runs and gives its numbers to
//! the last digit. Arrays cross as native-endian `f64` bytes (numpy's `tobytes`/`frombuffer`),
//! options as dicts with the CLI's names (the Python side fills every key, with the CLI's
//! defaults). Every long call releases the GIL, so threads fit in parallel.

use appell::data::synth::{self, SynthOptions};
use appell::data::{read_recording, ReadOptions, Recording};
use appell::fit::joint::{JointReport, JointSettings};
use appell::fit::{FitReport, FitSettings, Observations};
use appell::pipeline::{self, FitArgs, FitFailure, FitSetup, RecordingArgs};
use appell::report::fit::{answer, fit_json, fit_text, FitFigure, FrictionFigure};
use appell::report::joint::{joint_answer, joint_json, joint_text, JointFigure};
use appell::report::plot::{render, svg_string};
use appell::scene::Scene;
use appell::sim::Cancel;
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::RecvTimeoutError;
use std::sync::Arc;
use std::time::Duration;

/// Bad input: `ValueError` with the CLI's message (its causes joined).
fn input(e: anyhow::Error) -> PyErr {
    PyValueError::new_err(pipeline::messages(&e).join(": "))
}

/// A run that could not finish: `RuntimeError` with the CLI's message.
fn run(e: anyhow::Error) -> PyErr {
    PyRuntimeError::new_err(pipeline::messages(&e).join(": "))
}

/// The most threads one call may ask for.
const MAX_THREADS: usize = 256;

thread_local! {
    /// The pool of this Python thread's fits with `threads=N` (kept: a thread per call costs
    /// more than a short fit's overhead), with its size.
    static POOL: std::cell::RefCell<Option<(usize, Arc<rayon::ThreadPool>)>> =
        const { std::cell::RefCell::new(None) };
    /// This Python thread's request to cancel its fit (Ctrl-C): the integrator's options
    /// hold a `'static` flag, so each thread leaks one, once.
    static CANCEL: &'static AtomicBool = Box::leak(Box::new(AtomicBool::new(false)));
}

/// The pool a fit runs on: `None` for the shared one (`threads` None: a lone fit uses every
/// core), or a pool of `threads` of this caller's own, so that fits run in parallel by
/// threads or cluster workers do not queue for one shared pool.
fn pool_of(threads: Option<usize>) -> PyResult<Option<Arc<rayon::ThreadPool>>> {
    let Some(n) = threads else {
        return Ok(None);
    };
    if !(1..=MAX_THREADS).contains(&n) {
        return Err(PyValueError::new_err(format!(
            "threads must be from 1 to {MAX_THREADS}, got {n}"
        )));
    }
    POOL.with(|cell| {
        let mut cell = cell.borrow_mut();
        if let Some((size, pool)) = cell.as_ref() {
            if *size == n {
                return Ok(Some(pool.clone()));
            }
        }
        let pool = Arc::new(
            rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .map_err(|e| PyRuntimeError::new_err(format!("threads={n}: {e}")))?,
        );
        *cell = Some((n, pool.clone()));
        Ok(Some(pool))
    })
}

/// This thread's cancel request, lowered: a fit whose options hold it stops at its runs' next
/// step once [`interruptible`] raises it.
fn cancel_here() -> Cancel {
    let flag = CANCEL.with(|f| *f);
    flag.store(false, Ordering::Relaxed);
    Cancel::on(flag)
}

/// How often a caller waiting for a fit looks for signals (Ctrl-C).
const SIGNAL_POLL: Duration = Duration::from_millis(50);

/// The stack of the thread a fit runs on: the main thread's (the command's fit runs there).
const WORK_STACK: usize = 8 << 20;

/// Run `work` on the pool `threads` asks for ([`pool_of`]) on a thread of its own, the GIL
/// released, while this thread checks for signals every [`SIGNAL_POLL`]: a signal's exception
/// (Ctrl-C's KeyboardInterrupt) raises this thread's cancel request ([`cancel_here`], which
/// `work`'s runs poll), waits for `work` to stop and is raised. Python delivers signals to its
/// main thread only, so a fit started on another thread runs to its end, as Python code there
/// would.
fn interruptible<T: Send>(
    py: Python<'_>,
    threads: Option<usize>,
    work: impl FnOnce() -> T + Send,
) -> PyResult<T> {
    let pool = pool_of(threads)?;
    let flag = CANCEL.with(|f| *f);
    let out = std::thread::scope(|s| {
        let (tx, rx) = std::sync::mpsc::channel();
        let worker = std::thread::Builder::new()
            .stack_size(WORK_STACK)
            .spawn_scoped(s, move || {
                let out = match pool {
                    Some(pool) => pool.install(work),
                    None => work(),
                };
                // The receiver waits until this is sent, or until the worker has been joined.
                let _ = tx.send(out);
            })
            .map_err(|e| PyRuntimeError::new_err(format!("cannot start the fit's thread: {e}")))?;
        let mut rx = rx;
        loop {
            let (back, got) = py.detach(move || {
                let got = rx.recv_timeout(SIGNAL_POLL);
                (rx, got)
            });
            rx = back;
            match got {
                Ok(out) => return Ok(out),
                Err(RecvTimeoutError::Timeout) => {
                    if let Err(signal) = py.check_signals() {
                        flag.store(true, Ordering::Relaxed);
                        // Whatever the cancelled work gave (or a panic of it) is dropped.
                        let _ = py.detach(move || worker.join());
                        return Err(signal);
                    }
                }
                // The work panicked before it sent: its panic, as pyo3 reports any.
                Err(RecvTimeoutError::Disconnected) => {
                    return match py.detach(move || worker.join()) {
                        Err(panic) => std::panic::resume_unwind(panic),
                        Ok(()) => Err(PyRuntimeError::new_err("the fit's thread gave no result")),
                    };
                }
            }
        }
    });
    // Lowered again: a result's figures run the integrator with the same flag later.
    flag.store(false, Ordering::Relaxed);
    out
}

fn failure(e: FitFailure) -> PyErr {
    match e {
        FitFailure::Input(e) => input(e),
        FitFailure::Run(e) => run(e),
    }
}

/// The reading options, every key present (the Python side's defaults are the CLI's).
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
struct ReadKw {
    format: Option<String>,
    slider: Option<String>,
    bob: Option<String>,
    scale: Option<f64>,
    fps: Option<f64>,
    plane: Option<String>,
    y_down: bool,
    y_up: bool,
    rail_frame: bool,
    rod_length: Option<f64>,
    min_likelihood: f64,
    drop_outliers: bool,
    t_start: Option<f64>,
    t_end: Option<f64>,
    topic: Vec<String>,
}

impl ReadKw {
    fn args(self) -> RecordingArgs {
        RecordingArgs {
            format: self.format,
            slider: self.slider,
            bob: self.bob,
            scale: self.scale,
            fps: self.fps,
            plane: self.plane,
            y_down: self.y_down,
            y_up: self.y_up,
            rail_frame: self.rail_frame,
            rod_length: self.rod_length,
            min_likelihood: self.min_likelihood,
            drop_outliers: self.drop_outliers,
            t_start: self.t_start,
            t_end: self.t_end,
            topic: self.topic,
        }
    }

    /// The readers' options, checked with the CLI's messages; also the `--scale` given.
    fn resolve(self) -> PyResult<(ReadOptions, Option<f64>)> {
        let scale = self.scale;
        let opts = self.args().resolve().map_err(PyValueError::new_err)?;
        Ok((opts, scale))
    }
}

/// The fit's options, every key present.
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
struct FitKw {
    latitude: Option<f64>,
    altitude: Option<f64>,
    robust: Option<String>,
    fit_rod_length: bool,
    mu_static: String,
    no_profile: bool,
    starts: Vec<f64>,
    noise: Vec<String>,
    plain: bool,
    #[pyo3(item("with"))]
    with_: Vec<String>,
    friction: Option<String>,
}

impl FitKw {
    fn args(self) -> PyResult<FitArgs> {
        let with = self
            .with_
            .iter()
            .map(|n| pipeline::nuisance(n).map_err(|e| format!("with: {n:?}: {e}")))
            .collect::<Result<Vec<_>, _>>()
            .map_err(PyValueError::new_err)?;
        let friction = self
            .friction
            .as_deref()
            .map(|n| pipeline::friction_law(n).map_err(|e| format!("friction: {n:?}: {e}")))
            .transpose()
            .map_err(PyValueError::new_err)?;
        Ok(FitArgs {
            latitude: self.latitude,
            altitude: self.altitude,
            robust: self.robust,
            fit_rod_length: self.fit_rod_length,
            mu_static: self.mu_static,
            no_profile: self.no_profile,
            starts: self.starts,
            noise: self.noise,
            plain: self.plain,
            with,
            friction,
        })
    }
}

/// A rig file's text and the name it goes by (its path, or `Rig(...)` for one built in Python).
fn setup(rig_text: &str, rig_label: &str, fit: FitKw, scale: Option<f64>) -> PyResult<FitSetup> {
    FitSetup::from_text(rig_text, Path::new(rig_label), &fit.args()?, scale).map_err(input)
}

/// `x` to four significant digits, without trailing zeros (1000, 29.97, 120).
fn four_digits(x: f64) -> String {
    let decimals = (3 - x.abs().log10().floor() as i32).clamp(0, 12) as usize;
    let text = format!("{x:.decimals$}");
    match text.contains('.') {
        true => text.trim_end_matches('0').trim_end_matches('.').to_owned(),
        false => text,
    }
}

/// The note for a frame rate given to files that hold their own frame times: read with `fps`
/// and without it, the same times, so `fps` changed nothing (the readers use it only for files
/// of frame numbers, or, for Kinovea spreadsheets, to number the rows, which the comparison
/// sees). `None` when no `fps` was given, when the files need it, or when it was used.
fn fps_unused(paths: &[PathBuf], opts: &ReadOptions) -> Option<String> {
    let fps = opts.fps?;
    let own = read_recording(
        paths,
        &ReadOptions {
            fps: None,
            ..opts.clone()
        },
    )
    .ok()?;
    let given = read_recording(paths, opts).ok()?;
    if own.times != given.times {
        return None;
    }
    let mut steps: Vec<f64> = own.times.windows(2).map(|w| w[1] - w[0]).collect();
    steps.sort_by(f64::total_cmp);
    let rate = match steps.get(steps.len() / 2) {
        Some(&step) if step > 0.0 => format!(", a median rate of {} Hz", four_digits(1.0 / step)),
        _ => String::new(),
    };
    let files: Vec<String> = paths.iter().map(|p| p.display().to_string()).collect();
    let (files, hold) = match files.len() {
        1 => (files[0].clone(), "holds"),
        _ => (files.join(" and "), "hold"),
    };
    Some(format!(
        "fps={fps} is not used: {files} {hold} its own frame times ({} frames{rate}), which are read instead; leave fps out for such files",
        own.times.len()
    ))
}

fn floats(bytes: &Bound<'_, PyBytes>, what: &str) -> PyResult<Vec<f64>> {
    let b = bytes.as_bytes();
    if b.len() % 8 != 0 {
        return Err(PyValueError::new_err(format!(
            "{what}: {} bytes is not a whole number of float64 values",
            b.len()
        )));
    }
    Ok(b.chunks_exact(8)
        .map(|c| f64::from_ne_bytes(c.try_into().expect("8 bytes")))
        .collect())
}

fn to_bytes<'py>(py: Python<'py>, v: &[f64]) -> Bound<'py, PyBytes> {
    let mut b = Vec::with_capacity(v.len() * 8);
    for x in v {
        b.extend_from_slice(&x.to_ne_bytes());
    }
    PyBytes::new(py, &b)
}

/// A track as 2n floats, NaN where the marker was not seen.
fn track_floats(track: &[Option<[f64; 2]>]) -> Vec<f64> {
    track
        .iter()
        .flat_map(|p| p.unwrap_or([f64::NAN, f64::NAN]))
        .collect()
}

/// A recording as the Python side builds it: `t`, `slider` and `bob` arrays and its metadata.
fn recording_dict<'py>(py: Python<'py>, rec: &Recording) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("t", to_bytes(py, &rec.times))?;
    d.set_item("slider", to_bytes(py, &track_floats(&rec.slider)))?;
    d.set_item("bob", to_bytes(py, &track_floats(&rec.bob)))?;
    let p = &rec.provenance;
    let m = PyDict::new(py);
    let sources: Vec<String> = p.sources.iter().map(|s| s.display().to_string()).collect();
    m.set_item("sources", sources)?;
    m.set_item("format", p.format.map(|f| f.name()))?;
    m.set_item("format_detected", p.detected)?;
    m.set_item("slider_name", &p.slider_name)?;
    m.set_item("bob_name", &p.bob_name)?;
    m.set_item("time_origin", p.time_origin)?;
    m.set_item("scale", p.calibration.scale)?;
    m.set_item("scale_source", &p.calibration.scale_source)?;
    m.set_item("y_flipped", p.calibration.y_flipped)?;
    m.set_item("rail_angle", p.calibration.rail_angle)?;
    m.set_item("notes", p.notes.clone())?;
    m.set_item("warnings", p.warnings.clone())?;
    let meta = PyDict::new(py);
    for (k, v) in &p.metadata {
        meta.set_item(k, v)?;
    }
    m.set_item("file_metadata", meta)?;
    d.set_item("metadata", m)?;
    Ok(d)
}

/// Read a recording (a Tracker pair is two paths) as `appell convert` reads it.
#[pyfunction]
fn read_recording_py<'py>(
    py: Python<'py>,
    paths: Vec<PathBuf>,
    read: ReadKw,
) -> PyResult<Bound<'py, PyDict>> {
    let (opts, _) = read.resolve()?;
    let rec = py
        .detach(|| read_recording(&paths, &opts))
        .map_err(|e| input(e.into()))?;
    let d = recording_dict(py, &rec)?;
    d.set_item("fps_note", py.detach(|| fps_unused(&paths, &opts)))?;
    Ok(d)
}

/// What a recording holds (`appell inspect`): its JSON and its text report.
#[pyfunction]
fn inspect_py(py: Python<'_>, paths: Vec<PathBuf>, read: ReadKw) -> PyResult<(String, String)> {
    let (opts, _) = read.resolve()?;
    let ins = py
        .detach(|| appell::data::inspect::inspect(&paths, &opts))
        .map_err(|e| input(e.into()))?;
    Ok((
        appell::report::inspect::inspect_json(&ins).to_string(),
        appell::report::inspect::inspect_text(&ins),
    ))
}

/// One recording's fit: the report, the observations (for the figure), where they came from.
#[pyclass(frozen, module = "appell._appell")]
struct Fit {
    report: FitReport,
    obs: Observations,
    inputs: Vec<PathBuf>,
    rig_label: PathBuf,
    settings: FitSettings,
    notes: Vec<String>,
    /// The note that `fps` was given to files with their own frame times (also in `notes`).
    fps_note: Option<String>,
    seconds: f64,
}

#[pymethods]
impl Fit {
    /// Wall time of the work in Rust (read, check, fit), seconds: the call's overhead is the
    /// rest.
    fn seconds(&self) -> f64 {
        self.seconds
    }

    /// The JSON of `appell fit --json`, as text.
    fn json(&self) -> String {
        let mut v = fit_json(&self.report);
        pipeline::provenance(&mut v, &self.inputs, &self.rig_label);
        v.to_string()
    }

    /// The report `appell fit` prints.
    fn text(&self) -> String {
        fit_text(&self.report)
    }

    /// The one-line answer: mu, its interval and the verdict.
    fn answer(&self) -> String {
        answer(&self.report)
    }

    /// Notes the CLI prints on stderr (frame times joined), and the `fps` note.
    fn notes(&self) -> Vec<String> {
        self.notes.clone()
    }

    /// That `fps` was given to files with their own frame times, which were read instead
    /// (`None`: it was not given, or was used).
    fn fps_note(&self) -> Option<String> {
        self.fps_note.clone()
    }

    /// The fit figure (data, model, residuals, modes) as SVG text.
    fn svg(&self, py: Python<'_>) -> PyResult<String> {
        let figure = FitFigure {
            obs: &self.obs,
            report: &self.report,
        };
        py.detach(|| svg_string(&figure)).map_err(|e| run(e.into()))
    }

    /// Write the fit figure (SVG or PNG by extension), never over an input.
    fn plot(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let figure = FitFigure {
            obs: &self.obs,
            report: &self.report,
        };
        write_figure(py, Some(path), &paths(&self.inputs), &figure)
    }

    /// Write the friction figure: each slide's |F| / |N| against its speed, with the laws.
    fn friction_plot(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        check_figure_path(Some(&path), &paths(&self.inputs))?;
        let Some(law) = &self.report.friction else {
            return Err(PyRuntimeError::new_err(
                "friction_plot: the recording never slides, so it shows no friction law",
            ));
        };
        let name = self
            .inputs
            .first()
            .map_or("recording".to_owned(), |p| p.display().to_string());
        let figure = FrictionFigure {
            rig: &self.report.rig,
            law,
            releases: vec![(
                name,
                appell::fit::law::slide_points_of(&self.report.problem, &self.settings),
            )],
        };
        write_figure(py, Some(path), &paths(&self.inputs), &figure)
    }
}

/// Fit one recording: from its files (`paths`), or from arrays (`t`, `slider`, `bob`; metres,
/// seconds, rail frame, NaN where a marker was not seen).
#[pyfunction]
#[pyo3(signature = (paths, arrays, rig_text, rig_label, read, fit, threads))]
#[allow(clippy::too_many_arguments)]
fn fit_py(
    py: Python<'_>,
    paths: Vec<PathBuf>,
    arrays: Option<(Bound<'_, PyBytes>, Bound<'_, PyBytes>, Bound<'_, PyBytes>)>,
    rig_text: &str,
    rig_label: &str,
    read: ReadKw,
    fit: FitKw,
    threads: Option<usize>,
) -> PyResult<Fit> {
    let started = std::time::Instant::now();
    let (opts, scale) = read.resolve()?;
    let mut setup = setup(rig_text, rig_label, fit, scale)?;
    let (obs, report, notes) = match arrays {
        None => {
            setup.settings.options.cancel = cancel_here();
            interruptible(py, threads, || {
                pipeline::fit_files(&paths, &opts, &setup, true)
            })?
            .map_err(failure)?
        }
        Some((t, s, b)) => {
            // Bounded before the bytes are copied, as a file's frames are.
            appell::data::arrays::check_frames(t.as_bytes().len() / 8)
                .map_err(|e| input(e.into()))?;
            let rec = appell::data::arrays::recording_from_arrays(
                &floats(&t, "t")?,
                &floats(&s, "slider")?,
                &floats(&b, "bob")?,
            )
            .map_err(|e| input(e.into()))?;
            setup.settings.options.cancel = cancel_here();
            interruptible(py, threads, || {
                let obs = pipeline::observations_for_rig(&rec, &setup.rig_path, &setup.rig)
                    .map_err(FitFailure::Input)?;
                let report = pipeline::fit_observations(obs.clone(), &setup, "the arrays")?;
                Ok((obs, report, Vec::new()))
            })?
            .map_err(failure)?
        }
    };
    setup.settings.options.cancel = Cancel::default();
    let seconds = started.elapsed().as_secs_f64();
    let mut notes = notes;
    let fps_note = py.detach(|| fps_unused(&paths, &opts));
    notes.extend(fps_note.iter().map(|n| format!("note: {n}")));
    Ok(Fit {
        report,
        obs,
        inputs: paths,
        rig_label: setup.rig_path.clone(),
        settings: setup.settings,
        notes,
        fps_note,
        seconds,
    })
}

/// A joint fit of releases of one rig.
#[pyclass(frozen, module = "appell._appell")]
struct Joint {
    report: JointReport,
    inputs: Vec<PathBuf>,
    rig_label: PathBuf,
    notes: Vec<String>,
    /// The notes that `fps` was given to releases with their own frame times (also in `notes`).
    fps_notes: Vec<String>,
}

#[pymethods]
impl Joint {
    /// The JSON of `appell fit --joint --json`, as text.
    fn json(&self) -> String {
        let mut v = joint_json(&self.report);
        pipeline::provenance(&mut v, &self.inputs, &self.rig_label);
        v.to_string()
    }

    /// The report `appell fit --joint` prints.
    fn text(&self) -> String {
        joint_text(&self.report)
    }

    /// The one-line answer.
    fn answer(&self) -> String {
        joint_answer(&self.report)
    }

    /// Notes and left-out releases the CLI prints on stderr.
    fn notes(&self) -> Vec<String> {
        self.notes.clone()
    }

    /// That `fps` was given to releases with their own frame times, one note per release.
    fn fps_notes(&self) -> Vec<String> {
        self.fps_notes.clone()
    }

    /// Why the joint fit failed (`None`: it did not).
    fn failed(&self) -> Option<String> {
        self.report.failed.clone()
    }

    /// The joint figure as SVG text.
    fn svg(&self, py: Python<'_>) -> PyResult<String> {
        let figure = JointFigure {
            report: &self.report,
        };
        py.detach(|| svg_string(&figure)).map_err(|e| run(e.into()))
    }

    /// Write the joint figure (SVG or PNG by extension), never over an input.
    fn plot(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let figure = JointFigure {
            report: &self.report,
        };
        write_figure(py, Some(path), &paths(&self.inputs), &figure)
    }
}

/// Fit releases together: `releases` is one directory (its recordings) or a list of releases,
/// each a list of files (a Tracker pair is two).
#[pyfunction]
#[pyo3(signature = (directory, releases, rig_text, rig_label, read, fit, same_camera, keep_going, threads))]
#[allow(clippy::too_many_arguments)]
fn fit_joint_py(
    py: Python<'_>,
    directory: Option<PathBuf>,
    releases: Vec<Vec<PathBuf>>,
    rig_text: &str,
    rig_label: &str,
    read: ReadKw,
    fit: FitKw,
    same_camera: bool,
    keep_going: bool,
    threads: Option<usize>,
) -> PyResult<Joint> {
    let (opts, scale) = read.resolve()?;
    let setup = setup(rig_text, rig_label, fit, scale)?;
    let mut notes = Vec::new();
    let releases = match directory {
        Some(dir) => {
            let (files, skipped) =
                pipeline::directory_files(&dir, opts.format.is_some()).map_err(input)?;
            notes.extend(skipped.into_iter().map(|n| format!("note: {n}")));
            files.into_iter().map(|f| vec![f]).collect()
        }
        None => releases,
    };
    let (paths, dropped) = pipeline::once_each(releases);
    notes.extend(dropped.into_iter().map(|n| format!("note: {n}")));
    let joint = JointSettings {
        same_camera,
        keep_going,
    };
    let mut setup = setup;
    setup.settings.options.cancel = cancel_here();
    let (report, fit_notes) = interruptible(py, threads, || {
        pipeline::fit_joint_files(&paths, &opts, &setup, &joint)
    })?
    .map_err(failure)?;
    notes.extend(fit_notes);
    let fps_notes: Vec<String> =
        py.detach(|| paths.iter().filter_map(|r| fps_unused(r, &opts)).collect());
    notes.extend(fps_notes.iter().map(|n| format!("note: {n}")));
    Ok(Joint {
        report,
        inputs: paths.into_iter().flatten().collect(),
        rig_label: setup.rig_path.clone(),
        notes,
        fps_notes,
    })
}

/// Simulate a scene (TOML text; `label` names it in messages): its JSON (as `appell simulate
/// --json`), its timeline, and the samples column by column (floats as bytes; `mode` names).
#[pyfunction]
#[pyo3(signature = (text, label, frame_rate))]
fn simulate_py<'py>(
    py: Python<'py>,
    text: &str,
    label: &str,
    frame_rate: Option<f64>,
) -> PyResult<Bound<'py, PyDict>> {
    let path = Path::new(label);
    let mut scene = Scene::from_toml(text, path).map_err(|e| input(e.into()))?;
    if let Some(rate) = frame_rate.or(scene.output.frame_rate.is_none().then_some(1000.0)) {
        appell::scene::check_frames(path, scene.duration, rate, "frame_rate")
            .map_err(|e| input(e.into()))?;
        scene.output.frame_rate = Some(rate);
    }
    let sol = py
        .detach(|| {
            appell::sim::simulate(
                &scene.rig,
                &scene.initial,
                scene.duration,
                &scene.options,
                &scene.request(),
            )
        })
        .map_err(|e| run(anyhow::anyhow!(e).context(format!("simulating {label}"))))?;
    let d = PyDict::new(py);
    d.set_item(
        "json",
        appell::report::simulation_json(&scene, &sol).to_string(),
    )?;
    d.set_item("timeline", appell::report::timeline(&scene, &sol))?;
    let col = |f: &dyn Fn(&appell::sim::Sample<f64>) -> f64| -> Vec<f64> {
        sol.samples.iter().map(f).collect()
    };
    let columns = PyDict::new(py);
    columns.set_item("t", to_bytes(py, &col(&|s| s.t)))?;
    for (i, name) in ["x", "theta", "x_dot", "theta_dot"].iter().enumerate() {
        columns.set_item(name, to_bytes(py, &col(&|s| s.state[i])))?;
    }
    for (i, name) in ["slider_x", "slider_y", "bob_x", "bob_y"]
        .iter()
        .enumerate()
    {
        columns.set_item(
            name,
            to_bytes(
                py,
                &col(&|s| appell::model::markers(&scene.rig, &s.state)[i]),
            ),
        )?;
    }
    if scene.output.energy {
        columns.set_item(
            "energy",
            to_bytes(py, &col(&|s| appell::model::energy(&scene.rig, &s.state))),
        )?;
        columns.set_item(
            "friction_work",
            to_bytes(py, &col(&|s| s.friction_work.unwrap_or(f64::NAN))),
        )?;
        columns.set_item(
            "damping_work",
            to_bytes(py, &col(&|s| s.damping_work.unwrap_or(f64::NAN))),
        )?;
    }
    let modes: Vec<&str> = sol.samples.iter().map(|s| s.mode.name()).collect();
    d.set_item("mode", modes)?;
    d.set_item("columns", columns)?;
    Ok(d)
}

/// A plan (TOML text), after an earlier fit's JSON if given: the JSON of `appell plan --json`,
/// its table, and the figure as SVG text.
#[pyfunction]
#[pyo3(signature = (text, label, after_json, after_label, after_path, plot))]
fn plan_py(
    py: Python<'_>,
    text: &str,
    label: &str,
    after_json: Option<&str>,
    after_label: &str,
    after_path: Option<PathBuf>,
    plot: Option<PathBuf>,
) -> PyResult<(String, String, String)> {
    use appell::plan::prior::Prior;
    use appell::plan::PlanSpec;
    let path = Path::new(label);
    check_figure_path(plot.as_deref(), &[path])?;
    let mut spec = PlanSpec::from_toml(text, path).map_err(|e| input(e.into()))?;
    if after_json.is_some() || after_path.is_some() {
        let prior = match (after_json, &after_path) {
            (Some(after), _) => {
                let v: serde_json::Value = serde_json::from_str(after.trim()).map_err(|e| {
                    PyValueError::new_err(format!(
                        "{after_label}: not the JSON of `appell fit --json`: {e}"
                    ))
                })?;
                Prior::from_json(&v, Path::new(after_label))
            }
            (None, Some(p)) => Prior::from_path(p),
            (None, None) => unreachable!("one of the two is given"),
        }
        .map_err(|e| input(e.into()))?;
        let after_path = after_path.as_deref().unwrap_or(Path::new(after_label));
        prior.apply(&mut spec).map_err(|e| input(e.into()))?;
        spec.check_work(path, Some(after_path))
            .map_err(|e| input(e.into()))?;
        spec.prior = Some(prior);
    }
    let report = py
        .detach(|| appell::plan::plan(&spec))
        .map_err(|e| run(e.into()))?;
    let figure = appell::report::plan::PlanFigure { report: &report };
    let svg = svg_string(&figure).map_err(|e| run(e.into()))?;
    write_figure(
        py,
        plot,
        &[path, after_path.as_deref().unwrap_or(path)],
        &figure,
    )?;
    Ok((
        appell::report::plan::plan_json(&report).to_string(),
        appell::report::plan::plan_table(&report),
        svg,
    ))
}

/// A synthetic recording of a scene (TOML text) with the CLI's `synth` options; written to
/// `output` (CSV or MCAP by extension) when given. Returns the recording and the truth.
#[pyfunction]
#[pyo3(signature = (text, label, fps, duration, noise, dropout, outliers, outlier_size, seed, output))]
#[allow(clippy::too_many_arguments)]
fn synth_py<'py>(
    py: Python<'py>,
    text: &str,
    label: &str,
    fps: f64,
    duration: Option<f64>,
    noise: f64,
    dropout: f64,
    outliers: f64,
    outlier_size: f64,
    seed: u64,
    output: Option<PathBuf>,
) -> PyResult<Bound<'py, PyDict>> {
    let opts = SynthOptions {
        fps,
        duration,
        noise,
        dropout,
        outliers,
        outlier_size,
        seed,
    };
    opts.validate().map_err(PyValueError::new_err)?;
    let path = Path::new(label);
    let scene = Scene::from_toml(text, path).map_err(|e| input(e.into()))?;
    appell::scene::check_frames(path, duration.unwrap_or(scene.duration), fps, "fps")
        .map_err(|e| input(e.into()))?;
    if let Some(out) = &output {
        appell::output::refuse_input(out, &[path]).map_err(|e| input(anyhow::anyhow!(e)))?;
    }
    let syn = py
        .detach(|| synth::synthesize(&scene, &opts))
        .map_err(|e| run(anyhow::anyhow!(e).context(format!("simulating {label}"))))?;
    if let Some(out) = &output {
        py.detach(|| synth::write(out, &syn.recording, &syn.truth))
            .map_err(|e| run(e.into()))?;
    }
    let d = recording_dict(py, &syn.recording)?;
    let truth = PyDict::new(py);
    for (k, v) in &syn.truth {
        truth.set_item(k, v)?;
    }
    d.set_item("truth", truth)?;
    d.set_item("stopped_at", syn.stopped_at)?;
    Ok(d)
}

/// The regions of a rig (TOML text): the JSON of `appell regions --json`, its summary, and
/// the figure as SVG text.
#[pyfunction]
#[pyo3(signature = (text, label, trajectories, duration, plot))]
fn regions_py(
    py: Python<'_>,
    text: &str,
    label: &str,
    trajectories: usize,
    duration: f64,
    plot: Option<PathBuf>,
) -> PyResult<(String, String, String)> {
    use appell::model::regions::RegionMap;
    use appell::report::regions::{
        figure_window, phase_portrait, regions_json, regions_summary, PortraitOptions, RegionFigure,
    };
    pipeline::check_portrait(trajectories, duration).map_err(PyValueError::new_err)?;
    check_figure_path(plot.as_deref(), &[Path::new(label)])?;
    let rig = appell::scene::RigFile::parse(text, Path::new(label)).map_err(|e| input(e.into()))?;
    let (json, summary, svg, map, paths) = py.detach(|| {
        let map = RegionMap::new(&rig, &figure_window(&rig));
        let paths = phase_portrait(
            &rig,
            &PortraitOptions {
                trajectories,
                duration,
                ..PortraitOptions::default()
            },
        );
        let svg = svg_string(&RegionFigure::new(&rig, &map, &paths)).map_err(|e| run(e.into()))?;
        PyResult::Ok((
            regions_json(&map, &paths).to_string(),
            regions_summary(&rig, &map, &paths),
            svg,
            map,
            paths,
        ))
    })?;
    let figure = RegionFigure::new(&rig, &map, &paths);
    write_figure(py, plot, &[Path::new(label)], &figure)?;
    Ok((json, summary, svg))
}

/// The paths a figure must not be written over, as `check_figure_path` takes them.
fn paths(files: &[PathBuf]) -> Vec<&Path> {
    files.iter().map(PathBuf::as_path).collect()
}

/// A figure's path checked before any work: SVG or PNG, and never one of the inputs.
fn check_figure_path(plot: Option<&Path>, inputs: &[&Path]) -> PyResult<()> {
    if let Some(p) = plot {
        appell::report::plot::ImageFormat::from_path(p).map_err(|e| input(e.into()))?;
        appell::output::refuse_input(p, inputs).map_err(|e| input(anyhow::anyhow!(e)))?;
    }
    Ok(())
}

/// Write `figure` to `plot` when given (SVG or PNG by extension), never over an input.
fn write_figure(
    py: Python<'_>,
    plot: Option<PathBuf>,
    inputs: &[&Path],
    figure: &(impl appell::report::plot::Figure + Sync),
) -> PyResult<()> {
    let Some(p) = plot else { return Ok(()) };
    check_figure_path(Some(&p), inputs)?;
    py.detach(|| render(&p, figure)).map_err(|e| run(e.into()))
}

/// A TOML file's text (a rig, scene or plan file), with the CLI's size limit and messages.
#[pyfunction]
fn read_toml_py(path: PathBuf) -> PyResult<String> {
    appell::scene::read_text(&path, appell::scene::MAX_TOML_BYTES).map_err(|e| input(e.into()))
}

/// Refuse a recording of `frames` frames that a file could not hold (before its arrays are
/// copied): `ValueError` naming the bound.
#[pyfunction]
fn check_frames_py(frames: usize) -> PyResult<()> {
    appell::data::arrays::check_frames(frames).map_err(|e| input(e.into()))
}

/// Check a rig file's text as a fit loads it (`ValueError` naming the key at fault).
#[pyfunction]
fn check_rig_py(text: &str, label: &str) -> PyResult<()> {
    appell::scene::RigFile::parse_on_earth(text, Path::new(label), pipeline::MU_GUESS, None)
        .map(|_| ())
        .map_err(|e| input(e.into()))
}

/// The version of the Rust library (`appell X.Y.Z`, as the CLI's JSON says).
#[pyfunction]
fn version() -> &'static str {
    concat!("appell ", env!("CARGO_PKG_VERSION"))
}

#[pymodule]
fn _appell(m: &Bound<'_, PyModule>) -> PyResult<()> {
    // A wheel built for another machine's CPU: an ImportError that says so, not a crash.
    if let Some(feature) = appell::cpu::missing_feature() {
        return Err(pyo3::exceptions::PyImportError::new_err(format!(
            "{}{feature}{}",
            appell::cpu::REFUSAL_START,
            appell::cpu::REFUSAL_END
        )));
    }
    m.add_function(wrap_pyfunction!(read_recording_py, m)?)?;
    m.add_function(wrap_pyfunction!(inspect_py, m)?)?;
    m.add_function(wrap_pyfunction!(fit_py, m)?)?;
    m.add_function(wrap_pyfunction!(fit_joint_py, m)?)?;
    m.add_function(wrap_pyfunction!(simulate_py, m)?)?;
    m.add_function(wrap_pyfunction!(plan_py, m)?)?;
    m.add_function(wrap_pyfunction!(synth_py, m)?)?;
    m.add_function(wrap_pyfunction!(regions_py, m)?)?;
    m.add_function(wrap_pyfunction!(version, m)?)?;
    m.add_function(wrap_pyfunction!(read_toml_py, m)?)?;
    m.add_function(wrap_pyfunction!(check_rig_py, m)?)?;
    m.add_function(wrap_pyfunction!(check_frames_py, m)?)?;
    m.add_class::<Fit>()?;
    m.add_class::<Joint>()?;
    Ok(())
}
