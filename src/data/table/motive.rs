//! OptiTrack Motive's CSV export: a metadata row (format version, length units, export frame
//! rate), labelled or unlabelled header rows, then `Frame,Time,X,Y,Z,...`; y up. Markers Motive
//! renamed when they reappeared are joined under their first name.

use super::rows::Rows;
use super::xyz::{complete, group_xyz, read_xyz_rows_off_plane, unit_scale};
use crate::data::{DataError, Parsed, Plane, ReadOptions, Series};
use std::collections::HashMap;
use std::io::Read;
use std::path::Path;

/// Read a Motive CSV export: the markers' positions (rigid bodies' rotations are skipped).
pub(super) fn read_motive(
    input: impl Read,
    path: &Path,
    opts: &ReadOptions,
) -> Result<Parsed, DataError> {
    let mut rows = Rows::new(input, path, b',');
    let meta = rows.header("a Motive export (Format Version, ...)")?;
    let (units, rate) = units_and_rate(&meta);
    let head = header_rows(&mut rows, path)?;
    let markers = position_markers(&rows, head)?;
    let plane = opts.plane.unwrap_or(Plane::Xy);
    let scale = units.as_deref().and_then(unit_scale);
    // Time from the frame number and the export rate: the Time column is rounded (to the
    // millisecond in 1.23 exports).
    let rate_hz = rate
        .as_deref()
        .and_then(|r| r.parse::<f64>().ok())
        .filter(|r| r.is_finite() && *r > 0.0);
    let mut base = None;
    let (mut series, off_plane) = read_xyz_rows_off_plane(
        &mut rows,
        path,
        &markers,
        plane,
        &mut |r| match rate_hz {
            Some(hz) => {
                let f = r.req(0, "Frame", false)?;
                let b = *base.get_or_insert(f);
                Ok((f - b) / hz)
            }
            None => {
                let t = r.req(1, "Time (Seconds)", false)?;
                let b = *base.get_or_insert(t);
                Ok(t - b)
            }
        },
        false,
    )?;
    // Each marker's mean depth off the plane, by name before the joins (a joined marker keeps
    // its first name, and that name's depth).
    let off_plane = series
        .iter()
        .zip(off_plane)
        .filter_map(|(s, d)| Some((s.name.clone(), d?)))
        .collect();
    let (join_notes, joined, join_warning) = join_renamed_unlabeled(&mut series);
    let time_note = match rate_hz {
        Some(hz) => format!("t = (Frame - first frame) / Export Frame Rate {hz} Hz from the header (the Time column is rounded)"),
        None => "t from the Time column (no Export Frame Rate in the header)".to_string(),
    };
    let base = match rate_hz {
        Some(hz) => base.map(|f| f / hz),
        None => base,
    };
    Ok(Parsed {
        series,
        scale: Some(match scale {
            Some(s) => (
                s,
                format!("Length Units {} from the file", units.unwrap_or_default()),
            ),
            None => (1.0, "metres assumed: no Length Units in the file".into()),
        }),
        time_base: base.unwrap_or(0.0),
        notes: std::iter::once(format!(
            "Motive: plane {} (Motive's y is up; --plane to change); {time_note}",
            plane.name(),
        ))
        .chain(join_notes)
        .collect(),
        joined,
        warnings: join_warning.into_iter().collect(),
        plane: Some(plane),
        frame_rate: rate_hz,
        off_plane,
        ..Parsed::default()
    })
}

/// The length units and the export frame rate the metadata row names, as written.
fn units_and_rate(meta: &[String]) -> (Option<String>, Option<String>) {
    let mut units = None;
    let mut rate = None;
    for kv in meta.chunks(2) {
        if let [k, v] = kv {
            match k.as_str() {
                "Length Units" => units = Some(v.clone()),
                "Export Frame Rate" => rate = Some(v.clone()),
                _ => {}
            }
        }
    }
    (units, rate)
}

/// The header rows after the metadata.
struct HeaderRows {
    /// The `Frame,Time,X,Y,Z,...` row.
    header: Vec<String>,
    /// The marker names per column: the `,Name` row, else the second (or only) unlabelled row.
    names: Option<Vec<String>>,
    /// The `Position`/`Rotation` row (empty when there is none).
    kinds: Vec<String>,
}

/// Read the header rows up to `Frame,Time`, told apart by their label or their order.
fn header_rows<R: Read>(rows: &mut Rows<R>, path: &Path) -> Result<HeaderRows, DataError> {
    // Header rows between the metadata and `Frame,Time`: labelled `,Type`, `,Name`, `,ID`,
    // `,Parent` (1.23 on), or unlabelled in that order (1.21); the row of `Position` and
    // `Rotation` comes last.
    let mut labelled: HashMap<String, Vec<String>> = HashMap::new();
    let mut unlabelled: Vec<Vec<String>> = Vec::new();
    let mut kinds: Vec<String> = Vec::new();
    let header = loop {
        if !rows.next()? {
            return Err(DataError::NoFrames {
                path: path.to_owned(),
                what: "no Frame,Time header row and".into(),
            });
        }
        let row: Vec<String> = rows.rec.iter().map(|c| c.trim().to_string()).collect();
        if row.first().is_some_and(|c| c.eq_ignore_ascii_case("frame")) {
            break row;
        }
        if rows.is_blank() {
            continue;
        }
        let label = row.get(1).map(|c| c.to_lowercase()).unwrap_or_default();
        if ["type", "name", "id", "parent"].contains(&label.as_str()) {
            labelled.insert(label, row);
        } else if row
            .iter()
            .skip(2)
            .any(|c| c.eq_ignore_ascii_case("position") || c.eq_ignore_ascii_case("rotation"))
        {
            kinds = row;
        } else {
            unlabelled.push(row);
        }
    };
    let names = labelled
        .remove("name")
        .or_else(|| unlabelled.get(1).cloned())
        .or_else(|| unlabelled.first().cloned());
    Ok(HeaderRows {
        header,
        names,
        kinds,
    })
}

/// The markers' X, Y, Z columns (positions only, named columns only); an error that says the
/// export holds no marker data when there are none.
fn position_markers<R: Read>(
    rows: &Rows<R>,
    head: HeaderRows,
) -> Result<Vec<(String, [usize; 3])>, DataError> {
    let HeaderRows {
        header,
        names,
        kinds,
    } = head;
    if header.len() <= 2
        || names
            .as_ref()
            .is_none_or(|n| n.iter().skip(2).all(|c| c.is_empty()))
    {
        return Err(rows.err(
            "header",
            "marker position columns X, Y, Z after Frame and Time",
            format!(
                "{:?}: this export holds no marker data (export again with markers or rigid bodies ticked)",
                header.join(",")
            ),
        ));
    }
    let names = names.expect("checked above");
    let groups = group_xyz(
        (2..header.len()).filter_map(|j| {
            let kind = kinds.get(j).map(String::as_str).unwrap_or("");
            (kind.eq_ignore_ascii_case("position") && !names.get(j)?.is_empty())
                .then(|| (j, names[j].clone()))
        }),
        &header,
    );
    complete(
        |e| rows.err("header", e, format!("{:?}", header.join(","))),
        groups,
    )
}

/// A marker hidden longer than this (seconds) is taken for a new marker when it reappears,
/// wherever it is.
const MAX_REAPPEAR_S: f64 = 0.5;
/// The most comparisons the joining may make (tracks that end early x all tracks): each end
/// is compared with every track, so a header of 20,000 unlabeled markers would cost seconds
/// and a pair list of gigabytes; a real take has at most a few hundred.
const MAX_JOIN_WORK: usize = 10_000_000;
/// Motive names a marker it has lost and found again anew ("Unlabeled 1036" comes back as
/// "Unlabeled 1052"): its track is split into a column that ends and one that starts later.
/// Join such pairs under the first name when the join is unambiguous: the new track starts
/// after the old one ends, at most [`MAX_REAPPEAR_S`] later, where the old one was heading
/// (its last velocity carried over the gap), nearer to that point than half the distance
/// from the old track's last position to any other marker then visible; the closest pairs
/// are joined first, each track at most once at either end. Returns a note per joined
/// marker, the (later name, kept name) pairs, and a warning when there are too many tracks
/// to try ([`MAX_JOIN_WORK`]).
fn join_renamed_unlabeled(
    series: &mut Vec<Series>,
) -> (Vec<String>, Vec<(String, String)>, Option<String>) {
    let unlabeled = |s: &Series| s.name.to_lowercase().starts_with("unlabeled");
    let spans: Vec<Option<(usize, usize)>> = series
        .iter()
        .map(|s| {
            let first = s.points.iter().position(Option::is_some)?;
            Some((first, s.points.iter().rposition(Option::is_some)?))
        })
        .collect();
    let frames = series.first().map_or(0, |s| s.points.len());
    // Only tracks that end early can have a successor, only late starters a predecessor.
    let ends: Vec<usize> = (0..series.len())
        .filter(|&k| unlabeled(&series[k]) && spans[k].is_some_and(|(_, e)| e + 1 < frames))
        .collect();
    let starts: Vec<usize> = (0..series.len())
        .filter(|&k| unlabeled(&series[k]) && spans[k].is_some_and(|(s, _)| s > 0))
        .collect();
    if ends.len().saturating_mul(series.len()) > MAX_JOIN_WORK {
        let warning = format!(
            "Motive: {} unlabeled tracks end early among {} tracks: too many to join renamed \
             markers (over {MAX_JOIN_WORK} comparisons); every track is kept under its own name",
            ends.len(),
            series.len()
        );
        return (Vec::new(), Vec::new(), Some(warning));
    }
    let mut pairs = Vec::new();
    for &a in &ends {
        let Some((_, end)) = spans[a] else { continue };
        let (times, pa) = (
            &series[a].times,
            series[a].points[end].expect("end of a span"),
        );
        // The last velocity (per frame), when the frame before the end has a position.
        let v = match end.checked_sub(1).and_then(|i| series[a].points[i]) {
            Some(p) => [pa[0] - p[0], pa[1] - p[1]],
            None => [0.0, 0.0],
        };
        let room = series
            .iter()
            .enumerate()
            .filter(|&(k, _)| k != a)
            .filter_map(|(_, s)| s.points[end])
            .map(|p| (p[0] - pa[0]).hypot(p[1] - pa[1]))
            .fold(f64::INFINITY, f64::min)
            / 2.0;
        for &b in &starts {
            let Some((start, _)) = spans[b] else { continue };
            if start <= end || times[start] - times[end] > MAX_REAPPEAR_S {
                continue;
            }
            let pb = series[b].points[start].expect("start of a span");
            let g = (start - end) as f64;
            let d = (pb[0] - pa[0] - v[0] * g).hypot(pb[1] - pa[1] - v[1] * g);
            if d < room {
                pairs.push((d, a, b));
            }
        }
    }
    pairs.sort_by(|x, y| x.0.total_cmp(&y.0));
    // successor[a] = b; each track gets at most one successor and one predecessor.
    let mut successor: Vec<Option<usize>> = vec![None; series.len()];
    // For each joined track (each track with a predecessor): the frames missing before it and
    // its distance from where the track before it was heading.
    let mut joins: Vec<Option<(usize, f64)>> = vec![None; series.len()];
    for (d, a, b) in pairs {
        if successor[a].is_some() || joins[b].is_some() {
            continue;
        }
        successor[a] = Some(b);
        let ((_, end), (start, _)) = (spans[a].expect("a span"), spans[b].expect("a span"));
        joins[b] = Some((start - end - 1, d));
    }
    // Fill each chain's head from its successors, then drop the successors.
    let (mut notes, mut joined) = (Vec::new(), Vec::new());
    for head in (0..series.len()).filter(|&k| joins[k].is_none()) {
        let mut next = successor[head];
        let mut parts = Vec::new();
        while let Some(b) = next {
            let (missing, d) = joins[b].expect("a joined track");
            joined.push((series[b].name.clone(), series[head].name.clone()));
            parts.push(format!(
                "{:?} after {missing} missing frames ({d:.3} file units from where it was heading)",
                series[b].name
            ));
            let tail = std::mem::take(&mut series[b].points);
            for (slot, p) in series[head].points.iter_mut().zip(tail) {
                if p.is_some() {
                    *slot = p;
                }
            }
            next = successor[b];
        }
        if !parts.is_empty() {
            notes.push(format!(
                "Motive: {:?} continues as {}: Motive renamed the marker when it reappeared; \
                 joined under the first name",
                series[head].name,
                parts.join(", then ")
            ));
        }
    }
    let mut heads = joins.iter().map(Option::is_none);
    series.retain(|_| heads.next().unwrap_or(true));
    (notes, joined, None)
}
