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
    let run = ModelRun {
        rig: &rep.rig,
        initial: &rep.initial,
        camera: &rep.camera,
        options: &rep.problem.options,
    };
    model_overlay(
        w,
        obs,
        &run,
        &rep.events,
        super::fit::answer(rep),
        origin_ns,
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
    let run = ModelRun {
        rig: &part.rig,
        initial: &part.initial,
        camera: &part.camera,
        options: &part.options,
    };
    model_overlay(w, obs, &run, &events, answer, origin_ns)
}

/// A recording and a model's run over its frames, with the model's events and an answer line.
fn model_overlay(
    w: &mut dyn Write,
    obs: &Observations,
    run: &ModelRun,
    events: &[crate::sim::Event],
    answer: String,
    origin_ns: u64,
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
    };
    write_overlay(w, &input, Some(run))
}

/// Where `fit --joint --overlay OUT.mcap` writes a release's overlay: beside `OUT`, named
/// `OUT`'s stem, an underscore and the release's first file's stem (`fit_release_03.mcap`).
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
    out.with_file_name(format!("{stem}_{name}.mcap"))
}

/// The kinds of overlay file, by the output's extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OverlayFormat {
    /// MCAP for Foxglove (`.mcap`).
    Mcap,
}

/// An overlay path whose extension names no overlay format.
#[derive(Debug, thiserror::Error)]
#[error("--overlay {}: expected a file ending in .mcap (Foxglove), got {}", path.display(), ext.as_deref().map_or("no extension".to_owned(), |e| format!(".{e}")))]
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
    };
    let run = ModelRun {
        rig: &scene.rig,
        initial: &scene.initial,
        camera: &crate::model::Camera::default(),
        options: &scene.options,
    };
    write_overlay(w, &input, Some(&run))
}
