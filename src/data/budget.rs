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
//!   per file byte.

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
}

/// Every resource, in the order of [`Budget`]'s counters.
const ALL: [Resource; 7] = [
    Resource::DecodedBytes,
    Resource::Samples,
    Resource::Series,
    Resource::Channels,
    Resource::Schemas,
    Resource::MetadataEntries,
    Resource::TfWork,
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
    file_bytes: u64,
    used: [u64; ALL.len()],
}

impl Budget {
    /// The budget of a file of `file_bytes` bytes (its size on disk, or the bytes given).
    pub fn new(path: &Path, file_bytes: u64) -> Self {
        Budget {
            path: path.to_owned(),
            file_bytes,
            used: [0; ALL.len()],
        }
    }

    /// The most of `r` this file may spend.
    pub fn limit(&self, r: Resource) -> u64 {
        let (floor, num, den, cap) = r.rule();
        floor
            .saturating_add((self.file_bytes / den).saturating_mul(num))
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
            return Err(DataError::OverBudget {
                path: self.path.clone(),
                what: r.name(),
                limit,
                file_bytes: self.file_bytes,
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
}
