//! Scenes: a TOML file with a rig, an initial state, a run and what the run should produce.
//! Key names are fixed (scripts use them); unknown keys are errors so typos never pass.

use crate::model::Param;
use crate::model::{FrictionLaw, PendulumKeys, Rig, RigError, State};
use crate::sim::{Method, Options, Request, RestRule};
use serde::Deserialize;
use std::io::Read;
use std::path::{Path, PathBuf};
use thiserror::Error;

/// The `[rig]` section. Also a file of its own (`RIG.toml`) for commands that take a rig.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RigSpec {
    /// Slider mass (kg).
    pub slider_mass: f64,
    /// Bob mass (kg); required unless the pendulum is given as `pendulum_mass`,
    /// `pendulum_com` and `pendulum_inertia`.
    pub bob_mass: Option<f64>,
    /// Rod length (m): the pivot to the bob's centre, where the bob's marker is.
    pub rod_length: f64,
    /// Mass of the rod (kg), a uniform rod from the pivot to the bob's centre (default 0).
    pub rod_mass: Option<f64>,
    /// Radius of the bob (m), a solid sphere (default 0).
    pub bob_radius: Option<f64>,
    /// Mass of everything that swings (kg), for a pendulum of any other shape.
    pub pendulum_mass: Option<f64>,
    /// Pivot to the pendulum's centre of mass (m).
    pub pendulum_com: Option<f64>,
    /// The pendulum's moment of inertia about the pivot (kg m^2).
    pub pendulum_inertia: Option<f64>,
    /// Gravity (m/s^2); when left out, [`EARTH_GRAVITY`] (a fit can take Earth's at the lab's
    /// latitude instead, [`normal_gravity`]).
    pub gravity: Option<f64>,
    /// Kinetic friction coefficient (required in scenes; a starting guess in rig files for
    /// fitting, where it may be left out).
    pub mu_kinetic: Option<f64>,
    /// Static friction coefficient (defaults to `mu_kinetic`).
    pub mu_static: Option<f64>,
    /// Rail tilt in degrees, +x downhill for positive values (default 0).
    pub rail_tilt_deg: Option<f64>,
    /// Viscous torque at the pivot, N m s (default 0).
    pub pivot_damping: Option<f64>,
    /// `coulomb` (default), `stribeck`, `direction` or `load` (docs/physics.md, "Friction
    /// laws").
    pub friction_law: Option<FrictionLaw>,
    /// Kinetic coefficient sliding toward +x, under `friction_law = "direction"` (which takes
    /// these four keys instead of `mu_kinetic` and `mu_static`).
    pub mu_kinetic_positive: Option<f64>,
    /// Kinetic coefficient sliding toward -x (direction law).
    pub mu_kinetic_negative: Option<f64>,
    /// Static coefficient holding a slider about to slip toward +x (direction law; default
    /// `mu_kinetic_positive`).
    pub mu_static_positive: Option<f64>,
    /// Static coefficient toward -x (direction law; default `mu_kinetic_negative`).
    pub mu_static_negative: Option<f64>,
    /// Exponent n of `friction_law = "load"`: |F| = mu N_0 (|N| / N_0)^n, N_0 = (m1 + m2) g,
    /// with `mu_kinetic` and `mu_static` the coefficients at N_0.
    pub load_exponent: Option<f64>,
    /// Stribeck speed v_s in m/s (required with `friction_law = "stribeck"`, refused otherwise).
    pub stribeck_velocity: Option<f64>,
    /// Viscous rail friction, N s/m, added to either law (default 0).
    pub viscous_friction: Option<f64>,
    /// Standard deviation of `rod_length` as measured (m); the fit's default is a ruler's
    /// 1 mm, 0 takes the value as exact. Scenes and plans simulate the value as given.
    pub rod_length_sd: Option<f64>,
    /// Standard deviation of `slider_mass` (kg); default 3 % (at least 0.5 g).
    pub slider_mass_sd: Option<f64>,
    /// Standard deviation of `bob_mass` (kg); default 2 % (at least 0.5 g).
    pub bob_mass_sd: Option<f64>,
    /// Standard deviation of `rod_mass` (kg); default 2 % (at least 0.5 g).
    pub rod_mass_sd: Option<f64>,
    /// Standard deviation of `bob_radius` (m); default 0.5 mm.
    pub bob_radius_sd: Option<f64>,
    /// Standard deviation of `gravity` (m/s^2) for the fit; default 0 (held as typed), 0.015
    /// when `gravity` is left out.
    pub gravity_sd: Option<f64>,
}

impl RigSpec {
    /// The rig's gravity: the file's `gravity`, or [`EARTH_GRAVITY`].
    pub fn gravity(&self) -> f64 {
        self.gravity.unwrap_or(EARTH_GRAVITY)
    }

    /// The validated rig.
    pub fn rig(&self) -> Result<Rig<f64>, RigError> {
        let law = self.friction_law.unwrap_or_default();
        let friction = self.friction(law)?;
        let mut rig = self.pendulum_keys().rig(
            self.slider_mass,
            self.rod_length,
            self.gravity(),
            friction.mu_kinetic,
            Some(friction.mu_static),
        )?;
        rig.kinetic_split = friction.kinetic_split;
        rig.static_split = friction.static_split;
        if law == FrictionLaw::Load {
            rig.load_exponent = self.load_exponent.ok_or(RigError::Missing {
                key: "load_exponent",
            })?;
        }
        rig.rail_tilt = self.rail_tilt_deg.unwrap_or(0.0).to_radians();
        rig.pivot_damping = self.pivot_damping.unwrap_or(0.0);
        rig.viscous_friction = self.viscous_friction.unwrap_or(0.0);
        rig.friction_law = self.friction_law.unwrap_or_default();
        match (rig.friction_law, self.stribeck_velocity) {
            (FrictionLaw::Stribeck, Some(v)) => rig.stribeck_velocity = v,
            (FrictionLaw::Stribeck, None) => {
                return Err(RigError::Missing {
                    key: "stribeck_velocity",
                })
            }
            (_, Some(_)) => return Err(RigError::StribeckWithoutLaw),
            (_, None) => {}
        }
        if let Some(deg) = self.rail_tilt_deg {
            if !(deg.is_finite() && deg.abs() < 90.0) {
                return Err(RigError::Tilt { value: deg });
            }
        }
        rig.validate()?;
        Ok(rig)
    }

    /// The validated rig with every range checked, the errors naming `path`: the keys as
    /// written first ([`check_rig_range`]), then the rig built from them, then what was
    /// computed ([`check_rig`]). Scenes, rig files and plans all build their rig here.
    pub fn checked(&self, path: &Path) -> Result<Rig<f64>, SceneError> {
        check_rig_range(path, self)?;
        let rig = self.rig().map_err(|e| SceneError::Invalid {
            path: path.to_owned(),
            message: e.to_string(),
        })?;
        check_rig(path, &rig, RigOrigin::File { friction: "rig" })?;
        Ok(rig)
    }

    /// The friction coefficients of `law` from the keys: the direction law's four keys as
    /// means and half differences, the others' `mu_kinetic` and `mu_static`; keys of another
    /// law are refused rather than ignored.
    fn friction(&self, law: FrictionLaw) -> Result<FrictionKeys, RigError> {
        let direction_keys = [
            ("mu_kinetic_positive", self.mu_kinetic_positive),
            ("mu_kinetic_negative", self.mu_kinetic_negative),
            ("mu_static_positive", self.mu_static_positive),
            ("mu_static_negative", self.mu_static_negative),
        ];
        if law != FrictionLaw::Load && self.load_exponent.is_some() {
            return Err(RigError::KeyWithoutLaw {
                key: "load_exponent",
                law: "load",
            });
        }
        if law != FrictionLaw::Direction {
            if let Some((key, _)) = direction_keys.iter().find(|k| k.1.is_some()) {
                return Err(RigError::KeyWithoutLaw {
                    key,
                    law: "direction",
                });
            }
            let mu_kinetic = self
                .mu_kinetic
                .ok_or(RigError::Missing { key: "mu_kinetic" })?;
            return Ok(FrictionKeys {
                mu_kinetic,
                mu_static: self.mu_static.unwrap_or(mu_kinetic),
                kinetic_split: 0.0,
                static_split: 0.0,
            });
        }
        for (key, v) in [
            ("mu_kinetic", self.mu_kinetic),
            ("mu_static", self.mu_static),
        ] {
            if v.is_some() {
                return Err(RigError::Law {
                    key,
                    expected: "left out under friction_law = \"direction\" (give mu_kinetic_positive and mu_kinetic_negative, and optionally mu_static_positive and mu_static_negative)".into(),
                    value: v.unwrap_or(f64::NAN),
                });
            }
        }
        let need = |key: &'static str, v: Option<f64>| -> Result<f64, RigError> {
            let v = v.ok_or(RigError::Missing { key })?;
            if v.is_finite() && v >= 0.0 {
                Ok(v)
            } else {
                Err(RigError::Negative { key, value: v })
            }
        };
        let kp = need("mu_kinetic_positive", self.mu_kinetic_positive)?;
        let kn = need("mu_kinetic_negative", self.mu_kinetic_negative)?;
        let sp = need("mu_static_positive", self.mu_static_positive.or(Some(kp)))?;
        let sn = need("mu_static_negative", self.mu_static_negative.or(Some(kn)))?;
        for (key, st, k) in [
            ("mu_static_positive", sp, kp),
            ("mu_static_negative", sn, kn),
        ] {
            if st < k {
                return Err(RigError::Law {
                    key,
                    expected: format!(">= the same direction's kinetic coefficient {k}"),
                    value: st,
                });
            }
        }
        Ok(FrictionKeys {
            mu_kinetic: 0.5 * (kp + kn),
            mu_static: 0.5 * (sp + sn),
            kinetic_split: 0.5 * (kp - kn),
            static_split: 0.5 * (sp - sn),
        })
    }

    /// The keys with `mu_guess` wherever a friction coefficient is left out (rig files for
    /// fitting, where friction is only a starting value): `mu_kinetic` and `mu_static`, or
    /// under the direction law its kinetic keys.
    pub fn with_guess(&self, mu_guess: f64) -> RigSpec {
        if self.friction_law == Some(FrictionLaw::Direction) {
            return RigSpec {
                mu_kinetic_positive: self.mu_kinetic_positive.or(Some(mu_guess)),
                mu_kinetic_negative: self.mu_kinetic_negative.or(Some(mu_guess)),
                ..*self
            };
        }
        RigSpec {
            mu_kinetic: Some(self.mu_kinetic.unwrap_or(mu_guess)),
            mu_static: self.mu_static.or(self.mu_kinetic).or(Some(mu_guess)),
            ..*self
        }
    }

    /// The pendulum's keys, in either form.
    pub fn pendulum_keys(&self) -> PendulumKeys {
        PendulumKeys {
            bob_mass: self.bob_mass,
            rod_mass: self.rod_mass,
            bob_radius: self.bob_radius,
            pendulum_mass: self.pendulum_mass,
            pendulum_com: self.pendulum_com,
            pendulum_inertia: self.pendulum_inertia,
        }
    }

    /// The validated rig, with `mu_guess` where mu_kinetic is left out (rig files for fitting:
    /// mu there is only a starting value).
    pub fn rig_or_guess(&self, mu_guess: f64) -> Result<Rig<f64>, RigError> {
        self.with_guess(mu_guess).rig()
    }
}

/// A rig file's friction coefficients as the rig stores them (means and half differences).
struct FrictionKeys {
    mu_kinetic: f64,
    mu_static: f64,
    kinetic_split: f64,
    static_split: f64,
}

/// The `[initial]` section: the state at t = 0 in docs/physics.md's convention (radians, y down).
#[derive(Debug, Clone, Copy, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct InitialSpec {
    /// Slider position (m).
    pub x: f64,
    /// Rod angle from the rail's +x direction, y down (rad): pi/2 hangs straight down.
    pub theta: f64,
    /// Slider velocity (m/s).
    pub x_dot: f64,
    /// Angular velocity (rad/s).
    pub theta_dot: f64,
}

/// The `[run]` section.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RunSpec {
    /// Duration (s).
    pub duration: f64,
    /// Relative tolerance (default 1e-10).
    pub rtol: Option<f64>,
    /// Absolute tolerance (default 1e-12).
    pub atol: Option<f64>,
    /// `dop853` (default) or `dp5`.
    pub method: Option<Method>,
    /// Step limit, accepted and rejected steps together: a whole number from 1 to
    /// [`MAX_STEPS`] (default 1e6). A number rather than an integer so `1e6` may be written.
    pub max_steps: Option<f64>,
    /// Choice at rest where the Painleve paradox allows several motions: `prefer_stick`
    /// (default), `prefer_slide` or `halt`.
    pub rest_rule: Option<RestRule>,
}

/// The optional `[output]` section: what the run should produce besides events and the
/// final state. Nothing here is computed unless asked for.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Default)]
#[serde(deny_unknown_fields)]
pub struct OutputSpec {
    /// Sample the trajectory at this frame rate (Hz).
    pub frame_rate: Option<f64>,
    /// Add marker positions (rail frame, metres, y up) to the samples.
    #[serde(default)]
    pub markers: bool,
    /// Add energy and friction work to the samples (integrates the friction work).
    #[serde(default)]
    pub energy: bool,
}

/// A whole scene file as written.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    /// `[rig]`.
    pub rig: RigSpec,
    /// `[initial]`.
    pub initial: InitialSpec,
    /// `[run]`.
    pub run: RunSpec,
    /// `[output]`.
    #[serde(default)]
    pub output: OutputSpec,
}

/// A validated scene, ready to simulate.
#[derive(Debug, Clone, PartialEq)]
pub struct Scene {
    /// The rig.
    pub rig: Rig<f64>,
    /// State at t = 0.
    pub initial: State<f64>,
    /// Duration (s).
    pub duration: f64,
    /// Integrator options.
    pub options: Options,
    /// What to produce.
    pub output: OutputSpec,
}

/// A scene that cannot be used, with the file and the key at fault.
#[derive(Debug, Error)]
pub enum SceneError {
    /// The file could not be read.
    #[error("{path}: cannot read: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// TOML syntax, a missing or unknown key, or a wrong type (the message names the key and
    /// line).
    #[error("{path}: {message}")]
    Parse {
        /// The file.
        path: PathBuf,
        /// The parser's message with line and key.
        message: String,
    },
    /// A file larger than its kind may be, refused before it is parsed.
    #[error("{path}: {}: expected a file of at most {limit} bytes", too_large(*size, *limit))]
    TooLarge {
        /// The file.
        path: PathBuf,
        /// The most bytes such a file may have.
        limit: u64,
        /// Its size, when the file says it (`None`: a stream, cut after `limit` + 1 bytes).
        size: Option<u64>,
    },
    /// A value outside its range.
    #[error("{path}: {message}")]
    Invalid {
        /// The file.
        path: PathBuf,
        /// What is wrong, naming the key.
        message: String,
    },
}

fn check(path: &Path, ok: bool, key: &str, expected: &str, value: f64) -> Result<(), SceneError> {
    if ok {
        Ok(())
    } else {
        Err(SceneError::Invalid {
            path: path.to_owned(),
            message: format!("{key} must be {expected}, got {value:?}"),
        })
    }
}

/// The size part of [`SceneError::TooLarge`]'s message.
fn too_large(size: Option<u64>, limit: u64) -> String {
    match size {
        Some(size) => format!("the file has {size} bytes"),
        None => format!("more than {limit} bytes read, and it goes on"),
    }
}

/// The largest scene, rig or plan file read, 1 MiB: the shipped ones are under 2 KB. The toml
/// crate parses the whole document before any key is checked, at up to 80 bytes of memory a
/// byte: a 30 MB array of small integers took 15 s and 2.4 GB, a 1 MiB one takes 0.4 s and
/// 84 MB, so a larger file (a runaway generator's) is refused before parsing.
pub const MAX_TOML_BYTES: u64 = 1 << 20;

/// Read a text file of at most `limit` bytes, the error naming the file: shared by scene, rig
/// and plan files ([`MAX_TOML_BYTES`]) and a fit's JSON. A file whose size says it is larger
/// is refused before a byte is read; since devices, pipes and FIFOs say 0 (and a file may
/// grow), at most `limit` + 1 bytes are read, so `/dev/zero` cannot make the read endless.
pub fn read_text(path: &Path, limit: u64) -> Result<String, SceneError> {
    let io = |source| SceneError::Io {
        path: path.to_owned(),
        source,
    };
    let too_large = |size| SceneError::TooLarge {
        path: path.to_owned(),
        limit,
        size,
    };
    let file = std::fs::File::open(path).map_err(io)?;
    let size = file.metadata().map_err(io)?.len();
    if size > limit {
        return Err(too_large(Some(size)));
    }
    let mut bytes = Vec::new();
    file.take(limit + 1).read_to_end(&mut bytes).map_err(io)?;
    if bytes.len() as u64 > limit {
        return Err(too_large(None));
    }
    String::from_utf8(bytes)
        .map_err(|e| io(std::io::Error::new(std::io::ErrorKind::InvalidData, e)))
}

/// Parse TOML into `F`; the error names the file, and the parser's message the key and line
/// (unknown keys included, with `deny_unknown_fields`).
pub fn parse_toml<F: serde::de::DeserializeOwned>(
    text: &str,
    path: &Path,
) -> Result<F, SceneError> {
    toml::from_str(text).map_err(|e| SceneError::Parse {
        path: path.to_owned(),
        message: match placeholder(text) {
            // The parser's own words ("invalid string") do not say what to do.
            Some((line, key, value)) => format!(
                "line {line}: {key} = {value} is a template's placeholder, still to fill in: {}",
                placeholder_fix(&value)
            ),
            None => e.to_string().trim_end().to_owned(),
        },
    })
}

/// The placeholders a rig template (`appell inspect FILE --rig-template RIG.toml`) leaves for
/// the lab to fill in, with what each asks for: upper case, as in the commands `inspect`
/// prints. They are not TOML values, so a file still holding one is refused, naming it.
pub const RIG_PLACEHOLDERS: [(&str, &str); 3] = [
    (
        "SLIDER_KG",
        "the slider's mass in kilograms, with its pivot and whatever rides on it, as weighed (306 g is 0.306)",
    ),
    (
        "BOB_KG",
        "the bob's mass in kilograms, as weighed (147 g is 0.147)",
    ),
    (
        "METRES",
        "the rod's length in metres, from the pivot's axis to the bob's centre, as measured (25.1 cm is 0.251)",
    ),
];

/// What a placeholder asks for.
fn placeholder_fix(value: &str) -> String {
    RIG_PLACEHOLDERS
        .iter()
        .find(|(name, _)| *name == value)
        .map_or("write a number in its place".to_owned(), |(_, what)| {
            format!("write {what}")
        })
}

/// The first line holding `key = PLACEHOLDER` (an upper-case word, which no TOML value is), as
/// its line number, key and word.
fn placeholder(text: &str) -> Option<(usize, String, String)> {
    text.lines().enumerate().find_map(|(i, line)| {
        let code = line.split('#').next().unwrap_or("");
        let (key, value) = code.split_once('=')?;
        let (key, value) = (key.trim(), value.trim());
        let word = value.starts_with(|c: char| c.is_ascii_uppercase())
            && value
                .chars()
                .all(|c| c.is_ascii_uppercase() || c.is_ascii_digit() || c == '_');
        word.then(|| (i + 1, key.to_owned(), value.to_owned()))
    })
}

/// A rig file's keys written before any section (the `[rig]` line left out): the parser would
/// call the first one an unknown section. The key and its line.
fn missing_rig_header(text: &str) -> Option<(usize, String)> {
    let table: toml::Table = toml::from_str(text).ok()?;
    if table.contains_key("rig") {
        return None;
    }
    let key = table.iter().find(|(_, v)| !v.is_table())?.0;
    let line = text.lines().position(|l| {
        l.trim_start()
            .strip_prefix(key.as_str())
            .is_some_and(|rest| rest.trim_start().starts_with('='))
    })?;
    Some((line + 1, key.clone()))
}

impl Scene {
    /// Read and validate a scene file.
    pub fn from_path(path: &Path) -> Result<Self, SceneError> {
        Self::from_toml(&read_text(path, MAX_TOML_BYTES)?, path)
    }

    /// Parse and validate scene text; `path` only labels errors.
    pub fn from_toml(text: &str, path: &Path) -> Result<Self, SceneError> {
        parse_toml::<SceneFile>(text, path)?.validate(path)
    }
}

/// The most frames a sampled trajectory or synthetic recording may hold (duration times
/// frame rate): 10^7, about 0.5 GB of output.
pub const MAX_FRAMES: f64 = 1e7;

/// The most steps `run.max_steps` may allow (accepted and rejected together): 10^7. `appell
/// bench` measures 0.44 us a step on the paper scene, and a run that never ends (a slide down
/// a tilted rail) takes 0.5 us a step on the plain rig and 1.2 us with every real-rig term
/// and the energy on, so a run at the cap ends in 5 to 12 s; 10^8 would take up to two
/// minutes. Ten times the default, and a 2 s release takes about a hundred steps.
pub const MAX_STEPS: f64 = 1e7;

/// The largest magnitude of an initial position, angle or rate: beyond it, the simulation's
/// numbers (energies, forces) leave the range where f64 keeps them meaningful.
pub const MAX_INITIAL: f64 = 1e6;

/// Masses (kg) and rod length (m) must lie in [RIG_MIN, RIG_MAX], and mu at most RIG_MAX:
/// wider ranges make mass ratios and mu* overflow (gravity has its own, narrower
/// [`GRAVITY_RANGE`]).
pub const RIG_MIN: f64 = 1e-9;
/// See [`RIG_MIN`].
pub const RIG_MAX: f64 = 1e9;

/// The gravity a rig may have (m/s^2): from 0.1, below Ceres' 0.28 and Pluto's 0.62, to 30,
/// above Jupiter's 24.8 at its cloud tops: any planet or moon a lab could stand on. Outside
/// it the value is a typo or a unit slip (1e9, or 981 in cm/s^2), which `fit` would otherwise
/// fit for minutes to a meaningless answer.
pub const GRAVITY_RANGE: [f64; 2] = [0.1, 30.0];

/// The gravity of a rig file without `gravity` (m/s^2): Earth's, rounded. At sea level Earth's
/// is 9.780 at the equator to 9.832 at the poles, so the default is within 0.3 % anywhere a lab
/// stands, and a fit says so (a fitted mu carries that 0.3 %, see [`RigFile::load_measured`]).
pub const EARTH_GRAVITY: f64 = 9.81;

/// The standard deviation of [`EARTH_GRAVITY`] for a rig file without `gravity` (m/s^2): the
/// spread of a uniform 9.780 to 9.832, the equator to the poles.
pub const EARTH_GRAVITY_SD: f64 = 0.015;
/// The standard deviation of [`normal_gravity`] at a known site (m/s^2): local anomalies.
pub const SITE_GRAVITY_SD: f64 = 0.003;

/// The latitudes (deg) and altitudes (m) [`normal_gravity`] takes: the Earth's, from the Dead
/// Sea's shore to the highest observatories.
pub const LATITUDE_RANGE: [f64; 2] = [-90.0, 90.0];
/// See [`LATITUDE_RANGE`].
pub const ALTITUDE_RANGE: [f64; 2] = [-500.0, 6000.0];

/// Earth's normal gravity (m/s^2) at a geodetic latitude (deg) and an altitude above the
/// ellipsoid (m): the WGS 84 Somigliana formula with the free-air gradient. Local anomalies
/// (mountains, dense rock) are below 0.03 %, a tenth of what the latitude alone changes.
pub fn normal_gravity(latitude_deg: f64, altitude_m: f64) -> f64 {
    // WGS 84: equatorial gravity, Somigliana's constant k and the first eccentricity squared.
    const G_E: f64 = 9.780_325_335_9;
    const K: f64 = 0.001_931_852_652_41;
    const E2: f64 = 0.006_694_379_990_13;
    let s2 = latitude_deg.to_radians().sin().powi(2);
    G_E * (1.0 + K * s2) / (1.0 - E2 * s2).sqrt() - 3.086e-6 * altitude_m
}

/// Check `rig.gravity` against [`GRAVITY_RANGE`]: every file with a rig (scene, rig file,
/// plan) calls it, so simulate, fit, regions and plan refuse alike.
pub fn check_gravity(path: &Path, gravity: f64) -> Result<(), SceneError> {
    let [lo, hi] = GRAVITY_RANGE;
    check(
        path,
        (lo..=hi).contains(&gravity),
        "rig.gravity",
        &format!("between {lo} and {hi} m/s^2 (any planet or moon a lab could be on)"),
        gravity,
    )
}

/// The relative tolerance `run.rtol` may ask for: from 1e-14, near what f64 arithmetic
/// resolves (tighter only multiplies the steps), to 1e-2, past which the step control lets
/// the error grow unseen (rtol 0.5 ended a light-slider scene in NaN, 0.9 gave theta' of
/// 2.8e20 rad/s with exit 0).
pub const RTOL_RANGE: [f64; 2] = [1e-14, 1e-2];

/// The absolute tolerance `run.atol` may ask for (metres, radians and their rates alike):
/// from 1e-16 to 1e-3, a millimetre or milliradian per step, which still keeps the shipped
/// scenes' final states within a few millimetres; a larger one lets the step control accept
/// any step (atol 1 moved a rigid rig's slide by 0.2 m).
pub const ATOL_RANGE: [f64; 2] = [1e-16, 1e-3];

/// The fastest rate (1/s) a rig may have: its time scale must be at least 10 ms. The explicit
/// integrator takes about one step per 1/6 of the fastest time scale however loose the
/// tolerance (stability, not accuracy): 3,149 steps for a 2 s run of the paper scene at a
/// damping rate of 1.1e4 /s, against 107 at the paper's 8 /s. A fit runs hundreds of runs:
/// `tests/data/rigid/rigid_paper.csv` with the measured rig fits in 0.05 s, with pivot damping
/// at a rate of 95 /s (c_p = 0.4 N m s) in 9.7 s, at 950 /s (c_p = 4) in 250 s, and at 1e5 /s
/// (c_p = 1e3, or an equivalent length of 1e-9 m) for over three minutes before this check.
/// Real rigs are far below it: a 1 cm pendulum on a slider of its own mass swings at 44
/// rad/s, the paper's at 8, and critically damping the paper's pendulum is a rate of 11 /s.
pub const MAX_RIG_RATE: f64 = 100.0;

/// Where a rig's values came from: what names a bad one in a message.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum RigOrigin<'a> {
    /// Typed in a file's `[rig]` (scene, rig file or plan); `friction` is the section the
    /// friction coefficients are in (`rig`, or `friction` in a plan).
    File {
        /// Section of `mu_kinetic` and `mu_static`.
        friction: &'static str,
    },
    /// Computed by a fit and read from its JSON (`plan --after`): the parameters it fitted
    /// and their values, under `section` (`shared` for a joint fit, `parameters` otherwise).
    Fit {
        /// Where the values are in the JSON.
        section: &'static str,
        /// The parameters the fit set in the rig.
        names: &'a [Param],
        /// Their values, as in the JSON.
        values: &'a [f64],
    },
}

/// A value of the rig the dynamics use, for [`check_rig`]'s messages.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Quantity {
    MarkerLength,
    Length,
    MassRatio,
    MuKinetic,
    MuStatic,
    Tilt,
    PivotDamping,
    Viscous,
    Stribeck,
}

impl RigOrigin<'_> {
    /// [`Rig::validate_law`]'s error worded for where the values came from: a fit's values
    /// are named by their place in its JSON (`shared.load_exponent.value`), a direction's
    /// coefficient by the two values it is made of.
    fn law_message(&self, e: crate::model::RigError) -> String {
        let (
            RigOrigin::Fit { section, .. },
            crate::model::RigError::Law {
                key,
                expected,
                value,
            },
        ) = (self, &e)
        else {
            return e.to_string();
        };
        let from = "(a value the fit computed, read from the fit JSON)";
        // The JSON's names are the parameters' own.
        let (mu, split) = (Param::MuKinetic.name(), Param::FrictionSplit.name());
        match *key {
            "load_exponent" => format!(
                "{section}.{}.value {from} must be {expected}, got {value}",
                Param::LoadExponent.name()
            ),
            "mu_kinetic_positive" | "mu_kinetic_negative" => format!(
                "the kinetic coefficient {key} = {section}.{mu}.value {} {section}.{split}.value {from} must be {expected}, got {value}",
                if *key == "mu_kinetic_negative" { "-" } else { "+" }
            ),
            _ => format!(
                "{key}, from {section}.{mu}.value, {section}.{split}.value and the plan's mu_static {from}, must be {expected}, got {value}"
            ),
        }
    }

    /// The field a quantity of `rig` is named by, and the value to show (a fit's own value
    /// where it fitted the quantity, so a mass ratio of -1 shows as -1, not as the NaN it
    /// makes of the masses).
    fn name(&self, q: Quantity, rig: &Rig<f64>, value: f64) -> (String, f64) {
        let rigid = rig.pendulum.is_some_and(|p| !p.is_point());
        match *self {
            RigOrigin::File { friction } => {
                let name = match q {
                    Quantity::MarkerLength => "rig.rod_length".into(),
                    Quantity::Length if rigid => "the pendulum's equivalent length L = J / (m_p d) (from rig.rod_length, rig.bob_mass, rig.rod_mass and rig.bob_radius, or rig.pendulum_mass, rig.pendulum_com and rig.pendulum_inertia)".into(),
                    Quantity::Length => "rig.rod_length".into(),
                    Quantity::MassRatio if rigid => "the equivalent mass ratio r' = (m1 + m_p - m_e) / m_e (from rig.slider_mass and the pendulum's keys)".into(),
                    Quantity::MassRatio => "the mass ratio rig.slider_mass / rig.bob_mass".into(),
                    Quantity::MuKinetic => format!("{friction}.mu_kinetic"),
                    Quantity::MuStatic => format!("{friction}.mu_static"),
                    Quantity::Tilt => "rig.rail_tilt_deg".into(),
                    Quantity::PivotDamping => "rig.pivot_damping".into(),
                    Quantity::Viscous => "rig.viscous_friction".into(),
                    Quantity::Stribeck => "rig.stribeck_velocity".into(),
                };
                let value = if q == Quantity::Tilt {
                    value.to_degrees()
                } else {
                    value
                };
                (name, value)
            }
            RigOrigin::Fit {
                section,
                names,
                values,
            } => {
                let param = match q {
                    Quantity::MarkerLength => Param::RodLength,
                    Quantity::Length if names.contains(&Param::PendulumLength) => {
                        Param::PendulumLength
                    }
                    Quantity::Length => Param::RodLength,
                    Quantity::MassRatio => Param::MassRatio,
                    Quantity::MuKinetic => Param::MuKinetic,
                    Quantity::MuStatic if names.contains(&Param::MuStatic) => Param::MuStatic,
                    Quantity::MuStatic => Param::MuKinetic,
                    Quantity::Tilt => Param::RailTilt,
                    Quantity::PivotDamping => Param::PivotDamping,
                    Quantity::Viscous => Param::ViscousFriction,
                    Quantity::Stribeck => Param::StribeckVelocity,
                };
                let given = names.iter().position(|&n| n == param).map(|i| values[i]);
                let name = format!(
                    "{section}.{}.value (a value the fit computed, {})",
                    param.name(),
                    if given.is_some() {
                        "read from the fit JSON"
                    } else {
                        "the plan's, moved by the fit's other values"
                    }
                );
                (name, given.unwrap_or(value))
            }
        }
    }
}

/// Check a rig however it arrived (scene, rig file, plan, a fit's JSON) against the same
/// ranges, on the values the dynamics use: lengths within [`RIG_MIN`]..[`RIG_MAX`], the
/// (equivalent) mass ratio within their quotients, friction coefficients from 0 to
/// [`RIG_MAX`] with mu_static >= mu_kinetic, a tilt below 90 degrees, damping and viscous
/// friction from 0 to [`RIG_MAX`], a Stribeck speed within [`RIG_MIN`]..[`RIG_MAX`]. Errors
/// name `path` and the field by `origin`. The rig's keys as written are checked before it is
/// built (`check_rig_range`), so this catches what was computed: a rigid pendulum's
/// equivalents and a fit's values.
pub fn check_rig(path: &Path, rig: &Rig<f64>, origin: RigOrigin) -> Result<(), SceneError> {
    let bad = |q: Quantity, value: f64, expected: String| -> SceneError {
        let (name, value) = origin.name(q, rig, value);
        SceneError::Invalid {
            path: path.to_owned(),
            message: format!("{name} must be {expected}, got {value:?}"),
        }
    };
    let within = |v: f64, lo: f64, hi: f64| (lo..=hi).contains(&v);
    let range = format!("between {RIG_MIN:e} and {RIG_MAX:e}");
    check_gravity(path, rig.gravity)?;
    for (q, v) in [
        (Quantity::MarkerLength, rig.marker_length),
        (Quantity::Length, rig.rod_length),
    ] {
        if !within(v, RIG_MIN, RIG_MAX) {
            return Err(bad(q, v, format!("{range} m")));
        }
    }
    let [r_lo, r_hi] = [RIG_MIN / RIG_MAX, RIG_MAX / RIG_MIN];
    let ratio = rig.mass_ratio();
    if !(within(ratio, r_lo, r_hi) && rig.slider_mass > 0.0 && rig.bob_mass > 0.0) {
        return Err(bad(
            Quantity::MassRatio,
            ratio,
            format!("between {r_lo:e} and {r_hi:e} (masses {range} kg)"),
        ));
    }
    for (q, v) in [
        (Quantity::MuKinetic, rig.mu_kinetic),
        (Quantity::MuStatic, rig.mu_static),
    ] {
        if !within(v, 0.0, RIG_MAX) {
            return Err(bad(q, v, format!("between 0 and {RIG_MAX:e}")));
        }
    }
    if rig.mu_static < rig.mu_kinetic {
        return Err(bad(
            Quantity::MuStatic,
            rig.mu_static,
            format!("at least mu_kinetic ({})", rig.mu_kinetic),
        ));
    }
    if !(rig.rail_tilt.is_finite() && rig.rail_tilt.abs() < std::f64::consts::FRAC_PI_2) {
        let expected = match origin {
            RigOrigin::File { .. } => "strictly between -90 and 90 degrees",
            RigOrigin::Fit { .. } => "strictly between -pi/2 and pi/2 rad (-90 and 90 degrees)",
        };
        return Err(bad(Quantity::Tilt, rig.rail_tilt, expected.into()));
    }
    for (q, v, unit) in [
        (Quantity::PivotDamping, rig.pivot_damping, "N m s"),
        (Quantity::Viscous, rig.viscous_friction, "N s/m"),
    ] {
        if !within(v, 0.0, RIG_MAX) {
            return Err(bad(q, v, format!("between 0 and {RIG_MAX:e} {unit}")));
        }
    }
    // The direction and load laws' own ranges, on values a fit computed too.
    rig.validate_law().map_err(|e| SceneError::Invalid {
        path: path.to_owned(),
        message: origin.law_message(e),
    })?;
    if rig.friction_law == FrictionLaw::Stribeck && !within(rig.stribeck_velocity, RIG_MIN, RIG_MAX)
    {
        return Err(bad(
            Quantity::Stribeck,
            rig.stribeck_velocity,
            format!("{range} m/s"),
        ));
    }
    Ok(())
}

/// The pendulum's swing rate sqrt(g (1 + m2/m1) / L) with the slider free, `free` = 1 + m2/m1.
fn swing_rate(rig: &Rig<f64>, free: f64) -> f64 {
    (rig.gravity * free / rig.rod_length).sqrt()
}

/// The rig's fastest rate (1/s) and the quantity that sets it: the pendulum's swing with the
/// slider free, sqrt(g (1 + m2/m1) / L); the pivot damping's c_p (1 + m2/m1) / (m2 L^2); the
/// rail's viscous friction c_v / m1 (the dynamics' point rig: m2 and L a rigid pendulum's
/// equivalents). The slider-free forms are the larger, so the estimate holds in every mode.
fn rig_rate(rig: &Rig<f64>) -> (f64, Quantity) {
    let (m1, m2, l) = (rig.slider_mass, rig.bob_mass, rig.rod_length);
    let free = 1.0 + m2 / m1;
    [
        (swing_rate(rig, free), Quantity::Length),
        (
            rig.pivot_damping * free / (m2 * l * l),
            Quantity::PivotDamping,
        ),
        (rig.viscous_friction / m1, Quantity::Viscous),
    ]
    .into_iter()
    .fold((0.0, Quantity::Length), |best, (rate, q)| {
        // NaN (never from a rig [`check_rig`] passed) counts as too fast.
        if rate.is_nan() || rate > best.0 {
            (if rate.is_nan() { f64::INFINITY } else { rate }, q)
        } else {
            best
        }
    })
}

/// The rig's fastest rate (1/s), for work estimates: see [`MAX_RIG_RATE`].
pub fn rig_time_rate(rig: &Rig<f64>) -> f64 {
    rig_rate(rig).0
}

/// Check that the rig's fastest time scale is at least 1 / [`MAX_RIG_RATE`] s, before any
/// integration: a stiffer rig makes the explicit integrator's steps (and a fit's or a
/// region map's runs) take minutes. Every command that integrates a rig calls it: simulate
/// and synth (scenes), regions (rig files), fits (after the rig is compared with the
/// recording) and plans (the plan's rig, and again with a fit's values).
pub fn check_time_scale(path: &Path, rig: &Rig<f64>, origin: RigOrigin) -> Result<(), SceneError> {
    let (rate, mut q) = rig_rate(rig);
    if rate <= MAX_RIG_RATE {
        return Ok(());
    }
    // A swing too fast on a pendulum that would pass with equal masses: the masses' ratio
    // sets it (a 1e-9 kg slider under a 1e9 kg bob), not the length.
    if q == Quantity::Length && swing_rate(rig, 2.0) <= MAX_RIG_RATE {
        q = Quantity::MassRatio;
    }
    let what = match q {
        Quantity::PivotDamping => "c_p (1 + m2/m1) / (m2 L^2)",
        Quantity::Viscous => "c_v / m1",
        _ => "sqrt(g (1 + m2/m1) / L)",
    };
    let value = match q {
        Quantity::PivotDamping => rig.pivot_damping,
        Quantity::Viscous => rig.viscous_friction,
        Quantity::MassRatio => rig.mass_ratio(),
        _ => rig.rod_length,
    };
    let (name, value) = origin.name(q, rig, value);
    Err(SceneError::Invalid {
        path: path.to_owned(),
        message: format!(
            "{name} must give the rig a time scale of at least {} ms (a rate {what} of at most {MAX_RIG_RATE:e} /s; a stiffer rig takes the integrator minutes), got {value:?} (a rate of {rate:.3e} /s)",
            1e3 / MAX_RIG_RATE
        ),
    })
}

/// Check the rig's keys as written against their ranges, before the rig is built from them
/// (so a bad key is named, not a value computed from it): every file with a `[rig]` (scene,
/// rig file, plan) calls it.
pub fn check_rig_range(path: &Path, r: &RigSpec) -> Result<(), SceneError> {
    let within = |v: f64| (RIG_MIN..=RIG_MAX).contains(&v);
    let range = format!("between {RIG_MIN:e} and {RIG_MAX:e}");
    check(
        path,
        within(r.slider_mass),
        "rig.slider_mass",
        &range,
        r.slider_mass,
    )?;
    for (key, v) in [
        ("rig.bob_mass", r.bob_mass),
        ("rig.pendulum_mass", r.pendulum_mass),
        ("rig.pendulum_com", r.pendulum_com),
        ("rig.pendulum_inertia", r.pendulum_inertia),
    ] {
        if let Some(v) = v {
            check(path, within(v), key, &range, v)?;
        }
    }
    for (key, v) in [
        ("rig.rod_mass", r.rod_mass),
        ("rig.bob_radius", r.bob_radius),
    ] {
        if let Some(v) = v {
            check(
                path,
                v == 0.0 || within(v),
                key,
                &format!("0 or {range}"),
                v,
            )?;
        }
    }
    check(
        path,
        within(r.rod_length),
        "rig.rod_length",
        &range,
        r.rod_length,
    )?;
    check_gravity(path, r.gravity())?;
    for (key, sd, value) in [
        ("rig.rod_length_sd", r.rod_length_sd, Some(r.rod_length)),
        ("rig.slider_mass_sd", r.slider_mass_sd, Some(r.slider_mass)),
        ("rig.bob_mass_sd", r.bob_mass_sd, r.bob_mass),
        ("rig.rod_mass_sd", r.rod_mass_sd, r.rod_mass),
        ("rig.bob_radius_sd", r.bob_radius_sd, r.bob_radius),
        ("rig.gravity_sd", r.gravity_sd, Some(r.gravity())),
    ] {
        if let Some(sd) = sd {
            let value = value.unwrap_or(0.0);
            // A measurement's error is below its value: a larger one says nothing was measured.
            check(
                path,
                sd.is_finite() && sd >= 0.0 && sd <= 0.5 * value,
                key,
                &format!("a standard deviation >= 0 and at most half the value ({value})"),
                sd,
            )?;
        }
    }
    // Every friction key the file can hold, each under its own name: the direction law's
    // means would name `mu_kinetic`, a key its file lacks, and let one direction past 1e9.
    for (key, mu) in [
        ("rig.mu_kinetic", r.mu_kinetic),
        ("rig.mu_static", r.mu_static),
        ("rig.mu_kinetic_positive", r.mu_kinetic_positive),
        ("rig.mu_kinetic_negative", r.mu_kinetic_negative),
        ("rig.mu_static_positive", r.mu_static_positive),
        ("rig.mu_static_negative", r.mu_static_negative),
    ] {
        if let Some(mu) = mu {
            check(
                path,
                mu <= RIG_MAX,
                key,
                &format!("at most {RIG_MAX:e}"),
                mu,
            )?;
        }
    }
    Ok(())
}

/// Check that `duration` at `rate` frames per second stays within [`MAX_FRAMES`]; `key` names
/// the rate in the message.
pub fn check_frames(path: &Path, duration: f64, rate: f64, key: &str) -> Result<(), SceneError> {
    let frames = duration * rate;
    check(
        path,
        frames.is_finite() && frames <= MAX_FRAMES,
        key,
        &format!(
            "a rate that gives at most {MAX_FRAMES:e} frames over the duration {duration} s (that is at most {} Hz)",
            MAX_FRAMES / duration
        ),
        rate,
    )
}

impl SceneFile {
    /// Check every value, naming the first bad key.
    pub fn validate(&self, path: &Path) -> Result<Scene, SceneError> {
        let rig = self.rig.checked(path)?;
        check_time_scale(path, &rig, RigOrigin::File { friction: "rig" })?;
        let i = &self.initial;
        for (key, v) in [
            ("initial.x", i.x),
            ("initial.theta", i.theta),
            ("initial.x_dot", i.x_dot),
            ("initial.theta_dot", i.theta_dot),
        ] {
            check(
                path,
                v.is_finite() && v.abs() <= MAX_INITIAL,
                key,
                &format!("a finite number within +-{MAX_INITIAL:e}"),
                v,
            )?;
        }
        let r = &self.run;
        check(
            path,
            r.duration.is_finite() && r.duration > 0.0,
            "run.duration",
            "a finite number > 0",
            r.duration,
        )?;
        if let Some(n) = r.max_steps {
            check(
                path,
                n.fract() == 0.0 && (1.0..=MAX_STEPS).contains(&n),
                "run.max_steps",
                &format!("a whole number of steps from 1 to {MAX_STEPS:e} (a run at the cap ends within seconds)"),
                n,
            )?;
        }
        let defaults = Options::default();
        let rtol = r.rtol.unwrap_or(defaults.rtol);
        let atol = r.atol.unwrap_or(defaults.atol);
        for (key, value, [lo, hi]) in [
            ("run.rtol", rtol, RTOL_RANGE),
            ("run.atol", atol, ATOL_RANGE),
        ] {
            check(
                path,
                (lo..=hi).contains(&value),
                key,
                &format!("between {lo:e} and {hi:e} (tighter only adds steps; looser lets the integrator's error grow unchecked)"),
                value,
            )?;
        }
        if let Some(fr) = self.output.frame_rate {
            check(
                path,
                fr.is_finite() && fr > 0.0,
                "output.frame_rate",
                "a finite number > 0 (Hz)",
                fr,
            )?;
            check_frames(path, r.duration, fr, "output.frame_rate")?;
        }
        Ok(Scene {
            rig,
            initial: [i.x, i.theta, i.x_dot, i.theta_dot],
            duration: r.duration,
            options: Options {
                rtol,
                atol,
                method: r.method.unwrap_or_default(),
                // A whole number from 1 to MAX_STEPS, checked above.
                max_steps: r.max_steps.map_or(defaults.max_steps, |n| n as usize),
                rest_rule: r.rest_rule.unwrap_or_default(),
                ..defaults
            },
            output: self.output,
        })
    }
}

impl Scene {
    /// Frame times 0, 1/rate, ... up to the duration, when a frame rate is asked for.
    pub fn frame_times(&self) -> Vec<f64> {
        match self.output.frame_rate {
            Some(rate) => {
                let n = (self.duration * rate + 1e-9).floor() as usize;
                (0..=n).map(|k| k as f64 / rate).collect()
            }
            None => Vec::new(),
        }
    }

    /// What the simulator must compute for this scene: samples only when a trajectory is
    /// asked for, friction work only when energy is.
    pub fn request(&self) -> Request {
        Request {
            sample_times: self.frame_times(),
            friction_work: self.output.energy,
            positions_only: false,
        }
    }
}

/// A rig file (`RIG.toml`): the `[rig]` section of a scene, alone or in a whole scene file
/// (whose `[initial]`, `[run]` and `[output]` are then not read). Any other section is an
/// error naming it.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RigFile {
    /// `[rig]`.
    pub rig: RigSpec,
    /// A scene's `[initial]`, ignored.
    #[serde(default)]
    initial: Option<serde::de::IgnoredAny>,
    /// A scene's `[run]`, ignored.
    #[serde(default)]
    run: Option<serde::de::IgnoredAny>,
    /// A scene's `[output]`, ignored.
    #[serde(default)]
    output: Option<serde::de::IgnoredAny>,
}

impl RigFile {
    /// Parse a rig file's text, a missing `[rig]` line said as such.
    fn from_text(text: &str, path: &Path) -> Result<RigFile, SceneError> {
        parse_toml(text, path).map_err(|e| match missing_rig_header(text) {
            Some((line, key)) => SceneError::Parse {
                path: path.to_owned(),
                message: format!(
                    "line {line}: {key} comes before any section: a rig file's keys go under a [rig] line (add one above them; appell inspect RECORDING --rig-template RIG.toml writes a rig file to fill in)"
                ),
            },
            None => e,
        })
    }

    /// Read and validate a rig file; errors name the file and the key at fault.
    pub fn load(path: &Path) -> Result<Rig<f64>, SceneError> {
        Self::parse(&read_text(path, MAX_TOML_BYTES)?, path)
    }

    /// Read a rig file for fitting: mu values are optional starting guesses (`mu_guess` when
    /// left out).
    pub fn load_for_fit(path: &Path, mu_guess: f64) -> Result<Rig<f64>, SceneError> {
        Self::load_measured(path, mu_guess).map(|(rig, _)| rig)
    }

    /// [`RigFile::load_for_fit`] with the `[rig]` section as written (its measurement
    /// uncertainties: `*_sd` keys).
    pub fn load_measured(path: &Path, mu_guess: f64) -> Result<(Rig<f64>, RigSpec), SceneError> {
        Self::load_on_earth(path, mu_guess, None).map(|(rig, spec, _)| (rig, spec))
    }

    /// [`RigFile::load_measured`] for a fit on Earth: a file without `gravity` takes Earth's
    /// normal gravity at `site` (latitude in deg, altitude in m; [`normal_gravity`]) or else
    /// [`EARTH_GRAVITY`], and the third value is the note the fit reports about it (`None`
    /// when the file gives gravity).
    pub fn load_on_earth(
        path: &Path,
        mu_guess: f64,
        site: Option<(f64, f64)>,
    ) -> Result<(Rig<f64>, RigSpec, Option<String>), SceneError> {
        Self::parse_on_earth(&read_text(path, MAX_TOML_BYTES)?, path, mu_guess, site)
    }

    /// [`RigFile::load_on_earth`] on a rig file's text; `path` only labels errors and notes.
    pub fn parse_on_earth(
        text: &str,
        path: &Path,
        mu_guess: f64,
        site: Option<(f64, f64)>,
    ) -> Result<(Rig<f64>, RigSpec, Option<String>), SceneError> {
        let file = RigFile::from_text(text, path)?;
        let mut measured = file.rig;
        // Gravity is a measured value like the rod and the masses: the fit takes it with a
        // prior of this deviation, and the recording (its swings) pins it far better.
        let note = match (measured.gravity, site) {
            (Some(_), _) => None,
            (None, Some((lat, alt))) => {
                let g = normal_gravity(lat, alt);
                measured.gravity = Some(g);
                measured.gravity_sd = measured.gravity_sd.or(Some(SITE_GRAVITY_SD));
                Some(format!(
                    "{}: rig.gravity not given: {g:.4} +- {SITE_GRAVITY_SD} m/s^2, Earth's normal gravity at latitude {lat} deg and altitude {alt} m (WGS 84; local anomalies are below 0.03 %), fitted with the rod and the masses",
                    path.display()
                ))
            }
            (None, None) => {
                measured.gravity_sd = measured.gravity_sd.or(Some(EARTH_GRAVITY_SD));
                Some(format!(
                    "{}: rig.gravity not given: {EARTH_GRAVITY} +- {EARTH_GRAVITY_SD} m/s^2 (Earth's is 9.780 at the equator to 9.832 at the poles), fitted with the rod and the masses; give rig.gravity or --latitude to narrow it",
                    path.display()
                ))
            }
        };
        let spec = measured.with_guess(mu_guess);
        // The time scale is checked by the fit once the rig is compared with the recording
        // (a rod its markers contradict is the better message).
        Ok((spec.checked(path)?, measured, note))
    }

    /// Parse and validate rig-file text, its time scale included; `path` only labels errors.
    pub fn parse(text: &str, path: &Path) -> Result<Rig<f64>, SceneError> {
        let file = RigFile::from_text(text, path)?;
        let rig = file.rig.checked(path)?;
        check_time_scale(path, &rig, RigOrigin::File { friction: "rig" })?;
        Ok(rig)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_gravity_matches_the_published_values() {
        // WGS 84's own table: 9.7803253359 at the equator, 9.8321849379 at the poles; the
        // free-air gradient 0.3086 mGal/m.
        assert!((normal_gravity(0.0, 0.0) - 9.780_325_335_9).abs() < 1e-9);
        assert!((normal_gravity(90.0, 0.0) - 9.832_184_937_9).abs() < 1e-8);
        assert!((normal_gravity(-90.0, 0.0) - normal_gravity(90.0, 0.0)).abs() < 1e-12);
        assert!((normal_gravity(45.0, 0.0) - 9.806_2).abs() < 1e-3);
        assert!((normal_gravity(45.0, 1000.0) - normal_gravity(45.0, 0.0) + 3.086e-3).abs() < 1e-9);
        // The default is Earth's within 0.3 % at any latitude.
        for lat in [0.0, 30.0, 60.0, 90.0] {
            assert!((normal_gravity(lat, 0.0) / EARTH_GRAVITY - 1.0).abs() < 3.1e-3);
        }
    }
}
