//! Tracker's text exports: one track (an optional name line, then `t x y`) or several
//! (`#multi:`, a name row, then `t x y t x y ...`), delimited by tab, semicolon, comma or space,
//! with the decimal comma of some locales. Projects (`.trk`, XML) are `data::tracker_project`'s.

use super::rows::{read_error, Clock, Rows};
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
    let head = read_head(&mut input, path)?;
    let header_line = head.lines.len() as u64;
    let groups = track_columns(&head, path, header_line)?;
    let decimal_comma = head.delim != b',';
    let mut rows = Rows::new(input, path, head.delim);
    rows.lines_before = header_line;
    let series = read_tracks(rows, &groups, path, header_line, decimal_comma)?;
    let notes = vec![note(path, &head, &series, decimal_comma)];
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

/// The lines of a Tracker export before its data.
struct Head {
    /// The lines read, up to three (`#multi:`, a name row, the column names), the column names
    /// last.
    lines: Vec<String>,
    /// The delimiter of the column names (and of the rows).
    delim: u8,
    /// The nearest line above the column names that is neither blank nor `#multi:`: the track's
    /// name, or the tracks' names in a multi-track export.
    names_row: Option<String>,
    /// Whether the export holds several tracks (its first line is `#multi:`).
    multi: bool,
}

/// One track's columns: its name and the cells of its t, x and y.
type Group = (String, usize, usize, usize);

/// Read the lines up to the column names (`t x y` in some delimiter): at most three, else an
/// error that says what was found.
fn read_head(input: &mut impl BufRead, path: &Path) -> Result<Head, DataError> {
    let io = |e, line: usize| read_error(path, line as u64 + 1, e);
    // Up to three lines before the data: `#multi:`, a name row, the column names.
    let mut head: Vec<String> = Vec::new();
    let (delim, names_row) = loop {
        let mut line = String::new();
        if input.read_line(&mut line).map_err(|e| io(e, head.len()))? == 0 || head.len() == 3 {
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
    let multi = head.first().is_some_and(|l| {
        l.trim_start_matches('\u{feff}')
            .trim()
            .eq_ignore_ascii_case("#multi:")
    });
    Ok(Head {
        lines: head,
        delim,
        names_row,
        multi,
    })
}

/// A head line without its byte-order mark and line end.
fn clean(l: &str) -> String {
    l.trim_start_matches('\u{feff}')
        .trim_end_matches(['\r', '\n'])
        .to_string()
}

/// The tracks' columns, named from the name row (or the file's name); an error when no x
/// column has a t before it and a y after it (`header_line` is the column names' line).
fn track_columns(head: &Head, path: &Path, header_line: u64) -> Result<Vec<Group>, DataError> {
    let (delim, multi, names_row) = (head.delim, head.multi, &head.names_row);
    let cols: Vec<String> = clean(&head.lines[head.lines.len() - 1])
        .split(delim as char)
        .map(tracker_column)
        .collect();
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "track".into());
    // One group per x column: its y is the next y, its t the nearest t before it, its name the
    // nearest name above it or before it in a multi-track name row.
    let name_cells: Vec<String> = match names_row {
        Some(l) if multi => clean(l)
            .split(delim as char)
            .map(|c| c.trim().trim_matches('"').to_string())
            .collect(),
        _ => Vec::new(),
    };
    let single_name = match names_row {
        Some(l) if !multi => clean(l).trim().trim_matches('"').to_string(),
        _ => stem.clone(),
    };
    // Per column, the next y at or after it, the last t and the last named cell at or before
    // it: one pass each, so that a header of many x columns is read in linear time.
    let mut next_y = vec![None; cols.len() + 1];
    for j in (0..cols.len()).rev() {
        next_y[j] = if cols[j] == "y" {
            Some(j)
        } else {
            next_y[j + 1]
        };
    }
    let mut last_t = vec![None; cols.len()];
    let mut last_name = vec![None; cols.len()];
    let (mut t, mut named) = (None, None);
    for j in 0..cols.len() {
        last_t[j] = t;
        if cols[j] == "t" {
            t = Some(j);
        }
        if name_cells.get(j).is_some_and(|n| !n.is_empty()) {
            named = Some(j);
        }
        last_name[j] = named;
    }
    let mut groups: Vec<Group> = Vec::new();
    for (xc, c) in cols.iter().enumerate() {
        if c != "x" {
            continue;
        }
        let Some(yc) = next_y[xc + 1] else {
            continue;
        };
        let Some(tc) = last_t[xc] else {
            continue;
        };
        let name = if multi {
            last_name[xc]
                .map(|j: usize| name_cells[j].clone())
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
    Ok(groups)
}

/// Read the data rows into one series per group (line numbers counted after the head's
/// `header_line` lines); a track's row without a point or a time is skipped, and tracks
/// without a row are dropped.
fn read_tracks<R: Read>(
    mut rows: Rows<R>,
    groups: &[Group],
    path: &Path,
    header_line: u64,
    decimal_comma: bool,
) -> Result<Vec<Series>, DataError> {
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
    Ok(series)
}

/// The note on what was read: the tracks, the delimiter, and how they were named.
fn note(path: &Path, head: &Head, series: &[Series], decimal_comma: bool) -> String {
    let multi = head.multi;
    format!(
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
        head.delim as char,
        match (&head.names_row, multi) {
            (None, _) => ", no name row (named after the file)",
            _ if decimal_comma => ", decimal comma accepted",
            _ => "",
        }
    )
}
