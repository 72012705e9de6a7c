//! The releases that disagree, found one at a time: the worst set aside and the rest refitted
//! jointly until the rest agree, each release's own mu then taken under the rest's shared
//! values.

use super::agreement::{consistency, leave_one_out, own_mu, own_mus, AGREE_P};
use super::{JointProblem, ReleaseRow};
use crate::fit::lm::LeastSquares;
use crate::fit::problem::{Param, TrajectoryProblem};
use crate::fit::select::Candidate;
use crate::fit::solve::solve_loose;
use crate::fit::uncertainty;
use crate::fit::{Estimate, FitSettings};
use nalgebra::DVector;

/// Each release's own (mu, se) and z, keyed by release index.
type Zs = Vec<(usize, (f64, f64), f64)>;

/// The releases other than `out` refitted jointly (same model): their mu, each release's own
/// mu and z (the rest's leave-one-out z; those in `out` against the rest's mu, their own mu
/// under the rest's shared values), and whether the rest agree.
fn fit_rest(
    jp: &JointProblem,
    out: &[usize],
    settings: &FitSettings,
) -> Option<(Estimate, Zs, bool)> {
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
    let mut zs: Zs = keep
        .iter()
        .zip(&pairs)
        .zip(&rz)
        .map(|((&i, &own), &zi)| (i, own, zi))
        .collect();
    for &i in out {
        let mut m = jp.parts[i].clone();
        for &q in &rest.shared {
            let v = rest.parts[0].get(q);
            set_param(&mut m, q, v);
        }
        if let Some(e) = own_mu(&m, &rest.shared, settings) {
            let zi = (e.value - mu.value) / e.stderr.hypot(mu.stderr);
            zs.push((i, (e.value, e.stderr), zi));
        }
    }
    let agree = consistency(&pairs).is_none_or(|p| p >= AGREE_P);
    Some((mu, zs, agree))
}

/// The releases that disagree: the one with the largest |z| set aside, the rest refitted
/// jointly (same model) and tested again, until the rest agree or only half are left; then
/// a release set aside whose own mu lies within 3 standard errors of the rest's is taken
/// back (an odd release pulls the shared tilt, and with it the first |z|s). The releases
/// that disagree, and the others' fit ([`fit_rest`]).
fn set_aside(
    jp: &JointProblem,
    z: &[f64],
    settings: &FitSettings,
) -> (Vec<usize>, Option<(Estimate, Zs)>) {
    let n = jp.parts.len();
    let mut out: Vec<usize> = Vec::new();
    let mut z = z.to_vec();
    let mut rest_fit = None;
    while out.len() < n / 2 && n - out.len() > 2 {
        let Some(worst) = (0..n)
            .filter(|i| !out.contains(i))
            .max_by(|&a, &b| z[a].abs().total_cmp(&z[b].abs()))
        else {
            break;
        };
        out.push(worst);
        let Some((mu, zs, agree)) = fit_rest(jp, &out, settings) else {
            break;
        };
        for &(i, _, zi) in &zs {
            z[i] = zi;
        }
        rest_fit = Some((mu, zs));
        if agree {
            break;
        }
    }
    let back: Vec<usize> = out.iter().copied().filter(|&i| z[i].abs() <= 3.0).collect();
    if !back.is_empty() && back.len() < out.len() {
        out.retain(|i| !back.contains(i));
        if let Some((mu, zs, _)) = fit_rest(jp, &out, settings) {
            rest_fit = Some((mu, zs));
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
