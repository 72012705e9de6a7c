//! The figure of `appell fit`: slider and bob positions, data and fit, their residuals against
//! the measured noise, the fitted modes as bands, and mu_kinetic per window.

use crate::fit::{Estimate, FitReport, Observations, StaticResult};
use crate::model::{observed_markers, Mode};
use crate::report::plot::{
    data_range, draw_key, draw_side_legend, finite_runs, thin_line, thin_points, Figure, PlotError,
    Swatch,
};
use crate::sim::{simulate_each, Options, Request};
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::ops::Range;

/// Most residual points one time panel draws: a few thousand dots show what the eye can see
/// in a panel 900 pixels wide, and keep the SVG of a long recording small (each dot is an
/// element of its own).
const PANEL_POINTS: usize = 1600;

/// Most data points one coordinate draws over its model line: spaced enough that the line
/// shows between and through them.
const DATA_POINTS: usize = 400;

/// The width in pixels of the column groups whose largest and smallest residual are always
/// drawn ([`thin_points`]).
const EXTREMES_EVERY: i32 = 10;

/// The fit's figure: slider x and bob position, data and fit, residuals, mode bands, and
/// mu_kinetic per window.
pub struct FitFigure<'a> {
    /// The recording.
    pub obs: &'a Observations,
    /// The fit.
    pub report: &'a FitReport,
}

/// The four observed coordinates in drawing order, each with the one colour it has in every
/// panel and the legend: slider x, slider y, bob x, bob y (Okabe and Ito's palette, told
/// apart with any colour vision).
const COORDS: [(&str, RGBColor); 4] = [
    ("slider x", RGBColor(0, 114, 178)),
    ("slider y", RGBColor(230, 159, 0)),
    ("bob x", RGBColor(213, 94, 0)),
    ("bob y", RGBColor(0, 158, 115)),
];

/// The fitted model's lines.
const MODEL: RGBColor = RGBColor(0, 0, 0);

/// Positions left out of the fit as mis-tracked.
const LEFT_OUT: RGBColor = RGBColor(110, 110, 110);

/// The whole fit's mu_kinetic in the windows' panel.
const WHOLE: RGBColor = RGBColor(204, 121, 167);

/// The names of the direction law's whole-fit intervals in the windows' panel.
const WHOLE_TEXT: RGBColor = RGBColor(150, 60, 110);

/// A window that slides both ways under the direction law: its mean, not a direction's.
const MIXED: RGBColor = RGBColor(120, 120, 120);

/// One drawn point: time (s), value (mm) and residual (fitted - observed, mm).
type Point = (f64, f64, f64);

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
    /// The legend's key numbers: mu with its error and interval, the model, the fit's quality,
    /// and what the drawing left out (`thinned`: the points drawn and those there were).
    fn notes(&self, tr: &Traces, thinned: (usize, usize)) -> Vec<String> {
        let rep = self.report;
        let mut notes = Vec::new();
        match &rep.mu_kinetic {
            Some(mu) => notes.push(format!(
                "mu_kinetic = {} [{}]",
                super::answer::with_interval(mu),
                mu.interval
            )),
            None => notes.push("mu_kinetic: not identifiable (no slide)".into()),
        }
        notes.extend(self.direction_notes());
        if let Some(n) = self.static_note() {
            notes.push(n);
        }
        if let Some(n) = self.theta_note() {
            notes.push(n);
        }
        // The chosen model by the name the report's table gives it (spaced at its `+`, so
        // that a long one wraps in the panel).
        let model = rep
            .models
            .iter()
            .find(|m| m.chosen)
            .map(|m| m.name.clone())
            .unwrap_or_else(|| {
                if rep.nuisances.is_empty() {
                    "base".to_owned()
                } else {
                    rep.nuisances
                        .iter()
                        .map(|n| n.name())
                        .collect::<Vec<_>>()
                        .join("+")
                }
            });
        notes.push(format!("model: {}", model.replace('+', " + ")));
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
        if !a.limited_by_model.is_empty() {
            notes.push("limited by the model, not by the noise (see the report)".into());
        }
        let left_out = tr.left_out.iter().flatten().filter(|b| **b).count();
        if left_out > 0 {
            notes.push(format!(
                "{left_out} positions left out of the fit as mis-tracked (x; beyond an axis, drawn at its edge)"
            ));
        }
        let (drawn, total) = thinned;
        if drawn < total {
            notes.push(format!(
                "thinned to draw: {drawn} of {total} points shown ({DATA_POINTS} data a coordinate, {PANEL_POINTS} residuals a panel at most, every {EXTREMES_EVERY} pixels' largest and smallest residual among them); the fit used them all"
            ));
        }
        notes
    }
}

impl FitFigure<'_> {
    /// Under the direction law, each direction's coefficient (mu_kinetic is their mean).
    fn direction_notes(&self) -> Vec<String> {
        self.per_direction()
            .map(|[p, m]| {
                vec![
                    format!("toward +x: {}", super::answer::with_interval(&p)),
                    format!("toward -x: {}", super::answer::with_interval(&m)),
                ]
            })
            .unwrap_or_default()
    }

    /// Each direction's coefficient (+x, then -x) as an estimate, under the direction law.
    fn per_direction(&self) -> Option<[Estimate; 2]> {
        let f = self.report.friction.as_ref()?;
        if !f.chosen.starts_with("direction") {
            return None;
        }
        let get = |name: &str| {
            f.parameters
                .iter()
                .find(|p| p.name == name)
                .map(|p| Estimate {
                    value: p.value,
                    stderr: p.stderr,
                    ci95: p.ci95,
                    interval: "",
                })
        };
        Some([get("mu_kinetic_positive")?, get("mu_kinetic_negative")?])
    }

    /// mu_static at the precision its error gives; tied at its bound mu_kinetic, the
    /// one-sided bound said as such.
    fn static_note(&self) -> Option<String> {
        let rep = self.report;
        let free = rep
            .params
            .iter()
            .any(|(p, _)| *p == crate::fit::Param::MuStatic);
        match &rep.mu_static {
            StaticResult::Estimated(e) if free => Some(format!(
                "mu_static = {} [{}]",
                super::answer::with_interval(e),
                e.interval
            )),
            StaticResult::Estimated(e) => {
                let d = rep
                    .mu_kinetic
                    .and_then(|m| crate::report::two_digit_decimals(m.stderr))
                    .map_or(6, |d| d.min(12));
                Some(format!(
                    "mu_static: at its bound mu_kinetic; one-sided 95 %: at most {:.d$}",
                    e.ci95[1]
                ))
            }
            StaticResult::LowerBound(b) => Some(format!("mu_static >= {b:.4}")),
            StaticResult::NotIdentifiable => None,
        }
    }

    /// The release angle with its convention: theta runs from the rail's +x direction with y
    /// down (docs/physics.md), so the bob hangs at pi/2.
    fn theta_note(&self) -> Option<String> {
        let rep = self.report;
        let se = rep
            .params
            .iter()
            .find(|(p, _)| *p == crate::fit::Param::Theta)
            .map_or(f64::NAN, |(_, e)| e.stderr);
        let theta = rep
            .params
            .iter()
            .find(|(p, _)| *p == crate::fit::Param::Theta)
            .map(|(_, e)| e.value)
            .or_else(|| {
                rep.fixed
                    .iter()
                    .find(|(p, _)| *p == crate::fit::Param::Theta)
                    .map(|(_, v)| *v)
            })
            .unwrap_or(f64::NAN);
        let d = crate::report::two_digit_decimals(se).map_or(4, |d| d.clamp(2, 8));
        theta.is_finite().then(|| {
            // Never "-0.0000": a theta within its last decimal of zero reads as 0.
            let shown = format!("{theta:.d$}");
            let shown = if shown
                .trim_start_matches('-')
                .trim_matches(['0', '.'])
                .is_empty()
            {
                shown.trim_start_matches('-').to_owned()
            } else {
                shown
            };
            format!(
                "released at theta = {shown} rad {}",
                super::answer::from_hanging(theta, se)
            )
        })
    }
}

/// A time panel: its title, the coordinates it draws (indices into [`COORDS`]) and whether it
/// shows their residuals rather than data and fit.
type Panel = (&'static str, &'static [usize], bool);

/// The four time panels, top to bottom.
const PANELS: [Panel; 4] = [
    ("slider x [mm]: data over the fitted model", &[0], false),
    (
        "bob x and y [mm]: data over the fitted model",
        &[2, 3],
        false,
    ),
    (
        "slider residual [mm]: fitted - observed; band +-2 noise",
        &[0, 1],
        true,
    ),
    (
        "bob residual [mm]: fitted - observed; band +-2 noise",
        &[2, 3],
        true,
    ),
];

/// What the time panels draw: every frame's time from zero, the fitted model's markers and
/// mode at each, and which positions the fit left out.
struct Traces<'a> {
    /// The recording.
    obs: &'a Observations,
    /// Frame times from the first (s).
    times: Vec<f64>,
    /// The last time drawn (s), above zero.
    t_end: f64,
    /// At each frame: its time, the fitted markers (slider x, y, bob x, y; m) and the mode.
    pred: Vec<(f64, [f64; 4], Mode)>,
    /// At each frame, whether the fit left out the slider's and the bob's position.
    left_out: Vec<[bool; 2]>,
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

    /// The observed points of coordinate `k` with their residuals (fitted minus observed, as
    /// docs/fit.md and docs/glossary.md define them): those the fit used, or those it `left_out`.
    fn points(&self, k: usize, left_out: bool) -> Vec<Point> {
        (0..self.times.len().min(self.pred.len()))
            .filter(|&i| self.left_out[i][k / 2] == left_out)
            .filter_map(|i| {
                let v = self.observed(k, i)?;
                Some((self.times[i], v, self.pred[i].1[k] * 1e3 - v))
            })
            .collect()
    }

    /// The fitted coordinate `k` (mm) at every frame.
    fn fitted(&self, k: usize) -> Vec<(f64, f64)> {
        self.pred.iter().map(|p| (p.0, p.1[k] * 1e3)).collect()
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
    /// The fitted model at every frame, and the positions the fit left out. Every frame is
    /// simulated; the drawing, not the data, is thinned to what a panel's pixels can show.
    fn traces(&self) -> Result<Traces<'a>, PlotError> {
        let rep = self.report;
        let obs = self.obs;
        let t0 = obs.times[0];
        let times: Vec<f64> = obs.times.iter().map(|t| t - t0).collect();
        let t_end = times.last().copied().unwrap_or(1.0).max(1e-9);
        // Each sample made a point of the trace as the run passes it: a million frames keep
        // no simulated state besides.
        let mut pred: Vec<(f64, [f64; 4], Mode)> = Vec::with_capacity(times.len());
        simulate_each(
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
            &mut |s| {
                let markers = observed_markers(&rep.rig, &rep.camera, s.mode, &s.state);
                pred.push((s.t, markers, s.mode));
            },
        )
        .map_err(|e| PlotError::Draw(e.to_string()))?;
        // The fit's own observations are the same frames; it weighs all but what it left out.
        let weighed = rep.problem.weighed_positions();
        let left_out = if weighed.len() == obs.times.len() {
            (0..obs.times.len())
                .map(|i| {
                    [
                        obs.slider[i].is_some() && !weighed[i][0],
                        obs.bob[i].is_some() && !weighed[i][1],
                    ]
                })
                .collect()
        } else {
            vec![[false; 2]; obs.times.len()]
        };
        Ok(Traces {
            obs,
            times,
            t_end,
            pred,
            left_out,
        })
    }
}

/// A time chart of the figure: f64 seconds against f64 values.
type TimeChart<'c, DB> = ChartContext<'c, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// Draw `points` (t, value) as a line thinned to the pixels it covers ([`thin_line`]).
fn draw_line<DB: DrawingBackend>(
    chart: &mut TimeChart<'_, DB>,
    points: &[(f64, f64)],
    style: ShapeStyle,
) -> Result<(), PlotError> {
    for run in finite_runs(points) {
        let pixels: Vec<(i32, i32)> = run.iter().map(|p| chart.backend_coord(p)).collect();
        let kept = thin_line(&pixels);
        chart.draw_series(LineSeries::new(kept.into_iter().map(|i| run[i]), style))?;
    }
    Ok(())
}

/// Draw `points` (t, y, key) as dots of `style` with at most `budget` drawn
/// ([`thin_points`], the key telling the extremes), a value outside `yr` at its edge, as
/// crosses when `cross`. Returns how many were drawn.
fn draw_dots<DB: DrawingBackend>(
    chart: &mut TimeChart<'_, DB>,
    points: &[(f64, f64, f64)],
    yr: &Range<f64>,
    (style, radius, cross): (ShapeStyle, i32, bool),
    budget: usize,
) -> Result<usize, PlotError> {
    let at = |p: &(f64, f64, f64)| (p.0, p.1.clamp(yr.start, yr.end));
    let pixels: Vec<(i32, i32)> = points.iter().map(|p| chart.backend_coord(&at(p))).collect();
    let keys: Vec<f64> = points.iter().map(|p| p.2).collect();
    let kept = thin_points(&pixels, &keys, budget, EXTREMES_EVERY);
    let drawn = kept.len();
    if cross {
        chart.draw_series(
            kept.into_iter()
                .map(|i| Cross::new(at(&points[i]), radius, style)),
        )?;
    } else {
        chart.draw_series(
            kept.into_iter()
                .map(|i| Circle::new(at(&points[i]), radius, style)),
        )?;
    }
    Ok(drawn)
}

/// The points a panel draws and the points there were.
type Drawn = (usize, usize);

impl FitFigure<'_> {
    /// One time panel on `area`: data over the fitted model, or residuals within a band of
    /// twice the measured noise, over the fitted modes, with its title and key above it.
    fn panel<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        (title, coords, is_resid): Panel,
        tr: &Traces,
    ) -> Result<Drawn, PlotError> {
        let t_end = tr.t_end;
        let used: Vec<Vec<Point>> = coords.iter().map(|&k| tr.points(k, false)).collect();
        let left: Vec<Vec<Point>> = coords.iter().map(|&k| tr.points(k, true)).collect();
        let fitted: Vec<Vec<(f64, f64)>> = coords.iter().map(|&k| tr.fitted(k)).collect();
        // The drawn value: the residual or the observation.
        let value = |p: &Point| -> Point {
            if is_resid {
                (p.0, p.2, p.2)
            } else {
                *p
            }
        };
        let band = if is_resid {
            2.0 * self.report.noise_m[coords[0] / 2] * 1e3
        } else {
            0.0
        };
        // The axis holds what the fit used and the model: a position left out as mis-tracked
        // may lie metres off, and is drawn at the axis's edge.
        let ys = used
            .iter()
            .flatten()
            .map(|p| value(p).1)
            .chain(fitted.iter().flatten().filter(|_| !is_resid).map(|p| p.1))
            .chain([band, -band]);
        let yr = data_range(ys, 0.05);
        let span = yr.end - yr.start;
        let mut chart = ChartBuilder::on(area)
            .margin(6)
            .margin_top(26)
            .x_label_area_size(32)
            .y_label_area_size(84)
            .build_cartesian_2d(0.0..t_end, yr.clone())?;
        chart
            .configure_mesh()
            .light_line_style(WHITE.mix(0.0))
            .x_desc("t [s]")
            .y_desc(if is_resid {
                "residual [mm]"
            } else {
                "position [mm]"
            })
            .y_label_formatter(&|v| tick_label(*v, span))
            .x_label_formatter(&|v| tick_label(*v, t_end))
            .label_style(("sans-serif", 13))
            .draw()?;
        let font = ("sans-serif", 16).into_font().color(&BLACK);
        area.draw(&Text::new(title, (90, 6), font))?;
        let mut key: Vec<(Swatch, String)> = coords
            .iter()
            .map(|&k| {
                let (name, c) = COORDS[k];
                let swatch = if is_resid {
                    Swatch::Dot(c)
                } else {
                    Swatch::Ring(c)
                };
                (swatch, name.to_owned())
            })
            .collect();
        if !is_resid {
            key.push((Swatch::Line(MODEL, 1), "fitted model".into()));
        }
        if left.iter().any(|l| !l.is_empty()) {
            key.push((Swatch::Cross(LEFT_OUT), "left out".into()));
        }
        let right = area.dim_in_pixel().0 as i32 - 10;
        draw_key(area, &key, (right, 13), 13)?;
        chart.draw_series(tr.bands(yr.end, yr.start))?;
        if is_resid {
            chart.draw_series(std::iter::once(Rectangle::new(
                [(0.0, -band), (t_end, band)],
                RGBColor(120, 120, 120).mix(0.25).filled(),
            )))?;
            chart.draw_series(LineSeries::new([(0.0, 0.0), (t_end, 0.0)], BLACK))?;
        } else {
            // The model first and thin, so that the data drawn over it stay visible, and
            // where they leave it, the model shows through them.
            for f in &fitted {
                draw_line(&mut chart, f, MODEL.stroke_width(1))?;
            }
        }
        // Residuals as dots; data as open circles, through which the model line shows.
        let (budget, radius) = if is_resid {
            (PANEL_POINTS / coords.len(), 2)
        } else {
            (DATA_POINTS, 3)
        };
        let mut drawn = 0;
        for (&k, pts) in coords.iter().zip(&used) {
            let style = if is_resid {
                COORDS[k].1.mix(0.6).filled()
            } else {
                COORDS[k].1.stroke_width(1)
            };
            let shown: Vec<Point> = pts.iter().map(value).collect();
            drawn += draw_dots(&mut chart, &shown, &yr, (style, radius, false), budget)?;
        }
        for pts in &left {
            let shown: Vec<Point> = pts.iter().map(value).collect();
            let style = LEFT_OUT.stroke_width(1);
            drawn += draw_dots(&mut chart, &shown, &yr, (style, 3, true), PANEL_POINTS)?;
        }
        let total = used.iter().chain(&left).map(Vec::len).sum();
        Ok((drawn, total))
    }

    /// The direction (+1 toward +x, -1 toward -x) in which the fitted motion slides for at
    /// least 90 % of its sliding frames between `t0` and `t1` (times from the first frame);
    /// `None` for a window that slides both ways.
    fn window_direction(tr: &Traces, t0: f64, t1: f64) -> Option<f64> {
        let (mut plus, mut minus) = (0usize, 0usize);
        for (t, _, mode) in &tr.pred {
            if *t < t0 || *t > t1 {
                continue;
            }
            match mode {
                Mode::Slide(crate::model::Direction::Positive) => plus += 1,
                Mode::Slide(crate::model::Direction::Negative) => minus += 1,
                Mode::Stick => {}
            }
        }
        let n = (plus + minus) as f64;
        if n > 0.0 && plus as f64 >= 0.9 * n {
            Some(1.0)
        } else if n > 0.0 && minus as f64 >= 0.9 * n {
            Some(-1.0)
        } else {
            None
        }
    }

    /// The windows: mu_kinetic fitted on each stretch against the whole fit's interval `mu`.
    /// Under the direction law each window's fit holds the split at the whole fit's, so its
    /// own coefficient is its mean plus the split toward its direction: drawn against that
    /// direction's whole-fit interval (a window sliding both ways at its mean, in grey).
    fn windows_panel<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        mu: Estimate,
        tr: &Traces,
    ) -> Result<(), PlotError> {
        let rep = self.report;
        let t_end = tr.t_end;
        let t_first = self.obs.times[0];
        let split = self.per_direction().map(|_| rep.rig.kinetic_split);
        // Each window's span (from the first frame), value and colour.
        let marks: Vec<(f64, f64, f64, f64, RGBColor)> = rep
            .windows
            .iter()
            .map(|w| {
                let (t0w, t1w) = (w.t_start - t_first, w.t_end - t_first);
                let (value, colour) = match split {
                    Some(split) => match Self::window_direction(tr, t0w, t1w) {
                        Some(s) => (w.mu_kinetic + split * s, BLACK),
                        None => (w.mu_kinetic, MIXED),
                    },
                    None => (w.mu_kinetic, BLACK),
                };
                (t0w, t1w, value, 1.96 * w.stderr, colour)
            })
            .collect();
        // The whole fit's intervals: one, or one per direction with its name.
        let wholes: Vec<(Estimate, &str)> = match self.per_direction() {
            Some([p, m]) => vec![(p, "toward +x"), (m, "toward -x")],
            None => vec![(mu, "")],
        };
        let ys = marks
            .iter()
            .flat_map(|m| [m.2 - m.3, m.2 + m.3])
            .chain(wholes.iter().flat_map(|(e, _)| e.ci95));
        let yr = data_range(ys, 0.15);
        let span = yr.end - yr.start;
        let what = if split.is_some() {
            "mu_kinetic toward +x and -x"
        } else {
            "mu_kinetic"
        };
        let title = match rep.window_cut {
            Some(cut) => format!(
                "{what} per {} ({}), 95% bars, against the whole fit's 95% interval{}",
                cut.per(),
                cut.how(),
                if split.is_some() { "s" } else { "" }
            ),
            None => format!("{what} of the whole fit (95% interval; no window fitted)"),
        };
        let mut chart = ChartBuilder::on(area)
            .caption(title, ("sans-serif", 16))
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
        for (e, name) in &wholes {
            chart.draw_series(std::iter::once(Rectangle::new(
                [(0.0, e.ci95[0]), (t_end, e.ci95[1])],
                WHOLE.mix(0.25).filled(),
            )))?;
            chart.draw_series(LineSeries::new(
                [(0.0, e.value), (t_end, e.value)],
                WHOLE.stroke_width(2),
            ))?;
            if !name.is_empty() {
                chart.draw_series(std::iter::once(
                    EmptyElement::at((0.0, e.value))
                        + Text::new(
                            format!(
                                "{name} {:.d$}",
                                e.value,
                                d = crate::report::two_digit_decimals(e.stderr)
                                    .map_or(5, |d| d.min(12))
                            ),
                            (6, -18),
                            ("sans-serif", 14).into_font().color(&WHOLE_TEXT),
                        ),
                ))?;
            }
        }
        for &(t0w, t1w, value, half, colour) in &marks {
            let mid = 0.5 * (t0w + t1w);
            chart.draw_series(LineSeries::new(
                [(t0w, value), (t1w, value)],
                colour.stroke_width(2),
            ))?;
            chart.draw_series(LineSeries::new(
                [(mid, value - half), (mid, value + half)],
                colour,
            ))?;
            chart.draw_series(std::iter::once(Circle::new(
                (mid, value),
                4,
                colour.filled(),
            )))?;
        }
        Ok(())
    }

    /// The legend's entries: the coordinates' colours, the fit, what was left out, the noise
    /// band, the fitted modes and the windows' marks.
    fn legend_entries(&self, tr: &Traces) -> Vec<(Swatch, String)> {
        let mut entries: Vec<(Swatch, String)> = COORDS
            .iter()
            .map(|(name, c)| (Swatch::Dot(*c), (*name).to_owned()))
            .collect();
        let grey = RGBColor(90, 90, 90);
        entries.push((Swatch::Ring(grey), "data (observed)".into()));
        entries.push((Swatch::Dot(grey), "residual (fitted - observed)".into()));
        entries.push((Swatch::Line(MODEL, 1), "fitted model".into()));
        entries.push((
            Swatch::Cross(LEFT_OUT),
            "left out of the fit as mis-tracked".into(),
        ));
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
        let one = self.report.window_cut.map_or("window", |c| c.per());
        if self.per_direction().is_some() {
            entries.push((
                Swatch::Line(WHOLE, 2),
                "mu_kinetic toward +x and toward -x, whole fit (bands: 95%)".into(),
            ));
            entries.push((
                Swatch::Line(BLACK, 2),
                format!("mu_kinetic, one {one} (in its direction)"),
            ));
            let t_first = self.obs.times[0];
            let mixed = self.report.windows.iter().any(|w| {
                Self::window_direction(tr, w.t_start - t_first, w.t_end - t_first).is_none()
            });
            if mixed {
                entries.push((
                    Swatch::Line(MIXED, 2),
                    format!("mu_kinetic, one {one} sliding both ways (their mean)"),
                ));
            }
        } else {
            entries.push((
                Swatch::Line(WHOLE, 2),
                "mu_kinetic, whole fit (band: 95%)".into(),
            ));
            entries.push((Swatch::Line(BLACK, 2), format!("mu_kinetic, one {one}")));
        }
        entries
    }
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
        let mut thinned = (0, 0);
        for (area, panel) in areas.iter().zip(PANELS) {
            let (drawn, total) = self.panel(area, panel, &traces)?;
            thinned = (thinned.0 + drawn, thinned.1 + total);
        }
        if let Some(mu) = self.report.mu_kinetic {
            self.windows_panel(&windows_area, mu, &traces)?;
        }
        let notes = self.notes(&traces, thinned);
        draw_side_legend(&side, "Fit", &self.legend_entries(&traces), &notes, 30)?;
        Ok(())
    }
}
