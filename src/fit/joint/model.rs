//! The joint model: the releases fitted together from the single fits' start, the nuisances
//! chosen by the data (the single fit's forward selection over the joint problem), and the
//! chosen model polished to the solver's full tolerance.

use super::singles::Start;
use super::{JointError, JointProblem, Release};
use crate::fit::select::{self, Candidate, ModelRow, Nuisance, SelectOptions};
use crate::fit::solve::{solve_loose, STAGE_FTOL};
use crate::fit::{FitReport, FitSettings};
use nalgebra::DVector;

/// The chosen joint model at its optimum, with the comparison behind it.
pub(super) struct JointModel {
    /// The chosen model, values set.
    pub(super) problem: JointProblem,
    /// Its optimum.
    pub(super) p: DVector<f64>,
    /// Nuisances in it.
    pub(super) nuisances: Vec<Nuisance>,
    /// Every joint model compared.
    pub(super) models: Vec<ModelRow>,
    /// Levenberg-Marquardt iterations spent.
    pub(super) iterations: u64,
}

/// The joint model: the start fitted (loosely: it only starts the selection), the nuisances
/// chosen, the winner polished.
pub(super) fn fit_model(
    start: Start,
    kept: &[(&Release, FitReport)],
    settings: &FitSettings,
) -> Result<JointModel, JointError> {
    let Start {
        problem: jp,
        restarts,
        mu0,
    } = start;
    let p0 = jp.values();
    let (p, cost, iterations) =
        solve_loose(&jp, p0, settings.max_iters, Some(STAGE_FTOL)).map_err(JointError::Joint)?;
    let mut jp = jp;
    jp.set_values(&p);
    let static_evidence = kept.iter().any(|(_, rep)| {
        rep.nuisances
            .iter()
            .any(|n| matches!(n, Nuisance::StaticFriction | Nuisance::Stribeck))
    });
    let mut model = JointModel {
        problem: jp,
        p,
        nuisances: Vec::new(),
        models: Vec::new(),
        iterations,
    };
    if settings.nuisances || !settings.with.is_empty() {
        model = choose_nuisances(model, cost, static_evidence, restarts, mu0, settings);
    }
    polish(model, settings)
}

/// The nuisances chosen by the data from `model` at its optimum (cost `cost`): the single
/// fit's forward selection, the friction laws offered when a single fit chose one
/// (`static_evidence`), each release's `restarts` for a misfitting model.
fn choose_nuisances(
    model: JointModel,
    cost: f64,
    static_evidence: bool,
    restarts: Vec<(crate::model::State<f64>, f64)>,
    mu0: f64,
    settings: &FitSettings,
) -> JointModel {
    let opts = SelectOptions {
        friction_candidates: settings.nuisances,
        static_evidence,
        mu_static_start: mu0 * 1.1,
        max_added: if settings.nuisances {
            Nuisance::ALL.len()
        } else {
            0
        },
        max_iters: settings.max_iters,
        already: Vec::new(),
        fresh_start: Some(restarts),
        forced: settings.forced(),
        excluded: settings.excluded(),
    };
    let sel = select::forward(model.problem, model.p, 2.0 * cost, &opts);
    JointModel {
        problem: sel.problem,
        p: sel.p,
        nuisances: sel.chosen,
        models: sel.rows,
        iterations: model.iterations + sel.iterations,
    }
}

/// The chosen model polished to the solver's full tolerance.
fn polish(mut model: JointModel, settings: &FitSettings) -> Result<JointModel, JointError> {
    let (p, _, it) = solve_loose(&model.problem, model.p, settings.max_iters, None)
        .map_err(JointError::Joint)?;
    model.iterations += it;
    model.problem.set_values(&p);
    model.p = p;
    Ok(model)
}
