//! One rig, many releases: the releases fitted together. The rail and the pendulum are the
//! same in every release, so the friction law, the tilt, the viscous terms and the pendulum's
//! build are shared; each release keeps its initial state and marker lag, and its camera
//! unless the camera is the same. The releases' problems are the single fit's
//! ([`TrajectoryProblem`]); the joint problem sums their normal equations into the shared and
//! per-release blocks, so its cost grows linearly with the releases, and its nuisances are
//! chosen by the single fit's selection ([`select::forward`] over [`Candidate`]).
//!
//! The folder's files, in the order [`fit_joint`] runs them: `rigs.rs` releases of another
//! rig; `singles.rs` the single fits and the joint start (their consensus nuisances);
//! `problem.rs` the joint problem; `analysis.rs` one set of releases analysed: `model.rs` the
//! joint model (its fit, nuisances and polish), `shared.rs` the shared parameters'
//! covariance, `releases.rs` each release under the joint model, `agreement.rs` the
//! releases' own mu and their agreement; `set_aside.rs` the releases that disagree, each
//! judged by a model chosen without it; this file the joint fit's settings, report and
//! driver.

mod agreement;
mod analysis;
mod error;
mod model;
mod outcome;
mod problem;
mod releases;
mod rigs;
mod set_aside;
mod settings;
mod shared;
mod singles;

pub use error::JointError;
pub use outcome::{JointReport, ReleaseRow};
pub use problem::JointProblem;
pub use rigs::other_rigs;
pub use settings::{JointSettings, Release};

use super::estimate::{Estimate, RigValue};
use super::intervals::model_uncertainty;
use super::problem::Param;
use super::select;
use super::settings::FitSettings;
use crate::model::Rig;
use nalgebra::DMatrix;

/// Fit the releases jointly: each alone first (its start, noise, outliers, own mu and
/// nuisances), then all together from the single fits' consensus, the nuisances chosen by the
/// data and the releases' agreement tested. Releases that disagree are set aside only when a
/// model chosen without them still finds them off ([`set_aside`]); the result is then the
/// other releases', the ones set aside listed apart.
pub fn fit_joint(
    releases: &[Release],
    rig_guess: &Rig<f64>,
    settings: &FitSettings,
    joint: &JointSettings,
) -> Result<JointReport, JointError> {
    singles::check_releases(releases)?;
    let singles::Singles {
        kept,
        left_out,
        mut warnings,
    } = singles::fit_singles(releases, rig_guess, settings, joint)?;
    warnings.extend(settings.measured.iter().flat_map(|m| m.notes.clone()));
    let ctx = analysis::Context {
        rig_guess,
        settings,
        joint,
    };
    let set_aside::Outcome {
        analysis: found,
        aside,
        unresolved,
        all_p: consistency_p_all,
    } = set_aside::set_aside(&kept, &ctx)?;
    let analysis::Analysis {
        model,
        mut shared,
        rows,
        consistency_p,
        sel,
    } = found;
    for &(q, value) in &model.held {
        warnings.push(crate::fit::stages::held_warning(
            q,
            value,
            "these releases together (nothing the markers show depends on it at its fitted value)",
        ));
    }
    let mut mu = shared.estimates[shared.mu_index].1;
    model_uncertainty(
        &mut mu,
        &model.models,
        shared.reduced_chi2.max(1.0),
        &mut warnings,
    );
    if unresolved {
        let spread = agreement::spread(&rows, mu.value);
        super::intervals::widen(&mut mu, spread, "releases");
    }
    if select::misfits(&model.problem, shared.chi2) {
        warnings.push(format!(
            "the joint model misfits the releases (reduced chi-square {:.2}): the interval is the Jacobian's scaled by it",
            shared.reduced_chi2
        ));
    }
    let mu = shared::carry_mu(&mut shared, mu);
    let single_se: Vec<f64> = sel
        .iter()
        .filter_map(|&i| kept[i].1.mu_kinetic.map(|e| e.stderr))
        .collect();
    // Warned of whether or not the result fails for another reason.
    let off_rig = off_the_rig_file(&shared.estimates, &model.problem.parts, &mut warnings);
    let failed = failure(&mu, single_se).or(off_rig.filter(|_| !aside.is_empty()));
    // The shared parameters' correlation from their covariance, for the law's section.
    let k = shared.estimates.len();
    let correlation = DMatrix::from_fn(k, k, |i, j| {
        let d = (shared.covariance[(i, i)] * shared.covariance[(j, j)]).sqrt();
        if d > 0.0 {
            shared.covariance[(i, j)] / d
        } else {
            f64::from(u8::from(i == j))
        }
    });
    let friction = crate::fit::law::friction_law(&crate::fit::law::LawInputs {
        params: &shared.estimates,
        correlation: &correlation,
        models: &model.models,
        chosen: &model.nuisances,
        screening: &[],
        n_rows: 0,
        forced: settings.friction.is_some(),
    });
    // A shared value (a tilt) is the same in every release: each sentence once.
    let mut implausible: Vec<String> = Vec::new();
    for part in &model.problem.parts {
        for sentence in crate::fit::implausible::implausible(part) {
            if !implausible.contains(&sentence) {
                implausible.push(sentence);
            }
        }
    }
    for sentence in &implausible {
        warnings.push(format!(
            "the joint model needs what no real rig has, so the result is limited by the model: {sentence}"
        ));
    }
    if let Some(why) = &failed {
        warnings.insert(0, format!("the joint fit failed: {why}"));
    }
    Ok(JointReport {
        rig_keys: settings
            .measured
            .as_ref()
            .map_or_else(Vec::new, |m| m.keys.clone()),
        implausible,
        parts: model.problem.parts.clone(),
        friction,
        mu_kinetic: mu,
        failed,
        shared: shared.estimates,
        shared_covariance: shared.covariance,
        releases: rows,
        disagreeing: aside.iter().map(|r| r.name.clone()).collect(),
        set_aside: aside,
        left_out,
        consistency_p,
        consistency_p_all,
        nuisances: model.nuisances,
        models: model.models,
        chi2: shared.chi2,
        dof: shared.dof,
        reduced_chi2: shared.reduced_chi2,
        n_params: model.p.len(),
        unresolved,
        warnings,
        iterations: model.iterations,
    })
}

/// How many of the rig file's deviations a shared rod length or mass ratio may lie from the
/// file's value before a joint result that set releases aside fails: the kept releases are
/// then of another rig than the file describes, and those set aside may be the file's.
const OFF_RIG_FILE: f64 = 5.0;

/// The rig file as a measurement against the releases kept: each shared rod length or mass
/// ratio beyond 3 of the file's deviations gets a warning (as a single fit's does), and the
/// worst beyond [`OFF_RIG_FILE`] is returned as the reason the result fails when releases
/// were set aside (half a campaign from another rig kept the other rig's releases and set
/// the file's aside: its mass ratio 0.349 against the file's 1.87 +- 0.064, exit 0).
fn off_the_rig_file(
    shared: &[(Param, Estimate)],
    parts: &[super::problem::TrajectoryProblem],
    warnings: &mut Vec<String>,
) -> Option<String> {
    let values = RigValue::of(shared, |q| parts.iter().find_map(|p| p.prior_on(q)));
    for r in values.iter().filter(|r| r.off()) {
        warnings.push(format!(
            "{}: check the rig file (the fit used the releases' value)",
            r.said("the releases kept put")
        ));
    }
    values
        .iter()
        .filter(|r| r.z.abs() > OFF_RIG_FILE)
        .max_by(|a, b| a.z.abs().total_cmp(&b.z.abs()))
        .map(|r| {
            format!(
                "{}: they are not of the rig the rig file describes, and the releases set aside may be",
                r.said("the releases kept put")
            )
        })
}

/// Why the joint result `mu` is no measurement, if it is none: its standard error above the
/// median of the releases' own single fits' (`single`: the releases together know less than
/// one alone, so the model trades mu against a nuisance), or mu at its bound 0.
fn failure(mu: &Estimate, mut single: Vec<f64>) -> Option<String> {
    single.sort_by(f64::total_cmp);
    let median = single.get(single.len() / 2).copied();
    if !mu.stderr.is_finite() || !mu.value.is_finite() {
        return Some("mu_kinetic's standard error is not finite".into());
    }
    if mu.value <= 0.0 {
        return Some(format!(
            "mu_kinetic is at its bound 0 (+- {:.1e}): the model traded friction against a nuisance",
            mu.stderr
        ));
    }
    match median {
        Some(m) if mu.stderr > m => Some(format!(
            "mu_kinetic's standard error {:.1e} is above a single release's ({m:.1e}, the median): the releases together pin mu down less than one alone, so the joint model trades it against a nuisance",
            mu.stderr
        )),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::failure;
    use crate::fit::Estimate;

    fn est(value: f64, stderr: f64) -> Estimate {
        Estimate::wald(value, stderr)
    }

    /// The rules of a failed joint result: wider than the median single release, at the
    /// bound 0, or not finite; a joint interval narrower than the releases' is a value.
    #[test]
    fn a_result_no_narrower_than_one_release_or_at_zero_fails() {
        let singles = vec![1e-3, 2e-3, 4e-3];
        assert!(failure(&est(0.25, 5e-4), singles.clone()).is_none());
        let wide = failure(&est(0.127, 7.1), singles.clone()).unwrap();
        assert!(wide.contains("above a single release"), "{wide}");
        let zero = failure(&est(0.0, 4e-4), singles.clone()).unwrap();
        assert!(zero.contains("bound 0"), "{zero}");
        assert!(failure(&est(f64::NAN, 1e-3), singles).is_some());
    }
}
