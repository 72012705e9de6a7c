//! What a recording holds, told before the options a reader needs are known (`appell
//! inspect`): the format and how it was told, the markers with the frames they are seen in and
//! how they move, the time span and frame rate, the units, the distance between every pair of
//! markers and which pair looks like the slider and the bob, and every option still missing,
//! with a ready command line.
//!
//! The readers are the ones `convert` uses, called as they are: where one refuses a file for a
//! missing `--fps`, the file is read again with its frames numbered 0, 1, 2, ... (and the report
//! says so), and the scale is left as the file gives it (pixels stay pixels).
//!
//! The files:
//! - `mod.rs`: the report's types, the reading, the times and the units.
//! - `pairs.rs`: each marker's motion, each pair's distance and how much it looks like a rig.
//! - `advice.rs`: the missing options, the pair the names pick, and the command lines.

mod advice;
mod pairs;

pub use advice::{Need, Suggestion};
pub use pairs::{together, Marker, Pair};

use super::{read_parsed, same_frame, DataError, Format, Parsed, Plane, ReadOptions, Series};
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The most markers whose pairs are compared: the most often seen, so that a Motive take with
/// hundreds of unlabeled markers costs seconds, not hours (a cap the report names).
pub const MAX_PAIR_MARKERS: usize = 100;

/// The most frames a pair is compared over: longer recordings are sampled at an even stride.
pub const MAX_PAIR_FRAMES: usize = 5000;

/// The frame rate the readers number frames at when the file has no times and `--fps` was not
/// given: times are then frame numbers.
const FRAME_NUMBERS: f64 = 1.0;

/// What one recording (one file, or a Tracker file per marker) holds.
#[derive(Debug, Clone, Serialize)]
pub struct Inspection {
    /// The files, in the order given.
    pub files: Vec<PathBuf>,
    /// The format's name (as `--format` takes it).
    pub format: String,
    /// How the format was told: what in the file showed it, or `given by --format`.
    pub detection: String,
    /// Frame times and rate.
    pub time: Timing,
    /// The file's units and what the report's lengths are in.
    pub units: Units,
    /// For 3-D files: the plane the positions were projected onto, and the one that shows the
    /// rig best.
    pub plane: Option<PlaneUse>,
    /// Every marker, in the file's order.
    pub markers: Vec<Marker>,
    /// Pairs of the compared markers, the most rig-like first.
    pub pairs: Vec<Pair>,
    /// Why some markers or frames were left out of the pairs, when any were.
    pub left_out: Vec<String>,
    /// The slider and the bob: the pair the suggestions use, and why.
    pub rig: RigChoice,
    /// Every option still missing or advised, with the value it would take.
    pub suggestions: Vec<Suggestion>,
    /// A ready `appell convert` command (upper-case words are for the user to fill in).
    pub convert_command: String,
    /// A ready `appell fit` command.
    pub fit_command: String,
    /// What the readers said (notes) and inspect assumed.
    pub notes: Vec<String>,
    /// Problems that did not stop the reading.
    pub warnings: Vec<String>,
    /// Why `convert` and `fit` refuse the recording as the printed commands read it (the
    /// readers' own checks after reading: a marker never seen, the scale, coordinates beyond
    /// any rig, the time window), when they do; `None`: they read it.
    pub refused: Option<String>,
    /// Key-value metadata stored in the file.
    pub metadata: BTreeMap<String, String>,
    /// The rod's length in metres, when the file's scale or `--rod-length` tells it: the value
    /// a rig file for the recording starts from.
    pub rod_length: Option<RodLength>,
}

/// The rod's length as a recording or its flags tell it.
#[derive(Debug, Clone, Serialize)]
pub struct RodLength {
    /// Metres.
    pub metres: f64,
    /// Where it comes from: `--rod-length`, or the median slider-bob marker distance of a
    /// file in metric units.
    pub from: String,
}

/// Frame times: from the file, or frame numbers only.
#[derive(Debug, Clone, Serialize)]
pub struct Timing {
    /// Whether positions have times (from the file, or `--fps`); `false`: frame numbers only,
    /// and `--fps` is needed.
    pub timed: bool,
    /// Distinct frame times over every marker.
    pub frames: usize,
    /// The first and last frame's time (seconds in the file's clock), or frame number.
    pub first: f64,
    /// See `first`.
    pub last: f64,
    /// The time from the first frame to the last (seconds, or frames), from the readers' times
    /// relative to the first frame: `last - first` loses the digits a large clock (nanoseconds
    /// since 1970) holds.
    pub span: f64,
    /// The median step between frames (seconds, or frames).
    pub step: Option<f64>,
    /// The smallest and largest step, when they differ from the median by over 1 %.
    pub uneven: Option<[f64; 2]>,
    /// Frames per second, when timed.
    pub rate: Option<f64>,
    /// A frame rate the file's name states (`take_360Hz.csv`), when it has no times.
    pub name_says: Option<f64>,
}

/// The file's units, and the unit the report's positions and distances are in.
#[derive(Debug, Clone, Serialize)]
pub struct Units {
    /// Metres per file unit, when the file says (or `--scale` gives it).
    pub metres_per_unit: Option<f64>,
    /// What the file says of its units, or what is assumed.
    pub said: String,
    /// The unit of the report's lengths: `m` when the scale is known, else the file's (`px`,
    /// `file units`).
    pub unit: String,
    /// Whether y points down in the file (image coordinates).
    pub y_down: bool,
}

/// The plane of a 3-D file.
#[derive(Debug, Clone, Serialize)]
pub struct PlaneUse {
    /// The plane the report's positions are projected onto (`xy`, `xz`, `yz`): `--plane`'s, or
    /// the one whose projection looks most like the rig, or the format's default.
    pub used: String,
    /// Whether `--plane` chose it.
    pub given: bool,
    /// The plane the format is read in without `--plane`.
    pub default: String,
    /// Whether the markers look like a slider and a bob in the plane used.
    pub rig: bool,
}

/// The slider and the bob, by name and by motion.
#[derive(Debug, Clone, Serialize)]
pub struct RigChoice {
    /// The slider's marker the commands use (`None`: no marker can be named).
    pub slider: Option<String>,
    /// The bob's marker the commands use.
    pub bob: Option<String>,
    /// Whether that pair moves like a slider and a bob on a rail.
    pub looks_like_rig: bool,
    /// One line saying why.
    pub why: String,
    /// The pair the names pick (the default "slider"/"bob" matching, or `--slider`/`--bob`);
    /// `None` when they pick none (the suggestions say why).
    pub by_name: Option<[String; 2]>,
}

/// Inspect one recording: one file, or one file per marker (Tracker), read as `convert` reads
/// them. Errors are the readers' (a missing or empty file, an unknown format, a malformed
/// line); a missing `--fps`, scale or marker name is not an error but a suggestion.
pub fn inspect(paths: &[PathBuf], opts: &ReadOptions) -> Result<Inspection, DataError> {
    let mut read = read_lenient(paths, opts)?;
    let mut plane_used = None;
    let plane = match read.parsed.plane {
        Some(default) => {
            let (best, rig) = choose_plane(paths, opts, default, &read)?;
            plane_used = Some(best);
            if best != default {
                let other = ReadOptions {
                    plane: Some(best),
                    ..opts.clone()
                };
                read = read_lenient(paths, &other)?;
            }
            Some(PlaneUse {
                used: best.name().into(),
                given: opts.plane.is_some(),
                default: default.name().into(),
                rig,
            })
        }
        None => None,
    };
    let y_down = opts.y_down.unwrap_or(read.parsed.y_down);
    let units = units(&read.parsed, opts, y_down);
    let scale = units.metres_per_unit.unwrap_or(1.0);
    let look = pairs::Look {
        scale,
        y_down,
        unit: &units.unit,
    };
    let analysis = pairs::analyse(&read.parsed.series, look);
    let time = timing(&read.parsed, read.numbered, paths)?;
    let detection = match (opts.format, paths.first()) {
        (Some(_), _) | (None, None) => "given by --format".to_string(),
        (None, Some(first)) => {
            let how = super::detect_why(first).map_or("its contents", |(_, why)| why);
            format!("detected from {how}")
        }
    };
    let mut notes = Vec::new();
    if read.numbered {
        notes.push(format!(
            "no times in the file and no --fps: frames are numbered 0, 1, 2, ... here (the readers' notes say t = frame / {FRAME_NUMBERS} Hz)"
        ));
    }
    if opts.time_window.is_some() {
        notes.push(
            "inspect looks at the whole recording; --t-start/--t-end are passed on to the commands"
                .into(),
        );
    }
    let mut ins = Inspection {
        files: paths.to_vec(),
        format: read.format.name().into(),
        detection,
        time,
        units,
        plane,
        markers: analysis.markers,
        pairs: analysis.pairs,
        left_out: analysis.left_out,
        rig: RigChoice {
            slider: None,
            bob: None,
            looks_like_rig: false,
            why: String::new(),
            by_name: None,
        },
        suggestions: Vec::new(),
        convert_command: String::new(),
        fit_command: String::new(),
        rod_length: None,
        notes,
        warnings: read.parsed.warnings.clone(),
        metadata: read.parsed.metadata.clone(),
        refused: None,
    };
    ins.notes.extend(read.parsed.notes.iter().cloned());
    advice::advise(&mut ins, &read.parsed, paths, opts);
    ins.refused = refusal(paths, opts, plane_used, read, &ins);
    Ok(ins)
}

/// Why `convert` and `fit` refuse the recording as the printed commands read it, when they do:
/// the checks [`super::recording_of`] makes after reading (the ones `convert` makes), on the
/// pair the commands name and the plane they read, with frame numbers in place of a missing
/// `--fps` and a rod of one metre in place of a missing scale (which the message then says).
/// `None` also when no pair can be named or the files are to be given otherwise: the
/// suggestions say what is missing first.
fn refusal(
    paths: &[PathBuf],
    opts: &ReadOptions,
    plane: Option<Plane>,
    read: Read,
    ins: &Inspection,
) -> Option<String> {
    let (Some(slider), Some(bob)) = (&ins.rig.slider, &ins.rig.bob) else {
        return None;
    };
    if ins.suggestions.iter().any(|s| !s.files.is_empty()) {
        return None;
    }
    let no_scale = ins.units.metres_per_unit.is_none() && opts.rod_length.is_none();
    let as_printed = ReadOptions {
        fps: opts.fps.or(read.numbered.then_some(FRAME_NUMBERS)),
        plane: plane.or(opts.plane),
        slider: Some(slider.clone()),
        bob: Some(bob.clone()),
        rod_length: opts.rod_length.or(no_scale.then_some(1.0)),
        ..opts.clone()
    };
    let e =
        super::recording_of(paths, read.format, read.detected, read.parsed, &as_printed).err()?;
    let mut stand_ins = Vec::new();
    if read.numbered && opts.fps.is_none() {
        stand_ins.push(format!("--fps {FRAME_NUMBERS} (frame numbers)"));
    }
    if no_scale {
        stand_ins.push("--rod-length 1".to_string());
    }
    Some(if stand_ins.is_empty() {
        e.to_string()
    } else {
        format!(
            "{e} (read with {} in place of the values still to give)",
            stand_ins.join(" and ")
        )
    })
}

/// What the readers returned, and whether frames were numbered for want of times.
struct Read {
    parsed: Parsed,
    format: Format,
    /// Whether the format was detected (not given by `--format`).
    detected: bool,
    numbered: bool,
}

/// Read as `convert` does; a file refused without `--fps` (frame numbers only) is read again
/// with its frames numbered. When that fails too, its error is the one reported: it is the
/// next thing wrong with the file (or the same).
fn read_lenient(paths: &[PathBuf], opts: &ReadOptions) -> Result<Read, DataError> {
    match read_parsed(paths, opts) {
        Ok((parsed, format, detected)) => Ok(Read {
            parsed,
            format,
            detected,
            numbered: false,
        }),
        Err(first) if opts.fps.is_none() => {
            let numbered = ReadOptions {
                fps: Some(FRAME_NUMBERS),
                ..opts.clone()
            };
            match read_parsed(paths, &numbered) {
                Ok((parsed, format, detected)) => Ok(Read {
                    parsed,
                    format,
                    detected,
                    numbered: true,
                }),
                Err(again) => Err(match again {
                    // Not an error of the frames' numbering: the first one is as good.
                    DataError::Io { .. } | DataError::Empty { .. } => first,
                    e => e,
                }),
            }
        }
        Err(e) => Err(e),
    }
}

/// The plane of a 3-D file whose projection looks most like the rig (each other plane is read
/// again and its pairs compared), and whether any does; `--plane` is kept as given.
fn choose_plane(
    paths: &[PathBuf],
    opts: &ReadOptions,
    used: Plane,
    read: &Read,
) -> Result<(Plane, bool), DataError> {
    let given = opts.plane.is_some();
    let rank = |parsed: &Parsed| {
        let y_down = opts.y_down.unwrap_or(parsed.y_down);
        let u = units(parsed, opts, y_down);
        let look = pairs::Look {
            scale: u.metres_per_unit.unwrap_or(1.0),
            y_down,
            unit: &u.unit,
        };
        pairs::analyse(&parsed.series, look)
            .pairs
            .first()
            .filter(|p| p.rig)
            .map(|p| p.score)
    };
    let mut best = rank(&read.parsed).map(|s| (s, used));
    if !given {
        for plane in [Plane::Xy, Plane::Xz, Plane::Yz] {
            if plane == used {
                continue;
            }
            let other = ReadOptions {
                plane: Some(plane),
                fps: read.numbered.then_some(FRAME_NUMBERS).or(opts.fps),
                ..opts.clone()
            };
            let (parsed, _, _) = read_parsed(paths, &other)?;
            if let Some(score) = rank(&parsed) {
                if best.is_none_or(|(b, _)| score > b) {
                    best = Some((score, plane));
                }
            }
        }
    }
    Ok(best.map_or((used, false), |(_, p)| (p, true)))
}

/// The file's units as the reader found them (or `--scale`), and the unit the report uses.
fn units(parsed: &Parsed, opts: &ReadOptions, y_down: bool) -> Units {
    let (scale, said) = match (opts.scale, &parsed.scale) {
        (Some(s), _) => (Some(s), format!("{s} m per file unit from --scale")),
        (None, Some((s, why))) => (Some(*s), why.clone()),
        (None, None) if y_down => (None, "no units in the file: pixels".to_string()),
        (None, None) => (
            None,
            "no units in the file (those of its calibration)".to_string(),
        ),
    };
    Units {
        metres_per_unit: scale,
        said,
        unit: match scale {
            Some(_) => "m".into(),
            None if y_down => "px".into(),
            None => "file units".into(),
        },
        y_down,
    }
}

/// The frames over every marker: times that [`same_frame`] joins are one frame (two Tracker
/// exports of one video round its times each their own way). A marker whose own successive
/// times it would join was refused by the reading (`data::check_frame_spacing`).
fn timing(parsed: &Parsed, numbered: bool, paths: &[PathBuf]) -> Result<Timing, DataError> {
    let times = frame_times(&parsed.series.iter().collect::<Vec<_>>());
    let mut steps: Vec<f64> = times.windows(2).map(|w| w[1] - w[0]).collect();
    let step = (!steps.is_empty()).then(|| super::calibrate::median(&mut steps.clone()));
    let uneven = step.and_then(|m| {
        steps.sort_by(f64::total_cmp);
        let (lo, hi) = (steps[0], steps[steps.len() - 1]);
        (lo < 0.99 * m || hi > 1.01 * m).then_some([lo, hi])
    });
    let base = parsed.time_base;
    let (first, last) = (
        times.first().copied().unwrap_or(0.0),
        times.last().copied().unwrap_or(0.0),
    );
    Ok(Timing {
        timed: !numbered,
        frames: times.len(),
        first: base + first,
        last: base + last,
        span: last - first,
        step,
        uneven,
        rate: step.filter(|s| !numbered && *s > 0.0).map(|s| 1.0 / s),
        name_says: if numbered {
            paths.iter().find_map(|p| rate_in_name(p))
        } else {
            None
        },
    })
}

/// Every marker's times merged into one increasing list of frames.
fn frame_times(series: &[&Series]) -> Vec<f64> {
    if let Some(first) = series.first() {
        if series.iter().all(|s| s.times == first.times) {
            return first.times.clone();
        }
    }
    let mut all: Vec<f64> = series
        .iter()
        .flat_map(|s| s.times.iter().copied())
        .collect();
    all.sort_by(f64::total_cmp);
    all.dedup_by(|b, a| same_frame(*a, *b));
    all
}

/// A frame rate stated in a file's name: a number followed by `Hz` or `fps`
/// (`take_360Hz.csv`, `video-120 fps.csv`), case aside.
fn rate_in_name(path: &Path) -> Option<f64> {
    let name = path.file_stem()?.to_str()?.to_ascii_lowercase();
    let bytes = name.as_bytes();
    let mut i = 0;
    while i < bytes.len() {
        if !bytes[i].is_ascii_digit() {
            i += 1;
            continue;
        }
        let start = i;
        while i < bytes.len() && (bytes[i].is_ascii_digit() || bytes[i] == b'.') {
            i += 1;
        }
        let number = &name[start..i];
        let rest = name[i..].trim_start_matches([' ', '_', '-']);
        if rest.starts_with("hz") || rest.starts_with("fps") {
            if let Ok(v) = number.parse::<f64>() {
                if v.is_finite() && v > 0.0 {
                    return Some(v);
                }
            }
        }
    }
    None
}

/// `x` to `digits` significant digits (`450.0`, `0.3000`, `2.9e-8`; `0` for zero): a report's
/// numbers say what they carry, not the seventeen digits of an `f64`.
pub fn sig(x: f64, digits: usize) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let digits = digits.max(1) as i32;
    let mut exponent = x.abs().log10().floor() as i32;
    // 99.996 to four digits is 100.0, not 100.00: the rounding may carry into a new digit.
    let rounded = format!("{:.*e}", (digits - 1) as usize, x);
    if let Some(e) = rounded
        .split('e')
        .nth(1)
        .and_then(|e| e.parse::<i32>().ok())
    {
        exponent = e;
    }
    if !(-4..6).contains(&exponent) {
        return rounded;
    }
    let decimals = (digits - 1 - exponent).max(0) as usize;
    format!("{x:.decimals$}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_frame_rate_is_read_from_a_file_name() {
        let r = |n: &str| rate_in_name(Path::new(n));
        assert_eq!(r("motive_v1.23_ha5dzs_markers_mm_360Hz.csv"), Some(360.0));
        assert_eq!(r("dir/video-119.88 FPS_DLC.csv"), Some(119.88));
        assert_eq!(r("rig_120_fps.h5"), Some(120.0));
        assert_eq!(r("release_01.csv"), None);
        assert_eq!(r("hz.csv"), None);
    }

    #[test]
    fn numbers_carry_their_digits() {
        assert_eq!(sig(449.9999972682611, 4), "450.0");
        assert_eq!(sig(0.0006666666707136873, 3), "0.000667");
        assert_eq!(sig(2.91e-8, 2), "2.9e-8");
        assert_eq!(sig(1.069561, 4), "1.070");
        assert_eq!(sig(123456.0, 3), "123456");
        assert_eq!(sig(0.0, 3), "0");
        assert_eq!(sig(99.99999, 4), "100.0");
        assert_eq!(sig(-0.0123456, 3), "-0.0123");
    }

    #[test]
    fn times_a_hair_apart_are_one_frame() {
        assert!(same_frame(0.03333333333333212, 0.03333333333332848));
        assert!(!same_frame(0.0333, 0.0334));
    }
}
