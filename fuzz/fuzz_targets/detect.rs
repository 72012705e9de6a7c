//! Fuzz format detection plus whichever reader it picks.
#![no_main]

use appell::data::{read_recording_bytes, ReadOptions};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = read_recording_bytes(data, std::path::Path::new("fuzz-input"), &ReadOptions::default());
});
