//! No input can exhaust the machine (issue 25): a text file above its size cap, a step limit
//! above its cap and a rig the recording contradicts are refused at once, with exit code 2
//! and a message naming the file and the limit or key, under a 4 GiB address-space cap, the
//! inputs left byte for byte as they were and no output written.

use std::collections::hash_map::DefaultHasher;
use std::hash::{Hash, Hasher};
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

/// The address space each reproducer runs in: the acceptance cap.
const ADDRESS_SPACE: u64 = 4 << 30;

/// How long a refusal may take (the bound; they take milliseconds).
const QUICK: Duration = Duration::from_secs(20);

pub(crate) fn root(p: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(p)
}

/// The command `appell args`, to run in an address space of [`ADDRESS_SPACE`].
pub(crate) fn capped_command<S: AsRef<std::ffi::OsStr>>(args: &[S]) -> Command {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_appell"));
    cmd.args(args);
    // SAFETY: setrlimit is async-signal-safe and touches no memory of the parent.
    unsafe {
        cmd.pre_exec(|| {
            let cap = libc::rlimit {
                rlim_cur: ADDRESS_SPACE,
                rlim_max: ADDRESS_SPACE,
            };
            if libc::setrlimit(libc::RLIMIT_AS, &cap) == 0 {
                Ok(())
            } else {
                Err(std::io::Error::last_os_error())
            }
        });
    }
    cmd
}

/// `appell args` in an address space of [`ADDRESS_SPACE`], and how long it ran.
fn appell_capped<S: AsRef<std::ffi::OsStr>>(args: &[S]) -> (Output, Duration) {
    let mut cmd = capped_command(args);
    let start = Instant::now();
    let out = cmd.output().expect("appell runs");
    (out, start.elapsed())
}

/// Every file of `dir` and each of `more` with a hash of its bytes: what must not change.
fn snapshot(dir: &Path, more: &[PathBuf]) -> Vec<(PathBuf, u64)> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .chain(more.iter().cloned())
        .collect();
    files.sort();
    files
        .into_iter()
        .map(|f| {
            let mut h = DefaultHasher::new();
            std::fs::read(&f).unwrap().hash(&mut h);
            (f, h.finish())
        })
        .collect()
}

/// Run `args` and check the refusal: exit code 2 within [`QUICK`], stderr naming each of
/// `names`, and `dir` and `inputs` as they were (no output, no temporary left). Returns the
/// run time.
fn assert_refused(dir: &Path, inputs: &[PathBuf], args: &[String], names: &[&str]) -> Duration {
    let before = snapshot(dir, inputs);
    let (out, took) = appell_capped(args);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
    assert!(took < QUICK, "{args:?} took {took:?}");
    for name in names {
        assert!(err.contains(name), "{args:?}: {name:?} not in: {err}");
    }
    assert_eq!(
        snapshot(dir, inputs),
        before,
        "{args:?} changed or left a file"
    );
    eprintln!("{args:?}: exit 2 in {took:?}");
    took
}

pub(crate) fn s(p: &Path) -> String {
    p.display().to_string()
}

/// A copy of the shipped file `from` in `dir` as `name`, with each `(key, value)` of `edits`
/// applied: the line setting `key` set to `key = value` (added after `[section]` when there is
/// no such line), or taken out where `value` is `None`.
pub(crate) fn edited(
    from: &str,
    dir: &Path,
    name: &str,
    edits: &[(&str, Option<&str>)],
    section: &str,
) -> PathBuf {
    let mut lines: Vec<String> = std::fs::read_to_string(root(from))
        .unwrap()
        .lines()
        .map(String::from)
        .collect();
    for &(key, value) in edits {
        let at = lines
            .iter()
            .position(|l| l.split('=').next().unwrap().trim() == key);
        match (at, value) {
            (Some(i), Some(v)) => lines[i] = format!("{key} = {v}"),
            (Some(i), None) => {
                lines.remove(i);
            }
            (None, Some(v)) => {
                let i = lines.iter().position(|l| l.trim() == section).unwrap();
                lines.insert(i + 1, format!("{key} = {v}"));
            }
            (None, None) => {}
        }
    }
    let path = dir.join(name);
    std::fs::write(&path, lines.join("\n") + "\n").unwrap();
    path
}

/// The edits that make a rig file's rigid pendulum a point bob with rod length `rod` (a rod
/// of 1e-9 m is shorter than the bob's radius, which its own check refuses first).
fn point_rod(rod: &str) -> [(&str, Option<&str>); 3] {
    [
        ("rod_length", Some(rod)),
        ("rod_mass", None),
        ("bob_radius", None),
    ]
}

#[test]
fn a_60_mb_toml_file_is_refused_unparsed_by_every_command() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // A valid scene (it serves as a rig file too) and then a 60 MB array: parsed whole (a
    // 30 MB one took the toml crate 15 s and 2.4 GB).
    let big = d.join("big.toml");
    let mut text = std::fs::read_to_string(root("configs/paper_rest_horizontal.toml")).unwrap();
    text.push_str("junk = [");
    text.push_str(&"1,".repeat(30 << 20));
    text.push_str("1]\n");
    std::fs::write(&big, text).unwrap();
    let size = format!("{} bytes", std::fs::metadata(&big).unwrap().len());
    let rec = root("tests/data/rigid/rigid_paper.csv");
    let out = s(&d.join("out.csv"));
    for args in [
        vec!["simulate".into(), s(&big), "--out".into(), out.clone()],
        vec!["synth".into(), s(&big), out.clone()],
        vec!["regions".into(), s(&big)],
        vec!["plan".into(), s(&big)],
        vec!["fit".into(), s(&rec), "--rig".into(), s(&big)],
    ] {
        assert_refused(
            d,
            std::slice::from_ref(&rec),
            &args,
            &[&s(&big), &size, "1048576 bytes"],
        );
    }
}

#[test]
fn dev_zero_and_an_endless_fifo_are_read_no_further_than_the_cap() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for args in [
        vec!["simulate", "/dev/zero"],
        vec!["regions", "/dev/zero"],
        vec!["plan", "/dev/zero"],
    ] {
        let args: Vec<String> = args.into_iter().map(String::from).collect();
        assert_refused(d, &[], &args, &["/dev/zero", "1048576 bytes"]);
    }
    // A FIFO fed without end: the writer stops when appell closes its end.
    let fifo = d.join("scene.toml");
    let c = std::ffi::CString::new(s(&fifo)).unwrap();
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
    let writer = {
        let fifo = fifo.clone();
        std::thread::spawn(move || {
            use std::io::Write;
            let mut f = std::fs::OpenOptions::new().write(true).open(fifo).unwrap();
            let chunk = [b'#'; 1 << 16];
            while f.write_all(&chunk).is_ok() {}
        })
    };
    let (out, took) = appell_capped(&["simulate".to_owned(), s(&fifo)]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(took < QUICK, "{took:?}");
    assert!(
        err.contains(&s(&fifo)) && err.contains("1048576 bytes"),
        "{err}"
    );
    writer.join().unwrap();
}

#[test]
fn max_steps_is_a_whole_number_up_to_its_cap() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = "configs/paper_rest_horizontal.toml";
    for (i, value) in [
        "1e18",
        "1000000000000000000",
        "10000001",
        "0",
        "-1",
        "2.5",
        "nan",
    ]
    .into_iter()
    .enumerate()
    {
        let path = edited(
            scene,
            d,
            &format!("s{i}.toml"),
            &[("max_steps", Some(value))],
            "[run]",
        );
        let args = vec![
            "simulate".into(),
            s(&path),
            "--out".into(),
            s(&d.join("out.csv")),
        ];
        assert_refused(d, &[], &args, &[&s(&path), "run.max_steps", "1e7"]);
    }
    // The cap itself, written either way, is a limit like any other.
    for value in ["1e7", "10000000"] {
        let path = edited(scene, d, "cap.toml", &[("max_steps", Some(value))], "[run]");
        let (out, _) = appell_capped(&["simulate".to_owned(), s(&path)]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
}

#[test]
fn a_rig_the_recording_or_any_planet_contradicts_is_refused_before_fitting() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let rig = "tests/data/rigid/rigid_paper_measured.toml";
    let rec = root("tests/data/rigid/rigid_paper.csv");
    let tiny = edited(rig, d, "tiny.toml", &point_rod("1e-9"), "[rig]");
    let long = edited(rig, d, "long.toml", &[("rod_length", Some("0.7"))], "[rig]");
    let heavy = edited(rig, d, "heavy.toml", &[("gravity", Some("1e9"))], "[rig]");
    let light = edited(rig, d, "light.toml", &[("gravity", Some("0.05"))], "[rig]");
    let plot = s(&d.join("fit.svg"));
    for (file, key, value) in [
        (&tiny, "rig.rod_length", "1e-9"),
        (&long, "rig.rod_length", "0.7"),
        (&heavy, "rig.gravity", "1000000000"),
        (&light, "rig.gravity", "0.05"),
    ] {
        let args = vec![
            "fit".into(),
            s(&rec),
            "--rig".into(),
            s(file),
            "--plot".into(),
            plot.clone(),
        ];
        let mut names = vec![s(file), key.to_owned(), value.to_owned()];
        if key == "rig.rod_length" {
            names.push("median slider-bob marker distance of".into());
            names.push(s(&rec));
        } else {
            names.push("between 0.1 and 30".into());
        }
        let names: Vec<&str> = names.iter().map(String::as_str).collect();
        assert_refused(d, std::slice::from_ref(&rec), &args, &names);
    }
    // Gravity is checked wherever a rig is read: scenes, rig files, plans.
    let scene = edited(
        "configs/paper_rest_horizontal.toml",
        d,
        "scene.toml",
        &[("gravity", Some("1e9"))],
        "[rig]",
    );
    let plan = edited(
        "configs/plan_example.toml",
        d,
        "plan.toml",
        &[("gravity", Some("1e9"))],
        "[rig]",
    );
    let rig_file = edited(
        "configs/rig_paper.toml",
        d,
        "rig.toml",
        &[("gravity", Some("1e9"))],
        "[rig]",
    );
    for args in [
        vec!["simulate".to_owned(), s(&scene)],
        vec!["regions".to_owned(), s(&rig_file)],
        vec!["plan".to_owned(), s(&plan)],
    ] {
        let file = args[1].clone();
        assert_refused(d, &[], &args, &[&file, "rig.gravity", "between 0.1 and 30"]);
    }
}

#[test]
fn a_joint_fit_refuses_a_rod_its_releases_contradict() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let campaign = root("tests/data/campaign");
    let rig = edited(
        "tests/data/campaign/rig_measured.toml",
        d,
        "rig.toml",
        &point_rod("1e-9"),
        "[rig]",
    );
    let recordings: Vec<PathBuf> = (1..=4)
        .map(|i| campaign.join(format!("release_{i:02}.csv")))
        .collect();
    let args = vec![
        "fit".into(),
        s(&campaign),
        "--joint".into(),
        "--rig".into(),
        s(&rig),
        "--plot".into(),
        s(&d.join("joint.svg")),
    ];
    assert_refused(
        d,
        &recordings,
        &args,
        &[&s(&rig), "rig.rod_length", "1e-9", "release_01.csv"],
    );
}

#[test]
fn a_rod_ten_percent_off_is_plausible_and_fitted() {
    let dir = tempfile::tempdir().unwrap();
    let rig = edited(
        "tests/data/rigid/rigid_paper_measured.toml",
        dir.path(),
        "rig.toml",
        &[("rod_length", Some("0.33"))],
        "[rig]",
    );
    let rec = root("tests/data/rigid/rigid_paper.csv");
    let (out, _) = appell_capped(&[
        "fit".to_owned(),
        s(&rec),
        "--rig".into(),
        s(&rig),
        "--plain".into(),
        "--no-profile".into(),
        "--json".into(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(
        v["mu_kinetic"]["value"].as_f64().unwrap().is_finite(),
        "{v}"
    );
}
