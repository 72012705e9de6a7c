//! Fuzz scene, rig and plan files: any text gives a validated value or an error, never a
//! panic (sizes taken from numbers are bounded before any work, so nothing runs here).
#![no_main]

use appell::plan::spec::PlanSpec;
use appell::scene::{RigFile, Scene};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let path = std::path::Path::new("fuzz.toml");
    let _ = Scene::from_toml(text, path);
    let _ = RigFile::parse(text, path);
    let _ = PlanSpec::from_toml(text, path);
});
