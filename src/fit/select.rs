//! Physics and camera nuisances chosen by the data: candidate models as data ([`Nuisance`]),
//! screened by a score test (the chi-square drop a parameter would buy, predicted from one
//! Jacobian at the current optimum), the promising ones fitted, and the best kept while it
//! lowers the Bayesian information criterion BIC = chi2 + k ln(n) (forward selection).

use super::lm::LeastSquares;
use super::problem::{Param, TrajectoryProblem, MAX_FREE};
use super::{solve, Solved};
use crate::model::FrictionLaw;
use nalgebra::DVector;
use rayon::prelude::*;

/// A departure from the ideal rig or camera that a candidate model adds (PHYSICS.md, "Real
/// rigs" and "What a camera adds").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Nuisance {
    /// mu_static free above mu_kinetic (Coulomb friction with two coefficients).
    StaticFriction,
    /// Stribeck friction: mu_static and the Stribeck speed free.
    Stribeck,
    /// Rail tilt.
    RailTilt,
    /// Viscous damping at the pivot.
    PivotDamping,
    /// Viscous rail friction.
    ViscousFriction,
    /// Camera scale error (the bob marker at the rod's end).
    CameraScale,
    /// Bob marker off the rod's end: along and across the rod.
    BobOffset,
    /// Slider marker off the pivot.
    SliderOffset,
    /// A time lag between the two markers' tracks.
    Lag,
}

impl Nuisance {
    /// Every candidate, in the order ties are broken.
    pub const ALL: [Nuisance; 9] = [
        Nuisance::StaticFriction,
        Nuisance::Stribeck,
        Nuisance::RailTilt,
        Nuisance::PivotDamping,
        Nuisance::ViscousFriction,
        Nuisance::CameraScale,
        Nuisance::BobOffset,
        Nuisance::SliderOffset,
        Nuisance::Lag,
    ];

    /// Name in reports and JSON.
    pub fn name(self) -> &'static str {
        match self {
            Nuisance::StaticFriction => "mu_static",
            Nuisance::Stribeck => "stribeck",
            Nuisance::RailTilt => "rail_tilt",
            Nuisance::PivotDamping => "pivot_damping",
            Nuisance::ViscousFriction => "viscous_friction",
            Nuisance::CameraScale => "camera_scale",
            Nuisance::BobOffset => "bob_marker_offset",
            Nuisance::SliderOffset => "slider_marker_offset",
            Nuisance::Lag => "marker_lag",
        }
    }

    /// The parameters it frees.
    pub fn params(self) -> &'static [Param] {
        match self {
            Nuisance::StaticFriction => &[Param::MuStatic],
            Nuisance::Stribeck => &[Param::MuStatic, Param::StribeckVelocity],
            Nuisance::RailTilt => &[Param::RailTilt],
            Nuisance::PivotDamping => &[Param::PivotDamping],
            Nuisance::ViscousFriction => &[Param::ViscousFriction],
            Nuisance::CameraScale => &[Param::ScaleError],
            Nuisance::BobOffset => &[Param::BobAlong, Param::BobAcross],
            Nuisance::SliderOffset => &[Param::SliderDx, Param::SliderDy],
            Nuisance::Lag => &[Param::Lag],
        }
    }

    /// Whether a score test can screen it: a parameter whose neutral value is an interior
    /// point. mu_static at mu_static = mu_kinetic has a vanishing first-order effect (the slip
    /// then starts with x'' = 0), and Stribeck changes the law: both are fitted outright.
    fn screened(self) -> bool {
        !matches!(self, Nuisance::StaticFriction | Nuisance::Stribeck)
    }

    /// Candidates it cannot join: camera scale and the bob marker's distance along the rod
    /// act through their product; Stribeck contains mu_static.
    fn conflicts(self, other: Nuisance) -> bool {
        use Nuisance::*;
        matches!(
            (self, other),
            (CameraScale, BobOffset)
                | (BobOffset, CameraScale)
                | (Stribeck, StaticFriction)
                | (StaticFriction, Stribeck)
        )
    }

    /// `problem` with this nuisance added at its neutral value (mu_static from `mu_static`).
    fn add_to(self, problem: &TrajectoryProblem, mu_static: f64) -> TrajectoryProblem {
        let mut m = problem.clone();
        if self == Nuisance::Stribeck {
            m.rig.friction_law = FrictionLaw::Stribeck;
            m.rig.stribeck_velocity = 0.05;
        }
        for &q in self.params() {
            if !m.free.contains(&q) {
                m.free.push(q);
            }
        }
        if self.params().contains(&Param::MuStatic) {
            m.tie_static = false;
            m.rig.mu_static = mu_static.max(m.rig.mu_kinetic * 1.02);
        }
        m
    }
}

/// One candidate model of the comparison.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ModelRow {
    /// The nuisances it adds to the base model, joined by `+` (`base` for none).
    pub name: String,
    /// Its free parameters.
    pub free: Vec<&'static str>,
    /// Chi-square against the measured noise (sum of squared standardised residuals).
    pub chi2: f64,
    /// BIC = chi2 + k ln(n).
    pub bic: f64,
    /// BIC minus the chosen model's (0 for the chosen one).
    pub delta_bic: f64,
    /// Whether this is the model the fit reports.
    pub chosen: bool,
}

/// The outcome of forward selection: the chosen problem and optimum, the nuisances it holds
/// and every model compared.
pub struct Selection {
    /// The chosen model, values set.
    pub problem: TrajectoryProblem,
    /// Its optimum.
    pub p: DVector<f64>,
    /// Nuisances in the chosen model.
    pub chosen: Vec<Nuisance>,
    /// Every model fitted, with the comparison.
    pub rows: Vec<ModelRow>,
    /// Levenberg-Marquardt iterations spent.
    pub iterations: u64,
}

/// Chi-square of a solved model (the solver's cost is half of it).
fn chi2_of(cost: f64) -> f64 {
    2.0 * cost
}

/// Predicted chi-square drops of the screened candidates from one augmented Jacobian per
/// group of columns (the score test): with residuals r and base columns B at the optimum and
/// candidate columns C, drop = (C'r)' S^-1 (C'r) with S = C'C - C'B (B'B)^-1 B'C.
fn score_drops(
    problem: &TrajectoryProblem,
    p: &DVector<f64>,
    candidates: &[Nuisance],
) -> Vec<(Nuisance, f64)> {
    let k = problem.free.len();
    let room = MAX_FREE.saturating_sub(k);
    let mut out = Vec::new();
    let mut group: Vec<Nuisance> = Vec::new();
    let flush = |group: &mut Vec<Nuisance>, out: &mut Vec<(Nuisance, f64)>| {
        if group.is_empty() {
            return;
        }
        let mut aug = problem.clone();
        for n in group.iter() {
            aug.free.extend(n.params());
        }
        let mut q = p.clone().resize_vertically(aug.free.len(), 0.0);
        for (i, &param) in aug.free.iter().enumerate().skip(k) {
            q[i] = problem.get(param);
        }
        if let Ok((r, j)) = aug.residuals_jacobian(&q) {
            let b = j.columns(0, k).into_owned();
            let btb = b.tr_mul(&b);
            if let Some(btb_inv) = btb.try_inverse() {
                let mut col = k;
                for n in group.iter() {
                    let w = n.params().len();
                    let c = j.columns(col, w).into_owned();
                    col += w;
                    let g = c.tr_mul(&r);
                    let bc = b.tr_mul(&c);
                    let s = c.tr_mul(&c) - bc.transpose() * &btb_inv * &bc;
                    let drop = s
                        .try_inverse()
                        .map(|si| (g.transpose() * si * &g)[(0, 0)])
                        .unwrap_or(0.0);
                    out.push((*n, if drop.is_finite() { drop } else { 0.0 }));
                }
            }
        }
        group.clear();
    };
    for &n in candidates {
        if group.iter().map(|g| g.params().len()).sum::<usize>() + n.params().len() > room {
            flush(&mut group, &mut out);
        }
        if n.params().len() <= room {
            group.push(n);
        }
    }
    flush(&mut group, &mut out);
    out
}

/// Settings of the selection.
pub struct SelectOptions {
    /// Try mu_static and Stribeck friction (the data show a stick-to-slide onset).
    pub friction_candidates: bool,
    /// Start value of mu_static for those candidates.
    pub mu_static_start: f64,
    /// Most nuisances added.
    pub max_added: usize,
    /// Most Levenberg-Marquardt iterations per fit.
    pub max_iters: u64,
    /// Nuisances the model holds already (not offered again).
    pub already: Vec<Nuisance>,
}

/// Forward selection from the base model `problem` at its optimum `p` (chi-square `chi2`).
pub fn forward(
    problem: TrajectoryProblem,
    p: DVector<f64>,
    chi2: f64,
    opts: &SelectOptions,
) -> Selection {
    let n = problem.n_rows() as f64;
    let bic = |k: usize, chi2: f64| chi2 + k as f64 * n.ln();
    let name_of = |ns: &[Nuisance]| {
        if ns.is_empty() {
            "base".to_owned()
        } else {
            ns.iter().map(|n| n.name()).collect::<Vec<_>>().join("+")
        }
    };
    let row = |ns: &[Nuisance], m: &TrajectoryProblem, chi2: f64| ModelRow {
        name: name_of(ns),
        free: m.free.iter().map(|q| q.name()).collect(),
        chi2,
        bic: bic(m.free.len(), chi2),
        delta_bic: 0.0,
        chosen: false,
    };
    let mut chosen: Vec<Nuisance> = opts.already.clone();
    let mut current = (problem, p, chi2);
    let mut rows = vec![row(&chosen, &current.0, chi2)];
    let mut iterations = 0;
    for _ in 0..opts.max_added {
        let (cur_problem, cur_p, cur_chi2) = &current;
        let open: Vec<Nuisance> = Nuisance::ALL
            .into_iter()
            .filter(|n| !chosen.contains(n) && !chosen.iter().any(|c| c.conflicts(*n)))
            .filter(|n| cur_problem.free.len() + n.params().len() <= MAX_FREE)
            .filter(|n| n.screened() || opts.friction_candidates)
            .collect();
        if open.is_empty() {
            break;
        }
        let screened: Vec<Nuisance> = open.iter().copied().filter(|n| n.screened()).collect();
        let mut drops = score_drops(cur_problem, cur_p, &screened);
        drops.sort_by(|a, b| b.1.total_cmp(&a.1));
        // Fit the two most promising screened candidates whose predicted drop pays their BIC
        // penalty, and the friction candidates outright.
        let mut to_fit: Vec<Nuisance> = drops
            .iter()
            .filter(|(nu, d)| *d > nu.params().len() as f64 * n.ln())
            .take(2)
            .map(|(n, _)| *n)
            .collect();
        to_fit.extend(open.iter().copied().filter(|n| !n.screened()));
        if to_fit.is_empty() {
            break;
        }
        let fits: Vec<(Nuisance, TrajectoryProblem, Solved)> = to_fit
            .par_iter()
            .with_max_len(1)
            .map(|&nu| {
                let m = nu.add_to(cur_problem, opts.mu_static_start);
                let p0 = m.values();
                let solved = solve(&m, p0, opts.max_iters);
                (nu, m, solved)
            })
            .collect();
        let mut best: Option<(Nuisance, TrajectoryProblem, DVector<f64>, f64)> = None;
        for (nu, m, solved) in fits {
            let Ok((q, cost, iters)) = solved else {
                continue;
            };
            iterations += iters;
            let c2 = chi2_of(cost);
            let mut with = chosen.clone();
            with.push(nu);
            rows.push(row(&with, &m, c2));
            if best
                .as_ref()
                .is_none_or(|b| bic(m.free.len(), c2) < bic(b.1.free.len(), b.3))
            {
                best = Some((nu, m, q, c2));
            }
        }
        let Some((nu, mut m, q, c2)) = best else {
            break;
        };
        // Positive evidence (Kass and Raftery): a BIC lower by more than 2.
        if bic(m.free.len(), c2) < bic(cur_problem.free.len(), *cur_chi2) - 2.0 {
            m.set_values(&q);
            chosen.push(nu);
            current = (m, q, c2);
        } else {
            break;
        }
    }
    let chosen_name = name_of(&chosen);
    let best_bic = bic(current.0.free.len(), current.2);
    for r in &mut rows {
        r.delta_bic = r.bic - best_bic;
        r.chosen = r.name == chosen_name && (r.bic - best_bic).abs() < 1e-9;
    }
    let (problem, p, _) = current;
    Selection {
        problem,
        p,
        chosen,
        rows,
        iterations,
    }
}
