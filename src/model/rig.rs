//! Rig parameters (masses, rod, gravity, friction) and their validation.

use super::Scalar;
use thiserror::Error;

/// (|x'| / v_s)^2 past which the Stribeck hump, e^-(|x'|/v_s)^2 < 2e-22, is left out.
const STRIBECK_TAIL: f64 = 50.0;

/// A Painleve-Appell rig. Generic over the scalar so the fit can carry derivatives with
/// respect to mu or the rod length through every formula.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rig<T> {
    /// Slider mass m1 (kg).
    pub slider_mass: T,
    /// Bob mass m2 (kg).
    pub bob_mass: T,
    /// Rod length l (m).
    pub rod_length: T,
    /// Gravity g (m/s^2).
    pub gravity: T,
    /// Kinetic friction coefficient mu_k (used while sliding).
    pub mu_kinetic: T,
    /// Static friction coefficient mu_s >= mu_k (the threshold for leaving stick).
    pub mu_static: T,
    /// Rail tilt alpha (rad); +x runs downhill for alpha > 0 (PHYSICS.md, "Real rigs").
    pub rail_tilt: T,
    /// Viscous torque coefficient c_p at the pivot (N m s): a torque -c_p theta' on the rod.
    pub pivot_damping: T,
    /// Viscous rail friction c_v (N s/m): a force -c_v x' on the slider while it slides, with
    /// either friction law.
    pub viscous_friction: T,
    /// How the sliding friction coefficient depends on speed.
    pub friction_law: FrictionLaw,
    /// Stribeck speed v_s (m/s) of [`FrictionLaw::Stribeck`]; unused by Coulomb's law.
    pub stribeck_velocity: T,
}

/// Factors of the real-rig terms that depend only on the rig, computed once per run
/// ([`Rig::constants`]) because the right-hand side and the guards would otherwise repeat a
/// tilt's sine and cosine and three divisions on every evaluation. One place computes them;
/// the model's functions take them from here.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RigConstants<T> {
    /// g_x = g sin(alpha): gravity along the rail (downhill +x).
    pub gx: T,
    /// g_y = g cos(alpha): gravity across the rail.
    pub gy: T,
    /// c_p / (m2 l): the pivot damping's part of A per unit theta'.
    pub damping_drive: T,
    /// (m1 + m2) c_p / l: the pivot damping's part of Q per unit theta' cos(theta).
    pub damping_normal: T,
    /// 1 / v_s under Stribeck's law (zero under Coulomb's, where v_s is not used).
    pub inverse_stribeck_velocity: T,
}

/// How the friction coefficient of a slide depends on the slider's speed v = |x'|.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum FrictionLaw {
    /// mu(v) = mu_k at every speed.
    #[default]
    Coulomb,
    /// mu(v) = mu_k + (mu_s - mu_k) exp(-(v / v_s)^2): friction falls from mu_s at rest to mu_k.
    Stribeck,
}

/// A rig parameter outside its physical range, named by its scene key.
#[derive(Debug, Error, PartialEq)]
pub enum RigError {
    /// A parameter that must be finite and positive is not.
    #[error("rig.{key} must be a finite positive number, got {value}")]
    NotPositive {
        /// Scene key of the parameter.
        key: &'static str,
        /// The offending value.
        value: f64,
    },
    /// A friction coefficient that must be finite and non-negative is not.
    #[error("rig.{key} must be a finite number >= 0, got {value}")]
    Negative {
        /// Scene key of the parameter.
        key: &'static str,
        /// The offending value.
        value: f64,
    },
    /// A required parameter is missing.
    #[error("rig.{key} is missing")]
    Missing {
        /// Scene key of the parameter.
        key: &'static str,
    },
    /// A rail tilt of 90 degrees or more (the rail would not be below the rig).
    #[error("rig.rail_tilt_deg must be a finite angle strictly between -90 and 90, got {value}")]
    Tilt {
        /// The tilt given (degrees).
        value: f64,
    },
    /// A Stribeck speed given for Coulomb's law, where it would be silently ignored.
    #[error("rig.stribeck_velocity is only used with rig.friction_law = \"stribeck\"")]
    StribeckWithoutLaw,
    /// Static friction below kinetic friction.
    #[error("rig.mu_static ({mu_static}) must be >= rig.mu_kinetic ({mu_kinetic})")]
    StaticBelowKinetic {
        /// The static coefficient given.
        mu_static: f64,
        /// The kinetic coefficient given.
        mu_kinetic: f64,
    },
}

impl Rig<f64> {
    /// A validated rig; `mu_static` defaults to `mu_kinetic`.
    pub fn new(
        slider_mass: f64,
        bob_mass: f64,
        rod_length: f64,
        gravity: f64,
        mu_kinetic: f64,
        mu_static: Option<f64>,
    ) -> Result<Self, RigError> {
        let rig = Rig {
            slider_mass,
            bob_mass,
            rod_length,
            gravity,
            mu_kinetic,
            mu_static: mu_static.unwrap_or(mu_kinetic),
            ..Rig::paper(0.0)
        };
        rig.validate()?;
        Ok(rig)
    }

    /// The paper's rig: equal masses 0.1 kg, l = 0.30 m, g = 9.81, mu_s = mu_k = `mu`.
    pub fn paper(mu: f64) -> Self {
        Rig {
            slider_mass: 0.1,
            bob_mass: 0.1,
            rod_length: 0.3,
            gravity: 9.81,
            mu_kinetic: mu,
            mu_static: mu,
            rail_tilt: 0.0,
            pivot_damping: 0.0,
            viscous_friction: 0.0,
            friction_law: FrictionLaw::Coulomb,
            stribeck_velocity: 1.0,
        }
    }

    /// The same rig on a rail tilted by `alpha` (rad, +x downhill for alpha > 0).
    pub fn with_rail_tilt(self, alpha: f64) -> Self {
        Rig {
            rail_tilt: alpha,
            ..self
        }
    }

    /// The same rig with viscous damping `c_p` (N m s) at the pivot.
    pub fn with_pivot_damping(self, c_p: f64) -> Self {
        Rig {
            pivot_damping: c_p,
            ..self
        }
    }

    /// The same rig with viscous rail friction `c_v` (N s/m) added to its friction law.
    pub fn with_viscous_friction(self, c_v: f64) -> Self {
        Rig {
            viscous_friction: c_v,
            ..self
        }
    }

    /// The same rig with Stribeck friction of speed `v_s` (m/s) between its mu_s and mu_k.
    pub fn with_stribeck(self, v_s: f64) -> Self {
        Rig {
            friction_law: FrictionLaw::Stribeck,
            stribeck_velocity: v_s,
            ..self
        }
    }

    /// Check every parameter, naming the first bad one by its scene key.
    pub fn validate(&self) -> Result<(), RigError> {
        for (key, value) in [
            ("slider_mass", self.slider_mass),
            ("bob_mass", self.bob_mass),
            ("rod_length", self.rod_length),
            ("gravity", self.gravity),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return Err(RigError::NotPositive { key, value });
            }
        }
        for (key, value) in [
            ("mu_kinetic", self.mu_kinetic),
            ("mu_static", self.mu_static),
        ] {
            if !(value.is_finite() && value >= 0.0) {
                return Err(RigError::Negative { key, value });
            }
        }
        for (key, value) in [
            ("pivot_damping", self.pivot_damping),
            ("viscous_friction", self.viscous_friction),
        ] {
            if !(value.is_finite() && value >= 0.0) {
                return Err(RigError::Negative { key, value });
            }
        }
        if !(self.rail_tilt.is_finite() && self.rail_tilt.abs() < std::f64::consts::FRAC_PI_2) {
            return Err(RigError::Tilt {
                value: self.rail_tilt.to_degrees(),
            });
        }
        if self.friction_law == FrictionLaw::Stribeck
            && !(self.stribeck_velocity.is_finite() && self.stribeck_velocity > 0.0)
        {
            return Err(RigError::NotPositive {
                key: "stribeck_velocity",
                value: self.stribeck_velocity,
            });
        }
        if self.mu_static < self.mu_kinetic {
            return Err(RigError::StaticBelowKinetic {
                mu_static: self.mu_static,
                mu_kinetic: self.mu_kinetic,
            });
        }
        Ok(())
    }

    /// The same rig in another scalar type (derivative parts zero).
    pub fn lift<T: Scalar>(&self) -> Rig<T> {
        Rig {
            slider_mass: T::from(self.slider_mass),
            bob_mass: T::from(self.bob_mass),
            rod_length: T::from(self.rod_length),
            gravity: T::from(self.gravity),
            mu_kinetic: T::from(self.mu_kinetic),
            mu_static: T::from(self.mu_static),
            rail_tilt: T::from(self.rail_tilt),
            pivot_damping: T::from(self.pivot_damping),
            viscous_friction: T::from(self.viscous_friction),
            friction_law: self.friction_law,
            stribeck_velocity: T::from(self.stribeck_velocity),
        }
    }
}

impl<T: Scalar> Rig<T> {
    /// Real parts, for decisions and reports.
    pub fn re(&self) -> Rig<f64> {
        Rig {
            slider_mass: self.slider_mass.re(),
            bob_mass: self.bob_mass.re(),
            rod_length: self.rod_length.re(),
            gravity: self.gravity.re(),
            mu_kinetic: self.mu_kinetic.re(),
            mu_static: self.mu_static.re(),
            rail_tilt: self.rail_tilt.re(),
            pivot_damping: self.pivot_damping.re(),
            viscous_friction: self.viscous_friction.re(),
            friction_law: self.friction_law,
            stribeck_velocity: self.stribeck_velocity.re(),
        }
    }

    /// Whether the rig is the ideal one of the paper (level rail, no damping, Coulomb friction
    /// with no speed dependence): the closed forms that assume it (the conservative pendulum,
    /// mirror symmetry) hold only then.
    pub fn is_ideal(&self) -> bool {
        self.rail_tilt.is_exact_zero()
            && self.pivot_damping.is_exact_zero()
            && self.viscous_friction.is_exact_zero()
            && (self.friction_law == FrictionLaw::Coulomb || self.mu_static == self.mu_kinetic)
    }

    /// True on the seed paper's rig: level rail, no pivot damping, Coulomb friction without a
    /// viscous part. Unlike [`Rig::is_ideal`] a Stribeck law with mu_s = mu_k is not plain,
    /// because its derivative with respect to mu_s is not zero. The simulator tests this once
    /// per mode, not on every right-hand side.
    pub fn is_plain(&self) -> bool {
        self.rail_tilt.is_exact_zero()
            && self.pivot_damping.is_exact_zero()
            && self.viscous_friction.is_exact_zero()
            && self.friction_law == FrictionLaw::Coulomb
    }

    /// Gravity's components (g_x, g_y) in the rail frame: (g sin alpha, g cos alpha). A level
    /// rail skips the trigonometry (and keeps its results bit for bit).
    #[inline(always)]
    pub fn gravity_components(&self) -> (T, T) {
        if self.rail_tilt.is_exact_zero() {
            (T::zero(), self.gravity)
        } else {
            let (s, c) = self.rail_tilt.sin_cos();
            (self.gravity * s, self.gravity * c)
        }
    }

    /// The per-rig factors of the real-rig terms ([`RigConstants`]), for a caller that
    /// evaluates the model many times on one rig.
    #[inline]
    pub fn constants(&self) -> RigConstants<T> {
        let (gx, gy) = self.gravity_components();
        let (m1, m2, l) = (self.slider_mass, self.bob_mass, self.rod_length);
        let c_p = self.pivot_damping;
        RigConstants {
            gx,
            gy,
            damping_drive: c_p / (m2 * l),
            damping_normal: (m1 + m2) * c_p / l,
            inverse_stribeck_velocity: self.inverse_stribeck_velocity(),
        }
    }

    /// 1 / v_s under Stribeck's law, zero under Coulomb's (where v_s is not used).
    #[inline]
    pub fn inverse_stribeck_velocity(&self) -> T {
        match self.friction_law {
            FrictionLaw::Coulomb => T::zero(),
            FrictionLaw::Stribeck => self.stribeck_velocity.recip(),
        }
    }

    /// The sliding friction coefficient at speed `speed` = |x'| under the rig's law.
    #[inline(always)]
    pub fn friction_mu(&self, speed: T) -> T {
        self.friction_mu_on(speed, self.inverse_stribeck_velocity())
    }

    /// [`Rig::friction_mu`] with [`Rig::inverse_stribeck_velocity`] at hand (a caller that
    /// evaluates it many times keeps it in [`RigConstants`]).
    #[inline(always)]
    pub fn friction_mu_on(&self, speed: T, inverse_stribeck_velocity: T) -> T {
        match self.friction_law {
            FrictionLaw::Coulomb => self.mu_kinetic,
            FrictionLaw::Stribeck => {
                let u = speed * inverse_stribeck_velocity;
                let u2 = u * u;
                if u2.re() > STRIBECK_TAIL {
                    // The hump is below e^-50 = 2e-22 of mu_s - mu_k here: mu_k to far
                    // below any friction measurement, without an exp on every evaluation
                    // of a fast slide.
                    return self.mu_kinetic;
                }
                self.mu_kinetic + (self.mu_static - self.mu_kinetic) * (-u2).exp()
            }
        }
    }

    /// The largest coefficient a slide can meet (mu_s for Stribeck, reached as v -> 0): it
    /// decides whether the Painleve paradox is possible.
    pub fn mu_slide_max(&self) -> T {
        match self.friction_law {
            FrictionLaw::Coulomb => self.mu_kinetic,
            FrictionLaw::Stribeck => self.mu_static,
        }
    }

    /// Mass ratio r = m1 / m2 that sets the critical friction.
    pub fn mass_ratio(&self) -> T {
        self.slider_mass / self.bob_mass
    }
}
