//! Output of `appell fit`: the readable report, the JSON object and the figure (data, fit,
//! residuals and mode bands).

use super::plot::{data_range, Figure, PlotError};
use crate::fit::{Estimate, FitReport, Observations, Param, StaticResult};
use crate::model::{markers, Mode};
use crate::sim::{simulate, Options, Request};
use plotters::coord::Shift;
use plotters::prelude::*;
use serde_json::{json, Value};
use std::fmt::Write as _;

fn estimate_json(e: &Estimate) -> Value {
    json!({"value": e.value, "stderr": e.stderr, "ci95": e.ci95})
}

fn get(rep: &FitReport, p: Param) -> f64 {
    rep.params.iter().find(|(q, _)| *q == p).map_or_else(
        || match p {
            Param::X => rep.initial[0],
            Param::Theta => rep.initial[1],
            Param::XDot => rep.initial[2],
            Param::ThetaDot => rep.initial[3],
            Param::MuKinetic => rep.rig.mu_kinetic,
            Param::MuStatic => rep.rig.mu_static,
            Param::RodLength => rep.rig.rod_length,
        },
        |(_, e)| e.value,
    )
}

/// The JSON object of `appell fit --json` (one line per recording for a directory).
pub fn fit_json(rep: &FitReport) -> Value {
    let mu_static = match &rep.mu_static {
        StaticResult::Estimated(e) => estimate_json(e),
        StaticResult::LowerBound(b) => json!({"lower_bound": b}),
        StaticResult::NotIdentifiable => json!({"identifiable": false}),
    };
    let k = rep.params.iter().position(|(p, _)| *p == Param::MuKinetic);
    let correlations: serde_json::Map<String, Value> = match k {
        Some(k) => rep
            .params
            .iter()
            .enumerate()
            .filter(|(i, _)| *i != k)
            .map(|(i, (p, _))| (p.name().to_owned(), json!(rep.correlation[(k, i)])))
            .collect(),
        None => Default::default(),
    };
    json!({
        "mu_kinetic": rep.mu_kinetic.as_ref().map(estimate_json),
        "mu_static": mu_static,
        "initial": {
            "x": get(rep, Param::X), "theta": get(rep, Param::Theta),
            "x_dot": get(rep, Param::XDot), "theta_dot": get(rep, Param::ThetaDot),
        },
        "parameters": rep.params.iter().map(|(p, e)| (p.name().to_owned(), estimate_json(e))).collect::<serde_json::Map<_, _>>(),
        "correlation_with_mu_kinetic": correlations,
        "rms_residual_m": rep.rms_residual_m,
        "rms_residual_per_marker_m": {"slider": rep.rms_per_marker_m[0], "bob": rep.rms_per_marker_m[1]},
        "noise_m": {"slider": rep.noise_m[0], "bob": rep.noise_m[1]},
        "reduced_chi2": rep.reduced_chi2,
        "residual_lag1_autocorrelation": rep.residual_autocorrelation,
        "identifiable": rep.identifiable,
        "events": rep.events.iter().map(|e| json!({"t": e.t, "from": e.from.name(), "to": e.to.name(), "kind": e.kind})).collect::<Vec<_>>(),
        "starts": rep.starts,
        "n_residuals": rep.n_residuals,
        "warnings": rep.warnings,
    })
}

fn line(s: &mut String, name: &str, e: &Estimate, unit: &str) {
    let _ = writeln!(
        s,
        "  {name:<12} {:>14.8} +- {:<11.3e} 95% [{:.8}, {:.8}] {unit}",
        e.value, e.stderr, e.ci95[0], e.ci95[1]
    );
}

/// The readable report of `appell fit`.
pub fn fit_text(rep: &FitReport) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "fitted parameters (value +- standard error, 95% interval: for mu from its profile, unless --no-profile):"
    );
    for (p, e) in &rep.params {
        let unit = match p {
            Param::X | Param::RodLength => "m",
            Param::Theta => "rad",
            Param::XDot => "m/s",
            Param::ThetaDot => "rad/s",
            _ => "",
        };
        line(&mut s, p.name(), e, unit);
    }
    match (&rep.mu_kinetic, &rep.mu_static) {
        (None, StaticResult::LowerBound(b)) => {
            let _ = writeln!(
                s,
                "  mu_kinetic   not identifiable (the slider never slides)"
            );
            let _ = writeln!(
                s,
                "  mu_static    >= {b:.5} (largest |F|/|N| the stuck slider needed)"
            );
        }
        (_, StaticResult::NotIdentifiable) => {
            let _ = writeln!(
                s,
                "  mu_static    not identifiable (tied to mu_kinetic for the fit)"
            );
        }
        _ => {}
    }
    if let Some(k) = rep.params.iter().position(|(p, _)| *p == Param::MuKinetic) {
        let corr: Vec<String> = rep
            .params
            .iter()
            .enumerate()
            .filter(|(i, _)| *i != k)
            .map(|(i, (p, _))| format!("{} {:+.3}", p.name(), rep.correlation[(k, i)]))
            .collect();
        let _ = writeln!(s, "correlation of mu_kinetic with: {}", corr.join(", "));
    }
    let _ = writeln!(
        s,
        "residual RMS {:.3e} m (slider {:.3e}, bob {:.3e}); reduced chi2 {:.3}; lag-1 autocorrelation {:.3}; {} residuals",
        rep.rms_residual_m, rep.rms_per_marker_m[0], rep.rms_per_marker_m[1], rep.reduced_chi2, rep.residual_autocorrelation, rep.n_residuals
    );
    let _ = writeln!(s, "event timeline of the fit:");
    for e in &rep.events {
        let _ = writeln!(s, "  {:>12.6} s  {:<7} -> {}", e.t, e.from.name(), e.to);
    }
    for w in &rep.warnings {
        let _ = writeln!(s, "warning: {w}");
    }
    s
}

/// The fit's figure: slider x and bob position, data and fit, residuals, mode bands.
pub struct FitFigure<'a> {
    /// The recording.
    pub obs: &'a Observations,
    /// The fit.
    pub report: &'a FitReport,
}

/// Points of one coordinate: data, fit and residuals, each (t, value).
type Panel = (Vec<(f64, f64)>, Vec<(f64, f64)>, Vec<(f64, f64)>);

fn mode_color(m: Mode) -> RGBColor {
    match m {
        Mode::Stick => RGBColor(230, 230, 230),
        Mode::Slide(crate::model::Direction::Positive) => RGBColor(255, 224, 204),
        Mode::Slide(crate::model::Direction::Negative) => RGBColor(204, 224, 255),
    }
}

impl Figure for FitFigure<'_> {
    fn size(&self) -> (u32, u32) {
        (1100, 1000)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), PlotError> {
        let rep = self.report;
        let t0 = self.obs.times[0];
        let times: Vec<f64> = self.obs.times.iter().map(|t| t - t0).collect();
        let t_end = *times.last().unwrap_or(&1.0);
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
            },
        )
        .map_err(|e| PlotError::Draw(e.to_string()))?;
        let pred: Vec<(f64, [f64; 4], Mode)> = sol
            .samples
            .iter()
            .map(|s| (s.t, markers(&rep.rig, &s.state), s.mode))
            .collect();
        let panels = root.split_evenly((3, 1));
        let series = |k: usize| -> Panel {
            let mut data = Vec::new();
            let mut fit = Vec::new();
            let mut resid = Vec::new();
            for (i, &t) in times.iter().enumerate() {
                let obs = if k < 2 {
                    self.obs.slider[i].map(|p| p[k])
                } else {
                    self.obs.bob[i].map(|p| p[k - 2])
                };
                if let Some(o) = obs {
                    data.push((t, o));
                    if let Some(p) = pred.get(i) {
                        resid.push((t, o - p.1[k]));
                    }
                }
                if let Some(p) = pred.get(i) {
                    fit.push((t, p.1[k]));
                }
            }
            (data, fit, resid)
        };
        let bands = |chart_top: f64, chart_bot: f64| -> Vec<Rectangle<(f64, f64)>> {
            let mut out = Vec::new();
            let mut start = 0;
            for i in 1..=pred.len() {
                if i == pred.len() || pred[i].2 != pred[start].2 {
                    let t1 = if i == pred.len() { t_end } else { pred[i].0 };
                    out.push(Rectangle::new(
                        [(pred[start].0, chart_bot), (t1, chart_top)],
                        mode_color(pred[start].2).filled(),
                    ));
                    start = i;
                }
            }
            out
        };
        let titles = [
            "slider x [m] (bands: grey stick, orange slide+, blue slide-)",
            "bob x and y [m]",
            "residuals [mm]",
        ];
        for (panel, title) in panels.iter().zip(titles) {
            let (data_sets, is_resid): (Vec<usize>, bool) = match title.chars().next() {
                Some('s') => (vec![0], false),
                Some('b') => (vec![2, 3], false),
                _ => (vec![0, 2, 3], true),
            };
            let all: Vec<Panel> = data_sets.iter().map(|&k| series(k)).collect();
            let scale = if is_resid { 1e3 } else { 1.0 };
            let ys = all
                .iter()
                .flat_map(|(d, f, r)| {
                    if is_resid {
                        r.clone()
                    } else {
                        d.iter().chain(f).cloned().collect()
                    }
                })
                .map(|p| p.1 * scale);
            let yr = data_range(ys, 0.05);
            let mut chart = ChartBuilder::on(panel)
                .caption(title, ("sans-serif", 18))
                .margin(8)
                .x_label_area_size(30)
                .y_label_area_size(70)
                .build_cartesian_2d(0.0..t_end, yr.clone())?;
            chart.configure_mesh().x_desc("t [s]").draw()?;
            chart.draw_series(bands(yr.end, yr.start))?;
            let colors = [
                RGBColor(0, 90, 200),
                RGBColor(200, 60, 0),
                RGBColor(0, 150, 60),
            ];
            for (j, (d, f, r)) in all.iter().enumerate() {
                let c = colors[j % 3];
                if is_resid {
                    chart.draw_series(
                        r.iter()
                            .map(|&(t, v)| Circle::new((t, v * scale), 1, c.filled())),
                    )?;
                } else {
                    chart.draw_series(
                        d.iter()
                            .map(|&(t, v)| Circle::new((t, v), 1, c.mix(0.5).filled())),
                    )?;
                    chart.draw_series(LineSeries::new(f.iter().cloned(), BLACK.stroke_width(1)))?;
                }
            }
        }
        Ok(())
    }
}
