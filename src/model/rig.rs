//! Rig parameters (masses, rod, gravity, friction) and their validation.

use super::Scalar;
use thiserror::Error;

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
        }
    }

    /// Mass ratio r = m1 / m2 that sets the critical friction.
    pub fn mass_ratio(&self) -> T {
        self.slider_mass / self.bob_mass
    }
}
