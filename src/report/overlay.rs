//! Overlays: a fit, a simulation or a synthetic recording written back as MCAP for Foxglove
//! (the topics of docs/overlay.md, by [`crate::data::mcap::overlay::OverlayWriter`]).
//!
//! The model's markers, modes and forces come from one run of the simulator over the frame
//! times, the model's own functions turning each sample into markers
//! ([`crate::model::observed_markers`]) and forces ([`crate::model::Rig::contact`]): the same
//! numbers `appell simulate` gives for the fitted scene. Frames are written as the run passes
//! them, so a long recording keeps no per-frame state.

use crate::data::mcap::overlay::{ModelFrame, OverlayFrame, OverlayWriter, Topics};
use crate::fit::{FitReport, Observations};
use crate::model::{observed_markers, Camera, Rig, State};
use crate::sim::{simulate_each, Event, Options, Request, Sample};
use std::collections::BTreeMap;
use std::io::Write;

/// Why an overlay could not be written.
#[derive(Debug, thiserror::Error)]
pub enum OverlayError {
    /// The model could not be simulated over the frames.
    #[error("simulating the model over the frames: {0}")]
    Sim(#[from] crate::sim::SimError),
    /// The MCAP file could not be written.
    #[error("{0}")]
    Mcap(#[from] ::mcap::McapError),
}

impl From<OverlayError> for std::io::Error {
    fn from(e: OverlayError) -> Self {
        match e {
            OverlayError::Mcap(::mcap::McapError::Io(io)) => io,
            other => std::io::Error::other(other.to_string()),
        }
    }
}

/// The model a run samples: rig, start, camera and the integrator's options.
pub struct ModelRun<'a> {
    /// The rig.
    pub rig: &'a Rig<f64>,
    /// State at the first frame.
    pub initial: &'a State<f64>,
    /// How the camera sees the markers (the ideal camera for a simulation).
    pub camera: &'a Camera<f64>,
    /// Integrator options.
    pub options: &'a Options,
}

impl ModelRun<'_> {
    /// The model at one sample: markers, mode and forces.
    pub fn frame(&self, s: &Sample<f64>) -> ModelFrame {
        ModelFrame {
            markers: observed_markers(self.rig, self.camera, s.mode, &s.state),
            mode: s.mode,
            contact: self.rig.contact(s.mode, &s.state),
        }
    }
}

/// One marker's recorded positions, a frame each (`None` where it was not seen).
pub type Positions<'a> = &'a [Option<[f64; 2]>];

/// What an overlay holds besides the model: frame times (s from the first frame), the
/// recorded tracks when there is a recording, the events, the answer line and the metadata.
pub struct OverlayInput<'a> {
    /// Frame times (s from the first frame, ascending).
    pub times: &'a [f64],
    /// Slider and bob as recorded, one entry per frame (`None`: no recording).
    pub recorded: Option<[Positions<'a>; 2]>,
    /// The model's events (the fit's, or the simulation's).
    pub events: &'a [Event],
    /// The one-line answer, written at the first frame.
    pub answer: Option<String>,
    /// The first frame's stamp in the recording's clock (ns).
    pub origin_ns: u64,
    /// MCAP metadata records (name -> key -> value).
    pub metadata: BTreeMap<String, BTreeMap<String, String>>,
}

/// Write an overlay of `input` and the model `run` (sampled at every frame time) on `w`.
/// Frames the run does not reach (it stopped at a paradox) keep their recorded markers only.
pub fn write_overlay(
    w: &mut dyn Write,
    input: &OverlayInput,
    run: Option<&ModelRun>,
) -> Result<(), OverlayError> {
    let topics = Topics {
        recorded: input.recorded.is_some(),
        model: run.is_some(),
    };
    let mut out = OverlayWriter::new(w, input.origin_ns, topics, input.events, &input.metadata)?;
    let times = input.times;
    if let (Some(answer), Some(&t0)) = (&input.answer, times.first()) {
        out.answer(t0, answer)?;
    }
    let recorded = |i: usize| input.recorded.map(|[s, b]| [s[i], b[i]]);
    let mut written = 0;
    if let (Some(run), Some(&t_end)) = (run, times.last()) {
        let mut failed: Option<::mcap::McapError> = None;
        simulate_each(
            run.rig,
            run.initial,
            t_end,
            run.options,
            &Request {
                sample_times: times.to_vec(),
                friction_work: false,
                positions_only: false,
            },
            &mut |s| {
                if failed.is_some() {
                    return;
                }
                let frame = OverlayFrame {
                    t: s.t,
                    recorded: recorded(written),
                    model: Some(run.frame(&s)),
                };
                written += 1;
                if let Err(e) = out.frame(&frame) {
                    failed = Some(e);
                }
            },
        )?;
        if let Some(e) = failed {
            return Err(e.into());
        }
    }
    for (i, &t) in times.iter().enumerate().skip(written) {
        out.frame(&OverlayFrame {
            t,
            recorded: recorded(i),
            model: None,
        })?;
    }
    out.finish()?;
    Ok(())
}

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
