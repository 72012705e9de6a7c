//! Throughput of the recording readers on large files, with the process's peak memory.
//!
//! ```text
//! cargo run --release --example read_throughput -- gen /tmp/big 1000000
//! cargo run --release --example read_throughput -- read /tmp/big/big.mcap
//! cargo run --release --example read_throughput -- read /tmp/big/big.csv
//! ```
//! Run `read` in its own process per file so the peak memory (VmHWM) belongs to that read.

use appell::data::{read_recording, ReadOptions, Recording};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Peak resident memory of this process (Linux), in MiB.
fn peak_mib() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb / 1024.0)
}

/// A pendulum-like recording without physics: the slider drifts, the bob swings.
fn synthetic(n: usize) -> Recording {
    let mut rec = Recording::default();
    for k in 0..n {
        let t = k as f64 / 1000.0;
        let x = 0.01 * (0.3 * t).sin();
        let th = 0.6 * (6.0 * t).cos() + 1.0;
        rec.times.push(t);
        rec.slider.push(Some([x, 0.0]));
        rec.bob.push(Some([x + 0.3 * th.cos(), -0.3 * th.sin()]));
    }
    rec
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args.first().map(String::as_str) {
        Some("gen") if args.len() >= 2 => {
            let dir = PathBuf::from(&args[1]);
            let n: usize = args
                .get(2)
                .map_or(1_000_000, |s| s.parse().expect("frame count"));
            std::fs::create_dir_all(&dir).expect("output directory");
            let rec = synthetic(n);
            let meta = Default::default();
            appell::data::synth::write(&dir.join("big.mcap"), &rec, &meta).expect("write MCAP");
            appell::data::synth::write(&dir.join("big.csv"), &rec, &meta).expect("write CSV");
            println!("wrote {n} frames to {}/big.mcap and big.csv", dir.display());
        }
        Some("read") if args.len() >= 2 => {
            let path = Path::new(&args[1]);
            let size = std::fs::metadata(path).map(|m| m.len()).unwrap_or(0);
            let t0 = Instant::now();
            let rec = read_recording(&[path.to_owned()], &ReadOptions::default())
                .unwrap_or_else(|e| panic!("{e}"));
            let secs = t0.elapsed().as_secs_f64();
            println!(
                "{}: {} frames, {:.1} MiB file, {:.3} s, {:.0} frames/s, peak memory {:.1} MiB",
                path.display(),
                rec.len(),
                size as f64 / 1048576.0,
                secs,
                rec.len() as f64 / secs,
                peak_mib().unwrap_or(f64::NAN)
            );
        }
        _ => eprintln!("usage: read_throughput gen DIR [FRAMES] | read FILE"),
    }
}
