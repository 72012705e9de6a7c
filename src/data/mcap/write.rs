//! The writer: a recording as MCAP JSON marker frames (`lab.MarkerFrame2D`).

use crate::data::Recording;
use ::mcap::records::{MessageHeader, Metadata};
use ::mcap::McapError;
use serde::Serialize;
use std::collections::BTreeMap;
use std::io::Write;

/// A marker in a JSON frame message.
#[derive(Serialize)]
struct OutMarker<'a> {
    id: &'a str,
    x: Option<f64>,
    y: Option<f64>,
}

#[derive(Serialize)]
struct OutStamp {
    sec: i64,
    nsec: i64,
}

#[derive(Serialize)]
struct OutFrame<'a> {
    timestamp: OutStamp,
    frame_id: &'a str,
    markers: Vec<OutMarker<'a>>,
}

/// JSON Schema of the frame messages [`write_json`] writes (schema `lab.MarkerFrame2D`).
pub const FRAME_SCHEMA: &str = r#"{"title":"lab.MarkerFrame2D","type":"object","properties":{"timestamp":{"type":"object","properties":{"sec":{"type":"integer"},"nsec":{"type":"integer"}}},"frame_id":{"type":"string"},"markers":{"type":"array","items":{"type":"object","properties":{"id":{"type":"string"},"x":{"type":"number"},"y":{"type":"number"}}}}}}"#;

/// Write a recording as MCAP: topic `/markers`, JSON frames (`lab.MarkerFrame2D`, a markers
/// array, a missing marker with null x and y), zstd chunks, the stamps `start_ns` + t, and one metadata
/// record per entry of `metadata` (name -> key -> value).
pub fn write_json(
    w: &mut dyn Write,
    rec: &Recording,
    start_ns: i64,
    metadata: &BTreeMap<String, BTreeMap<String, String>>,
) -> Result<(), McapError> {
    let mut out = ::mcap::WriteOptions::new()
        .compression(Some(::mcap::Compression::Zstd))
        .profile("")
        .disable_seeking(true)
        .create(::mcap::write::NoSeek::new(w))?;
    let schema = out.add_schema("lab.MarkerFrame2D", "jsonschema", FRAME_SCHEMA.as_bytes())?;
    let channel = out.add_channel(schema, "/markers", "json", &BTreeMap::new())?;
    for (name, map) in metadata {
        out.write_metadata(&Metadata {
            name: name.clone(),
            metadata: map.clone(),
        })?;
    }
    let mut buf = Vec::with_capacity(256);
    for i in 0..rec.len() {
        let ns = start_ns + (rec.times[i] * 1e9).round() as i64;
        let mut markers = Vec::with_capacity(2);
        for (id, p) in [("slider", rec.slider[i]), ("bob", rec.bob[i])] {
            markers.push(OutMarker {
                id,
                x: p.map(|p| p[0]),
                y: p.map(|p| p[1]),
            });
        }
        let frame = OutFrame {
            timestamp: OutStamp {
                sec: ns.div_euclid(1_000_000_000),
                nsec: ns.rem_euclid(1_000_000_000),
            },
            frame_id: "rail",
            markers,
        };
        buf.clear();
        serde_json::to_writer(&mut buf, &frame).map_err(|e| McapError::Io(e.into()))?;
        out.write_to_known_channel(
            &MessageHeader {
                channel_id: channel,
                sequence: i as u32,
                log_time: ns as u64,
                publish_time: ns as u64,
            },
            &buf,
        )?;
    }
    out.finish()?;
    Ok(())
}
