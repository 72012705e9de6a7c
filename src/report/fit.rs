//! Output of `appell fit`: the readable report, the JSON object and the figure (data, fit,
//! residuals and mode bands).

use super::plot::{data_range, draw_side_legend, Figure, PlotError, Swatch};
use crate::fit::{Estimate, FitReport, Observations, Param, StaticResult};
use crate::model::{observed_markers, Mode};
use crate::sim::{simulate, Options, Request};
use plotters::coord::Shift;
use plotters::prelude::*;
use serde_json::{json, Value};
use std::fmt::Write as _;

fn estimate_json(e: &Estimate) -> Value {
    json!({"value": e.value, "stderr": e.stderr, "ci95": e.ci95, "interval": e.interval})
}

fn get(rep: &FitReport, p: Param) -> f64 {
    rep.params
        .iter()
        .find(|(q, _)| *q == p)
        .map(|(_, e)| e.value)
        .or_else(|| rep.fixed.iter().find(|(q, _)| *q == p).map(|(_, v)| *v))
        .unwrap_or(f64::NAN)
}

/// Pairs of free parameters whose correlation exceeds 0.1 in size, largest first.
fn correlated_pairs(rep: &FitReport) -> Vec<(Param, Param, f64)> {
    let mut out = Vec::new();
    for i in 0..rep.params.len() {
        for j in i + 1..rep.params.len() {
            let r = rep.correlation[(i, j)];
            if r.abs() > 0.1 {
                out.push((rep.params[i].0, rep.params[j].0, r));
            }
        }
    }
    out.sort_by(|a, b| b.2.abs().total_cmp(&a.2.abs()));
    out
}

/// The JSON object of `appell fit --json` (one line per recording for a directory). Keys are
/// stable: `mu_kinetic.value`, `.stderr`, `.ci95`; `mu_static.lower_bound` when only a bound is
/// known.
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
    let start = |p: Param| {
        rep.start_values
            .iter()
            .find(|(q, _)| *q == p)
            .map(|(_, v)| *v)
    };
    let parameters: serde_json::Map<String, Value> = rep
        .params
        .iter()
        .map(|(p, e)| {
            let mut v = estimate_json(e);
            v["stderr_percent"] = json!(100.0 * e.stderr / e.value.abs());
            v["start"] = json!(start(*p));
            v["unit"] = json!(p.unit());
            (p.name().to_owned(), v)
        })
        .collect();
    let noise = |m: usize| {
        rep.noise[m].map_or(
            json!({"sigma": rep.noise_m[m], "source": "fallback"}),
            |n| json!({"sigma": rep.noise_m[m], "dof": n.dof, "source": n.source}),
        )
    };
    let a = &rep.adequacy;
    let mut v = json!({
        "mu_kinetic": rep.mu_kinetic.as_ref().map(estimate_json),
        "mu_static": mu_static,
        "initial": {
            "x": get(rep, Param::X), "theta": get(rep, Param::Theta),
            "x_dot": get(rep, Param::XDot), "theta_dot": get(rep, Param::ThetaDot),
        },
        "parameters": parameters,
        "fixed": rep.fixed.iter().map(|(p, v)| (p.name().to_owned(), json!(v))).collect::<serde_json::Map<_, _>>(),
        "correlation_with_mu_kinetic": correlations,
        "correlations": correlated_pairs(rep).iter().map(|(a, b, r)| json!({"a": a.name(), "b": b.name(), "r": r})).collect::<Vec<_>>(),
        "method": "Levenberg-Marquardt (argmin executor), exact Jacobian by dual numbers through the hybrid simulation",
        "iterations": rep.work.iterations,
        "residual_evals": rep.work.residual_evals,
        "jacobian_evals": rep.work.jacobian_evals,
        "stop_reason": rep.stop_reason,
        "n_frames": rep.n_frames,
        "n_residuals": rep.n_residuals,
        "n_variables": rep.params.len(),
        "dof": a.dof,
        "chi2": a.chi2,
        "reduced_chi2": a.reduced_chi2,
        "chi2_p_value": a.p_value,
        "aic": a.aic,
        "bic": a.bic,
        "criterion": "BIC (forward selection; a nuisance is kept when it lowers BIC by more than 2)",
    });
    let more = json!({
        "noise": {"slider": noise(0), "bob": noise(1)},
        "noise_m": {"slider": rep.noise_m[0], "bob": rep.noise_m[1]},
        "models": rep.models,
        "nuisances": rep.nuisances.iter().map(|n| n.name()).collect::<Vec<_>>(),
        "windows": rep.windows,
        "windows_p_value": a.windows_p_value,
        "runs_p_value": a.runs_p_value,
        "block_se_ratio": a.block_se_ratio,
        "block_frames": a.block_frames,
        "limited_by_model": a.limited_by_model,
        "noise_free": a.noise_free,
        "outliers": {"slider": rep.outliers[0], "bob": rep.outliers[1]},
        "sliding_speed_range": rep.sliding_speed_range,
        "rms_residual_m": rep.rms_residual_m,
        "rms_residual_per_marker_m": {"slider": rep.rms_per_marker_m[0], "bob": rep.rms_per_marker_m[1]},
        "residual_lag1_autocorrelation": rep.residual_autocorrelation,
        "identifiable": rep.identifiable,
        "events": rep.events.iter().map(|e| json!({"t": e.t, "from": e.from.name(), "to": e.to.name(), "kind": e.kind})).collect::<Vec<_>>(),
        "starts": rep.starts,
        "warnings": rep.warnings,
        "failed": rep.failed,
        "pendulum": rep.pendulum,
    });
    if let (Value::Object(m), Value::Object(extra)) = (&mut v, more) {
        m.extend(extra);
    }
    if rep.mu_kinetic.is_some() && rep.failed.is_none() {
        v["shared_covariance"] = rig_covariance(rep);
    }
    v
}

/// The covariance of the rig's fitted parameters (mu and the rig's nuisances; not the
/// release's state or camera) from the correlations and the reported standard errors (which
/// hold any widening): what `plan --after` takes as known, in the joint fit's form.
fn rig_covariance(rep: &FitReport) -> Value {
    let rig: Vec<usize> = (0..rep.params.len())
        .filter(|&i| rep.params[i].0.is_rig())
        .collect();
    let names: Vec<&str> = rig.iter().map(|&i| rep.params[i].0.name()).collect();
    let matrix: Vec<Vec<f64>> = rig
        .iter()
        .map(|&i| {
            rig.iter()
                .map(|&j| rep.correlation[(i, j)] * rep.params[i].1.stderr * rep.params[j].1.stderr)
                .collect()
        })
        .collect();
    json!({"names": names, "matrix": matrix})
}

/// The rigid pendulum the data found, in a lab's words.
fn pendulum_text(s: &mut String, p: &crate::fit::PendulumFound) {
    let _ = writeln!(
        s,
        "[[Rigid pendulum]] its equivalent length and mass ratio, found by the data"
    );
    let row = |s: &mut String, name: &str, v: &crate::fit::ValueSe, unit: &str| {
        let _ = writeln!(
            s,
            "    {name:<24} {:>12.6e} +- {:.2e} {unit}",
            v.value, v.stderr
        );
    };
    row(s, "equivalent length L", &p.equivalent_length, "m");
    row(s, "equivalent mass ratio r'", &p.mass_ratio, "");
    row(s, "equivalent bob mass m_e", &p.equivalent_bob_mass, "kg");
    row(s, "inertia about pivot J", &p.inertia, "kg m^2");
    row(s, "radius of gyration", &p.radius_of_gyration, "m");
    row(s, "centre of mass d", &p.com, "m");
    let _ = writeln!(
        s,
        "    (m_e and J from the total mass {} kg = slider_mass + bob_mass; the radius of gyration and d with everything that swings taken as bob_mass = {} kg: a rod's mass missing from the rig file scales them)",
        p.total_mass, p.swinging_mass
    );
}

/// The readable report of `appell fit`: what lmfit's fit_report gives, and the model
/// comparison, the noise, the windows and the adequacy verdict.
pub fn fit_text(rep: &FitReport) -> String {
    let mut s = String::new();
    let a = &rep.adequacy;
    if let Some(sentence) = &a.limited_by_model {
        let _ = writeln!(s, "{sentence}\n");
    }
    let _ = writeln!(s, "[[Fit statistics]]");
    let _ = writeln!(
        s,
        "    method             Levenberg-Marquardt, exact dual-number Jacobian"
    );
    let _ = writeln!(
        s,
        "    evaluations        {} iterations, {} residual and {} Jacobian evaluations; stopped: {}",
        rep.work.iterations, rep.work.residual_evals, rep.work.jacobian_evals, rep.stop_reason
    );
    let _ = writeln!(
        s,
        "    data points        {} residuals from {} frames ({} slider and {} bob positions left out as mis-tracked)",
        rep.n_residuals, rep.n_frames, rep.outliers[0], rep.outliers[1]
    );
    let _ = writeln!(
        s,
        "    variables          {} (degrees of freedom {:.0})",
        rep.params.len(),
        a.dof
    );
    let src = |m: usize| rep.noise[m].map_or("fallback", |n| n.source);
    let _ = writeln!(
        s,
        "    noise              slider {:.3e} m ({}), bob {:.3e} m ({})",
        rep.noise_m[0],
        src(0),
        rep.noise_m[1],
        src(1)
    );
    let _ = writeln!(
        s,
        "    chi-square         {:.1}; reduced {:.4}; p = {:.3} (against the noise above)",
        a.chi2, a.reduced_chi2, a.p_value
    );
    let _ = writeln!(s, "    AIC, BIC           {:.1}, {:.1}", a.aic, a.bic);
    let _ = writeln!(
        s,
        "    residual RMS       {:.3e} m (slider {:.3e}, bob {:.3e}); lag-1 autocorrelation {:.3}",
        rep.rms_residual_m, rep.rms_per_marker_m[0], rep.rms_per_marker_m[1], a.lag1
    );
    let _ = writeln!(
        s,
        "[[Variables]] value +- standard error (%), 95% interval [method], start"
    );
    for (p, e) in &rep.params {
        let start = rep
            .start_values
            .iter()
            .find(|(q, _)| q == p)
            .map_or(f64::NAN, |(_, v)| *v);
        let _ = writeln!(
            s,
            "    {:<20} {:>14.8} +- {:<10.3e} ({:>6.2}%) [{:.8}, {:.8}] [{}] start {:.6} {}",
            p.name(),
            e.value,
            e.stderr,
            100.0 * e.stderr / e.value.abs(),
            e.ci95[0],
            e.ci95[1],
            e.interval,
            start,
            p.unit()
        );
    }
    for (p, v) in &rep.fixed {
        let _ = writeln!(s, "    {:<20} {v:>14.8} (fixed) {}", p.name(), p.unit());
    }
    match (&rep.mu_kinetic, &rep.mu_static) {
        (None, StaticResult::LowerBound(b)) => {
            let _ = writeln!(
                s,
                "    mu_kinetic           not identifiable (the slider never slides)"
            );
            let _ = writeln!(
                s,
                "    mu_static            >= {b:.5} (largest |F|/|N| the stuck slider needed)"
            );
        }
        (_, StaticResult::NotIdentifiable) => {
            let _ = writeln!(
                s,
                "    mu_static            not identifiable (tied to mu_kinetic for the fit)"
            );
        }
        (_, StaticResult::Estimated(e))
            if !rep.params.iter().any(|(p, _)| *p == Param::MuStatic) =>
        {
            let _ = writeln!(
                s,
                "    mu_static            at its bound mu_kinetic; 95% [{:.6}, {:.6}] [{}]",
                e.ci95[0], e.ci95[1], e.interval
            );
        }
        _ => {}
    }
    if let Some([lo, hi]) = rep.sliding_speed_range {
        let _ = writeln!(
            s,
            "    sliding speeds     {lo:.4} to {hi:.4} m/s behind mu_kinetic"
        );
    }
    if let Some(p) = &rep.pendulum {
        pendulum_text(&mut s, p);
    }
    let pairs = correlated_pairs(rep);
    if !pairs.is_empty() {
        let _ = writeln!(s, "[[Correlations]] (|r| > 0.1)");
        for (p, q, r) in pairs {
            let _ = writeln!(s, "    C({}, {}) = {r:+.3}", p.name(), q.name());
        }
    }
    if !rep.models.is_empty() {
        let _ = writeln!(
            s,
            "[[Models compared]] by BIC = chi2 + k ln(n), forward selection"
        );
        for m in rep.models.iter().filter(|m| m.failed.is_none()) {
            let _ = writeln!(
                s,
                "  {} {:<36} k {:>2}  chi2 {:>12.1}  BIC {:>12.1}  dBIC {:>+10.1}  weight {:.3}  mu_kinetic {:.5}",
                if m.chosen { "*" } else { " " },
                m.name,
                m.free.len(),
                m.chi2,
                m.bic,
                m.delta_bic,
                m.weight,
                m.mu_kinetic
            );
        }
        for m in rep.models.iter().filter(|m| m.failed.is_some()) {
            let _ = writeln!(
                s,
                "  failed {:<36} k {:>2}  {}",
                m.name,
                m.free.len(),
                m.failed.as_deref().unwrap_or("")
            );
        }
    }
    if !rep.windows.is_empty() {
        let _ = writeln!(
            s,
            "[[Windows]] mu_kinetic per slide (cut at sticks and reversals; agreement p = {})",
            a.windows_p_value
                .map_or("-".to_owned(), |p| format!("{p:.3}"))
        );
        for w in &rep.windows {
            let _ = writeln!(
                s,
                "    {:>7.3} - {:>7.3} s   {:.6} +- {:.2e}",
                w.t_start, w.t_end, w.mu_kinetic, w.stderr
            );
        }
    }
    if rep.events.is_empty() {
        let _ = writeln!(s, "[[Fitted timeline]] no mode changes");
    } else {
        let _ = writeln!(s, "[[Fitted timeline]]");
        // A long stick-slip recording has hundreds of events: the first and the last ones
        // here, every one in the JSON.
        let n = rep.events.len();
        let (head, tail) = if n > 40 { (30, 5) } else { (n, 0) };
        let line = |s: &mut String, e: &crate::sim::Event| {
            let _ = writeln!(s, "  {:>12.6} s  {:<7} -> {}", e.t, e.from.name(), e.to);
        };
        for e in &rep.events[..head] {
            line(&mut s, e);
        }
        if tail > 0 {
            let _ = writeln!(
                s,
                "  ... {} more events (every one in --json) ...",
                n - head - tail
            );
            for e in &rep.events[n - tail..] {
                line(&mut s, e);
            }
        }
    }
    for w in &rep.warnings {
        let _ = writeln!(s, "warning: {w}");
    }
    s
}

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
            "chi2 = {:.1} for {:.0} dof (reduced {:.3}, p = {:.3})",
            a.chi2, a.dof, a.reduced_chi2, a.p_value
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

impl Figure for FitFigure<'_> {
    fn size(&self) -> (u32, u32) {
        (1300, 1150)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), PlotError> {
        let rep = self.report;
        // A figure cannot show more frames than it has pixels: a long recording is drawn
        // from every k-th frame (at most PLOT_FRAMES), the fit's numbers still from all.
        let stride = self.obs.times.len().div_ceil(PLOT_FRAMES).max(1);
        let thinned;
        let obs = if stride > 1 {
            thinned = Observations {
                times: self.obs.times.iter().step_by(stride).copied().collect(),
                slider: self.obs.slider.iter().step_by(stride).copied().collect(),
                bob: self.obs.bob.iter().step_by(stride).copied().collect(),
            };
            &thinned
        } else {
            self.obs
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
        // Observed coordinate k (0..4 as in COORDS) at frame i, in mm.
        let observed = |k: usize, i: usize| -> Option<f64> {
            let m = if k < 2 { obs.slider[i] } else { obs.bob[i] };
            m.map(|p| p[k % 2] * 1e3)
        };
        let data = |k: usize| -> Vec<(f64, f64)> {
            (0..times.len())
                .filter_map(|i| observed(k, i).map(|v| (times[i], v)))
                .collect()
        };
        let fitted =
            |k: usize| -> Vec<(f64, f64)> { pred.iter().map(|p| (p.0, p.1[k] * 1e3)).collect() };
        // Residuals as the fit and the README define them: fitted minus observed.
        let resid = |k: usize| -> Vec<(f64, f64)> {
            (0..times.len())
                .filter_map(|i| Some((times[i], pred.get(i)?.1[k] * 1e3 - observed(k, i)?)))
                .collect()
        };
        let bands = |top: f64, bottom: f64| -> Vec<Rectangle<(f64, f64)>> {
            let mut out = Vec::new();
            let mut start = 0;
            for i in 1..=pred.len() {
                if i == pred.len() || pred[i].2 != pred[start].2 {
                    let t1 = if i == pred.len() { t_end } else { pred[i].0 };
                    out.push(Rectangle::new(
                        [(pred[start].0, bottom), (t1, top)],
                        mode_color(pred[start].2).filled(),
                    ));
                    start = i;
                }
            }
            out
        };

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
        // (panel title, coordinates drawn, residual panel?)
        let panels: [(&str, &[usize], bool); 4] = [
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
        for (area, (title, coords, is_resid)) in areas.iter().zip(panels) {
            let series: Vec<(usize, Points, Points)> = coords
                .iter()
                .map(|&k| {
                    if is_resid {
                        (k, resid(k), Vec::new())
                    } else {
                        (k, data(k), fitted(k))
                    }
                })
                .collect();
            let band = if is_resid {
                2.0 * rep.noise_m[coords[0] / 2] * 1e3
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
            chart.draw_series(bands(yr.end, yr.start))?;
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
        }

        // The windows: mu_kinetic fitted on each stretch against the whole fit's interval.
        if let Some(mu) = rep.mu_kinetic {
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
            let mut chart = ChartBuilder::on(&windows_area)
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
        }

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
        draw_side_legend(&side, "Fit", &entries, &self.notes(), 30)?;
        Ok(())
    }
}
