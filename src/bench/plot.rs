//! The work-precision diagram: run time against error on log axes, one panel per scene, one
//! line per method and error measure (final state, event times), points in tolerance order.

use super::work_precision::{WorkPrecision, WpPoint};
use crate::report::plot::{Figure, PlotError};
use plotters::coord::Shift;
use plotters::prelude::*;

/// Errors below this are drawn at it (a log axis has no zero).
const ERROR_FLOOR: f64 = 1e-16;

/// The diagram of a [`WorkPrecision`] result.
#[derive(Debug, Clone)]
pub struct WorkPrecisionPlot<'a> {
    /// The measured points.
    pub result: &'a WorkPrecision,
}

/// One line of a panel: (label, colour, error measure).
type Measure = (&'static str, RGBColor, fn(&WpPoint) -> Option<f64>);

const MEASURES: [Measure; 4] = [
    ("dp5 final state", RGBColor(31, 119, 180), |p| p.state_error),
    ("dop853 final state", RGBColor(214, 39, 40), |p| {
        p.state_error
    }),
    ("dp5 event times [s]", RGBColor(140, 190, 230), |p| {
        p.event_time_error_s
    }),
    ("dop853 event times [s]", RGBColor(255, 152, 60), |p| {
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

    /// (error, seconds) points of one line, in the ladder's order.
    fn line(&self, scene: &str, measure: &Measure) -> Vec<(f64, f64)> {
        let method = measure.0.split(' ').next().unwrap_or_default();
        self.result
            .work_precision
            .iter()
            .filter(|p| p.scene == scene && p.method == method)
            .filter_map(|p| Some(((measure.2)(p)?.max(ERROR_FLOOR), p.seconds?)))
            .collect()
    }
}

fn log_range(values: impl Iterator<Item = f64>) -> std::ops::Range<f64> {
    let (lo, hi) = values
        .filter(|v| v.is_finite() && *v > 0.0)
        .fold((f64::INFINITY, 0.0_f64), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    if lo > hi {
        return 1e-16..1.0;
    }
    (lo / 2.0)..(hi * 2.0)
}

impl Figure for WorkPrecisionPlot<'_> {
    fn size(&self) -> (u32, u32) {
        let n = self.scenes().len().max(1) as u32;
        (1200, 420 * n.div_ceil(2))
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), PlotError> {
        let scenes = self.scenes();
        let rows = scenes.len().max(1).div_ceil(2);
        let panels = root.split_evenly((rows, 2));
        for (panel, scene) in panels.iter().zip(&scenes) {
            let lines: Vec<_> = MEASURES.iter().map(|m| (m, self.line(scene, m))).collect();
            let all = || lines.iter().flat_map(|(_, pts)| pts.iter());
            let x = log_range(all().map(|p| p.0));
            let y = log_range(all().map(|p| p.1));
            let mut chart = ChartBuilder::on(panel)
                .caption(
                    format!("{scene}: run time against error"),
                    ("sans-serif", 18),
                )
                .margin(10)
                .x_label_area_size(40)
                .y_label_area_size(60)
                .build_cartesian_2d(x.log_scale(), y.log_scale())?;
            chart
                .configure_mesh()
                .x_desc("error (final state: max-norm; events: s)")
                .y_desc("run time [s]")
                .x_label_formatter(&|v| format!("{v:.0e}"))
                .y_label_formatter(&|v| format!("{v:.0e}"))
                .label_style(("sans-serif", 12))
                .draw()?;
            for (measure, pts) in &lines {
                if pts.is_empty() {
                    continue;
                }
                let color = measure.1;
                chart
                    .draw_series(LineSeries::new(pts.clone(), color.stroke_width(2)))?
                    .label(measure.0)
                    .legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2))
                    });
                chart.draw_series(pts.iter().map(|&p| Circle::new(p, 3, color.filled())))?;
            }
            crate::report::plot::draw_legend(&mut chart, SeriesLabelPosition::UpperRight, 12)?;
        }
        Ok(())
    }
}
