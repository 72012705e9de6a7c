//! A recording that cannot be fitted ([`FitError`]).

use thiserror::Error;

/// A recording that cannot be fitted.
#[derive(Debug, Error)]
pub enum FitError {
    /// Too little data.
    #[error("too few frames with both markers ({0}); need at least 10")]
    TooFewFrames(usize),
    /// No start produced a usable model prediction.
    #[error("no start could be fitted: {0}")]
    NoStart(String),
    /// A setting out of range.
    #[error("{0}")]
    Settings(String),
    /// The mis-tracked filter dropped so many positions that too few frames with both
    /// markers are left: the sentence says how many, against which noise, and the fix.
    #[error("{0}")]
    AllDropped(String),
    /// Neither marker moves beyond its noise: nothing in the recording shows mu.
    #[error("{0}")]
    NoMotion(String),
}
