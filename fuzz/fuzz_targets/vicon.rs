//! Fuzz the vicon reader: any bytes give a recording or an error, never a panic.
#![no_main]

use appell::data::{read_recording_bytes, Format, ReadOptions};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let opts = ReadOptions {
        format: Some(Format::Vicon),
        fps: Some(30.0),
        scale: Some(1.0),
        ..ReadOptions::default()
    };
    let _ = read_recording_bytes(data, std::path::Path::new("fuzz-input"), &opts);
});
