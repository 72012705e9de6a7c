//! Plan experiments: releases of the rig that make the wanted mode transitions happen inside
//! the recording, large enough for the camera, for any mu within its uncertainty and any
//! release within its execution error, ranked by how well a fit of the recording would pin
//! down mu (the predicted standard error from the fit's own Jacobian).
//!
//! [`plan`] runs the search of [`search`] and, when no release can work, says why and what the
//! nearest achievable release is.

pub mod criteria;
pub mod discriminate;
pub mod law;
pub mod prior;
pub mod reach;
pub mod rig_match;
pub mod search;
pub mod spec;

pub use criteria::{Criteria, Evaluation, Hit};
pub use spec::{PlanSpec, Target, Uncertain};

use crate::model::regions::{max_mass_ratio_for_paradox, mu_critical};
use crate::model::{Rig, Shorthands, State};
use crate::sim::{Event, Request, Sample};
use indicatif::ProgressBar;
use rayon::prelude::*;
use search::{Candidate, Draws, Evaluator, ReleaseValues};
use std::f64::consts::PI;
use thiserror::Error;

/// One proposed release with its predicted recording.
#[derive(Debug, Clone)]
pub struct Proposal {
    /// The release (x, theta, x', theta').
    pub initial: State<f64>,
    /// The nominal run's events.
    pub events: Vec<Event>,
    /// The nominal run's verdict with every margin.
    pub nominal: Evaluation,
    /// Claimed robustness: a one-sided 95% lower bound of the fraction of draws (mu across its
    /// uncertainty, release error) showing every target.
    pub robustness: f64,
    /// The fraction observed in the check's draws.
    pub robustness_observed: f64,
    /// Number of draws of the check.
    pub draws: usize,
    /// Predicted standard error of mu_kinetic (fit of mu and the initial state).
    pub predicted_mu_stderr: f64,
    /// Whether the claimed robustness reaches the plan's `min_robustness`.
    pub meets_min_robustness: bool,
    /// When the plan weighs laws: each pair's separation by this release (the planned
    /// recording added to what came before), worst first.
    pub separations: Vec<discriminate::Separation>,
    /// The expected number of pairs of laws a fit will resolve with this release (NaN when
    /// the plan weighs no laws).
    pub separation: f64,
    /// Predicted standard errors of each weighed law's parameters (mu_kinetic and the
    /// law's own) from a recording of this release, the law at its reference departure,
    /// with their range over the departures a law may have.
    pub law_stderr: Vec<law::LawError>,
    /// Samples of the nominal run at the frame rate (for figures).
    pub samples: Vec<Sample<f64>>,
}

impl Proposal {
    /// Whether the proposal is ranked: its robustness reaches the plan's `min_robustness` and
    /// a recording of it pins mu down (a finite predicted standard error).
    pub fn ranked(&self) -> bool {
        self.meets_min_robustness && self.predicted_mu_stderr.is_finite()
    }
}

/// What the plan cannot do, and the closest thing it can.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Nearest {
    /// One or more sentences: why, and what would work.
    pub message: String,
    /// A release outside the feasible set that shows every target at the nominal friction
    /// (x, theta, x', theta'), when one was found.
    pub release: Option<State<f64>>,
    /// Its robustness over the search's draws.
    pub robustness: Option<f64>,
}

/// A side of an allowed range.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Limit {
    /// The range's smallest value.
    Lower,
    /// The range's largest value.
    Upper,
}

impl std::fmt::Display for Limit {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Limit::Lower => "lower",
            Limit::Upper => "upper",
        })
    }
}

/// The best proposal at a limit of the release box: a wider range there may do better.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct AtLimit {
    /// The plan file's key of the range (`release.theta_deg`, `release.theta_dot`,
    /// `release.x_dot`).
    pub quantity: &'static str,
    /// Which end of the range.
    pub limit: Limit,
    /// The limit, in the key's unit.
    pub bound: f64,
    /// The proposal's value, in the key's unit.
    pub value: f64,
}

/// A release closer than this fraction of a range to one of its ends is at that limit.
pub const AT_LIMIT_FRACTION: f64 = 0.015;

/// The planner's answer.
#[derive(Debug, Clone)]
pub struct PlanReport {
    /// Whether some release meets every criterion with the required robustness (that is,
    /// whether `proposals` has any).
    pub feasible: bool,
    /// The targets.
    pub targets: Vec<Target>,
    /// Ranked proposals, best first by predicted stderr: only releases whose claimed
    /// robustness reaches `min_robustness` (and whose mu is identifiable).
    pub proposals: Vec<Proposal>,
    /// The search's other choices, listed apart and never ranked: below `min_robustness` in
    /// the fresh check (or mu not identifiable), most robust first; only when fewer than
    /// `top` proposals are ranked, and at most as many as fill the list up to `top`.
    pub unranked: Vec<Proposal>,
    /// The plan's `min_robustness`.
    pub min_robustness: f64,
    /// The release box (theta rad, theta' rad/s, x' m/s), as the plan file allows.
    pub release_box: [[f64; 2]; 3],
    /// The limits of the box the best proposal sits at (empty when none).
    pub at_limit: Vec<AtLimit>,
    /// When infeasible: why, and the nearest achievable.
    pub nearest: Option<Nearest>,
    /// Facts worth knowing (paradox threshold and the like).
    pub notes: Vec<String>,
    /// Releases simulated at the nominal friction during the search.
    pub evaluated: usize,
    /// The rig at nominal friction.
    pub rig: Rig<f64>,
    /// mu's standard error known before (the fit of `--after`): each proposal's predicted
    /// standard error is mu's after adding it to that knowledge.
    pub prior_mu_stderr: Option<f64>,
    /// The laws weighed (empty: the plan ranks by mu's precision).
    pub laws: Vec<law::Law>,
    /// Why these laws, or why none, in plain sentences.
    pub law_notes: Vec<String>,
}

/// A plan that could not be computed.
#[derive(Debug, Error)]
pub enum PlanError {
    /// The nominal run of a proposal could not be repeated for the report.
    #[error("simulating the proposal from {initial:?} failed: {message}")]
    Simulation {
        /// The release.
        initial: State<f64>,
        /// The simulator's message.
        message: String,
    },
}

/// Plan with no progress display.
pub fn plan(spec: &PlanSpec) -> Result<PlanReport, PlanError> {
    plan_with_progress(spec, &ProgressBar::hidden())
}

/// Plan, advancing `bar` once per release judged on the grid.
pub fn plan_with_progress(spec: &PlanSpec, bar: &ProgressBar) -> Result<PlanReport, PlanError> {
    let mut ev = Evaluator::new(spec);
    let planned_rows = 4.0 * spec.camera.frame_times().len() as f64;
    let (laws, law_notes) = discriminate::resolve(&ev, planned_rows);
    let weighed: Vec<law::Law> = laws
        .as_ref()
        .map_or_else(Vec::new, |l| l.candidates.iter().map(|c| c.0).collect());
    ev.laws = laws;
    let ev = ev;
    // Only a law plan searches at the looser tolerance (its ranking moves in steps of a
    // pair's chance); a plan for mu's precision keeps its proposals as they were.
    let search_ev = match ev.laws {
        Some(_) => ev.searching(),
        None => ev.clone(),
    };
    let ranges = search::release_box(spec);
    let points = search::grid(&ranges, spec.search.grid_points);
    bar.set_length(points.len() as u64);
    let draws = Draws::new(spec.search.draws, spec.search.seed);
    let min_rob = spec.goal.min_robustness;
    let mut notes = paradox_notes(spec);
    let mut grid_found = search::screen(&search_ev, &points, &draws, bar);
    let evaluated = points.len();
    grid_found.retain(|c| c.usable() || c.robustness > 0.0);
    if grid_found.is_empty() {
        bar.finish_and_clear();
        let nearest = nearest(&ev, &draws);
        return Ok(PlanReport {
            feasible: false,
            targets: spec.goal.targets.clone(),
            proposals: Vec::new(),
            unranked: Vec::new(),
            min_robustness: min_rob,
            release_box: ranges,
            at_limit: Vec::new(),
            nearest: Some(nearest),
            notes,
            evaluated,
            rig: spec.rig,
            prior_mu_stderr: prior_mu_stderr(spec),
            laws: weighed,
            law_notes,
        });
    }
    grid_found.sort_by(|a, b| a.objective(min_rob).total_cmp(&b.objective(min_rob)));
    // Refine a few distinct grid winners; keep the rest of the grid as fallbacks. A winner
    // that already tells every pair of laws apart by the margin cap is kept as it is: moving
    // it could only buy mu's precision, and a move judged at the laws' reference departures
    // alone has found releases whose other departures show nothing.
    let seeds = distinct(&grid_found, &ranges, spec.search.top.min(4));
    let refined: Vec<Candidate> = seeds
        .par_iter()
        .map(|c| match c.saturated {
            true => *c,
            false => search::refine(&search_ev, &draws, c, 30),
        })
        .collect();
    let mut pool = refined;
    pool.extend(grid_found.iter().copied());
    pool.sort_by(|a, b| a.objective(min_rob).total_cmp(&b.objective(min_rob)));
    let top = spec.search.top;
    let chosen = distinct(&pool, &ranges, top);
    // The claim comes from fresh draws, so selection on the search's draws cannot inflate it.
    let check = Draws::new(
        spec.search.verify_draws,
        spec.search.seed.wrapping_add(0x5eed),
    );
    // First the fresh robustness and mu's error alone (what decides a release's place);
    // the rivals' full fits and the laws' errors only for the releases reported.
    let fresh_all =
        |cs: &[Candidate]| -> Vec<Fresh> { cs.par_iter().map(|c| fresh(&ev, &check, c)).collect() };
    let mut all = fresh_all(&chosen);
    // A release failing the fresh check leaves a place free: once more, the best candidates
    // away from every release checked so far (a failed one's neighbours would likely fail too).
    let ranked = all.iter().filter(|f| f.ranked(min_rob)).count();
    if ranked < all.len() {
        let checked: Vec<ReleaseValues> = all.iter().map(|f| f.candidate.release).collect();
        let rest: Vec<Candidate> = pool
            .iter()
            .filter(|c| far_from(&ranges, &checked, &c.release))
            .copied()
            .collect();
        let second = distinct(&rest, &ranges, top - ranked);
        all.extend(fresh_all(&second));
    }
    // Only releases meeting the plan's own rule are ranked. The others fill the list up to
    // `top`, apart and unranked (the most robust first, away from the ranked ones and from each
    // other); with `top` ranked ones they are dropped.
    let seen: Vec<ReleaseValues> = all.iter().map(|f| f.candidate.release).collect();
    let (kept, mut failed): (Vec<Fresh>, Vec<Fresh>) =
        all.into_iter().partition(|f| f.ranked(min_rob));
    failed.sort_by_key(|f| std::cmp::Reverse(f.passed));
    let mut taken: Vec<ReleaseValues> = kept.iter().map(|f| f.candidate.release).collect();
    let mut kept_failed = Vec::new();
    for f in failed {
        if kept.len() + kept_failed.len() < top && far_from(&ranges, &taken, &f.candidate.release) {
            taken.push(f.candidate.release);
            kept_failed.push(f);
        }
    }
    let full = |fs: &[Fresh]| {
        fs.par_iter()
            .map(|f| checked(&ev, f))
            .collect::<Result<Vec<_>, PlanError>>()
    };
    let mut proposals = full(&kept)?;
    let unranked = full(&kept_failed)?;
    bar.finish_and_clear();
    if let Some(laws) = ev.laws.as_ref() {
        proposals.sort_by(|a, b| law_key(a).total_cmp(&law_key(b)));
        let look = SecondLook {
            ev: &ev,
            search: &search_ev,
            laws,
            pool: &pool,
            seen: &seen,
            check: &check,
            min_robustness: min_rob,
        };
        if let Some((found, note)) = look.run(&proposals) {
            let more: Vec<Fresh> = found.into_iter().collect();
            let named: Vec<State<f64>> = more
                .iter()
                .map(|f| ev.initial(&f.candidate.release))
                .collect();
            proposals.extend(full(&more)?);
            proposals.sort_by(|a, b| law_key(a).total_cmp(&law_key(b)));
            // The release the note names stays listed (a law it would not show at some
            // departure can rank it below the others); the rest fill up to `top`.
            let mut place = 0;
            proposals.retain(|p| {
                place += 1;
                place <= top || named.contains(&p.initial)
            });
            notes.push(note);
        }
    } else {
        proposals.sort_by(|a, b| a.predicted_mu_stderr.total_cmp(&b.predicted_mu_stderr));
    }
    // The errors' ranges over mu, for the best proposal only (the release a lab makes next):
    // two predictions per law, a tenth of a law plan's CPU for all three.
    if let Some(best) = proposals.first_mut() {
        let release = search::release_values(&best.initial);
        ev.add_mu_ranges(&release, &mut best.law_stderr);
    }
    let feasible = !proposals.is_empty();
    let at_limit = proposals
        .first()
        .map_or_else(Vec::new, |p| at_limit(&ranges, &p.initial));
    // Once the best release tells every pair apart, the ranking is mu's precision.
    let saturated = proposals.first().is_some_and(|p| {
        p.separations
            .iter()
            .all(|s| s.expected_delta_bic >= discriminate::MARGIN_CAP)
    });
    let aim = if ev.laws.is_some() && !saturated {
        "tell the laws apart"
    } else {
        "pin mu down"
    };
    notes.extend(at_limit.iter().map(|a| at_limit_note(a, aim)));
    if let Some(best) = proposals.first() {
        notes.extend(discriminate::unresolved_notes(&best.separations));
        // Say once why a stick-slip law stays hidden when the box cannot restart the slider.
        let stick_slip_hidden = best.separations.iter().any(|s| {
            s.probability < 0.5 && matches!(s.truth, law::Law::Static | law::Law::Stribeck)
        });
        if stick_slip_hidden {
            notes.extend(reach::no_restart_note(spec));
        }
    }
    let nearest = (!feasible).then(|| {
        let best = &unranked[0];
        Nearest {
            message: format!(
                "every target shows at the nominal friction, but no release in the feasible set reaches robustness {:.2}: the best, theta = {:.1} deg, theta' = {:.2} rad/s, x' = {:.3} m/s, shows them in {:.0}% of {} draws; narrow the uncertainty of mu, reduce the release error, or widen the release ranges",
                min_rob,
                best.initial[1].to_degrees(),
                best.initial[3],
                best.initial[2],
                100.0 * best.robustness_observed,
                best.draws
            ),
            release: Some(best.initial),
            robustness: Some(best.robustness_observed),
        }
    });
    if !feasible {
        notes.push("no proposal meets the required robustness".into());
    }
    Ok(PlanReport {
        feasible,
        targets: spec.goal.targets.clone(),
        proposals,
        unranked,
        min_robustness: min_rob,
        release_box: ranges,
        at_limit,
        nearest,
        notes,
        evaluated,
        rig: spec.rig,
        prior_mu_stderr: prior_mu_stderr(spec),
        laws: weighed,
        law_notes,
    })
}

/// mu's standard error from the fit of `--after`, when given.
fn prior_mu_stderr(spec: &PlanSpec) -> Option<f64> {
    spec.prior
        .as_ref()
        .and_then(|p| p.get(crate::fit::Param::MuKinetic))
        .map(|(_, se)| se)
}

/// A candidate's fresh check: its robustness over the check's draws and mu's predicted
/// error, all that decides whether and where it is reported.
struct Fresh {
    candidate: Candidate,
    /// Draws of the check showing every target.
    passed: usize,
    /// mu's predicted standard error from every frame.
    mu_stderr: f64,
    draws: usize,
    /// The laws' predicted errors when already computed (the second look asks whether a
    /// release hides a law before it is checked in full).
    law_stderr: Option<Vec<law::LawError>>,
}

impl Fresh {
    /// The one-sided 95% lower bound of the robustness.
    fn robustness(&self) -> f64 {
        search::robustness_lower_bound(self.passed, self.draws)
    }

    /// Whether the release is ranked ([`Proposal::ranked`]).
    fn ranked(&self, min_robustness: f64) -> bool {
        self.robustness() >= min_robustness && self.mu_stderr.is_finite()
    }
}

/// The fresh check of a candidate's robustness over `check`.
fn fresh(ev: &Evaluator, check: &Draws, c: &Candidate) -> Fresh {
    Fresh {
        candidate: *c,
        passed: ev.passes(&c.release, check),
        // A plan for mu's precision searched with the reporting tolerance and every frame: its
        // own value. A law plan's search ran looser and on a sample of the frames.
        mu_stderr: if ev.laws.is_some() {
            ev.mu_stderr(&c.release)
        } else {
            c.stderr
        },
        draws: check.len(),
        law_stderr: None,
    }
}

/// A checked release as reported: its nominal run sampled at the frames, the rivals' full
/// fits and the laws' errors.
fn checked(ev: &Evaluator, f: &Fresh) -> Result<Proposal, PlanError> {
    let spec = ev.spec;
    let c = &f.candidate;
    let passed = f.passed;
    let y0 = ev.initial(&c.release);
    let request = Request {
        sample_times: spec.camera.frame_times(),
        friction_work: false,
        positions_only: false,
    };
    let (sol, nominal) = ev
        .run(&spec.rig, &y0, &request)
        .ok_or_else(|| PlanError::Simulation {
            initial: y0,
            message: "the nominal run failed".into(),
        })?;
    let robustness = f.robustness();
    // The claim is the rivals' full fits, not the search's linearisation (which a rival that
    // moves far from Coulomb's law can beat).
    let verified: Vec<Option<discriminate::Separation>> = ev
        .laws
        .as_ref()
        .map_or_else(Vec::new, |l| l.verified(ev, &y0));
    let separation = if ev.laws.is_some() {
        discriminate::Laws::score(&verified)
    } else {
        c.separation
    };
    let mut separations: Vec<discriminate::Separation> = verified.into_iter().flatten().collect();
    separations.sort_by(|a, b| a.expected_delta_bic.total_cmp(&b.expected_delta_bic));
    Ok(Proposal {
        initial: y0,
        events: sol.events,
        nominal,
        robustness,
        meets_min_robustness: robustness >= spec.goal.min_robustness,
        robustness_observed: passed as f64 / f.draws as f64,
        draws: f.draws,
        predicted_mu_stderr: f.mu_stderr,
        separations,
        separation,
        law_stderr: f
            .law_stderr
            .clone()
            .unwrap_or_else(|| ev.law_stderr(&c.release)),
        samples: sol.samples,
    })
}

/// A law plan's order of its reported proposals: the search's own (the separation, then mu's
/// precision), from the rivals' full fits, less a pair for each law the release would not
/// show at some of its departures. The search counts a pair at the laws' reference
/// departures only, where a static step a tenth above kinetic restarts a slider that the
/// step of a fifth leaves stuck: on the heavy rig's wide box its best release then showed no
/// static friction for the truth's step, and the joint fits failed.
fn law_key(p: &Proposal) -> f64 {
    let hidden: std::collections::BTreeSet<law::Law> = p
        .law_stderr
        .iter()
        .filter(|e| e.hidden_somewhere())
        .map(|e| e.law)
        .collect();
    Candidate {
        release: search::release_values(&p.initial),
        robustness: 1.0,
        stderr: p.predicted_mu_stderr,
        separation: p.separation,
        saturated: false,
    }
    .objective(0.0)
        + search::PAIR * hidden.len() as f64
}

/// Releases a law plan fits in full at most when its best proposal's full fits fall short of
/// the search's linearised separation.
const SECOND_LOOK_RELEASES: usize = 48;

/// The chance of every short pair at which the second look stops: the release it reports
/// costs the rivals' full fits of every pair at the plan's tolerance, a third of a light-rig
/// plan's CPU, so it reports one.
const SECOND_LOOK_SURE: f64 = 0.9;

/// Releases the second look fresh-checks at most (each 100 runs or so).
const SECOND_LOOK_FRESH: usize = 6;

/// Releases judged together in the second look (fixed, so its stop does not depend on the
/// machine's threads).
const SECOND_LOOK_CHUNK: usize = 8;

/// A law plan's second look. The search ranks releases by each rival's linearised fit, which
/// a rival that moves far from Coulomb's law can beat: static friction's step, shifted, mimics
/// a Stribeck hump. On the light rig every release of the search's box then read 15 of 15
/// pairs, and the rivals' full fits of the reported ones 14 of 15, while 4 of its 89 robust
/// grid releases do tell every pair apart. When the best proposal's full fits leave a pair
/// the linearisation called told apart, the pool's next releases (the search's order) are
/// fitted in full for those pairs alone until some tell them apart.
struct SecondLook<'a> {
    ev: &'a Evaluator<'a>,
    /// The search's evaluator: the fits that only choose which releases to report run at its
    /// tolerance (the reported ones are checked at the plan's).
    search: &'a Evaluator<'a>,
    laws: &'a discriminate::Laws,
    /// The search's releases, best first.
    pool: &'a [Candidate],
    /// Releases already checked.
    seen: &'a [ReleaseValues],
    check: &'a Draws,
    min_robustness: f64,
}

/// What the second look has fresh-checked so far.
#[derive(Default)]
struct Looked {
    /// Releases fresh-checked, and whether each met the robustness.
    tried: Vec<(ReleaseValues, bool)>,
    /// The first robust one that shows every weighed law at every departure, with its chance.
    found: Option<(Fresh, f64)>,
    /// The first robust one that does not: kept should none show every law.
    hiding: Option<(Fresh, f64)>,
}

impl Looked {
    /// Whether the look stops: a release found, or its fresh checks spent.
    fn done(&self) -> bool {
        self.found.is_some() || self.tried.len() == SECOND_LOOK_FRESH
    }
}

impl SecondLook<'_> {
    /// Fresh-checks `j` (a release and its chance), unless the look is done, and keeps it as
    /// found when robust and showing every weighed law at every departure. A release that
    /// hides one ranks a pair lower ([`law_key`]) and is kept only as a fallback: on the
    /// light rig the surest releases for the hump against a step were such, ranked below
    /// releases that do not tell the pair apart at all.
    fn try_release(&self, j: &(Candidate, f64), look: &mut Looked) {
        if look.done() {
            return;
        }
        let mut f = fresh(self.ev, self.check, &j.0);
        let ranked = f.ranked(self.min_robustness);
        look.tried.push((j.0.release, ranked));
        if !ranked {
            return;
        }
        let errors = self.ev.law_stderr(&j.0.release);
        let hides = errors.iter().any(|e| e.hidden_somewhere());
        f.law_stderr = Some(errors);
        match (hides, look.hiding.is_some()) {
            (false, _) => look.found = Some((f, j.1)),
            (true, false) => look.hiding = Some((f, j.1)),
            (true, true) => {}
        }
    }

    /// The pairs (indices into the laws' pairs) the linearisation calls told apart at `best`
    /// and its rivals' full fits do not.
    fn short(&self, best: &Proposal) -> Vec<usize> {
        let linear = self.laws.separations(self.ev, &best.initial);
        (0..self.laws.pairs.len())
            .filter(|&i| {
                let (a, b) = self.laws.pairs[i];
                let (t, r) = (self.laws.candidates[a].0, self.laws.candidates[b].0);
                let full = best
                    .separations
                    .iter()
                    .find(|s| s.truth == t && s.rival == r)
                    .map_or(0.0, |s| s.probability);
                linear[i].as_ref().is_some_and(|s| s.probability >= 0.5) && full < 0.5
            })
            .collect()
    }

    /// The release found (fresh-checked and meeting the plan's robustness) and a note of what
    /// was done; `None` when the best proposal keeps the linearisation's word.
    fn run(&self, proposals: &[Proposal]) -> Option<(Option<Fresh>, String)> {
        let best = proposals.first()?;
        let short = self.short(best);
        if short.is_empty() {
            return None;
        }
        // A mirror-image release (x, theta, x', theta') -> (-x, pi - theta, -x', -theta')
        // separates a pair of laws alike when neither law has a direction and the rail is
        // level: one of the two is fitted.
        let symmetric = self.ev.spec.rig.rail_tilt == 0.0
            && short.iter().all(|&i| {
                let (a, b) = self.laws.pairs[i];
                [a, b]
                    .iter()
                    .all(|&k| self.laws.candidates[k].0 != law::Law::Direction)
            });
        let mirror = |r: &ReleaseValues| [PI - r[0], -r[1], -r[2]];
        // The grid's mirror images agree to rounding only (pi - theta).
        let same = |a: &ReleaseValues, b: &ReleaseValues| {
            a.iter()
                .zip(b)
                .all(|(u, v)| (u - v).abs() <= 1e-9 * (1.0 + u.abs()))
        };
        let mut queue: Vec<Candidate> = Vec::new();
        for c in self.pool {
            let new = !self
                .seen
                .iter()
                .chain(queue.iter().map(|q| &q.release))
                .any(|s| same(s, &c.release) || (symmetric && same(s, &mirror(&c.release))));
            // Only a release whose linearised count beats the best's full one could gain.
            if new
                && c.usable()
                && c.robustness >= self.min_robustness
                && c.separation > best.separation + 0.25
            {
                queue.push(*c);
            }
            if queue.len() == SECOND_LOOK_RELEASES {
                break;
            }
        }
        // Each release fitted, with the short pairs' smallest chance; a sure one is
        // fresh-checked at once, and the look goes on past one that fails (a release at the
        // edge of the robust set fails the fresh draws more often than its neighbours).
        let mut judged: Vec<(Candidate, f64)> = Vec::new();
        let mut look = Looked::default();
        for chunk in queue.chunks(SECOND_LOOK_CHUNK) {
            let part: Vec<(Candidate, f64)> = chunk
                .par_iter()
                .map(|c| {
                    let y0 = self.search.initial(&c.release);
                    let worst = self
                        .laws
                        .verified_pairs(self.search, &y0, &short, &[])
                        .iter()
                        .map(|s| s.as_ref().map_or(0.0, |s| s.probability))
                        .fold(1.0, f64::min);
                    (*c, worst)
                })
                .collect();
            for j in part.iter().filter(|j| j.1 >= SECOND_LOOK_SURE) {
                self.try_release(j, &mut look);
            }
            judged.extend(part);
            if look.done() {
                break;
            }
        }
        let fitted = judged.len();
        // None sure, robust and showing every law: the surest of the rest (a pair told apart
        // by a coin's chance still beats one not told apart).
        judged.sort_by(|a, b| b.1.total_cmp(&a.1));
        for j in judged.iter().filter(|j| j.1 >= 0.5) {
            if look.done() {
                break;
            }
            if !look.tried.iter().any(|t| t.0 == j.0.release) {
                self.try_release(j, &mut look);
            }
        }
        let Looked {
            tried,
            found,
            hiding: fallback,
        } = look;
        let hiding = found.is_none() && fallback.is_some();
        let found = found.or(fallback);
        let names: Vec<String> = short
            .iter()
            .map(|&i| {
                let (a, b) = self.laws.pairs[i];
                format!(
                    "{} (true) from {}",
                    self.laws.candidates[a].0, self.laws.candidates[b].0
                )
            })
            .collect();
        let (pair, it) = match short.len() {
            1 => ("that pair", "it"),
            _ => ("those pairs", "them"),
        };
        let failed = tried.iter().filter(|t| !t.1).count();
        let failed_text = match failed {
            0 => String::new(),
            1 => format!("; 1 release that would tell {it} apart fails the fresh robustness check"),
            n => {
                format!("; {n} releases that would tell {it} apart fail the fresh robustness check")
            }
        };
        let outcome = match &found {
            None if failed == 0 => format!("none of them tells {it} apart"),
            None => format!("none of them that tells {it} apart meets the robustness{failed_text}"),
            Some((f, chance)) => format!(
                "the surest that meets the robustness{}, {}, tells {it} apart with a chance of {chance:.2} and is proposed{failed_text}",
                match hiding {
                    true => " (every such release would not show a weighed law at some departure)",
                    false => " and shows every weighed law",
                },
                release_text(&f.candidate.release),
            ),
        };
        let note = format!(
            "the search's linearised criterion counted {} told apart at its best release, the rivals' full fits did not; {fitted} more releases were fitted in full for {pair}: {outcome}",
            names.join(" and "),
        );
        Some((found.map(|f| f.0), note))
    }
}

/// A release as the notes print it.
fn release_text(r: &ReleaseValues) -> String {
    format!(
        "theta = {:.1} deg, theta' = {:.2} rad/s, x' = {:.3} m/s",
        r[0].to_degrees(),
        r[1],
        r[2]
    )
}

/// Whether `r` is at least [`search::MIN_SEPARATION`] of the box's diagonal from each of
/// `taken`.
fn far_from<'a>(
    ranges: &[[f64; 2]; 3],
    taken: impl IntoIterator<Item = &'a ReleaseValues>,
    r: &ReleaseValues,
) -> bool {
    taken
        .into_iter()
        .all(|t| search::box_distance(ranges, t, r) >= search::MIN_SEPARATION)
}

/// Up to `n` candidates, greedily from the best of `sorted` (best first), each at least
/// [`search::MIN_SEPARATION`] of the box's diagonal from every one taken before, so that the
/// proposals lie in different regions of the release space, not on top of each other.
fn distinct(sorted: &[Candidate], ranges: &[[f64; 2]; 3], n: usize) -> Vec<Candidate> {
    let mut out: Vec<Candidate> = Vec::new();
    for c in sorted {
        if far_from(ranges, out.iter().map(|o| &o.release), &c.release) {
            out.push(*c);
        }
        if out.len() == n {
            break;
        }
    }
    out
}

/// The limits of the release box (theta, theta', x') that `initial` lies at, within
/// [`AT_LIMIT_FRACTION`] of the range; quantities the plan fixes are never at a limit.
pub fn at_limit(ranges: &[[f64; 2]; 3], initial: &State<f64>) -> Vec<AtLimit> {
    let keys = ["release.theta_deg", "release.theta_dot", "release.x_dot"];
    let values = search::release_values(initial);
    let mut out = Vec::new();
    for ((&quantity, &[lo, hi]), &v) in keys.iter().zip(ranges).zip(&values) {
        let tol = AT_LIMIT_FRACTION * (hi - lo);
        if tol <= 0.0 {
            continue;
        }
        let unit = |x: f64| {
            if quantity == keys[0] {
                x.to_degrees()
            } else {
                x
            }
        };
        for (limit, bound) in [(Limit::Lower, lo), (Limit::Upper, hi)] {
            if (v - bound).abs() <= tol {
                out.push(AtLimit {
                    quantity,
                    limit,
                    bound: unit(bound),
                    value: unit(v),
                });
            }
        }
    }
    out
}

/// The note of a limit the best proposal sits at; `aim` is what the ranking seeks.
fn at_limit_note(a: &AtLimit, aim: &str) -> String {
    format!(
        "the best proposal (#1) lies at the {} limit of {} ({:.3}, the limit {:.3}): a release beyond it may {aim} better; widen {} if the rig allows",
        a.limit, a.quantity, a.value, a.bound, a.quantity
    )
}

/// The paradox threshold of the rig, and for a sudden-stop target what mass ratio it needs.
fn paradox_notes(spec: &PlanSpec) -> Vec<String> {
    let r = spec.rig.mass_ratio();
    let mu_star = mu_critical(r);
    let [_, mu_hi] = spec.mu_kinetic.span();
    let ratio = match spec.rig.pendulum.filter(|p| !p.is_point()) {
        Some(p) => format!(
            "rigid pendulum: equivalent mass ratio r' = (m1 + m_p - m_e)/m_e = {r:.3} (L = {:.4} m; the point rig's r = m1/m_p = {:.3} would give mu* = {:.3})",
            spec.rig.rod_length,
            p.point_mass_ratio(),
            mu_critical(p.point_mass_ratio())
        ),
        None => format!("mass ratio r = m1/m2 = {r:.3}"),
    };
    let mut notes = vec![format!(
        "{ratio}: mu* = 2 sqrt(r (1 + r)) = {mu_star:.3}; mu_kinetic = {}",
        spec.mu_kinetic
    )];
    if spec.goal.targets.contains(&Target::SuddenStop) && mu_hi <= mu_star {
        notes.push(sudden_stop_advice(spec));
    }
    notes
}

fn sudden_stop_advice(spec: &PlanSpec) -> String {
    let r = spec.rig.mass_ratio();
    let mu = spec.rig.mu_kinetic;
    let r_max = max_mass_ratio_for_paradox(mu);
    if spec.rig.pendulum.is_some_and(|p| !p.is_point()) {
        // A rigid pendulum's masses enter through r' = (m1 + m_p - m_e) / m_e alone.
        return format!(
            "sudden_stop needs mu above mu* = {:.3} (rigid pendulum, r' = {r:.3}); with mu = {mu} an equivalent mass ratio r' below {r_max:.4} brings mu* below mu (a lighter slider, or a pendulum with more of its mass at the bob and less in the rod)",
            mu_critical(r)
        );
    }
    format!(
        "sudden_stop needs mu above mu* = {:.3} (r = {r:.3}); with mu = {mu} a mass ratio r = m1/m2 below {r_max:.4} brings mu* below mu (slider mass below {:.4} kg with this bob, or bob mass above {:.4} kg with this slider)",
        mu_critical(r),
        r_max * spec.rig.bob_mass,
        spec.rig.slider_mass / r_max
    )
}

/// Largest friction ratio |c| / |b| the stuck pendulum needs along its swing from
/// (theta0, w0): slip from such a release is impossible when mu_static is above it. The
/// swing is the arc reachable with the pendulum's energy (whole turns when it rotates).
pub fn max_stick_ratio(rig: &Rig<f64>, theta0: f64, w0: f64) -> f64 {
    let k = 2.0 * rig.gravity / rig.rod_length;
    let w2 = |th: f64| w0 * w0 + k * (th.sin() - theta0.sin());
    let ratio = |th: f64| {
        let w = w2(th).max(0.0).sqrt();
        let sh = Shorthands::new(rig, th, w);
        sh.c.abs() / sh.b.abs().max(1e-300)
    };
    let n = 1440;
    let step = 2.0 * PI / n as f64;
    let mut best = ratio(theta0);
    for dir in [1.0, -1.0] {
        for i in 1..=n {
            let th = theta0 + dir * step * i as f64;
            if w2(th) < 0.0 {
                break;
            }
            best = best.max(ratio(th));
        }
    }
    best
}

/// Why nothing in the feasible set works, and the nearest release that does: first wider
/// pushes, then wider angles.
fn nearest(ev: &Evaluator, draws: &Draws) -> Nearest {
    let spec = ev.spec;
    let ranges = search::release_box(spec);
    let mut reasons = Vec::new();
    let mu_s = spec.rig.mu_static;
    let needs_slip = spec.goal.targets.iter().any(|t| {
        matches!(
            t,
            Target::StickToSlide | Target::StickSlipCycles(_) | Target::SlideToStick
        )
    });
    let sudden_impossible = spec.goal.targets.contains(&Target::SuddenStop)
        && spec.mu_kinetic.span()[1] <= mu_critical(spec.rig.mass_ratio());
    if sudden_impossible {
        reasons.push(sudden_stop_advice(spec));
    }
    if needs_slip && ranges[2] == [0.0, 0.0] {
        let pts = search::grid(&ranges, spec.search.grid_points);
        let best = pts
            .iter()
            .map(|p| max_stick_ratio(&spec.rig, p[0], p[1]))
            .fold(0.0, f64::max);
        if best < mu_s {
            reasons.push(format!(
                "no slip for mu_static above {best:.3} from any release in the feasible set (the stuck pendulum never needs more friction than that; the plan's mu_static is {mu_s})"
            ));
        }
    }
    if sudden_impossible {
        return Nearest {
            message: reasons.join("; "),
            release: None,
            robustness: None,
        };
    }
    // Widen the push first (the cheapest change to a release mechanism), then the angle.
    let w_now = ranges[1][0].abs().max(ranges[1][1].abs());
    let mut tries: Vec<[[f64; 2]; 3]> = [1.0, 2.0, 3.0, 5.0, 8.0, 12.0]
        .iter()
        .filter(|&&w| w > w_now)
        .map(|&w| [ranges[0], [-w, w], ranges[2]])
        .collect();
    tries.push([
        [(-60f64).to_radians(), 240f64.to_radians()],
        [-12f64.max(w_now), 12f64.max(w_now)],
        ranges[2],
    ]);
    let distance = |p: &ReleaseValues| -> f64 {
        // Distance outside the feasible box, angle in degrees and push in rad/s weighted alike.
        let out = |v: f64, [lo, hi]: [f64; 2]| (lo - v).max(v - hi).max(0.0);
        out(p[0], ranges[0]).to_degrees() / 10.0 + out(p[1], ranges[1]) + out(p[2], ranges[2])
    };
    for wide in tries {
        let pts = search::grid(&wide, spec.search.grid_points.max(13) + 8);
        let ok: Vec<ReleaseValues> = pts
            .par_iter()
            .filter(|p| ev.nominal_ok(p))
            .copied()
            .collect();
        if let Some(p) = ok.iter().min_by(|a, b| distance(a).total_cmp(&distance(b))) {
            let rob = ev.passes(p, draws) as f64 / draws.len() as f64;
            let push = if p[1] < ranges[1][0] || p[1] > ranges[1][1] {
                format!("a push of at least |theta'| = {:.2} rad/s", p[1].abs())
            } else {
                format!("theta' = {:.2} rad/s", p[1])
            };
            reasons.push(format!(
                "nearest achievable: {push} at theta = {:.1} deg (x' = {:.3} m/s) shows every target at the nominal friction, in {:.0}% of the draws; the release ranges allow theta {:.1}..{:.1} deg, theta' {}..{} rad/s",
                p[0].to_degrees(),
                p[2],
                100.0 * rob,
                ranges[0][0].to_degrees(),
                ranges[0][1].to_degrees(),
                ranges[1][0],
                ranges[1][1]
            ));
            return Nearest {
                message: reasons.join("; "),
                release: Some(ev.initial(p)),
                robustness: Some(rob),
            };
        }
    }
    reasons.push(
        "no release with theta in -60..240 deg and |theta'| up to 12 rad/s shows every target: relax the targets, the camera criteria or the rail".into(),
    );
    Nearest {
        message: reasons.join("; "),
        release: None,
        robustness: None,
    }
}
