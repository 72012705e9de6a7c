//! The releases that disagree, found in rounds that double what is set aside: the worst set
//! aside and the rest refitted jointly until the rest agree, each release's own mu then taken
//! under the rest's shared values.

use super::agreement::{consistency, leave_one_out, own_mu, own_mus, AGREE_P};
use super::{JointProblem, ReleaseRow};
use crate::fit::lm::LeastSquares;
use crate::fit::problem::{Param, TrajectoryProblem};
use crate::fit::select::Candidate;
use crate::fit::solve::solve_loose;
use crate::fit::uncertainty;
use crate::fit::{Estimate, FitSettings};
use nalgebra::DVector;
use rayon::prelude::*;

/// Each release's own (mu, se) and z, keyed by release index.
type Zs = Vec<(usize, (f64, f64), f64)>;

/// The releases other than some refitted jointly: the fit, its mu, each release's own mu and
/// z, and whether the rest agree.
struct Rest {
    /// The rest's joint problem at its optimum.
    problem: JointProblem,
    /// Its mu_kinetic (Wald).
    mu: Estimate,
    /// The rest's own mu and leave-one-out z, then (once [`score_out`] ran) those set aside.
    zs: Zs,
    /// Whether the rest's own mu agree.
    agree: bool,
}

/// The releases other than `out` refitted jointly (same model, started from the joint
/// values): their mu, each one's own mu and leave-one-out z, and whether they agree.
fn fit_rest(jp: &JointProblem, out: &[usize], settings: &FitSettings) -> Option<Rest> {
    let keep: Vec<usize> = (0..jp.parts.len()).filter(|i| !out.contains(i)).collect();
    let mut rest = JointProblem::new(
        keep.iter().map(|&i| jp.parts[i].clone()).collect(),
        jp.same_camera,
    );
    let (p, _, _) = solve_loose(&rest, rest.values(), settings.max_iters, None).ok()?;
    rest.set_values(&p);
    let mu = wald_mu(&rest, &p)?;
    let pairs = own_mus(&rest, settings);
    let rz = leave_one_out(&pairs);
    let zs: Zs = keep
        .iter()
        .zip(&pairs)
        .zip(&rz)
        .map(|((&i, &own), &zi)| (i, own, zi))
        .collect();
    let agree = consistency(&pairs).is_none_or(|p| p >= AGREE_P);
    Some(Rest {
        problem: rest,
        mu,
        zs,
        agree,
    })
}

/// The releases in `out` scored against `rest`: each one's own mu under the rest's shared
/// values and its z against the rest's mu, added to `rest.zs`. Only the last round's rest
/// needs them (the take-back and the report), so the rounds before skip them.
fn score_out(jp: &JointProblem, rest: &mut Rest, out: &[usize], settings: &FitSettings) {
    let shared = &rest.problem.shared;
    let scored: Vec<_> = out
        .par_iter()
        .with_max_len(1)
        .filter_map(|&i| {
            let mut m = jp.parts[i].clone();
            for &q in shared {
                let v = rest.problem.parts[0].get(q);
                set_param(&mut m, q, v);
            }
            let e = own_mu(&m, shared, settings)?;
            let zi = (e.value - rest.mu.value) / e.stderr.hypot(rest.mu.stderr);
            Some((i, (e.value, e.stderr), zi))
        })
        .collect();
    rest.zs.extend(scored);
}

/// The releases that disagree, in rounds: the worst by |z| set aside and the rest refitted
/// jointly (same model) and tested again, until the rest agree or only half are left; each
/// round sets aside as many more as are already out (1, then 1, 2, 4, ...: the refits are
/// logarithmic in the releases, each linear, instead of one refit per release set aside), the
/// worst by the last refit's |z|. Then a release set aside whose own mu lies within 3 standard
/// errors of the rest's is taken back (an odd release pulls the shared tilt, and with it the
/// first |z|s; a round that set aside one too many gives it back here). The releases that
/// disagree, and the others' fit ([`fit_rest`], [`score_out`]).
fn set_aside(
    jp: &JointProblem,
    z: &[f64],
    settings: &FitSettings,
) -> (Vec<usize>, Option<(Estimate, Zs)>) {
    let n = jp.parts.len();
    let cap = (n / 2).min(n.saturating_sub(2));
    let mut out: Vec<usize> = Vec::new();
    let mut z = z.to_vec();
    // The last rest fitted and the releases it left out.
    let mut last: Option<(Rest, Vec<usize>)> = None;
    while out.len() < cap {
        let mut kept: Vec<usize> = (0..n).filter(|i| !out.contains(i)).collect();
        kept.sort_by(|&a, &b| z[b].abs().total_cmp(&z[a].abs()));
        let batch = out.len().max(1).min(cap - out.len());
        out.extend(kept.into_iter().take(batch));
        let Some(rest) = fit_rest(jp, &out, settings) else {
            break;
        };
        for &(i, _, zi) in &rest.zs {
            z[i] = zi;
        }
        let done = rest.agree || out.len() >= cap;
        last = Some((rest, out.clone()));
        if done {
            break;
        }
    }
    let mut rest_fit = None;
    if let Some((mut rest, left)) = last {
        score_out(jp, &mut rest, &left, settings);
        for &(i, _, zi) in &rest.zs {
            z[i] = zi;
        }
        rest_fit = Some((rest.mu, rest.zs));
    }
    let back: Vec<usize> = out.iter().copied().filter(|&i| z[i].abs() <= 3.0).collect();
    if !back.is_empty() && back.len() < out.len() {
        out.retain(|i| !back.contains(i));
        if let Some(mut rest) = fit_rest(jp, &out, settings) {
            score_out(jp, &mut rest, &out, settings);
            rest_fit = Some((rest.mu, rest.zs));
        }
    }
    (out, rest_fit)
}

/// Set parameter `q` of `m` to `v` (through its values, with `q` briefly free).
fn set_param(m: &mut TrajectoryProblem, q: Param, v: f64) {
    let free = std::mem::replace(&mut m.free, vec![q]);
    m.set_values(&DVector::from_element(1, v));
    m.free = free;
}

/// mu_kinetic of `jp` at its optimum `p` with the Jacobian's standard error, scaled by the
/// reduced chi-square when above one.
fn wald_mu(jp: &JointProblem, p: &DVector<f64>) -> Option<Estimate> {
    let i = jp.shared.iter().position(|q| *q == Param::MuKinetic)?;
    let c = uncertainty::covariances(jp.normal_equations(p).ok()?, jp.n_rows(), 1.0);
    if c.singular {
        return None;
    }
    let se = c.se[i];
    Some(Estimate {
        value: p[i],
        stderr: se,
        ci95: [p[i] - 1.96 * se, p[i] + 1.96 * se],
        interval: "wald",
    })
}

/// The releases that disagree ([`set_aside`]) marked in `rows`, and each release's own mu and
/// z under the agreeing releases' shared values. Their names, and mu of the others.
pub(super) fn mark_disagreeing(
    jp: &JointProblem,
    z: &[f64],
    rows: &mut [ReleaseRow],
    settings: &FitSettings,
) -> (Vec<String>, Option<Estimate>) {
    let mut disagreeing = Vec::new();
    let mut others = None;
    let (out, rest) = set_aside(jp, z, settings);
    for &i in &out {
        rows[i].agrees = false;
        disagreeing.push(rows[i].name.clone());
    }
    if let Some((rest_mu, rest_z)) = rest {
        // Each release's own mu and z under the agreeing releases' shared values.
        for (i, (v, se), zi) in rest_z {
            rows[i].z = zi;
            if let Some(e) = rows[i].own_mu.as_mut() {
                *e = Estimate {
                    value: v,
                    stderr: se,
                    ci95: [v - 1.96 * se, v + 1.96 * se],
                    interval: "wald",
                };
            }
        }
        others = Some(rest_mu);
    }
    (disagreeing, others)
}
