//! Files written by the tools labs use, found in public repositories (`tests/data/PROVENANCE.tsv`
//! says where each came from): every one reads, row for row, to the values the file itself holds
//! (parsed again here with plain string handling, independently of the readers), or, where the
//! file holds no marker data, gives an error that says so.

use appell::data::{read_recording, DataError, Format, Plane, ReadOptions, Recording};
use std::path::{Path, PathBuf};

type Row = (f64, Option<[f64; 2]>, Option<[f64; 2]>);

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

fn text(name: &str) -> String {
    let t = std::fs::read_to_string(data(name)).unwrap();
    t.trim_start_matches('\u{feff}').replace('\r', "")
}

fn read(names: &[&str], opts: ReadOptions) -> Result<Recording, DataError> {
    let paths: Vec<PathBuf> = names.iter().map(|n| data(n)).collect();
    read_recording(&paths, &opts)
}

fn with(slider: &str, bob: &str) -> ReadOptions {
    ReadOptions {
        slider: Some(slider.into()),
        bob: Some(bob.into()),
        ..ReadOptions::default()
    }
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs()).max(1e-300) || a == b
}

/// A number as the file writes it: decimal comma allowed, empty or nan is missing.
fn num(cell: &str) -> Option<f64> {
    let c = cell.trim().trim_matches('"').replace(',', ".");
    if c.is_empty() || c.eq_ignore_ascii_case("nan") {
        None
    } else {
        Some(c.parse().unwrap_or_else(|_| panic!("number {cell:?}")))
    }
}

fn pt(x: Option<f64>, y: Option<f64>) -> Option<[f64; 2]> {
    Some([x?, y?])
}

/// Compare every frame: times to 1e-9 relative (or 1e-12 s), positions to 1e-12 relative.
fn check(rec: &Recording, want: &[Row]) {
    assert_eq!(rec.len(), want.len(), "frame count");
    for (i, w) in want.iter().enumerate() {
        assert!(
            close(rec.times[i], w.0, 1e-9) || (rec.times[i] - w.0).abs() < 1e-12,
            "frame {i}: t {} != {}",
            rec.times[i],
            w.0
        );
        for (got, want, role) in [(rec.slider[i], w.1, "slider"), (rec.bob[i], w.2, "bob")] {
            match (got, want) {
                (None, None) => {}
                (Some(g), Some(e)) => assert!(
                    close(g[0], e[0], 1e-12) && close(g[1], e[1], 1e-12),
                    "frame {i} {role}: {g:?} != {e:?}"
                ),
                _ => panic!("frame {i} {role}: {got:?} != {want:?}"),
            }
        }
    }
}

/// Rows with both markers in columns `s` and `b` (x, y indices) of delimited lines, the time
/// from `time(cells, row index)`, positions mapped by `map`.
fn rows(
    lines: &[&str],
    delim: char,
    time: impl Fn(&[&str], usize) -> f64,
    s: [usize; 2],
    b: [usize; 2],
    map: impl Fn([f64; 2]) -> [f64; 2],
) -> Vec<Row> {
    lines
        .iter()
        .filter(|l| !l.trim().is_empty())
        .enumerate()
        .map(|(k, l)| {
            let c: Vec<&str> = l.split(delim).collect();
            let p = |ix: [usize; 2]| pt(num(c[ix[0]]), num(c[ix[1]])).map(&map);
            (time(&c, k), p(s), p(b))
        })
        .collect()
}

/// Merge two single-marker tracks (time, point) on the union of their times.
fn merge(a: &[(f64, Option<[f64; 2]>)], b: &[(f64, Option<[f64; 2]>)]) -> Vec<Row> {
    let mut t: Vec<f64> = a.iter().chain(b).map(|r| r.0).collect();
    t.sort_by(f64::total_cmp);
    t.dedup();
    let at = |v: &[(f64, Option<[f64; 2]>)], t: f64| v.iter().find(|r| r.0 == t).and_then(|r| r.1);
    t.iter().map(|&t| (t, at(a, t), at(b, t))).collect()
}

/// Two tracks of one video exported apart: each time of `b` within half a frame (the 30 fps
/// video's 1/30 s) of a time of `a` is that frame's time (the exports round the times their
/// own way); then merged on the union of the times.
fn merge_frames(
    a: &[(f64, Option<[f64; 2]>)],
    b: &[(f64, Option<[f64; 2]>)],
    frame: f64,
) -> Vec<Row> {
    let snapped: Vec<(f64, Option<[f64; 2]>)> = b
        .iter()
        .map(|&(t, p)| {
            let near = a
                .iter()
                .map(|r| r.0)
                .min_by(|x, y| (x - t).abs().total_cmp(&(y - t).abs()))
                .unwrap();
            (
                (if (near - t).abs() < frame / 2.0 {
                    near
                } else {
                    t
                }),
                p,
            )
        })
        .collect();
    merge(a, &snapped)
}

fn t0(rows: &mut [Row]) {
    let t0 = rows[0].0;
    for r in rows {
        r.0 -= t0;
    }
}

#[test]
fn tracker_exports_without_a_name_row_and_with_subscripts_read_in_file_order_and_joined_by_frame() {
    let track = |name: &str| -> Vec<(f64, Option<[f64; 2]>)> {
        let t = text(name);
        t.lines()
            .skip(1)
            .filter(|l| !l.trim().is_empty())
            .map(|l| {
                let c: Vec<&str> = l.split('\t').collect();
                (num(c[0]).unwrap(), pt(num(c[1]), num(c[2])))
            })
            .collect()
    };
    let a = track("tracker_jiarui_8047_noname.txt");
    let b = track("tracker_jiarui_8048_subscript.txt");
    let rec = read(
        &[
            "tracker_jiarui_8047_noname.txt",
            "tracker_jiarui_8048_subscript.txt",
        ],
        ReadOptions::default(),
    )
    .unwrap();
    assert_eq!(rec.provenance.format, Some(Format::Tracker));
    assert!(rec
        .provenance
        .notes
        .iter()
        .any(|n| n.contains("file order")));
    // Their times differ by rounding (up to 1/20 of a frame): one video's frames, joined.
    check(&rec, &merge_frames(&a, &b, 1.0 / 30.0));
    let both = rec
        .slider
        .iter()
        .zip(&rec.bob)
        .filter(|(s, b)| s.is_some() && b.is_some())
        .count();
    assert_eq!(both, b.iter().filter(|r| r.1.is_some()).count());
    assert!(rec
        .provenance
        .notes
        .iter()
        .any(|n| n.contains("less than half a frame")));
}

#[test]
fn two_tracker_files_both_named_mass_a_are_read_in_file_order() {
    let dir = tempfile::tempdir().unwrap();
    let mut paths = Vec::new();
    let mut tracks = Vec::new();
    for name in ["tracker_slider.txt", "tracker_bob.txt"] {
        let t = text(name);
        let renamed = format!("mass_A\n{}", t.split_once('\n').unwrap().1);
        let p = dir.path().join(name);
        std::fs::write(&p, &renamed).unwrap();
        paths.push(p);
        tracks.push(
            renamed
                .lines()
                .skip(2)
                .map(|l| {
                    let c: Vec<&str> = l.split('\t').collect();
                    (num(c[0]).unwrap(), pt(num(c[1]), num(c[2])))
                })
                .collect::<Vec<_>>(),
        );
    }
    let rec = read_recording(&paths, &ReadOptions::default()).unwrap();
    check(&rec, &merge(&tracks[0], &tracks[1]));
}

#[test]
fn tracker_multi_track_export_reads_each_track() {
    let t = text("DERIVED_tracker6_multitrack_layout.tsv");
    let lines: Vec<&str> = t.lines().skip(3).collect();
    let want = rows(
        &lines,
        '\t',
        |c, _| num(c[0]).unwrap(),
        [1, 2],
        [3, 4],
        |p| p,
    );
    let rec = read(
        &["DERIVED_tracker6_multitrack_layout.tsv"],
        ReadOptions::default(),
    )
    .unwrap();
    assert_eq!(rec.provenance.slider_name, "slider");
    check(&rec, &want);
}

/// Markers 1036 and 1037 of the real Motive export, written out from its text: t = frame /
/// 360 Hz, millimetres to metres.
fn motive_1036_1037(t: &str) -> Vec<Row> {
    let lines: Vec<&str> = t.lines().skip(7).collect();
    rows(
        &lines,
        ',',
        |c, _| num(c[0]).unwrap() / 360.0,
        [2, 3],
        [5, 6],
        |p| [p[0] / 1000.0, p[1] / 1000.0],
    )
}

#[test]
fn motive_times_come_from_frame_and_export_rate() {
    let t = text("motive_v1.23_ha5dzs_markers_mm_360Hz.csv");
    let want = motive_1036_1037(&t);
    let rec = read(
        &["motive_v1.23_ha5dzs_markers_mm_360Hz.csv"],
        with("Unlabeled 1036", "Unlabeled 1037"),
    )
    .unwrap();
    check(&rec, &want);
}

#[test]
fn motive_export_without_markers_says_it_holds_no_marker_data() {
    let e = read(
        &["motive_v1.23_ha5dzs_default_nodata.csv"],
        ReadOptions::default(),
    )
    .unwrap_err();
    assert!(e.to_string().contains("no marker data"), "{e}");
}

#[test]
fn qualisys_tsv_reads_millimetres_in_the_xz_plane() {
    let t = text("qualisys_qtm_reiv27_Measurement1.tsv");
    let lines: Vec<&str> = t
        .lines()
        .skip_while(|l| !l.starts_with("Frame"))
        .skip(1)
        .collect();
    let want = rows(
        &lines,
        '\t',
        |c, _| (num(c[0]).unwrap() - 1.0) / 100.0,
        [2, 4],
        [5, 7],
        |p| [p[0] / 1000.0, p[1] / 1000.0],
    );
    let rec = read(
        &["qualisys_qtm_reiv27_Measurement1.tsv"],
        with("New 0000", "New 0002"),
    )
    .unwrap();
    assert_eq!(rec.provenance.format, Some(Format::Qualisys));
    check(&rec, &want);
}

/// DeepLabCut-style CSV (3 or 4 header rows): columns of the two markers, frames from the row
/// (or the index), pixels flipped to y up, points under the likelihood missing.
fn dlc_want(
    name: &str,
    header_rows: usize,
    s: usize,
    b: usize,
    lik: Option<f64>,
    fps: f64,
) -> Vec<Row> {
    let t = text(name);
    t.lines()
        .skip(header_rows)
        .filter(|l| !l.trim().is_empty())
        .enumerate()
        .map(|(k, l)| {
            let c: Vec<&str> = l.split(',').collect();
            let frame = c[0].parse::<f64>().unwrap_or(k as f64);
            let p = |j: usize| {
                let p = pt(num(c[j]), num(c[j + 1]))?;
                if lik.is_some_and(|min| num(c[j + 2]).unwrap_or(0.0) < min) {
                    return None;
                }
                Some([p[0], -p[1]])
            };
            (frame / fps, p(s), p(b))
        })
        .collect()
}

fn px(slider: &str, bob: &str) -> ReadOptions {
    ReadOptions {
        fps: Some(30.0),
        scale: Some(1.0),
        ..with(slider, bob)
    }
}

#[test]
fn deeplabcut_outputs_and_labelled_data_read_row_for_row() {
    let cases = [
        // Every point of this one is under the default likelihood 0.6.
        (
            "dlc_movementdata_mouse_single.csv",
            3,
            "snout",
            1,
            "left_ear",
            4,
            Some(0.0),
        ),
        (
            "dlc_movementdata_mouse_multi_4row.csv",
            4,
            "individual1/snout",
            1,
            "individual1/leftear",
            4,
            Some(0.6),
        ),
        (
            "dlc_reachingvideo1shortDLC_resnet50_TESTNov4shuffle1_10.csv",
            3,
            "bodypart1",
            1,
            "bodypart2",
            4,
            Some(0.6),
        ),
        (
            "dlc_labeled_CollectedData_Mackenzie.csv",
            3,
            "Hand",
            1,
            "Finger1",
            3,
            None,
        ),
    ];
    for (name, hdr, s, sc, b, bc, lik) in cases {
        let opts = ReadOptions {
            min_likelihood: lik.unwrap_or(0.6),
            ..px(s, b)
        };
        let rec = read(&[name], opts).unwrap_or_else(|e| panic!("{e}"));
        check(&rec, &dlc_want(name, hdr, sc, bc, lik, 30.0));
    }
    // Lightning Pose writes the same layout.
    let t = text("lightningpose_movementdata_mouse_twoview.csv");
    let parts: Vec<&str> = t.lines().nth(1).unwrap().split(',').collect();
    let rec = read(
        &["lightningpose_movementdata_mouse_twoview.csv"],
        px(parts[1], parts[4]),
    )
    .unwrap();
    check(
        &rec,
        &dlc_want(
            "lightningpose_movementdata_mouse_twoview.csv",
            3,
            1,
            4,
            Some(0.6),
            30.0,
        ),
    );
}

#[test]
fn deeplabcut_3d_file_without_any_position_says_so() {
    let e = read(&["dlc3d_vid1_DLC_3D.csv"], px("bodypart1", "bodypart2")).unwrap_err();
    assert!(e.to_string().contains("never with a position"), "{e}");
}

#[test]
fn anipose_3d_columns_are_projected_on_the_chosen_plane() {
    let t = text("anipose_movementdata_mouse_paw.csv");
    let header: Vec<&str> = t.lines().next().unwrap().split(',').collect();
    let col = |n: &str| header.iter().position(|h| *h == n).unwrap();
    let (sx, sz, bx, bz, f) = (
        col("l-base_x"),
        col("l-base_z"),
        col("l-edge_x"),
        col("l-edge_z"),
        col("fnum"),
    );
    let lines: Vec<&str> = t.lines().skip(1).collect();
    let mut want: Vec<Row> = lines
        .iter()
        .map(|l| {
            let c: Vec<&str> = l.split(',').collect();
            let p = |x: usize, z: usize| {
                let y = num(c[x + 1]);
                pt(num(c[x]), num(c[z]).and(y).and(num(c[z])))
            };
            (num(c[f]).unwrap() / 30.0, p(sx, sz), p(bx, bz))
        })
        .collect();
    t0(&mut want);
    let rec = read(
        &["anipose_movementdata_mouse_paw.csv"],
        ReadOptions {
            plane: Some(Plane::Xz),
            ..px("l-base", "l-edge")
        },
    )
    .unwrap();
    check(&rec, &want);
}

#[test]
fn idtracker_trajectories_read_with_nan_as_missing() {
    let t = text("idtrackerai_movementdata_trajectories.csv");
    let lines: Vec<&str> = t.lines().skip(1).collect();
    let want = rows(
        &lines,
        ',',
        |c, _| num(c[0]).unwrap(),
        [1, 2],
        [3, 4],
        |p| [p[0], -p[1]],
    );
    let rec = read(
        &["idtrackerai_movementdata_trajectories.csv"],
        ReadOptions {
            scale: Some(1.0),
            ..with("1", "2")
        },
    )
    .unwrap();
    check(&rec, &want);
}

#[test]
fn kinovea_text_export_reads_each_trajectory_block() {
    let t = text("kinovea_gnuplot_anaaim_pas_camera_01.txt");
    let block = |name: &str| -> Vec<(f64, Option<[f64; 2]>)> {
        t.split(&format!("# {name}\n"))
            .nth(1)
            .unwrap()
            .lines()
            .take_while(|l| !l.trim().is_empty())
            .map(|l| {
                let c: Vec<&str> = l.split_whitespace().collect();
                (num(c[0]).unwrap(), pt(num(c[1]), num(c[2])))
            })
            .collect()
    };
    let rec = read(
        &["kinovea_gnuplot_anaaim_pas_camera_01.txt"],
        ReadOptions {
            scale: Some(1.0),
            ..with("tarse", "jarret")
        },
    )
    .unwrap();
    assert_eq!(rec.provenance.format, Some(Format::Kinovea));
    check(&rec, &merge(&block("tarse"), &block("jarret")));
}

#[test]
fn sleap_analysis_csv_reads_its_nodes() {
    let t = text("sleap_analysis_minimal_instance.csv");
    let lines: Vec<&str> = t.lines().skip(1).collect();
    let want = rows(
        &lines,
        ',',
        |c, _| num(c[1]).unwrap() / 30.0,
        [3, 4],
        [6, 7],
        |p| [p[0], -p[1]],
    );
    let rec = read(&["sleap_analysis_minimal_instance.csv"], px("A", "B")).unwrap();
    assert_eq!(rec.provenance.format, Some(Format::Sleap));
    check(&rec, &want);
}

#[test]
fn trex_csv_reads_centimetres_with_microsecond_stamps() {
    let t = text("trex_movementdata_beetle.csv");
    let header: Vec<&str> = t.lines().next().unwrap().split(',').collect();
    let col = |n: &str| header.iter().position(|h| *h == n).unwrap();
    let (x, y, mx, my, ts) = (
        col("X (cm)"),
        col("Y (cm)"),
        col("midline_x"),
        col("midline_y"),
        col("timestamp"),
    );
    let lines: Vec<&str> = t.lines().skip(1).collect();
    let mut want = rows(
        &lines,
        ',',
        |c, _| num(c[ts]).unwrap() * 1e-6,
        [x, y],
        [mx, my],
        |p| [p[0] / 100.0, -p[1] / 100.0],
    );
    t0(&mut want);
    let rec = read(
        &["trex_movementdata_beetle.csv"],
        with("centroid", "midline"),
    )
    .unwrap();
    check(&rec, &want);
}

#[test]
fn mcap_files_without_marker_data_say_so_and_list_their_channels() {
    for (name, channel) in [
        ("mcap_json_foxglove_tutorial.mcap", "speed"),
        ("mcap_ros2_rosbag2_cdr_test_0.mcap", "/test_topic"),
        ("mcap_ros2_rosbag2_talker.mcap", "/rosout"),
    ] {
        let e = read(&[name], ReadOptions::default()).unwrap_err();
        assert!(
            matches!(e, DataError::NoMarkerChannel { .. }),
            "{name}: {e}"
        );
        assert!(e.to_string().contains(channel), "{e}");
    }
}

#[test]
fn tracker_projects_give_point_mass_positions_or_say_a_model_has_no_data() {
    // BallToss: one point mass (the ball), positions in metres through the project's
    // coordinate system; one track cannot be both markers, so pair it with itself shifted.
    let t = text("tracker_trk_BallToss.trk");
    let pm = &t[t.find("PointMass").unwrap()..];
    let values = |tag: &str| -> Vec<f64> {
        pm.split(&format!("<property name=\"{tag}\" type=\"double\">"))
            .skip(1)
            .map(|s| s.split('<').next().unwrap().parse().unwrap())
            .collect()
    };
    let (xs, ys) = (values("x"), values("y"));
    assert_eq!(xs.len(), 11);
    let e = read(&["tracker_trk_BallToss.trk"], ReadOptions::default()).unwrap_err();
    assert!(e.to_string().contains("holds one track"), "{e}");
    let dir = tempfile::tempdir().unwrap();
    let copy = dir.path().join("second.trk");
    std::fs::write(
        &copy,
        t.replace(
            "<property name=\"name\" type=\"string\">ball<",
            "<property name=\"name\" type=\"string\">ball2<",
        ),
    )
    .unwrap();
    let rec = read_recording(
        &[data("tracker_trk_BallToss.trk"), copy],
        &ReadOptions::default(),
    )
    .unwrap();
    // The coordinate system: origin (131.28, 207.86) px, angle 0.044 rad, 398.7 px per metre.
    let (x0, y0, a, s): (f64, f64, f64, f64) = (
        131.2767066180302,
        207.85825951016153,
        0.04401895816986783,
        398.70891559670895,
    );
    let want: Vec<Row> = xs
        .iter()
        .zip(&ys)
        .enumerate()
        .map(|(k, (&x, &y))| {
            let (dx, dy) = (x - x0, y - y0);
            let p = [
                (dx * a.cos() - dy * a.sin()) / s,
                (-dx * a.sin() - dy * a.cos()) / s,
            ];
            (k as f64 * 0.066, Some(p), Some(p))
        })
        .collect();
    check(&rec, &want);
    let e = read(&["tracker_trk_asinewave.trk"], ReadOptions::default()).unwrap_err();
    assert!(e.to_string().contains("formulas, not data"), "{e}");
}

#[test]
fn sleap_analysis_hdf5_matches_the_values_h5py_reads() {
    // The reference was written by scripts/fixtures/sleap_h5_reference.py with h5py (the HDF5 C
    // library), independently of the pure-Rust reader.
    let t = text("sleap_three-mice_Aeon.analysis.reference.csv");
    let lines: Vec<&str> = t.lines().skip(1).collect();
    let want = rows(
        &lines,
        ',',
        |c, _| num(c[0]).unwrap() / 50.0,
        [1, 2],
        [3, 4],
        |p| [p[0], -p[1]],
    );
    let rec = read(
        &["sleap_three-mice_Aeon.analysis.h5"],
        ReadOptions {
            fps: Some(50.0),
            ..px("AEON3B_NTP/centroid", "AEON3B_TP1/centroid")
        },
    )
    .unwrap();
    assert_eq!(rec.provenance.format, Some(Format::Sleap));
    check(&rec, &want);
}

#[test]
fn kinovea_spreadsheet_export_reads_its_tracks_with_rows_numbered_at_fps() {
    let t = text("kinovea_excelxml_pariterre_box_jump.xml");
    // Each <Row>'s <Data> texts, in order.
    let rows: Vec<Vec<String>> = t
        .split("<Row")
        .skip(1)
        .map(|r| {
            r.split("<Data")
                .skip(1)
                .map(|d| {
                    let (head, rest) = d.split_once('>').unwrap();
                    if head.ends_with('/') {
                        String::new()
                    } else {
                        rest.split("</Data>").next().unwrap().trim().to_string()
                    }
                })
                .collect()
        })
        .collect();
    let track = |name: &str| -> Vec<(f64, Option<[f64; 2]>)> {
        let start = rows
            .iter()
            .position(|r| r.len() >= 2 && r[0] == "Label :" && r[1] == name)
            .unwrap();
        let hms = |s: &str| {
            let p: Vec<f64> = s.split(':').map(|v| v.parse().unwrap()).collect();
            p[0] * 3600.0 + p[1] * 60.0 + p[2] + p[3] / 100.0
        };
        let data: Vec<&Vec<String>> = rows[start + 3..]
            .iter()
            .take_while(|r| r.iter().any(|c| !c.is_empty()) && r[0] != "Track")
            .collect();
        let t0 = hms(&data[0][2]);
        data.iter()
            .enumerate()
            .map(|(k, r)| {
                (
                    t0 + k as f64 / 24.0,
                    pt(num(&r[0]), num(&r[1])).map(|p| [p[0] / 100.0, p[1] / 100.0]),
                )
            })
            .collect()
    };
    let rec = read(
        &["kinovea_excelxml_pariterre_box_jump.xml"],
        ReadOptions {
            fps: Some(24.0),
            ..with("Hanche", "Genou")
        },
    )
    .unwrap();
    assert_eq!(rec.provenance.format, Some(Format::Kinovea));
    let mut want = merge(&track("Hanche"), &track("Genou"));
    t0(&mut want);
    check(&rec, &want);
    // Without --fps the rounded times repeat: the error says what to give.
    let e = read(
        &["kinovea_excelxml_pariterre_box_jump.xml"],
        with("Hanche", "Genou"),
    )
    .unwrap_err();
    assert!(e.to_string().contains("--fps"), "{e}");
}

#[test]
fn ros2_tf_is_composed_to_the_tree_root_as_an_independent_decoder_composes_it() {
    // Reference: scripts/fixtures/tf_reference.py (the official mcap-ros2-support decoder and
    // numpy).
    let t = text("mcap_ros2_evo_nav2_turtlebot_tf.reference.csv");
    let lines: Vec<&str> = t.lines().skip(1).collect();
    let want = rows(
        &lines,
        ',',
        |c, _| num(c[0]).unwrap(),
        [1, 2],
        [3, 4],
        |p| p,
    );
    let rec = read(
        &["mcap_ros2_evo_nav2_turtlebot_tf.mcap"],
        with("base_link", "front_caster_link"),
    )
    .unwrap();
    assert!(rec.provenance.notes.iter().any(|n| n.contains("\"map\"")));
    check(&rec, &want);
}

/// DeepLabCut's marker names in the order of a CSV's columns (`individual/bodypart` when the
/// header has an individuals row), parsed here from the header alone.
fn dlc_markers(csv: &str, header_rows: usize) -> Vec<String> {
    let t = text(csv);
    let rows: Vec<Vec<&str>> = t
        .lines()
        .take(header_rows)
        .map(|l| l.split(',').collect())
        .collect();
    let (parts, inds) = (&rows[header_rows - 2], (header_rows == 4).then(|| &rows[1]));
    let mut names: Vec<String> = Vec::new();
    for j in 1..parts.len() {
        let name = match inds {
            Some(i) if !i[j].is_empty() && i[j] != "single" => format!("{}/{}", i[j], parts[j]),
            _ => parts[j].to_string(),
        };
        if !names.contains(&name) {
            names.push(name);
        }
    }
    names
}

/// The HDF5 files DeepLabCut writes (tests/data/make_dlc_h5.py made these from the CSVs as
/// DeepLabCut does): each with its source CSV and header rows.
const DLC_H5: [(&str, &str, usize); 4] = [
    (
        "dlc_reachingvideo1shortDLC_resnet50_TESTNov4shuffle1_10.h5",
        "dlc_reachingvideo1shortDLC_resnet50_TESTNov4shuffle1_10.csv",
        3,
    ),
    (
        "dlc_movementdata_mouse_multi_4row.h5",
        "dlc_movementdata_mouse_multi_4row.csv",
        4,
    ),
    (
        "dlc_labeled_CollectedData_Mackenzie.h5",
        "dlc_labeled_CollectedData_Mackenzie.csv",
        3,
    ),
    (
        "dlc_labeled_CollectedData_Mackenzie_fixed.h5",
        "dlc_labeled_CollectedData_Mackenzie.csv",
        3,
    ),
];

#[test]
fn deeplabcut_hdf5_converts_as_its_source_csv_for_every_marker() {
    for (h5, csv, hdr) in DLC_H5 {
        let markers = dlc_markers(csv, hdr);
        assert!(markers.len() >= 4, "{csv}: {markers:?}");
        let mut compared = 0;
        for (k, s) in markers.iter().enumerate() {
            let b = &markers[(k + 1) % markers.len()];
            for min_likelihood in [0.6, 0.0] {
                let opts = ReadOptions {
                    min_likelihood,
                    ..px(s, b)
                };
                match (read(&[h5], opts.clone()), read(&[csv], opts)) {
                    (Ok(a), Ok(c)) => {
                        let canonical = |r: &Recording| {
                            let mut out = Vec::new();
                            r.write_csv(&mut out).unwrap();
                            String::from_utf8(out).unwrap()
                        };
                        assert_eq!(canonical(&a), canonical(&c), "{h5}: {s}, {b}");
                        assert_eq!(a.provenance.format, Some(Format::DeepLabCut));
                        assert!(a.provenance.detected);
                        assert_eq!(a.provenance.notes, c.provenance.notes, "{h5}");
                        assert_eq!(a.provenance.warnings, c.provenance.warnings, "{h5}");
                        compared += 1;
                    }
                    (Err(a), Err(c)) => {
                        assert_eq!(a.to_string().replace(h5, csv), c.to_string(), "{h5}");
                    }
                    (a, c) => panic!("{h5}: {s}, {b}: {:?} but the CSV {:?}", a.err(), c.err()),
                }
            }
        }
        assert!(
            compared >= markers.len(),
            "{h5}: only {compared} pairs read"
        );
    }
}

#[test]
fn deeplabcut_hdf5_holds_the_values_of_its_source_csv() {
    // The first two markers' columns in the CSV, parsed here; their likelihood follows x, y
    // where the file has one.
    for (h5, csv, hdr) in DLC_H5 {
        let markers = dlc_markers(csv, hdr);
        let labelled = csv.contains("labeled");
        let (bc, lik) = if labelled { (3, None) } else { (4, Some(0.6)) };
        let rec = read(&[h5], px(&markers[0], &markers[1])).unwrap();
        check(&rec, &dlc_want(csv, hdr, 1, bc, lik, 30.0));
        assert!(rec.slider.iter().flatten().count() > 0, "{h5}");
    }
}

#[test]
fn deeplabcut_hdf5_with_other_columns_than_x_y_likelihood_says_which() {
    let e = read(
        &["DERIVED_dlc_coords_x_y_speed.h5"],
        px("bodypart1", "bodypart2"),
    )
    .unwrap_err()
    .to_string();
    for part in [
        "DERIVED_dlc_coords_x_y_speed.h5",
        "/df_with_missing/table attribute values_block_0_kind",
        "coords column 3",
        "expected x, y, z or likelihood",
        "\"speed\"",
    ] {
        assert!(e.contains(part), "{part:?} not in {e}");
    }
}

#[test]
fn truncated_deeplabcut_hdf5_is_an_error_naming_the_file_never_a_panic() {
    let name = "dlc_movementdata_mouse_multi_4row.h5";
    let whole = std::fs::read(data(name)).unwrap();
    let opts = px("individual1/snout", "individual1/leftear");
    let label = Path::new("cut.h5");
    let mut errors = 0;
    for n in (0..whole.len()).step_by(211) {
        if let Err(e) = appell::data::read_recording_bytes(&whole[..n], label, &opts) {
            assert!(e.to_string().starts_with("cut.h5: "), "{n}: {e}");
            errors += 1;
        }
    }
    assert!(errors > 100, "{errors}");
    // Through the command line: exit code 2 and one line that names the file and the field.
    let dir = tempfile::tempdir().unwrap();
    let cut = dir.path().join("cut.h5");
    std::fs::write(&cut, &whole[..20_000]).unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_appell"))
        .args(["convert", cut.to_str().unwrap()])
        .arg(dir.path().join("out.csv"))
        .args(["--fps", "30", "--scale", "1"])
        .args([
            "--slider",
            "individual1/snout",
            "--bob",
            "individual1/leftear",
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    assert!(
        err.contains("cut.h5: /df_with_missing/table: table: expected a readable dataset"),
        "{err}"
    );
}

#[test]
fn deeplabcut_hdf5_with_bytes_changed_reads_or_errs_never_panics() {
    // A fixed pseudo-random walk over the files: set one byte, read, restore.
    let n: usize = std::env::var("APPELL_H5_MUTATIONS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(300);
    let mut seed = 0x9e37_79b9_7f4a_7c15_u64;
    for (h5, _, _) in DLC_H5 {
        let mut bytes = std::fs::read(data(h5)).unwrap();
        let opts = ReadOptions {
            fps: Some(30.0),
            scale: Some(1.0),
            ..ReadOptions::default()
        };
        for _ in 0..n {
            seed = seed
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            let at = (seed >> 33) as usize % bytes.len();
            let old = bytes[at];
            bytes[at] = (seed >> 13) as u8;
            let _ = appell::data::read_recording_bytes(&bytes, Path::new("m.h5"), &opts);
            bytes[at] = old;
        }
    }
}

#[test]
fn deeplabcut_hdf5_declaring_more_rows_than_it_holds_is_refused_before_reading() {
    // The table's dataspace: 12 rows, unlimited at most; declare 2^40 rows instead.
    let name = "dlc_reachingvideo1shortDLC_resnet50_TESTNov4shuffle1_10.h5";
    let mut bytes = std::fs::read(data(name)).unwrap();
    let dims = [12u64.to_le_bytes(), [0xff; 8]].concat();
    let at: Vec<usize> = (0..bytes.len() - 16)
        .filter(|&i| bytes[i..i + 16] == dims[..])
        .collect();
    assert_eq!(at.len(), 1, "the table's dataspace");
    bytes[at[0]..at[0] + 8].copy_from_slice(&(1u64 << 40).to_le_bytes());
    let e = appell::data::read_recording_bytes(
        &bytes,
        Path::new("huge.h5"),
        &px("bodypart1", "bodypart2"),
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.starts_with("huge.h5: /df_with_missing/table: table: expected at most"),
        "{e}"
    );
    assert!(e.contains("times the file's size"), "{e}");
}

/// The real Motive export with markers split the way Motive splits a marker it loses and
/// finds again: the columns of `old` keep frames before `at`, a new column `new` (appended)
/// holds frames from `at + gap` on, shifted by `shift` (file units, X), and the frames
/// between are missing everywhere.
fn motive_split(t: &str, splits: &[(&str, &str, usize, usize, f64)]) -> String {
    let lines: Vec<&str> = t.lines().collect();
    let names: Vec<&str> = lines[3].split(',').collect();
    let mut out: Vec<String> = lines.iter().map(|l| l.to_string()).collect();
    for &(old, new, at, gap, shift) in splits {
        let j = names.iter().position(|n| *n == old).expect("marker column");
        for (k, extra) in [(2, "Marker"), (3, new), (4, "\"X\""), (5, "Position")] {
            out[k].push_str(&format!(",{extra},{extra},{extra}"));
        }
        out[6].push_str(",X,Y,Z");
        for (i, line) in out.iter_mut().enumerate().skip(7) {
            let frame = i - 7;
            let mut c: Vec<String> = line.split(',').map(str::to_string).collect();
            let xyz: Vec<String> = c[j..j + 3].to_vec();
            if frame >= at {
                c[j..j + 3].iter_mut().for_each(|v| v.clear());
            }
            let moved: Vec<String> = if frame >= at + gap {
                let x: f64 = xyz[0].parse().unwrap();
                vec![format!("{}", x + shift), xyz[1].clone(), xyz[2].clone()]
            } else {
                vec![String::new(); 3]
            };
            c.extend(moved);
            *line = c.join(",");
        }
    }
    out.join("\n") + "\n"
}

/// Motive renames a marker it loses and finds again, so one track becomes two columns. A
/// reader that keeps them apart loses the bob at the first dropout. Split the real export's
/// "Unlabeled 1037" at frame 600, back as "Unlabeled 1054" at frame 610: read under the old
/// name it is the whole track again, with the ten frames missing, and a note names both.
/// "Unlabeled 1040", split the same way but back 500 mm from where it was heading, is a new
/// marker and stays apart.
#[test]
fn motive_renamed_unlabeled_marker_is_joined_only_where_it_was_heading() {
    let t = text("motive_v1.23_ha5dzs_markers_mm_360Hz.csv");
    let split = motive_split(
        &t,
        &[
            ("Unlabeled 1037", "Unlabeled 1054", 600, 10, 0.0),
            ("Unlabeled 1040", "Unlabeled 1055", 800, 10, 500.0),
        ],
    );
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("motive_split.csv");
    std::fs::write(&path, split).unwrap();
    let mut want = motive_1036_1037(&t);
    for row in &mut want[600..610] {
        row.2 = None;
    }
    let rec = read_recording(
        std::slice::from_ref(&path),
        &with("Unlabeled 1036", "Unlabeled 1037"),
    )
    .unwrap();
    check(&rec, &want);
    let notes = rec.provenance.notes.join("\n");
    assert!(
        notes
            .contains("\"Unlabeled 1037\" continues as \"Unlabeled 1054\" after 10 missing frames"),
        "{notes}"
    );
    assert!(!notes.contains("Unlabeled 1055"), "{notes}");
    // Asked for by its later name, the joined marker is the same whole track.
    let later = read_recording(
        std::slice::from_ref(&path),
        &with("Unlabeled 1036", "Unlabeled 1054"),
    )
    .unwrap();
    assert_eq!(later.bob, rec.bob);
    // The far one is still its own marker: readable under its new name, from frame 810.
    let far = read_recording(
        std::slice::from_ref(&path),
        &with("Unlabeled 1036", "Unlabeled 1055"),
    )
    .unwrap();
    let first = far.bob.iter().position(Option::is_some).unwrap();
    assert_eq!(first, 810);
    // The export as Motive wrote it has no such pair: nothing is joined.
    let rec = read(
        &["motive_v1.23_ha5dzs_markers_mm_360Hz.csv"],
        with("Unlabeled 1036", "Unlabeled 1037"),
    )
    .unwrap();
    assert!(
        !rec.provenance.notes.iter().any(|n| n.contains("continues")),
        "{:?}",
        rec.provenance.notes
    );
}
