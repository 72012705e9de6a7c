//! The read benchmark: a long synthetic recording (the paper scene at 10 kHz, 0.5 mm noise)
//! written as canonical wide CSV, long (tidy) CSV and MCAP (JSON frames, zstd) to a temporary
//! directory, then read back with [`read_recording`], the function every command uses; the
//! median read time and frames per second per format.

use crate::data::synth::{self, synthesize, SynthOptions};
use crate::data::{read_recording, ReadOptions, Recording};
use crate::scene::Scene;
use serde::Serialize;
use std::io::Write;
use std::path::Path;
use std::time::Instant;

/// The paper's rig released from rest with the rod horizontal.
const SCENE: &str = include_str!("../../configs/paper_rest_horizontal.toml");

/// Frame rate of the benchmark's recording (Hz).
pub const FPS: f64 = 10_000.0;

/// Frames read by default: 100 s at 10 kHz.
pub const DEFAULT_FRAMES: usize = 1_000_000;

/// Read timing of one format.
#[derive(Debug, Clone, Serialize)]
pub struct ReadTiming {
    /// The format (`wide`, `long`, `mcap`).
    pub format: String,
    /// Frames in the recording.
    pub frames: usize,
    /// Size of the file (bytes).
    pub bytes: u64,
    /// Median wall time of one whole read (s).
    pub median_s: f64,
    /// Fastest read (s).
    pub min_s: f64,
    /// Frames read per second at the median.
    pub frames_per_s: f64,
    /// Reads timed (after one untimed warm-up read).
    pub runs: usize,
}

/// The benchmark's recording: the paper scene at [`FPS`] with 0.5 mm noise (seed 2), `frames`
/// frames long, and the truth it was made with.
pub fn recording(
    frames: usize,
) -> Result<(Recording, std::collections::BTreeMap<String, String>), String> {
    if frames < 2 {
        return Err(format!("at least 2 frames are needed, got {frames}"));
    }
    let scene = Scene::from_toml(SCENE, "configs/paper_rest_horizontal.toml".as_ref())
        .map_err(|e| e.to_string())?;
    let opts = SynthOptions {
        fps: FPS,
        duration: Some(frames as f64 / FPS),
        noise: 5e-4,
        seed: 2,
        ..SynthOptions::default()
    };
    let mut syn = synthesize(&scene, &opts).map_err(|e| e.to_string())?;
    let rec = &mut syn.recording;
    if rec.len() < frames {
        return Err(format!(
            "the simulation gave {} frames, fewer than {frames}",
            rec.len()
        ));
    }
    rec.times.truncate(frames);
    rec.slider.truncate(frames);
    rec.bob.truncate(frames);
    Ok((syn.recording, syn.truth))
}

/// Write `rec` as long (tidy) CSV: `t,marker,x,y`, one row per marker per frame.
fn write_long(path: &Path, rec: &Recording) -> std::io::Result<()> {
    let mut w = std::io::BufWriter::new(std::fs::File::create(path)?);
    writeln!(w, "t,marker,x,y")?;
    for i in 0..rec.len() {
        for (name, p) in [("slider", rec.slider[i]), ("bob", rec.bob[i])] {
            match p {
                Some([x, y]) => writeln!(w, "{},{name},{x},{y}", rec.times[i])?,
                None => writeln!(w, "{},{name},,", rec.times[i])?,
            }
        }
    }
    w.flush()
}

/// Write a `frames`-frame recording as wide CSV, long CSV and MCAP to a temporary directory
/// (removed afterwards, or on a signal) and time `batches` reads of each (after one untimed read) with
/// [`read_recording`] and default options. Every read must give back the frames written.
pub fn read_benchmark(frames: usize, batches: usize) -> Result<Vec<ReadTiming>, String> {
    let (rec, truth) = recording(frames)?;
    // Removed when done, and by the signal handler on SIGINT, SIGTERM or SIGHUP.
    let dir = crate::output::TempDir::new("appell-read-bench-")
        .map_err(|e| format!("creating a temporary directory: {e}"))?;
    let files = [
        ("wide", dir.path().join("recording.csv")),
        ("long", dir.path().join("recording_long.csv")),
        ("mcap", dir.path().join("recording.mcap")),
    ];
    for (format, path) in &files {
        match *format {
            "long" => write_long(path, &rec).map_err(|e| format!("{}: {e}", path.display()))?,
            _ => synth::write(path, &rec, &truth).map_err(|e| e.to_string())?,
        }
    }
    drop(rec);
    let opts = ReadOptions::default();
    let mut out = Vec::new();
    for (format, path) in &files {
        let bytes = std::fs::metadata(path)
            .map_err(|e| format!("{}: {e}", path.display()))?
            .len();
        let paths = [path.clone()];
        let read = || read_recording(&paths, &opts).map_err(|e| e.to_string());
        let got = read()?;
        if got.len() != frames {
            return Err(format!(
                "{format}: read {} frames, wrote {frames}",
                got.len()
            ));
        }
        drop(got);
        let mut times = Vec::with_capacity(batches.max(1));
        for _ in 0..batches.max(1) {
            let t = Instant::now();
            std::hint::black_box(read()?);
            times.push(t.elapsed().as_secs_f64());
        }
        times.sort_by(f64::total_cmp);
        let median = times[times.len() / 2];
        out.push(ReadTiming {
            format: format.to_string(),
            frames,
            bytes,
            median_s: median,
            min_s: times[0],
            frames_per_s: frames as f64 / median,
            runs: times.len(),
        });
    }
    Ok(out)
}
