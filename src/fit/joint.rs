//! One rig, many releases: the releases fitted together. The rail and the pendulum are the
//! same in every release, so the friction law, the tilt, the viscous terms and the pendulum's
//! build are shared; each release keeps its initial state and marker lag, and its camera
//! unless the camera is the same. The releases' problems are the single fit's
//! ([`TrajectoryProblem`]); the joint problem sums their normal equations into the shared and
//! per-release blocks, so its cost grows linearly with the releases, and its nuisances are
//! chosen by the single fit's selection ([`select::forward`] over [`Candidate`]).

use super::intervals::{model_uncertainty, widen, within_bounds};
use super::lm::{LeastSquares, Normal};
use super::problem::{Observations, Param, TrajectoryProblem};
use super::select::{self, Candidate, ModelRow, Nuisance, SelectOptions};
use super::solve::{solve_loose, STAGE_FTOL};
use super::uncertainty::{self, WindowFit};
use super::{fit, Estimate, FitError, FitReport, FitSettings};
use crate::model::{Rig, State};
use crate::sim::{simulate, Request};
use argmin::core::Error;
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;
use serde::Serialize;

/// Whether a parameter is the rig's (one value for every release) rather than the release's.
/// The camera's parameters are the release's unless the camera is the same in all.
fn is_shared(q: Param, same_camera: bool) -> bool {
    q.is_rig() || (same_camera && q.is_camera() && q != Param::Lag)
}

/// Several releases' problems with their shared parameters tied: the parameter vector is the
/// shared parameters, then each release's own, release by release. Each release's problem
/// frees the shared parameters first, then its own.
#[derive(Debug, Clone)]
pub struct JointProblem {
    /// The releases' problems (their values are the current ones).
    pub parts: Vec<TrajectoryProblem>,
    /// The shared free parameters, in the order of the vector.
    pub shared: Vec<Param>,
    /// Camera and marker parameters shared by every release.
    pub same_camera: bool,
}

impl JointProblem {
    /// The releases' problems tied: each one's free parameters split into shared and own.
    pub fn new(mut parts: Vec<TrajectoryProblem>, same_camera: bool) -> Self {
        let mut shared: Vec<Param> = Vec::new();
        for part in &parts {
            for &q in &part.free {
                if is_shared(q, same_camera) && !shared.contains(&q) {
                    shared.push(q);
                }
            }
        }
        for part in &mut parts {
            let own: Vec<Param> = part
                .free
                .iter()
                .copied()
                .filter(|&q| !is_shared(q, same_camera))
                .collect();
            part.free = shared.iter().copied().chain(own).collect();
        }
        JointProblem {
            parts,
            shared,
            same_camera,
        }
    }

    /// Where each release's own parameters start in the vector.
    fn offsets(&self) -> Vec<usize> {
        let mut at = self.shared.len();
        self.parts
            .iter()
            .map(|p| {
                let o = at;
                at += p.free.len() - self.shared.len();
                o
            })
            .collect()
    }

    /// Indices in the joint vector of release `k`'s parameters, in its own order.
    fn index(&self, k: usize, offset: usize) -> Vec<usize> {
        let s = self.shared.len();
        (0..self.parts[k].free.len())
            .map(|j| if j < s { j } else { offset + j - s })
            .collect()
    }

    /// Every entry of the vector as (release, parameter); the release is `None` when shared.
    fn labels(&self) -> Vec<(Option<usize>, Param)> {
        let s = self.shared.len();
        let mut out: Vec<_> = self.shared.iter().map(|&q| (None, q)).collect();
        for (k, part) in self.parts.iter().enumerate() {
            out.extend(part.free[s..].iter().map(|&q| (Some(k), q)));
        }
        out
    }

    /// Release `k`'s part of the joint vector `p`.
    fn sub(&self, p: &DVector<f64>, idx: &[usize]) -> DVector<f64> {
        DVector::from_iterator(idx.len(), idx.iter().map(|&i| p[i]))
    }

    /// Each release's normal equations at `p` (in parallel), with their block sums when
    /// `block` gives each release's frames per block.
    fn part_normals(
        &self,
        p: &DVector<f64>,
        block: Option<&[usize]>,
    ) -> Result<Vec<(Vec<usize>, Normal)>, Error> {
        let offsets = self.offsets();
        (0..self.parts.len())
            .into_par_iter()
            .with_max_len(1)
            .map(|k| {
                let idx = self.index(k, offsets[k]);
                let q = self.sub(p, &idx);
                let n = self.parts[k].normal_equations_blocked(&q, block.map(|b| b[k]))?;
                Ok((idx, n))
            })
            .collect()
    }

    /// The releases' normal equations summed into the joint ones.
    fn assemble(&self, n: usize, parts: Vec<(Vec<usize>, Normal)>) -> Normal {
        let mut out = Normal {
            cost: 0.0,
            jtj: DMatrix::zeros(n, n),
            jtr: DVector::zeros(n),
            meat: None,
        };
        let mut meat: Option<DMatrix<f64>> = None;
        for (idx, part) in parts {
            out.cost += part.cost;
            for (a, &i) in idx.iter().enumerate() {
                out.jtr[i] += part.jtr[a];
                for (b, &j) in idx.iter().enumerate() {
                    out.jtj[(i, j)] += part.jtj[(a, b)];
                }
            }
            if let Some(m) = part.meat {
                let acc = meat.get_or_insert_with(|| DMatrix::zeros(n, n));
                for (a, &i) in idx.iter().enumerate() {
                    for (b, &j) in idx.iter().enumerate() {
                        acc[(i, j)] += m[(a, b)];
                    }
                }
            }
        }
        out.meat = meat;
        out
    }

    /// The joint normal equations with the block sums of each release's residuals (frames per
    /// block per release).
    pub fn normal_equations_blocked(
        &self,
        p: &DVector<f64>,
        block: Option<&[usize]>,
    ) -> Result<Normal, Error> {
        let parts = self.part_normals(p, block)?;
        Ok(self.assemble(p.len(), parts))
    }
}

impl LeastSquares for JointProblem {
    fn normal_equations(&self, p: &DVector<f64>) -> Result<Normal, Error> {
        self.normal_equations_blocked(p, None)
    }

    fn project(&self, p: &mut DVector<f64>) {
        // Each release's bounds on its own slice; the shared entries come out the same from
        // every release (their bounds depend on shared values only).
        let offsets = self.offsets();
        for (k, part) in self.parts.iter().enumerate() {
            let idx = self.index(k, offsets[k]);
            let mut q = self.sub(p, &idx);
            part.project(&mut q);
            for (a, &i) in idx.iter().enumerate() {
                p[i] = q[a];
            }
        }
    }
}

impl Candidate for JointProblem {
    type Start = Vec<(State<f64>, f64)>;
    fn n_rows(&self) -> usize {
        self.parts.iter().map(|p| p.n_rows()).sum()
    }
    fn n_free(&self) -> usize {
        self.labels().len()
    }
    fn width(&self) -> usize {
        self.parts.iter().map(|p| p.free.len()).max().unwrap_or(0)
    }
    fn frees(&self, q: Param) -> bool {
        self.parts.iter().any(|p| p.free.contains(&q))
    }
    fn free_names(&self) -> Vec<&'static str> {
        let mut names: Vec<&'static str> = Vec::new();
        for (_, q) in self.labels() {
            if !names.contains(&q.name()) {
                names.push(q.name());
            }
        }
        names
    }
    fn values(&self) -> DVector<f64> {
        let s = self.shared.len();
        let mut v: Vec<f64> = self.shared.iter().map(|&q| self.parts[0].get(q)).collect();
        for part in &self.parts {
            v.extend(part.free[s..].iter().map(|&q| part.get(q)));
        }
        DVector::from_vec(v)
    }
    fn set_values(&mut self, v: &DVector<f64>) {
        let offsets = self.offsets();
        let idx: Vec<Vec<usize>> = (0..self.parts.len())
            .map(|k| self.index(k, offsets[k]))
            .collect();
        for (part, idx) in self.parts.iter_mut().zip(idx) {
            part.set_values(&DVector::from_iterator(
                idx.len(),
                idx.iter().map(|&i| v[i]),
            ));
        }
    }
    fn mu_kinetic(&self) -> f64 {
        self.parts[0].rig.mu_kinetic
    }
    fn mu_static(&self) -> f64 {
        self.parts[0].rig.mu_static
    }
    fn pendulum_given(&self) -> bool {
        self.parts[0].rig.pendulum.is_some()
    }
    fn with_nuisance(&self, nu: Nuisance, mu_static: f64) -> Self {
        let parts = self
            .parts
            .iter()
            .map(|p| p.with_nuisance(nu, mu_static))
            .collect();
        JointProblem::new(parts, self.same_camera)
    }
    fn restarted(&self, start: &Self::Start) -> Self {
        let mut out = self.clone();
        for (part, s) in out.parts.iter_mut().zip(start) {
            *part = part.restarted(s);
        }
        out
    }
    fn static_tied(&self) -> Self {
        let parts = self.parts.iter().map(|p| p.static_tied()).collect();
        JointProblem::new(parts, self.same_camera)
    }
    fn static_near_tie(&self) -> Self {
        let mut out = self.clone();
        out.parts = out.parts.iter().map(|p| p.static_near_tie()).collect();
        out
    }
    fn score_drops(&self, p: &DVector<f64>, candidates: &[Nuisance]) -> Vec<(Nuisance, f64)> {
        let mut at = self.clone();
        at.set_values(p);
        let labels = at.labels();
        select::score_drops_by(&at, candidates, |nu| {
            let aug = at.with_nuisance(nu, at.mu_static());
            let new = aug.labels();
            let cols = labels
                .iter()
                .filter_map(|l| new.iter().position(|n| n == l))
                .collect();
            (aug, cols)
        })
    }
}

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

/// Marker distance per release: the median slider-to-bob distance and the spread of one
/// frame's distance (a robust standard deviation).
fn marker_distance(obs: &Observations) -> Option<(f64, f64)> {
    let mut d: Vec<f64> = super::guess::marker_distances(obs)
        .into_iter()
        .filter(|d| d.is_finite())
        .collect();
    if d.len() < 10 {
        return None;
    }
    d.sort_by(f64::total_cmp);
    let med = d[d.len() / 2];
    let mut dev: Vec<f64> = d.iter().map(|x| (x - med).abs()).collect();
    dev.sort_by(f64::total_cmp);
    Some((med, 1.4826 * dev[dev.len() / 2]))
}

/// Releases of another rig: their marker distance (the rod, as the camera sees it) differs
/// from the releases' median by more than five times the frames' spread plus 2 % (what a
/// camera's scale may differ by between releases). The names of those releases.
pub fn other_rigs(releases: &[Release]) -> Vec<(String, f64, f64)> {
    let d: Vec<Option<(f64, f64)>> = releases.iter().map(|r| marker_distance(&r.obs)).collect();
    let mut meds: Vec<f64> = d.iter().flatten().map(|x| x.0).collect();
    if meds.len() < 2 {
        return Vec::new();
    }
    meds.sort_by(f64::total_cmp);
    let median = meds[meds.len() / 2];
    releases
        .iter()
        .zip(&d)
        .filter_map(|(r, d)| {
            let (m, s) = (*d)?;
            ((m - median).abs() > 5.0 * s + 0.02 * median).then(|| (r.name.clone(), m, median))
        })
        .collect()
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

/// A p-value for a sentence: below double precision's resolution as a bound.
fn p_text(p: f64) -> String {
    if p < 1e-16 {
        "< 1e-16".to_owned()
    } else {
        format!("{p:.1e}")
    }
}

/// Below this p-value the releases' own mu disagree (the single fit's windows use the same).
const AGREE_P: f64 = 0.01;

/// The releases' own (mu, se) as the windows' test sees them.
fn as_windows(pairs: &[(f64, f64)]) -> Vec<WindowFit> {
    pairs
        .iter()
        .filter(|(m, s)| m.is_finite() && *s > 0.0)
        .map(|&(mu_kinetic, stderr)| WindowFit {
            t_start: 0.0,
            t_end: 0.0,
            mu_kinetic,
            stderr,
        })
        .collect()
}

/// p-value of the releases' own mu agreeing: the single fit's windows test
/// ([`uncertainty::window_consistency`]).
fn consistency(pairs: &[(f64, f64)]) -> Option<f64> {
    uncertainty::window_consistency(&as_windows(pairs))
}

/// The releases' precision-weighted spread about `mu` ([`uncertainty::window_spread`]).
fn window_spread_of(pairs: &[(f64, f64)], mu: f64) -> f64 {
    uncertainty::window_spread(&as_windows(pairs), mu)
}

/// Each release's own mu under `jp`'s shared values, in parallel.
fn own_mus(jp: &JointProblem, settings: &FitSettings) -> Vec<(f64, f64)> {
    jp.parts
        .par_iter()
        .with_max_len(1)
        .map(|m| own_mu(m, &jp.shared, settings).map_or((f64::NAN, 0.0), |e| (e.value, e.stderr)))
        .collect()
}

/// Each release's own (mu, se) and z, keyed by release index.
type Zs = Vec<(usize, (f64, f64), f64)>;

/// The releases other than `out` refitted jointly (same model): their mu, each release's own
/// mu and z (the rest's leave-one-out z; those in `out` against the rest's mu, their own mu
/// under the rest's shared values), and whether the rest agree.
fn fit_rest(
    jp: &JointProblem,
    out: &[usize],
    settings: &FitSettings,
) -> Option<(Estimate, Zs, bool)> {
    let keep: Vec<usize> = (0..jp.parts.len()).filter(|i| !out.contains(i)).collect();
    let mut rest = JointProblem::new(
        keep.iter().map(|&i| jp.parts[i].clone()).collect(),
        jp.same_camera,
    );
    let (p, _, _) = solve_loose(&rest, rest.values(), settings.max_iters, None).ok()?;
    rest.set_values(&p);
    let mu = wald_mu(&rest, &p)?;
    let pairs = own_mus(&rest, settings);
    let rz = leave_one_out(&pairs);
    let mut zs: Zs = keep
        .iter()
        .zip(&pairs)
        .zip(&rz)
        .map(|((&i, &own), &zi)| (i, own, zi))
        .collect();
    for &i in out {
        let mut m = jp.parts[i].clone();
        for &q in &rest.shared {
            let v = rest.parts[0].get(q);
            set_param(&mut m, q, v);
        }
        if let Some(e) = own_mu(&m, &rest.shared, settings) {
            let zi = (e.value - mu.value) / e.stderr.hypot(mu.stderr);
            zs.push((i, (e.value, e.stderr), zi));
        }
    }
    let agree = consistency(&pairs).is_none_or(|p| p >= AGREE_P);
    Some((mu, zs, agree))
}

/// The releases that disagree: the one with the largest |z| set aside, the rest refitted
/// jointly (same model) and tested again, until the rest agree or only half are left; then
/// a release set aside whose own mu lies within 3 standard errors of the rest's is taken
/// back (an odd release pulls the shared tilt, and with it the first |z|s). The releases
/// that disagree, and the others' fit ([`fit_rest`]).
fn set_aside(
    jp: &JointProblem,
    z: &[f64],
    settings: &FitSettings,
) -> (Vec<usize>, Option<(Estimate, Zs)>) {
    let n = jp.parts.len();
    let mut out: Vec<usize> = Vec::new();
    let mut z = z.to_vec();
    let mut rest_fit = None;
    while out.len() < n / 2 && n - out.len() > 2 {
        let Some(worst) = (0..n)
            .filter(|i| !out.contains(i))
            .max_by(|&a, &b| z[a].abs().total_cmp(&z[b].abs()))
        else {
            break;
        };
        out.push(worst);
        let Some((mu, zs, agree)) = fit_rest(jp, &out, settings) else {
            break;
        };
        for &(i, _, zi) in &zs {
            z[i] = zi;
        }
        rest_fit = Some((mu, zs));
        if agree {
            break;
        }
    }
    let back: Vec<usize> = out.iter().copied().filter(|&i| z[i].abs() <= 3.0).collect();
    if !back.is_empty() && back.len() < out.len() {
        out.retain(|i| !back.contains(i));
        if let Some((mu, zs, _)) = fit_rest(jp, &out, settings) {
            rest_fit = Some((mu, zs));
        }
    }
    (out, rest_fit)
}

/// Set parameter `q` of `m` to `v` (through its values, with `q` briefly free).
fn set_param(m: &mut TrajectoryProblem, q: Param, v: f64) {
    let free = std::mem::replace(&mut m.free, vec![q]);
    m.set_values(&DVector::from_element(1, v));
    m.free = free;
}

/// mu_kinetic of `jp` at its optimum `p` with the Jacobian's standard error, scaled by the
/// reduced chi-square when above one.
fn wald_mu(jp: &JointProblem, p: &DVector<f64>) -> Option<Estimate> {
    let i = jp.shared.iter().position(|q| *q == Param::MuKinetic)?;
    let c = uncertainty::covariances(jp.normal_equations(p).ok()?, jp.n_rows(), 1.0);
    if c.singular {
        return None;
    }
    let se = c.se[i];
    Some(Estimate {
        value: p[i],
        stderr: se,
        ci95: [p[i] - 1.96 * se, p[i] + 1.96 * se],
        interval: "wald",
    })
}

/// Leave-one-out agreement: each release's own mu against the precision-weighted mean of the
/// others', as z = difference / combined standard error.
fn leave_one_out(own: &[(f64, f64)]) -> Vec<f64> {
    (0..own.len())
        .map(|i| {
            let (mut num, mut den) = (0.0, 0.0);
            for (j, &(m, s)) in own.iter().enumerate() {
                if j != i && s > 0.0 {
                    num += m / (s * s);
                    den += 1.0 / (s * s);
                }
            }
            if den == 0.0 || own[i].1 <= 0.0 {
                return 0.0;
            }
            (own[i].0 - num / den) / (own[i].1.powi(2) + 1.0 / den).sqrt()
        })
        .collect()
}

/// mu_kinetic of release `part` alone: mu and its own parameters free, the shared nuisances
/// held at the joint values. Its value and standard error (the larger of the Jacobian's and
/// the block covariance's, as in the single fit).
fn own_mu(part: &TrajectoryProblem, shared: &[Param], settings: &FitSettings) -> Option<Estimate> {
    let mut m = part.clone();
    m.free
        .retain(|q| *q == Param::MuKinetic || !shared.contains(q));
    let (p, _, _) = solve_loose(&m, m.values(), settings.max_iters, None).ok()?;
    m.set_values(&p);
    let a = uncertainty::assess(&m, &p, f64::INFINITY).ok()?;
    let i = m.free.iter().position(|q| *q == Param::MuKinetic)?;
    let se = a.se[i].max(a.se_block[i]);
    Some(Estimate {
        value: p[i],
        stderr: se,
        ci95: [p[i] - 1.96 * se, p[i] + 1.96 * se],
        interval: "wald",
    })
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

#[cfg(test)]
mod tests {
    use super::leave_one_out;

    /// A release 10 standard errors off the others has z of about 10/sqrt(1 + 1/(n-1)); the
    /// others stay within a few units of zero.
    #[test]
    fn leave_one_out_names_the_odd_release() {
        let own = [(0.25, 0.001), (0.25, 0.001), (0.25, 0.001), (0.26, 0.001)];
        let z = leave_one_out(&own);
        let want = 0.01 / (0.001f64.powi(2) + 0.001f64.powi(2) / 3.0).sqrt();
        assert!((z[3] - want).abs() < 1e-9, "{z:?}");
        assert!(z[..3].iter().all(|v| v.abs() < 3.5), "{z:?}");
    }
}
