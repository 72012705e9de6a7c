//! What the HDF5 readers share to read no more than a file holds: the byte caps, a dataset's
//! raw bytes refused past them before they are read, and the numbers in those bytes (integers
//! and floats of any width and byte order).

use crate::data::{Budget, DataError, Resource};
use hdf5_reader::{ByteOrder, Dataset, Datatype};
use std::cell::RefCell;
use std::path::Path;

/// The most bytes an HDF5 input may be, and may decompress to in one read: far beyond an
/// analysis file of markers (a 2-track, 20-node hour at 100 Hz is under 100 MB).
pub(crate) const MAX_H5_BYTES: usize = 1 << 30;

/// How many times its file's size a dataset may decode to: deflate's largest ratio (1032:1), so
/// that a small file cannot declare a table it does not hold (DeepLabCut writes uncompressed).
pub(super) const MAX_RATIO: usize = 1032;

/// The file being read: its name, the most bytes one dataset may decode to, and the file's
/// budget, charged before anything is decoded.
pub(super) struct Src<'a> {
    /// The file's name, for errors.
    pub(super) path: &'a Path,
    /// The most bytes one dataset may decode to.
    pub(super) limit: usize,
    /// What the whole file may spend (every dataset and label together).
    pub(super) budget: RefCell<Budget>,
}

impl<'a> Src<'a> {
    /// The file `path` of `file_len` bytes.
    pub(super) fn new(path: &'a Path, file_len: usize) -> Self {
        Src {
            path,
            limit: MAX_H5_BYTES.min(file_len.saturating_mul(MAX_RATIO)),
            budget: RefCell::new(Budget::new(path, file_len as u64)),
        }
    }

    /// Spend `n` of `r` from the file's budget, or refuse the file.
    pub(super) fn charge(&self, r: Resource, n: u64) -> Result<(), DataError> {
        self.budget.borrow_mut().charge(r, n)
    }

    /// Charge the bytes `ds` declares (its element count times its element size, whatever its
    /// filters) before it is decoded: a small file cannot then decode to more than its budget.
    pub(super) fn charge_declared(&self, ds: &Dataset, at: &str) -> Result<(), DataError> {
        let len = ds.raw_byte_len().map_err(|e| {
            DataError::parse(
                self.path,
                at,
                ds.name(),
                "a readable dataset",
                e.to_string(),
            )
        })?;
        self.charge(Resource::DecodedBytes, len as u64)
    }
}

/// A number stored as an HDF5 integer or float of any size and byte order.
pub(super) fn number(bytes: &[u8], dt: &Datatype) -> Option<f64> {
    let (size, order) = match dt {
        Datatype::FixedPoint {
            size, byte_order, ..
        }
        | Datatype::FloatingPoint { size, byte_order } => (*size as usize, *byte_order),
        _ => return None,
    };
    let mut b = [0u8; 8];
    let src = bytes.get(..size)?;
    if order == ByteOrder::BigEndian {
        b[8 - size..].copy_from_slice(src);
        b.reverse();
    } else {
        b[..size].copy_from_slice(src);
    }
    let u = u64::from_le_bytes(b);
    Some(match dt {
        Datatype::FloatingPoint { size: 8, .. } => f64::from_bits(u),
        Datatype::FloatingPoint { size: 4, .. } => f32::from_bits(u as u32) as f64,
        Datatype::FixedPoint { signed: true, .. } if size < 8 => {
            let shift = 64 - 8 * size as u32;
            ((u << shift) as i64 >> shift) as f64
        }
        Datatype::FixedPoint { signed: true, .. } => u as i64 as f64,
        Datatype::FixedPoint { .. } => u as f64,
        _ => return None,
    })
}

/// Whether `dt` is a number [`number`] reads.
pub(super) fn numeric(dt: &Datatype) -> bool {
    matches!(
        dt,
        Datatype::FixedPoint {
            size: 1 | 2 | 4 | 8,
            ..
        } | Datatype::FloatingPoint { size: 4 | 8, .. }
    )
}

/// A dataset's raw bytes, refused past the file's limit before reading.
pub(super) fn raw(ds: &Dataset, at: &str, src: &Src) -> Result<Vec<u8>, DataError> {
    let bad =
        |expected: &str, found: String| DataError::parse(src.path, at, ds.name(), expected, found);
    let len = ds
        .raw_byte_len()
        .map_err(|e| bad("a readable dataset", e.to_string()))?;
    if len > src.limit {
        return Err(bad(
            &format!(
                "at most {} bytes ({MAX_RATIO} times the file's size, at most {MAX_H5_BYTES})",
                src.limit
            ),
            format!("{len} bytes declared"),
        ));
    }
    src.charge(Resource::DecodedBytes, len as u64)?;
    ds.read_raw_bytes()
        .map_err(|e| bad("a readable dataset", e.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_of_any_width_and_order() {
        let i8 = Datatype::FixedPoint {
            size: 1,
            signed: true,
            byte_order: ByteOrder::LittleEndian,
        };
        assert_eq!(number(&[0xff], &i8), Some(-1.0));
        let u16be = Datatype::FixedPoint {
            size: 2,
            signed: false,
            byte_order: ByteOrder::BigEndian,
        };
        assert_eq!(number(&[1, 2], &u16be), Some(258.0));
        let f32le = Datatype::FloatingPoint {
            size: 4,
            byte_order: ByteOrder::LittleEndian,
        };
        assert_eq!(number(&1.5f32.to_le_bytes(), &f32le), Some(1.5));
        assert_eq!(number(&[1], &f32le), None);
    }
}
