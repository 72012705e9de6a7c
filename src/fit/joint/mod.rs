//! One rig, many releases: the releases fitted together. The rail and the pendulum are the
//! same in every release, so the friction law, the tilt, the viscous terms and the pendulum's
//! build are shared; each release keeps its initial state and marker lag, and its camera
//! unless the camera is the same. The releases' problems are the single fit's
//! ([`TrajectoryProblem`]); the joint problem sums their normal equations into the shared and
//! per-release blocks, so its cost grows linearly with the releases, and its nuisances are
//! chosen by the single fit's selection ([`select::forward`] over [`Candidate`]).
//!
//! The folder's files: `problem.rs` the joint problem; `rigs.rs` releases of another rig;
//! `agreement.rs` the releases' own mu and their agreement; `set_aside.rs` the releases that
//! disagree; this file the joint fit's settings, report and driver [`fit_joint`].

mod agreement;
mod problem;
mod rigs;
mod set_aside;

pub use problem::JointProblem;
pub use rigs::other_rigs;

use super::intervals::{model_uncertainty, widen, within_bounds};
use super::problem::{Observations, Param, TrajectoryProblem};
use super::select::{self, Candidate, ModelRow, Nuisance, SelectOptions};
use super::solve::{solve_loose, STAGE_FTOL};
use super::uncertainty;
use super::{fit, Estimate, FitError, FitReport, FitSettings};
use crate::model::{Rig, State};
use crate::sim::{simulate, Request};
use agreement::{consistency, leave_one_out, own_mu, p_text, window_spread_of, AGREE_P};
use nalgebra::DMatrix;
use rayon::prelude::*;
use serde::Serialize;
use set_aside::set_aside;

/// One release of a joint fit: its name and its tracks.
#[derive(Debug, Clone)]
pub struct Release {
    /// The recording's name (its file, for messages and the table).
    pub name: String,
    /// Its tracks.
    pub obs: Observations,
}

/// Settings of a joint fit beyond the single fit's.
#[derive(Debug, Clone, Default)]
pub struct JointSettings {
    /// One camera for every release: its scale and marker offsets shared.
    pub same_camera: bool,
    /// Fit the other releases when one fails (it is named); otherwise a failure ends the fit.
    pub keep_going: bool,
}

/// A release in the joint fit's table.
#[derive(Debug, Clone, Serialize)]
pub struct ReleaseRow {
    /// The recording's name.
    pub name: String,
    /// Frames with a marker.
    pub frames: usize,
    /// Mode transitions of the joint model in this release.
    pub transitions: usize,
    /// mu_kinetic of this release alone, with the shared nuisances held at the joint values.
    pub own_mu: Option<Estimate>,
    /// mu_kinetic of the release's single fit (its own nuisances, chosen from it alone).
    pub single_mu: Option<Estimate>,
    /// Nuisances its single fit chose.
    pub single_nuisances: Vec<&'static str>,
    /// RMS residual under the joint model (m).
    pub rms_residual_m: f64,
    /// Chi-square of its residuals under the joint model.
    pub chi2: f64,
    /// Its residual rows.
    pub n_residuals: usize,
    /// (own mu - the others' joint mu) / combined standard error.
    pub z: f64,
    /// Whether its own mu agrees with the other releases' (|z| below 3, or the releases agree).
    pub agrees: bool,
}

/// The result of a joint fit.
#[derive(Debug, Clone)]
pub struct JointReport {
    /// mu_kinetic of the rail, with its interval.
    pub mu_kinetic: Estimate,
    /// Every shared parameter with its estimate (mu_kinetic first).
    pub shared: Vec<(Param, Estimate)>,
    /// Covariance of the shared parameters (the releases' own parameters marginalised):
    /// its inverse is what the releases know of them.
    pub shared_covariance: DMatrix<f64>,
    /// The releases.
    pub releases: Vec<ReleaseRow>,
    /// Releases that failed and were left out (name, why), with `keep_going`.
    pub left_out: Vec<(String, String)>,
    /// p-value of the releases' own mu agreeing (chi-square of their spread), with two or
    /// more releases.
    pub consistency_p: Option<f64>,
    /// The releases whose own mu disagrees with the others'.
    pub disagreeing: Vec<String>,
    /// mu_kinetic of the other releases fitted jointly without those (Wald interval).
    pub mu_without_disagreeing: Option<Estimate>,
    /// Nuisances in the joint model.
    pub nuisances: Vec<Nuisance>,
    /// Every joint model compared.
    pub models: Vec<ModelRow>,
    /// Chi-square of the joint model.
    pub chi2: f64,
    /// Residual rows minus free parameters.
    pub dof: f64,
    /// chi2 / dof.
    pub reduced_chi2: f64,
    /// Free parameters in all.
    pub n_params: usize,
    /// One plain sentence on what the interval holds.
    pub sentence: String,
    /// Warnings.
    pub warnings: Vec<String>,
    /// Levenberg-Marquardt iterations of the joint stages (the single fits not counted).
    pub iterations: u64,
}

/// Why a joint fit could not run.
#[derive(Debug, thiserror::Error)]
pub enum JointError {
    /// Fewer than two releases to fit.
    #[error("a joint fit needs two or more recordings, got {0}")]
    TooFew(usize),
    /// Releases of different rigs.
    #[error("{0}")]
    OtherRig(String),
    /// A release's own fit failed.
    #[error("{name}: {error}")]
    Release {
        /// The release.
        name: String,
        /// Its failure.
        error: FitError,
    },
    /// The joint fit failed.
    #[error("the joint fit failed: {0}")]
    Joint(String),
}

/// Fit the releases jointly: each alone first (its start, noise, outliers and own mu), then
/// all together with the shared parameters tied, the nuisances chosen by the data, and the
/// releases' agreement tested.
pub fn fit_joint(
    releases: &[Release],
    rig_guess: &Rig<f64>,
    settings: &FitSettings,
    joint: &JointSettings,
) -> Result<JointReport, JointError> {
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
    let singles: Vec<Result<FitReport, FitError>> = releases
        .par_iter()
        .with_max_len(1)
        .map(|r| fit(r.obs.clone(), rig_guess, settings))
        .collect();
    let mut warnings = Vec::new();
    let mut left_out = Vec::new();
    let mut kept: Vec<(&Release, FitReport)> = Vec::new();
    for (r, s) in releases.iter().zip(singles) {
        match s {
            Ok(rep) if rep.failed.is_none() && rep.mu_kinetic.is_some() => kept.push((r, rep)),
            Ok(rep) => {
                let why = rep
                    .failed
                    .clone()
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
    // The start: mu the precision-weighted mean of the single fits', each release's state
    // and noise from its single fit, the rig's nuisances at their neutral values.
    let (mut num, mut den) = (0.0, 0.0);
    for (_, rep) in &kept {
        let e = rep.mu_kinetic.expect("kept fits have mu");
        let w = 1.0 / e.stderr.max(1e-12).powi(2);
        num += w * e.value;
        den += w;
    }
    let mu0 = num / den;
    let parts: Vec<TrajectoryProblem> = kept
        .iter()
        .map(|(_, rep)| {
            let single = &rep.problem;
            let mut rig = *rig_guess;
            rig.mu_kinetic = mu0;
            rig.mu_static = mu0;
            rig.marker_length = single.rig.marker_length;
            let free: Vec<Param> = single
                .free
                .iter()
                .copied()
                .filter(|q| {
                    q.is_state()
                        || *q == Param::MuKinetic
                        || (*q == Param::RodLength && settings.fit_rod_length)
                })
                .collect();
            let mut part = single.clone();
            part.rig = rig;
            part.camera = Default::default();
            part.free = free;
            part.tie_static = true;
            part
        })
        .collect();
    let starts: Vec<(State<f64>, f64)> = kept
        .iter()
        .map(|(_, rep)| (rep.problem.initial, mu0))
        .collect();
    let jp = JointProblem::new(parts, joint.same_camera);
    let p0 = jp.values();
    let (p, cost, mut iterations) =
        solve_loose(&jp, p0, settings.max_iters, Some(STAGE_FTOL)).map_err(JointError::Joint)?;
    let mut jp = jp;
    jp.set_values(&p);
    let static_evidence = kept.iter().any(|(_, rep)| {
        rep.nuisances
            .iter()
            .any(|n| matches!(n, Nuisance::StaticFriction | Nuisance::Stribeck))
    });
    let (mut jp, p, nuisances, models) = if settings.nuisances || !settings.with.is_empty() {
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
            fresh_start: Some(starts),
            forced: settings.with.clone(),
        };
        let sel = select::forward(jp, p, 2.0 * cost, &opts);
        iterations += sel.iterations;
        (sel.problem, sel.p, sel.chosen, sel.rows)
    } else {
        (jp, p, Vec::new(), Vec::new())
    };
    // Polish the chosen model to the solver's full tolerance.
    let (p, _, it) = solve_loose(&jp, p, settings.max_iters, None).map_err(JointError::Joint)?;
    iterations += it;
    jp.set_values(&p);
    // The covariance: the Jacobian's, scaled by the reduced chi-square when above one, and
    // the block covariance over each release's stretches of frames (the larger of the two).
    let blocks: Vec<usize> = kept
        .iter()
        .map(|(_, rep)| rep.adequacy.block_frames.max(5))
        .collect();
    let normal = jp
        .normal_equations_blocked(&p, Some(&blocks))
        .map_err(|e| JointError::Joint(e.to_string()))?;
    let n_blocks: f64 = jp
        .parts
        .iter()
        .zip(&blocks)
        .map(|(m, b)| m.frame_times().len().div_ceil(*b) as f64)
        .sum();
    let k = p.len();
    let c = uncertainty::covariances(
        normal,
        jp.parts.iter().map(|m| m.rows_used()).sum(),
        n_blocks,
    );
    if c.singular {
        return Err(JointError::Joint(
            "the joint information matrix is singular".into(),
        ));
    }
    let (chi2, dof, reduced) = (c.chi2, c.dof, c.reduced_chi2);
    let (cov, cov_block) = (&c.cov, &c.block);
    let s = jp.shared.len();
    let se: Vec<f64> = (0..s)
        .map(|i| cov[(i, i)].max(cov_block[(i, i)]).max(0.0).sqrt())
        .collect();
    let shared_cov = DMatrix::from_fn(s, s, |i, j| {
        let scale = (se[i] * se[j]) / (cov[(i, i)] * cov[(j, j)]).sqrt().max(1e-300);
        cov[(i, j)] * scale
    });
    let mut shared: Vec<(Param, Estimate)> = jp
        .shared
        .iter()
        .enumerate()
        .map(|(i, &q)| {
            (
                q,
                Estimate {
                    value: p[i],
                    stderr: se[i],
                    ci95: [p[i] - 1.96 * se[i], p[i] + 1.96 * se[i]],
                    interval: if cov_block[(i, i)] > cov[(i, i)] * 1.0002 {
                        "wald+block"
                    } else {
                        "wald"
                    },
                },
            )
        })
        .collect();
    let mu_i = jp
        .shared
        .iter()
        .position(|q| *q == Param::MuKinetic)
        .ok_or_else(|| JointError::Joint("mu_kinetic is not free".into()))?;
    // Each release alone under the joint model: its own mu, its residuals and transitions.
    let shared_params = jp.shared.clone();
    let rows: Vec<ReleaseRow> = jp
        .parts
        .par_iter()
        .zip(kept.par_iter())
        .with_max_len(1)
        .map(|(m, (r, rep))| {
            let own = own_mu(m, &shared_params, settings);
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
            let t_end = m.frame_times().last().copied().unwrap_or(0.0);
            let transitions = simulate(
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
            .unwrap_or(0);
            ReleaseRow {
                name: r.name.clone(),
                frames: m.frame_times().len(),
                transitions,
                own_mu: own,
                single_mu: rep.mu_kinetic,
                single_nuisances: rep.nuisances.iter().map(|n| n.name()).collect(),
                rms_residual_m: rms,
                chi2,
                n_residuals: m.rows_used(),
                z: 0.0,
                agrees: true,
            }
        })
        .collect();
    let mut rows = rows;
    // The releases' agreement: the same test and widening as the single fit's windows.
    let pairs: Vec<(f64, f64)> = rows
        .iter()
        .map(|r| r.own_mu.map_or((f64::NAN, 0.0), |e| (e.value, e.stderr)))
        .collect();
    let consistency_p = consistency(&pairs);
    let z = leave_one_out(&pairs);
    rows.iter_mut().zip(&z).for_each(|(r, z)| r.z = *z);
    let disagree = consistency_p.is_some_and(|pv| pv < AGREE_P);
    let mut mu = shared[mu_i].1;
    model_uncertainty(&mut mu, &models, &mut warnings);
    let mut sentence = format!(
        "The {} releases agree (p = {:.2}); the interval is what they support together.",
        rows.len(),
        consistency_p.unwrap_or(f64::NAN)
    );
    let mut disagreeing = Vec::new();
    let mut others = None;
    if disagree {
        // Which releases: the worst one set aside at a time and the rest refitted (an odd
        // release pulls the shared tilt and so every release's own mu), until the rest agree.
        let (out, rest) = set_aside(&jp, &z, settings);
        for &i in &out {
            rows[i].agrees = false;
            disagreeing.push(rows[i].name.clone());
        }
        if let Some((rest_mu, rest_z)) = rest {
            // Each release's own mu and z under the agreeing releases' shared values.
            for (i, (v, se), zi) in rest_z {
                rows[i].z = zi;
                if let Some(e) = rows[i].own_mu.as_mut() {
                    *e = Estimate {
                        value: v,
                        stderr: se,
                        ci95: [v - 1.96 * se, v + 1.96 * se],
                        interval: "wald",
                    };
                }
            }
            others = Some(rest_mu);
        }
        let spread = window_spread_of(&pairs, mu.value);
        widen(&mut mu, spread, "releases");
        sentence = format!(
            "The releases disagree (p = {}): {} {} off the others{}; the interval is widened by the releases' spread, and is the rail's only if every release ran on one rail.",
            p_text(consistency_p.unwrap_or(f64::NAN)),
            disagreeing.join(", "),
            if disagreeing.len() == 1 { "lies" } else { "lie" },
            others.map_or(String::new(), |e: Estimate| format!(
                " (without {}, mu_kinetic {:.5} +- {:.1e})",
                if disagreeing.len() == 1 { "it" } else { "them" },
                e.value,
                e.stderr
            ))
        );
    }
    if select::misfits(&jp, chi2) {
        warnings.push(format!(
            "the joint model misfits the releases (reduced chi-square {reduced:.2}): the interval is the Jacobian's scaled by it"
        ));
    }
    mu = within_bounds(Param::MuKinetic, mu, 0.0);
    shared[mu_i].1 = mu;
    // mu's row and column carry its final standard error (widened by the models and the
    // releases), so what a plan takes as known is no more than the report claims.
    let mut shared_cov = shared_cov;
    let ratio = mu.stderr / shared_cov[(mu_i, mu_i)].max(1e-300).sqrt();
    for j in 0..s {
        shared_cov[(mu_i, j)] *= ratio;
        shared_cov[(j, mu_i)] *= ratio;
    }
    Ok(JointReport {
        mu_kinetic: mu,
        shared,
        shared_covariance: shared_cov,
        releases: rows,
        left_out,
        consistency_p,
        disagreeing,
        mu_without_disagreeing: others,
        nuisances,
        models,
        chi2,
        dof,
        reduced_chi2: reduced,
        n_params: k,
        sentence,
        warnings,
        iterations,
    })
}
