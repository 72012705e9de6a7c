//! Physics and camera nuisances chosen by the data: candidate models as data ([`Nuisance`]),
//! screened by a score test (the chi-square drop a parameter would buy, predicted from one
//! Jacobian at the current optimum), the promising ones fitted, and the best kept while it
//! lowers the Bayesian information criterion BIC = chi2 + k ln(n) (forward selection).

use super::problem::{Param, TrajectoryProblem, MAX_FREE};
use super::{solve, Solved};
use crate::model::{FrictionLaw, State};
use nalgebra::DVector;
use rayon::prelude::*;

/// A departure from the ideal rig or camera that a candidate model adds (PHYSICS.md, "Real
/// rigs" and "What a camera adds").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Nuisance {
    /// mu_static free above mu_kinetic (Coulomb friction with two coefficients).
    StaticFriction,
    /// Stribeck friction: mu_static and the Stribeck speed free.
    Stribeck,
    /// Rail tilt.
    RailTilt,
    /// Viscous damping at the pivot.
    PivotDamping,
    /// Viscous rail friction.
    ViscousFriction,
    /// Camera scale error (the bob marker at the rod's end).
    CameraScale,
    /// Bob marker off the rod's end: along and across the rod.
    BobOffset,
    /// Slider marker off the pivot.
    SliderOffset,
    /// A time lag between the two markers' tracks.
    Lag,
    /// A rigid pendulum (a rod with mass, a bob with size) whose build the rig file does not
    /// give: its equivalent length and mass ratio free (PHYSICS.md, "Rigid pendulum").
    RigidPendulum,
}

impl Nuisance {
    /// Every candidate, in the order ties are broken.
    pub const ALL: [Nuisance; 10] = [
        Nuisance::RigidPendulum,
        Nuisance::StaticFriction,
        Nuisance::Stribeck,
        Nuisance::RailTilt,
        Nuisance::PivotDamping,
        Nuisance::ViscousFriction,
        Nuisance::CameraScale,
        Nuisance::BobOffset,
        Nuisance::SliderOffset,
        Nuisance::Lag,
    ];

    /// Name in reports and JSON.
    pub fn name(self) -> &'static str {
        match self {
            Nuisance::StaticFriction => "mu_static",
            Nuisance::Stribeck => "stribeck",
            Nuisance::RailTilt => "rail_tilt",
            Nuisance::PivotDamping => "pivot_damping",
            Nuisance::ViscousFriction => "viscous_friction",
            Nuisance::CameraScale => "camera_scale",
            Nuisance::BobOffset => "bob_marker_offset",
            Nuisance::SliderOffset => "slider_marker_offset",
            Nuisance::Lag => "marker_lag",
            Nuisance::RigidPendulum => "rigid_pendulum",
        }
    }

    /// The parameters it frees.
    pub fn params(self) -> &'static [Param] {
        match self {
            Nuisance::StaticFriction => &[Param::MuStatic],
            Nuisance::Stribeck => &[Param::MuStatic, Param::StribeckVelocity],
            Nuisance::RailTilt => &[Param::RailTilt],
            Nuisance::PivotDamping => &[Param::PivotDamping],
            Nuisance::ViscousFriction => &[Param::ViscousFriction],
            Nuisance::CameraScale => &[Param::ScaleError],
            Nuisance::BobOffset => &[Param::BobAlong, Param::BobAcross],
            Nuisance::SliderOffset => &[Param::SliderDx, Param::SliderDy],
            Nuisance::Lag => &[Param::Lag],
            Nuisance::RigidPendulum => &[Param::PendulumLength, Param::MassRatio],
        }
    }

    /// Whether a score test can screen it: a parameter whose neutral value is an interior
    /// point. mu_static at mu_static = mu_kinetic has a vanishing first-order effect (the slip
    /// then starts with x'' = 0), and Stribeck changes the law: both are fitted outright.
    fn screened(self) -> bool {
        !matches!(self, Nuisance::StaticFriction | Nuisance::Stribeck)
    }

    /// Whether a model holding `self` cannot take `other`: camera scale and the bob marker's
    /// distance along the rod act through their product; Stribeck contains mu_static, so
    /// mu_static is not offered on top of it (Stribeck on top of mu_static replaces it:
    /// [`Nuisance::supersedes`]).
    fn conflicts(self, other: Nuisance) -> bool {
        use Nuisance::*;
        matches!(
            (self, other),
            (CameraScale, BobOffset) | (BobOffset, CameraScale) | (Stribeck, StaticFriction)
        )
    }

    /// The nuisance this one replaces when added: Stribeck friction generalises mu_static.
    fn supersedes(self) -> Option<Nuisance> {
        (self == Nuisance::Stribeck).then_some(Nuisance::StaticFriction)
    }

    /// Parameters it adds to `problem` (those not free already).
    fn new_params(self, problem: &TrajectoryProblem) -> usize {
        self.params()
            .iter()
            .filter(|q| !problem.free.contains(q))
            .count()
    }

    /// `chosen` with this nuisance added (and what it supersedes removed).
    fn join(self, chosen: &[Nuisance]) -> Vec<Nuisance> {
        let mut out: Vec<Nuisance> = chosen
            .iter()
            .copied()
            .filter(|&c| Some(c) != self.supersedes())
            .collect();
        out.push(self);
        out
    }

    /// `problem` with this nuisance added at its neutral value (mu_static from `mu_static`).
    fn add_to(self, problem: &TrajectoryProblem, mu_static: f64) -> TrajectoryProblem {
        let mut m = problem.clone();
        if self == Nuisance::Stribeck {
            m.rig.friction_law = FrictionLaw::Stribeck;
            m.rig.stribeck_velocity = 0.05;
        }
        for &q in self.params() {
            if !m.free.contains(&q) {
                m.free.push(q);
            }
        }
        if self.params().contains(&Param::MuStatic) && !problem.free.contains(&Param::MuStatic) {
            m.tie_static = false;
            m.rig.mu_static = mu_static.max(m.rig.mu_kinetic * 1.02);
        }
        m
    }
}

/// One candidate model of the comparison.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ModelRow {
    /// The nuisances it adds to the base model, joined by `+` (`base` for none).
    pub name: String,
    /// Its free parameters.
    pub free: Vec<&'static str>,
    /// Chi-square against the measured noise (sum of squared standardised residuals).
    pub chi2: f64,
    /// BIC = chi2 + k ln(n).
    pub bic: f64,
    /// BIC minus the chosen model's (0 for the chosen one).
    pub delta_bic: f64,
    /// Whether this is the model the fit reports.
    pub chosen: bool,
}

/// The outcome of forward selection: the chosen problem and optimum, the nuisances it holds
/// and every model compared.
pub struct Selection {
    /// The chosen model, values set.
    pub problem: TrajectoryProblem,
    /// Its optimum.
    pub p: DVector<f64>,
    /// Nuisances in the chosen model.
    pub chosen: Vec<Nuisance>,
    /// Every model fitted, with the comparison.
    pub rows: Vec<ModelRow>,
    /// Levenberg-Marquardt iterations spent.
    pub iterations: u64,
}

/// Chi-square of a solved model (the solver's cost is half of it).
fn chi2_of(cost: f64) -> f64 {
    2.0 * cost
}

/// Predicted chi-square drops of the screened candidates from one augmented Jacobian per
/// group of columns (the score test): with residuals r and base columns B at the optimum and
/// candidate columns C, drop = (C'r)' S^-1 (C'r) with S = C'C - C'B (B'B)^-1 B'C. The camera's
/// candidates join the first group's pass: their columns come from the observation model
/// alone ([`TrajectoryProblem::normal_equations_observed`]), so only the rig's candidates
/// widen the dual numbers carried through the motion.
fn score_drops(
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
        for n in group.iter() {
            aug.free.extend(n.params());
        }
        let extra: Vec<Param> = seen.iter().flat_map(|n| n.params()).copied().collect();
        let mut q = p.clone().resize_vertically(aug.free.len(), 0.0);
        for (i, &param) in aug.free.iter().enumerate().skip(k) {
            q[i] = problem.get(param);
        }
        // Every block the score test needs is a block of the augmented normal equations:
        // B'B, B'C, C'C and C'r.
        if let Ok(nq) = aug.normal_equations_observed(&q, &extra) {
            let btb = nq.jtj.view((0, 0), (k, k)).into_owned();
            if let Some(btb_inv) = btb.try_inverse() {
                let mut col = k;
                for n in group.iter().chain(seen.iter()) {
                    let w = n.params().len();
                    let g = nq.jtr.rows(col, w).into_owned();
                    let bc = nq.jtj.view((0, col), (k, w)).into_owned();
                    let ctc = nq.jtj.view((col, col), (w, w)).into_owned();
                    col += w;
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

/// Settings of the selection.
pub struct SelectOptions {
    /// Try mu_static and Stribeck friction (the data show a stick-to-slide onset) in a round
    /// whose model misfits, or in every round when `static_evidence` is set.
    pub friction_candidates: bool,
    /// The onsets show mu_static above mu_kinetic: the friction candidates are offered even
    /// when the model describes the recording.
    pub static_evidence: bool,
    /// Start value of mu_static for those candidates.
    pub mu_static_start: f64,
    /// Most nuisances added.
    pub max_added: usize,
    /// Most Levenberg-Marquardt iterations per fit.
    pub max_iters: u64,
    /// Nuisances the model holds already (not offered again).
    pub already: Vec<Nuisance>,
    /// A second start for each candidate, used while the current model misfits: the data's
    /// initial state and mu_kinetic. A misfitting model's optimum is often a compromise far
    /// from the truth (a drift fitted by a push), from which the right nuisance alone does
    /// not lead back.
    pub fresh_start: Option<(State<f64>, f64)>,
    /// Nuisances the user put in the model (`--with`): added first, whatever they cost.
    pub forced: Vec<Nuisance>,
}

/// Whether `problem`'s chi-square is far beyond its degrees of freedom (5 standard
/// deviations): the model misfits, so the linear screening and the current optimum are not
/// to be trusted.
pub fn misfits(problem: &TrajectoryProblem, chi2: f64) -> bool {
    let dof = (problem.n_rows().saturating_sub(problem.free.len()) as f64).max(1.0);
    chi2 > dof + 5.0 * (2.0 * dof).sqrt()
}

/// `m` restarted from the data's initial state and mu_kinetic (parameters the start does
/// not name keep their values).
fn restarted(m: &TrajectoryProblem, (y0, mu0): (State<f64>, f64)) -> TrajectoryProblem {
    let mut f = m.clone();
    let keep_x_dot = !f.free.contains(&Param::XDot);
    for (i, (v, &guess)) in f.initial.iter_mut().zip(&y0).enumerate() {
        // A release from rest keeps x'(0) = 0.
        if !(i == 2 && keep_x_dot) {
            *v = guess;
        }
    }
    f.rig.mu_kinetic = mu0;
    if f.free.contains(&Param::MuStatic) {
        // Just above the tie: a mu_static chosen while the model misfitted is part of the
        // compromise this start leaves (the current start keeps it).
        f.rig.mu_static = mu0 * 1.02;
    } else if f.tie_static {
        f.rig.mu_static = mu0;
    }
    f
}

/// Solve `m` from its values and, when `fresh` is given, also from a restart; the lower
/// cost wins. Iterations of both count.
fn solve_starts(m: &TrajectoryProblem, fresh: Option<(State<f64>, f64)>, max_iters: u64) -> Solved {
    let a = solve(m, m.values(), max_iters);
    let Some(start) = fresh else {
        return a;
    };
    let f = restarted(m, start);
    let b = solve(&f, f.values(), max_iters);
    match (a, b) {
        (Ok(x), Ok(y)) => {
            let iters = x.2 + y.2;
            let (p, c) = if y.1 < x.1 { (y.0, y.1) } else { (x.0, x.1) };
            Ok((p, c, iters))
        }
        (Ok(x), Err(_)) => Ok(x),
        (Err(_), b) => b,
    }
}

/// Forward selection from the base model `problem` at its optimum `p` (chi-square `chi2`).
pub fn forward(
    problem: TrajectoryProblem,
    p: DVector<f64>,
    chi2: f64,
    opts: &SelectOptions,
) -> Selection {
    let n = problem.n_rows() as f64;
    let bic = |k: usize, chi2: f64| chi2 + k as f64 * n.ln();
    let name_of = |ns: &[Nuisance]| {
        if ns.is_empty() {
            "base".to_owned()
        } else {
            ns.iter().map(|n| n.name()).collect::<Vec<_>>().join("+")
        }
    };
    let row = |ns: &[Nuisance], m: &TrajectoryProblem, chi2: f64| ModelRow {
        name: name_of(ns),
        free: m.free.iter().map(|q| q.name()).collect(),
        chi2,
        bic: bic(m.free.len(), chi2),
        delta_bic: 0.0,
        chosen: false,
    };
    let mut chosen: Vec<Nuisance> = opts.already.clone();
    let mut current = (problem, p, chi2);
    let mut rows = vec![row(&chosen, &current.0, chi2)];
    let mut iterations = 0;
    for &nu in &opts.forced {
        if chosen.contains(&nu) || chosen.iter().any(|c| c.conflicts(nu)) {
            continue;
        }
        let m = nu.add_to(&current.0, opts.mu_static_start);
        if let Ok((q, cost, iters)) = solve_starts(&m, opts.fresh_start, opts.max_iters) {
            iterations += iters;
            let mut m = m;
            m.set_values(&q);
            chosen = nu.join(&chosen);
            rows.push(row(&chosen, &m, chi2_of(cost)));
            current = (m, q, chi2_of(cost));
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
            .filter(|n| cur_problem.free.len() + n.new_params(cur_problem) <= MAX_FREE)
            .filter(|n| n.screened() || friction)
            // A pendulum the rig file gives is used as given (`--with` may still free it).
            .filter(|n| *n != Nuisance::RigidPendulum || cur_problem.rig.pendulum.is_none())
            .collect();
        if open.is_empty() {
            break;
        }
        let screened: Vec<Nuisance> = open.iter().copied().filter(|n| n.screened()).collect();
        let mut drops = score_drops(cur_problem, cur_p, &screened);
        drops.sort_by(|a, b| b.1.total_cmp(&a.1));
        // Fit the two most promising screened candidates whose predicted drop pays their BIC
        // penalty, and the friction candidates outright. A misfitting model's linearisation
        // ranks poorly: then every screened candidate is fitted, from two starts.
        let misfit = misfits(cur_problem, *cur_chi2);
        let fresh = opts.fresh_start.filter(|_| misfit);
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
        // variants) are fitted first, and the rest only when none of those describes the
        // recording (a candidate that does leaves the others at most noise to gain this round).
        let leading = if misfit { 2 } else { to_fit.len() };
        let (mut first, mut rest) = (Vec::new(), Vec::new());
        for (i, &nu) in to_fit.iter().enumerate() {
            let jobs = if i < leading { &mut first } else { &mut rest };
            jobs.push((
                nu.join(&chosen),
                nu.add_to(cur_problem, opts.mu_static_start),
            ));
            if drop_static && nu.supersedes() != Some(Nuisance::StaticFriction) {
                let mut tied = cur_problem.clone();
                tied.free.retain(|&q| q != Param::MuStatic);
                tied.tie_static = true;
                tied.rig.mu_static = tied.rig.mu_kinetic;
                let without: Vec<Nuisance> = chosen
                    .iter()
                    .copied()
                    .filter(|&c| c != Nuisance::StaticFriction)
                    .collect();
                jobs.push((nu.join(&without), nu.add_to(&tied, opts.mu_static_start)));
            }
        }
        let run = |jobs: Vec<(Vec<Nuisance>, TrajectoryProblem)>| {
            jobs.into_par_iter()
                .with_max_len(1)
                .map(|(set, m)| {
                    let solved = solve_starts(&m, fresh, opts.max_iters);
                    (set, m, solved)
                })
                .collect::<Vec<_>>()
        };
        let mut fits = run(first);
        let adequate = fits.iter().any(|(_, m, s)| {
            s.as_ref()
                .is_ok_and(|(_, cost, _)| !misfits(m, chi2_of(*cost)))
        });
        if !adequate {
            fits.extend(run(rest));
        }
        let mut best: Option<(Vec<Nuisance>, TrajectoryProblem, DVector<f64>, f64)> = None;
        for (set, m, solved) in fits {
            let Ok((q, cost, iters)) = solved else {
                continue;
            };
            iterations += iters;
            let c2 = chi2_of(cost);
            rows.push(row(&set, &m, c2));
            if best
                .as_ref()
                .is_none_or(|b| bic(m.free.len(), c2) < bic(b.1.free.len(), b.3))
            {
                best = Some((set, m, q, c2));
            }
        }
        let Some((set, mut m, q, c2)) = best else {
            break;
        };
        // Positive evidence (Kass and Raftery): a BIC lower by more than 2.
        if bic(m.free.len(), c2) < bic(cur_problem.free.len(), *cur_chi2) - 2.0 {
            m.set_values(&q);
            chosen = set;
            current = (m, q, c2);
        } else {
            break;
        }
    }
    let chosen_name = name_of(&chosen);
    let best_bic = bic(current.0.free.len(), current.2);
    for r in &mut rows {
        r.delta_bic = r.bic - best_bic;
        r.chosen = r.name == chosen_name && (r.bic - best_bic).abs() < 1e-9;
    }
    let (problem, p, _) = current;
    Selection {
        problem,
        p,
        chosen,
        rows,
        iterations,
    }
}
