//! Forward selection: nuisances added one at a time while the data support them (a BIC lower
//! by more than 2), the candidates screened by the score test and the promising ones fitted in
//! parallel.

use super::attempt::{failed_row, fit_candidate};
use super::{
    chi2_of, misfits, model_weights, Candidate, ModelRow, Nuisance, SelectOptions, Selection,
};
use crate::fit::problem::MAX_FREE;
use nalgebra::DVector;
use rayon::prelude::*;

/// Under misfit, a screened candidate predicted to lower the chi-square by this share of the
/// best candidate's drop or more is fitted in the round's first batch.
const LEADING_SHARE: f64 = 0.1;

/// The round's best candidate: its nuisances, problem, optimum, chi-square and row.
type Best<M> = (Vec<Nuisance>, M, DVector<f64>, f64, usize);

/// Forward selection from the base model `problem` at its optimum `p` (chi-square `chi2`).
pub fn forward<M: Candidate>(
    problem: M,
    p: DVector<f64>,
    chi2: f64,
    opts: &SelectOptions<M::Start>,
) -> Selection<M> {
    let n = problem.n_rows() as f64;
    let bic = |k: usize, chi2: f64| chi2 + k as f64 * n.ln();
    let name_of = |ns: &[Nuisance]| {
        if ns.is_empty() {
            "base".to_owned()
        } else {
            ns.iter().map(|n| n.name()).collect::<Vec<_>>().join("+")
        }
    };
    let row = |ns: &[Nuisance], m: &M, chi2: f64| ModelRow {
        name: name_of(ns),
        free: m.free_names(),
        chi2,
        bic: bic(m.n_free(), chi2),
        delta_bic: 0.0,
        chosen: false,
        mu_kinetic: m.mu_kinetic(),
        failed: None,
        weight: 0.0,
        path: false,
    };
    let mut chosen: Vec<Nuisance> = opts.already.clone();
    let mut current = (problem, p, chi2);
    let mut rows = vec![ModelRow {
        path: true,
        ..row(&chosen, &current.0, chi2)
    }];
    let mut iterations = 0;
    for &nu in &opts.forced {
        if chosen.contains(&nu) || chosen.iter().any(|c| c.conflicts(nu)) {
            continue;
        }
        let m = current.0.with_nuisance(nu, opts.mu_static_start);
        match fit_candidate(&m, opts.fresh_start.as_ref(), opts, Some(current.2)) {
            Ok((q, cost, iters)) => {
                iterations += iters;
                let mut m = m;
                m.set_values(&q);
                chosen = nu.join(&chosen);
                rows.push(ModelRow {
                    path: true,
                    ..row(&chosen, &m, chi2_of(cost))
                });
                current = (m, q, chi2_of(cost));
            }
            Err((why, chi2, iters)) => {
                iterations += iters;
                rows.push(failed_row(row(&nu.join(&chosen), &m, chi2), why));
            }
        }
    }
    for _ in 0..opts.max_added {
        let (cur_problem, cur_p, cur_chi2) = &current;
        // The friction laws are fitted outright (no score test screens them), so only when
        // the onsets ask for them or this round's model misfits: a model that describes the
        // recording does not pay for two more fits.
        let friction =
            opts.friction_candidates && (opts.static_evidence || misfits(cur_problem, *cur_chi2));
        let open: Vec<Nuisance> = Nuisance::ALL
            .into_iter()
            .filter(|n| !chosen.contains(n) && !chosen.iter().any(|c| c.conflicts(*n)))
            .filter(|n| cur_problem.width() + n.new_params(cur_problem) <= MAX_FREE)
            .filter(|n| n.screened() || friction)
            // A pendulum the rig file gives is used as given (`--with` may still free it).
            .filter(|n| *n != Nuisance::RigidPendulum || !cur_problem.pendulum_given())
            .collect();
        if open.is_empty() {
            break;
        }
        let screened: Vec<Nuisance> = open.iter().copied().filter(|n| n.screened()).collect();
        let mut drops = cur_problem.score_drops(cur_p, &screened);
        drops.sort_by(|a, b| b.1.total_cmp(&a.1));
        // Fit the two most promising screened candidates whose predicted drop pays their BIC
        // penalty, and the friction candidates outright. A misfitting model's linearisation
        // ranks poorly: then every screened candidate is fitted, from two starts.
        let misfit = misfits(cur_problem, *cur_chi2);
        let fresh = opts.fresh_start.as_ref().filter(|_| misfit);
        let mut to_fit: Vec<Nuisance> = drops
            .iter()
            .filter(|(nu, d)| misfit || *d > nu.params().len() as f64 * n.ln())
            .take(if misfit { usize::MAX } else { 2 })
            .map(|(n, _)| *n)
            .collect();
        to_fit.extend(open.iter().copied().filter(|n| !n.screened()));
        if to_fit.is_empty() {
            break;
        }
        // Each candidate as a nuisance set and its problem. A mu_static chosen while the model
        // misfitted may be part of the compromise (a late slip fitted by static friction while
        // the pendulum's period is wrong): under misfit each candidate is also fitted without it.
        let drop_static = misfit && chosen.contains(&Nuisance::StaticFriction);
        // Under misfit the score test only orders the candidates: the first two (and their
        // variants) are fitted first, and the rest only when neither of those earns its place
        // (lowers the criterion by more than 2). The selection is greedy: one that does is
        // taken, and the next round screens the others again from the better model; fitting
        // every candidate in every round of a misfitting model cost seconds. A candidate whose
        // predicted drop is a tenth of the leader's or more is among the first too: two
        // nuisances that explain the same misfit (a marker off the rod's line and a rail
        // tilt both shift where the pendulum hangs) must both be fitted, or the one left out
        // gets no weight and mu's interval holds only the other's value.
        let top = drops.first().map_or(0.0, |d| d.1);
        let strong = drops
            .iter()
            .filter(|(_, d)| *d >= LEADING_SHARE * top)
            .count();
        let leading = if misfit { strong.max(2) } else { to_fit.len() };
        let (mut first, mut rest) = (Vec::new(), Vec::new());
        for (i, &nu) in to_fit.iter().enumerate() {
            // The friction laws, which no score test ranks, are among the first when the
            // onsets show mu_static above mu_kinetic.
            let jobs = if i < leading || (!nu.screened() && opts.static_evidence) {
                &mut first
            } else {
                &mut rest
            };
            // Nested: the current model is the candidate at its neutral values, so its fit
            // can be no worse than the current one's.
            jobs.push((
                nu.join(&chosen),
                cur_problem.with_nuisance(nu, opts.mu_static_start),
                Some(*cur_chi2),
            ));
            if drop_static && nu.supersedes() != Some(Nuisance::StaticFriction) {
                let tied = cur_problem.static_tied();
                let without: Vec<Nuisance> = chosen
                    .iter()
                    .copied()
                    .filter(|&c| c != Nuisance::StaticFriction)
                    .collect();
                jobs.push((
                    nu.join(&without),
                    tied.with_nuisance(nu, opts.mu_static_start),
                    None,
                ));
            }
        }
        let run = |jobs: Vec<(Vec<Nuisance>, M, Option<f64>)>| {
            jobs.into_par_iter()
                .with_max_len(1)
                .map(|(set, m, parent)| {
                    let solved = fit_candidate(&m, fresh, opts, parent);
                    (set, m, solved)
                })
                .collect::<Vec<_>>()
        };
        let mut fits = run(first);
        let cur_bic = bic(cur_problem.n_free(), *cur_chi2);
        let earns = fits.iter().any(|(_, m, s)| {
            s.as_ref()
                .is_ok_and(|(_, cost, _)| bic(m.n_free(), chi2_of(*cost)) < cur_bic - 2.0)
        });
        if !earns {
            fits.extend(run(rest));
        }
        let mut best: Option<Best<M>> = None;
        for (set, m, solved) in fits {
            let (q, cost, iters) = match solved {
                Ok(s) => s,
                Err((why, chi2, iters)) => {
                    iterations += iters;
                    rows.push(failed_row(row(&set, &m, chi2), why));
                    continue;
                }
            };
            iterations += iters;
            let c2 = chi2_of(cost);
            let mut fitted = m.clone();
            fitted.set_values(&q);
            rows.push(row(&set, &fitted, c2));
            let at = rows.len() - 1;
            if best
                .as_ref()
                .is_none_or(|b| bic(m.n_free(), c2) < bic(b.1.n_free(), b.3))
            {
                best = Some((set, m, q, c2, at));
            }
        }
        let Some((set, mut m, q, c2, at)) = best else {
            break;
        };
        // Positive evidence (Kass and Raftery): a BIC lower by more than 2.
        if bic(m.n_free(), c2) < bic(cur_problem.n_free(), *cur_chi2) - 2.0 {
            m.set_values(&q);
            chosen = set;
            rows[at].path = true;
            current = (m, q, c2);
        } else {
            break;
        }
    }
    let chosen_name = name_of(&chosen);
    let best_bic = bic(current.0.n_free(), current.2);
    for r in &mut rows {
        r.delta_bic = r.bic - best_bic;
        r.chosen = r.failed.is_none() && r.name == chosen_name && (r.bic - best_bic).abs() < 1e-9;
    }
    let dof = (n - current.0.n_free() as f64).max(1.0);
    model_weights(&mut rows, (current.2 / dof).max(1.0));
    let (problem, p, _) = current;
    Selection {
        problem,
        p,
        chosen,
        rows,
        iterations,
    }
}
