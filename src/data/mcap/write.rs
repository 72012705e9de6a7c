//! The writer: a recording as MCAP JSON marker frames (`lab.MarkerFrame2D`).

use super::overlay::{OverlayFrame, OverlayWriter, Topics};
use crate::data::Recording;
use ::mcap::McapError;
use std::collections::BTreeMap;
use std::io::Write;

/// Write a recording as MCAP: topic `/markers`, JSON frames (`lab.MarkerFrame2D`, a markers
/// array, a missing marker with null x and y), zstd chunks, the stamps `start_ns` + t, and one
/// metadata record per entry of `metadata` (name -> key -> value): the overlay writer with
/// appell's own recording topic only.
pub fn write_json(
    w: &mut dyn Write,
    rec: &Recording,
    start_ns: i64,
    metadata: &BTreeMap<String, BTreeMap<String, String>>,
) -> Result<(), McapError> {
    let topics = Topics {
        lab_markers: true,
        recorded: false,
        model: false,
    };
    let mut out = OverlayWriter::new(w, start_ns.max(0) as u64, topics, &[], metadata)?;
    for i in 0..rec.len() {
        out.frame(&OverlayFrame {
            t: rec.times[i],
            recorded: Some([rec.slider[i], rec.bob[i]]),
            model: None,
        })?;
    }
    out.finish()
}
