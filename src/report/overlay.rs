//! Overlays of a fit: the recording and the fitted model written back as MCAP for Foxglove
//! (the topics of docs/overlay.md, by [`crate::data::mcap::overlay::write_overlay`]).
//!
//! The model's markers, modes and forces come from one run of the simulator over the frame
//! times with the fit's rig, start, camera and integrator options, the model's own functions
//! turning each sample into markers and forces: the same numbers `appell simulate` gives for
//! the fitted scene.

use crate::data::mcap::overlay::{write_overlay, ModelRun, OverlayError, OverlayInput};
use crate::fit::{FitReport, Observations};
use std::collections::BTreeMap;
use std::io::Write;

/// The overlay of `appell fit --overlay`: the recording (`obs`, frames from zero), the fitted
/// model at every frame (the fit's rig, start, camera and integrator options), the fit's
/// events and its one-line answer, stamped from `origin_ns` (the recording's first frame in
/// its own clock, [`crate::data::Provenance::origin_ns`]).
pub fn write_fit_overlay(
    w: &mut dyn Write,
    obs: &Observations,
    rep: &FitReport,
    origin_ns: u64,
) -> Result<(), OverlayError> {
    write_fit_overlay_with_input(w, obs, rep, origin_ns, None)
}

/// [`write_fit_overlay`], with the recording's own MCAP file (`input`, its bytes) copied
/// beside the overlay's topics when given: its channels, schemas and messages as they are
/// (`appell fit --overlay-with-input`).
pub fn write_fit_overlay_with_input(
    w: &mut dyn Write,
    obs: &Observations,
    rep: &FitReport,
    origin_ns: u64,
    input: Option<&[u8]>,
) -> Result<(), OverlayError> {
    let run = fit_run(rep);
    model_overlay(
        w,
        obs,
        &run,
        &rep.events,
        super::fit::answer(rep),
        origin_ns,
        input,
    )
}

/// The overlay of one release of `appell fit --joint --overlay`: the release's recording and
/// the joint model at its optimum for that release (`part`), its events (the model's own run
/// over the release's frames) and the joint fit's one-line answer, stamped from `origin_ns`.
pub fn write_release_overlay(
    w: &mut dyn Write,
    part: &crate::fit::TrajectoryProblem,
    answer: String,
    origin_ns: u64,
) -> Result<(), OverlayError> {
    let obs = part.observations();
    let t_end = obs.times.last().copied().unwrap_or(0.0);
    let events = crate::sim::simulate_each(
        &part.rig,
        &part.initial,
        t_end,
        &part.options,
        // Sampled at the frames as the overlay's run is: a run that samples nothing takes its
        // stick phases in closed form, with switch times a nanosecond apart from these.
        &crate::sim::Request {
            sample_times: obs.times.clone(),
            ..crate::sim::Request::default()
        },
        &mut |_| {},
    )?
    .events;
    let run = part_run(part);
    model_overlay(w, obs, &run, &events, answer, origin_ns, None)
}

/// The fitted model a fit's overlays sample: its rig, start, camera and integrator options.
fn fit_run(rep: &FitReport) -> ModelRun<'_> {
    ModelRun {
        rig: &rep.rig,
        initial: &rep.initial,
        camera: &rep.camera,
        options: &rep.problem.options,
    }
}

/// The joint model at its optimum for one release (`part`), as its overlays sample it.
fn part_run(part: &crate::fit::TrajectoryProblem) -> ModelRun<'_> {
    ModelRun {
        rig: &part.rig,
        initial: &part.initial,
        camera: &part.camera,
        options: &part.options,
    }
}

/// A recording and a model's run over its frames, with the model's events and an answer line.
fn model_overlay(
    w: &mut dyn Write,
    obs: &Observations,
    run: &ModelRun,
    events: &[crate::sim::Event],
    answer: String,
    origin_ns: u64,
    with_input: Option<&[u8]>,
) -> Result<(), OverlayError> {
    let mut metadata = BTreeMap::new();
    metadata.insert(
        "appell.fit".to_owned(),
        BTreeMap::from([
            ("answer".to_owned(), answer.clone()),
            (
                "version".to_owned(),
                concat!("appell ", env!("CARGO_PKG_VERSION")).to_owned(),
            ),
        ]),
    );
    let input = OverlayInput {
        times: &obs.times,
        recorded: Some([&obs.slider, &obs.bob]),
        events,
        answer: Some(answer),
        origin_ns,
        lab_markers: false,
        metadata,
        with_input,
    };
    write_overlay(w, &input, Some(run))
}

/// Where `fit --joint --overlay OUT.mcap` writes a release's overlay: beside `OUT`, named
/// `OUT`'s stem, an underscore and the release's first file's stem (`fit_release_03.mcap`;
/// `OUT`'s own extension, `.csv` for tables).
pub fn release_overlay_path(
    out: &std::path::Path,
    release: &[std::path::PathBuf],
) -> std::path::PathBuf {
    let stem = out
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let name = release
        .first()
        .and_then(|p| p.file_stem())
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let ext = out
        .extension()
        .map_or("mcap".to_owned(), |e| e.to_string_lossy().into_owned());
    out.with_file_name(format!("{stem}_{name}.{ext}"))
}

/// The overlay of `appell fit --overlay FILE.csv`: the fitted model's markers at every frame
/// (the fit's rig, start, camera and integrator options, one run as for the MCAP overlay) in
/// the recording's own units, axes and time column, in its tool's table where it has one
/// ([`crate::data::overlay_csv`]); `prov` is the recording's provenance (its calibration,
/// format, marker names and clock).
pub fn write_fit_overlay_csv(
    w: &mut dyn Write,
    obs: &Observations,
    rep: &FitReport,
    prov: &crate::data::Provenance,
) -> Result<(), OverlayError> {
    let run = fit_run(rep);
    model_csv(w, &obs.times, &run, prov)
}

/// The `.csv` overlay of one release of `appell fit --joint`: the joint model at its optimum
/// for that release (`part`), in the release's own units and time column (`prov`).
pub fn write_release_overlay_csv(
    w: &mut dyn Write,
    part: &crate::fit::TrajectoryProblem,
    prov: &crate::data::Provenance,
) -> Result<(), OverlayError> {
    let run = part_run(part);
    model_csv(w, &part.observations().times, &run, prov)
}

/// A model's run over the frames written as a table in the recording's own units.
fn model_csv(
    w: &mut dyn Write,
    times: &[f64],
    run: &ModelRun,
    prov: &crate::data::Provenance,
) -> Result<(), OverlayError> {
    let mut out = crate::data::overlay_csv::CsvOverlay::new(w, prov)?;
    let mut failed: Option<std::io::Error> = None;
    run.each_frame(times, &mut |t, m| {
        if failed.is_none() {
            failed = out.row(t, m.map(|m| m.markers)).err();
        }
    })?;
    if let Some(e) = failed {
        return Err(e.into());
    }
    out.finish()?;
    Ok(())
}

/// The kinds of overlay file, by the output's extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OverlayFormat {
    /// MCAP for Foxglove (`.mcap`).
    Mcap,
    /// The model's markers as a table in the recording's own units and layout (`.csv`).
    Csv,
}

/// An overlay path whose extension names no overlay format.
#[derive(Debug, thiserror::Error)]
#[error("--overlay {}: expected a file ending in .mcap (Foxglove) or .csv (the model's markers in the recording's own units), got {}", path.display(), ext.as_deref().map_or("no extension".to_owned(), |e| format!(".{e}")))]
pub struct UnknownOverlay {
    /// The path given.
    pub path: std::path::PathBuf,
    /// Its extension, if any.
    pub ext: Option<String>,
}

impl OverlayFormat {
    /// The format an overlay path asks for by its extension (any letter case).
    pub fn from_path(path: &std::path::Path) -> Result<OverlayFormat, UnknownOverlay> {
        let ext = path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase());
        match ext.as_deref() {
            Some("mcap") => Ok(OverlayFormat::Mcap),
            Some("csv") => Ok(OverlayFormat::Csv),
            _ => Err(UnknownOverlay {
                path: path.to_owned(),
                ext,
            }),
        }
    }
}

/// The overlay of `appell simulate --out FILE.mcap`: the scene's motion as the model (its
/// markers as an ideal camera sees them, modes, forces and events) at the samples' times,
/// stamped from zero.
pub fn write_simulation_overlay(
    w: &mut dyn Write,
    scene: &crate::scene::Scene,
    sol: &crate::sim::Solution<f64>,
) -> Result<(), OverlayError> {
    let times: Vec<f64> = sol.samples.iter().map(|s| s.t).collect();
    let last = times.last().copied().unwrap_or(0.0);
    let events: Vec<_> = sol.events.iter().filter(|e| e.t <= last).cloned().collect();
    let input = OverlayInput {
        times: &times,
        recorded: None,
        events: &events,
        answer: None,
        origin_ns: 0,
        lab_markers: false,
        metadata: BTreeMap::new(),
        with_input: None,
    };
    let run = ModelRun {
        rig: &scene.rig,
        initial: &scene.initial,
        camera: &crate::model::Camera::default(),
        options: &scene.options,
    };
    write_overlay(w, &input, Some(&run))
}
