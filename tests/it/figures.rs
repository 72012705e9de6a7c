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
    for p in [&svg_path, &png_path] {
        let report = fit_with_plot(
            &[&path("data/example_recording.mcap")],
            &path("configs/rig_example.toml"),
            p,
        );
        // The report's windows are slides (README, [[Windows]]).
        assert!(report.contains("[[Windows]] mu_kinetic per slide"));
    }
    let svg = std::fs::read_to_string(&svg_path).unwrap();
    let text = svg_text(&svg);
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
