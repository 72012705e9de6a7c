//! Physics and camera nuisances chosen by the data: candidate models as data ([`Nuisance`]),
//! screened by a score test (the chi-square drop a parameter would buy, predicted from one
//! Jacobian at the current optimum), the promising ones fitted, and the best kept while it
//! lowers the Bayesian information criterion BIC = chi2 + k ln(n) (forward selection).
//!
//! The folder's files: `nuisance.rs` the candidates; `candidate.rs` what the selection needs
//! of a model; `score.rs` the score test; `attempt.rs` one candidate's fit; `forward.rs` the
//! selection; `weights.rs` the models' weights and mu's spread across them; `selection.rs`
//! the selection's settings, results and table rows; `problem_candidate.rs` a single
//! recording's problem as a candidate. This file is the folder's face: its modules and what
//! it offers the fit.

mod attempt;
mod candidate;
mod forward;
mod nuisance;
mod problem_candidate;
mod score;
mod selection;
mod weights;

pub use candidate::Candidate;
pub use forward::{forward, name_of};
pub use nuisance::{Nuisance, MU_PINNED};
pub use score::score_drops_by;
pub use selection::{misfits, ModelRow, SelectOptions};
pub use weights::{adequate_spread, model_spread, model_weights};
