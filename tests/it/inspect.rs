//! `appell inspect` (issue 38): on the real files, the format, the markers and their counts as
//! `convert`'s reading gives them, and `--fps` asked for exactly where that reading needs it; on
//! rig recordings, the slider and the bob found by their motion (also under other names, in the
//! wrong file order, upside down, in another plane), and the printed commands run as printed
//! once the upper-case placeholders are filled in.

use appell::data::{read_recording, ReadOptions};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn appell(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_appell"))
        .args(args)
        .output()
        .expect("run appell")
}

/// The command ended well; else the test fails with its stderr.
fn ok(out: &Output, what: &str) {
    assert!(
        out.status.success(),
        "{what}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

fn root(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

fn s(p: &Path) -> String {
    p.display().to_string()
}

/// `appell inspect FILES... --json [FLAGS]` for one recording: its JSON object.
fn inspect(files: &[&Path], flags: &[&str]) -> Value {
    let mut args = vec!["inspect".to_string()];
    args.extend(files.iter().map(|f| s(f)));
    args.push("--json".into());
    args.extend(flags.iter().map(|f| f.to_string()));
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let out = appell(&args);
    ok(&out, &format!("{args:?}"));
    serde_json::from_slice(&out.stdout).unwrap_or_else(|e| panic!("{args:?}: {e}"))
}

/// The flags of every suggestion, as `--flag` names.
fn suggested(v: &Value) -> Vec<String> {
    v["suggestions"]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|s| s["flags"].as_array().unwrap().iter())
        .map(|f| f[0].as_str().unwrap().to_string())
        .collect()
}

/// A command line split as a POSIX shell splits it (single quotes, `'\''`).
fn shell_words(line: &str) -> Vec<String> {
    let (mut words, mut word, mut quoted, mut any) = (Vec::new(), String::new(), false, false);
    let mut chars = line.chars();
    while let Some(c) = chars.next() {
        match c {
            '\'' => {
                quoted = !quoted;
                any = true;
            }
            '\\' if !quoted => word.extend(chars.next()),
            ' ' if !quoted => {
                if any || !word.is_empty() {
                    words.push(std::mem::take(&mut word));
                }
                any = false;
            }
            c => word.push(c),
        }
    }
    if any || !word.is_empty() {
        words.push(word);
    }
    words
}

/// Run a printed command (without its leading `appell`), each upper-case placeholder replaced.
fn run_printed(command: &str, fill: &[(&str, String)]) -> Output {
    let words = shell_words(command);
    assert_eq!(words[0], "appell", "{command}");
    let args: Vec<String> = words[1..]
        .iter()
        .map(|w| {
            fill.iter()
                .find(|(k, _)| k == w)
                .map_or_else(|| w.clone(), |(_, v)| v.clone())
        })
        .collect();
    for w in &args {
        assert!(
            ![
                "FPS",
                "METRES",
                "SLIDER",
                "BOB",
                "RIG.toml",
                "OUT.csv",
                "OTHER_FILE"
            ]
            .contains(&w.as_str()),
            "placeholder {w} left in {command}"
        );
    }
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    appell(&args)
}

/// The real files of `tests/data` with markers (as `tests/data/README.md` lists them).
const REAL: [&str; 17] = [
    "tests/data/dlc_example.csv",
    "tests/data/dlc_movementdata_mouse_single.csv",
    "tests/data/dlc_movementdata_mouse_multi_4row.csv",
    "tests/data/dlc_movementdata_mouse_multi_4row.h5",
    "tests/data/dlc_labeled_CollectedData_Mackenzie.csv",
    "tests/data/dlc_labeled_CollectedData_Mackenzie.h5",
    "tests/data/dlc_reachingvideo1shortDLC_resnet50_TESTNov4shuffle1_10.h5",
    "tests/data/sleap_analysis_minimal_instance.csv",
    "tests/data/sleap_three-mice_Aeon.analysis.h5",
    "tests/data/motive_v1.23_ha5dzs_markers_mm_360Hz.csv",
    "tests/data/qualisys_qtm_reiv27_Measurement1.tsv",
    "tests/data/idtrackerai_movementdata_trajectories.csv",
    "tests/data/anipose_movementdata_mouse_paw.csv",
    "tests/data/tracker_jiarui_8047_noname.txt",
    "tests/data/kinovea_gnuplot_anaaim_pas_camera_01.txt",
    "tests/data/markers_ros2_pointstamped.mcap",
    "tests/data/mcap_ros2_evo_nav2_turtlebot_tf.mcap",
];

/// Every marker's frames as `convert` reads them: each marker read as the slider against
/// another as the bob (with a frame rate and a scale, which change no count); a Tracker file of
/// one track against the shipped slider track.
fn counts_by_convert(file: &Path, names: &[String]) -> Vec<Option<usize>> {
    let opts = |slider: &str, bob: &str| ReadOptions {
        slider: Some(slider.to_string()),
        bob: Some(bob.to_string()),
        fps: Some(30.0),
        scale: Some(1.0),
        ..ReadOptions::default()
    };
    if names.len() == 1 {
        let other = root("tests/data/tracker_slider.txt");
        // Two tracks that do not say which is which are read in file order, this one first.
        let rec = read_recording(&[file.to_owned(), other], &ReadOptions::default()).unwrap();
        return vec![Some(rec.seen().0)];
    }
    names
        .iter()
        .enumerate()
        .map(|(i, name)| {
            let other = &names[if i == 0 { 1 } else { 0 }];
            read_recording(&[file.to_owned()], &opts(name, other))
                .ok()
                .map(|r| r.seen().0)
        })
        .collect()
}

#[test]
fn real_files_name_their_format_and_markers_with_the_counts_convert_reads() {
    for rel in REAL {
        let file = root(rel);
        let v = inspect(&[&file], &[]);
        let format = appell::data::detect(&file).unwrap();
        assert_eq!(v["format"], format.name(), "{rel}");
        assert!(
            v["detection"]
                .as_str()
                .unwrap()
                .starts_with("detected from"),
            "{rel}"
        );
        let markers = v["markers"].as_array().unwrap();
        let names: Vec<String> = markers
            .iter()
            .map(|m| m["name"].as_str().unwrap().to_string())
            .collect();
        let counts = counts_by_convert(&file, &names);
        for (m, count) in markers.iter().zip(counts) {
            let seen = m["seen"].as_u64().unwrap() as usize;
            match count {
                Some(c) => assert_eq!(seen, c, "{rel}: {}", m["name"]),
                // `convert` refuses a marker that is named but never seen.
                None => assert_eq!(seen, 0, "{rel}: {}", m["name"]),
            }
        }
    }
}

/// The frame rates the files state in their headers (Motive's Export Frame Rate, QTM's
/// FREQUENCY) and the shipped example's 1 kHz.
#[test]
fn frame_rates_are_the_files_own() {
    for (rel, hz) in [
        ("tests/data/motive_v1.23_ha5dzs_markers_mm_360Hz.csv", 360.0),
        ("tests/data/qualisys_qtm_reiv27_Measurement1.tsv", 100.0),
        ("data/example_recording.mcap", 1000.0),
    ] {
        let v = inspect(&[&root(rel)], &[]);
        let rate = v["time"]["rate"].as_f64().unwrap();
        assert!((rate - hz).abs() < 1e-6 * hz, "{rel}: {rate}");
        assert_eq!(v["time"]["timed"], true, "{rel}");
    }
}

/// `--fps` is asked for exactly where `convert` refuses the file without it and reads it with
/// it.
#[test]
fn fps_is_asked_for_exactly_where_convert_needs_it() {
    let mut asked = 0;
    for rel in REAL {
        let file = root(rel);
        let v = inspect(&[&file], &[]);
        // Two markers that are seen, so that convert's reading can succeed.
        let names: Vec<String> = v["markers"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|m| m["seen"].as_u64().unwrap() > 0)
            .map(|m| m["name"].as_str().unwrap().to_string())
            .collect();
        if names.len() < 2 {
            continue;
        }
        let opts = |fps: Option<f64>| ReadOptions {
            slider: Some(names[0].clone()),
            bob: Some(names[1].clone()),
            fps,
            scale: Some(1.0),
            ..ReadOptions::default()
        };
        let needs = read_recording(std::slice::from_ref(&file), &opts(None)).is_err()
            && read_recording(std::slice::from_ref(&file), &opts(Some(30.0))).is_ok();
        let says = suggested(&v).contains(&"--fps".to_string());
        assert_eq!(says, needs, "{rel}");
        assert_eq!(v["time"]["timed"], !needs, "{rel}");
        asked += usize::from(needs);
    }
    assert!(asked >= 8, "{asked} files need --fps");
}

/// A lab's own markers on bodies (mice, a person, a robot's frames) are not taken for a rig.
#[test]
fn files_of_animals_and_people_show_no_rig() {
    let rigs = [
        "tests/data/dlc_example.csv",
        "tests/data/markers_ros2_pointstamped.mcap",
    ];
    for rel in REAL.iter().filter(|r| !rigs.contains(r)) {
        let v = inspect(&[&root(rel)], &[]);
        assert_eq!(v["rig"]["looks_like_rig"], false, "{rel}: {}", v["rig"]);
    }
}

/// The recordings of the rig: the slider and the bob found by their motion, and nothing
/// missing where the file says everything.
#[test]
fn rig_recordings_show_their_slider_and_bob() {
    let mut files: Vec<PathBuf> = std::fs::read_dir(root("tests/data/misspec"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "csv"))
        .collect();
    files.sort();
    assert_eq!(files.len(), 21);
    files.push(root("data/example_recording.mcap"));
    files.push(root("tests/data/markers_ros2_pointstamped.mcap"));
    for f in &files {
        let v = inspect(&[f], &[]);
        let pair = &v["pairs"][0];
        assert_eq!(pair["rig"], true, "{}: {pair}", f.display());
        assert!(pair["slider"].as_str().unwrap().ends_with("slider"));
        assert!(pair["bob"].as_str().unwrap().ends_with("bob"));
        assert_eq!(v["rig"]["looks_like_rig"], true);
        assert!(
            suggested(&v).is_empty(),
            "{}: {}",
            f.display(),
            v["suggestions"]
        );
    }
}

/// A scratch directory for files made by a test.
fn scratch() -> tempfile::TempDir {
    tempfile::Builder::new()
        .prefix("appell-inspect-")
        .tempdir()
        .unwrap()
}

/// `appell convert ARGS... OUTPUT`; the CSV it wrote.
fn convert(args: &[String], output: &Path) -> String {
    let mut args: Vec<&str> = args.iter().map(String::as_str).collect();
    let out_arg = s(output);
    args.insert(0, "convert");
    args.push(&out_arg);
    let out = appell(&args);
    ok(&out, &format!("{args:?}"));
    std::fs::read_to_string(output).unwrap()
}

/// The DeepLabCut example (pixels, no times, a camera tilted 3 degrees) needs --fps, the rod
/// length and the rail frame: the printed commands, filled in with its 100 Hz and 0.30 m,
/// convert it as the README's command does and fit it.
#[test]
fn the_dlc_example_runs_as_printed() {
    let file = root("tests/data/dlc_example.csv");
    let v = inspect(&[&file], &[]);
    assert_eq!(
        suggested(&v),
        ["--fps", "--rod-length", "--rail-frame"],
        "{}",
        v["suggestions"]
    );
    let dir = scratch();
    let (printed, readme) = (
        dir.path().join("printed.csv"),
        dir.path().join("readme.csv"),
    );
    let fill = [
        ("FPS", "100".to_string()),
        ("METRES", "0.30".to_string()),
        ("OUT.csv", s(&printed)),
        ("RIG.toml", s(&root("configs/markers_example.toml"))),
    ];
    let out = run_printed(v["convert_command"].as_str().unwrap(), &fill);
    ok(&out, "");
    let by_readme = convert(
        &[
            "--fps".into(),
            "100".into(),
            "--rod-length".into(),
            "0.30".into(),
            "--rail-frame".into(),
            s(&file),
        ],
        &readme,
    );
    assert_eq!(std::fs::read_to_string(&printed).unwrap(), by_readme);
    let fit = run_printed(v["fit_command"].as_str().unwrap(), &fill);
    ok(&fit, "");
}

/// The shipped Tracker pair, the example MCAP and a generated wide CSV need no flag: their
/// printed fit commands run with the rig filled in.
#[test]
fn metric_rig_recordings_fit_as_printed() {
    for (files, rig) in [
        (
            vec![
                root("tests/data/tracker_slider.txt"),
                root("tests/data/tracker_bob.txt"),
            ],
            "configs/markers_example.toml",
        ),
        (
            vec![root("data/example_recording.mcap")],
            "configs/rig_example.toml",
        ),
        (
            vec![root("tests/data/misspec/none_paper.csv")],
            "tests/data/misspec/paper_measured.toml",
        ),
    ] {
        let paths: Vec<&Path> = files.iter().map(PathBuf::as_path).collect();
        let v = inspect(&paths, &[]);
        assert!(suggested(&v).is_empty(), "{files:?}: {}", v["suggestions"]);
        let fit = run_printed(
            v["fit_command"].as_str().unwrap(),
            &[("RIG.toml", s(&root(rig)))],
        );
        ok(&fit, &format!("{files:?}"));
    }
}

/// A wide CSV of the paper rig written again by a test: the slider's and the bob's columns
/// under other names, a third, static marker (with noise), and optionally y reversed or the
/// motion put into the xz plane of 3-D columns.
fn rewritten(dir: &Path, name: &str, header: &str, row: impl Fn(&[f64], f64) -> String) -> PathBuf {
    let text = std::fs::read_to_string(root("tests/data/misspec/none_paper.csv")).unwrap();
    let mut out = vec![header.to_string()];
    for (k, line) in text.lines().skip(1).enumerate() {
        let v: Vec<f64> = line.split(',').map(|c| c.parse().unwrap()).collect();
        // A static marker with a 0.2 mm wobble (deterministic, no generator needed).
        let wobble = 2e-4 * ((k as f64) * 1.7).sin();
        out.push(row(&v, wobble));
    }
    let path = dir.join(name);
    std::fs::write(&path, out.join("\n") + "\n").unwrap();
    path
}

/// The paper rig's file converted as shipped: what each rewritten file must convert back to.
fn shipped_conversion(dir: &Path) -> String {
    convert(
        &[s(&root("tests/data/misspec/none_paper.csv"))],
        &dir.join("shipped.csv"),
    )
}

#[test]
fn markers_named_otherwise_are_found_by_their_motion() {
    let dir = scratch();
    let file = rewritten(
        dir.path(),
        "m.csv",
        "t,m3_x,m3_y,m2_x,m2_y,m1_x,m1_y",
        |v, w| {
            format!(
                "{},{},{},{},{},{},{}",
                v[0],
                0.5 + w,
                0.1 - w,
                v[3],
                v[4],
                v[1],
                v[2]
            )
        },
    );
    let v = inspect(&[&file], &[]);
    assert_eq!(v["rig"]["slider"], "m1", "{}", v["rig"]);
    assert_eq!(v["rig"]["bob"], "m2");
    let flags = &v["suggestions"][0]["flags"];
    assert_eq!(flags[0][1], "m1");
    assert_eq!(flags[1][1], "m2");
    assert_eq!(suggested(&v), ["--slider", "--bob"]);
    // Every other pair with the static marker fails: its distance to either is not a rod's.
    for p in v["pairs"].as_array().unwrap().iter().skip(1) {
        assert_eq!(p["rig"], false, "{p}");
    }
    let out = dir.path().join("out.csv");
    let run = run_printed(
        v["convert_command"].as_str().unwrap(),
        &[("OUT.csv", s(&out))],
    );
    ok(&run, "");
    assert_eq!(
        std::fs::read_to_string(&out).unwrap(),
        shipped_conversion(dir.path())
    );
}

#[test]
fn an_upside_down_file_is_read_with_the_other_y() {
    let dir = scratch();
    let file = rewritten(
        dir.path(),
        "flip.csv",
        "t,slider_x,slider_y,bob_x,bob_y",
        |v, _| format!("{},{},{},{},{}", v[0], v[1], -v[2], v[3], -v[4]),
    );
    let v = inspect(&[&file], &[]);
    assert_eq!(suggested(&v), ["--y-down"], "{}", v["suggestions"]);
    let out = dir.path().join("out.csv");
    let run = run_printed(
        v["convert_command"].as_str().unwrap(),
        &[("OUT.csv", s(&out))],
    );
    ok(&run, "");
    // y is negated twice: the same numbers, but for the sign of a zero.
    let norm = |t: String| t.replace("-0,", "0,").replace("-0\n", "0\n");
    assert_eq!(
        norm(std::fs::read_to_string(&out).unwrap()),
        norm(shipped_conversion(dir.path()))
    );
}

#[test]
fn a_3d_file_is_read_in_the_plane_of_the_swing() {
    let dir = scratch();
    let header = "t,slider_x,slider_y,slider_z,bob_x,bob_y,bob_z";
    let file = rewritten(dir.path(), "xz.csv", header, |v, w| {
        format!(
            "{},{},{},{},{},{},{}",
            v[0],
            v[1],
            0.05 + w,
            v[2],
            v[3],
            0.05 - w,
            v[4]
        )
    });
    let v = inspect(&[&file], &[]);
    assert_eq!(v["plane"]["used"], "xz", "{}", v["plane"]);
    assert_eq!(v["plane"]["default"], "xy");
    assert!(suggested(&v).contains(&"--plane".to_string()));
    let out = dir.path().join("out.csv");
    let fill = [("OUT.csv", s(&out)), ("METRES", "0.3".to_string())];
    let run = run_printed(v["convert_command"].as_str().unwrap(), &fill);
    ok(&run, "");
    let got = std::fs::read_to_string(&out).unwrap();
    let want = shipped_conversion(dir.path());
    // 3-D columns carry no unit: the rod length sets the scale, within its median's rounding.
    for (g, w) in got.lines().zip(want.lines()).skip(1) {
        for (a, b) in g.split(',').zip(w.split(',')) {
            let (a, b): (f64, f64) = (a.parse().unwrap(), b.parse().unwrap());
            assert!((a - b).abs() < 1e-3, "{g} against {w}");
        }
    }
}

/// Two Tracker files named `mass_A` (Tracker's default) given bob first: inspect says to give
/// them the other way round, and so they convert as the shipped pair does.
#[test]
fn tracker_files_in_the_wrong_order_are_turned_round() {
    let dir = scratch();
    let copy = |from: &str, to: &str| {
        let text = std::fs::read_to_string(root(from)).unwrap();
        let (_, rest) = text.split_once('\n').unwrap();
        let path = dir.path().join(to);
        std::fs::write(&path, format!("mass_A\n{rest}")).unwrap();
        path
    };
    let (a, b) = (
        copy("tests/data/tracker_slider.txt", "a.txt"),
        copy("tests/data/tracker_bob.txt", "b.txt"),
    );
    let v = inspect(&[&b, &a], &[]);
    let files = &v["suggestions"][0]["files"];
    assert_eq!(files[0], s(&a), "{}", v["suggestions"]);
    assert_eq!(files[1], s(&b));
    let out = dir.path().join("out.csv");
    let run = run_printed(
        v["convert_command"].as_str().unwrap(),
        &[("OUT.csv", s(&out))],
    );
    ok(&run, "");
    let shipped = convert(
        &[
            s(&root("tests/data/tracker_slider.txt")),
            s(&root("tests/data/tracker_bob.txt")),
        ],
        &dir.path().join("shipped.csv"),
    );
    assert_eq!(std::fs::read_to_string(&out).unwrap(), shipped);
}

/// A file that is no rig still gets a complete command: with the placeholders filled in (any
/// two of its markers), `convert` reads it.
#[test]
fn placeholders_filled_in_make_a_command_that_runs() {
    let dir = scratch();
    for rel in [
        "tests/data/sleap_three-mice_Aeon.analysis.h5",
        "tests/data/motive_v1.23_ha5dzs_markers_mm_360Hz.csv",
        "tests/data/idtrackerai_movementdata_trajectories.csv",
    ] {
        let v = inspect(&[&root(rel)], &[]);
        let names = &v["markers"];
        let out = dir.path().join("out.csv");
        let fill = [
            ("FPS", "30".to_string()),
            ("METRES", "0.3".to_string()),
            ("SLIDER", names[0]["name"].as_str().unwrap().to_string()),
            ("BOB", names[1]["name"].as_str().unwrap().to_string()),
            ("OUT.csv", s(&out)),
        ];
        let run = run_printed(v["convert_command"].as_str().unwrap(), &fill);
        ok(&run, rel);
    }
}

/// Flags the user already knows are used and carried into the commands.
#[test]
fn known_flags_are_kept() {
    let v = inspect(
        &[&root("tests/data/dlc_example.csv")],
        &["--fps", "100", "--rod-length", "0.3"],
    );
    assert_eq!(suggested(&v), ["--rail-frame"]);
    assert_eq!(v["time"]["timed"], true);
    assert!((v["time"]["rate"].as_f64().unwrap() - 100.0).abs() < 1e-9);
    let cmd = v["convert_command"].as_str().unwrap();
    assert!(
        cmd.contains("--fps 100 --rod-length 0.3 --rail-frame"),
        "{cmd}"
    );
}

#[test]
fn several_files_are_reported_in_turn() {
    let out = appell(&[
        "inspect",
        &s(&root("data/example_recording.mcap")),
        &s(&root("tests/data/tracker_slider.txt")),
        &s(&root("tests/data/tracker_bob.txt")),
        "--json",
    ]);
    ok(&out, "");
    let lines: Vec<Value> = String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines.len(), 2);
    assert_eq!(lines[0]["format"], "mcap");
    assert_eq!(lines[1]["format"], "tracker");
    assert_eq!(lines[1]["files"].as_array().unwrap().len(), 2);
}

#[test]
fn bad_input_is_an_error_naming_the_file() {
    let dir = scratch();
    let empty = dir.path().join("empty.csv");
    std::fs::write(&empty, "").unwrap();
    let unknown = dir.path().join("notes.csv");
    std::fs::write(&unknown, "hello,world\n1,2\n").unwrap();
    let missing = dir.path().join("missing.csv");
    for (file, says) in [
        (&missing, "cannot read"),
        (&empty, "the file is empty"),
        (&unknown, "cannot tell the format"),
    ] {
        let out = appell(&["inspect", &s(file)]);
        assert_eq!(out.status.code(), Some(2), "{}", file.display());
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(&s(file)) && err.contains(says), "{err}");
        assert!(out.stdout.is_empty());
    }
    // With a good file beside it, the good one is reported and the run still ends with 2.
    let out = appell(&[
        "inspect",
        &s(&root("data/example_recording.mcap")),
        &s(&empty),
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stdout).contains("example_recording.mcap"));
    assert!(String::from_utf8_lossy(&out.stderr).contains("the file is empty"));
}

/// Issue 38's acceptance: a DeepLabCut, a SLEAP, a Motive and a Tracker recording of a rig
/// (`tests/data/showcase/`, made by an independent generator) go from `appell inspect` to a
/// fit with nothing but the printed fit command, its placeholders filled with what a lab knows
/// (the video's frame rate, the rod length and the rig file as measured): each fit names the
/// model adequate and its mu is within 3 standard errors of the generator's. (Not always
/// within the 95 % interval: where the pixels' scale comes from the rod as measured, 1 mm
/// long, the fit takes a bob marker offset for the scale error and mu comes out about 0.1 %
/// high; the SLEAP file is 2 standard errors off.)
#[test]
fn showcase_recordings_go_from_inspect_to_a_fit_with_the_printed_command() {
    let dir = root("tests/data/showcase");
    let truth: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("truth.json")).unwrap()).unwrap();
    let mu = truth["rig"]["mu_kinetic"].as_f64().unwrap();
    let rod = truth["measured_rig"]["rod_length"].as_f64().unwrap();
    let rig = s(&dir.join("showcase_rig.toml"));
    let cases: [(&str, Vec<&str>); 4] = [
        ("dlc", vec!["showcase_dlc.csv"]),
        ("sleap", vec!["showcase_sleap.csv"]),
        ("motive", vec!["showcase_motive.csv"]),
        (
            "tracker",
            vec!["showcase_tracker_slider.txt", "showcase_tracker_bob.txt"],
        ),
    ];
    for (tool, files) in cases {
        let paths: Vec<PathBuf> = files.iter().map(|f| dir.join(f)).collect();
        let refs: Vec<&Path> = paths.iter().map(PathBuf::as_path).collect();
        let v = inspect(&refs, &[]);
        assert!(v["rig"].is_object(), "{tool}: no rig found: {v}");
        let fps = truth["files"][tool]["fps"].as_f64().unwrap();
        let command = v["fit_command"].as_str().expect("a fit command");
        let mut fill = vec![
            ("FPS", fps.to_string()),
            ("METRES", rod.to_string()),
            ("RIG.toml", rig.clone()),
        ];
        fill.retain(|(k, _)| command.contains(k) || *k == "RIG.toml");
        fits_within_3_standard_errors(tool, command, &fill, mu);
    }
}

/// Run a printed fit command with `--json`, its placeholders filled: the model adequate, mu
/// within 3 standard errors of `mu`.
fn fits_within_3_standard_errors(tool: &str, command: &str, fill: &[(&str, String)], mu: f64) {
    let out = run_printed(&format!("{command} --json"), fill);
    ok(&out, &format!("{tool}: {command}"));
    let fit: Value = serde_json::from_slice(&out.stdout).unwrap();
    let value = fit["mu_kinetic"]["value"].as_f64().unwrap();
    let se = fit["mu_kinetic"]["stderr"].as_f64().unwrap();
    let z = (value - mu) / se;
    assert!(
        z.abs() < 3.0,
        "{tool}: {value} +- {se} against {mu}: z {z:.1}"
    );
    assert!(
        fit["limited_by_model"].is_null(),
        "{tool}: {}",
        fit["answer"]
    );
}

/// Issue 61's acceptance: from each showcase file to a fit using only what `inspect` prints.
/// The rig file is inspect's own template (`--rig-template`, the JSON's `rig_template`), its
/// upper-case values replaced by the lab's measurements (truth.json's `measured_rig`: the
/// masses as weighed, the rod as measured); left in, the fit refuses it naming the
/// placeholder and what to write (the one error allowed). Each fit is adequate and within 3
/// standard errors of the generator's mu.
#[test]
fn showcase_recordings_fit_with_the_rig_file_inspect_writes() {
    let dir = root("tests/data/showcase");
    let truth: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("truth.json")).unwrap()).unwrap();
    let mu = truth["rig"]["mu_kinetic"].as_f64().unwrap();
    let measured = &truth["measured_rig"];
    let m = |k: &str| measured[k].as_f64().unwrap().to_string();
    let scratch = scratch();
    for (tool, files) in [
        ("dlc", vec!["showcase_dlc.csv"]),
        ("motive", vec!["showcase_motive.csv"]),
        (
            "tracker",
            vec!["showcase_tracker_slider.txt", "showcase_tracker_bob.txt"],
        ),
    ] {
        let paths: Vec<String> = files.iter().map(|f| s(&dir.join(f))).collect();
        let rig = scratch.path().join(format!("{tool}.toml"));
        let mut args: Vec<&str> = vec!["inspect"];
        args.extend(paths.iter().map(String::as_str));
        let rig_s = s(&rig);
        args.extend(["--json", "--rig-template", &rig_s]);
        let out = appell(&args);
        ok(&out, &format!("{tool}: inspect --rig-template"));
        let v: Value = serde_json::from_slice(&out.stdout).unwrap();
        let template = std::fs::read_to_string(&rig).unwrap();
        assert_eq!(v["rig_template"].as_str(), Some(template.as_str()));
        // The metric files' rod (Motive's millimetres, Tracker's calibrated metres) comes from
        // their markers; the pixel file's from the lab.
        assert_eq!(template.contains("METRES"), tool == "dlc", "{template}");
        let fps = truth["files"][tool]["fps"].as_f64().unwrap();
        let command = v["fit_command"].as_str().expect("a fit command");
        let fill = [
            ("FPS", fps.to_string()),
            ("METRES", m("rod_length")),
            ("RIG.toml", rig_s.clone()),
        ];
        let out = run_printed(command, &fill);
        assert_eq!(
            out.status.code(),
            Some(2),
            "{tool}: the template as written"
        );
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            err.contains("slider_mass = SLIDER_KG") && err.contains("kilograms"),
            "{tool}: {err}"
        );
        let filled = template
            .replace("SLIDER_KG", &m("slider_mass"))
            .replace("BOB_KG", &m("bob_mass"))
            .replace("METRES", &m("rod_length"));
        std::fs::write(&rig, filled).unwrap();
        fits_within_3_standard_errors(tool, command, &fill, mu);
    }
}

/// `--rig-template` never writes over a file (a rig file holds measurements) nor for a
/// recording without a rig.
#[test]
fn a_rig_template_is_not_written_over_a_file() {
    let scratch = scratch();
    let rig = scratch.path().join("rig.toml");
    std::fs::write(&rig, "[rig]\n").unwrap();
    let dlc = s(&root("tests/data/showcase/showcase_dlc.csv"));
    let out = appell(&["inspect", &dlc, "--rig-template", &s(&rig)]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("not overwritten"));
    assert_eq!(std::fs::read_to_string(&rig).unwrap(), "[rig]\n");
    let mice = s(&root("tests/data/dlc_movementdata_mouse_single.csv"));
    let none = scratch.path().join("mice.toml");
    let out = appell(&["inspect", &mice, "--rig-template", &s(&none)]);
    assert_eq!(out.status.code(), Some(2));
    assert!(!none.exists());
}
