//! Qualisys QTM's TSV export: `KEY<tab>value` metadata lines, then the `Frame Time NAME X ...`
//! header and the rows, read through the 3-D steps of `xyz.rs`; millimetres, z up.

use super::rows::Rows;
use super::xyz::{complete, group_xyz, read_xyz_rows, unit_scale};
use crate::data::{DataError, Parsed, Plane, ReadOptions};
use std::collections::HashMap;
use std::io::Read;
use std::path::Path;

/// Qualisys QTM's TSV export: `KEY<tab>value` lines (`FREQUENCY`, `MARKER_NAMES`, ...), then
/// `Frame Time NAME X NAME Y NAME Z ...`; millimetres, z up.
pub(super) fn read_qualisys(
    input: impl Read,
    path: &Path,
    opts: &ReadOptions,
) -> Result<Parsed, DataError> {
    let mut rows = Rows::new(input, path, b'\t');
    let mut meta: HashMap<String, String> = HashMap::new();
    let header = loop {
        if !rows.next()? {
            return Err(DataError::NoFrames {
                path: path.to_owned(),
                what: "a QTM header without a Frame/Time column row and".into(),
            });
        }
        let row: Vec<String> = rows.rec.iter().map(|c| c.trim().to_string()).collect();
        let key = row.first().cloned().unwrap_or_default();
        if key.eq_ignore_ascii_case("frame") {
            break row;
        }
        // Old exports have no Frame/Time columns: their first numeric row is data.
        if key.parse::<f64>().is_ok() {
            return Err(rows.err(
                "header",
                "a row Frame, Time, NAME X, NAME Y, NAME Z (export with the column header option)",
                format!("{key:?}"),
            ));
        }
        meta.insert(key.to_uppercase(), row.get(1).cloned().unwrap_or_default());
    };
    let rate = meta
        .get("FREQUENCY")
        .and_then(|f| f.parse::<f64>().ok())
        .filter(|f| f.is_finite() && *f > 0.0);
    let axis: Vec<String> = header
        .iter()
        .map(|h| h.rsplit(' ').next().unwrap_or("").to_string())
        .collect();
    let groups = group_xyz(
        (2..header.len()).filter_map(|j| {
            let h = &header[j];
            let (name, _) = h.rsplit_once(' ')?;
            Some((j, name.to_string()))
        }),
        &axis,
    );
    let markers = complete(
        |e| rows.err("header", e, format!("{:?}", header.join(" "))),
        groups,
    )?;
    let time_col = header.iter().position(|h| h.eq_ignore_ascii_case("time"));
    let plane = opts.plane.unwrap_or(Plane::Xz);
    let mut first = None;
    let series = read_xyz_rows(
        &mut rows,
        path,
        &markers,
        plane,
        |r| match (rate, time_col) {
            (Some(hz), _) => {
                let f = r.req(0, "Frame", false)?;
                let f0 = *first.get_or_insert(f);
                Ok((f - f0) / hz)
            }
            (None, Some(tc)) => {
                let t = r.req(tc, "Time", false)?;
                let t0 = *first.get_or_insert(t);
                Ok(t - t0)
            }
            (None, None) => Err(r.err("FREQUENCY", "a frame rate in the header", "none")),
        },
        false,
    )?;
    let unit = meta.get("UNITS").cloned().unwrap_or_else(|| "mm".into());
    Ok(Parsed {
        series,
        scale: Some(match unit_scale(&unit) {
            Some(s) => (s, format!("QTM units {unit}")),
            None => (0.001, "millimetres (QTM's unit)".into()),
        }),
        notes: vec![format!(
            "Qualisys QTM TSV: {}; plane {} (QTM's z is up; --plane to change)",
            match rate {
                Some(hz) => format!("t = (Frame - first frame) / FREQUENCY {hz} Hz"),
                None => "t from the Time column".into(),
            },
            plane.name()
        )],
        plane: Some(plane),
        ..Parsed::default()
    })
}
