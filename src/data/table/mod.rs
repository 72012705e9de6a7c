//! Readers for the CSV family: one file per tool, each streaming its rows through the `csv`
//! crate (or, for the gnuplot-style Kinovea text, line by line) into marker series in file
//! units. This file dispatches a format to its reader and tells the XML and HDF5 variants that
//! share a format with a text export.
//!
//! The files:
//! - `rows.rs`: what the readers share: delimited rows with line numbers and errors that name
//!   the file (`Rows`), the time column and its units, the check that times increase (`Clock`)
//!   and that a point is whole or missing (`all_or_none`).
//! - `xyz.rs`: the 3-D motion-capture tables' shared steps (X, Y, Z columns grouped by marker,
//!   rows projected onto the plane of motion, length units), for Motive, Vicon and Qualisys.
//! - `wide.rs`: the plain wide CSV (`t,NAME_x,NAME_y,...`; also Anipose, idtracker.ai).
//! - `long.rs`: the long (tidy) CSV (`t,marker,x,y`).
//! - `tracker.rs`: Tracker's text exports (one track or `#multi:`).
//! - `dlc.rs`: DeepLabCut's CSV (its layout is `data::dlc`'s, shared with the HDF5 reader).
//! - `sleap.rs`: SLEAP's analysis CSV.
//! - `motive.rs`: OptiTrack Motive's CSV, with renamed unlabeled markers joined.
//! - `vicon.rs`: Vicon Nexus' CSV (its Trajectories section).
//! - `qualisys.rs`: Qualisys QTM's TSV.
//! - `kinovea.rs`: Kinovea's trajectory text export.
//! - `trex.rs`: TRex's per-individual CSV.

mod dlc;
mod kinovea;
mod long;
mod motive;
mod qualisys;
pub(super) mod rows;
mod sleap;
mod tracker;
mod trex;
mod vicon;
mod wide;
mod xyz;

pub(super) use long::long_columns;
pub(super) use tracker::tracker_header_delimiter;
pub(super) use wide::wide_markers;

use super::{DataError, Format, Parsed, ReadOptions};
use dlc::read_dlc;
use kinovea::read_kinovea;
use long::read_long;
use motive::read_motive;
use qualisys::read_qualisys;
use rows::LineCap;
use sleap::read_sleap_csv;
use std::io::{BufRead, BufReader, Read};
use std::path::Path;
use tracker::read_tracker;
use trex::read_trex;
use vicon::read_vicon;
use wide::read_wide;

/// Read one CSV-family file in format `f`.
pub(crate) fn read(path: &Path, f: Format, opts: &ReadOptions) -> Result<Parsed, DataError> {
    let file = std::fs::File::open(path).map_err(|source| DataError::Io {
        path: path.to_owned(),
        source,
    })?;
    read_from(BufReader::with_capacity(1 << 16, file), path, f, opts)
}

/// Read CSV-family text from any reader; `path` labels errors.
pub(crate) fn read_from(
    input: impl Read,
    path: &Path,
    f: Format,
    opts: &ReadOptions,
) -> Result<Parsed, DataError> {
    // Text is read through `LineCap`, so that no line can grow a buffer past its cap; HDF5 and
    // XML are read whole, within their own byte caps.
    let text = LineCap::new;
    match f {
        Format::Wide => read_wide(text(input), path, opts),
        Format::Long => read_long(text(input), path, opts),
        Format::Tracker => read_tracker_any(input, path),
        Format::DeepLabCut => read_h5_or(input, path, opts, |i| read_dlc(i, path, opts)),
        Format::Motive => read_motive(text(input), path, opts),
        Format::Vicon => read_vicon(text(input), path, opts),
        Format::Sleap => read_h5_or(input, path, opts, |i| read_sleap_csv(i, path, opts)),
        Format::Qualisys => read_qualisys(text(input), path, opts),
        Format::Kinovea => read_kinovea_any(input, path, opts),
        Format::Trex => read_trex(text(input), path),
        Format::Mcap => unreachable!("MCAP is not a CSV format"),
    }
}

/// An HDF5 file (SLEAP's analysis file or DeepLabCut's DataFrame, told apart by content), or
/// else the CSV that `csv` reads (its lines capped).
fn read_h5_or<R: Read>(
    input: R,
    path: &Path,
    opts: &ReadOptions,
    csv: impl FnOnce(LineCap<BufReader<R>>) -> Result<Parsed, DataError>,
) -> Result<Parsed, DataError> {
    let mut input = BufReader::new(input);
    let io = |source| DataError::Io {
        path: path.to_owned(),
        source,
    };
    if input
        .fill_buf()
        .map_err(io)?
        .starts_with(super::hdf5::MAGIC)
    {
        let bytes = read_h5_bytes(input, path)?;
        return super::hdf5::read(bytes, path, opts);
    }
    csv(LineCap::new(input))
}

/// The bytes of `input`, at most `max` + 1 of them (one more than a reader takes, so that it can
/// tell a file that is too large).
fn read_at_most(input: impl Read, path: &Path, max: usize) -> Result<Vec<u8>, DataError> {
    let mut bytes = Vec::new();
    input
        .take(max as u64 + 1)
        .read_to_end(&mut bytes)
        .map_err(|source| DataError::Io {
            path: path.to_owned(),
            source,
        })?;
    Ok(bytes)
}

/// An HDF5 file's bytes, refused past [`super::hdf5::MAX_H5_BYTES`].
pub(crate) fn read_h5_bytes(input: impl Read, path: &Path) -> Result<Vec<u8>, DataError> {
    let bytes = read_at_most(input, path, super::hdf5::MAX_H5_BYTES)?;
    if bytes.len() > super::hdf5::MAX_H5_BYTES {
        return Err(DataError::parse(
            path,
            "the HDF5 file",
            "file",
            format!("at most {} bytes", super::hdf5::MAX_H5_BYTES),
            "more",
        ));
    }
    Ok(bytes)
}

/// A Kinovea text export, or (XML) its spreadsheet export.
fn read_kinovea_any(
    input: impl Read,
    path: &Path,
    opts: &ReadOptions,
) -> Result<Parsed, DataError> {
    let mut input = BufReader::new(input);
    let io = |source| DataError::Io {
        path: path.to_owned(),
        source,
    };
    let head = input.fill_buf().map_err(io)?;
    let head = String::from_utf8_lossy(&head[..head.len().min(64)]);
    if head
        .trim_start_matches('\u{feff}')
        .trim_start()
        .starts_with("<?xml")
    {
        let bytes = read_at_most(input, path, super::kinovea_xml::MAX_XML_BYTES)?;
        return super::kinovea_xml::read(&bytes, path, opts);
    }
    read_kinovea(LineCap::new(input), path)
}

/// A Tracker export, or (XML) a Tracker project.
fn read_tracker_any(input: impl Read, path: &Path) -> Result<Parsed, DataError> {
    let mut input = BufReader::new(input);
    let head = input.fill_buf().map_err(|source| DataError::Io {
        path: path.to_owned(),
        source,
    })?;
    let head = String::from_utf8_lossy(&head[..head.len().min(64)]);
    if head
        .trim_start_matches('\u{feff}')
        .trim_start()
        .starts_with("<?xml")
    {
        let bytes = read_at_most(input, path, super::tracker_project::MAX_TRK_BYTES)?;
        return super::tracker_project::read(&bytes, path);
    }
    read_tracker(LineCap::new(input), path)
}
