//! A joint fit that cannot be made ([`JointError`]).

use crate::fit::error::FitError;

/// Why a joint fit could not run.
#[derive(Debug, thiserror::Error)]
pub enum JointError {
    /// Fewer than two releases to fit.
    #[error("a joint fit needs two or more recordings, got {0}")]
    TooFew(usize),
    /// Releases of different rigs.
    #[error("{0}")]
    OtherRig(String),
    /// A release's own fit failed.
    #[error("{name}: {error}")]
    Release {
        /// The release.
        name: String,
        /// Its failure.
        error: FitError,
    },
    /// The joint fit failed.
    #[error("the joint fit failed: {0}")]
    Joint(String),
    /// The releases together do not determine these shared parameters (nothing the markers
    /// show depends on them at their fitted values) and no nuisance the data chose frees them.
    #[error("the joint fit failed: the joint information matrix is singular ({}: not determined by the releases together)", .0.iter().map(|q| q.name()).collect::<Vec<_>>().join(", "))]
    Undetermined(Vec<crate::fit::problem::Param>),
}
