//! The selection's settings ([`SelectOptions`]), its result ([`Selection`]) and the rows of
//! its table of models ([`ModelRow`]).

use super::candidate::Candidate;
use super::nuisance::Nuisance;
use nalgebra::DVector;

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
    /// Whether its values hold one no real rig has (a nuisance beyond its plausible range):
    /// it is then no adequate description, and carries no weight in mu's model uncertainty.
    pub implausible: bool,
    /// Whether its fit was stopped out of reach of the best model before converging (the
    /// selection's first pass, far behind the round's best; or a law that even its predicted
    /// drop leaves outside Occam's window): its chi-square is then an upper bound.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub stopped_early: bool,
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
    /// The score test's predicted chi-square drop of each screened candidate at the chosen
    /// model (its last round): the evidence for a candidate that was not fitted.
    pub screening: Vec<(Nuisance, f64)>,
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
    /// Iterations a start of a round's candidate gets first; one stopped then is fitted to
    /// the end only when near the round's best (0: every candidate to the end).
    pub first_iters: u64,
    /// Nuisances the model holds already (not offered again).
    pub already: Vec<Nuisance>,
    /// A second start for each candidate, used while the current model misfits: the data's
    /// initial state and mu_kinetic. A misfitting model's optimum is often a compromise far
    /// from the truth (a drift fitted by a push), from which the right nuisance alone does
    /// not lead back.
    pub fresh_start: Option<S>,
    /// Nuisances the user put in the model (`--with`): added first, whatever they cost.
    pub forced: Vec<Nuisance>,
    /// Nuisances never offered (`--friction LAW` leaves out the other laws).
    pub excluded: Vec<Nuisance>,
}

/// Whether `problem`'s chi-square is far beyond its degrees of freedom (5 standard
/// deviations): the model misfits, so the linear screening and the current optimum are not
/// to be trusted.
pub fn misfits<M: Candidate>(problem: &M, chi2: f64) -> bool {
    let dof = (problem.n_rows().saturating_sub(problem.n_free()) as f64).max(1.0);
    chi2 > dof + 5.0 * (2.0 * dof).sqrt()
}

/// Chi-square of a solved model (the solver's cost is half of it).
pub(super) fn chi2_of(cost: f64) -> f64 {
    2.0 * cost
}
