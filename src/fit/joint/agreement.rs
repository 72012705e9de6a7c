//! Whether the releases agree on mu_kinetic: each release's own mu with the shared nuisances
//! held, tested as the single fit tests its windows, and each one's leave-one-out z; the
//! releases' spread (the report words what the interval holds).

use super::outcome::ReleaseRow;
use crate::fit::problem::{Param, TrajectoryProblem};
use crate::fit::solve::solve_loose;
use crate::fit::uncertainty::{self, WindowFit};
use crate::fit::{Estimate, FitSettings};

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

/// The rows' own (mu, se), (NaN, 0) where a release has none: what the tests below take.
pub(super) fn own_pairs<'a>(rows: impl IntoIterator<Item = &'a ReleaseRow>) -> Vec<(f64, f64)> {
    rows.into_iter()
        .map(|r| r.own_mu.map_or((f64::NAN, 0.0), |e| (e.value, e.stderr)))
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
    Some(Estimate::wald(p[i], a.se[i].max(a.se_block[i])))
}

/// The releases' precision-weighted spread of own mu about `mu` (their rows'), by which an
/// interval is widened when they disagree.
pub(super) fn spread(rows: &[ReleaseRow], mu: f64) -> f64 {
    window_spread_of(&own_pairs(rows), mu)
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
