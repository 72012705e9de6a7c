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

    fn entries(&self) -> Vec<(Swatch, String)> {
        let mut out = Vec::new();
        if self.releases.len() == 1 {
            out.push((
                Swatch::Dot(PLUS),
                "slides toward +x (each its own Coulomb fit, 95 % bars; speed range)".into(),
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
                Swatch::Line(BLACK, 3),
                format!("{law} law (chosen){at}, both directions"),
            ));
        } else {
            out.push((
                Swatch::Line(PLUS, 3),
                format!("{law} law (chosen), sliding toward +x"),
            ));
            out.push((
                Swatch::Line(MINUS, 3),
                format!("{law} law (chosen), sliding toward -x"),
            ));
        }
        out.push((
            Swatch::Square(BLACK),
            "the chosen law's value: the same fit on the law's own motion".into(),
        ));
        out.push((
            Swatch::Dashed(RGBColor(120, 120, 120)),
            "compared laws (their models' mu_kinetic)".into(),
        ));
        out
    }

    fn notes(&self) -> Vec<String> {
        let mut notes = vec![format!("law chosen: {}", self.law.chosen)];
        for p in &self.law.parameters {
            notes.push(format!("{} = {:.5} +- {:.1e}", p.name, p.value, p.stderr));
        }
        for l in self.law.laws.iter().filter(|l| l.status == "fitted") {
            if let Some(d) = l.delta_bic {
                notes.push(format!("{}: BIC {:+.1} against the chosen", l.law, d));
            }
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
        let compared: Vec<(&str, f64)> = self
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
        // the axis: only those within the data's span are drawn.
        let core = data_range(ys.iter().copied(), 0.15);
        let shown: Vec<(&str, f64)> = compared
            .into_iter()
            .filter(|(_, m)| core.contains(m))
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
        for (k, (name, m)) in shown.iter().enumerate() {
            chart.draw_series(DashedLineSeries::new(
                [(0.0, *m), (v_max * 1e3, *m)],
                6,
                4,
                RGBColor(120, 120, 120).stroke_width(1),
            ))?;
            chart.draw_series(std::iter::once(Text::new(
                name.to_string(),
                // Staggered, so that the names of laws with close values stay legible.
                (v_max * 1e3 * (0.88 - 0.14 * (k % 5) as f64), *m),
                ("sans-serif", 13).into_font().color(&RGBColor(90, 90, 90)),
            )))?;
        }
        if self.symmetric() {
            chart.draw_series(LineSeries::new(curve(1.0), BLACK.stroke_width(3)))?;
        } else {
            for (s, c) in [(1.0, PLUS), (-1.0, MINUS)] {
                chart.draw_series(LineSeries::new(curve(s), c.stroke_width(3)))?;
            }
        }
        for (i, (_, pts)) in self.releases.iter().enumerate() {
            for p in pts {
                // The law's square first, so that the slide's own dot shows inside it.
                chart.draw_series(std::iter::once(
                    EmptyElement::at((p.speed[0] * 1e3, p.law_mu))
                        + Rectangle::new([(-7, -7), (7, 7)], BLACK.stroke_width(2)),
                ))?;
                let c = self.colour(i, p.direction);
                let x = p.speed[0] * 1e3;
                let (lo, hi) = (p.mu - 1.96 * p.stderr, p.mu + 1.96 * p.stderr);
                chart.draw_series(LineSeries::new([(x, lo), (x, hi)], c.stroke_width(2)))?;
                chart.draw_series(LineSeries::new(
                    [(p.speed[1] * 1e3, p.mu), (p.speed[2] * 1e3, p.mu)],
                    c.mix(0.6).stroke_width(1),
                ))?;
                let filled = self.releases.len() == 1 || p.direction > 0.0;
                let style = if filled {
                    c.filled()
                } else {
                    c.stroke_width(2)
                };
                chart.draw_series(std::iter::once(Circle::new((x, p.mu), 5, style)))?;
            }
        }
        draw_side_legend(&side, "Friction law", &self.entries(), &self.notes(), 32)?;
        Ok(())
    }
}
