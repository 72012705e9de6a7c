//! The candidate nuisances as data ([`Nuisance`]): what each frees, which ones exclude each
//! other, and how one is added to a model at its neutral value.

use crate::fit::problem::{Param, TrajectoryProblem};
use crate::model::FrictionLaw;

/// mu_kinetic below this while a law carries the friction alone
/// ([`Nuisance::carries_friction_alone`]) is pinned at its bound 0: no coefficient was measured.
pub const MU_PINNED: f64 = 1e-3;

/// Where Stribeck's speed starts when the law is added (m/s).
pub const STRIBECK_START: f64 = 0.05;

/// Stribeck's speed's second start (m/s), for a law just added: from 0.05 m/s alone, fits of
/// a release with slow slides both ways (the heavy slider, v_s 0.02 m/s) fell to a hump at
/// 1-1.6 mm/s, 100-125 above the true law's chi-square, mu_static 30-43 and the speed 60-100
/// standard errors off; from 0.005, 0.01 or 0.02 m/s each found the true law's optimum.
pub const STRIBECK_SLOW_START: f64 = 0.01;

/// A departure from the ideal rig or camera that a candidate model adds (docs/physics.md, "Real
/// rigs" and "What a camera adds").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Nuisance {
    /// mu_static free above mu_kinetic (Coulomb friction with two coefficients).
    StaticFriction,
    /// Stribeck friction: mu_static and the Stribeck speed free.
    Stribeck,
    /// Friction that differs by sliding direction (the direction law).
    Direction,
    /// Friction growing as a power of the normal force (the load law).
    Load,
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
    /// Bob marker off the rod's line only (across it): unlike the full offset it can join a
    /// camera scale error, which acts through the marker's distance along the rod.
    BobAcross,
    /// Slider marker off the pivot.
    SliderOffset,
    /// A time lag between the two markers' tracks.
    Lag,
    /// A rigid pendulum (a rod with mass, a bob with size) whose build the rig file does not
    /// give: its equivalent length and mass ratio free (docs/physics.md, "The rigid pendulum").
    RigidPendulum,
}

impl Nuisance {
    /// Every candidate, in the order ties are broken.
    pub const ALL: [Nuisance; 13] = [
        Nuisance::RigidPendulum,
        Nuisance::StaticFriction,
        Nuisance::Stribeck,
        Nuisance::Direction,
        Nuisance::Load,
        Nuisance::RailTilt,
        Nuisance::PivotDamping,
        Nuisance::ViscousFriction,
        Nuisance::CameraScale,
        Nuisance::BobOffset,
        Nuisance::BobAcross,
        Nuisance::SliderOffset,
        Nuisance::Lag,
    ];

    /// Name in reports and JSON.
    pub fn name(self) -> &'static str {
        match self {
            Nuisance::StaticFriction => "mu_static",
            Nuisance::Stribeck => "stribeck",
            Nuisance::Direction => "direction",
            Nuisance::Load => "load",
            Nuisance::RailTilt => "rail_tilt",
            Nuisance::PivotDamping => "pivot_damping",
            Nuisance::ViscousFriction => "viscous_friction",
            Nuisance::CameraScale => "camera_scale",
            Nuisance::BobOffset => "bob_marker_offset",
            Nuisance::BobAcross => "bob_marker_across",
            Nuisance::SliderOffset => "slider_marker_offset",
            Nuisance::Lag => "marker_lag",
            Nuisance::RigidPendulum => "rigid_pendulum",
        }
    }

    /// The parameters it frees.
    pub fn params(self) -> &'static [Param] {
        match self {
            Nuisance::StaticFriction => &[Param::MuStatic],
            Nuisance::Stribeck => &[Param::MuStatic, Param::StribeckVelocity],
            Nuisance::Direction => &[Param::FrictionSplit],
            Nuisance::Load => &[Param::LoadExponent],
            Nuisance::RailTilt => &[Param::RailTilt],
            Nuisance::PivotDamping => &[Param::PivotDamping],
            Nuisance::ViscousFriction => &[Param::ViscousFriction],
            Nuisance::CameraScale => &[Param::ScaleError],
            Nuisance::BobOffset => &[Param::BobAlong, Param::BobAcross],
            Nuisance::BobAcross => &[Param::BobAcross],
            Nuisance::SliderOffset => &[Param::SliderDx, Param::SliderDy],
            Nuisance::Lag => &[Param::Lag],
            Nuisance::RigidPendulum => &[Param::PendulumLength, Param::MassRatio],
        }
    }

    /// Whether a score test can screen it: a parameter whose neutral value is an interior
    /// point. mu_static at mu_static = mu_kinetic has a vanishing first-order effect (the slip
    /// then starts with x'' = 0), and Stribeck changes the law: both are fitted outright. The
    /// direction and load laws are screened: their neutral values (no split, exponent 1) are
    /// interior, and the law's effect is first order there.
    pub(super) fn screened(self) -> bool {
        !matches!(self, Nuisance::StaticFriction | Nuisance::Stribeck)
    }

    /// Whether a model holding `self` cannot take `other`: camera scale and the bob marker's
    /// distance along the rod act through their product; Stribeck contains mu_static, so
    /// mu_static is not offered on top of it (Stribeck on top of mu_static replaces it:
    /// [`Nuisance::supersedes`]); the full bob offset contains the offset across the rod; a
    /// rig has one friction law (Stribeck, direction or load).
    pub(crate) fn conflicts(self, other: Nuisance) -> bool {
        use Nuisance::*;
        matches!(
            (self, other),
            (CameraScale, BobOffset)
                | (BobOffset, CameraScale)
                | (Stribeck, StaticFriction)
                | (BobOffset, BobAcross)
                | (BobAcross, BobOffset)
        ) || (self != other && self.is_law() && other.is_law())
    }

    /// Whether it is a friction law of its own ([`FrictionLaw`] other than Coulomb's): a rig
    /// holds one.
    pub fn is_law(self) -> bool {
        self.law().is_some()
    }

    /// The friction law it puts in the model, if it is one.
    pub fn law(self) -> Option<FrictionLaw> {
        match self {
            Nuisance::Stribeck => Some(FrictionLaw::Stribeck),
            Nuisance::Direction => Some(FrictionLaw::Direction),
            Nuisance::Load => Some(FrictionLaw::Load),
            _ => None,
        }
    }

    /// The nuisance this one replaces when added: Stribeck friction generalises mu_static.
    pub(super) fn supersedes(self) -> Option<Nuisance> {
        (self == Nuisance::Stribeck).then_some(Nuisance::StaticFriction)
    }

    /// Parameters it adds to each simulation of a model that frees those `frees` says.
    pub(super) fn new_params(self, frees: impl Fn(Param) -> bool) -> usize {
        self.params().iter().filter(|&&q| !frees(q)).count()
    }

    /// `chosen` with this nuisance added (and what it supersedes removed).
    pub(super) fn join(self, chosen: &[Nuisance]) -> Vec<Nuisance> {
        let mut out: Vec<Nuisance> = chosen
            .iter()
            .copied()
            .filter(|&c| Some(c) != self.supersedes())
            .collect();
        out.push(self);
        out
    }

    /// Whether it describes the rail's friction (a law of its own, static above kinetic or
    /// viscous friction): the laws weighed outright on the chosen model's other nuisances.
    pub fn is_friction(self) -> bool {
        self.is_law() || matches!(self, Nuisance::StaticFriction | Nuisance::ViscousFriction)
    }

    /// Whether it can carry the rail's friction with mu_kinetic at 0 (Stribeck's law through
    /// mu_static, viscous friction through its coefficient): a fit that leaves mu_kinetic below
    /// [`MU_PINNED`] with it has measured no friction coefficient.
    pub fn carries_friction_alone(self) -> bool {
        matches!(self, Nuisance::Stribeck | Nuisance::ViscousFriction)
    }

    /// `problem` with this nuisance added at its neutral value (mu_static from `mu_static`).
    pub(super) fn add_to(self, problem: &TrajectoryProblem, mu_static: f64) -> TrajectoryProblem {
        let mut m = problem.clone();
        self.set_law(&mut m);
        for &q in self.params() {
            if !m.free.contains(&q) {
                m.free.push(q);
            }
        }
        if self.params().contains(&Param::MuStatic) && !problem.free.contains(&Param::MuStatic) {
            m.tie_static = false;
            m.rig.mu_static = mu_static.max(m.rig.mu_kinetic * 1.02);
        }
        m
    }

    /// `m`'s friction law made this law's (a law nuisance) at its neutral value; nothing for
    /// the other nuisances. The law's parameters act only under its own law: scored under
    /// Coulomb's, the direction and load laws' columns were zero and their predicted drops 0.
    pub(super) fn set_law(self, m: &mut TrajectoryProblem) {
        match self {
            Nuisance::Stribeck => {
                m.rig.friction_law = FrictionLaw::Stribeck;
                m.rig.stribeck_velocity = STRIBECK_START;
            }
            // At the neutral values, where the law is Coulomb's bit for bit.
            Nuisance::Direction => {
                m.rig.friction_law = FrictionLaw::Direction;
                m.rig.kinetic_split = 0.0;
                m.rig.static_split = 0.0;
            }
            Nuisance::Load => {
                m.rig.friction_law = FrictionLaw::Load;
                m.rig.load_exponent = 1.0;
            }
            _ => {}
        }
    }
}

/// `problem` with its friction back at Coulomb's law with one coefficient and no viscous
/// friction: mu_static tied to mu_kinetic, the law's parameters no longer free and at their
/// neutral values. Every other value stays where it is (a warm start for the laws weighed on
/// the chosen model's other nuisances).
pub(super) fn coulomb_of(problem: &TrajectoryProblem) -> TrajectoryProblem {
    let mut m = problem.clone();
    let law_params = [
        Param::MuStatic,
        Param::StribeckVelocity,
        Param::FrictionSplit,
        Param::LoadExponent,
        Param::ViscousFriction,
    ];
    m.free.retain(|q| !law_params.contains(q));
    m.rig.friction_law = FrictionLaw::Coulomb;
    m.rig.kinetic_split = 0.0;
    m.rig.static_split = 0.0;
    m.rig.load_exponent = 1.0;
    m.rig.viscous_friction = 0.0;
    m.tie_static = true;
    m.rig.mu_static = m.rig.mu_kinetic;
    m
}
