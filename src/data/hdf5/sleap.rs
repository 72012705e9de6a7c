//! SLEAP's analysis HDF5 file: `tracks[track][xy][node][frame]`, `node_names`, `track_names`;
//! pixels, y down, NaN where missing, no frame rate stored.

use crate::data::{DataError, Parsed, ReadOptions, Series};
use hdf5_reader::Hdf5File;
use std::path::Path;

/// Read a SLEAP analysis file (`f`, opened from `path`): one series per track and node.
pub(super) fn read(f: &Hdf5File, path: &Path, opts: &ReadOptions) -> Result<Parsed, DataError> {
    let bad = |field: &str, expected: &str, found: String| {
        DataError::parse(path, "the HDF5 file", field, expected, found)
    };
    let Ok(tracks) = f.dataset("tracks") else {
        let found = match f.root_group().and_then(|g| g.member_names()) {
            Ok((groups, sets)) => format!("members {}", [groups, sets].concat().join(", ")),
            Err(e) => format!("no readable root group ({e})"),
        };
        return Err(bad(
            "tracks",
            "a SLEAP analysis file (a tracks dataset) or DeepLabCut's pandas DataFrame (a group such as df_with_missing written by pandas)",
            found,
        ));
    };
    let shape: Vec<usize> = tracks.shape().iter().map(|&d| d as usize).collect();
    let [n_tracks, two, n_nodes, n_frames] = shape[..] else {
        return Err(bad(
            "tracks",
            "4 dimensions [track][xy][node][frame]",
            format!("shape {shape:?}"),
        ));
    };
    if two != 2 {
        return Err(bad(
            "tracks",
            "2 coordinates (x, y) in the second dimension",
            format!("shape {shape:?}"),
        ));
    }
    let values = tracks
        .read_array::<f64>()
        .map_err(|e| bad("tracks", "64-bit or 32-bit floats", e.to_string()))?;
    let values: Vec<f64> = values.iter().copied().collect();
    if values.len() != n_tracks * 2 * n_nodes * n_frames {
        return Err(bad(
            "tracks",
            &format!(
                "{} values for shape {shape:?}",
                n_tracks * 2 * n_nodes * n_frames
            ),
            format!("{}", values.len()),
        ));
    }
    let strings = |name: &str| -> Vec<String> {
        f.dataset(name)
            .and_then(|d| d.read_strings())
            .unwrap_or_default()
    };
    let nodes = strings("node_names");
    let track_names = strings("track_names");
    let fps = opts.fps.ok_or_else(|| DataError::Options {
        path: path.to_owned(),
        message:
            "SLEAP files store frame numbers, not times: give the video's frame rate with --fps HZ"
                .into(),
    })?;
    let times: Vec<f64> = (0..n_frames).map(|k| k as f64 / fps).collect();
    let at =
        |t: usize, c: usize, n: usize, k: usize| values[((t * 2 + c) * n_nodes + n) * n_frames + k];
    let mut series = Vec::new();
    for t in 0..n_tracks {
        for n in 0..n_nodes {
            let node = nodes.get(n).cloned().unwrap_or_else(|| format!("node{n}"));
            let name = match track_names.get(t) {
                Some(tr) if n_tracks > 1 && !tr.is_empty() => format!("{tr}/{node}"),
                _ if n_tracks > 1 => format!("track{t}/{node}"),
                _ => node,
            };
            let points = (0..n_frames)
                .map(|k| {
                    let (x, y) = (at(t, 0, n, k), at(t, 1, n, k));
                    (x.is_finite() && y.is_finite()).then_some([x, y])
                })
                .collect();
            series.push(Series {
                name,
                times: times.clone(),
                points,
            });
        }
    }
    Ok(Parsed {
        series,
        y_down: true,
        notes: vec![format!(
            "SLEAP analysis HDF5: {n_tracks} track(s), {n_nodes} node(s), {n_frames} frames; pixels with y down, t = frame / {fps} Hz, NaN as missing"
        )],
        ..Parsed::default()
    })
}
