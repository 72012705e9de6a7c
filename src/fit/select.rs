//! Physics and camera nuisances chosen by the data: candidate models as data ([`Nuisance`]),
//! screened by a score test (the chi-square drop a parameter would buy, predicted from one
//! Jacobian at the current optimum), the promising ones fitted, and the best kept while it
//! lowers the Bayesian information criterion BIC = chi2 + k ln(n) (forward selection).

use super::lm::LeastSquares;
use super::problem::{Param, TrajectoryProblem, MAX_FREE};
use super::solve::{solve_loose, Solved, STAGE_FTOL};
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
    /// Bob marker off the rod's line only (across it): unlike the full offset it can join a
    /// camera scale error, which acts through the marker's distance along the rod.
    BobAcross,
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
    pub const ALL: [Nuisance; 11] = [
        Nuisance::RigidPendulum,
        Nuisance::StaticFriction,
        Nuisance::Stribeck,
        Nuisance::RailTilt,
        Nuisance::PivotDamping,
        Nuisance::ViscousFriction,
        Nuisance::CameraScale,
        Nuisance::BobOffset,
        Nuisance::BobAcross,
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
            Nuisance::BobAcross => "bob_marker_across",
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
            Nuisance::BobAcross => &[Param::BobAcross],
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
    /// [`Nuisance::supersedes`]); the full bob offset contains the offset across the rod.
    fn conflicts(self, other: Nuisance) -> bool {
        use Nuisance::*;
        matches!(
            (self, other),
            (CameraScale, BobOffset)
                | (BobOffset, CameraScale)
                | (Stribeck, StaticFriction)
                | (BobOffset, BobAcross)
                | (BobAcross, BobOffset)
        )
    }

    /// The nuisance this one replaces when added: Stribeck friction generalises mu_static.
    fn supersedes(self) -> Option<Nuisance> {
        (self == Nuisance::Stribeck).then_some(Nuisance::StaticFriction)
    }

    /// Parameters it adds to each simulation of `m` (those not free already).
    fn new_params<M: Candidate>(self, m: &M) -> usize {
        self.params().iter().filter(|&&q| !m.frees(q)).count()
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
    /// Its mu_kinetic (NaN when its fit failed).
    pub mu_kinetic: f64,
    /// Why its fit failed (`None` when it converged): a failed candidate is no evidence and
    /// takes no part in the comparison or the weights.
    pub failed: Option<String>,
    /// Its weight among the converged models (quasi-BIC weight, [`model_weights`]).
    pub weight: f64,
    /// Whether the selection passed through it: the base model and each model it took.
    pub path: bool,
}

/// The outcome of forward selection: the chosen problem and optimum, the nuisances it holds
/// and every model compared.
pub struct Selection<M> {
    /// The chosen model, values set.
    pub problem: M,
    /// Its optimum.
    pub p: DVector<f64>,
    /// Nuisances in the chosen model.
    pub chosen: Vec<Nuisance>,
    /// Every model fitted, with the comparison.
    pub rows: Vec<ModelRow>,
    /// Levenberg-Marquardt iterations spent.
    pub iterations: u64,
}

/// What the forward selection needs of a model: one recording's problem
/// ([`TrajectoryProblem`]) or several recordings fitted jointly (`fit::joint`). The selection
/// ([`forward`]) is written once against this.
pub trait Candidate: LeastSquares + Clone + Send + Sync + 'static {
    /// A restart for a misfitting model: the data's own initial state(s) and mu_kinetic.
    type Start: Clone + Send + Sync;
    /// Residual rows (the sample size of the criterion).
    fn n_rows(&self) -> usize;
    /// Free parameters in all.
    fn n_free(&self) -> usize;
    /// Free parameters of the widest single simulation (the dual numbers' width, at most
    /// [`MAX_FREE`]).
    fn width(&self) -> usize;
    /// Whether `q` is free.
    fn frees(&self, q: Param) -> bool;
    /// Names of the free parameters, for the model table.
    fn free_names(&self) -> Vec<&'static str>;
    /// Current values of the free parameters.
    fn values(&self) -> DVector<f64>;
    /// Store a parameter vector.
    fn set_values(&mut self, v: &DVector<f64>);
    /// Current mu_kinetic.
    fn mu_kinetic(&self) -> f64;
    /// Current mu_static.
    fn mu_static(&self) -> f64;
    /// Whether the rig file gives the pendulum's build (then it is not a candidate).
    fn pendulum_given(&self) -> bool;
    /// The model with `nu` added at its neutral value (mu_static from `mu_static`).
    fn with_nuisance(&self, nu: Nuisance, mu_static: f64) -> Self;
    /// The model restarted from `start` (parameters the start does not name keep their
    /// values).
    fn restarted(&self, start: &Self::Start) -> Self;
    /// The model with mu_static no longer free, tied to mu_kinetic.
    fn static_tied(&self) -> Self;
    /// The model with mu_static just above mu_kinetic, where the static coefficient (and
    /// Stribeck's law) does what Coulomb's law with one coefficient does.
    fn static_near_tie(&self) -> Self;
    /// Predicted chi-square drop of each screened candidate at `p` (the score test).
    fn score_drops(&self, p: &DVector<f64>, candidates: &[Nuisance]) -> Vec<(Nuisance, f64)>;
}

impl Candidate for TrajectoryProblem {
    type Start = (State<f64>, f64);
    fn n_rows(&self) -> usize {
        TrajectoryProblem::n_rows(self)
    }
    fn n_free(&self) -> usize {
        self.free.len()
    }
    fn width(&self) -> usize {
        self.free.len()
    }
    fn frees(&self, q: Param) -> bool {
        self.free.contains(&q)
    }
    fn free_names(&self) -> Vec<&'static str> {
        self.free.iter().map(|q| q.name()).collect()
    }
    fn values(&self) -> DVector<f64> {
        TrajectoryProblem::values(self)
    }
    fn set_values(&mut self, v: &DVector<f64>) {
        TrajectoryProblem::set_values(self, v)
    }
    fn mu_kinetic(&self) -> f64 {
        self.rig.mu_kinetic
    }
    fn mu_static(&self) -> f64 {
        self.rig.mu_static
    }
    fn pendulum_given(&self) -> bool {
        self.rig.pendulum.is_some()
    }
    fn with_nuisance(&self, nu: Nuisance, mu_static: f64) -> Self {
        nu.add_to(self, mu_static)
    }
    fn restarted(&self, start: &Self::Start) -> Self {
        restarted(self, *start)
    }
    fn static_tied(&self) -> Self {
        let mut tied = self.clone();
        tied.free.retain(|&q| q != Param::MuStatic);
        tied.tie_static = true;
        tied.rig.mu_static = tied.rig.mu_kinetic;
        tied
    }
    fn static_near_tie(&self) -> Self {
        let mut tied = self.clone();
        tied.rig.mu_static = tied.rig.mu_kinetic * (1.0 + 1e-9);
        tied
    }
    fn score_drops(&self, p: &DVector<f64>, candidates: &[Nuisance]) -> Vec<(Nuisance, f64)> {
        score_drops(self, p, candidates)
    }
}

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

/// Under misfit, a screened candidate predicted to lower the chi-square by this share of the
/// best candidate's drop or more is fitted in the round's first batch.
const LEADING_SHARE: f64 = 0.1;

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
                let mut col = k;
                for n in group.iter() {
                    cols.push((col..col + n.params().len()).collect());
                    col += n.params().len();
                }
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

/// Settings of the selection.
pub struct SelectOptions<S> {
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
    pub fresh_start: Option<S>,
    /// Nuisances the user put in the model (`--with`): added first, whatever they cost.
    pub forced: Vec<Nuisance>,
}

/// Whether `problem`'s chi-square is far beyond its degrees of freedom (5 standard
/// deviations): the model misfits, so the linear screening and the current optimum are not
/// to be trusted.
pub fn misfits<M: Candidate>(problem: &M, chi2: f64) -> bool {
    let dof = (problem.n_rows().saturating_sub(problem.n_free()) as f64).max(1.0);
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

/// A candidate's fit: to a relative cost decrease of [`STAGE_FTOL`], which settles its
/// chi-square to far below a unit (the criterion's differences that matter are units), while
/// the last digits cost as many iterations again. The chosen model is polished after the
/// selection.
fn solve_candidate<M: Candidate>(m: &M, p0: DVector<f64>, max_iters: u64) -> Solved {
    solve_loose(m, p0, max_iters, Some(STAGE_FTOL))
}

/// Solve `m` from its values and, when `fresh` is given, also from a restart; the lower
/// cost wins. Iterations of both count.
fn solve_starts<M: Candidate>(m: &M, fresh: Option<&M::Start>, max_iters: u64) -> Solved {
    let a = solve_candidate(m, m.values(), max_iters);
    let Some(start) = fresh else {
        return a;
    };
    let f = m.restarted(start);
    let b = solve_candidate(&f, f.values(), max_iters);
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

/// Chi-square a candidate may end above the model it nests and still count as converged:
/// the solvers' stopping tolerance, with a floor of one unit.
fn nested_slack(parent_chi2: f64) -> f64 {
    (1e-4 * parent_chi2).max(1.0)
}

/// The round's best candidate: its nuisances, problem, optimum, chi-square and row.
type Best<M> = (Vec<Nuisance>, M, DVector<f64>, f64, usize);

/// A failed candidate: why, the chi-square it reached (NaN when none) and the iterations.
type Failure = (String, f64, u64);

/// Fit candidate `m` from its own start (and `fresh` when given). A candidate that nests the
/// current model (`parent`: that model's chi-square) yet ends worse than it has not converged:
/// it is retried, longer and from the data's start, and is a failure when it still ends
/// worse (it is then no evidence about the nuisance, and must not be compared as if it were).
fn fit_candidate<M: Candidate>(
    m: &M,
    fresh: Option<&M::Start>,
    opts: &SelectOptions<M::Start>,
    parent: Option<f64>,
) -> Result<(DVector<f64>, f64, u64), Failure> {
    let worse = |cost: f64| parent.is_some_and(|c| chi2_of(cost) > c + nested_slack(c));
    let first = solve_starts(m, fresh, opts.max_iters);
    let (mut best, mut iters) = match first {
        Ok((q, cost, it)) if !worse(cost) => return Ok((q, cost, it)),
        Ok((q, cost, it)) => (Some((q, cost)), it),
        Err(e) if parent.is_none() => return Err((e, f64::NAN, 0)),
        Err(_) => (None, 0),
    };
    // The retries: on from where the first fit stopped with twice the iterations, and from
    // the data's start when the first fit did not use it.
    let mut retries: Vec<(M, DVector<f64>)> = Vec::new();
    if let Some((q, _)) = &best {
        retries.push((m.clone(), q.clone()));
    }
    if m.frees(Param::MuStatic) && m.mu_static() > m.mu_kinetic() {
        // From the current model itself: mu_static just above mu_kinetic.
        let tied = m.static_near_tie();
        let v = tied.values();
        retries.push((tied, v));
    }
    if let (None, Some(start)) = (fresh, opts.fresh_start.as_ref()) {
        let f = m.restarted(start);
        let v = f.values();
        retries.push((f, v));
    }
    let mut last_err = String::from("no start converged");
    for (r, p0) in retries {
        match solve_candidate(&r, p0, 2 * opts.max_iters) {
            Ok((q, cost, it)) => {
                iters += it;
                if best.as_ref().is_none_or(|b| cost < b.1) {
                    best = Some((q, cost));
                }
            }
            Err(e) => last_err = e,
        }
    }
    match best {
        Some((q, cost)) if !worse(cost) => Ok((q, cost, iters)),
        Some((_, cost)) => Err((
            format!(
                "did not converge: its chi-square {:.1} stayed above the {:.1} of the model it extends",
                chi2_of(cost),
                parent.unwrap_or(f64::NAN)
            ),
            chi2_of(cost),
            iters,
        )),
        None => Err((last_err, f64::NAN, iters)),
    }
}

/// `r` marked as a failed fit.
fn failed_row(mut r: ModelRow, why: String) -> ModelRow {
    r.failed = Some(why);
    r.mu_kinetic = f64::NAN;
    r.bic = f64::NAN;
    r
}

/// Each converged model's weight w_i = exp(-dBIC_i / (2 c)) / sum, the Bayesian information
/// criterion's approximation to the posterior probability of the model (Burnham and Anderson,
/// "Model selection and multimodel inference", 6.4), with the chi-squares divided by the
/// chosen model's reduced chi-square `c` (at least 1: their quasi-likelihood correction for
/// overdispersion). A model that misfits overstates every chi-square difference by that
/// factor, which would make one model look certain. A model fitted twice (the same
/// nuisances) counts once.
pub fn model_weights(rows: &mut [ModelRow], c: f64) {
    let mut seen = std::collections::HashSet::new();
    let mut total = 0.0;
    for r in rows.iter_mut() {
        r.weight = 0.0;
        let mut set: Vec<&str> = r.name.split('+').collect();
        set.sort_unstable();
        if r.failed.is_some() || !r.delta_bic.is_finite() || !seen.insert(set.join("+")) {
            continue;
        }
        r.weight = (-0.5 * r.delta_bic / c).exp();
        total += r.weight;
    }
    if total > 0.0 {
        rows.iter_mut().for_each(|r| r.weight /= total);
    }
}

/// The spread of mu_kinetic across the models the weights leave in play: sum w_i (mu_i -
/// mu)^2 around the chosen model's `mu`, and the models that carry it (the chosen one, and
/// each that gives a tenth of the sum or more).
/// Added in quadrature to the chosen model's variance it gives the unconditional standard
/// error (Burnham and Anderson, eq. 4.9, with the chosen model's value for the average).
pub fn model_spread(rows: &[ModelRow], mu: f64) -> (f64, Vec<String>) {
    let var = rows
        .iter()
        .filter(|r| r.weight > 0.0 && r.mu_kinetic.is_finite())
        .map(|r| r.weight * (r.mu_kinetic - mu).powi(2))
        .sum();
    let names = rows
        .iter()
        .filter(|r| r.weight > 0.0 && r.mu_kinetic.is_finite())
        .filter(|r| r.chosen || r.weight * (r.mu_kinetic - mu).powi(2) >= 0.1 * var)
        .map(|r| {
            format!(
                "{} (weight {:.2e}, mu_kinetic {:.6})",
                r.name, r.weight, r.mu_kinetic
            )
        })
        .collect();
    (var, names)
}

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

#[cfg(test)]
mod tests {
    use super::{model_spread, model_weights, ModelRow};

    fn row(name: &str, delta_bic: f64, mu: f64, chosen: bool) -> ModelRow {
        ModelRow {
            name: name.to_owned(),
            free: Vec::new(),
            chi2: 0.0,
            bic: delta_bic,
            delta_bic,
            chosen,
            mu_kinetic: mu,
            failed: None,
            weight: 0.0,
            path: false,
        }
    }

    /// Weights exp(-dBIC / 2c): equal criteria share, a model 10 units worse gets e^-5 of the
    /// best's weight (e^-2.5 under an overdispersion c = 2), a failed model and a second fit of
    /// the same nuisances get none; the spread is the weighted variance about the chosen mu.
    #[test]
    fn model_weights_follow_the_criterion() {
        let mut rows = vec![
            row("base", 10.0, 0.20, false),
            row("rail_tilt", 0.0, 0.25, true),
            row("rail_tilt+marker_lag", 0.0, 0.27, false),
            row("marker_lag+rail_tilt", 0.0, 0.27, false),
            ModelRow {
                failed: Some("did not converge".into()),
                ..row("pivot_damping", -50.0, 0.9, false)
            },
        ];
        model_weights(&mut rows, 1.0);
        let total = 2.0 + (-5.0f64).exp();
        assert!((rows[1].weight - 1.0 / total).abs() < 1e-12);
        assert!((rows[2].weight - rows[1].weight).abs() < 1e-12);
        assert!((rows[0].weight / rows[1].weight - (-5.0f64).exp()).abs() < 1e-12);
        assert_eq!(rows[3].weight, 0.0);
        assert_eq!(rows[4].weight, 0.0);
        let (var, names) = model_spread(&rows, 0.25);
        let want = rows[0].weight * 0.05f64.powi(2) + rows[2].weight * 0.02f64.powi(2);
        assert!((var - want).abs() < 1e-15);
        assert!(names.iter().any(|n| n.starts_with("rail_tilt+marker_lag")));
        assert!(names.iter().any(|n| n.starts_with("rail_tilt ")));
        model_weights(&mut rows, 2.0);
        assert!((rows[0].weight / rows[1].weight - (-2.5f64).exp()).abs() < 1e-12);
    }
}
