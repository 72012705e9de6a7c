//! Each release alone under the joint model, for the joint fit's table: its own mu (the shared
//! nuisances held), its residuals and its mode transitions.

use super::agreement::own_mu;
use super::outcome::ReleaseRow;
use super::problem::JointProblem;
use super::settings::Release;
use super::singles::Single;
use crate::fit::problem::{Param, TrajectoryProblem};
use crate::fit::{FitReport, FitSettings};
use crate::sim::{simulate, Request};
use rayon::prelude::*;

/// Each release's row (in parallel), in the order of `kept`: z and agreement left for the
/// agreement test.
pub(super) fn release_rows(
    jp: &JointProblem,
    kept: &[&Single],
    settings: &FitSettings,
) -> Vec<ReleaseRow> {
    let shared_params = jp.shared.clone();
    jp.parts
        .par_iter()
        .zip(kept.par_iter())
        .with_max_len(1)
        .map(|(m, single)| release_row(m, single.0, &single.1, &shared_params, settings))
        .collect()
}

/// Release `r`'s row: `m` its part of the joint model, `rep` its single fit.
pub(super) fn release_row(
    m: &TrajectoryProblem,
    r: &Release,
    rep: &FitReport,
    shared_params: &[Param],
    settings: &FitSettings,
) -> ReleaseRow {
    let own = own_mu(m, shared_params, settings);
    let v = m.values();
    let raw = m.raw_residuals(&v).unwrap_or_default();
    let used: Vec<f64> = raw
        .iter()
        .enumerate()
        .filter(|(i, _)| m.row_weight(*i) > 0.0)
        .map(|(_, x)| *x)
        .collect();
    let rms = (used.iter().map(|x| x * x).sum::<f64>() / used.len().max(1) as f64).sqrt();
    let chi2 = m.chi2(&v).unwrap_or(f64::NAN);
    ReleaseRow {
        name: r.name.clone(),
        frames: m.frame_times().len(),
        transitions: transitions(m),
        own_mu: own,
        single_mu: rep.mu_kinetic,
        single_nuisances: rep.nuisances.iter().map(|n| n.name()).collect(),
        rms_residual_m: rms,
        chi2,
        n_residuals: m.rows_used(),
        z: 0.0,
        agrees: true,
    }
}

/// Mode transitions of `m`'s motion over its recording (0 when it cannot be simulated).
fn transitions(m: &TrajectoryProblem) -> usize {
    let t_end = m.frame_times().last().copied().unwrap_or(0.0);
    simulate(
        &m.rig,
        &m.initial,
        t_end,
        &m.options,
        &Request {
            sample_times: Vec::new(),
            friction_work: false,
            positions_only: true,
        },
    )
    .map(|s| s.events.len())
    .unwrap_or(0)
}
