//! The joint model: the releases fitted together from the single fits' start (their
//! consensus nuisances in it), the nuisances chosen by the data (the single fit's forward
//! selection over the joint problem, from the consensus on), and the chosen model polished
//! to the solver's full tolerance.

use super::error::JointError;
use super::problem::JointProblem;
use super::singles::{Single, Start};
use crate::fit::problem::{Param, TrajectoryProblem};
use crate::fit::select::{self, Candidate, ModelRow, Nuisance, SelectOptions};
use crate::fit::solve::{solve_loose, STAGE_FTOL};
use crate::fit::FitSettings;
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
    /// Whether the nuisances were chosen by the data (else the consensus was kept).
    pub(super) selected: bool,
    /// Shared parameters held at their values after the choice because the releases together
    /// did not determine them ([`hold_undetermined`]), with the values.
    pub(super) held: Vec<(Param, f64)>,
    /// The releases' parts without any nuisance (to fit the model without one).
    plain: Vec<TrajectoryProblem>,
    /// The start's mu_kinetic (where a nuisance's mu_static starts).
    mu0: f64,
}

/// The joint model: the start fitted (loosely: it only starts the selection), the nuisances
/// chosen (with `select`; else the start's consensus kept), the winner polished.
pub(super) fn fit_model(
    start: Start,
    kept: &[&Single],
    settings: &FitSettings,
    select: bool,
) -> Result<JointModel, JointError> {
    let Start {
        problem: jp,
        restarts,
        mu0,
        consensus,
        plain,
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
        selected: select,
        held: Vec::new(),
        plain,
        mu0,
    };
    if select && (settings.nuisances || !settings.with.is_empty()) {
        let from = Origin {
            cost,
            static_evidence,
            restarts,
            mu0,
            consensus: consensus.clone(),
        };
        model = choose_nuisances(model, from, settings);
        model = drop_unsupported(model, &consensus, settings);
    } else {
        model.nuisances = consensus;
    }
    polish(model, settings)
}

/// Where the selection starts: the start's cost, whether a single fit chose a static law,
/// each release's restart, the start's mu and the consensus nuisances already in the model.
struct Origin {
    cost: f64,
    static_evidence: bool,
    restarts: Vec<(crate::model::State<f64>, f64)>,
    mu0: f64,
    consensus: Vec<Nuisance>,
}

/// The consensus nuisances the joint data do not support taken out again: each one the
/// selection kept (not forced by the user) is dropped when the model without it, fitted from
/// the current values, has a BIC less than 2 above the model with it (the selection's own
/// rule for adding one, the other way round). Single fits of one slide each may agree on a
/// nuisance the releases together do not need.
fn drop_unsupported(
    mut model: JointModel,
    consensus: &[Nuisance],
    settings: &FitSettings,
) -> JointModel {
    let n = model.problem.n_rows() as f64;
    let chi2 = |m: &JointProblem, p: &DVector<f64>| -> Option<f64> {
        let cost = crate::fit::lm::LeastSquares::normal_equations(m, p)
            .ok()?
            .cost;
        Some(2.0 * cost)
    };
    let bic = |m: &JointProblem, chi2: f64| chi2 + m.n_free() as f64 * n.ln();
    let forced = settings.forced();
    for &nu in consensus {
        if !model.nuisances.contains(&nu) || forced.contains(&nu) {
            continue;
        }
        let Some(with) = chi2(&model.problem, &model.p).map(|c| bic(&model.problem, c)) else {
            continue;
        };
        let keep: Vec<Nuisance> = model
            .nuisances
            .iter()
            .copied()
            .filter(|c| *c != nu)
            .collect();
        let Some((without, p, it)) = without(&model, &keep, settings) else {
            continue;
        };
        model.iterations += it;
        let Some(c) = chi2(&without, &p) else {
            continue;
        };
        let b = bic(&without, c);
        if b < with + 2.0 {
            rechosen(&mut model.models, &keep, &without, c, b, n);
            model.problem = without;
            model.p = p;
            model.nuisances = keep;
        }
    }
    model
}

/// The models table after a drop made `m` (holding `keep`, at chi-square `chi2` and BIC `bic`
/// over `n` rows) the chosen model: its row in (one of the same name replaced), the others'
/// criteria against it and the weights again. The table mu's model uncertainty and the law
/// table are read from would otherwise name a model the fit no longer reports as chosen.
fn rechosen(
    rows: &mut Vec<ModelRow>,
    keep: &[Nuisance],
    m: &JointProblem,
    chi2: f64,
    bic: f64,
    n: f64,
) {
    let name = select::name_of(keep);
    rows.retain(|r| r.name != name);
    for r in rows.iter_mut() {
        r.chosen = false;
        r.delta_bic = r.bic - bic;
    }
    rows.push(ModelRow {
        name,
        free: m.free_names(),
        chi2,
        bic,
        delta_bic: 0.0,
        chosen: true,
        mu_kinetic: m.mu_kinetic(),
        failed: None,
        weight: 0.0,
        path: true,
        implausible: m.implausible(),
        stopped_early: false,
    });
    let dof = (n - m.n_free() as f64).max(1.0);
    select::model_weights(rows, (chi2 / dof).max(1.0));
}

/// `model` with only the nuisances `keep`, every value it shares with `model` kept, fitted
/// (loosely, as the selection fits): its problem (values set), optimum and iterations.
fn without(
    model: &JointModel,
    keep: &[Nuisance],
    settings: &FitSettings,
) -> Option<(JointProblem, DVector<f64>, u64)> {
    let parts = model
        .plain
        .iter()
        .zip(&model.problem.parts)
        .map(|(p, cur)| {
            let mut m = p.clone();
            for &c in keep {
                m = m.with_nuisance(c, model.mu0 * 1.1);
            }
            m.initial = cur.initial;
            for q in m.free.clone() {
                super::singles::set_param(&mut m, q, cur.get(q));
            }
            m
        })
        .collect();
    let mut without = JointProblem::new(parts, model.problem.same_camera);
    let (p, _, it) = solve_loose(
        &without,
        without.values(),
        settings.max_iters,
        Some(STAGE_FTOL),
    )
    .ok()?;
    without.set_values(&p);
    Some((without, p, it))
}

/// The chosen model with the shared parameters `undetermined` (those the releases together do
/// not determine: nothing the markers show depends on them at their fitted values) held at
/// their values, as a single fit holds them; an error when mu_kinetic is among them. A static
/// coefficient the consensus model put in whose step no release's restart reaches is such:
/// its fit is no worse for any larger value, but no better without it (a slider held stuck
/// is no Coulomb slider that slips), so the term stays and its value is a bound.
pub(super) fn hold_undetermined(
    mut model: JointModel,
    undetermined: &[Param],
) -> Result<JointModel, JointError> {
    if undetermined.is_empty() || undetermined.contains(&Param::MuKinetic) {
        return Err(JointError::Undetermined(undetermined.to_vec()));
    }
    let parts: Vec<TrajectoryProblem> = model
        .problem
        .parts
        .iter()
        .map(|part| {
            let mut m = part.clone();
            m.free.retain(|q| !undetermined.contains(q));
            m
        })
        .collect();
    for &q in undetermined {
        model.held.push((q, model.problem.parts[0].get(q)));
    }
    model.problem = JointProblem::new(parts, model.problem.same_camera);
    model.p = model.problem.values();
    Ok(model)
}

/// The nuisances chosen by the data from `model` at its optimum: the single fit's forward
/// selection from the consensus on, the friction laws offered when a single fit chose one,
/// each release's restart for a misfitting model.
fn choose_nuisances(model: JointModel, from: Origin, settings: &FitSettings) -> JointModel {
    let Origin {
        cost,
        static_evidence,
        restarts,
        mu0,
        consensus,
    } = from;
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
        first_iters: settings.first_iters,
        already: consensus,
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
        selected: true,
        held: model.held,
        plain: model.plain,
        mu0: model.mu0,
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
