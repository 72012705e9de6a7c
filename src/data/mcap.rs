//! MCAP recordings: a streaming linear reader (no summary or index needed, bounded memory)
//! decoding JSON, ROS 2 CDR and protobuf (Foxglove) marker messages, and a writer of JSON
//! marker frames.

use super::{DataError, Parsed, Plane, ReadOptions, Recording, Series};
use ::mcap::records::{MessageHeader, Metadata, Record};
use ::mcap::sans_io::linear_reader::{LinearReadEvent, LinearReader};
use ::mcap::McapError;
use prost_reflect::{DescriptorPool, DynamicMessage, MessageDescriptor, ReflectMessage, Value};
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, HashMap};
use std::fmt;
use std::io::{Read, Write};
use std::path::Path;

/// Message encodings the reader decodes (channel encoding / schema).
pub const SUPPORTED: &str = "json (markers array per frame, or one point per topic), \
cdr with ros2msg schemas geometry_msgs/msg/PointStamped, PoseStamped, TransformStamped, \
tf2_msgs/msg/TFMessage, protobuf (schema a FileDescriptorSet) foxglove.FrameTransform, \
foxglove.PointsAnnotation; chunks uncompressed, zstd or lz4";

/// Marker names given to the points of a `foxglove.PointsAnnotation`, which carries no names:
/// identity is the index (point 0 the slider, point 1 the bob, further points `point2`, ...).
pub const POINTS_NAMES: [&str; 2] = ["slider", "bob"];

/// Read an MCAP file linearly (summary and index are not needed).
pub(crate) fn read(path: &Path, opts: &ReadOptions) -> Result<Parsed, DataError> {
    let file = std::fs::File::open(path).map_err(|source| DataError::Io {
        path: path.to_owned(),
        source,
    })?;
    read_from(file, path, opts)
}

#[derive(Deserialize)]
struct JStamp {
    sec: i64,
    #[serde(default, alias = "nanosec", alias = "nanos")]
    nsec: i64,
}

#[derive(Deserialize)]
struct JHeader {
    stamp: Option<JStamp>,
}

#[derive(Deserialize)]
struct JPoint {
    x: Option<f64>,
    y: Option<f64>,
    z: Option<f64>,
}

#[derive(Deserialize)]
struct JMarker {
    #[serde(alias = "name", alias = "label")]
    id: String,
    x: Option<f64>,
    y: Option<f64>,
    z: Option<f64>,
}

#[derive(Deserialize)]
struct JMsg {
    timestamp: Option<JStamp>,
    header: Option<JHeader>,
    markers: Option<Vec<JMarker>>,
    x: Option<f64>,
    y: Option<f64>,
    z: Option<f64>,
    point: Option<JPoint>,
    position: Option<JPoint>,
}

#[derive(Deserialize)]
struct RosTime {
    sec: i32,
    nanosec: u32,
}

#[derive(Deserialize)]
struct RosHeader {
    stamp: RosTime,
    #[allow(dead_code)]
    frame_id: String,
}

#[derive(Deserialize)]
struct Vec3 {
    x: f64,
    y: f64,
    z: f64,
}

#[derive(Deserialize)]
#[allow(dead_code)]
struct Quat {
    x: f64,
    y: f64,
    z: f64,
    w: f64,
}

#[derive(Deserialize)]
struct PointStamped {
    header: RosHeader,
    point: Vec3,
}

#[derive(Deserialize)]
#[allow(dead_code)]
struct Pose {
    position: Vec3,
    orientation: Quat,
}

#[derive(Deserialize)]
struct PoseStamped {
    header: RosHeader,
    pose: Pose,
}

#[derive(Deserialize)]
#[allow(dead_code)]
struct Transform {
    translation: Vec3,
    rotation: Quat,
}

#[derive(Deserialize)]
struct TransformStamped {
    header: RosHeader,
    child_frame_id: String,
    transform: Transform,
}

#[derive(Deserialize)]
struct TfMessage {
    transforms: Vec<TransformStamped>,
}

/// How a channel's messages are decoded. The protobuf ones carry the message descriptor built
/// from the channel's schema (the file's own definition, not one compiled in).
#[derive(Clone)]
enum Decoder {
    Json,
    PointStamped,
    PoseStamped,
    TransformStamped,
    TfMessage,
    FrameTransform(MessageDescriptor),
    PointsAnnotation(MessageDescriptor),
}

// By hand so channel lists show the type name, not the whole descriptor.
impl fmt::Debug for Decoder {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Decoder::Json => "Json",
            Decoder::PointStamped => "PointStamped",
            Decoder::PoseStamped => "PoseStamped",
            Decoder::TransformStamped => "TransformStamped",
            Decoder::TfMessage => "TfMessage",
            Decoder::FrameTransform(_) => "protobuf FrameTransform",
            Decoder::PointsAnnotation(_) => "protobuf PointsAnnotation",
        })
    }
}

/// Why a channel gets no decoder.
enum Reject {
    /// An encoding or type this reader does not decode.
    Unsupported(String),
    /// A supported type whose schema is unusable.
    Invalid(String),
}

#[derive(Debug)]
enum ChannelState {
    Markers(Decoder),
    Ignored(String),
}

struct Channel {
    topic: String,
    state: ChannelState,
    decoded: usize,
}

fn ros_ns(t: &RosTime) -> i64 {
    t.sec as i64 * 1_000_000_000 + t.nanosec as i64
}

/// One marker's samples with nanosecond stamps.
type Stamped = Vec<(i64, Option<[f64; 2]>)>;

/// Accumulates marker samples with nanosecond stamps.
#[derive(Default)]
struct Acc {
    index: HashMap<String, usize>,
    series: Vec<(String, Stamped)>,
}

impl Acc {
    fn push(&mut self, name: &str, ns: i64, p: Option<[f64; 2]>) {
        let k = match self.index.get(name) {
            Some(&k) => k,
            None => {
                self.index.insert(name.to_string(), self.series.len());
                self.series.push((name.to_string(), Vec::new()));
                self.series.len() - 1
            }
        };
        self.series[k].1.push((ns, p));
    }
}

fn xy(x: Option<f64>, y: Option<f64>, z: Option<f64>, plane: Option<Plane>) -> Option<[f64; 2]> {
    match (x, y, z, plane) {
        (Some(x), Some(y), Some(z), Some(p)) => Some(p.project([x, y, z])),
        (Some(x), Some(y), _, _) => Some([x, y]),
        _ => None,
    }
}

fn decoder_for(
    encoding: &str,
    schema_name: &str,
    schema_encoding: &str,
    schema_data: &[u8],
) -> Result<Decoder, Reject> {
    match encoding {
        "json" => Ok(Decoder::Json),
        "cdr" => {
            if schema_encoding != "ros2msg" && schema_encoding != "ros2idl" {
                return Err(Reject::Unsupported(format!(
                    "cdr with schema encoding {schema_encoding:?}"
                )));
            }
            match schema_name {
                "geometry_msgs/msg/PointStamped" => Ok(Decoder::PointStamped),
                "geometry_msgs/msg/PoseStamped" => Ok(Decoder::PoseStamped),
                "geometry_msgs/msg/TransformStamped" => Ok(Decoder::TransformStamped),
                "tf2_msgs/msg/TFMessage" => Ok(Decoder::TfMessage),
                other => Err(Reject::Unsupported(format!("cdr schema {other:?}"))),
            }
        }
        "protobuf" => {
            if schema_encoding != "protobuf" {
                return Err(Reject::Unsupported(format!(
                    "protobuf with schema encoding {schema_encoding:?}"
                )));
            }
            let wrap: fn(MessageDescriptor) -> Decoder = match schema_name {
                "foxglove.FrameTransform" => Decoder::FrameTransform,
                "foxglove.PointsAnnotation" => Decoder::PointsAnnotation,
                other => return Err(Reject::Unsupported(format!("protobuf schema {other:?}"))),
            };
            // The schema data is the FileDescriptorSet the writer compiled against; decoding with
            // it (rather than a built-in copy) follows the file if Foxglove's types grow fields.
            let pool = DescriptorPool::decode(schema_data).map_err(|e| {
                Reject::Invalid(format!(
                    "its schema {schema_name} is not a valid binary FileDescriptorSet ({e})"
                ))
            })?;
            let desc = pool.get_message_by_name(schema_name).ok_or_else(|| {
                Reject::Invalid(format!(
                    "its schema's FileDescriptorSet does not define {schema_name}"
                ))
            })?;
            Ok(wrap(desc))
        }
        other => Err(Reject::Unsupported(format!("message encoding {other:?}"))),
    }
}

/// Field `name` of a protobuf message, or what was expected.
fn pb_field<'a>(m: &'a DynamicMessage, name: &str) -> Result<std::borrow::Cow<'a, Value>, String> {
    m.get_field_by_name(name).ok_or_else(|| {
        format!(
            "a field {name:?} in {} (the schema lacks it)",
            m.descriptor().full_name()
        )
    })
}

/// Field `name` as f64 (foxglove vectors and points are doubles).
fn pb_f64(m: &DynamicMessage, name: &str) -> Result<f64, String> {
    let v = pb_field(m, name)?;
    match *v {
        Value::F64(x) => Ok(x),
        Value::F32(x) => Ok(x as f64),
        ref other => Err(format!(
            "a number in {}.{name}, found {other:?}",
            m.descriptor().full_name()
        )),
    }
}

/// Field `name` as an integer of any protobuf width.
fn pb_int(m: &DynamicMessage, name: &str) -> Result<i64, String> {
    let v = pb_field(m, name)?;
    match *v {
        Value::I64(x) => Ok(x),
        Value::I32(x) => Ok(x as i64),
        Value::U32(x) => Ok(x as i64),
        Value::U64(x) => i64::try_from(x).map_err(|_| format!("{name} {x} out of range")),
        ref other => Err(format!(
            "an integer in {}.{name}, found {other:?}",
            m.descriptor().full_name()
        )),
    }
}

/// The message's `timestamp` (google.protobuf.Timestamp) in ns, `None` when it is not set.
fn pb_stamp(m: &DynamicMessage) -> Result<Option<i64>, String> {
    if !m.has_field_by_name("timestamp") {
        return Ok(None);
    }
    let v = pb_field(m, "timestamp")?;
    let ts = v
        .as_message()
        .ok_or("a google.protobuf.Timestamp message in timestamp")?;
    Ok(Some(
        pb_int(ts, "seconds")? * 1_000_000_000 + pb_int(ts, "nanos")?,
    ))
}

/// Decode a protobuf message against its descriptor.
fn pb_decode(desc: &MessageDescriptor, data: &[u8]) -> Result<DynamicMessage, String> {
    DynamicMessage::decode(desc.clone(), data)
        .map_err(|e| format!("protobuf {}: {e}", desc.full_name()))
}

/// Decode one message into samples; `Err` is a message for the caller to locate.
fn decode(
    dec: &Decoder,
    topic: &str,
    data: &[u8],
    log_time: i64,
    plane: Option<Plane>,
    acc: &mut Acc,
) -> Result<usize, String> {
    match dec {
        Decoder::Json => {
            let m: JMsg = serde_json::from_slice(data).map_err(|e| format!("JSON: {e}"))?;
            let stamp = m
                .timestamp
                .or(m.header.and_then(|h| h.stamp))
                .map_or(log_time, |s| s.sec * 1_000_000_000 + s.nsec);
            if let Some(markers) = m.markers {
                let n = markers.len();
                for mk in markers {
                    acc.push(&mk.id, stamp, xy(mk.x, mk.y, mk.z, plane));
                }
                Ok(n)
            } else if let Some(p) = m.point.or(m.position) {
                acc.push(topic, stamp, xy(p.x, p.y, p.z, plane));
                Ok(1)
            } else if m.x.is_some() || m.y.is_some() {
                acc.push(topic, stamp, xy(m.x, m.y, m.z, plane));
                Ok(1)
            } else {
                Err("a JSON object with a \"markers\" array, a \"point\", or x and y".into())
            }
        }
        Decoder::PointStamped => {
            let m: PointStamped =
                cdr::deserialize(data).map_err(|e| format!("CDR PointStamped: {e}"))?;
            let p = &m.point;
            acc.push(
                topic,
                ros_ns(&m.header.stamp),
                xy(Some(p.x), Some(p.y), Some(p.z), plane),
            );
            Ok(1)
        }
        Decoder::PoseStamped => {
            let m: PoseStamped =
                cdr::deserialize(data).map_err(|e| format!("CDR PoseStamped: {e}"))?;
            let p = &m.pose.position;
            acc.push(
                topic,
                ros_ns(&m.header.stamp),
                xy(Some(p.x), Some(p.y), Some(p.z), plane),
            );
            Ok(1)
        }
        Decoder::TransformStamped => {
            let m: TransformStamped =
                cdr::deserialize(data).map_err(|e| format!("CDR TransformStamped: {e}"))?;
            let p = &m.transform.translation;
            acc.push(
                &m.child_frame_id,
                ros_ns(&m.header.stamp),
                xy(Some(p.x), Some(p.y), Some(p.z), plane),
            );
            Ok(1)
        }
        Decoder::TfMessage => {
            let m: TfMessage = cdr::deserialize(data).map_err(|e| format!("CDR TFMessage: {e}"))?;
            let n = m.transforms.len();
            for t in m.transforms {
                let p = &t.transform.translation;
                acc.push(
                    &t.child_frame_id,
                    ros_ns(&t.header.stamp),
                    xy(Some(p.x), Some(p.y), Some(p.z), plane),
                );
            }
            Ok(n)
        }
        Decoder::FrameTransform(desc) => {
            let m = pb_decode(desc, data)?;
            let stamp = pb_stamp(&m)?.unwrap_or(log_time);
            let name = pb_field(&m, "child_frame_id")?;
            let name = name.as_str().unwrap_or_default();
            if name.is_empty() {
                return Err("a FrameTransform whose child_frame_id names the marker".into());
            }
            // An unset translation is a marker the tracker lost in this frame, not the origin.
            let p = if m.has_field_by_name("translation") {
                let v = pb_field(&m, "translation")?;
                let t = v.as_message().ok_or("a foxglove.Vector3 in translation")?;
                xy(
                    Some(pb_f64(t, "x")?),
                    Some(pb_f64(t, "y")?),
                    Some(pb_f64(t, "z")?),
                    plane,
                )
            } else {
                None
            };
            acc.push(name, stamp, p);
            Ok(1)
        }
        Decoder::PointsAnnotation(desc) => {
            let m = pb_decode(desc, data)?;
            let stamp = pb_stamp(&m)?.unwrap_or(log_time);
            let v = pb_field(&m, "points")?;
            let points = v.as_list().ok_or("a repeated foxglove.Point2 in points")?;
            let mut xys = Vec::with_capacity(points.len());
            for p in points {
                let p = p.as_message().ok_or("foxglove.Point2 messages in points")?;
                xys.push([pb_f64(p, "x")?, pb_f64(p, "y")?]);
            }
            // Identity by index; the two roles get a sample every frame so a short list reads
            // as missing markers rather than shifting the others.
            for (k, name) in POINTS_NAMES.iter().enumerate() {
                acc.push(name, stamp, xys.get(k).copied());
            }
            for (k, p) in xys.iter().enumerate().skip(POINTS_NAMES.len()) {
                acc.push(&format!("point{k}"), stamp, Some(*p));
            }
            Ok(xys.len())
        }
    }
}

/// Read MCAP bytes from any reader, streaming; `path` labels errors.
pub(crate) fn read_from(
    mut input: impl Read,
    path: &Path,
    opts: &ReadOptions,
) -> Result<Parsed, DataError> {
    let mut reader = LinearReader::new();
    let mut schemas: HashMap<u16, (String, String, Vec<u8>)> = HashMap::new();
    let mut channels: HashMap<u16, Channel> = HashMap::new();
    let mut acc = Acc::default();
    let mut parsed = Parsed::default();
    let mut records = 0u64;
    let mut messages = 0u64;
    let mut bytes = 0u64;
    let mut damage: Option<McapError> = None;
    // With a time window, reading stops once marker messages are past its end (by log_time,
    // with a second of margin for stamps that differ from it): the rest is never decoded.
    let window_end = opts.time_window.map(|(_, end)| end + 1.0);
    let mut first_log_time: Option<u64> = None;
    let mut stopped_at: Option<f64> = None;
    'records: while let Some(event) = reader.next_event() {
        let event = match event {
            Ok(e) => e,
            Err(e) => {
                damage = Some(e);
                break;
            }
        };
        match event {
            LinearReadEvent::ReadRequest(need) => {
                let n = input
                    .read(reader.insert(need))
                    .map_err(|source| DataError::Io {
                        path: path.to_owned(),
                        source,
                    })?;
                bytes += n as u64;
                reader.notify_read(n);
            }
            LinearReadEvent::Record { opcode, data } => {
                records += 1;
                let record = match ::mcap::parse_record(opcode, data) {
                    Ok(r) => r,
                    Err(e) => {
                        damage = Some(e);
                        break;
                    }
                };
                match record {
                    Record::Schema { header, data } => {
                        // Only protobuf needs the schema's bytes; keep memory bounded otherwise.
                        let data = if header.encoding == "protobuf" {
                            data.into_owned()
                        } else {
                            Vec::new()
                        };
                        schemas.insert(header.id, (header.name, header.encoding, data));
                    }
                    Record::Channel(c) => {
                        let (sname, senc, sdata) = schemas
                            .get(&c.schema_id)
                            .map(|(n, e, d)| (n.as_str(), e.as_str(), d.as_slice()))
                            .unwrap_or_default();
                        let state = match decoder_for(&c.message_encoding, sname, senc, sdata) {
                            Ok(d) => ChannelState::Markers(d),
                            Err(Reject::Unsupported(why)) => {
                                ChannelState::Ignored(format!("{why} is not supported"))
                            }
                            Err(Reject::Invalid(why)) => ChannelState::Ignored(why),
                        };
                        channels.entry(c.id).or_insert(Channel {
                            topic: c.topic,
                            state,
                            decoded: 0,
                        });
                    }
                    Record::Message { header, data } => {
                        messages += 1;
                        let Some(ch) = channels.get_mut(&header.channel_id) else {
                            return Err(DataError::parse(
                                path,
                                format!("record {records}"),
                                "channel id",
                                "a channel defined before its messages",
                                header.channel_id.to_string(),
                            ));
                        };
                        let ChannelState::Markers(dec) = &ch.state else {
                            continue;
                        };
                        if let Some(end) = window_end {
                            let first = *first_log_time.get_or_insert(header.log_time);
                            let since = header.log_time.saturating_sub(first) as f64 * 1e-9;
                            if since > end {
                                stopped_at = Some(since);
                                break 'records;
                            }
                        }
                        match decode(
                            dec,
                            &ch.topic,
                            &data,
                            header.log_time as i64,
                            opts.plane,
                            &mut acc,
                        ) {
                            Ok(_) => ch.decoded += 1,
                            Err(why) if ch.decoded == 0 => {
                                ch.state = ChannelState::Ignored(format!(
                                    "its first message is not marker data: {why}"
                                ));
                            }
                            Err(why) => {
                                return Err(DataError::parse(
                                    path,
                                    format!(
                                        "message {messages} (record {records}) on {}",
                                        ch.topic
                                    ),
                                    "message",
                                    "marker data like the channel's earlier messages",
                                    why,
                                ))
                            }
                        }
                    }
                    Record::Metadata(Metadata { name, metadata }) => {
                        for (k, v) in metadata {
                            parsed.metadata.insert(format!("{name}.{k}"), v);
                        }
                    }
                    _ => {}
                }
            }
        }
    }
    let channel_list = || {
        let mut v: Vec<String> = channels
            .values()
            .map(|c| match &c.state {
                ChannelState::Markers(d) => format!("{} ({d:?})", c.topic),
                ChannelState::Ignored(why) => format!("{} ({why})", c.topic),
            })
            .collect();
        v.sort();
        if v.is_empty() {
            "the file has no channels".into()
        } else {
            format!("channels {}", v.join("; "))
        }
    };
    if let Some(t) = stopped_at {
        parsed.notes.push(format!(
            "stopped reading at {t:.3} s: past the time window, the rest of the file is not decoded"
        ));
    }
    if let Some(err) = damage {
        if let McapError::UnsupportedCompression(c) = &err {
            return Err(DataError::Unsupported {
                path: path.to_owned(),
                what: "chunk compression".into(),
                found: c.clone(),
                supported: "none, zstd, lz4".into(),
            });
        }
        if acc.series.is_empty() {
            return Err(DataError::Mcap {
                path: path.to_owned(),
                at: format!("after {records} record(s), {bytes} byte(s)"),
                source: err,
            });
        }
        parsed.warnings.push(format!(
            "{}: damaged after {messages} message(s) ({records} records, {bytes} bytes read): {err}; \
             kept the frames before the damage",
            path.display()
        ));
    }
    if acc.series.is_empty() {
        let unsupported: Vec<&Channel> = channels
            .values()
            .filter(
                |c| matches!(&c.state, ChannelState::Ignored(w) if w.ends_with("not supported")),
            )
            .collect();
        if !unsupported.is_empty() && unsupported.len() == channels.len() {
            let c = unsupported[0];
            let ChannelState::Ignored(why) = &c.state else {
                unreachable!()
            };
            return Err(DataError::Unsupported {
                path: path.to_owned(),
                what: format!("channel {}", c.topic),
                found: why.trim_end_matches(" is not supported").to_string(),
                supported: SUPPORTED.into(),
            });
        }
        if messages == 0 && !channels.is_empty() {
            return Err(DataError::NoFrames {
                path: path.to_owned(),
                what: channel_list(),
            });
        }
        return Err(DataError::NoMarkerChannel {
            path: path.to_owned(),
            channels: channel_list(),
            expected: SUPPORTED.into(),
        });
    }
    for c in channels.values() {
        if let ChannelState::Ignored(why) = &c.state {
            parsed
                .notes
                .push(format!("channel {} skipped: {why}", c.topic));
        }
    }
    // Sort, check duplicates, convert to seconds from the earliest stamp (exact integer
    // differences first).
    let mut t0 = i64::MAX;
    for (_, s) in &mut acc.series {
        if !s.is_sorted_by_key(|x| x.0) {
            s.sort_by_key(|x| x.0);
        }
        t0 = t0.min(s[0].0);
    }
    for (name, s) in acc.series {
        if let Some(w) = s.windows(2).find(|w| w[0].0 == w[1].0) {
            return Err(DataError::Time {
                path: path.to_owned(),
                at: format!("marker {name:?}"),
                time: (w[1].0 - t0) as f64 * 1e-9,
                previous: (w[0].0 - t0) as f64 * 1e-9,
                problem: "is repeated",
            });
        }
        parsed.series.push(Series {
            name,
            times: s.iter().map(|x| (x.0 - t0) as f64 / 1e9).collect(),
            points: s.iter().map(|x| x.1).collect(),
        });
    }
    parsed.time_base = t0 as f64 / 1e9;
    parsed.scale = Some((1.0, "metres (MCAP marker messages)".into()));
    parsed.notes.push(format!(
        "MCAP: {messages} message(s) on {} channel(s), read linearly; in-message stamps used where present",
        channels.len()
    ));
    Ok(parsed)
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

/// JSON Schema of the frame messages [`write_json`] writes (schema `lab.MarkerFrame2D`).
pub const FRAME_SCHEMA: &str = r#"{"title":"lab.MarkerFrame2D","type":"object","properties":{"timestamp":{"type":"object","properties":{"sec":{"type":"integer"},"nsec":{"type":"integer"}}},"frame_id":{"type":"string"},"markers":{"type":"array","items":{"type":"object","properties":{"id":{"type":"string"},"x":{"type":"number"},"y":{"type":"number"}}}}}}"#;

/// Write a recording as MCAP: topic `/markers`, JSON frames (`lab.MarkerFrame2D`, a markers
/// array, a missing marker with null x and y), zstd chunks, the stamps `start_ns` + t, and one metadata
/// record per entry of `metadata` (name -> key -> value).
pub fn write_json(
    w: &mut dyn Write,
    rec: &Recording,
    start_ns: i64,
    metadata: &BTreeMap<String, BTreeMap<String, String>>,
) -> Result<(), McapError> {
    let mut out = ::mcap::WriteOptions::new()
        .compression(Some(::mcap::Compression::Zstd))
        .profile("")
        .disable_seeking(true)
        .create(::mcap::write::NoSeek::new(w))?;
    let schema = out.add_schema("lab.MarkerFrame2D", "jsonschema", FRAME_SCHEMA.as_bytes())?;
    let channel = out.add_channel(schema, "/markers", "json", &BTreeMap::new())?;
    for (name, map) in metadata {
        out.write_metadata(&Metadata {
            name: name.clone(),
            metadata: map.clone(),
        })?;
    }
    let mut buf = Vec::with_capacity(256);
    for i in 0..rec.len() {
        let ns = start_ns + (rec.times[i] * 1e9).round() as i64;
        let mut markers = Vec::with_capacity(2);
        for (id, p) in [("slider", rec.slider[i]), ("bob", rec.bob[i])] {
            markers.push(OutMarker {
                id,
                x: p.map(|p| p[0]),
                y: p.map(|p| p[1]),
            });
        }
        let frame = OutFrame {
            timestamp: OutStamp {
                sec: ns.div_euclid(1_000_000_000),
                nsec: ns.rem_euclid(1_000_000_000),
            },
            frame_id: "rail",
            markers,
        };
        buf.clear();
        serde_json::to_writer(&mut buf, &frame).map_err(|e| McapError::Io(e.into()))?;
        out.write_to_known_channel(
            &MessageHeader {
                channel_id: channel,
                sequence: i as u32,
                log_time: ns as u64,
                publish_time: ns as u64,
            },
            &buf,
        )?;
    }
    out.finish()?;
    Ok(())
}
