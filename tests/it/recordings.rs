//! Recordings in and out: the example MCAP files against their reference CSV, synth round
//! trips, every reader on small files whose values are known, and bad input.

use appell::data::synth::{self, SynthOptions};
use appell::data::{read_recording, DataError, Format, ReadOptions, Recording};
use appell::scene::Scene;
use std::path::{Path, PathBuf};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

fn read(paths: &[PathBuf], opts: &ReadOptions) -> Result<Recording, DataError> {
    read_recording(paths, opts)
}

fn read1(path: &Path) -> Result<Recording, DataError> {
    read(&[path.to_owned()], &ReadOptions::default())
}

/// The reference CSV read independently of the library: (t, slider, bob) per line.
fn reference() -> Vec<(f64, [f64; 2], [f64; 2])> {
    let text = std::fs::read_to_string(data("markers_reference.csv")).unwrap();
    text.lines()
        .skip(1)
        .map(|l| {
            let v: Vec<f64> = l.split(',').map(|c| c.parse().unwrap()).collect();
            (v[1], [v[2], v[3]], [v[4], v[5]])
        })
        .collect()
}

fn assert_matches_reference(rec: &Recording) {
    let reference = reference();
    assert_eq!(rec.len(), reference.len());
    for (i, (t, s, b)) in reference.iter().enumerate() {
        assert!(
            (rec.times[i] - t).abs() < 1e-12,
            "frame {i}: t {} vs {t}",
            rec.times[i]
        );
        assert_eq!(rec.slider[i], Some(*s), "frame {i} slider");
        assert_eq!(rec.bob[i], Some(*b), "frame {i} bob");
    }
}

#[test]
fn example_json_mcap_reads_to_the_reference_csv() {
    let rec = read1(&data("markers_json_zstd.mcap")).unwrap();
    assert_eq!(rec.provenance.format, Some(Format::Mcap));
    assert_matches_reference(&rec);
    // The truth record the file was made with comes along.
    assert_eq!(rec.provenance.metadata["truth.mu"], "0.12");
}

#[test]
fn example_ros2_cdr_mcap_reads_to_the_reference_csv() {
    let rec = read1(&data("markers_ros2_pointstamped.mcap")).unwrap();
    assert_eq!(rec.provenance.slider_name, "/markers/slider");
    assert_matches_reference(&rec);
}

#[test]
fn example_protobuf_frame_transform_mcap_reads_to_the_reference_csv() {
    // One foxglove.FrameTransform per marker per frame; log_time carries jitter, so matching
    // the reference also shows the in-message timestamp is the one used.
    let rec = read1(&data("markers_foxglove_frametransform.mcap")).unwrap();
    assert_eq!(rec.provenance.format, Some(Format::Mcap));
    assert_eq!(rec.provenance.slider_name, "slider");
    assert_eq!(rec.provenance.bob_name, "bob");
    assert_matches_reference(&rec);
}

#[test]
fn example_protobuf_points_annotation_mcap_reads_to_the_reference_csv() {
    // foxglove.PointsAnnotation: point 0 is the slider, point 1 the bob.
    let rec = read1(&data("markers_foxglove_points.mcap")).unwrap();
    assert_eq!(rec.provenance.slider_name, "slider");
    assert_eq!(rec.provenance.bob_name, "bob");
    assert_matches_reference(&rec);
    // The flags can still swap the roles.
    let swapped = read(
        &[data("markers_foxglove_points.mcap")],
        &ReadOptions {
            slider: Some("bob".into()),
            bob: Some("slider".into()),
            ..ReadOptions::default()
        },
    )
    .unwrap();
    assert_eq!(swapped.slider, rec.bob);
}

#[test]
fn cli_converts_the_protobuf_examples() {
    let dir = tempfile::tempdir().unwrap();
    for name in [
        "markers_foxglove_frametransform.mcap",
        "markers_foxglove_points.mcap",
    ] {
        let out = dir.path().join(format!("{name}.csv"));
        let run = std::process::Command::new(env!("CARGO_BIN_EXE_appell"))
            .arg("convert")
            .arg(data(name))
            .arg(&out)
            .output()
            .unwrap();
        assert_eq!(
            run.status.code(),
            Some(0),
            "{name}: {}",
            String::from_utf8_lossy(&run.stderr)
        );
        let back = read1(&out).unwrap();
        let reference = reference();
        assert_eq!(back.len(), reference.len(), "{name}");
        assert_eq!(back.slider[17], Some(reference[17].1), "{name}");
    }
}

#[test]
fn reference_csv_reads_as_wide_csv_with_the_known_rod_length() {
    let rec = read1(&data("markers_reference.csv")).unwrap();
    assert_eq!(rec.provenance.format, Some(Format::Wide));
    assert_matches_reference(&rec);
    let g = rec.provenance.geometry.unwrap();
    // l = 0.30 m with 0.2 mm noise on each coordinate.
    assert!((g.median - 0.30).abs() < 2e-4, "median {}", g.median);
    assert!(g.std < 5e-4);
    assert!(g.outliers.is_empty());
}

const SCENE: &str = r#"
[rig]
slider_mass = 0.5
bob_mass = 0.2
rod_length = 0.30
gravity = 9.81
mu_kinetic = 0.12
[initial]
x = 0.0
theta = 0.6707963267948966
x_dot = 0.0
theta_dot = 0.0
[run]
duration = 0.4
"#;

fn scene() -> Scene {
    Scene::from_toml(SCENE, Path::new("test-scene.toml")).unwrap()
}

fn noisy() -> SynthOptions {
    SynthOptions {
        fps: 500.0,
        noise: 2e-4,
        dropout: 0.05,
        outliers: 0.02,
        seed: 7,
        ..SynthOptions::default()
    }
}

#[test]
fn synth_is_reproducible_by_seed() {
    let a = synth::synthesize(&scene(), &noisy()).unwrap();
    let b = synth::synthesize(&scene(), &noisy()).unwrap();
    assert_eq!(a.recording, b.recording);
    let c = synth::synthesize(&scene(), &SynthOptions { seed: 8, ..noisy() }).unwrap();
    assert_ne!(a.recording.slider, c.recording.slider);
    assert_eq!(a.recording.len(), 201);
}

#[test]
fn synth_csv_round_trip_gives_the_same_values() {
    let dir = tempfile::tempdir().unwrap();
    let syn = synth::synthesize(&scene(), &noisy()).unwrap();
    let path = dir.path().join("syn.csv");
    synth::write(&path, &syn.recording, &syn.truth).unwrap();
    let back = read1(&path).unwrap();
    assert_eq!(back.times, syn.recording.times);
    assert_eq!(back.slider, syn.recording.slider);
    assert_eq!(back.bob, syn.recording.bob);
}

#[test]
fn synth_mcap_round_trip_gives_the_same_values_and_truth() {
    let dir = tempfile::tempdir().unwrap();
    let syn = synth::synthesize(&scene(), &noisy()).unwrap();
    let path = dir.path().join("syn.mcap");
    synth::write(&path, &syn.recording, &syn.truth).unwrap();
    let back = read1(&path).unwrap();
    assert_eq!(back.len(), syn.recording.len());
    for (a, b) in back.times.iter().zip(&syn.recording.times) {
        assert!((a - b).abs() < 1e-9);
    }
    assert_eq!(back.slider, syn.recording.slider);
    assert_eq!(back.bob, syn.recording.bob);
    assert_eq!(back.provenance.metadata["truth.mu_kinetic"], "0.12");
    assert_eq!(back.provenance.metadata["truth.seed"], "7");
}

#[test]
fn synth_without_noise_keeps_the_rod_length_and_flags_injected_outliers() {
    let syn = synth::synthesize(
        &scene(),
        &SynthOptions {
            fps: 500.0,
            outliers: 0.05,
            outlier_size: 0.05,
            seed: 3,
            ..SynthOptions::default()
        },
    )
    .unwrap();
    let rec = &syn.recording;
    let g = appell::data::calibrate::check_geometry(rec, Some(0.30)).unwrap();
    // Exact markers sit at the rod length; every flagged frame is off by the outlier size
    // projected on the rod, and clean frames are never flagged.
    for i in 0..rec.len() {
        let (s, b) = (rec.slider[i].unwrap(), rec.bob[i].unwrap());
        let d = (b[0] - s[0]).hypot(b[1] - s[1]);
        assert_eq!(g.outliers.contains(&i), (d - 0.30).abs() > g.tolerance);
    }
    assert!(!g.outliers.is_empty());
    assert!(g.outliers.len() < rec.len() / 5);
}

/// The synthetic truth, drawn in a camera's pixel frame: scaled, rotated, shifted, y down,
/// written as DeepLabCut CSV.
#[test]
fn dlc_pixels_in_a_tilted_camera_calibrate_back_into_the_rail_frame() {
    let dir = tempfile::tempdir().unwrap();
    let syn = synth::synthesize(
        &scene(),
        &SynthOptions {
            fps: 250.0,
            ..SynthOptions::default()
        },
    )
    .unwrap();
    let rec = &syn.recording;
    let (px_per_m, tilt, off) = (1500.0_f64, 0.05_f64, [320.0, 100.0]);
    let to_px = |p: [f64; 2]| {
        let (s, c) = tilt.sin_cos();
        let (x, y) = (c * p[0] - s * p[1], s * p[0] + c * p[1]);
        [off[0] + px_per_m * x, off[1] - px_per_m * y]
    };
    let mut text = String::from(
        "scorer,DLC,DLC,DLC,DLC,DLC,DLC\nbodyparts,slider,slider,slider,bob,bob,bob\ncoords,x,y,likelihood,x,y,likelihood\n",
    );
    for i in 0..rec.len() {
        let (s, b) = (to_px(rec.slider[i].unwrap()), to_px(rec.bob[i].unwrap()));
        let lk = if i == 3 { 0.2 } else { 0.99 };
        text += &format!("{i},{},{},{lk},{},{},1.0\n", s[0], s[1], b[0], b[1]);
    }
    let path = write(dir.path(), "dlc.csv", &text);
    let opts = ReadOptions {
        fps: Some(250.0),
        rod_length: Some(0.30),
        rail_frame: true,
        ..ReadOptions::default()
    };
    let back = read(std::slice::from_ref(&path), &opts).unwrap();
    assert_eq!(back.provenance.format, Some(Format::DeepLabCut));
    let cal = &back.provenance.calibration;
    assert!(cal.y_flipped);
    assert!((cal.scale - 1.0 / px_per_m).abs() < 1e-9);
    assert!((cal.rail_angle.unwrap() - tilt).abs() < 1e-9);
    assert_eq!(
        back.slider[3], None,
        "likelihood 0.2 < 0.6 counts as missing"
    );
    let x0 = rec.slider[0].unwrap()[0];
    for i in (0..rec.len()).filter(|&i| i != 3) {
        assert!((back.times[i] - i as f64 / 250.0).abs() < 1e-12);
        for (a, b) in [(back.slider[i], rec.slider[i]), (back.bob[i], rec.bob[i])] {
            let (a, b) = (a.unwrap(), b.unwrap());
            assert!((a[0] - (b[0] - x0)).abs() < 1e-9 && (a[1] - b[1]).abs() < 1e-9);
        }
    }
    // Without a scale or a rod length, pixels are refused with the flag to use.
    let err = read(
        &[path],
        &ReadOptions {
            fps: Some(250.0),
            ..ReadOptions::default()
        },
    )
    .unwrap_err();
    assert!(err.to_string().contains("--scale"), "{err}");
}

#[test]
fn tracker_files_one_per_marker_with_locale_variants() {
    let dir = tempfile::tempdir().unwrap();
    // Tab, decimal comma, exponent notation, an empty cell.
    let slider = write(
        dir.path(),
        "slider.txt",
        "slider\nt\tx\ty\n0,0\t1,0E-2\t0,0\n0,1\t\t\n0,2\t3,0E-2\t0,0\n",
    );
    // Semicolon delimited with a decimal comma; the bob is missing at t = 0.1.
    let bob = write(
        dir.path(),
        "bob.txt",
        "mass_bob\nt;x;y\n0,0;0,31;-0,1\n0,2;0,32;-0,2\n",
    );
    let rec = read(&[slider.clone(), bob.clone()], &ReadOptions::default()).unwrap();
    assert_eq!(rec.provenance.format, Some(Format::Tracker));
    assert_eq!(rec.times, vec![0.0, 0.1, 0.2]);
    assert_eq!(rec.slider, vec![Some([0.01, 0.0]), None, Some([0.03, 0.0])]);
    assert_eq!(rec.bob, vec![Some([0.31, -0.1]), None, Some([0.32, -0.2])]);
    // Comma and space delimited, point decimals.
    let s2 = write(
        dir.path(),
        "s2.txt",
        "slider\nt,x,y\n0.0,1.5,2\n1.0,2.5,3\n",
    );
    let b2 = write(dir.path(), "b2.txt", "bob\nt x y\n0.0 4 5\n1.0 6 7\n");
    let rec = read(&[s2, b2], &ReadOptions::default()).unwrap();
    assert_eq!(rec.slider, vec![Some([1.5, 2.0]), Some([2.5, 3.0])]);
    assert_eq!(rec.bob, vec![Some([4.0, 5.0]), Some([6.0, 7.0])]);
}

#[test]
fn long_form_csv_aligns_markers_on_time() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(
        dir.path(),
        "long.csv",
        "time,marker,x,y\n0.0,Rig_slider,0.0,0.0\n0.0,Rig_bob,0.3,0.0\n0.01,Rig_bob,0.29,-0.05\n0.02,Rig_slider,0.001,0.0\n0.02,Rig_bob,0.28,-0.1\n",
    );
    let rec = read1(&p).unwrap();
    assert_eq!(rec.provenance.format, Some(Format::Long));
    assert_eq!(rec.times, vec![0.0, 0.01, 0.02]);
    assert_eq!(rec.slider, vec![Some([0.0, 0.0]), None, Some([0.001, 0.0])]);
    assert_eq!(rec.bob[1], Some([0.29, -0.05]));
}

#[test]
fn motive_and_vicon_read_units_plane_and_time_from_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let motive = write(
        dir.path(),
        "motive.csv",
        "Format Version,1.23,Take Name,T1,Capture Frame Rate,120.000000,Export Frame Rate,120.000000,Total Exported Frames,2,Rotation Type,Quaternion,Length Units,Millimeters,Coordinate Space,Global\n\n\
,Type,Marker,Marker,Marker,Marker,Marker,Marker\n\
,Name,Rig:slider,Rig:slider,Rig:slider,Rig:bob,Rig:bob,Rig:bob\n\
,ID,1,1,1,2,2,2\n\
,,Position,Position,Position,Position,Position,Position\n\
Frame,Time (Seconds),X,Y,Z,X,Y,Z\n\
0,0.000000,100.0,200.0,300.0,,,\n\
1,0.008333,110.0,200.0,300.0,400.0,-100.0,300.0\n",
    );
    let rec = read1(&motive).unwrap();
    assert_eq!(rec.provenance.format, Some(Format::Motive));
    assert_eq!(rec.provenance.slider_name, "Rig:slider");
    // Frame / Export Frame Rate, not the rounded Time column.
    assert_eq!(rec.times, vec![0.0, 1.0 / 120.0]);
    assert_eq!(rec.slider[0], Some([0.1, 0.2]));
    assert_eq!(rec.bob, vec![None, Some([0.4, -0.1])]);

    let vicon = write(
        dir.path(),
        "vicon.csv",
        "Devices\n100\n,,Force\n\nTrajectories\n100\n,,Rig:slider,,,Rig:bob,,\n\
Frame,Sub Frame,X,Y,Z,X,Y,Z\n,,mm,mm,mm,mm,mm,mm\n\
5,0,12.0,45.0,789.0,,,\n6,0,13.0,45.0,789.0,300.0,40.0,500.0\n\nModel Outputs\n",
    );
    let rec = read1(&vicon).unwrap();
    assert_eq!(rec.provenance.format, Some(Format::Vicon));
    assert_eq!(rec.times, vec![0.0, 0.01]);
    // Plane xz by default: Vicon's z is up.
    assert_eq!(rec.slider[1], Some([0.013, 0.789]));
    assert_eq!(rec.bob[1], Some([0.3, 0.5]));
    let yz = ReadOptions {
        plane: Some(appell::data::Plane::Yz),
        ..ReadOptions::default()
    };
    assert_eq!(read(&[vicon], &yz).unwrap().bob[1], Some([0.04, 0.5]));
}

#[test]
fn dlc_multi_animal_header_names_markers_by_individual() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(
        dir.path(),
        "ma.csv",
        "scorer,S,S,S,S,S,S\nindividuals,rig,rig,rig,rig,rig,rig\nbodyparts,slider,slider,slider,bob,bob,bob\ncoords,x,y,likelihood,x,y,likelihood\n0,10,20,0.9,40,80,0.9\n1,,,,41,81,0.95\n",
    );
    let opts = ReadOptions {
        fps: Some(10.0),
        scale: Some(0.01),
        ..ReadOptions::default()
    };
    let rec = read(&[p], &opts).unwrap();
    assert_eq!(rec.provenance.slider_name, "rig/slider");
    assert_eq!(rec.times, vec![0.0, 0.1]);
    assert_eq!(rec.slider, vec![Some([0.1, -0.2]), None]);
    assert_eq!(rec.bob[1], Some([0.41, -0.81]));
}

// ---------------------------------------------------------------- bad input

fn bad(text: &str, opts: &ReadOptions) -> DataError {
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "bad.csv", text);
    read(&[p], opts).unwrap_err()
}

fn wide() -> ReadOptions {
    ReadOptions {
        format: Some(Format::Wide),
        ..ReadOptions::default()
    }
}

#[test]
fn empty_and_header_only_files_are_named_errors() {
    assert!(matches!(
        bad("", &ReadOptions::default()),
        DataError::Empty { .. }
    ));
    assert!(matches!(bad("", &wide()), DataError::Empty { .. }));
    let e = bad("t,slider_x,slider_y,bob_x,bob_y\n", &ReadOptions::default());
    assert!(matches!(e, DataError::NoFrames { .. }), "{e}");
}

#[test]
fn wrong_columns_text_and_non_finite_cells_name_line_and_field() {
    let e = bad("t,a,b\n0,1,2\n", &wide());
    assert!(
        matches!(&e, DataError::Parse { field, .. } if field == "header"),
        "{e}"
    );
    let e = bad("q,slider_x,slider_y\n0,1,2\n", &wide());
    assert!(e.to_string().contains("a time column"), "{e}");
    let e = bad(
        "t,slider_x,slider_y,bob_x,bob_y\n0,1,2,3,4\n0.1,1,abc,3,4\n",
        &wide(),
    );
    match &e {
        DataError::Parse {
            at, field, found, ..
        } => {
            assert_eq!(at, "line 3");
            assert_eq!(field, "slider y");
            assert!(found.contains("abc"));
        }
        other => panic!("{other}"),
    }
    for cell in ["NaN", "inf", "-inf", "1e999"] {
        let e = bad(
            &format!("t,slider_x,slider_y,bob_x,bob_y\n0,1,2,3,{cell}\n"),
            &wide(),
        );
        assert!(
            matches!(&e, DataError::Parse { expected, .. } if expected == "a finite number"),
            "{e}"
        );
    }
    let e = bad("t,slider_x,slider_y,bob_x,bob_y\n0,1,2\n", &wide());
    assert!(
        matches!(&e, DataError::Parse { at, .. } if at == "line 2"),
        "{e}"
    );
}

#[test]
fn times_that_repeat_or_go_backwards_are_errors() {
    let e = bad(
        "t,slider_x,slider_y,bob_x,bob_y\n0,1,2,3,4\n0,1,2,3,4\n",
        &wide(),
    );
    assert!(
        matches!(
            e,
            DataError::Time {
                problem: "is repeated",
                ..
            }
        ),
        "{e}"
    );
    let e = bad(
        "t,slider_x,slider_y,bob_x,bob_y\n0.2,1,2,3,4\n0.1,1,2,3,4\n",
        &wide(),
    );
    assert!(
        matches!(&e, DataError::Time { problem: "goes backwards", at, .. } if at == "line 3"),
        "{e}"
    );
}

#[test]
fn a_marker_that_never_appears_lists_the_markers_present() {
    let e = bad(
        "t,slider_x,slider_y,pendulum_x,pendulum_y\n0,1,2,3,4\n",
        &wide(),
    );
    match &e {
        DataError::MissingMarker {
            role, available, ..
        } => {
            assert_eq!(*role, "bob");
            assert!(available.contains("pendulum"));
        }
        other => panic!("{other}"),
    }
    // Named but never with a position.
    let e = bad("t,slider_x,slider_y,bob_x,bob_y\n0,1,2,,\n", &wide());
    assert!(
        matches!(e, DataError::MissingMarker { role: "bob", .. }),
        "{e}"
    );
    let e = bad("t,marker,x,y\n0,slider,1,2\n", &ReadOptions::default());
    assert!(
        matches!(e, DataError::MissingMarker { role: "bob", .. }),
        "{e}"
    );
}

#[test]
fn unknown_format_says_which_are_supported() {
    let e = bad("hello world\n1 2 3\n", &ReadOptions::default());
    assert!(
        matches!(&e, DataError::UnknownFormat { supported, .. } if supported.contains("tracker")),
        "{e}"
    );
}

#[test]
fn dlc_without_a_frame_rate_asks_for_fps() {
    let e = bad(
        "scorer,S,S,S,S,S,S\nbodyparts,slider,slider,slider,bob,bob,bob\ncoords,x,y,likelihood,x,y,likelihood\n0,1,2,1,3,4,1\n",
        &ReadOptions::default(),
    );
    assert!(e.to_string().contains("--fps"), "{e}");
}

#[test]
fn truncated_mcap_keeps_the_frames_before_the_damage_and_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let bytes = std::fs::read(data("markers_ros2_pointstamped.mcap")).unwrap();
    let cut = write_bytes(dir.path(), "cut.mcap", &bytes[..bytes.len() / 2]);
    let rec = read1(&cut).unwrap();
    assert!(rec.len() > 100 && rec.len() < 2000, "{} frames", rec.len());
    assert!(rec
        .provenance
        .warnings
        .iter()
        .any(|w| w.contains("damaged")));
    for (s, r) in rec.slider.iter().zip(reference()) {
        if let Some(s) = s {
            assert_eq!(*s, r.1);
        }
    }
    // Cut inside the header: nothing to keep, an error naming the file.
    let stub = write_bytes(dir.path(), "stub.mcap", &bytes[..20]);
    let e = read1(&stub).unwrap_err();
    assert!(matches!(e, DataError::Mcap { .. }), "{e}");
}

fn write_bytes(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

fn mcap_with(encoding: &str, schema: (&str, &str), payload: &[u8]) -> Vec<u8> {
    use std::collections::BTreeMap;
    let mut buf = std::io::Cursor::new(Vec::new());
    {
        let mut w = mcap::WriteOptions::new().create(&mut buf).unwrap();
        let s = w.add_schema(schema.0, schema.1, b"{}").unwrap();
        let c = w
            .add_channel(s, "/diagnostics", encoding, &BTreeMap::new())
            .unwrap();
        w.write_to_known_channel(
            &mcap::records::MessageHeader {
                channel_id: c,
                sequence: 0,
                log_time: 1,
                publish_time: 1,
            },
            payload,
        )
        .unwrap();
        w.finish().unwrap();
    }
    buf.into_inner()
}

#[test]
fn mcap_without_a_marker_channel_or_with_an_unknown_encoding_is_explained() {
    let dir = tempfile::tempdir().unwrap();
    let p = write_bytes(
        dir.path(),
        "diag.mcap",
        &mcap_with("json", ("diag", "jsonschema"), br#"{"cpu": 0.5}"#),
    );
    let e = read1(&p).unwrap_err();
    assert!(
        matches!(&e, DataError::NoMarkerChannel { channels, .. } if channels.contains("/diagnostics")),
        "{e}"
    );
    let p = write_bytes(
        dir.path(),
        "mp.mcap",
        &mcap_with("msgpack", ("diag", "x"), b"\x80"),
    );
    let e = read1(&p).unwrap_err();
    match &e {
        DataError::Unsupported {
            found, supported, ..
        } => {
            assert!(found.contains("msgpack"));
            assert!(supported.contains("json") && supported.contains("cdr"));
        }
        other => panic!("{other}"),
    }
}

#[test]
fn protobuf_channels_of_other_types_or_with_a_broken_schema_are_explained() {
    let dir = tempfile::tempdir().unwrap();
    let p = write_bytes(
        dir.path(),
        "log.mcap",
        &mcap_with("protobuf", ("foxglove.Log", "protobuf"), b"\x08\x01"),
    );
    match read1(&p).unwrap_err() {
        DataError::Unsupported {
            found, supported, ..
        } => {
            assert!(found.contains("foxglove.Log"), "{found}");
            assert!(
                supported.contains("foxglove.FrameTransform")
                    && supported.contains("foxglove.PointsAnnotation"),
                "{supported}"
            );
        }
        other => panic!("{other}"),
    }
    // The CLI reports it with exit code 2, naming the file.
    let out = dir.path().join("log.csv");
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_appell"))
        .arg("convert")
        .arg(&p)
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(run.status.code(), Some(2));
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(
        err.contains("log.mcap") && err.contains("foxglove.Log"),
        "{err}"
    );
    assert!(!out.exists());
    // A supported type whose schema data is not a FileDescriptorSet: the channel is listed
    // with the reason.
    let p = write_bytes(
        dir.path(),
        "badschema.mcap",
        &mcap_with(
            "protobuf",
            ("foxglove.FrameTransform", "protobuf"),
            b"\x08\x01",
        ),
    );
    let e = read1(&p).unwrap_err();
    assert!(
        matches!(&e, DataError::NoMarkerChannel { channels, .. } if channels.contains("FileDescriptorSet")),
        "{e}"
    );
}

#[test]
fn a_damaged_protobuf_message_after_good_ones_names_the_message() {
    // The example's own schema (a FileDescriptorSet), two good messages, then garbage.
    let bytes = std::fs::read(data("markers_foxglove_frametransform.mcap")).unwrap();
    let good: Vec<_> = mcap::MessageStream::new(&bytes)
        .unwrap()
        .take(2)
        .map(|m| m.unwrap())
        .collect();
    let schema = good[0].channel.schema.clone().unwrap();
    assert_eq!(schema.name, "foxglove.FrameTransform");
    let mut buf = std::io::Cursor::new(Vec::new());
    {
        let mut w = mcap::WriteOptions::new().create(&mut buf).unwrap();
        let s = w
            .add_schema(&schema.name, &schema.encoding, &schema.data)
            .unwrap();
        let c = w
            .add_channel(s, "/tf", "protobuf", &std::collections::BTreeMap::new())
            .unwrap();
        let payloads = [&good[0].data[..], &good[1].data[..], b"\x0a\xff\x01"];
        for (i, d) in payloads.into_iter().enumerate() {
            w.write_to_known_channel(
                &mcap::records::MessageHeader {
                    channel_id: c,
                    sequence: i as u32,
                    log_time: i as u64,
                    publish_time: i as u64,
                },
                d,
            )
            .unwrap();
        }
        w.finish().unwrap();
    }
    let dir = tempfile::tempdir().unwrap();
    let p = write_bytes(dir.path(), "damaged_tf.mcap", &buf.into_inner());
    let e = read1(&p).unwrap_err();
    let text = e.to_string();
    assert!(matches!(e, DataError::Parse { .. }), "{text}");
    assert!(
        text.contains("damaged_tf.mcap") && text.contains("message 3") && text.contains("/tf"),
        "{text}"
    );
}

#[test]
fn cli_bad_input_exits_2_and_leaves_no_output() {
    let dir = tempfile::tempdir().unwrap();
    let input = write(
        dir.path(),
        "in.csv",
        "t,slider_x,slider_y,bob_x,bob_y\n0,1,x,3,4\n",
    );
    let out = dir.path().join("out.csv");
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_appell"))
        .args(["convert"])
        .arg(&input)
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(run.status.code(), Some(2));
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(err.contains("in.csv") && err.contains("line 2"), "{err}");
    assert!(!out.exists());
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        1,
        "no temporary file left"
    );
}

#[test]
fn cli_convert_and_synth_write_files_that_read_back() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write(dir.path(), "scene.toml", SCENE);
    let mcap = dir.path().join("s.mcap");
    let bin = env!("CARGO_BIN_EXE_appell");
    let run = std::process::Command::new(bin)
        .args(["synth", "--fps", "200", "--noise", "1e-4", "--seed", "5"])
        .arg(&scene)
        .arg(&mcap)
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let csv = dir.path().join("s.csv");
    let run = std::process::Command::new(bin)
        .arg("convert")
        .arg(&mcap)
        .arg(&csv)
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(stdout.contains("mcap format, detected"), "{stdout}");
    let a = read1(&mcap).unwrap();
    let b = read1(&csv).unwrap();
    assert_eq!(a.slider, b.slider);
    assert_eq!(a.bob, b.bob);
    assert_eq!(b.len(), 81);
}

// ---------------------------------------------------------------- properties

mod props {
    use super::*;
    use proptest::prelude::*;

    fn point() -> impl Strategy<Value = Option<[f64; 2]>> {
        prop::option::weighted(0.9, prop::array::uniform2(-1e3..1e3f64))
    }

    /// Increasing times with both tracks seen at least once.
    fn recording() -> impl Strategy<Value = Recording> {
        prop::collection::vec((1e-4..1.0f64, point(), point()), 1..40)
            .prop_map(|rows| {
                let mut rec = Recording::default();
                let mut t = 0.0;
                for (i, (dt, s, b)) in rows.into_iter().enumerate() {
                    if i > 0 {
                        t += dt;
                    }
                    rec.times.push(t);
                    rec.slider.push(s);
                    rec.bob.push(b);
                }
                rec
            })
            .prop_filter("both markers seen", |r| r.seen().0 > 0 && r.seen().1 > 0)
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

        #[test]
        fn wide_csv_round_trips_exactly(rec in recording()) {
            let mut bytes = Vec::new();
            rec.write_csv(&mut bytes).unwrap();
            let back = appell::data::read_recording_from(
                bytes.as_slice(), Path::new("prop.csv"), &ReadOptions::default()).unwrap();
            prop_assert_eq!(back.times, rec.times);
            prop_assert_eq!(back.slider, rec.slider);
            prop_assert_eq!(back.bob, rec.bob);
        }

        #[test]
        fn tracker_reads_every_delimiter_and_decimal_style(
            rows in prop::collection::vec(prop::array::uniform2(-1e3..1e3f64), 1..30),
            style in 0usize..4,
            exponent in any::<bool>(),
        ) {
            let (delim, comma) = [("\t", true), (";", true), (" ", false), (",", false)][style];
            let fmt = |v: f64| {
                let s = if exponent { format!("{v:E}") } else { format!("{v}") };
                if comma { s.replace('.', ",") } else { s }
            };
            let mut text = format!("slider\nt{delim}x{delim}y\n");
            for (i, p) in rows.iter().enumerate() {
                text += &format!("{}{delim}{}{delim}{}\n", fmt(i as f64 * 0.5), fmt(p[0]), fmt(p[1]));
            }
            let dir = tempfile::tempdir().unwrap();
            let s = write(dir.path(), "s.txt", &text);
            let b = write(dir.path(), "b.txt", &text.replacen("slider", "bob", 1));
            let rec = read(&[s, b], &ReadOptions::default()).unwrap();
            prop_assert_eq!(rec.len(), rows.len());
            for (i, p) in rows.iter().enumerate() {
                prop_assert_eq!(rec.slider[i], Some(*p));
            }
        }

        #[test]
        fn csv_readers_never_panic_on_arbitrary_text(
            text in "(t|slider_x|bob_y|scorer|coords|bodyparts|,|;|\t|\n|0|1\\.5|-|e|NaN| |x|y)*",
            f in 0usize..6,
        ) {
            let format = [Format::Wide, Format::Long, Format::Tracker, Format::DeepLabCut, Format::Motive, Format::Vicon][f];
            let opts = ReadOptions { format: Some(format), fps: Some(30.0), scale: Some(1.0), ..ReadOptions::default() };
            let _ = appell::data::read_recording_from(text.as_bytes(), Path::new("fuzz.csv"), &opts);
        }
    }
}

/// The shipped Tracker (German locale) and DeepLabCut (pixels, camera tilted 3 degrees)
/// examples were drawn from configs/markers_example.toml at 100 Hz: they read back to the
/// simulated markers.
#[test]
fn shipped_tracker_and_dlc_examples_read_back_to_the_simulated_markers() {
    let cfg = Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/markers_example.toml");
    let scene = Scene::from_path(&cfg).unwrap();
    let truth = synth::synthesize(
        &scene,
        &SynthOptions {
            fps: 100.0,
            ..SynthOptions::default()
        },
    )
    .unwrap()
    .recording;
    let tracker = read(
        &[data("tracker_slider.txt"), data("tracker_bob.txt")],
        &ReadOptions::default(),
    )
    .unwrap();
    let dlc = read(
        &[data("dlc_example.csv")],
        &ReadOptions {
            fps: Some(100.0),
            rod_length: Some(0.30),
            rail_frame: true,
            ..ReadOptions::default()
        },
    )
    .unwrap();
    assert!((dlc.provenance.calibration.rail_angle.unwrap().to_degrees() - 3.0).abs() < 1e-4);
    for (rec, tol, missing) in [
        (&tracker, 1e-9, (None, Some(5))),
        (&dlc, 1e-6, (Some(7), None)),
    ] {
        assert_eq!(rec.len(), truth.len());
        for i in 0..rec.len() {
            assert!((rec.times[i] - truth.times[i]).abs() < 1e-12);
            for (got, want, gap) in [
                (rec.slider[i], truth.slider[i], missing.0),
                (rec.bob[i], truth.bob[i], missing.1),
            ] {
                if gap == Some(i) {
                    assert_eq!(got, None);
                    continue;
                }
                let (g, w) = (got.unwrap(), want.unwrap());
                assert!(
                    (g[0] - w[0]).abs() < tol && (g[1] - w[1]).abs() < tol,
                    "frame {i}: {g:?} vs {w:?}"
                );
            }
        }
    }
}

/// A time window keeps exactly the reference frames inside it (times re-zeroed), and an MCAP
/// file is not decoded past it.
#[test]
fn time_window_keeps_the_frames_inside_and_stops_reading_mcap_after_it() {
    let reference = reference();
    for file in ["markers_json_zstd.mcap", "markers_reference.csv"] {
        let opts = ReadOptions {
            time_window: Some((0.2, 0.5)),
            ..ReadOptions::default()
        };
        let rec = read(&[data(file)], &opts).unwrap();
        let inside: Vec<_> = reference
            .iter()
            .filter(|r| r.0 >= 0.2 - 1e-9 && r.0 <= 0.5 + 1e-9)
            .collect();
        assert_eq!(rec.times.len(), inside.len(), "{file}");
        for (i, r) in inside.iter().enumerate() {
            assert!(
                (rec.times[i] - (r.0 - inside[0].0)).abs() < 1e-9,
                "{file} frame {i}"
            );
            assert_eq!(rec.slider[i].unwrap(), r.1, "{file} frame {i}");
            assert_eq!(rec.bob[i].unwrap(), r.2, "{file} frame {i}");
        }
        if file.ends_with(".mcap") {
            assert!(
                rec.provenance
                    .notes
                    .iter()
                    .any(|n| n.contains("stopped reading")),
                "{:?}",
                rec.provenance.notes
            );
        }
    }
    let empty = ReadOptions {
        time_window: Some((5.0, 6.0)),
        ..ReadOptions::default()
    };
    assert!(matches!(
        read(&[data("markers_reference.csv")], &empty),
        Err(DataError::Options { .. })
    ));
}
