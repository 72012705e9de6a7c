//! What the forward selection needs of a model ([`Candidate`]), written once so that one
//! recording's problem and several recordings fitted jointly share the selection; here also
//! its implementation for one recording ([`TrajectoryProblem`]).

use super::score::score_drops;
use super::Nuisance;
use crate::fit::lm::LeastSquares;
use crate::fit::problem::{Param, TrajectoryProblem};
use crate::model::State;
use nalgebra::DVector;

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
    /// The model with Coulomb's law with one coefficient in place of its friction law
    /// ([`Nuisance::is_friction`] left out), every other value kept.
    fn coulomb(&self) -> Self;
    /// Predicted chi-square drop of each screened candidate at `p` (the score test).
    fn score_drops(&self, p: &DVector<f64>, candidates: &[Nuisance]) -> Vec<(Nuisance, f64)>;
    /// Whether its current values hold one no real rig has ([`crate::fit::priors`]): such a
    /// model is no adequate description, whatever its criterion.
    fn implausible(&self) -> bool {
        false
    }
    /// The model with the rig's measured values held at their current values (`None` when
    /// none is free): a candidate fitted while the model misfits first settles its nuisance
    /// with them held, so that they do not take up the misfit on the way.
    fn rig_held(&self) -> Option<Self> {
        None
    }
    /// This model (its free parameters, priors and weights) at `other`'s values.
    fn adopt(&self, other: &Self) -> Self {
        let _ = other;
        self.clone()
    }
    /// Whether a measured rig value stands more than 3 of its deviations from the rig file's
    /// at `p`: the sign that it may have taken up a misfit.
    fn rig_moved(&self, p: &DVector<f64>) -> bool {
        let _ = p;
        false
    }
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
    fn coulomb(&self) -> Self {
        super::nuisance::coulomb_of(self)
    }
    fn score_drops(&self, p: &DVector<f64>, candidates: &[Nuisance]) -> Vec<(Nuisance, f64)> {
        score_drops(self, p, candidates)
    }
    fn implausible(&self) -> bool {
        !crate::fit::priors::implausible(self).is_empty()
    }
    fn rig_held(&self) -> Option<Self> {
        let measured = |q: &Param| q.is_measured() && self.prior_on(*q).is_some();
        if !self.free.iter().any(measured) {
            return None;
        }
        let mut held = self.clone();
        held.free.retain(|q| !measured(q));
        Some(held)
    }
    fn rig_moved(&self, p: &DVector<f64>) -> bool {
        self.prior_rows(p.as_slice())
            .any(|(i, z, _)| self.free[i].is_measured() && z.abs() > 3.0)
    }
    fn adopt(&self, other: &Self) -> Self {
        let mut m = self.clone();
        m.rig = other.rig;
        m.initial = other.initial;
        m.camera = other.camera;
        m
    }
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
    // The rig's measured values back at the rig file's: freed while the model misfitted, they
    // may have taken part of its compromise.
    let mut v = f.values();
    for (i, &q) in f.free.iter().enumerate() {
        if let Some(pr) = f.prior_on(q).filter(|_| q.is_measured()) {
            v[i] = pr.centre;
        }
    }
    f.set_values(&v);
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
