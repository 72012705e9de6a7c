//! The releases that disagree, set aside by re-choosing the model without them: a release is
//! named only when its own mu lies more than 3 standard errors off the others' under a model
//! chosen on the others alone. The nuisances chosen on every release may have absorbed the
//! odd one (a friction law that differs by direction, a marker lag) and made clean releases
//! look odd; a model chosen without it does not.

use super::agreement::{consistency, own_pairs};
use super::analysis::{analyse, score, Analysis, Context};
use super::error::JointError;
use super::outcome::ReleaseRow;
use super::singles::Single;
use rayon::prelude::*;

/// What the search found.
pub(super) struct Outcome {
    /// The releases kept, analysed with the model chosen on them.
    pub(super) analysis: Analysis,
    /// The releases set aside, each judged by the kept releases' model.
    pub(super) aside: Vec<ReleaseRow>,
    /// Whether the releases disagree and no set of at most half of them, set aside, leaves
    /// releases that agree (the analysis is then every release's).
    pub(super) unresolved: bool,
    /// p-value of every release's own mu agreeing (under the model chosen on all, or on the
    /// releases kept when the single fits pointed at the others).
    pub(super) all_p: Option<f64>,
}

/// Every release but `out`, in order.
fn others(n: usize, out: &[usize]) -> Vec<usize> {
    (0..n).filter(|i| !out.contains(i)).collect()
}

/// Each release's single-fit mu against the weighted median of the other single fits', in
/// its own standard errors: which release is odd by its own fit alone, whatever model the
/// joint fit chose on all of them.
fn single_z(kept: &[Single]) -> Vec<f64> {
    let pairs: Vec<(f64, f64)> = kept
        .iter()
        .map(|(_, rep)| {
            rep.mu_kinetic
                .map_or((f64::NAN, 0.0), |e| (e.value, e.stderr))
        })
        .collect();
    (0..pairs.len())
        .map(|i| {
            let mut others: Vec<(f64, f64)> = pairs
                .iter()
                .enumerate()
                .filter(|(j, (m, s))| *j != i && m.is_finite() && *s > 0.0)
                .map(|(_, &(m, s))| (m, 1.0 / (s * s)))
                .collect();
            others.sort_by(|a, b| a.0.total_cmp(&b.0));
            let total: f64 = others.iter().map(|o| o.1).sum();
            let mut acc = 0.0;
            let centre = others.iter().find(|o| {
                acc += o.1;
                acc >= 0.5 * total
            });
            match (centre, pairs[i]) {
                (Some(c), (m, s)) if m.is_finite() && s > 0.0 => (m - c.0) / s,
                _ => 0.0,
            }
        })
        .collect()
}

/// The releases to try setting aside first (indices into `kept`, none in `out`): the one the
/// joint model `a` fits worst (the largest chi-square per residual: a release on another tilt
/// may keep its own mu and pull the shared tilt instead), the one whose single fit lies
/// farthest from the others' (`zs`; one off by mu alone was already tried when it is more
/// than 3 off, [`set_aside`]), and the one whose own mu lies farthest off under `a`.
fn candidates(a: &Analysis, zs: &[f64], out: &[usize]) -> Vec<usize> {
    let by_single = (0..zs.len())
        .filter(|i| !out.contains(i))
        .max_by(|&x, &y| zs[x].abs().total_cmp(&zs[y].abs()));
    let worst_fit = a
        .rows
        .iter()
        .zip(&a.sel)
        .max_by(|x, y| x.0.chi2_per_residual().total_cmp(&y.0.chi2_per_residual()))
        .map(|(_, &i)| i);
    let by_joint = a
        .rows
        .iter()
        .zip(&a.sel)
        .max_by(|x, y| x.0.z.abs().total_cmp(&y.0.z.abs()))
        .map(|(_, &i)| i);
    let mut c: Vec<usize> = Vec::new();
    for i in [worst_fit, by_single, by_joint].into_iter().flatten() {
        if !c.contains(&i) {
            c.push(i);
        }
    }
    c
}

/// The releases set aside.
/// 1. The single fits alone may point at releases (a single fit's mu more than 3 of its
///    standard errors from the others' weighted median, at most half, the largest first):
///    they are set aside first and the rest analysed with the model chosen on them.
/// 2. Otherwise every release is looked at under the consensus model (the model is chosen on
///    all of them only when they agree there: a model chosen on every release, odd ones
///    among them, is the costliest step and the least useful). When they disagree, the
///    [`candidates`] are tried in turn, each with the model chosen again on the rest; the
///    first whose rest agrees and which lies off it is kept (else the one whose rest agrees
///    best).
/// 3. While the rest disagree, as many more as are out are set aside (1, 1, 2, 4: the
///    analyses are logarithmic in the releases), the worst under the last rest's model, up to
///    half; each rest is looked at under the consensus model first.
/// 4. Each release set aside is judged by the rest's model ([`score`]); one that is not off
///    it is taken back (the rest analysed once more).
///
/// When the rest still disagree, or every release comes back, nothing is set aside: every
/// release with the model chosen on all of them (unresolved unless they agree there).
pub(super) fn set_aside(kept: &[Single], ctx: &Context) -> Result<Outcome, JointError> {
    let n = kept.len();
    let cap = (n / 2).min(n.saturating_sub(2));
    let all: Vec<usize> = (0..n).collect();
    let whole = |pre: Option<Analysis>| -> Result<Outcome, JointError> {
        let analysis = match pre {
            Some(a) if a.model.selected => a,
            _ => analyse(kept, &all, ctx, true)?,
        };
        Ok(Outcome {
            all_p: analysis.consistency_p,
            unresolved: !analysis.agree(),
            analysis,
            aside: Vec::new(),
        })
    };
    let zs = single_z(kept);
    let mut out: Vec<usize> = (0..n).filter(|&i| zs[i].abs() > 3.0).collect();
    out.sort_by(|&a, &b| zs[b].abs().total_cmp(&zs[a].abs()));
    out.truncate(cap);
    let mut rest: Option<Analysis> = None;
    if !out.is_empty() {
        rest = analyse(kept, &others(n, &out), ctx, true).ok();
    }
    // Every release's look, when the search started from it.
    let mut first: Option<Analysis> = None;
    if rest.is_none() {
        out.clear();
        let quick = analyse(kept, &all, ctx, false)?;
        let f = if quick.agree() {
            analyse(kept, &all, ctx, true)?
        } else {
            quick
        };
        if f.agree() || cap == 0 {
            return whole(Some(f));
        }
        let mut best: Option<(usize, Analysis, (bool, f64, f64))> = None;
        for c in candidates(&f, &zs, &out) {
            let Ok(a) = analyse(kept, &others(n, &[c]), ctx, true) else {
                continue;
            };
            let judged = score(kept, c, &a, ctx);
            // A rest that agrees and a release its model finds off ([`score`]'s rule): no
            // other candidate can do better (each try is a model chosen again).
            if a.agree() && !judged.agrees {
                best = Some((c, a, (true, f64::INFINITY, f64::INFINITY)));
                break;
            }
            let key = (a.agree(), a.consistency_p.unwrap_or(1.0), judged.z.abs());
            let better = best
                .as_ref()
                .is_none_or(|(_, _, k)| key.partial_cmp(k) == Some(std::cmp::Ordering::Greater));
            if better {
                best = Some((c, a, key));
            }
        }
        let Some((c, a, _)) = best else {
            return whole(Some(f));
        };
        out.push(c);
        rest = Some(a);
        first = Some(f);
    }
    while out.len() < cap && !rest.as_ref().is_some_and(Analysis::agree) {
        let Some(cur) = rest.take() else { break };
        let batch = out.len().min(cap - out.len());
        let mut worst: Vec<(usize, f64)> = cur
            .sel
            .iter()
            .zip(&cur.rows)
            .map(|(&i, r)| (i, r.z))
            .collect();
        worst.sort_by(|a, b| b.1.abs().total_cmp(&a.1.abs()));
        out.extend(worst.into_iter().take(batch).map(|w| w.0));
        // The consensus model first (a rest that still holds odd releases misfits, and
        // choosing its model is the costliest step of all); the model is chosen only on a
        // rest that agrees there.
        rest = match analyse(kept, &others(n, &out), ctx, false) {
            Ok(q) if q.agree() => analyse(kept, &others(n, &out), ctx, true).ok(),
            other => other.ok(),
        };
    }
    let Some(mut cur) = rest.filter(Analysis::agree) else {
        return whole(first);
    };
    let mut aside = judge(kept, &out, &cur, ctx);
    if aside.iter().any(|r| r.agrees) {
        out = still_off(out, &aside);
        if out.is_empty() {
            return whole(first);
        }
        cur = analyse(kept, &others(n, &out), ctx, true)?;
        aside = judge(kept, &out, &cur, ctx);
        if !cur.agree() || aside.iter().any(|r| r.agrees) {
            return whole(first);
        }
    }
    Ok(Outcome {
        all_p: consistency(&own_pairs(cur.rows.iter().chain(&aside))),
        analysis: cur,
        aside,
        unresolved: false,
    })
}

/// The releases of `out` whose judgement (`aside`, in the same order) finds them off.
fn still_off(out: Vec<usize>, aside: &[ReleaseRow]) -> Vec<usize> {
    out.into_iter()
        .zip(aside)
        .filter(|(_, r)| !r.agrees)
        .map(|(i, _)| i)
        .collect()
}

/// The releases `out` judged by the rest's analysis `a` (in parallel).
fn judge(kept: &[Single], out: &[usize], a: &Analysis, ctx: &Context) -> Vec<ReleaseRow> {
    out.par_iter()
        .with_max_len(1)
        .map(|&i| score(kept, i, a, ctx))
        .collect()
}
