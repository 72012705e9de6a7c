//! Message decoding: which decoder a channel gets ([`decoder_for`]), and one message to
//! marker samples ([`decode`]). JSON lives in `json`, protobuf in `protobuf`; ROS 2 CDR is
//! read by `data::ros_cdr`.

mod json;
mod protobuf;

pub(crate) use json::{PreFrame, PreParsed};

use super::tf::Acc;
use crate::data::{ros_cdr, DataError, Plane, Resource};
use json::{canonical_frame, FastMsg, JMsg, JStamp};
use prost_reflect::{DescriptorPool, MessageDescriptor};
use protobuf::{pb_count, pb_decode, pb_f64, pb_field, pb_stamp};
use std::fmt;

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

/// How a channel's messages are decoded. The protobuf ones carry the message descriptor built
/// from the channel's schema (the file's own definition, not one compiled in).
#[derive(Clone)]
pub(super) enum Decoder {
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
#[derive(Clone, Debug)]
pub(super) enum Reject {
    /// An encoding or type this reader does not decode.
    Unsupported(String),
    /// A supported type whose schema is unusable.
    Invalid(String),
}

/// Why a message gave no samples: it is not what its channel should carry (a message for the
/// caller to locate), or reading it would take the file over its budget.
pub(super) enum Failed {
    /// What was expected, or what is wrong.
    Message(String),
    /// The file is over its budget: refused whole.
    Budget(DataError),
}

impl From<String> for Failed {
    fn from(why: String) -> Self {
        Failed::Message(why)
    }
}

impl From<&str> for Failed {
    fn from(why: &str) -> Self {
        Failed::Message(why.to_string())
    }
}

impl From<DataError> for Failed {
    fn from(e: DataError) -> Self {
        Failed::Budget(e)
    }
}

/// A 3-D point (`p3`) on the plane of motion: see [`xy`].
fn p3(p: [f64; 3], plane: Option<Plane>) -> Option<[f64; 2]> {
    xy(Some(p[0]), Some(p[1]), Some(p[2]), plane)
}

/// A point from its coordinates: x and y, or x, y, z projected onto `plane` when all three
/// and a plane are given; missing without x or y.
fn xy(x: Option<f64>, y: Option<f64>, z: Option<f64>, plane: Option<Plane>) -> Option<[f64; 2]> {
    match (x, y, z, plane) {
        (Some(x), Some(y), Some(z), Some(p)) => Some(p.project([x, y, z])),
        (Some(x), Some(y), _, _) => Some([x, y]),
        _ => None,
    }
}

pub(super) fn decoder_for(
    encoding: &str,
    schema_name: &str,
    schema_encoding: &str,
    schema_data: &[u8],
) -> Result<Decoder, Reject> {
    match encoding {
        // Foxglove's JSON types that hold no position: a velocity in a Vector3 is not a marker.
        // An overlay's numbers (appell's own plot topics) are not markers either.
        "json"
            if NOT_POSITIONS.contains(&schema_name)
                || super::overlay::OVERLAY_JSON_SCHEMAS.contains(&schema_name) =>
        {
            Err(Reject::Invalid(format!(
                "{schema_name} holds no marker position"
            )))
        }
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
            // prost keeps a struct of a few hundred bytes for each (two-byte) entry of a
            // FileDescriptorSet: a large one would expand a hundredfold. Foxglove's are a few KB.
            if schema_data.len() > MAX_SCHEMA_BYTES {
                return Err(Reject::Invalid(format!(
                    "its schema {schema_name} is a FileDescriptorSet of {} bytes: at most {MAX_SCHEMA_BYTES}",
                    schema_data.len()
                )));
            }
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

/// The longest message a decoder takes (bytes). Decoding expands a message: prost-reflect
/// keeps every field of a protobuf message, unknown ones included, at about 16 times its wire
/// size (a 250 MB message of unknown fields in a 1 MB file ran past 4 GiB); serde buffers an
/// untagged JSON stamp as a tree. A marker frame is at most a few kilobytes, a frame of 10^5
/// JSON markers about 6 MB.
pub(super) const MAX_MESSAGE_BYTES: usize = 16 << 20;

/// The largest protobuf schema (a binary FileDescriptorSet) decoded, in bytes.
pub(super) const MAX_SCHEMA_BYTES: usize = 1 << 20;

/// Decode one message into samples; `Err` is a message for the caller to locate.
pub(super) fn decode(
    dec: &Decoder,
    topic: &str,
    data: &[u8],
    log_time: i64,
    plane: Option<Plane>,
    acc: &mut Acc,
    pre: Option<PreFrame<'_>>,
) -> Result<usize, Failed> {
    if data.len() > MAX_MESSAGE_BYTES {
        return Err(format!(
            "a marker message of at most {MAX_MESSAGE_BYTES} bytes (decoding expands it), found {}",
            data.len()
        )
        .into());
    }
    match dec {
        Decoder::Json => decode_json(topic, data, log_time, plane, acc, pre),
        Decoder::PointStamped | Decoder::PoseStamped => {
            let pose = matches!(dec, Decoder::PoseStamped);
            let (h, p) = ros_cdr::point_stamped(data, pose).map_err(|e| {
                format!(
                    "CDR {}: {e}",
                    if pose { "PoseStamped" } else { "PointStamped" }
                )
            })?;
            acc.budget.charge(Resource::Samples, 1)?;
            acc.push(topic, topic, h.stamp.ns(), p3(p, plane))?;
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
        Decoder::FrameTransform(desc) => frame_transform(desc, topic, data, log_time, plane, acc),
        Decoder::PointsAnnotation(desc) => points_annotation(desc, topic, data, log_time, acc),
    }
}

/// A JSON message: the canonical frame parsed ahead (`pre`), else parsed here, else any of the
/// layouts serde reads (a markers array, a point, or x and y; stamped, or at `log_time`).
fn decode_json(
    topic: &str,
    data: &[u8],
    log_time: i64,
    plane: Option<Plane>,
    acc: &mut Acc,
    pre: Option<PreFrame<'_>>,
) -> Result<usize, Failed> {
    // Each position kept is charged before the message's are pushed.
    let keep = |acc: &mut Acc, n: usize| acc.budget.charge(Resource::Samples, n as u64);
    if let Some(f) = pre {
        // Parsed ahead by canonical_frame from these same bytes.
        let stamp = JStamp::Parts {
            sec: f.sec,
            nsec: f.nsec,
        }
        .ns()?;
        keep(acc, f.markers.len())?;
        for (at, x, y) in f.markers {
            let id = data
                .get(at.clone())
                .and_then(|b| std::str::from_utf8(b).ok())
                .ok_or("a marker name parsed ahead is not in the message")?;
            acc.push(topic, id, stamp, xy(*x, *y, None, plane))?;
        }
        return Ok(f.markers.len());
    }
    if let Some(f) = canonical_frame(data) {
        let stamp = JStamp::Parts {
            sec: f.sec,
            nsec: f.nsec,
        }
        .ns()?;
        keep(acc, f.len)?;
        for &(id, x, y) in &f.markers[..f.len] {
            acc.push(topic, id, stamp, xy(x, y, None, plane))?;
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
            keep(acc, markers.len())?;
            for mk in &markers {
                acc.push(topic, &mk.id, stamp, xy(mk.x, mk.y, mk.z, plane))?;
            }
            return Ok(markers.len());
        }
        if let Some(p) = m.point.or(m.position) {
            keep(acc, 1)?;
            acc.push(topic, topic, stamp, xy(p.x, p.y, p.z, plane))?;
            return Ok(1);
        }
        if m.x.is_some() || m.y.is_some() {
            keep(acc, 1)?;
            acc.push(topic, topic, stamp, xy(m.x, m.y, m.z, plane))?;
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
        keep(acc, n)?;
        for mk in markers {
            acc.push(topic, &mk.id, stamp, xy(mk.x, mk.y, mk.z, plane))?;
        }
        Ok(n)
    } else if let Some(p) = m.point.or(m.position) {
        keep(acc, 1)?;
        acc.push(topic, topic, stamp, xy(p.x, p.y, p.z, plane))?;
        Ok(1)
    } else if m.x.is_some() || m.y.is_some() {
        keep(acc, 1)?;
        acc.push(topic, topic, stamp, xy(m.x, m.y, m.z, plane))?;
        Ok(1)
    } else {
        Err("a JSON object with a \"markers\" array, a \"point\", or x and y".into())
    }
}

/// A protobuf `foxglove.FrameTransform`: the marker `child_frame_id` at its translation
/// (missing when unset).
fn frame_transform(
    desc: &MessageDescriptor,
    topic: &str,
    data: &[u8],
    log_time: i64,
    plane: Option<Plane>,
    acc: &mut Acc,
) -> Result<usize, Failed> {
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
        p3([pb_f64(t, "x")?, pb_f64(t, "y")?, pb_f64(t, "z")?], plane)
    } else {
        None
    };
    acc.budget.charge(Resource::Samples, 1)?;
    acc.push(topic, name, stamp, p)?;
    Ok(1)
}

/// A protobuf `foxglove.PointsAnnotation`: its points by index, the first two the slider and
/// the bob ([`POINTS_NAMES`]).
fn points_annotation(
    desc: &MessageDescriptor,
    topic: &str,
    data: &[u8],
    log_time: i64,
    acc: &mut Acc,
) -> Result<usize, Failed> {
    // Every point is a position kept, and a marker of its own past the known ones: both are
    // counted in the encoded message and charged before it is decoded (decoding allocates for
    // each point).
    let n = pb_count(desc, "points", data);
    let keep = n.max(POINTS_NAMES.len());
    acc.budget.charge(Resource::Samples, keep as u64)?;
    let known = acc.widest.get(topic).copied().unwrap_or(0);
    acc.afford(Resource::Series, keep.saturating_sub(known) as u64)?;
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
        acc.push(topic, name, stamp, xys.get(k).copied())?;
    }
    for (k, p) in xys.iter().enumerate().skip(POINTS_NAMES.len()) {
        acc.push(topic, &format!("point{k}"), stamp, Some(*p))?;
    }
    if keep > known {
        acc.widest.insert(topic.to_string(), keep);
    }
    Ok(xys.len())
}
