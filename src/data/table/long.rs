//! The long (tidy) CSV: one row per marker per frame, `t,marker,x,y` (or the synonyms
//! [`long_columns`] accepts), metres assumed.

use super::rows::{lower, time_column, Clock, Rows, TimeReader, TimeUnit};
use crate::data::{DataError, Parsed, ReadOptions, Resource, Series};
use std::collections::HashMap;
use std::io::Read;
use std::path::Path;

/// Time, marker, x and y columns of a long-form lower-cased header.
pub(crate) fn long_columns(header: &[String]) -> Option<(usize, TimeUnit, usize, usize, usize)> {
    let find = |names: &[&str]| header.iter().position(|h| names.contains(&h.as_str()));
    let (t, unit) = time_column(header)?;
    let m = find(&[
        "marker",
        "name",
        "label",
        "track",
        "track_id",
        "bodypart",
        "body_part",
        "point",
        "object",
    ])?;
    let x = find(&["x", "x_m", "x (m)", "position_x", "pos_x"])?;
    let y = find(&["y", "y_m", "y (m)", "position_y", "pos_y"])?;
    Some((t, unit, m, x, y))
}

/// Read a long CSV: one series per marker name, in the order the names first appear.
pub(super) fn read_long(
    input: impl Read,
    path: &Path,
    opts: &ReadOptions,
) -> Result<Parsed, DataError> {
    let mut rows = Rows::new(input, path, b',');
    let header = rows.header("a header t,marker,x,y")?;
    let (tcol, unit, mcol, xcol, ycol) = long_columns(&lower(&header)).ok_or_else(|| {
        rows.err(
            "header",
            "columns for time, marker, x and y (e.g. t,marker,x,y)",
            format!("{:?}", header.join(",")),
        )
    })?;
    let mut time = TimeReader::new(path, tcol, unit, opts)?;
    let mut index: HashMap<String, usize> = HashMap::new();
    let mut series: Vec<Series> = Vec::new();
    let mut clocks: Vec<Clock> = Vec::new();
    let mut rowcount = 0usize;
    let mut next = 0usize;
    while rows.next()? {
        if rows.is_blank() {
            continue;
        }
        rows.width(header.len())?;
        let t = time.read(&rows)?;
        let name = rows.cell(mcol).trim();
        if name.is_empty() {
            return Err(rows.err("marker", "a marker name", "an empty cell"));
        }
        // Markers come in the same order in every frame: the one after the last row's first.
        let guess = next % series.len().max(1);
        let k = match series.get(guess) {
            Some(s) if s.name == name => guess,
            _ => match index.get(name) {
                Some(&k) => k,
                None => {
                    rows.charge(Resource::Series, 1)?;
                    index.insert(name.to_string(), series.len());
                    series.push(Series {
                        name: name.to_string(),
                        ..Series::default()
                    });
                    clocks.push(Clock::default());
                    series.len() - 1
                }
            },
        };
        next = k + 1;
        clocks[k].check(path, || format!("{} (marker {name:?})", rows.at()), t)?;
        let p = rows.point([xcol, ycol], name, false)?;
        series[k].times.push(t);
        series[k].points.push(p);
        rowcount += 1;
    }
    if rowcount == 0 {
        return Err(DataError::NoFrames {
            path: path.to_owned(),
            what: "a header".into(),
        });
    }
    Ok(Parsed {
        series,
        scale: opts.scale.is_none().then(|| {
            (
                1.0,
                "metres assumed (long CSV carries no units)".to_string(),
            )
        }),
        time_base: time.base.unwrap_or(0.0),
        ..Parsed::default()
    })
}
