//! The readable report of `appell fit`: lmfit's fit report with the model comparison, the
//! noise, the windows, the fitted timeline and the adequacy verdict.

use super::correlated_pairs;
use crate::fit::{FitReport, Param, StaticResult};
use std::fmt::Write as _;

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
    let _ = writeln!(s, "{}\n", super::answer(rep));
    if let Some(sentence) = &rep.not_identifiable {
        let _ = writeln!(s, "{sentence}\n");
    }
    if let Some(sentence) = &super::answer::limited_sentence(&rep.adequacy) {
        let _ = writeln!(s, "{sentence}\n");
    }
    statistics(&mut s, rep);
    variables(&mut s, rep);
    if let Some(f) = &rep.friction {
        friction_law_text(&mut s, f);
    }
    uncertainty(&mut s, rep);
    if let Some(p) = &rep.pendulum {
        pendulum_text(&mut s, p);
    }
    correlations(&mut s, rep);
    models(&mut s, rep);
    windows(&mut s, rep);
    timeline(&mut s, rep);
    for w in &rep.warnings {
        let _ = writeln!(s, "warning: {w}");
    }
    let _ = writeln!(s, "{TERMS}");
    s
}

/// The report's last line: where its words are explained (a text report cannot link).
pub const TERMS: &str = "terms: docs/glossary.md (what each word and heading of this report means)";

/// [[Uncertainty of mu_kinetic]]: its standard error in parts, and [[Rig as measured]]: the
/// rig file's measured values with their deviations, and what the recording made of them.
fn uncertainty(s: &mut String, rep: &FitReport) {
    if let Some(p) = &rep.mu_parts {
        let _ = writeln!(
            s,
            "[[Uncertainty of mu_kinetic]] standard error {:.2e} = noise {:.2e} (+) rig {:.2e} (+) model {:.2e} (in quadrature)",
            p.total, p.noise, p.rig, p.model
        );
    }
    if rep.rig_keys.is_empty() {
        return;
    }
    let _ = writeln!(
        s,
        "[[Rig as measured]] value +- standard deviation (stated in the rig file, from --latitude, or the default of a ruler and a kitchen scale)"
    );
    for (key, v, sd, source) in &rep.rig_keys {
        let _ = writeln!(s, "    {key:<20} {v:>12.6} +- {sd:.2e} ({source})");
    }
    for r in &rep.rig_values {
        let _ = writeln!(
            s,
            "    fitted {:<20} {:>12.6} +- {:.2e}, {:+.1} deviations from the measured {:.6}",
            r.param, r.value, r.stderr, r.z, r.file
        );
    }
}

/// [[Fit statistics]]: the method and its work, the data, the noise and the chi-square.
fn statistics(s: &mut String, rep: &FitReport) {
    let a = &rep.adequacy;
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
        "    chi-square         {:.1}; reduced {:.4}; {} (against the noise above)",
        a.chi2,
        a.reduced_chi2,
        crate::report::p_is(a.p_value)
    );
    let _ = writeln!(s, "    AIC, BIC           {:.1}, {:.1}", a.aic, a.bic);
    let _ = writeln!(
        s,
        "    residual RMS       {:.3e} m (slider {:.3e}, bob {:.3e}); lag-1 autocorrelation {:.3}",
        rep.rms_residual_m, rep.rms_per_marker_m[0], rep.rms_per_marker_m[1], a.lag1
    );
}

/// [[Variables]]: each free parameter with its error, interval and start, the fixed ones,
/// what is said of mu_static when it is not free, and the sliding speeds behind mu_kinetic.
fn variables(s: &mut String, rep: &FitReport) {
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
            "    {:<20} {:>14.8} +- {:<10.3e} ({:>8}) [{:.8}, {:.8}] [{}] start {:.6} {}{}",
            p.name(),
            e.value,
            e.stderr,
            crate::report::percent_of(e.stderr, e.value),
            e.ci95[0],
            e.ci95[1],
            e.interval,
            start,
            crate::report::unit_of(*p, e.value),
            if *p == Param::Theta {
                format!(" {}", super::answer::from_hanging(e.value, e.stderr))
            } else {
                String::new()
            }
        );
    }
    // mu_static tied to mu_kinetic is said once, below, with what the data allow.
    let static_said = !matches!(rep.mu_static, StaticResult::Estimated(_))
        || !rep.params.iter().any(|(p, _)| *p == Param::MuStatic);
    for (p, v) in &rep.fixed {
        if *p == Param::MuStatic && static_said {
            continue;
        }
        let _ = writeln!(
            s,
            "    {:<20} {v:>14.8} (fixed) {}",
            p.name(),
            crate::report::unit_of(*p, *v)
        );
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
}

/// [[Correlations]]: the pairs of free parameters with |r| above 0.1, when there are any.
fn correlations(s: &mut String, rep: &FitReport) {
    let pairs = correlated_pairs(rep);
    if !pairs.is_empty() {
        let _ = writeln!(s, "[[Correlations]] (|r| > 0.1)");
        for (p, q, r) in pairs {
            let _ = writeln!(s, "    C({}, {}) = {r:+.3}", p.name(), q.name());
        }
    }
}

/// [[Models compared]]: the converged models by BIC, then the failed ones.
fn models(s: &mut String, rep: &FitReport) {
    if !rep.models.is_empty() {
        let _ = writeln!(
            s,
            "[[Models compared]] by BIC = chi2 + k ln(n), forward selection"
        );
        for m in rep.models.iter().filter(|m| m.failed.is_none()) {
            let _ = writeln!(
                s,
                "  {} {:<36} k {:>2}  chi2 {:>12.1}  BIC {:>12.1}  dBIC {:>+10.1}  weight {:.3}  mu_kinetic {:.5}{}",
                if m.chosen { "*" } else { " " },
                m.name,
                m.free.len(),
                m.chi2,
                m.bic,
                m.delta_bic,
                m.weight,
                m.mu_kinetic,
                if m.stopped_early {
                    "  (stopped out of reach of the best: chi2 at most)"
                } else if m.implausible {
                    "  (needs what no real rig has)"
                } else {
                    ""
                }
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
}

/// [[Friction law]]: the law chosen, its parameters, every law's evidence and the notes on
/// what this recording cannot tell apart.
pub fn friction_law_text(s: &mut String, f: &crate::fit::law::FrictionLawResult) {
    let _ = writeln!(
        s,
        "[[Friction law]] {}{}",
        f.chosen,
        if f.forced {
            " (forced with --friction)"
        } else {
            ""
        }
    );
    for p in &f.parameters {
        let _ = writeln!(
            s,
            "    {:<22} {:>12.6} +- {:<10.2e} (95 %: {:.6} to {:.6})",
            p.name, p.value, p.stderr, p.ci95[0], p.ci95[1]
        );
    }
    for l in &f.laws {
        let detail = match (l.status, l.delta_bic, l.predicted_drop) {
            ("chosen", _, _) => "chosen".to_owned(),
            (_, Some(d), _) => format!("its best model's BIC {d:+.1} against the chosen"),
            ("screened", _, Some([drop, need])) => format!(
                "not fitted: the score test predicts a chi-square drop of {drop:.1}, below the {need:.1} it would cost"
            ),
            // Coulomb's law is the plain model's: a single fit always compares it, so only
            // a forced law or a joint selection started from a consensus with another law
            // leaves it out.
            _ if l.law == "coulomb" && f.forced => "not tried: the law is forced".to_owned(),
            _ if l.law == "coulomb" => {
                "not fitted: every model compared had another law (the joint model starts from its releases' consensus)".to_owned()
            }
            _ => "not tried: the model described the recording without it".to_owned(),
        };
        let _ = writeln!(s, "    {:<10} {detail}", l.law);
    }
    for n in &f.notes {
        let _ = writeln!(s, "  {n}");
    }
    let _ = writeln!(s);
}

/// [[Windows]]: mu_kinetic per window (a slide each, as they were cut) with the windows'
/// agreement.
fn windows(s: &mut String, rep: &FitReport) {
    let a = &rep.adequacy;
    if let (false, Some(cut)) = (rep.windows.is_empty(), rep.window_cut) {
        let _ = writeln!(
            s,
            "[[Windows]] mu_kinetic per {} ({}; agreement {})",
            cut.per(),
            cut.how(),
            crate::report::p_is(a.windows_p_value.unwrap_or(f64::NAN))
        );
        for w in &rep.windows {
            let _ = writeln!(
                s,
                "    {:>7.3} - {:>7.3} s   {:.6} +- {:.2e}",
                w.t_start, w.t_end, w.mu_kinetic, w.stderr
            );
        }
    }
}

/// [[Fitted timeline]]: the mode changes of the fitted motion (the first and last ones of a
/// long recording).
fn timeline(s: &mut String, rep: &FitReport) {
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
            line(s, e);
        }
        if tail > 0 {
            let _ = writeln!(
                s,
                "  ... {} more events (every one in --json) ...",
                n - head - tail
            );
            for e in &rep.events[n - tail..] {
                line(s, e);
            }
        }
    }
}
