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
    let answer = super::fit::answer(rep);
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
        events: &rep.events,
        answer: Some(answer),
        origin_ns,
        lab_markers: false,
        metadata,
    };
    let run = ModelRun {
        rig: &rep.rig,
        initial: &rep.initial,
        camera: &rep.camera,
        options: &rep.problem.options,
    };
    write_overlay(w, &input, Some(&run))
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
