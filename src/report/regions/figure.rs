//! The region figure of `appell regions`: the stick region and the paradox band's solution
//! counts shaded in the (theta, theta') plane, with the stick boundary, the curves where N
//! changes sign, and the phase portrait's trajectories and releases over them.

use super::Trajectory;
use crate::model::regions::{
    band_edges, in_paradox_band, slide_count_intervals, stick_intervals, Curve, LawBand,
    PlaneWindow, RegionMap,
};
use crate::model::{Direction, FrictionLaw, Mode, Rig, THETA, THETA_DOT};
use crate::numbers::plain;
use crate::report::plot::{draw_side_legend, side_legend_height, Figure, PlotError, Swatch};
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::f64::consts::PI;

/// Colour of a mode in the phase portraits.
pub fn mode_color(mode: Mode) -> RGBColor {
    match mode {
        Mode::Stick => RGBColor(20, 20, 20),
        Mode::Slide(crate::model::Direction::Positive) => RGBColor(220, 90, 0),
        Mode::Slide(crate::model::Direction::Negative) => RGBColor(0, 110, 200),
    }
}

// Opaque fills, so that overlapping columns draw no seams and each region shows exactly the
// colour of its legend swatch.
const STICK_FILL: RGBColor = RGBColor(205, 235, 205);
const NONE_FILL: RGBColor = RGBColor(248, 190, 190);
const TWO_FILL: RGBColor = RGBColor(195, 205, 248);
const BOUNDARY: RGBColor = RGBColor(0, 120, 0);
const Q_ZERO: RGBColor = RGBColor(150, 0, 150);
const EDGE: RGBColor = RGBColor(90, 90, 90);
/// The band edges of a law's second and third coefficients (Stribeck's mu_k; the load law's
/// static and largest loads), after [`EDGE`].
const EDGES: [RGBColor; 3] = [EDGE, RGBColor(215, 120, 0), RGBColor(0, 150, 170)];
const OTHER_SLIDE: RGBColor = RGBColor(175, 175, 175);
const JUMP: RGBColor = RGBColor(200, 0, 0);
const RELEASE_BOX: RGBColor = RGBColor(160, 110, 0);

/// Width of the legend column beside the panels (px), and its text width (characters).
const LEGEND_WIDTH: u32 = 360;
const LEGEND_WRAP: usize = 42;

/// The window of the region figures: theta from -90 to 270 degrees, so that the hanging
/// position (90) is in the middle and releases on either side (e.g. -20 deg) keep their sign;
/// |theta'| up to 3 sqrt(g / l) as in [`PlaneWindow::for_rig`].
pub fn figure_window(rig: &Rig<f64>) -> PlaneWindow {
    PlaneWindow {
        theta_min: -PI / 2.0,
        theta_max: 1.5 * PI,
        ..PlaneWindow::for_rig(rig)
    }
}

/// The region figure in the (theta, theta') plane: the stick region shaded and outlined, the
/// curve Q = 0, the paradox band's edges and regions where sliding in direction s has no or
/// two solutions, and the phase-portrait trajectories coloured by mode. With a paradox band
/// there is one panel per slide direction (s = +1 above, s = -1 below); without one, nothing
/// in the plane depends on s and one panel is drawn. The legend and the rig's key numbers sit
/// in a column of their own beside the panels.
pub struct RegionFigure<'a> {
    /// The rig.
    pub rig: &'a Rig<f64>,
    /// Its region map (curves and window; [`figure_window`] is the one to use).
    pub map: &'a RegionMap,
    /// Trajectories to overlay.
    pub trajectories: &'a [Trajectory],
    /// A label per trajectory drawn at its start (e.g. `#1`; empty: none).
    pub labels: Vec<String>,
    /// Lines of key numbers added under the rig's in the legend column.
    pub notes: Vec<String>,
    /// Draw the first trajectory thicker than the others (the plan's best proposal).
    pub emphasise_first: bool,
    /// The releases a plan allows, ranges of (theta rad, theta' rad/s): drawn as a dashed box
    /// (clipped to the window). `None`: no box.
    pub release_box: Option<[[f64; 2]; 2]>,
}

impl<'a> RegionFigure<'a> {
    /// The figure of `appell regions`: no labels, no extra notes.
    pub fn new(rig: &'a Rig<f64>, map: &'a RegionMap, trajectories: &'a [Trajectory]) -> Self {
        RegionFigure {
            rig,
            map,
            trajectories,
            labels: Vec::new(),
            notes: Vec::new(),
            emphasise_first: false,
            release_box: None,
        }
    }

    /// Two panels (one per slide direction) when the sliding model's solution count depends on
    /// s somewhere in the plane, that is when there is a paradox band.
    pub fn two_panels(&self) -> bool {
        self.map.summary.paradox_possible()
            || self
                .map
                .law_bands
                .iter()
                .any(|b| !b.paradox_band_deg.is_empty())
    }

    /// A law band's coefficient in words, e.g. `sliding toward +x: mu_k+ = 0.47`.
    fn band_words(&self, b: &LawBand) -> String {
        let what = match (self.rig.friction_law, b.label) {
            (FrictionLaw::Coulomb, _) => "mu_k".to_owned(),
            (FrictionLaw::Direction, d) => format!("sliding toward {d}: mu_k{}", &d[..1]),
            (FrictionLaw::Stribeck, "at rest") => "at rest: mu_s".to_owned(),
            (FrictionLaw::Stribeck, _) => "sliding fast: mu_k".to_owned(),
            (FrictionLaw::Load, label) => format!(
                "{label} |N| = {} N: mu",
                plain(b.normal_load.unwrap_or(f64::NAN))
            ),
        };
        format!("{what} = {}", plain(b.mu))
    }

    /// The law bands with their edge colours, those that open a band only.
    fn drawn_bands(&self) -> Vec<(&LawBand, RGBColor)> {
        self.map
            .law_bands
            .iter()
            .enumerate()
            .filter(|(_, b)| !b.paradox_band_deg.is_empty())
            .map(|(i, b)| {
                // The direction law's two bands are in panels of their own: one colour.
                let k = if self.rig.friction_law == FrictionLaw::Direction {
                    0
                } else {
                    i.min(EDGES.len() - 1)
                };
                (b, EDGES[k])
            })
            .collect()
    }

    /// The key numbers printed beside the panels (a fitted rig's values to 7 digits, not 17).
    pub fn key_numbers(&self) -> Vec<String> {
        let s = &self.map.summary;
        let mut out = match self.rig.pendulum {
            Some(_) => vec![
                format!(
                    "rigid pendulum: r' = {:.3}, L = {:.4} m, l = {} m, {}",
                    s.mass_ratio,
                    self.rig.rod_length,
                    plain(self.rig.marker_length),
                    self.friction_words()
                ),
                format!(
                    "mu* = 2 sqrt(r' (1 + r')) = {:.3}, theta* = {:.1} deg",
                    s.mu_critical, s.theta_critical_deg
                ),
            ],
            None => vec![
                format!(
                    "m1/m2 = {:.3}, l = {} m, {}",
                    s.mass_ratio,
                    plain(self.rig.rod_length),
                    self.friction_words()
                ),
                format!(
                    "mu* = 2 sqrt(r (1 + r)) = {:.3}, theta* = {:.1} deg",
                    s.mu_critical, s.theta_critical_deg
                ),
            ],
        };
        if let Some(m) = s.point_rig_mu_critical {
            out.push(format!("point rig with the same masses: mu* = {m:.3}"));
        }
        if self.rig.rail_tilt != 0.0 {
            out.push(format!(
                "rail tilt {:.2} deg (+x downhill): the plane is not mirror-symmetric",
                self.rig.rail_tilt.to_degrees()
            ));
        }
        if self.rig.friction_law == FrictionLaw::Load {
            out.push(
                "load law: mu = mu_k (|N| / N_0)^(n - 1) at the stuck normal force |b| a swing meets with the bob below the rail in this window (smallest and largest) and at N_0 = (m1 + m2) g; shading: the sign rule at N_0"
                    .to_owned(),
            );
        }
        if self.two_panels() {
            for b in &self.map.law_bands {
                let band = if b.paradox_band_deg.is_empty() {
                    "no band (mu <= mu*)".to_owned()
                } else {
                    let parts: Vec<String> = b
                        .paradox_band_deg
                        .iter()
                        .map(|[lo, hi]| format!("{lo:.1}..{hi:.1}"))
                        .collect();
                    format!("paradox band {} deg", parts.join(" and "))
                };
                out.push(format!("{}: {band}", self.band_words(b)));
            }
            out.push(
                "(each band: mu |a| > D, the same |tan theta| below 0 and above 180 deg)"
                    .to_owned(),
            );
            if self.rig.rail_tilt == 0.0 && self.rig.friction_law != FrictionLaw::Direction {
                out.push(
                    "level rig: the s = -1 panel is the s = +1 panel mirrored, (theta, theta') -> (180 deg - theta, -theta')"
                        .to_owned(),
                );
            }
        } else {
            out.push(
                "no paradox band (the largest sliding mu <= mu*): sliding has exactly one solution everywhere in either direction, so one panel serves s = +1 and s = -1"
                    .to_owned(),
            );
        }
        out
    }

    /// The friction law's coefficients, numbers at seven significant digits.
    fn friction_words(&self) -> String {
        let r = self.rig;
        let (k, st) = (plain(r.mu_kinetic), plain(r.mu_static));
        match r.friction_law {
            FrictionLaw::Coulomb => format!("mu_k = {k}, mu_s = {st}"),
            FrictionLaw::Stribeck => format!(
                "Stribeck: mu_k = {k}, mu_s = {st}, v_s = {} m/s",
                plain(r.stribeck_velocity)
            ),
            FrictionLaw::Direction => format!(
                "direction law: mu_k+ = {}, mu_k- = {}, mu_s+ = {}, mu_s- = {}",
                plain(r.friction_mu(1.0, 0.0)),
                plain(r.friction_mu(-1.0, 0.0)),
                plain(r.static_mu(1.0)),
                plain(r.static_mu(-1.0))
            ),
            FrictionLaw::Load => format!(
                "load law: mu_k = {k}, mu_s = {st} at N_0 = {} N, n = {}",
                plain(r.static_load()),
                plain(r.load_exponent)
            ),
        }
    }

    /// The rig's key numbers, then the figure's own notes.
    fn all_notes(&self) -> Vec<String> {
        let mut notes = self.key_numbers();
        notes.extend(self.notes.iter().cloned());
        notes
    }

    fn legend_entries(&self) -> Vec<(Swatch, String)> {
        let mut out = vec![
            (
                Swatch::Fill(STICK_FILL),
                "stick region |c| <= mu_s |b| (pendulum model holds)".to_owned(),
            ),
            (
                Swatch::Line(BOUNDARY, 2),
                "stick boundary |c| = mu_s |b|: branches c = +mu_s b and c = -mu_s b (two close lines bound a thin stick strip)".to_owned(),
            ),
        ];
        if !self.map.q_zero.is_empty() {
            out.push((
                Swatch::Line(Q_ZERO, 2),
                "Q = 0: the rail reaction N changes sign while sliding".to_owned(),
            ));
        }
        if self.map.summary.paradox_possible() {
            out.push((
                Swatch::Fill(NONE_FILL),
                "sliding in direction s: no solution".to_owned(),
            ));
            out.push((
                Swatch::Fill(TWO_FILL),
                "sliding in direction s: two solutions".to_owned(),
            ));
        }
        if self.two_panels() {
            for (b, color) in self.drawn_bands() {
                out.push((
                    Swatch::Dashed(color),
                    format!("band edge mu |a| = D, {}", self.band_words(b)),
                ));
            }
        }
        if self.release_box.is_some() {
            out.push((
                Swatch::Dashed(RELEASE_BOX),
                "allowed releases: the plan's theta and theta' ranges".to_owned(),
            ));
        }
        if !self.trajectories.is_empty() {
            out.push((
                Swatch::Line(mode_color(Mode::Stick), 2),
                "trajectory: stick".to_owned(),
            ));
            out.push((
                Swatch::Line(mode_color(Mode::Slide(Direction::Positive)), 2),
                "trajectory: slide+ (x' > 0)".to_owned(),
            ));
            out.push((
                Swatch::Line(mode_color(Mode::Slide(Direction::Negative)), 2),
                "trajectory: slide- (x' < 0)".to_owned(),
            ));
            if self.two_panels() {
                out.push((
                    Swatch::Line(OTHER_SLIDE, 2),
                    "trajectory sliding in the other panel's direction".to_owned(),
                ));
            }
            out.push((
                Swatch::Dot(BLACK),
                "release (start of a trajectory)".to_owned(),
            ));
            if self
                .trajectories
                .iter()
                .any(|t| !t.impulse_times.is_empty())
            {
                out.push((
                    Swatch::Dashed(JUMP),
                    "impulsive stop: x' -> 0, theta' jumps".to_owned(),
                ));
            }
        }
        out
    }
}

/// The (theta in degrees, theta') plane of a panel.
type Plane<'a, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// A trajectory cut for drawing: pieces of one mode, and the jumps of impulsive stops.
struct Pieces {
    /// Points in degrees and rad/s with their mode; consecutive pieces share their switching
    /// sample.
    lines: Vec<(Mode, Vec<(f64, f64)>)>,
    /// (before, after) of each impulsive stop, drawn as a dashed jump, not as motion.
    jumps: Vec<[(f64, f64); 2]>,
}

/// Points of a trajectory in degrees, wrapped into the window and split where the wrap jumps,
/// the mode changes or an impulsive stop makes theta' jump.
fn trajectory_pieces(map: &RegionMap, t: &Trajectory) -> Pieces {
    let win = &map.window;
    let mut out = Pieces {
        lines: Vec::new(),
        jumps: Vec::new(),
    };
    let mut prev: Option<(f64, f64, f64)> = None;
    for s in &t.samples {
        let p = (
            win.wrap(s.state[THETA]).to_degrees(),
            s.state[THETA_DOT].clamp(-win.w_max, win.w_max),
        );
        let wrapped = prev.is_some_and(|q| (p.0 - q.0).abs() > 180.0);
        let impulsive =
            prev.is_some_and(|q| t.impulse_times.iter().any(|&te| q.2 <= te && te <= s.t));
        if let (Some(q), true, false) = (prev, impulsive, wrapped) {
            out.jumps.push([(q.0, q.1), p]);
        }
        let joined = !(wrapped || impulsive);
        match out.lines.last_mut() {
            Some((m, pts)) if *m == s.mode && joined => pts.push(p),
            _ => {
                let mut pts = Vec::new();
                if let (Some(q), true) = (prev, joined) {
                    pts.push((q.0, q.1));
                }
                pts.push(p);
                out.lines.push((s.mode, pts));
            }
        }
        prev = Some((p.0, p.1, s.t));
    }
    out
}

impl RegionFigure<'_> {
    /// One panel: `s` is the slide direction whose solution counts are shaded (`None`: the
    /// single panel of a rig without a paradox band).
    fn panel<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        s: Option<f64>,
    ) -> Result<(), PlotError> {
        let win = &self.map.window;
        let (t0, t1) = (win.theta_min.to_degrees(), win.theta_max.to_degrees());
        let w = win.w_max;
        let caption = match s {
            Some(s) if s > 0.0 => "slide direction s = +1 (x' > 0)".to_owned(),
            Some(_) => "slide direction s = -1 (x' < 0)".to_owned(),
            None => "stick region and phase portraits (either slide direction)".to_owned(),
        };
        let mut chart = ChartBuilder::on(area)
            .caption(caption, ("sans-serif", 18))
            .margin(10)
            .x_label_area_size(45)
            .y_label_area_size(60)
            .build_cartesian_2d(t0..t1, -w..w)?;
        self.shade_regions(&mut chart, s)?;
        chart
            .configure_mesh()
            .x_desc("theta [deg]   (90 = hanging, 0 and 180 = rod along the rail, 270 = bob above the slider)")
            .y_desc("theta' [rad/s]")
            .label_style(("sans-serif", 14))
            .axis_desc_style(("sans-serif", 15))
            .x_labels(13)
            .y_labels(9)
            .x_label_formatter(&|v| format!("{v:.0}"))
            .y_label_formatter(&|v| format!("{v:.0}"))
            .light_line_style(TRANSPARENT)
            .bold_line_style(BLACK.mix(0.12))
            .draw()?;
        self.draw_curves(&mut chart, s)?;
        self.draw_release_box(&mut chart)?;
        self.draw_trajectories(&mut chart, s)?;
        self.draw_releases(&mut chart)
    }

    /// The plan's release box, dashed, clipped to the window.
    fn draw_release_box<DB: DrawingBackend>(
        &self,
        chart: &mut Plane<'_, DB>,
    ) -> Result<(), PlotError> {
        let Some([theta, theta_dot]) = self.release_box else {
            return Ok(());
        };
        let win = &self.map.window;
        let deg = |t: f64| t.clamp(win.theta_min, win.theta_max).to_degrees();
        let w = |v: f64| v.clamp(-win.w_max, win.w_max);
        let (t0, t1) = (deg(theta[0]), deg(theta[1]));
        let (w0, w1) = (w(theta_dot[0]), w(theta_dot[1]));
        let corners = vec![(t0, w0), (t1, w0), (t1, w1), (t0, w1), (t0, w0)];
        chart.draw_series(DashedLineSeries::new(
            corners,
            8,
            5,
            RELEASE_BOX.stroke_width(2),
        ))?;
        Ok(())
    }

    /// The shaded regions, one column per degree, exact in theta' within each column; the
    /// paradox regions of slide direction `s` are drawn over the stick region, whose outline
    /// stays visible on top.
    fn shade_regions<DB: DrawingBackend>(
        &self,
        chart: &mut Plane<'_, DB>,
        s: Option<f64>,
    ) -> Result<(), PlotError> {
        let win = &self.map.window;
        let (t0, t1) = (win.theta_min.to_degrees(), win.theta_max.to_degrees());
        let w = win.w_max;
        let columns = (t1 - t0).round().max(1.0) as usize;
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
            if let Some(s) = s {
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
        }
        for (rects, color) in [
            (stick_rects, STICK_FILL),
            (none_rects, NONE_FILL),
            (two_rects, TWO_FILL),
        ] {
            chart.draw_series(rects.into_iter().map(|r| Rectangle::new(r, color.filled())))?;
        }
        Ok(())
    }

    /// The band edges (with a slide direction `s`), the curves where Q = 0 and the stick
    /// boundary.
    fn draw_curves<DB: DrawingBackend>(
        &self,
        chart: &mut Plane<'_, DB>,
        s: Option<f64>,
    ) -> Result<(), PlotError> {
        let w = self.map.window.w_max;
        let to_deg = |c: &Curve| -> Vec<(f64, f64)> {
            c.points.iter().map(|p| (p[0].to_degrees(), p[1])).collect()
        };
        let win = &self.map.window;
        for (b, color) in self.drawn_bands() {
            if !s.is_none_or(|s| b.applies_to(s)) {
                continue;
            }
            let edges = band_edges(self.rig.mass_ratio(), b.mu, win.theta_min, win.theta_max);
            for e in edges {
                let e = e.to_degrees();
                chart.draw_series(DashedLineSeries::new(
                    vec![(e, -w), (e, w)],
                    6,
                    4,
                    color.stroke_width(if color == EDGE { 1 } else { 2 }),
                ))?;
            }
        }
        for c in &self.map.q_zero {
            chart.draw_series(LineSeries::new(to_deg(c), Q_ZERO.stroke_width(2)))?;
        }
        for c in &self.map.stick_boundary {
            chart.draw_series(LineSeries::new(to_deg(c), BOUNDARY.stroke_width(2)))?;
        }
        Ok(())
    }

    /// The trajectories, piece by piece in their modes' colours (a slide against direction `s`
    /// in grey), with the jumps of impulsive stops dashed.
    fn draw_trajectories<DB: DrawingBackend>(
        &self,
        chart: &mut Plane<'_, DB>,
        s: Option<f64>,
    ) -> Result<(), PlotError> {
        for (k, t) in self.trajectories.iter().enumerate() {
            let width = if self.emphasise_first && k > 0 { 1 } else { 2 };
            let pieces = trajectory_pieces(self.map, t);
            for (mode, pts) in pieces.lines {
                let color = match (s, mode) {
                    (Some(s), Mode::Slide(dir)) if dir.sign() != s => OTHER_SLIDE,
                    _ => mode_color(mode),
                };
                chart.draw_series(LineSeries::new(pts, color.stroke_width(width)))?;
            }
            for [a, b] in pieces.jumps {
                chart.draw_series(DashedLineSeries::new(
                    vec![a, b],
                    4,
                    3,
                    JUMP.stroke_width(2),
                ))?;
            }
        }
        Ok(())
    }

    /// Release dots and labels last, so no curve hides them. Labels are stacked in a column
    /// left of the leftmost labelled release (right of the rightmost when there is no room),
    /// in the order of their dots from top to bottom so that the leaders do not cross, each
    /// joined to its dot by a thin leader line, so releases a few pixels apart keep readable
    /// labels.
    fn draw_releases<DB: DrawingBackend>(
        &self,
        chart: &mut Plane<'_, DB>,
    ) -> Result<(), PlotError> {
        let win = &self.map.window;
        let w = win.w_max;
        let mut labelled: Vec<(&str, (i32, i32))> = Vec::new();
        for (k, t) in self.trajectories.iter().enumerate() {
            let Some(first) = t.samples.first() else {
                continue;
            };
            let p = (
                win.wrap(first.state[THETA]).to_degrees(),
                first.state[THETA_DOT].clamp(-w, w),
            );
            chart.draw_series(std::iter::once(Circle::new(p, 4, BLACK.filled())))?;
            if let Some(label) = self.labels.get(k).filter(|l| !l.is_empty()) {
                labelled.push((label, chart.backend_coord(&p)));
            }
        }
        labelled.sort_by_key(|(_, dot)| dot.1);
        if !labelled.is_empty() {
            let plot = chart.plotting_area();
            let (x_px, y_px) = plot.get_pixel_range();
            let step = 19;
            let n = labelled.len() as i32;
            let mean_y = labelled.iter().map(|l| l.1 .1).sum::<i32>() / n;
            let top = (mean_y - step * (n - 1) / 2)
                .clamp(y_px.start + 4, (y_px.end - step * n).max(y_px.start + 4));
            let min_x = labelled.iter().map(|l| l.1 .0).min().unwrap_or(0);
            let max_x = labelled.iter().map(|l| l.1 .0).max().unwrap_or(0);
            let left = min_x - 70 > x_px.start;
            let font = ("sans-serif", 16).into_font().color(&BLACK);
            let root = plot.strip_coord_spec();
            for (i, (label, dot)) in labelled.iter().enumerate() {
                let y = top + step * i as i32;
                let (text_x, anchor_x) = if left {
                    (min_x - 66, min_x - 32)
                } else {
                    (max_x + 34, max_x + 30)
                };
                let rel = |(x, y): (i32, i32)| (x - x_px.start, y - y_px.start);
                root.draw(&PathElement::new(
                    vec![rel((anchor_x, y)), rel(*dot)],
                    BLACK.mix(0.5).stroke_width(1),
                ))?;
                root.draw(&Text::new(
                    label.to_string(),
                    rel((text_x, y - 8)),
                    font.clone(),
                ))?;
            }
        }
        Ok(())
    }
}

impl Figure for RegionFigure<'_> {
    fn size(&self) -> (u32, u32) {
        let panels = if self.two_panels() { 1100 } else { 650 };
        let legend = side_legend_height(&self.legend_entries(), &self.all_notes(), LEGEND_WRAP);
        (1400, panels.max(legend))
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), PlotError> {
        let (width, _) = root.dim_in_pixel();
        let (plots, side) = root.split_horizontally(width.saturating_sub(LEGEND_WIDTH));
        if self.two_panels() {
            let panels = plots.split_evenly((2, 1));
            self.panel(&panels[0], Some(1.0))?;
            self.panel(&panels[1], Some(-1.0))?;
        } else {
            self.panel(&plots, None)?;
        }
        draw_side_legend(
            &side,
            "Legend",
            &self.legend_entries(),
            &self.all_notes(),
            LEGEND_WRAP,
        )
    }
}
