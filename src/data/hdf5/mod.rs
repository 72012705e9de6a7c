//! HDF5 inputs, read with the pure-Rust `hdf5-reader` crate (no C library): SLEAP analysis
//! files and DeepLabCut's pandas DataFrame, told apart by their content (a top-level group
//! written by pandas is DeepLabCut's).
//!
//! The files:
//! - `mod.rs`: the signature, the limits every file is opened with, which layout a file holds
//!   and the reader it goes to.
//! - `io.rs`: the byte caps, a dataset's bytes read under them, and numbers of any width and
//!   byte order.
//! - `dlc.rs`: DeepLabCut's DataFrame (pandas' table and fixed formats), its columns turned
//!   into series by `data::dlc`, as the CSV's are.
//! - `pickle.rs`: the column labels PyTables pickles, checked before they are decoded.
//! - `sleap.rs`: SLEAP's analysis file.

mod dlc;
mod io;
mod pickle;
mod sleap;

pub(super) use io::MAX_H5_BYTES;

use super::{DataError, Format, Parsed, ReadOptions};
use hdf5_reader::{Hdf5File, OpenOptions};
use std::path::Path;

/// The HDF5 signature.
pub const MAGIC: &[u8] = b"\x89HDF\r\n\x1a\n";

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
        Ok(f) if dlc::pandas_key(&f).is_some() => Format::DeepLabCut,
        _ => Format::Sleap,
    }
}

/// [`detect_file`] for a file held in memory.
pub(crate) fn detect_bytes(bytes: &[u8]) -> Format {
    match Hdf5File::from_bytes_with_options(bytes, limits()) {
        Ok(f) if dlc::pandas_key(&f).is_some() => Format::DeepLabCut,
        _ => Format::Sleap,
    }
}

/// Read an HDF5 file held in memory: DeepLabCut's DataFrame when it holds one, else a SLEAP
/// analysis file.
pub(crate) fn read(bytes: Vec<u8>, path: &Path, opts: &ReadOptions) -> Result<Parsed, DataError> {
    let bad = |field: &str, expected: &str, found: String| {
        DataError::parse(path, "the HDF5 file", field, expected, found)
    };
    // One budget for the whole file: what every dataset and label decodes to is charged
    // against it before it is decoded.
    let src = io::Src::new(path, bytes.len());
    let f = Hdf5File::from_vec_with_options(bytes, limits())
        .map_err(|e| bad("file", "an HDF5 file", e.to_string()))?;
    if let Some(key) = dlc::pandas_key(&f) {
        return dlc::read(&f, &key, &src, opts);
    }
    sleap::read(&f, &src, opts)
}
