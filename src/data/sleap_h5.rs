//! HDF5 inputs, read with the pure-Rust `hdf5-reader` crate (no C library): SLEAP analysis files
//! (`tracks[track][xy][node][frame]`, `node_names`, `track_names`; pixels, y down, NaN where
//! missing, no frame rate stored) here, and DeepLabCut's pandas DataFrame (told apart by its
//! content: a top-level group written by pandas) in [`super::dlc_h5`].

use super::{dlc_h5, DataError, Format, Parsed, ReadOptions, Series};
use hdf5_reader::{Hdf5File, OpenOptions};
use std::path::Path;

/// The HDF5 signature.
pub const MAGIC: &[u8] = b"\x89HDF\r\n\x1a\n";

/// The most bytes an HDF5 input may be, and may decompress to in one read: far beyond an
/// analysis file of markers (a 2-track, 20-node hour at 100 Hz is under 100 MB).
pub const MAX_H5_BYTES: usize = 1 << 30;

/// The read limits of every HDF5 input.
fn limits() -> OpenOptions {
    OpenOptions::default()
        .with_max_read_bytes(MAX_H5_BYTES)
        .with_max_chunk_bytes(64 << 20)
}

/// Which format an HDF5 file holds: DeepLabCut when it has a pandas DataFrame, else SLEAP
/// (whose reader then says what is missing). Opens the file without reading it whole.
pub(crate) fn detect_file(path: &Path) -> Format {
    match Hdf5File::open_with_options(path, limits()) {
        Ok(f) if dlc_h5::pandas_key(&f).is_some() => Format::DeepLabCut,
        _ => Format::Sleap,
    }
}

/// [`detect_file`] for a file held in memory.
pub(crate) fn detect_bytes(bytes: &[u8]) -> Format {
    match Hdf5File::from_bytes_with_options(bytes, limits()) {
        Ok(f) if dlc_h5::pandas_key(&f).is_some() => Format::DeepLabCut,
        _ => Format::Sleap,
    }
}

/// Read an HDF5 file held in memory: DeepLabCut's DataFrame when it holds one, else a SLEAP
/// analysis file.
pub(crate) fn read(bytes: Vec<u8>, path: &Path, opts: &ReadOptions) -> Result<Parsed, DataError> {
    let bad = |field: &str, expected: &str, found: String| {
        DataError::parse(path, "the HDF5 file", field, expected, found)
    };
    let file_len = bytes.len();
    let f = Hdf5File::from_vec_with_options(bytes, limits())
        .map_err(|e| bad("file", "an HDF5 file", e.to_string()))?;
    if let Some(key) = dlc_h5::pandas_key(&f) {
        return dlc_h5::read(&f, &key, file_len, path, opts);
    }
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
