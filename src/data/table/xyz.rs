//! The steps the 3-D motion-capture tables share (Motive, Vicon, Qualisys): X, Y, Z columns
//! grouped by marker, rows read into series projected onto the plane of motion, and the length
//! units they name.

use super::rows::{Clock, Rows};
use crate::data::{DataError, Plane, Series};
use std::collections::HashMap;
use std::io::Read;
use std::path::Path;

/// Metres per unit for a length unit's name (m, cm, mm, spelt out or not).
pub(super) fn unit_scale(unit: &str) -> Option<f64> {
    match unit.trim().to_lowercase().as_str() {
        "m" | "meters" | "metres" | "meter" | "metre" => Some(1.0),
        "cm" | "centimeters" | "centimetres" => Some(0.01),
        "mm" | "millimeters" | "millimetres" => Some(0.001),
        _ => None,
    }
}

/// Group 3-D position columns `(name, [x, y, z])` from per-column names and axis labels.
pub(super) fn group_xyz(
    names: impl Iterator<Item = (usize, String)>,
    axis: &[String],
) -> Vec<(String, [Option<usize>; 3])> {
    let mut out: Vec<(String, [Option<usize>; 3])> = Vec::new();
    let mut index: HashMap<String, usize> = HashMap::new();
    for (j, name) in names {
        let slot = match axis.get(j).map(|a| a.trim().to_lowercase()) {
            Some(a) if a == "x" => 0,
            Some(a) if a == "y" => 1,
            Some(a) if a == "z" => 2,
            _ => continue,
        };
        let k = *index.entry(name.clone()).or_insert_with(|| {
            out.push((name, [None; 3]));
            out.len() - 1
        });
        out[k].1[slot] = Some(j);
    }
    out
}

/// Read 3-D rows into series: `time(rows)` gives each row's time.
pub(super) fn read_xyz_rows<R: Read>(
    rows: &mut Rows<R>,
    path: &Path,
    markers: &[(String, [usize; 3])],
    plane: Plane,
    mut time: impl FnMut(&Rows<R>) -> Result<f64, DataError>,
    stop_at_blank: bool,
) -> Result<Vec<Series>, DataError> {
    read_xyz_rows_off_plane(rows, path, markers, plane, &mut time, stop_at_blank).map(|(s, _)| s)
}

/// [`read_xyz_rows`], with each marker's mean coordinate off the plane (the axis the
/// projection drops; `None` for a marker never seen), file units, in the markers' order: an
/// overlay written back in the file's three axes puts the model there.
pub(super) fn read_xyz_rows_off_plane<R: Read>(
    rows: &mut Rows<R>,
    path: &Path,
    markers: &[(String, [usize; 3])],
    plane: Plane,
    time: &mut dyn FnMut(&Rows<R>) -> Result<f64, DataError>,
    stop_at_blank: bool,
) -> Result<(Vec<Series>, Vec<Option<f64>>), DataError> {
    let off = match plane {
        Plane::Xy => 2,
        Plane::Xz => 1,
        Plane::Yz => 0,
    };
    let mut sums = vec![(0.0, 0usize); markers.len()];
    let mut series: Vec<Series> = markers
        .iter()
        .map(|(n, _)| Series {
            name: n.clone(),
            ..Series::default()
        })
        .collect();
    let mut times = Vec::new();
    let mut clock = Clock::default();
    while rows.next()? {
        // The csv crate skips blank lines: a section ends at a row of one cell (a blank line or
        // the next section's title).
        if stop_at_blank && rows.rec.len() == 1 {
            break;
        }
        if rows.is_blank() {
            continue;
        }
        let t = time(rows)?;
        clock.check(path, || rows.at(), t)?;
        times.push(t);
        for (k, (name, idx)) in markers.iter().enumerate() {
            let p = rows.point(*idx, name, false)?;
            if let Some(p) = p {
                sums[k].0 += p[off];
                sums[k].1 += 1;
            }
            series[k].points.push(p.map(|p| plane.project(p)));
        }
    }
    if times.is_empty() {
        return Err(DataError::NoFrames {
            path: path.to_owned(),
            what: "header rows".into(),
        });
    }
    for s in &mut series {
        s.times = times.clone();
    }
    let means = sums
        .into_iter()
        .map(|(sum, n)| (n > 0).then(|| sum / n as f64))
        .collect();
    Ok((series, means))
}

/// The markers of `groups` with all three columns; `rows_err(expected)` makes the header error
/// when there are none or one lacks a column.
pub(super) fn complete(
    rows_err: impl Fn(&str) -> DataError,
    groups: Vec<(String, [Option<usize>; 3])>,
) -> Result<Vec<(String, [usize; 3])>, DataError> {
    if groups.is_empty() {
        return Err(rows_err("marker position columns X, Y, Z"));
    }
    groups
        .into_iter()
        .map(|(n, [x, y, z])| match (x, y, z) {
            (Some(x), Some(y), Some(z)) => Ok((n, [x, y, z])),
            _ => Err(rows_err(&format!("X, Y and Z columns for {n:?}"))),
        })
        .collect()
}
