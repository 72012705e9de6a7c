//! The stages of [`super::fit`] after the data are prepared (`prepare.rs`), each a function
//! over the model being fitted ([`Fitting`]): the motion seen, the nuisances chosen, the late
//! outliers, a recording that never slides, mu_static at its bound, the polish, the
//! estimates, the adequacy and its widenings, mu_static's result and the report. Each stage says what it reads and returns;
//! the driver only orders them.

use super::adequacy::{self, failed_part, is_noise_free, LimitPart, WINDOWS_P};
use super::base::Base;
use super::error::FitError;
use super::estimate::{Estimate, MuParts, RigValue};
use super::intervals::{model_uncertainty, pinned_friction, widen, within_bounds};
use super::law;
use super::motion::{motion, slider_moves, Motion};
use super::outcome::{Adequacy, FitReport, StaticResult, Work};
use super::outliers::{residual_outliers, ResidualOutliers, RESIDUAL_OUTLIER};
use super::pendulum::pendulum_found;
use super::prepare::Prepared;
use super::problem::{idx, Observations, Param, TrajectoryProblem, MAX_FREE};
use super::select::{self, ModelRow, Nuisance, SelectOptions};
use super::settings::{FitSettings, StaticMode};
use super::solve::{solve, solve_traced};
use super::uncertainty::{self, Assessment, WindowCut, WindowFit};
use crate::model::{FrictionLaw, Rig};
use crate::sim::EventKind;
use nalgebra::{DMatrix, DVector};
use std::sync::atomic::Ordering;
use std::sync::Arc;

/// The model being fitted and what the fit has spent and noted, passed from stage to stage.
pub(super) struct Fitting {
    pub problem: TrajectoryProblem,
    pub p: DVector<f64>,
    pub iterations: u64,
    pub warnings: Vec<String>,
    /// The model changed after the base fit's last solve over the whole recording.
    pub moved: bool,
}

/// What the base fit's motion shows.
pub(super) struct Seen {
    pub motion: Motion,
    /// The fitted motion slides by more than the slider's noise.
    pub slides: bool,
    /// The raw slider track's range when it moves by more than its noise explains.
    pub raw_moves: Option<f64>,
}

/// The rig file as a measurement and the nuisances' plausible ranges ([`super::priors`]):
/// every nuisance gets its range's prior, and with a measured rig the rod length and the mass
/// ratio are freed with the measurement's priors and the base model refitted (the data
/// correct what they can; mu's interval carries the rest). `--fit-rod-length` frees the rod
/// without a prior. The base fit has freed them already (a short recording's candidates from
/// their first solve, a long one's doubling stages), so the refit is only a safety net for a
/// base model that came without them.
pub(super) fn measured_rig(f: &mut Fitting, frame: f64, settings: &FitSettings) {
    let freed = super::rig_priors::apply_measured(&mut f.problem, frame, settings);
    f.p = f.problem.values();
    if freed {
        if let Ok((q, _, it)) = solve(&f.problem, f.p.clone(), settings.max_iters) {
            f.iterations += it;
            f.problem.set_values(&q);
            f.p = q;
        }
        f.moved = true;
    }
}

/// Does the fitted motion slide? A slide shorter than the slider's noise is not seen;
/// a raw track that clearly moves while no fit slides is a failed fit, said as such.
pub(super) fn seen(f: &Fitting, obs: &Observations) -> Result<Seen, FitError> {
    let motion = motion(&f.problem)?;
    let (lo, hi) = motion.range;
    let slides = motion.slides && hi - lo > 3.0 * f.problem.sigma[0];
    Ok(Seen {
        raw_moves: slider_moves(obs, f.problem.sigma[0]),
        motion,
        slides,
    })
}

/// The nuisances the data ask for (forward selection). Returns the models compared, the
/// nuisances chosen and the score test at the chosen model.
pub(super) fn nuisances(
    f: &mut Fitting,
    seen: &Seen,
    base: &Base,
    n_frames: usize,
    settings: &FitSettings,
) -> (Vec<ModelRow>, Vec<Nuisance>, Vec<(Nuisance, f64)>) {
    if !seen.slides || (!settings.nuisances && settings.forced().is_empty()) {
        return (Vec::new(), Vec::new(), Vec::new());
    }
    let chi2 = f.problem.chi2(&f.p).unwrap_or(f64::INFINITY);
    let mu_k = f.p[0];
    let opts = SelectOptions {
        // The friction laws: offered in every round whose model misfits, and in every round
        // when the onsets show mu_static above mu_kinetic. No gate on the data keeps them
        // out: a release from rest whose base model slips at once shows no onset, yet its
        // static coefficient is the misfit (a threshold has no gradient at its start, so no
        // score test can ask for it either).
        friction_candidates: settings.mu_static == StaticMode::Auto,
        static_evidence: base.static_evidence == Some(true),
        mu_static_start: base.mu_s_data.unwrap_or(1.15 * mu_k).max(1.05 * mu_k),
        // No cap decides the answer: the criterion stops the selection (every candidate is
        // screened each round, and at most two plus the friction laws are fitted).
        max_added: if settings.nuisances {
            Nuisance::ALL.len()
        } else {
            0
        },
        max_iters: settings.max_iters,
        first_iters: settings.first_iters,
        already: if f.problem.free.contains(&Param::MuStatic) {
            vec![Nuisance::StaticFriction]
        } else {
            Vec::new()
        },
        // A fresh start over a long recording would meet events it cannot match yet (the
        // base fit reaches such recordings through their first frames).
        fresh_start: (n_frames <= settings.long_prefix.saturating_mul(2))
            .then_some((base.y0_guess, base.mu0)),
        forced: settings.forced(),
        excluded: settings.excluded(),
    };
    let sel = select::forward(f.problem.clone(), f.p.clone(), chi2, &opts);
    f.iterations += sel.iterations;
    f.problem = sel.problem;
    f.p = sel.p;
    f.moved |= !sel.chosen.is_empty();
    (sel.rows, sel.chosen, sel.screening)
}

/// The residual outliers a misfitting base model left for the chosen one
/// ([`residual_outliers`]), and the report's note on every position left out or down-weighted.
/// Returns the positions left out in all (slider, bob) and what this step did.
pub(super) fn late_outliers(
    f: &mut Fitting,
    mut late: ResidualOutliers,
    from_tracks: [usize; 2],
    settings: &FitSettings,
) -> ([usize; 2], ResidualOutliers) {
    if late.deferred {
        late = residual_outliers(&mut f.problem, &mut f.p, settings, &mut f.iterations, true);
        f.moved |= late != ResidualOutliers::default();
    }
    let out = [0, 1].map(|m| from_tracks[m] + late.dropped[m]);
    if out.iter().sum::<usize>() > 0 {
        f.warnings.push(format!(
            "{} slider and {} bob positions were mis-tracked (beyond {} noise deviations) and left out",
            out[0], out[1], RESIDUAL_OUTLIER
        ));
    }
    if late.weighted.iter().sum::<usize>() > 0 {
        f.warnings.push(format!(
            "{} slider and {} bob positions lie beyond {} deviations of the fit, but the model does not describe the rest of the recording either: they were down-weighted (Huber), not left out",
            late.weighted[0], late.weighted[1], RESIDUAL_OUTLIER
        ));
    }
    (out, late)
}

/// For a recording whose fit never slides: said as such (or as a failed fit when the
/// raw track moves), and the stuck pendulum fitted with mu where it never slips (0.999 mu*, no
/// paradox either).
pub(super) fn hold_stuck(f: &mut Fitting, raw_moves: Option<f64>, settings: &FitSettings) {
    if let Some(range) = raw_moves {
        f.warnings.push(format!(
            "the slider moves by {range:.4} m in the recording but no fit reproduces a slide: the fit failed; try --starts with other mu values"
        ));
    } else {
        f.warnings.push("the slider never slides in the recording: mu_kinetic is not identifiable from it; mu_static is only bounded from below".into());
    }
    let problem = &mut f.problem;
    let mu_hold = 0.999 * crate::model::regions::mu_critical(problem.rig.mass_ratio());
    problem.rig.mu_kinetic = mu_hold;
    problem.rig.mu_static = mu_hold;
    problem.initial[2] = 0.0;
    problem.free = vec![Param::X, Param::Theta, Param::ThetaDot];
    if let Ok((q, _, it)) = solve(problem, problem.values(), settings.max_iters) {
        f.iterations += it;
        f.p = q;
        problem.set_values(&f.p);
    } else {
        f.p = problem.values();
    }
    f.moved = true;
}

/// How mu_static stands after the selection.
#[derive(Clone, Copy, Default)]
pub(super) struct StaticState {
    /// It was free and fitted at its bound mu_static = mu_kinetic: it now says only "up to".
    pub at_bound: bool,
    /// It is free above mu_kinetic.
    pub free: bool,
}

/// A free mu_static at its bound mu_static = mu_kinetic is tied again.
pub(super) fn static_bound(f: &mut Fitting, slides: bool) -> StaticState {
    let mut s = StaticState::default();
    if !slides {
        return s;
    }
    if let Some(i) = idx(&f.problem, Param::MuStatic) {
        if f.p[i] - f.p[0] <= 1e-6 * f.p[0].max(1e-9) {
            f.problem.free.remove(i);
            f.problem.tie_static = true;
            f.p = f.problem.values();
            s.at_bound = true;
            f.moved = true;
        } else {
            s.free = true;
        }
    }
    s
}

/// The final polish, unless a long recording's whole fit already converged on this
/// very model and weights (each pass over a million frames costs a third of a second).
/// Returns why the solver stopped.
pub(super) fn polish(f: &mut Fitting, settled: Option<String>, settings: &FitSettings) -> String {
    let polished = match settled.filter(|_| !f.moved) {
        Some(reason) => Ok((f.p.clone(), 0.0, 0, reason)),
        None => solve_traced(&f.problem, f.p.clone(), settings.max_iters),
    };
    match polished {
        Ok((q, _, it, reason)) => {
            f.iterations += it;
            f.problem.set_values(&q);
            f.p = q;
            if super::solve::at_iteration_limit(&reason) {
                // Never silent: a value the solver was still moving is no estimate.
                f.warnings.push(format!(
                    "the final solve stopped at its iteration limit ({it} iterations) before converging: the values and intervals are not those of a minimum (the model may have more freedom than the recording pins down: try --friction coulomb, or fewer --with nuisances)"
                ));
            }
            reason
        }
        Err(e) => format!("final polish failed: {e}"),
    }
}

/// Every free parameter's estimate with the covariances behind them.
pub(super) struct Estimates {
    pub a: Assessment,
    pub params: Vec<(Param, Estimate)>,
    /// Standard errors: the larger of the plain and the block ones.
    pub se: Vec<f64>,
    pub correlation: DMatrix<f64>,
    /// max(1, reduced chi-square): the profiles' scale.
    pub scale: f64,
    /// mu_kinetic's index when it is identifiable.
    pub mu_index: Option<usize>,
    /// The share of mu_kinetic's variance that the rig's measured values carry (their priors'
    /// width and correlation with mu): 1 - var(mu | rig values held) / var(mu).
    pub rig_fraction: f64,
}

/// The warning for a parameter `q` held at `value` because `by` (the recording, or the
/// releases together) does not determine it; a single fit and a joint fit say it alike.
pub(crate) fn held_warning(q: Param, value: f64, by: &str) -> String {
    let unit = match q.unit() {
        "" => String::new(),
        u => format!(" {u}"),
    };
    format!(
        "{} is not determined by {by}: held at {}{unit}, not fitted; a release that shows it would pin it",
        q.name(),
        crate::data::inspect::sig(value, 4),
    )
}

/// Standard errors (Jacobian, block covariance) and Wald intervals; mu_kinetic's profile
/// interval comes after ([`mu_profile`]).
///
/// A parameter the data do not determine (nothing depends on it: a forced law's speed with no
/// static excess to shape) has no standard error; the pseudo-inverse's 0 would print it as
/// exact. It is held at its value, not fitted, with a warning saying so, and the rest assessed
/// again (mu_kinetic is never held: left undetermined, its interval is unbounded).
pub(super) fn estimates(
    f: &mut Fitting,
    noise_dof: f64,
    identifiable: bool,
) -> Result<Estimates, FitError> {
    let mut a = uncertainty::assess(&f.problem, &f.p, noise_dof).map_err(FitError::NoStart)?;
    let held: Vec<Param> = a
        .undetermined
        .iter()
        .map(|&i| f.problem.free[i])
        .filter(|&q| q != Param::MuKinetic)
        .collect();
    if !held.is_empty() {
        for &q in &held {
            f.warnings.push(held_warning(
                q,
                f.problem.get(q),
                "this recording (nothing the markers show depends on it)",
            ));
        }
        f.problem.free.retain(|q| !held.contains(q));
        f.p = f.problem.values();
        a = uncertainty::assess(&f.problem, &f.p, noise_dof).map_err(FitError::NoStart)?;
    }
    let (problem, p) = (&f.problem, &f.p);
    let k = p.len();
    let scale = a.reduced_chi2.max(1.0);
    let unbounded = |i: usize| a.undetermined.contains(&i);
    let se: Vec<f64> = (0..k)
        .map(|i| {
            if unbounded(i) {
                f64::INFINITY
            } else {
                a.se[i].max(a.se_block[i])
            }
        })
        .collect();
    let correlation =
        DMatrix::from_fn(k, k, |i, j| a.cov[(i, j)] / (a.se[i] * a.se[j]).max(1e-300));
    let params: Vec<(Param, Estimate)> = problem
        .free
        .iter()
        .enumerate()
        .map(|(i, &q)| {
            let widened = se[i] > a.se[i] * 1.0001;
            (
                q,
                Estimate {
                    value: p[i],
                    stderr: se[i],
                    ci95: [p[i] - 1.96 * se[i], p[i] + 1.96 * se[i]],
                    interval: if widened { "wald+block" } else { "wald" },
                },
            )
        })
        .collect();
    let mu_index = idx(problem, Param::MuKinetic).filter(|_| identifiable);
    let rig_fraction = mu_index.map_or(0.0, |i| rig_fraction(problem, &a.cov, i));
    Ok(Estimates {
        a,
        params,
        se,
        correlation,
        scale,
        mu_index,
        rig_fraction,
    })
}

/// mu_kinetic's profile interval at the fit ([`estimates`]' covariances), when asked for: `None`
/// when it is not computed. A model that misfits bends the profile by its misfit, not by the
/// data's information: there the interval stays +- 1.96 stderr (the errors scaled by the
/// reduced chi-square and the block covariance), which the adequacy stage widens further; the
/// profile's fits, a second or more on a misfitting recording, are not run. It only reads the
/// fit, so it runs beside the windows and mu_static's profile ([`mu_profile_taken`] applies it).
pub(super) fn mu_profile(
    f: &Fitting,
    est: &Estimates,
    settings: &FitSettings,
) -> Option<Option<[f64; 2]>> {
    let (problem, p, a) = (&f.problem, &f.p, &est.a);
    let i = est.mu_index?;
    if !settings.profile || select::misfits(problem, a.chi2) {
        return None;
    }
    Some(uncertainty::profile_interval(
        problem,
        p,
        i,
        a.se[i],
        est.scale,
        settings,
        0.0,
        Some((&a.cov, a.chi2)),
    ))
}

/// mu_kinetic's interval from its profile ([`mu_profile`]), when computed.
pub(super) fn mu_profile_taken(
    f: &mut Fitting,
    est: &mut Estimates,
    profile: Option<Option<[f64; 2]>>,
) {
    let (Some(profile), Some(i)) = (profile, est.mu_index) else {
        return;
    };
    match profile {
        Some(ci) => {
            // The profile knows the curvature, the block covariance the correlated
            // residuals: widen the profile's half-widths by the block's excess.
            let ratio = (est.se[i] / est.a.se[i]).max(1.0);
            let v = f.p[i];
            let e = &mut est.params[i].1;
            e.ci95 = [v - (v - ci[0]) * ratio, v + (ci[1] - v) * ratio];
            e.interval = if ratio > 1.0001 {
                "profile+block"
            } else {
                "profile"
            };
        }
        None => f.warnings.push(
            "the profile interval for mu_kinetic did not close; the interval shown is value +- 1.96 stderr"
                .into(),
        ),
    }
}

/// The share of parameter `i`'s variance carried by the rig's measured values (the free
/// parameters with a measurement's prior: rod length, mass ratio): 1 - the variance with them
/// held over the variance with them free, from the covariance `cov` (the Schur complement).
fn rig_fraction(problem: &TrajectoryProblem, cov: &DMatrix<f64>, i: usize) -> f64 {
    let rig: Vec<usize> = problem
        .free
        .iter()
        .enumerate()
        .filter(|(_, q)| q.is_measured())
        .filter(|(_, q)| problem.prior_on(**q).is_some())
        .map(|(j, _)| j)
        .collect();
    let total = cov[(i, i)];
    if rig.is_empty() || total.is_nan() || total <= 0.0 {
        return 0.0;
    }
    let s = DMatrix::from_fn(rig.len(), rig.len(), |a, b| cov[(rig[a], rig[b])]);
    let c = DVector::from_fn(rig.len(), |a, _| cov[(i, rig[a])]);
    let Some(inv) = s.try_inverse() else {
        return 0.0;
    };
    let held = total - (c.transpose() * inv * &c)[(0, 0)];
    (1.0 - held / total).clamp(0.0, 1.0)
}

/// What the adequacy stage found.
pub(super) struct Verdict {
    pub windows: Vec<WindowFit>,
    /// How the windows were cut (`None` when none were fitted).
    pub window_cut: Option<uncertainty::WindowCut>,
    pub windows_p: Option<f64>,
    pub runs_p: f64,
    pub block_ratio: f64,
    pub lag1: f64,
    /// The one plain sentence when the model limits the result.
    pub limited: Vec<LimitPart>,
    /// The chosen model's values no real rig has, a sentence each ([`crate::fit::implausible::implausible`]).
    pub implausible: Vec<String>,
    /// Why the fit failed although it ran.
    pub failed: Option<String>,
    pub noise_free: bool,
    pub rms_per_marker_m: [f64; 2],
    pub rms_residual_m: f64,
}

/// mu_kinetic fitted in each window of the recording (cut by the motion), when asked for and
/// mu_kinetic is identifiable; reads the fit only ([`adequacy`] judges them).
pub(super) fn windows(
    problem: &TrajectoryProblem,
    mu_index: Option<usize>,
    events: &[crate::sim::Event],
    settings: &FitSettings,
) -> (Vec<WindowFit>, Option<WindowCut>) {
    if !(settings.windows && mu_index.is_some()) {
        return (Vec::new(), None);
    }
    let (bounds, cut) = uncertainty::motion_bounds(&problem.observations().times, events);
    let windows = uncertainty::windows(problem, &bounds, settings);
    let cut = (!windows.is_empty()).then_some(cut);
    (windows, cut)
}

/// Adequacy. mu_kinetic on each window cut by the motion (a slide each), the runs
/// test, the chi-square and the block ratio; when any fails, mu's interval widens by the
/// windows' spread and by mu's shift along the selection's path, and by the spread of close
/// models in any case; then the physical bounds, the one plain sentence, a failed fit, and a
/// noise-free recording recognised.
pub(super) fn adequacy(
    f: &mut Fitting,
    est: &mut Estimates,
    models: &[ModelRow],
    (windows, window_cut): (Vec<WindowFit>, Option<WindowCut>),
    settings: &FitSettings,
) -> Verdict {
    let (problem, a) = (&f.problem, &est.a);
    let mu_index = est.mu_index;
    let windows_p = uncertainty::window_consistency(&windows);
    let block_ratio = mu_index.map_or(1.0, |i| a.se_block[i] / a.se[i]);
    let runs_p = a.residuals.runs_p;
    // A value no real rig has is evidence that the model explains the recording with
    // something the rig does not have: it flags the fit (below). It does not widen the
    // interval: a real rig can have it (a worn pivot), and then the model is right.
    let implausible = super::implausible::implausible(problem);
    // The selection stopped for want of room (every free parameter the dual numbers allow
    // taken) while its model still misfits by the selection's own rule: what is left of the
    // misfit was never given a chance to be explained.
    let capped = problem.free.len() >= MAX_FREE && select::misfits(problem, a.chi2);
    if let Some(i) = mu_index {
        let e = &mut est.params[i].1;
        // Slides that disagree beyond the family's rate scale mu's standard error by their
        // scale factor S = sqrt(chi2 / (windows - 1)), as particle-data tables scale an error
        // for inconsistent measurements: in proportion to the disagreement seen.
        if windows_p.is_some_and(|p| p < WINDOWS_P) {
            let s = uncertainty::window_scale_factor(&windows);
            widen(e, e.stderr * (s * s - 1.0).max(0.0).sqrt(), "windows");
        }
        // Models close in the criterion that give another mu_kinetic: their spread joins the
        // interval (model uncertainty), and the report names them.
        model_uncertainty(e, models, est.scale, &mut f.warnings);
        // A model shown to lack an effect (chi-square beyond the family's share, every free
        // parameter taken, or a value no real rig has with a test failed) is one more
        // nuisance away from another
        // mu: the interval keeps room for as much as mu moved along the selection's path. Not
        // for the runs or the slides alone, which a clean recording fails at their share of
        // the family's rate: there the slides' scale factor above is in proportion. Without
        // it, flagged fits of recordings with four effects at once lay 9-14 standard errors
        // off (tests/data/misspec/four_*).
        let failed = !adequacy::failed_tests(a.p_value, runs_p, windows_p).is_empty();
        let shown = a.p_value < adequacy::CHI2_P || capped || (failed && !implausible.is_empty());
        if shown {
            let shift = models
                .iter()
                .filter(|m| m.path && m.mu_kinetic.is_finite())
                .map(|m| (m.mu_kinetic - e.value).abs())
                .fold(0.0, f64::max);
            widen(e, shift, "path");
        }
    }
    // Physical bounds: no interval reaches below mu_kinetic = 0 or negative damping.
    for (q, e) in est.params.iter_mut() {
        *e = within_bounds(*q, *e, 0.0);
    }
    let mu = mu_index.map(|i| &est.params[i].1);
    // Why the model limits the result, in the order the report says it (each later reason
    // goes first): the failed tests, mu pinned at a bound, every parameter taken, a value no
    // real rig has.
    let mut limited: Vec<LimitPart> = failed_part(a, windows_p, runs_p, mu).into_iter().collect();
    let mu_static = est
        .params
        .iter()
        .find(|(q, _)| *q == Param::MuStatic)
        .map(|(_, e)| e);
    let failed = pinned_friction(problem, mu, mu_static);
    if let Some(why) = &failed {
        limited.insert(0, LimitPart::Said(why.clone()));
    }
    let (rms_per_marker_m, rms_residual_m) = (a.residuals.rms_per_marker_m, a.residuals.rms_m);
    let noise_free = is_noise_free(
        problem.sigma,
        rms_residual_m,
        problem.rig.marker_length,
        settings.options.rtol,
        a.reduced_chi2,
    );
    if noise_free && failed.is_none() {
        limited.clear();
        if let Some(e) = mu {
            f.warnings.push(format!(
                "the recording is noise-free to the model's numerical accuracy (noise measured from the tracks {:.1e} m, residual RMS {:.1e} m): mu_kinetic is recovered as {:.10}, and its standard error and interval are not meaningful",
                problem.sigma[0].max(problem.sigma[1]),
                rms_residual_m,
                e.value
            ));
        }
    }
    if capped {
        let s = format!(
            "The result is limited by the model: it took every free parameter the fit allows ({MAX_FREE}) and still misfits (chi-square {:.0} for {:.0} degrees of freedom, beyond 5 standard deviations of its distribution), so an effect it lacks may be in mu_kinetic.",
            a.chi2, a.dof
        );
        limited.insert(0, LimitPart::Said(s));
    }
    if !implausible.is_empty() {
        let s = format!(
            "The fit needs what no real rig has, so the result is limited by the model, not by the noise: {}; mu_kinetic may carry an effect the model lacks.",
            implausible.join("; ")
        );
        limited.insert(0, LimitPart::Said(s));
    }
    Verdict {
        implausible,
        lag1: a.residuals.lag1,
        windows,
        window_cut,
        windows_p,
        runs_p,
        block_ratio,
        limited,
        failed,
        noise_free,
        rms_per_marker_m,
        rms_residual_m,
    }
}

/// Which of mu_static's cases the fit is in ([`mu_static`]).
pub(super) enum StaticCase {
    /// Free above mu_kinetic, at this index.
    Free(usize),
    /// The slider never slides.
    Stuck,
    /// At its bound mu_static = mu_kinetic, or onsets that show none above it: the upper
    /// limit the data allow.
    AtBound,
    /// Nothing said about it.
    Unknown,
}

/// mu_static's case after the selection, decided once for [`upper_limit`] and [`mu_static`].
pub(super) fn static_case(
    f: &Fitting,
    state: StaticState,
    slides: bool,
    motion: &Motion,
    base: &Base,
) -> StaticCase {
    let slip_after_stick = motion
        .sol
        .events
        .iter()
        .any(|e| e.kind == EventKind::Slip && e.t > 0.0);
    if let Some(i) = idx(&f.problem, Param::MuStatic).filter(|_| state.free) {
        return StaticCase::Free(i);
    }
    if !slides {
        return StaticCase::Stuck;
    }
    if state.at_bound || (slip_after_stick && base.static_evidence == Some(false)) {
        return StaticCase::AtBound;
    }
    StaticCase::Unknown
}

/// mu_static. Free above mu_kinetic: its profile interval, starting no lower than
/// mu_kinetic's. At its bound (or with onsets that show none above mu_kinetic): mu_kinetic and
/// the upper limit the data allow (one-sided profile; `upper`, when computed already by
/// [`upper_limit`]). Stuck throughout: the lower bound the motion needs. Otherwise not
/// identifiable.
pub(super) fn mu_static(
    f: &mut Fitting,
    est: &mut Estimates,
    case: StaticCase,
    motion: &Motion,
    obs: &Observations,
    settings: &FitSettings,
    upper: Option<UpperLimit>,
) -> StaticResult {
    let mu_kinetic = est.mu_index.map(|i| est.params[i].1);
    match case {
        StaticCase::Free(i) => {
            // A mu_static the fitted motion does not feel (no slip after a stick, or one the
            // other parameters take over) has no standard error: that is no measurement.
            let se = est.params[i].1.stderr;
            if !(se.is_finite() && se > 0.0) {
                f.warnings.push(format!(
                    "mu_static ended at {:.5} but the fitted motion does not depend on it (standard error {se:.1e}): it is not measured",
                    est.params[i].1.value
                ));
                return StaticResult::NotIdentifiable;
            }
            // Under a misfit the profile is bent by the misfit (as mu_kinetic's): +- 1.96 stderr.
            if settings.profile && !select::misfits(&f.problem, est.a.chi2) {
                let a = &est.a;
                match uncertainty::profile_interval(
                    &f.problem,
                    &f.p,
                    i,
                    a.se[i],
                    est.scale,
                    settings,
                    f.p[0],
                    Some((&a.cov, a.chi2)),
                ) {
                    Some(ci) => {
                        est.params[i].1.ci95 = ci;
                        est.params[i].1.interval = "profile";
                    }
                    None => f
                        .warnings
                        .push("the profile interval for mu_static did not close".into()),
                }
            }
            // mu_static >= mu_kinetic: its interval starts no lower than mu_kinetic's.
            let mu_k_low = mu_kinetic.map_or(0.0, |e| e.ci95[0]);
            est.params[i].1 = within_bounds(Param::MuStatic, est.params[i].1, mu_k_low);
            StaticResult::Estimated(est.params[i].1)
        }
        StaticCase::Stuck => StaticResult::LowerBound(motion.needed_ratio),
        StaticCase::AtBound => {
            let upper = upper.unwrap_or_else(|| upper_profile(f, est, obs, settings));
            static_upper_limit(f, upper)
        }
        StaticCase::Unknown => {
            if !motion.sticks {
                f.warnings.push(
                    "the slider never sticks: the recording says nothing about mu_static".into(),
                );
            }
            StaticResult::NotIdentifiable
        }
    }
}

/// mu_static's one-sided profile at its bound, or why there is none.
pub(super) enum UpperLimit {
    /// The model misfits: its profile says what the misfit allows, not the data.
    Misfit,
    /// Profiles are off.
    Off,
    /// The upper end (`None`: the profile did not close), the iterations it took and whether
    /// it comes from the recording's first frames.
    Profiled(Option<f64>, u64, bool),
}

/// mu_static's upper limit when the fit is at its bound (`case`), computed apart from the
/// report's stages: it only reads the fit, so it runs beside the windows.
pub(super) fn upper_limit(
    case: &StaticCase,
    f: &Fitting,
    est: &Estimates,
    obs: &Observations,
    settings: &FitSettings,
) -> Option<UpperLimit> {
    matches!(case, StaticCase::AtBound).then(|| upper_profile(f, est, obs, settings))
}

/// The one-sided profile of mu_static above mu_kinetic (on a long recording's first frames,
/// refitted there).
fn upper_profile(
    f: &Fitting,
    est: &Estimates,
    obs: &Observations,
    settings: &FitSettings,
) -> UpperLimit {
    if select::misfits(&f.problem, est.a.chi2) {
        return UpperLimit::Misfit;
    }
    if !settings.profile {
        return UpperLimit::Off;
    }
    let mut iterations = 0;
    let mut free_static = f.problem.clone();
    free_static.free.push(Param::MuStatic);
    free_static.tie_static = false;
    let mut q = free_static.values();
    // A long recording's limit comes from its first frames, refitted there: a limit from
    // fewer frames is looser, never narrower, and the search probes mu_static from afar, a
    // full-length fit each time.
    let prefix_limit = obs.times.len() > settings.long_prefix.saturating_mul(2);
    if prefix_limit {
        free_static = free_static.on(Arc::new(obs.prefix(settings.long_prefix)));
        if let Ok((opt, _, it)) = solve(&free_static, q.clone(), settings.max_iters) {
            iterations += it;
            q = opt;
            free_static.set_values(&q);
        }
    }
    let upper = uncertainty::profile_interval(
        &free_static,
        &q,
        q.len() - 1,
        f64::NAN,
        est.scale,
        settings,
        q[0],
        None,
    )
    .map(|ci| ci[1]);
    UpperLimit::Profiled(upper, iterations, prefix_limit)
}

/// mu_static at its bound mu_static = mu_kinetic: the upper limit the data allow, from the
/// one-sided profile `upper`.
fn static_upper_limit(f: &mut Fitting, upper: UpperLimit) -> StaticResult {
    let mu = f.p[0];
    match upper {
        UpperLimit::Misfit => {
            f.warnings.push(
                "mu_static fits at its bound mu_static = mu_kinetic (no upper limit: the model misfits the recording)"
                    .into(),
            );
            StaticResult::NotIdentifiable
        }
        UpperLimit::Off => {
            f.warnings.push(
                "mu_static fits at its bound mu_static = mu_kinetic (no upper limit computed: profiles are off)"
                    .into(),
            );
            StaticResult::NotIdentifiable
        }
        UpperLimit::Profiled(Some(u), iterations, prefix_limit) => {
            f.iterations += iterations;
            // No warning: Coulomb's law with one coefficient is what the data say, and the
            // report's mu_static row gives the limit.
            StaticResult::Estimated(Estimate {
                value: mu,
                stderr: (u - mu) / 1.96,
                ci95: [mu, u],
                interval: if prefix_limit {
                    "profile (one-sided, on the first frames)"
                } else {
                    "profile (one-sided)"
                },
            })
        }
        UpperLimit::Profiled(None, iterations, _) => {
            f.iterations += iterations;
            f.warnings.push(
                "mu_static fits at its bound mu_static = mu_kinetic (its upper limit's profile did not close)"
                    .into(),
            );
            StaticResult::NotIdentifiable
        }
    }
}

/// Starts that ended statistically as good as the best (cost within the 1-dof
/// likelihood ratio) but at a different mu are a real ambiguity, said as such.
pub(super) fn starts_agree(f: &mut Fitting, base: &Base, est: &Estimates) {
    let starts = &base.starts;
    let best_cost = starts.iter().map(|s| s.cost).fold(f64::INFINITY, f64::min);
    let tied: Vec<f64> = starts
        .iter()
        .filter(|s| s.cost <= best_cost + 2.0 * est.scale)
        .map(|s| s.mu_end)
        .collect();
    if let (Some(lo), Some(hi), Some(i)) = (
        tied.iter().cloned().reduce(f64::min),
        tied.iter().cloned().reduce(f64::max),
        est.mu_index,
    ) {
        if hi - lo > 3.0 * est.se[i].max(1e-6) {
            f.warnings.push(format!("starts disagree: equally good fits have mu_kinetic from {lo:.5} to {hi:.5}; the best was kept"));
        }
    }
}

/// The values the fit held, each parameter not free but the Stribeck speed under another
/// law and a point pendulum's equivalent length and mass ratio (its rod and masses).
fn fixed_values(problem: &TrajectoryProblem) -> Vec<(Param, f64)> {
    Param::ALL
        .into_iter()
        // The Stribeck speed means nothing under Coulomb's law.
        .filter(|q| {
            *q != Param::StribeckVelocity || problem.rig.friction_law == FrictionLaw::Stribeck
        })
        // A point pendulum's equivalent length and mass ratio are its rod and masses.
        .filter(|q| {
            !matches!(q, Param::PendulumLength | Param::MassRatio) || problem.rig.pendulum.is_some()
        })
        .filter(|q| !problem.free.contains(q))
        .map(|q| (q, problem.get(q)))
        .collect()
}

/// Where each free parameter started: the data's initial state and mu on the rig as given.
fn start_values(
    problem: &TrajectoryProblem,
    data: &Prepared,
    base: &Base,
    rig_guess: &Rig<f64>,
    settings: &FitSettings,
) -> Vec<(Param, f64)> {
    let start_problem = TrajectoryProblem::new(
        data.obs.clone(),
        *rig_guess,
        base.y0_guess,
        problem.free.clone(),
        settings.options,
    );
    problem
        .free
        .iter()
        .map(|&q| {
            let v = if q == Param::MuKinetic {
                base.mu0
            } else {
                start_problem.get(q)
            };
            (q, v)
        })
        .collect()
}

/// mu_kinetic's standard error in its parts: the noise's and the rig's shares of the
/// Jacobian's, and the model uncertainty the widenings added.
fn mu_parts(est: &Estimates) -> Option<MuParts> {
    est.mu_index.map(|i| {
        let total = est.params[i].1.stderr;
        let base = est.se[i].min(total);
        // A share of 0 is no part at all, also of an unbounded error (inf * 0 would be NaN).
        let part = |share: f64| {
            if share > 0.0 {
                base * share.sqrt()
            } else {
                0.0
            }
        };
        MuParts {
            noise: part(1.0 - est.rig_fraction),
            rig: part(est.rig_fraction),
            model: (total * total - base * base).max(0.0).sqrt(),
            total,
        }
    })
}

/// The friction law's result, with what the motion cannot test: a recording that slides one
/// way only cannot measure the other way's coefficient, nor slides at one load a load law.
fn friction_result(inputs: &law::LawInputs, motion: &Motion) -> law::FrictionLawResult {
    let mut fr = law::friction_law(inputs);
    // The modes the fitted motion passes through.
    let modes: Vec<crate::model::Mode> = motion
        .sol
        .events
        .iter()
        .map(|e| e.from)
        .chain(std::iter::once(motion.sol.final_mode))
        .collect();
    // Under the direction law both coefficients are reported with their own errors.
    if !inputs.chosen.contains(&Nuisance::Direction) {
        fr.untested = law::untested_by(&modes);
    }
    if !inputs.chosen.contains(&Nuisance::Load) {
        fr.untested
            .extend(law::load_untested_by(motion.slide_loads));
    }
    fr
}

/// Everything the report is built from.
pub(super) struct Parts<'a> {
    pub data: Prepared,
    pub base: Base,
    pub rig_guess: &'a Rig<f64>,
    pub settings: &'a FitSettings,
    pub est: Estimates,
    pub verdict: Verdict,
    pub models: Vec<ModelRow>,
    pub nuisances: Vec<Nuisance>,
    pub screening: Vec<(Nuisance, f64)>,
    pub outliers: [usize; 2],
    pub motion: Motion,
    pub mu_static: StaticResult,
    pub identifiable: bool,
    pub stop_reason: String,
}

/// The report.
pub(super) fn report(f: Fitting, parts: Parts) -> FitReport {
    let Parts {
        data,
        mut base,
        rig_guess,
        settings,
        est,
        verdict: v,
        models,
        nuisances,
        screening,
        outliers,
        motion,
        mu_static,
        identifiable,
        stop_reason,
    } = parts;
    let problem = f.problem;
    let a = &est.a;
    base.starts
        .sort_by(|a, b| a.mu_start.total_cmp(&b.mu_start));
    let fixed = fixed_values(&problem);
    let start_values = start_values(&problem, &data, &base, rig_guess, settings);
    let n_rows = problem.rows_used();
    let adequacy = Adequacy {
        chi2: a.chi2,
        dof: a.dof,
        reduced_chi2: a.reduced_chi2,
        p_value: a.p_value,
        aic: a.chi2 + 2.0 * f.p.len() as f64,
        bic: a.chi2 + f.p.len() as f64 * (n_rows as f64).ln(),
        lag1: v.lag1,
        runs_p_value: v.runs_p,
        block_se_ratio: v.block_ratio,
        block_frames: a.block_frames,
        windows_p_value: v.windows_p,
        limited_by_model: v.limited,
        noise_free: v.noise_free,
    };
    let pendulum = pendulum_found(&problem, &est.params, &est.correlation, rig_guess);
    let rig_values = RigValue::of(&est.params, |q| problem.prior_on(q));
    let mut warnings = f.warnings;
    for r in rig_values.iter().filter(|r| r.off()) {
        warnings.push(format!(
            "{}: check the rig file (the fit used the recording's value)",
            r.said("the recording puts")
        ));
    }
    let friction = identifiable.then(|| {
        let inputs = law::LawInputs {
            params: &est.params,
            correlation: &est.correlation,
            models: &models,
            chosen: &nuisances,
            screening: &screening,
            n_rows,
            forced: settings.friction.is_some(),
        };
        friction_result(&inputs, &motion)
    });
    let c = &problem.counters;
    FitReport {
        friction,
        mu_parts: mu_parts(&est),
        rig_keys: settings
            .measured
            .as_ref()
            .map_or_else(Vec::new, |m| m.keys.clone()),
        rig_values,
        implausible: v.implausible,
        mu_kinetic: est.mu_index.map(|i| est.params[i].1),
        params: est.params,
        start_values,
        fixed,
        mu_static,
        rig: problem.rig,
        initial: problem.initial,
        camera: problem.camera,
        correlation: est.correlation,
        rms_residual_m: v.rms_residual_m,
        rms_per_marker_m: v.rms_per_marker_m,
        noise_m: problem.sigma,
        noise: data.noise,
        reduced_chi2: adequacy.reduced_chi2,
        residual_autocorrelation: v.lag1,
        adequacy,
        models,
        nuisances,
        windows: v.windows,
        window_cut: v.window_cut,
        outliers,
        sliding_speed_range: motion.slide_speeds,
        events: motion.sol.events,
        identifiable,
        starts: base.starts,
        n_residuals: n_rows,
        n_frames: data.n_frames,
        work: Work {
            iterations: f.iterations,
            residual_evals: c.residuals.load(Ordering::Relaxed),
            jacobian_evals: c.jacobians.load(Ordering::Relaxed),
        },
        stop_reason,
        warnings,
        pendulum,
        failed: v.failed,
        not_identifiable: None,
        problem,
    }
}
