//! Recordings in and out: readers for the CSV family, HDF5, XML and MCAP, calibration into the
//! rail frame, the canonical CSV and synthetic recordings with a known mu.
//!
//! Every reader produces marker series in file units; [`read_recording`] picks the slider and
//! the bob, aligns them on common frame times and calibrates them into one [`Recording`], so
//! the fit never sees a format.
//!
//! The files, in the order a read goes through them:
//! - `mod.rs`: the entry points, format detection, and the assembly of what a reader returns
//!   into a calibrated recording (the slider and the bob picked, aligned on common times).
//! - `arrays.rs`: recordings made from arrays (Python), held to a file's bounds.
//! - `budget.rs`: one budget per input file: what a reader may decode, hold and compute.
//! - `options.rs`: `ReadOptions` and `Plane`; `parsed.rs`: what a reader returns (`Series`,
//!   `Parsed`).
//! - `table/`: the CSV-family readers, one file per tool (wide, long, Tracker, DeepLabCut,
//!   SLEAP, Motive, Vicon, Qualisys, Kinovea, TRex) over shared rows (`table/rows.rs`); its
//!   `mod.rs` sends a format to its reader, and a format's XML or HDF5 variant to theirs.
//! - `hdf5/`: HDF5 inputs: which layout a file holds (DeepLabCut's pandas DataFrame or SLEAP's
//!   analysis file), their readers, and the byte caps they share.
//! - `dlc.rs`: DeepLabCut's table layout (columns to markers, likelihood, frames to times),
//!   shared by its CSV reader (`table/dlc.rs`) and its HDF5 reader (`hdf5/dlc.rs`).
//! - `tracker_project.rs`, `kinovea_xml.rs`: Tracker's projects and Kinovea's spreadsheets (XML).
//! - `xml_limits.rs`: the attributes per element both XML readers allow, checked before parsing.
//! - `mcap/`: MCAP recordings, read and written; ROS 2 CDR messages in `ros_cdr.rs`.
//! - `calibrate.rs`: into the rail frame (metres, y up, the rail axis, the origin) and the
//!   rod-length check that flags outlier frames.
//! - `recording.rs`: the formats, the calibrated `Recording` with its provenance, and the
//!   canonical CSV it writes; `error.rs`: the one error type, `DataError`.
//! - `overlay_csv.rs`: a model's markers written back in a recording's own units and layout
//!   (`fit --overlay FILE.csv`), through the calibration's inverse.
//! - `synth.rs`: synthetic recordings with a known mu.
//! - `inspect/`: what a file holds before the options a reader needs are known (`appell
//!   inspect`): markers, times, units, the pair that moves like the slider and the bob, and the
//!   options still missing.

pub mod arrays;
mod budget;
pub mod calibrate;
mod dlc;
mod error;
mod hdf5;
pub mod inspect;
mod kinovea_xml;
pub mod mcap;
mod options;
pub mod overlay_csv;
mod parsed;
mod recording;
mod ros_cdr;
pub mod synth;
mod table;
mod tracker_project;
mod xml_limits;

pub use budget::{Budget, Resource};
pub use error::DataError;
pub use options::{Plane, ReadOptions};
pub(crate) use parsed::{Parsed, Series};
pub use recording::{
    Calibration, Format, Geometry, Provenance, Recording, Track, CANONICAL_HEADER,
    MIN_FRAMES_PER_SWING,
};

use std::io::Read;
use std::path::{Path, PathBuf};

/// Read a recording from one file, or from one file per marker (Tracker), and calibrate it
/// into the rail frame. The format is detected unless `opts.format` is set.
pub fn read_recording(paths: &[PathBuf], opts: &ReadOptions) -> Result<Recording, DataError> {
    let (parsed, format, detected) = read_parsed(paths, opts)?;
    recording_of(paths, format, detected, parsed, opts)
}

/// The recording in what the readers gave: the slider and the bob picked and aligned, the
/// calibration, the time window; every check `convert` makes after reading the files, so that
/// `inspect`'s verdict is theirs.
pub(crate) fn recording_of(
    paths: &[PathBuf],
    format: Format,
    detected: bool,
    parsed: Parsed,
    opts: &ReadOptions,
) -> Result<Recording, DataError> {
    let mut rec = assemble(paths, format, detected, parsed, opts)?;
    if let Some((start, end)) = opts.time_window {
        crop(&mut rec, start, end, &paths_label(paths))?;
    }
    Ok(rec)
}

/// Every marker series of one recording's files as the readers give them, before the slider
/// and the bob are picked: the files' series in order (a name repeated in a later file is told
/// apart by that file's name), two one-track files named in file order, the format and
/// whether it was detected.
pub(crate) fn read_parsed(
    paths: &[PathBuf],
    opts: &ReadOptions,
) -> Result<(Parsed, Format, bool), DataError> {
    let Some(first) = paths.first() else {
        return Err(DataError::Options {
            path: PathBuf::from("(no input)"),
            message: "no input file given".into(),
        });
    };
    let mut parsed: Option<Parsed> = None;
    let mut per_file: Vec<(PathBuf, usize)> = Vec::new();
    let mut format = opts.format;
    let detected = format.is_none();
    for path in paths {
        let f = match opts.format {
            Some(f) => f,
            None => {
                let f = detect(path)?;
                if let Some(prev) = format {
                    if prev != f {
                        return Err(DataError::Options {
                            path: path.clone(),
                            message: format!(
                                "looks like {f} but {} is {prev}: inputs must share a format",
                                first.display()
                            ),
                        });
                    }
                }
                f
            }
        };
        format = Some(f);
        let p = match f {
            Format::Mcap => {
                if paths.len() > 1 {
                    return Err(DataError::Options {
                        path: path.clone(),
                        message: "MCAP recordings are read one file at a time".into(),
                    });
                }
                mcap::read(path, opts)?
            }
            _ => table::read(path, f, opts)?,
        };
        per_file.push((path.clone(), p.series.len()));
        parsed = Some(match parsed {
            None => p,
            Some(mut acc) => {
                for mut s in p.series {
                    if acc.series.iter().any(|a| a.name == s.name) {
                        // Tracker names every track mass_A by default: keep both, told apart
                        // by their file.
                        let file = path.file_name().unwrap_or_default().to_string_lossy();
                        s.name = format!("{} ({file})", s.name);
                        if acc.series.iter().any(|a| a.name == s.name) {
                            return Err(DataError::Options {
                                path: path.clone(),
                                message: format!(
                                    "marker {:?} appears twice: the same file given twice?",
                                    s.name
                                ),
                            });
                        }
                    }
                    acc.series.push(s);
                }
                acc.notes.extend(p.notes);
                acc.warnings.extend(p.warnings);
                acc
            }
        });
    }
    let mut parsed = parsed.expect("at least one path");
    for s in &parsed.series {
        check_frame_spacing(
            &paths_label(paths),
            &format!("marker {:?}", s.name),
            &s.times,
        )?;
    }
    by_file_order(&mut parsed, &per_file, opts);
    let format = format.expect("format set with the first path");
    Ok((parsed, format, detected))
}

/// Two times of one frame: within a ten-billionth of their size (or of one second or frame).
/// Two exports of one video differ by their rounding, some 1e-14 of the time; frames of a
/// clock that counts nanoseconds (MCAP stamps, a `t_ns` column) a nanosecond apart stay two.
pub(crate) fn same_frame(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-10 * a.abs().max(b.abs()).max(1.0)
}

/// Refuse successive `times` (seconds from the first frame) of one marker that [`same_frame`]
/// would take for one frame: closer than any clock keeps frames apart (times 5e-324 s apart),
/// they make every rate infinite and every derivative a division by nothing. One rule for
/// every reader and for arrays, so `convert`, `inspect` and `fit` refuse the same files.
pub(crate) fn check_frame_spacing(path: &Path, what: &str, times: &[f64]) -> Result<(), DataError> {
    let Some(k) = times.windows(2).position(|w| same_frame(w[0], w[1])) else {
        return Ok(());
    };
    let (previous, time) = (times[k], times[k + 1]);
    Err(DataError::parse(
        path,
        format!("{what}, frame {}", k + 2),
        "time",
        "frames more than a tenth of a nanosecond (a ten-billionth of their time beyond 1 s) apart, as any clock that counts nanoseconds keeps them",
        format!(
            "{time:.6e} s after {previous:.6e} s (seconds from the first frame), {:.3e} s apart",
            time - previous
        ),
    ))
}

/// The words of the note that says two tracks were taken as the slider and the bob in the
/// order of their files (their names do not say which is which).
pub const FILE_ORDER_NOTE: &str = "read in file order";

/// Two files of one track each (Tracker's single-track exports) whose names do not say which
/// is which: the first file is the slider, the second the bob, with a notice. Names that do say
/// (`slider`, `bob`) or the `--slider`/`--bob` flags take precedence.
fn by_file_order(parsed: &mut Parsed, per_file: &[(PathBuf, usize)], opts: &ReadOptions) {
    if per_file.len() != 2 || per_file.iter().any(|f| f.1 != 1) {
        return;
    }
    if opts.slider.is_some() || opts.bob.is_some() {
        return;
    }
    let names: Vec<String> = parsed
        .series
        .iter()
        .map(|s| s.name.to_lowercase())
        .collect();
    let clear = names[0].contains("slider") && names[1].contains("bob")
        || names[0].contains("bob") && names[1].contains("slider");
    if clear {
        return;
    }
    parsed.notes.push(format!(
        "the tracks {:?} ({}) and {:?} ({}) do not say which marker they are: {FILE_ORDER_NOTE}, the first as the slider, the second as the bob (--slider/--bob NAME to choose)",
        parsed.series[0].name,
        per_file[0].0.display(),
        parsed.series[1].name,
        per_file[1].0.display()
    ));
    parsed.series[0].name = "slider".into();
    parsed.series[1].name = "bob".into();
}

/// Keep the frames inside [start, end] (seconds from the first frame) and re-zero the times.
fn crop(rec: &mut Recording, start: f64, end: f64, label: &Path) -> Result<(), DataError> {
    let keep: Vec<usize> = (0..rec.times.len())
        .filter(|&i| rec.times[i] >= start && rec.times[i] <= end)
        .collect();
    let (Some(&first), Some(_)) = (keep.first(), keep.last()) else {
        return Err(DataError::Options {
            path: label.to_owned(),
            message: format!(
                "no frame inside the time window {start}..{end} s (the recording spans 0..{} s)",
                rec.times.last().copied().unwrap_or(0.0)
            ),
        });
    };
    let t0 = rec.times[first];
    rec.times = keep.iter().map(|&i| rec.times[i] - t0).collect();
    // The first frame kept is the recording's first now: its clock starts there, so that an
    // overlay is stamped (and numbered) at the frames it holds.
    let p = &mut rec.provenance;
    p.time_origin += t0;
    p.time_origin_ns = p
        .time_origin_ns
        .map(|ns| ns.saturating_add((t0 * 1e9).round() as i64));
    rec.slider = keep.iter().map(|&i| rec.slider[i]).collect();
    rec.bob = keep.iter().map(|&i| rec.bob[i]).collect();
    rec.provenance.notes.push(format!(
        "time window {start}..{end} s: {} frames kept, times re-zeroed at {t0} s",
        keep.len()
    ));
    Ok(())
}

/// Pick the slider and bob series, align them, calibrate.
fn assemble(
    paths: &[PathBuf],
    format: Format,
    detected: bool,
    mut parsed: Parsed,
    opts: &ReadOptions,
) -> Result<Recording, DataError> {
    let label = paths_label(paths);
    if parsed.series.len() == 1 {
        return Err(DataError::MissingMarker {
            path: label,
            role: "bob",
            wanted: "(a second marker: a recording needs the slider and the bob, and this input holds one track; give the other marker's file too)".into(),
            available: format!("{:?}", parsed.series[0].name),
        });
    }
    let si = select(&label, &parsed, "slider", opts.slider.as_deref())?;
    let bi = select(&label, &parsed, "bob", opts.bob.as_deref())?;
    if si == bi {
        return Err(DataError::AmbiguousMarker {
            path: label,
            role: "bob",
            wanted: format!("{:?}", parsed.series[bi].name),
            candidates: "the slider's marker".into(),
        });
    }
    let available = parsed
        .series
        .iter()
        .map(|s| format!("{:?}", s.name))
        .collect::<Vec<_>>()
        .join(", ");
    let a = std::mem::take(&mut parsed.series[si]);
    let b = std::mem::take(&mut parsed.series[bi]);
    let (slider_name, bob_name) = (a.name.clone(), b.name.clone());
    let mut b = b;
    if format == Format::Tracker {
        if let Some(note) = join_rounded_times(&a, &mut b) {
            parsed.notes.push(note);
        }
    }
    let (times, slider, bob) = align(a, b);
    if times.is_empty() {
        return Err(DataError::NoFrames {
            path: label,
            what: "a header".into(),
        });
    }
    let t0 = times[0];
    let mut times = times;
    for t in &mut times {
        *t -= t0;
    }
    let off_plane = [&slider_name, &bob_name].map(|n| parsed.off_plane.get(n).copied());
    let mut rec = Recording {
        times,
        slider,
        bob,
        provenance: Provenance {
            sources: paths.to_vec(),
            format: Some(format),
            detected,
            slider_name,
            bob_name,
            time_origin: parsed.time_base + t0,
            // The stamps' own integers: t0 is an exact difference of two of them over 1e9.
            time_origin_ns: parsed
                .time_base_ns
                .map(|base| base.saturating_add((t0 * 1e9).round() as i64)),
            frame_rate: parsed.frame_rate,
            plane: parsed.plane,
            off_plane,
            notes: parsed.notes,
            warnings: parsed.warnings,
            metadata: parsed.metadata,
            ..Provenance::default()
        },
    };
    let seen = rec.seen();
    if seen.0 == 0 || seen.1 == 0 {
        let role = if seen.0 == 0 { "slider" } else { "bob" };
        let name = if role == "slider" {
            &rec.provenance.slider_name
        } else {
            &rec.provenance.bob_name
        };
        return Err(DataError::MissingMarker {
            path: paths_label(paths),
            role,
            wanted: format!("{name:?} (named, but never with a position)"),
            available,
        });
    }
    calibrate::calibrate(&mut rec, parsed.scale, parsed.y_down, opts).map_err(|message| {
        DataError::Options {
            path: paths_label(paths),
            message,
        }
    })?;
    Ok(rec)
}

/// The files of one recording as errors name them: `A + B`.
pub(crate) fn paths_label(paths: &[PathBuf]) -> PathBuf {
    PathBuf::from(
        paths
            .iter()
            .map(|p| p.display().to_string())
            .collect::<Vec<_>>()
            .join(" + "),
    )
}

/// The index of the series for `role`: an exact name (or a name joined into a series), else
/// the one name containing `wanted` (or the role itself), case-insensitively.
pub(crate) fn select(
    path: &Path,
    parsed: &Parsed,
    role: &'static str,
    wanted: Option<&str>,
) -> Result<usize, DataError> {
    let series = &parsed.series;
    let needle = wanted.unwrap_or(role);
    let needle = parsed
        .joined
        .iter()
        .find(|(later, _)| later == needle)
        .map_or(needle, |(_, kept)| kept.as_str());
    if let Some(i) = series.iter().position(|s| s.name == needle) {
        return Ok(i);
    }
    let lower = needle.to_lowercase();
    let hits: Vec<usize> = (0..series.len())
        .filter(|&i| series[i].name.to_lowercase().contains(&lower))
        .collect();
    let rule = match wanted {
        Some(w) => format!("{w:?}"),
        None => format!("(a name containing {role:?}; --{role} NAME to choose)"),
    };
    match hits.as_slice() {
        [i] => Ok(*i),
        [] => Err(DataError::MissingMarker {
            path: path.to_owned(),
            role,
            wanted: rule,
            available: if series.is_empty() {
                "none".into()
            } else {
                series
                    .iter()
                    .map(|s| format!("{:?}", s.name))
                    .collect::<Vec<_>>()
                    .join(", ")
            },
        }),
        many => Err(DataError::AmbiguousMarker {
            path: path.to_owned(),
            role,
            wanted: rule,
            candidates: many
                .iter()
                .map(|&i| format!("{:?}", series[i].name))
                .collect::<Vec<_>>()
                .join(", "),
        }),
    }
}

/// The words that begin the note of [`join_rounded_times`] (`fit` repeats it on stderr).
pub const TIMES_JOINED_NOTE: &str = "frame times joined";

/// The median step between a series' increasing times (`None` with fewer than two).
fn frame_step(times: &[f64]) -> Option<f64> {
    let mut steps: Vec<f64> = times
        .windows(2)
        .map(|w| w[1] - w[0])
        .filter(|d| *d > 0.0)
        .collect();
    (!steps.is_empty()).then(|| calibrate::median(&mut steps))
}

/// Two tracks of one video exported apart (Tracker) share its frame times, but each file rounds
/// them its own way (0.03333333333333212 and 0.03333333333332848): each of `b`'s times within
/// less than half a frame of one of `a`'s, and not equal to it, takes `a`'s time, so the two
/// markers of a frame meet in one frame. Times that would then not increase are left alone.
/// Returns a note saying how many were joined and by how much they differed, when any were.
fn join_rounded_times(a: &Series, b: &mut Series) -> Option<String> {
    let frame = frame_step(&a.times)?.min(frame_step(&b.times)?);
    let half = 0.5 * frame;
    let (mut i, mut joined, mut largest) = (0, 0usize, 0.0f64);
    for k in 0..b.times.len() {
        let t = b.times[k];
        while i + 1 < a.times.len() && a.times[i + 1] <= t {
            i += 1;
        }
        // The nearest of a's times: a.times[i] (at or before t, or the first) or the next one.
        let nearest = [Some(i), (i + 1 < a.times.len()).then_some(i + 1)]
            .into_iter()
            .flatten()
            .map(|j| a.times[j])
            .min_by(|x, y| (x - t).abs().total_cmp(&(y - t).abs()))?;
        let d = (nearest - t).abs();
        let increases = (k == 0 || b.times[k - 1] < nearest)
            && b.times.get(k + 1).is_none_or(|next| nearest < *next);
        if d > 0.0 && d < half && increases {
            b.times[k] = nearest;
            joined += 1;
            largest = largest.max(d);
        }
    }
    (joined > 0).then(|| {
        format!(
            "{TIMES_JOINED_NOTE}: {joined} of {:?}'s frame times differ from {:?}'s by less than half a frame (at most {largest:.3e} s of a {frame:.6e} s frame): the exports' rounding of one video's times, so each was joined to the frame it belongs to",
            b.name, a.name
        )
    })
}

/// Merge two series with increasing times into common frames: the union of their times, each
/// marker missing where it has no sample.
pub(crate) fn align(a: Series, b: Series) -> (Vec<f64>, Track, Track) {
    if a.times == b.times {
        return (a.times, a.points, b.points);
    }
    let n = a.times.len().max(b.times.len());
    let (mut t, mut pa, mut pb) = (
        Vec::with_capacity(n),
        Vec::with_capacity(n),
        Vec::with_capacity(n),
    );
    let (mut i, mut j) = (0, 0);
    while i < a.times.len() || j < b.times.len() {
        let ta = a.times.get(i).copied().unwrap_or(f64::INFINITY);
        let tb = b.times.get(j).copied().unwrap_or(f64::INFINITY);
        if ta == tb {
            t.push(ta);
            pa.push(a.points[i]);
            pb.push(b.points[j]);
            i += 1;
            j += 1;
        } else if ta < tb {
            t.push(ta);
            pa.push(a.points[i]);
            pb.push(None);
            i += 1;
        } else {
            t.push(tb);
            pa.push(None);
            pb.push(b.points[j]);
            j += 1;
        }
    }
    (t, pa, pb)
}

/// Read one recording from any reader (a file or bytes in memory); `label` names it in
/// errors and provenance. The format is detected from the first bytes unless given.
pub fn read_recording_from(
    input: impl Read,
    label: &Path,
    opts: &ReadOptions,
) -> Result<Recording, DataError> {
    read_sized(input, label, opts, None)
}

/// Read one recording held in memory; its length bounds every length the input declares.
pub fn read_recording_bytes(
    bytes: &[u8],
    label: &Path,
    opts: &ReadOptions,
) -> Result<Recording, DataError> {
    read_sized(bytes, label, opts, Some(bytes.len() as u64))
}

fn read_sized(
    mut input: impl Read,
    label: &Path,
    opts: &ReadOptions,
    size: Option<u64>,
) -> Result<Recording, DataError> {
    let mut head = Vec::with_capacity(4096);
    input
        .by_ref()
        .take(4096)
        .read_to_end(&mut head)
        .map_err(|source| DataError::Io {
            path: label.to_owned(),
            source,
        })?;
    let detected = opts.format.is_none();
    let mut format = match opts.format {
        Some(f) => f,
        None => detect_head(&head, label)?,
    };
    if detected && head.starts_with(hdf5::MAGIC) {
        // Which HDF5 layout it is takes the whole file to tell.
        let bytes = table::read_h5_bytes(head.as_slice().chain(input), label)?;
        format = hdf5::detect_bytes(&bytes);
        let parsed = hdf5::read(bytes, label, opts)?;
        return assemble(&[label.to_owned()], format, detected, parsed, opts);
    }
    let chained = head.as_slice().chain(input);
    let parsed = match format {
        Format::Mcap => mcap::read_from(chained, label, opts, size)?,
        f => table::read_from(chained, label, f, opts)?,
    };
    assemble(&[label.to_owned()], format, detected, parsed, opts)
}

/// Tell the format from the file's first bytes and lines; for HDF5, from its groups and datasets
/// (DeepLabCut's pandas DataFrame, else SLEAP).
pub fn detect(path: &Path) -> Result<Format, DataError> {
    detect_why(path).map(|(f, _)| f)
}

/// [`detect`], with what in the file told the format (`a first row starting "scorer"`), for a
/// report that says how it knows.
pub fn detect_why(path: &Path) -> Result<(Format, &'static str), DataError> {
    let mut head = Vec::with_capacity(4096);
    std::fs::File::open(path)
        .and_then(|f| f.take(4096).read_to_end(&mut head))
        .map_err(|source| DataError::Io {
            path: path.to_owned(),
            source,
        })?;
    if head.starts_with(hdf5::MAGIC) {
        return Ok(match hdf5::detect_file(path) {
            Format::DeepLabCut => (
                Format::DeepLabCut,
                "an HDF5 file holding a pandas DataFrame (DeepLabCut's output)",
            ),
            f => (
                f,
                "an HDF5 file without a pandas DataFrame (SLEAP's analysis file)",
            ),
        });
    }
    head_why(&head, path)
}

/// Tell the format from a file's first bytes (up to 4 KiB); `path` names it in errors. HDF5 is
/// taken for SLEAP here: [`detect`] looks inside it.
pub fn detect_head(head: &[u8], path: &Path) -> Result<Format, DataError> {
    head_why(head, path).map(|(f, _)| f)
}

/// [`detect_head`], with what told the format.
fn head_why(head: &[u8], path: &Path) -> Result<(Format, &'static str), DataError> {
    if head.starts_with(::mcap::MAGIC) {
        return Ok((Format::Mcap, "the MCAP magic bytes"));
    }
    if head.starts_with(hdf5::MAGIC) {
        return Ok((Format::Sleap, "an HDF5 file"));
    }
    if head.is_empty() {
        return Err(DataError::Empty {
            path: path.to_owned(),
            expected: "a recording (CSV or MCAP)".into(),
        });
    }
    let text = String::from_utf8_lossy(head);
    let text = text.trim_start_matches('\u{feff}');
    if text.trim_start().starts_with("<?xml") && text.contains("Excel.Sheet") {
        return Ok((
            Format::Kinovea,
            "an Excel XML spreadsheet (Kinovea's export)",
        ));
    }
    if text.trim_start().starts_with("<?xml")
        && text.contains("org.opensourcephysics.cabrillo.tracker")
    {
        return Ok((Format::Tracker, "an XML Tracker project"));
    }
    let lines: Vec<&str> = text.lines().take(8).collect();
    let first = lines.first().copied().unwrap_or("").trim();
    let unknown = || DataError::UnknownFormat {
        path: path.to_owned(),
        first_line: first.chars().take(80).collect(),
        supported: Format::names(),
    };
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("mcap"))
    {
        return Ok((Format::Mcap, "the .mcap extension"));
    }
    let cells = |l: &str| -> Vec<String> {
        l.split([',', '\t', ';'])
            .map(|c| c.trim().trim_matches('"').to_lowercase())
            .collect()
    };
    let c0 = cells(first);
    let key = c0.first().cloned().unwrap_or_default();
    if key == "scorer" {
        return Ok((Format::DeepLabCut, "a first row starting \"scorer\""));
    }
    if key == "format version" {
        return Ok((Format::Motive, "a first row starting \"Format Version\""));
    }
    if key.starts_with("#kinovea") {
        return Ok((Format::Kinovea, "a first line starting \"#Kinovea\""));
    }
    if [
        "no_of_frames",
        "no_of_cameras",
        "no_of_markers",
        "frequency",
    ]
    .contains(&key.as_str())
    {
        return Ok((
            Format::Qualisys,
            "a header of QTM keys (NO_OF_FRAMES, FREQUENCY, ...)",
        ));
    }
    if c0.contains(&"frame_idx".to_string()) && c0.iter().any(|c| c.ends_with(".x")) {
        return Ok((Format::Sleap, "the columns frame_idx and NODE.x"));
    }
    if c0.iter().any(|c| c == "x (cm)" || c == "x#wcentroid (cm)")
        || (c0.contains(&"midline_x".to_string()) && c0.contains(&"timestamp".to_string()))
    {
        return Ok((Format::Trex, "TRex's columns (X (cm), timestamp, ...)"));
    }
    if [
        "trajectories",
        "devices",
        "model outputs",
        "joints",
        "segments",
    ]
    .contains(&key.as_str())
    {
        return Ok((
            Format::Vicon,
            "a Nexus section title (Trajectories, Devices, ...)",
        ));
    }
    if table::long_columns(&c0).is_some() {
        return Ok((Format::Long, "the columns time, marker, x, y"));
    }
    // Tracker: `#multi:`, or a lone track name then `t x y`, or `t x y` itself.
    if first.eq_ignore_ascii_case("#multi:")
        || table::tracker_header_delimiter(first).is_some()
        || (lines.len() >= 2
            && c0.len() == 1
            && !first.contains(' ')
            && table::tracker_header_delimiter(lines[1]).is_some())
    {
        return Ok((Format::Tracker, "Tracker's columns t, x, y"));
    }
    if !table::wide_markers(&c0).is_empty() {
        return Ok((Format::Wide, "columns NAME_x, NAME_y (or x1, y1, ...)"));
    }
    Err(unknown())
}
