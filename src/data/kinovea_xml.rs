//! Kinovea's spreadsheet export (Excel 2003 XML, `<?mso-application progid="Excel.Sheet"?>`):
//! per track a `Track` row, `Label :` and the name, the units (`Coords (x,y:cm; t:time)`), the
//! header `x y t`, then one row per point with the time as `h:mm:ss:cc`.

use super::{DataError, Parsed, ReadOptions, Series};
use roxmltree::Document;
use std::path::Path;

/// The largest spreadsheet read (bytes).
pub const MAX_XML_BYTES: usize = 64 << 20;

/// `h:mm:ss:cc` (hundredths), `mm:ss:cc` or plain seconds, in seconds.
fn time(cell: &str) -> Option<f64> {
    let parts: Vec<f64> = cell
        .trim()
        .split(':')
        .map(|p| p.trim().replace(',', ".").parse::<f64>().ok())
        .collect::<Option<_>>()?;
    let v = match parts[..] {
        [s] => s,
        [m, s, c] => m * 60.0 + s + c / 100.0,
        [h, m, s, c] => h * 3600.0 + m * 60.0 + s + c / 100.0,
        _ => return None,
    };
    v.is_finite().then_some(v)
}

/// Read the tracks of a Kinovea spreadsheet export.
/// Times are written to the hundredth, so at 24 fps two frames can show the same time: with
/// `--fps`, a track's rows are numbered from its first time instead.
pub(crate) fn read(bytes: &[u8], path: &Path, opts: &ReadOptions) -> Result<Parsed, DataError> {
    let bad = |at: String, field: &str, expected: &str, found: String| {
        DataError::parse(path, at, field, expected, found)
    };
    if bytes.len() > MAX_XML_BYTES {
        return Err(bad(
            "the file".into(),
            "file",
            &format!("at most {MAX_XML_BYTES} bytes"),
            format!("{} bytes", bytes.len()),
        ));
    }
    let text = std::str::from_utf8(bytes)
        .map_err(|e| bad("the file".into(), "file", "UTF-8 XML", e.to_string()))?;
    super::xml_limits::check_attributes(text, path)?;
    let doc = Document::parse(text).map_err(|e| {
        bad(
            format!("line {}", e.pos().row),
            "XML",
            "a Kinovea spreadsheet export",
            e.to_string(),
        )
    })?;
    let rows = sheet_rows(&doc);
    let mut series: Vec<Series> = Vec::new();
    let mut unit: Option<String> = None;
    let mut cols: Option<[usize; 3]> = None;
    let mut clock_prev: Option<f64> = None;
    for (line, cells) in &rows {
        let at = format!("line {line}");
        let first = cells.first().map(String::as_str).unwrap_or("");
        if first == "Label :" {
            series.push(Series {
                name: cells
                    .get(1)
                    .cloned()
                    .unwrap_or_else(|| format!("track{}", series.len())),
                ..Series::default()
            });
            cols = None;
            clock_prev = None;
        } else if let Some(u) = first.strip_prefix("Coords (") {
            // "x,y:cm; t:time)"
            unit = u
                .split(';')
                .next()
                .and_then(|xy| xy.split(':').nth(1))
                .map(|u| u.trim().to_string());
        } else if !series.is_empty()
            && cells.iter().any(|c| c == "x")
            && cells.iter().any(|c| c == "t")
        {
            let find = |n: &str| cells.iter().position(|c| c == n);
            cols = match (find("x"), find("y"), find("t")) {
                (Some(x), Some(y), Some(t)) => Some([x, y, t]),
                _ => None,
            };
        } else if cells.iter().all(|c| c.is_empty()) {
            cols = None;
        } else if let (Some(cols), Some(s)) = (cols, series.last_mut()) {
            read_point(cells, cols, s, &mut clock_prev, at, opts, path)?;
        }
    }
    series.retain(|s| !s.times.is_empty());
    if series.is_empty() {
        return Err(DataError::NoFrames {
            path: path.to_owned(),
            what: "a Kinovea spreadsheet without tracks".into(),
        });
    }
    Ok(Parsed {
        series,
        scale: coords_scale(unit.as_deref()),
        notes: vec![match opts.fps {
            Some(fps) => format!("Kinovea spreadsheet export: rows numbered at --fps {fps} Hz from each track's first time (the file's times are rounded to the hundredth), y up"),
            None => "Kinovea spreadsheet export: times h:mm:ss:cc (hundredths, as written), y up".into(),
        }],
        ..Parsed::default()
    })
}

/// The spreadsheet's rows: each row's line in the file and its cells' text, trimmed. Rows come
/// in the order of the text, so each line is counted on from the last row's (asking the
/// document for each row's position would rescan the text from its start). One walk of the
/// tree: a `Data` belongs to the innermost open `Row` (rows do not nest in Kinovea's export;
/// collecting each row's descendants would make nested rows quadratic: 400,000 of them, 4.4
/// MB, took 95 s).
fn sheet_rows(doc: &Document) -> Vec<(u32, Vec<String>)> {
    let text = doc.input_text().as_bytes();
    let (mut pos, mut line) = (0usize, 1u32);
    let mut rows: Vec<(u32, Vec<String>)> = Vec::new();
    // The open rows, innermost last: each one's index in `rows` and where its text ends.
    let mut open: Vec<(usize, usize)> = Vec::new();
    for n in doc.descendants() {
        let range = n.range();
        while open.last().is_some_and(|&(_, end)| end <= range.start) {
            open.pop();
        }
        match n.tag_name().name() {
            "Row" => {
                let start = range.start.max(pos);
                line += text[pos..start].iter().filter(|&&c| c == b'\n').count() as u32;
                pos = start;
                open.push((rows.len(), range.end));
                rows.push((line, Vec::new()));
            }
            "Data" => {
                if let Some(&(r, _)) = open.last() {
                    rows[r].1.push(n.text().unwrap_or("").trim().to_string());
                }
            }
            _ => {}
        }
    }
    rows
}

/// Add a track's row (`cells`, at `at`; its x, y and t in `cols`) to `s`: the time as written,
/// or with `--fps` the row's number after the track's first time; times must increase
/// (`clock_prev` is the track's last).
/// A finite number as Kinovea writes it in either export: with the locale's decimal
/// separator, a comma or a point; `field` at `at` names it in the error.
pub(crate) fn locale_number(
    raw: &str,
    path: &Path,
    at: &str,
    field: &str,
) -> Result<f64, DataError> {
    raw.replace(',', ".")
        .parse::<f64>()
        .ok()
        .filter(|v| v.is_finite())
        .ok_or_else(|| DataError::parse(path, at, field, "a finite number", format!("{raw:?}")))
}

fn read_point(
    cells: &[String],
    [x, y, t]: [usize; 3],
    s: &mut Series,
    clock_prev: &mut Option<f64>,
    at: String,
    opts: &ReadOptions,
    path: &Path,
) -> Result<(), DataError> {
    let num = |i: usize, field: &str| {
        locale_number(cells.get(i).map_or("", String::as_str), path, &at, field)
    };
    let raw_t = cells.get(t).map(String::as_str).unwrap_or("");
    let written = time(raw_t).ok_or_else(|| {
        DataError::parse(path, &at, "t", "a time h:mm:ss:cc", format!("{raw_t:?}"))
    })?;
    let tv = match (opts.fps, s.times.first()) {
        (Some(fps), Some(&t0)) => t0 + s.times.len() as f64 / fps,
        _ => written,
    };
    if (*clock_prev).is_some_and(|p| tv <= p) {
        if opts.fps.is_none() {
            return Err(DataError::parse(
                path,
                at,
                "t",
                "increasing times (they are rounded to the hundredth: give the video's frame rate with --fps HZ to number the rows)",
                format!("{raw_t:?} again"),
            ));
        }
        return Err(DataError::Time {
            path: path.to_owned(),
            at,
            time: tv,
            previous: clock_prev.unwrap_or_default(),
            problem: if *clock_prev == Some(tv) {
                "is repeated"
            } else {
                "goes backwards"
            },
        });
    }
    *clock_prev = Some(tv);
    s.times.push(tv);
    s.points.push(Some([num(x, "x")?, num(y, "y")?]));
    Ok(())
}

/// Metres per unit for the export's `Coords` unit (cm, mm, m), with the wording for the
/// report; `None` for any other unit.
fn coords_scale(unit: Option<&str>) -> Option<(f64, String)> {
    match unit {
        Some("cm") => Some((
            0.01,
            "centimetres (the export's Coords (x,y:cm))".to_string(),
        )),
        Some("mm") => Some((0.001, "millimetres (the export's Coords)".to_string())),
        Some("m") => Some((1.0, "metres (the export's Coords)".to_string())),
        _ => None,
    }
}
