//! The plain wide CSV, the canonical format (`t,slider_x,slider_y,bob_x,bob_y`, metres), and the
//! wide tables other tools write: Anipose and DeepLabCut 3-D (`NAME_x,NAME_y,NAME_z`, no time
//! column), idtracker.ai (`x1,y1,x2,y2,...`, `nan` where lost).

use super::rows::{first_index, lower, time_column, Clock, Rows, TimeReader, TimeUnit};
use crate::data::{DataError, Parsed, Plane, ReadOptions, Series};
use std::io::Read;
use std::path::Path;

/// The marker columns of a lower-cased wide header: `NAME_x,NAME_y[,NAME_z]` (Anipose and
/// DeepLabCut 3-D add `_z`) or idtracker.ai's `x1,y1,x2,y2,...`; each as (name as written, x,
/// y, z).
pub(crate) fn wide_markers(header: &[String]) -> Vec<(String, usize, usize, Option<usize>)> {
    let low = lower(header);
    let at = first_index(&low);
    let find = |want: &str| at.get(want).copied();
    let mut out = Vec::new();
    for (i, h) in low.iter().enumerate() {
        if let Some(stem) = h.strip_suffix("_x") {
            if let Some(j) = find(&format!("{stem}_y")) {
                let z = find(&format!("{stem}_z"));
                out.push((header[i][..header[i].len() - 2].to_string(), i, j, z));
            }
        } else if let Some(n) = h.strip_prefix('x') {
            if !n.is_empty() && n.bytes().all(|b| b.is_ascii_digit()) {
                if let Some(j) = find(&format!("y{n}")) {
                    out.push((n.to_string(), i, j, None));
                }
            }
        }
    }
    out
}

/// The first non-empty lower-cased column name that appears twice, with both 1-based columns.
fn repeated_column(low: &[String]) -> Option<(&str, usize, usize)> {
    let mut seen = std::collections::HashMap::with_capacity(low.len());
    for (i, name) in low.iter().enumerate() {
        let name = name.trim();
        if name.is_empty() {
            continue;
        }
        if let Some(first) = seen.insert(name, i) {
            return Some((name, first + 1, i + 1));
        }
    }
    None
}

/// Read a wide CSV: a time column (or `--fps` to number the rows) and `NAME_x,NAME_y[,NAME_z]`
/// or `xN,yN` column pairs, one series per marker.
pub(super) fn read_wide(
    input: impl Read,
    path: &Path,
    opts: &ReadOptions,
) -> Result<Parsed, DataError> {
    let mut rows = Rows::new(input, path, b',');
    let header = rows.header("a header t,slider_x,slider_y,bob_x,bob_y")?;
    let low = lower(&header);
    // A column named twice (a marker exported twice, a pasted block) was read from its first
    // occurrence without a word: which copy holds the marker is the lab's to say.
    if let Some((name, first, second)) = repeated_column(&low) {
        return Err(rows.err(
            "header",
            "each column named once (delete or rename the copy)",
            format!("{name:?} as column {first} and again as column {second}"),
        ));
    }
    let time = time_column(&low);
    let pairs = wide_markers(&header);
    if pairs.is_empty() {
        return Err(rows.err(
            "header",
            "NAME_x,NAME_y column pairs (e.g. slider_x,slider_y,bob_x,bob_y)",
            format!("{:?}", header.join(",")),
        ));
    }
    // Without a time column (Anipose writes its frame number last, some files none at all),
    // frames are numbered by row and need --fps.
    let (tcol, unit) = match time {
        Some(t) => (Some(t.0), t.1),
        None if opts.fps.is_some() => (None, TimeUnit::Frame),
        None => {
            return Err(rows.err(
                "header",
                "a time column (t, time, seconds, t_ms, t_ns, or frame/fnum with --fps; or --fps to number the rows)",
                format!("{:?}", header.join(",")),
            ))
        }
    };
    let plane = opts.plane.unwrap_or(Plane::Xy);
    let mut time = TimeReader::new(path, tcol.unwrap_or(usize::MAX), unit, opts)?;
    let mut times = Vec::new();
    let mut tracks: Vec<Vec<Option<[f64; 2]>>> = vec![Vec::new(); pairs.len()];
    let mut clock = Clock::default();
    let mut row_number = 0u64;
    // idtracker.ai and Anipose write `nan` for a lost marker; in the canonical CSV it is an
    // error (missing is an empty cell).
    let foreign = pairs
        .iter()
        .any(|p| p.3.is_some() || p.0.bytes().all(|b| b.is_ascii_digit()));
    rows.nan_missing = foreign;
    while rows.next()? {
        if rows.is_blank() {
            continue;
        }
        rows.width(header.len())?;
        let t = match tcol {
            Some(_) => time.read(&rows)?,
            None => row_number as f64 / opts.fps.expect("checked above"),
        };
        row_number += 1;
        clock.check(path, || rows.at(), t)?;
        times.push(t);
        for (k, (name, i, j, z)) in pairs.iter().enumerate() {
            let p = match z {
                Some(z) => rows
                    .point([*i, *j, *z], name, false)?
                    .map(|p| plane.project(p)),
                None => rows.point([*i, *j], name, false)?,
            };
            tracks[k].push(p);
        }
    }
    if times.is_empty() {
        return Err(DataError::NoFrames {
            path: path.to_owned(),
            what: "a header".into(),
        });
    }
    let three_d = pairs.iter().any(|p| p.3.is_some());
    let mut notes = Vec::new();
    if three_d {
        notes.push(format!(
            "3-D columns NAME_x, NAME_y, NAME_z: plane {} (--plane to change)",
            plane.name()
        ));
    }
    if tcol.is_none() {
        notes.push(format!(
            "no time column: rows numbered from 0 at --fps {} Hz",
            opts.fps.unwrap_or_default()
        ));
    }
    let series = pairs
        .into_iter()
        .zip(tracks)
        .map(|((name, ..), points)| Series {
            name,
            times: times.clone(),
            points,
        })
        .collect();
    Ok(Parsed {
        series,
        // Canonical wide CSV is metres; 3-D tables (Anipose, DeepLabCut 3-D) and idtracker.ai
        // carry the calibration's or the camera's units.
        scale: (opts.scale.is_none()
            && !three_d
            && !header.iter().any(|h| h.eq_ignore_ascii_case("x1")))
        .then(|| (1.0, "metres, as the wide CSV is".to_string())),
        y_down: header.iter().any(|h| h.eq_ignore_ascii_case("x1")),
        time_base: time.base.unwrap_or(0.0),
        notes,
        plane: three_d.then_some(plane),
        ..Parsed::default()
    })
}
