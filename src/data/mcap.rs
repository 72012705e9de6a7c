//! MCAP recordings: a streaming linear reader (no summary or index needed, bounded memory)
//! decoding JSON, ROS 2 CDR and protobuf (Foxglove) marker messages, and a writer of JSON
//! marker frames.

use super::{ros_cdr, DataError, Parsed, Plane, ReadOptions, Recording, Series};
use ::mcap::records::{op, MessageHeader, Metadata, Record};
use ::mcap::sans_io::linear_reader::{LinearReadEvent, LinearReader, LinearReaderOptions};
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

/// One marker's samples with nanosecond stamps.
type Stamped = Vec<(i64, Option<[f64; 2]>)>;

/// One transform of a `/tf` tree: the child frame's pose in its parent frame.
struct Tf {
    ns: i64,
    parent: String,
    child: String,
    translation: [f64; 3],
    rotation: [f64; 4],
    /// From `/tf_static`: holds for the whole recording.
    fixed: bool,
}

/// Accumulates marker samples with nanosecond stamps, per channel (topic) and marker name,
/// and the transforms of `/tf` trees to compose at the end.
#[derive(Default)]
struct Acc {
    index: HashMap<(String, String), usize>,
    /// Topic, marker name, samples; in the order markers were first seen.
    series: Vec<(String, String, Stamped)>,
    tf: Vec<Tf>,
}

impl Acc {
    fn push(&mut self, topic: &str, name: &str, ns: i64, p: Option<[f64; 2]>) {
        let key = (topic.to_string(), name.to_string());
        let k = match self.index.get(&key) {
            Some(&k) => k,
            None => {
                self.index.insert(key, self.series.len());
                self.series
                    .push((topic.to_string(), name.to_string(), Vec::new()));
                self.series.len() - 1
            }
        };
        self.series[k].2.push((ns, p));
    }

    fn push_tf(&mut self, t: ros_cdr::TransformStamped, fixed: bool) {
        self.tf.push(Tf {
            ns: t.header.stamp.ns(),
            parent: t.header.frame_id,
            child: t.child_frame_id,
            translation: t.translation,
            rotation: t.rotation,
            fixed,
        });
    }

    fn is_empty(&self) -> bool {
        self.series.is_empty() && self.tf.is_empty()
    }
}

/// Rotate `v` by the quaternion `q` (x, y, z, w; normalised here).
fn rotate(q: [f64; 4], v: [f64; 3]) -> [f64; 3] {
    let n = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
    if !(n.is_finite() && n > 0.0) {
        return v;
    }
    let (x, y, z, w) = (q[0] / n, q[1] / n, q[2] / n, q[3] / n);
    // v' = v + 2 w (u x v) + 2 u x (u x v), u = (x, y, z)
    let c = [
        y * v[2] - z * v[1],
        z * v[0] - x * v[2],
        x * v[1] - y * v[0],
    ];
    let cc = [
        y * c[2] - z * c[1],
        z * c[0] - x * c[2],
        x * c[1] - y * c[0],
    ];
    [
        v[0] + 2.0 * (w * c[0] + cc[0]),
        v[1] + 2.0 * (w * c[1] + cc[1]),
        v[2] + 2.0 * (w * c[2] + cc[2]),
    ]
}

/// The most samples a `/tf` tree may expand into (frames times distinct stamps).
pub const TF_SAMPLE_LIMIT: usize = 20_000_000;

/// Compose `/tf` transforms to their tree's root: at every stamp of a dynamic transform, every
/// frame's origin in the root frame. Static transforms hold for the whole recording. The samples
/// go to `acc` under the topic `/tf`; returns notes on the roots used.
fn compose_tf(acc: &mut Acc, plane: Option<Plane>) -> Result<Vec<String>, String> {
    let tf = std::mem::take(&mut acc.tf);
    let mut current: BTreeMap<String, (String, [f64; 3], [f64; 4])> = BTreeMap::new();
    let mut dynamic: Vec<&Tf> = Vec::new();
    for t in &tf {
        if t.fixed {
            current.insert(
                t.child.clone(),
                (t.parent.clone(), t.translation, t.rotation),
            );
        } else {
            dynamic.push(t);
        }
    }
    dynamic.sort_by_key(|t| t.ns);
    let mut frames: BTreeMap<&str, ()> = BTreeMap::new();
    for t in &tf {
        frames.insert(&t.child, ());
    }
    let stamps = dynamic.chunk_by(|a, b| a.ns == b.ns).count();
    if stamps.saturating_mul(frames.len()) > TF_SAMPLE_LIMIT {
        return Err(format!(
            "a /tf tree of at most {TF_SAMPLE_LIMIT} frame samples, found {} frames at {stamps} stamps",
            frames.len()
        ));
    }
    // Each frame's root in the whole recording's tree: a frame is placed only once its chain
    // reaches that root, so its positions never switch frames when a parent arrives late.
    let mut parent_of: HashMap<&str, &str> = HashMap::new();
    for t in &tf {
        parent_of.insert(&t.child, &t.parent);
    }
    let depth_limit = frames.len() + 1;
    let root_of = |f: &str| -> Option<String> {
        let mut f = f;
        for _ in 0..=depth_limit {
            match parent_of.get(f) {
                Some(p) => f = p,
                None => return Some(f.to_string()),
            }
        }
        None
    };
    let final_root: HashMap<String, Option<String>> =
        frames.keys().map(|f| (f.to_string(), root_of(f))).collect();
    let mut roots: BTreeMap<String, usize> = BTreeMap::new();
    for group in dynamic.chunk_by(|a, b| a.ns == b.ns) {
        for t in group {
            current.insert(
                t.child.clone(),
                (t.parent.clone(), t.translation, t.rotation),
            );
        }
        let ns = group[0].ns;
        for child in current.keys() {
            let (mut frame, mut p) = (child.as_str(), [0.0; 3]);
            let mut depth = 0;
            while let Some((parent, tr, q)) = current.get(frame) {
                let r = rotate(*q, p);
                p = [r[0] + tr[0], r[1] + tr[1], r[2] + tr[2]];
                frame = parent;
                depth += 1;
                if depth > depth_limit {
                    return Err(format!("a /tf tree, found a cycle through frame {child:?}"));
                }
            }
            if final_root.get(child).and_then(|r| r.as_deref()) != Some(frame) {
                // The chain to the root is not complete yet at this stamp.
                continue;
            }
            if p.iter().all(|v| v.is_finite()) {
                *roots.entry(frame.to_string()).or_default() += 1;
                let xy = match plane {
                    Some(pl) => pl.project(p),
                    None => [p[0], p[1]],
                };
                acc.push("/tf", child, ns, Some(xy));
            } else {
                acc.push("/tf", child, ns, None);
            }
        }
    }
    let mut notes = Vec::new();
    if !tf.is_empty() {
        let statics = tf.iter().filter(|t| t.fixed).count();
        notes.push(format!(
            "/tf: {} transform(s) ({statics} static, held for the whole recording) composed to the root frame{} {} at {stamps} stamp(s)",
            tf.len(),
            if roots.len() == 1 { "" } else { "s" },
            roots.keys().map(|r| format!("{r:?}")).collect::<Vec<_>>().join(", ")
        ));
    }
    Ok(notes)
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
) -> Result<usize, String> {
    let p3 = |p: [f64; 3]| xy(Some(p[0]), Some(p[1]), Some(p[2]), plane);
    match dec {
        Decoder::Json => {
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
    let mut reader = LinearReader::new_with_options(
        LinearReaderOptions::default().with_record_length_limit(limit),
    );
    let mut schemas: HashMap<u16, (String, String, Vec<u8>)> = HashMap::new();
    let mut channels: BTreeMap<u16, Channel> = BTreeMap::new();
    let mut acc = Acc::default();
    let mut parsed = Parsed::default();
    let mut records = 0u64;
    let mut messages = 0u64;
    let mut bytes = 0u64;
    let mut record_bytes = 0u64;
    let mut damage: Option<String> = None;
    let mut unsupported_compression: Option<String> = None;
    // With a time window, reading stops once marker messages are past its end (by log_time,
    // with a second of margin for stamps that differ from it): the rest is never decoded.
    let window_end = opts.time_window.map(|(_, end)| end + 1.0);
    let mut first_log_time: Option<u64> = None;
    let mut stopped_at: Option<f64> = None;
    'records: while let Some(event) = reader.next_event() {
        let event = match event {
            Ok(e) => e,
            Err(e) => {
                if let McapError::UnsupportedCompression(c) = &e {
                    unsupported_compression = Some(c.clone());
                }
                damage = Some(match e {
                    McapError::RecordTooLarge { opcode, len } => format!(
                        "record (opcode {opcode:#04x}) of {len} bytes: more than the {limit}-byte limit for a file of this size"
                    ),
                    McapError::ChunkTooLarge(len) => format!(
                        "chunk of {len} bytes: more than the {limit}-byte limit for a file of this size"
                    ),
                    other => plain(&other),
                });
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
                record_bytes += data.len() as u64;
                if record_bytes > budget {
                    damage = Some(format!(
                        "records decompress to more than {budget} bytes (1024 times the file plus 64 MiB)"
                    ));
                    break;
                }
                // Only these records are used; the mcap crate sizes strings from their length
                // fields before checking them, so their lengths are checked here first.
                if ![op::SCHEMA, op::CHANNEL, op::MESSAGE, op::METADATA].contains(&opcode) {
                    continue;
                }
                if let Err(why) = check_lengths(opcode, data) {
                    damage = Some(format!("record {records} (opcode {opcode:#04x}): {why}"));
                    break;
                }
                let record = match ::mcap::parse_record(opcode, data) {
                    Ok(r) => r,
                    Err(e) => {
                        damage = Some(plain(&e));
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
                        let result = match i64::try_from(header.log_time) {
                            Ok(log_time) => {
                                decode(dec, &ch.topic, &data, log_time, opts.plane, &mut acc)
                            }
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
