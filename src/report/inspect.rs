//! `appell inspect`'s report: what a recording holds, the pair that looks like the slider and
//! the bob, the options still missing and the commands to run, as text or one JSON object.

use crate::data::inspect::{sig, Inspection, Need};
use crate::fit::priors::{DEFAULT_BOB_MASS_REL, DEFAULT_ROD_LENGTH_SD, DEFAULT_SLIDER_MASS_REL};
use crate::scene::RIG_PLACEHOLDERS;
use serde_json::Value;

/// The pairs the text lists (the JSON lists every pair compared).
pub const PAIRS_SHOWN: usize = 8;

/// The inspection as one JSON object, with the rig file to fill in (`rig_template`) when the
/// file holds a rig.
pub fn inspect_json(ins: &Inspection) -> Value {
    let mut v = serde_json::to_value(ins).expect("an inspection serializes");
    if ins.rig.looks_like_rig && ins.refused.is_none() {
        v["rig_template"] = Value::String(rig_template(ins));
    }
    v
}

/// A rig file for the recording: the `[rig]` section with every key a lab measures, its unit
/// and how it is measured; what the recording or its flags tell (the rod's length) filled in,
/// the rest upper-case placeholders ([`RIG_PLACEHOLDERS`]) that the fit refuses, naming them,
/// until they are replaced; the measurement errors' defaults as comments.
pub fn rig_template(ins: &Inspection) -> String {
    let files: Vec<String> = ins.files.iter().map(|f| f.display().to_string()).collect();
    let key = |key: &str, value: &str, comment: &str| {
        format!("{:<26}# {comment}\n", format!("{key} = {value}"))
    };
    let (rod, rod_from) = match &ins.rod_length {
        Some(l) => (
            sig(l.metres, 4),
            format!("m, pivot axis to the bob's centre: {}", l.from),
        ),
        None => (
            RIG_PLACEHOLDERS[2].0.to_owned(),
            "m, pivot axis to the bob's centre (its marker), as measured".to_owned(),
        ),
    };
    let mut s = format!(
        "# The rig of {}, from `appell inspect`.\n# Replace the upper-case values with what the lab measured (upper case left in is refused).\n[rig]\n",
        files.join(" + ")
    );
    s += &key(
        "slider_mass",
        RIG_PLACEHOLDERS[0].0,
        "kg, the slider with its pivot and what rides on it, as weighed",
    );
    s += &key("bob_mass", RIG_PLACEHOLDERS[1].0, "kg, as weighed");
    s += &key("rod_length", &rod, &rod_from);
    s += &key(
        "# gravity",
        "9.81",
        "m/s^2; left out, 9.81 +- 0.015 is fitted (or give --latitude)",
    );
    s += &key(
        "# rod_length_sd",
        &DEFAULT_ROD_LENGTH_SD.to_string(),
        "m, 1 sd, the default (a ruler); 0 holds a value exact",
    );
    s += &format!(
        "# slider_mass_sd, bob_mass_sd: 1 sd in kg; left out, {} % and {} % of the masses (a scale)\n",
        DEFAULT_SLIDER_MASS_REL * 100.0,
        DEFAULT_BOB_MASS_REL * 100.0
    );
    s += "# A rigid pendulum (a rod with mass, a bob of some size): rod_mass (kg), bob_radius (m).\n";
    s += "# mu and the friction law are what the fit finds; docs/simulation.md lists every key.\n";
    s
}

/// The inspection as text, one item per line.
pub fn inspect_text(ins: &Inspection) -> String {
    let mut s = String::new();
    let files: Vec<String> = ins.files.iter().map(|f| f.display().to_string()).collect();
    s += &format!("{}\n", files.join(" + "));
    s += &format!("  format     {}, {}\n", ins.format, ins.detection);
    s += &format!("  frames     {}\n", frames_line(ins));
    let u = &ins.units;
    s += &format!(
        "  units      {}; y {} in the file; lengths below in {}\n",
        u.said,
        if u.y_down { "down" } else { "up" },
        u.unit
    );
    if let Some(p) = &ins.plane {
        let how = if p.given {
            "from --plane".to_string()
        } else if p.used == p.default {
            format!(
                "the format's default{}",
                if p.rig {
                    ""
                } else {
                    "; no plane shows a slider and a bob"
                }
            )
        } else {
            format!(
                "where the markers look most like a slider and a bob (the format's default is {})",
                p.default
            )
        };
        s += &format!("  plane      {} ({how})\n", p.used);
    }
    markers(&mut s, ins);
    pairs(&mut s, ins);
    let r = &ins.rig;
    let verdict = match (&r.slider, &r.bob, r.looks_like_rig) {
        (Some(a), Some(b), true) => format!("slider {a:?}, bob {b:?}: {}", r.why),
        _ => r.why.clone(),
    };
    s += &format!("  rig        {verdict}\n");
    if let Some(why) = &ins.refused {
        // No commands to run: convert and fit stop at what is wrong with the file.
        s += &format!("  refused    convert and fit refuse this recording: {why}\n");
    } else {
        s += &options_and_commands(ins);
    }
    for n in &ins.left_out {
        s += &format!("  note: {n}\n");
    }
    for n in &ins.notes {
        s += &format!("  note: {n}\n");
    }
    for w in &ins.warnings {
        s += &format!("  warning: {w}\n");
    }
    if !ins.metadata.is_empty() {
        let kv: Vec<String> = ins
            .metadata
            .iter()
            .map(|(k, v)| format!("{k}={v}"))
            .collect();
        s += &format!("  metadata: {}\n", kv.join(", "));
    }
    s
}

/// The options still missing, the commands to run and the rig file to fill in.
fn options_and_commands(ins: &Inspection) -> String {
    let mut out = String::new();
    if ins.suggestions.is_empty() {
        out += "  options    none missing: the file reads as it is\n";
    }
    for (k, sg) in ins.suggestions.iter().enumerate() {
        let head = if k == 0 {
            "  options    "
        } else {
            "             "
        };
        let need = match sg.need {
            Need::Required => "required",
            Need::Advised => "advised",
        };
        let what = if sg.flags.is_empty() {
            format!("files {}", sg.typed())
        } else {
            sg.typed()
        };
        out += &format!("{head}{what} ({need}): {}\n", sg.why);
    }
    out += &format!("  run        {}\n", ins.convert_command);
    out += &format!("             {}\n", ins.fit_command);
    out += &format!("             ({})\n", placeholders(ins));
    if ins.rig.looks_like_rig {
        out += "  rig file   RIG.toml for the fit, to fill in (`--rig-template RIG.toml` writes it):\n";
        for line in rig_template(ins).lines() {
            out += &format!("    {line}\n");
        }
    }
    out
}

/// How many frames, over what, at what rate.
fn frames_line(ins: &Inspection) -> String {
    let t = &ins.time;
    let uneven = |unit: &str| match t.uneven {
        Some([lo, hi]) => format!(
            "; steps uneven, from {} to {} {unit}",
            sig(lo, 3),
            sig(hi, 3)
        ),
        None => String::new(),
    };
    if !t.timed {
        let hint = match t.name_says {
            Some(hz) => format!(" (the file's name says {hz} Hz)"),
            None => String::new(),
        };
        let frame = |x: f64| {
            if x.fract() == 0.0 && x.abs() < 1e15 {
                format!("{}", x as i64)
            } else {
                sig(x, 6)
            }
        };
        return format!(
            "{}, frame numbers {} to {} only: the file holds no times, so --fps is needed{hint}{}",
            t.frames,
            frame(t.first),
            frame(t.last),
            uneven("frames")
        );
    }
    let rate = match t.rate {
        Some(hz) => format!(", {} frames/s", sig(hz, 4)),
        None => String::new(),
    };
    // A clock of seconds since 1970 is said to the millisecond, not to six digits.
    let start = match t.first {
        0.0 => String::new(),
        x if x.abs() >= 1e4 => format!(", from {x:.3} s on the file's clock"),
        x => format!(", from {} s on the file's clock", sig(x, 6)),
    };
    format!(
        "{} over {} s{start}{rate}{}",
        t.frames,
        sig(t.span, 4),
        uneven("s")
    )
}

/// Decimal places that show the report's lengths to about four significant digits at the size
/// of the largest of them.
fn length_decimals(ins: &Inspection) -> usize {
    let largest = ins
        .markers
        .iter()
        .flat_map(|m| m.x.into_iter().chain(m.y).flatten())
        .fold(0.0f64, |a, v| a.max(v.abs()));
    if largest > 0.0 {
        (3 - largest.log10().floor() as i32).clamp(0, 8) as usize
    } else {
        1
    }
}

/// One line a marker: frames seen, ranges, travel, spread off a line.
fn markers(s: &mut String, ins: &Inspection) {
    let dec = length_decimals(ins);
    let width = ins
        .markers
        .iter()
        .map(|m| m.name.len())
        .max()
        .unwrap_or(0)
        .min(30);
    let frames = ins.time.frames;
    *s += &format!(
        "  markers    {}: frames seen, x and y ranges, travel and robust spread off a straight line ({})\n",
        ins.markers.len(),
        ins.units.unit
    );
    for m in &ins.markers {
        let range = |r: Option<[f64; 2]>| match r {
            // Beyond a million, digits to the unit say nothing more.
            Some([a, b]) if a.abs().max(b.abs()) >= 1e6 => {
                format!("{} to {}", sig(a, 4), sig(b, 4))
            }
            Some([a, b]) => format!("{a:.dec$} to {b:.dec$}"),
            None => "-".into(),
        };
        *s += &format!(
            "    {:width$}  {:>w$} of {frames}  x {}  y {}  travel {}  off line {}\n",
            m.name,
            m.seen,
            range(m.x),
            range(m.y),
            // Positions a whole f64 range apart have a travel no number holds.
            if m.travel.is_finite() {
                sig(m.travel, 3)
            } else {
                "-".into()
            },
            m.off_line.map_or("-".into(), |d| sig(d, 2)),
            w = frames.to_string().len()
        );
    }
}

/// The ranked pairs, at most [`PAIRS_SHOWN`].
fn pairs(s: &mut String, ins: &Inspection) {
    let unit = &ins.units.unit;
    if ins.pairs.is_empty() {
        *s += &format!(
            "  pairs      none compared (no two markers are {})\n",
            crate::data::inspect::together()
        );
        return;
    }
    *s += &format!(
        "  pairs      {} compared, the most like a slider and a bob first: slider -> bob, distance median +- robust spread ({unit}), slider off its line, swing\n",
        ins.pairs.len()
    );
    for (k, p) in ins.pairs.iter().take(PAIRS_SHOWN).enumerate() {
        *s += &format!(
            "    {:>2}. {:?} -> {:?}  {} +- {} over {} frames  off line {}  swing {} deg  score {:.2}{}\n",
            k + 1,
            p.slider,
            p.bob,
            sig(p.median, 4),
            sig(p.spread, 2),
            p.frames,
            sig(p.slider_off_line, 2),
            sig(p.swing_deg, 2),
            p.score,
            if p.rig { "  rig" } else { "" }
        );
    }
    if ins.pairs.len() > PAIRS_SHOWN {
        *s += &format!(
            "        ... {} more pairs (--json lists them all)\n",
            ins.pairs.len() - PAIRS_SHOWN
        );
    }
}

/// What the upper-case words of the commands stand for.
fn placeholders(ins: &Inspection) -> String {
    let words = format!("{} {}", ins.convert_command, ins.fit_command);
    let mut said = Vec::new();
    for (word, meaning) in [
        ("OTHER_FILE", "OTHER_FILE the other marker's file"),
        ("FPS", "FPS the video's frame rate in Hz"),
        ("METRES", "METRES the rig's rod length in metres"),
        ("SLIDER", "SLIDER and BOB the markers' names"),
        (
            "RIG.toml",
            "RIG.toml your rig file (below, with what the file tells filled in)",
        ),
        ("OUT.csv", "OUT.csv the canonical CSV to write"),
    ] {
        if words.split(' ').any(|w| w == word) {
            said.push(meaning);
        }
    }
    format!("upper case is yours to fill in: {}", said.join(", "))
}
