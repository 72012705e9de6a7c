//! MCAP recordings: a streaming linear reader (no summary or index needed, bounded memory)
//! decoding JSON, ROS 2 CDR and protobuf (Foxglove) marker messages, and a writer of JSON
//! marker frames.

mod tf;
mod write;

pub use tf::TF_SAMPLE_LIMIT;
pub use write::{write_json, FRAME_SCHEMA};

use super::{ros_cdr, DataError, Parsed, Plane, ReadOptions, Series};
use ::mcap::records::{op, MessageHeader, Metadata, Record};
use ::mcap::sans_io::linear_reader::{LinearReadEvent, LinearReader, LinearReaderOptions};
use ::mcap::McapError;
use prost_reflect::{DescriptorPool, DynamicMessage, MessageDescriptor, ReflectMessage, Value};
use serde::Deserialize;
use std::collections::{BTreeMap, HashMap};
use std::fmt;
use std::io::Read;
use std::path::Path;
use tf::{compose_tf, Acc};

/// Message encodings the reader decodes (channel encoding / schema).
pub const SUPPORTED: &str = "json (markers array per frame, or one point per topic), \
cdr with ros2msg schemas geometry_msgs/msg/PointStamped, PoseStamped, TransformStamped, \
tf2_msgs/msg/TFMessage, protobuf (schema a FileDescriptorSet) foxglove.FrameTransform, \
foxglove.PointsAnnotation; chunks uncompressed, zstd or lz4";

/// JSON schemas (Foxglove's) whose x, y are not a position: skipped rather than read as
/// markers.
pub const NOT_POSITIONS: [&str; 6] = [
    "foxglove.Vector3",
    "foxglove.Vector2",
    "foxglove.Quaternion",
    "foxglove.LocationFix",
    "foxglove.Battery",
    "foxglove.Log",
];

/// Marker names given to the points of a `foxglove.PointsAnnotation`, which carries no names:
/// identity is the index (point 0 the slider, point 1 the bob, further points `point2`, ...).
pub const POINTS_NAMES: [&str; 2] = ["slider", "bob"];

/// Read an MCAP file linearly (summary and index are not needed).
pub(crate) fn read(path: &Path, opts: &ReadOptions) -> Result<Parsed, DataError> {
    let file = std::fs::File::open(path).map_err(|source| DataError::Io {
        path: path.to_owned(),
        source,
    })?;
    let size = file
        .metadata()
        .ok()
        .filter(|m| m.is_file())
        .map(|m| m.len());
    read_from(file, path, opts, size)
}

/// A JSON time stamp: `{"sec", "nsec"}` (also `nanosec`, `nanos`) or, as Foxglove tools
/// write it, a float of seconds.
#[derive(Deserialize)]
#[serde(untagged)]
enum JStamp {
    Parts {
        sec: i64,
        #[serde(default, alias = "nanosec", alias = "nanos")]
        nsec: i64,
    },
    Seconds(f64),
}

impl JStamp {
    /// Nanoseconds, or what was expected when the stamp does not fit in i64 nanoseconds.
    fn ns(&self) -> Result<i64, String> {
        match *self {
            JStamp::Parts { sec, nsec } => sec
                .checked_mul(1_000_000_000)
                .and_then(|s| s.checked_add(nsec))
                .ok_or_else(|| {
                    format!("a timestamp within +-292 years of 1970, found sec {sec}, nsec {nsec}")
                }),
            JStamp::Seconds(s) => seconds_to_ns(s),
        }
    }
}

/// Float seconds as nanoseconds, when they fit.
fn seconds_to_ns(s: f64) -> Result<i64, String> {
    if s.is_finite() && s.abs() < 9.2e9 {
        // Whole seconds and the fraction apart: 1.7e9 s times 1e9 would round to 256 ns.
        let whole = s.floor();
        Ok(whole as i64 * 1_000_000_000 + ((s - whole) * 1e9).round() as i64)
    } else {
        Err(format!(
            "a timestamp in seconds within +-9.2e9 (292 years), found {s}"
        ))
    }
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

/// The common JSON frame (a `markers` array, `{"sec", "nsec"}` stamps), read without copying
/// marker names: a message this reads, [`JMsg`] reads to the same values; any other message
/// (a stamp in float seconds, a malformed one) goes to [`JMsg`], which words the errors.
#[derive(Deserialize)]
struct FastMsg<'a> {
    timestamp: Option<FastStamp>,
    header: Option<FastHeader>,
    #[serde(borrow)]
    markers: Option<Vec<FastMarker<'a>>>,
    x: Option<f64>,
    y: Option<f64>,
    z: Option<f64>,
    point: Option<JPoint>,
    position: Option<JPoint>,
}

/// [`JStamp::Parts`] alone.
#[derive(Deserialize)]
struct FastStamp {
    sec: i64,
    #[serde(default, alias = "nanosec", alias = "nanos")]
    nsec: i64,
}

#[derive(Deserialize)]
struct FastHeader {
    stamp: Option<FastStamp>,
}

/// [`JMarker`] with its name borrowed from the message when it holds no escapes.
#[derive(Deserialize)]
struct FastMarker<'a> {
    #[serde(borrow, alias = "name", alias = "label")]
    id: std::borrow::Cow<'a, str>,
    x: Option<f64>,
    y: Option<f64>,
    z: Option<f64>,
}

/// The most markers a frame read by [`canonical_frame`] holds (more go to serde).
const CANONICAL_MARKERS: usize = 8;

/// One frame in the exact layout [`write_json`] (and the Python example files) write:
/// `{"timestamp":{"sec":S,"nsec":N},"frame_id":"..","markers":[{"id":"..","x":X,"y":Y},..]}`
/// without whitespace: the stamp's parts and up to [`CANONICAL_MARKERS`] markers (name, x, y),
/// names and the frame id without escapes.
struct CanonicalFrame<'a> {
    sec: i64,
    nsec: i64,
    len: usize,
    markers: [(&'a str, Option<f64>, Option<f64>); CANONICAL_MARKERS],
}

/// A byte cursor over one message for [`canonical_frame`]; every method returns `None` (the
/// message then goes to serde) at anything outside the narrow layout it accepts.
struct Bytes<'a> {
    d: &'a [u8],
    at: usize,
}

impl<'a> Bytes<'a> {
    /// The literal `s` (a fixed-size array, compared without a library call).
    fn lit<const N: usize>(&mut self, s: &[u8; N]) -> Option<()> {
        let w: &[u8; N] = self.d.get(self.at..self.at + N)?.try_into().ok()?;
        (w == s).then(|| self.at += N)
    }

    fn digits(&self, from: usize) -> usize {
        self.d[from..]
            .iter()
            .take_while(|b| b.is_ascii_digit())
            .count()
    }

    /// A string without escapes or control characters: its bytes are its text.
    fn string(&mut self) -> Option<&'a str> {
        self.lit(b"\"")?;
        let start = self.at;
        let len = self.d[start..].iter().position(|&b| b == b'"')?;
        if self.d[start..start + len]
            .iter()
            .any(|&b| b == b'\\' || b < 0x20)
        {
            return None;
        }
        self.at = start + len + 1;
        // Only strings may hold other than ASCII: each is checked for UTF-8 here.
        std::str::from_utf8(&self.d[start..start + len]).ok()
    }

    /// A JSON integer of at most 18 digits (no `-0`, which serde reads as a float).
    fn int(&mut self) -> Option<i64> {
        let neg = self.lit(b"-").is_some();
        let n = self.digits(self.at);
        let digits = &self.d[self.at..self.at + n];
        if n == 0 || n > 18 || (n > 1 && digits[0] == b'0') {
            return None;
        }
        let v = digits
            .iter()
            .fold(0i64, |v, &b| v * 10 + i64::from(b - b'0'));
        if neg && v == 0 {
            return None;
        }
        self.at += n;
        Some(if neg { -v } else { v })
    }

    /// Digits from `i`: where they end and how many are significant (from the first nonzero
    /// one on, counting those already seen, `significant`).
    fn count_digits(&self, mut i: usize, mut significant: usize) -> (usize, usize) {
        while let Some(&c) = self.d.get(i) {
            if !c.is_ascii_digit() {
                break;
            }
            if significant > 0 || c != b'0' {
                significant += 1;
            }
            i += 1;
        }
        (i, significant)
    }

    /// `null`, or a JSON number with a fraction or an exponent (how serde_json writes every
    /// f64) of at most 19 significant digits and a finite value: exact input to both std's and
    /// serde_json's correctly rounded parsers, so the same f64.
    fn float(&mut self) -> Option<Option<f64>> {
        if self.lit(b"null").is_some() {
            return Some(None);
        }
        let start = self.at;
        let int_start = start + usize::from(self.d.get(start) == Some(&b'-'));
        let (mut i, mut significant) = self.count_digits(int_start, 0);
        if i == int_start || (i - int_start > 1 && self.d[int_start] == b'0') {
            return None;
        }
        let mut fraction = false;
        if self.d.get(i) == Some(&b'.') {
            let (end, sig) = self.count_digits(i + 1, significant);
            if end == i + 1 {
                return None;
            }
            (i, significant, fraction) = (end, sig, true);
        }
        let mut exponent = false;
        if matches!(self.d.get(i), Some(b'e' | b'E')) {
            i += 1;
            if matches!(self.d.get(i), Some(b'+' | b'-')) {
                i += 1;
            }
            let n = self.digits(i);
            if n == 0 || n > 4 {
                return None;
            }
            i += n;
            exponent = true;
        }
        if !(fraction || exponent) || significant > 19 {
            return None;
        }
        let v: f64 = std::str::from_utf8(&self.d[start..i]).ok()?.parse().ok()?;
        if !v.is_finite() {
            return None;
        }
        self.at = i;
        Some(Some(v))
    }
}

/// Read a frame in the exact layout of [`CanonicalFrame`], or `None` for any other message
/// (spaces, other keys or key order, escapes, integers where floats are written, more
/// markers), which serde then reads. What this accepts, serde reads to the same values.
fn canonical_frame(data: &[u8]) -> Option<CanonicalFrame<'_>> {
    // Outside its strings a frame is ASCII literals and digits, matched byte by byte; the
    // strings are checked for UTF-8 as they are read.
    let mut b = Bytes { d: data, at: 0 };
    b.lit(b"{\"timestamp\":{\"sec\":")?;
    let sec = b.int()?;
    b.lit(b",\"nsec\":")?;
    let nsec = b.int()?;
    b.lit(b"},\"frame_id\":")?;
    b.string()?;
    b.lit(b",\"markers\":[")?;
    let mut frame = CanonicalFrame {
        sec,
        nsec,
        len: 0,
        markers: [("", None, None); CANONICAL_MARKERS],
    };
    loop {
        if frame.len == CANONICAL_MARKERS {
            return None;
        }
        b.lit(b"{\"id\":")?;
        let id = b.string()?;
        b.lit(b",\"x\":")?;
        let x = b.float()?;
        b.lit(b",\"y\":")?;
        let y = b.float()?;
        b.lit(b"}")?;
        frame.markers[frame.len] = (id, x, y);
        frame.len += 1;
        if b.lit(b",").is_none() {
            break;
        }
    }
    b.lit(b"]}")?;
    (b.at == data.len()).then_some(frame)
}

/// One marker of a frame parsed ahead: where its name lies in the message, and x, y.
type PreMarker = (std::ops::Range<usize>, Option<f64>, Option<f64>);

/// A chunk's canonical JSON frames, parsed ahead on the thread pool while the chunks before
/// are read (see [`Reading::chunk`]): per message record in chunk order, its stamp's parts and
/// its markers' span in `markers`, or `None` when the message is not a canonical frame (it is
/// then decoded as before, in order).
#[derive(Default)]
struct PreParsed {
    frames: Vec<Option<(i64, i64, std::ops::Range<usize>)>>,
    markers: Vec<PreMarker>,
}

impl PreParsed {
    /// Parse the payloads of `messages` (each a message record's body) with
    /// [`canonical_frame`].
    fn parse(messages: &[&[u8]]) -> PreParsed {
        let mut out = PreParsed::default();
        for body in messages {
            let frame = body.get(22..).and_then(|payload| {
                let f = canonical_frame(payload)?;
                let first = out.markers.len();
                for &(id, x, y) in &f.markers[..f.len] {
                    // The name is a slice of the payload: its offset locates it.
                    let at = id.as_ptr() as usize - payload.as_ptr() as usize;
                    out.markers.push((at..at + id.len(), x, y));
                }
                Some((f.sec, f.nsec, first..out.markers.len()))
            });
            out.frames.push(frame);
        }
        out
    }

    /// The `k`-th message's frame, when it was canonical.
    fn frame(&self, k: usize) -> Option<PreFrame<'_>> {
        let (sec, nsec, r) = self.frames.get(k)?.as_ref()?;
        Some(PreFrame {
            sec: *sec,
            nsec: *nsec,
            markers: &self.markers[r.clone()],
        })
    }
}

/// A message's canonical frame parsed ahead (see [`PreParsed`]).
#[derive(Clone, Copy)]
struct PreFrame<'a> {
    sec: i64,
    nsec: i64,
    markers: &'a [PreMarker],
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
        // Foxglove's JSON types that hold no position: a velocity in a Vector3 is not a marker.
        "json" if NOT_POSITIONS.contains(&schema_name) => Err(Reject::Invalid(format!(
            "{schema_name} holds no marker position"
        ))),
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
    let (sec, nanos) = (pb_int(ts, "seconds")?, pb_int(ts, "nanos")?);
    JStamp::Parts { sec, nsec: nanos }.ns().map(Some)
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
    pre: Option<PreFrame<'_>>,
) -> Result<usize, String> {
    let p3 = |p: [f64; 3]| xy(Some(p[0]), Some(p[1]), Some(p[2]), plane);
    match dec {
        Decoder::Json => {
            if let Some(f) = pre {
                // Parsed ahead by canonical_frame from these same bytes.
                let stamp = JStamp::Parts {
                    sec: f.sec,
                    nsec: f.nsec,
                }
                .ns()?;
                for (at, x, y) in f.markers {
                    let id = data
                        .get(at.clone())
                        .and_then(|b| std::str::from_utf8(b).ok())
                        .ok_or("a marker name parsed ahead is not in the message")?;
                    acc.push(topic, id, stamp, xy(*x, *y, None, plane));
                }
                return Ok(f.markers.len());
            }
            if let Some(f) = canonical_frame(data) {
                let stamp = JStamp::Parts {
                    sec: f.sec,
                    nsec: f.nsec,
                }
                .ns()?;
                for &(id, x, y) in &f.markers[..f.len] {
                    acc.push(topic, id, stamp, xy(x, y, None, plane));
                }
                return Ok(f.len);
            }
            if let Ok(m) = serde_json::from_slice::<FastMsg>(data) {
                let stamp = match m.timestamp.or(m.header.and_then(|h| h.stamp)) {
                    Some(s) => JStamp::Parts {
                        sec: s.sec,
                        nsec: s.nsec,
                    }
                    .ns()?,
                    None => log_time,
                };
                if let Some(markers) = m.markers {
                    for mk in &markers {
                        acc.push(topic, &mk.id, stamp, xy(mk.x, mk.y, mk.z, plane));
                    }
                    return Ok(markers.len());
                }
                if let Some(p) = m.point.or(m.position) {
                    acc.push(topic, topic, stamp, xy(p.x, p.y, p.z, plane));
                    return Ok(1);
                }
                if m.x.is_some() || m.y.is_some() {
                    acc.push(topic, topic, stamp, xy(m.x, m.y, m.z, plane));
                    return Ok(1);
                }
            }
            let m: JMsg = serde_json::from_slice(data).map_err(|e| format!("JSON: {e}"))?;
            let stamp = match m.timestamp.or(m.header.and_then(|h| h.stamp)) {
                Some(s) => s.ns()?,
                None => log_time,
            };
            if let Some(markers) = m.markers {
                let n = markers.len();
                for mk in markers {
                    acc.push(topic, &mk.id, stamp, xy(mk.x, mk.y, mk.z, plane));
                }
                Ok(n)
            } else if let Some(p) = m.point.or(m.position) {
                acc.push(topic, topic, stamp, xy(p.x, p.y, p.z, plane));
                Ok(1)
            } else if m.x.is_some() || m.y.is_some() {
                acc.push(topic, topic, stamp, xy(m.x, m.y, m.z, plane));
                Ok(1)
            } else {
                Err("a JSON object with a \"markers\" array, a \"point\", or x and y".into())
            }
        }
        Decoder::PointStamped | Decoder::PoseStamped => {
            let pose = matches!(dec, Decoder::PoseStamped);
            let (h, p) = ros_cdr::point_stamped(data, pose).map_err(|e| {
                format!(
                    "CDR {}: {e}",
                    if pose { "PoseStamped" } else { "PointStamped" }
                )
            })?;
            acc.push(topic, topic, h.stamp.ns(), p3(p));
            Ok(1)
        }
        Decoder::TransformStamped => {
            let t = ros_cdr::transform_stamped(data)
                .map_err(|e| format!("CDR TransformStamped: {e}"))?;
            acc.push_tf(t, topic.ends_with("tf_static"));
            Ok(1)
        }
        Decoder::TfMessage => {
            let ts = ros_cdr::tf_message(data).map_err(|e| format!("CDR TFMessage: {e}"))?;
            let n = ts.len();
            for t in ts {
                acc.push_tf(t, topic.ends_with("tf_static"));
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
                p3([pb_f64(t, "x")?, pb_f64(t, "y")?, pb_f64(t, "z")?])
            } else {
                None
            };
            acc.push(topic, name, stamp, p);
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
                acc.push(topic, name, stamp, xys.get(k).copied());
            }
            for (k, p) in xys.iter().enumerate().skip(POINTS_NAMES.len()) {
                acc.push(topic, &format!("point{k}"), stamp, Some(*p));
            }
            Ok(xys.len())
        }
    }
}

/// The largest record (or decompressed chunk record) read from a file of `size` bytes: 256
/// times the file (compressed chunks may hold records larger than the file), at least 1 MiB,
/// at most 256 MiB; 256 MiB when the size is unknown.
pub fn record_limit(size: Option<u64>) -> usize {
    const MIB: u64 = 1 << 20;
    let limit = size.map_or(256 * MIB, |s| s.saturating_mul(256).clamp(MIB, 256 * MIB));
    limit as usize
}

/// The most bytes the records of a file of `size` bytes may decompress to, in all: 1024 times
/// the file plus 64 MiB (a bomb of zeros stops here instead of running for minutes).
pub fn decompressed_limit(size: Option<u64>) -> u64 {
    size.unwrap_or(1 << 30)
        .saturating_mul(1024)
        .saturating_add(64 << 20)
}

/// Check that every length field of a Schema, Channel, Message or Metadata record fits in
/// the record, so parsing it allocates no more than the record holds.
fn check_lengths(opcode: u8, data: &[u8]) -> Result<(), String> {
    struct Cur<'a> {
        d: &'a [u8],
        at: usize,
    }
    impl Cur<'_> {
        fn skip(&mut self, n: usize, what: &str) -> Result<(), String> {
            match self.at.checked_add(n) {
                Some(end) if end <= self.d.len() => {
                    self.at = end;
                    Ok(())
                }
                _ => Err(format!(
                    "{what}: {n} byte(s) at offset {}, beyond the record's {} bytes",
                    self.at,
                    self.d.len()
                )),
            }
        }
        fn len(&mut self, what: &str) -> Result<usize, String> {
            let start = self.at;
            self.skip(4, what)?;
            let b: [u8; 4] = self.d[start..start + 4].try_into().expect("4 bytes");
            Ok(u32::from_le_bytes(b) as usize)
        }
        fn string(&mut self, what: &str) -> Result<(), String> {
            let n = self.len(what)?;
            self.skip(n, what)
        }
        fn map(&mut self, what: &str) -> Result<(), String> {
            let n = self.len(what)?;
            let end = self.at;
            self.skip(n, what)?;
            let mut inner = Cur {
                d: &self.d[end..end + n],
                at: 0,
            };
            while inner.at < n {
                inner.string(what)?;
                inner.string(what)?;
            }
            Ok(())
        }
    }
    let mut c = Cur { d: data, at: 0 };
    match opcode {
        op::SCHEMA => {
            c.skip(2, "schema id")?;
            c.string("schema name")?;
            c.string("schema encoding")?;
            c.string("schema data")
        }
        op::CHANNEL => {
            c.skip(4, "channel ids")?;
            c.string("topic")?;
            c.string("message encoding")?;
            c.map("channel metadata")
        }
        op::MESSAGE => c.skip(22, "message header"),
        op::METADATA => {
            c.string("metadata name")?;
            c.map("metadata")
        }
        _ => Ok(()),
    }
}

/// A Message record whose body (at least 22 bytes) is `data`: channel id, sequence, log time
/// and publish time (little-endian), then the payload, borrowed.
fn message_record(data: &[u8]) -> Record<'_> {
    let le = |at: usize, n: usize| {
        data[at..at + n]
            .iter()
            .rev()
            .fold(0u64, |v, &b| (v << 8) | u64::from(b))
    };
    Record::Message {
        header: MessageHeader {
            channel_id: le(0, 2) as u16,
            sequence: le(2, 4) as u32,
            log_time: le(6, 8),
            publish_time: le(14, 8),
        },
        data: std::borrow::Cow::Borrowed(&data[22..]),
    }
}

/// The first line of an mcap error, without terminal escape codes (binrw's errors carry a
/// coloured backtrace).
fn plain(err: &McapError) -> String {
    let text = err.to_string();
    let mut out = String::new();
    let mut chars = text.lines().next().unwrap_or("").chars().peekable();
    while let Some(c) = chars.next() {
        if c == '\u{1b}' {
            // CSI: ESC [ params final-byte
            if chars.peek() == Some(&'[') {
                chars.next();
                for d in chars.by_ref() {
                    if ('@'..='~').contains(&d) {
                        break;
                    }
                }
            }
        } else if !c.is_control() {
            out.push(c);
        }
    }
    out.trim().trim_end_matches(':').to_string()
}

/// What one record came to.
enum Step {
    /// Read on.
    Next,
    /// The file is damaged here (why); what was read before is kept.
    Damage(String),
    /// Past the time window: stop reading.
    Stop,
}

/// The records read; the others are only counted.
const USED_RECORDS: [u8; 4] = [op::SCHEMA, op::CHANNEL, op::MESSAGE, op::METADATA];

/// The bytes of a chunk record before its records field: start and end time, uncompressed
/// size, CRC and compression length (8 + 8 + 8 + 4 + 4), the compression string, then the
/// compressed size (8).
const CHUNK_FIXED: usize = 32;

/// Buffers reused across chunks, so a file of many chunks allocates a few times only.
#[derive(Default)]
struct ChunkBuffers {
    spare: Vec<Vec<u8>>,
}

/// Chunks read while others are prepared on the thread pool.
const CHUNKS_AHEAD: usize = 3;

thread_local! {
    /// Each pool thread's zstd decoder, reused across chunks.
    static ZSTD: std::cell::RefCell<Option<::zstd::zstd_safe::DCtx<'static>>> =
        const { std::cell::RefCell::new(None) };
}

/// Decompress `src` (one chunk's compressed records) into `out`, at most `size` bytes, the way
/// the mcap crate's decoders do (frames after frames until `size` bytes; bytes past that are
/// ignored). Whatever came out before an error is kept in `out`; the error is returned.
fn decompress_chunk(
    compression: &str,
    src: &[u8],
    size: usize,
    zstd: &mut Option<::zstd::zstd_safe::DCtx<'static>>,
    out: &mut Vec<u8>,
) -> Option<String> {
    use ::zstd::zstd_safe::{get_error_name, DCtx, InBuffer, OutBuffer, ResetDirective};
    out.clear();
    // Only `size` bytes are asked for; the capacity bounds what the decoder may write.
    out.reserve_exact(size);
    let short = match compression {
        "zstd" => {
            let dctx = zstd.get_or_insert_with(DCtx::create);
            let mut input = InBuffer::around(src);
            let mut output = OutBuffer::around(out);
            let mut failed = None;
            while output.pos() < size && input.pos < src.len() {
                let before = (input.pos, output.pos());
                if let Err(code) = dctx.decompress_stream(&mut output, &mut input) {
                    failed = Some(McapError::DecompressionError(get_error_name(code).into()));
                    break;
                }
                if (input.pos, output.pos()) == before {
                    break;
                }
            }
            // A frame cut short or an error leaves the context mid-frame: the next chunk starts
            // clean.
            let _ = dctx.reset(ResetDirective::SessionOnly);
            failed
        }
        "lz4" => {
            let mut rest = src;
            let mut failed = None;
            // One lz4 decoder per frame: a chunk may hold several frames back to back.
            while out.len() < size && !rest.is_empty() {
                let before = (rest.len(), out.len());
                let read = ::lz4::Decoder::new(rest).and_then(|mut dec| {
                    let want = (size - out.len()) as u64;
                    let read = Read::by_ref(&mut dec).take(want).read_to_end(out);
                    rest = dec.finish().0;
                    read
                });
                if let Err(e) = read {
                    failed = Some(McapError::Io(e));
                    break;
                }
                if (rest.len(), out.len()) == before {
                    break;
                }
            }
            failed
        }
        _ => unreachable!("compression checked by the caller"),
    };
    out.truncate(size);
    short.map(|e| plain(&e))
}

/// Where the next record of a chunk ends, or why it cannot be read: `left` bytes of the
/// chunk's records remain (as declared), of which `avail` are at hand. Checked arithmetic
/// only: every length is compared with what remains, nothing is subtracted past zero.
enum NextRecord {
    /// The record's opcode and body length; its body follows the 9-byte opcode and length.
    Record(u8, usize),
    /// The 9-byte opcode and length, or the body, run past the chunk's end: the chunk is
    /// damaged.
    Beyond(String),
    /// The body is longer than the record limit.
    TooLarge(u8, u64),
    /// The bytes at hand end first (a truncated file or a decompression error).
    Short,
}

/// The record at the start of `rest` (`left` bytes of the chunk remain, `rest.len()` of them
/// at hand), checked against the chunk and the record `limit`.
fn next_in_chunk(rest: &[u8], left: u64, limit: usize) -> NextRecord {
    const HEAD: u64 = 9;
    if left < HEAD {
        return NextRecord::Beyond(format!(
            "its opcode and length: 9 bytes, beyond the {left} byte(s) left in the chunk"
        ));
    }
    let Some((&[opcode], tail)) = rest.split_first_chunk::<1>() else {
        return NextRecord::Short;
    };
    let Some(len) = tail.first_chunk::<8>().map(|b| u64::from_le_bytes(*b)) else {
        return NextRecord::Short;
    };
    // The limit first, as the mcap crate's reader checks it.
    let Some(body) = usize::try_from(len).ok().filter(|&n| n <= limit) else {
        return NextRecord::TooLarge(opcode, len);
    };
    let room = left - HEAD;
    if len > room {
        return NextRecord::Beyond(format!(
            "length {len} bytes, beyond the {room} byte(s) left in the chunk after its opcode and length"
        ));
    }
    if (rest.len() - 9) < body {
        return NextRecord::Short;
    }
    NextRecord::Record(opcode, body)
}

/// The decoding state of one read: channels, samples and counts, fed record by record.
struct Reading<'a> {
    path: &'a Path,
    opts: &'a ReadOptions,
    limit: usize,
    budget: u64,
    schemas: HashMap<u16, (String, String, Vec<u8>)>,
    channels: BTreeMap<u16, Channel>,
    acc: Acc,
    parsed: Parsed,
    records: u64,
    messages: u64,
    record_bytes: u64,
    unsupported_compression: Option<String>,
    window_end: Option<f64>,
    first_log_time: Option<u64>,
    stopped_at: Option<f64>,
    bufs: ChunkBuffers,
    /// The chunks taken, in preparation or prepared, not yet read, in file order.
    deferred: std::collections::VecDeque<Deferred>,
}

impl Reading<'_> {
    /// The damage text of a record longer than the limit.
    fn too_large(&self, opcode: u8, len: u64) -> String {
        format!(
            "record (opcode {opcode:#04x}) of {len} bytes: more than the {}-byte limit for a file of this size",
            self.limit
        )
    }

    /// Count a record of `len` bytes against the budget of decompressed bytes.
    fn tally(&mut self, len: usize) -> Option<Step> {
        self.records += 1;
        self.record_bytes += len as u64;
        (self.record_bytes > self.budget).then(|| {
            Step::Damage(format!(
                "records decompress to more than {} bytes (1024 times the file plus 64 MiB)",
                self.budget
            ))
        })
    }

    /// Read one record (outside chunks or inside one); `pre` is the message's canonical frame
    /// when it was parsed ahead.
    fn record(
        &mut self,
        opcode: u8,
        data: &[u8],
        pre: Option<PreFrame<'_>>,
    ) -> Result<Step, DataError> {
        let (path, opts) = (self.path, self.opts);
        if let Some(damage) = self.tally(data.len()) {
            return Ok(damage);
        }
        let records = self.records;
        // Only these records are used; the mcap crate sizes strings from their length
        // fields before checking them, so their lengths are checked here first.
        if !USED_RECORDS.contains(&opcode) {
            return Ok(Step::Next);
        }
        if let Err(why) = check_lengths(opcode, data) {
            return Ok(Step::Damage(format!(
                "record {records} (opcode {opcode:#04x}): {why}"
            )));
        }
        // A message's header is four fixed fields (check_lengths saw its 22 bytes):
        // read here, the payload borrowed, as parse_record would give them.
        let parsed_record = if opcode == op::MESSAGE {
            Ok(message_record(data))
        } else {
            ::mcap::parse_record(opcode, data)
        };
        let record = match parsed_record {
            Ok(r) => r,
            Err(e) => return Ok(Step::Damage(plain(&e))),
        };
        match record {
            Record::Schema { header, data } => {
                // Only protobuf needs the schema's bytes; keep memory bounded otherwise.
                let data = if header.encoding == "protobuf" {
                    data.into_owned()
                } else {
                    Vec::new()
                };
                self.schemas
                    .insert(header.id, (header.name, header.encoding, data));
            }
            Record::Channel(c) => {
                let (sname, senc, sdata) = self
                    .schemas
                    .get(&c.schema_id)
                    .map(|(n, e, d)| (n.as_str(), e.as_str(), d.as_slice()))
                    .unwrap_or_default();
                let state = if !opts.topics.is_empty() && !opts.topics.contains(&c.topic) {
                    ChannelState::Ignored("not chosen by --topic".into())
                } else {
                    match decoder_for(&c.message_encoding, sname, senc, sdata) {
                        Ok(d) => ChannelState::Markers(d),
                        Err(Reject::Unsupported(why)) => {
                            ChannelState::Ignored(format!("{why} is not supported"))
                        }
                        Err(Reject::Invalid(why)) => ChannelState::Ignored(why),
                    }
                };
                self.channels.entry(c.id).or_insert(Channel {
                    topic: c.topic,
                    state,
                    decoded: 0,
                });
            }
            Record::Message { header, data } => {
                self.messages += 1;
                let messages = self.messages;
                let Some(ch) = self.channels.get_mut(&header.channel_id) else {
                    return Err(DataError::parse(
                        path,
                        format!("record {records}"),
                        "channel id",
                        "a channel defined before its messages",
                        header.channel_id.to_string(),
                    ));
                };
                let ChannelState::Markers(dec) = &ch.state else {
                    return Ok(Step::Next);
                };
                if let Some(end) = self.window_end {
                    let first = *self.first_log_time.get_or_insert(header.log_time);
                    let since = header.log_time.saturating_sub(first) as f64 * 1e-9;
                    if since > end {
                        self.stopped_at = Some(since);
                        return Ok(Step::Stop);
                    }
                }
                let result = match i64::try_from(header.log_time) {
                    Ok(log_time) => decode(
                        dec,
                        &ch.topic,
                        &data,
                        log_time,
                        opts.plane,
                        &mut self.acc,
                        pre,
                    ),
                    Err(_) => Err(format!(
                        "a log_time below 2^63 ns (year 2262), found {}",
                        header.log_time
                    )),
                };
                match result {
                    Ok(_) => ch.decoded += 1,
                    Err(why) if ch.decoded == 0 => {
                        ch.state = ChannelState::Ignored(format!(
                            "its first message is not marker data: {why}"
                        ));
                    }
                    Err(why) => {
                        return Err(DataError::parse(
                            path,
                            format!("message {messages} (record {records}) on {}", ch.topic),
                            "message",
                            "marker data like the channel's earlier messages",
                            why,
                        ))
                    }
                }
            }
            Record::Metadata(Metadata { name, metadata }) => {
                for (k, v) in metadata {
                    self.parsed.metadata.insert(format!("{name}.{k}"), v);
                }
            }
            _ => {}
        }
        Ok(Step::Next)
    }

    /// Take a chunk record's `body` (everything after its opcode and length `len`; fewer bytes
    /// than `len` when the file ends inside it; `start` is its offset in the file, `bytes` the
    /// bytes read so far). It is prepared ([`prepare_chunk`]: header, decompression, CRC,
    /// canonical frames) on the thread pool while the reader reads on, and read in order once
    /// [`CHUNKS_AHEAD`] chunks are taken after it, or by [`Reading::flush`]. Returns what
    /// reading the chunk that came due came to: the step, and the file offset the damage is
    /// reported at.
    fn chunk(
        &mut self,
        body: &[u8],
        len: u64,
        start: u64,
        bytes: u64,
    ) -> Result<(Step, Option<u64>), DataError> {
        // The budget left before the chunks ahead are read: looser than when this chunk is
        // read (checked again then), so at most CHUNKS_AHEAD + 1 budgets are held at once.
        let room = self.budget.saturating_sub(self.record_bytes);
        let (budget, limit) = (self.budget, self.limit);
        let out = self.bufs.spare.pop().unwrap_or_default();
        // The reader's buffer moves on: the chunk is copied for the pool.
        let body = body.to_vec();
        let (tx, ready) = std::sync::mpsc::sync_channel(1);
        let prepare = move || {
            let prepared = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                let mut zstd = ZSTD.take();
                let prepared =
                    prepare_chunk(&body, len, start, (room, budget, limit), &mut zstd, out);
                ZSTD.set(zstd);
                prepared
            }))
            .unwrap_or_else(|_| Prepared::Damage(format!("chunk at byte {start}: unreadable")));
            // The receiver is gone only when reading stopped before this chunk.
            let _ = tx.send(prepared);
        };
        // On a pool thread (a directory's recordings are read in parallel) the chunk is
        // prepared here: waiting there for the pool could leave no thread to prepare it.
        if rayon::current_thread_index().is_some() {
            prepare();
        } else {
            rayon::spawn(prepare);
        }
        self.deferred.push_back(Deferred {
            ready,
            start,
            bytes,
            counted: Vec::new(),
        });
        if self.deferred.len() > CHUNKS_AHEAD {
            let due = self.deferred.pop_front().expect("more than CHUNKS_AHEAD");
            return self.finish_chunk(due);
        }
        Ok((Step::Next, None))
    }

    /// Read the chunks taken and not yet read, in order (before any record that is read, and
    /// at the end); those after a chunk that stops the reading are dropped.
    fn flush(&mut self) -> Result<(Step, Option<u64>), DataError> {
        while let Some(d) = self.deferred.pop_front() {
            let read = self.finish_chunk(d)?;
            if !matches!(read.0, Step::Next) {
                self.deferred.clear();
                return Ok(read);
            }
        }
        Ok((Step::Next, None))
    }

    /// Read a prepared chunk's records in order. Damage is reported at the bytes read when
    /// the chunk was (the reader has read on since), unless a place in the file is known.
    fn finish_chunk(&mut self, d: Deferred) -> Result<(Step, Option<u64>), DataError> {
        let prepared = d
            .ready
            .recv()
            .unwrap_or_else(|_| Prepared::Damage(format!("chunk at byte {}: unreadable", d.start)));
        let (step, at) = match prepared {
            Prepared::Damage(why) => (Step::Damage(why), None),
            Prepared::Unsupported(c) => {
                let why = plain(&McapError::UnsupportedCompression(c.clone()));
                self.unsupported_compression = Some(c);
                (Step::Damage(why), None)
            }
            Prepared::Records(r) => {
                let room = self.budget.saturating_sub(self.record_bytes);
                let result = match r.uncompressed {
                    Some(size) if size > room => {
                        Ok((Step::Damage(over_budget(self.budget, d.start, size)), None))
                    }
                    _ => self.chunk_records(&r, d.start),
                };
                self.bufs.spare.push(r.out);
                result?
            }
        };
        if let Step::Damage(_) = step {
            return Ok((step, at.or(Some(d.bytes))));
        }
        if let Step::Next = step {
            for (len, bytes) in d.counted {
                if let Some(damage) = self.tally(len) {
                    return Ok((damage, Some(bytes)));
                }
            }
        }
        Ok((step, at))
    }

    /// Check the CRC of a chunk's records (all of them when none are short) and read them.
    fn chunk_records(
        &mut self,
        r: &ChunkRecords,
        start: u64,
    ) -> Result<(Step, Option<u64>), DataError> {
        let (records, declared, in_file) = (&r.out[..], r.declared, r.in_file);
        if let Some(calculated) = r.calculated_crc.filter(|&c| c != r.crc) {
            let err = McapError::BadChunkCrc {
                saved: r.crc,
                calculated,
            };
            return Ok((
                Step::Damage(format!("chunk at byte {start}: {}", plain(&err))),
                None,
            ));
        }
        let mut at = 0usize;
        // Message records read so far: the index of the next one's frame parsed ahead.
        let mut message = 0usize;
        loop {
            // at <= records.len() <= declared throughout.
            let left = declared - at as u64;
            if left == 0 {
                return Ok((Step::Next, None));
            }
            let rest = &records[at..];
            // Where the record's opcode and length end in the file (uncompressed chunks).
            let head_end = in_file.map(|f| f + at as u64 + 9);
            match next_in_chunk(rest, left, self.limit) {
                NextRecord::Record(opcode, len) => {
                    let data = &rest[9..9 + len];
                    at += 9 + len;
                    let pre = if opcode == op::MESSAGE {
                        message += 1;
                        r.pre.frame(message - 1)
                    } else {
                        None
                    };
                    let step = self.record(opcode, data, pre)?;
                    if !matches!(step, Step::Next) {
                        return Ok((step, in_file.map(|f| f + at as u64)));
                    }
                }
                NextRecord::TooLarge(opcode, len) => {
                    return Ok((Step::Damage(self.too_large(opcode, len)), head_end));
                }
                NextRecord::Beyond(why) => {
                    let n = self.records + 1;
                    return Ok((
                        Step::Damage(format!("record {n} (in the chunk at byte {start}): {why}")),
                        head_end.filter(|_| rest.len() >= 9),
                    ));
                }
                NextRecord::Short => {
                    let why = r
                        .short
                        .clone()
                        .unwrap_or_else(|| plain(&McapError::UnexpectedEoc));
                    return Ok((Step::Damage(why), None));
                }
            }
        }
    }
}

/// The damage text of a chunk at `start` declaring `size` decompressed bytes, past `budget`.
fn over_budget(budget: u64, start: u64, size: u64) -> String {
    format!(
        "records decompress to more than {budget} bytes (1024 times the file plus 64 MiB): the chunk at byte {start} declares {size}"
    )
}

/// A chunk taken by [`Reading::chunk`], waiting to be read in order.
struct Deferred {
    /// Where the pool sends the chunk prepared.
    ready: std::sync::mpsc::Receiver<Prepared>,
    /// The chunk's offset in the file.
    start: u64,
    /// The bytes read when the chunk was taken.
    bytes: u64,
    /// Records after it that are only counted (message indexes follow every chunk): their
    /// lengths and the bytes read when each was, counted once the chunk is read, so the
    /// chunk is read beside the next one.
    counted: Vec<(usize, u64)>,
}

/// A chunk made ready to read by [`prepare_chunk`].
enum Prepared {
    /// Damaged before its records (why).
    Damage(String),
    /// Its compression is not supported (the name).
    Unsupported(String),
    /// Its records.
    Records(ChunkRecords),
}

/// A chunk's records, decompressed (or copied, when stored uncompressed), as far as they
/// could be had.
struct ChunkRecords {
    out: Vec<u8>,
    /// The records' length as the chunk declares it.
    declared: u64,
    /// A compressed chunk's declared uncompressed size, checked against the budget again when
    /// the chunk is read.
    uncompressed: Option<u64>,
    /// The CRC the chunk declares (0: none).
    crc: u32,
    /// The CRC of the records, computed when all are at hand and one is declared.
    calculated_crc: Option<u32>,
    /// Why fewer bytes than declared are at hand.
    short: Option<String>,
    /// Where the records lie in the file (uncompressed chunks).
    in_file: Option<u64>,
    /// The message records' canonical frames, parsed ahead.
    pre: PreParsed,
}

/// Prepare a chunk record's `body` (see [`Reading::chunk`]): check its header, decompress its
/// records in one go into `out` (at most `room` bytes of the `budget`), compute their CRC and
/// parse the canonical JSON frames of its messages (records longer than `limit` are left to
/// the ordered read, which reports them). Touches no reading state, so it runs beside the
/// ordered read of the chunk before.
fn prepare_chunk(
    body: &[u8],
    len: u64,
    start: u64,
    (room, budget, limit): (u64, u64, usize),
    zstd: &mut Option<::zstd::zstd_safe::DCtx<'static>>,
    mut out: Vec<u8>,
) -> Prepared {
    let complete = body.len() as u64 == len;
    let eof = || plain(&McapError::UnexpectedEof);
    let at_chunk = |why: String| format!("chunk at byte {start}: {why}");
    // The fixed fields and the compression string's length.
    let Some(cl) = body.get(CHUNK_FIXED - 4..CHUNK_FIXED) else {
        return Prepared::Damage(if complete {
            at_chunk(plain(&McapError::BadChunkLength {
                header: (CHUNK_FIXED + 8) as u64,
                available: len,
            }))
        } else {
            eof()
        });
    };
    let cl = u32::from_le_bytes(cl.try_into().expect("4 bytes"));
    let header_len = (CHUNK_FIXED as u64 + 8).saturating_add(u64::from(cl));
    if header_len > len {
        return Prepared::Damage(plain(&McapError::BadChunkLength {
            header: header_len,
            available: len,
        }));
    }
    // header_len <= len, which the reader held in memory: it fits in usize.
    let header_len = header_len as usize;
    let Some(header) = body.get(..header_len) else {
        return Prepared::Damage(eof());
    };
    let le64 = |at: usize| u64::from_le_bytes(header[at..at + 8].try_into().expect("8 bytes"));
    let uncompressed_size = le64(16);
    let crc = u32::from_le_bytes(header[24..28].try_into().expect("4 bytes"));
    let compressed_size = le64(header_len - 8);
    let Ok(compression) = std::str::from_utf8(&header[CHUNK_FIXED..header_len - 8]) else {
        return Prepared::Damage(at_chunk("compression: not UTF-8".into()));
    };
    if compressed_size > len - header_len as u64 {
        return Prepared::Damage(at_chunk(format!(
            "compressed size {compressed_size} bytes, beyond the record's {} byte(s) after the chunk header",
            len - header_len as u64
        )));
    }
    let src = &body[header_len..body.len().min(header_len + compressed_size as usize)];
    let (declared, short, in_file, uncompressed) = match compression {
        // Records of an uncompressed chunk lie in the file from here; copied, as the reader's
        // buffer moves on before they are read.
        "" => {
            out.clear();
            out.extend_from_slice(src);
            (
                compressed_size,
                (!complete).then(eof),
                Some(start + 9 + header_len as u64),
                None,
            )
        }
        "zstd" | "lz4" => {
            // Checked before allocating: the declared size is untrusted.
            let size = match usize::try_from(uncompressed_size) {
                Ok(size) if uncompressed_size <= room => size,
                _ => {
                    return Prepared::Damage(over_budget(budget, start, uncompressed_size));
                }
            };
            let failed = decompress_chunk(compression, src, size, zstd, &mut out);
            // Fewer bytes than declared: the file ended inside the chunk, or its data is bad.
            let short = (out.len() < size).then(|| match failed {
                _ if !complete => eof(),
                Some(why) => why,
                None => plain(&McapError::DecompressionError(
                    "decompressor made no progress".into(),
                )),
            });
            (uncompressed_size, short, None, Some(uncompressed_size))
        }
        other => return Prepared::Unsupported(other.to_string()),
    };
    // A CRC of 0 means none was written; a partial chunk has nothing to check it against.
    let calculated_crc = (crc != 0 && short.is_none()).then(|| crc32fast::hash(&out));
    // The message records, walked as the ordered read walks them, up to where it would stop.
    let mut messages = Vec::new();
    let mut at = 0usize;
    while let NextRecord::Record(opcode, n) = next_in_chunk(&out[at..], declared - at as u64, limit)
    {
        if opcode == op::MESSAGE {
            messages.push(&out[at + 9..at + 9 + n]);
        }
        at += 9 + n;
        if at as u64 == declared {
            break;
        }
    }
    let pre = PreParsed::parse(&messages);
    Prepared::Records(ChunkRecords {
        declared,
        uncompressed,
        crc,
        calculated_crc,
        short,
        in_file,
        pre,
        out,
    })
}

/// Read MCAP bytes from any reader, streaming; `path` labels errors; `size` (the file's
/// length, when known) bounds every length the file declares.
pub(crate) fn read_from(
    mut input: impl Read,
    path: &Path,
    opts: &ReadOptions,
    size: Option<u64>,
) -> Result<Parsed, DataError> {
    let limit = record_limit(size);
    let budget = decompressed_limit(size);
    // Chunks come whole and are read here: decompressed in one call and walked with checked
    // lengths (the crate's record-by-record decompression is slower, and its walk through
    // uncompressed chunks can overflow).
    let mut reader = LinearReader::new_with_options(
        LinearReaderOptions::default()
            .with_record_length_limit(limit)
            .with_emit_chunks(true),
    );
    let mut st = Reading {
        path,
        opts,
        limit,
        budget,
        schemas: HashMap::new(),
        channels: BTreeMap::new(),
        acc: Acc::default(),
        parsed: Parsed::default(),
        records: 0,
        messages: 0,
        record_bytes: 0,
        unsupported_compression: None,
        // With a time window, reading stops once marker messages are past its end (by
        // log_time, with a second of margin for stamps that differ from it): the rest is never
        // decoded.
        window_end: opts.time_window.map(|(_, end)| end + 1.0),
        first_log_time: None,
        stopped_at: None,
        bufs: ChunkBuffers::default(),
        deferred: Default::default(),
    };
    let mut bytes = 0u64;
    let mut damage: Option<String> = None;
    // Where the damage is reported when not at `bytes` (see `Reading::chunk`).
    let mut damage_at: Option<u64> = None;
    // The reader asks for exactly the bytes the next record needs, so the bytes read since
    // it last gave a record are the record in progress (after the magic, at first). They are
    // kept while that record is a chunk: when the file ends inside it, its records before the
    // cut are still read, as the crate's record-by-record reading did.
    let mut pending: Vec<u8> = Vec::new();
    let mut skip = ::mcap::MAGIC.len();
    let mut record_start = skip as u64;
    // What a step came to: read on, or stop with the damage (and where it is reported).
    let mut settle = |step: (Step, Option<u64>)| match step {
        (Step::Next, _) => false,
        (Step::Damage(why), at) => {
            damage = Some(why);
            damage_at = at;
            true
        }
        (Step::Stop, _) => true,
    };
    loop {
        let Some(event) = reader.next_event() else {
            // The end: the chunk taken last is read.
            settle(st.flush()?);
            break;
        };
        let event = match event {
            Ok(e) => e,
            Err(e) => {
                // The chunk taken before comes first.
                if settle(st.flush()?) {
                    break;
                }
                let in_progress = pending.get(skip..).unwrap_or_default();
                if let (McapError::UnexpectedEof, Some((&[op::CHUNK], rest))) =
                    (&e, in_progress.split_first_chunk::<1>())
                {
                    if let Some((len, body)) = rest.split_first_chunk::<8>() {
                        let len = u64::from_le_bytes(*len);
                        let taken = st.chunk(body, len, record_start, bytes)?;
                        if settle(taken) || settle(st.flush()?) {
                            break;
                        }
                    }
                }
                let why = match e {
                    McapError::RecordTooLarge { opcode, len } => st.too_large(opcode, len),
                    McapError::ChunkTooLarge(len) => format!(
                        "chunk of {len} bytes: more than the {limit}-byte limit for a file of this size"
                    ),
                    other => plain(&other),
                };
                settle((Step::Damage(why), None));
                break;
            }
        };
        match event {
            LinearReadEvent::ReadRequest(need) => {
                let buf = reader.insert(need);
                let n = input.read(buf).map_err(|source| DataError::Io {
                    path: path.to_owned(),
                    source,
                })?;
                if pending.get(skip).is_none_or(|&o| o == op::CHUNK) {
                    pending.extend_from_slice(&buf[..n]);
                }
                bytes += n as u64;
                reader.notify_read(n);
            }
            LinearReadEvent::Record { opcode, data } => {
                pending.clear();
                skip = 0;
                let start = std::mem::replace(&mut record_start, bytes);
                let step = if opcode == op::CHUNK {
                    st.chunk(data, data.len() as u64, start, bytes)?
                } else if let (Some(d), false) =
                    (st.deferred.back_mut(), USED_RECORDS.contains(&opcode))
                {
                    // Only counted: after the chunk taken before it is read.
                    d.counted.push((data.len(), bytes));
                    (Step::Next, None)
                } else {
                    // Records read come after the chunk taken before them.
                    match st.flush()? {
                        (Step::Next, _) => (st.record(opcode, data, None)?, None),
                        other => other,
                    }
                };
                if settle(step) {
                    break;
                }
            }
        }
    }
    let bytes = damage_at.unwrap_or(bytes);
    let Reading {
        channels,
        mut acc,
        mut parsed,
        records,
        messages,
        unsupported_compression,
        stopped_at,
        ..
    } = st;
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
    for t in &opts.topics {
        if !channels.values().any(|c| c.topic == *t) && damage.is_none() {
            return Err(DataError::Options {
                path: path.to_owned(),
                message: format!("--topic {t}: no such channel; {}", channel_list()),
            });
        }
    }
    if let Some(t) = stopped_at {
        parsed.notes.push(format!(
            "stopped reading at {t:.3} s: past the time window, the rest of the file is not decoded"
        ));
    }
    if let Some(c) = unsupported_compression {
        return Err(DataError::Unsupported {
            path: path.to_owned(),
            what: "chunk compression".into(),
            found: c,
            supported: "none, zstd, lz4".into(),
        });
    }
    if let Some(err) = damage {
        if acc.is_empty() {
            return Err(DataError::Mcap {
                path: path.to_owned(),
                at: format!("after {records} record(s), {bytes} byte(s)"),
                message: err,
            });
        }
        parsed.warnings.push(format!(
            "{}: damaged after {messages} message(s) ({records} records, {bytes} bytes read): {err}; \
             kept the frames before the damage",
            path.display()
        ));
    }
    let tf_notes = compose_tf(&mut acc, opts.plane)
        .map_err(|why| DataError::parse(path, "the /tf messages", "transforms", why, "more"))?;
    parsed.notes.extend(tf_notes);
    if acc.series.is_empty() {
        // Channels in id order, so the same file gives the same message on every run.
        let unsupported: Vec<&Channel> = channels
            .values()
            .filter(
                |c| matches!(&c.state, ChannelState::Ignored(w) if w.ends_with("not supported")),
            )
            .collect();
        if unsupported.len() == 1 && channels.len() == 1 {
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
    // A marker on several channels (the same motion as points and as transforms): the first
    // channel it appeared on is read, the others are named in a note.
    let mut chosen: HashMap<String, String> = HashMap::new();
    let mut series = Vec::new();
    for (topic, name, s) in std::mem::take(&mut acc.series) {
        match chosen.get(&name) {
            Some(first) => parsed.notes.push(format!(
                "marker {name:?} is also on channel {topic}: read from {first} (--topic to choose)"
            )),
            None => {
                chosen.insert(name.clone(), topic);
                series.push((name, s));
            }
        }
    }
    // Sort, check duplicates, convert to seconds from the earliest stamp (exact integer
    // differences first, in i128 so no pair of i64 stamps overflows).
    let mut t0 = i64::MAX;
    for (_, s) in &mut series {
        if !s.is_sorted_by_key(|x| x.0) {
            s.sort_by_key(|x| x.0);
        }
        t0 = t0.min(s[0].0);
    }
    let secs = |ns: i64| (ns as i128 - t0 as i128) as f64 / 1e9;
    for (name, s) in series {
        if let Some(w) = s.windows(2).find(|w| w[0].0 == w[1].0) {
            return Err(DataError::Time {
                path: path.to_owned(),
                at: format!("marker {name:?}"),
                time: secs(w[1].0),
                previous: secs(w[0].0),
                problem: "is repeated",
            });
        }
        parsed.series.push(Series {
            name,
            times: s.iter().map(|x| secs(x.0)).collect(),
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::Recording;
    use rand::{Rng, SeedableRng};

    /// Samples: marker, stamp, position bits.
    type Samples = Vec<(String, i64, Option<[u64; 2]>)>;

    /// What the serde reader alone makes of a JSON message: its samples, bit for bit.
    fn by_serde(data: &[u8]) -> Result<Samples, String> {
        let m: JMsg = serde_json::from_slice(data).map_err(|e| format!("JSON: {e}"))?;
        let stamp = m.timestamp.expect("a stamp").ns()?;
        Ok(m.markers
            .expect("markers")
            .into_iter()
            .map(|mk| {
                let p = xy(mk.x, mk.y, mk.z, None);
                (mk.id, stamp, p.map(|p| p.map(f64::to_bits)))
            })
            .collect())
    }

    /// What `decode` gives (the canonical layout first, then serde); the same as when the
    /// frame is parsed ahead in a message record, as chunks are.
    fn by_decode(data: &[u8]) -> Result<Samples, String> {
        let samples = |pre: Option<PreFrame<'_>>| -> Result<Samples, String> {
            let mut acc = Acc::default();
            decode(&Decoder::Json, "/markers", data, 0, None, &mut acc, pre)?;
            let mut out = Vec::new();
            for (_, name, s) in acc.series {
                for (ns, p) in s {
                    out.push((name.clone(), ns, p.map(|p| p.map(f64::to_bits))));
                }
            }
            // decode groups by marker; by_serde lists in message order: compare by name.
            out.sort_by(|a, b| a.0.cmp(&b.0));
            Ok(out)
        };
        let record = [&[0u8; 22][..], data].concat();
        let ahead = PreParsed::parse(&[&record]);
        let direct = samples(None);
        assert_eq!(samples(ahead.frame(0)), direct, "parsed ahead");
        direct
    }

    fn frame(sec: &str, nsec: &str, x: &str, y: &str) -> String {
        format!(
            r#"{{"timestamp":{{"sec":{sec},"nsec":{nsec}}},"frame_id":"rail","markers":[{{"id":"slider","x":{x},"y":{y}}},{{"id":"bob","x":0.2350487,"y":-0.186438}}]}}"#
        )
    }

    #[test]
    fn canonical_layout_reads_what_serde_reads() {
        let numbers = [
            "6.09e-05",
            "-9.04e-05",
            "-0.0",
            "0.0",
            "1e-320",
            "5e-324",
            "2.4703282292062328e-324",
            "0.30000000000000004",
            "1.7976931348623157e308",
            "2.2250738585072014e-308",
            "123456789012345678.9",
            "0.000000000000000000001234567890123456789",
            "9007199254740993.0",
            "1E5",
            "1e+05",
            "null",
        ];
        for x in numbers {
            for y in numbers {
                let m = frame("1700000000", "5", x, y);
                let fast = canonical_frame(m.as_bytes());
                assert!(fast.is_some(), "{m}");
                let mut want = by_serde(m.as_bytes()).unwrap();
                want.sort_by(|a, b| a.0.cmp(&b.0));
                assert_eq!(by_decode(m.as_bytes()).unwrap(), want, "{m}");
            }
        }
        // Not the layout: serde reads them (or words the error) as before.
        for m in [
            frame("-0", "0", "1.0", "2.0"),
            frame("1", "0", "1", "2.0"),
            frame("1", "0", "01.5", "2.0"),
            frame("1", "0", "1.", "2.0"),
            frame("1", "0", "1e400", "2.0"),
            frame("1", "0", "12345678901234567890.5", "2.0"),
            frame("1.5", "0", "1.0", "2.0"),
            frame("9223372036854775807", "0", "1.0", "2.0"),
            frame("1", "0", "1.0", "2.0").replace("slider", "sli\\u0064er"),
            frame("1", "0", "1.0", "2.0").replace(",\"y\"", ", \"y\""),
            frame("1", "0", "1.0", "2.0") + " ",
        ] {
            assert!(canonical_frame(m.as_bytes()).is_none(), "{m}");
            let want = by_serde(m.as_bytes()).map(|mut v| {
                v.sort_by(|a, b| a.0.cmp(&b.0));
                v
            });
            assert_eq!(by_decode(m.as_bytes()), want, "{m}");
        }
    }

    /// A recording of `frames` frames at 10 kHz, both markers moving, as MCAP bytes.
    fn multi_chunk_mcap(frames: usize) -> (Vec<u8>, Recording) {
        let mut rec = Recording::default();
        for k in 0..frames {
            let t = k as f64 * 1e-4;
            rec.times.push(t);
            rec.slider.push(Some([0.01 * (3.0 * t).sin(), 0.0]));
            rec.bob.push(Some([0.3 * t.cos(), -0.3 * t.sin()]));
        }
        let mut bytes = Vec::new();
        write_json(
            &mut bytes,
            &rec,
            1_700_000_000_000_000_000,
            &BTreeMap::new(),
        )
        .unwrap();
        (bytes, rec)
    }

    #[test]
    fn chunks_read_on_a_pool_thread_do_not_wait_for_the_pool() {
        // 60,000 frames: tens of chunks, more than are prepared ahead.
        let (bytes, rec) = multi_chunk_mcap(60_000);
        // Top-level records: opcode, length, body; chunks counted until the footer.
        let (mut at, mut chunks) = (::mcap::MAGIC.len(), 0);
        while bytes[at] != op::FOOTER {
            chunks += usize::from(bytes[at] == op::CHUNK);
            at += 9 + u64::from_le_bytes(bytes[at + 1..at + 9].try_into().unwrap()) as usize;
        }
        assert!(chunks > CHUNKS_AHEAD, "{chunks}");
        let read = |bytes: &[u8]| {
            read_from(bytes, Path::new("t.mcap"), &ReadOptions::default(), None).unwrap()
        };
        let outside = read(&bytes);
        // A pool of one thread, busy reading: its chunks cannot be handed to it.
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let inside = pool.install(|| read(&bytes));
        for parsed in [&outside, &inside] {
            assert_eq!(parsed.series.len(), 2);
            for s in &parsed.series {
                assert_eq!(s.times.len(), rec.times.len());
                let truth = if s.name == "slider" {
                    &rec.slider
                } else {
                    &rec.bob
                };
                assert_eq!(&s.points, truth, "{}", s.name);
            }
        }
    }

    #[test]
    fn canonical_names_are_checked_for_utf8_as_serde_checks_them() {
        // Non-ASCII names are read by the canonical layout, as serde reads them.
        let m = frame("3", "7", "0.5", "-0.25").replace("slider", "sl\u{e9}der");
        assert!(canonical_frame(m.as_bytes()).is_some(), "{m}");
        let mut want = by_serde(m.as_bytes()).unwrap();
        want.sort_by(|a, b| a.0.cmp(&b.0));
        assert_eq!(by_decode(m.as_bytes()).unwrap(), want);
        // Bytes that are not UTF-8, in a name or elsewhere: not the layout, and serde's error.
        let good = frame("3", "7", "0.5", "-0.25").into_bytes();
        for (at, byte) in [(good.len() / 2, 0xffu8), (1, 0xc3), (good.len() - 3, 0x80)] {
            let mut bad = good.clone();
            bad[at] = byte;
            assert!(canonical_frame(&bad).is_none());
            assert!(
                by_decode(&bad).is_err(),
                "{}",
                String::from_utf8_lossy(&bad)
            );
        }
        let mut bad = good.clone();
        let name = good.windows(6).position(|w| w == b"slider").unwrap();
        bad[name + 2] = 0xff;
        assert!(canonical_frame(&bad).is_none());
        assert_eq!(by_decode(&bad), by_serde(&bad));
    }

    #[test]
    fn canonical_floats_are_serdes_bit_for_bit() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        for k in 0..200_000 {
            let v = match k % 3 {
                0 => f64::from_bits(rng.random::<u64>()),
                1 => rng.random::<f64>() * 10f64.powi(rng.random_range(-12..12)),
                _ => (rng.random::<f64>() - 0.5) * 1e-3,
            };
            if !v.is_finite() {
                continue;
            }
            for text in [
                serde_json::to_string(&v).unwrap(),
                format!("{v:e}"),
                format!("{v:.17e}"),
                format!("{v:.9}"),
            ] {
                let m = frame("1", "0", &text, "0.5");
                let Some(f) = canonical_frame(m.as_bytes()) else {
                    continue;
                };
                let serde: JMsg = serde_json::from_slice(m.as_bytes()).unwrap();
                let want = serde.markers.unwrap()[0].x.unwrap();
                assert_eq!(f.markers[0].1.unwrap().to_bits(), want.to_bits(), "{text}");
            }
        }
    }

    #[test]
    fn message_headers_read_as_parse_record_reads_them() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        for _ in 0..100 {
            let mut body: Vec<u8> = (0..22).map(|_| rng.random()).collect();
            body.extend_from_slice(b"{\"x\":1}");
            let Record::Message { header, data } =
                ::mcap::parse_record(op::MESSAGE, &body).unwrap()
            else {
                panic!("a message");
            };
            let Record::Message { header: h, data: d } = message_record(&body) else {
                panic!("a message");
            };
            assert_eq!(
                (h.channel_id, h.sequence, h.log_time, h.publish_time),
                (
                    header.channel_id,
                    header.sequence,
                    header.log_time,
                    header.publish_time
                )
            );
            assert_eq!(d, data);
        }
    }

    /// A record of `opcode` with `body`, as MCAP frames it.
    fn framed(opcode: u8, body: &[u8]) -> Vec<u8> {
        let mut v = vec![opcode];
        v.extend_from_slice(&(body.len() as u64).to_le_bytes());
        v.extend_from_slice(body);
        v
    }

    /// An uncompressed chunk record holding `records` (CRC 0: none written).
    fn uncompressed_chunk(records: &[u8]) -> Vec<u8> {
        let mut body = Vec::new();
        body.extend_from_slice(&0u64.to_le_bytes()); // start time
        body.extend_from_slice(&0u64.to_le_bytes()); // end time
        body.extend_from_slice(&(records.len() as u64).to_le_bytes());
        body.extend_from_slice(&0u32.to_le_bytes()); // CRC
        body.extend_from_slice(&0u32.to_le_bytes()); // compression ""
        body.extend_from_slice(&(records.len() as u64).to_le_bytes());
        body.extend_from_slice(records);
        framed(op::CHUNK, &body)
    }

    #[test]
    fn chunk_walk_rejects_lengths_past_the_chunk_without_wrapping() {
        // A record claiming 100 bytes with 10 left after its opcode and length.
        let mut rest = framed(op::MESSAGE, &[0; 10]);
        rest[1..9].copy_from_slice(&100u64.to_le_bytes());
        assert!(matches!(
            next_in_chunk(&rest, rest.len() as u64, 1 << 20),
            NextRecord::Beyond(why) if why.contains("length 100 bytes, beyond the 10 byte(s)")
        ));
        // Fewer than 9 bytes left in the chunk: no room for an opcode and length.
        assert!(matches!(
            next_in_chunk(&rest, 5, 1 << 20),
            NextRecord::Beyond(why) if why.contains("beyond the 5 byte(s)")
        ));
        // The largest length: the limit catches it first, nothing overflows.
        rest[1..9].copy_from_slice(&u64::MAX.to_le_bytes());
        assert!(matches!(
            next_in_chunk(&rest, rest.len() as u64, 1 << 20),
            NextRecord::TooLarge(op::MESSAGE, u64::MAX)
        ));
        // Within the chunk but past the bytes at hand (a cut file): short, not beyond.
        rest[1..9].copy_from_slice(&10u64.to_le_bytes());
        assert!(matches!(
            next_in_chunk(&rest[..12], rest.len() as u64, 1 << 20),
            NextRecord::Short
        ));
        assert!(matches!(
            next_in_chunk(&rest, rest.len() as u64, 1 << 20),
            NextRecord::Record(op::MESSAGE, 10)
        ));
    }

    #[test]
    fn a_record_longer_than_its_uncompressed_chunk_is_a_clear_error() {
        // Magic, a record inside an uncompressed chunk claiming 1000 bytes where 20 are left,
        // then bytes after the chunk that a reader going past its end would take for records.
        let mut inner = framed(op::METADATA, &[0; 20]);
        inner[1..9].copy_from_slice(&1000u64.to_le_bytes());
        let mut file = ::mcap::MAGIC.to_vec();
        file.extend(uncompressed_chunk(&inner));
        file.extend([0xff; 64]);
        let e = read_from(
            &file[..],
            Path::new("hand.mcap"),
            &ReadOptions::default(),
            Some(file.len() as u64),
        )
        .unwrap_err();
        let text = e.to_string();
        assert!(text.contains("hand.mcap"), "{text}");
        assert!(
            text.contains("after 0 record(s), 66 byte(s)")
                && text.contains("record 1 (in the chunk at byte 8): length 1000 bytes, beyond the 20 byte(s) left in the chunk"),
            "{text}"
        );
    }
}
