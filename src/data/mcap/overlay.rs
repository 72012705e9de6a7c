//! The overlay writer: a recording and a model's motion as MCAP for Foxglove, on the topics
//! docs/overlay.md lists. Marker positions go out as Foxglove's well-known `foxglove.SceneUpdate`
//! (protobuf, the schemas from the `foxglove` crate) so the 3D panel draws them; the numbers a
//! plot wants (coordinates, residuals, mode, forces) as JSON with a JSON Schema each, since
//! Foxglove's plot panel reads any field; events and the answer as `foxglove.Log`.
//!
//! One writer serves `fit --overlay`, `synth` and `simulate --out`: frames are handed to it in
//! time order and written as they come (no frame is kept), events at their own times between
//! them.

use crate::model::{Camera, Contact, Mode, Rig, State};
use crate::sim::{simulate_each, Event, Options, Request};
use ::mcap::records::{MessageHeader, Metadata};
use ::mcap::McapError;
use foxglove::messages::{
    line_primitive, log, Color, Log, Point3, Pose, Quaternion, SceneEntity, SceneUpdate,
    SpherePrimitive, Timestamp, Vector3,
};
use foxglove::Encode;
use serde::Serialize;
use std::collections::BTreeMap;
use std::io::Write;

/// The frame every position is given in: the rail frame (x along the rail, y up, metres).
pub const OVERLAY_FRAME_ID: &str = "rail";

/// Topic of the recorded markers (`foxglove.SceneUpdate`).
pub const TOPIC_RECORDED: &str = "/appell/recorded";
/// Topic of the model's markers and rod (`foxglove.SceneUpdate`).
pub const TOPIC_MODEL: &str = "/appell/model";
/// Topic of both marker sets' coordinates, for plots (JSON `appell.Markers`).
pub const TOPIC_MARKERS: &str = "/appell/markers";
/// Topic of each frame's residual, model minus recorded (JSON `appell.Residual`).
pub const TOPIC_RESIDUAL: &str = "/appell/residual";
/// Topic of the model's mode (JSON `appell.Mode`).
pub const TOPIC_MODE: &str = "/appell/mode";
/// Topic of the rail's forces and the friction coefficient in use (JSON `appell.Forces`).
pub const TOPIC_FORCES: &str = "/appell/forces";
/// Topic of the mode switches, one `foxglove.Log` at each event's time.
pub const TOPIC_EVENTS: &str = "/appell/events";
/// Topic of the one-line answer (`foxglove.Log`, once, at the first frame).
pub const TOPIC_ANSWER: &str = "/appell/answer";

/// JSON Schema of [`TOPIC_MARKERS`]' messages.
pub const MARKERS_SCHEMA: &str = r#"{"title":"appell.Markers","type":"object","properties":{"t":{"type":"number","description":"seconds from the first frame"},"recorded":{"type":["object","null"],"properties":{"slider_x":{"type":["number","null"]},"slider_y":{"type":["number","null"]},"bob_x":{"type":["number","null"]},"bob_y":{"type":["number","null"]}}},"model":{"type":["object","null"],"properties":{"slider_x":{"type":["number","null"]},"slider_y":{"type":["number","null"]},"bob_x":{"type":["number","null"]},"bob_y":{"type":["number","null"]}}}}}"#;
/// JSON Schema of [`TOPIC_RESIDUAL`]'s messages.
pub const RESIDUAL_SCHEMA: &str = r#"{"title":"appell.Residual","type":"object","properties":{"t":{"type":"number"},"slider_x":{"type":["number","null"]},"slider_y":{"type":["number","null"]},"bob_x":{"type":["number","null"]},"bob_y":{"type":["number","null"]},"slider":{"type":["number","null"]},"bob":{"type":["number","null"]}}}"#;
/// JSON Schema of [`TOPIC_MODE`]'s messages.
pub const MODE_SCHEMA: &str = r#"{"title":"appell.Mode","type":"object","properties":{"t":{"type":"number"},"mode":{"type":"string","enum":["stick","slide+","slide-"]},"sliding":{"type":"integer"},"direction":{"type":"integer"}}}"#;
/// JSON Schema of [`TOPIC_FORCES`]' messages.
pub const FORCES_SCHEMA: &str = r#"{"title":"appell.Forces","type":"object","properties":{"t":{"type":"number"},"normal":{"type":"number","description":"rail reaction N (N)"},"friction":{"type":"number","description":"friction along the rail, positive toward +x (N)"},"mu":{"type":"number","description":"the law's mu while sliding, |F|/|N| while stuck"}}}"#;

/// The JSON schema names [`OverlayWriter`] writes: none holds a marker position the MCAP reader
/// should take for a marker.
pub const OVERLAY_JSON_SCHEMAS: [&str; 4] = [
    "appell.Markers",
    "appell.Residual",
    "appell.Mode",
    "appell.Forces",
];

/// The model at one frame: its markers `[slider_x, slider_y, bob_x, bob_y]` (m, rail frame),
/// its mode and the rail's forces.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModelFrame {
    /// Marker positions (m).
    pub markers: [f64; 4],
    /// Mode at the frame.
    pub mode: Mode,
    /// Forces and the friction coefficient in use.
    pub contact: Contact<f64>,
}

impl ModelFrame {
    /// The model at one sample of a run: its markers as `camera` sees them
    /// ([`crate::model::observed_markers`]), its mode and its forces ([`crate::model::Rig::contact`]).
    pub fn of(
        rig: &crate::model::Rig<f64>,
        camera: &crate::model::Camera<f64>,
        s: &crate::sim::Sample<f64>,
    ) -> ModelFrame {
        ModelFrame {
            markers: crate::model::observed_markers(rig, camera, s.mode, &s.state),
            mode: s.mode,
            contact: rig.contact(s.mode, &s.state),
        }
    }
}

/// One frame of an overlay: its time (s from the first frame), the recorded markers when
/// there is a recording, the model when there is one.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OverlayFrame {
    /// Time (s from the first frame).
    pub t: f64,
    /// Slider and bob as recorded (`None` where a marker was not seen); `None` without a
    /// recording.
    pub recorded: Option<[Option<[f64; 2]>; 2]>,
    /// The model; `None` without one.
    pub model: Option<ModelFrame>,
}

/// Which topics an overlay holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Topics {
    /// The recorded markers also as appell's own recording (`/markers`, JSON
    /// `lab.MarkerFrame2D`, [`super::write_json`]), which its reader reads back: `synth`'s.
    pub lab_markers: bool,
    /// The recorded markers.
    pub recorded: bool,
    /// The model's markers, mode and forces (and the residual, with `recorded`).
    pub model: bool,
}

#[derive(Serialize)]
struct XY {
    slider_x: Option<f64>,
    slider_y: Option<f64>,
    bob_x: Option<f64>,
    bob_y: Option<f64>,
}

impl XY {
    fn of(m: [Option<[f64; 2]>; 2]) -> XY {
        XY {
            slider_x: m[0].map(|p| p[0]),
            slider_y: m[0].map(|p| p[1]),
            bob_x: m[1].map(|p| p[0]),
            bob_y: m[1].map(|p| p[1]),
        }
    }
}

#[derive(Serialize)]
struct MarkersMsg {
    t: f64,
    recorded: Option<XY>,
    model: Option<XY>,
}

#[derive(Serialize)]
struct ResidualMsg {
    t: f64,
    #[serde(flatten)]
    xy: XY,
    slider: Option<f64>,
    bob: Option<f64>,
}

#[derive(Serialize)]
struct ModeMsg {
    t: f64,
    mode: &'static str,
    sliding: u8,
    direction: i8,
}

#[derive(Serialize)]
struct ForcesMsg {
    t: f64,
    normal: f64,
    friction: f64,
    mu: f64,
}

/// The channel ids of the topics written.
struct Channels {
    recorded: u16,
    model: u16,
    markers: u16,
    residual: u16,
    mode: u16,
    forces: u16,
    events: u16,
    answer: u16,
}

/// Writes an overlay frame by frame (see the module's description). Created with the events to
/// interleave; [`OverlayWriter::finish`] ends the file.
pub struct OverlayWriter<'w> {
    out: ::mcap::Writer<::mcap::write::NoSeek<&'w mut dyn Write>>,
    ch: Option<Channels>,
    lab: Option<u16>,
    topics: Topics,
    origin_ns: u64,
    events: Vec<Event>,
    next_event: usize,
    sequence: u32,
    buf: Vec<u8>,
}

/// Colours: recorded markers blue, the model by mode (Okabe and Ito's palette, as the figure).
fn color(r: u8, g: u8, b: u8) -> Color {
    Color {
        r: f64::from(r) / 255.0,
        g: f64::from(g) / 255.0,
        b: f64::from(b) / 255.0,
        a: 1.0,
    }
}

fn mode_color(m: Mode) -> Color {
    match m {
        Mode::Stick => color(0, 0, 0),
        Mode::Slide(crate::model::Direction::Positive) => color(213, 94, 0),
        Mode::Slide(crate::model::Direction::Negative) => color(0, 114, 178),
    }
}

/// Diameter of the drawn marker spheres (m).
const MARKER_SIZE: f64 = 0.01;

fn sphere(p: [f64; 2], c: Color) -> SpherePrimitive {
    SpherePrimitive {
        pose: Some(Pose {
            position: Some(Vector3 {
                x: p[0],
                y: p[1],
                z: 0.0,
            }),
            orientation: Some(Quaternion {
                x: 0.0,
                y: 0.0,
                z: 0.0,
                w: 1.0,
            }),
        }),
        size: Some(Vector3 {
            x: MARKER_SIZE,
            y: MARKER_SIZE,
            z: MARKER_SIZE,
        }),
        color: Some(c),
    }
}

fn stamp(ns: u64) -> Timestamp {
    Timestamp::new((ns / 1_000_000_000) as u32, (ns % 1_000_000_000) as u32)
}

fn io(e: impl Into<std::io::Error>) -> McapError {
    McapError::Io(e.into())
}

impl<'w> OverlayWriter<'w> {
    /// Start an overlay on `w`: `origin_ns` is the first frame's stamp in the recording's
    /// clock (ns; frames at `origin_ns` + t), `events` the model's, in time order, written at
    /// their times on [`TOPIC_EVENTS`]; `metadata` one MCAP metadata record per entry.
    pub fn new(
        w: &'w mut dyn Write,
        origin_ns: u64,
        topics: Topics,
        events: &[Event],
        metadata: &BTreeMap<String, BTreeMap<String, String>>,
    ) -> Result<Self, McapError> {
        // An overlay's frames are eight small messages each: zstd's fastest level writes them
        // at a fraction of the default level's cost (which took a fifth of a long fit with its
        // overlay), and lz4's frame encoder pays per message. A recording alone keeps the
        // default level's smaller file.
        let level = if topics.recorded || topics.model {
            1
        } else {
            0
        };
        let mut out = ::mcap::WriteOptions::new()
            .compression(Some(::mcap::Compression::Zstd))
            .compression_level(level)
            .compression_threads(0)
            .profile("")
            .disable_seeking(true)
            .create(::mcap::write::NoSeek::new(w))?;
        let none = BTreeMap::new();
        let lab = match topics.lab_markers {
            true => {
                let id =
                    out.add_schema("lab.MarkerFrame2D", "jsonschema", FRAME_SCHEMA.as_bytes())?;
                Some(out.add_channel(id, "/markers", "json", &none)?)
            }
            false => None,
        };
        let proto = |out: &mut ::mcap::Writer<_>, schema: foxglove::Schema, topic: &str| {
            let id = out.add_schema(&schema.name, &schema.encoding, &schema.data)?;
            out.add_channel(id, topic, "protobuf", &none)
        };
        let overlay = topics.recorded || topics.model;
        let scene = SceneUpdate::get_schema().expect("foxglove.SceneUpdate has a schema");
        let log = Log::get_schema().expect("foxglove.Log has a schema");
        let ch = if overlay {
            let recorded = proto(&mut out, scene.clone(), TOPIC_RECORDED)?;
            let model = proto(&mut out, scene, TOPIC_MODEL)?;
            let events_ch = proto(&mut out, log.clone(), TOPIC_EVENTS)?;
            let answer = proto(&mut out, log, TOPIC_ANSWER)?;
            let json = |out: &mut ::mcap::Writer<_>, name: &str, schema: &str, topic: &str| {
                let id = out.add_schema(name, "jsonschema", schema.as_bytes())?;
                out.add_channel(id, topic, "json", &none)
            };
            let markers = json(&mut out, "appell.Markers", MARKERS_SCHEMA, TOPIC_MARKERS)?;
            let residual = json(&mut out, "appell.Residual", RESIDUAL_SCHEMA, TOPIC_RESIDUAL)?;
            let mode = json(&mut out, "appell.Mode", MODE_SCHEMA, TOPIC_MODE)?;
            let forces = json(&mut out, "appell.Forces", FORCES_SCHEMA, TOPIC_FORCES)?;
            Some(Channels {
                recorded,
                model,
                markers,
                residual,
                mode,
                forces,
                events: events_ch,
                answer,
            })
        } else {
            None
        };
        for (name, map) in metadata {
            out.write_metadata(&Metadata {
                name: name.clone(),
                metadata: map.clone(),
            })?;
        }
        Ok(OverlayWriter {
            out,
            ch,
            lab,
            topics,
            origin_ns,
            events: events.to_owned(),
            next_event: 0,
            sequence: 0,
            buf: Vec::with_capacity(512),
        })
    }

    /// The stamp (ns in the recording's clock) of time `t` (s from the first frame).
    pub fn stamp_of(&self, t: f64) -> u64 {
        stamp_of(self.origin_ns, t)
    }

    /// Write `self.buf` on `channel` at `ns`.
    fn put(&mut self, channel: u16, ns: u64) -> Result<(), McapError> {
        self.sequence = self.sequence.wrapping_add(1);
        self.out.write_to_known_channel(
            &MessageHeader {
                channel_id: channel,
                sequence: self.sequence,
                log_time: ns,
                publish_time: ns,
            },
            &self.buf,
        )
    }

    fn put_json(&mut self, channel: u16, ns: u64, msg: &impl Serialize) -> Result<(), McapError> {
        self.buf.clear();
        serde_json::to_writer(&mut self.buf, msg).map_err(io)?;
        self.put(channel, ns)
    }

    fn put_proto(&mut self, channel: u16, ns: u64, msg: &impl Encode) -> Result<(), McapError> {
        self.buf.clear();
        msg.encode(&mut self.buf)
            .map_err(|e| io(std::io::Error::other(e.to_string())))?;
        self.put(channel, ns)
    }

    /// A `foxglove.Log` line on `channel` at time `t`.
    fn log(&mut self, channel: u16, t: f64, name: &str, message: String) -> Result<(), McapError> {
        let ns = self.stamp_of(t);
        let msg = Log {
            timestamp: Some(stamp(ns)),
            level: log::Level::Info as i32,
            message,
            name: name.to_owned(),
            file: String::new(),
            line: 0,
        };
        self.put_proto(channel, ns, &msg)
    }

    /// The events up to time `t` (inclusive), each at its own time.
    fn events_until(&mut self, t: f64) -> Result<(), McapError> {
        while let Some(e) = self.events.get(self.next_event).filter(|e| e.t <= t) {
            let text = format!(
                "{}: {} -> {} at t = {} s",
                e.kind.name(),
                e.from.name(),
                e.to,
                e.t
            );
            let at = e.t;
            if let Some(ch) = self.ch.as_ref().filter(|_| self.topics.model) {
                self.log(ch.events, at, "appell.event", text)?;
            }
            self.next_event += 1;
        }
        Ok(())
    }

    /// The one-line answer, at time `t` (the first frame's).
    pub fn answer(&mut self, t: f64, text: &str) -> Result<(), McapError> {
        match &self.ch {
            Some(ch) => self.log(ch.answer, t, "appell.answer", text.to_owned()),
            None => Ok(()),
        }
    }

    /// Write one frame (frames in time order).
    pub fn frame(&mut self, f: &OverlayFrame) -> Result<(), McapError> {
        self.events_until(f.t)?;
        let ns = self.stamp_of(f.t);
        if let (Some(lab), Some([slider, bob])) = (self.lab, f.recorded) {
            self.buf.clear();
            frame_json(&mut self.buf, ns as i64, slider, bob).map_err(io)?;
            self.put(lab, ns)?;
        }
        let Some(ch) = self
            .ch
            .as_ref()
            .map(|c| (c.recorded, c.model, c.markers, c.residual, c.mode, c.forces))
        else {
            return Ok(());
        };
        let (ch_recorded, ch_model, ch_markers, ch_residual, ch_mode, ch_forces) = ch;
        let ts = Some(stamp(ns));
        let entity = |id: &str, spheres, lines| SceneEntity {
            timestamp: ts,
            frame_id: OVERLAY_FRAME_ID.to_owned(),
            id: id.to_owned(),
            spheres,
            lines,
            ..SceneEntity::default()
        };
        let recorded = f.recorded.filter(|_| self.topics.recorded);
        let model = f.model.filter(|_| self.topics.model);
        if let Some(r) = recorded {
            let c = color(86, 180, 233);
            let spheres = r.iter().flatten().map(|p| sphere(*p, c)).collect();
            let update = SceneUpdate {
                deletions: vec![],
                entities: vec![entity("recorded", spheres, vec![])],
            };
            self.put_proto(ch_recorded, ns, &update)?;
        }
        if let Some(m) = &model {
            let c = mode_color(m.mode);
            let [sx, sy, bx, by] = m.markers;
            let rod = foxglove::messages::LinePrimitive {
                r#type: line_primitive::Type::LineStrip as i32,
                pose: sphere([0.0, 0.0], c).pose,
                thickness: 2.0,
                scale_invariant: true,
                points: vec![
                    Point3 {
                        x: sx,
                        y: sy,
                        z: 0.0,
                    },
                    Point3 {
                        x: bx,
                        y: by,
                        z: 0.0,
                    },
                ],
                color: Some(c),
                ..Default::default()
            };
            let spheres = vec![sphere([sx, sy], c), sphere([bx, by], c)];
            let update = SceneUpdate {
                deletions: vec![],
                entities: vec![entity("model", spheres, vec![rod])],
            };
            self.put_proto(ch_model, ns, &update)?;
        }
        let model_xy = model.map(|m| {
            let [sx, sy, bx, by] = m.markers;
            [Some([sx, sy]), Some([bx, by])]
        });
        self.put_json(
            ch_markers,
            ns,
            &MarkersMsg {
                t: f.t,
                recorded: recorded.map(XY::of),
                model: model_xy.map(XY::of),
            },
        )?;
        let Some(m) = model else {
            return Ok(());
        };
        if let Some(r) = recorded {
            // Model minus recorded, as the fit's residuals (docs/glossary.md).
            let diff =
                |k: usize| r[k].map(|p| [m.markers[2 * k] - p[0], m.markers[2 * k + 1] - p[1]]);
            let (ds, db) = (diff(0), diff(1));
            let msg = ResidualMsg {
                t: f.t,
                xy: XY::of([ds, db]),
                slider: ds.map(|d| d[0].hypot(d[1])),
                bob: db.map(|d| d[0].hypot(d[1])),
            };
            self.put_json(ch_residual, ns, &msg)?;
        }
        let (sliding, direction) = match m.mode {
            Mode::Stick => (0, 0),
            Mode::Slide(d) => (1, d.sign() as i8),
        };
        self.put_json(
            ch_mode,
            ns,
            &ModeMsg {
                t: f.t,
                mode: m.mode.name(),
                sliding,
                direction,
            },
        )?;
        self.put_json(
            ch_forces,
            ns,
            &ForcesMsg {
                t: f.t,
                normal: m.contact.normal,
                friction: m.contact.friction,
                mu: m.contact.mu,
            },
        )
    }

    /// Copy every message of the MCAP file `input` (its bytes) with its channel and schema,
    /// stamps and sequence numbers as they are, beside the overlay's topics: a recording read
    /// from MCAP kept whole in its overlay. Read linearly, as the reader reads it; a damaged
    /// tail (which the reader warned of) ends the copy where the reader's frames ended.
    /// Returns the messages copied.
    pub fn copy_messages(&mut self, input: &[u8]) -> Result<usize, McapError> {
        let mut ids: std::collections::HashMap<u16, u16> = std::collections::HashMap::new();
        let mut copied = 0;
        for m in ::mcap::MessageStream::new(input)? {
            let Ok(m) = m else { break };
            let channel = match ids.get(&m.channel.id) {
                Some(&id) => id,
                None => {
                    let schema = match &m.channel.schema {
                        Some(s) => self.out.add_schema(&s.name, &s.encoding, &s.data)?,
                        None => 0,
                    };
                    let id = self.out.add_channel(
                        schema,
                        &m.channel.topic,
                        &m.channel.message_encoding,
                        &m.channel.metadata,
                    )?;
                    ids.insert(m.channel.id, id);
                    id
                }
            };
            self.out.write_to_known_channel(
                &MessageHeader {
                    channel_id: channel,
                    sequence: m.sequence,
                    log_time: m.log_time,
                    publish_time: m.publish_time,
                },
                &m.data,
            )?;
            copied += 1;
        }
        Ok(copied)
    }

    /// Write the events left (those after the last frame) and end the file.
    pub fn finish(mut self) -> Result<(), McapError> {
        self.events_until(f64::INFINITY)?;
        self.out.finish().map(drop)
    }
}

/// Why an overlay could not be written.
#[derive(Debug, thiserror::Error)]
pub enum OverlayError {
    /// The model could not be simulated over the frames.
    #[error("simulating the model over the frames: {0}")]
    Sim(#[from] crate::sim::SimError),
    /// The MCAP file could not be written.
    #[error("{0}")]
    Mcap(#[from] ::mcap::McapError),
    /// A table (`.csv`) could not be written.
    #[error("{0}")]
    Io(#[from] std::io::Error),
}

impl From<OverlayError> for std::io::Error {
    fn from(e: OverlayError) -> Self {
        match e {
            OverlayError::Mcap(::mcap::McapError::Io(io)) | OverlayError::Io(io) => io,
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
    pub fn frame(&self, s: &crate::sim::Sample<f64>) -> ModelFrame {
        ModelFrame::of(self.rig, self.camera, s)
    }

    /// One run over `times` (ascending, s from the first frame), each frame's model handed to
    /// `each` as it is sampled (`None` for the frames after a run that stopped early, a
    /// paradox): nothing is kept, so a long recording costs no memory but its times.
    pub fn each_frame(
        &self,
        times: &[f64],
        each: &mut dyn FnMut(f64, Option<ModelFrame>),
    ) -> Result<(), crate::sim::SimError> {
        let Some(&t_end) = times.last() else {
            return Ok(());
        };
        let mut reached = 0;
        simulate_each(
            self.rig,
            self.initial,
            t_end,
            self.options,
            &Request {
                sample_times: times.to_vec(),
                friction_work: false,
                positions_only: false,
            },
            &mut |s| {
                reached += 1;
                each(s.t, Some(self.frame(&s)));
            },
        )?;
        for &t in &times[reached..] {
            each(t, None);
        }
        Ok(())
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
    /// Also write the recorded markers as appell's own recording (`/markers`), which its
    /// reader reads back.
    pub lab_markers: bool,
    /// MCAP metadata records (name -> key -> value).
    pub metadata: BTreeMap<String, BTreeMap<String, String>>,
    /// The recording's own MCAP file (its bytes), whose channels, schemas and messages are
    /// copied beside the overlay's (`fit --overlay-with-input`).
    pub with_input: Option<&'a [u8]>,
}

/// Write an overlay of `input` and the model `run` (sampled at every frame time) on `w`.
/// Frames the run does not reach (it stopped at a paradox) keep their recorded markers only.
pub fn write_overlay(
    w: &mut dyn Write,
    input: &OverlayInput,
    run: Option<&ModelRun>,
) -> Result<(), OverlayError> {
    let topics = Topics {
        lab_markers: input.lab_markers,
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
    if let Some(bytes) = input.with_input {
        out.copy_messages(bytes)?;
    }
    out.finish()?;
    Ok(())
}

/// The stamp (ns) of time `t` (s) after `origin_ns`, rounded to the nanosecond.
pub fn stamp_of(origin_ns: u64, t: f64) -> u64 {
    origin_ns.saturating_add_signed((t * 1e9).round() as i64)
}

/// A marker in a JSON frame message.
#[derive(Serialize)]
struct OutMarker<'a> {
    id: &'a str,
    x: Option<f64>,
    y: Option<f64>,
}

#[derive(Serialize)]
struct OutStamp {
    sec: i64,
    nsec: i64,
}

#[derive(Serialize)]
struct OutFrame<'a> {
    timestamp: OutStamp,
    frame_id: &'a str,
    markers: Vec<OutMarker<'a>>,
}

/// JSON Schema of the frame messages [`write_json`] writes (schema `lab.MarkerFrame2D`); a
/// marker not seen has null x and y, which the schema allows (a validator refused it).
pub const FRAME_SCHEMA: &str = r#"{"title":"lab.MarkerFrame2D","type":"object","properties":{"timestamp":{"type":"object","properties":{"sec":{"type":"integer"},"nsec":{"type":"integer"}}},"frame_id":{"type":"string"},"markers":{"type":"array","items":{"type":"object","properties":{"id":{"type":"string"},"x":{"type":["number","null"]},"y":{"type":["number","null"]}}}}}}"#;

/// One `lab.MarkerFrame2D` JSON frame at `ns` (a missing marker with null x and y) into `buf`.
fn frame_json(
    buf: &mut Vec<u8>,
    ns: i64,
    slider: Option<[f64; 2]>,
    bob: Option<[f64; 2]>,
) -> serde_json::Result<()> {
    let markers = [("slider", slider), ("bob", bob)]
        .into_iter()
        .map(|(id, p)| OutMarker {
            id,
            x: p.map(|p| p[0]),
            y: p.map(|p| p[1]),
        })
        .collect();
    let frame = OutFrame {
        timestamp: OutStamp {
            sec: ns.div_euclid(1_000_000_000),
            nsec: ns.rem_euclid(1_000_000_000),
        },
        frame_id: "rail",
        markers,
    };
    serde_json::to_writer(buf, &frame)
}
