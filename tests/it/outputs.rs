//! No command writes over one of its inputs, however the output path spells it, and an
//! interrupted write leaves nothing behind.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn appell(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_appell"))
        .args(args)
        .output()
        .expect("appell runs")
}

fn root(p: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(p)
}

/// A scratch directory with copies of a scene, a rig, a plan and a recording.
fn scratch() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    for (from, to) in [
        ("configs/paper_rest_horizontal.toml", "scene.toml"),
        ("configs/rig_paper.toml", "rig.toml"),
        ("configs/plan_impossible.toml", "plan.toml"),
        ("tests/data/tracker_slider.txt", "slider.txt"),
        ("tests/data/tracker_bob.txt", "bob.txt"),
        ("configs/markers_example.toml", "markers.toml"),
    ] {
        std::fs::copy(root(from), dir.path().join(to)).unwrap();
    }
    std::fs::create_dir(dir.path().join("sub")).unwrap();
    dir
}

/// Every way to name `target` again: itself, `./`, `sub/..`, a symbolic link, a hard link.
fn spellings(dir: &Path, target: &str) -> Vec<String> {
    let t = dir.join(target);
    let soft = dir.join(format!("soft-{target}.svg"));
    let hard = dir.join(format!("hard-{target}"));
    let _ = std::os::unix::fs::symlink(&t, &soft);
    let _ = std::fs::hard_link(&t, &hard);
    [
        t.clone(),
        dir.join(".").join(target),
        dir.join("sub").join("..").join(target),
        soft,
        hard,
    ]
    .iter()
    .map(|p| p.display().to_string())
    .collect()
}

/// Every file of the directory with its bytes, to check nothing changed.
fn snapshot(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut v: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.path().is_file())
        .map(|e| (e.path(), std::fs::read(e.path()).unwrap()))
        .collect();
    v.sort();
    v
}

fn assert_refused(dir: &Path, args: &[&str], out: &str) {
    let before = snapshot(dir);
    let o = appell(args);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
    assert!(
        err.contains("refusing to overwrite an input") && err.contains(out),
        "{args:?}: {err}"
    );
    assert_eq!(snapshot(dir), before, "{args:?} changed a file");
}

#[test]
fn no_command_writes_over_its_inputs_through_any_spelling() {
    let dir = scratch();
    let d = dir.path();
    let p = |n: &str| d.join(n).display().to_string();
    for out in spellings(d, "scene.toml") {
        assert_refused(d, &["simulate", &p("scene.toml"), "--out", &out], &out);
        assert_refused(d, &["synth", &p("scene.toml"), &out], &out);
    }
    for out in spellings(d, "rig.toml") {
        assert_refused(d, &["regions", &p("rig.toml"), "--plot", &out], &out);
    }
    for out in spellings(d, "plan.toml") {
        assert_refused(d, &["plan", &p("plan.toml"), "--plot", &out], &out);
    }
    for target in ["slider.txt", "bob.txt", "markers.toml"] {
        for out in spellings(d, target) {
            let fit = [
                "fit",
                &p("slider.txt"),
                &p("bob.txt"),
                "--rig",
                &p("markers.toml"),
                "--plot",
                &out,
            ];
            assert_refused(d, &fit, &out);
            if target != "markers.toml" {
                let convert = ["convert", &p("slider.txt"), &p("bob.txt"), &out];
                assert_refused(d, &convert, &out);
            }
        }
    }
}

#[test]
fn a_plot_into_a_fitted_directory_must_not_name_one_of_its_recordings() {
    let dir = scratch();
    let d = dir.path();
    let recs = d.join("recs");
    std::fs::create_dir(&recs).unwrap();
    std::fs::copy(root("tests/data/rigid/rigid_paper.csv"), recs.join("a.csv")).unwrap();
    let link = d.join("a-link.svg");
    std::os::unix::fs::symlink(recs.join("a.csv"), &link).unwrap();
    let out = link.display().to_string();
    let rig = root("tests/data/rigid/rigid_paper_measured.toml");
    let args = [
        "fit",
        recs.to_str().unwrap(),
        "--rig",
        rig.to_str().unwrap(),
        "--plot",
        &out,
    ];
    let before = std::fs::read(recs.join("a.csv")).unwrap();
    let o = appell(&args);
    assert_eq!(o.status.code(), Some(2));
    assert_eq!(std::fs::read(recs.join("a.csv")).unwrap(), before);
}

#[test]
fn an_interrupted_synth_leaves_no_temporary_file() {
    let dir = scratch();
    let d = dir.path();
    let out = d.join("big.csv");
    // About 4 million frames of CSV: long enough to be caught while it writes.
    let mut child = Command::new(env!("CARGO_BIN_EXE_appell"))
        .args([
            "synth",
            d.join("scene.toml").to_str().unwrap(),
            out.to_str().unwrap(),
            "--fps",
            "2000000",
            "--duration",
            "2",
        ])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let temporaries = || {
        std::fs::read_dir(d)
            .unwrap()
            .filter_map(|e| e.ok())
            .filter(|e| e.file_name().to_string_lossy().ends_with(".tmp"))
            .count()
    };
    let start = std::time::Instant::now();
    let mut caught = false;
    while start.elapsed().as_secs() < 60 {
        if temporaries() > 0 {
            caught = true;
            break;
        }
        if child.try_wait().unwrap().is_some() {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
    // SIGTERM, as a shell's `kill` sends it.
    unsafe {
        libc::kill(child.id() as i32, libc::SIGTERM);
    }
    let status = child.wait().unwrap();
    if caught {
        assert_eq!(status.code(), Some(130), "{status:?}");
    }
    assert_eq!(temporaries(), 0, "a temporary file was left behind");
    assert!(caught, "the write finished before it could be interrupted");
    assert!(!out.exists(), "an interrupted write left an output");
}

/// `fit --plot k.svg --friction-plot k.svg` (or another spelling of one file) wrote both
/// figures to one file and said both were written: two outputs of one command naming one file
/// are refused with exit 2 before any work, naming both flags, and nothing is written.
#[test]
fn two_outputs_of_one_fit_naming_one_file_are_refused() {
    let dir = scratch();
    let d = dir.path();
    let p = |n: &str| d.join(n).display().to_string();
    let k = p("k.svg");
    for other in [
        k.clone(),
        p("sub/../k.svg"),
        format!("{}/./k.svg", d.display()),
    ] {
        let before = snapshot(d);
        let o = appell(&[
            "fit",
            &p("slider.txt"),
            &p("bob.txt"),
            "--rig",
            &p("markers.toml"),
            "--plot",
            &k,
            "--friction-plot",
            &other,
        ]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{other}: {err}");
        assert!(
            err.contains("--plot") && err.contains("--friction-plot") && err.contains("same file"),
            "{other}: {err}"
        );
        // Refused before any work: no report on stdout, no file written.
        assert!(
            o.stdout.is_empty(),
            "{}",
            String::from_utf8_lossy(&o.stdout)
        );
        assert_eq!(snapshot(d), before, "{other}: a file was written");
    }
}
