//! A single recording's problem ([`TrajectoryProblem`]) as a candidate of the selection.

use super::candidate::Candidate;
use super::nuisance::{coulomb_of, Nuisance, STRIBECK_SLOW_START, STRIBECK_START};
use super::score::score_drops;
use crate::fit::problem::{Param, TrajectoryProblem};
use crate::model::State;
use nalgebra::DVector;

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
    fn stribeck_slow_start(&self) -> Option<Self> {
        let fresh = self.free.contains(&Param::StribeckVelocity)
            && self.rig.stribeck_velocity == STRIBECK_START;
        fresh.then(|| {
            let mut m = self.clone();
            m.rig.stribeck_velocity = STRIBECK_SLOW_START;
            m
        })
    }
    fn coulomb(&self) -> Self {
        coulomb_of(self)
    }
    fn score_drops(&self, p: &DVector<f64>, candidates: &[Nuisance]) -> Vec<(Nuisance, f64)> {
        score_drops(self, p, candidates)
    }
    fn implausible(&self) -> bool {
        !crate::fit::implausible::implausible(self).is_empty()
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
