//! The score test: the chi-square drop each candidate nuisance would buy, predicted from the
//! augmented normal equations at the current optimum, so that only the promising candidates
//! are fitted.

use super::{Candidate, Nuisance};
use crate::fit::problem::{Param, TrajectoryProblem, MAX_FREE};
use nalgebra::DVector;

/// Score-test drops of `candidates` for any model `m` (its values at the optimum), one augmented normal-equation pass per
/// candidate: with residuals r and base columns B at the optimum and candidate columns C,
/// drop = (C'r)' S^-1 (C'r) with S = C'C - C'B (B'B)^-1 B'C. `augmented(nu)` gives the model
/// with `nu` added at its neutral value and the positions of the base model's parameters in
/// its parameter vector.
pub fn score_drops_by<M: Candidate>(
    m: &M,
    candidates: &[Nuisance],
    augmented: impl Fn(Nuisance) -> (M, Vec<usize>),
) -> Vec<(Nuisance, f64)> {
    candidates
        .iter()
        .filter(|nu| m.width() + nu.new_params(m) <= MAX_FREE)
        .map(|&nu| {
            let (aug, base_cols) = augmented(nu);
            let q = aug.values();
            let drop = aug.normal_equations(&q).ok().and_then(|nq| {
                let cols: Vec<usize> = (0..q.len()).filter(|i| !base_cols.contains(i)).collect();
                let btb_inv = nq
                    .jtj
                    .select_rows(&base_cols)
                    .select_columns(&base_cols)
                    .try_inverse()?;
                let g = nq.jtr.select_rows(&cols);
                let bc = nq.jtj.select_rows(&base_cols).select_columns(&cols);
                let ctc = nq.jtj.select_rows(&cols).select_columns(&cols);
                let s = ctc - bc.transpose() * &btb_inv * &bc;
                s.try_inverse().map(|si| (g.transpose() * si * &g)[(0, 0)])
            });
            (nu, drop.filter(|d| d.is_finite()).unwrap_or(0.0))
        })
        .collect()
}

/// Predicted chi-square drops of the screened candidates from one augmented Jacobian per
/// group of columns (the score test): with residuals r and base columns B at the optimum and
/// candidate columns C, drop = (C'r)' S^-1 (C'r) with S = C'C - C'B (B'B)^-1 B'C. The camera's
/// candidates join the first group's pass: their columns come from the observation model
/// alone ([`TrajectoryProblem::normal_equations_observed`]), so only the rig's candidates
/// widen the dual numbers carried through the motion.
pub(super) fn score_drops(
    problem: &TrajectoryProblem,
    p: &DVector<f64>,
    candidates: &[Nuisance],
) -> Vec<(Nuisance, f64)> {
    let k = problem.free.len();
    let room = MAX_FREE.saturating_sub(k);
    let seen_only = |n: &Nuisance| {
        n.params()
            .iter()
            .all(|q| q.is_camera() && !problem.free.contains(q))
    };
    let mut out = Vec::new();
    let mut group: Vec<Nuisance> = Vec::new();
    let mut seen: Vec<Nuisance> = candidates.iter().copied().filter(seen_only).collect();
    let flush = |group: &mut Vec<Nuisance>, seen: &mut Vec<Nuisance>, out: &mut Vec<_>| {
        if group.is_empty() && seen.is_empty() {
            return;
        }
        let mut aug = problem.clone();
        // Only the parameters not free already: the rigid pendulum's mass ratio is free
        // whenever the rig file's masses are measured, and a column twice made the group's
        // pass fail, which silently dropped every candidate tested with it (the camera's
        // among them).
        for n in group.iter() {
            for &q in n.params() {
                if !aug.free.contains(&q) {
                    aug.free.push(q);
                }
            }
        }
        // Each camera parameter once (candidates may share one: the bob's offset across the
        // rod is in both bob candidates).
        let mut extra: Vec<Param> = Vec::new();
        for &q in seen.iter().flat_map(|n| n.params()) {
            if !extra.contains(&q) {
                extra.push(q);
            }
        }
        let mut q = p.clone().resize_vertically(aug.free.len(), 0.0);
        for (i, &param) in aug.free.iter().enumerate().skip(k) {
            q[i] = problem.get(param);
        }
        // Every block the score test needs is a block of the augmented normal equations:
        // B'B, B'C, C'C and C'r.
        if let Ok(nq) = aug.normal_equations_observed(&q, &extra) {
            let btb = nq.jtj.view((0, 0), (k, k)).into_owned();
            if let Some(btb_inv) = btb.try_inverse() {
                // The columns of each candidate's parameters in the augmented equations.
                let mut cols: Vec<Vec<usize>> = Vec::new();
                for n in group.iter() {
                    cols.push(
                        n.params()
                            .iter()
                            .filter(|q| !problem.free.contains(q))
                            .filter_map(|q| aug.free.iter().position(|f| f == q))
                            .collect(),
                    );
                }
                let col = aug.free.len();
                for n in seen.iter() {
                    cols.push(
                        n.params()
                            .iter()
                            .filter_map(|q| extra.iter().position(|e| e == q))
                            .map(|j| col + j)
                            .collect(),
                    );
                }
                for (n, c) in group.iter().chain(seen.iter()).zip(&cols) {
                    if c.is_empty() {
                        // Nothing new to test: its parameters are all free already.
                        out.push((*n, 0.0));
                        continue;
                    }
                    let g = nq.jtr.select_rows(c);
                    let bc = nq.jtj.rows(0, k).select_columns(c);
                    let ctc = nq.jtj.select_rows(c).select_columns(c);
                    let s = ctc - bc.transpose() * &btb_inv * &bc;
                    let drop = s
                        .try_inverse()
                        .map(|si| (g.transpose() * si * &g)[(0, 0)])
                        .unwrap_or(0.0);
                    out.push((*n, if drop.is_finite() { drop } else { 0.0 }));
                }
            }
        }
        group.clear();
        seen.clear();
    };
    for &n in candidates.iter().filter(|n| !seen_only(n)) {
        if group.iter().map(|g| g.params().len()).sum::<usize>() + n.params().len() > room {
            flush(&mut group, &mut seen, &mut out);
        }
        if n.params().len() <= room {
            group.push(n);
        }
    }
    flush(&mut group, &mut seen, &mut out);
    // In the candidates' order, which breaks ties.
    out.sort_by_key(|(n, _)| candidates.iter().position(|c| c == n));
    out
}
