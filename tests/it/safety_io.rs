//! Issue 35, the classes of joint fits, still recordings, bench flags, outputs and the
//! streams: each reproducer runs the binary as a user would and asks for exit 0 with a right
//! result, 1 with a reason or 2 naming the file and field or flag, within 20 s, no panic text,
//! no input changed and no partial output left.

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

fn root(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

fn s(p: &Path) -> String {
    p.display().to_string()
}

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_appell"))
}

/// Run the binary with `args` (stdin closed), killed after `limit`; its output.
fn run_within(args: &[&str], limit: Duration) -> Output {
    let child = bin()
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("appell runs");
    wait_within(child, limit, args)
}

/// Wait for `child` at most `limit` (then kill it and fail), reading its streams.
fn wait_within(mut child: std::process::Child, limit: Duration, what: &[&str]) -> Output {
    let mut out = child.stdout.take();
    let mut err = child.stderr.take();
    let reader = std::thread::spawn(move || {
        let mut o = Vec::new();
        if let Some(s) = out.as_mut() {
            let _ = s.read_to_end(&mut o);
        }
        o
    });
    let err_reader = std::thread::spawn(move || {
        let mut e = Vec::new();
        if let Some(s) = err.as_mut() {
            let _ = s.read_to_end(&mut e);
        }
        e
    });
    let t0 = Instant::now();
    let status = loop {
        if let Some(st) = child.try_wait().unwrap() {
            break st;
        }
        if t0.elapsed() > limit {
            let _ = child.kill();
            let _ = child.wait();
            panic!("appell {what:?} still running after {limit:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    Output {
        status,
        stdout: reader.join().unwrap(),
        stderr: err_reader.join().unwrap(),
    }
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// No panic text and no Rust backtrace hint on stderr, and not the panic exit code.
fn no_panic(out: &Output) {
    let err = stderr(out);
    assert!(
        !err.contains("panicked") && !err.contains("RUST_BACKTRACE"),
        "{err}"
    );
    assert_ne!(out.status.code(), Some(101), "{err}");
}

/// Every file under `dir` (recursively) with its bytes, to check nothing changed.
fn snapshot(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut v = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap().flatten() {
            let p = e.path();
            let meta = std::fs::symlink_metadata(&p).unwrap();
            if meta.is_dir() {
                stack.push(p);
            } else if meta.is_file() {
                v.push((p.clone(), std::fs::read(&p).unwrap()));
            } else {
                v.push((p.clone(), Vec::new()));
            }
        }
    }
    v.sort();
    v
}

const SECONDS: Duration = Duration::from_secs(20);

/// A scene of the example rig (m1 0.5 kg, m2 0.2 kg, l 0.30 m) at (theta, x_dot), 2 s.
fn scene(dir: &Path, name: &str, mu: f64, theta: f64, x_dot: f64) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(
        &p,
        format!(
            "[rig]\nslider_mass = 0.5\nbob_mass = 0.2\nrod_length = 0.30\ngravity = 9.81\nmu_kinetic = {mu}\n\n[initial]\nx = 0.0\ntheta = {theta}\nx_dot = {x_dot}\ntheta_dot = 0.0\n\n[run]\nduration = 2.0\n"
        ),
    )
    .unwrap();
    p
}

/// `appell synth SCENE OUT --fps 200 --noise 2e-4 --seed SEED`.
fn synth(scene: &Path, out: &Path, seed: u64) {
    let o = run_within(
        &[
            "synth",
            &s(scene),
            &s(out),
            "--fps",
            "200",
            "--noise",
            "2e-4",
            "--seed",
            &seed.to_string(),
        ],
        SECONDS,
    );
    assert!(o.status.success(), "{}", stderr(&o));
}

/// A joint fit counts a file once however it is named: `A` and `DIR/./A` given as releases,
/// or a symbolic link to `A` beside it in the directory, are one release, with a note that
/// names both (it counted twice: an interval sqrt(2) narrower, exit 0).
#[test]
fn a_file_named_twice_is_one_release_of_a_joint_fit() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let campaign = root("tests/data/campaign");
    for name in ["release_01.csv", "release_02.csv", "release_03.csv"] {
        std::fs::copy(campaign.join(name), d.join(name)).unwrap();
    }
    std::os::unix::fs::symlink(d.join("release_01.csv"), d.join("release_09.csv")).unwrap();
    let before = snapshot(d);
    let rig = s(&campaign.join("rig_measured.toml"));
    let fast = ["--json", "--plain", "--no-profile", "--with", "rail_tilt"];
    let mut args = vec!["fit", "--joint", "--rig", &rig];
    args.extend(fast);
    let dir_arg = s(d);
    let mut by_dir = args.clone();
    by_dir.push(&dir_arg);
    let out = run_within(&by_dir, Duration::from_secs(60));
    no_panic(&out);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["releases"].as_array().unwrap().len(), 3, "{v}");
    let err = stderr(&out);
    assert!(
        err.contains("release_09.csv") && err.contains("counted once"),
        "{err}"
    );
    // The same through `--release A --release DIR/./A`.
    let a = s(&d.join("release_01.csv"));
    let again = s(&d.join(".").join("release_01.csv"));
    let b = s(&d.join("release_02.csv"));
    let mut by_release = args.clone();
    by_release.extend(["--release", &a, "--release", &again, "--release", &b]);
    let out = run_within(&by_release, Duration::from_secs(60));
    no_panic(&out);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["releases"].as_array().unwrap().len(), 2, "{v}");
    assert!(stderr(&out).contains("counted once"), "{}", stderr(&out));
    assert_eq!(snapshot(d), before, "an input changed");
}

/// Releases from rails of other mu: those that disagree are named and the others' mu is
/// given, and setting them aside takes a few joint refits (the rounds double what is set
/// aside), not one per release: six releases, three of them off, in well under the time the
/// one-at-a-time search took.
#[test]
fn disagreeing_releases_are_set_aside_in_few_refits() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for (k, mu) in [0.12, 0.12, 0.12, 0.15, 0.17, 0.19].into_iter().enumerate() {
        let theta = 0.55 + 0.05 * (k % 4) as f64;
        let x_dot = if k % 2 == 0 { 0.3 } else { -0.3 };
        let sc = scene(d, &format!("s{k}.toml"), mu, theta, x_dot);
        synth(&sc, &d.join(format!("rel_{k}.csv")), k as u64 + 1);
        std::fs::remove_file(sc).unwrap();
    }
    let rig = s(&root("configs/markers_example.toml"));
    let out = run_within(
        &[
            "fit",
            "--joint",
            "--json",
            "--plain",
            "--no-profile",
            "--rig",
            &rig,
            &s(d),
        ],
        Duration::from_secs(60),
    );
    no_panic(&out);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let disagreeing = v["disagreeing"].as_array().unwrap();
    assert!(
        !disagreeing.is_empty() && disagreeing.len() <= 3,
        "{disagreeing:?}"
    );
}

/// A recording in which nothing moves (a pendulum hanging at rest, with noise, or exactly
/// still) is refused with exit 1: nothing moves, mu is not identifiable. It was fitted and
/// exited 0.
#[test]
fn a_recording_in_which_nothing_moves_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let rest = d.join("rest.csv");
    synth(
        &scene(d, "rest.toml", 0.12, std::f64::consts::FRAC_PI_2, 0.0),
        &rest,
        3,
    );
    let exact = d.join("exact.csv");
    let mut text = String::from("t,slider_x,slider_y,bob_x,bob_y\n");
    for k in 0..400 {
        text += &format!("{},0,0,0,-0.3\n", k as f64 / 200.0);
    }
    std::fs::write(&exact, text).unwrap();
    let before = snapshot(d);
    let rig = s(&root("configs/markers_example.toml"));
    for file in [&rest, &exact] {
        let out = run_within(&["fit", &s(file), "--rig", &rig], SECONDS);
        no_panic(&out);
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(1), "{err}");
        assert!(
            err.contains(&s(file))
                && err.contains("nothing moves")
                && err.contains("not identifiable"),
            "{err}"
        );
        assert!(out.stdout.is_empty());
    }
    assert_eq!(snapshot(d), before, "an input changed");
}

/// When the mis-tracked filter drops every position (here: a noise given far below the
/// tracks'), the error says so, with the counts, the noise and the fix, not "too few frames".
#[test]
fn a_filter_that_drops_every_position_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let rec = d.join("swing.csv");
    synth(&scene(d, "swing.toml", 0.12, 0.6, 0.3), &rec, 4);
    let rig = s(&root("configs/markers_example.toml"));
    let out = run_within(
        &["fit", &s(&rec), "--rig", &rig, "--noise", "1e-9"],
        SECONDS,
    );
    no_panic(&out);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains(&s(&rec))
            && err.contains("mis-tracked filter dropped")
            && err.contains("--noise")
            && !err.contains("too few frames"),
        "{err}"
    );
}

/// A noise given for one marker far below its track's (`--noise 2e-4,1e-10`) drops most of
/// that track (1991 of 2001 bob positions) but leaves ten frames with both markers: the rest
/// was fitted, a misfit with exit 0. More than half of a track is no few mis-tracked frames:
/// refused as the filter's doing, exit 1, naming the counts and `--noise`.
#[test]
fn a_filter_that_drops_most_of_one_track_says_so() {
    let rec = s(&root("data/campaign/release_01.csv"));
    let rig = s(&root("data/campaign/rig_measured.toml"));
    let out = run_within(
        &["fit", &rec, "--rig", &rig, "--noise", "2e-4,1e-10"],
        SECONDS,
    );
    no_panic(&out);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains("release_01.csv")
            && err.contains("mis-tracked filter dropped")
            && err.contains("more than half")
            && err.contains("--noise"),
        "{err}"
    );
    assert!(out.stdout.is_empty());
}

/// Every bench flag is bounded: a value out of range is bad input (exit 2) naming the flag
/// and the range, at once. `--frames 10^12` aborted on allocation, `--batches 2^64-1`
/// panicked, `--batches 10^9` and `--seconds-per-point 1e300` never ended.
#[test]
fn bench_flags_out_of_range_are_refused_naming_the_flag() {
    for (args, flag) in [
        (&["--read", "--frames", "1000000000000"][..], "--frames"),
        (&["--read", "--frames", "1"][..], "--frames"),
        (&["--batches", "18446744073709551615"][..], "--batches"),
        (&["--batches", "1000000000"][..], "--batches"),
        (&["--batches", "0"][..], "--batches"),
        (
            &["--work-precision", "--seconds-per-point", "1e300"][..],
            "--seconds-per-point",
        ),
        (
            &["--work-precision", "--seconds-per-point", "nan"][..],
            "--seconds-per-point",
        ),
        (&["--work-precision", "--rtols", "1e-300"][..], "--rtols"),
        (
            &["--joint", ".", "--rig", "x.toml", "--batches", "100000"][..],
            "--batches",
        ),
    ] {
        let mut all = vec!["bench"];
        all.extend_from_slice(args);
        let t0 = Instant::now();
        let out = run_within(&all, SECONDS);
        no_panic(&out);
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(flag), "{args:?}: {err}");
        assert!(err.len() < 400, "{args:?}: {err}");
        assert!(t0.elapsed() < Duration::from_secs(5), "{args:?}");
    }
}

/// `bench --read` removes its temporary directory when interrupted (SIGINT, SIGTERM): it
/// stayed behind (93 MB at the default size).
#[test]
fn bench_read_leaves_no_temporary_directory_on_a_signal() {
    for signal in [libc::SIGTERM, libc::SIGINT] {
        let tmp = tempfile::tempdir().unwrap();
        let mut child = bin()
            .args(["bench", "--read", "--frames", "2000000", "--batches", "3"])
            .env("TMPDIR", tmp.path())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        // Wait until it has made its directory and begun writing into it.
        let t0 = Instant::now();
        loop {
            let started = std::fs::read_dir(tmp.path())
                .unwrap()
                .flatten()
                .any(|e| std::fs::read_dir(e.path()).is_ok_and(|mut d| d.next().is_some()));
            if started {
                break;
            }
            assert!(
                t0.elapsed() < SECONDS && child.try_wait().unwrap().is_none(),
                "no temporary directory appeared"
            );
            std::thread::sleep(Duration::from_millis(10));
        }
        let pid = i32::try_from(child.id()).unwrap();
        // SAFETY: kill(2) on the child this test started and has not yet reaped.
        unsafe {
            libc::kill(pid, signal);
        }
        let out = wait_within(child, SECONDS, &["bench", "--read"]);
        no_panic(&out);
        assert_eq!(out.status.code(), Some(130), "{}", stderr(&out));
        let left: Vec<_> = std::fs::read_dir(tmp.path()).unwrap().flatten().collect();
        assert!(left.is_empty(), "signal {signal}: left {left:?}");
    }
}

/// The old temporary name (`.NAME.PID.tmp`) was predictable, and a file of that name was
/// deleted when the write failed: now the temporary is created exclusively under a random
/// name, and a file the tool did not create is never touched, whether the write succeeds or
/// fails.
#[test]
fn a_file_with_the_temporary_name_is_never_removed() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let theirs = d.join(format!(".out.csv.{}.tmp", std::process::id()));
    std::fs::write(&theirs, "an input").unwrap();
    appell::output::write_atomic(&d.join("out.csv"), |w| w.write_all(b"t\n")).unwrap();
    let failed = appell::output::write_atomic(&d.join("out.csv"), |_| {
        Err(std::io::Error::other("the fill failed"))
    });
    assert!(failed.is_err());
    assert_eq!(std::fs::read(&theirs).unwrap(), b"an input");
    assert_eq!(std::fs::read(d.join("out.csv")).unwrap(), b"t\n");
    let names: Vec<String> = std::fs::read_dir(d)
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names.len(), 2, "{names:?}");
}

/// stdout on a full disk ends with exit 1 and the reason (it exited 0 with nothing written);
/// stderr on a full disk or a closed pipe is ignored (it panicked, exit 101) and the exit
/// code is the command's own.
#[test]
fn a_full_disk_on_stdout_is_exit_1_and_a_failing_stderr_no_panic() {
    let full = || {
        std::fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .unwrap()
    };
    let scene = s(&root("configs/paper_rest_horizontal.toml"));
    let out = bin()
        .args(["simulate", &scene])
        .stdout(full())
        .stderr(Stdio::piped())
        .output()
        .unwrap();
    no_panic(&out);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert!(stderr(&out).contains("standard output"), "{}", stderr(&out));
    // A bad input with stderr on a full disk: exit 2, not a panic.
    let missing = s(&root("tests/data/no_such_file.csv"));
    let rig = s(&root("configs/markers_example.toml"));
    let out = bin()
        .args(["fit", &missing, "--rig", &rig])
        .stdout(Stdio::null())
        .stderr(full())
        .status()
        .unwrap();
    assert_eq!(out.code(), Some(2));
    // And with stderr a pipe closed before anything is written.
    let mut child = bin()
        .args(["fit", &missing, "--rig", &rig])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stderr.take());
    assert_eq!(child.wait().unwrap().code(), Some(2));
}

/// A reader that closes stdout early (`appell bench --work-precision ... | head`) ends the
/// command quietly with exit 0 (it panicked on the broken pipe).
#[test]
fn a_closed_stdout_is_a_quiet_exit() {
    let mut child = bin()
        .args([
            "bench",
            "--work-precision",
            "--scenes",
            "paper",
            "--rtols",
            "1e-4,1e-6",
            "--seconds-per-point",
            "0",
            "--batches",
            "1",
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let out = wait_within(child, SECONDS, &["bench", "--work-precision"]);
    no_panic(&out);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
}

/// `--out -` and `--out /dev/stdout` write the trajectory into a pipe (the second failed), and
/// what the command says about it goes to stderr so the CSV stays whole; `synth SCENE -`
/// likewise.
#[test]
fn outputs_to_stdout_work_into_pipes() {
    let scene = s(&root("configs/paper_rest_horizontal.toml"));
    for target in ["-", "/dev/stdout"] {
        let out = run_within(&["simulate", &scene, "--out", target], SECONDS);
        no_panic(&out);
        assert_eq!(out.status.code(), Some(0), "{target}: {}", stderr(&out));
        let text = String::from_utf8_lossy(&out.stdout);
        let mut lines = text.lines();
        assert!(lines.next().unwrap().starts_with("t,"), "{target}: {text}");
        assert!(lines.count() > 1000, "{target}");
        assert!(stderr(&out).contains("samples written to"), "{target}");
    }
    let scene = s(&root("configs/markers_example.toml"));
    let out = run_within(&["synth", &scene, "-", "--fps", "100"], SECONDS);
    no_panic(&out);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.starts_with("t,slider_x"), "{text}");
    assert!(stderr(&out).contains("wrote"), "{}", stderr(&out));
}

/// A named pipe as the output: written when someone reads it, and an exit 1 with the reason
/// at once when nobody does (the command waited in `open` for ever); the pipe stays.
#[test]
fn a_named_pipe_nobody_reads_is_an_error_not_a_hang() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("out.csv");
    let made = Command::new("mkfifo").arg(&fifo).status().unwrap();
    assert!(made.success());
    let scene = s(&root("configs/paper_rest_horizontal.toml"));
    let out = run_within(&["simulate", &scene, "--out", &s(&fifo)], SECONDS);
    no_panic(&out);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("out.csv") && stderr(&out).contains("named pipe that nobody reads"),
        "{}",
        stderr(&out)
    );
    use std::os::unix::fs::FileTypeExt;
    assert!(std::fs::metadata(&fifo).unwrap().file_type().is_fifo());
    // With a reader, the whole trajectory arrives.
    let path = fifo.clone();
    let reader = std::thread::spawn(move || std::fs::read_to_string(path).unwrap());
    let mut tries = 0;
    let out = loop {
        let out = run_within(&["simulate", &scene, "--out", &s(&fifo)], SECONDS);
        // The reader may not have opened its end yet: try again briefly.
        if out.status.code() == Some(0) || tries == 50 {
            break out;
        }
        tries += 1;
        std::thread::sleep(Duration::from_millis(20));
    };
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let text = reader.join().unwrap();
    assert!(text.starts_with("t,") && text.lines().count() > 1000);
}

/// `synth --noise` and `--outlier-size` are lengths a rig and camera can have: 1e300 wrote
/// a recording of coordinates near 1e300 that no command would read, with exit 0.
#[test]
fn synth_noise_beyond_any_camera_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let out_csv = dir.path().join("out.csv");
    let scene = s(&root("configs/paper_rest_horizontal.toml"));
    for (flag, extra) in [("--noise", None), ("--outlier-size", Some("--outliers"))] {
        let mut args = vec!["synth", &scene, out_csv.to_str().unwrap(), flag, "1e300"];
        if let Some(e) = extra {
            args.extend([e, "0.1"]);
        }
        let out = run_within(&args, SECONDS);
        no_panic(&out);
        assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
        assert!(
            stderr(&out).contains(flag) && stderr(&out).contains("got 1e300"),
            "{}",
            stderr(&out)
        );
        assert!(!out_csv.exists());
    }
}
