//! Kinovea's trajectory text export (gnuplot style), read line by line: a `# NAME` line per
//! trajectory, then its `t x y` rows. Its spreadsheet export (XML) is `data::kinovea_xml`'s.

use super::rows::{read_error, Clock};
use crate::data::kinovea_xml::locale_number;
use crate::data::{Budget, DataError, Parsed, Resource, Series};
use std::io::{BufRead, BufReader, Read};
use std::path::Path;

/// Kinovea's trajectory text export (gnuplot style): `#Kinovea Trajectory data export`,
/// `#T X Y`, then per trajectory a `# NAME` line and rows `t x y` (space-separated, the
/// locale's decimal separator), blocks separated by blank lines. Units are the calibration's.
pub(super) fn read_kinovea(input: impl Read, path: &Path) -> Result<Parsed, DataError> {
    let mut series: Vec<Series> = Vec::new();
    let mut clocks: Vec<Clock> = Vec::new();
    let mut saw_header = false;
    // Lines are capped (`LineCap`), not their number: the tracks and rows kept are charged.
    let mut budget = Budget::capped(path);
    let reader = BufReader::new(input);
    for (k, line) in reader.split(b'\n').enumerate() {
        let line = line.map_err(|e| read_error(path, k as u64 + 1, e))?;
        let line = String::from_utf8_lossy(&line);
        let line = line.trim_start_matches('\u{feff}').trim();
        let at = format!("line {}", k + 1);
        if line.is_empty() {
            continue;
        }
        if let Some(c) = line.strip_prefix('#') {
            let c = c.trim();
            if c.to_lowercase().starts_with("kinovea") {
                saw_header = true;
            } else if !c.eq_ignore_ascii_case("t x y") {
                budget.charge(Resource::Series, 1)?;
                series.push(Series {
                    name: c.to_string(),
                    ..Series::default()
                });
                clocks.push(Clock::default());
            }
            continue;
        }
        if !saw_header {
            return Err(DataError::parse(
                path,
                at,
                "header",
                "#Kinovea Trajectory data export",
                format!("{:?}", line.chars().take(60).collect::<String>()),
            ));
        }
        let Some(s) = series.last_mut() else {
            return Err(DataError::parse(
                path,
                at,
                "trajectory",
                "a '# NAME' line before the rows",
                format!("{line:?}"),
            ));
        };
        let cells: Vec<&str> = line.split_whitespace().collect();
        budget.charge(Resource::Cells, cells.len() as u64)?;
        let num = |i: usize, field: &str| {
            locale_number(cells.get(i).copied().unwrap_or(""), path, &at, field)
        };
        if cells.len() < 3 {
            return Err(DataError::parse(
                path,
                &at,
                "row",
                "three cells t x y",
                format!("{line:?}"),
            ));
        }
        let t = num(0, "t")?;
        clocks
            .last_mut()
            .expect("one per series")
            .check(path, || at.clone(), t)?;
        s.times.push(t);
        s.points.push(Some([num(1, "x")?, num(2, "y")?]));
    }
    series.retain(|s| !s.times.is_empty());
    if series.is_empty() {
        return Err(DataError::NoFrames {
            path: path.to_owned(),
            what: "a Kinovea header".into(),
        });
    }
    Ok(Parsed {
        series,
        notes: vec![
            "Kinovea trajectory export: times as written, positions in the calibration's units (y up)"
                .into(),
        ],
        ..Parsed::default()
    })
}
