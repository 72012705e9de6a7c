//! Telling friction laws apart: which release would make a recording decide between laws a
//! fit could not (docs/plan.md, "Telling laws apart").
//!
//! For a law A taken as true (its parameters at a reference departure, see
//! [`reference_rig`]) and a rival law B, the noise-free recording A predicts for a release is
//! fitted with B (its own coefficient, law parameters and the whole initial state free): the
//! weighted sum of squares left, lambda(A, B), is the chi-square difference the rival pays on
//! that recording, on average (the noncentrality of a T-optimal design, Atkinson and Fedorov's
//! criterion). The fit chooses laws by BIC, so a truth with k_A parameters beats the rival
//! when lambda exceeds (k_A - k_B) ln n; the release's separation is the smallest such
//! margin over the pairs (Box and Hill's worst pair), and the plan ranks releases by it.
//! Pairs whose rival contains the truth (Coulomb inside every law, static friction inside
//! Stribeck's as v_s -> 0) are not weighed: there the rival fits the truth exactly and the
//! BIC's penalty, not the data, decides.

use super::search::Evaluator;
use crate::fit::lm::LeastSquares;
use crate::fit::{Observations, Param, TrajectoryProblem};
use super::spec::normal_cdf;
use crate::model::{FrictionLaw, Rig, State};
use serde::Serialize;
use std::sync::Arc;

/// A friction law the plan can weigh: the fit's names (`static` is Coulomb's law with a
/// static coefficient above the kinetic one).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, PartialOrd, Ord)]
#[serde(rename_all = "lowercase")]
pub enum Law {
    /// One coefficient, mu_s = mu_k.
    Coulomb,
    /// Coulomb's law with mu_s > mu_k.
    Static,
    /// mu(v) falling from mu_s to mu_k over the Stribeck speed v_s.
    Stribeck,
    /// Coefficients that differ by sliding direction.
    Direction,
    /// Friction growing as a power n of the normal load.
    Load,
}

impl Law {
    /// Every law, in the order reports list them.
    pub const ALL: [Law; 5] = [
        Law::Coulomb,
        Law::Static,
        Law::Stribeck,
        Law::Direction,
        Law::Load,
    ];

    /// The name in plan files, fits and reports.
    pub fn name(self) -> &'static str {
        match self {
            Law::Coulomb => "coulomb",
            Law::Static => "static",
            Law::Stribeck => "stribeck",
            Law::Direction => "direction",
            Law::Load => "load",
        }
    }

    /// The law of a name (the fit's names; `+viscous` and the like are not laws here).
    pub fn from_name(s: &str) -> Option<Law> {
        Law::ALL.into_iter().find(|l| l.name() == s)
    }

    /// The law's parameters beyond mu_kinetic, as the fit frees them.
    pub fn params(self) -> &'static [Param] {
        match self {
            Law::Coulomb => &[],
            Law::Static => &[Param::MuStatic],
            Law::Stribeck => &[Param::MuStatic, Param::StribeckVelocity],
            Law::Direction => &[Param::FrictionSplit],
            Law::Load => &[Param::LoadExponent],
        }
    }

    /// The law the simulator runs.
    pub fn friction_law(self) -> FrictionLaw {
        match self {
            Law::Coulomb | Law::Static => FrictionLaw::Coulomb,
            Law::Stribeck => FrictionLaw::Stribeck,
            Law::Direction => FrictionLaw::Direction,
            Law::Load => FrictionLaw::Load,
        }
    }

    /// Whether this law describes every rail `other` does (so a recording can never weigh
    /// against it when `other` is true): each law contains Coulomb's, Stribeck's contains
    /// static friction (v_s -> 0).
    pub fn contains(self, other: Law) -> bool {
        self == other || other == Law::Coulomb || (self == Law::Stribeck && other == Law::Static)
    }

    /// The law of a rig (static when mu_s is above mu_k under Coulomb's law).
    pub fn of_rig(rig: &Rig<f64>) -> Law {
        match rig.friction_law {
            FrictionLaw::Coulomb if rig.mu_static > rig.mu_kinetic => Law::Static,
            FrictionLaw::Coulomb => Law::Coulomb,
            FrictionLaw::Stribeck => Law::Stribeck,
            FrictionLaw::Direction => Law::Direction,
            FrictionLaw::Load => Law::Load,
        }
    }
}

impl std::fmt::Display for Law {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// The reference departures: the smallest departure from Coulomb's law a dry-rail lab
/// reports, used for a law the plan file does not give values for. Static friction 10 %
/// above kinetic; Stribeck's hump 10 % above kinetic over 0.05 m/s; coefficients 5 % apart
/// by direction (a split of 2.5 % of mu); a load exponent of 0.9.
pub const REFERENCE_STATIC_RATIO: f64 = 1.1;
/// Stribeck speed of the reference departure (m/s).
pub const REFERENCE_STRIBECK_VELOCITY: f64 = 0.05;
/// Half the relative difference of the direction law's coefficients at the reference.
pub const REFERENCE_SPLIT_FRACTION: f64 = 0.025;
/// Load exponent of the reference departure.
pub const REFERENCE_LOAD_EXPONENT: f64 = 0.9;

/// The rig under `law` at its reference departure from `base` (whose law's own values are
/// kept when it is that law: a plan file's or a fit's).
pub fn reference_rig(base: &Rig<f64>, law: Law) -> Rig<f64> {
    let mut rig = *base;
    let own = Law::of_rig(base) == law;
    let mu = base.mu_kinetic;
    rig.friction_law = law.friction_law();
    if !own {
        rig.mu_static = mu;
        rig.kinetic_split = 0.0;
        rig.static_split = 0.0;
        rig.load_exponent = 1.0;
        match law {
            Law::Coulomb => {}
            Law::Static => rig.mu_static = REFERENCE_STATIC_RATIO * mu,
            Law::Stribeck => {
                rig.mu_static = REFERENCE_STATIC_RATIO * mu;
                rig.stribeck_velocity = REFERENCE_STRIBECK_VELOCITY;
            }
            Law::Direction => {
                rig.kinetic_split = REFERENCE_SPLIT_FRACTION * mu;
                rig.static_split = rig.kinetic_split;
            }
            Law::Load => rig.load_exponent = REFERENCE_LOAD_EXPONENT,
        }
    }
    rig
}

/// How far a recording would separate one law, taken as true, from a rival.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Separation {
    /// The law taken as true (at its reference departure).
    pub truth: Law,
    /// The rival fitted to its recording.
    pub rival: Law,
    /// The chi-square the rival's best fit leaves (the noncentrality lambda).
    pub lambda: f64,
    /// lambda minus the BIC's price of the truth's extra parameters, (k_A - k_B) ln n: the
    /// BIC difference the recording is expected to give in the truth's favour.
    pub expected_delta_bic: f64,
    /// The chance that the fit's BIC prefers the truth, from a normal approximation of the
    /// noncentral chi-square (mean lambda + k, variance 2 (k + 2 lambda)).
    pub probability: f64,
}

/// The laws a plan weighs and the pairs it separates.
#[derive(Debug, Clone, PartialEq)]
pub struct Laws {
    /// The candidate laws, each at its reference rig.
    pub candidates: Vec<(Law, Rig<f64>)>,
    /// The pairs (truth, rival) weighed: the rival does not contain the truth.
    pub pairs: Vec<(usize, usize)>,
    /// Residual rows of the recordings the fit will have (for the BIC's ln n): the planned
    /// release's and those before it.
    pub rows: f64,
}

impl Laws {
    /// The laws `candidates` (at least two, else `None`: nothing to tell apart), each at its
    /// reference departure from `base`, over recordings of `rows` residual rows in all.
    pub fn new(base: &Rig<f64>, candidates: &[Law], rows: f64) -> Option<Laws> {
        let mut laws: Vec<Law> = candidates.to_vec();
        laws.sort();
        laws.dedup();
        if laws.len() < 2 {
            return None;
        }
        let candidates: Vec<(Law, Rig<f64>)> =
            laws.iter().map(|&l| (l, reference_rig(base, l))).collect();
        let mut pairs = Vec::new();
        for (a, &la) in laws.iter().enumerate() {
            for (b, &lb) in laws.iter().enumerate() {
                if a != b && !lb.contains(la) {
                    pairs.push((a, b));
                }
            }
        }
        Some(Laws {
            candidates,
            pairs,
            rows,
        })
    }

    /// Every pair's separation by a recording of release `y0` (`None` for a pair whose
    /// truth cannot be simulated from it).
    pub fn separations(&self, ev: &Evaluator, y0: &State<f64>) -> Vec<Option<Separation>> {
        let ln_n = self.rows.max(2.0).ln();
        let mut predicted: Vec<Option<Arc<Observations>>> = vec![None; self.candidates.len()];
        for &(a, _) in &self.pairs {
            if predicted[a].is_none() {
                predicted[a] = predict(ev, &self.candidates[a].1, y0).map(Arc::new);
            }
        }
        self.pairs
            .iter()
            .map(|&(a, b)| {
                let obs = predicted[a].clone()?;
                let (la, lb) = (self.candidates[a].0, self.candidates[b].0);
                let start = rival_start(&self.candidates[a].1, &self.candidates[b].1, lb);
                let lambda = rival_chi2(ev, obs, start, y0, lb);
                let dk = la.params().len() as f64 - lb.params().len() as f64;
                let expected = lambda - dk * ln_n;
                let sd = (2.0 * (dk.abs() + 2.0 * lambda)).max(1e-12).sqrt();
                Some(Separation {
                    truth: la,
                    rival: lb,
                    lambda,
                    expected_delta_bic: expected,
                    probability: normal_cdf((expected + dk.abs()) / sd),
                })
            })
            .collect()
    }

    /// The release's separation: the smallest expected BIC margin over the pairs (minus
    /// infinity when a pair could not be computed).
    pub fn worst(separations: &[Option<Separation>]) -> f64 {
        separations
            .iter()
            .map(|s| s.as_ref().map_or(f64::NEG_INFINITY, |s| s.expected_delta_bic))
            .fold(f64::INFINITY, f64::min)
    }
}

/// The noise-free marker positions a release of `rig` predicts at the plan's frames.
fn predict(ev: &Evaluator, rig: &Rig<f64>, y0: &State<f64>) -> Option<Observations> {
    let base = ev.placeholder();
    let mut problem = TrajectoryProblem::new(base.clone(), *rig, *y0, Vec::new(), ev.options);
    // The rig's own mu_static (a problem ties it to mu_kinetic unless told otherwise).
    problem.tie_static = false;
    let values = problem
        .raw_residuals(&nalgebra::DVector::zeros(0))
        .ok()?;
    let n = base.times.len();
    let mut obs = Observations {
        times: base.times.clone(),
        slider: vec![None; n],
        bob: vec![None; n],
    };
    // The placeholder observes zeros, so each residual row is the predicted coordinate.
    for (row, v) in problem.rows().zip(values) {
        let track = if row.marker == 0 {
            &mut obs.slider
        } else {
            &mut obs.bob
        };
        track[row.frame].get_or_insert([0.0; 2])[row.coord] = v;
    }
    obs.slider.iter().chain(&obs.bob).all(Option::is_some).then_some(obs)
}

/// The rival's starting rig: the truth's, under the rival's law, with each of the rival's
/// parameters at the truth's value where the truth has it and at its null departure (the tie
/// mu_s = mu_k just above it, no split, exponent 1; the reference's v_s) where it has not.
fn rival_start(truth: &Rig<f64>, reference: &Rig<f64>, rival: Law) -> Rig<f64> {
    let t = Law::of_rig(truth);
    let mut rig = *truth;
    rig.friction_law = rival.friction_law();
    let has = |l: Law, q: Param| l.params().contains(&q);
    if !has(rival, Param::MuStatic) {
        rig.mu_static = rig.mu_kinetic;
    } else if !has(t, Param::MuStatic) {
        // Just above the tie: at mu_s = mu_k the stick test's derivative is one-sided.
        rig.mu_static = rig.mu_kinetic * (1.0 + 1e-6);
    }
    if has(rival, Param::StribeckVelocity) && !has(t, Param::StribeckVelocity) {
        rig.stribeck_velocity = reference.stribeck_velocity;
    }
    if !(has(rival, Param::FrictionSplit) && has(t, Param::FrictionSplit)) {
        rig.kinetic_split = 0.0;
        rig.static_split = 0.0;
    }
    if !(has(rival, Param::LoadExponent) && has(t, Param::LoadExponent)) {
        rig.load_exponent = 1.0;
    }
    rig
}

/// Gauss-Newton iterations of the rival's fit: lambda settles in two or three (the start is
/// the truth's coefficient and release, one step from the optimum when the departure is
/// small).
const RIVAL_ITERATIONS: u64 = 4;

/// The chi-square of the rival's best fit (its coefficient, law parameters and the release)
/// to the recording `obs`, with the plan's camera noise.
fn rival_chi2(
    ev: &Evaluator,
    obs: Arc<Observations>,
    start: Rig<f64>,
    y0: &State<f64>,
    rival: Law,
) -> f64 {
    let mut free = vec![Param::MuKinetic];
    free.extend_from_slice(rival.params());
    free.extend([Param::X, Param::Theta, Param::XDot, Param::ThetaDot]);
    let mut problem = TrajectoryProblem::new(obs, start, *y0, free, ev.options);
    problem.tie_static = !matches!(rival, Law::Static | Law::Stribeck);
    let noise = ev.spec.camera.noise_m;
    problem.sigma = [noise, noise];
    let p0 = problem.values();
    let start_chi2 = problem
        .normal_equations(&p0)
        .map_or(f64::INFINITY, |n| 2.0 * n.cost);
    let lm = crate::fit::solve::loose(Some(1e-6));
    match crate::fit::solve::run_lm(&problem, p0, RIVAL_ITERATIONS, lm) {
        Ok((_, cost, _, _)) => (2.0 * cost).min(start_chi2),
        Err(_) => start_chi2,
    }
}


/// What a fit's JSON says about the laws: the one it chose, each law's evidence, and the
/// recording's release (a single fit's), for [`resolve`].
#[derive(Debug, Clone, PartialEq, Default)]
pub struct LawTable {
    /// The law chosen (`None`: a law this planner does not weigh, e.g. with viscous friction
    /// alone).
    pub chosen: Option<Law>,
    /// Each law's status (`fitted`, `screened`, `not tried`) and BIC against the chosen.
    pub rows: Vec<(Law, String, Option<f64>)>,
    /// The fitted release of a single recording's fit (a joint fit's are not in its JSON).
    pub initial: Option<State<f64>>,
    /// Residual rows the fit used.
    pub n_residuals: f64,
}

impl LawTable {
    /// The table in a fit's JSON (`friction_law`, `initial`, `n_residuals`); `None` when the
    /// JSON has no friction law section.
    pub fn from_json(v: &serde_json::Value) -> Option<LawTable> {
        let f = &v["friction_law"];
        let chosen = f["chosen"].as_str()?;
        let rows = f["laws"]
            .as_array()?
            .iter()
            .filter_map(|r| {
                let law = Law::from_name(r["law"].as_str()?)?;
                Some((law, r["status"].as_str()?.to_owned(), r["delta_bic"].as_f64()))
            })
            .collect();
        let i = &v["initial"];
        let initial = (|| Some([i["x"].as_f64()?, i["theta"].as_f64()?, i["x_dot"].as_f64()?, i["theta_dot"].as_f64()?]))()
            .filter(|s| s.iter().all(|x| x.is_finite()));
        let n_residuals = v["n_residuals"]
            .as_f64()
            .or_else(|| {
                v["releases"]
                    .as_array()
                    .map(|rs| rs.iter().filter_map(|r| r["n_residuals"].as_f64()).sum())
            })
            .unwrap_or(0.0);
        Some(LawTable {
            chosen: Law::from_name(chosen),
            rows,
            initial,
            n_residuals: if n_residuals.is_finite() { n_residuals.max(0.0) } else { 0.0 },
        })
    }
}

/// The fit's line for strong evidence (docs/fit.md, "Friction law"): a BIC difference of 6.
pub const STRONG: f64 = 6.0;

/// The laws a plan weighs, and why, in plain sentences: the plan file's `discriminate` list
/// when given; after a fit, the law it chose and every law the recording left open (not
/// fitted, or fitted and worse by less than [`STRONG`] in its chi-square, and, for a law
/// that contains the chosen one, whose reference departure the fitted release would not
/// have shown strongly); otherwise none (the plan ranks by mu's precision).
pub fn resolve(ev: &Evaluator, rows_planned: f64) -> (Option<Laws>, Vec<String>) {
    let spec = ev.spec;
    let mut notes = Vec::new();
    if !spec.discriminate.is_empty() {
        let rows = rows_planned + spec.prior.as_ref().and_then(|p| p.laws.as_ref()).map_or(0.0, |t| t.n_residuals);
        let laws = Laws::new(&spec.rig, &spec.discriminate, rows);
        notes.push(format!(
            "telling apart the laws the plan names ({}): releases ranked by the worst pair's expected BIC margin",
            names(&spec.discriminate)
        ));
        return (laws, notes);
    }
    let Some(table) = spec.prior.as_ref().and_then(|p| p.laws.as_ref()) else {
        return (None, notes);
    };
    let Some(chosen) = table.chosen else {
        notes.push("the fit's law is not one the planner weighs: planning for mu's precision".into());
        return (None, notes);
    };
    let rows = rows_planned + table.n_residuals;
    let ln_n = table.n_residuals.max(2.0).ln();
    let mut open = vec![chosen];
    let mut told = Vec::new();
    for (law, status, delta) in &table.rows {
        let (law, delta) = (*law, *delta);
        if law == chosen {
            continue;
        }
        let dk = law.params().len() as f64 - chosen.params().len() as f64;
        // The chi-square difference, the BIC's penalty taken out: what the data said.
        let data = delta.map(|d| d - dk * ln_n);
        match (status.as_str(), data) {
            ("fitted", Some(d)) if d >= STRONG && !law.contains(chosen) => {
                told.push(format!("{law} (chi-square worse by {d:.0})"));
                continue;
            }
            _ => {}
        }
        if law.contains(chosen) {
            // The fit cannot weigh against a law containing its choice: ask whether the
            // recording would have shown the law's reference departure.
            if let Some(y0) = table.initial {
                let first = Laws::new(&spec.rig, &[chosen, law], table.n_residuals);
                let shown = first
                    .map(|l| Laws::worst(&l.separations(ev, &y0)))
                    .unwrap_or(f64::NEG_INFINITY);
                if shown >= STRONG {
                    told.push(format!(
                        "{law} (the fitted release would have shown its reference departure by {shown:.0} in BIC)"
                    ));
                    continue;
                }
            }
        }
        open.push(law);
    }
    if !told.is_empty() {
        notes.push(format!(
            "the fit's recording already tells {chosen} from {}",
            told.join(", ")
        ));
    }
    if open.len() < 2 {
        notes.push(format!(
            "the fit's law ({chosen}) has no rival its recording left open: no law to tell apart, planning for mu's precision"
        ));
        return (None, notes);
    }
    let laws = Laws::new(&spec.rig, &open, rows);
    notes.push(format!(
        "the fit chose {chosen} but its recording cannot tell it from {}: releases ranked by how surely they separate {} (the worst pair's expected BIC margin)",
        names(&open[1..]),
        names(&open)
    ));
    (laws, notes)
}

fn names(laws: &[Law]) -> String {
    laws.iter().map(|l| l.name()).collect::<Vec<_>>().join(", ")
}
