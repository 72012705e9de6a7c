//! Inputs that used to crash, hang, overflow or destroy data (issue 12's fuzzing and review):
//! each ends quickly with a clear error and exit code 2, or is now read correctly. Every test
//! is named after what it pins.

use appell::data::{read_recording, read_recording_bytes, DataError, Format, ReadOptions};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

fn appell(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_appell"))
        .args(args)
        .output()
        .expect("run appell")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn write(dir: &Path, name: &str, bytes: impl AsRef<[u8]>) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

fn mcap_opts() -> ReadOptions {
    ReadOptions {
        format: Some(Format::Mcap),
        ..ReadOptions::default()
    }
}

/// An MCAP file with JSON channels: (topic, [(log_time, payload)]).
fn json_mcap(channels: &[(&str, Vec<(u64, String)>)]) -> Vec<u8> {
    let mut buf = std::io::Cursor::new(Vec::new());
    {
        let mut w = mcap::WriteOptions::new().create(&mut buf).unwrap();
        let s = w.add_schema("lab.Markers", "jsonschema", b"{}").unwrap();
        let ids: Vec<u16> = channels
            .iter()
            .map(|(topic, _)| w.add_channel(s, topic, "json", &BTreeMap::new()).unwrap())
            .collect();
        for ((_, msgs), id) in channels.iter().zip(ids) {
            for (i, (t, payload)) in msgs.iter().enumerate() {
                w.write_to_known_channel(
                    &mcap::records::MessageHeader {
                        channel_id: id,
                        sequence: i as u32,
                        log_time: *t,
                        publish_time: *t,
                    },
                    payload.as_bytes(),
                )
                .unwrap();
            }
        }
        w.finish().unwrap();
    }
    buf.into_inner()
}

fn frame(sec: &str, s: [f64; 2], b: [f64; 2]) -> String {
    format!(
        r#"{{"timestamp":{sec},"markers":[{{"id":"slider","x":{},"y":{}}},{{"id":"bob","x":{},"y":{}}}]}}"#,
        s[0], s[1], b[0], b[1]
    )
}

#[test]
fn mcap_17_byte_file_declaring_a_huge_record_is_an_error_not_an_abort() {
    let mut bytes = mcap::MAGIC.to_vec();
    bytes.push(0x03);
    bytes.extend_from_slice(&(u64::MAX - 3).to_le_bytes());
    assert_eq!(bytes.len(), 17);
    let start = Instant::now();
    let e = read_recording_bytes(&bytes, Path::new("tiny.mcap"), &mcap_opts()).unwrap_err();
    assert!(start.elapsed() < Duration::from_secs(2));
    assert!(matches!(e, DataError::Mcap { .. }), "{e}");
    let text = e.to_string();
    assert!(text.contains("limit"), "{text}");
    assert!(!text.contains('\n') && !text.contains('\u{1b}'), "{text:?}");
}

#[test]
fn mcap_parse_errors_are_one_line_without_escape_codes() {
    // A schema record whose string length runs past the record: binrw's error carries a
    // coloured backtrace, which must not reach the user.
    let mut bytes = mcap::MAGIC.to_vec();
    bytes.push(0x03);
    bytes.extend_from_slice(&8u64.to_le_bytes());
    bytes.extend_from_slice(&[1, 0, 0xff, 0xff, 0xff, 0x7f, 0, 0]);
    bytes.extend_from_slice(mcap::MAGIC);
    let e = read_recording_bytes(&bytes, Path::new("bad.mcap"), &mcap_opts()).unwrap_err();
    let text = e.to_string();
    assert!(!text.contains('\n') && !text.contains('\u{1b}'), "{text:?}");
}

#[test]
fn json_stamps_that_overflow_nanoseconds_are_not_wrapped_into_negative_times() {
    let m = json_mcap(&[(
        "/markers",
        vec![
            (
                1,
                frame(r#"{"sec":10000000000,"nsec":0}"#, [0.0, 0.0], [0.1, 0.0]),
            ),
            (
                2,
                frame(r#"{"sec":10000000001,"nsec":0}"#, [0.0, 0.0], [0.1, 0.0]),
            ),
        ],
    )]);
    let e = read_recording_bytes(&m, Path::new("big.mcap"), &mcap_opts()).unwrap_err();
    assert!(e.to_string().contains("292 years"), "{e}");
}

#[test]
fn json_timestamps_as_float_seconds_are_read() {
    let m = json_mcap(&[(
        "/markers",
        (0..5)
            .map(|k| {
                (
                    k + 1,
                    frame(
                        &format!("{}", 1.7e9 + k as f64 * 0.25),
                        [k as f64, 0.0],
                        [0.0, 0.3],
                    ),
                )
            })
            .collect(),
    )]);
    let rec = read_recording_bytes(&m, Path::new("f.mcap"), &mcap_opts()).unwrap();
    assert_eq!(rec.times, vec![0.0, 0.25, 0.5, 0.75, 1.0]);
    assert_eq!(rec.slider[3], Some([3.0, 0.0]));
}

#[test]
fn a_marker_on_two_channels_is_read_from_the_first_and_topic_chooses() {
    let msgs = |dx: f64| {
        (0..4)
            .map(|k| {
                (
                    k + 1,
                    frame(
                        &format!(r#"{{"sec":{},"nsec":0}}"#, 100 + k),
                        [k as f64 + dx, 0.0],
                        [dx, 0.3],
                    ),
                )
            })
            .collect::<Vec<_>>()
    };
    let m = json_mcap(&[("/a", msgs(0.0)), ("/b", msgs(10.0))]);
    let rec = read_recording_bytes(&m, Path::new("two.mcap"), &mcap_opts()).unwrap();
    assert_eq!(rec.slider[2], Some([2.0, 0.0]));
    assert!(rec
        .provenance
        .notes
        .iter()
        .any(|n| n.contains("also on channel /b")));
    let opts = ReadOptions {
        topics: vec!["/b".into()],
        ..mcap_opts()
    };
    let rec = read_recording_bytes(&m, Path::new("two.mcap"), &opts).unwrap();
    assert_eq!(rec.slider[2], Some([12.0, 0.0]));
    let opts = ReadOptions {
        topics: vec!["/nope".into()],
        ..mcap_opts()
    };
    let e = read_recording_bytes(&m, Path::new("two.mcap"), &opts).unwrap_err();
    assert!(e.to_string().contains("--topic /nope"), "{e}");
}

#[test]
fn unsupported_channels_give_the_same_message_on_every_run() {
    let mut buf = std::io::Cursor::new(Vec::new());
    {
        let mut w = mcap::WriteOptions::new().create(&mut buf).unwrap();
        for k in 0..8 {
            let s = w
                .add_schema(&format!("x/msg/T{k}"), "ros2msg", b"")
                .unwrap();
            let c = w
                .add_channel(s, &format!("/t{k}"), "cdr", &BTreeMap::new())
                .unwrap();
            w.write_to_known_channel(
                &mcap::records::MessageHeader {
                    channel_id: c,
                    sequence: 0,
                    log_time: 1,
                    publish_time: 1,
                },
                &[0, 1, 0, 0],
            )
            .unwrap();
        }
        w.finish().unwrap();
    }
    let bytes = buf.into_inner();
    let first = read_recording_bytes(&bytes, Path::new("u.mcap"), &mcap_opts())
        .unwrap_err()
        .to_string();
    for _ in 0..5 {
        let again = read_recording_bytes(&bytes, Path::new("u.mcap"), &mcap_opts())
            .unwrap_err()
            .to_string();
        assert_eq!(again, first);
    }
}

#[test]
fn csv_times_of_plus_minus_1e308_are_errors_not_inf() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(
        dir.path(),
        "a.csv",
        "t,slider_x,slider_y,bob_x,bob_y\n-1e308,0,0,0,0.3\n1e308,0,0,0,0.3\n",
    );
    let e = read_recording(&[p], &ReadOptions::default()).unwrap_err();
    assert!(e.to_string().contains("time"), "{e}");
}

#[test]
fn a_frame_rate_of_1e_300_is_an_error_not_inf() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(
        dir.path(),
        "a.csv",
        "frame,slider_x,slider_y,bob_x,bob_y\n0,0,0,0,0.3\n1,0,0,0,0.3\n",
    );
    let opts = ReadOptions {
        fps: Some(1e-300),
        ..ReadOptions::default()
    };
    let e = read_recording(&[p], &opts).unwrap_err();
    assert!(e.to_string().contains("time"), "{e}");
}

#[test]
fn t_ns_at_the_ends_of_i64_does_not_overflow() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(
        dir.path(),
        "a.csv",
        format!(
            "t_ns,slider_x,slider_y,bob_x,bob_y\n{},0,0,0,0.3\n{},0,0,0,0.3\n",
            i64::MIN,
            i64::MAX
        ),
    );
    let e = read_recording(&[p], &ReadOptions::default()).unwrap_err();
    assert!(e.to_string().contains("time"), "{e}");
}

#[test]
fn positions_of_1e300_are_an_error_not_a_median_of_inf() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(
        dir.path(),
        "a.csv",
        "t,slider_x,slider_y,bob_x,bob_y\n0,1e300,0,0,0.3\n1,0,0,-1e300,0.3\n",
    );
    let e = read_recording(&[p], &ReadOptions::default()).unwrap_err();
    assert!(e.to_string().contains("within"), "{e}");
}

#[test]
fn convert_refuses_to_overwrite_its_input_named_another_way() {
    let dir = tempfile::tempdir().unwrap();
    let csv = std::fs::read(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/markers_reference.csv"),
    )
    .unwrap();
    let p = write(dir.path(), "a.csv", &csv);
    let other = dir.path().join(".").join("a.csv");
    let o = appell(&["convert", p.to_str().unwrap(), other.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("refusing"), "{}", stderr(&o));
    assert_eq!(std::fs::read(&p).unwrap(), csv);
}

#[cfg(unix)]
#[test]
fn outputs_follow_links_and_write_special_files_directly() {
    let dir = tempfile::tempdir().unwrap();
    let input = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/markers_reference.csv");
    // A link: the file it points to gets the output, the link stays a link.
    let target = dir.path().join("target.csv");
    let link = dir.path().join("link.csv");
    std::os::unix::fs::symlink(&target, &link).unwrap();
    let o = appell(&["convert", input.to_str().unwrap(), link.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(std::fs::symlink_metadata(&link)
        .unwrap()
        .file_type()
        .is_symlink());
    assert!(std::fs::read_to_string(&target)
        .unwrap()
        .starts_with("t,slider_x"));
    // A device: /dev/full refuses the bytes (exit 1) and stays a device.
    if Path::new("/dev/full").exists() {
        let o = appell(&["convert", input.to_str().unwrap(), "/dev/full"]);
        assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
        assert!(!std::fs::metadata("/dev/full").unwrap().is_file());
    }
    // /dev/null takes the output and stays a device.
    let o = appell(&["convert", input.to_str().unwrap(), "/dev/null"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!std::fs::metadata("/dev/null").unwrap().is_file());
}

fn scene(extra_rig: &str, initial: &str, output: &str) -> String {
    format!(
        "[rig]\nslider_mass = 0.1\nbob_mass = {extra_rig}\nrod_length = 0.3\ngravity = 9.81\nmu_kinetic = 0.35\n\n[initial]\nx = 0.0\ntheta = 0.0\nx_dot = 0.0\ntheta_dot = {initial}\n\n[run]\nduration = 2.0\n{output}"
    )
}

#[test]
fn sizes_and_values_from_numbers_are_bounded_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let cases: Vec<(Vec<String>, &str)> = vec![
        (
            vec![
                "simulate".into(),
                write(
                    d,
                    "fr.toml",
                    scene("0.1", "0.0", "[output]\nframe_rate = 1e12\n"),
                )
                .display()
                .to_string(),
            ],
            "output.frame_rate",
        ),
        (
            vec![
                "simulate".into(),
                write(
                    d,
                    "fr3.toml",
                    scene("0.1", "0.0", "[output]\nframe_rate = 1e300\n"),
                )
                .display()
                .to_string(),
            ],
            "output.frame_rate",
        ),
        (
            vec![
                "simulate".into(),
                write(d, "td.toml", scene("0.1", "1e300", ""))
                    .display()
                    .to_string(),
            ],
            "initial.theta_dot",
        ),
        (
            vec![
                "simulate".into(),
                write(d, "m.toml", scene("5e-324", "0.0", ""))
                    .display()
                    .to_string(),
            ],
            "rig.bob_mass",
        ),
        (
            vec![
                "synth".into(),
                write(d, "s.toml", scene("0.1", "0.0", ""))
                    .display()
                    .to_string(),
                d.join("o.csv").display().to_string(),
                "--fps".into(),
                "1e12".into(),
            ],
            "--fps",
        ),
        (
            vec![
                "regions".into(),
                Path::new(env!("CARGO_MANIFEST_DIR"))
                    .join("configs/rig_paper.toml")
                    .display()
                    .to_string(),
                "--trajectories".into(),
                u64::MAX.to_string(),
            ],
            "--trajectories",
        ),
    ];
    for (args, key) in cases {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let start = Instant::now();
        let o = appell(&args);
        assert!(start.elapsed() < Duration::from_secs(5), "{args:?}");
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(stderr(&o).contains(key), "{args:?}: {}", stderr(&o));
    }
    assert!(!d.join("o.csv").exists());
}

/// `text` with the line setting `key` replaced by `key = value`.
fn set_key(text: &str, key: &str, value: &str) -> String {
    text.lines()
        .map(|l| {
            if l.trim_start().starts_with(key) {
                format!("{key} = {value}")
            } else {
                l.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join("\n")
}

#[test]
fn plan_searches_too_large_to_finish_and_zero_frame_cameras_are_refused() {
    let base = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/plan_example.toml"),
    )
    .unwrap();
    let dir = tempfile::tempdir().unwrap();
    let with_search = set_key(&base, "grid_points", "100000");
    let p = write(dir.path(), "big.toml", with_search);
    let o = appell(&["plan", p.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("simulations"), "{}", stderr(&o));
    let short = set_key(&base, "duration", "1e-300");
    let p = write(dir.path(), "short.toml", short);
    let o = appell(&["plan", p.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("camera.duration"), "{}", stderr(&o));
}

#[test]
fn mcap_record_string_length_beyond_the_record_is_an_error_not_a_2_7_gb_allocation() {
    // Found by cargo fuzz (mcap target): a record whose string length field says 2.7 GB; the
    // mcap crate reserved it before checking it against the record.
    let bytes = std::fs::read(
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/data/fuzz/mcap_record_string_length_beyond_the_record.mcap"),
    )
    .unwrap();
    let start = Instant::now();
    let r = read_recording_bytes(&bytes, Path::new("oom.mcap"), &mcap_opts());
    assert!(start.elapsed() < Duration::from_secs(2));
    let e = r.unwrap_err();
    assert!(!e.to_string().contains('\n'), "{e}");
}

/// Found by cargo fuzz (mcap target): a record inside an uncompressed chunk that claims more
/// bytes than the chunk has left. The mcap crate (0.26, sans_io linear reader) subtracts
/// without a check: with overflow checks on (debug builds, the test profile, fuzzing) it
/// panicked inside the crate, and in release builds it read on past the chunk until a garbage
/// length hit the record limit. Chunks are now walked by appell with checked lengths, in every
/// profile: the error names the record, the chunk and how much of it was left.
#[test]
fn mcap_uncompressed_chunk_record_longer_than_its_chunk_is_a_clear_error() {
    let bytes = std::fs::read(
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/data/fuzz/mcap_uncompressed_chunk_record_longer_than_its_chunk.mcap"),
    )
    .unwrap();
    let e = read_recording_bytes(&bytes, Path::new("chunk.mcap"), &mcap_opts()).unwrap_err();
    assert!(matches!(e, DataError::Mcap { .. }), "{e}");
    let text = e.to_string();
    assert!(text.contains("chunk.mcap"), "{text}");
    assert!(
        text.contains("record 3 (in the chunk at byte 42)")
            && text.contains("length 11519 bytes, beyond the 6311 byte(s) left in the chunk"),
        "{text}"
    );
}

/// A JSON marker recording of `n` frames written with `compression` in chunks of about
/// `chunk` bytes (chunk CRCs on).
fn chunked_mcap(n: usize, compression: Option<mcap::Compression>, chunk: u64) -> Vec<u8> {
    let mut buf = std::io::Cursor::new(Vec::new());
    {
        let mut w = mcap::WriteOptions::new()
            .compression(compression)
            .chunk_size(Some(chunk))
            // No message indexes: a file cut in half is cut inside its chunks.
            .emit_message_indexes(false)
            .create(&mut buf)
            .unwrap();
        let s = w.add_schema("lab.Markers", "jsonschema", b"{}").unwrap();
        let c = w
            .add_channel(s, "/markers", "json", &BTreeMap::new())
            .unwrap();
        for i in 0..n {
            let k = i as f64;
            let payload = frame(
                &format!(
                    r#"{{"sec":{},"nsec":{}}}"#,
                    100 + i / 100,
                    (i % 100) * 10_000_000
                ),
                [0.001 * k, 0.0],
                [0.3, -0.0005 * k],
            );
            w.write_to_known_channel(
                &mcap::records::MessageHeader {
                    channel_id: c,
                    sequence: i as u32,
                    log_time: 1 + i as u64,
                    publish_time: 1 + i as u64,
                },
                payload.as_bytes(),
            )
            .unwrap();
        }
        w.finish().unwrap();
    }
    buf.into_inner()
}

#[test]
fn mcap_chunks_read_alike_uncompressed_zstd_and_lz4_and_cut_files_keep_their_whole_records() {
    // Chunks are decompressed whole by appell (not the mcap crate): every compression must
    // give the same frames, over many small chunks.
    let n = 3000;
    let read = |bytes: &[u8]| read_recording_bytes(bytes, Path::new("c.mcap"), &mcap_opts());
    let plain = chunked_mcap(n, None, 4096);
    let want = read(&plain).unwrap();
    assert_eq!(want.len(), n);
    for compression in [mcap::Compression::Zstd, mcap::Compression::Lz4] {
        let bytes = chunked_mcap(n, Some(compression), 4096);
        let got = read(&bytes).unwrap();
        assert_eq!(got.times, want.times, "{compression:?}");
        assert_eq!(got.slider, want.slider, "{compression:?}");
        assert_eq!(got.bob, want.bob, "{compression:?}");
        // One big chunk cut in the middle: the records before the cut are read, as the mcap
        // crate's record-by-record reading did, and the damage is reported.
        let one = chunked_mcap(n, Some(compression), 1 << 30);
        let cut = read(&one[..one.len() / 2]).unwrap();
        assert!(cut.len() < n, "{compression:?}: {} frames", cut.len());
        assert!(
            cut.provenance
                .warnings
                .iter()
                .any(|w| w.contains("damaged")),
            "{compression:?}: {:?}",
            cut.provenance.warnings
        );
    }
    let one = chunked_mcap(n, None, 1 << 30);
    let cut = read(&one[..one.len() / 2]).unwrap();
    assert!(cut.len() > n / 3 && cut.len() < n, "{} frames", cut.len());
    assert_eq!(cut.times[..], want.times[..cut.len()]);
    assert!(cut
        .provenance
        .warnings
        .iter()
        .any(|w| w.contains("MCAP file ended in the middle of a record")));
}

#[test]
fn mcap_chunk_with_a_wrong_crc_is_reported_with_its_offset() {
    let mut bytes = chunked_mcap(50, None, 1 << 30);
    // Change one letter of a message inside the (only) chunk: its CRC no longer matches.
    let at = bytes
        .windows(6)
        .position(|w| w == b"\"bob\",")
        .expect("a bob marker");
    bytes[at + 1] = b'B';
    let e = read_recording_bytes(&bytes, Path::new("crc.mcap"), &mcap_opts()).unwrap_err();
    assert!(matches!(e, DataError::Mcap { .. }), "{e}");
    let text = e.to_string();
    assert!(
        text.contains("crc.mcap")
            && text.contains("chunk at byte")
            && text.contains("Chunk CRC failed (expected"),
        "{text}"
    );
}

/// Issue 59, class K: a marker's columns given twice in a wide CSV (the second copy different)
/// were read from the first without a word; convert, inspect and fit now refuse the header,
/// naming the column and both places.
#[test]
fn a_wide_csv_with_a_marker_column_named_twice_is_refused_naming_both_columns() {
    let dir = tempfile::tempdir().unwrap();
    let mut text = String::from("t,slider_x,slider_y,bob_x,bob_y,bob_x,bob_y\n");
    for k in 0..50 {
        let t = k as f64 * 0.01;
        text += &format!("{t},0,0,{},-0.25,{},-0.25\n", 0.1 * t.sin(), 0.3 * t.sin());
    }
    let p = write(dir.path(), "twice.csv", &text);
    let rig = write(
        dir.path(),
        "rig.toml",
        "[rig]\nslider_mass = 0.3\nbob_mass = 0.15\nrod_length = 0.25\n",
    );
    let out = dir.path().join("out.csv");
    let path = p.to_str().unwrap();
    for args in [
        vec!["convert", path, out.to_str().unwrap()],
        vec!["inspect", path],
        vec!["fit", path, "--rig", rig.to_str().unwrap()],
    ] {
        let o = appell(&args);
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {e}");
        assert!(
            e.contains("twice.csv")
                && e.contains("\"bob_x\"")
                && e.contains("column 4")
                && e.contains("column 6"),
            "{args:?}: {e}"
        );
    }
    assert!(!out.exists());
}

/// A recording at 1 kHz with its times in milliseconds (2,001 frames over 0 .. 2000 "s"): one
/// frame per 1 s against the rig's 1.1 s swing. The fit simulated a thousand times the span for
/// minutes to nonsense; now it is refused at once, exit 2, naming the file, the time column
/// and the likely cause (issue 59, class L). The same recording in seconds still fits.
#[test]
fn a_recording_with_its_times_in_milliseconds_is_refused_naming_the_cause() {
    let dir = tempfile::tempdir().unwrap();
    let data = super::measured::repo("tests/data/measured");
    let text = std::fs::read_to_string(data.join("equal_s1.csv")).unwrap();
    let mut lines = text.lines();
    let mut ms = format!("{}\n", lines.next().unwrap());
    for line in lines {
        let (t, rest) = line.split_once(',').unwrap();
        ms.push_str(&format!("{},{rest}\n", t.parse::<f64>().unwrap() * 1000.0));
    }
    let file = write(dir.path(), "ms.csv", ms);
    let rig = data.join("rigs/equal_true_nosd.toml");
    let started = Instant::now();
    let out = appell(&[
        "fit",
        file.to_str().unwrap(),
        "--rig",
        rig.to_str().unwrap(),
    ]);
    let took = started.elapsed();
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(took < Duration::from_secs(20), "{took:?}");
    for part in ["ms.csv", "milliseconds", "t_ms"] {
        assert!(err.contains(part), "{part:?} missing: {err}");
    }
    // inspect reads the file as it is (no rig to refuse it by) but says what the fit it
    // suggests will refuse, from the markers' own distance.
    let out = appell(&["inspect", file.to_str().unwrap()]);
    let text = format!("{}{}", String::from_utf8_lossy(&out.stdout), stderr(&out));
    assert_eq!(out.status.code(), Some(0), "{text}");
    assert!(
        text.contains("milliseconds") && text.contains("t_ms"),
        "{text}"
    );
}

/// A rig file with its rail near vertical (`rail_tilt_deg = 89.9`, and 30: steeper than the
/// widest tilt the fit searches) fitted the shipped example for a minute to nonsense (mu 3073 +-
/// 17000); now refused at once, exit 2, naming the key and the range (issue 59, class C).
#[test]
fn a_rig_file_with_a_rail_near_vertical_is_refused_for_a_fit() {
    let dir = tempfile::tempdir().unwrap();
    let example = super::measured::repo("data/example_recording.mcap");
    for tilt in ["89.9", "-30"] {
        let rig = write(
            dir.path(),
            "rig.toml",
            format!("[rig]\nslider_mass = 0.5\nbob_mass = 0.2\nrod_length = 0.30\ngravity = 9.81\nrail_tilt_deg = {tilt}\n"),
        );
        let started = Instant::now();
        let out = appell(&[
            "fit",
            example.to_str().unwrap(),
            "--rig",
            rig.to_str().unwrap(),
        ]);
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{tilt}: {err}");
        assert!(started.elapsed() < Duration::from_secs(20));
        assert!(
            err.contains("rig.toml") && err.contains("rig.rail_tilt_deg") && err.contains("17.19"),
            "{err}"
        );
    }
}

/// A pendulum of 0.3 m on a slider, 200 frames at 100 Hz: (t, slider, bob) in metres.
fn swinging(k: usize) -> (f64, [f64; 2], [f64; 2]) {
    let t = k as f64 * 0.01;
    let (a, x) = (0.5 * (3.0 * t).cos(), 0.02 * (3.0 * t).sin());
    (t, [x, 0.0], [x + 0.3 * a.sin(), -0.3 * a.cos()])
}

/// `appell inspect` on `args`, text and JSON: the exit code and stderr of the text run, its
/// stdout, and the JSON object.
fn inspected(args: &[&str]) -> (Option<i32>, String, String, serde_json::Value) {
    let mut all = vec!["inspect"];
    all.extend_from_slice(args);
    let text = appell(&all);
    all.push("--json");
    let json = appell(&all);
    let v = serde_json::from_slice(&json.stdout).unwrap_or(serde_json::Value::Null);
    (
        text.status.code(),
        stderr(&text),
        String::from_utf8_lossy(&text.stdout).into_owned(),
        v,
    )
}

/// Issue 59, class G: `inspect` said "the file reads as it is" of files `convert` refuses
/// (coordinates near 1.7e308, printed as "distance inf +- NaN"; an MCAP whose every frame lost
/// its positions; `--scale 1e300`). Its verdict is now the readers' own checks: each is refused
/// with convert's reason naming the file (exit 2, as for a file it cannot read), what it can
/// describe still described, with no inf or NaN for a measurement.
#[test]
fn inspect_refuses_what_convert_refuses_with_convert_s_reason() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mut huge = String::from("t,slider_x,slider_y,bob_x,bob_y\n");
    let mut good = huge.clone();
    for k in 0..200 {
        let (t, s, b) = swinging(k);
        let x = if k % 2 == 0 { 1.6e308 } else { 1.7e308 };
        huge += &format!("{t},{x},0,-1.7e308,-1e308\n");
        good += &format!("{t},{},{},{},{}\n", s[0], s[1], b[0], b[1]);
    }
    let huge = write(d, "huge.csv", huge);
    let good = write(d, "good.csv", good);
    let null = r#"{"id":"slider","x":null,"y":null},{"id":"bob","x":null,"y":null}"#;
    let dropped = json_mcap(&[(
        "/markers",
        (0..200)
            .map(|k| {
                let stamp = format!(r#"{{"sec":{},"nsec":{}}}"#, k / 100, k % 100 * 10_000_000);
                let body = format!(r#"{{"timestamp":{stamp},"markers":[{null}]}}"#);
                (k + 1, body)
            })
            .collect(),
    )]);
    let dropped = write(d, "dropped.mcap", dropped);
    let out = d.join("out.csv");
    let s = |p: &Path| p.to_str().unwrap().to_string();
    for (input, flags) in [
        (s(&huge), vec![]),
        (s(&dropped), vec![]),
        (s(&good), vec!["--scale", "1e300"]),
    ] {
        let mut convert = vec!["convert", input.as_str(), out.to_str().unwrap()];
        convert.extend(&flags);
        let c = appell(&convert);
        assert_eq!(c.status.code(), Some(2), "{convert:?}: {}", stderr(&c));
        let mut args = vec![input.as_str()];
        args.extend(&flags);
        let (code, err, text, json) = inspected(&args);
        assert_eq!(code, Some(2), "{args:?}: {err}\n{text}");
        // Convert's own reason (its last line, after the file's name), not one of inspect's.
        let reason = stderr(&c);
        let reason = reason.trim().trim_start_matches("error: ");
        assert!(err.contains(reason), "{args:?}: {err} against {reason}");
        assert!(!text.contains("reads as it is"), "{args:?}: {text}");
        for word in ["inf", "NaN"] {
            assert!(
                !text
                    .split(|c: char| !c.is_alphanumeric())
                    .any(|w| w == word),
                "{args:?}: {text}"
            );
        }
        assert!(json["refused"].as_str().unwrap().contains(reason), "{json}");
        assert!(json.get("rig_template").is_none(), "{json}");
    }
    assert!(!out.exists());
}

/// Issue 59, class H: `inspect` took spans and rates from clock times it had added back to the
/// file's start: 1000 frames a nanosecond apart near 2^63 ns were "over 1.907e-6 s" (convert
/// reads 999 ns); frames 5e-324 s apart were "inf frames/s" with a wrong reason ("seen together
/// in fewer than 20 frames"). The span is now the readers' times' own (convert's), and frames
/// closer than any clock keeps apart are refused, naming the marker, the frame and the times.
#[test]
fn inspect_keeps_nanoseconds_and_refuses_frames_no_clock_keeps_apart() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mut ns = String::from("t_ns,slider_x,slider_y,bob_x,bob_y\n");
    let mut tiny = String::from("t,slider_x,slider_y,bob_x,bob_y\n");
    let start = i64::MAX - 2000;
    for k in 0..1000 {
        let (_, s, b) = swinging(k);
        let xy = format!("{},{},{},{}", s[0], s[1], b[0], b[1]);
        ns += &format!("{},{xy}\n", start + k as i64);
        if k < 200 {
            tiny += &format!("{:e},{xy}\n", k as f64 * 5e-324);
        }
    }
    let ns = write(d, "ns.csv", ns);
    let rec = read_recording(std::slice::from_ref(&ns), &ReadOptions::default()).unwrap();
    let span = rec.times[rec.times.len() - 1] - rec.times[0];
    assert!((span - 999e-9).abs() < 1e-15, "convert's span {span}");
    let (code, err, text, json) = inspected(&[ns.to_str().unwrap()]);
    assert_eq!(code, Some(0), "{err}");
    let said: f64 = text
        .split("frames     1000 over ")
        .nth(1)
        .and_then(|r| r.split(' ').next())
        .and_then(|x| x.parse().ok())
        .unwrap_or_else(|| panic!("{text}"));
    assert!(
        (said - span).abs() <= 1e-3 * span,
        "{said} s against {span} s: {text}"
    );
    let rate = json["time"]["rate"].as_f64().unwrap();
    assert!((rate - 1e9).abs() < 1e3, "{rate}");

    let tiny = write(d, "tiny.csv", tiny);
    let (code, err, text, _) = inspected(&[tiny.to_str().unwrap()]);
    assert_eq!(code, Some(2), "{err}\n{text}");
    assert!(
        err.contains("tiny.csv") && err.contains("time") && err.contains("frame 2"),
        "{err}"
    );
    assert!(
        !err.contains("fewer than") && !text.contains("inf"),
        "{err}\n{text}"
    );
    // One rule where every reader passes: convert and fit refuse the file as inspect does (they
    // took it: convert wrote "1000 frames over 0 s", fit exited 0 with no mu).
    let rig = write(
        d,
        "rig.toml",
        "[rig]\nslider_mass = 0.1\nbob_mass = 0.1\nrod_length = 0.3\ngravity = 9.81\n",
    );
    let out_csv = d.join("out.csv");
    for args in [
        vec!["convert", tiny.to_str().unwrap(), out_csv.to_str().unwrap()],
        vec![
            "fit",
            tiny.to_str().unwrap(),
            "--rig",
            rig.to_str().unwrap(),
        ],
    ] {
        let out = appell(&args);
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(
            err.contains("tiny.csv") && err.contains("time") && err.contains("frame 2"),
            "{args:?}: {err}"
        );
    }
    assert!(!out_csv.exists());
}
