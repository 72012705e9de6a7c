//! One analysis of a set of releases: the joint model chosen on them (from their single fits'
//! consensus), the shared parameters' covariance, each release's row and their agreement. The
//! set-aside search ([`super::set_aside`]) runs one per set of releases it tries, so a release
//! is judged against a model chosen without it.

use super::agreement::{consistency, leave_one_out, own_pairs, AGREE_P};
use super::error::JointError;
use super::model::{self, JointModel};
use super::outcome::ReleaseRow;
use super::releases::{release_row, release_rows};
use super::settings::JointSettings;
use super::shared::{self, SharedFit};
use super::singles::{self, set_param, Single};
use crate::fit::select::Candidate;
use crate::fit::solve::solve_loose;
use crate::fit::{Estimate, FitSettings};
use crate::model::Rig;

/// What an analysis needs besides its releases: the rig guessed and the settings.
pub(super) struct Context<'a> {
    /// The rig file's rig.
    pub(super) rig_guess: &'a Rig<f64>,
    /// The fit's settings.
    pub(super) settings: &'a FitSettings,
    /// The joint settings.
    pub(super) joint: &'a JointSettings,
}

/// A set of releases fitted jointly with the model chosen on them.
pub(super) struct Analysis {
    /// The releases in it (indices into the single fits).
    pub(super) sel: Vec<usize>,
    /// The model chosen on them, at its optimum.
    pub(super) model: JointModel,
    /// Its shared parameters' estimates and covariance.
    pub(super) shared: SharedFit,
    /// Each release's row, in the order of `sel`, z its leave-one-out z.
    pub(super) rows: Vec<ReleaseRow>,
    /// p-value of the releases' own mu agreeing.
    pub(super) consistency_p: Option<f64>,
}

impl Analysis {
    /// Whether the releases' own mu agree (p at least [`AGREE_P`], or too few to test).
    pub(super) fn agree(&self) -> bool {
        self.consistency_p.is_none_or(|p| p >= AGREE_P)
    }

    /// mu_kinetic of the releases together (the Jacobian's or the block covariance's
    /// standard error, before any widening).
    pub(super) fn mu(&self) -> Estimate {
        self.shared.estimates[self.shared.mu_index].1
    }
}

/// The releases `sel` of `kept` analysed: the model chosen on them (with `select`; else the
/// single fits' consensus model, a quick look), its covariance, each release's row with its
/// own mu and leave-one-out z, and their agreement.
pub(super) fn analyse(
    kept: &[Single],
    sel: &[usize],
    ctx: &Context,
    select: bool,
) -> Result<Analysis, JointError> {
    let sub: Vec<&Single> = sel.iter().map(|&i| &kept[i]).collect();
    let start = singles::start(&sub, ctx.rig_guess, ctx.settings, ctx.joint);
    let mut model = model::fit_model(start, &sub, ctx.settings, select)?;
    let shared = match shared::shared_fit(&model.problem, &model.p, &sub) {
        // A shared parameter the releases together leave undetermined is held, once.
        Err(JointError::Undetermined(params)) => {
            model = model::hold_undetermined(model, &params)?;
            shared::shared_fit(&model.problem, &model.p, &sub)?
        }
        r => r?,
    };
    let mut rows = release_rows(&model.problem, &sub, ctx.settings);
    let pairs = own_pairs(&rows);
    let consistency_p = consistency(&pairs);
    for (r, z) in rows.iter_mut().zip(leave_one_out(&pairs)) {
        r.z = z;
    }
    Ok(Analysis {
        sel: sel.to_vec(),
        model,
        shared,
        rows,
        consistency_p,
    })
}

/// Release `i` of `kept` (not in `a`) judged by `a`: its problem under `a`'s model with the
/// shared values held at `a`'s, its own parameters fitted, then its own mu (mu free too); z
/// against `a`'s mu. Its row, marked as not agreeing when it lies off `a` by either of two
/// tests that must survive `a`'s own uncertainty:
/// - its mu: more than 3 standard errors off `a`'s both under `a`'s shared values (z) and by
///   its single fit (its own nuisances: a rest whose tilt is poorly known biases the first
///   alone);
/// - its fit: `a`'s model fits it far worse than any release in `a` (a chi-square per
///   residual over twice their largest and over 2), when `a` knows mu better than the
///   release alone does (a release on another tilt keeps its own mu and misfits; a rest of a
///   few weak releases misfits a strong one by its own error).
pub(super) fn score(kept: &[Single], i: usize, a: &Analysis, ctx: &Context) -> ReleaseRow {
    let (release, rep) = &kept[i];
    let mu = a.mu();
    let jp = &a.model.problem;
    let mut part = singles::start_part(&rep.problem, ctx.rig_guess, mu.value, ctx.settings);
    for &nu in &a.model.nuisances {
        part = part.with_nuisance(nu, mu.value * 1.1);
    }
    for &q in &jp.shared {
        set_param(&mut part, q, jp.parts[0].get(q));
    }
    // Its own parameters fitted under the shared values (mu held): the residuals the row
    // reports are the release's under the others' model.
    let mut own = part.clone();
    own.free.retain(|q| !jp.shared.contains(q));
    if let Ok((p, _, _)) = solve_loose(&own, own.values(), ctx.settings.max_iters, None) {
        own.set_values(&p);
        part.initial = own.initial;
        part.camera = own.camera;
    }
    let mut row = release_row(&part, release, rep, &jp.shared, ctx.settings);
    row.z = row
        .own_mu
        .map_or(0.0, |e| (e.value - mu.value) / e.stderr.hypot(mu.stderr));
    let worst_in = a
        .rows
        .iter()
        .map(ReleaseRow::chi2_per_residual)
        .fold(0.0, f64::max);
    let single = rep.mu_kinetic;
    let z_single = single.map_or(0.0, |e| (e.value - mu.value) / e.stderr.hypot(mu.stderr));
    let off_by_mu = row.z.abs() > 3.0 && z_single.abs() > 3.0;
    let known_better = single.is_some_and(|e| mu.stderr < e.stderr);
    let off_by_fit = known_better && row.chi2_per_residual() > (2.0 * worst_in).max(2.0);
    row.agrees = !(off_by_mu || off_by_fit);
    row
}
