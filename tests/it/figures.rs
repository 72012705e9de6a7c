//! The fit's figures as a reader looks at them: data drawn over the model, four residual
//! series told apart, windows named for what they are, and a long recording drawn in an SVG
//! whose size does not grow with its frames while its extremes stay in it.

use crate::helpers::{svg_text, Normal};
use std::path::Path;
use std::process::Command;

/// Run appell with `args`; it must succeed. Returns its stdout.
fn appell(args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_appell"))
        .args(args)
        .output()
        .expect("runs");
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// `appell fit FIRST [MORE...] --rig RIG --no-profile --plot PLOT`; its report.
fn fit_with_plot(inputs: &[&str], rig: &str, plot: &Path) -> String {
    let mut args = vec!["fit"];
    args.extend_from_slice(inputs);
    args.extend([
        "--rig",
        rig,
        "--no-profile",
        "--plot",
        plot.to_str().unwrap(),
    ]);
    appell(&args)
}

fn path(rel: &str) -> String {
    format!("{}/{rel}", env!("CARGO_MANIFEST_DIR"))
}

/// An SVG element's attribute, as a string.
fn attr<'a>(element: &'a str, name: &str) -> Option<&'a str> {
    let key = format!(" {name}=\"");
    let start = element.find(&key)? + key.len();
    let len = element[start..].find('"')?;
    Some(&element[start..start + len])
}

/// Every element `<tag ...>` of an SVG with its byte offset, in document order.
fn elements<'a>(svg: &'a str, tag: &str) -> Vec<(usize, &'a str)> {
    let open = format!("<{tag} ");
    svg.match_indices(&open)
        .map(|(i, _)| {
            let end = svg[i..].find('>').map_or(svg.len(), |e| i + e + 1);
            (i, &svg[i..end])
        })
        .collect()
}

/// A circle: centre, radius, fill and stroke.
struct Circle<'a> {
    offset: usize,
    cx: f64,
    cy: f64,
    r: f64,
    fill: &'a str,
    stroke: &'a str,
}

fn circles(svg: &str) -> Vec<Circle<'_>> {
    elements(svg, "circle")
        .into_iter()
        .map(|(offset, e)| Circle {
            offset,
            cx: attr(e, "cx").unwrap().parse().unwrap(),
            cy: attr(e, "cy").unwrap().parse().unwrap(),
            r: attr(e, "r").unwrap().parse().unwrap(),
            fill: attr(e, "fill").unwrap_or("none"),
            stroke: attr(e, "stroke").unwrap_or("none"),
        })
        .collect()
}

/// The most common radius among filled circles of `colour`: the residual dots (the legend's
/// swatch of the same colour is one circle of another size).
fn dots<'a>(all: &'a [Circle<'a>], colour: &str) -> Vec<&'a Circle<'a>> {
    let filled: Vec<&Circle> = all.iter().filter(|c| c.fill == colour).collect();
    let mut radii: Vec<f64> = filled.iter().map(|c| c.r).collect();
    radii.sort_by(f64::total_cmp);
    let common = radii
        .chunk_by(|a, b| a == b)
        .max_by_key(|run| run.len())
        .map_or(0.0, |run| run[0]);
    filled.into_iter().filter(|c| c.r == common).collect()
}

/// The fill of the legend's swatch beside the text `name` (its last text of that content: the
/// side legend is drawn last).
fn legend_colour<'a>(svg: &str, all: &[Circle<'a>], name: &str) -> &'a str {
    let (_, label) = elements(svg, "text")
        .into_iter()
        .rev()
        .find(|(i, _)| {
            let body = svg[*i..].split('>').nth(1).unwrap();
            body.trim_end_matches("</text").trim() == name
        })
        .unwrap_or_else(|| panic!("{name} is a text of its own"));
    let x: f64 = attr(label, "x").unwrap().parse().unwrap();
    let y: f64 = attr(label, "y").unwrap().parse().unwrap();
    all.iter()
        .find(|c| c.fill != "none" && (c.cy - y).abs() < 14.0 && c.cx < x && c.cx > x - 30.0)
        .unwrap_or_else(|| panic!("a swatch beside {name}"))
        .fill
}

/// The fit of the shipped example draws its data after (over) the model, tells the four
/// residual series apart by four colours the legend names, names its windows after the
/// slides they are, and writes the same figure as a PNG.
#[test]
fn fit_figure_draws_data_over_the_model_and_tells_the_residuals_apart() {
    let tmp = tempfile::tempdir().unwrap();
    let svg_path = tmp.path().join("fit.svg");
    let png_path = tmp.path().join("fit.png");
    let mut chosen = String::new();
    for p in [&svg_path, &png_path] {
        let report = fit_with_plot(
            &[&path("data/example_recording.mcap")],
            &path("configs/rig_example.toml"),
            p,
        );
        // The report's windows are slides (docs/glossary.md, [[Windows]]).
        assert!(report.contains("[[Windows]] mu_kinetic per slide"));
        chosen = chosen_model(&report);
    }
    let svg = std::fs::read_to_string(&svg_path).unwrap();
    let text = svg_text(&svg);
    // One name per model: the figure's is the report's.
    assert!(
        text.replace(" + ", "+")
            .contains(&format!("model: {chosen}")),
        "{chosen}: {text}"
    );
    let all = circles(&svg);

    // Four residual series, four distinct fill colours, each named in the legend with a
    // swatch of its colour.
    let fills: std::collections::BTreeSet<&str> = all
        .iter()
        .filter(|c| c.fill != "none")
        .map(|c| c.fill)
        .collect();
    let series: Vec<(&str, &str)> = ["slider x", "slider y", "bob x", "bob y"]
        .into_iter()
        .map(|name| (name, legend_colour(&svg, &all, name)))
        .collect();
    let colours: std::collections::BTreeSet<&str> = series.iter().map(|s| s.1).collect();
    assert_eq!(colours.len(), 4, "four distinct colours: {series:?}");
    for (name, colour) in &series {
        assert!(fills.contains(colour), "{name}");
        assert!(
            dots(&all, colour).len() > 100,
            "{name}'s residuals are drawn in its colour {colour}"
        );
    }

    // The model's lines (black polylines of many points: slider x's, then the bob's x and y)
    // come before the data's open circles of their panel, so the data are drawn over them;
    // each panel's key swatch (one ring a colour) stands before.
    let models: Vec<usize> = elements(&svg, "polyline")
        .into_iter()
        .filter(|(_, e)| attr(e, "stroke") == Some("#000000"))
        .filter(|(_, e)| attr(e, "points").map_or(0, |p| p.split(' ').count()) > 100)
        .map(|(i, _)| i)
        .collect();
    assert_eq!(models.len(), 3, "one model line a coordinate drawn");
    for (name, line) in [
        ("slider x", models[0]),
        ("bob x", models[2]),
        ("bob y", models[2]),
    ] {
        let colour = series.iter().find(|s| s.0 == name).unwrap().1;
        let rings: Vec<&Circle> = all
            .iter()
            .filter(|c| c.fill == "none" && c.stroke == colour)
            .collect();
        assert!(rings.len() > 100, "{name}: the data are open circles");
        assert!(
            rings.iter().filter(|c| c.offset < line).count() <= 1,
            "{name}: the data come after the model line"
        );
    }
    // The windows are slides, and the panel says so.
    assert!(text.contains("mu_kinetic per slide"), "{text}");
    assert!(!text.contains("third"), "{text}");

    // The PNG: its signature and the figure's size in the header.
    let png = std::fs::read(&png_path).unwrap();
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    let width = u32::from_be_bytes(png[16..20].try_into().unwrap());
    let height = u32::from_be_bytes(png[20..24].try_into().unwrap());
    assert_eq!((width, height), (1300, 1150));
}

/// A 30 s recording at 1 kHz: the figure stays below 1 MB, says that it thinned what it
/// drew, and still draws the largest residual where it is: one slider position displaced by
/// five noise deviations, every other one's noise bounded by three.
#[test]
fn long_recording_figure_is_small_and_keeps_the_largest_residual() {
    let tmp = tempfile::tempdir().unwrap();
    let clean = tmp.path().join("clean.csv");
    appell(&[
        "synth",
        &path("configs/markers_example.toml"),
        clean.to_str().unwrap(),
        "--duration",
        "30",
        "--fps",
        "1000",
    ]);
    // The noise added here, bounded at 3 sigma, and the one displaced position.
    let sigma = 2e-4;
    let (spike_frame, spike) = (17_300, 5.0 * sigma);
    let mut normal = Normal::new(38);
    let text = std::fs::read_to_string(&clean).unwrap();
    let mut csv = String::new();
    let mut frames = 0;
    for (i, line) in text.lines().enumerate() {
        if i == 0 {
            csv.push_str(line);
            csv.push('\n');
            continue;
        }
        let mut cells: Vec<f64> = line.split(',').map(|c| c.parse().unwrap()).collect();
        for v in &mut cells[1..] {
            *v += sigma * normal.sample().clamp(-3.0, 3.0);
        }
        if i - 1 == spike_frame {
            let truth: Vec<f64> = line.split(',').map(|c| c.parse().unwrap()).collect();
            cells[1] = truth[1] + spike;
        }
        let row: Vec<String> = cells.iter().map(|v| v.to_string()).collect();
        csv.push_str(&row.join(","));
        csv.push('\n');
        frames += 1;
    }
    assert_eq!(frames, 30_001);
    let t_spike = spike_frame as f64 * 1e-3;
    let recording = tmp.path().join("long.csv");
    std::fs::write(&recording, csv).unwrap();
    let svg_path = tmp.path().join("long.svg");
    let report = fit_with_plot(
        &[recording.to_str().unwrap()],
        &path("configs/rig_example.toml"),
        &svg_path,
    );
    assert!(
        report.contains("(0 slider and 0 bob positions left out"),
        "the displaced position stays in the fit"
    );
    let size = std::fs::metadata(&svg_path).unwrap().len();
    assert!(size < 1_000_000, "{size} bytes");
    let svg = std::fs::read_to_string(&svg_path).unwrap();
    assert!(svg_text(&svg).contains("thinned to draw"));

    // The slider x residual dots: the displaced position, observed 5 sigma too far, has the
    // most negative residual (fitted - observed), the lowest dot; it stands at its time on
    // the axis the dots span (the first and last frames are drawn).
    let all = circles(&svg);
    let slider_x = legend_colour(&svg, &all, "slider x");
    let residuals = dots(&all, slider_x);
    // Fewer than every frame: thinned.
    assert!(residuals.len() < 10_000, "{}", residuals.len());
    let x0 = residuals.iter().map(|c| c.cx).fold(f64::INFINITY, f64::min);
    let x1 = residuals
        .iter()
        .map(|c| c.cx)
        .fold(f64::NEG_INFINITY, f64::max);
    let lowest = residuals
        .iter()
        .max_by(|a, b| a.cy.total_cmp(&b.cy))
        .unwrap();
    let want = x0 + (x1 - x0) * t_spike / 30.0;
    assert!(
        (lowest.cx - want).abs() <= 3.0,
        "the largest residual at x = {} px, its time at {want:.1} px",
        lowest.cx
    );
    // The data panel keeps it too: an open circle of the slider's colour at that time.
    assert!(
        all.iter().any(|c| c.fill == "none"
            && c.stroke == slider_x
            && (c.cx - want).abs() <= 3.0
            && c.cy < lowest.cy),
        "the displaced position's data point is drawn"
    );
}

/// The joint fit's figure says what its marks are: each release's own mu and the joint
/// interval and value.
#[test]
fn joint_figure_has_a_key() {
    let tmp = tempfile::tempdir().unwrap();
    let svg_path = tmp.path().join("joint.svg");
    fit_with_plot(
        &[&path("data/campaign"), "--joint"],
        &path("data/campaign/rig_measured.toml"),
        &svg_path,
    );
    let text = svg_text(&std::fs::read_to_string(&svg_path).unwrap());
    for want in [
        "own mu, 95 % bar",
        "joint 95 % interval",
        "joint value",
        "release_01.csv",
    ] {
        assert!(text.contains(want), "{want}: {text}");
    }
}

/// The chosen model's name in a fit report's `[[Models compared]]` (the row marked `*`).
fn chosen_model(report: &str) -> String {
    report
        .lines()
        .find_map(|l| l.strip_prefix("  * "))
        .and_then(|l| l.split_whitespace().next())
        .unwrap_or_else(|| panic!("a chosen model: {report}"))
        .to_owned()
}

/// Every text element's content, in document order.
fn texts(svg: &str) -> Vec<String> {
    elements(svg, "text")
        .into_iter()
        .map(|(i, _)| {
            let body = svg[i..].split('>').nth(1).unwrap();
            body.trim_end_matches("</text").trim().to_owned()
        })
        .collect()
}

/// A two-point polyline: its offset, stroke, width and end points (pixels).
struct Segment<'a> {
    offset: usize,
    stroke: &'a str,
    width: f64,
    a: (f64, f64),
    b: (f64, f64),
}

fn segments(svg: &str) -> Vec<Segment<'_>> {
    elements(svg, "polyline")
        .into_iter()
        .filter_map(|(offset, e)| {
            let pts: Vec<(f64, f64)> = attr(e, "points")?
                .split_whitespace()
                .map(|p| {
                    let (x, y) = p.split_once(',').unwrap();
                    (x.parse().unwrap(), y.parse().unwrap())
                })
                .collect();
            (pts.len() == 2).then(|| Segment {
                offset,
                stroke: attr(e, "stroke").unwrap_or("none"),
                width: attr(e, "stroke-width").map_or(1.0, |w| w.parse().unwrap()),
                a: pts[0],
                b: pts[1],
            })
        })
        .collect()
}

/// `appell fit REC --rig RIG --plot FIT --friction-plot FRICTION` (the whole fit, profiles
/// included): its report and the two SVGs.
fn fit_both_figures(rec: &str, rig: &str, dir: &Path) -> (String, String, String) {
    fit_both_figures_with(rec, rig, &[], dir)
}

/// [`fit_both_figures`] with more options.
fn fit_both_figures_with(
    rec: &str,
    rig: &str,
    more: &[&str],
    dir: &Path,
) -> (String, String, String) {
    let (fit, friction) = (dir.join("fit.svg"), dir.join("friction.svg"));
    let (rec, rig) = (path(rec), path(rig));
    let mut args = vec![
        "fit",
        &rec,
        "--rig",
        &rig,
        "--plot",
        fit.to_str().unwrap(),
        "--friction-plot",
        friction.to_str().unwrap(),
    ];
    args.extend_from_slice(more);
    let report = appell(&args);
    (
        report,
        std::fs::read_to_string(fit).unwrap(),
        std::fs::read_to_string(friction).unwrap(),
    )
}

/// Colours of the friction figure: a slide toward +x and -x, and the compared laws' dashes.
const PLUS: &str = "#D75F00";
const MINUS: &str = "#005AC8";
const COMPARED: &str = "#505050";

/// The friction figure draws what its legend lists, bars and speed ranges that can be seen,
/// and a side panel that keeps each value with its error: on a Coulomb rail (compared laws
/// within the data's span) and a direction-dependent one (most compared laws far off, each
/// slide's bar shorter than its dot).
#[test]
fn friction_figure_draws_what_it_lists() {
    let tmp = tempfile::tempdir().unwrap();
    let equal = "tests/data/friction/rigs/equal.toml";
    for (rec, more) in [
        ("tests/data/friction/coulomb_equal_s1.csv", &[][..]),
        ("tests/data/friction/direction_equal_s1.csv", &[]),
        // The plain model: no other law is fitted, none is drawn or listed.
        ("tests/data/friction/coulomb_equal_s1.csv", &["--plain"]),
    ] {
        let (report, _, svg) = fit_both_figures_with(rec, equal, more, tmp.path());
        let text = texts(&svg);
        let all = text.join(" ");
        let segs = segments(&svg);
        // Compared laws: listed in the legend exactly when a dashed line is drawn, and every
        // law the report fitted is in the side panel, dashed or said off the axis.
        let dashes = segs.iter().filter(|s| s.stroke == COMPARED).count();
        assert_eq!(
            all.contains("compared laws (their models"),
            dashes > 0,
            "{rec}: {dashes} dashes; {all}"
        );
        let fitted: Vec<&str> = report
            .lines()
            .filter(|l| l.contains("its best model's BIC"))
            .map(|l| l.split_whitespace().next().unwrap())
            .collect();
        assert_eq!(fitted.is_empty(), !more.is_empty(), "{rec}: {report}");
        for law in &fitted {
            let said = format!("{law}: mu_kinetic ");
            let at = all
                .find(&said)
                .unwrap_or_else(|| panic!("{rec}: {law}: {all}"));
            let note = &all[at..];
            assert!(
                note.contains("(dashed)") || note.contains("the axis)"),
                "{rec}: {law}: {note}"
            );
            if all[at..].split(',').next().unwrap().contains("(dashed)") {
                assert!(
                    text.iter().any(|t| t == law),
                    "{rec}: {law} labels its line"
                );
            }
        }
        // A value and its error stay on one line of the side panel.
        for t in &text {
            assert!(!t.ends_with("+-") && !t.starts_with("+-"), "{rec}: {t:?}");
        }
        // The 95 % bars: vertical, 3 px wide, each with a cap at both ends.
        let bars: Vec<&Segment> = segs
            .iter()
            .filter(|s| (s.stroke == PLUS || s.stroke == MINUS) && s.a.0 == s.b.0 && s.width >= 3.0)
            .collect();
        assert!(bars.len() >= 2, "{rec}: {} bars", bars.len());
        for bar in &bars {
            for y in [bar.a.1, bar.b.1] {
                assert!(
                    segs.iter().any(|c| c.stroke == bar.stroke
                        && c.a.1 == y
                        && c.b.1 == y
                        && (c.a.0 - bar.a.0).abs() >= 4.0
                        && (c.b.0 - bar.a.0).abs() >= 4.0
                        && c.a.0.min(c.b.0) < bar.a.0
                        && c.a.0.max(c.b.0) > bar.a.0),
                    "{rec}: a cap at {y} on the bar at {}",
                    bar.a.0
                );
            }
        }
        // Bars shorter than their dot (10 px) are said in the side panel, and only then.
        let short = bars.iter().filter(|b| (b.a.1 - b.b.1).abs() < 10.0).count();
        assert_eq!(
            all.contains("bars are shorter than their dot"),
            short > 0,
            "{rec}: {short} short bars; {all}"
        );
        // The chosen law is a wide pale band drawn first; each slide's speed range (a
        // horizontal line of the slide's colour) comes after it, in a colour of its own.
        let band = elements(&svg, "polyline")
            .into_iter()
            .find(|(_, e)| attr(e, "stroke-width") == Some("6"))
            .map(|(i, e)| (i, attr(e, "stroke").unwrap()));
        let (band_at, band_colour) = band.unwrap_or_else(|| panic!("{rec}: the law's band"));
        let ranges: Vec<&Segment> = segs
            .iter()
            .filter(|s| (s.stroke == PLUS || s.stroke == MINUS) && s.a.1 == s.b.1 && s.width == 2.0)
            .filter(|s| (s.b.0 - s.a.0).abs() > 10.0)
            .collect();
        assert!(ranges.len() >= bars.len(), "{rec}: a speed range a slide");
        for r in &ranges {
            assert!(r.offset > band_at, "{rec}: the range is drawn over the law");
            assert_ne!(r.stroke, band_colour, "{rec}");
        }
        if rec.contains("direction") {
            assert!(all.contains("coulomb: mu_kinetic"), "{all}");
            assert!(all.contains("(above the axis)"), "{all}");
        }
    }
}

/// Under the direction law the fit figure shows the law's own coefficients: each window's
/// value in its direction on that direction's whole-fit line (not the mean of the two), both
/// coefficients in the side panel, mu_static at its bound as a one-sided bound, the release
/// angle with its convention, and the model by the report's name.
#[test]
fn direction_law_fit_figure_shows_each_direction() {
    let tmp = tempfile::tempdir().unwrap();
    let (report, svg, _) = fit_both_figures(
        "tests/data/friction/direction_equal_s1.csv",
        "tests/data/friction/rigs/equal.toml",
        tmp.path(),
    );
    assert!(report.contains("[[Friction law]] direction"), "{report}");
    let all = texts(&svg).join(" ");
    // The whole fit's lines across the windows' panel (the legend's swatch is short).
    const WHOLE: &str = "#CC79A7";
    let lines: Vec<f64> = segments(&svg)
        .iter()
        .filter(|s| s.stroke == WHOLE && s.a.1 == s.b.1 && (s.b.0 - s.a.0).abs() > 500.0)
        .map(|s| s.a.1)
        .collect();
    assert_eq!(lines.len(), 2, "one line a direction: {lines:?}");
    assert!((lines[0] - lines[1]).abs() > 50.0, "{lines:?}");
    for want in [
        "toward +x 0.",
        "toward -x 0.",
        "toward +x: 0.",
        "toward -x: 0.",
    ] {
        assert!(all.contains(want), "{want}: {all}");
    }
    // Each window's dot on one of the two lines, both lines with windows.
    let all_circles = circles(&svg);
    let windows: Vec<&Circle> = all_circles
        .iter()
        .filter(|c| c.fill == "#000000" && c.r == 4.0)
        .collect();
    assert!(windows.len() >= 2, "{}", windows.len());
    let mut on = [0; 2];
    for w in &windows {
        let k = if (w.cy - lines[0]).abs() < (w.cy - lines[1]).abs() {
            0
        } else {
            1
        };
        assert!((w.cy - lines[k]).abs() <= 3.0, "a window at {} px", w.cy);
        on[k] += 1;
    }
    assert!(on[0] > 0 && on[1] > 0, "{on:?}");
    // mu_static tied at its bound: a one-sided bound, not a two-sided interval.
    if report.contains("mu_static            at its bound mu_kinetic") {
        assert!(all.contains("one-sided 95 %"), "{all}");
        assert!(!all.contains("mu_static = "), "{all}");
    }
    assert!(all.contains("theta = pi/2 hangs"), "{all}");
    assert!(
        all.replace(" + ", "+")
            .contains(&format!("model: {}", chosen_model(&report))),
        "{all}"
    );
}
