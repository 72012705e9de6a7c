//! Errors of the recording readers and writers: each names the file, where in it, and what was
//! expected.

use std::path::PathBuf;
use thiserror::Error;

/// A recording that cannot be read or written. Every variant names the file; parse errors also
/// name the line (CSV) or record (MCAP), the field and what was expected.
#[derive(Debug, Error)]
pub enum DataError {
    /// The file would make a reader spend more than its budget (`budget.rs`).
    #[error("{path}: over the input budget: more than {limit} {what}{basis}; refusing to read it")]
    OverBudget {
        /// The file.
        path: PathBuf,
        /// What would be spent (decoded bytes, marker tracks, ...).
        what: &'static str,
        /// The limit for this file.
        limit: u64,
        /// Where the limit comes from: the file's size, or a fixed limit for every file.
        basis: String,
    },
    /// The file could not be opened or read.
    #[error("{path}: cannot read: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// The file is empty.
    #[error("{path}: the file is empty (expected {expected})")]
    Empty {
        /// The file.
        path: PathBuf,
        /// What the file should have held.
        expected: String,
    },
    /// A header without any data row or message.
    #[error("{path}: no frames: the file has {what} but no data")]
    NoFrames {
        /// The file.
        path: PathBuf,
        /// What was found (a header, channels, ...).
        what: String,
    },
    /// A cell, column, line or message that does not hold what it should.
    #[error("{path}: {at}: {field}: expected {expected}, found {found}")]
    Parse {
        /// The file.
        path: PathBuf,
        /// Where: `line N` for text files, `message N on TOPIC` or `record N` for MCAP.
        at: String,
        /// The column, field or key at fault.
        field: String,
        /// What should have been there.
        expected: String,
        /// What was there (quoted when it is text).
        found: String,
    },
    /// Times that go backwards or repeat within one marker's track.
    #[error("{path}: {at}: time {time} s {problem} (previous {previous} s); times must increase")]
    Time {
        /// The file.
        path: PathBuf,
        /// Where.
        at: String,
        /// The offending time.
        time: f64,
        /// The time before it.
        previous: f64,
        /// `goes backwards` or `is repeated`.
        problem: &'static str,
    },
    /// The format could not be told from the header.
    #[error(
        "{path}: cannot tell the format from the first line {first_line:?}; give --format (one of {supported})"
    )]
    UnknownFormat {
        /// The file.
        path: PathBuf,
        /// The first line, shortened.
        first_line: String,
        /// The formats this reader knows.
        supported: String,
    },
    /// A marker asked for (or the default name) is not in the recording.
    #[error("{path}: the {role} marker {wanted} never appears; markers present: {available}")]
    MissingMarker {
        /// The file(s).
        path: PathBuf,
        /// `slider` or `bob`.
        role: &'static str,
        /// The name or rule used.
        wanted: String,
        /// The markers found.
        available: String,
    },
    /// More than one marker matches a name.
    #[error(
        "{path}: the {role} marker {wanted} is ambiguous: {candidates} all match; give --{role} NAME"
    )]
    AmbiguousMarker {
        /// The file(s).
        path: PathBuf,
        /// `slider` or `bob`.
        role: &'static str,
        /// The name or rule used.
        wanted: String,
        /// The matching markers.
        candidates: String,
    },
    /// An encoding (message, schema or chunk compression) this reader cannot decode.
    #[error("{path}: {what} {found:?} is not supported; supported: {supported}")]
    Unsupported {
        /// The file.
        path: PathBuf,
        /// What kind of encoding (`channel /x message encoding`, `chunk compression`, ...).
        what: String,
        /// The encoding found.
        found: String,
        /// The encodings that are supported.
        supported: String,
    },
    /// An MCAP file without any channel that carries marker positions.
    #[error("{path}: no marker channel: {channels}; expected {expected}")]
    NoMarkerChannel {
        /// The file.
        path: PathBuf,
        /// The channels found (topic, encoding, schema).
        channels: String,
        /// What a marker channel looks like.
        expected: String,
    },
    /// An MCAP file damaged before any frame could be read.
    #[error("{path}: {at}: damaged MCAP file: {message}")]
    Mcap {
        /// The file.
        path: PathBuf,
        /// The record where reading stopped.
        at: String,
        /// What is wrong (one line: the mcap crate's error without its backtrace).
        message: String,
    },
    /// Options that do not fit the input (e.g. a frame rate missing for a format without times).
    #[error("{path}: {message}")]
    Options {
        /// The file.
        path: PathBuf,
        /// What is missing or wrong, naming the flag.
        message: String,
    },
    /// Writing an output failed.
    #[error("{path}: cannot write: {source}")]
    Write {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
}

impl DataError {
    /// A parse error at a location.
    pub(crate) fn parse(
        path: &std::path::Path,
        at: impl Into<String>,
        field: impl Into<String>,
        expected: impl Into<String>,
        found: impl Into<String>,
    ) -> Self {
        DataError::Parse {
            path: path.to_owned(),
            at: at.into(),
            field: field.into(),
            expected: expected.into(),
            found: found.into(),
        }
    }
}
