//! The releases that disagree, set aside by re-choosing the model without them: a release is
//! named only when its own mu lies more than 3 standard errors off the others' under a model
//! chosen on the others alone. The nuisances chosen on every release may have absorbed the
//! odd one (a friction law that differs by direction, a marker lag) and made clean releases
//! look odd; a model chosen without it does not.

use super::agreement::consistency;
use super::analysis::{analyse, score, Analysis, Context};
use super::singles::Single;
use super::{JointError, ReleaseRow};
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
/// than 3 off, [`by_single_fits`]), and the one whose own mu lies farthest off under `a`.
fn candidates(a: &Analysis, zs: &[f64], out: &[usize]) -> Vec<usize> {
    let by_single = (0..zs.len())
        .filter(|i| !out.contains(i))
        .max_by(|&x, &y| zs[x].abs().total_cmp(&zs[y].abs()));
    let per_row = |r: &ReleaseRow| r.chi2 / r.n_residuals.max(1) as f64;
    let worst_fit = a
        .rows
        .iter()
        .zip(&a.sel)
        .max_by(|x, y| per_row(x.0).total_cmp(&per_row(y.0)))
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

/// The releases set aside. While the releases kept disagree: the first round tries the
/// [`candidates`] in turn, each with the model re-chosen on the rest, and keeps the first
/// whose rest agrees and which lies off it (or else the one whose rest agrees best); later rounds set aside as many more as are out (1, 1, 2, 4: the analyses
/// are logarithmic in the releases), the worst under the last rest's model, up to half.
/// Then each release set aside is judged by the rest's model, and one within 3 standard
/// errors of it is taken back (the rest re-analysed without it once). When the rest still
/// disagree, or every release comes back, the search is unresolved and every release's
/// analysis stands.
pub(super) fn set_aside(kept: &[Single], ctx: &Context) -> Result<Outcome, JointError> {
    let n = kept.len();
    let cap = (n / 2).min(n.saturating_sub(2));
    let zs = single_z(kept);
    if cap > 0 {
        if let Some(found) = by_single_fits(kept, &zs, cap, ctx) {
            return Ok(found);
        }
    }
    let all: Vec<usize> = (0..n).collect();
    // A quick look first: every release under the single fits' consensus model. When they
    // agree there, the model is chosen on all of them; when they do not, it ranks the
    // candidates, and the model is chosen only on the sets tried (a model chosen on every
    // release, the odd one among them, is the most costly and the least useful).
    let quick = analyse(kept, &all, ctx, false)?;
    let first = if quick.agree() {
        analyse(kept, &all, ctx, true)?
    } else {
        quick
    };
    let all_p = first.consistency_p;
    // Every release's analysis, the model chosen on all (when the search finds no set).
    // No set found: every release with the model chosen on all of them (when only the quick
    // look found them disagreeing, that model may agree after all).
    let unresolved = |first: Analysis| -> Result<Outcome, JointError> {
        let analysis = if first.model.selected {
            first
        } else {
            analyse(kept, &all, ctx, true)?
        };
        Ok(Outcome {
            all_p: analysis.consistency_p,
            unresolved: !analysis.agree(),
            analysis,
            aside: Vec::new(),
        })
    };
    if first.agree() {
        return Ok(Outcome {
            analysis: first,
            aside: Vec::new(),
            unresolved: false,
            all_p,
        });
    }
    if cap == 0 {
        return unresolved(first);
    }
    let mut out: Vec<usize> = Vec::new();
    let mut rest: Option<Analysis> = None;
    while out.len() < cap {
        let cur = rest.as_ref().unwrap_or(&first);
        if rest.is_some() && cur.agree() {
            break;
        }
        if out.is_empty() {
            let mut best: Option<(usize, Analysis, (bool, f64, f64))> = None;
            for c in candidates(cur, &zs, &out) {
                let Ok(a) = analyse(kept, &others(n, &[c]), ctx, true) else {
                    continue;
                };
                let z = score(kept, c, &a, ctx).z.abs();
                let key = (a.agree(), a.consistency_p.unwrap_or(1.0), z);
                let better = best.as_ref().is_none_or(|(_, _, k)| {
                    (key.0, key.1, key.2).partial_cmp(&(k.0, k.1, k.2))
                        == Some(std::cmp::Ordering::Greater)
                });
                if better {
                    best = Some((c, a, key));
                }
                // A rest that agrees and a release off it: no other candidate can do better
                // than agree (each try is a model chosen again).
                if best.as_ref().is_some_and(|b| b.2 .0 && b.2 .2 > 3.0) {
                    break;
                }
            }
            let Some((c, a, _)) = best else {
                return unresolved(first);
            };
            out.push(c);
            rest = Some(a);
        } else {
            let batch = out.len().min(cap - out.len());
            let mut worst: Vec<(usize, f64)> = cur
                .sel
                .iter()
                .zip(&cur.rows)
                .map(|(&i, r)| (i, r.z))
                .collect();
            worst.sort_by(|a, b| b.1.abs().total_cmp(&a.1.abs()));
            out.extend(worst.into_iter().take(batch).map(|w| w.0));
            match analyse(kept, &others(n, &out), ctx, true) {
                Ok(a) => rest = Some(a),
                Err(_) => return unresolved(first),
            }
        }
    }
    let Some(mut cur) = rest.filter(Analysis::agree) else {
        return unresolved(first);
    };
    let mut aside = judge(kept, &out, &cur, ctx);
    if aside.iter().any(|r| r.agrees) {
        out = still_off(out, &aside);
        if out.is_empty() {
            return unresolved(first);
        }
        cur = analyse(kept, &others(n, &out), ctx, true)?;
        aside = judge(kept, &out, &cur, ctx);
        if !cur.agree() || aside.iter().any(|r| r.agrees) {
            return unresolved(first);
        }
    }
    Ok(Outcome {
        analysis: cur,
        aside,
        unresolved: false,
        all_p,
    })
}

/// The quick way, when the single fits alone point at releases (|z| above 3 against the
/// others' weighted median, at most `cap`, the largest first): the rest analysed without
/// them, each judged by the rest's model; one within 3 standard errors of it is taken back
/// (the rest analysed once more). The outcome when the rest agree and every release left
/// out lies off them; otherwise `None`, and the search starts from every release.
fn by_single_fits(kept: &[Single], zs: &[f64], cap: usize, ctx: &Context) -> Option<Outcome> {
    let mut out: Vec<usize> = (0..kept.len()).filter(|&i| zs[i].abs() > 3.0).collect();
    out.sort_by(|&a, &b| zs[b].abs().total_cmp(&zs[a].abs()));
    out.truncate(cap);
    for _ in 0..2 {
        if out.is_empty() {
            return None;
        }
        let rest = analyse(kept, &others(kept.len(), &out), ctx, true).ok()?;
        if !rest.agree() {
            return None;
        }
        let aside = judge(kept, &out, &rest, ctx);
        if aside.iter().all(|r| !r.agrees) {
            let pairs: Vec<(f64, f64)> = rest
                .rows
                .iter()
                .chain(&aside)
                .map(|r| r.own_mu.map_or((f64::NAN, 0.0), |e| (e.value, e.stderr)))
                .collect();
            return Some(Outcome {
                all_p: consistency(&pairs),
                analysis: rest,
                aside,
                unresolved: false,
            });
        }
        out = still_off(out, &aside);
    }
    None
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
