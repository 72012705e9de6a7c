//! The rigid pendulum the data found (the `rigid_pendulum` nuisance), in quantities a lab can
//! check against its pendulum: its own file because the delta method over (L, r') is
//! self-contained and only the report reads it.

use super::estimate::Estimate;
use super::problem::{idx, Param, TrajectoryProblem};
use crate::model::Rig;
use nalgebra::DMatrix;

/// A value with its standard error.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct ValueSe {
    /// The value.
    pub value: f64,
    /// Its standard error (delta method from the fitted parameters' covariance).
    pub stderr: f64,
}

/// What the fit found of a rigid pendulum the rig file did not give (the `rigid_pendulum`
/// nuisance), in quantities a lab can check against its pendulum. The data fix L and r'; the
/// masses follow from the rig file's total mass, taken as slider_mass + bob_mass (a rod's
/// mass missing there scales m_e, J and d by the same factor).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct PendulumFound {
    /// Equivalent length L = J / (m_p d) (m): the simple pendulum with the same period.
    pub equivalent_length: ValueSe,
    /// Equivalent mass ratio r' = (m1 + m_p - m_e) / m_e.
    pub mass_ratio: ValueSe,
    /// Equivalent bob mass m_e = (m_p d)^2 / J (kg), from the total mass.
    pub equivalent_bob_mass: ValueSe,
    /// Moment of inertia about the pivot J = m_e L^2 (kg m^2).
    pub inertia: ValueSe,
    /// Radius of gyration about the pivot sqrt(J / m_p) (m), m_p taken as the rig's bob_mass.
    pub radius_of_gyration: ValueSe,
    /// Pivot to the centre of mass d = m_e L / m_p (m), m_p taken as the rig's bob_mass.
    pub com: ValueSe,
    /// The total mass m1 + m_p assumed (kg): the rig file's slider_mass + bob_mass.
    pub total_mass: f64,
    /// The swinging mass m_p assumed (kg): the rig file's bob_mass.
    pub swinging_mass: f64,
}

impl PendulumFound {
    /// From L and r' with their covariance `cov` ([[var L, cov], [cov, var r']]), the total
    /// mass `total` and the swinging mass `m_p`.
    pub fn new(l: f64, r: f64, cov: [[f64; 2]; 2], total: f64, m_p: f64) -> Self {
        // Each derived quantity with its gradient in (L, r'): the delta method.
        let se = |g: [f64; 2]| {
            (g[0] * g[0] * cov[0][0] + 2.0 * g[0] * g[1] * cov[0][1] + g[1] * g[1] * cov[1][1])
                .max(0.0)
                .sqrt()
        };
        let m_e = total / (1.0 + r);
        let dm_e = -total / ((1.0 + r) * (1.0 + r));
        let j = m_e * l * l;
        let dj = [2.0 * m_e * l, dm_e * l * l];
        let k = (j / m_p).sqrt();
        let dk = [dj[0] / (2.0 * k * m_p), dj[1] / (2.0 * k * m_p)];
        let d = m_e * l / m_p;
        let dd = [m_e / m_p, dm_e * l / m_p];
        PendulumFound {
            equivalent_length: ValueSe {
                value: l,
                stderr: se([1.0, 0.0]),
            },
            mass_ratio: ValueSe {
                value: r,
                stderr: se([0.0, 1.0]),
            },
            equivalent_bob_mass: ValueSe {
                value: m_e,
                stderr: se([0.0, dm_e]),
            },
            inertia: ValueSe {
                value: j,
                stderr: se(dj),
            },
            radius_of_gyration: ValueSe {
                value: k,
                stderr: se(dk),
            },
            com: ValueSe {
                value: d,
                stderr: se(dd),
            },
            total_mass: total,
            swinging_mass: m_p,
        }
    }
}

/// What the `rigid_pendulum` nuisance found, when the chosen model frees it.
pub(super) fn pendulum_found(
    problem: &TrajectoryProblem,
    params: &[(Param, Estimate)],
    correlation: &DMatrix<f64>,
    rig_guess: &Rig<f64>,
) -> Option<PendulumFound> {
    let i = idx(problem, Param::PendulumLength)?;
    let j = idx(problem, Param::MassRatio)?;
    let (l, r) = (params[i].1, params[j].1);
    let c = correlation[(i, j)] * l.stderr * r.stderr;
    let cov = [[l.stderr * l.stderr, c], [c, r.stderr * r.stderr]];
    let (total, m_p) = match rig_guess.pendulum {
        Some(p) => (p.slider_mass + p.mass, p.mass),
        None => (
            rig_guess.slider_mass + rig_guess.bob_mass,
            rig_guess.bob_mass,
        ),
    };
    Some(PendulumFound::new(l.value, r.value, cov, total, m_p))
}
