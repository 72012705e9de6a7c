//! The joint fit's first stages: the releases checked (two or more, of one rig), each fitted
//! alone (its state, noise, outliers and nuisances), and the joint problem's start built from
//! those single fits.

use super::error::JointError;
use super::problem::JointProblem;
use super::rigs::other_rigs;
use super::settings::{JointSettings, Release};
use crate::fit::problem::{Param, TrajectoryProblem};
use crate::fit::select::{Candidate, Nuisance};
use crate::fit::{fit, FitError, FitReport, FitSettings};
use crate::model::{Rig, State};
use rayon::prelude::*;

/// Two or more releases, all of one rig (their marker distances agree, [`other_rigs`]).
pub(super) fn check_releases(releases: &[Release]) -> Result<(), JointError> {
    if releases.len() < 2 {
        return Err(JointError::TooFew(releases.len()));
    }
    let odd = other_rigs(releases);
    if !odd.is_empty() {
        let list: Vec<String> = odd
            .iter()
            .map(|(n, d, m)| {
                format!("{n} (marker distance {d:.4} m, the releases' median {m:.4} m)")
            })
            .collect();
        return Err(JointError::OtherRig(format!(
            "the recordings are not of one rig: {}; a joint fit shares the rig, so fit them apart",
            list.join("; ")
        )));
    }
    Ok(())
}

/// A release with its single fit.
pub(super) type Single<'a> = (&'a Release, FitReport);

/// The releases' single fits the joint fit builds on, and those left out.
pub(super) struct Singles<'a> {
    /// Each release kept, with its single fit (mu_kinetic identified, not failed).
    pub(super) kept: Vec<Single<'a>>,
    /// Releases left out (name, why), with `keep_going`.
    pub(super) left_out: Vec<(String, String)>,
    /// One warning per release left out.
    pub(super) warnings: Vec<String>,
}

/// Each release fitted alone (in parallel). A release whose fit fails, or does not identify
/// mu_kinetic, ends the joint fit unless `keep_going`, when it is left out and named; two
/// releases must remain. The single fits give the joint fit its start, its candidate
/// nuisances and each release's own value: their Wald intervals do (no profile, no windows,
/// which the joint fit never reads and which cost a sixth of its time).
pub(super) fn fit_singles<'a>(
    releases: &'a [Release],
    rig_guess: &Rig<f64>,
    settings: &FitSettings,
    joint: &JointSettings,
) -> Result<Singles<'a>, JointError> {
    let quick = FitSettings {
        profile: false,
        windows: false,
        ..settings.clone()
    };
    let singles: Vec<Result<FitReport, FitError>> = releases
        .par_iter()
        .with_max_len(1)
        .map(|r| fit(r.obs.clone(), rig_guess, &quick))
        .collect();
    let mut warnings = Vec::new();
    let mut left_out = Vec::new();
    let mut kept: Vec<Single> = Vec::new();
    for (r, s) in releases.iter().zip(singles) {
        match s {
            Ok(rep) if rep.failed.is_none() && rep.mu_kinetic.is_some() => kept.push((r, rep)),
            Ok(rep) => {
                let why = rep
                    .failed
                    .clone()
                    .or_else(|| rep.not_identifiable.clone())
                    .unwrap_or_else(|| "its motion does not identify mu_kinetic".into());
                if !joint.keep_going {
                    return Err(JointError::Release {
                        name: r.name.clone(),
                        error: FitError::Settings(format!(
                            "{why} (--keep-going fits the others without it)"
                        )),
                    });
                }
                left_out.push((r.name.clone(), why));
            }
            Err(e) if joint.keep_going => left_out.push((r.name.clone(), e.to_string())),
            Err(e) => {
                return Err(JointError::Release {
                    name: r.name.clone(),
                    error: e,
                })
            }
        }
    }
    if kept.len() < 2 {
        return Err(JointError::TooFew(kept.len()));
    }
    for (name, why) in &left_out {
        warnings.push(format!("{name} was left out: {why}"));
    }
    Ok(Singles {
        kept,
        left_out,
        warnings,
    })
}

/// The joint problem at its start, and each release's restart for the selection.
pub(super) struct Start {
    /// The releases' problems tied: mu the single fits' precision-weighted mean, each
    /// release's state and noise from its single fit, the consensus nuisances in the model at
    /// the single fits' values.
    pub(super) problem: JointProblem,
    /// Each release's initial state from its single fit, with the start's mu.
    pub(super) restarts: Vec<(State<f64>, f64)>,
    /// The start's mu_kinetic.
    pub(super) mu0: f64,
    /// The consensus: nuisances chosen by half the single fits or more, in the start's
    /// model already (the selection goes on from them).
    pub(super) consensus: Vec<Nuisance>,
    /// The releases' parts before the consensus was added (to fit the model without one).
    pub(super) plain: Vec<TrajectoryProblem>,
}

/// The start: mu the precision-weighted mean of the single fits', each release's state and
/// noise from its single fit, and the nuisances half the single fits chose or more in the
/// model, each value the median of the single fits' (a release whose fit did not choose it
/// at its neutral value). The selection then goes on from the releases' consensus instead of
/// finding it again from the plain model, which cost as much as the single fits.
pub(super) fn start(
    kept: &[&Single],
    rig_guess: &Rig<f64>,
    settings: &FitSettings,
    joint: &JointSettings,
) -> Start {
    let (mut num, mut den) = (0.0, 0.0);
    for (_, rep) in kept {
        let e = rep.mu_kinetic.expect("kept fits have mu");
        let w = 1.0 / e.stderr.max(1e-12).powi(2);
        num += w * e.value;
        den += w;
    }
    let mu0 = num / den;
    let consensus = consensus(kept, settings, joint.same_camera);
    let plain: Vec<TrajectoryProblem> = kept
        .iter()
        .map(|(_, rep)| start_part(&rep.problem, rig_guess, mu0, settings))
        .collect();
    let mut parts = plain.clone();
    for part in &mut parts {
        for &nu in &consensus {
            *part = part.with_nuisance(nu, mu0 * 1.1);
        }
    }
    let mut problem = JointProblem::new(parts, joint.same_camera);
    // Each parameter the consensus frees at the single fits' median (shared) or the release's
    // own single fit's value.
    let singles: Vec<&TrajectoryProblem> = kept.iter().map(|(_, rep)| &rep.problem).collect();
    for q in consensus.iter().flat_map(|n| n.params()).copied() {
        let own: Vec<Option<f64>> = singles
            .iter()
            .map(|m| m.free.contains(&q).then(|| m.get(q)))
            .collect();
        let shared = problem.shared.contains(&q);
        let median = median(own.iter().flatten().copied().collect());
        for (part, v) in problem.parts.iter_mut().zip(&own) {
            match (shared, v, median) {
                (true, _, Some(m)) => set_param(part, q, m),
                (false, Some(v), _) => set_param(part, q, *v),
                _ => {}
            }
        }
    }
    let restarts: Vec<(State<f64>, f64)> = kept
        .iter()
        .map(|(_, rep)| (rep.problem.initial, mu0))
        .collect();
    Start {
        problem,
        restarts,
        mu0,
        consensus,
        plain,
    }
}

/// The nuisances half the single fits chose or more (in the order of [`Nuisance::ALL`]), one
/// of any two that conflict, none the settings leave out; none when the data choose none.
/// Only the rig's (shared) ones: a camera nuisance is each release's own, and one release
/// often takes a marker offset for what the releases together show as a tilt, so the joint
/// selection finds those again itself.
fn consensus(kept: &[&Single], settings: &FitSettings, same_camera: bool) -> Vec<Nuisance> {
    if !settings.nuisances {
        return Vec::new();
    }
    let excluded = settings.excluded();
    let mut out: Vec<Nuisance> = Vec::new();
    for nu in Nuisance::ALL {
        let votes = kept
            .iter()
            .filter(|(_, rep)| rep.nuisances.contains(&nu))
            .count();
        let shared = nu
            .params()
            .iter()
            .all(|q| q.is_rig() || (same_camera && q.is_camera() && *q != Param::Lag));
        if 2 * votes >= kept.len()
            && shared
            && !excluded.contains(&nu)
            && !out.iter().any(|c| c.conflicts(nu))
        {
            out.push(nu);
        }
    }
    out
}

/// The median of `v` (`None` when empty).
fn median(mut v: Vec<f64>) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    Some(0.5 * (v[(n - 1) / 2] + v[n / 2]))
}

/// Set parameter `q` of `m` to `v` (through its values, with `q` briefly free).
pub(super) fn set_param(m: &mut TrajectoryProblem, q: Param, v: f64) {
    let free = std::mem::replace(&mut m.free, vec![q]);
    m.set_values(&nalgebra::DVector::from_element(1, v));
    m.free = free;
}

/// A release's part of the start: its single fit's problem (state, noise, row weights) on the
/// guessed rig with mu at `mu0`, the ideal camera, and only the state, mu and (when fitted)
/// the rod length free.
pub(super) fn start_part(
    single: &TrajectoryProblem,
    rig_guess: &Rig<f64>,
    mu0: f64,
    settings: &FitSettings,
) -> TrajectoryProblem {
    let mut rig = *rig_guess;
    rig.mu_kinetic = mu0;
    rig.mu_static = mu0;
    // The rod the single fit found (a rigid pendulum's equivalent length in proportion).
    rig.rod_length *= single.rig.marker_length / rig_guess.marker_length;
    rig.marker_length = single.rig.marker_length;
    let free: Vec<Param> = single
        .free
        .iter()
        .copied()
        .filter(|q| {
            q.is_state()
                || *q == Param::MuKinetic
                || (*q == Param::RodLength && settings.fit_rod_length)
                // The rig file as a measurement: its rod, mass ratio and gravity, with their priors
                // (the joint problem counts a shared prior once).
                || (q.is_measured() && single.prior_on(*q).is_some())
        })
        .collect();
    let mut part = single.clone();
    part.rig = rig;
    part.camera = Default::default();
    part.free = free;
    part.tie_static = true;
    part
}
