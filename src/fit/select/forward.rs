//! Forward selection: nuisances added one at a time while the data support them (a BIC lower
//! by more than 2), the candidates screened by the score test and the promising ones fitted in
//! parallel. [`forward`] reads as its steps: the nuisances the user forces, then rounds (the
//! open candidates, those worth fitting, their fits in two batches, the best taken or the
//! selection ended), then the table completed with the models' weights.

use super::attempt::{
    failed_row, fit_candidate, fit_candidate_within, fit_law, held_rig_start, Outcome,
};
use super::candidate::Candidate;
use super::nuisance::{Nuisance, MU_PINNED};
use super::selection::{chi2_of, misfits, ModelRow, SelectOptions, Selection};
use super::weights::model_weights;
use super::weights::OCCAM_BIC;
use crate::fit::problem::MAX_FREE;
use nalgebra::DVector;
use rayon::prelude::*;

/// Under misfit, a screened candidate predicted to lower the chi-square by this share of the
/// best candidate's drop or more is fitted in the round's first batch.
const LEADING_SHARE: f64 = 0.1;

/// Under misfit, a candidate whose criterion is within this many units of the round's best
/// (or [`HELD_SHARE`] of the best's chi-square, when more) is also fitted with the rig's
/// measured values held ([`held_rig_start`]): that start lowered a candidate's chi-square by 16
/// units where it was needed, and on a candidate far behind the round's best it only costs time
/// (four times the CPU on a recording with four effects at once).
const HELD_MARGIN: f64 = 100.0;

/// The share of the round's best chi-square within which [`HELD_MARGIN`] widens.
const HELD_SHARE: f64 = 0.02;

/// The share of the round's best chi-square (or [`HELD_MARGIN`], when more) within which a
/// candidate stopped after its first iterations (`SelectOptions::first_iters`, 15 by
/// default: most candidates converge in 3 to 9) is fitted again with the whole budget. A
/// friction law that crawls along a valley (Stribeck friction on a tilted rail: 45 to 60
/// iterations a start, each lowering the cost by 1e-4) while it lies 20 times the best
/// model's chi-square behind was 40 % of a joint fit's work. One further behind keeps
/// its chi-square at the stop, an upper bound, and is marked so; it would have to lower
/// its chi-square by a quarter or more in its last iterations to matter, which the crawls
/// measured (at most 1.3 %) never came near.
const FAR_SHARE: f64 = 0.25;

/// The round's best candidate: its nuisances, problem, optimum, chi-square and row.
type Best<M> = (Vec<Nuisance>, M, DVector<f64>, f64, usize);

/// A candidate to fit: its nuisances, its problem, and the chi-square of the model it nests
/// (`None` when it nests none).
type Job<M> = (Vec<Nuisance>, M, Option<f64>);

/// A law to weigh: as a [`Job`], with the chi-square it must reach to come within Occam's
/// window of the chosen model (+inf: fitted to its optimum whatever it reaches).
type LawJob<M> = (Vec<Nuisance>, M, Option<f64>, f64);

/// A candidate fitted: its nuisances, its problem, its optimum, cost and iterations (or why
/// it failed), and whether it was stopped after its first iterations (its chi-square an
/// upper bound).
type Fitted<M> = (Vec<Nuisance>, M, Outcome, bool);

/// A candidate in a round's first pass: as [`Fitted`], with the chi-square of the model it
/// nests (for its fit to the end).
type Trial<M> = (Vec<Nuisance>, M, Outcome, bool, Option<f64>);

/// The criterion over a sample of `n` residual rows, and the rows of the model table it scores.
struct Criterion {
    /// Residual rows (the sample size).
    n: f64,
}

impl Criterion {
    /// BIC = chi2 + k ln(n).
    fn bic(&self, k: usize, chi2: f64) -> f64 {
        chi2 + k as f64 * self.n.ln()
    }

    /// The table's row of model `m`, holding the nuisances `ns`, at chi-square `chi2`.
    fn row<M: Candidate>(&self, ns: &[Nuisance], m: &M, chi2: f64) -> ModelRow {
        ModelRow {
            stopped_early: false,
            name: name_of(ns),
            free: m.free_names(),
            chi2,
            bic: self.bic(m.n_free(), chi2),
            delta_bic: 0.0,
            chosen: false,
            mu_kinetic: m.mu_kinetic(),
            failed: None,
            weight: 0.0,
            path: false,
            implausible: m.implausible(),
        }
    }
}

/// A model's name in the table: its nuisances joined by `+`, `base` for none.
pub fn name_of(ns: &[Nuisance]) -> String {
    if ns.is_empty() {
        "base".to_owned()
    } else {
        ns.iter().map(|n| n.name()).collect::<Vec<_>>().join("+")
    }
}

/// The selection as it goes: the model it stands on and everything compared so far.
struct Search<M> {
    /// Nuisances in the current model.
    chosen: Vec<Nuisance>,
    /// The current model, its optimum and its chi-square.
    current: (M, DVector<f64>, f64),
    /// Every model fitted.
    rows: Vec<ModelRow>,
    /// Levenberg-Marquardt iterations spent.
    iterations: u64,
    /// The last round's screening at the model it stood on.
    screening: Vec<(Nuisance, f64)>,
    /// The model the selection started from (the nuisances given already), at its optimum.
    base: M,
}

/// Forward selection from the base model `problem` at its optimum `p` (chi-square `chi2`).
pub fn forward<M: Candidate>(
    problem: M,
    p: DVector<f64>,
    chi2: f64,
    opts: &SelectOptions<M::Start>,
) -> Selection<M> {
    let crit = Criterion {
        n: problem.n_rows() as f64,
    };
    let chosen: Vec<Nuisance> = opts.already.clone();
    let rows = vec![ModelRow {
        path: true,
        ..crit.row(&chosen, &problem, chi2)
    }];
    let mut base = problem.clone();
    base.set_values(&p);
    let mut search = Search {
        chosen,
        current: (problem, p, chi2),
        rows,
        iterations: 0,
        screening: Vec::new(),
        base,
    };
    add_forced(&mut search, opts, &crit);
    for _ in 0..opts.max_added {
        if !round(&mut search, opts, &crit) {
            break;
        }
    }
    swap_twins(&mut search, opts, &crit);
    weigh_laws(&mut search, opts, &crit);
    finish(search, &crit)
}

/// The nuisances the user put in the model (`--with`), added first whatever they cost: one
/// held already or in conflict with one held is passed over, one whose fit fails is a failed
/// row of the table.
fn add_forced<M: Candidate>(s: &mut Search<M>, opts: &SelectOptions<M::Start>, crit: &Criterion) {
    for &nu in &opts.forced {
        if s.chosen.contains(&nu) || s.chosen.iter().any(|c| c.conflicts(nu)) {
            continue;
        }
        let m = s.current.0.with_nuisance(nu, opts.mu_static_start);
        let fit = |m: &M| fit_candidate(m, opts.fresh_start.as_ref(), opts, Some(s.current.2));
        let solved = fit(&m);
        // Stribeck's law also from its speed's second start, the lower cost kept.
        let (m, solved) = match m.stribeck_slow_start() {
            Some(slow) => {
                let other = fit(&slow);
                lower((m, solved), (slow, other))
            }
            None => (m, solved),
        };
        let solved = match (solved, opts.fresh_start.as_ref()) {
            (Ok(got), Some(start)) => Ok(held_rig_start(&m, start, got, opts.max_iters)),
            (other, _) => other,
        };
        match solved {
            Ok((q, cost, iters)) => {
                s.iterations += iters;
                let mut m = m;
                m.set_values(&q);
                s.chosen = nu.join(&s.chosen);
                s.rows.push(ModelRow {
                    path: true,
                    ..crit.row(&s.chosen, &m, chi2_of(cost))
                });
                s.current = (m, q, chi2_of(cost));
            }
            Err((why, chi2, iters)) => {
                s.iterations += iters;
                s.rows
                    .push(failed_row(crit.row(&nu.join(&s.chosen), &m, chi2), why));
            }
        }
    }
}

/// One round: the open candidates screened, those worth it fitted, and the best taken when it
/// lowers the criterion by more than 2. Whether the selection goes on.
fn round<M: Candidate>(
    s: &mut Search<M>,
    opts: &SelectOptions<M::Start>,
    crit: &Criterion,
) -> bool {
    let (cur_problem, cur_p, cur_chi2) = &s.current;
    let open = open_candidates(&s.chosen, cur_problem, *cur_chi2, opts);
    if open.is_empty() {
        return false;
    }
    let screened: Vec<Nuisance> = open.iter().copied().filter(|n| n.screened()).collect();
    let mut drops = cur_problem.score_drops(cur_p, &screened);
    drops.sort_by(|a, b| b.1.total_cmp(&a.1));
    s.screening = drops.clone();
    let misfit = misfits(cur_problem, *cur_chi2);
    let fresh = opts.fresh_start.as_ref().filter(|_| misfit);
    let to_fit = worth_fitting(&open, &drops, misfit, crit);
    if to_fit.is_empty() {
        return false;
    }
    let (first, rest) = jobs(s, &to_fit, &drops, misfit, opts);
    let fits = best_of_each(fit_jobs(first, rest, s, fresh, opts, crit));
    let Some((set, mut m, q, c2, at)) = record(s, fits, crit) else {
        return false;
    };
    // Positive evidence (Kass and Raftery): a BIC lower by more than 2.
    if crit.bic(m.n_free(), c2) < crit.bic(s.current.0.n_free(), s.current.2) - 2.0 {
        m.set_values(&q);
        s.chosen = set;
        s.rows[at].path = true;
        s.current = (m, q, c2);
        true
    } else {
        false
    }
}

/// The candidates open to the current model (`chi2` its chi-square): not held, not in
/// conflict with one held, within the dual numbers' width. The friction laws are fitted
/// outright (no score test screens them), so only when the onsets ask for them or the model
/// misfits: a model that describes the recording does not pay for two more fits.
fn open_candidates<M: Candidate>(
    chosen: &[Nuisance],
    cur_problem: &M,
    chi2: f64,
    opts: &SelectOptions<M::Start>,
) -> Vec<Nuisance> {
    let friction = opts.friction_candidates && (opts.static_evidence || misfits(cur_problem, chi2));
    Nuisance::ALL
        .into_iter()
        .filter(|n| !chosen.contains(n) && !chosen.iter().any(|c| c.conflicts(*n)))
        .filter(|n| !opts.excluded.contains(n))
        .filter(|n| cur_problem.width() + n.new_params(|q| cur_problem.frees(q)) <= MAX_FREE)
        .filter(|n| n.screened() || friction)
        // A pendulum the rig file gives is used as given (`--with` may still free it).
        .filter(|n| *n != Nuisance::RigidPendulum || !cur_problem.pendulum_given())
        .collect()
}

/// The candidates worth fitting: the two most promising screened candidates (`drops`, best
/// first) whose predicted drop pays their BIC penalty, and the friction candidates outright.
/// A misfitting model's linearisation ranks poorly: then every screened candidate is fitted,
/// from two starts.
fn worth_fitting(
    open: &[Nuisance],
    drops: &[(Nuisance, f64)],
    misfit: bool,
    crit: &Criterion,
) -> Vec<Nuisance> {
    let mut to_fit: Vec<Nuisance> = drops
        .iter()
        .filter(|(nu, d)| misfit || *d > nu.params().len() as f64 * crit.n.ln())
        .take(if misfit { usize::MAX } else { 2 })
        .map(|(n, _)| *n)
        .collect();
    to_fit.extend(open.iter().copied().filter(|n| !n.screened()));
    to_fit
}

/// Each candidate as a job (its nuisance set and problem), in the first batch or the rest. A
/// mu_static chosen while the model misfitted may be part of the compromise (a late slip
/// fitted by static friction while the pendulum's period is wrong): under misfit each
/// candidate is also fitted without it.
fn jobs<M: Candidate>(
    s: &Search<M>,
    to_fit: &[Nuisance],
    drops: &[(Nuisance, f64)],
    misfit: bool,
    opts: &SelectOptions<M::Start>,
) -> (Vec<Job<M>>, Vec<Job<M>>) {
    let (cur_problem, _, cur_chi2) = &s.current;
    let chosen = &s.chosen;
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
        // onsets show mu_static above mu_kinetic. In the first round of a misfitting model
        // every law is among the first: the base model's score test ranks a law below the
        // nuisance that mimics it (a rail tilt is the force of friction that differs by
        // direction on a heavy slider), and the greedy selection would never come back to
        // it. Later rounds screen the laws like any nuisance (fitting them in every round
        // of a misfitting model doubled the work on a recording with four effects).
        let first_round = chosen
            .iter()
            .all(|c| opts.already.contains(c) || opts.forced.contains(c));
        let law_first = misfit && nu.is_law() && first_round;
        let jobs = if i < leading || (!nu.screened() && opts.static_evidence) || law_first {
            &mut first
        } else {
            &mut rest
        };
        // Nested: the current model is the candidate at its neutral values, so its fit
        // can be no worse than the current one's.
        let m = cur_problem.with_nuisance(nu, opts.mu_static_start);
        // Stribeck's law also from its speed's second start, a job of its own so that each
        // start is cut and finished alike ([`best_of_each`] keeps the lower).
        if let Some(slow) = m.stribeck_slow_start() {
            jobs.push((nu.join(chosen), slow, Some(*cur_chi2)));
        }
        jobs.push((nu.join(chosen), m, Some(*cur_chi2)));
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
    (first, rest)
}

/// The first batch fitted in parallel (from `fresh` too when given), and the rest only when
/// none of the first lowers the current model's criterion by more than 2. Each batch is
/// fitted `first_iters` iterations a start first, then those stopped near the best to the end
/// ([`finish_near`]).
fn fit_jobs<M: Candidate>(
    first: Vec<Job<M>>,
    rest: Vec<Job<M>>,
    s: &Search<M>,
    fresh: Option<&M::Start>,
    opts: &SelectOptions<M::Start>,
    crit: &Criterion,
) -> Vec<Fitted<M>> {
    let (cur_problem, _, cur_chi2) = &s.current;
    let budget = match opts.first_iters {
        0 => opts.max_iters,
        n => n.min(opts.max_iters),
    };
    let run = |jobs: Vec<Job<M>>| {
        jobs.into_par_iter()
            .with_max_len(1)
            .map(|(set, m, parent)| {
                let (solved, capped) = fit_candidate_within(&m, fresh, opts, parent, budget);
                (set, m, solved, capped && budget < opts.max_iters, parent)
            })
            .collect::<Vec<_>>()
    };
    let mut fits = run(first);
    finish_near(&mut fits, fresh, opts, crit);
    let cur_bic = crit.bic(cur_problem.n_free(), *cur_chi2);
    let earns = fits.iter().any(|(_, m, s, _, _)| {
        s.as_ref()
            .is_ok_and(|(_, cost, _)| crit.bic(m.n_free(), chi2_of(*cost)) < cur_bic - 2.0)
    });
    if !earns {
        fits.extend(run(rest));
        finish_near(&mut fits, fresh, opts, crit);
    }
    let mut fits: Vec<Fitted<M>> = fits
        .into_iter()
        .map(|(set, m, solved, capped, _)| (set, m, solved, capped))
        .collect();
    if let Some(start) = fresh {
        held_starts(&mut fits, start, opts, crit);
    }
    fits
}

/// The candidates stopped after their first iterations that ended within [`FAR_SHARE`] of the
/// best chi-square fitted on from where they stopped with the whole budget (those that failed
/// afresh), in parallel: those far behind keep their stop's chi-square, marked as an upper
/// bound.
fn finish_near<M: Candidate>(
    fits: &mut [Trial<M>],
    fresh: Option<&M::Start>,
    opts: &SelectOptions<M::Start>,
    crit: &Criterion,
) {
    let near = near_best(fits.iter().map(|f| (&f.1, &f.2)), FAR_SHARE, crit);
    fits.par_iter_mut()
        .with_max_len(1)
        .zip(near)
        .filter(|(f, near)| f.3 && (f.2.is_err() || *near))
        .for_each(|((_, m, solved, capped, parent), _)| {
            // On from where it stopped (the better start's point), or afresh when it failed.
            let (again, spent) = match solved {
                Ok((q, _, it)) => {
                    let mut at = m.clone();
                    at.set_values(q);
                    (fit_candidate(&at, None, opts, *parent), *it)
                }
                Err(e) => (fit_candidate(m, fresh, opts, *parent), e.2),
            };
            *solved = again.map(|(q, c, it)| (q, c, it + spent));
            *capped = false;
        });
}

/// For each fitted candidate, whether its criterion is within `share` of the round's best
/// chi-square (or [`HELD_MARGIN`], when more) of the best criterion; a failed one is not.
fn near_best<'a, M: Candidate + 'a>(
    fits: impl Iterator<Item = (&'a M, &'a Outcome)> + Clone,
    share: f64,
    crit: &Criterion,
) -> Vec<bool> {
    let bic_of = |(m, solved): (&M, &Outcome)| {
        solved.as_ref().map_or(f64::INFINITY, |(_, cost, _)| {
            crit.bic(m.n_free(), chi2_of(*cost))
        })
    };
    let best = fits.clone().map(bic_of).fold(f64::INFINITY, f64::min);
    let best_chi2 = fits
        .clone()
        .filter_map(|(_, s)| s.as_ref().ok().map(|(_, cost, _)| chi2_of(*cost)))
        .fold(f64::INFINITY, f64::min);
    let margin = HELD_MARGIN.max(share * best_chi2);
    fits.map(|f| bic_of(f) <= best + margin).collect()
}

/// The held-rig start ([`held_rig_start`]) for each fitted candidate within [`HELD_MARGIN`]
/// of the round's best criterion, in parallel.
fn held_starts<M: Candidate>(
    fits: &mut [Fitted<M>],
    start: &M::Start,
    opts: &SelectOptions<M::Start>,
    crit: &Criterion,
) {
    let near = near_best(fits.iter().map(|f| (&f.1, &f.2)), HELD_SHARE, crit);
    fits.par_iter_mut()
        .with_max_len(1)
        .zip(near)
        .filter(|(_, near)| *near)
        .for_each(|((_, m, solved, _), _)| {
            if let Ok(got) = solved {
                *got = held_rig_start(m, start, got.clone(), opts.max_iters);
            }
        });
}

/// The round's fits put in the table (a failed one marked as such) and their iterations
/// counted; the best by the criterion, with its row.
fn record<M: Candidate>(
    s: &mut Search<M>,
    fits: Vec<Fitted<M>>,
    crit: &Criterion,
) -> Option<Best<M>> {
    let mut best: Option<Best<M>> = None;
    for (set, m, solved, capped) in fits {
        let (q, cost, iters) = match solved {
            Ok(s) => s,
            Err((why, chi2, iters)) => {
                s.iterations += iters;
                s.rows.push(failed_row(crit.row(&set, &m, chi2), why));
                continue;
            }
        };
        s.iterations += iters;
        let c2 = chi2_of(cost);
        let mut fitted = m.clone();
        fitted.set_values(&q);
        s.rows.push(ModelRow {
            stopped_early: capped,
            ..crit.row(&set, &fitted, c2)
        });
        let at = s.rows.len() - 1;
        if best
            .as_ref()
            .is_none_or(|b| crit.bic(m.n_free(), c2) < crit.bic(b.1.n_free(), b.3))
        {
            best = Some((set, m, q, c2, at));
        }
    }
    best
}

/// The nuisance a chosen one stands in for on a short recording: a bob marker off the rod's
/// line and a rail tilt both move where the pendulum hangs, and one slide barely tells them
/// apart.
fn twin_of(nu: Nuisance) -> Option<Nuisance> {
    match nu {
        Nuisance::BobOffset | Nuisance::BobAcross => Some(Nuisance::RailTilt),
        _ => None,
    }
}

/// The other path the greedy selection did not take: each chosen nuisance that has a twin
/// ([`twin_of`]) not in the model is swapped for it and that model fitted from the start's
/// model (a model holding both was compared already, and the first taken had absorbed the
/// other). It takes the place of the chosen model when its criterion is lower by more than
/// 2; otherwise it stays in the table, where its weight carries its mu into the interval
/// when the recording cannot tell them apart (one slide on a damped rig took the marker for
/// the tilt, 5 to 47 standard errors off, with the tilt and damping never tried together).
fn swap_twins<M: Candidate>(s: &mut Search<M>, opts: &SelectOptions<M::Start>, crit: &Criterion) {
    let swaps: Vec<Vec<Nuisance>> = s
        .chosen
        .iter()
        .filter_map(|&nu| {
            let twin = twin_of(nu)?;
            let free = !s.chosen.contains(&twin)
                && !opts.excluded.contains(&twin)
                && !opts.forced.contains(&nu)
                && !opts.already.contains(&nu);
            free.then(|| {
                s.chosen
                    .iter()
                    .map(|&c| if c == nu { twin } else { c })
                    .collect()
            })
        })
        .collect();
    for set in swaps {
        if s.rows.iter().any(|r| r.name == name_of(&set)) {
            continue;
        }
        let mut m = s.base.clone();
        for &nu in set.iter().filter(|n| !opts.already.contains(n)) {
            if m.width() + nu.new_params(|q| m.frees(q)) > MAX_FREE {
                continue;
            }
            m = m.with_nuisance(nu, opts.mu_static_start);
        }
        match fit_candidate(&m, opts.fresh_start.as_ref(), opts, None) {
            Ok((q, cost, iters)) => {
                s.iterations += iters;
                let c2 = chi2_of(cost);
                let mut fitted = m.clone();
                fitted.set_values(&q);
                let better =
                    crit.bic(m.n_free(), c2) < crit.bic(s.current.0.n_free(), s.current.2) - 2.0;
                s.rows.push(ModelRow {
                    path: better,
                    ..crit.row(&set, &fitted, c2)
                });
                if better {
                    s.chosen = set;
                    s.current = (fitted, q, c2);
                }
            }
            Err((why, chi2, iters)) => {
                s.iterations += iters;
                s.rows.push(failed_row(crit.row(&set, &m, chi2), why));
            }
        }
    }
}

/// `jobs` and, for each that adds Stribeck's law, the same from its speed's second start
/// ([`super::nuisance::STRIBECK_SLOW_START`]); [`best_of_each`] keeps the lower of the two.
fn with_slow_starts<M: Candidate>(mut jobs: Vec<LawJob<M>>) -> Vec<LawJob<M>> {
    let slow: Vec<LawJob<M>> = jobs
        .iter()
        .filter_map(|(set, m, parent, reach)| {
            Some((set.clone(), m.stribeck_slow_start()?, *parent, *reach))
        })
        .collect();
    jobs.extend(slow);
    jobs
}

/// Starts of mu_static over mu_kinetic for the static law besides the onsets' value: its
/// cost has a valley per stick the slip ends, and a single start stalled in the wrong one
/// (reduced chi-square 3.2 where the truth gives 1.0).
const STATIC_RATIOS: [f64; 2] = [1.1, 1.3];

/// Every friction law fitted to convergence (or until it cannot come within Occam's window of
/// the chosen model, [`LawJob`]) on the chosen model's other nuisances and compared
/// on the one criterion: Coulomb's (one coefficient), static above kinetic, Stribeck's, the
/// direction and the load law, viscous friction, and, when static friction earns its place,
/// static friction with the direction or the load law. The selection's rounds only screen
/// laws (a law dropped by the score test, or fitted in an early round without the nuisances
/// found later, is no evidence against it); here each is weighed where the answer stands. The
/// best replaces the chosen model when its criterion is lower by more than 2. Skipped when
/// the user fixed the law (`--friction`, `--with` a law, `--mu-static`) or the plain model.
fn weigh_laws<M: Candidate>(s: &mut Search<M>, opts: &SelectOptions<M::Start>, crit: &Criterion) {
    let user_law = opts
        .forced
        .iter()
        .chain(&opts.already)
        .any(|n| n.is_friction());
    if opts.max_added == 0 || !opts.friction_candidates || user_law {
        return;
    }
    let core: Vec<Nuisance> = s
        .chosen
        .iter()
        .copied()
        .filter(|n| !n.is_friction())
        .collect();
    let allowed = |n: &Nuisance| !opts.excluded.contains(n);
    // Coulomb's law on the other nuisances, from the chosen optimum with the law taken out.
    let (coulomb, coulomb_chi2) = if core.len() == s.chosen.len() {
        (s.current.0.clone(), s.current.2)
    } else {
        let m = s.current.0.coulomb();
        match fit_candidate(&m, None, opts, None) {
            Ok((q, cost, iters)) => {
                s.iterations += iters;
                let mut fitted = m;
                fitted.set_values(&q);
                let c2 = chi2_of(cost);
                s.rows.push(crit.row(&core, &fitted, c2));
                (fitted, c2)
            }
            Err((why, chi2, iters)) => {
                s.iterations += iters;
                s.rows.push(failed_row(crit.row(&core, &m, chi2), why));
                return;
            }
        }
    };
    let mu_k = coulomb.mu_kinetic();
    let cur_bic = crit.bic(s.current.0.n_free(), s.current.2);
    let misfit = misfits(&coulomb, coulomb_chi2);
    let push = |jobs: &mut Vec<LawJob<M>>, set: &[Nuisance], mu_s: f64| {
        let mut m = coulomb.clone();
        for &nu in set {
            m = m.with_nuisance(nu, mu_s);
        }
        let mut all = core.clone();
        for &nu in set {
            all = nu.join(&all);
        }
        // A model the selection fitted on these nuisances already is in the table: it did
        // not beat the model chosen then, nor can it the chosen one now.
        let done = s
            .rows
            .iter()
            .any(|r| r.failed.is_none() && !r.stopped_early && same_set(&r.name, &all));
        let fits = coulomb.width()
            + set
                .iter()
                .map(|n| n.new_params(|q| coulomb.frees(q)))
                .sum::<usize>();
        // A smooth law from its neutral value, on a model that fits: its first Gauss-Newton
        // step predicts its drop, and it stops there when even that cannot bring it within
        // Occam's window of the chosen model (the direction law and viscous friction on the
        // shipped example: 3 and 2 iterations for 1.1 and 1.7 units, each 8 short of it).
        // `first_iters` 0 asks for every candidate to the end: no such stop then.
        let smooth = matches!(
            set,
            [Nuisance::Direction | Nuisance::Load | Nuisance::ViscousFriction]
        );
        let reach = if smooth && !misfit && opts.first_iters > 0 {
            cur_bic + OCCAM_BIC - crit.bic(m.n_free(), 0.0)
        } else {
            f64::INFINITY
        };
        if !done && fits <= MAX_FREE && set.iter().all(allowed) {
            jobs.push((all, m, Some(coulomb_chi2), reach));
        }
    };
    // Static friction (a threshold has no gradient at mu_static = mu_kinetic: no score test
    // can screen it), the direction and the load law and viscous friction, each fitted
    // outright: on a load-law recording whose other nuisances had taken part of the load's
    // effect, the load law lowered the chi-square by 310. Static friction starts just above
    // the tie unless the onsets show it higher: from the onsets' guess, a law the recording
    // does not have took 7 iterations to come back.
    let mut jobs: Vec<LawJob<M>> = Vec::new();
    let static_start = if opts.static_evidence {
        opts.mu_static_start
    } else {
        1.02 * mu_k
    };
    push(&mut jobs, &[Nuisance::StaticFriction], static_start);
    for law in [
        Nuisance::Direction,
        Nuisance::Load,
        Nuisance::ViscousFriction,
    ] {
        push(&mut jobs, &[law], opts.mu_static_start);
    }
    let mut best = fit_law_jobs(with_slow_starts(jobs), opts);
    let static_fit = best
        .iter()
        .find(|(set, ..)| set.len() == core.len() + 1 && set.contains(&Nuisance::StaticFriction))
        .and_then(|(_, m, got, _)| {
            got.as_ref().ok().map(|g| {
                let mut at = m.clone();
                at.set_values(&g.0);
                (at, chi2_of(g.1))
            })
        });
    // Static friction that lowers the chi-square by a unit or more: its other starts, with
    // the direction or the load law too, and Stribeck's law from its optimum (at v_s -> 0
    // Stribeck's law is the static one; where mu_static adds nothing, Stribeck's speed has no
    // gradient and its fit crawled 38-45 iterations along that valley for no change).
    let mut more: Vec<LawJob<M>> = Vec::new();
    if let Some((at, c2)) = static_fit.filter(|(_, c2)| *c2 < coulomb_chi2 - 1.0) {
        let earns = c2 < coulomb_chi2 - crit.n.ln() - 2.0;
        if earns {
            let onsets = (static_start != opts.mu_static_start).then_some(opts.mu_static_start);
            for mu_s in STATIC_RATIOS.iter().map(|r| r * mu_k).chain(onsets) {
                push(&mut more, &[Nuisance::StaticFriction], mu_s);
            }
            for law in [Nuisance::Direction, Nuisance::Load] {
                push(
                    &mut more,
                    &[law, Nuisance::StaticFriction],
                    opts.mu_static_start,
                );
            }
        }
        let mut stribeck = Vec::new();
        push(&mut stribeck, &[Nuisance::Stribeck], at.mu_static());
        for (set, m, parent, reach) in stribeck {
            // From the static law's optimum: its mu_static and mu_kinetic, and the state.
            let m = m.adopt(&at.with_nuisance(Nuisance::Stribeck, at.mu_static()));
            more.push((set, m, parent, reach));
        }
    }
    best.extend(fit_law_jobs(with_slow_starts(more), opts));
    let best = best_of_each(best);
    let mut winner: Option<Best<M>> = None;
    for (set, m, solved, capped) in best {
        let same = same_nuisances(&set, &s.chosen);
        match solved {
            Ok((q, cost, iters)) => {
                s.iterations += iters;
                if same {
                    continue;
                }
                let c2 = chi2_of(cost);
                let mut at = m.clone();
                at.set_values(&q);
                // A law that measures no friction coefficient (mu_kinetic pinned at 0 while
                // Stribeck's law or viscous friction carries it all, where Coulomb's law finds
                // friction) is no dry rail's law: listed as needing what no real rig has, it
                // cannot take the model (air drag on a heavy rig: Stribeck with mu_kinetic 0
                // and a 1.4 m/s speed, 5,600 below in chi-square, and a failed fit).
                let pinned = set.iter().any(|n| n.carries_friction_alone())
                    && at.mu_kinetic() < MU_PINNED
                    && mu_k >= MU_PINNED;
                let row = crit.row(&set, &at, c2);
                s.rows.push(ModelRow {
                    stopped_early: capped,
                    implausible: row.implausible || pinned,
                    ..row
                });
                let bic = crit.bic(m.n_free(), c2);
                let beats = !capped
                    && !pinned
                    && bic < cur_bic - 2.0
                    && winner
                        .as_ref()
                        .is_none_or(|w| bic < crit.bic(w.1.n_free(), w.3));
                if beats {
                    winner = Some((set, at, q, c2, s.rows.len() - 1));
                }
            }
            Err((why, chi2, iters)) => {
                s.iterations += iters;
                if !same {
                    s.rows.push(failed_row(crit.row(&set, &m, chi2), why));
                }
            }
        }
    }
    if let Some((set, m, q, c2, at)) = winner {
        s.rows[at].path = true;
        s.chosen = set;
        s.current = (m, q, c2);
    }
}

/// The laws' fits, in parallel. One that used every iteration is marked so (its chi-square
/// an upper bound, `stopped_early` in the table) and cannot take the model.
fn fit_law_jobs<M: Candidate>(
    jobs: Vec<LawJob<M>>,
    opts: &SelectOptions<M::Start>,
) -> Vec<Fitted<M>> {
    jobs.into_par_iter()
        .with_max_len(1)
        .map(|(set, m, parent, reach)| {
            let (solved, capped) = fit_law(&m, opts, parent, reach);
            (set, m, solved, capped)
        })
        .collect()
}

/// Whether two sets of nuisances are the same, whatever their order.
fn same_nuisances(a: &[Nuisance], b: &[Nuisance]) -> bool {
    a.len() == b.len() && a.iter().all(|n| b.contains(n))
}

/// Whether the model row named `name` holds exactly the nuisances `set`.
fn same_set(name: &str, set: &[Nuisance]) -> bool {
    let ns: Vec<&str> = if name == "base" {
        Vec::new()
    } else {
        name.split('+').collect()
    };
    ns.len() == set.len() && set.iter().all(|n| ns.contains(&n.name()))
}

/// The best fit of each nuisance set among several starts (the iterations of all counted).
fn best_of_each<M: Candidate>(fits: Vec<Fitted<M>>) -> Vec<Fitted<M>> {
    let mut out: Vec<Fitted<M>> = Vec::new();
    for (set, m, solved, capped) in fits {
        match out.iter().position(|o| same_nuisances(&o.0, &set)) {
            None => out.push((set, m, solved, capped)),
            Some(i) => {
                let (s0, m0, solved0, capped0) = out.remove(i);
                let ((set, m, capped), solved) =
                    lower(((s0, m0, capped0), solved0), ((set, m, capped), solved));
                out.insert(i, (set, m, solved, capped));
            }
        }
    }
    out
}

/// The lower-cost of two fits of one candidate (`a` on a tie or when both failed), with the
/// iterations of both.
fn lower<T>(a: (T, Outcome), b: (T, Outcome)) -> (T, Outcome) {
    let spent = |x: &Outcome| x.as_ref().map_or_else(|e| e.2, |g| g.2);
    let total = spent(&a.1) + spent(&b.1);
    let b_lower = match (&a.1, &b.1) {
        (Ok(x), Ok(y)) => y.1 < x.1,
        (Err(_), Ok(_)) => true,
        _ => false,
    };
    let (t, mut o) = if b_lower { b } else { a };
    match &mut o {
        Ok(g) => g.2 = total,
        Err(e) => e.2 = total,
    }
    (t, o)
}

/// The table completed: each row's BIC against the chosen model's, the chosen row marked and
/// every model's weight.
fn finish<M: Candidate>(s: Search<M>, crit: &Criterion) -> Selection<M> {
    let Search {
        chosen,
        current,
        mut rows,
        iterations,
        screening,
        ..
    } = s;
    let chosen_name = name_of(&chosen);
    let best_bic = crit.bic(current.0.n_free(), current.2);
    for r in &mut rows {
        r.delta_bic = r.bic - best_bic;
        r.chosen = r.failed.is_none() && r.name == chosen_name && (r.bic - best_bic).abs() < 1e-9;
    }
    let dof = (crit.n - current.0.n_free() as f64).max(1.0);
    model_weights(&mut rows, (current.2 / dof).max(1.0));
    let (problem, p, _) = current;
    Selection {
        problem,
        p,
        chosen,
        rows,
        iterations,
        screening,
    }
}
