//! The figure of `appell fit`: slider and bob positions, data and fit, their residuals against
//! the measured noise, the fitted modes as bands, and mu_kinetic per window.

use crate::fit::{Estimate, FitReport, Observations, StaticResult};
use crate::model::{observed_markers, Mode};
use crate::report::plot::{data_range, draw_side_legend, Figure, PlotError, Swatch};
use crate::sim::{simulate, Options, Request};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::borrow::Cow;

/// Most frames the fit's figure draws.
const PLOT_FRAMES: usize = 20_000;

/// The fit's figure: slider x and bob position, data and fit, residuals, mode bands.
pub struct FitFigure<'a> {
    /// The recording.
    pub obs: &'a Observations,
    /// The fit.
    pub report: &'a FitReport,
}

/// The four observed coordinates in drawing order, each with the one colour it has in every
/// panel and the legend: slider x, slider y, bob x, bob y.
const COORDS: [(&str, RGBColor); 4] = [
    ("slider x", RGBColor(0, 90, 200)),
    ("slider y", RGBColor(130, 60, 180)),
    ("bob x", RGBColor(215, 95, 0)),
    ("bob y", RGBColor(0, 140, 60)),
];

/// (t, value) points of one series.
type Points = Vec<(f64, f64)>;

/// Pale fills of the fitted modes behind the time panels.
fn mode_color(m: Mode) -> RGBColor {
    match m {
        Mode::Stick => RGBColor(228, 228, 228),
        Mode::Slide(crate::model::Direction::Positive) => RGBColor(255, 236, 200),
        Mode::Slide(crate::model::Direction::Negative) => RGBColor(214, 232, 250),
    }
}

/// Tick labels with as many decimals as the axis span needs, and never "-0".
fn tick_label(v: f64, span: f64) -> String {
    let decimals = (1.0 - (span / 5.0).log10().floor()).clamp(0.0, 6.0) as usize;
    let text = format!("{v:.decimals$}");
    if text
        .trim_start_matches('-')
        .chars()
        .all(|c| c == '0' || c == '.')
    {
        text.trim_start_matches('-').to_owned()
    } else {
        text
    }
}

impl FitFigure<'_> {
    /// The legend's key numbers: mu with its error and interval, the model, the fit's quality
    /// and the windows.
    fn notes(&self) -> Vec<String> {
        let rep = self.report;
        let mut notes = Vec::new();
        match &rep.mu_kinetic {
            Some(mu) => notes.push(format!(
                "mu_kinetic = {:.6} +- {:.2e}, 95% [{:.6}, {:.6}] ({})",
                mu.value, mu.stderr, mu.ci95[0], mu.ci95[1], mu.interval
            )),
            None => notes.push("mu_kinetic: not identifiable (no slide)".into()),
        }
        match &rep.mu_static {
            StaticResult::Estimated(e) => notes.push(format!(
                "mu_static = {:.6}, 95% [{:.6}, {:.6}]",
                e.value, e.ci95[0], e.ci95[1]
            )),
            StaticResult::LowerBound(b) => notes.push(format!("mu_static >= {b:.4}")),
            StaticResult::NotIdentifiable => {}
        }
        let model = if rep.nuisances.is_empty() {
            "plain".to_owned()
        } else {
            rep.nuisances
                .iter()
                .map(|n| n.name())
                .collect::<Vec<_>>()
                .join(" + ")
        };
        notes.push(format!("model: {model}"));
        let a = &rep.adequacy;
        notes.push(format!(
            "chi2 = {:.1} for {:.0} dof (reduced {:.3}, {})",
            a.chi2,
            a.dof,
            a.reduced_chi2,
            crate::report::p_is(a.p_value)
        ));
        notes.push(format!(
            "noise (measured): slider {:.3} mm, bob {:.3} mm",
            rep.noise_m[0] * 1e3,
            rep.noise_m[1] * 1e3
        ));
        if a.limited_by_model.is_some() {
            notes.push("limited by the model, not by the noise (see the report)".into());
        }
        notes
    }
}

/// A time panel: its title, the coordinates it draws (indices into [`COORDS`]) and whether it
/// shows their residuals rather than data and fit.
type Panel = (&'static str, &'static [usize], bool);

/// The four time panels, top to bottom.
const PANELS: [Panel; 4] = [
    ("slider x [mm] (data and fit)", &[0], false),
    ("bob x and y [mm] (data and fit)", &[2, 3], false),
    (
        "slider residual [mm] (fitted - observed; band +-2 noise)",
        &[0, 1],
        true,
    ),
    (
        "bob residual [mm] (fitted - observed; band +-2 noise)",
        &[2, 3],
        true,
    ),
];

/// What the time panels draw: the frames drawn (every k-th of a long recording), their times
/// from zero, and the fitted model's markers and mode at each.
struct Traces<'a> {
    /// The frames drawn.
    obs: Cow<'a, Observations>,
    /// Their times from the first (s).
    times: Vec<f64>,
    /// The last time drawn (s), above zero.
    t_end: f64,
    /// At each frame: its time, the fitted markers (slider x, y, bob x, y; m) and the mode.
    pred: Vec<(f64, [f64; 4], Mode)>,
}

impl Traces<'_> {
    /// Observed coordinate k (0..4 as in COORDS) at frame i, in mm.
    fn observed(&self, k: usize, i: usize) -> Option<f64> {
        let m = if k < 2 {
            self.obs.slider[i]
        } else {
            self.obs.bob[i]
        };
        m.map(|p| p[k % 2] * 1e3)
    }

    /// The data of coordinate `k` (mm) at the frames that have it.
    fn data(&self, k: usize) -> Points {
        (0..self.times.len())
            .filter_map(|i| self.observed(k, i).map(|v| (self.times[i], v)))
            .collect()
    }

    /// The fitted coordinate `k` (mm) at every frame.
    fn fitted(&self, k: usize) -> Points {
        self.pred.iter().map(|p| (p.0, p.1[k] * 1e3)).collect()
    }

    /// Residuals of coordinate `k` (mm) as the fit and the README define them: fitted minus
    /// observed.
    fn resid(&self, k: usize) -> Points {
        (0..self.times.len())
            .filter_map(|i| {
                Some((
                    self.times[i],
                    self.pred.get(i)?.1[k] * 1e3 - self.observed(k, i)?,
                ))
            })
            .collect()
    }

    /// The fitted modes as bands from `bottom` to `top`, one per stretch of one mode.
    fn bands(&self, top: f64, bottom: f64) -> Vec<Rectangle<(f64, f64)>> {
        let pred = &self.pred;
        let mut out = Vec::new();
        let mut start = 0;
        for i in 1..=pred.len() {
            if i == pred.len() || pred[i].2 != pred[start].2 {
                let t1 = if i == pred.len() {
                    self.t_end
                } else {
                    pred[i].0
                };
                out.push(Rectangle::new(
                    [(pred[start].0, bottom), (t1, top)],
                    mode_color(pred[start].2).filled(),
                ));
                start = i;
            }
        }
        out
    }
}

impl<'a> FitFigure<'a> {
    /// The frames to draw and the fitted model at them. A figure cannot show more frames than
    /// it has pixels: a long recording is drawn from every k-th frame (at most PLOT_FRAMES),
    /// the fit's numbers still from all.
    fn traces(&self) -> Result<Traces<'a>, PlotError> {
        let rep = self.report;
        let stride = self.obs.times.len().div_ceil(PLOT_FRAMES).max(1);
        let obs = if stride > 1 {
            Cow::Owned(Observations {
                times: self.obs.times.iter().step_by(stride).copied().collect(),
                slider: self.obs.slider.iter().step_by(stride).copied().collect(),
                bob: self.obs.bob.iter().step_by(stride).copied().collect(),
            })
        } else {
            Cow::Borrowed(self.obs)
        };
        let t0 = obs.times[0];
        let times: Vec<f64> = obs.times.iter().map(|t| t - t0).collect();
        let t_end = times.last().copied().unwrap_or(1.0).max(1e-9);
        let sol = simulate(
            &rep.rig,
            &rep.initial,
            t_end,
            &Options {
                rtol: 1e-9,
                atol: 1e-11,
                ..Options::default()
            },
            &Request {
                sample_times: times.clone(),
                friction_work: false,
                positions_only: false,
            },
        )
        .map_err(|e| PlotError::Draw(e.to_string()))?;
        let pred: Vec<(f64, [f64; 4], Mode)> = sol
            .samples
            .iter()
            .map(|s| {
                (
                    s.t,
                    observed_markers(&rep.rig, &rep.camera, s.mode, &s.state),
                    s.mode,
                )
            })
            .collect();
        Ok(Traces {
            obs,
            times,
            t_end,
            pred,
        })
    }
}

impl FitFigure<'_> {
    /// One time panel on `area`: data and fit, or residuals within a band of twice the
    /// measured noise, over the fitted modes.
    fn panel<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        (title, coords, is_resid): Panel,
        tr: &Traces,
    ) -> Result<(), PlotError> {
        let t_end = tr.t_end;
        let series: Vec<(usize, Points, Points)> = coords
            .iter()
            .map(|&k| {
                if is_resid {
                    (k, tr.resid(k), Vec::new())
                } else {
                    (k, tr.data(k), tr.fitted(k))
                }
            })
            .collect();
        let band = if is_resid {
            2.0 * self.report.noise_m[coords[0] / 2] * 1e3
        } else {
            0.0
        };
        let ys = series
            .iter()
            .flat_map(|(_, d, f)| d.iter().chain(f).map(|p| p.1))
            .chain([band, -band]);
        let yr = data_range(ys, 0.05);
        let span = yr.end - yr.start;
        let mut chart = ChartBuilder::on(area)
            .caption(title, ("sans-serif", 16))
            .margin(6)
            .x_label_area_size(32)
            .y_label_area_size(84)
            .build_cartesian_2d(0.0..t_end, yr.clone())?;
        chart
            .configure_mesh()
            .light_line_style(WHITE.mix(0.0))
            .x_desc("t [s]")
            .y_desc(if is_resid { "residual [mm]" } else { "[mm]" })
            .y_label_formatter(&|v| tick_label(*v, span))
            .x_label_formatter(&|v| tick_label(*v, t_end))
            .label_style(("sans-serif", 13))
            .draw()?;
        chart.draw_series(tr.bands(yr.end, yr.start))?;
        if is_resid {
            chart.draw_series(std::iter::once(Rectangle::new(
                [(0.0, -band), (t_end, band)],
                RGBColor(120, 120, 120).mix(0.25).filled(),
            )))?;
            chart.draw_series(LineSeries::new([(0.0, 0.0), (t_end, 0.0)], BLACK))?;
        }
        for (k, d, f) in &series {
            let c = COORDS[*k].1;
            chart.draw_series(
                d.iter()
                    .map(|&(t, v)| Circle::new((t, v), 1, c.mix(0.7).filled())),
            )?;
            if !f.is_empty() {
                chart.draw_series(LineSeries::new(
                    f.iter().cloned(),
                    BLACK.mix(0.8).stroke_width(1),
                ))?;
            }
        }
        Ok(())
    }

    /// The windows: mu_kinetic fitted on each stretch against the whole fit's interval `mu`.
    fn windows_panel<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        mu: Estimate,
        t_end: f64,
    ) -> Result<(), PlotError> {
        let rep = self.report;
        let ys = rep
            .windows
            .iter()
            .flat_map(|w| {
                [
                    w.mu_kinetic - 1.96 * w.stderr,
                    w.mu_kinetic + 1.96 * w.stderr,
                ]
            })
            .chain(mu.ci95);
        let yr = data_range(ys, 0.15);
        let span = yr.end - yr.start;
        let mut chart = ChartBuilder::on(area)
            .caption(
                "mu_kinetic per third of the recording (95% bars) against the whole fit's 95% interval",
                ("sans-serif", 16),
            )
            .margin(6)
            .x_label_area_size(32)
            .y_label_area_size(84)
            .build_cartesian_2d(0.0..t_end, yr)?;
        chart
            .configure_mesh()
            .light_line_style(WHITE.mix(0.0))
            .x_desc("t [s]")
            .y_desc("mu_kinetic")
            .y_label_formatter(&|v| tick_label(*v, span))
            .x_label_formatter(&|v| tick_label(*v, t_end))
            .label_style(("sans-serif", 13))
            .draw()?;
        chart.draw_series(std::iter::once(Rectangle::new(
            [(0.0, mu.ci95[0]), (t_end, mu.ci95[1])],
            RGBColor(0, 90, 200).mix(0.18).filled(),
        )))?;
        chart.draw_series(LineSeries::new(
            [(0.0, mu.value), (t_end, mu.value)],
            RGBColor(0, 90, 200).stroke_width(2),
        ))?;
        for w in &rep.windows {
            let (t0w, t1w) = (w.t_start, w.t_end);
            let mid = 0.5 * (t0w + t1w);
            let lo = w.mu_kinetic - 1.96 * w.stderr;
            let hi = w.mu_kinetic + 1.96 * w.stderr;
            chart.draw_series(LineSeries::new(
                [(t0w, w.mu_kinetic), (t1w, w.mu_kinetic)],
                BLACK.stroke_width(2),
            ))?;
            chart.draw_series(LineSeries::new([(mid, lo), (mid, hi)], BLACK))?;
            chart.draw_series(std::iter::once(Circle::new(
                (mid, w.mu_kinetic),
                4,
                BLACK.filled(),
            )))?;
        }
        Ok(())
    }
}

/// The legend's entries: the coordinates' colours, the fit, the noise band, the fitted modes
/// and the windows' marks.
fn legend_entries() -> Vec<(Swatch, String)> {
    let mut entries: Vec<(Swatch, String)> = COORDS
        .iter()
        .map(|(name, c)| (Swatch::Dot(*c), format!("{name} observed")))
        .collect();
    entries.push((Swatch::Line(BLACK, 1), "fitted model".into()));
    entries.push((
        Swatch::Fill(RGBColor(200, 200, 200)),
        "+-2 measured noise".into(),
    ));
    entries.push((
        Swatch::Fill(mode_color(Mode::Stick)),
        "fitted: stuck".into(),
    ));
    entries.push((
        Swatch::Fill(mode_color(Mode::Slide(crate::model::Direction::Positive))),
        "fitted: sliding +x".into(),
    ));
    entries.push((
        Swatch::Fill(mode_color(Mode::Slide(crate::model::Direction::Negative))),
        "fitted: sliding -x".into(),
    ));
    entries.push((
        Swatch::Line(RGBColor(0, 90, 200), 2),
        "mu_kinetic, whole fit".into(),
    ));
    entries.push((Swatch::Line(BLACK, 2), "mu_kinetic, one third".into()));
    entries
}

impl Figure for FitFigure<'_> {
    fn size(&self) -> (u32, u32) {
        (1300, 1150)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), PlotError> {
        let traces = self.traces()?;
        let (charts, side) = root.split_horizontally(1000);
        let heights = [250, 250, 200, 200];
        let (rows, windows_area) = charts.split_vertically(heights.iter().sum::<u32>());
        let mut areas = Vec::new();
        let mut rest = rows;
        for h in &heights[..3] {
            let (a, b) = rest.split_vertically(*h);
            areas.push(a);
            rest = b;
        }
        areas.push(rest);
        for (area, panel) in areas.iter().zip(PANELS) {
            self.panel(area, panel, &traces)?;
        }
        if let Some(mu) = self.report.mu_kinetic {
            self.windows_panel(&windows_area, mu, traces.t_end)?;
        }
        draw_side_legend(&side, "Fit", &legend_entries(), &self.notes(), 30)?;
        Ok(())
    }
}
