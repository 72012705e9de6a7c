//! One budget per input file: what a reader may decode, hold and compute is counted against
//! limits derived from the file's size, so that no file, however it is built, can make the
//! tool allocate or compute without bound.
//!
//! Every limit is `min(cap, floor + ratio x file bytes)`: the ratio follows what real files of
//! the densest format need (with a wide margin), the floor lets small files hold a few
//! frames, and the absolute cap keeps the whole read well under a 4 GiB address space. A
//! reader charges what it is about to spend *before* it spends it, and a file over budget
//! is refused (exit 2) with the file, the resource and the limit named.
//!
//! The figures behind the ratios (the densest real inputs, `appell bench --read`):
//! - decoded bytes: zstd-compressed JSON frames decode to about 12 bytes per file byte, a
//!   deflated HDF5 dataset of one repeated value to about 1000; the budget allows 1032 per file
//!   byte (the ratio the readers already used for deflate) and at most 1 GiB;
//! - samples (marker positions kept): a 10^6-frame, two-marker recording holds 2 x 10^6 samples
//!   in 70 MB of MCAP and 89 MB of CSV, so 16 per file byte is a 200-fold margin; at most
//!   5 x 10^7 samples (about 1.2 GB as series of time and position);
//! - series (marker tracks): a lab's file holds a few to a few hundred; at most 10^5, and one
//!   per 16 file bytes (a track needs at least a name and a value);
//! - channels and schemas (MCAP): at most 1024 channels and 256 schemas whatever the size (a
//!   lab's file has a few; the largest real file here, a ROS 2 bag, has 10), each schema
//!   decoded once;
//! - metadata entries (MCAP metadata records and channel metadata): at most 10^4 in all;
//! - TF work (stamps x the depth of the frame chains walked, MCAP `/tf`): at most 10^8, and 64
//!   per file byte; the transforms kept until they are composed are bounded by the decoded
//!   bytes (76 bytes of CDR each at least, 80 bytes kept: frame names are kept once);
//! - table cells (the CSV family's rows, header included, counted as the csv crate splits
//!   them): at most 10^8 whatever the size, so that a file or pipe of any length keeps at most
//!   5 x 10^7 marker positions (two cells each at least; 1.8 GB resident for a wide CSV at the
//!   limit) and a bounded number of tracks. A cell takes at least two bytes, so no CSV under
//!   200 MB reaches it; a 10^6-frame recording of 30 3-D markers has 9 x 10^7.

use super::DataError;
use std::path::{Path, PathBuf};

/// What a reader spends.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Resource {
    /// Bytes produced by decompression or decoding (HDF5 filters, MCAP chunks, pickles).
    DecodedBytes,
    /// Marker positions kept (one per marker per frame).
    Samples,
    /// Marker tracks (series) created.
    Series,
    /// MCAP channels.
    Channels,
    /// Schemas decoded (each decoded once, then shared).
    Schemas,
    /// Metadata entries kept or scanned.
    MetadataEntries,
    /// Frame-chain steps walked to compose transforms (stamps x chain depth).
    TfWork,
    /// Cells of a delimited text table (CSV-family readers), which bound the positions and
    /// tracks those readers keep.
    Cells,
}

/// Every resource, in the order of [`Budget`]'s counters.
const ALL: [Resource; 8] = [
    Resource::DecodedBytes,
    Resource::Samples,
    Resource::Series,
    Resource::Channels,
    Resource::Schemas,
    Resource::MetadataEntries,
    Resource::TfWork,
    Resource::Cells,
];

impl Resource {
    /// The resource's name in messages.
    pub fn name(self) -> &'static str {
        match self {
            Resource::DecodedBytes => "decoded bytes",
            Resource::Samples => "marker positions",
            Resource::Series => "marker tracks",
            Resource::Channels => "channels",
            Resource::Schemas => "schemas",
            Resource::MetadataEntries => "metadata entries",
            Resource::TfWork => "transform-chain steps",
            Resource::Cells => "table cells",
        }
    }

    /// `(floor, per file bytes: numerator and denominator, absolute cap)`; see the module's
    /// notes for the figures.
    fn rule(self) -> (u64, u64, u64, u64) {
        match self {
            Resource::DecodedBytes => (64 << 20, 1032, 1, 1 << 30),
            Resource::Samples => (1 << 20, 16, 1, 50_000_000),
            Resource::Series => (1024, 1, 16, 100_000),
            Resource::Channels => (1024, 0, 1, 1024),
            Resource::Schemas => (256, 0, 1, 256),
            Resource::MetadataEntries => (10_000, 0, 1, 10_000),
            Resource::TfWork => (1 << 20, 64, 1, 100_000_000),
            Resource::Cells => (100_000_000, 0, 1, 100_000_000),
        }
    }

    fn index(self) -> usize {
        ALL.iter().position(|&r| r == self).unwrap_or(0)
    }
}

/// The budget of one input file: its limits and what has been spent.
#[derive(Clone, Debug)]
pub struct Budget {
    path: PathBuf,
    /// The file's size; `None` for a stream read to its end, whose limits are the caps.
    file_bytes: Option<u64>,
    used: [u64; ALL.len()],
}

impl Budget {
    /// The budget of a file of `file_bytes` bytes (its size on disk, or the bytes given).
    pub fn new(path: &Path, file_bytes: u64) -> Self {
        Budget {
            path: path.to_owned(),
            file_bytes: Some(file_bytes),
            used: [0; ALL.len()],
        }
    }

    /// The budget of an input read as a stream to its end (the CSV family, whose readers keep
    /// at most a few values per byte and so need no ratio): every limit at its cap.
    pub fn capped(path: &Path) -> Self {
        Budget {
            path: path.to_owned(),
            file_bytes: None,
            used: [0; ALL.len()],
        }
    }

    /// The most of `r` this file may spend.
    pub fn limit(&self, r: Resource) -> u64 {
        let (floor, num, den, cap) = r.rule();
        let Some(file_bytes) = self.file_bytes else {
            return cap;
        };
        floor
            .saturating_add((file_bytes / den).saturating_mul(num))
            .min(cap)
    }

    /// What is left of `r`.
    pub fn remaining(&self, r: Resource) -> u64 {
        self.limit(r).saturating_sub(self.used[r.index()])
    }

    /// Spend `n` of `r`, or refuse the file if that would go over its limit. Call it before
    /// allocating or computing what `n` counts.
    pub fn charge(&mut self, r: Resource, n: u64) -> Result<(), DataError> {
        let used = self.used[r.index()].saturating_add(n);
        let limit = self.limit(r);
        if used > limit {
            let (floor, num, _, cap) = r.rule();
            let basis = match self.file_bytes {
                Some(bytes) if num > 0 && floor < cap => format!(
                    " for a file of {bytes} bytes (the limits grow with the file's size up to a fixed cap)"
                ),
                _ => " (a fixed limit for every file)".to_string(),
            };
            return Err(DataError::OverBudget {
                path: self.path.clone(),
                what: r.name(),
                limit,
                basis,
            });
        }
        self.used[r.index()] = used;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn limits_grow_with_the_file_up_to_their_caps() {
        let small = Budget::new(Path::new("a"), 1000);
        let large = Budget::new(Path::new("a"), 1 << 40);
        for r in ALL {
            let (floor, _, _, cap) = r.rule();
            assert!(small.limit(r) >= floor.min(cap), "{r:?}");
            assert_eq!(large.limit(r), cap, "{r:?}");
            assert!(small.limit(r) <= large.limit(r));
        }
    }

    #[test]
    fn a_charge_over_the_limit_names_the_file_and_the_limit_and_spends_nothing() {
        let mut b = Budget::new(Path::new("rec.h5"), 100);
        let limit = b.limit(Resource::Series);
        b.charge(Resource::Series, limit - 1).unwrap();
        let e = b.charge(Resource::Series, 2).unwrap_err().to_string();
        assert!(
            e.contains("rec.h5") && e.contains(&limit.to_string()),
            "{e}"
        );
        assert!(e.contains("marker tracks"), "{e}");
        assert_eq!(b.remaining(Resource::Series), 1);
        b.charge(Resource::Series, 1).unwrap();
        assert!(b.charge(Resource::Series, u64::MAX).is_err());
    }

    #[test]
    fn a_stream_has_the_caps_and_its_message_does_not_invent_a_size() {
        let mut b = Budget::capped(Path::new("pipe"));
        for r in ALL {
            assert_eq!(b.limit(r), r.rule().3, "{r:?}");
        }
        let e = b
            .charge(Resource::Cells, 100_000_001)
            .unwrap_err()
            .to_string();
        assert!(e.contains("100000000 table cells (a fixed limit"), "{e}");
        let mut sized = Budget::new(Path::new("f"), 10);
        let e = sized
            .charge(Resource::Series, 5000)
            .unwrap_err()
            .to_string();
        assert!(e.contains("for a file of 10 bytes"), "{e}");
    }
}
