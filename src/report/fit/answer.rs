//! The one-line answer that opens a fit's report (and the JSON's `answer`): mu_kinetic with
//! as many digits as its uncertainty carries, and the verdict in a few words, so that a lab
//! reads the result before the tables that back it.

use crate::fit::{failed_tests, Adequacy, Estimate, FailedTest, FitReport, LimitPart};
use crate::report::{p_is, two_digit_decimals};

/// `value +- se` rounded where the uncertainty puts it: the standard error to two significant
/// digits and the value to the same decimal place (0.2499917541986817 +- 5.35e-6 reads
/// `0.2499918 +- 0.0000054`). Without a usable error, six significant digits.
pub fn value_pm(value: f64, se: f64) -> String {
    match decimals(se) {
        Some(d) => format!("{value:.d$} +- {se:.d$}"),
        None => format!("{value:.6}"),
    }
}

/// `value +- se (95 %: lo to hi)`, every number to the decimal place of [`value_pm`]: how an
/// estimate reads in the answers and the joint fit's table.
pub fn with_interval(e: &Estimate) -> String {
    let d = decimals(e.stderr).unwrap_or(6);
    format!(
        "{} (95 %: {:.d$} to {:.d$})",
        value_pm(e.value, e.stderr),
        e.ci95[0],
        e.ci95[1]
    )
}

/// Decimal places that show a standard error to two significant digits (at most 12).
fn decimals(se: f64) -> Option<usize> {
    two_digit_decimals(se).map(|d| d.min(12))
}

/// How many times the models' spread widens mu_kinetic's standard error over the noise's and
/// the rig's (1 when it does not).
pub fn models_widening(rep: &FitReport) -> f64 {
    rep.mu_parts.map_or(1.0, |p| {
        let own = p.noise.hypot(p.rig);
        if own > 0.0 && p.total.is_finite() {
            (p.total / own).max(1.0)
        } else {
            1.0
        }
    })
}

/// The words said when models that fit as well widen mu's interval more than twice: a
/// widening the answer does not state is a claim hidden in a number.
fn models_words(rep: &FitReport) -> String {
    let w = models_widening(rep);
    if w > 2.0 {
        format!(
            "; other models fit about as well and give other mu_kinetic, and its interval is {w:.1} times as wide to hold them (see the models compared)"
        )
    } else {
        String::new()
    }
}

/// The one-line answer: `mu_kinetic = V +- E (95 %: LO to HI), model adequate`, or `...,
/// limited by the model: WHY; WHAT TO TRY`, or why there is no value.
pub fn answer(rep: &FitReport) -> String {
    if let Some(why) = &rep.not_identifiable {
        return format!("mu_kinetic not identifiable: {why}");
    }
    let Some(mu) = &rep.mu_kinetic else {
        return "mu_kinetic not measured (see below)".to_owned();
    };
    if let Some(why) = &rep.failed {
        return format!("mu_kinetic not measured, the fit failed: {why}");
    }
    if rep.adequacy.noise_free {
        return format!(
            "mu_kinetic = {:.10} (a noise-free recording: no interval is meaningful)",
            mu.value
        );
    }
    let mut head = format!("mu_kinetic = {}{}", with_interval(mu), law_words(rep));
    for u in rep.friction.iter().flat_map(|f| &f.untested) {
        head.push_str(&format!(" ({u})"));
    }
    if crate::fit::solve::at_iteration_limit(&rep.stop_reason) {
        // Said first, whatever else holds: the value is no minimum. What the model misses,
        // when the checks say it, still follows.
        head.push_str(", not converged: the solve stopped at its iteration limit");
        if rep.adequacy.limited_by_model.is_empty() {
            return head;
        }
    } else if rep.adequacy.limited_by_model.is_empty() {
        return format!("{head}, model adequate{}", models_words(rep));
    }
    let a = &rep.adequacy;
    let mut why: Vec<String> = rep
        .implausible
        .iter()
        .map(|s| {
            let what = s.split(" is beyond").next().unwrap_or(s);
            format!("needs {what}")
        })
        .collect();
    why.extend(
        failed_tests(a.p_value, a.runs_p_value, a.windows_p_value)
            .into_iter()
            .map(|t| match t {
                FailedTest::ChiSquare(_) => {
                    format!("misfits (reduced chi-square {:.2})", a.reduced_chi2)
                }
                FailedTest::Runs(_) => "residuals keep their sign over long stretches".to_owned(),
                FailedTest::Slides(p) => format!("the slides disagree on mu ({})", p_is(p)),
            }),
    );
    if why.is_empty() {
        why.push("an effect the model lacks (see below)".to_owned());
    }
    let try_this = if rep.implausible.is_empty() {
        "the interval is widened for it; --plot FIT.svg shows where the model misses"
    } else {
        "check on the rig what it names (below)"
    };
    format!(
        "{head}, limited by the model: {}; {try_this}",
        why.join(", ")
    )
}

/// The friction law in a few words when it is not Coulomb's with one coefficient: under the
/// direction law each direction's coefficient (mu_kinetic is their mean), under the load law
/// the exponent (mu_kinetic is the coefficient at the static load).
fn law_words(rep: &FitReport) -> String {
    let Some(f) = &rep.friction else {
        return String::new();
    };
    let get = |name: &str| f.parameters.iter().find(|p| p.name == name);
    let law = f.chosen.split('+').next().unwrap_or("");
    match law {
        "direction" => match (get("mu_kinetic_positive"), get("mu_kinetic_negative")) {
            (Some(p), Some(m)) => format!(
                ", the mean of {} sliding toward +x and {} toward -x (direction law)",
                value_pm(p.value, p.stderr),
                value_pm(m.value, m.stderr)
            ),
            _ => ", direction law".to_owned(),
        },
        "load" => get("load_exponent").map_or_else(
            || ", load law".to_owned(),
            |n| {
                format!(
                    " at the static load, friction as |N|^{} (load law)",
                    value_pm(n.value, n.stderr)
                )
            },
        ),
        "coulomb" if f.chosen.ends_with("+viscous") => ", with viscous rail friction".to_owned(),
        "coulomb" => String::new(),
        "static" => ", with mu_static above it".to_owned(),
        "stribeck" => ", Stribeck law".to_owned(),
        other => format!(", {other} law"),
    }
}

/// The one plain sentence that says why the result is limited by the model (`None` when it is
/// not): the fit's own sentences, then the adequacy tests that failed, worded here with their
/// p-values, and what the widened interval of mu_kinetic holds.
pub fn limited_sentence(a: &Adequacy) -> Option<String> {
    let parts: Vec<String> = a.limited_by_model.iter().map(limit_part).collect();
    (!parts.is_empty()).then(|| parts.join(" "))
}

/// One part of [`limited_sentence`].
fn limit_part(part: &LimitPart) -> String {
    let t = match part {
        LimitPart::Said(s) => return s.clone(),
        LimitPart::Tests(t) => t,
    };
    let why: Vec<String> = t
        .tests
        .iter()
        .map(|test| match *test {
            FailedTest::ChiSquare(p) => format!(
                "chi-square is {:.0} for {:.0} degrees of freedom against the noise measured from the tracks (reduced {:.2}, {})",
                t.chi2,
                t.dof,
                t.reduced_chi2,
                p_is(p)
            ),
            FailedTest::Runs(p) => format!(
                "the residuals keep their sign over long stretches (runs test {})",
                p_is(p)
            ),
            FailedTest::Slides(p) => format!(
                "the recording's slides, fitted one by one, disagree on mu_kinetic ({})",
                p_is(p)
            ),
        })
        .collect();
    let interval = t
        .mu_interval
        .as_ref()
        .map_or(String::new(), |(ci95, method)| {
            let what: Vec<&str> = method
                .split('+')
                .filter_map(|tag| match tag {
                    "block" => Some("the residuals' correlation"),
                    "windows" => Some("the slides' disagreement (their scale factor)"),
                    "models" => Some("the spread of close models"),
                    "path" => Some("as much as mu moved while nuisances were added"),
                    _ => None,
                })
                .collect();
            let held = if what.is_empty() {
                String::new()
            } else {
                format!(" to hold {}", what.join(", "))
            };
            format!(
                "; the interval for mu_kinetic was widened{held}: [{:.5}, {:.5}] ({method})",
                ci95[0], ci95[1]
            )
        });
    format!(
        "The result is limited by the model, not by the noise: {}{interval}.",
        why.join("; ")
    )
}

/// The release angle read from hanging, for a lab that measures its angle from the vertical:
/// the model's theta (docs/physics.md) runs from the rail's +x direction with y down, so the
/// bob hangs at pi/2 and `theta 0.4707 rad` is 1.1 rad from hanging, toward +x. Decimals
/// follow the standard error `se` (four without one).
pub fn from_hanging(theta: f64, se: f64) -> String {
    let phi = theta - std::f64::consts::FRAC_PI_2;
    let d = crate::report::two_digit_decimals(se).map_or(4, |d| d.clamp(2, 8));
    let side = if phi < 0.0 { "+x" } else { "-x" };
    if format!("{:.d$}", phi.abs())
        .trim_matches(['0', '.'])
        .is_empty()
    {
        "(hanging straight down; theta = pi/2 hangs)".to_owned()
    } else {
        format!(
            "({:.d$} rad from hanging, toward {side}; theta = pi/2 hangs)",
            phi.abs()
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn digits_follow_the_uncertainty() {
        assert_eq!(
            value_pm(0.2499917541986817, 0.000005351765541894624),
            "0.2499918 +- 0.0000054"
        );
        assert_eq!(value_pm(0.11992163, 4.932e-5), "0.119922 +- 0.000049");
        assert_eq!(value_pm(0.2517570, 0.0424), "0.252 +- 0.042");
        assert_eq!(value_pm(0.127, 7.1), "0.1 +- 7.1");
        assert_eq!(value_pm(0.12, 0.0), "0.120000");
        assert_eq!(value_pm(0.12, f64::NAN), "0.120000");
    }
}
