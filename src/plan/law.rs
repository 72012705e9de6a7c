//! The friction laws a plan weighs, their reference departures from Coulomb's law, and what a
//! fit's JSON says about them: the vocabulary the plan file, the earlier fit's prior and the
//! law criterion ([`super::discriminate`]) share, kept below all three.

use crate::fit::Param;
use crate::model::{FrictionLaw, Rig, State};
use serde::Serialize;

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
/// above kinetic; Stribeck's hump 10 % above kinetic over 0.01 m/s; coefficients 5 % apart
/// by direction (a split of 2.5 % of mu); a load exponent of 0.9.
pub const REFERENCE_STATIC_RATIO: f64 = 1.1;
/// Stribeck speed of the reference departure (m/s): the top of the 1-10 mm/s dry rails
/// show. A slower hump is harder to tell from a static step (it shows only in slower
/// slides); at 0.05 m/s, the value before, a release the planner counted as separating
/// Stribeck's law from static friction left them tied at a true 0.02 m/s.
pub const REFERENCE_STRIBECK_VELOCITY: f64 = 0.01;
/// Half the relative difference of the direction law's coefficients at the reference.
pub const REFERENCE_SPLIT_FRACTION: f64 = 0.025;
/// Load exponent of the reference departure.
pub const REFERENCE_LOAD_EXPONENT: f64 = 0.9;

/// A predicted standard error of one law's parameter from a proposal's recording: at the
/// law's reference departure (or its given values), and, for a law at a reference
/// departure, the smallest and largest over [`DEPARTURE_SCALES`] and the reference.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LawError {
    /// The law.
    pub law: Law,
    /// The parameter.
    pub param: Param,
    /// Its predicted standard error at the reference departure (infinite: not shown).
    pub stderr: f64,
    /// Smallest and largest predicted standard error over the departures; `None` when the
    /// law's values are given (a plan file's or a fit's), not a reference.
    pub range: Option<[f64; 2]>,
    /// Smallest and largest predicted standard error with every friction coefficient of the
    /// law scaled by mu_kinetic one standard deviation lower and higher than the plan's (at
    /// the same departure): a first release leaves mu known to some per cent, and how long
    /// the planned release slides, so what it shows, moves with it. `None` when mu is given
    /// exactly, and on every proposal but a plan's best.
    pub mu_range: Option<[f64; 2]>,
}

impl LawError {
    /// Whether the recording would not pin the parameter down at the reference departure or
    /// at one of the others ([`DEPARTURE_SCALES`]): infinite there, "not shown".
    pub fn hidden_somewhere(&self) -> bool {
        !self.stderr.is_finite() || self.range.is_some_and(|[_, hi]| !hi.is_finite())
    }
}

/// The multiples of the reference departure a proposal's predicted errors are also given at
/// ([`departure_rig`]; with the reference, a factor 2 apart): a law's errors depend on how far
/// it departs from Coulomb's (a larger static step restarts the slider later, a wider split
/// lengthens one way's slides), which a plan cannot know before the release. Half the
/// reference to four times it spans the departures dry rails report: static friction 5-40 %
/// above kinetic, Stribeck speeds 5-40 mm/s, coefficients 2.5-20 % apart by direction, load
/// exponents 0.95-0.6. Sampled, not swept: static friction's errors jump where a slip appears
/// or goes (between the samples, within a fifth of the range on the example's swing, tested).
pub const DEPARTURE_SCALES: [f64; 3] = [0.5, 2.0, 4.0];

/// `rig` with every friction coefficient (mu_kinetic, mu_static and the direction law's
/// splits) multiplied by `factor`: the same law, departing from Coulomb's in the same
/// proportion, at another mu.
pub fn scaled_friction(rig: &Rig<f64>, factor: f64) -> Rig<f64> {
    let mut r = *rig;
    r.mu_kinetic *= factor;
    r.mu_static *= factor;
    r.kinetic_split *= factor;
    r.static_split *= factor;
    r
}

/// The rig under `law` at its reference departure from `base` (whose law's own values are
/// kept when it is that law: a plan file's or a fit's).
pub fn reference_rig(base: &Rig<f64>, law: Law) -> Rig<f64> {
    departure_rig(base, law, 1.0)
}

/// The rig under `law` at `scale` times its reference departure from Coulomb's law (the
/// static step, the Stribeck hump and its speed, the split, one minus the exponent), from
/// `base`; `base`'s own values when it is that law.
pub fn departure_rig(base: &Rig<f64>, law: Law, scale: f64) -> Rig<f64> {
    let mut rig = *base;
    let own = Law::of_rig(base) == law;
    let mu = base.mu_kinetic;
    rig.friction_law = law.friction_law();
    if !own {
        rig.mu_static = mu;
        rig.kinetic_split = 0.0;
        rig.static_split = 0.0;
        rig.load_exponent = 1.0;
        let step = (1.0 + (REFERENCE_STATIC_RATIO - 1.0) * scale) * mu;
        match law {
            Law::Coulomb => {}
            Law::Static => rig.mu_static = step,
            Law::Stribeck => {
                rig.mu_static = step;
                rig.stribeck_velocity = REFERENCE_STRIBECK_VELOCITY * scale;
            }
            Law::Direction => {
                rig.kinetic_split = REFERENCE_SPLIT_FRACTION * scale * mu;
                rig.static_split = rig.kinetic_split;
            }
            Law::Load => rig.load_exponent = 1.0 - (1.0 - REFERENCE_LOAD_EXPONENT) * scale,
        }
    }
    rig
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
                Some((
                    law,
                    r["status"].as_str()?.to_owned(),
                    r["delta_bic"].as_f64(),
                ))
            })
            .collect();
        let i = &v["initial"];
        let initial = (|| {
            Some([
                i["x"].as_f64()?,
                i["theta"].as_f64()?,
                i["x_dot"].as_f64()?,
                i["theta_dot"].as_f64()?,
            ])
        })()
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
            n_residuals: if n_residuals.is_finite() {
                n_residuals.max(0.0)
            } else {
                0.0
            },
        })
    }
}

/// The fit's line for strong evidence (docs/fit.md, "The friction law"): a BIC difference of 6.
pub const STRONG: f64 = 6.0;
