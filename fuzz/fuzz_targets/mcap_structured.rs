//! Structure-aware MCAP fuzzing: the input describes a file (schemas, channels, messages,
//! metadata, chunking) which the `mcap` crate's writer turns into a well-formed MCAP; messages
//! are built structurally (JSON marker frames, ROS 2 CDR PointStamped / PoseStamped /
//! TFMessage, Foxglove protobuf FrameTransform / PointsAnnotation) or are raw bytes. The
//! result goes to the reader like a file: a recording or an error, never a panic.
#![no_main]

use appell::data::{read_recording_bytes, Format, ReadOptions};
use libfuzzer_sys::arbitrary::{self, Arbitrary};
use libfuzzer_sys::fuzz_target;
use std::collections::BTreeMap;
use std::io::Cursor;
use std::sync::OnceLock;

/// The most bytes of message payload one input may write (keeps a file under about 1 MB).
const MAX_PAYLOAD: usize = 900_000;

/// The protobuf FileDescriptorSets of the repo's Foxglove recordings (schema name -> data).
fn descriptors() -> &'static BTreeMap<String, Vec<u8>> {
    static D: OnceLock<BTreeMap<String, Vec<u8>>> = OnceLock::new();
    D.get_or_init(|| {
        let mut out = BTreeMap::new();
        for file in [
            &include_bytes!("../../tests/data/markers_foxglove_frametransform.mcap")[..],
            &include_bytes!("../../tests/data/markers_foxglove_points.mcap")[..],
        ] {
            for m in mcap::MessageStream::new(file)
                .expect("a seed mcap")
                .flatten()
            {
                if let Some(s) = &m.channel.schema {
                    out.insert(s.name.clone(), s.data.to_vec());
                }
            }
        }
        out
    })
}

#[derive(Arbitrary, Debug, Clone, Copy)]
enum SchemaKind {
    JsonMarkers,
    JsonNotPosition,
    PointStamped,
    PoseStamped,
    TransformStamped,
    TfMessage,
    FrameTransform,
    PointsAnnotation,
    /// A protobuf schema whose data is the other type's descriptor (or a truncated one).
    ProtobufMismatch,
    Unknown,
}

#[derive(Arbitrary, Debug)]
struct Schema {
    kind: SchemaKind,
    /// Cut the schema data to this many bytes (protobuf descriptors included).
    truncate: Option<u16>,
    /// Use an arbitrary schema encoding instead of the right one.
    encoding: Option<String>,
}

#[derive(Arbitrary, Debug)]
enum Topic {
    Markers,
    Tf,
    TfStatic,
    Named(u8),
    Any(String),
}

#[derive(Arbitrary, Debug)]
struct Channel {
    /// Index into the schemas (modulo their count); `None`: schemaless.
    schema: Option<u8>,
    topic: Topic,
    /// Use this message encoding instead of the schema's.
    encoding: Option<String>,
    metadata: Vec<(String, String)>,
}

#[derive(Arbitrary, Debug)]
enum Name {
    Slider,
    Bob,
    World,
    Map,
    BaseLink,
    Rail,
    Empty,
    Indexed(u8),
    Any(String),
}

impl Name {
    fn text(&self) -> String {
        match self {
            Name::Slider => "slider".into(),
            Name::Bob => "bob".into(),
            Name::World => "world".into(),
            Name::Map => "map".into(),
            Name::BaseLink => "base_link".into(),
            Name::Rail => "rail".into(),
            Name::Empty => String::new(),
            Name::Indexed(i) => format!("frame{i}"),
            Name::Any(s) => s.clone(),
        }
    }
}

#[derive(Arbitrary, Debug, Clone, Copy)]
enum Num {
    Small(i8),
    Float(f64),
    Nan,
    Inf,
    NegInf,
    Huge,
    Zero,
}

impl Num {
    fn get(self) -> f64 {
        match self {
            Num::Small(i) => i as f64 / 10.0,
            Num::Float(f) => f,
            Num::Nan => f64::NAN,
            Num::Inf => f64::INFINITY,
            Num::NegInf => f64::NEG_INFINITY,
            Num::Huge => 1e308,
            Num::Zero => 0.0,
        }
    }
    /// As JSON text (non-finite values as JSON cannot hold them: tokens the parser refuses).
    fn json(self) -> String {
        let f = self.get();
        if f.is_finite() {
            format!("{f:?}")
        } else if f.is_nan() {
            "NaN".into()
        } else {
            "1e999".into()
        }
    }
}

#[derive(Arbitrary, Debug)]
struct Stamp {
    sec: i64,
    nsec: i64,
    /// Write the stamp as float seconds instead of `{sec, nsec}`.
    float: Option<Num>,
}

#[derive(Arbitrary, Debug)]
enum JsonValue {
    Num(Num),
    Null,
    Str(String),
    Missing,
}

#[derive(Arbitrary, Debug)]
struct JsonMarker {
    name: Name,
    key: u8,
    x: JsonValue,
    y: JsonValue,
    z: JsonValue,
}

#[derive(Arbitrary, Debug)]
enum Json {
    /// The canonical frame (timestamp, frame_id, markers) or a variant of it.
    Frame {
        stamp: Option<Stamp>,
        header_stamp: bool,
        markers: Vec<JsonMarker>,
        /// Repeat the marker list this many times (many markers per frame).
        repeat: u8,
        spaces: bool,
    },
    /// One point per topic: `{"x":..,"y":..}` or nested in `point` / `position`.
    Point {
        stamp: Option<Stamp>,
        nest: u8,
        x: JsonValue,
        y: JsonValue,
        z: JsonValue,
    },
    Text(String),
}

#[derive(Arbitrary, Debug)]
struct Transform {
    stamp_sec: i32,
    stamp_nsec: u32,
    parent: Name,
    child: Name,
    t: [Num; 3],
    q: [Num; 4],
}

#[derive(Arbitrary, Debug)]
struct Cdr {
    little: bool,
    kind: u8,
    /// Replace the n-th length field written (strings, sequences) with this value.
    bad_length: Option<(u8, u32)>,
    /// Cut the message to this many bytes.
    truncate: Option<u16>,
}

#[derive(Arbitrary, Debug)]
enum Payload {
    Json(Json),
    PointStamped {
        cdr: Cdr,
        sec: i32,
        nsec: u32,
        frame: Name,
        p: [Num; 3],
        q: [Num; 4],
    },
    Tf {
        cdr: Cdr,
        transforms: Vec<Transform>,
        /// A chain: each transform's parent is the previous one's child.
        chain: bool,
    },
    FrameTransform {
        t: Option<(i64, i32)>,
        tf: Transform,
        junk: Vec<u8>,
    },
    PointsAnnotation {
        t: Option<(i64, i32)>,
        kind: u8,
        points: Vec<(Num, Num)>,
        repeat: u8,
        junk: Vec<u8>,
    },
    Raw(Vec<u8>),
}

#[derive(Arbitrary, Debug)]
struct Msg {
    channel: u8,
    log_time: u64,
    publish_time: u64,
    sequence: u32,
    /// Repeat this message this many times with increasing log times.
    repeat: u8,
    payload: Payload,
}

#[derive(Arbitrary, Debug)]
enum Compression {
    None,
    Zstd,
    Lz4,
}

#[derive(Arbitrary, Debug)]
struct File {
    schemas: Vec<Schema>,
    channels: Vec<Channel>,
    metadata: Vec<(String, Vec<(String, String)>)>,
    messages: Vec<Msg>,
    compression: Compression,
    chunk_size: Option<u32>,
    use_chunks: bool,
    summary: bool,
    /// Metadata written between messages rather than first.
    metadata_late: bool,
}

fn json_value(key: &str, v: &JsonValue, out: &mut Vec<String>) {
    match v {
        JsonValue::Num(n) => out.push(format!("\"{key}\":{}", n.json())),
        JsonValue::Null => out.push(format!("\"{key}\":null")),
        JsonValue::Str(s) => out.push(format!("\"{key}\":{s:?}")),
        JsonValue::Missing => {}
    }
}

fn json_stamp(s: &Stamp) -> String {
    match s.float {
        Some(f) => f.json(),
        None => format!("{{\"sec\":{},\"nsec\":{}}}", s.sec, s.nsec),
    }
}

fn json(j: &Json) -> Vec<u8> {
    match j {
        Json::Frame {
            stamp,
            header_stamp,
            markers,
            repeat,
            spaces,
        } => {
            let mut parts = Vec::new();
            if let Some(s) = stamp {
                if *header_stamp {
                    parts.push(format!("\"header\":{{\"stamp\":{}}}", json_stamp(s)));
                } else {
                    parts.push(format!("\"timestamp\":{}", json_stamp(s)));
                }
            }
            parts.push("\"frame_id\":\"rail\"".into());
            let mut ms = Vec::new();
            for _ in 0..=(*repeat as usize % 64) {
                for m in markers {
                    let key = ["id", "name", "label", "nom"][m.key as usize % 4];
                    let mut fields = vec![format!("\"{key}\":{:?}", m.name.text())];
                    json_value("x", &m.x, &mut fields);
                    json_value("y", &m.y, &mut fields);
                    json_value("z", &m.z, &mut fields);
                    ms.push(format!("{{{}}}", fields.join(",")));
                }
            }
            parts.push(format!("\"markers\":[{}]", ms.join(",")));
            let sep = if *spaces { ", " } else { "," };
            format!("{{{}}}", parts.join(sep)).into_bytes()
        }
        Json::Point {
            stamp,
            nest,
            x,
            y,
            z,
        } => {
            let mut p = Vec::new();
            json_value("x", x, &mut p);
            json_value("y", y, &mut p);
            json_value("z", z, &mut p);
            let p = p.join(",");
            let mut parts = Vec::new();
            if let Some(s) = stamp {
                parts.push(format!("\"timestamp\":{}", json_stamp(s)));
            }
            match nest % 3 {
                0 => parts.push(p),
                1 => parts.push(format!("\"point\":{{{p}}}")),
                _ => parts.push(format!("\"position\":{{{p}}}")),
            }
            format!("{{{}}}", parts.join(",")).into_bytes()
        }
        Json::Text(t) => t.clone().into_bytes(),
    }
}

/// A CDR (XCDR1) writer: alignment from the end of the encapsulation header.
struct CdrOut<'a> {
    buf: Vec<u8>,
    little: bool,
    lengths: u8,
    cfg: &'a Cdr,
}

impl<'a> CdrOut<'a> {
    fn new(cfg: &'a Cdr) -> Self {
        let kind = if cfg.kind % 8 == 0 {
            cfg.little as u8
        } else {
            cfg.kind
        };
        CdrOut {
            buf: vec![0, kind, 0, 0],
            little: cfg.little,
            lengths: 0,
            cfg,
        }
    }
    fn align(&mut self, n: usize) {
        while (self.buf.len() - 4) % n != 0 {
            self.buf.push(0);
        }
    }
    fn u32(&mut self, v: u32) {
        self.align(4);
        let b = if self.little {
            v.to_le_bytes()
        } else {
            v.to_be_bytes()
        };
        self.buf.extend_from_slice(&b);
    }
    fn length(&mut self, v: u32) {
        let v = match self.cfg.bad_length {
            Some((i, bad)) if i == self.lengths => bad,
            _ => v,
        };
        self.lengths = self.lengths.wrapping_add(1);
        self.u32(v);
    }
    fn f64(&mut self, v: f64) {
        self.align(8);
        let b = if self.little {
            v.to_le_bytes()
        } else {
            v.to_be_bytes()
        };
        self.buf.extend_from_slice(&b);
    }
    fn string(&mut self, s: &str) {
        self.length(s.len() as u32 + 1);
        self.buf.extend_from_slice(s.as_bytes());
        self.buf.push(0);
    }
    fn header(&mut self, sec: i32, nsec: u32, frame: &str) {
        self.u32(sec as u32);
        self.u32(nsec);
        self.string(frame);
    }
    fn finish(mut self) -> Vec<u8> {
        if let Some(n) = self.cfg.truncate {
            self.buf.truncate(n as usize);
        }
        self.buf
    }
}

/// Protobuf wire encoding.
fn varint(out: &mut Vec<u8>, mut v: u64) {
    loop {
        let b = (v & 0x7f) as u8;
        v >>= 7;
        if v == 0 {
            out.push(b);
            return;
        }
        out.push(b | 0x80);
    }
}

fn pb_len(out: &mut Vec<u8>, field: u32, data: &[u8]) {
    varint(out, (field as u64) << 3 | 2);
    varint(out, data.len() as u64);
    out.extend_from_slice(data);
}

fn pb_f64(out: &mut Vec<u8>, field: u32, v: f64) {
    varint(out, (field as u64) << 3 | 1);
    out.extend_from_slice(&v.to_le_bytes());
}

fn pb_int(out: &mut Vec<u8>, field: u32, v: i64) {
    varint(out, (field as u64) << 3);
    varint(out, v as u64);
}

fn pb_stamp(out: &mut Vec<u8>, t: Option<(i64, i32)>) {
    if let Some((s, n)) = t {
        let mut ts = Vec::new();
        pb_int(&mut ts, 1, s);
        pb_int(&mut ts, 2, n as i64);
        pb_len(out, 1, &ts);
    }
}

fn payload(p: &Payload) -> Vec<u8> {
    match p {
        Payload::Json(j) => json(j),
        Payload::PointStamped {
            cdr,
            sec,
            nsec,
            frame,
            p,
            q,
        } => {
            let mut w = CdrOut::new(cdr);
            w.header(*sec, *nsec, &frame.text());
            for v in p {
                w.f64(v.get());
            }
            // A PoseStamped's orientation (ignored by PointStamped's reader, trailing bytes).
            for v in q {
                w.f64(v.get());
            }
            w.finish()
        }
        Payload::Tf {
            cdr,
            transforms,
            chain,
        } => {
            let mut w = CdrOut::new(cdr);
            w.length(transforms.len() as u32);
            let mut parent = String::from("world");
            for t in transforms.iter().take(2000) {
                let p = if *chain {
                    parent.clone()
                } else {
                    t.parent.text()
                };
                let c = t.child.text();
                w.header(t.stamp_sec, t.stamp_nsec, &p);
                w.string(&c);
                for v in t.t {
                    w.f64(v.get());
                }
                for v in t.q {
                    w.f64(v.get());
                }
                parent = c;
            }
            w.finish()
        }
        Payload::FrameTransform { t, tf, junk } => {
            let mut out = Vec::new();
            pb_stamp(&mut out, *t);
            pb_len(&mut out, 2, tf.parent.text().as_bytes());
            pb_len(&mut out, 3, tf.child.text().as_bytes());
            let mut v = Vec::new();
            for (i, n) in tf.t.iter().enumerate() {
                pb_f64(&mut v, i as u32 + 1, n.get());
            }
            pb_len(&mut out, 4, &v);
            let mut q = Vec::new();
            for (i, n) in tf.q.iter().enumerate() {
                pb_f64(&mut q, i as u32 + 1, n.get());
            }
            pb_len(&mut out, 5, &q);
            out.extend_from_slice(junk);
            out
        }
        Payload::PointsAnnotation {
            t,
            kind,
            points,
            repeat,
            junk,
        } => {
            let mut out = Vec::new();
            pb_stamp(&mut out, *t);
            pb_int(&mut out, 2, *kind as i64);
            for _ in 0..=(*repeat as usize % 32) {
                for (x, y) in points {
                    let mut p = Vec::new();
                    pb_f64(&mut p, 1, x.get());
                    pb_f64(&mut p, 2, y.get());
                    pb_len(&mut out, 3, &p);
                }
            }
            out.extend_from_slice(junk);
            out
        }
        Payload::Raw(b) => b.clone(),
    }
}

/// Schema name, encoding, data and the channel's message encoding.
fn schema(s: &Schema) -> (String, String, Vec<u8>, &'static str) {
    let d = descriptors();
    let pb = |name: &str| d.get(name).cloned().unwrap_or_default();
    let (name, enc, mut data, msg) = match s.kind {
        SchemaKind::JsonMarkers => (
            "lab.MarkerFrame2D",
            "jsonschema",
            br#"{"type":"object"}"#.to_vec(),
            "json",
        ),
        SchemaKind::JsonNotPosition => ("foxglove.Vector3", "jsonschema", vec![], "json"),
        SchemaKind::PointStamped => (
            "geometry_msgs/msg/PointStamped",
            "ros2msg",
            b"std_msgs/Header header\ngeometry_msgs/Point point".to_vec(),
            "cdr",
        ),
        SchemaKind::PoseStamped => ("geometry_msgs/msg/PoseStamped", "ros2msg", vec![], "cdr"),
        SchemaKind::TransformStamped => (
            "geometry_msgs/msg/TransformStamped",
            "ros2idl",
            vec![],
            "cdr",
        ),
        SchemaKind::TfMessage => ("tf2_msgs/msg/TFMessage", "ros2msg", vec![], "cdr"),
        SchemaKind::FrameTransform => (
            "foxglove.FrameTransform",
            "protobuf",
            pb("foxglove.FrameTransform"),
            "protobuf",
        ),
        SchemaKind::PointsAnnotation => (
            "foxglove.PointsAnnotation",
            "protobuf",
            pb("foxglove.PointsAnnotation"),
            "protobuf",
        ),
        SchemaKind::ProtobufMismatch => (
            "foxglove.FrameTransform",
            "protobuf",
            pb("foxglove.PointsAnnotation"),
            "protobuf",
        ),
        SchemaKind::Unknown => ("some/Thing", "omgidl", b"struct X {};".to_vec(), "cdr"),
    };
    if let Some(n) = s.truncate {
        data.truncate(n as usize);
    }
    let enc = s.encoding.clone().unwrap_or_else(|| enc.to_string());
    (name.to_string(), enc, data, msg)
}

fn build(f: &File) -> Option<Vec<u8>> {
    let compression = match f.compression {
        Compression::None => None,
        Compression::Zstd => Some(mcap::Compression::Zstd),
        Compression::Lz4 => Some(mcap::Compression::Lz4),
    };
    let opts = mcap::WriteOptions::new()
        .compression(compression)
        .chunk_size(f.chunk_size.map(|c| c as u64 % 2_000_000))
        .use_chunks(f.use_chunks)
        .emit_summary_records(f.summary)
        .emit_statistics(f.summary)
        .emit_message_indexes(f.summary)
        .emit_chunk_indexes(f.summary);
    let mut w = opts.create(Cursor::new(Vec::new())).ok()?;
    let mut schema_ids = Vec::new();
    let mut schema_msg = Vec::new();
    for s in f.schemas.iter().take(8) {
        let (name, enc, data, msg) = schema(s);
        schema_ids.push(w.add_schema(&name, &enc, &data).ok()?);
        schema_msg.push(msg);
    }
    let mut channels = Vec::new();
    for c in f.channels.iter().take(16) {
        let (sid, enc) = match c.schema {
            Some(i) if !schema_ids.is_empty() => {
                let i = i as usize % schema_ids.len();
                (schema_ids[i], schema_msg[i])
            }
            _ => (0, "json"),
        };
        let enc = c.encoding.clone().unwrap_or_else(|| enc.to_string());
        let topic = match &c.topic {
            Topic::Markers => "/markers".to_string(),
            Topic::Tf => "/tf".to_string(),
            Topic::TfStatic => "/tf_static".to_string(),
            Topic::Named(i) => format!("/marker{i}"),
            Topic::Any(s) => s.clone(),
        };
        let meta: BTreeMap<String, String> = c.metadata.iter().take(64).cloned().collect();
        channels.push(w.add_channel(sid, &topic, &enc, &meta).ok()?);
    }
    let write_meta = |w: &mut mcap::Writer<Cursor<Vec<u8>>>| -> Option<()> {
        for (name, entries) in f.metadata.iter().take(16) {
            w.write_metadata(&mcap::records::Metadata {
                name: name.clone(),
                metadata: entries.iter().take(256).cloned().collect(),
            })
            .ok()?;
        }
        Some(())
    };
    if !f.metadata_late {
        write_meta(&mut w)?;
    }
    let mut total = 0usize;
    for (k, m) in f.messages.iter().take(4000).enumerate() {
        if channels.is_empty() {
            break;
        }
        let data = payload(&m.payload);
        for r in 0..=(m.repeat as u64 % 100) {
            total += data.len() + 32;
            if total > MAX_PAYLOAD {
                break;
            }
            let header = mcap::records::MessageHeader {
                channel_id: channels[m.channel as usize % channels.len()],
                sequence: m.sequence,
                log_time: m.log_time.wrapping_add(r * 33_333_333),
                publish_time: m.publish_time,
            };
            w.write_to_known_channel(&header, &data).ok()?;
        }
        if f.metadata_late && k == f.messages.len() / 2 {
            write_meta(&mut w)?;
        }
    }
    w.finish().ok()?;
    Some(w.into_inner().into_inner())
}

fuzz_target!(|f: File| {
    let Some(bytes) = build(&f) else { return };
    let opts = ReadOptions {
        format: Some(Format::Mcap),
        fps: Some(30.0),
        scale: Some(1.0),
        ..ReadOptions::default()
    };
    // FUZZ_WRITE=PATH: keep the built file (to reproduce an input with the CLI), and print
    // what reading it gave.
    let write = std::env::var_os("FUZZ_WRITE");
    if let Some(path) = &write {
        std::fs::write(path, &bytes).expect("write FUZZ_WRITE");
    }
    let read = read_recording_bytes(&bytes, std::path::Path::new("fuzz-input"), &opts);
    if write.is_some() {
        match read {
            Ok(r) => eprintln!("read: {} frames", r.len()),
            Err(e) => eprintln!("error: {e}"),
        }
    }
});
