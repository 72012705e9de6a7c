//! SLEAP's analysis CSV: one row per instance per frame with a prediction, markers per node (and
//! track); pixels, y down, frame numbers timed by `--fps`. Its HDF5 analysis file is
//! `data::hdf5`'s.

use super::rows::{first_index, lower, Clock, Rows};
use crate::data::{DataError, Parsed, ReadOptions, Resource, Series};
use std::collections::HashMap;
use std::io::Read;
use std::path::Path;

/// SLEAP's analysis CSV: `track,frame_idx,instance.score,NODE.x,NODE.y,NODE.score,...`, one
/// row per instance per frame with a prediction (frames without one are left out); pixels, y
/// down. Markers are `NODE`, or `TRACK/NODE` when the track has a name.
pub(super) fn read_sleap_csv(
    input: impl Read,
    path: &Path,
    opts: &ReadOptions,
) -> Result<Parsed, DataError> {
    let mut rows = Rows::new(input, path, b',');
    rows.nan_missing = true;
    let header = rows.header("a SLEAP header track,frame_idx,instance.score,NODE.x,NODE.y,...")?;
    let low = lower(&header);
    let at = first_index(&low);
    let find = |n: &str| at.get(n).copied();
    let (Some(track_col), Some(frame_col)) = (find("track"), find("frame_idx")) else {
        return Err(rows.err(
            "header",
            "columns track and frame_idx",
            format!("{:?}", header.join(",")),
        ));
    };
    let nodes: Vec<(String, usize, usize)> = low
        .iter()
        .enumerate()
        .filter_map(|(i, h)| {
            let stem = h.strip_suffix(".x")?;
            let j = find(&format!("{stem}.y"))?;
            Some((header[i][..header[i].len() - 2].to_string(), i, j))
        })
        .collect();
    if nodes.is_empty() {
        return Err(rows.err(
            "header",
            "NODE.x,NODE.y column pairs",
            format!("{:?}", header.join(",")),
        ));
    }
    let fps = opts.fps.ok_or_else(|| DataError::Options {
        path: path.to_owned(),
        message:
            "SLEAP files store frame numbers, not times: give the video's frame rate with --fps HZ"
                .into(),
    })?;
    let mut index: HashMap<String, usize> = HashMap::new();
    let mut series: Vec<Series> = Vec::new();
    let mut clocks: Vec<Clock> = Vec::new();
    while rows.next()? {
        if rows.is_blank() {
            continue;
        }
        rows.width(header.len())?;
        let t = rows.req(frame_col, "frame_idx", false)? / fps;
        let track = rows.cell(track_col).trim().to_string();
        for (node, x, y) in &nodes {
            let name = if track.is_empty() {
                node.clone()
            } else {
                format!("{track}/{node}")
            };
            let k = match index.get(&name) {
                Some(&k) => k,
                None => {
                    rows.charge(Resource::Series, 1)?;
                    series.push(Series {
                        name: name.clone(),
                        ..Series::default()
                    });
                    clocks.push(Clock::default());
                    index.insert(name.clone(), series.len() - 1);
                    series.len() - 1
                }
            };
            clocks[k].check(path, || format!("{} (marker {name:?})", rows.at()), t)?;
            series[k].times.push(t);
            series[k].points.push(rows.point([*x, *y], &name, false)?);
        }
    }
    if series.is_empty() {
        return Err(DataError::NoFrames {
            path: path.to_owned(),
            what: "a SLEAP header".into(),
        });
    }
    Ok(Parsed {
        series,
        y_down: true,
        notes: vec![format!(
            "SLEAP analysis CSV: pixels with y down, t = frame_idx / {fps} Hz"
        )],
        frame_rate: Some(fps),
        ..Parsed::default()
    })
}
