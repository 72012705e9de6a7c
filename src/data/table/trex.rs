//! TRex's per-individual CSV: a row per frame with the centroid, the weighted centroid and the
//! midline as markers, rows marked missing as lost; centimetres when the columns say so, y down.

use super::rows::{lower, Clock, Rows};
use crate::data::{DataError, Parsed, Series};
use std::io::Read;
use std::path::Path;

/// TRex's per-individual CSV: `frame`, `time`, `timestamp` (microseconds), `X (cm)`, `Y (cm)`,
/// `X#wcentroid (cm)`, ..., `midline_x`, `midline_y`, `missing`. Markers: `centroid`,
/// `wcentroid`, `midline`; centimetres when the columns say so, y down.
pub(super) fn read_trex(input: impl Read, path: &Path) -> Result<Parsed, DataError> {
    let mut rows = Rows::new(input, path, b',');
    rows.nan_missing = true;
    let header = rows.header("a TRex header frame,...,X (cm),Y (cm),...")?;
    let low = lower(&header);
    let find = |n: &str| low.iter().position(|c| c == n);
    let pairs: Vec<(&str, usize, usize)> = [
        ("centroid", ["x (cm)", "x"], ["y (cm)", "y"]),
        (
            "wcentroid",
            ["x#wcentroid (cm)", "x#wcentroid"],
            ["y#wcentroid (cm)", "y#wcentroid"],
        ),
        (
            "midline",
            ["midline_x", "midline_x"],
            ["midline_y", "midline_y"],
        ),
    ]
    .into_iter()
    .filter_map(|(n, xs, ys)| {
        let x = xs.iter().find_map(|c| find(c))?;
        let y = ys.iter().find_map(|c| find(c))?;
        Some((n, x, y))
    })
    .collect();
    if pairs.is_empty() {
        return Err(rows.err(
            "header",
            "TRex position columns X (cm), Y (cm)",
            format!("{:?}", header.join(",")),
        ));
    }
    let cm = low.iter().any(|c| c == "x (cm)");
    let (tcol, factor, what) = if let Some(i) = find("timestamp") {
        (i, 1e-6, "timestamp (microseconds)")
    } else if let Some(i) = find("time") {
        (i, 1.0, "time (seconds)")
    } else {
        return Err(rows.err(
            "header",
            "a timestamp or time column",
            format!("{:?}", header.join(",")),
        ));
    };
    let missing = find("missing");
    let mut series: Vec<Series> = pairs
        .iter()
        .map(|(n, ..)| Series {
            name: n.to_string(),
            ..Series::default()
        })
        .collect();
    let mut clock = Clock::default();
    let mut base = None;
    let mut times = Vec::new();
    while rows.next()? {
        if rows.is_blank() {
            continue;
        }
        rows.width(header.len())?;
        let raw = rows.req(tcol, what, false)? * factor;
        let b = *base.get_or_insert(raw);
        let t = raw - b;
        clock.check(path, || rows.at(), t)?;
        times.push(t);
        let lost = match missing {
            Some(m) => rows.num(m, "missing", false)?.is_some_and(|v| v != 0.0),
            None => false,
        };
        for (k, (n, x, y)) in pairs.iter().enumerate() {
            let p = rows.point([*x, *y], n, false)?;
            series[k].points.push(if lost { None } else { p });
        }
    }
    if times.is_empty() {
        return Err(DataError::NoFrames {
            path: path.to_owned(),
            what: "a TRex header".into(),
        });
    }
    for s in &mut series {
        s.times = times.clone();
    }
    Ok(Parsed {
        series,
        scale: cm.then(|| (0.01, "centimetres (TRex's X (cm), Y (cm))".to_string())),
        y_down: true,
        time_base: base.unwrap_or(0.0),
        notes: vec![format!(
            "TRex: t from {what}; rows marked missing count as missing; y down (image axes)"
        )],
        ..Parsed::default()
    })
}
