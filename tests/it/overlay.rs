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
/// report printed in full and no file left.
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
        && std::os::unix::fs::symlink("/dev/full", d.join("full.mcap")).is_ok();
    let mut targets = vec![p("missing/o.mcap")];
    if full {
        targets.push(p("full.mcap"));
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
