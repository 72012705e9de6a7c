//! Output of `appell fit`: the readable report, the JSON object and the figure (data, fit,
//! residuals and mode bands).//!
//! `text.rs` writes the readable report, `figure.rs` draws the figure; this file writes the
//! JSON object.

mod answer;
mod figure;
mod friction_figure;
mod text;

pub use answer::{
    answer, from_hanging, limited_sentence, models_widening, value_pm, with_interval,
};
pub use figure::FitFigure;
pub use friction_figure::FrictionFigure;
pub use text::{fit_text, friction_law_text, TERMS};

use crate::fit::{Estimate, FitReport, Param, StaticResult};
use serde_json::{json, Value};

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
        "answer": answer(rep),
        // A failed fit gives no mu: its value is not a friction coefficient (`failed` says why).
        "mu_kinetic": rep.mu_kinetic.as_ref().filter(|_| rep.failed.is_none()).map(estimate_json),
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
        "time_noise_s": rep.problem.time_noise,
        "models_widening": models_widening(rep),
        "models": rep.models,
        "nuisances": rep.nuisances.iter().map(|n| n.name()).collect::<Vec<_>>(),
        "friction_law": rep.friction,
        "windows": rep.windows,
        "windows_cut": rep.window_cut,
        "windows_p_value": a.windows_p_value,
        "runs_p_value": a.runs_p_value,
        "block_se_ratio": a.block_se_ratio,
        "block_frames": a.block_frames,
        "limited_by_model": limited_sentence(a),
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
        "not_identifiable": rep.not_identifiable,
        "pendulum": rep.pendulum,
        "implausible": rep.implausible,
        "rig_measured": {
            "keys": rep.rig_keys.iter().map(|(k, v, sd, source)| json!({"key": k, "value": v, "sd": sd, "stated": *source == "stated", "source": source})).collect::<Vec<_>>(),
            "fitted": rep.rig_values,
        },
    });
    if let (Value::Object(m), Value::Object(extra)) = (&mut v, more) {
        m.extend(extra);
    }
    if let (Some(parts), true) = (
        rep.mu_parts,
        rep.mu_kinetic.is_some() && rep.failed.is_none(),
    ) {
        v["mu_kinetic"]["parts"] = json!(parts);
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
