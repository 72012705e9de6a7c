//! SLEAP's analysis HDF5 file: `tracks[track][xy][node][frame]`, `node_names`, `track_names`;
//! pixels, y down, NaN where missing, no frame rate stored.

use super::io::Src;
use crate::data::{DataError, Parsed, ReadOptions, Resource, Series};
use hdf5_reader::Hdf5File;

/// Read a SLEAP analysis file (`f`, opened from `src`): one series per track and node. What
/// the `tracks` shape declares (series, positions, decoded bytes) is charged against the
/// file's budget before anything is decoded or built.
pub(super) fn read(f: &Hdf5File, src: &Src, opts: &ReadOptions) -> Result<Parsed, DataError> {
    let path = src.path;
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
    // Declared sizes, saturated: a shape past u64 is over every limit. First the values as
    // f64 (whatever the stored type and filters) and their copy, then what they make.
    let n_series = (n_tracks as u64).saturating_mul(n_nodes as u64);
    let n_values = n_series.saturating_mul(2).saturating_mul(n_frames as u64);
    src.charge(Resource::DecodedBytes, n_values.saturating_mul(16))?;
    src.charge(Resource::Series, n_series)?;
    src.charge(Resource::Samples, n_series.saturating_mul(n_frames as u64))?;
    let values = tracks
        .read_array::<f64>()
        .map_err(|e| bad("tracks", "64-bit or 32-bit floats", e.to_string()))?;
    let values: Vec<f64> = values.iter().copied().collect();
    if values.len() as u64 != n_values {
        return Err(bad(
            "tracks",
            &format!("{n_values} values for shape {shape:?}"),
            format!("{}", values.len()),
        ));
    }
    let strings = |name: &str| -> Result<Vec<String>, DataError> {
        // Names that cannot be read are left out (nodes are then numbered), as before; names
        // that can are charged for what they declare.
        let Some((d, len)) = f
            .dataset(name)
            .ok()
            .and_then(|d| Some((d.raw_byte_len().ok()?, d)).map(|(l, d)| (d, l)))
        else {
            return Ok(Vec::new());
        };
        src.charge(Resource::DecodedBytes, len as u64)?;
        Ok(d.read_strings().unwrap_or_default())
    };
    let nodes = strings("node_names")?;
    let track_names = strings("track_names")?;
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
        frame_rate: Some(fps),
        ..Parsed::default()
    })
}
