//! What the releases know together of the rig's parameters: the joint model's covariance (the
//! Jacobian's, scaled by the reduced chi-square when above one, or the block covariance over
//! each release's stretches of frames when larger), the shared estimates and their covariance.

use super::error::JointError;
use super::problem::JointProblem;
use super::singles::Single;
use crate::fit::intervals::within_bounds;
use crate::fit::problem::Param;
use crate::fit::uncertainty;
use crate::fit::Estimate;
use nalgebra::{DMatrix, DVector};

/// The shared parameters' estimates and covariance, and the joint model's chi-square.
pub(super) struct SharedFit {
    /// Every shared parameter with its estimate (in the joint vector's order).
    pub(super) estimates: Vec<(Param, Estimate)>,
    /// Their covariance, the releases' own parameters marginalised.
    pub(super) covariance: DMatrix<f64>,
    /// Where mu_kinetic stands among them.
    pub(super) mu_index: usize,
    /// Chi-square of the joint model.
    pub(super) chi2: f64,
    /// Residual rows minus free parameters.
    pub(super) dof: f64,
    /// chi2 / dof.
    pub(super) reduced_chi2: f64,
}

/// The covariance: the Jacobian's, scaled by the reduced chi-square when above one, and the
/// block covariance over each release's stretches of frames (the larger of the two), each
/// release's blocks as long as its single fit's.
pub(super) fn shared_fit(
    jp: &JointProblem,
    p: &DVector<f64>,
    kept: &[&Single],
) -> Result<SharedFit, JointError> {
    let blocks: Vec<usize> = kept
        .iter()
        .map(|(_, rep)| rep.adequacy.block_frames.max(5))
        .collect();
    let normal = jp
        .normal_equations_blocked(p, Some(&blocks))
        .map_err(|e| JointError::Joint(e.to_string()))?;
    let n_blocks: f64 = jp
        .parts
        .iter()
        .zip(&blocks)
        .map(|(m, b)| m.frame_times().len().div_ceil(*b) as f64)
        .sum();
    let c = uncertainty::covariances(
        normal,
        jp.parts.iter().map(|m| m.rows_used()).sum(),
        n_blocks,
    );
    if c.singular {
        // The joint vector starts with the shared parameters; undetermined ones among them
        // the analysis holds ([`super::model::hold_undetermined`]).
        let s = jp.shared.len();
        let shared: Vec<Param> = c
            .undetermined
            .iter()
            .filter(|&&i| i < s)
            .map(|&i| jp.shared[i])
            .collect();
        return Err(match shared.is_empty() {
            true => JointError::Joint("the joint information matrix is singular".into()),
            false => JointError::Undetermined(shared),
        });
    }
    let (cov, cov_block) = (&c.cov, &c.block);
    let s = jp.shared.len();
    let se: Vec<f64> = (0..s)
        .map(|i| cov[(i, i)].max(cov_block[(i, i)]).max(0.0).sqrt())
        .collect();
    let covariance = DMatrix::from_fn(s, s, |i, j| {
        let scale = (se[i] * se[j]) / (cov[(i, i)] * cov[(j, j)]).sqrt().max(1e-300);
        cov[(i, j)] * scale
    });
    let estimates: Vec<(Param, Estimate)> = jp
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
    let mu_index = jp
        .shared
        .iter()
        .position(|q| *q == Param::MuKinetic)
        .ok_or_else(|| JointError::Joint("mu_kinetic is not free".into()))?;
    Ok(SharedFit {
        estimates,
        covariance,
        mu_index,
        chi2: c.chi2,
        dof: c.dof,
        reduced_chi2: c.reduced_chi2,
    })
}

/// mu_kinetic's final estimate `mu` (widened by the models and the releases) cut at its
/// bound 0 and put in the shared estimates; mu's row and column of the covariance carry its
/// final standard error, so what a plan takes as known is no more than the report claims.
pub(super) fn carry_mu(shared: &mut SharedFit, mu: Estimate) -> Estimate {
    let mu = within_bounds(Param::MuKinetic, mu, 0.0);
    let mu_i = shared.mu_index;
    shared.estimates[mu_i].1 = mu;
    let cov = &mut shared.covariance;
    let ratio = mu.stderr / cov[(mu_i, mu_i)].max(1e-300).sqrt();
    for j in 0..shared.estimates.len() {
        cov[(mu_i, j)] *= ratio;
        cov[(j, mu_i)] *= ratio;
    }
    mu
}
