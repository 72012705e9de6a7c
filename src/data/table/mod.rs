//! Readers for the CSV family: plain wide, long (tidy), Tracker, DeepLabCut, OptiTrack Motive
//! and Vicon Nexus. Each streams its rows through the `csv` crate and returns marker series in
//! file units.

use super::{dlc, DataError, Format, Parsed, Plane, ReadOptions, Series};
use csv::StringRecord;
use std::collections::HashMap;
use std::io::{BufRead, BufReader, Read};
use std::path::Path;

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
    match f {
        Format::Wide => read_wide(input, path, opts),
        Format::Long => read_long(input, path, opts),
        Format::Tracker => read_tracker_any(input, path),
        Format::DeepLabCut => read_h5_or(input, path, opts, |i| read_dlc(i, path, opts)),
        Format::Motive => read_motive(input, path, opts),
        Format::Vicon => read_vicon(input, path, opts),
        Format::Sleap => read_h5_or(input, path, opts, |i| read_sleap_csv(i, path, opts)),
        Format::Qualisys => read_qualisys(input, path, opts),
        Format::Kinovea => read_kinovea_any(input, path, opts),
        Format::Trex => read_trex(input, path),
        Format::Mcap => unreachable!("MCAP is not a CSV format"),
    }
}

/// Rows of a delimited file with line numbers and errors that name the file.
struct Rows<R: Read> {
    rdr: csv::Reader<R>,
    rec: StringRecord,
    path: std::path::PathBuf,
    line: u64,
    /// Whether a `nan` cell means a missing value (pandas and idtracker.ai write it so).
    nan_missing: bool,
}

impl<R: Read> Rows<R> {
    fn new(input: R, path: &Path, delimiter: u8) -> Self {
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
        }
    }

    /// Advance to the next row; `false` at the end.
    fn next(&mut self) -> Result<bool, DataError> {
        match self.rdr.read_record(&mut self.rec) {
            Ok(more) => {
                if let Some(p) = self.rec.position() {
                    self.line = p.line();
                }
                Ok(more)
            }
            Err(e) => {
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

    fn at(&self) -> String {
        format!("line {}", self.line)
    }

    fn cell(&self, i: usize) -> &str {
        self.rec.get(i).unwrap_or("")
    }

    fn is_blank(&self) -> bool {
        self.rec.iter().all(|c| c.trim().is_empty())
    }

    fn err(
        &self,
        field: impl Into<String>,
        expected: impl Into<String>,
        found: impl Into<String>,
    ) -> DataError {
        DataError::parse(&self.path, self.at(), field, expected, found)
    }

    /// The header row, or `Empty`.
    fn header(&mut self, expected: &str) -> Result<Vec<String>, DataError> {
        if !self.next()? {
            return Err(DataError::Empty {
                path: self.path.clone(),
                expected: expected.into(),
            });
        }
        Ok(self.rec.iter().map(|c| c.trim().to_string()).collect())
    }

    /// A number cell: empty is `None`; text, NaN and infinities are errors.
    fn num(&self, i: usize, field: &str, decimal_comma: bool) -> Result<Option<f64>, DataError> {
        self.num_named(i, || field.to_string(), decimal_comma)
    }

    /// [`Rows::num`] with the field's name made only for an error.
    fn num_named(
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
    fn req(&self, i: usize, field: &str, decimal_comma: bool) -> Result<f64, DataError> {
        self.num(i, field, decimal_comma)?
            .ok_or_else(|| self.err(field, "a number", "an empty cell"))
    }

    /// A point from two or three cells: all empty is missing, some empty is an error.
    fn point<const N: usize>(
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
    fn width(&self, n: usize) -> Result<(), DataError> {
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
pub(crate) const MAX_SECONDS: f64 = 1e9;

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
pub(crate) fn time_column(header: &[String]) -> Option<(usize, TimeUnit)> {
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

/// Time, marker, x and y columns of a long-form lower-cased header.
pub(crate) fn long_columns(header: &[String]) -> Option<(usize, TimeUnit, usize, usize, usize)> {
    let find = |names: &[&str]| header.iter().position(|h| names.contains(&h.as_str()));
    let (t, unit) = time_column(header)?;
    let m = find(&[
        "marker",
        "name",
        "label",
        "track",
        "track_id",
        "bodypart",
        "body_part",
        "point",
        "object",
    ])?;
    let x = find(&["x", "x_m", "x (m)", "position_x", "pos_x"])?;
    let y = find(&["y", "y_m", "y (m)", "position_y", "pos_y"])?;
    Some((t, unit, m, x, y))
}

/// Turns a time cell into seconds relative to the first one (kept exact for integer
/// nanoseconds), with the first one's absolute value as the base.
struct TimeReader {
    col: usize,
    unit: TimeUnit,
    fps: Option<f64>,
    base: Option<f64>,
    base_ns: Option<i64>,
    /// The last time cell read and what it came to: long files repeat a frame's time on
    /// every marker's row.
    last: Option<(String, f64)>,
}

impl TimeReader {
    fn new(path: &Path, col: usize, unit: TimeUnit, opts: &ReadOptions) -> Result<Self, DataError> {
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

    fn read<R: Read>(&mut self, rows: &Rows<R>) -> Result<f64, DataError> {
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

fn lower(h: &[String]) -> Vec<String> {
    h.iter().map(|c| c.to_lowercase()).collect()
}

/// The marker columns of a lower-cased wide header: `NAME_x,NAME_y[,NAME_z]` (Anipose and
/// DeepLabCut 3-D add `_z`) or idtracker.ai's `x1,y1,x2,y2,...`; each as (name as written, x,
/// y, z).
pub(crate) fn wide_markers(header: &[String]) -> Vec<(String, usize, usize, Option<usize>)> {
    let low = lower(header);
    let find = |want: &str| low.iter().position(|c| c == want);
    let mut out = Vec::new();
    for (i, h) in low.iter().enumerate() {
        if let Some(stem) = h.strip_suffix("_x") {
            if let Some(j) = find(&format!("{stem}_y")) {
                let z = find(&format!("{stem}_z"));
                out.push((header[i][..header[i].len() - 2].to_string(), i, j, z));
            }
        } else if let Some(n) = h.strip_prefix('x') {
            if !n.is_empty() && n.bytes().all(|b| b.is_ascii_digit()) {
                if let Some(j) = find(&format!("y{n}")) {
                    out.push((n.to_string(), i, j, None));
                }
            }
        }
    }
    out
}

fn read_wide(input: impl Read, path: &Path, opts: &ReadOptions) -> Result<Parsed, DataError> {
    let mut rows = Rows::new(input, path, b',');
    let header = rows.header("a header t,slider_x,slider_y,bob_x,bob_y")?;
    let low = lower(&header);
    let time = time_column(&low);
    let pairs = wide_markers(&header);
    if pairs.is_empty() {
        return Err(rows.err(
            "header",
            "NAME_x,NAME_y column pairs (e.g. slider_x,slider_y,bob_x,bob_y)",
            format!("{:?}", header.join(",")),
        ));
    }
    // Without a time column (Anipose writes its frame number last, some files none at all),
    // frames are numbered by row and need --fps.
    let (tcol, unit) = match time {
        Some(t) => (Some(t.0), t.1),
        None if opts.fps.is_some() => (None, TimeUnit::Frame),
        None => {
            return Err(rows.err(
                "header",
                "a time column (t, time, seconds, t_ms, t_ns, or frame/fnum with --fps; or --fps to number the rows)",
                format!("{:?}", header.join(",")),
            ))
        }
    };
    let plane = opts.plane.unwrap_or(Plane::Xy);
    let mut time = TimeReader::new(path, tcol.unwrap_or(usize::MAX), unit, opts)?;
    let mut times = Vec::new();
    let mut tracks: Vec<Vec<Option<[f64; 2]>>> = vec![Vec::new(); pairs.len()];
    let mut clock = Clock::default();
    let mut row_number = 0u64;
    // idtracker.ai and Anipose write `nan` for a lost marker; in the canonical CSV it is an
    // error (missing is an empty cell).
    let foreign = pairs
        .iter()
        .any(|p| p.3.is_some() || p.0.bytes().all(|b| b.is_ascii_digit()));
    rows.nan_missing = foreign;
    while rows.next()? {
        if rows.is_blank() {
            continue;
        }
        rows.width(header.len())?;
        let t = match tcol {
            Some(_) => time.read(&rows)?,
            None => row_number as f64 / opts.fps.expect("checked above"),
        };
        row_number += 1;
        clock.check(path, || rows.at(), t)?;
        times.push(t);
        for (k, (name, i, j, z)) in pairs.iter().enumerate() {
            let p = match z {
                Some(z) => rows
                    .point([*i, *j, *z], name, false)?
                    .map(|p| plane.project(p)),
                None => rows.point([*i, *j], name, false)?,
            };
            tracks[k].push(p);
        }
    }
    if times.is_empty() {
        return Err(DataError::NoFrames {
            path: path.to_owned(),
            what: "a header".into(),
        });
    }
    let three_d = pairs.iter().any(|p| p.3.is_some());
    let mut notes = Vec::new();
    if three_d {
        notes.push(format!(
            "3-D columns NAME_x, NAME_y, NAME_z: plane {} (--plane to change)",
            plane.name()
        ));
    }
    if tcol.is_none() {
        notes.push(format!(
            "no time column: rows numbered from 0 at --fps {} Hz",
            opts.fps.unwrap_or_default()
        ));
    }
    let series = pairs
        .into_iter()
        .zip(tracks)
        .map(|((name, ..), points)| Series {
            name,
            times: times.clone(),
            points,
        })
        .collect();
    Ok(Parsed {
        series,
        // Canonical wide CSV is metres; 3-D tables (Anipose, DeepLabCut 3-D) and idtracker.ai
        // carry the calibration's or the camera's units.
        scale: (opts.scale.is_none()
            && !three_d
            && !header.iter().any(|h| h.eq_ignore_ascii_case("x1")))
        .then(|| (1.0, "metres, as the wide CSV is".to_string())),
        y_down: header.iter().any(|h| h.eq_ignore_ascii_case("x1")),
        time_base: time.base.unwrap_or(0.0),
        notes,
        ..Parsed::default()
    })
}

fn read_long(input: impl Read, path: &Path, opts: &ReadOptions) -> Result<Parsed, DataError> {
    let mut rows = Rows::new(input, path, b',');
    let header = rows.header("a header t,marker,x,y")?;
    let (tcol, unit, mcol, xcol, ycol) = long_columns(&lower(&header)).ok_or_else(|| {
        rows.err(
            "header",
            "columns for time, marker, x and y (e.g. t,marker,x,y)",
            format!("{:?}", header.join(",")),
        )
    })?;
    let mut time = TimeReader::new(path, tcol, unit, opts)?;
    let mut index: HashMap<String, usize> = HashMap::new();
    let mut series: Vec<Series> = Vec::new();
    let mut clocks: Vec<Clock> = Vec::new();
    let mut rowcount = 0usize;
    let mut next = 0usize;
    while rows.next()? {
        if rows.is_blank() {
            continue;
        }
        rows.width(header.len())?;
        let t = time.read(&rows)?;
        let name = rows.cell(mcol).trim();
        if name.is_empty() {
            return Err(rows.err("marker", "a marker name", "an empty cell"));
        }
        // Markers come in the same order in every frame: the one after the last row's first.
        let guess = next % series.len().max(1);
        let k = match series.get(guess) {
            Some(s) if s.name == name => guess,
            _ => match index.get(name) {
                Some(&k) => k,
                None => {
                    index.insert(name.to_string(), series.len());
                    series.push(Series {
                        name: name.to_string(),
                        ..Series::default()
                    });
                    clocks.push(Clock::default());
                    series.len() - 1
                }
            },
        };
        next = k + 1;
        clocks[k].check(path, || format!("{} (marker {name:?})", rows.at()), t)?;
        let p = rows.point([xcol, ycol], name, false)?;
        series[k].times.push(t);
        series[k].points.push(p);
        rowcount += 1;
    }
    if rowcount == 0 {
        return Err(DataError::NoFrames {
            path: path.to_owned(),
            what: "a header".into(),
        });
    }
    Ok(Parsed {
        series,
        scale: opts.scale.is_none().then(|| {
            (
                1.0,
                "metres assumed (long CSV carries no units)".to_string(),
            )
        }),
        time_base: time.base.unwrap_or(0.0),
        ..Parsed::default()
    })
}

/// A Tracker column name without its subscript (`x_{1}` is `x`), trimmed and lower-cased.
pub(crate) fn tracker_column(cell: &str) -> String {
    let c = cell.trim().trim_matches('"').to_lowercase();
    match c.find("_{") {
        Some(i) if c.ends_with('}') => c[..i].to_string(),
        _ => c,
    }
}

/// The delimiter of a Tracker column-name line (`t x y`), if it is one: the first of tab,
/// semicolon, comma and space that splits it into cells with t, x and y.
pub(crate) fn tracker_header_delimiter(line: &str) -> Option<u8> {
    let line = line
        .trim_start_matches('\u{feff}')
        .trim_end_matches(['\r', '\n']);
    [b'\t', b';', b',', b' '].into_iter().find(|&d| {
        let cells: Vec<String> = line.split(d as char).map(tracker_column).collect();
        cells.first().is_some_and(|c| c == "t")
            && cells.iter().any(|c| c == "x")
            && cells.iter().any(|c| c == "y")
    })
}

/// An HDF5 file (SLEAP's analysis file or DeepLabCut's DataFrame, told apart by content), or
/// else the CSV that `csv` reads.
fn read_h5_or<R: Read>(
    input: R,
    path: &Path,
    opts: &ReadOptions,
    csv: impl FnOnce(BufReader<R>) -> Result<Parsed, DataError>,
) -> Result<Parsed, DataError> {
    let mut input = BufReader::new(input);
    let io = |source| DataError::Io {
        path: path.to_owned(),
        source,
    };
    if input
        .fill_buf()
        .map_err(io)?
        .starts_with(super::sleap_h5::MAGIC)
    {
        let bytes = read_h5_bytes(input, path)?;
        return super::sleap_h5::read(bytes, path, opts);
    }
    csv(input)
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

/// An HDF5 file's bytes, refused past [`super::sleap_h5::MAX_H5_BYTES`].
pub(crate) fn read_h5_bytes(input: impl Read, path: &Path) -> Result<Vec<u8>, DataError> {
    let bytes = read_at_most(input, path, super::sleap_h5::MAX_H5_BYTES)?;
    if bytes.len() > super::sleap_h5::MAX_H5_BYTES {
        return Err(DataError::parse(
            path,
            "the HDF5 file",
            "file",
            format!("at most {} bytes", super::sleap_h5::MAX_H5_BYTES),
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
    read_kinovea(input, path)
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
    read_tracker(input, path)
}

fn read_tracker(input: impl Read, path: &Path) -> Result<Parsed, DataError> {
    let mut input = BufReader::new(input);
    let io = |source| DataError::Io {
        path: path.to_owned(),
        source,
    };
    // Up to three lines before the data: `#multi:`, a name row, the column names.
    let mut head: Vec<String> = Vec::new();
    let (delim, names_row) = loop {
        let mut line = String::new();
        if input.read_line(&mut line).map_err(io)? == 0 || head.len() == 3 {
            return Err(if head.iter().all(|l| l.trim().is_empty()) {
                DataError::Empty {
                    path: path.to_owned(),
                    expected: "a Tracker export (track name, then t x y)".into(),
                }
            } else {
                DataError::parse(
                    path,
                    format!("line {}", head.len().max(1)),
                    "header",
                    "column names t, x, y separated by tab, comma, semicolon or space (after an optional track name or #multi: line)",
                    format!("{:?}", head.last().map(|l| l.trim()).unwrap_or("")),
                )
            });
        }
        if let Some(d) = tracker_header_delimiter(&line) {
            let names = head
                .iter()
                .rev()
                .find(|l| {
                    !l.trim().is_empty() && !l.trim_start_matches('\u{feff}').starts_with("#multi")
                })
                .cloned();
            head.push(line);
            break (d, names);
        }
        head.push(line);
    };
    let header_line = head.len() as u64;
    let clean = |l: &str| {
        l.trim_start_matches('\u{feff}')
            .trim_end_matches(['\r', '\n'])
            .to_string()
    };
    let cols: Vec<String> = clean(&head[head.len() - 1])
        .split(delim as char)
        .map(tracker_column)
        .collect();
    let multi = head.first().is_some_and(|l| {
        l.trim_start_matches('\u{feff}')
            .trim()
            .eq_ignore_ascii_case("#multi:")
    });
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "track".into());
    // One group per x column: its y is the next y, its t the nearest t before it, its name the
    // nearest name above it or before it in a multi-track name row.
    let name_cells: Vec<String> = match &names_row {
        Some(l) if multi => clean(l)
            .split(delim as char)
            .map(|c| c.trim().trim_matches('"').to_string())
            .collect(),
        _ => Vec::new(),
    };
    let single_name = match &names_row {
        Some(l) if !multi => clean(l).trim().trim_matches('"').to_string(),
        _ => stem.clone(),
    };
    let mut groups: Vec<(String, usize, usize, usize)> = Vec::new();
    for (xc, c) in cols.iter().enumerate() {
        if c != "x" {
            continue;
        }
        let Some(yc) = (xc + 1..cols.len()).find(|&j| cols[j] == "y") else {
            continue;
        };
        let Some(tc) = (0..xc).rev().find(|&j| cols[j] == "t") else {
            continue;
        };
        let name = if multi {
            (0..=xc.min(name_cells.len().saturating_sub(1)))
                .rev()
                .find(|&j| name_cells.get(j).is_some_and(|n| !n.is_empty()))
                .map(|j| name_cells[j].clone())
                .unwrap_or_else(|| format!("{stem} {}", groups.len() + 1))
        } else if groups.is_empty() {
            single_name.clone()
        } else {
            format!("{single_name} {}", groups.len() + 1)
        };
        groups.push((name, tc, xc, yc));
    }
    if groups.is_empty() {
        return Err(DataError::parse(
            path,
            format!("line {header_line}"),
            "header",
            "columns t, x and y",
            format!("{:?}", cols.join(" ")),
        ));
    }
    let decimal_comma = delim != b',';
    let mut rows = Rows::new(input, path, delim);
    let mut series: Vec<Series> = groups
        .iter()
        .map(|(name, ..)| Series {
            name: name.clone(),
            ..Series::default()
        })
        .collect();
    let mut clocks: Vec<Clock> = groups.iter().map(|_| Clock::default()).collect();
    while rows.next()? {
        if rows.is_blank() {
            continue;
        }
        rows.line += header_line;
        for (k, (name, tc, xc, yc)) in groups.iter().enumerate() {
            let p = rows.point([*xc, *yc], name, decimal_comma)?;
            let t = match rows.num(*tc, "t", decimal_comma)? {
                Some(t) => t,
                None if p.is_none() => continue,
                None => return Err(rows.err("t", "a time", "an empty cell")),
            };
            clocks[k].check(path, || rows.at(), t)?;
            series[k].times.push(t);
            series[k].points.push(p);
        }
    }
    if series.iter().all(|s| s.times.is_empty()) {
        return Err(DataError::NoFrames {
            path: path.to_owned(),
            what: "a track name and a header".into(),
        });
    }
    series.retain(|s| !s.times.is_empty());
    let notes = vec![format!(
        "Tracker file {}: {} {}, delimiter {:?}{}",
        path.display(),
        if multi {
            "multi-track export, tracks"
        } else {
            "track"
        },
        series
            .iter()
            .map(|s| format!("{:?}", s.name))
            .collect::<Vec<_>>()
            .join(", "),
        delim as char,
        match (&names_row, multi) {
            (None, _) => ", no name row (named after the file)",
            _ if decimal_comma => ", decimal comma accepted",
            _ => "",
        }
    )];
    Ok(Parsed {
        series,
        scale: Some((
            1.0,
            "metres assumed: Tracker writes no units (use --scale if calibrated otherwise)".into(),
        )),
        notes,
        ..Parsed::default()
    })
}

fn read_dlc(input: impl Read, path: &Path, opts: &ReadOptions) -> Result<Parsed, DataError> {
    let mut rows = Rows::new(input, path, b',');
    let scorer = rows.header("DeepLabCut header rows scorer, bodyparts, coords")?;
    if scorer.first().map(|s| s.to_lowercase()) != Some("scorer".into()) {
        return Err(rows.err(
            "first cell",
            "\"scorer\"",
            format!("{:?}", scorer.first().cloned().unwrap_or_default()),
        ));
    }
    let next_header = |rows: &mut Rows<_>, want: &[&str]| -> Result<Vec<String>, DataError> {
        if !rows.next()? {
            return Err(DataError::NoFrames {
                path: path.to_owned(),
                what: "an incomplete DeepLabCut header".into(),
            });
        }
        let row: Vec<String> = rows.rec.iter().map(|c| c.trim().to_string()).collect();
        let key = row.first().map(|c| c.to_lowercase()).unwrap_or_default();
        if !want.contains(&key.as_str()) {
            return Err(rows.err("first cell", want.join(" or "), format!("{key:?}")));
        }
        Ok(row)
    };
    let r1 = next_header(&mut rows, &["individuals", "bodyparts"])?;
    let (individuals, bodyparts) = if r1[0].eq_ignore_ascii_case("individuals") {
        (Some(r1), next_header(&mut rows, &["bodyparts"])?)
    } else {
        (None, r1)
    };
    let coords = next_header(&mut rows, &["coords"])?;
    // Index columns come first: the frame number, or (labelled data) the image path, in one
    // column or three.
    let first_data = (1..coords.len())
        .find(|&j| ["x", "y", "z", "likelihood"].contains(&coords[j].to_lowercase().as_str()))
        .unwrap_or(1);
    fn label(row: &[String], j: usize) -> &str {
        row.get(j).map_or("", |c| c.as_str())
    }
    let columns = (first_data..coords.len()).map(|j| {
        (
            j,
            individuals.as_ref().map(|ind| label(ind, j)),
            label(&bodyparts, j),
            coords[j].as_str(),
        )
    });
    let mut dlc = dlc::Builder::new(columns, path, opts, |field, expected, found| {
        rows.err(field, expected, found)
    })?;
    while rows.next()? {
        if rows.is_blank() {
            continue;
        }
        rows.width(coords.len())?;
        // Labelled data index rows by image path: number them instead.
        let frame = if first_data == 1 && rows.num(0, "frame index", false).is_ok() {
            rows.req(0, "frame index", false)?
        } else {
            dlc.frames() as f64
        };
        dlc.row(path, frame, &rows)?;
    }
    dlc.finish(path, "DeepLabCut header rows")
}

impl<R: Read> dlc::Cells for Rows<R> {
    fn number(&self, j: usize, field: &dyn Fn() -> String) -> Result<Option<f64>, DataError> {
        self.num_named(j, field, false)
    }

    fn error(&self, field: &str, expected: &str, found: String) -> DataError {
        self.err(field, expected, found)
    }

    fn at(&self) -> String {
        Rows::at(self)
    }
}

fn unit_scale(unit: &str) -> Option<f64> {
    match unit.trim().to_lowercase().as_str() {
        "m" | "meters" | "metres" | "meter" | "metre" => Some(1.0),
        "cm" | "centimeters" | "centimetres" => Some(0.01),
        "mm" | "millimeters" | "millimetres" => Some(0.001),
        _ => None,
    }
}

/// Group 3-D position columns `(name, [x, y, z])` from per-column names and axis labels.
fn group_xyz(
    names: impl Iterator<Item = (usize, String)>,
    axis: &[String],
) -> Vec<(String, [Option<usize>; 3])> {
    let mut out: Vec<(String, [Option<usize>; 3])> = Vec::new();
    for (j, name) in names {
        let slot = match axis.get(j).map(|a| a.trim().to_lowercase()) {
            Some(a) if a == "x" => 0,
            Some(a) if a == "y" => 1,
            Some(a) if a == "z" => 2,
            _ => continue,
        };
        let k = match out.iter().position(|(n, _)| *n == name) {
            Some(k) => k,
            None => {
                out.push((name, [None; 3]));
                out.len() - 1
            }
        };
        out[k].1[slot] = Some(j);
    }
    out
}

/// Read 3-D rows into series: `time(rows)` gives each row's time.
fn read_xyz_rows<R: Read>(
    rows: &mut Rows<R>,
    path: &Path,
    markers: &[(String, [usize; 3])],
    plane: Plane,
    mut time: impl FnMut(&Rows<R>) -> Result<f64, DataError>,
    stop_at_blank: bool,
) -> Result<Vec<Series>, DataError> {
    let mut series: Vec<Series> = markers
        .iter()
        .map(|(n, _)| Series {
            name: n.clone(),
            ..Series::default()
        })
        .collect();
    let mut times = Vec::new();
    let mut clock = Clock::default();
    while rows.next()? {
        // The csv crate skips blank lines: a section ends at a row of one cell (a blank line or
        // the next section's title).
        if stop_at_blank && rows.rec.len() == 1 {
            break;
        }
        if rows.is_blank() {
            continue;
        }
        let t = time(rows)?;
        clock.check(path, || rows.at(), t)?;
        times.push(t);
        for (k, (name, idx)) in markers.iter().enumerate() {
            series[k]
                .points
                .push(rows.point(*idx, name, false)?.map(|p| plane.project(p)));
        }
    }
    if times.is_empty() {
        return Err(DataError::NoFrames {
            path: path.to_owned(),
            what: "header rows".into(),
        });
    }
    for s in &mut series {
        s.times = times.clone();
    }
    Ok(series)
}

fn complete(
    rows_err: impl Fn(&str) -> DataError,
    groups: Vec<(String, [Option<usize>; 3])>,
) -> Result<Vec<(String, [usize; 3])>, DataError> {
    if groups.is_empty() {
        return Err(rows_err("marker position columns X, Y, Z"));
    }
    groups
        .into_iter()
        .map(|(n, [x, y, z])| match (x, y, z) {
            (Some(x), Some(y), Some(z)) => Ok((n, [x, y, z])),
            _ => Err(rows_err(&format!("X, Y and Z columns for {n:?}"))),
        })
        .collect()
}

fn read_motive(input: impl Read, path: &Path, opts: &ReadOptions) -> Result<Parsed, DataError> {
    let mut rows = Rows::new(input, path, b',');
    let meta = rows.header("a Motive export (Format Version, ...)")?;
    let mut units = None;
    let mut rate = None;
    for kv in meta.chunks(2) {
        if let [k, v] = kv {
            match k.as_str() {
                "Length Units" => units = Some(v.clone()),
                "Export Frame Rate" => rate = Some(v.clone()),
                _ => {}
            }
        }
    }
    // Header rows between the metadata and `Frame,Time`: labelled `,Type`, `,Name`, `,ID`,
    // `,Parent` (1.23 on), or unlabelled in that order (1.21); the row of `Position` and
    // `Rotation` comes last.
    let mut labelled: HashMap<String, Vec<String>> = HashMap::new();
    let mut unlabelled: Vec<Vec<String>> = Vec::new();
    let mut kinds: Vec<String> = Vec::new();
    let header = loop {
        if !rows.next()? {
            return Err(DataError::NoFrames {
                path: path.to_owned(),
                what: "no Frame,Time header row and".into(),
            });
        }
        let row: Vec<String> = rows.rec.iter().map(|c| c.trim().to_string()).collect();
        if row.first().is_some_and(|c| c.eq_ignore_ascii_case("frame")) {
            break row;
        }
        if rows.is_blank() {
            continue;
        }
        let label = row.get(1).map(|c| c.to_lowercase()).unwrap_or_default();
        if ["type", "name", "id", "parent"].contains(&label.as_str()) {
            labelled.insert(label, row);
        } else if row
            .iter()
            .skip(2)
            .any(|c| c.eq_ignore_ascii_case("position") || c.eq_ignore_ascii_case("rotation"))
        {
            kinds = row;
        } else {
            unlabelled.push(row);
        }
    };
    let names = labelled
        .remove("name")
        .or_else(|| unlabelled.get(1).cloned())
        .or_else(|| unlabelled.first().cloned());
    if header.len() <= 2
        || names
            .as_ref()
            .is_none_or(|n| n.iter().skip(2).all(|c| c.is_empty()))
    {
        return Err(rows.err(
            "header",
            "marker position columns X, Y, Z after Frame and Time",
            format!(
                "{:?}: this export holds no marker data (export again with markers or rigid bodies ticked)",
                header.join(",")
            ),
        ));
    }
    let names = names.expect("checked above");
    let groups = group_xyz(
        (2..header.len()).filter_map(|j| {
            let kind = kinds.get(j).map(String::as_str).unwrap_or("");
            (kind.eq_ignore_ascii_case("position") && !names.get(j)?.is_empty())
                .then(|| (j, names[j].clone()))
        }),
        &header,
    );
    let markers = complete(
        |e| rows.err("header", e, format!("{:?}", header.join(","))),
        groups,
    )?;
    let plane = opts.plane.unwrap_or(Plane::Xy);
    let scale = units.as_deref().and_then(unit_scale);
    // Time from the frame number and the export rate: the Time column is rounded (to the
    // millisecond in 1.23 exports).
    let rate_hz = rate
        .as_deref()
        .and_then(|r| r.parse::<f64>().ok())
        .filter(|r| r.is_finite() && *r > 0.0);
    let mut base = None;
    let mut series = read_xyz_rows(
        &mut rows,
        path,
        &markers,
        plane,
        |r| match rate_hz {
            Some(hz) => {
                let f = r.req(0, "Frame", false)?;
                let b = *base.get_or_insert(f);
                Ok((f - b) / hz)
            }
            None => {
                let t = r.req(1, "Time (Seconds)", false)?;
                let b = *base.get_or_insert(t);
                Ok(t - b)
            }
        },
        false,
    )?;
    let (join_notes, joined) = join_renamed_unlabeled(&mut series);
    let time_note = match rate_hz {
        Some(hz) => format!("t = (Frame - first frame) / Export Frame Rate {hz} Hz from the header (the Time column is rounded)"),
        None => "t from the Time column (no Export Frame Rate in the header)".to_string(),
    };
    let base = match rate_hz {
        Some(hz) => base.map(|f| f / hz),
        None => base,
    };
    Ok(Parsed {
        series,
        scale: Some(match scale {
            Some(s) => (
                s,
                format!("Length Units {} from the file", units.unwrap_or_default()),
            ),
            None => (1.0, "metres assumed: no Length Units in the file".into()),
        }),
        time_base: base.unwrap_or(0.0),
        notes: std::iter::once(format!(
            "Motive: plane {} (Motive's y is up; --plane to change); {time_note}",
            plane.name(),
        ))
        .chain(join_notes)
        .collect(),
        joined,
        ..Parsed::default()
    })
}

/// A marker hidden longer than this (seconds) is taken for a new marker when it reappears,
/// wherever it is.
const MAX_REAPPEAR_S: f64 = 0.5;
/// Motive names a marker it has lost and found again anew ("Unlabeled 1036" comes back as
/// "Unlabeled 1052"): its track is split into a column that ends and one that starts later.
/// Join such pairs under the first name when the join is unambiguous: the new track starts
/// after the old one ends, at most [`MAX_REAPPEAR_S`] later, where the old one was heading
/// (its last velocity carried over the gap), nearer to that point than half the distance
/// from the old track's last position to any other marker then visible; the closest pairs
/// are joined first, each track at most once at either end. Returns a note per joined
/// marker and the (later name, kept name) pairs.
fn join_renamed_unlabeled(series: &mut Vec<Series>) -> (Vec<String>, Vec<(String, String)>) {
    let unlabeled = |s: &Series| s.name.to_lowercase().starts_with("unlabeled");
    let spans: Vec<Option<(usize, usize)>> = series
        .iter()
        .map(|s| {
            let first = s.points.iter().position(Option::is_some)?;
            Some((first, s.points.iter().rposition(Option::is_some)?))
        })
        .collect();
    let frames = series.first().map_or(0, |s| s.points.len());
    // Only tracks that end early can have a successor, only late starters a predecessor.
    let ends: Vec<usize> = (0..series.len())
        .filter(|&k| unlabeled(&series[k]) && spans[k].is_some_and(|(_, e)| e + 1 < frames))
        .collect();
    let starts: Vec<usize> = (0..series.len())
        .filter(|&k| unlabeled(&series[k]) && spans[k].is_some_and(|(s, _)| s > 0))
        .collect();
    let mut pairs = Vec::new();
    for &a in &ends {
        let Some((_, end)) = spans[a] else { continue };
        let (times, pa) = (
            &series[a].times,
            series[a].points[end].expect("end of a span"),
        );
        // The last velocity (per frame), when the frame before the end has a position.
        let v = match end.checked_sub(1).and_then(|i| series[a].points[i]) {
            Some(p) => [pa[0] - p[0], pa[1] - p[1]],
            None => [0.0, 0.0],
        };
        let room = series
            .iter()
            .enumerate()
            .filter(|&(k, _)| k != a)
            .filter_map(|(_, s)| s.points[end])
            .map(|p| (p[0] - pa[0]).hypot(p[1] - pa[1]))
            .fold(f64::INFINITY, f64::min)
            / 2.0;
        for &b in &starts {
            let Some((start, _)) = spans[b] else { continue };
            if start <= end || times[start] - times[end] > MAX_REAPPEAR_S {
                continue;
            }
            let pb = series[b].points[start].expect("start of a span");
            let g = (start - end) as f64;
            let d = (pb[0] - pa[0] - v[0] * g).hypot(pb[1] - pa[1] - v[1] * g);
            if d < room {
                pairs.push((d, a, b));
            }
        }
    }
    pairs.sort_by(|x, y| x.0.total_cmp(&y.0));
    // successor[a] = b; each track gets at most one successor and one predecessor.
    let mut successor: Vec<Option<usize>> = vec![None; series.len()];
    // For each joined track (each track with a predecessor): the frames missing before it and
    // its distance from where the track before it was heading.
    let mut joins: Vec<Option<(usize, f64)>> = vec![None; series.len()];
    for (d, a, b) in pairs {
        if successor[a].is_some() || joins[b].is_some() {
            continue;
        }
        successor[a] = Some(b);
        let ((_, end), (start, _)) = (spans[a].expect("a span"), spans[b].expect("a span"));
        joins[b] = Some((start - end - 1, d));
    }
    // Fill each chain's head from its successors, then drop the successors.
    let (mut notes, mut joined) = (Vec::new(), Vec::new());
    for head in (0..series.len()).filter(|&k| joins[k].is_none()) {
        let mut next = successor[head];
        let mut parts = Vec::new();
        while let Some(b) = next {
            let (missing, d) = joins[b].expect("a joined track");
            joined.push((series[b].name.clone(), series[head].name.clone()));
            parts.push(format!(
                "{:?} after {missing} missing frames ({d:.3} file units from where it was heading)",
                series[b].name
            ));
            let tail = std::mem::take(&mut series[b].points);
            for (slot, p) in series[head].points.iter_mut().zip(tail) {
                if p.is_some() {
                    *slot = p;
                }
            }
            next = successor[b];
        }
        if !parts.is_empty() {
            notes.push(format!(
                "Motive: {:?} continues as {}: Motive renamed the marker when it reappeared; \
                 joined under the first name",
                series[head].name,
                parts.join(", then ")
            ));
        }
    }
    let mut heads = joins.iter().map(Option::is_none);
    series.retain(|_| heads.next().unwrap_or(true));
    (notes, joined)
}

fn read_vicon(input: impl Read, path: &Path, opts: &ReadOptions) -> Result<Parsed, DataError> {
    let mut rows = Rows::new(input, path, b',');
    let mut any = false;
    loop {
        if !rows.next()? {
            return Err(if any {
                DataError::parse(
                    path,
                    format!("line {}", rows.line),
                    "section",
                    "a Trajectories section",
                    "end of file",
                )
            } else {
                DataError::Empty {
                    path: path.to_owned(),
                    expected: "a Vicon Nexus export with a Trajectories section".into(),
                }
            });
        }
        any = true;
        if rows.cell(0).trim().eq_ignore_ascii_case("trajectories") {
            break;
        }
    }
    let need = |rows: &mut Rows<_>, what: &str| -> Result<Vec<String>, DataError> {
        if !rows.next()? {
            return Err(DataError::NoFrames {
                path: path.to_owned(),
                what: format!("a Trajectories section without {what}"),
            });
        }
        Ok(rows.rec.iter().map(|c| c.trim().to_string()).collect())
    };
    need(&mut rows, "a frame rate")?;
    let rate = rows.req(0, "frame rate (Hz)", false)?;
    if rate <= 0.0 {
        return Err(rows.err("frame rate (Hz)", "a positive number", rate.to_string()));
    }
    let names = need(&mut rows, "marker names")?;
    let header = need(&mut rows, "a Frame,Sub Frame,X,Y,Z header")?;
    if !header
        .first()
        .is_some_and(|c| c.eq_ignore_ascii_case("frame"))
    {
        return Err(rows.err(
            "header",
            "Frame,Sub Frame,X,Y,Z,...",
            format!("{:?}", header.join(",")),
        ));
    }
    let units = need(&mut rows, "a units row")?;
    let mut current = String::new();
    let groups = group_xyz(
        (2..header.len()).map(|j| {
            if let Some(n) = names.get(j).filter(|n| !n.is_empty()) {
                current = n.clone();
            }
            (j, current.clone())
        }),
        &header,
    );
    let markers = complete(
        |e| rows.err("header", e, format!("{:?}", names.join(","))),
        groups,
    )?;
    let unit = units.get(markers[0].1[0]).cloned().unwrap_or_default();
    let scale = unit_scale(&unit);
    let plane = opts.plane.unwrap_or(Plane::Xz);
    let mut first = None;
    let series = read_xyz_rows(
        &mut rows,
        path,
        &markers,
        plane,
        |r| {
            let f = r.req(0, "Frame", false)?;
            let f0 = *first.get_or_insert(f);
            Ok((f - f0) / rate)
        },
        true,
    )?;
    Ok(Parsed {
        series,
        scale: Some(match scale {
            Some(s) => (s, format!("units {unit} from the file")),
            None => (0.001, format!("units {unit:?} not recognised: millimetres assumed")),
        }),
        notes: vec![format!(
            "Vicon: {rate} Hz, t = (frame - first frame) / rate; plane {} (Vicon's z is up; --plane to change)",
            plane.name()
        )],
        ..Parsed::default()
    })
}

/// SLEAP's analysis CSV: `track,frame_idx,instance.score,NODE.x,NODE.y,NODE.score,...`, one
/// row per instance per frame with a prediction (frames without one are left out); pixels, y
/// down. Markers are `NODE`, or `TRACK/NODE` when the track has a name.
fn read_sleap_csv(input: impl Read, path: &Path, opts: &ReadOptions) -> Result<Parsed, DataError> {
    let mut rows = Rows::new(input, path, b',');
    rows.nan_missing = true;
    let header = rows.header("a SLEAP header track,frame_idx,instance.score,NODE.x,NODE.y,...")?;
    let low = lower(&header);
    let find = |n: &str| low.iter().position(|c| c == n);
    let (Some(track_col), Some(frame_col)) = (find("track"), find("frame_idx")) else {
        return Err(rows.err(
            "header",
            "columns track and frame_idx",
            format!("{:?}", header.join(",")),
        ));
    };
    let nodes: Vec<(String, usize, usize)> = low
        .iter()
        .enumerate()
        .filter_map(|(i, h)| {
            let stem = h.strip_suffix(".x")?;
            let j = find(&format!("{stem}.y"))?;
            Some((header[i][..header[i].len() - 2].to_string(), i, j))
        })
        .collect();
    if nodes.is_empty() {
        return Err(rows.err(
            "header",
            "NODE.x,NODE.y column pairs",
            format!("{:?}", header.join(",")),
        ));
    }
    let fps = opts.fps.ok_or_else(|| DataError::Options {
        path: path.to_owned(),
        message:
            "SLEAP files store frame numbers, not times: give the video's frame rate with --fps HZ"
                .into(),
    })?;
    let mut index: HashMap<String, usize> = HashMap::new();
    let mut series: Vec<Series> = Vec::new();
    let mut clocks: Vec<Clock> = Vec::new();
    while rows.next()? {
        if rows.is_blank() {
            continue;
        }
        rows.width(header.len())?;
        let t = rows.req(frame_col, "frame_idx", false)? / fps;
        let track = rows.cell(track_col).trim().to_string();
        for (node, x, y) in &nodes {
            let name = if track.is_empty() {
                node.clone()
            } else {
                format!("{track}/{node}")
            };
            let k = *index.entry(name.clone()).or_insert_with(|| {
                series.push(Series {
                    name: name.clone(),
                    ..Series::default()
                });
                clocks.push(Clock::default());
                series.len() - 1
            });
            clocks[k].check(path, || format!("{} (marker {name:?})", rows.at()), t)?;
            series[k].times.push(t);
            series[k].points.push(rows.point([*x, *y], &name, false)?);
        }
    }
    if series.is_empty() {
        return Err(DataError::NoFrames {
            path: path.to_owned(),
            what: "a SLEAP header".into(),
        });
    }
    Ok(Parsed {
        series,
        y_down: true,
        notes: vec![format!(
            "SLEAP analysis CSV: pixels with y down, t = frame_idx / {fps} Hz"
        )],
        ..Parsed::default()
    })
}

/// Qualisys QTM's TSV export: `KEY<tab>value` lines (`FREQUENCY`, `MARKER_NAMES`, ...), then
/// `Frame Time NAME X NAME Y NAME Z ...`; millimetres, z up.
fn read_qualisys(input: impl Read, path: &Path, opts: &ReadOptions) -> Result<Parsed, DataError> {
    let mut rows = Rows::new(input, path, b'\t');
    let mut meta: HashMap<String, String> = HashMap::new();
    let header = loop {
        if !rows.next()? {
            return Err(DataError::NoFrames {
                path: path.to_owned(),
                what: "a QTM header without a Frame/Time column row and".into(),
            });
        }
        let row: Vec<String> = rows.rec.iter().map(|c| c.trim().to_string()).collect();
        let key = row.first().cloned().unwrap_or_default();
        if key.eq_ignore_ascii_case("frame") {
            break row;
        }
        // Old exports have no Frame/Time columns: their first numeric row is data.
        if key.parse::<f64>().is_ok() {
            return Err(rows.err(
                "header",
                "a row Frame, Time, NAME X, NAME Y, NAME Z (export with the column header option)",
                format!("{key:?}"),
            ));
        }
        meta.insert(key.to_uppercase(), row.get(1).cloned().unwrap_or_default());
    };
    let rate = meta
        .get("FREQUENCY")
        .and_then(|f| f.parse::<f64>().ok())
        .filter(|f| f.is_finite() && *f > 0.0);
    let axis: Vec<String> = header
        .iter()
        .map(|h| h.rsplit(' ').next().unwrap_or("").to_string())
        .collect();
    let groups = group_xyz(
        (2..header.len()).filter_map(|j| {
            let h = &header[j];
            let (name, _) = h.rsplit_once(' ')?;
            Some((j, name.to_string()))
        }),
        &axis,
    );
    let markers = complete(
        |e| rows.err("header", e, format!("{:?}", header.join(" "))),
        groups,
    )?;
    let time_col = header.iter().position(|h| h.eq_ignore_ascii_case("time"));
    let plane = opts.plane.unwrap_or(Plane::Xz);
    let mut first = None;
    let series = read_xyz_rows(
        &mut rows,
        path,
        &markers,
        plane,
        |r| match (rate, time_col) {
            (Some(hz), _) => {
                let f = r.req(0, "Frame", false)?;
                let f0 = *first.get_or_insert(f);
                Ok((f - f0) / hz)
            }
            (None, Some(tc)) => {
                let t = r.req(tc, "Time", false)?;
                let t0 = *first.get_or_insert(t);
                Ok(t - t0)
            }
            (None, None) => Err(r.err("FREQUENCY", "a frame rate in the header", "none")),
        },
        false,
    )?;
    let unit = meta.get("UNITS").cloned().unwrap_or_else(|| "mm".into());
    Ok(Parsed {
        series,
        scale: Some(match unit_scale(&unit) {
            Some(s) => (s, format!("QTM units {unit}")),
            None => (0.001, "millimetres (QTM's unit)".into()),
        }),
        notes: vec![format!(
            "Qualisys QTM TSV: {}; plane {} (QTM's z is up; --plane to change)",
            match rate {
                Some(hz) => format!("t = (Frame - first frame) / FREQUENCY {hz} Hz"),
                None => "t from the Time column".into(),
            },
            plane.name()
        )],
        ..Parsed::default()
    })
}

/// Kinovea's trajectory text export (gnuplot style): `#Kinovea Trajectory data export`,
/// `#T X Y`, then per trajectory a `# NAME` line and rows `t x y` (space-separated, the
/// locale's decimal separator), blocks separated by blank lines. Units are the calibration's.
fn read_kinovea(input: impl Read, path: &Path) -> Result<Parsed, DataError> {
    let mut series: Vec<Series> = Vec::new();
    let mut clocks: Vec<Clock> = Vec::new();
    let mut saw_header = false;
    let reader = BufReader::new(input);
    for (k, line) in reader.split(b'\n').enumerate() {
        let line = line.map_err(|source| DataError::Io {
            path: path.to_owned(),
            source,
        })?;
        let line = String::from_utf8_lossy(&line);
        let line = line.trim_start_matches('\u{feff}').trim();
        let at = format!("line {}", k + 1);
        if line.is_empty() {
            continue;
        }
        if let Some(c) = line.strip_prefix('#') {
            let c = c.trim();
            if c.to_lowercase().starts_with("kinovea") {
                saw_header = true;
            } else if !c.eq_ignore_ascii_case("t x y") {
                series.push(Series {
                    name: c.to_string(),
                    ..Series::default()
                });
                clocks.push(Clock::default());
            }
            continue;
        }
        if !saw_header {
            return Err(DataError::parse(
                path,
                at,
                "header",
                "#Kinovea Trajectory data export",
                format!("{:?}", line.chars().take(60).collect::<String>()),
            ));
        }
        let Some(s) = series.last_mut() else {
            return Err(DataError::parse(
                path,
                at,
                "trajectory",
                "a '# NAME' line before the rows",
                format!("{line:?}"),
            ));
        };
        let cells: Vec<&str> = line.split_whitespace().collect();
        let num = |i: usize, field: &str| -> Result<f64, DataError> {
            let raw = cells.get(i).copied().unwrap_or("");
            raw.replace(',', ".")
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| {
                    DataError::parse(path, &at, field, "a finite number", format!("{raw:?}"))
                })
        };
        if cells.len() < 3 {
            return Err(DataError::parse(
                path,
                &at,
                "row",
                "three cells t x y",
                format!("{line:?}"),
            ));
        }
        let t = num(0, "t")?;
        clocks
            .last_mut()
            .expect("one per series")
            .check(path, || at.clone(), t)?;
        s.times.push(t);
        s.points.push(Some([num(1, "x")?, num(2, "y")?]));
    }
    series.retain(|s| !s.times.is_empty());
    if series.is_empty() {
        return Err(DataError::NoFrames {
            path: path.to_owned(),
            what: "a Kinovea header".into(),
        });
    }
    Ok(Parsed {
        series,
        notes: vec![
            "Kinovea trajectory export: times as written, positions in the calibration's units (y up)"
                .into(),
        ],
        ..Parsed::default()
    })
}

/// TRex's per-individual CSV: `frame`, `time`, `timestamp` (microseconds), `X (cm)`, `Y (cm)`,
/// `X#wcentroid (cm)`, ..., `midline_x`, `midline_y`, `missing`. Markers: `centroid`,
/// `wcentroid`, `midline`; centimetres when the columns say so, y down.
fn read_trex(input: impl Read, path: &Path) -> Result<Parsed, DataError> {
    let mut rows = Rows::new(input, path, b',');
    rows.nan_missing = true;
    let header = rows.header("a TRex header frame,...,X (cm),Y (cm),...")?;
    let low = lower(&header);
    let find = |n: &str| low.iter().position(|c| c == n);
    let pairs: Vec<(&str, usize, usize)> = [
        ("centroid", ["x (cm)", "x"], ["y (cm)", "y"]),
        (
            "wcentroid",
            ["x#wcentroid (cm)", "x#wcentroid"],
            ["y#wcentroid (cm)", "y#wcentroid"],
        ),
        (
            "midline",
            ["midline_x", "midline_x"],
            ["midline_y", "midline_y"],
        ),
    ]
    .into_iter()
    .filter_map(|(n, xs, ys)| {
        let x = xs.iter().find_map(|c| find(c))?;
        let y = ys.iter().find_map(|c| find(c))?;
        Some((n, x, y))
    })
    .collect();
    if pairs.is_empty() {
        return Err(rows.err(
            "header",
            "TRex position columns X (cm), Y (cm)",
            format!("{:?}", header.join(",")),
        ));
    }
    let cm = low.iter().any(|c| c == "x (cm)");
    let (tcol, factor, what) = if let Some(i) = find("timestamp") {
        (i, 1e-6, "timestamp (microseconds)")
    } else if let Some(i) = find("time") {
        (i, 1.0, "time (seconds)")
    } else {
        return Err(rows.err(
            "header",
            "a timestamp or time column",
            format!("{:?}", header.join(",")),
        ));
    };
    let missing = find("missing");
    let mut series: Vec<Series> = pairs
        .iter()
        .map(|(n, ..)| Series {
            name: n.to_string(),
            ..Series::default()
        })
        .collect();
    let mut clock = Clock::default();
    let mut base = None;
    let mut times = Vec::new();
    while rows.next()? {
        if rows.is_blank() {
            continue;
        }
        rows.width(header.len())?;
        let raw = rows.req(tcol, what, false)? * factor;
        let b = *base.get_or_insert(raw);
        let t = raw - b;
        clock.check(path, || rows.at(), t)?;
        times.push(t);
        let lost = match missing {
            Some(m) => rows.num(m, "missing", false)?.is_some_and(|v| v != 0.0),
            None => false,
        };
        for (k, (n, x, y)) in pairs.iter().enumerate() {
            let p = rows.point([*x, *y], n, false)?;
            series[k].points.push(if lost { None } else { p });
        }
    }
    if times.is_empty() {
        return Err(DataError::NoFrames {
            path: path.to_owned(),
            what: "a TRex header".into(),
        });
    }
    for s in &mut series {
        s.times = times.clone();
    }
    Ok(Parsed {
        series,
        scale: cm.then(|| (0.01, "centimetres (TRex's X (cm), Y (cm))".to_string())),
        y_down: true,
        time_base: base.unwrap_or(0.0),
        notes: vec![format!(
            "TRex: t from {what}; rows marked missing count as missing; y down (image axes)"
        )],
        ..Parsed::default()
    })
}
