//! Rig parameters (masses, rod, gravity, friction) and their validation, and the rigid
//! pendulum's equivalent point rig (docs/physics.md, "The rigid pendulum"), computed here once.

use super::Scalar;
use thiserror::Error;

/// The load law's exponents a rig may have: polymer contacts show 0.7-0.95; the range leaves room either side without letting |N|^n overflow.
pub const LOAD_EXPONENT_MIN: f64 = 0.3;
/// See [`LOAD_EXPONENT_MIN`].
pub const LOAD_EXPONENT_MAX: f64 = 2.0;

/// A Painleve-Appell rig. Generic over the scalar so the fit can carry derivatives with
/// respect to mu or the rod length through every formula.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rig<T> {
    /// Slider mass of the point rig the dynamics use (kg): m1 for a point pendulum, the
    /// equivalent m1 + m_p - m_e for a rigid one ([`Rig::with_rigid_pendulum`]).
    pub slider_mass: T,
    /// Bob mass of the point rig the dynamics use (kg): m2, or the equivalent m_e.
    pub bob_mass: T,
    /// Rod length of the point rig the dynamics use (m): l, or the equivalent length L.
    pub rod_length: T,
    /// Pivot to the bob's centre, where the bob's marker sits (m): the rig file's
    /// `rod_length`. The observation model uses it, the dynamics never do; it equals
    /// `rod_length` for a point pendulum.
    pub marker_length: T,
    /// The rigid pendulum as the rig file gives it (`None`: a point bob on a weightless rod).
    /// For reports and checks only: the dynamics read the equivalent rig above.
    pub pendulum: Option<RigidPendulum>,
    /// Gravity g (m/s^2).
    pub gravity: T,
    /// Kinetic friction coefficient mu_k (used while sliding).
    pub mu_kinetic: T,
    /// Static friction coefficient mu_s >= mu_k (the threshold for leaving stick).
    pub mu_static: T,
    /// Rail tilt alpha (rad); +x runs downhill for alpha > 0 (docs/physics.md, "Real rigs").
    pub rail_tilt: T,
    /// Viscous torque coefficient c_p at the pivot (N m s): a torque -c_p theta' on the rod.
    pub pivot_damping: T,
    /// Viscous rail friction c_v (N s/m): a force -c_v x' on the slider while it slides, with
    /// either friction law.
    pub viscous_friction: T,
    /// How the sliding friction coefficient depends on speed.
    pub friction_law: FrictionLaw,
    /// Stribeck speed v_s (m/s) of [`FrictionLaw::Stribeck`]; unused by the other laws.
    pub stribeck_velocity: T,
    /// Half the difference of the kinetic coefficients by sliding direction,
    /// (mu_k(+x) - mu_k(-x)) / 2, under [`FrictionLaw::Direction`] (zero under the others):
    /// `mu_kinetic` is then the mean of the two directions.
    pub kinetic_split: T,
    /// The same half difference of the static coefficients (`mu_static` their mean).
    pub static_split: T,
    /// Exponent n of [`FrictionLaw::Load`]: |F| = mu N_0 (|N| / N_0)^n with N_0 = (m1 + m2) g,
    /// the static load on a level rail; 1 (Coulomb's law) under the others.
    pub load_exponent: T,
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

/// The rail's dry friction law: how the friction force of a slide, and the most friction a
/// stuck slider can hold, depend on the sliding speed v = |x'|, the sliding direction and the
/// normal force N (docs/physics.md, "Friction laws"). Viscous rail friction (`c_v`) adds to
/// any of them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum FrictionLaw {
    /// |F| = mu_k |N| while sliding, at most mu_s |N| while stuck (mu_s >= mu_k).
    #[default]
    Coulomb,
    /// mu(v) = mu_k + (mu_s - mu_k) exp(-(v / v_s)^2): friction falls from mu_s at rest to mu_k.
    Stribeck,
    /// Coulomb's law with coefficients that differ by sliding direction: mu_k + s d_k while
    /// sliding in direction s, at most mu_s + s d_s while stuck and about to slip toward s
    /// (d_k = [`Rig::kinetic_split`], d_s = [`Rig::static_split`]).
    Direction,
    /// Load-dependent friction (polymer contacts): |F| = mu_k N_0 (|N| / N_0)^n while
    /// sliding, at most mu_s N_0 (|N| / N_0)^n while stuck, with N_0 = (m1 + m2) g; the
    /// coefficient |F| / |N| is mu_k at the static load and falls with load for n < 1.
    Load,
}

impl FrictionLaw {
    /// Every law, in the order reports list them.
    pub const ALL: [FrictionLaw; 4] = [
        FrictionLaw::Coulomb,
        FrictionLaw::Stribeck,
        FrictionLaw::Direction,
        FrictionLaw::Load,
    ];

    /// The law's name in files and reports.
    pub fn name(self) -> &'static str {
        match self {
            FrictionLaw::Coulomb => "coulomb",
            FrictionLaw::Stribeck => "stribeck",
            FrictionLaw::Direction => "direction",
            FrictionLaw::Load => "load",
        }
    }
}

/// The swinging part of a rig as one rigid body hinged at the slider (docs/physics.md, "Rigid
/// pendulum"): what a rig file describes when the rod has mass or the bob has size. Only
/// [`Rig::with_rigid_pendulum`] turns it into dynamics, through the equivalent point rig.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RigidPendulum {
    /// Slider mass m1 as weighed (kg).
    pub slider_mass: f64,
    /// Mass m_p of everything that swings (kg).
    pub mass: f64,
    /// Pivot to the pendulum's centre of mass, d (m).
    pub com: f64,
    /// Moment of inertia about the pivot, J (kg m^2).
    pub inertia: f64,
    /// Pivot to the bob's centre, l, where the bob's marker sits (m).
    pub marker_length: f64,
}

impl RigidPendulum {
    /// Whether the pendulum is a point bob on a massless rod (all its mass at the marker,
    /// J = m_p l^2 to rounding): a rig file that writes out `rod_mass = 0` and
    /// `bob_radius = 0` says the pendulum is known, not that it is rigid.
    pub fn is_point(&self) -> bool {
        let l = self.marker_length;
        (self.com - l).abs() <= 1e-12 * l
            && (self.inertia - self.mass * l * l).abs() <= 1e-12 * self.mass * l * l
    }

    /// A uniform rod of mass `rod_mass` from the pivot to the bob's centre (length `l`) and a
    /// solid sphere bob of mass `bob_mass` and radius `radius` centred at `l`:
    /// m_p = m2 + m_r, m_p d = m2 l + m_r l / 2, J = m2 (l^2 + 2 R^2 / 5) + m_r l^2 / 3.
    pub fn rod_and_sphere(
        slider_mass: f64,
        bob_mass: f64,
        rod_mass: f64,
        radius: f64,
        l: f64,
    ) -> Self {
        let mass = bob_mass + rod_mass;
        RigidPendulum {
            slider_mass,
            mass,
            com: (bob_mass * l + 0.5 * rod_mass * l) / mass,
            inertia: bob_mass * (l * l + 0.4 * radius * radius) + rod_mass * l * l / 3.0,
            marker_length: l,
        }
    }

    /// The equivalent length L = J / (m_p d): the simple pendulum with the same period.
    pub fn equivalent_length(&self) -> f64 {
        self.inertia / (self.mass * self.com)
    }

    /// The equivalent bob mass m_e = (m_p d)^2 / J (at most m_p).
    pub fn equivalent_bob_mass(&self) -> f64 {
        let mpd = self.mass * self.com;
        mpd * mpd / self.inertia
    }

    /// The equivalent slider mass m1 + m_p - m_e.
    pub fn equivalent_slider_mass(&self) -> f64 {
        self.slider_mass + self.mass - self.equivalent_bob_mass()
    }

    /// The mass ratio m1 / m_p of the point rig with the same masses (everything that swings
    /// at the bob), whose mu* a rigid rig is compared with.
    pub fn point_mass_ratio(&self) -> f64 {
        self.slider_mass / self.mass
    }
}

/// The pendulum keys of a rig file (scene, rig and plan files alike), in either form: the
/// rod-and-sphere form (`bob_mass`, optional `rod_mass` and `bob_radius`) or the general
/// rigid body (`pendulum_mass`, `pendulum_com`, `pendulum_inertia`). [`PendulumKeys::rig`]
/// checks them and builds the rig, so every file reads them by the same rules.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PendulumKeys {
    /// `bob_mass` (kg).
    pub bob_mass: Option<f64>,
    /// `rod_mass` (kg, a uniform rod from the pivot to the bob's centre; default 0).
    pub rod_mass: Option<f64>,
    /// `bob_radius` (m, a solid sphere; default 0).
    pub bob_radius: Option<f64>,
    /// `pendulum_mass` (kg, everything that swings).
    pub pendulum_mass: Option<f64>,
    /// `pendulum_com` (m, pivot to the centre of mass).
    pub pendulum_com: Option<f64>,
    /// `pendulum_inertia` (kg m^2, about the pivot).
    pub pendulum_inertia: Option<f64>,
}

impl PendulumKeys {
    /// The validated rig with slider mass `m1`, pivot-to-bob-centre distance `l`, gravity
    /// `g` and friction `mu_kinetic`, `mu_static`; a point pendulum (no rod mass, no radius)
    /// gives exactly [`Rig::new`]'s rig.
    pub fn rig(
        &self,
        m1: f64,
        l: f64,
        g: f64,
        mu_kinetic: f64,
        mu_static: Option<f64>,
    ) -> Result<Rig<f64>, RigError> {
        let point = [
            ("bob_mass", self.bob_mass),
            ("rod_mass", self.rod_mass),
            ("bob_radius", self.bob_radius),
        ];
        let body = [
            ("pendulum_mass", self.pendulum_mass),
            ("pendulum_com", self.pendulum_com),
            ("pendulum_inertia", self.pendulum_inertia),
        ];
        let given =
            |keys: &[(&'static str, Option<f64>)]| keys.iter().find(|k| k.1.is_some()).map(|k| k.0);
        if let (Some(point), Some(body)) = (given(&point), given(&body)) {
            return Err(RigError::MixedPendulum { point, body });
        }
        let bad = |key, expected: &str, value| RigError::Pendulum {
            key,
            expected: expected.to_owned(),
            value,
        };
        let p = if given(&body).is_some() {
            let need = |key: &'static str, v: Option<f64>| -> Result<f64, RigError> {
                let v = v.ok_or(RigError::Missing { key })?;
                if v.is_finite() && v > 0.0 {
                    Ok(v)
                } else {
                    Err(RigError::NotPositive { key, value: v })
                }
            };
            let mass = need("pendulum_mass", self.pendulum_mass)?;
            let com = need("pendulum_com", self.pendulum_com)?;
            let inertia = need("pendulum_inertia", self.pendulum_inertia)?;
            if l.is_finite() && l > 0.0 && com > 2.0 * l {
                return Err(bad(
                    "pendulum_com",
                    &format!("at most twice rod_length ({})", 2.0 * l),
                    com,
                ));
            }
            let least = mass * com * com;
            // No body has J below m d^2 (all its mass at the centre of mass); a last-digit
            // rounding of a point pendulum's J = m l^2 is allowed.
            if inertia < least * (1.0 - 1e-12) {
                return Err(bad(
                    "pendulum_inertia",
                    &format!("at least pendulum_mass * pendulum_com^2 = {least}"),
                    inertia,
                ));
            }
            RigidPendulum {
                slider_mass: m1,
                mass,
                com,
                inertia,
                marker_length: l,
            }
        } else {
            let m2 = self.bob_mass.ok_or(RigError::Missing { key: "bob_mass" })?;
            for (key, v) in [("rod_mass", self.rod_mass), ("bob_radius", self.bob_radius)] {
                if let Some(v) = v {
                    if !(v.is_finite() && v >= 0.0) {
                        return Err(RigError::Negative { key, value: v });
                    }
                }
            }
            let (m_r, radius) = (self.rod_mass.unwrap_or(0.0), self.bob_radius.unwrap_or(0.0));
            if l.is_finite() && radius >= l {
                return Err(bad(
                    "bob_radius",
                    &format!("smaller than rod_length ({l})"),
                    radius,
                ));
            }
            if m_r == 0.0 && radius == 0.0 {
                // The point rig, bit for bit: nothing is computed from it. Zeros written
                // out still say the pendulum is known (the fit then does not look for one).
                let mut rig = Rig::new(m1, m2, l, g, mu_kinetic, mu_static)?;
                if self.rod_mass.is_some() || self.bob_radius.is_some() {
                    rig.pendulum = Some(RigidPendulum::rod_and_sphere(m1, m2, 0.0, 0.0, l));
                }
                return Ok(rig);
            }
            RigidPendulum::rod_and_sphere(m1, m2, m_r, radius, l)
        };
        Ok(Rig::new(m1, p.mass, l, g, mu_kinetic, mu_static)?.with_rigid_pendulum(p))
    }
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
    /// Keys of the two descriptions of the pendulum mixed in one rig.
    #[error("rig.{point} and rig.{body} describe the pendulum in two ways: give bob_mass (with rod_mass and bob_radius if they are not zero) or pendulum_mass, pendulum_com and pendulum_inertia")]
    MixedPendulum {
        /// A key of the rod-and-sphere form.
        point: &'static str,
        /// A key of the general rigid-body form.
        body: &'static str,
    },
    /// A pendulum value no body can have, with what it must be.
    #[error("rig.{key} must be {expected}, got {value}")]
    Pendulum {
        /// Scene key of the parameter.
        key: &'static str,
        /// What the value must be.
        expected: String,
        /// The offending value.
        value: f64,
    },
    /// A value of a rigid pendulum's equivalent point rig (docs/physics.md, "The rigid pendulum") that
    /// is not finite and positive: it is computed from several keys, which the message names,
    /// so no single key is blamed for it.
    #[error("the pendulum's equivalent {what} (computed from rig.slider_mass and the pendulum's keys: bob_mass, rod_mass, bob_radius or pendulum_mass, pendulum_com, pendulum_inertia) must be a finite positive number, got {value}")]
    Equivalent {
        /// Which value: `slider mass m1 + m_p - m_e`, `bob mass m_e` or `length L`.
        what: &'static str,
        /// The value computed.
        value: f64,
    },
    /// A value of the direction or load law outside its range.
    #[error("rig.{key} must be {expected}, got {value}")]
    Law {
        /// Scene key of the value (or what it is, when computed).
        key: &'static str,
        /// What the value must be.
        expected: String,
        /// The offending value.
        value: f64,
    },
    /// Keys of a friction law given with another law.
    #[error("rig.{key} is only used with rig.friction_law = \"{law}\"")]
    KeyWithoutLaw {
        /// The key given.
        key: &'static str,
        /// The law it belongs to.
        law: &'static str,
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
            marker_length: rod_length,
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
            marker_length: 0.3,
            pendulum: None,
            gravity: 9.81,
            mu_kinetic: mu,
            mu_static: mu,
            rail_tilt: 0.0,
            pivot_damping: 0.0,
            viscous_friction: 0.0,
            friction_law: FrictionLaw::Coulomb,
            stribeck_velocity: 1.0,
            kinetic_split: 0.0,
            static_split: 0.0,
            load_exponent: 1.0,
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

    /// The same rig with direction-dependent friction: `mu_kinetic` and `mu_static` become
    /// the means of the two directions, and sliding toward +x meets them plus `kinetic_split`
    /// and `static_split`, toward -x minus them.
    pub fn with_direction_split(self, kinetic_split: f64, static_split: f64) -> Self {
        Rig {
            friction_law: FrictionLaw::Direction,
            kinetic_split,
            static_split,
            ..self
        }
    }

    /// The same rig with load-dependent friction of exponent `n` (mu_kinetic and mu_static
    /// are the coefficients at the static load (m1 + m2) g).
    pub fn with_load_exponent(self, n: f64) -> Self {
        Rig {
            friction_law: FrictionLaw::Load,
            load_exponent: n,
            ..self
        }
    }

    /// The same rig with the rigid pendulum `p` (docs/physics.md, "The rigid pendulum"): the dynamics
    /// take the equivalent point rig (slider m1 + m_p - m_e, bob m_e, rod L), computed here and
    /// nowhere else, and the bob's marker stays at the bob's centre, `p.marker_length`. Its
    /// energy is the rigid body's (m_e L = m_p d, m_e L^2 = J).
    pub fn with_rigid_pendulum(self, p: RigidPendulum) -> Self {
        Rig {
            slider_mass: p.equivalent_slider_mass(),
            bob_mass: p.equivalent_bob_mass(),
            rod_length: p.equivalent_length(),
            marker_length: p.marker_length,
            pendulum: Some(p),
            ..self
        }
    }

    /// Check every parameter, naming the first bad one by its scene key.
    pub fn validate(&self) -> Result<(), RigError> {
        if self.pendulum.is_some() {
            // The dynamics' masses and length are the equivalent point rig's, computed from
            // several keys: a bad one is named as what it is, not as `rig.slider_mass`.
            for (what, value) in [
                ("slider mass m1 + m_p - m_e", self.slider_mass),
                ("bob mass m_e", self.bob_mass),
                ("length L", self.rod_length),
            ] {
                if !(value.is_finite() && value > 0.0) {
                    return Err(RigError::Equivalent { what, value });
                }
            }
        }
        for (key, value) in [
            ("slider_mass", self.slider_mass),
            ("bob_mass", self.bob_mass),
            ("rod_length", self.rod_length),
            ("gravity", self.gravity),
            ("rod_length", self.marker_length),
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
        self.validate_law()
    }

    /// The checks of the direction and load laws' own values (also applied by
    /// `scene::check_rig` to the values a fit computed).
    pub(crate) fn validate_law(&self) -> Result<(), RigError> {
        let law = |key, expected: &str, value| RigError::Law {
            key,
            expected: expected.to_owned(),
            value,
        };
        match self.friction_law {
            FrictionLaw::Direction => {
                for (key, v) in [
                    ("kinetic split", self.kinetic_split),
                    ("static split", self.static_split),
                ] {
                    if !v.is_finite() {
                        return Err(law(key, "finite", v));
                    }
                }
                // Each direction's coefficients: both >= 0, static >= kinetic.
                for s in [1.0, -1.0] {
                    let (k, st) = (
                        self.mu_kinetic + s * self.kinetic_split,
                        self.mu_static + s * self.static_split,
                    );
                    let key = if s > 0.0 {
                        "mu_kinetic_positive"
                    } else {
                        "mu_kinetic_negative"
                    };
                    if k < 0.0 {
                        return Err(law(key, ">= 0", k));
                    }
                    if st < k {
                        let key = if s > 0.0 {
                            "mu_static_positive"
                        } else {
                            "mu_static_negative"
                        };
                        return Err(law(key, &format!(">= the kinetic coefficient {k}"), st));
                    }
                }
            }
            FrictionLaw::Load => {
                let n = self.load_exponent;
                if !(n.is_finite() && (LOAD_EXPONENT_MIN..=LOAD_EXPONENT_MAX).contains(&n)) {
                    return Err(law(
                        "load_exponent",
                        &format!("between {LOAD_EXPONENT_MIN} and {LOAD_EXPONENT_MAX}"),
                        n,
                    ));
                }
            }
            FrictionLaw::Coulomb | FrictionLaw::Stribeck => {}
        }
        Ok(())
    }

    /// The same rig in another scalar type (derivative parts zero).
    pub fn lift<T: Scalar>(&self) -> Rig<T> {
        Rig {
            slider_mass: T::from(self.slider_mass),
            bob_mass: T::from(self.bob_mass),
            rod_length: T::from(self.rod_length),
            marker_length: T::from(self.marker_length),
            pendulum: self.pendulum,
            gravity: T::from(self.gravity),
            mu_kinetic: T::from(self.mu_kinetic),
            mu_static: T::from(self.mu_static),
            rail_tilt: T::from(self.rail_tilt),
            pivot_damping: T::from(self.pivot_damping),
            viscous_friction: T::from(self.viscous_friction),
            friction_law: self.friction_law,
            stribeck_velocity: T::from(self.stribeck_velocity),
            kinetic_split: T::from(self.kinetic_split),
            static_split: T::from(self.static_split),
            load_exponent: T::from(self.load_exponent),
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
            marker_length: self.marker_length.re(),
            pendulum: self.pendulum,
            gravity: self.gravity.re(),
            mu_kinetic: self.mu_kinetic.re(),
            mu_static: self.mu_static.re(),
            rail_tilt: self.rail_tilt.re(),
            pivot_damping: self.pivot_damping.re(),
            viscous_friction: self.viscous_friction.re(),
            friction_law: self.friction_law,
            stribeck_velocity: self.stribeck_velocity.re(),
            kinetic_split: self.kinetic_split.re(),
            static_split: self.static_split.re(),
            load_exponent: self.load_exponent.re(),
        }
    }

    /// Whether the rig is the ideal one of the paper (level rail, no damping, Coulomb friction
    /// with no speed dependence): the closed forms that assume it (the conservative pendulum,
    /// mirror symmetry) hold only then.
    pub fn is_ideal(&self) -> bool {
        self.rail_tilt.is_exact_zero()
            && self.pivot_damping.is_exact_zero()
            && self.viscous_friction.is_exact_zero()
            && self.friction_is_symmetric_coulomb()
    }

    /// Whether the friction law acts as Coulomb's with one coefficient in both directions at
    /// every load: Coulomb's law; Stribeck's with mu_s = mu_k; the direction law with no
    /// split; the load law at exponent 1.
    pub fn friction_is_symmetric_coulomb(&self) -> bool {
        match self.friction_law {
            FrictionLaw::Coulomb => true,
            FrictionLaw::Stribeck => self.mu_static == self.mu_kinetic,
            FrictionLaw::Direction => {
                self.kinetic_split.re() == 0.0 && self.static_split.re() == 0.0
            }
            FrictionLaw::Load => self.load_exponent.re() == 1.0,
        }
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
            let (s, c) = self.rail_tilt.sine_cosine();
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

    /// Mass ratio r = m1 / m2 that sets the critical friction: for a rigid pendulum the
    /// equivalent r' = (m1 + m_p - m_e) / m_e (docs/physics.md, "The rigid pendulum").
    pub fn mass_ratio(&self) -> T {
        self.slider_mass / self.bob_mass
    }
}
