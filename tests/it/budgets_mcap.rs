//! Issue 25, MCAP: small files built to make the reader spend without bound (the same schema
//! decoded per channel, a series per point, kept samples, metadata entries, deep `/tf` chains).
//! Each is refused by the file's budget (exit 2, the file and the limit named, no output, the
//! input untouched) or read fast, under a 4 GiB address space and within 20 s.
//!
//! `APPELL_BUDGET_BIN=path` runs another build on the same files (to show how a build without
//! the budget fares); the assertions then say what it did.

use appell::data::{Budget, Resource};
use mcap::records::MessageHeader;
use prost_reflect::prost::Message as _;
use prost_reflect::prost_types::{
    field_descriptor_proto::{Label, Type},
    DescriptorProto, FieldDescriptorProto, FileDescriptorProto, FileDescriptorSet,
};
use std::collections::BTreeMap;
use std::io::{Cursor, Read};
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// The most a reproducer may take.
const DEADLINE: Duration = Duration::from_secs(20);

/// How one run of the binary ended.
#[derive(Debug)]
struct Run {
    code: Option<i32>,
    secs: f64,
    /// Killed at 1.5 times the deadline.
    killed: bool,
    stderr: String,
}

/// Run the binary under a 4 GiB address-space cap.
fn run_capped(args: &[&std::ffi::OsStr]) -> Run {
    let bin = std::env::var_os("APPELL_BUDGET_BIN")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_BIN_EXE_appell")));
    let mut cmd = Command::new(bin);
    cmd.args(args).stdout(Stdio::null()).stderr(Stdio::piped());
    // SAFETY: only setrlimit, which is async-signal-safe, runs between fork and exec.
    unsafe {
        cmd.pre_exec(|| {
            let cap = libc::rlimit {
                rlim_cur: 4 << 30,
                rlim_max: 4 << 30,
            };
            if libc::setrlimit(libc::RLIMIT_AS, &cap) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            Ok(())
        });
    }
    let start = Instant::now();
    let mut child = cmd.spawn().expect("run appell");
    let mut pipe = child.stderr.take().expect("stderr");
    let reader = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = pipe.read_to_string(&mut s);
        s
    });
    let mut killed = false;
    let status = loop {
        if let Some(s) = child.try_wait().expect("wait") {
            break s;
        }
        if start.elapsed() > DEADLINE * 3 / 2 {
            let _ = child.kill();
            killed = true;
            break child.wait().expect("wait");
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let secs = start.elapsed().as_secs_f64();
    Run {
        code: status.code(),
        secs,
        killed,
        stderr: reader.join().expect("stderr"),
    }
}

/// Convert `input` under the cap; the input is checked unchanged afterwards.
fn convert(dir: &Path, input: &Path) -> (Run, PathBuf) {
    let before = std::fs::read(input).unwrap();
    let out = dir.join("out.csv");
    let run = run_capped(&["convert".as_ref(), input.as_os_str(), out.as_os_str()]);
    eprintln!("{}: {run:?}", input.display());
    assert!(std::fs::read(input).unwrap() == before, "the input changed");
    (run, out)
}

/// `input` is refused fast for going over its limit of `r`, with nothing written.
fn assert_refused(dir: &Path, input: &Path, r: Resource) {
    let (run, out) = convert(dir, input);
    assert!(run.secs < DEADLINE.as_secs_f64() && !run.killed, "{run:?}");
    assert_eq!(run.code, Some(2), "{run:?}");
    let size = std::fs::metadata(input).unwrap().len();
    let limit = Budget::new(input, size).limit(r);
    let named = format!("more than {limit} {}", r.name());
    assert!(
        run.stderr.contains(&input.display().to_string())
            && run.stderr.contains("over the input budget")
            && run.stderr.contains(&named),
        "expected {named:?}: {run:?}"
    );
    assert!(!out.exists(), "output left behind");
}

/// Bytes that do not compress (so a file is as large as a budget needs), from a seed.
fn noise(n: usize, seed: u64) -> Vec<u8> {
    let mut x = seed | 1;
    (0..n)
        .map(|_| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x as u8
        })
        .collect()
}

/// The FileDescriptorSet of the protobuf type `name` (`foxglove.X`), as the example file
/// `tests/data/{file}` carries it.
fn example_schema(file: &str, name: &str) -> Vec<u8> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(file);
    let bytes = std::fs::read(path).unwrap();
    let m = mcap::MessageStream::new(&bytes)
        .unwrap()
        .next()
        .unwrap()
        .unwrap();
    let schema = m.channel.schema.as_ref().expect("a schema");
    assert_eq!(schema.name, name);
    schema.data.to_vec()
}

/// The FileDescriptorSet of `foxglove.PointsAnnotation`, as the example file carries it.
fn points_schema() -> Vec<u8> {
    example_schema("markers_foxglove_points.mcap", "foxglove.PointsAnnotation")
}

/// `dir/file`: an MCAP of `padding` incompressible bytes and one protobuf `message` of type
/// `name` (its FileDescriptorSet `schema`) on `topic`, in one zstd chunk.
fn one_protobuf_message(
    dir: &Path,
    file: &str,
    (name, schema): (&str, &[u8]),
    topic: &str,
    message: &[u8],
    padding: usize,
) -> PathBuf {
    let mut buf = Cursor::new(Vec::new());
    {
        let mut w = writer(&mut buf, 1 << 30);
        pad(&mut w, padding);
        let s = w.add_schema(name, "protobuf", schema).unwrap();
        let c = w
            .add_channel(s, topic, "protobuf", &BTreeMap::new())
            .unwrap();
        w.write_to_known_channel(&header(c, 0), message).unwrap();
        w.finish().unwrap();
    }
    let input = dir.join(file);
    std::fs::write(&input, buf.into_inner()).unwrap();
    input
}

/// A writer of zstd chunks of about `chunk` bytes into memory.
fn writer(buf: &mut Cursor<Vec<u8>>, chunk: u64) -> mcap::Writer<&mut Cursor<Vec<u8>>> {
    mcap::WriteOptions::new()
        .compression(Some(mcap::Compression::Zstd))
        .chunk_size(Some(chunk))
        .create(buf)
        .unwrap()
}

/// A writer of zstd chunks of 64 MiB without message indexes (16 bytes a message, outside the
/// chunks): many messages in a small file.
fn dense_writer(buf: &mut Cursor<Vec<u8>>) -> mcap::Writer<&mut Cursor<Vec<u8>>> {
    mcap::WriteOptions::new()
        .compression(Some(mcap::Compression::Zstd))
        .chunk_size(Some(64 << 20))
        .emit_message_indexes(false)
        .create(buf)
        .unwrap()
}

fn header(channel_id: u16, k: u64) -> MessageHeader {
    MessageHeader {
        channel_id,
        sequence: k as u32,
        log_time: 1_700_000_000_000_000_000 + k * 1_000_000,
        publish_time: 1_700_000_000_000_000_000 + k * 1_000_000,
    }
}

/// Pad a file with an attachment of `n` incompressible bytes: the budget grows with the
/// file's size, and these reproducers spend what a file of this size may not.
fn pad(w: &mut mcap::Writer<&mut Cursor<Vec<u8>>>, n: usize) {
    w.attach(&mcap::Attachment {
        log_time: 0,
        create_time: 0,
        name: "padding".into(),
        media_type: "application/octet-stream".into(),
        data: noise(n, 7).into(),
    })
    .unwrap();
}

#[test]
fn mcap_channels_sharing_one_large_protobuf_schema_decode_it_once_and_are_counted() {
    // The Foxglove schema plus 30,000 message types: about 1 MB, on 2,000 channels.
    let mut set = FileDescriptorSet::decode(&points_schema()[..]).unwrap();
    let field = |name: &str, number| FieldDescriptorProto {
        name: Some(name.into()),
        number: Some(number),
        label: Some(Label::Optional as i32),
        r#type: Some(Type::Double as i32),
        ..Default::default()
    };
    set.file.push(FileDescriptorProto {
        name: Some("bulk.proto".into()),
        package: Some("bulk".into()),
        message_type: (0..30_000)
            .map(|i| DescriptorProto {
                name: Some(format!("M{i}")),
                field: vec![field("a", 1), field("b", 2)],
                ..Default::default()
            })
            .collect(),
        syntax: Some("proto3".into()),
        ..Default::default()
    });
    let schema = set.encode_to_vec();
    assert!(schema.len() > 500_000, "{}", schema.len());
    let mut buf = Cursor::new(Vec::new());
    {
        let mut w = writer(&mut buf, 1 << 20);
        let s = w
            .add_schema("foxglove.PointsAnnotation", "protobuf", &schema)
            .unwrap();
        for k in 0..2000 {
            let c = w
                .add_channel(s, &format!("/points{k}"), "protobuf", &BTreeMap::new())
                .unwrap();
            w.write_to_known_channel(&header(c, k), &[]).unwrap();
        }
        w.finish().unwrap();
    }
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("channels.mcap");
    std::fs::write(&input, buf.into_inner()).unwrap();
    assert_refused(dir.path(), &input, Resource::Channels);
}

#[test]
fn mcap_a_points_annotation_of_eight_million_empty_points_is_refused_before_decoding() {
    let schema = points_schema();
    let pool = prost_reflect::DescriptorPool::decode(&schema[..]).unwrap();
    let points = pool
        .get_message_by_name("foxglove.PointsAnnotation")
        .unwrap()
        .get_field_by_name("points")
        .unwrap()
        .number();
    // Each point: the field's key and a length of 0 (a Point2 at its defaults).
    let key = u8::try_from(points << 3 | 2).unwrap();
    // 16 MB: under the longest message decoded (16 MiB), over the positions a file of this
    // size may keep.
    let message: Vec<u8> = [key, 0].repeat(8_000_000);
    let dir = tempfile::tempdir().unwrap();
    // A 16 MB record needs a file of 64 kB (records are at most 256 times the file).
    let input = one_protobuf_message(
        dir.path(),
        "points.mcap",
        ("foxglove.PointsAnnotation", &schema),
        "/points",
        &message,
        300_000,
    );
    assert!(std::fs::metadata(&input).unwrap().len() < 1 << 20);
    assert_refused(dir.path(), &input, Resource::Samples);
}

#[test]
fn mcap_a_protobuf_message_of_250_mb_of_unknown_fields_is_refused_before_decoding() {
    // prost-reflect keeps every unknown field: this 1 MB file (a 250 MB FrameTransform of
    // field 99 set to 0, zstd-compressed) aborted at the 4 GiB cap after 7 s.
    let name = "foxglove.FrameTransform";
    let schema = example_schema("markers_foxglove_frametransform.mcap", name);
    let message: Vec<u8> = [0x98, 0x06, 0x00].repeat(250_000_000 / 3);
    let dir = tempfile::tempdir().unwrap();
    let input = one_protobuf_message(
        dir.path(),
        "unknown_fields.mcap",
        (name, &schema),
        "/markers",
        &message,
        1_000_000,
    );
    assert!(std::fs::metadata(&input).unwrap().len() < 1_100_000);
    let (run, out) = convert(dir.path(), &input);
    assert!(run.secs < DEADLINE.as_secs_f64() && !run.killed, "{run:?}");
    assert_eq!(run.code, Some(2), "{run:?}");
    assert!(
        run.stderr.contains("unknown_fields.mcap")
            && run
                .stderr
                .contains("a marker message of at most 16777216 bytes"),
        "{run:?}"
    );
    assert!(!out.exists(), "output left behind");
}

/// The padding of the JSON reproducer: its file is about 1 MB.
const PAD: usize = 400_000;

#[test]
fn mcap_a_gibibyte_of_tiny_json_markers_is_bounded_by_the_samples_kept() {
    // 2,000 markers without positions per message (14 bytes each), 36,000 messages: 1 GB of
    // JSON and 72 million samples, in a file of about 1 MB (padded, so that the bytes decoded
    // fit the file's budget and the samples do not).
    let mut msg = String::from("{\"markers\":[");
    for k in 0..2000 {
        if k > 0 {
            msg.push(',');
        }
        msg.push_str(&format!("{{\"id\":\"m{k}\"}}"));
    }
    msg.push_str("]}");
    let messages = 36_000u64;
    let mut buf = Cursor::new(Vec::new());
    {
        let mut w = dense_writer(&mut buf);
        pad(&mut w, PAD);
        let s = w.add_schema("lab.Markers", "jsonschema", b"{}").unwrap();
        let c = w
            .add_channel(s, "/markers", "json", &BTreeMap::new())
            .unwrap();
        for k in 0..messages {
            w.write_to_known_channel(&header(c, k), msg.as_bytes())
                .unwrap();
        }
        w.finish().unwrap();
    }
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("markers.mcap");
    std::fs::write(&input, buf.into_inner()).unwrap();
    let size = std::fs::metadata(&input).unwrap().len();
    let budget = Budget::new(&input, size);
    let decoded = messages * (msg.len() as u64 + 31);
    assert!(
        decoded > 1_000_000_000 && budget.limit(Resource::DecodedBytes) > decoded,
        "the decoded bytes fit the budget: {size} bytes"
    );
    assert!(
        budget.limit(Resource::Samples) < messages * 2000 / 2,
        "{size} bytes"
    );
    assert_refused(dir.path(), &input, Resource::Samples);
}

/// An MCAP record: opcode, length, body.
fn record(opcode: u8, body: &[u8]) -> Vec<u8> {
    let mut v = vec![opcode];
    v.extend_from_slice(&(body.len() as u64).to_le_bytes());
    v.extend_from_slice(body);
    v
}

/// A string or byte array as MCAP frames it: a u32 length, then the bytes.
fn string(out: &mut Vec<u8>, s: &[u8]) {
    out.extend_from_slice(&(s.len() as u32).to_le_bytes());
    out.extend_from_slice(s);
}

/// A zstd chunk record holding `records`.
fn zstd_chunk(records: &[u8]) -> Vec<u8> {
    let compressed = zstd::bulk::compress(records, 3).unwrap();
    let mut body = Vec::new();
    body.extend_from_slice(&0u64.to_le_bytes()); // start time
    body.extend_from_slice(&0u64.to_le_bytes()); // end time
    body.extend_from_slice(&(records.len() as u64).to_le_bytes());
    body.extend_from_slice(&crc32fast::hash(records).to_le_bytes());
    string(&mut body, b"zstd");
    body.extend_from_slice(&(compressed.len() as u64).to_le_bytes());
    body.extend_from_slice(&compressed);
    record(mcap::records::op::CHUNK, &body)
}

/// A whole file: magic, header, `data` (records), data end, footer, magic.
fn mcap_file(data: &[u8]) -> Vec<u8> {
    use mcap::records::op;
    let mut file = mcap::MAGIC.to_vec();
    let mut h = Vec::new();
    string(&mut h, b"");
    string(&mut h, b"appell tests");
    file.extend(record(op::HEADER, &h));
    file.extend_from_slice(data);
    file.extend(record(op::DATA_END, &0u32.to_le_bytes()));
    file.extend(record(op::FOOTER, &[0; 20]));
    file.extend_from_slice(mcap::MAGIC);
    file
}

#[test]
fn mcap_metadata_records_of_ninety_thousand_entries_are_counted() {
    use mcap::records::op;
    // 800 metadata records of 90,000 entries (72 million in all, 1 GB), in zstd chunks of 100
    // records: writers put metadata outside chunks, where it would take the space it holds.
    let entries: Vec<u8> = {
        let mut m = Vec::new();
        for k in 0..90_000 {
            string(&mut m, format!("k{k}").as_bytes());
            string(&mut m, b"");
        }
        m
    };
    let mut data = Vec::new();
    for c in 0..8 {
        let mut records = Vec::new();
        for r in 0..100 {
            let mut body = Vec::new();
            string(&mut body, format!("r{}", c * 100 + r).as_bytes());
            string(&mut body, &entries);
            records.extend(record(op::METADATA, &body));
        }
        data.extend(zstd_chunk(&records));
    }
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("metadata.mcap");
    std::fs::write(&input, mcap_file(&data)).unwrap();
    let size = std::fs::metadata(&input).unwrap().len();
    assert!(size < 4 << 20, "{size}");
    assert_refused(dir.path(), &input, Resource::MetadataEntries);
}

/// A ROS 2 CDR `tf2_msgs/msg/TFMessage` of (parent, child, translation) transforms, rotations
/// the identity, stamped `sec`.
fn tf_message(sec: u32, transforms: &[(String, String, [f64; 3])]) -> Vec<u8> {
    let mut b: Vec<u8> = Vec::new();
    // Aligned to `n` from the body's start (after the 4-byte encapsulation header).
    let align = |b: &mut Vec<u8>, n: usize| {
        while !b.len().is_multiple_of(n) {
            b.push(0);
        }
    };
    let text = |b: &mut Vec<u8>, s: &str| {
        align(b, 4);
        b.extend_from_slice(&(s.len() as u32 + 1).to_le_bytes());
        b.extend_from_slice(s.as_bytes());
        b.push(0);
    };
    b.extend_from_slice(&(transforms.len() as u32).to_le_bytes());
    for (parent, child, t) in transforms {
        align(&mut b, 4);
        b.extend_from_slice(&sec.to_le_bytes());
        b.extend_from_slice(&0u32.to_le_bytes());
        text(&mut b, parent);
        text(&mut b, child);
        align(&mut b, 8);
        for v in t.iter().chain(&[0.0, 0.0, 0.0, 1.0]) {
            b.extend_from_slice(&v.to_le_bytes());
        }
    }
    [&[0, 1, 0, 0][..], &b].concat()
}

#[test]
fn mcap_a_static_tf_chain_of_five_thousand_frames_composes_in_linear_time() {
    // world <- odom (moving, 1,000 stamps) <- f0 <- f1 ... <- bob <- slider: a static chain of
    // 5,000 frames, each 1 mm along x from its parent.
    let mut chain = Vec::new();
    let mut parent = "odom".to_string();
    for k in 0..5000 {
        let child = match k {
            4998 => "bob".to_string(),
            4999 => "slider".to_string(),
            _ => format!("f{k}"),
        };
        chain.push((parent, child.clone(), [0.001, 0.0, 0.0]));
        parent = child;
    }
    let mut buf = Cursor::new(Vec::new());
    {
        // Uncompressed, as recorders write them: the budget follows the bytes on disk.
        let mut w = mcap::WriteOptions::new()
            .compression(None)
            .create(&mut buf)
            .unwrap();
        let s = w
            .add_schema("tf2_msgs/msg/TFMessage", "ros2msg", b"")
            .unwrap();
        let fixed = w
            .add_channel(s, "/tf_static", "cdr", &BTreeMap::new())
            .unwrap();
        let moving = w.add_channel(s, "/tf", "cdr", &BTreeMap::new()).unwrap();
        w.write_to_known_channel(&header(fixed, 0), &tf_message(1, &chain))
            .unwrap();
        for k in 0..1000u32 {
            let odom = (
                "world".to_string(),
                "odom".to_string(),
                [k as f64, 0.0, 0.0],
            );
            w.write_to_known_channel(&header(moving, 1 + k as u64), &tf_message(2 + k, &[odom]))
                .unwrap();
        }
        w.finish().unwrap();
    }
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("tf.mcap");
    std::fs::write(&input, buf.into_inner()).unwrap();
    let (run, out) = convert(dir.path(), &input);
    assert!(run.secs < DEADLINE.as_secs_f64() && !run.killed, "{run:?}");
    assert_eq!(run.code, Some(0), "{run:?}");
    // The slider is 5 m along x from odom, which moves 1 m a second.
    let csv = std::fs::read_to_string(out).unwrap();
    let rows: Vec<Vec<f64>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|c| c.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 1000);
    for r in &rows {
        let (t, slider_x, bob_x) = (r[0], r[1], r[3]);
        assert!((slider_x - (t + 5.0)).abs() < 1e-9, "{r:?}");
        assert!((bob_x - (t + 4.999)).abs() < 1e-9, "{r:?}");
    }
}
