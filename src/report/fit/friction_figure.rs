//! The friction figure of `appell fit --friction-plot`: each slide's own friction
//! coefficient |F| / |N| against its sliding speed, both directions, with error bars, the
//! chosen law's curves and the compared laws' coefficients: the figure a tribologist puts in
//! a paper. A joint fit draws one colour per release.

use crate::fit::law::{FrictionLawResult, SlidePoint};
use crate::model::{FrictionLaw, Rig};
use crate::report::plot::{data_range, draw_side_legend, Figure, PlotError, Swatch};
use plotters::coord::Shift;
use plotters::prelude::*;

/// Colours of the two directions (one release) and of the releases (a joint fit).
const PLUS: RGBColor = RGBColor(215, 95, 0);
const MINUS: RGBColor = RGBColor(0, 90, 200);
const RELEASES: [RGBColor; 6] = [
    RGBColor(215, 95, 0),
    RGBColor(0, 90, 200),
    RGBColor(0, 140, 60),
    RGBColor(130, 60, 180),
    RGBColor(180, 30, 60),
    RGBColor(90, 90, 90),
];

/// The compared laws' dashed lines and names: dark enough to show over the chosen law's band.
const COMPARED: RGBColor = RGBColor(80, 80, 80);

/// `c` mixed with white, `share` of it kept: the chosen law drawn as a pale band, so that a
/// slide's speed range and error bar in the full colour show on it.
fn pale(c: RGBColor, share: f64) -> RGBColor {
    let mix = |v: u8| (255.0 - share * (255.0 - v as f64)).round() as u8;
    RGBColor(mix(c.0), mix(c.1), mix(c.2))
}

/// Width in pixels of the chosen law's band.
const LAW_WIDTH: u32 = 6;

/// Half-length in pixels of the caps on the error bars and the speed ranges.
const CAP: i32 = 5;

/// Radius in pixels of a slide's dot.
const DOT: i32 = 5;

/// A compared law's value as the figure shows it: its name, its model's mu_kinetic and where
/// it stands against the axis (`None` drawn, else "above" or "below").
type Compared<'a> = (&'a str, f64, Option<&'static str>);

/// The friction figure.
pub struct FrictionFigure<'a> {
    /// The fitted rig (its law and coefficients draw the curves).
    pub rig: &'a Rig<f64>,
    /// The friction section of the fit.
    pub law: &'a FrictionLawResult,
    /// Each release's name and slides (one release for a single fit).
    pub releases: Vec<(String, Vec<SlidePoint>)>,
}

impl FrictionFigure<'_> {
    /// The chosen law's coefficient sliding toward `s` at speed `v` at the static load
    /// (viscous rail friction as c_v v / ((m1 + m2) g)).
    fn law_mu(&self, s: f64, v: f64) -> f64 {
        let rig = self.rig;
        rig.friction_mu(s, v) + rig.viscous_friction * v / rig.static_load()
    }

    /// Whether the law is the same both ways (one curve drawn).
    fn symmetric(&self) -> bool {
        self.rig.friction_law != FrictionLaw::Direction
    }

    fn colour(&self, release: usize, direction: f64) -> RGBColor {
        if self.releases.len() == 1 {
            if direction > 0.0 {
                PLUS
            } else {
                MINUS
            }
        } else {
            RELEASES[release % RELEASES.len()]
        }
    }

    /// The legend's entries; the compared laws' dashed line only when one is drawn.
    fn entries(&self, compared_drawn: bool) -> Vec<(Swatch, String)> {
        let mut out = Vec::new();
        if self.releases.len() == 1 {
            out.push((
                Swatch::Dot(PLUS),
                "slides toward +x (each its own Coulomb fit, 95 % bars; speed range as |-|)".into(),
            ));
            out.push((Swatch::Dot(MINUS), "slides toward -x".into()));
        } else {
            for (i, (name, _)) in self.releases.iter().enumerate() {
                out.push((Swatch::Dot(self.colour(i, 1.0)), name.clone()));
            }
            out.push((
                Swatch::Ring(BLACK),
                "filled: toward +x, open: toward -x".into(),
            ));
        }
        let law = &self.law.chosen;
        let at = if self.rig.friction_law == FrictionLaw::Load {
            " at the static load"
        } else {
            ""
        };
        if self.symmetric() {
            out.push((
                Swatch::Line(pale(BLACK, 0.35), LAW_WIDTH),
                format!("{law} law (chosen){at}, both directions"),
            ));
        } else if self.releases.len() > 1 {
            // The releases have the colours: the two directions' bands are grey, named.
            out.push((
                Swatch::Line(pale(BLACK, 0.35), LAW_WIDTH),
                format!("{law} law (chosen), a band a direction (named at its end)"),
            ));
        } else {
            out.push((
                Swatch::Line(pale(PLUS, 0.45), LAW_WIDTH),
                format!("{law} law (chosen), sliding toward +x"),
            ));
            out.push((
                Swatch::Line(pale(MINUS, 0.45), LAW_WIDTH),
                format!("{law} law (chosen), sliding toward -x"),
            ));
        }
        out.push((
            Swatch::Square(BLACK),
            "the chosen law's value: the same fit on the law's own motion".into(),
        ));
        if compared_drawn {
            out.push((
                Swatch::Dashed(COMPARED),
                "compared laws (their models' mu_kinetic)".into(),
            ));
        }
        out
    }

    /// The side panel's numbers: the law, its parameters at the precision their errors give,
    /// each compared law's mu_kinetic and BIC (said off the axis when it is not drawn), and
    /// how many error bars hide under their dots.
    fn notes(&self, compared: &[Compared], hidden_bars: (usize, usize, f64)) -> Vec<String> {
        let mut notes = vec![format!("law chosen: {}", self.law.chosen)];
        for p in &self.law.parameters {
            notes.push(format!(
                "{} = {}",
                p.name,
                super::answer::value_pm(p.value, p.stderr)
            ));
        }
        for l in self.law.laws.iter().filter(|l| l.status == "fitted") {
            let Some(d) = l.delta_bic else { continue };
            let mu = match compared.iter().find(|c| c.0 == l.law) {
                Some((_, m, None)) => format!("mu_kinetic {m:.5} (dashed)"),
                Some((_, m, Some(side))) => format!("mu_kinetic {m:.5} ({side} the axis)"),
                None => "no mu_kinetic".to_owned(),
            };
            notes.push(format!("{}: {mu}, BIC {d:+.1} against the chosen", l.law));
        }
        let (hidden, total, widest) = hidden_bars;
        if hidden > 0 {
            notes.push(format!(
                "{hidden} of {total} slides' 95 % bars are shorter than their dot (half-widths up to {widest:.1e})"
            ));
        }
        notes
    }
}

impl Figure for FrictionFigure<'_> {
    fn size(&self) -> (u32, u32) {
        (1200, 700)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), PlotError> {
        let (chart_area, side) = root.split_horizontally(820);
        let points: Vec<&SlidePoint> = self.releases.iter().flat_map(|r| r.1.iter()).collect();
        let v_max = points
            .iter()
            .map(|p| p.speed[2])
            .fold(0.0, f64::max)
            .max(1e-3)
            * 1.1;
        let fitted: Vec<(&str, f64)> = self
            .law
            .laws
            .iter()
            .filter(|l| l.status == "fitted")
            .filter_map(|l| l.mu_kinetic.map(|m| (l.law, m)))
            .filter(|(_, m)| m.is_finite())
            .collect();
        let speeds: Vec<f64> = (0..=200).map(|i| v_max * i as f64 / 200.0).collect();
        let curve = |s: f64| -> Vec<(f64, f64)> {
            speeds
                .iter()
                .map(|&v| (v * 1e3, self.law_mu(s, v)))
                .collect()
        };
        let mut ys: Vec<f64> = points
            .iter()
            .flat_map(|p| [p.mu - 1.96 * p.stderr, p.mu + 1.96 * p.stderr, p.law_mu])
            .collect();
        ys.extend(curve(1.0).iter().chain(curve(-1.0).iter()).map(|p| p.1));
        // Compared laws far off the data (a model that failed to describe it) would squash
        // the axis: only those within the data's span are drawn, the others said in the side
        // panel with their values.
        let core = data_range(ys.iter().copied(), 0.15);
        let compared: Vec<Compared> = fitted
            .into_iter()
            .map(|(name, m)| {
                let side = if core.contains(&m) {
                    None
                } else if m > core.end {
                    Some("above")
                } else {
                    Some("below")
                };
                (name, m, side)
            })
            .collect();
        let shown: Vec<(&str, f64)> = compared
            .iter()
            .filter(|c| c.2.is_none())
            .map(|c| (c.0, c.1))
            .collect();
        let y = data_range(ys.into_iter().chain(shown.iter().map(|c| c.1)), 0.1);
        let mut chart = ChartBuilder::on(&chart_area)
            .margin(14)
            .caption("Rail friction against sliding speed", ("sans-serif", 20))
            .x_label_area_size(45)
            .y_label_area_size(70)
            .build_cartesian_2d(0.0..v_max * 1e3, y)?;
        chart
            .configure_mesh()
            .x_desc("sliding speed |x'| (mm/s)")
            .x_label_formatter(&|v| format!("{v:.0}"))
            .y_desc("friction coefficient |F| / |N|")
            .label_style(("sans-serif", 14))
            .axis_desc_style(("sans-serif", 16))
            .draw()?;
        // The chosen law first, as a pale band: what is drawn over it shows.
        if self.symmetric() {
            chart.draw_series(LineSeries::new(
                curve(1.0),
                pale(BLACK, 0.35).stroke_width(LAW_WIDTH),
            ))?;
        } else {
            let joint = self.releases.len() > 1;
            for (s, c, name) in [(1.0, PLUS, "toward +x"), (-1.0, MINUS, "toward -x")] {
                let band = if joint {
                    pale(BLACK, 0.35)
                } else {
                    pale(c, 0.45)
                };
                let line = curve(s);
                chart.draw_series(LineSeries::new(line.clone(), band.stroke_width(LAW_WIDTH)))?;
                if let (true, Some(&end)) = (joint, line.last()) {
                    chart.draw_series(std::iter::once(
                        EmptyElement::at(end)
                            + Text::new(
                                name,
                                (-70, -22),
                                ("sans-serif", 13).into_font().color(&COMPARED),
                            ),
                    ))?;
                }
            }
        }
        // The compared laws over the chosen one: a law that gives the same value shows as
        // dashes on its band.
        for (k, (name, m)) in shown.iter().enumerate() {
            chart.draw_series(DashedLineSeries::new(
                [(0.0, *m), (v_max * 1e3, *m)],
                8,
                5,
                COMPARED.stroke_width(2),
            ))?;
            chart.draw_series(std::iter::once(Text::new(
                name.to_string(),
                // Staggered, so that the names of laws with close values stay legible.
                (v_max * 1e3 * (0.88 - 0.14 * (k % 5) as f64), *m),
                ("sans-serif", 13).into_font().color(&COMPARED),
            )))?;
        }
        let mut hidden = (0, 0, 0.0_f64);
        for (i, (_, pts)) in self.releases.iter().enumerate() {
            for p in pts {
                // The law's square first, so that the slide's own dot shows inside it.
                chart.draw_series(std::iter::once(
                    EmptyElement::at((p.speed[0] * 1e3, p.law_mu))
                        + Rectangle::new([(-7, -7), (7, 7)], BLACK.stroke_width(2)),
                ))?;
                let c = self.colour(i, p.direction);
                let x = p.speed[0] * 1e3;
                let half = 1.96 * p.stderr;
                let (lo, hi) = (p.mu - half, p.mu + half);
                // The speed range: a line with end caps, in the full colour over the band.
                let (v0, v1) = (p.speed[1] * 1e3, p.speed[2] * 1e3);
                chart.draw_series(LineSeries::new([(v0, p.mu), (v1, p.mu)], c.stroke_width(2)))?;
                for v in [v0, v1] {
                    chart.draw_series(std::iter::once(
                        EmptyElement::at((v, p.mu))
                            + PathElement::new(vec![(0, -CAP), (0, CAP)], c.stroke_width(2)),
                    ))?;
                }
                // The 95 % bar, wide and capped.
                chart.draw_series(LineSeries::new([(x, lo), (x, hi)], c.stroke_width(3)))?;
                for v in [lo, hi] {
                    chart.draw_series(std::iter::once(
                        EmptyElement::at((x, v))
                            + PathElement::new(vec![(-CAP, 0), (CAP, 0)], c.stroke_width(2)),
                    ))?;
                }
                let bar_px =
                    (chart.backend_coord(&(x, lo)).1 - chart.backend_coord(&(x, hi)).1).abs();
                hidden.1 += 1;
                if bar_px < 2 * DOT {
                    hidden.0 += 1;
                    hidden.2 = hidden.2.max(half);
                }
                let filled = self.releases.len() == 1 || p.direction > 0.0;
                let style = if filled {
                    c.filled()
                } else {
                    c.stroke_width(2)
                };
                chart.draw_series(std::iter::once(Circle::new((x, p.mu), DOT, style)))?;
            }
        }
        let notes = self.notes(&compared, hidden);
        draw_side_legend(
            &side,
            "Friction law",
            &self.entries(!shown.is_empty()),
            &notes,
            44,
        )?;
        Ok(())
    }
}
