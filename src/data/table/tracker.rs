//! Tracker's text exports: one track (an optional name line, then `t x y`) or several
//! (`#multi:`, a name row, then `t x y t x y ...`), delimited by tab, semicolon, comma or space,
//! with the decimal comma of some locales. Projects (`.trk`, XML) are `data::tracker_project`'s.

use super::rows::{Clock, Rows};
use crate::data::{DataError, Parsed, Series};
use std::io::{BufRead, BufReader, Read};
use std::path::Path;

/// A Tracker column name without its subscript (`x_{1}` is `x`), trimmed and lower-cased.
fn tracker_column(cell: &str) -> String {
    let c = cell.trim().trim_matches('"').to_lowercase();
    match c.find("_{") {
        Some(i) if c.ends_with('}') => c[..i].to_string(),
        _ => c,
    }
}

/// The delimiter of a Tracker column-name line (`t x y`), if it is one: the first of tab,
/// semicolon, comma and space that splits it into cells with t, x and y.
pub(crate) fn tracker_header_delimiter(line: &str) -> Option<u8> {
    let line = line
        .trim_start_matches('\u{feff}')
        .trim_end_matches(['\r', '\n']);
    [b'\t', b';', b',', b' '].into_iter().find(|&d| {
        let cells: Vec<String> = line.split(d as char).map(tracker_column).collect();
        cells.first().is_some_and(|c| c == "t")
            && cells.iter().any(|c| c == "x")
            && cells.iter().any(|c| c == "y")
    })
}

/// Read a Tracker text export: one series per track (per x column with its t and y).
pub(super) fn read_tracker(input: impl Read, path: &Path) -> Result<Parsed, DataError> {
    let mut input = BufReader::new(input);
    let io = |source| DataError::Io {
        path: path.to_owned(),
        source,
    };
    // Up to three lines before the data: `#multi:`, a name row, the column names.
    let mut head: Vec<String> = Vec::new();
    let (delim, names_row) = loop {
        let mut line = String::new();
        if input.read_line(&mut line).map_err(io)? == 0 || head.len() == 3 {
            return Err(if head.iter().all(|l| l.trim().is_empty()) {
                DataError::Empty {
                    path: path.to_owned(),
                    expected: "a Tracker export (track name, then t x y)".into(),
                }
            } else {
                DataError::parse(
                    path,
                    format!("line {}", head.len().max(1)),
                    "header",
                    "column names t, x, y separated by tab, comma, semicolon or space (after an optional track name or #multi: line)",
                    format!("{:?}", head.last().map(|l| l.trim()).unwrap_or("")),
                )
            });
        }
        if let Some(d) = tracker_header_delimiter(&line) {
            let names = head
                .iter()
                .rev()
                .find(|l| {
                    !l.trim().is_empty() && !l.trim_start_matches('\u{feff}').starts_with("#multi")
                })
                .cloned();
            head.push(line);
            break (d, names);
        }
        head.push(line);
    };
    let header_line = head.len() as u64;
    let clean = |l: &str| {
        l.trim_start_matches('\u{feff}')
            .trim_end_matches(['\r', '\n'])
            .to_string()
    };
    let cols: Vec<String> = clean(&head[head.len() - 1])
        .split(delim as char)
        .map(tracker_column)
        .collect();
    let multi = head.first().is_some_and(|l| {
        l.trim_start_matches('\u{feff}')
            .trim()
            .eq_ignore_ascii_case("#multi:")
    });
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "track".into());
    // One group per x column: its y is the next y, its t the nearest t before it, its name the
    // nearest name above it or before it in a multi-track name row.
    let name_cells: Vec<String> = match &names_row {
        Some(l) if multi => clean(l)
            .split(delim as char)
            .map(|c| c.trim().trim_matches('"').to_string())
            .collect(),
        _ => Vec::new(),
    };
    let single_name = match &names_row {
        Some(l) if !multi => clean(l).trim().trim_matches('"').to_string(),
        _ => stem.clone(),
    };
    let mut groups: Vec<(String, usize, usize, usize)> = Vec::new();
    for (xc, c) in cols.iter().enumerate() {
        if c != "x" {
            continue;
        }
        let Some(yc) = (xc + 1..cols.len()).find(|&j| cols[j] == "y") else {
            continue;
        };
        let Some(tc) = (0..xc).rev().find(|&j| cols[j] == "t") else {
            continue;
        };
        let name = if multi {
            (0..=xc.min(name_cells.len().saturating_sub(1)))
                .rev()
                .find(|&j| name_cells.get(j).is_some_and(|n| !n.is_empty()))
                .map(|j| name_cells[j].clone())
                .unwrap_or_else(|| format!("{stem} {}", groups.len() + 1))
        } else if groups.is_empty() {
            single_name.clone()
        } else {
            format!("{single_name} {}", groups.len() + 1)
        };
        groups.push((name, tc, xc, yc));
    }
    if groups.is_empty() {
        return Err(DataError::parse(
            path,
            format!("line {header_line}"),
            "header",
            "columns t, x and y",
            format!("{:?}", cols.join(" ")),
        ));
    }
    let decimal_comma = delim != b',';
    let mut rows = Rows::new(input, path, delim);
    let mut series: Vec<Series> = groups
        .iter()
        .map(|(name, ..)| Series {
            name: name.clone(),
            ..Series::default()
        })
        .collect();
    let mut clocks: Vec<Clock> = groups.iter().map(|_| Clock::default()).collect();
    while rows.next()? {
        if rows.is_blank() {
            continue;
        }
        rows.line += header_line;
        for (k, (name, tc, xc, yc)) in groups.iter().enumerate() {
            let p = rows.point([*xc, *yc], name, decimal_comma)?;
            let t = match rows.num(*tc, "t", decimal_comma)? {
                Some(t) => t,
                None if p.is_none() => continue,
                None => return Err(rows.err("t", "a time", "an empty cell")),
            };
            clocks[k].check(path, || rows.at(), t)?;
            series[k].times.push(t);
            series[k].points.push(p);
        }
    }
    if series.iter().all(|s| s.times.is_empty()) {
        return Err(DataError::NoFrames {
            path: path.to_owned(),
            what: "a track name and a header".into(),
        });
    }
    series.retain(|s| !s.times.is_empty());
    let notes = vec![format!(
        "Tracker file {}: {} {}, delimiter {:?}{}",
        path.display(),
        if multi {
            "multi-track export, tracks"
        } else {
            "track"
        },
        series
            .iter()
            .map(|s| format!("{:?}", s.name))
            .collect::<Vec<_>>()
            .join(", "),
        delim as char,
        match (&names_row, multi) {
            (None, _) => ", no name row (named after the file)",
            _ if decimal_comma => ", decimal comma accepted",
            _ => "",
        }
    )];
    Ok(Parsed {
        series,
        scale: Some((
            1.0,
            "metres assumed: Tracker writes no units (use --scale if calibrated otherwise)".into(),
        )),
        notes,
        ..Parsed::default()
    })
}
