//! What is still missing to read a recording as the rig, said at once: the frame rate, the
//! scale, the marker names (the pair the names pick, against the pair that moves like a slider
//! and a bob), the plane, the rail frame, the y axis; and the command lines built from them.

use super::pairs::{pair_as_named, Look, Pair, LINE_NOISE, LINE_SHARE, MAX_LEAN_DEG};
use super::{sig, Inspection, RigChoice, RodLength};
use crate::data::calibrate::fit_rail;
use crate::data::{
    align, paths_label, select, DataError, Parsed, ReadOptions, Recording, Series,
    MIN_FRAMES_PER_SWING,
};
use serde::Serialize;
use std::path::PathBuf;

/// Whether a suggestion is needed to read the file at all (or to fit it), or advised.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Need {
    /// `convert` or `fit` refuses the file without it.
    Required,
    /// The file is read without it, but the fit would be of the wrong geometry.
    Advised,
}

/// One option to add: its flags (each with its value, upper case where only the user knows
/// it) or the input files in another order, whether it is required, and why.
#[derive(Debug, Clone, Serialize)]
pub struct Suggestion {
    /// The flags and their values (`("--fps", Some("FPS"))`, `("--rail-frame", None)`).
    pub flags: Vec<(String, Option<String>)>,
    /// The input files as they should be given (empty: as given); `OTHER_FILE` stands for a
    /// file only the user has.
    pub files: Vec<String>,
    /// Required or advised.
    pub need: Need,
    /// Why, with the figures behind it.
    pub why: String,
}

impl Suggestion {
    fn one(flag: &str, value: Option<String>, need: Need, why: String) -> Suggestion {
        Suggestion {
            flags: vec![(flag.to_string(), value)],
            files: Vec::new(),
            need,
            why,
        }
    }

    /// The input files in a new order (or with one added).
    fn files(files: Vec<String>, need: Need, why: String) -> Suggestion {
        Suggestion {
            flags: Vec::new(),
            files,
            need,
            why,
        }
    }

    /// The flags as they are typed (values quoted for the shell where needed), or the files.
    pub fn typed(&self) -> String {
        if self.flags.is_empty() {
            return self
                .files
                .iter()
                .map(|f| quote(f))
                .collect::<Vec<_>>()
                .join(" ");
        }
        self.flags
            .iter()
            .map(|(f, v)| match v {
                Some(v) => format!("{f} {}", quote(v)),
                None => f.clone(),
            })
            .collect::<Vec<_>>()
            .join(" ")
    }
}

/// The slider's track must show the rail's direction to this angle (degrees) or better, beyond
/// three standard errors, for `--rail-frame` to be advised: a camera levelled by eye is off by
/// about a degree, and a rail's tilt is fitted on top.
const TILT_DEG: f64 = 0.1;

/// Fill in the rig choice, the suggestions and the command lines.
pub(super) fn advise(ins: &mut Inspection, parsed: &Parsed, paths: &[PathBuf], opts: &ReadOptions) {
    let unit = ins.units.unit.clone();
    let look = Look {
        scale: ins.units.metres_per_unit.unwrap_or(1.0),
        y_down: ins.units.y_down,
        unit: &unit,
    };
    let mut out = Vec::new();
    if !ins.time.timed {
        let why = match ins.time.name_says {
            Some(hz) => format!("the file holds frame numbers, not times: give the video's frame rate (the file's name says {hz} Hz)"),
            None => "the file holds frame numbers, not times: give the video's frame rate".into(),
        };
        let value = ins
            .time
            .name_says
            .map_or("FPS".to_string(), |hz| hz.to_string());
        out.push(Suggestion::one("--fps", Some(value), Need::Required, why));
    }
    let (rig, names) = choose(ins, parsed, paths, opts, look);
    out.extend(names);
    if let Some(p) = ins
        .plane
        .as_ref()
        .filter(|p| !p.given && p.used != p.default)
    {
        out.push(Suggestion::one(
            "--plane",
            Some(p.used.clone()),
            Need::Required,
            format!(
                "projected onto {}, the markers move like a slider and a bob; onto the format's default plane ({}) they do not as well",
                p.used, p.default
            ),
        ));
    }
    let pair = rig.pair.as_ref();
    ins.rod_length = match (opts.rod_length, ins.units.metres_per_unit, pair) {
        (Some(l), _, _) => Some(RodLength {
            metres: l,
            from: "as given with --rod-length".into(),
        }),
        // The pairs' lengths are in metres once the file's units are known.
        (None, Some(_), Some(p)) if rig.choice.looks_like_rig => Some(RodLength {
            metres: p.median,
            from: format!(
                "the markers' median in {} frames (a ruler's is better)",
                p.frames
            ),
        }),
        _ => None,
    };
    if let Some(w) = too_sparse(ins) {
        ins.warnings.push(w);
    }
    if ins.units.metres_per_unit.is_none() {
        match opts.rod_length {
            None => out.push(Suggestion::one(
                "--rod-length",
                Some("METRES".into()),
                Need::Required,
                match pair {
                    Some(p) => format!(
                        "the positions are in {} with no scale: the rig's measured rod length (pivot to the bob's centre) sets it, dividing the median slider-bob distance of {} {} over {} frames (or give --scale METRES_PER_UNIT)",
                        ins.units.unit,
                        sig(p.median, 4),
                        ins.units.unit,
                        p.frames
                    ),
                    None => format!(
                        "the positions are in {} with no scale: give the rig's measured rod length, which divides the slider-bob distance (or --scale METRES_PER_UNIT)",
                        ins.units.unit
                    ),
                },
            )),
            Some(l) => {
                if let Some(p) = pair {
                    ins.notes.push(format!(
                        "--rod-length {l} m over the median slider-bob distance of {} {} gives {} m per {}",
                        sig(p.median, 4),
                        ins.units.unit,
                        sig(l / p.median, 4),
                        ins.units.unit
                    ));
                }
            }
        }
    }
    if let (Some(p), Some((si, bi)), true) = (pair, rig.indices, rig.choice.looks_like_rig) {
        out.extend(frame(parsed, (si, bi), p, opts, look));
    }
    let files: Vec<String> = out.iter().rev().find(|s| !s.files.is_empty()).map_or_else(
        || paths.iter().map(|p| p.display().to_string()).collect(),
        |s| s.files.clone(),
    );
    ins.convert_command = command("convert", &files, "OUT.csv", opts, &out);
    ins.fit_command = command("fit", &files, "--rig RIG.toml", opts, &out);
    ins.suggestions = out;
    ins.rig = rig.choice;
}

/// The rig choice with the pair's indices into the series, when there is one.
struct Chosen {
    choice: RigChoice,
    pair: Option<Pair>,
    indices: Option<(usize, usize)>,
}

impl Chosen {
    /// No pair to name: `why` says what is missing.
    fn none(why: &str) -> Chosen {
        Chosen {
            choice: RigChoice {
                slider: None,
                bob: None,
                looks_like_rig: false,
                why: why.to_string(),
                by_name: None,
            },
            pair: None,
            indices: None,
        }
    }

    /// The pair `p` of `series`, and what the names picked.
    fn pair(p: &Pair, series: &[Series], by_name: Option<[String; 2]>) -> Chosen {
        let index = |name: &str| series.iter().position(|s| s.name == name);
        Chosen {
            choice: RigChoice {
                slider: Some(p.slider.clone()),
                bob: Some(p.bob.clone()),
                looks_like_rig: usable(p),
                why: p.why.clone(),
                by_name,
            },
            pair: Some(p.clone()),
            indices: index(&p.slider).zip(index(&p.bob)),
        }
    }
}

/// `--slider A --bob B`, required.
fn name_flags(slider: &str, bob: &str, why: String) -> Suggestion {
    Suggestion {
        flags: vec![
            ("--slider".into(), Some(slider.to_string())),
            ("--bob".into(), Some(bob.to_string())),
        ],
        files: Vec::new(),
        need: Need::Required,
        why,
    }
}

/// The slider and the bob: the pair the names pick when it moves like one, else the pair
/// that does, with the flags (or the file order) that name it.
fn choose(
    ins: &Inspection,
    parsed: &Parsed,
    paths: &[PathBuf],
    opts: &ReadOptions,
    look: Look,
) -> (Chosen, Vec<Suggestion>) {
    let series = &parsed.series;
    if series.len() < 2 {
        let why = match series.first() {
            Some(s) => format!(
                "a recording needs the slider and the bob, and this input holds one track ({:?}): give the other marker's file too",
                s.name
            ),
            None => "the input holds no marker".into(),
        };
        let mut with_other: Vec<String> = paths.iter().map(|p| p.display().to_string()).collect();
        with_other.push("OTHER_FILE".into());
        let more = Suggestion::files(with_other, Need::Required, why.clone());
        return (Chosen::none(&why), vec![more]);
    }
    let best = ins
        .pairs
        .iter()
        .find(|p| p.rig)
        .or_else(|| ins.pairs.iter().find(|p| usable(p)));
    let label = paths_label(paths);
    let named = match (
        select(&label, parsed, "slider", opts.slider.as_deref()),
        select(&label, parsed, "bob", opts.bob.as_deref()),
    ) {
        (Ok(s), Ok(b)) if s != b => Ok((s, b)),
        (Ok(_), Ok(_)) => Err("the slider's and the bob's names pick the same marker".to_string()),
        (Err(e), _) => Err(name_problem(&e, opts.slider.as_deref())),
        (_, Err(e)) => Err(name_problem(&e, opts.bob.as_deref())),
    };
    match named {
        Ok(ix) => by_names(ix, best, parsed, paths, look),
        Err(problem) => match best {
            Some(p) => {
                let why = format!(
                    "{problem}; {:?} and {:?} move like a slider and a bob",
                    p.slider, p.bob
                );
                let flags = name_flags(&p.slider, &p.bob, why);
                (Chosen::pair(p, series, None), vec![flags])
            }
            None => {
                let why = match ins.pairs.first() {
                    Some(p) => format!(
                        "{problem}, and no pair of markers moves like a slider and a bob (the closest, {:?} and {:?}: {}): name them",
                        p.slider, p.bob, p.why
                    ),
                    None => format!(
                        "{problem}, and no two markers are {}: name them",
                        super::pairs::together()
                    ),
                };
                let flags = name_flags("SLIDER", "BOB", why.clone());
                (Chosen::none(&why), vec![flags])
            }
        },
    }
}

/// The pair the names pick (`si`, `bi`): kept when it moves like a slider and a bob; turned
/// round (by the flags, or by the files' order when that is what named it) when it does the
/// other way round; else the pair that moves like one, when any does.
fn by_names(
    (si, bi): (usize, usize),
    best: Option<&Pair>,
    parsed: &Parsed,
    paths: &[PathBuf],
    look: Look,
) -> (Chosen, Vec<Suggestion>) {
    let series = &parsed.series;
    let by_name = Some([series[si].name.clone(), series[bi].name.clone()]);
    let as_named = pair_as_named(&series[si], &series[bi], look);
    if let Some(p) = as_named.as_ref().filter(|p| usable(p)) {
        return (Chosen::pair(p, series, by_name), Vec::new());
    }
    let reversed = pair_as_named(&series[bi], &series[si], look);
    if let Some(r) = reversed.as_ref().filter(|p| usable(p)) {
        let by_order = paths.len() == 2
            && parsed
                .notes
                .iter()
                .any(|n| n.contains(crate::data::FILE_ORDER_NOTE));
        if by_order {
            // The tracks were named "slider" and "bob" by their order: say which file is which.
            let track = |k: usize, i: usize| Series {
                name: paths[k].display().to_string(),
                ..series[i].clone()
            };
            let r = pair_as_named(&track(1, bi), &track(0, si), look).unwrap_or_else(|| r.clone());
            let why = format!(
                "{}: give the files the other way round (the first is read as the slider)",
                r.why
            );
            let swapped = vec![r.slider.clone(), r.bob.clone()];
            let mut c = Chosen::pair(&r, series, by_name);
            c.indices = Some((bi, si));
            return (c, vec![Suggestion::files(swapped, Need::Required, why)]);
        }
        let why = format!(
            "the markers read as the slider ({:?}) and the bob ({:?}) are the other way round: {}",
            series[si].name, series[bi].name, r.why
        );
        let flags = name_flags(&r.slider, &r.bob, why);
        return (Chosen::pair(r, series, by_name), vec![flags]);
    }
    let what = match &as_named {
        Some(p) => p.why.clone(),
        None => format!("they are not {}", super::pairs::together()),
    };
    if let Some(p) = best {
        let why = format!(
            "the markers the names pick, {:?} and {:?}, do not move like a slider and a bob ({what}); {:?} and {:?} do",
            series[si].name, series[bi].name, p.slider, p.bob
        );
        let flags = name_flags(&p.slider, &p.bob, why);
        return (Chosen::pair(p, series, by_name), vec![flags]);
    }
    let mut c = match &as_named {
        Some(p) => Chosen::pair(p, series, by_name),
        None => Chosen {
            indices: Some((si, bi)),
            ..Chosen::none("")
        },
    };
    c.choice.slider = Some(series[si].name.clone());
    c.choice.bob = Some(series[bi].name.clone());
    c.choice.why = format!(
        "the markers the names pick do not move like a slider and a bob ({what}), and no other pair does"
    );
    (c, Vec::new())
}

/// A pair that moves like a slider and a bob: every test passes, or all but the bob below the
/// slider, which it is with the file's y the other way (a flag sets that right).
fn usable(p: &Pair) -> bool {
    p.rig || (p.fails == ["hang"] && 180.0 - p.lean_deg <= MAX_LEAN_DEG)
}

/// Why the names pick no marker, in words (the reader's error names the file and lists every
/// marker, which the report lists anyway).
fn name_problem(e: &DataError, wanted: Option<&str>) -> String {
    match (e, wanted) {
        (DataError::MissingMarker { role, .. }, None) => {
            format!("no marker's name contains {role:?}")
        }
        (DataError::MissingMarker { .. }, Some(w)) => format!("no marker is named {w:?}"),
        (
            DataError::AmbiguousMarker {
                role, candidates, ..
            },
            None,
        ) => {
            format!("{candidates} all contain {role:?}")
        }
        (DataError::AmbiguousMarker { candidates, .. }, Some(w)) => {
            format!("{candidates} all match {w:?}")
        }
        (e, _) => e.to_string(),
    }
}

/// The y axis and the rail frame: the other y direction when the bob hangs above the slider
/// as read; `--rail-frame` when the slider's track (with y the right way) shows the rail at an
/// angle to the file's x axis or away from its origin.
fn frame(
    parsed: &Parsed,
    (si, bi): (usize, usize),
    pair: &Pair,
    opts: &ReadOptions,
    look: Look,
) -> Vec<Suggestion> {
    let mut out = Vec::new();
    let upside_down = pair.lean_deg > 90.0;
    if upside_down && opts.y_down.is_none() {
        let (flag, says) = if look.y_down {
            ("--y-up", "down")
        } else {
            ("--y-down", "up")
        };
        out.push(Suggestion::one(
            flag,
            None,
            Need::Required,
            format!(
                "the bob is above the slider with y {says} as read (their mean direction {} deg from straight down), where a pendulum hangs below its pivot: the file's y points the other way",
                sig(pair.lean_deg, 2)
            ),
        ));
    }
    let d = pair.median;
    let moves = pair.slider_travel > LINE_SHARE * d + LINE_NOISE * pair.noise;
    if opts.rail_frame || !moves {
        return out;
    }
    let (times, slider, bob) = align(parsed.series[si].clone(), parsed.series[bi].clone());
    // y up, as the fit reads it (after the flip just advised).
    let flip = if look.y_down != upside_down {
        -1.0
    } else {
        1.0
    };
    let up = |t: Vec<Option<[f64; 2]>>| {
        t.into_iter()
            .map(|p| p.map(|p| [p[0] * look.scale, flip * p[1] * look.scale]))
            .collect()
    };
    let rec = Recording {
        times,
        slider: up(slider),
        bob: up(bob),
        ..Recording::default()
    };
    let Ok((angle, origin, rms)) = fit_rail(&rec) else {
        return out;
    };
    let n = rec.slider.iter().flatten().count().max(1) as f64;
    // The slope's standard error for positions spread evenly along the travel.
    let se = (rms * 12f64.sqrt() / (pair.slider_travel * n.sqrt())).to_degrees();
    let folded = angle - std::f64::consts::PI * (angle / std::f64::consts::PI).round();
    let tilt = folded.to_degrees();
    let (s, c) = angle.sin_cos();
    let offset = (-s * origin[0] + c * origin[1]).abs();
    let tilted = tilt.abs() > TILT_DEG.max(3.0 * se);
    let shifted = offset > LINE_SHARE * d + LINE_NOISE * pair.noise;
    let mut what = Vec::new();
    if tilted {
        what.push(format!("at {} deg to the file's x axis", sig(tilt, 2)));
    }
    if shifted {
        what.push(format!("{} {} from its origin", sig(offset, 3), look.unit));
    }
    if !what.is_empty() {
        out.push(Suggestion::one(
            "--rail-frame",
            None,
            Need::Advised,
            format!(
                "the slider's track (the rail) runs {}: the fit takes x along the rail, and --rail-frame turns and shifts the positions so, the origin at the slider's first position",
                what.join(", ")
            ),
        ));
    }
    out
}

/// A command line: the given recording flags, then the suggested ones (a suggestion replaces a
/// given flag of the same name; `--y-down` and `--y-up` replace each other).
fn command(
    name: &str,
    files: &[String],
    after_files: &str,
    opts: &ReadOptions,
    suggestions: &[Suggestion],
) -> String {
    let mut flags = given_flags(opts);
    for s in suggestions {
        for (flag, value) in &s.flags {
            let same = |f: &str| f == flag || (is_y(f) && is_y(flag));
            flags.retain(|(f, _)| !same(f));
            flags.push((flag.clone(), value.clone()));
        }
    }
    let mut words = vec!["appell".to_string(), name.to_string()];
    words.extend(files.iter().map(|f| quote(f)));
    words.push(after_files.to_string());
    for (f, v) in flags {
        words.push(f);
        if let Some(v) = v {
            words.push(quote(&v));
        }
    }
    words.join(" ")
}

fn is_y(flag: &str) -> bool {
    flag == "--y-down" || flag == "--y-up"
}

/// The recording flags `opts` holds, as typed.
fn given_flags(opts: &ReadOptions) -> Vec<(String, Option<String>)> {
    let mut flags: Vec<(String, Option<String>)> = Vec::new();
    let mut put = |f: &str, v: Option<String>| flags.push((f.to_string(), v));
    if let Some(f) = opts.format {
        put("--format", Some(f.name().into()));
    }
    if let Some(s) = &opts.slider {
        put("--slider", Some(s.clone()));
    }
    if let Some(b) = &opts.bob {
        put("--bob", Some(b.clone()));
    }
    for (flag, v) in [
        ("--scale", opts.scale),
        ("--fps", opts.fps),
        ("--rod-length", opts.rod_length),
    ] {
        if let Some(v) = v {
            put(flag, Some(v.to_string()));
        }
    }
    if let Some(p) = opts.plane {
        put("--plane", Some(p.name().into()));
    }
    match opts.y_down {
        Some(true) => put("--y-down", None),
        Some(false) => put("--y-up", None),
        None => {}
    }
    if opts.rail_frame {
        put("--rail-frame", None);
    }
    if opts.min_likelihood != ReadOptions::default().min_likelihood {
        put("--min-likelihood", Some(opts.min_likelihood.to_string()));
    }
    if opts.drop_outliers {
        put("--drop-outliers", None);
    }
    if let Some((start, end)) = opts.time_window {
        if start > 0.0 {
            put("--t-start", Some(start.to_string()));
        }
        if end.is_finite() {
            put("--t-end", Some(end.to_string()));
        }
    }
    for t in &opts.topics {
        put("--topic", Some(t.clone()));
    }
    flags
}

/// A word as a POSIX shell reads it back: as it is when it holds only safe characters (and
/// upper-case placeholders), else in single quotes.
pub fn quote(word: &str) -> String {
    let safe = |c: char| c.is_ascii_alphanumeric() || "_./:=+,@%-".contains(c);
    if !word.is_empty() && word.chars().all(safe) {
        word.to_string()
    } else {
        format!("'{}'", word.replace('\'', r"'\''"))
    }
}

/// A warning when the frames are too far apart for a pendulum of the rod's length: the fit
/// refuses fewer than [`MIN_FRAMES_PER_SWING`] frames a swing (`fit::check_frame_rate`), and
/// such spacing is almost always times in milliseconds read as seconds. Said here so that the
/// fit command inspect suggests is not refused without a word.
fn too_sparse(ins: &Inspection) -> Option<String> {
    // The rod as inspect takes it, else the closest pair's distance once the units are
    // metres (a clip that starts with the rod level does not look like a rig, yet swings so).
    let rod = match &ins.rod_length {
        Some(r) => r.metres,
        None => ins
            .units
            .metres_per_unit
            .and(ins.pairs.first())
            .map(|p| p.median)?,
    };
    let step = ins.time.step?;
    if !ins.time.timed || rod.is_nan() || rod <= 0.0 {
        return None;
    }
    let rig = crate::model::Rig {
        rod_length: rod,
        marker_length: rod,
        ..crate::model::Rig::paper(0.0)
    };
    let period = crate::model::pendulum::stuck_period(&rig, 0.0);
    let per_swing = period / step;
    (per_swing < MIN_FRAMES_PER_SWING).then(|| {
        format!(
            "the frames are {} s apart, {} a swing of a {} m pendulum (a period of {} s), where a fit needs at least {MIN_FRAMES_PER_SWING}: are the times in milliseconds? a column of milliseconds is headed t_ms (or time_ms)",
            sig(step, 4),
            sig(per_swing, 3),
            sig(rod, 3),
            sig(period, 3)
        )
    })
}

#[cfg(test)]
mod tests {
    use super::quote;

    #[test]
    fn words_are_quoted_only_when_the_shell_needs_it() {
        assert_eq!(
            quote("tests/data/dlc_example.csv"),
            "tests/data/dlc_example.csv"
        );
        assert_eq!(quote("Unlabeled 1036"), "'Unlabeled 1036'");
        assert_eq!(quote("it's"), r"'it'\''s'");
        assert_eq!(quote(""), "''");
    }
}
