//! How each marker moves, and how much each pair of markers looks like the slider and the bob:
//! the slider runs along the rail (its track close to a straight line, or it barely moves), the
//! bob keeps a rod's length from it and swings.

use super::{frame_times, same_frame, sig, MAX_PAIR_FRAMES, MAX_PAIR_MARKERS};
use crate::data::calibrate::{geometry, off_line_spread};
use crate::data::{Geometry, Series};
use serde::Serialize;

/// The share of the pair's distance the slider's track may lie off its best straight line
/// (robust spread), besides its noise: a slider on a straight rail seen through a lens that
/// distorts by up to 2 % at the frame's edge stays well within it (as `fit`'s swap check,
/// `fit::checks::SWAP_SHARE`).
pub const LINE_SHARE: f64 = 0.01;

/// Noise deviations of the pair's distance the slider's track may also lie off its line.
pub const LINE_NOISE: f64 = 5.0;

/// The bob's swing about the slider (degrees, between the 5th and 95th percentiles of its
/// direction) below which the pair does not look like a pendulum: a release that shows the
/// friction swings through tens of degrees, and markers at rest jitter through a few (a Motive
/// take of static markers: up to 2.6 deg between markers 28 mm apart).
pub const MIN_SWING_DEG: f64 = 5.0;

/// How many times the distance's robust spread (or its noise, if larger) the bob's arc must
/// bow out from its chord: the sagitta d (1 - cos(swing / 2)) of a swing about a fixed point.
/// A marker running along a straight line past another keeps a nearly constant distance from it
/// too, but varies it by about the sagitta its sweep would have: a pendulum's bob swings far
/// enough for its distance to hold several times better than that (the shipped rigs: arcs of
/// 0.1 to 0.2 m against spreads under 0.6 mm).
pub const ARC_SPREADS: f64 = 4.0;

/// The largest angle (degrees) between straight down (the file's) and the mean direction from
/// the slider to the bob: a pendulum swings about the vertical below its pivot (offset by a
/// camera's or a rail's tilt of a few degrees); two feet on a floor keep their distance too,
/// side by side.
pub const MAX_LEAN_DEG: f64 = 30.0;

/// The largest angle (degrees) between the slider's line and the file's x axis: a rail is
/// level, and a camera is mounted about level (a tilt of a few degrees is what `--rail-frame`
/// takes out); a marker running up and down is a limb, not a slider.
pub const MAX_TILT_DEG: f64 = 45.0;

/// Frames with both markers a pair needs to be compared: fewer tell nothing of a motion.
pub const MIN_COMMON_FRAMES: usize = 20;

/// What two markers must be to be compared, in the words every reason uses: seen together in
/// [`MIN_COMMON_FRAMES`] frames, at a distance (and spread) an `f64` holds.
pub fn together() -> String {
    format!("seen together in {MIN_COMMON_FRAMES} frames at a distance a number holds")
}

/// Frames with both markers a pair needs to be taken for the rig when the names do not say
/// so: over a short clip two body parts can keep their distance by chance (a DeepLabCut clip of
/// two mice: an ear of one and the snout of the other within 0.7 % over 27 frames), and a
/// release worth fitting has hundreds.
pub const MIN_RIG_FRAMES: usize = 50;

/// The share of the distance its robust spread may reach (besides five noise deviations) for
/// a pair the names do not pick: the rigs' recordings spread by 0.1-0.2 % (a lens, a rolling
/// shutter), markers on a body by several per cent. A pair the names pick is held to the fit's
/// own limit, [`Geometry::RIGID_SHARE`].
pub const ROD_SHARE: f64 = 0.02;

/// One marker: how often it is seen and how it moves (lengths in the report's unit).
#[derive(Debug, Clone, Serialize)]
pub struct Marker {
    /// Its name in the file.
    pub name: String,
    /// Frames with a position.
    pub seen: usize,
    /// The smallest and largest x (`None` when never seen).
    pub x: Option<[f64; 2]>,
    /// The smallest and largest y.
    pub y: Option<[f64; 2]>,
    /// How far it travels: the diagonal of the box holding its positions between their 2nd and
    /// 98th percentiles (a few mis-tracked positions do not stretch it); infinite for
    /// positions the whole range of a number apart (the text then shows `-`).
    pub travel: f64,
    /// The robust spread of its positions across their best straight line (`None` with fewer
    /// than 10 positions, or positions so large that the spread is no number).
    pub off_line: Option<f64>,
    /// The angle of that line to the file's x axis, degrees in (-90, 90] (`None` with fewer
    /// than 2 positions).
    pub heading_deg: Option<f64>,
    /// Whether its pairs were compared (the most often seen, at least 10 frames).
    pub compared: bool,
}

/// A pair of markers read as a slider and a bob (lengths in the report's unit).
#[derive(Debug, Clone, Serialize)]
pub struct Pair {
    /// The marker read as the slider.
    pub slider: String,
    /// The marker read as the bob.
    pub bob: String,
    /// Frames with both (of those compared).
    pub frames: usize,
    /// The median distance between them.
    pub median: f64,
    /// Its robust spread (1.4826 times the median absolute deviation).
    pub spread: f64,
    /// The spread a rod's markers may show: five noise deviations plus 2 % of the median (5 %,
    /// the fit's limit, for the pair the names pick).
    pub rod_allows: f64,
    /// The distance's noise from frame to frame.
    pub noise: f64,
    /// The slider's robust spread off its best straight line.
    pub slider_off_line: f64,
    /// How far the slider travels.
    pub slider_travel: f64,
    /// The bob's swing about the slider (degrees, 5th to 95th percentile of its direction).
    pub swing_deg: f64,
    /// The mean direction from the slider to the bob, in degrees from straight down (the file's
    /// down): near 0 for a pendulum, near 180 when the file's y points the other way.
    pub lean_deg: f64,
    /// How much the pair looks like a rig, from 0 to 1: the product over the five tests
    /// (constant distance, slider on a line, the line about level, bob swinging, bob below) of
    /// 1 / (1 + r^2), r each test's measure over its limit.
    pub score: f64,
    /// Whether all five tests pass (over at least [`MIN_RIG_FRAMES`] frames, for a pair the
    /// names do not pick).
    pub rig: bool,
    /// The tests that fail: `rod`, `line`, `level`, `swing`, `hang`, `frames`.
    pub fails: Vec<String>,
    /// One line saying what passes and what does not.
    pub why: String,
}

/// How positions are read: file units times `scale` give the report's `unit`, and whether y
/// points down.
#[derive(Debug, Clone, Copy)]
pub(super) struct Look<'a> {
    pub scale: f64,
    pub y_down: bool,
    pub unit: &'a str,
}

/// Every marker, and the compared pairs ranked, the most rig-like first.
pub(super) struct Analysis {
    pub markers: Vec<Marker>,
    pub pairs: Vec<Pair>,
    pub left_out: Vec<String>,
}

/// Describe every marker and compare the pairs of the most often seen ones (at most
/// [`MAX_PAIR_MARKERS`], over at most [`MAX_PAIR_FRAMES`] frames at an even stride).
pub(super) fn analyse(series: &[Series], look: Look) -> Analysis {
    let scale = look.scale;
    let mut markers: Vec<Marker> = series.iter().map(|s| marker(s, scale)).collect();
    let mut order: Vec<usize> = (0..series.len())
        .filter(|&i| markers[i].seen >= MIN_COMMON_FRAMES)
        .collect();
    let rare = series.len() - order.len();
    // The most often seen first; among equals those that move most (a rig's markers among
    // static ones), then the file's order.
    order.sort_by(|&i, &j| {
        (markers[j].seen.cmp(&markers[i].seen))
            .then(markers[j].travel.total_cmp(&markers[i].travel))
    });
    let mut left_out = Vec::new();
    if rare > 0 {
        left_out.push(format!(
            "{rare} marker(s) seen in fewer than {MIN_COMMON_FRAMES} frames, not compared"
        ));
    }
    if order.len() > MAX_PAIR_MARKERS {
        left_out.push(format!(
            "pairs compared among the {MAX_PAIR_MARKERS} markers seen most often, of {}",
            order.len()
        ));
        order.truncate(MAX_PAIR_MARKERS);
    }
    order.sort_unstable();
    for &i in &order {
        markers[i].compared = true;
    }
    let chosen: Vec<&Series> = order.iter().map(|&i| &series[i]).collect();
    let (tracks, stride, frames) = on_common_frames(&chosen, scale);
    if stride > 1 {
        left_out.push(format!(
            "pairs compared over every {} frame of {frames}",
            ordinal(stride)
        ));
    }
    let mut pairs = Vec::new();
    for a in 0..order.len() {
        for b in a + 1..order.len() {
            let (ma, mb) = (&markers[order[a]], &markers[order[b]]);
            if let Some(p) = compare(&tracks[a], &tracks[b], ma, mb, look) {
                pairs.push(p);
            }
        }
    }
    rank(&mut pairs);
    Analysis {
        markers,
        pairs,
        left_out,
    }
}

/// Rank pairs: those that pass every test first, then by score.
pub(super) fn rank(pairs: &mut [Pair]) {
    pairs.sort_by(|p, q| q.rig.cmp(&p.rig).then(q.score.total_cmp(&p.score)));
}

/// Compare two series as slider and bob, the slider first (both orders are not tried): for a
/// pair the names pick. `None` when they share fewer than [`MIN_COMMON_FRAMES`] frames.
pub(super) fn pair_as_named(slider: &Series, bob: &Series, look: Look) -> Option<Pair> {
    let (tracks, _, _) = on_common_frames(&[slider, bob], look.scale);
    let (ms, mb) = (marker(slider, look.scale), marker(bob, look.scale));
    let g = pair_geometry(&tracks[0], &tracks[1])?;
    let (swing, lean) = swing_and_lean(&tracks[0], &tracks[1], look.y_down);
    Some(judge(&ms, &mb, &g, (swing, lean), look, true))
}

/// One marker's count and motion.
fn marker(s: &Series, scale: f64) -> Marker {
    let pts: Vec<[f64; 2]> = s
        .points
        .iter()
        .flatten()
        .map(|p| [p[0] * scale, p[1] * scale])
        .collect();
    let range = |k: usize| {
        pts.iter().fold(None, |r: Option<[f64; 2]>, p| {
            Some(r.map_or([p[k], p[k]], |r| [r[0].min(p[k]), r[1].max(p[k])]))
        })
    };
    let travel = if pts.is_empty() {
        0.0
    } else {
        let spread = |k: usize| {
            let mut v: Vec<f64> = pts.iter().map(|p| p[k]).collect();
            v.sort_by(f64::total_cmp);
            let n = v.len() - 1;
            v[n * 98 / 100] - v[n * 2 / 100]
        };
        spread(0).hypot(spread(1))
    };
    Marker {
        name: s.name.clone(),
        seen: pts.len(),
        x: range(0),
        y: range(1),
        travel,
        off_line: off_line_spread(&s.points)
            .map(|d| d * scale)
            .filter(|d| d.is_finite()),
        heading_deg: heading(&pts),
        compared: false,
    }
}

/// The angle of the principal axis of a cloud of points to the x axis, degrees in (-90, 90].
fn heading(pts: &[[f64; 2]]) -> Option<f64> {
    if pts.len() < 2 {
        return None;
    }
    let n = pts.len() as f64;
    let (mx, my) = pts
        .iter()
        .fold((0.0, 0.0), |(a, b), p| (a + p[0] / n, b + p[1] / n));
    let (sxx, syy, sxy) = pts.iter().fold((0.0, 0.0, 0.0), |(xx, yy, xy), p| {
        let (dx, dy) = (p[0] - mx, p[1] - my);
        (xx + dx * dx, yy + dy * dy, xy + dx * dy)
    });
    let a = (0.5 * (2.0 * sxy).atan2(sxx - syy)).to_degrees();
    Some(if a <= -90.0 { a + 180.0 } else { a })
}

/// The series' positions (scaled) on their common frames: the union of their times, sampled at
/// a stride that keeps at most [`MAX_PAIR_FRAMES`]. Returns the tracks, the stride and the
/// number of frames before sampling.
fn on_common_frames(series: &[&Series], scale: f64) -> (Vec<Vec<Option<[f64; 2]>>>, usize, usize) {
    let times = frame_times(series);
    let stride = times.len().div_ceil(MAX_PAIR_FRAMES).max(1);
    let tracks = series
        .iter()
        .map(|s| {
            let mut track = vec![None; times.len().div_ceil(stride)];
            let mut k = 0;
            for (t, p) in s.times.iter().zip(&s.points) {
                while k < times.len() && times[k] < *t && !same_frame(times[k], *t) {
                    k += 1;
                }
                if k < times.len() && same_frame(times[k], *t) && k % stride == 0 {
                    track[k / stride] = p.map(|p| [p[0] * scale, p[1] * scale]);
                }
            }
            track
        })
        .collect();
    (tracks, stride, times.len())
}

/// The distance of two tracks (`None` with fewer than [`MIN_COMMON_FRAMES`] frames with both,
/// or positions so far apart that the distance or its spread is no number).
fn pair_geometry(a: &[Option<[f64; 2]>], b: &[Option<[f64; 2]>]) -> Option<Geometry> {
    geometry(a, b, None).filter(|g| {
        g.frames >= MIN_COMMON_FRAMES && [g.median, g.spread, g.noise].iter().all(|v| v.is_finite())
    })
}

/// Compare two tracks both ways round and keep the order that looks more like a rig.
fn compare(
    a: &[Option<[f64; 2]>],
    b: &[Option<[f64; 2]>],
    ma: &Marker,
    mb: &Marker,
    look: Look,
) -> Option<Pair> {
    let g = pair_geometry(a, b)?;
    let (swing, lean) = swing_and_lean(a, b, look.y_down);
    let ab = judge(ma, mb, &g, (swing, lean), look, false);
    let ba = judge(mb, ma, &g, (swing, 180.0 - lean), look, false);
    // Equal scores (two markers at rest) leave the bob the one below.
    Some(
        if (ba.rig, ba.score, -ba.lean_deg) > (ab.rig, ab.score, -ab.lean_deg) {
            ba
        } else {
            ab
        },
    )
}

/// The swing of `b` about `a` in degrees (the range between the 5th and 95th percentiles of
/// the direction from `a` to `b`, measured from its mean direction, so with no wrap at
/// +-180 deg), and how far that mean direction leans from straight down (degrees, 0 to 180).
fn swing_and_lean(a: &[Option<[f64; 2]>], b: &[Option<[f64; 2]>], y_down: bool) -> (f64, f64) {
    let v: Vec<[f64; 2]> = a
        .iter()
        .zip(b)
        .filter_map(|(a, b)| {
            Some([
                b.as_ref()?[0] - a.as_ref()?[0],
                b.as_ref()?[1] - a.as_ref()?[1],
            ])
        })
        .filter(|v| v[0] != 0.0 || v[1] != 0.0)
        .collect();
    let mean = v.iter().fold([0.0, 0.0], |m, v| {
        let r = v[0].hypot(v[1]);
        [m[0] + v[0] / r, m[1] + v[1] / r]
    });
    if v.is_empty() || (mean[0] == 0.0 && mean[1] == 0.0) {
        return (0.0, 90.0);
    }
    let mut angles: Vec<f64> = v
        .iter()
        .map(|v| (mean[0] * v[1] - mean[1] * v[0]).atan2(mean[0] * v[0] + mean[1] * v[1]))
        .collect();
    angles.sort_by(f64::total_cmp);
    let n = angles.len() - 1;
    let swing = (angles[n * 95 / 100] - angles[n * 5 / 100]).to_degrees();
    let down = if y_down { mean[1] } else { -mean[1] };
    let lean = mean[0].abs().atan2(down).to_degrees();
    (swing, lean)
}

/// Judge a pair read as slider `s` and bob `b` (the bob's swing about the slider and its lean
/// from straight below it, in degrees): the tests, the score and the line. `named`: the names
/// pick the pair, which is then held to the fit's own limits only.
fn judge(
    s: &Marker,
    b: &Marker,
    g: &Geometry,
    (swing, lean): (f64, f64),
    look: Look,
    named: bool,
) -> Pair {
    let Look { y_down, unit, .. } = look;
    let len = |x: f64, digits: usize| format!("{} {unit}", sig(x, digits));
    let d = g.median;
    let share = if named {
        Geometry::RIGID_SHARE
    } else {
        ROD_SHARE
    };
    let rod_allows = Geometry::RIGID_NOISE * g.noise + share * d;
    let line_allows = LINE_SHARE * d + LINE_NOISE * g.noise;
    // The swing whose arc bows out by ARC_SPREADS spreads: 2 acos(1 - k s / d).
    let bow = (ARC_SPREADS * g.spread.max(g.noise) / d.max(f64::MIN_POSITIVE)).min(1.0);
    let swing_needs = MIN_SWING_DEG.max(2.0 * (1.0 - bow).acos().to_degrees());
    let off = s.off_line.unwrap_or(f64::INFINITY);
    let ratio = |x: f64, limit: f64| if x <= 0.0 { 0.0 } else { x / limit };
    let barely = s.travel <= LINE_SHARE * d.max(0.0) + LINE_NOISE * g.noise;
    // A slider that barely moves shows no direction.
    let tilt = if barely {
        0.0
    } else {
        s.heading_deg.unwrap_or(0.0)
    };
    let r = [
        ratio(g.spread, rod_allows),
        ratio(off, line_allows),
        ratio(tilt.abs(), MAX_TILT_DEG),
        if swing > 0.0 {
            swing_needs / swing
        } else {
            f64::INFINITY
        },
        ratio(lean, MAX_LEAN_DEG),
    ];
    let score = r.iter().map(|r| 1.0 / (1.0 + r * r)).product::<f64>();
    let mut fails: Vec<String> = ["rod", "line", "level", "swing", "hang"]
        .iter()
        .zip(&r)
        .filter(|(_, r)| **r > 1.0)
        .map(|(t, _)| t.to_string())
        .collect();
    let short = !named && g.frames < MIN_RIG_FRAMES;
    if short {
        fails.push("frames".into());
    }
    let rig = fails.is_empty();
    let pct = 100.0 * g.spread / d.max(f64::MIN_POSITIVE);
    let (sn, bn) = (&s.name, &b.name);
    let keeps = format!(
        "{bn:?} keeps {} from {sn:?} (robust spread {}, {} %)",
        len(d, 4),
        len(g.spread, 2),
        sig(pct, 2)
    );
    let moves = if barely {
        format!("{sn:?} barely moves ({} of travel)", len(s.travel, 2))
    } else {
        format!(
            "{sn:?} moves along a line ({} off it over {} of travel)",
            len(off, 2),
            len(s.travel, 3)
        )
    };
    let hangs_wrong = format!(
        "{bn:?} is {} deg from straight below {sn:?} on average (y {} as read), where a pendulum swings about the vertical below its pivot",
        sig(lean, 2),
        if y_down { "down" } else { "up" }
    );
    let why = if rig {
        format!(
            "{moves} and {keeps} while swinging through {} deg",
            sig(swing, 2)
        )
    } else if fails == ["hang"] {
        format!(
            "{moves} and {keeps} while swinging through {} deg; but {hangs_wrong}",
            sig(swing, 2)
        )
    } else {
        let mut said = Vec::new();
        if r[0] > 1.0 {
            said.push(format!(
                "their distance is not a rod's (median {}, robust spread {}, where a rod's markers stay within {})",
                len(d, 4),
                len(g.spread, 2),
                len(rod_allows, 2)
            ));
        }
        if r[1] > 1.0 {
            said.push(match s.off_line {
                Some(off) => format!(
                    "{sn:?} does not run along a line ({} off its best line, where a rail allows {})",
                    len(off, 2),
                    len(line_allows, 2)
                ),
                None => format!("{sn:?} is seen too seldom to tell its line"),
            });
        }
        if r[2] > 1.0 {
            said.push(format!(
                "{sn:?} runs at {} deg to the file's x axis, where a rail is level",
                sig(tilt, 2)
            ));
        }
        if r[3] > 1.0 {
            said.push(format!(
                "{bn:?} does not swing about {sn:?} as a pendulum does ({} deg, where a swing that holds the distance as well as it does, and not a run along a line, takes at least {} deg)",
                sig(swing, 2),
                sig(swing_needs, 2)
            ));
        }
        if short {
            said.push(format!(
                "they are seen together in {} frames only, where a release worth fitting has at least {MIN_RIG_FRAMES}",
                g.frames
            ));
        }
        if r[4] > 1.0 {
            said.push(hangs_wrong);
        }
        said.join("; ")
    };
    Pair {
        slider: sn.clone(),
        bob: bn.clone(),
        frames: g.frames,
        median: d,
        spread: g.spread,
        rod_allows,
        noise: g.noise,
        slider_off_line: off,
        slider_travel: s.travel,
        swing_deg: swing,
        lean_deg: lean,
        score,
        rig,
        fails,
        why,
    }
}

/// `2nd`, `3rd`, `11th`, ...
fn ordinal(n: usize) -> String {
    let suffix = match (n % 10, n % 100) {
        (_, 11..=13) => "th",
        (1, _) => "st",
        (2, _) => "nd",
        (3, _) => "rd",
        _ => "th",
    };
    format!("{n}{suffix}")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A bob at angles spread evenly over +-30 deg about straight below a slider at rest swings
    /// through the middle 90 % of 60 deg (54 deg) and leans by nothing, whichever way y points;
    /// read upside down it leans by 180 deg.
    #[test]
    fn swing_and_lean_of_an_even_swing_about_the_vertical() {
        let n = 1001;
        let slider = vec![Some([0.2, 0.1]); n];
        for y_down in [false, true] {
            let down = if y_down { 1.0 } else { -1.0 };
            let bob: Vec<Option<[f64; 2]>> = (0..n)
                .map(|k| {
                    let a = (-30.0 + 60.0 * k as f64 / (n - 1) as f64).to_radians();
                    Some([0.2 + 0.3 * a.sin(), 0.1 + down * 0.3 * a.cos()])
                })
                .collect();
            let (swing, lean) = swing_and_lean(&slider, &bob, y_down);
            assert!((swing - 54.0).abs() < 0.1, "{swing}");
            assert!(lean.abs() < 1e-9, "{lean}");
            let (_, upside) = swing_and_lean(&slider, &bob, !y_down);
            assert!((upside - 180.0).abs() < 1e-9, "{upside}");
        }
    }

    /// A series sampled at 100 Hz for 10 s from a position function of time.
    fn series(name: &str, at: impl Fn(f64) -> [f64; 2]) -> Series {
        let times: Vec<f64> = (0..1000).map(|k| k as f64 * 0.01).collect();
        Series {
            name: name.into(),
            points: times.iter().map(|&t| Some(at(t))).collect(),
            times,
        }
    }

    const METRES: Look = Look {
        scale: 1.0,
        y_down: false,
        unit: "m",
    };

    /// A slider running 5 cm either way along the rail under a marker fixed 0.43 m above it
    /// keeps its distance to 0.7 % (the sagitta a^2 / 2h of its run) and sweeps 13 deg as seen
    /// from it: a run along a line, not a swing, which would hold the distance to its noise.
    #[test]
    fn a_run_along_a_line_past_a_fixed_marker_is_no_swing() {
        let fixed = series("fixed", |_| [0.0, 0.43]);
        let runner = series("runner", |t| [0.05 * (0.9 * t).sin(), 0.0]);
        let a = analyse(&[fixed, runner], METRES);
        let p = &a.pairs[0];
        assert_eq!((p.slider.as_str(), p.bob.as_str()), ("fixed", "runner"));
        // The distance runs from 0.43 to sqrt(0.43^2 + 0.05^2): well within a rod's 2 %.
        assert!(p.spread < 0.02 * p.median, "{p:?}");
        assert!(!p.fails.contains(&"rod".to_string()), "{p:?}");
        assert_eq!(p.fails, ["swing"], "{p:?}");
        assert!(!p.rig);
    }

    /// Among 150 fixed markers listed first, the rig's two are still compared (the cap keeps
    /// the markers that move), and found.
    #[test]
    fn the_rig_is_found_among_many_fixed_markers() {
        let mut all: Vec<Series> = (0..150)
            .map(|i| series(&format!("u{i}"), move |_| [0.01 * i as f64, 1.0]))
            .collect();
        let theta = |t: f64| 0.6 * (3.1 * t).sin();
        all.push(series("s", |t| [0.05 * (0.9 * t).sin(), 0.0]));
        all.push(series("b", move |t| {
            [
                0.05 * (0.9 * t).sin() + 0.3 * theta(t).sin(),
                -0.3 * theta(t).cos(),
            ]
        }));
        let a = analyse(&all, METRES);
        assert!(
            a.left_out.iter().any(|l| l.contains("100 markers")),
            "{:?}",
            a.left_out
        );
        let p = &a.pairs[0];
        assert_eq!(
            (p.slider.as_str(), p.bob.as_str(), p.rig),
            ("s", "b", true),
            "{p:?}"
        );
        assert!((p.median - 0.3).abs() < 1e-12);
    }

    #[test]
    fn ordinals_read_as_english() {
        let o: Vec<String> = [1, 2, 3, 4, 11, 12, 13, 21, 22, 101].map(ordinal).into();
        assert_eq!(
            o,
            ["1st", "2nd", "3rd", "4th", "11th", "12th", "13th", "21st", "22nd", "101st"]
        );
    }
}
