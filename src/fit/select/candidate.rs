//! What the forward selection needs of a model ([`Candidate`]), written once so that one
//! recording's problem and several recordings fitted jointly share the selection (the first
//! in `problem_candidate.rs`, the second in `fit::joint`).

use super::nuisance::Nuisance;
use crate::fit::lm::LeastSquares;
use crate::fit::problem::Param;
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
    /// The model with Stribeck's speed at its second start
    /// ([`super::nuisance::STRIBECK_SLOW_START`]) when the law was just added (its speed free
    /// and still at [`super::nuisance::STRIBECK_START`]); `None` otherwise.
    fn stribeck_slow_start(&self) -> Option<Self>;
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
