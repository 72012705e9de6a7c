//! `appell fit --overlay FILE.mcap` (issue 63): the fit written back as MCAP for Foxglove. Read
//! back with the `mcap` crate: every message decodes against its channel's schema (protobuf
//! through the FileDescriptorSet the file carries, JSON against its JSON Schema's properties),
//! the model's markers equal the simulator's for the fitted scene, the mode switches are the
//! fit's events, the stamps are the recording's own, and the output rules hold.

use appell::data::mcap::overlay as ov;
use appell::data::ReadOptions;
use appell::fit::{FitReport, Observations};
use appell::model::observed_markers;
use appell::pipeline::{fit_recording, FitArgs, FitSetup};
use appell::sim::{simulate, Request};
use foxglove::Decode;
use prost_reflect::{DescriptorPool, DynamicMessage};
use serde_json::Value;
use std::collections::BTreeMap;
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

const RECORDING: &str = "data/example_recording.mcap";
const RIG: &str = "configs/rig_example.toml";

/// The example fitted as `appell fit` fits it, with its provenance.
fn fitted() -> (Observations, appell::data::Provenance, FitReport) {
    let opts = ReadOptions::default();
    let setup = FitSetup::new(&root(RIG), &FitArgs::default(), None).unwrap();
    let (obs, prov, rep, _) = fit_recording(&[root(RECORDING)], &opts, &setup, true)
        .unwrap_or_else(|_| panic!("the example fits"));
    (obs, prov, rep)
}

/// One message read back: topic, schema name, log time, payload.
struct Msg {
    topic: String,
    log_time: u64,
    data: Vec<u8>,
}

/// Every message of an MCAP file, each checked against its channel's schema: a protobuf
/// message decodes with the file's FileDescriptorSet and leaves no unknown field; a JSON
/// message parses and has only keys its JSON Schema lists.
fn read_checked(bytes: &[u8]) -> Vec<Msg> {
    let mut out = Vec::new();
    for m in mcap::MessageStream::new(bytes).unwrap() {
        let m = m.unwrap();
        let schema = m
            .channel
            .schema
            .as_ref()
            .expect("every channel has a schema");
        match m.channel.message_encoding.as_str() {
            "protobuf" => {
                assert_eq!(schema.encoding, "protobuf");
                let pool = DescriptorPool::decode(schema.data.as_ref()).unwrap();
                let desc = pool.get_message_by_name(&schema.name).unwrap();
                let msg = DynamicMessage::decode(desc, m.data.as_ref())
                    .unwrap_or_else(|e| panic!("{}: {e}", m.channel.topic));
                assert_eq!(msg.unknown_fields().count(), 0, "{}", m.channel.topic);
            }
            "json" => {
                assert_eq!(schema.encoding, "jsonschema");
                let s: Value = serde_json::from_slice(&schema.data).unwrap();
                let v: Value = serde_json::from_slice(&m.data).unwrap();
                for key in v.as_object().unwrap().keys() {
                    assert!(
                        s["properties"].get(key).is_some(),
                        "{}: {key} not in {}",
                        m.channel.topic,
                        schema.name
                    );
                }
            }
            other => panic!("{}: encoding {other}", m.channel.topic),
        }
        out.push(Msg {
            topic: m.channel.topic.clone(),
            log_time: m.log_time,
            data: m.data.to_vec(),
        });
    }
    out
}

/// A run of the simulator sampled at `times`, as `simulate` gives it.
fn sampled(
    rig: &appell::model::Rig<f64>,
    initial: &appell::model::State<f64>,
    t_end: f64,
    options: &appell::sim::Options,
    times: Vec<f64>,
) -> appell::sim::Solution<f64> {
    let request = Request {
        sample_times: times,
        friction_work: false,
        positions_only: false,
    };
    simulate(rig, initial, t_end, options, &request).unwrap()
}

fn json(m: &Msg) -> Value {
    serde_json::from_slice(&m.data).unwrap()
}

#[test]
fn a_fit_overlay_holds_simulates_markers_the_fits_events_and_the_recordings_clock() {
    let (obs, prov, rep) = fitted();
    let origin = prov.origin_ns();
    let mut bytes = Vec::new();
    appell::report::overlay::write_fit_overlay(&mut bytes, &obs, &rep, origin).unwrap();
    let msgs = read_checked(&bytes);
    let on = |topic: &'static str| msgs.iter().filter(move |m| m.topic == topic);
    let n = obs.times.len();
    for topic in [
        ov::TOPIC_RECORDED,
        ov::TOPIC_MODEL,
        ov::TOPIC_MARKERS,
        ov::TOPIC_RESIDUAL,
        ov::TOPIC_MODE,
        ov::TOPIC_FORCES,
    ] {
        assert_eq!(on(topic).count(), n, "{topic}: one message a frame");
    }

    // The recording's own clock: the first frame is the example's first marker stamp.
    let recording = std::fs::read(root(RECORDING)).unwrap();
    let first = mcap::MessageStream::new(&recording)
        .unwrap()
        .map(|m| m.unwrap().log_time)
        .min()
        .unwrap();
    let markers: Vec<&Msg> = on(ov::TOPIC_MARKERS).collect();
    assert_eq!(markers[0].log_time, first);
    for (i, m) in markers.iter().enumerate() {
        assert_eq!(m.log_time, ov::stamp_of(origin, obs.times[i]));
    }

    // The model's markers: the simulator's for the fitted scene, through the model's markers.
    let sol = sampled(
        &rep.rig,
        &rep.initial,
        *obs.times.last().unwrap(),
        &rep.problem.options,
        obs.times.clone(),
    );
    assert_eq!(sol.samples.len(), n);
    let mut worst: f64 = 0.0;
    for ((m, s), scene) in markers.iter().zip(&sol.samples).zip(on(ov::TOPIC_MODEL)) {
        let want = observed_markers(&rep.rig, &rep.camera, s.mode, &s.state);
        let v = json(m);
        let got =
            ["slider_x", "slider_y", "bob_x", "bob_y"].map(|k| v["model"][k].as_f64().unwrap());
        let update = foxglove::messages::SceneUpdate::decode(scene.data.as_slice()).unwrap();
        let spheres = &update.entities[0].spheres;
        for k in 0..4 {
            worst = worst.max((got[k] - want[k]).abs());
            let p = spheres[k / 2]
                .pose
                .as_ref()
                .unwrap()
                .position
                .as_ref()
                .unwrap();
            let drawn = if k % 2 == 0 { p.x } else { p.y };
            worst = worst.max((drawn - want[k]).abs());
        }
        // Recorded markers as read, residual = model - recorded.
        let i = markers.iter().position(|x| std::ptr::eq(*x, *m)).unwrap();
        if let Some(p) = obs.bob[i] {
            assert_eq!(v["recorded"]["bob_x"].as_f64(), Some(p[0]));
        }
    }
    assert!(
        worst <= 1e-12,
        "model markers differ from simulate's by {worst:e} m"
    );

    // The mode switches are the fit's events: one log at each event's stamp, and the mode
    // topic changes only across an event.
    let events: Vec<&Msg> = on(ov::TOPIC_EVENTS).collect();
    assert!(!rep.events.is_empty());
    assert_eq!(events.len(), rep.events.len());
    for (m, e) in events.iter().zip(&rep.events) {
        assert_eq!(m.log_time, ov::stamp_of(origin, e.t));
        let log = foxglove::messages::Log::decode(m.data.as_slice()).unwrap();
        assert!(
            log.message.contains(&format!("t = {} s", e.t)),
            "{}",
            log.message
        );
    }
    let modes: Vec<Value> = on(ov::TOPIC_MODE).map(json).collect();
    for i in 1..n {
        if modes[i]["mode"] != modes[i - 1]["mode"] {
            let (a, b) = (obs.times[i - 1], obs.times[i]);
            let e = rep
                .events
                .iter()
                .find(|e| e.t > a && e.t <= b)
                .unwrap_or_else(|| panic!("a mode change in ({a}, {b}] without an event"));
            assert_eq!(modes[i]["mode"], e.to.name());
        }
    }
    for (s, m) in sol.samples.iter().zip(&modes) {
        assert_eq!(m["mode"], s.mode.name());
    }

    // The answer line, once, at the first frame.
    let answer: Vec<&Msg> = on(ov::TOPIC_ANSWER).collect();
    assert_eq!(answer.len(), 1);
    assert_eq!(answer[0].log_time, first);
    let log = foxglove::messages::Log::decode(answer[0].data.as_slice()).unwrap();
    assert_eq!(log.message, appell::report::fit::answer(&rep));

    // Forces: while stuck the friction holds the slider within the static cone; while sliding
    // mu is the fitted law's coefficient.
    let forces: Vec<Value> = on(ov::TOPIC_FORCES).map(json).collect();
    for (s, f) in sol.samples.iter().zip(&forces) {
        let c = rep.rig.contact(s.mode, &s.state);
        assert_eq!(f["normal"].as_f64(), Some(c.normal));
        assert_eq!(f["friction"].as_f64(), Some(c.friction));
        let (n, fr, mu) = (c.normal, c.friction, f["mu"].as_f64().unwrap());
        if s.mode == appell::model::Mode::Stick {
            // Held within the static cone, |F| = mu |N|.
            assert!(
                fr.abs() <= rep.rig.mu_static * n.abs() * (1.0 + 1e-9),
                "{fr} {n}"
            );
            assert!((fr.abs() - mu * n.abs()).abs() <= 1e-12 * n.abs().max(1.0));
        } else {
            // Coulomb sliding: mu the fitted coefficient, F = -mu sign(x') |N| against the motion.
            assert!((mu - rep.rig.mu_kinetic).abs() < 1e-9, "{mu}");
            let want = -mu * s.state[2].signum() * n.abs();
            assert!((fr - want).abs() <= 1e-9 * n.abs().max(1.0), "{fr} {want}");
        }
    }
}

/// The binary writes what the library does, says so, and the answer printed is the one stored.
#[test]
fn fit_overlay_from_the_command_line_decodes_and_holds_the_printed_answer() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("fit.mcap");
    let o = appell(&[
        "fit",
        root(RECORDING).to_str().unwrap(),
        "--rig",
        root(RIG).to_str().unwrap(),
        "--overlay",
        out.to_str().unwrap(),
        "--json",
    ]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let report: Value = serde_json::from_slice(&o.stdout).unwrap();
    let bytes = std::fs::read(&out).unwrap();
    let msgs = read_checked(&bytes);
    let answer = msgs.iter().find(|m| m.topic == ov::TOPIC_ANSWER).unwrap();
    let log = foxglove::messages::Log::decode(answer.data.as_slice()).unwrap();
    assert_eq!(Some(log.message.as_str()), report["answer"].as_str());
    let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
    let topics: BTreeMap<&str, usize> = summary
        .channels
        .values()
        .map(|c| (c.topic.as_str(), 0))
        .collect();
    assert_eq!(topics.len(), 8, "{topics:?}");
    // Nothing left beside it.
    let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
    assert_eq!(names.len(), 1);
}

/// Bad paths and an overlay over an input follow the output rules: refused before any work
/// (exit 2, nothing written) when it names an input or another output or has no known
/// extension; a directory that does not exist or a full disk is exit 1 with the reason, the
/// report printed in full and no file left, for either kind of overlay (`.mcap`, `.csv`).
#[test]
fn overlay_paths_follow_the_output_rules() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::copy(root(RECORDING), d.join("rec.mcap")).unwrap();
    std::fs::copy(root(RIG), d.join("rig.toml")).unwrap();
    let p = |n: &str| d.join(n).display().to_string();
    let before = std::fs::read(d.join("rec.mcap")).unwrap();
    std::fs::create_dir(d.join("sub")).unwrap();
    let fit = |extra: &[&str]| {
        let rec = p("rec.mcap");
        let rig = p("rig.toml");
        let mut args = vec!["fit", rec.as_str(), "--rig", rig.as_str()];
        args.extend_from_slice(extra);
        appell(&args)
    };
    for (args, what) in [
        (vec!["--overlay".to_owned(), p("rec.mcap")], "the input"),
        (
            vec!["--overlay".to_owned(), p("sub/../rec.mcap")],
            "the input",
        ),
        (vec!["--overlay".to_owned(), p("o.txt")], ".mcap"),
        (
            vec![
                "--overlay".to_owned(),
                p("x.mcap"),
                "--plot".to_owned(),
                p("x.mcap"),
            ],
            "same file",
        ),
    ] {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let o = fit(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(what), "{args:?}: {err}");
        assert!(o.stdout.is_empty(), "{args:?}: refused before the fit");
    }
    assert_eq!(std::fs::read(d.join("rec.mcap")).unwrap(), before);

    // Cannot be written: exit 1, the report kept, the reason named.
    // A full disk: a link named like an overlay to /dev/full, which refuses every write.
    let full = Path::new("/dev/full").exists()
        && std::os::unix::fs::symlink("/dev/full", d.join("full.mcap")).is_ok()
        && std::os::unix::fs::symlink("/dev/full", d.join("full.csv")).is_ok();
    let mut targets = vec![p("missing/o.mcap"), p("missing/o.csv")];
    if full {
        targets.push(p("full.mcap"));
        targets.push(p("full.csv"));
    }
    for target in targets {
        let o = fit(&["--overlay", &target]);
        let err = String::from_utf8_lossy(&o.stderr);
        let out = String::from_utf8_lossy(&o.stdout);
        assert_eq!(o.status.code(), Some(1), "{target}: {err}");
        assert!(
            out.contains("mu_kinetic"),
            "{target}: the report is kept: {out}"
        );
        assert!(
            err.contains(&target) && err.contains("only the overlay is missing"),
            "{target}: {err}"
        );
    }
    assert!(!d.join("missing").exists());
    let left: Vec<String> = std::fs::read_dir(d)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".tmp"))
        .collect();
    assert!(left.is_empty(), "{left:?}");
}

/// The shipped Foxglove layout names only topics and fields an overlay has.
#[test]
fn the_shipped_layout_opens_the_overlays_topics() {
    let layout: Value = serde_json::from_str(
        &std::fs::read_to_string(root("configs/foxglove_overlay.json")).unwrap(),
    )
    .unwrap();
    let topics = [
        ov::TOPIC_RECORDED,
        ov::TOPIC_MODEL,
        ov::TOPIC_MARKERS,
        ov::TOPIC_RESIDUAL,
        ov::TOPIC_MODE,
        ov::TOPIC_FORCES,
        ov::TOPIC_EVENTS,
        ov::TOPIC_ANSWER,
    ];
    let schemas: BTreeMap<&str, &str> = BTreeMap::from([
        (ov::TOPIC_MARKERS, ov::MARKERS_SCHEMA),
        (ov::TOPIC_RESIDUAL, ov::RESIDUAL_SCHEMA),
        (ov::TOPIC_MODE, ov::MODE_SCHEMA),
        (ov::TOPIC_FORCES, ov::FORCES_SCHEMA),
    ]);
    let mut named = Vec::new();
    fn strings(v: &Value, out: &mut Vec<String>) {
        match v {
            Value::String(s) if s.starts_with("/appell/") => out.push(s.clone()),
            Value::Array(a) => a.iter().for_each(|x| strings(x, out)),
            Value::Object(m) => m.iter().for_each(|(k, x)| {
                if k.starts_with("/appell/") {
                    out.push(k.clone());
                }
                strings(x, out)
            }),
            _ => {}
        }
    }
    strings(&layout["configById"], &mut named);
    assert!(named.len() >= 10, "{named:?}");
    for path in named {
        let (topic, field) = path.split_once('.').unwrap_or((&path, ""));
        assert!(topics.contains(&topic), "{path}: no such topic");
        if let (Some(schema), Some(first)) = (schemas.get(topic), field.split('.').next()) {
            let s: Value = serde_json::from_str(schema).unwrap();
            assert!(
                s["properties"].get(first).is_some(),
                "{path}: no such field"
            );
        }
    }
}

/// The model's markers on an overlay's `/appell/markers`, frame by frame.
fn model_markers(msgs: &[Msg]) -> Vec<[f64; 4]> {
    msgs.iter()
        .filter(|m| m.topic == ov::TOPIC_MARKERS)
        .map(|m| {
            let v = json(m);
            ["slider_x", "slider_y", "bob_x", "bob_y"].map(|k| v["model"][k].as_f64().unwrap())
        })
        .collect()
}

/// `synth` and `simulate --out X.mcap` write the same topics by the same writer: the scene's
/// motion as the model, equal to the simulator's markers; synth's recording is still read
/// back by appell's reader as before.
#[test]
fn synth_and_simulate_write_the_overlays_schemas() {
    let dir = tempfile::tempdir().unwrap();
    let scene_path = root("configs/paper_rest_horizontal.toml");
    let scene = appell::scene::Scene::from_path(&scene_path).unwrap();
    let syn_path = dir.path().join("syn.mcap");
    let o = appell(&[
        "synth",
        scene_path.to_str().unwrap(),
        syn_path.to_str().unwrap(),
        "--fps",
        "200",
        "--noise",
        "0.001",
    ]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let msgs = read_checked(&std::fs::read(&syn_path).unwrap());
    let rec =
        appell::data::read_recording(std::slice::from_ref(&syn_path), &ReadOptions::default())
            .unwrap();
    let sol = sampled(
        &scene.rig,
        &scene.initial,
        *rec.times.last().unwrap(),
        &scene.options,
        rec.times.clone(),
    );
    let got = model_markers(&msgs);
    assert_eq!(got.len(), rec.len());
    for (g, s) in got.iter().zip(&sol.samples) {
        let want = appell::model::markers(&scene.rig, &s.state);
        for k in 0..4 {
            assert!((g[k] - want[k]).abs() <= 1e-12, "{g:?} {want:?}");
        }
    }
    let events = msgs.iter().filter(|m| m.topic == ov::TOPIC_EVENTS).count();
    assert_eq!(events, sol.events.len());
    // The recorded topic holds what the reader reads from `/markers`.
    let recorded: Vec<Value> = msgs
        .iter()
        .filter(|m| m.topic == ov::TOPIC_MARKERS)
        .map(json)
        .collect();
    for (i, v) in recorded.iter().enumerate() {
        assert_eq!(v["recorded"]["bob_x"].as_f64(), rec.bob[i].map(|p| p[0]));
    }

    let sim_path = dir.path().join("sim.mcap");
    let o = appell(&[
        "simulate",
        scene_path.to_str().unwrap(),
        "--out",
        sim_path.to_str().unwrap(),
    ]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let msgs = read_checked(&std::fs::read(&sim_path).unwrap());
    let mut scene = scene;
    scene.output.frame_rate = scene.output.frame_rate.or(Some(1000.0));
    let sol = simulate(
        &scene.rig,
        &scene.initial,
        scene.duration,
        &scene.options,
        &scene.request(),
    )
    .unwrap();
    let got = model_markers(&msgs);
    assert_eq!(got.len(), sol.samples.len());
    for (g, s) in got.iter().zip(&sol.samples) {
        let want = appell::model::markers(&scene.rig, &s.state);
        for k in 0..4 {
            assert!((g[k] - want[k]).abs() <= 1e-12, "{g:?} {want:?}");
        }
    }
    let stamps: Vec<u64> = msgs
        .iter()
        .filter(|m| m.topic == ov::TOPIC_EVENTS)
        .map(|m| m.log_time)
        .collect();
    let want: Vec<u64> = sol
        .events
        .iter()
        .filter(|e| e.t <= sol.samples.last().unwrap().t)
        .map(|e| ov::stamp_of(0, e.t))
        .collect();
    assert_eq!(stamps, want);
}

/// `fit --joint --overlay OUT.mcap` writes one overlay a release beside OUT: each release's
/// recording and the joint model at its optimum for that release, equal to the simulator's.
#[test]
fn a_joint_fit_writes_one_overlay_a_release() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("fit.mcap");
    let campaign = root("data/campaign");
    let rig = campaign.join("rig_measured.toml");
    let o = appell(&[
        "fit",
        campaign.to_str().unwrap(),
        "--joint",
        "--rig",
        rig.to_str().unwrap(),
        "--overlay",
        out.to_str().unwrap(),
    ]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    // The library's joint fit gives each release's model.
    let setup = FitSetup::new(&rig, &FitArgs::default(), None).unwrap();
    let (files, _) = appell::pipeline::directory_files(&campaign, false).unwrap();
    let paths: Vec<Vec<PathBuf>> = files.into_iter().map(|f| vec![f]).collect();
    let joint = appell::fit::joint::JointSettings {
        same_camera: false,
        keep_going: false,
    };
    let (rep, _) =
        appell::pipeline::fit_joint_files(&paths, &ReadOptions::default(), &setup, &joint)
            .unwrap_or_else(|_| panic!("the campaign fits"));
    assert_eq!(rep.parts.len(), paths.len());
    for (p, part) in paths.iter().zip(&rep.parts) {
        let file = appell::report::overlay::release_overlay_path(&out, p);
        let msgs = read_checked(&std::fs::read(&file).unwrap());
        let obs = part.observations();
        let sol = sampled(
            &part.rig,
            &part.initial,
            *obs.times.last().unwrap(),
            &part.options,
            obs.times.clone(),
        );
        let got = model_markers(&msgs);
        assert_eq!(got.len(), obs.times.len(), "{}", file.display());
        for (g, s) in got.iter().zip(&sol.samples) {
            let want = observed_markers(&part.rig, &part.camera, s.mode, &s.state);
            for k in 0..4 {
                assert!(
                    (g[k] - want[k]).abs() <= 1e-12,
                    "{}: {g:?} {want:?}",
                    file.display()
                );
            }
        }
        let events: Vec<u64> = msgs
            .iter()
            .filter(|m| m.topic == ov::TOPIC_EVENTS)
            .map(|m| m.log_time)
            .collect();
        let origin = appell::pipeline::origin_ns(p, &ReadOptions::default()).unwrap();
        let want: Vec<u64> = sol
            .events
            .iter()
            .map(|e| ov::stamp_of(origin, e.t))
            .collect();
        assert_eq!(events, want, "{}", file.display());
    }
}

/// A shipped recording with the flags its tool needs: files under the repository root, the
/// flags as `fit` and `convert` take them, and the same as read options.
struct Shipped {
    files: &'static [&'static str],
    rig: &'static str,
    flags: &'static [&'static str],
    opts: fn() -> ReadOptions,
    /// The format `convert` should detect in the overlay.
    format: &'static str,
}

fn shipped() -> Vec<Shipped> {
    const SHOW: &str = "tests/data/showcase/showcase_rig.toml";
    vec![
        Shipped {
            files: &[
                "tests/data/showcase/showcase_tracker_slider.txt",
                "tests/data/showcase/showcase_tracker_bob.txt",
            ],
            rig: SHOW,
            flags: &["--rail-frame"],
            opts: || ReadOptions {
                rail_frame: true,
                ..ReadOptions::default()
            },
            format: "tracker",
        },
        Shipped {
            files: &["tests/data/showcase/showcase_dlc.csv"],
            rig: SHOW,
            flags: &["--fps", "100", "--rod-length", "0.251", "--rail-frame"],
            opts: || ReadOptions {
                fps: Some(100.0),
                rod_length: Some(0.251),
                rail_frame: true,
                ..ReadOptions::default()
            },
            format: "dlc",
        },
        Shipped {
            files: &["tests/data/showcase/showcase_sleap.csv"],
            rig: SHOW,
            flags: &["--fps", "200", "--scale", "0.00104", "--rail-frame"],
            opts: || ReadOptions {
                fps: Some(200.0),
                scale: Some(0.00104),
                rail_frame: true,
                ..ReadOptions::default()
            },
            format: "dlc",
        },
        Shipped {
            files: &["tests/data/showcase/showcase_motive.csv"],
            rig: SHOW,
            flags: &[
                "--slider",
                "Unlabeled 1001",
                "--bob",
                "Unlabeled 1002",
                "--rail-frame",
            ],
            opts: || ReadOptions {
                slider: Some("Unlabeled 1001".into()),
                bob: Some("Unlabeled 1002".into()),
                rail_frame: true,
                ..ReadOptions::default()
            },
            format: "motive",
        },
        Shipped {
            files: &[RECORDING],
            rig: RIG,
            flags: &[],
            opts: ReadOptions::default,
            format: "wide",
        },
    ]
}

/// `appell fit FILES --rig RIG FLAGS --overlay OUT`, which must succeed.
fn fit_with_overlay(s: &Shipped, out: &Path) {
    let files: Vec<String> = s
        .files
        .iter()
        .map(|f| root(f).display().to_string())
        .collect();
    let rig = root(s.rig).display().to_string();
    let mut args: Vec<&str> = vec!["fit"];
    args.extend(files.iter().map(String::as_str));
    args.extend(["--rig", rig.as_str()]);
    args.extend_from_slice(s.flags);
    args.extend(["--overlay", out.to_str().unwrap(), "--json"]);
    let o = appell(&args);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{:?}: {}",
        s.files,
        String::from_utf8_lossy(&o.stderr)
    );
}

/// A recording's positions in the file's own units and axes: read with a scale of 1, y as the
/// file has it, no rail frame.
fn raw(paths: &[PathBuf], opts: &ReadOptions) -> appell::data::Recording {
    let raw = ReadOptions {
        scale: Some(1.0),
        y_down: Some(false),
        rail_frame: false,
        rod_length: None,
        ..opts.clone()
    };
    appell::data::read_recording(paths, &raw).unwrap()
}

/// The acceptance of issue 63 for `--overlay FILE.csv`, on every shipped showcase (Tracker,
/// DeepLabCut, SLEAP, Motive) and the example MCAP: the table, read back in the file's units
/// and mapped through the recording's calibration, equals the fitted model's markers (the MCAP
/// overlay's, the simulator's for the fitted scene) to 1e-9 m at the same frame times; it is
/// written in its tool's layout, which `convert` reads again with the recording's own flags;
/// and its positions lie on the recorded markers in the file's own units (a y not flipped back
/// or a rail not turned back would put the model's bob a rod's length away).
#[test]
fn csv_overlays_map_back_through_the_calibration_to_the_fitted_markers() {
    let dir = tempfile::tempdir().unwrap();
    for (k, s) in shipped().iter().enumerate() {
        let csv = dir.path().join(format!("o{k}.csv"));
        let mcap_out = dir.path().join(format!("o{k}.mcap"));
        fit_with_overlay(s, &csv);
        fit_with_overlay(s, &mcap_out);
        let msgs = read_checked(&std::fs::read(&mcap_out).unwrap());
        let model = model_markers(&msgs);
        let model_t: Vec<f64> = msgs
            .iter()
            .filter(|m| m.topic == ov::TOPIC_MARKERS)
            .map(|m| json(m)["t"].as_f64().unwrap())
            .collect();

        let opts = (s.opts)();
        let inputs: Vec<PathBuf> = s.files.iter().map(|f| root(f)).collect();
        let recording = appell::data::read_recording(&inputs, &opts).unwrap();
        let cal = &recording.provenance.calibration;
        let back = raw(std::slice::from_ref(&csv), &opts);
        assert_eq!(back.len(), model.len(), "{:?}: one row a frame", s.files);
        let mut worst: f64 = 0.0;
        for i in 0..back.len() {
            assert!(
                (back.times[i] - model_t[i]).abs() < 1e-9,
                "{:?}: frame {i} at {} s, the model's at {} s",
                s.files,
                back.times[i],
                model_t[i]
            );
            let (p, q) = (back.slider[i].unwrap(), back.bob[i].unwrap());
            let rail = [cal.to_rail(p), cal.to_rail(q)];
            let m = model[i];
            for (j, v) in [rail[0][0], rail[0][1], rail[1][0], rail[1][1]]
                .iter()
                .enumerate()
            {
                worst = worst.max((v - m[j]).abs());
            }
        }
        assert!(worst <= 1e-9, "{:?}: {worst:e} m off", s.files);

        // The file's own units and axes: the model's bob on the recorded bob.
        let recorded = raw(&inputs, &opts);
        let rod = recording.provenance.geometry.as_ref().unwrap().median / cal.scale;
        let mut off: Vec<f64> = recorded
            .bob
            .iter()
            .zip(&back.bob)
            .filter_map(|(r, m)| {
                let (r, m) = ((*r)?, (*m)?);
                Some((r[0] - m[0]).hypot(r[1] - m[1]))
            })
            .collect();
        off.sort_by(f64::total_cmp);
        let median = off[off.len() / 2];
        assert!(
            median < 0.01 * rod,
            "{:?}: the model's bob {median} file units from the recorded one (rod {rod})",
            s.files
        );

        // Motive's third axis: the model's markers at the recorded markers' depth off the
        // plane (the take's Z, plane xy), within a few noise deviations (0.15 mm).
        if s.format == "motive" {
            let z = |path: &Path, col: usize| -> f64 {
                let text = std::fs::read_to_string(path).unwrap();
                let v: Vec<f64> = text
                    .lines()
                    .skip(7)
                    .filter_map(|l| l.split(',').nth(col)?.parse().ok())
                    .collect();
                v.iter().sum::<f64>() / v.len() as f64
            };
            for col in [4, 7] {
                let (got, want) = (z(&csv, col), z(&inputs[0], col));
                assert!(
                    (got - want).abs() < 0.5,
                    "Z column {col}: {got} against {want} mm"
                );
            }
        }

        // `convert` reads it again, in the tool's layout, with the recording's flags.
        let out = dir.path().join(format!("c{k}.csv"));
        let mut args = vec!["convert", csv.to_str().unwrap(), out.to_str().unwrap()];
        args.extend_from_slice(s.flags);
        let o = appell(&args);
        let said = String::from_utf8_lossy(&o.stdout);
        assert_eq!(
            o.status.code(),
            Some(0),
            "{:?}: {}",
            s.files,
            String::from_utf8_lossy(&o.stderr)
        );
        assert!(
            said.contains(&format!("({} format, detected)", s.format)),
            "{:?}: {said}",
            s.files
        );
        let converted = appell::data::read_recording(&[out], &ReadOptions::default()).unwrap();
        assert_eq!(converted.len(), model.len(), "{:?}", s.files);
    }
}

/// Messages and payload bytes per topic of an MCAP file.
fn per_topic(bytes: &[u8]) -> BTreeMap<String, (usize, usize)> {
    let mut out: BTreeMap<String, (usize, usize)> = BTreeMap::new();
    for m in mcap::MessageStream::new(bytes).unwrap() {
        let m = m.unwrap();
        let e = out.entry(m.channel.topic.clone()).or_default();
        e.0 += 1;
        e.1 += m.data.len();
    }
    out
}

/// `--overlay-with-input` keeps an MCAP recording's own topics beside the overlay's: each of
/// the input's topics holds as many messages and bytes as in the input, with the same schema,
/// and the overlay's eight topics are all there; a table overlay or a recording not in MCAP is
/// refused before the fit (exit 2, saying why).
#[test]
fn overlay_with_input_keeps_the_recordings_topics() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("with.mcap");
    let rec = root(RECORDING).display().to_string();
    let rig = root(RIG).display().to_string();
    let o = appell(&[
        "fit",
        &rec,
        "--rig",
        &rig,
        "--overlay",
        out.to_str().unwrap(),
        "--overlay-with-input",
    ]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let input = std::fs::read(root(RECORDING)).unwrap();
    let bytes = std::fs::read(&out).unwrap();
    let want = per_topic(&input);
    let got = per_topic(&bytes);
    assert!(!want.is_empty());
    for (topic, counts) in &want {
        assert_eq!(got.get(topic), Some(counts), "{topic}");
    }
    assert_eq!(got.len(), want.len() + 8, "{:?}", got.keys());
    // Each copied message decodes against its schema as the input's did (the JSON topics'
    // keys in their schemas), and the stamps are the input's.
    let msgs = read_checked(&bytes);
    let first_in = mcap::MessageStream::new(&input)
        .unwrap()
        .map(|m| m.unwrap().log_time)
        .collect::<Vec<_>>();
    let copied: Vec<u64> = msgs
        .iter()
        .filter(|m| want.contains_key(&m.topic))
        .map(|m| m.log_time)
        .collect();
    assert_eq!(copied, first_in);

    // Refused before the fit: a table overlay, and a recording that is not MCAP.
    let csv = dir.path().join("o.csv");
    let dlc = root("tests/data/showcase/showcase_dlc.csv")
        .display()
        .to_string();
    let show_rig = root("tests/data/showcase/showcase_rig.toml")
        .display()
        .to_string();
    let mcap_out = dir.path().join("o.mcap");
    for (args, what) in [
        (
            vec![
                "fit",
                &rec,
                "--rig",
                &rig,
                "--overlay",
                csv.to_str().unwrap(),
                "--overlay-with-input",
            ],
            "table (.csv)",
        ),
        (
            vec![
                "fit",
                &dlc,
                "--rig",
                &show_rig,
                "--fps",
                "100",
                "--rod-length",
                "0.251",
                "--overlay",
                mcap_out.to_str().unwrap(),
                "--overlay-with-input",
            ],
            "not MCAP",
        ),
    ] {
        let o = appell(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(
            err.contains("--overlay-with-input") && err.contains(what),
            "{args:?}: {err}"
        );
        assert!(o.stdout.is_empty(), "{args:?}: refused before the fit");
    }
    assert!(!csv.exists() && !mcap_out.exists());
}

/// A fit of part of a recording (`--t-start`) writes its overlay in the file's own clock: the
/// table's first frame number is the first frame kept (DeepLabCut at 100 fps from 0.5 s:
/// frame 50), and the MCAP overlay's first stamp is the recording's stamp of that frame.
#[test]
fn an_overlay_of_a_time_window_keeps_the_files_clock() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("w.csv");
    let dlc = Shipped {
        flags: &[
            "--fps",
            "100",
            "--rod-length",
            "0.251",
            "--rail-frame",
            "--t-start",
            "0.5",
        ],
        ..shipped().swap_remove(1)
    };
    fit_with_overlay(&dlc, &csv);
    let text = std::fs::read_to_string(&csv).unwrap();
    let first = text.lines().nth(3).unwrap();
    assert!(first.starts_with("50,"), "{first}");

    let out = dir.path().join("w.mcap");
    let rec = root(RECORDING);
    let example = Shipped {
        flags: &["--t-start", "0.5"],
        ..shipped().swap_remove(4)
    };
    fit_with_overlay(&example, &out);
    let msgs = read_checked(&std::fs::read(&out).unwrap());
    let stamps: Vec<u64> = mcap::MessageStream::new(&std::fs::read(&rec).unwrap())
        .unwrap()
        .map(|m| m.unwrap().log_time)
        .collect();
    let want = stamps[0] + 500_000_000;
    assert!(stamps.contains(&want));
    let first = msgs
        .iter()
        .find(|m| m.topic == ov::TOPIC_MARKERS)
        .unwrap()
        .log_time;
    assert_eq!(first, want);
}
