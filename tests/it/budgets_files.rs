//! Issue 25, the non-MCAP readers: small files built to make a reader allocate or compute
//! without bound. Each runs the binary under a 4 GiB address-space cap and must end within
//! 20 s: refused with exit code 2 naming the file and the limit (no output file left, the
//! input untouched), or read when it is a legitimate recording. The HDF5 files are made by
//! `scripts/fixtures/make_budget_h5.py` (tests/data/budget/README.md).

use std::fs::File;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// What a capped run did.
pub(crate) struct Run {
    pub(crate) code: Option<i32>,
    pub(crate) stdout: String,
    pub(crate) stderr: String,
    pub(crate) seconds: f64,
}

/// Run `appell ARGS` in `dir` under a 4 GiB address space, killed past 20 s.
fn capped(dir: &Path, args: &[&str]) -> Run {
    let (out, err) = (dir.join("stdout.txt"), dir.join("stderr.txt"));
    let start = Instant::now();
    let mut child = Command::new("prlimit")
        .arg("--as=4294967296")
        .arg("--")
        .arg(env!("CARGO_BIN_EXE_appell"))
        .args(args)
        .current_dir(dir)
        .stdin(Stdio::null())
        .stdout(File::create(&out).unwrap())
        .stderr(File::create(&err).unwrap())
        .spawn()
        .expect("run prlimit");
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if start.elapsed() > Duration::from_secs(20) {
            child.kill().unwrap();
            child.wait().unwrap();
            panic!("appell {args:?} still running after 20 s");
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    Run {
        code: status.code(),
        stdout: std::fs::read_to_string(dir.join("stdout.txt")).unwrap_or_default(),
        stderr: std::fs::read_to_string(err).unwrap_or_default(),
        seconds: start.elapsed().as_secs_f64(),
    }
}

/// `appell convert EXTRA INPUT out.csv` must refuse `input` with exit code 2, naming it and
/// each of `words` (the limit), leave no output and the input as it was; returns the run.
pub(crate) fn refused(input: &Path, extra: &[&str], words: &[&str]) -> Run {
    let dir = tempfile::tempdir().unwrap();
    // Regular files only: /dev/zero has no end to compare.
    let regular = std::fs::metadata(input).is_ok_and(|m| m.is_file());
    let bytes = || regular.then(|| std::fs::read(input).unwrap());
    let before = bytes();
    let mut args = vec!["convert"];
    args.extend(extra);
    let name = input.to_str().unwrap();
    args.extend([name, "out.csv"]);
    let run = capped(dir.path(), &args);
    assert_eq!(run.code, Some(2), "{args:?}: {}", run.stderr);
    let file_name = input.file_name().unwrap().to_str().unwrap();
    assert!(run.stderr.contains(file_name), "{}", run.stderr);
    for w in words {
        assert!(run.stderr.contains(w), "{w:?} not in {}", run.stderr);
    }
    assert!(!dir.path().join("out.csv").exists());
    assert_eq!(bytes(), before);
    eprintln!("{args:?}: exit 2 in {:.2} s", run.seconds);
    run
}

/// `appell convert EXTRA INPUT out.csv` on a file that is legitimate: it must end within
/// `seconds` (exit code 0, or 2 for a file that says what is wrong with it).
pub(crate) fn read_within(input: &Path, extra: &[&str], seconds: f64) -> Run {
    let dir = tempfile::tempdir().unwrap();
    let mut args = vec!["convert"];
    args.extend(extra);
    args.extend([input.to_str().unwrap(), "out.csv"]);
    let run = capped(dir.path(), &args);
    assert!(matches!(run.code, Some(0 | 2)), "{args:?}: {}", run.stderr);
    assert!(
        run.seconds < seconds,
        "{args:?} took {:.1} s: {}",
        run.seconds,
        run.stderr
    );
    eprintln!("{args:?}: exit {:?} in {:.2} s", run.code, run.seconds);
    run
}

fn budget_file(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/budget")
        .join(name)
}

fn write(dir: &Path, name: &str, bytes: impl AsRef<[u8]>) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

#[test]
fn sleap_h5_declaring_a_billion_nodes_is_refused_before_building_series() {
    let f = budget_file("sleap_1e9_nodes.h5");
    refused(
        &f,
        &["--fps", "30"],
        &["over the input budget", "marker tracks"],
    );
}

#[test]
fn sleap_h5_of_a_gib_through_scale_offset_and_deflate_is_refused_before_decoding() {
    let f = budget_file("sleap_scaleoffset_1gib.h5");
    refused(
        &f,
        &["--fps", "30"],
        &["over the input budget", "decoded bytes"],
    );
}

#[test]
fn dlc_fixed_h5_with_1e8_label_codes_is_checked_against_the_width_and_the_budget() {
    // Codes for 10^8 columns where the values have 3: refused before any label is made.
    let f = budget_file("dlc_fixed_1e8_codes.h5");
    refused(&f, &["--fps", "30"], &["3 codes, one per column"]);
    // The values declaring as many columns: the label strings are over the budget.
    let f = budget_file("dlc_fixed_1e8_columns.h5");
    refused(
        &f,
        &["--fps", "30"],
        &["over the input budget", "decoded bytes"],
    );
}

#[test]
fn dlc_table_pickle_referencing_one_512_kib_string_131072_times_is_refused() {
    let f = budget_file("dlc_table_pickle_refs.h5");
    refused(
        &f,
        &["--fps", "30"],
        &["over the input budget", "decoded bytes"],
    );
}

/// A header of `n` cells after `head`, named by `cell(k)`, then `rows` rows of `row`.
fn wide_text(head: &str, n: usize, cell: impl Fn(usize) -> String, rows: &[String]) -> String {
    let mut s = head.to_string();
    for k in 0..n {
        s.push_str(&cell(k));
    }
    s.push('\n');
    for r in rows {
        s.push_str(r);
        s.push('\n');
    }
    s
}

#[test]
fn headers_of_1e5_columns_are_matched_in_linear_time() {
    let dir = tempfile::tempdir().unwrap();
    let n = 100_000;
    // Wide: x columns without their y (each looked for its y across the header).
    let pad = ",".repeat(n);
    let rows: Vec<String> = (0..3).map(|t| format!("{t},0,0,0,1{pad}")).collect();
    let wide = wide_text(
        "t,slider_x,slider_y,bob_x,bob_y",
        n,
        |k| format!(",m{k}_x"),
        &rows,
    );
    read_within(&write(dir.path(), "wide.csv", wide), &[], 5.0);
    // SLEAP: NODE.x without NODE.y.
    let rows: Vec<String> = (0..3).map(|t| format!(",{t},1{pad}")).collect();
    let sleap = wide_text(
        "track,frame_idx,instance.score",
        n,
        |k| format!(",n{k}.x"),
        &rows,
    );
    let f = write(dir.path(), "sleap.csv", sleap);
    read_within(&f, &["--format", "sleap", "--fps", "30"], 5.0);
    // DeepLabCut: 10^5 columns, one bodypart each (each looked up among those before).
    let head = |label: &str, cell: &dyn Fn(usize) -> String| {
        let mut s = label.to_string();
        for k in 0..n {
            s.push(',');
            s.push_str(&cell(k));
        }
        s
    };
    let mut dlc = [
        head("scorer", &|_| "s".into()),
        head("bodyparts", &|k| format!("p{}", k / 2)),
        head("coords", &|k| ["x", "y"][k % 2].into()),
    ]
    .join("\n");
    for t in 0..3 {
        dlc.push_str(&format!("\n{t}{}", ",1".repeat(n)));
    }
    read_within(&write(dir.path(), "dlc.csv", dlc), &["--fps", "30"], 5.0);
    // Tracker's text export: x columns, each looked for its y after it and its t before it.
    let mut tracker = format!("t{}\ty\n", "\tx".repeat(n));
    for t in 0..3 {
        tracker.push_str(&format!("{t}{}\t1\n", "\t1".repeat(n)));
    }
    let f = write(dir.path(), "tracker.txt", tracker);
    read_within(&f, &["--format", "tracker"], 5.0);
}

#[test]
fn dev_zero_as_text_is_refused_at_line_1_whatever_the_format() {
    let zero = Path::new("/dev/zero");
    for format in [
        "wide", "long", "tracker", "dlc", "motive", "vicon", "sleap", "qualisys", "kinovea", "trex",
    ] {
        let run = refused(
            zero,
            &["--format", format, "--fps", "30"],
            &["line 1", "at most 1048576 bytes per line"],
        );
        assert!(run.seconds < 20.0);
    }
    // A finite file with one line over the cap after good ones names that line.
    let dir = tempfile::tempdir().unwrap();
    let mut text = "t,slider_x,slider_y,bob_x,bob_y\n0,0,0,0,1\n".to_string();
    text.push_str(&"9".repeat(2 << 20));
    let f = write(dir.path(), "long_line.csv", text);
    refused(&f, &[], &["line 3", "at most 1048576 bytes per line"]);
}

/// A Kinovea spreadsheet export of two tracks of `n` rows each, one row per line.
fn kinovea_xml(n: usize) -> String {
    let row = |cells: &[&str]| {
        let mut s = "<Row>".to_string();
        for c in cells {
            s.push_str(&format!("<Cell><Data>{c}</Data></Cell>"));
        }
        s.push_str("</Row>\n");
        s
    };
    let mut s = "<?xml version=\"1.0\"?>\n<?mso-application progid=\"Excel.Sheet\"?>\n<Workbook><Worksheet><Table>\n".to_string();
    for (name, y) in [("slider", "0"), ("bob", "-50")] {
        s.push_str(&row(&["Label :", name]));
        s.push_str(&row(&["Coords (x,y:cm; t:time)"]));
        s.push_str(&row(&["x", "y", "t"]));
        for k in 0..n {
            let x = format!("{}", (k as f64 * 0.01).sin());
            s.push_str(&row(&[&x, y, "0:00:00:00"]));
        }
        s.push_str(&row(&[""]));
    }
    s.push_str("</Table></Worksheet></Workbook>\n");
    s
}

#[test]
fn kinovea_xml_rows_are_numbered_without_rescanning_the_text() {
    let dir = tempfile::tempdir().unwrap();
    let f = write(dir.path(), "many_rows.xml", kinovea_xml(60_000));
    let run = read_within(&f, &["--format", "kinovea", "--fps", "100"], 10.0);
    assert_eq!(run.code, Some(0), "{}", run.stderr);
}

#[test]
fn xml_elements_with_100000_attributes_are_refused_before_parsing() {
    let dir = tempfile::tempdir().unwrap();
    let attrs: String = (0..100_000).map(|k| format!(" a{k}=\"{k}\"")).collect();
    let kinovea = format!(
        "<?xml version=\"1.0\"?>\n<?mso-application progid=\"Excel.Sheet\"?>\n<Workbook{attrs}></Workbook>\n"
    );
    let f = write(dir.path(), "attrs.xml", kinovea);
    refused(
        &f,
        &["--format", "kinovea"],
        &["line 3", "at most 1000 attributes per element"],
    );
    let tracker = format!(
        "<?xml version=\"1.0\"?>\n<object class=\"org.opensourcephysics.cabrillo.tracker.TrackerPanel\"{attrs}></object>\n"
    );
    let f = write(dir.path(), "attrs.trk", tracker);
    refused(&f, &[], &["line 2", "at most 1000 attributes per element"]);
}

/// A Tracker project whose coordinate system lists `n` frames and whose two point masses
/// (slider and bob) are marked on each of them.
fn tracker_project(n: usize) -> String {
    let mut s = String::from(
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<object class=\"org.opensourcephysics.cabrillo.tracker.TrackerPanel\">\n<object class=\"org.opensourcephysics.media.core.StepperClipControl\"><property name=\"delta_t\">10</property></object>\n<object class=\"org.opensourcephysics.media.core.ImageCoordSystem\"><property name=\"framedata\">\n",
    );
    for k in 0..n {
        s.push_str(&format!("<property name=\"[{k}]\"><object><property name=\"xorigin\">0</property><property name=\"yorigin\">0</property><property name=\"xscale\">100</property><property name=\"yscale\">100</property></object></property>\n"));
    }
    s.push_str("</property></object>\n");
    for (name, y) in [("slider", 0), ("bob", 50)] {
        s.push_str(&format!("<object class=\"org.opensourcephysics.cabrillo.tracker.PointMass\"><property name=\"name\">{name}</property><property name=\"framedata\">\n"));
        for k in 0..n {
            s.push_str(&format!("<property name=\"[{k}]\"><object><property name=\"x\">{}</property><property name=\"y\">{y}</property></object></property>\n", k % 7));
        }
        s.push_str("</property></object>\n");
    }
    s.push_str("</object>\n");
    s
}

#[test]
fn tracker_project_coordinate_frames_are_found_by_binary_search() {
    let dir = tempfile::tempdir().unwrap();
    let f = write(dir.path(), "many_frames.trk", tracker_project(150_000));
    let run = read_within(&f, &["--scale", "0.01"], 10.0);
    assert_eq!(run.code, Some(0), "{}", run.stderr);
}

/// A named pipe in `dir` that a thread fills with `head` and then `row(i)` for i = 0, 1, ...
/// until the reader closes it: an input with no end and no size, every line of it valid.
/// Returns the pipe and a function that ends the thread once the run is over.
fn endless_pipe(
    dir: &Path,
    head: &'static str,
    row: impl Fn(u64) -> String + Send + 'static,
) -> (PathBuf, impl FnOnce()) {
    use std::io::Write;
    let fifo = dir.join("endless.csv");
    let made = Command::new("mkfifo").arg(&fifo).status().expect("mkfifo");
    assert!(made.success());
    let path = fifo.clone();
    let writer = std::thread::spawn(move || {
        // Opening blocks until the reader opens; writing fails (EPIPE) once it has closed.
        let Ok(f) = std::fs::OpenOptions::new().write(true).open(&path) else {
            return;
        };
        let mut w = std::io::BufWriter::with_capacity(1 << 16, f);
        if w.write_all(head.as_bytes()).is_err() {
            return;
        }
        for i in 0.. {
            if w.write_all(row(i).as_bytes()).is_err() {
                return;
            }
        }
    });
    let fifo_for_end = fifo.clone();
    let end = move || {
        // A run that never opened the pipe leaves the writer waiting in open: release it.
        if !writer.is_finished() {
            drop(File::open(&fifo_for_end));
        }
        writer.join().unwrap();
    };
    (fifo, end)
}

#[test]
fn an_endless_pipe_of_valid_rows_is_refused_at_the_cell_limit_whatever_the_format() {
    // Before the table cells were charged, a 1 GB wide CSV of short valid rows (or any pipe
    // that does not end) aborted at the 4 GiB cap after 14 s.
    type Row = fn(u64) -> String;
    // Wide rows (16 to 21 cells) reach the limit in a few million lines.
    let cases: [(&str, &'static str, Row); 3] = [
        (
            "wide",
            "t,slider_x,slider_y,bob_x,bob_y,a_x,a_y,b_x,b_y,c_x,c_y,d_x,d_y,e_x,e_y,f_x,f_y,g_x,g_y,h_x,h_y\n",
            |i| format!("{i},0,0,0,1,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0\n"),
        ),
        (
            "long",
            "t,marker,x,y,a,b,c,d,e,f,g,h,i,j,k,l\n",
            |i| format!("{i},slider,0,0,,,,,,,,,,,,\n{i},bob,0,1,,,,,,,,,,,,\n"),
        ),
        (
            "kinovea",
            "#Kinovea Trajectory data export\n#T X Y\n# bob\n",
            |i| format!("{i} 0 1 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0\n"),
        ),
    ];
    for (format, head, row) in cases {
        let dir = tempfile::tempdir().unwrap();
        let (fifo, end) = endless_pipe(dir.path(), head, row);
        let fifo_name = fifo.to_str().unwrap().to_string();
        let run = capped(
            dir.path(),
            &[
                "convert", "--format", format, "--fps", "1", &fifo_name, "out.csv",
            ],
        );
        end();
        assert_eq!(run.code, Some(2), "{format}: {}", run.stderr);
        for w in [
            "endless.csv",
            "over the input budget",
            "100000000 table cells",
        ] {
            assert!(
                run.stderr.contains(w),
                "{format}: {w:?} not in {}",
                run.stderr
            );
        }
        assert!(!dir.path().join("out.csv").exists());
        eprintln!("{format}: exit 2 in {:.2} s", run.seconds);
    }
}

#[test]
fn a_new_marker_name_on_every_row_is_refused_at_the_track_limit() {
    // A long CSV or a SLEAP CSV makes a track for every name its rows bring: 10^5 at most
    // for a text file, each a name and two growing columns.
    let dir = tempfile::tempdir().unwrap();
    let n = 100_001;
    let mut long = String::from("t,marker,x,y\n");
    let mut sleap = String::from("track,frame_idx,instance.score,bob.x,bob.y,bob.score\n");
    for i in 0..n {
        long.push_str(&format!("0,m{i},0,0\n"));
        sleap.push_str(&format!("t{i},0,1,0,0,1\n"));
    }
    let long = write(dir.path(), "names.csv", long);
    let sleap = write(dir.path(), "tracks.csv", sleap);
    refused(&long, &["--format", "long"], &["100000 marker tracks"]);
    refused(
        &sleap,
        &["--format", "sleap", "--fps", "30"],
        &["100000 marker tracks"],
    );
}

#[test]
fn motive_joining_of_20000_unlabeled_markers_is_skipped_with_a_warning_not_tried_for_seconds() {
    // Each track that ends early was compared with every track: 10^4 x 2 x 10^4 comparisons
    // took 2.2 s for a 5.6 MB file (and the pairs kept grow with their product).
    let n = 20_000;
    let names = (0..n).flat_map(|i| vec![format!("Unlabeled {i}"); 3]);
    let mut text = String::from(
        "Format Version,1.23,Take Name,t,Capture Frame Rate,100.0,Export Frame Rate,100.0,\
         Length Units,Millimeters,Coordinate Space,Global\n\n",
    );
    text += &format!(",Type,{}\n", vec!["Marker"; 3 * n].join(","));
    text += &format!(",Name,{}\n", names.collect::<Vec<_>>().join(","));
    text += &format!(",,{}\n", vec!["Position"; 3 * n].join(","));
    text += &format!("Frame,Time (Seconds),{}\n", vec!["X,Y,Z"; n].join(","));
    for f in 0..20 {
        // The first half is seen in frames 0-9, the second half from frame 11: every track
        // of the first half ends early and could have a successor.
        let cells = (0..n).map(|i| match (i < n / 2, f < 10, f > 10) {
            (true, true, _) | (false, _, true) => format!("{}.0,0,0", (i % (n / 2)) * 1000),
            _ => ",,".to_string(),
        });
        text += &format!(
            "{f},{},{}\n",
            f as f64 / 100.0,
            cells.collect::<Vec<_>>().join(",")
        );
    }
    let dir = tempfile::tempdir().unwrap();
    let f = write(dir.path(), "unlabeled.csv", text);
    let run = read_within(
        &f,
        &["--slider", "Unlabeled 0", "--bob", "Unlabeled 1"],
        20.0,
    );
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    // convert prints its report, warnings included, on standard output.
    assert!(
        run.stdout
            .contains("warning: Motive: 10000 unlabeled tracks end early among 20000"),
        "{}",
        run.stdout
    );
}
