//! The work-precision diagram: run time against error on log axes, one row per scene and one
//! column per error measure (final state; event times in seconds), one line per method, points
//! in tolerance order with the loosest and tightest rtol written beside them.

use super::work_precision::{WorkPrecision, WpPoint};
use crate::report::plot::{draw_side_legend, Figure, PlotError, Swatch};
use plotters::coord::Shift;
use plotters::prelude::*;

/// Errors below this are drawn at it (a log axis has no zero).
const ERROR_FLOOR: f64 = 1e-16;

/// Width of the legend column (px).
const LEGEND_WIDTH: u32 = 300;

/// The diagram of a [`WorkPrecision`] result.
#[derive(Debug, Clone)]
pub struct WorkPrecisionPlot<'a> {
    /// The measured points.
    pub result: &'a WorkPrecision,
}

/// The methods, each with its colour in every panel.
const METHODS: [(&str, RGBColor); 2] = [
    ("dp5", RGBColor(31, 119, 180)),
    ("dop853", RGBColor(214, 39, 40)),
];

/// One column of panels: (caption, x axis label, error measure).
type Measure = (&'static str, &'static str, fn(&WpPoint) -> Option<f64>);

const MEASURES: [Measure; 2] = [
    (
        "final state",
        "final-state error (max-norm over x [m], theta [rad], x', theta')",
        |p| p.state_error,
    ),
    ("event times", "largest event-time error [s]", |p| {
        p.event_time_error_s
    }),
];

impl WorkPrecisionPlot<'_> {
    fn scenes(&self) -> Vec<&str> {
        let mut names: Vec<&str> = Vec::new();
        for p in &self.result.work_precision {
            if !names.contains(&p.scene.as_str()) {
                names.push(&p.scene);
            }
        }
        names
    }

    /// (error, microseconds, rtol) points of one method and measure, in the ladder's order.
    fn line(&self, scene: &str, method: &str, measure: &Measure) -> Vec<(f64, f64, f64)> {
        self.result
            .work_precision
            .iter()
            .filter(|p| p.scene == scene && p.method == method)
            .filter_map(|p| Some(((measure.2)(p)?.max(ERROR_FLOOR), p.seconds? * 1e6, p.rtol)))
            .collect()
    }

    /// The legend column's text: how to read a point, and each scene's reference floor.
    fn notes(&self) -> Vec<String> {
        let mut out = vec![
            "each point: one tolerance (atol = rtol / 100), median run time of a plain run; the loosest and tightest rtol are written beside their points".to_owned(),
            format!("errors below {ERROR_FLOOR:.0e} are drawn at {ERROR_FLOOR:.0e}"),
        ];
        for r in &self.result.references {
            out.push(match r.event_time_disagreement_s {
                Some(d) => format!(
                    "{}: references agree to {d:.1e} s in event times, {:.1e} in the final state",
                    r.scene, r.state_disagreement
                ),
                None => format!(
                    "{}: no events; references agree to {:.1e} in the final state",
                    r.scene, r.state_disagreement
                ),
            });
        }
        out
    }
}

/// The smallest decade-aligned range holding the positive finite `values`.
fn decade_range(values: impl Iterator<Item = f64>) -> std::ops::Range<f64> {
    let (lo, hi) = values
        .filter(|v| v.is_finite() && *v > 0.0)
        .fold((f64::INFINITY, 0.0_f64), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    if lo > hi {
        return 1e-16..1.0;
    }
    let (a, mut b) = (lo.log10().floor(), hi.log10().ceil());
    if b <= a {
        b = a + 1.0;
    }
    10f64.powf(a)..10f64.powf(b)
}

/// A tick label only at powers of ten (`1e-4`), empty elsewhere, so labels never pile up.
fn decade_label(v: &f64) -> String {
    let e = v.log10();
    if (e - e.round()).abs() < 1e-6 {
        format!("1e{}", e.round() as i32)
    } else {
        String::new()
    }
}

impl Figure for WorkPrecisionPlot<'_> {
    fn size(&self) -> (u32, u32) {
        let n = self.scenes().len().max(1) as u32;
        (1300, 40 + 360 * n)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), PlotError> {
        let scenes = self.scenes();
        let (width, _) = root.dim_in_pixel();
        let root = root.titled(
            "Work-precision: run time against error, DP5 and DOP853",
            ("sans-serif", 22),
        )?;
        let (plots, side) = root.split_horizontally(width.saturating_sub(LEGEND_WIDTH));
        let panels = plots.split_evenly((scenes.len().max(1), 2));
        for (row, scene) in scenes.iter().enumerate() {
            for (col, measure) in MEASURES.iter().enumerate() {
                let panel = &panels[2 * row + col];
                let lines: Vec<_> = METHODS
                    .iter()
                    .map(|&(m, color)| (color, self.line(scene, m, measure)))
                    .collect();
                if lines.iter().all(|(_, pts)| pts.is_empty()) {
                    // Nothing to draw: say why instead of drawing empty log axes.
                    let has_events = self
                        .result
                        .work_precision
                        .iter()
                        .any(|p| p.scene == *scene && p.reference_events > 0);
                    let why = if has_events {
                        "no comparable points: event sequences differ from the reference"
                    } else {
                        "no events in this scene: no event-time error"
                    };
                    let (w, h) = panel.dim_in_pixel();
                    let style = ("sans-serif", 15).into_font().color(&BLACK);
                    panel.draw(&Text::new(
                        format!("{scene}: {}", measure.0),
                        (w as i32 / 2 - 80, 8),
                        ("sans-serif", 17).into_font().color(&BLACK),
                    ))?;
                    panel.draw(&Text::new(why, (40, h as i32 / 2), style))?;
                    continue;
                }
                let all = || lines.iter().flat_map(|(_, pts)| pts.iter());
                let x = decade_range(all().map(|p| p.0));
                let y = decade_range(all().map(|p| p.1));
                let mut chart = ChartBuilder::on(panel)
                    .caption(format!("{scene}: {}", measure.0), ("sans-serif", 17))
                    .margin(10)
                    .x_label_area_size(42)
                    .y_label_area_size(62)
                    .build_cartesian_2d(x.log_scale(), y.log_scale())?;
                chart
                    .configure_mesh()
                    .x_desc(measure.1)
                    .y_desc("run time [µs]")
                    .x_labels(40)
                    .y_labels(20)
                    .x_label_formatter(&decade_label)
                    .y_label_formatter(&decade_label)
                    .light_line_style(TRANSPARENT)
                    .bold_line_style(BLACK.mix(0.10))
                    .label_style(("sans-serif", 13))
                    .axis_desc_style(("sans-serif", 13))
                    .draw()?;
                for (color, pts) in &lines {
                    let xy: Vec<(f64, f64)> = pts.iter().map(|p| (p.0, p.1)).collect();
                    chart.draw_series(LineSeries::new(xy.clone(), color.stroke_width(2)))?;
                    chart.draw_series(xy.iter().map(|&p| Circle::new(p, 3, color.filled())))?;
                    let ends = [pts.first(), pts.last()];
                    for (k, p) in ends.into_iter().flatten().enumerate() {
                        if k == 1 && pts.len() < 2 {
                            break;
                        }
                        chart.draw_series(std::iter::once(
                            EmptyElement::at((p.0, p.1))
                                + Text::new(
                                    format!("{:.0e}", p.2),
                                    (6, -16),
                                    ("sans-serif", 12).into_font().color(color),
                                ),
                        ))?;
                    }
                }
            }
        }
        let entries: Vec<(Swatch, String)> = METHODS
            .iter()
            .map(|&(m, c)| (Swatch::Line(c, 2), format!("{m} (rtol ladder)")))
            .collect();
        draw_side_legend(&side, "Legend", &entries, &self.notes(), 34)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bench::work_precision::{reference_scenes, run, WpConfig};
    use crate::sim::Method;

    /// Issue 13: one axis per error measure (never a state error and seconds on one axis),
    /// tick labels only at decades, the legend beside the panels.
    #[test]
    fn panels_separate_the_measures_and_label_only_decades() {
        let config = WpConfig {
            scenes: reference_scenes()
                .into_iter()
                .filter(|s| s.name == "paper")
                .collect(),
            rtols: vec![1e-5, 1e-7, 1e-9],
            methods: Method::ALL.to_vec(),
            batches: 1,
            seconds_per_point: 0.0,
        };
        let wp = run(&config, |_| {});
        // Removed with everything in it at the end of the test.
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().to_path_buf();
        let path = dir.join("wp.svg");
        crate::report::plot::render(&path, &WorkPrecisionPlot { result: &wp }).unwrap();
        let svg = std::fs::read_to_string(&path).unwrap();
        assert!(svg.contains("paper: final state") && svg.contains("paper: event times"));
        assert!(svg.contains("largest event-time error [s]"));
        assert!(svg.contains("run time [µs]"));
        assert!(svg.contains("Legend"));
        for label in ["2e-", "5e-", "3e-"] {
            assert!(
                !svg.contains(&format!(">{label}")),
                "non-decade tick {label}"
            );
        }
        assert_eq!(decade_label(&1e-4), "1e-4");
        assert_eq!(decade_label(&3e-4), "");
        let r = decade_range([4e-5, 0.3].into_iter());
        assert!((r.start / 1e-5 - 1.0).abs() < 1e-12 && (r.end - 1.0).abs() < 1e-12);
    }
}
