//! Output of `appell regions`: the phase portrait runs, the readable summary, the JSON object
//! and the region figure in the (theta, theta') plane.

use super::plot::{Figure, PlotError};
use crate::model::regions::{
    in_paradox_band, slide_count_intervals, slide_solution_count, stick_intervals, Curve, RegionMap,
};
use crate::model::{Mode, Rig, State, THETA, THETA_DOT};
use crate::sim::{simulate, Options, Request, Sample};
use plotters::coord::Shift;
use plotters::prelude::*;
use serde_json::{json, Value};
use std::f64::consts::PI;
use std::fmt::Write as _;

/// How the phase portrait is computed: how many runs, how long, sampled how often.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PortraitOptions {
    /// Number of trajectories (initial states from [`portrait_initial_states`]).
    pub trajectories: usize,
    /// Duration of each run (s).
    pub duration: f64,
    /// Sampling rate of each run (Hz).
    pub frame_rate: f64,
}

impl Default for PortraitOptions {
    /// Eight runs of 3 s at 200 Hz.
    fn default() -> Self {
        PortraitOptions {
            trajectories: 8,
            duration: 3.0,
            frame_rate: 200.0,
        }
    }
}

/// The initial states of a phase portrait of `n` runs: about half released from rest at angles
/// spread over -30..210 degrees (both sides of the hanging position, some with the bob above
/// the rail), the rest starting from the hanging position theta = 90 deg with angular
/// velocities +-1.0, +-1.7, +-2.4, ... sqrt(g / l) (alternating signs).
pub fn portrait_initial_states(rig: &Rig<f64>, n: usize) -> Vec<State<f64>> {
    let n_rest = n.div_ceil(2);
    let n_spin = n - n_rest;
    let (lo, hi) = (-30f64.to_radians(), 210f64.to_radians());
    let mut out = Vec::with_capacity(n);
    for k in 0..n_rest {
        let theta = if n_rest == 1 {
            0.0
        } else {
            lo + (hi - lo) * k as f64 / (n_rest - 1) as f64
        };
        out.push([0.0, theta, 0.0, 0.0]);
    }
    let unit = (rig.gravity / rig.rod_length).sqrt();
    for k in 0..n_spin {
        let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
        let w0 = sign * unit * (1.0 + 0.7 * (k / 2) as f64);
        out.push([0.0, PI / 2.0, 0.0, w0]);
    }
    out
}

/// One run of a phase portrait.
#[derive(Debug, Clone)]
pub struct Trajectory {
    /// Its initial state (x, theta, x', theta').
    pub initial: State<f64>,
    /// Samples at the frame rate (fewer when the run stopped early).
    pub samples: Vec<Sample<f64>>,
    /// The run stopped at a Painleve paradox event (no unique continuation).
    pub stopped_at_paradox: bool,
    /// Why the simulator failed, when it did (the samples are then empty).
    pub error: Option<String>,
}

/// Simulate the runs of a phase portrait with [`crate::sim::simulate`] (rtol 1e-8). A run
/// that fails is kept with its error and no samples, so one stiff start cannot hide the rest.
pub fn phase_portrait(rig: &Rig<f64>, options: &PortraitOptions) -> Vec<Trajectory> {
    let sim_options = Options {
        rtol: 1e-8,
        atol: 1e-10,
        ..Options::default()
    };
    let n = (options.duration * options.frame_rate + 1e-9).floor() as usize;
    let request = Request {
        sample_times: (0..=n).map(|k| k as f64 / options.frame_rate).collect(),
        friction_work: false,
    };
    portrait_initial_states(rig, options.trajectories)
        .into_iter()
        .map(
            |y0| match simulate(rig, &y0, options.duration, &sim_options, &request) {
                Ok(sol) => Trajectory {
                    initial: y0,
                    stopped_at_paradox: sol.stopped_at_paradox(),
                    samples: sol.samples,
                    error: None,
                },
                Err(e) => Trajectory {
                    initial: y0,
                    samples: Vec::new(),
                    stopped_at_paradox: false,
                    error: Some(e.to_string()),
                },
            },
        )
        .collect()
}

fn curves_json(curves: &[Curve]) -> Value {
    json!(curves)
}

/// The JSON object of `appell regions --json`: the summary fields at the top level
/// (`mu_critical`, `theta_critical_deg`, `paradox_band_deg`, `max_mass_ratio_for_paradox`,
/// ...), the boundary curves as point lists `[theta, theta']` (rad, rad/s), the band edges
/// and, per trajectory, its start, how many samples each mode has and how it ended.
pub fn regions_json(map: &RegionMap, trajectories: &[Trajectory]) -> Value {
    let mut out = json!(map.summary);
    out["window"] = json!(map.window);
    out["stick_boundary"] = curves_json(&map.stick_boundary);
    out["q_zero"] = curves_json(&map.q_zero);
    out["band_edges_deg"] = json!(map
        .band_edges
        .iter()
        .map(|t| t.to_degrees())
        .collect::<Vec<_>>());
    out["trajectories"] = json!(trajectories
        .iter()
        .map(|t| {
            let count = |m: Mode| t.samples.iter().filter(|s| s.mode == m).count();
            json!({
                "theta0_deg": t.initial[THETA].to_degrees(),
                "theta_dot0": t.initial[THETA_DOT],
                "samples": {
                    "stick": count(Mode::Stick),
                    "slide+": count(Mode::Slide(crate::model::Direction::Positive)),
                    "slide-": count(Mode::Slide(crate::model::Direction::Negative)),
                },
                "end_time": t.samples.last().map(|s| s.t),
                "stopped_at_paradox": t.stopped_at_paradox,
                "error": t.error,
            })
        })
        .collect::<Vec<_>>());
    out
}

/// The readable summary of `appell regions`.
pub fn regions_summary(rig: &Rig<f64>, map: &RegionMap, trajectories: &[Trajectory]) -> String {
    let s = &map.summary;
    let mut out = String::new();
    let _ = writeln!(
        out,
        "rig: m1 = {} kg, m2 = {} kg (r = m1/m2 = {:.4}), l = {} m, g = {} m/s^2, mu_k = {}, mu_s = {}",
        rig.slider_mass, rig.bob_mass, s.mass_ratio, rig.rod_length, rig.gravity, s.mu_kinetic, s.mu_static
    );
    let _ = writeln!(
        out,
        "critical friction mu* = {:.4} at theta* = {:.2} deg",
        s.mu_critical, s.theta_critical_deg
    );
    if s.paradox_possible() {
        let bands: Vec<String> = s
            .paradox_band_deg
            .iter()
            .map(|[lo, hi]| format!("{lo:.2}..{hi:.2} deg"))
            .collect();
        let _ = writeln!(
            out,
            "paradox band (mu_k |a| > D): {} (and the same |tan theta| in every quadrant)",
            bands.join(" and ")
        );
        let _ = writeln!(
            out,
            "  inside it a slide in direction s has two solutions where sign(Q) = sign(s a), none where they differ;"
        );
        for [lo, hi] in &s.paradox_band_deg {
            let mid = (0.5 * (lo + hi)).to_radians();
            let _ = writeln!(
                out,
                "  at rest in {lo:.2}..{hi:.2} deg: slide+ has {} solutions, slide- has {}",
                slide_solution_count(rig, mid, 0.0, 1.0),
                slide_solution_count(rig, mid, 0.0, -1.0)
            );
        }
    } else {
        let _ = writeln!(
            out,
            "paradox band: none (mu_k = {} <= mu* = {:.4}): the sliding equation has exactly one solution everywhere",
            s.mu_kinetic, s.mu_critical
        );
    }
    let _ = writeln!(
        out,
        "largest m1/m2 with a paradox band at mu_k = {}: {:.4}",
        s.mu_kinetic, s.max_mass_ratio_for_paradox
    );
    let _ = writeln!(
        out,
        "stick boundary |c| = mu_s |b|: {} curve pieces; Q = 0 (N changes sign while sliding): {} pieces; window theta {:.0}..{:.0} deg, |theta'| <= {:.2} rad/s",
        map.stick_boundary.len(),
        map.q_zero.len(),
        map.window.theta_min.to_degrees(),
        map.window.theta_max.to_degrees(),
        map.window.w_max
    );
    if !trajectories.is_empty() {
        let _ = writeln!(out, "trajectories:");
        for t in trajectories {
            let mut modes: Vec<&str> = Vec::new();
            for sample in &t.samples {
                let name = sample.mode.name();
                if modes.last() != Some(&name) {
                    modes.push(name);
                }
            }
            let end = match (&t.error, t.stopped_at_paradox) {
                (Some(e), _) => format!("failed: {e}"),
                (None, true) => format!(
                    "stopped at a paradox at t = {:.3} s",
                    t.samples.last().map_or(0.0, |s| s.t)
                ),
                (None, false) => "completed".to_owned(),
            };
            let mut timeline = modes.join(" > ");
            if modes.len() > 8 {
                timeline = format!(
                    "{} > ... ({} mode changes)",
                    modes[..8].join(" > "),
                    modes.len() - 1
                );
            }
            let _ = writeln!(
                out,
                "  theta0 = {:7.2} deg, theta'0 = {:6.2} rad/s: {timeline}; {end}",
                t.initial[THETA].to_degrees(),
                t.initial[THETA_DOT],
            );
        }
    }
    out
}

/// Colour of a mode in the phase portraits.
pub fn mode_color(mode: Mode) -> RGBColor {
    match mode {
        Mode::Stick => RGBColor(20, 20, 20),
        Mode::Slide(crate::model::Direction::Positive) => RGBColor(220, 90, 0),
        Mode::Slide(crate::model::Direction::Negative) => RGBColor(0, 110, 200),
    }
}

const STICK_FILL: RGBColor = RGBColor(150, 210, 150);
const NONE_FILL: RGBColor = RGBColor(240, 120, 120);
const TWO_FILL: RGBColor = RGBColor(140, 160, 240);
const BOUNDARY: RGBColor = RGBColor(0, 120, 0);
const Q_ZERO: RGBColor = RGBColor(150, 0, 150);
const EDGE: RGBColor = RGBColor(90, 90, 90);

/// The region figure: one panel per slide direction (s = +1 above, s = -1 below), each with
/// the stick region shaded and outlined, the sliding model's regions without a solution and
/// with two solutions shaded, the band edges, the curve Q = 0, and the phase-portrait
/// trajectories coloured by mode.
pub struct RegionFigure<'a> {
    /// The rig.
    pub rig: &'a Rig<f64>,
    /// Its region map (curves and window).
    pub map: &'a RegionMap,
    /// Trajectories to overlay.
    pub trajectories: &'a [Trajectory],
}

/// Points of a trajectory in degrees, wrapped into the window and split where the wrap jumps
/// or the mode changes; each piece carries its mode (pieces of one mode join the next at the
/// switching sample).
fn trajectory_pieces(map: &RegionMap, t: &Trajectory) -> Vec<(Mode, Vec<(f64, f64)>)> {
    let win = &map.window;
    let mut out: Vec<(Mode, Vec<(f64, f64)>)> = Vec::new();
    let mut prev: Option<(f64, f64)> = None;
    for s in &t.samples {
        let p = (
            win.wrap(s.state[THETA]).to_degrees(),
            s.state[THETA_DOT].clamp(-win.w_max, win.w_max),
        );
        let jump = prev.is_some_and(|q| (p.0 - q.0).abs() > 180.0);
        match out.last_mut() {
            Some((m, pts)) if *m == s.mode && !jump => pts.push(p),
            _ => {
                let mut pts = Vec::new();
                if let (Some(q), false) = (prev, jump) {
                    pts.push(q);
                }
                pts.push(p);
                out.push((s.mode, pts));
            }
        }
        prev = Some(p);
    }
    out
}

impl RegionFigure<'_> {
    fn panel<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        s: f64,
    ) -> Result<(), PlotError> {
        let win = &self.map.window;
        let (t0, t1) = (win.theta_min.to_degrees(), win.theta_max.to_degrees());
        let w = win.w_max;
        let sm = &self.map.summary;
        let caption = format!(
            "slide {} (s = {:+}): m1/m2 = {:.3}, mu_k = {}, mu_s = {}, mu* = {:.3}",
            if s > 0.0 { "+" } else { "-" },
            s as i32,
            sm.mass_ratio,
            sm.mu_kinetic,
            sm.mu_static,
            sm.mu_critical
        );
        let mut chart = ChartBuilder::on(area)
            .caption(caption, ("sans-serif", 18))
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(t0..t1, -w..w)?;
        chart
            .configure_mesh()
            .x_desc("theta [deg] (90: hanging, 270: above the rail)")
            .y_desc("theta' [rad/s]")
            .label_style(("sans-serif", 13))
            .light_line_style(WHITE.mix(0.0))
            .draw()?;
        // Shaded regions, one column per degree step, exact in theta' within each column.
        let columns = 360usize;
        let mut stick_rects = Vec::new();
        let mut none_rects = Vec::new();
        let mut two_rects = Vec::new();
        for i in 0..columns {
            let a = win.theta_min + (win.theta_max - win.theta_min) * i as f64 / columns as f64;
            let b =
                win.theta_min + (win.theta_max - win.theta_min) * (i + 1) as f64 / columns as f64;
            let mid = 0.5 * (a + b);
            let (ad, bd) = (a.to_degrees(), b.to_degrees());
            for (lo, hi) in stick_intervals(self.rig, mid, w) {
                stick_rects.push([(ad, lo), (bd, hi)]);
            }
            if in_paradox_band(self.rig, mid) {
                for (lo, hi, n) in slide_count_intervals(self.rig, mid, s, w) {
                    match n {
                        0 => none_rects.push([(ad, lo), (bd, hi)]),
                        2 => two_rects.push([(ad, lo), (bd, hi)]),
                        _ => {}
                    }
                }
            }
        }
        let legend_box = |c: RGBColor| {
            move |(x, y): (i32, i32)| Rectangle::new([(x, y - 6), (x + 18, y + 6)], c.filled())
        };
        chart
            .draw_series(
                stick_rects
                    .into_iter()
                    .map(|r| Rectangle::new(r, STICK_FILL.mix(0.45).filled())),
            )?
            .label("stick region |c| <= mu_s |b|")
            .legend(legend_box(STICK_FILL));
        if !none_rects.is_empty() {
            chart
                .draw_series(
                    none_rects
                        .into_iter()
                        .map(|r| Rectangle::new(r, NONE_FILL.mix(0.45).filled())),
                )?
                .label("sliding: no solution")
                .legend(legend_box(NONE_FILL));
        }
        if !two_rects.is_empty() {
            chart
                .draw_series(
                    two_rects
                        .into_iter()
                        .map(|r| Rectangle::new(r, TWO_FILL.mix(0.45).filled())),
                )?
                .label("sliding: two solutions")
                .legend(legend_box(TWO_FILL));
        }
        let to_deg = |c: &Curve| -> Vec<(f64, f64)> {
            c.points.iter().map(|p| (p[0].to_degrees(), p[1])).collect()
        };
        for (i, c) in self.map.stick_boundary.iter().enumerate() {
            let drawn = chart.draw_series(LineSeries::new(to_deg(c), BOUNDARY.stroke_width(2)))?;
            if i == 0 {
                drawn.label("|c| = mu_s |b|").legend(|(x, y)| {
                    PathElement::new(vec![(x, y), (x + 18, y)], BOUNDARY.stroke_width(2))
                });
            }
        }
        for (i, c) in self.map.q_zero.iter().enumerate() {
            let drawn = chart.draw_series(LineSeries::new(to_deg(c), Q_ZERO.stroke_width(2)))?;
            if i == 0 {
                drawn.label("Q = 0 (N changes sign)").legend(|(x, y)| {
                    PathElement::new(vec![(x, y), (x + 18, y)], Q_ZERO.stroke_width(2))
                });
            }
        }
        for (i, &e) in self.map.band_edges.iter().enumerate() {
            let e = e.to_degrees();
            let drawn = chart.draw_series(DashedLineSeries::new(
                vec![(e, -w), (e, w)],
                6,
                4,
                EDGE.stroke_width(1),
            ))?;
            if i == 0 {
                drawn.label("band edge mu_k |a| = D").legend(|(x, y)| {
                    PathElement::new(vec![(x, y), (x + 18, y)], EDGE.stroke_width(1))
                });
            }
        }
        let mut labelled = std::collections::HashSet::new();
        for t in self.trajectories {
            for (mode, pts) in trajectory_pieces(self.map, t) {
                let color = mode_color(mode);
                let drawn = chart.draw_series(LineSeries::new(pts, color.stroke_width(1)))?;
                if labelled.insert(mode) {
                    drawn
                        .label(format!("trajectory: {}", mode.name()))
                        .legend(move |(x, y)| {
                            PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2))
                        });
                }
            }
            if let Some(first) = t.samples.first() {
                chart.draw_series(std::iter::once(Circle::new(
                    (
                        win.wrap(first.state[THETA]).to_degrees(),
                        first.state[THETA_DOT],
                    ),
                    3,
                    BLACK.filled(),
                )))?;
            }
        }
        crate::report::plot::draw_legend(&mut chart, SeriesLabelPosition::UpperRight, 12)?;
        Ok(())
    }
}

impl Figure for RegionFigure<'_> {
    fn size(&self) -> (u32, u32) {
        (1200, 1100)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), PlotError> {
        let panels = root.split_evenly((2, 1));
        self.panel(&panels[0], 1.0)?;
        self.panel(&panels[1], -1.0)?;
        Ok(())
    }
}
