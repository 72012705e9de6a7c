//! Whether the releases agree on mu_kinetic: each release's own mu with the shared nuisances
//! held, tested as the single fit tests its windows, and each one's leave-one-out z; when
//! they disagree, the interval widened by their spread and the sentence that says so.

use super::set_aside::mark_disagreeing;
use super::{JointProblem, ReleaseRow};
use crate::fit::intervals::widen;
use crate::fit::problem::{Param, TrajectoryProblem};
use crate::fit::solve::solve_loose;
use crate::fit::uncertainty::{self, WindowFit};
use crate::fit::{Estimate, FitSettings};
use rayon::prelude::*;

/// Below this p-value the releases' own mu disagree. Stricter than the single fit's windows
/// ([`crate::fit::WINDOWS_P`]): a release set aside is named, and its value left out.
pub(super) const AGREE_P: f64 = 0.01;

/// The releases' own (mu, se) as the windows' test sees them.
fn as_windows(pairs: &[(f64, f64)]) -> Vec<WindowFit> {
    pairs
        .iter()
        .filter(|(m, s)| m.is_finite() && *s > 0.0)
        .map(|&(mu_kinetic, stderr)| WindowFit {
            t_start: 0.0,
            t_end: 0.0,
            mu_kinetic,
            stderr,
        })
        .collect()
}

/// p-value of the releases' own mu agreeing: the single fit's windows test
/// ([`uncertainty::window_consistency`]).
pub(super) fn consistency(pairs: &[(f64, f64)]) -> Option<f64> {
    uncertainty::window_consistency(&as_windows(pairs))
}

/// The releases' precision-weighted spread about `mu` ([`uncertainty::window_spread`]).
fn window_spread_of(pairs: &[(f64, f64)], mu: f64) -> f64 {
    uncertainty::window_spread(&as_windows(pairs), mu)
}

/// Each release's own mu under `jp`'s shared values, in parallel.
pub(super) fn own_mus(jp: &JointProblem, settings: &FitSettings) -> Vec<(f64, f64)> {
    jp.parts
        .par_iter()
        .with_max_len(1)
        .map(|m| own_mu(m, &jp.shared, settings).map_or((f64::NAN, 0.0), |e| (e.value, e.stderr)))
        .collect()
}

/// Leave-one-out agreement: each release's own mu against the precision-weighted mean of the
/// others', as z = difference / combined standard error.
pub(super) fn leave_one_out(own: &[(f64, f64)]) -> Vec<f64> {
    (0..own.len())
        .map(|i| {
            let (mut num, mut den) = (0.0, 0.0);
            for (j, &(m, s)) in own.iter().enumerate() {
                if j != i && s > 0.0 {
                    num += m / (s * s);
                    den += 1.0 / (s * s);
                }
            }
            if den == 0.0 || own[i].1 <= 0.0 {
                return 0.0;
            }
            (own[i].0 - num / den) / (own[i].1.powi(2) + 1.0 / den).sqrt()
        })
        .collect()
}

/// mu_kinetic of release `part` alone: mu and its own parameters free, the shared nuisances
/// held at the joint values. Its value and standard error (the larger of the Jacobian's and
/// the block covariance's, as in the single fit).
pub(super) fn own_mu(
    part: &TrajectoryProblem,
    shared: &[Param],
    settings: &FitSettings,
) -> Option<Estimate> {
    let mut m = part.clone();
    m.free
        .retain(|q| *q == Param::MuKinetic || !shared.contains(q));
    let (p, _, _) = solve_loose(&m, m.values(), settings.max_iters, None).ok()?;
    m.set_values(&p);
    let a = uncertainty::assess(&m, &p, f64::INFINITY).ok()?;
    let i = m.free.iter().position(|q| *q == Param::MuKinetic)?;
    let se = a.se[i].max(a.se_block[i]);
    Some(Estimate {
        value: p[i],
        stderr: se,
        ci95: [p[i] - 1.96 * se, p[i] + 1.96 * se],
        interval: "wald",
    })
}

/// What the releases' agreement test found.
pub(super) struct Agreement {
    /// p-value of the releases' own mu agreeing (`None` with fewer than two usable).
    pub(super) consistency_p: Option<f64>,
    /// The releases whose own mu disagrees with the others'.
    pub(super) disagreeing: Vec<String>,
    /// mu_kinetic of the other releases fitted jointly without those.
    pub(super) others: Option<Estimate>,
    /// One plain sentence on what the interval holds.
    pub(super) sentence: String,
}

/// The releases' agreement: the same test and widening as the single fit's windows. Each row
/// gets its z; when the releases disagree, the releases that do are set aside one at a time
/// ([`super::set_aside::set_aside`]), their rows marked, and `mu` widened by the releases'
/// spread.
pub(super) fn agreement(
    jp: &JointProblem,
    rows: &mut [ReleaseRow],
    mu: &mut Estimate,
    settings: &FitSettings,
) -> Agreement {
    let pairs: Vec<(f64, f64)> = rows
        .iter()
        .map(|r| r.own_mu.map_or((f64::NAN, 0.0), |e| (e.value, e.stderr)))
        .collect();
    let consistency_p = consistency(&pairs);
    let z = leave_one_out(&pairs);
    rows.iter_mut().zip(&z).for_each(|(r, z)| r.z = *z);
    if !consistency_p.is_some_and(|pv| pv < AGREE_P) {
        return Agreement {
            consistency_p,
            disagreeing: Vec::new(),
            others: None,
            sentence: format!(
                "The {} releases agree ({}); the interval is what they support together.",
                rows.len(),
                crate::report::p_is(consistency_p.unwrap_or(f64::NAN))
            ),
        };
    }
    // Which releases: the worst set aside in rounds and the rest refitted (an odd
    // release pulls the shared tilt and so every release's own mu), until the rest agree.
    let (disagreeing, others) = mark_disagreeing(jp, &z, rows, settings);
    let spread = window_spread_of(&pairs, mu.value);
    widen(mu, spread, "releases");
    let sentence = disagree_sentence(consistency_p, &disagreeing, others);
    Agreement {
        consistency_p,
        disagreeing,
        others,
        sentence,
    }
}

/// The sentence when the releases disagree (p-value `p`): which lie off the others, mu of the
/// others, and that the widened interval is the rail's only if every release ran on one rail.
fn disagree_sentence(p: Option<f64>, disagreeing: &[String], others: Option<Estimate>) -> String {
    format!(
        "The releases disagree ({}): {} {} off the others{}; the interval is widened by the releases' spread, and is the rail's only if every release ran on one rail.",
        crate::report::p_is(p.unwrap_or(f64::NAN)),
        disagreeing.join(", "),
        if disagreeing.len() == 1 { "lies" } else { "lie" },
        others.map_or(String::new(), |e: Estimate| format!(
            " (without {}, mu_kinetic {:.5} +- {:.1e})",
            if disagreeing.len() == 1 { "it" } else { "them" },
            e.value,
            e.stderr
        ))
    )
}

#[cfg(test)]
mod tests {
    use super::leave_one_out;

    /// A release 10 standard errors off the others has z of about 10/sqrt(1 + 1/(n-1)); the
    /// others stay within a few units of zero.
    #[test]
    pub(super) fn leave_one_out_names_the_odd_release() {
        let own = [(0.25, 0.001), (0.25, 0.001), (0.25, 0.001), (0.26, 0.001)];
        let z = leave_one_out(&own);
        let want = 0.01 / (0.001f64.powi(2) + 0.001f64.powi(2) / 3.0).sqrt();
        assert!((z[3] - want).abs() < 1e-9, "{z:?}");
        assert!(z[..3].iter().all(|v| v.abs() < 3.5), "{z:?}");
    }
}
