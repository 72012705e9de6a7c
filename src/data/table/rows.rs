//! What the CSV-family readers share: delimited rows with line numbers and errors that name the
//! file, number and point cells, the time column (its name and units, and its cells turned into
//! seconds), and the checks every reader applies to what it reads: times that increase
//! ([`Clock`], also used by DeepLabCut's HDF5 reader through `data::dlc`) and points whole or
//! missing ([`all_or_none`]).

use crate::data::{Budget, DataError, ReadOptions, Resource};
use csv::StringRecord;
use std::io::Read;
use std::path::Path;

/// The longest line a text reader takes (bytes, line end included). The widest real header,
/// a 20-animal DeepLabCut table of 3,000 columns, is under 100 KB; without a cap one endless
/// line (`/dev/zero`) grows the csv crate's record, or a line reader's buffer, until memory
/// runs out.
pub(crate) const MAX_LINE_BYTES: u64 = 1 << 20;

/// A line longer than [`MAX_LINE_BYTES`], carried in an `io::Error` by [`LineCap`]; the
/// reader behind it knows which line it was reading.
#[derive(Debug)]
pub(crate) struct LineTooLong;

impl std::fmt::Display for LineTooLong {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "a line longer than {MAX_LINE_BYTES} bytes")
    }
}

impl std::error::Error for LineTooLong {}

/// A reader that fails with [`LineTooLong`] as soon as a line passes [`MAX_LINE_BYTES`], so
/// that the parser behind it never holds more than that of one line. It looks only at the
/// first and last line ends of each read (lines are short), and scans a read whole only when
/// the read is longer than the cap.
pub(crate) struct LineCap<R> {
    inner: R,
    /// Bytes of the current (unended) line.
    current: u64,
}

impl<R: Read> LineCap<R> {
    /// Cap the lines of `inner`.
    pub(crate) fn new(inner: R) -> Self {
        LineCap { inner, current: 0 }
    }
}

impl<R: Read> Read for LineCap<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        let chunk = &buf[..n];
        // A line ends at `\n`, or at `\r` as the csv crate also takes it.
        let end = |b: &u8| *b == b'\n' || *b == b'\r';
        let too_long = || std::io::Error::other(LineTooLong);
        let Some(first) = chunk.iter().position(end) else {
            self.current += n as u64;
            if self.current > MAX_LINE_BYTES {
                return Err(too_long());
            }
            return Ok(n);
        };
        if self.current + first as u64 + 1 > MAX_LINE_BYTES {
            return Err(too_long());
        }
        let last = chunk.iter().rposition(end).unwrap_or(first);
        // Lines wholly inside the read can be too long only when the read is.
        if (last - first) as u64 > MAX_LINE_BYTES {
            let mut start = first + 1;
            for (i, b) in chunk.iter().enumerate().take(last + 1).skip(first + 1) {
                if end(b) {
                    if (i + 1 - start) as u64 > MAX_LINE_BYTES {
                        return Err(too_long());
                    }
                    start = i + 1;
                }
            }
        }
        self.current = (n - last - 1) as u64;
        if self.current > MAX_LINE_BYTES {
            return Err(too_long());
        }
        Ok(n)
    }
}

/// A read error at line `line` as the file's error: a line over [`MAX_LINE_BYTES`] is a parse
/// error that names the line and the limit (bad input), anything else an I/O error.
pub(crate) fn read_error(path: &Path, line: u64, e: std::io::Error) -> DataError {
    if e.get_ref().is_some_and(|i| i.is::<LineTooLong>()) {
        return DataError::parse(
            path,
            format!("line {line}"),
            "line",
            format!("at most {MAX_LINE_BYTES} bytes per line"),
            "a longer line; refusing to read it",
        );
    }
    DataError::Io {
        path: path.to_owned(),
        source: e,
    }
}

/// Rows of a delimited file with line numbers and errors that name the file.
pub(super) struct Rows<R: Read> {
    rdr: csv::Reader<R>,
    /// The current row.
    pub(super) rec: StringRecord,
    path: std::path::PathBuf,
    /// The current row's line number.
    pub(super) line: u64,
    /// Whether a `nan` cell means a missing value (pandas and idtracker.ai write it so).
    pub(super) nan_missing: bool,
    /// Lines read before these rows (Tracker's head), for a long line's number.
    pub(super) lines_before: u64,
    /// The file's budget: the tracks a reader makes from its rows, and the cells read (which
    /// bound the positions every reader of rows keeps, whatever the length of the file or
    /// pipe) once they are over their limit.
    budget: std::cell::RefCell<Budget>,
    /// Cells read so far and their limit, kept here so that a row costs one addition (the
    /// budget is charged, and names the limit, once they are over).
    cells: u64,
    cells_limit: u64,
}

impl<R: Read> Rows<R> {
    /// Rows of `input` split at `delimiter`; `path` names the file in errors.
    pub(super) fn new(input: R, path: &Path, delimiter: u8) -> Self {
        let budget = Budget::capped(path);
        Rows {
            rdr: csv::ReaderBuilder::new()
                .has_headers(false)
                .flexible(true)
                .delimiter(delimiter)
                // Large reads: the input is the file itself, read straight into this buffer.
                .buffer_capacity(1 << 18)
                .from_reader(input),
            rec: StringRecord::new(),
            path: path.to_owned(),
            line: 0,
            nan_missing: false,
            lines_before: 0,
            cells: 0,
            cells_limit: budget.limit(Resource::Cells),
            budget: std::cell::RefCell::new(budget),
        }
    }

    /// Advance to the next row; `false` at the end.
    pub(super) fn next(&mut self) -> Result<bool, DataError> {
        match self.rdr.read_record(&mut self.rec) {
            Ok(more) => {
                if let Some(p) = self.rec.position() {
                    self.line = p.line();
                }
                self.cells += self.rec.len() as u64;
                if self.cells > self.cells_limit {
                    self.budget.get_mut().charge(Resource::Cells, self.cells)?;
                }
                Ok(more)
            }
            Err(e) => {
                if let csv::ErrorKind::Io(io) = e.kind() {
                    if io.get_ref().is_some_and(|i| i.is::<LineTooLong>()) {
                        // The record being read, the long line, starts where the last ended.
                        let line = self.lines_before + self.rdr.position().line();
                        let long = std::io::Error::other(LineTooLong);
                        return Err(read_error(&self.path, line, long));
                    }
                }
                let line = e.position().map_or(self.line + 1, |p| p.line());
                Err(DataError::parse(
                    &self.path,
                    format!("line {line}"),
                    "row",
                    "UTF-8 delimited text",
                    e.to_string(),
                ))
            }
        }
    }

    /// Spend `n` of `r` from the file's budget (a reader that makes a track per new name in
    /// its rows charges the tracks here).
    pub(super) fn charge(&self, r: Resource, n: u64) -> Result<(), DataError> {
        self.budget.borrow_mut().charge(r, n)
    }

    /// Where the current row is: `line N`.
    pub(super) fn at(&self) -> String {
        format!("line {}", self.line)
    }

    /// Cell `i` of the current row (empty past its end).
    pub(super) fn cell(&self, i: usize) -> &str {
        self.rec.get(i).unwrap_or("")
    }

    /// Whether every cell of the current row is blank.
    pub(super) fn is_blank(&self) -> bool {
        self.rec.iter().all(|c| c.trim().is_empty())
    }

    /// An error about `field` of the current row.
    pub(super) fn err(
        &self,
        field: impl Into<String>,
        expected: impl Into<String>,
        found: impl Into<String>,
    ) -> DataError {
        DataError::parse(&self.path, self.at(), field, expected, found)
    }

    /// The header row, or `Empty`.
    pub(super) fn header(&mut self, expected: &str) -> Result<Vec<String>, DataError> {
        if !self.next()? {
            return Err(DataError::Empty {
                path: self.path.clone(),
                expected: expected.into(),
            });
        }
        Ok(self.rec.iter().map(|c| c.trim().to_string()).collect())
    }

    /// A number cell: empty is `None`; text, NaN and infinities are errors.
    pub(super) fn num(
        &self,
        i: usize,
        field: &str,
        decimal_comma: bool,
    ) -> Result<Option<f64>, DataError> {
        self.num_named(i, || field.to_string(), decimal_comma)
    }

    /// [`Rows::num`] with the field's name made only for an error.
    pub(super) fn num_named(
        &self,
        i: usize,
        field: impl FnOnce() -> String,
        decimal_comma: bool,
    ) -> Result<Option<f64>, DataError> {
        let raw = self.cell(i).trim();
        if raw.is_empty() || (self.nan_missing && raw.eq_ignore_ascii_case("nan")) {
            return Ok(None);
        }
        let fixed;
        let c = if decimal_comma && raw.contains(',') {
            fixed = raw.replace(',', ".");
            fixed.as_str()
        } else {
            raw
        };
        match c.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(Some(v)),
            Ok(_) => Err(self.err(field(), "a finite number", format!("{raw:?}"))),
            Err(_) => Err(self.err(field(), "a number", format!("{raw:?}"))),
        }
    }

    /// A number cell that must be there.
    pub(super) fn req(&self, i: usize, field: &str, decimal_comma: bool) -> Result<f64, DataError> {
        self.num(i, field, decimal_comma)?
            .ok_or_else(|| self.err(field, "a number", "an empty cell"))
    }

    /// A point from two or three cells: all empty is missing, some empty is an error.
    pub(super) fn point<const N: usize>(
        &self,
        idx: [usize; N],
        name: &str,
        decimal_comma: bool,
    ) -> Result<Option<[f64; N]>, DataError> {
        let mut cells = [None; N];
        for (k, &i) in idx.iter().enumerate() {
            cells[k] = self.num_named(
                i,
                || format!("{name} {}", ["x", "y", "z"][k]),
                decimal_comma,
            )?;
        }
        all_or_none(cells).map_err(|present| {
            self.err(
                name,
                "all coordinates or none",
                format!("{present} of {N} cells filled"),
            )
        })
    }

    /// Reject a row that is shorter than the header.
    pub(super) fn width(&self, n: usize) -> Result<(), DataError> {
        if self.rec.len() < n {
            Err(self.err(
                "row",
                format!("{n} columns as in the header"),
                format!("{} columns", self.rec.len()),
            ))
        } else {
            Ok(())
        }
    }
}

/// The largest time (seconds from the first frame) a recording may hold: about 32 years, far
/// beyond any recording, and small enough that differences of times stay exact to 1e-7 s.
const MAX_SECONDS: f64 = 1e9;

/// A point from its coordinates: all missing is `None`; some missing is `Err(how many are
/// present)`.
pub(crate) fn all_or_none<const N: usize>(
    cells: [Option<f64>; N],
) -> Result<Option<[f64; N]>, usize> {
    let present = cells.iter().flatten().count();
    match present {
        0 => Ok(None),
        p if p == N => Ok(Some(cells.map(|c| c.unwrap_or_default()))),
        p => Err(p),
    }
}

/// Checks that one track's times increase.
#[derive(Default)]
pub(crate) struct Clock {
    prev: Option<f64>,
}

impl Clock {
    /// Check `t` against the previous time; `at` (called only for an error) says where.
    pub(crate) fn check(
        &mut self,
        path: &Path,
        at: impl FnOnce() -> String,
        t: f64,
    ) -> Result<(), DataError> {
        if t.is_finite() && t.abs() < MAX_SECONDS && self.prev.is_none_or(|prev| t > prev) {
            self.prev = Some(t);
            return Ok(());
        }
        let at = at();
        if !(t.is_finite() && t.abs() < MAX_SECONDS) {
            return Err(DataError::parse(
                path,
                &at,
                "time",
                format!("a time within +-{MAX_SECONDS:e} s of the first frame"),
                t.to_string(),
            ));
        }
        if let Some(prev) = self.prev {
            if t <= prev {
                return Err(DataError::Time {
                    path: path.to_owned(),
                    at,
                    time: t,
                    previous: prev,
                    problem: if t == prev {
                        "is repeated"
                    } else {
                        "goes backwards"
                    },
                });
            }
        }
        self.prev = Some(t);
        Ok(())
    }
}

/// What a time column holds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum TimeUnit {
    /// Seconds times this factor.
    Scaled(f64),
    /// Frame numbers (needs a frame rate).
    Frame,
}

/// The time column of a lower-cased header: seconds first, then ms, ns, then frames.
pub(super) fn time_column(header: &[String]) -> Option<(usize, TimeUnit)> {
    let find = |names: &[&str]| header.iter().position(|h| names.contains(&h.as_str()));
    if let Some(i) = find(&[
        "t",
        "time",
        "t_s",
        "time_s",
        "time (s)",
        "time (seconds)",
        "timestamp",
        "seconds",
    ]) {
        return Some((i, TimeUnit::Scaled(1.0)));
    }
    if let Some(i) = find(&["t_ms", "time_ms", "time (ms)"]) {
        return Some((i, TimeUnit::Scaled(1e-3)));
    }
    if let Some(i) = find(&["t_ns", "time_ns", "timestamp_ns"]) {
        return Some((i, TimeUnit::Scaled(1e-9)));
    }
    find(&[
        "frame",
        "fnum",
        "frame_idx",
        "frame_index",
        "frame index",
        "frame_id",
    ])
    .map(|i| (i, TimeUnit::Frame))
}

/// Turns a time cell into seconds relative to the first one (kept exact for integer
/// nanoseconds), with the first one's absolute value as the base.
pub(super) struct TimeReader {
    col: usize,
    unit: TimeUnit,
    fps: Option<f64>,
    /// The first time cell's value in seconds: what the times read are relative to.
    pub(super) base: Option<f64>,
    base_ns: Option<i64>,
    /// The last time cell read and what it came to: long files repeat a frame's time on
    /// every marker's row.
    last: Option<(String, f64)>,
}

impl TimeReader {
    /// A reader of column `col` in `unit`; frame numbers need `--fps` (`path` names the file
    /// in the error).
    pub(super) fn new(
        path: &Path,
        col: usize,
        unit: TimeUnit,
        opts: &ReadOptions,
    ) -> Result<Self, DataError> {
        if unit == TimeUnit::Frame && opts.fps.is_none() {
            return Err(DataError::Options {
                path: path.to_owned(),
                message: "the time column holds frame numbers: give the frame rate with --fps HZ"
                    .into(),
            });
        }
        Ok(TimeReader {
            col,
            unit,
            fps: opts.fps,
            base: None,
            base_ns: None,
            last: None,
        })
    }

    /// The current row's time, in seconds from the first (the last cell's time again when the
    /// cell repeats it).
    pub(super) fn read<R: Read>(&mut self, rows: &Rows<R>) -> Result<f64, DataError> {
        let raw = rows.cell(self.col);
        if let Some((text, t)) = &self.last {
            if text == raw {
                return Ok(*t);
            }
        }
        let t = self.parse(rows)?;
        let (text, last) = self.last.get_or_insert_with(|| (String::new(), t));
        text.clear();
        text.push_str(raw);
        *last = t;
        Ok(t)
    }

    /// A time cell in seconds from the first (after it, the same cell gives the same time).
    fn parse<R: Read>(&mut self, rows: &Rows<R>) -> Result<f64, DataError> {
        if self.unit == TimeUnit::Scaled(1e-9) {
            let raw = rows.cell(self.col).trim();
            if let Ok(ns) = raw.parse::<i64>() {
                let base = *self.base_ns.get_or_insert(ns);
                self.base.get_or_insert(base as f64 * 1e-9);
                return Ok((ns as i128 - base as i128) as f64 * 1e-9);
            }
        }
        let v = rows.req(self.col, "time", false)?;
        let secs = match self.unit {
            TimeUnit::Scaled(f) => v * f,
            TimeUnit::Frame => v / self.fps.expect("checked in new"),
        };
        let base = *self.base.get_or_insert(secs);
        Ok(if base == 0.0 { secs } else { secs - base })
    }
}

/// The header's cells, lower-cased.
pub(super) fn lower(h: &[String]) -> Vec<String> {
    h.iter().map(|c| c.to_lowercase()).collect()
}

/// Each cell's first column: headers are matched through this map, so that matching is linear
/// in the header however many columns it has.
pub(crate) fn first_index(cells: &[String]) -> std::collections::HashMap<&str, usize> {
    let mut at = std::collections::HashMap::with_capacity(cells.len());
    for (i, c) in cells.iter().enumerate() {
        at.entry(c.as_str()).or_insert(i);
    }
    at
}
