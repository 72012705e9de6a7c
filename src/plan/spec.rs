//! Plan files: the rig with mu as an estimate and its uncertainty, the camera, what the
//! release mechanism can do, and the transitions to film. Unknown keys are errors, and every
//! value is checked with the file and the key named, like scenes.

use crate::model::Rig;
use crate::scene::{check_time_scale, rig_time_rate, RigOrigin, RigSpec, SceneError, RIG_MAX};
use serde::Deserialize;
use std::fmt;
use std::path::Path;

/// The `[rig]` section of a plan: the rig without friction (friction is uncertain, see
/// [`FrictionSpec`]).
#[derive(Debug, Clone, Copy, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct PlanRigSpec {
    /// Slider mass m1 (kg).
    pub slider_mass: f64,
    /// Bob mass m2 (kg); required unless the pendulum is given as `pendulum_mass`,
    /// `pendulum_com` and `pendulum_inertia`.
    pub bob_mass: Option<f64>,
    /// Rod length l (m): the pivot to the bob's centre.
    pub rod_length: f64,
    /// Rod mass (kg, uniform rod; default 0).
    pub rod_mass: Option<f64>,
    /// Bob radius (m, solid sphere; default 0).
    pub bob_radius: Option<f64>,
    /// Mass of everything that swings (kg), for a pendulum of any other shape.
    pub pendulum_mass: Option<f64>,
    /// Pivot to the pendulum's centre of mass (m).
    pub pendulum_com: Option<f64>,
    /// Moment of inertia about the pivot (kg m^2).
    pub pendulum_inertia: Option<f64>,
    /// Gravity (m/s^2); default [`crate::scene::EARTH_GRAVITY`].
    pub gravity: Option<f64>,
    /// Standard deviation of the rod length (m) as measured; default a ruler's (1 mm). These
    /// `_sd` keys are a rig file's: `plan --after` counts how far the fit's rig is from this
    /// one in them.
    pub rod_length_sd: Option<f64>,
    /// Standard deviation of the slider mass (kg); default a kitchen scale's.
    pub slider_mass_sd: Option<f64>,
    /// Standard deviation of the bob mass (kg); default a kitchen scale's.
    pub bob_mass_sd: Option<f64>,
    /// Standard deviation of the rod mass (kg).
    pub rod_mass_sd: Option<f64>,
    /// Standard deviation of the bob radius (m).
    pub bob_radius_sd: Option<f64>,
    /// Standard deviation of gravity (m/s^2).
    pub gravity_sd: Option<f64>,
}

/// The `[friction]` section: the law the lab expects (the rig file's keys: Coulomb's by
/// default) with its coefficients, each as an estimate with a standard deviation (`_sd`,
/// normal draws) or a range (`_range`, uniform draws), and optionally the laws to tell apart.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FrictionSpec {
    /// Estimate of mu_kinetic (left out under the direction law, which gives each
    /// direction's).
    pub mu_kinetic: Option<f64>,
    /// Standard deviation of mu_kinetic.
    pub mu_kinetic_sd: Option<f64>,
    /// Range `[lo, hi]` of mu_kinetic (instead of a standard deviation).
    pub mu_kinetic_range: Option<[f64; 2]>,
    /// Estimate of mu_static; left out: mu_static = mu_kinetic in every draw.
    pub mu_static: Option<f64>,
    /// Standard deviation of mu_static.
    pub mu_static_sd: Option<f64>,
    /// Range of mu_static.
    pub mu_static_range: Option<[f64; 2]>,
    /// The friction law (`coulomb`, `stribeck`, `direction`, `load`), as in a rig file.
    pub friction_law: Option<crate::model::FrictionLaw>,
    /// Stribeck speed v_s (m/s), with `friction_law = "stribeck"`.
    pub stribeck_velocity: Option<f64>,
    /// Its standard deviation.
    pub stribeck_velocity_sd: Option<f64>,
    /// Its range.
    pub stribeck_velocity_range: Option<[f64; 2]>,
    /// Kinetic coefficient toward +x, with `friction_law = "direction"`.
    pub mu_kinetic_positive: Option<f64>,
    /// Its standard deviation.
    pub mu_kinetic_positive_sd: Option<f64>,
    /// Kinetic coefficient toward -x.
    pub mu_kinetic_negative: Option<f64>,
    /// Its standard deviation.
    pub mu_kinetic_negative_sd: Option<f64>,
    /// Static coefficient toward +x (default: the kinetic one).
    pub mu_static_positive: Option<f64>,
    /// Static coefficient toward -x.
    pub mu_static_negative: Option<f64>,
    /// Exponent n of `friction_law = "load"`.
    pub load_exponent: Option<f64>,
    /// Its standard deviation.
    pub load_exponent_sd: Option<f64>,
    /// Its range.
    pub load_exponent_range: Option<[f64; 2]>,
    /// Laws to tell apart (`coulomb`, `static`, `stribeck`, `direction`, `load`): the plan
    /// then ranks releases by how surely a recording would separate them.
    pub discriminate: Option<Vec<String>>,
}

/// The `[camera]` section.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct CameraSpec {
    /// Frame rate (Hz).
    pub frame_rate: f64,
    /// Scale (m per pixel).
    pub metres_per_pixel: f64,
    /// Marker localisation noise (pixels, standard deviation per coordinate).
    pub noise_px: f64,
    /// Recording duration (s).
    pub duration: f64,
    /// Field of view along the rail `[lo, hi]` (m, rail frame): both markers must stay inside.
    pub field_of_view: [f64; 2],
}

/// The `[release]` section: ranges the release mechanism can set, the usable rail and how
/// precisely a release is executed.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ReleaseSpec {
    /// Initial slider position (m); default 0.
    #[serde(default)]
    pub x: f64,
    /// Range of the initial angle (degrees, docs/physics.md convention: 90 hangs down, 0 is the rod
    /// horizontal with the bob on the +x side).
    pub theta_deg: [f64; 2],
    /// Range of the initial angular velocity (rad/s): a push. Default `[0, 0]`.
    #[serde(default)]
    pub theta_dot: [f64; 2],
    /// Range of the initial slider velocity (m/s): a moving start. Default `[0, 0]`.
    #[serde(default)]
    pub x_dot: [f64; 2],
    /// Usable rail `[lo, hi]` (m): the slider must stay on it.
    pub rail: [f64; 2],
    /// Execution error of the angle (degrees, +-, uniform).
    #[serde(default)]
    pub theta_error_deg: f64,
    /// Execution error of the push (rad/s, +-, uniform).
    #[serde(default)]
    pub theta_dot_error: f64,
    /// Execution error of the moving start (m/s, +-, uniform).
    #[serde(default)]
    pub x_dot_error: f64,
}

/// A transition (or pattern of transitions) a lab wants to film.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq, Hash)]
#[serde(rename_all = "snake_case")]
pub enum Target {
    /// The stuck slider starts to slide.
    StickToSlide,
    /// The sliding slider stops and sticks.
    SlideToStick,
    /// The slider stops and slides back.
    Reversal,
    /// At least this many slides that end in a stick (`{ stick_slip_cycles = 3 }`).
    StickSlipCycles(u32),
    /// A slide that ends near the paradox band, where |N| grows and the slider stops hard
    /// (only possible above mu* = 2 sqrt(r (1 + r))).
    SuddenStop,
}

impl fmt::Display for Target {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Target::StickToSlide => f.write_str("stick_to_slide"),
            Target::SlideToStick => f.write_str("slide_to_stick"),
            Target::Reversal => f.write_str("reversal"),
            Target::StickSlipCycles(n) => write!(f, "stick_slip_cycles({n})"),
            Target::SuddenStop => f.write_str("sudden_stop"),
        }
    }
}

fn default_min_slide_px() -> f64 {
    20.0
}
fn default_min_frames() -> f64 {
    10.0
}
/// The most simulations a plan's search may ask for (grid releases x (1 + draws) + 2 x top x
/// verify_draws and the rest of [`PlanSpec::runs`]): about a minute of work on one core.
pub const MAX_PLAN_RUNS: f64 = 1e6;

/// The most work a plan may ask for, in frames (or integration steps, when a run has more of
/// them) summed over every simulation its search may run: each run costs its frames (samples
/// and the checks on them) or its steps. The example plan is 2.0e7 and takes 0.25 s on two
/// cores; 2e9 is about 30 s on one. A fine grid with a 10^6-frame camera (2e11) took about 20
/// minutes before it was counted this way.
pub const MAX_PLAN_WORK: f64 = 2e9;

/// Frame rates a camera may have (Hz): from 1 to 10^6, the fastest high-speed cameras.
pub const FRAME_RATE_RANGE: [f64; 2] = [1.0, 1e6];
/// Scales a camera may have (m per pixel): from 0.1 um (a microscope) to 1 m; outside, the
/// products with pixel counts leave the range where a rig's travel is meaningful.
pub const METRES_PER_PIXEL_RANGE: [f64; 2] = [1e-7, 1.0];
/// Marker noise a camera may have (pixels): from 1e-3 (better than any tracker) to 1000.
pub const NOISE_PX_RANGE: [f64; 2] = [1e-3, 1e3];
/// The longest recording a plan may simulate (s): ten minutes, far beyond a release's few
/// seconds; each run integrates the whole of it.
pub const MAX_DURATION: f64 = 600.0;
/// The largest magnitude of a position along the rail (m): field of view, rail, release x.
pub const MAX_POSITION: f64 = 1e3;
/// The largest magnitude of a release speed, its range or its error: theta' in rad/s and x'
/// in m/s (a push of 100 rad/s turns a 30 cm rod 16 times a second).
pub const MAX_RELEASE_SPEED: f64 = 100.0;
/// The most pixels or frames a goal's margin may ask for (`min_slide_px`, `min_frames`,
/// `edge_frames`): a recording has at most 10^6 frames.
pub const MAX_GOAL_COUNT: f64 = 1e6;

fn default_edge_frames() -> f64 {
    10.0
}
fn default_min_robustness() -> f64 {
    0.9
}

/// The `[goal]` section: the targets (all must show in one recording) and what observable
/// means for them.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct GoalSpec {
    /// Targets, e.g. `["stick_to_slide", "slide_to_stick", { stick_slip_cycles = 2 }]`.
    pub targets: Vec<Target>,
    /// Least slider travel of the slide next to a transition (pixels). Default 20.
    #[serde(default = "default_min_slide_px")]
    pub min_slide_px: f64,
    /// Least duration of each side of a transition (frames). Default 10.
    #[serde(default = "default_min_frames")]
    pub min_frames: f64,
    /// A transition must not fall in the first or last this many frames. Default 10.
    #[serde(default = "default_edge_frames")]
    pub edge_frames: f64,
    /// Least fraction of draws (mu and release error) that must show every target. Default 0.9.
    #[serde(default = "default_min_robustness")]
    pub min_robustness: f64,
}

/// The optional `[search]` section.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SearchSpec {
    /// Draws per candidate while searching (common to all candidates). Default 32.
    #[serde(default = "SearchSpec::default_draws")]
    pub draws: usize,
    /// Draws of the final check of each proposal (a fresh seed). Default 400.
    #[serde(default = "SearchSpec::default_verify_draws")]
    pub verify_draws: usize,
    /// Seed of every draw. Default 1.
    #[serde(default = "SearchSpec::default_seed")]
    pub seed: u64,
    /// Number of proposals reported. Default 5.
    #[serde(default = "SearchSpec::default_top")]
    pub top: usize,
    /// Grid points along each release range of nonzero width. Default 13.
    #[serde(default = "SearchSpec::default_grid")]
    pub grid_points: usize,
}

impl SearchSpec {
    fn default_draws() -> usize {
        32
    }
    fn default_verify_draws() -> usize {
        400
    }
    fn default_seed() -> u64 {
        1
    }
    fn default_top() -> usize {
        5
    }
    fn default_grid() -> usize {
        13
    }
}

impl Default for SearchSpec {
    fn default() -> Self {
        SearchSpec {
            draws: Self::default_draws(),
            verify_draws: Self::default_verify_draws(),
            seed: Self::default_seed(),
            top: Self::default_top(),
            grid_points: Self::default_grid(),
        }
    }
}

/// A plan file as written.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct PlanFile {
    /// `[rig]`.
    pub rig: PlanRigSpec,
    /// `[friction]`.
    pub friction: FrictionSpec,
    /// `[camera]`.
    pub camera: CameraSpec,
    /// `[release]`.
    pub release: ReleaseSpec,
    /// `[goal]`.
    pub goal: GoalSpec,
    /// `[search]`.
    #[serde(default)]
    pub search: SearchSpec,
}

/// An uncertain friction coefficient.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Uncertain {
    /// Normal draws (clamped at 0).
    Normal {
        /// Mean.
        mean: f64,
        /// Standard deviation.
        sd: f64,
    },
    /// Uniform draws over a range.
    Uniform {
        /// Lower end.
        lo: f64,
        /// Upper end.
        hi: f64,
    },
}

impl Uncertain {
    /// The value for a standard draw `z`: a standard normal for [`Uncertain::Normal`], mapped
    /// through the normal CDF onto the range for [`Uncertain::Uniform`], so one set of draws
    /// serves both kinds.
    pub fn at(&self, z: f64) -> f64 {
        match *self {
            Uncertain::Normal { mean, sd } => (mean + sd * z).max(0.0),
            Uncertain::Uniform { lo, hi } => lo + (hi - lo) * normal_cdf(z),
        }
    }

    /// The mean and standard deviation (a uniform range's: its width over sqrt(12)).
    pub fn mean_sd(&self) -> (f64, f64) {
        match *self {
            Uncertain::Normal { mean, sd } => (mean, sd),
            Uncertain::Uniform { lo, hi } => (0.5 * (lo + hi), (hi - lo) / 12f64.sqrt()),
        }
    }

    /// A plausible span: mean +- 2 sd, or the range.
    pub fn span(&self) -> [f64; 2] {
        match *self {
            Uncertain::Normal { mean, sd } => [(mean - 2.0 * sd).max(0.0), mean + 2.0 * sd],
            Uncertain::Uniform { lo, hi } => [lo, hi],
        }
    }
}

impl fmt::Display for Uncertain {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            // At the deviation's precision (0.17998 +- 0.00032), not an f64's seventeen digits.
            Uncertain::Normal { mean, sd } => {
                write!(f, "{} (sd)", crate::numbers::value_pm(mean, sd))
            }
            Uncertain::Uniform { lo, hi } => write!(f, "[{lo}, {hi}]"),
        }
    }
}

/// Standard normal CDF (Abramowitz-Stegun 7.1.26 erf, 1.5e-7): enough to map draws.
pub(crate) fn normal_cdf(z: f64) -> f64 {
    let x = z.abs() / std::f64::consts::SQRT_2;
    let t = 1.0 / (1.0 + 0.327_591_1 * x);
    let poly = t
        * (0.254_829_592
            + t * (-0.284_496_736
                + t * (1.421_413_741 + t * (-1.453_152_027 + t * 1.061_405_429))));
    let erf = 1.0 - poly * (-x * x).exp();
    if z >= 0.0 {
        0.5 * (1.0 + erf)
    } else {
        0.5 * (1.0 - erf)
    }
}

/// The camera, validated.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    /// Frame rate (Hz).
    pub frame_rate: f64,
    /// m per pixel.
    pub metres_per_pixel: f64,
    /// Marker noise (m).
    pub noise_m: f64,
    /// Duration (s).
    pub duration: f64,
    /// Field of view along the rail (m).
    pub field_of_view: [f64; 2],
}

impl Camera {
    /// Frame times 0, 1/rate, ... up to the duration.
    pub fn frame_times(&self) -> Vec<f64> {
        let n = (self.duration * self.frame_rate + 1e-9).floor() as usize;
        (0..=n).map(|k| k as f64 / self.frame_rate).collect()
    }
}

/// The release mechanism, validated, angles in radians.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Release {
    /// Initial slider position (m).
    pub x: f64,
    /// Range of theta (rad).
    pub theta: [f64; 2],
    /// Range of theta' (rad/s).
    pub theta_dot: [f64; 2],
    /// Range of x' (m/s).
    pub x_dot: [f64; 2],
    /// Usable rail (m).
    pub rail: [f64; 2],
    /// Execution errors (+-, uniform) of (theta rad, theta' rad/s, x' m/s).
    pub error: [f64; 3],
}

/// What observable means, validated.
#[derive(Debug, Clone, PartialEq)]
pub struct Goal {
    /// Targets (all in one recording).
    pub targets: Vec<Target>,
    /// Least slider travel next to a transition (pixels).
    pub min_slide_px: f64,
    /// Least duration of each side of a transition (frames).
    pub min_frames: f64,
    /// Frames excluded at each end of the window.
    pub edge_frames: f64,
    /// Least fraction of draws showing every target.
    pub min_robustness: f64,
}

/// A validated plan: what [`crate::plan::plan`] takes.
#[derive(Debug, Clone, PartialEq)]
pub struct PlanSpec {
    /// The rig at the nominal friction.
    pub rig: Rig<f64>,
    /// The `[rig]` section as the file gives it (an earlier fit's rig is compared with it).
    pub rig_file: PlanRigSpec,
    /// mu_kinetic and its uncertainty.
    pub mu_kinetic: Uncertain,
    /// mu_static and its uncertainty; `None`: equal to mu_kinetic in every draw.
    pub mu_static: Option<Uncertain>,
    /// The law's other parameters with their uncertainties (the Stribeck speed, the
    /// direction law's split, the load exponent), drawn like mu.
    pub law_uncertain: Vec<(crate::fit::Param, Uncertain)>,
    /// The camera.
    pub camera: Camera,
    /// The release mechanism.
    pub release: Release,
    /// What to film and how well.
    pub goal: Goal,
    /// Search settings.
    pub search: SearchSpec,
    /// What an earlier fit knows (`--after`): the releases are then ranked by mu's standard
    /// error with that knowledge added.
    pub prior: Option<super::prior::Prior>,
    /// Laws to tell apart (`friction.discriminate`); empty: those an earlier fit left open,
    /// or none.
    pub discriminate: Vec<super::law::Law>,
}

fn invalid(path: &Path, key: &str, expected: &str, value: impl fmt::Debug) -> SceneError {
    SceneError::Invalid {
        path: path.to_owned(),
        message: format!("{key} must be {expected}, got {value:?}"),
    }
}

fn uncertain(
    path: &Path,
    key: &str,
    mean: f64,
    sd: Option<f64>,
    range: Option<[f64; 2]>,
) -> Result<Uncertain, SceneError> {
    if !(mean.is_finite() && mean >= 0.0) {
        return Err(invalid(path, key, "a finite number >= 0", mean));
    }
    match (sd, range) {
        (Some(_), Some(_)) => Err(SceneError::Invalid {
            path: path.to_owned(),
            message: format!("give friction.{key}_sd or friction.{key}_range, not both"),
        }),
        (Some(sd), None) if !(sd.is_finite() && (0.0..=RIG_MAX).contains(&sd)) => Err(invalid(
            path,
            &format!("friction.{key}_sd"),
            &format!("between 0 and {RIG_MAX:e} (as mu itself)"),
            sd,
        )),
        (Some(sd), None) => Ok(Uncertain::Normal { mean, sd }),
        (None, Some([lo, hi])) if !(lo.is_finite() && 0.0 <= lo && lo <= hi && hi <= RIG_MAX) => {
            Err(invalid(
                path,
                &format!("friction.{key}_range"),
                &format!("[lo, hi] with 0 <= lo <= hi <= {RIG_MAX:e} (as mu itself)"),
                [lo, hi],
            ))
        }
        (None, Some([lo, hi])) if !(lo <= mean && mean <= hi) => Err(invalid(
            path,
            &format!("friction.{key}_range"),
            &format!("a range containing friction.{key} = {mean}"),
            [lo, hi],
        )),
        (None, Some([lo, hi])) => Ok(Uncertain::Uniform { lo, hi }),
        (None, None) => Ok(Uncertain::Normal { mean, sd: 0.0 }),
    }
}

fn range(path: &Path, key: &str, r: [f64; 2]) -> Result<[f64; 2], SceneError> {
    if r[0].is_finite() && r[1].is_finite() && r[0] <= r[1] {
        Ok(r)
    } else {
        Err(invalid(path, key, "[lo, hi] with finite lo <= hi", r))
    }
}

fn positive(path: &Path, key: &str, v: f64) -> Result<f64, SceneError> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(invalid(path, key, "a finite number > 0", v))
    }
}

/// `v` within `[lo, hi]` (`unit` and `why` for the message).
fn bounded(
    path: &Path,
    key: &str,
    v: f64,
    [lo, hi]: [f64; 2],
    unit: &str,
    why: &str,
) -> Result<f64, SceneError> {
    if (lo..=hi).contains(&v) {
        Ok(v)
    } else {
        Err(invalid(
            path,
            key,
            &format!("between {lo:e} and {hi:e}{unit} ({why})"),
            v,
        ))
    }
}

/// A range `[lo, hi]` within +-`limit`.
fn range_within(
    path: &Path,
    key: &str,
    r: [f64; 2],
    limit: f64,
    unit: &str,
) -> Result<[f64; 2], SceneError> {
    let r = range(path, key, r)?;
    if r[0] < -limit || r[1] > limit {
        return Err(invalid(
            path,
            key,
            &format!("[lo, hi] within +-{limit:e}{unit}"),
            r,
        ));
    }
    Ok(r)
}

fn non_negative(path: &Path, key: &str, v: f64) -> Result<f64, SceneError> {
    if v.is_finite() && v >= 0.0 {
        Ok(v)
    } else {
        Err(invalid(path, key, "a finite number >= 0", v))
    }
}

impl PlanSpec {
    /// Read and validate a plan file; errors name the file and the key.
    pub fn from_path(path: &Path) -> Result<Self, SceneError> {
        Self::from_toml(
            &crate::scene::read_text(path, crate::scene::MAX_TOML_BYTES)?,
            path,
        )
    }

    /// Parse and validate plan text; `path` only labels errors.
    pub fn from_toml(text: &str, path: &Path) -> Result<Self, SceneError> {
        crate::scene::parse_toml::<PlanFile>(text, path)?.validate(path)
    }
}

impl PlanFile {
    /// Check every value, naming the first bad key: the sections in the file's order, each
    /// by its own check.
    pub fn validate(&self, path: &Path) -> Result<PlanSpec, SceneError> {
        let rig = self.rig.rig(path, &self.friction)?;
        let (mu_kinetic, mu_static, law_uncertain) = self.friction.uncertainties(path, &rig)?;
        let discriminate = self.friction.discriminate(path)?;
        let camera = self.camera.validate(path)?;
        let release = self.release.validate(path)?;
        let goal = self.goal.validate(path, &camera)?;
        self.search.check_counts(path)?;
        let spec = PlanSpec {
            rig,
            rig_file: self.rig,
            mu_kinetic,
            mu_static,
            law_uncertain,
            camera,
            release,
            goal,
            search: self.search,
            prior: None,
            discriminate,
        };
        spec.check_work(path, None)?;
        Ok(spec)
    }
}

/// The law parameters' uncertainties of a plan's friction: (parameter, uncertainty).
type LawUncertain = Vec<(crate::fit::Param, Uncertain)>;

impl FrictionSpec {
    /// mu_kinetic and mu_static (when given) with their uncertainties, and the law's other
    /// parameters' (of `rig`, the plan's rig built from these keys); an uncertainty without
    /// its value is an error.
    fn uncertainties(
        &self,
        path: &Path,
        rig: &Rig<f64>,
    ) -> Result<(Uncertain, Option<Uncertain>, LawUncertain), SceneError> {
        use crate::fit::Param;
        let f = self;
        let missing = |key: &str| SceneError::Invalid {
            path: path.to_owned(),
            message: format!("friction.{key} is missing (its uncertainty is given)"),
        };
        let mut law = Vec::new();
        let mu_kinetic = match (f.mu_kinetic_positive, f.mu_kinetic_negative) {
            (Some(p), Some(n)) => {
                // Each direction's coefficient drawn on its own: their mean and half
                // difference are then independent with sd sqrt(sd+^2 + sd-^2) / 2 (the
                // same for equal errors).
                let sp = f.mu_kinetic_positive_sd.unwrap_or(0.0);
                let sn = f.mu_kinetic_negative_sd.unwrap_or(0.0);
                for (key, sd) in [
                    ("mu_kinetic_positive_sd", sp),
                    ("mu_kinetic_negative_sd", sn),
                ] {
                    if !(sd.is_finite() && (0.0..=RIG_MAX).contains(&sd)) {
                        return Err(invalid(
                            path,
                            &format!("friction.{key}"),
                            &format!("between 0 and {RIG_MAX:e} (as mu itself)"),
                            sd,
                        ));
                    }
                }
                let sd = 0.5 * sp.hypot(sn);
                law.push((
                    Param::FrictionSplit,
                    Uncertain::Normal {
                        mean: 0.5 * (p - n),
                        sd,
                    },
                ));
                Uncertain::Normal {
                    mean: 0.5 * (p + n),
                    sd,
                }
            }
            _ if f.mu_kinetic_positive_sd.is_some() => return Err(missing("mu_kinetic_positive")),
            _ if f.mu_kinetic_negative_sd.is_some() => return Err(missing("mu_kinetic_negative")),
            _ => uncertain(
                path,
                "mu_kinetic",
                rig.mu_kinetic,
                f.mu_kinetic_sd,
                f.mu_kinetic_range,
            )?,
        };
        let mu_static = match f.mu_static {
            Some(m) => Some(uncertain(
                path,
                "mu_static",
                m,
                f.mu_static_sd,
                f.mu_static_range,
            )?),
            None if f.mu_static_sd.is_some() || f.mu_static_range.is_some() => {
                return Err(missing("mu_static"))
            }
            None => None,
        };
        for (q, key, value, sd, range) in [
            (
                Param::StribeckVelocity,
                "stribeck_velocity",
                f.stribeck_velocity,
                f.stribeck_velocity_sd,
                f.stribeck_velocity_range,
            ),
            (
                Param::LoadExponent,
                "load_exponent",
                f.load_exponent,
                f.load_exponent_sd,
                f.load_exponent_range,
            ),
        ] {
            match value {
                Some(v) => {
                    let u = uncertain(path, key, v, sd, range)?;
                    if u != (Uncertain::Normal { mean: v, sd: 0.0 }) {
                        law.push((q, u));
                    }
                }
                None if sd.is_some() || range.is_some() => return Err(missing(key)),
                None => {}
            }
        }
        Ok((mu_kinetic, mu_static, law))
    }

    /// The laws of `discriminate`, each named once.
    fn discriminate(&self, path: &Path) -> Result<Vec<super::law::Law>, SceneError> {
        use super::law::Law;
        let Some(names) = &self.discriminate else {
            return Ok(Vec::new());
        };
        let mut laws = Vec::new();
        for (i, name) in names.iter().enumerate() {
            let law = Law::from_name(name).ok_or_else(|| {
                invalid(
                    path,
                    &format!("friction.discriminate[{i}]"),
                    "one of \"coulomb\", \"static\", \"stribeck\", \"direction\", \"load\"",
                    name,
                )
            })?;
            if laws.contains(&law) {
                return Err(invalid(
                    path,
                    &format!("friction.discriminate[{i}]"),
                    "a law not named before",
                    name,
                ));
            }
            laws.push(law);
        }
        if laws.len() < 2 {
            return Err(invalid(
                path,
                "friction.discriminate",
                "at least two laws to tell apart",
                names,
            ));
        }
        Ok(laws)
    }
}

/// The rig file's friction keys, named in a plan's messages as its `[friction]` keys.
const FRICTION_KEYS: [&str; 4] = ["mu_", "friction_law", "stribeck_velocity", "load_exponent"];

impl PlanRigSpec {
    /// The plan's rig as a rig file's `[rig]`: its masses, rod, pendulum, gravity and their
    /// deviations, no friction, tilt or damping.
    pub fn rig_spec(&self) -> RigSpec {
        let r = self;
        RigSpec {
            slider_mass: r.slider_mass,
            bob_mass: r.bob_mass,
            rod_length: r.rod_length,
            rod_mass: r.rod_mass,
            bob_radius: r.bob_radius,
            pendulum_mass: r.pendulum_mass,
            pendulum_com: r.pendulum_com,
            pendulum_inertia: r.pendulum_inertia,
            gravity: r.gravity,
            mu_kinetic: None,
            mu_static: None,
            rail_tilt_deg: None,
            pivot_damping: None,
            friction_law: None,
            mu_kinetic_positive: None,
            mu_kinetic_negative: None,
            mu_static_positive: None,
            mu_static_negative: None,
            load_exponent: None,
            stribeck_velocity: None,
            viscous_friction: None,
            rod_length_sd: r.rod_length_sd,
            slider_mass_sd: r.slider_mass_sd,
            bob_mass_sd: r.bob_mass_sd,
            rod_mass_sd: r.rod_mass_sd,
            bob_radius_sd: r.bob_radius_sd,
            gravity_sd: r.gravity_sd,
        }
    }

    /// The rig with the friction's central values, checked as a rig file's by the same
    /// function ([`RigSpec::checked`]: the same ranges and messages, the friction keys named
    /// as the plan's), and its time scale.
    fn rig(&self, path: &Path, f: &FrictionSpec) -> Result<Rig<f64>, SceneError> {
        let spec = RigSpec {
            mu_kinetic: f.mu_kinetic,
            mu_static: f.mu_static,
            friction_law: f.friction_law,
            mu_kinetic_positive: f.mu_kinetic_positive,
            mu_kinetic_negative: f.mu_kinetic_negative,
            mu_static_positive: f.mu_static_positive,
            mu_static_negative: f.mu_static_negative,
            load_exponent: f.load_exponent,
            stribeck_velocity: f.stribeck_velocity,
            ..self.rig_spec()
        };
        let rig = spec.checked(path).map_err(|e| match e {
            SceneError::Invalid { path, message } => SceneError::Invalid {
                path,
                message: FRICTION_KEYS.iter().fold(message, |m, k| {
                    m.replace(&format!("rig.{k}"), &format!("friction.{k}"))
                }),
            },
            e => e,
        })?;
        check_time_scale(
            path,
            &rig,
            RigOrigin::File {
                friction: "friction",
            },
        )?;
        Ok(rig)
    }
}

impl CameraSpec {
    /// The camera: positive rate, scale, noise and duration, a field of view, and a recording
    /// of 2 to 10^6 frames.
    fn validate(&self, path: &Path) -> Result<Camera, SceneError> {
        let c = self;
        let camera = Camera {
            frame_rate: bounded(
                path,
                "camera.frame_rate",
                c.frame_rate,
                FRAME_RATE_RANGE,
                " Hz",
                "up to the fastest high-speed cameras",
            )?,
            metres_per_pixel: bounded(
                path,
                "camera.metres_per_pixel",
                c.metres_per_pixel,
                METRES_PER_PIXEL_RANGE,
                " m",
                "a microscope's scale to a metre a pixel",
            )?,
            noise_m: bounded(
                path,
                "camera.noise_px",
                c.noise_px,
                NOISE_PX_RANGE,
                " px",
                "from better than any tracker to a thousand pixels",
            )? * c.metres_per_pixel,
            duration: bounded(
                path,
                "camera.duration",
                positive(path, "camera.duration", c.duration)?,
                [0.0, MAX_DURATION],
                " s",
                "each simulation integrates the whole recording",
            )?,
            field_of_view: range_within(
                path,
                "camera.field_of_view",
                c.field_of_view,
                MAX_POSITION,
                " m",
            )?,
        };
        if camera.duration * camera.frame_rate < 2.0 {
            return Err(invalid(
                path,
                "camera.duration",
                &format!(
                    "at least 2 frames long (2 / camera.frame_rate = {} s)",
                    2.0 / camera.frame_rate
                ),
                c.duration,
            ));
        }
        if camera.duration * camera.frame_rate > 1e6 {
            return Err(invalid(
                path,
                "camera.duration",
                "at most 10^6 frames long",
                c.duration,
            ));
        }
        Ok(camera)
    }
}

impl ReleaseSpec {
    /// The release ranges: theta within -360..360 degrees (converted to radians), x on the
    /// rail, the speeds' ranges and the non-negative errors.
    fn validate(&self, path: &Path) -> Result<Release, SceneError> {
        let rl = self;
        let theta = range(path, "release.theta_deg", rl.theta_deg)?;
        if theta[0] < -360.0 || theta[1] > 360.0 {
            return Err(invalid(
                path,
                "release.theta_deg",
                "within -360..360 degrees",
                theta,
            ));
        }
        let rail = range_within(path, "release.rail", rl.rail, MAX_POSITION, " m")?;
        if !(rail[0] <= rl.x && rl.x <= rail[1] && rl.x.is_finite()) {
            return Err(invalid(
                path,
                "release.x",
                &format!("on the rail [{}, {}]", rail[0], rail[1]),
                rl.x,
            ));
        }
        let release = Release {
            x: rl.x,
            theta: theta.map(f64::to_radians),
            theta_dot: range_within(
                path,
                "release.theta_dot",
                rl.theta_dot,
                MAX_RELEASE_SPEED,
                " rad/s",
            )?,
            x_dot: range_within(path, "release.x_dot", rl.x_dot, MAX_RELEASE_SPEED, " m/s")?,
            rail,
            error: [
                bounded(
                    path,
                    "release.theta_error_deg",
                    rl.theta_error_deg,
                    [0.0, 360.0],
                    " degrees",
                    "a whole turn at most",
                )?
                .to_radians(),
                bounded(
                    path,
                    "release.theta_dot_error",
                    rl.theta_dot_error,
                    [0.0, MAX_RELEASE_SPEED],
                    " rad/s",
                    "as the push itself",
                )?,
                bounded(
                    path,
                    "release.x_dot_error",
                    rl.x_dot_error,
                    [0.0, MAX_RELEASE_SPEED],
                    " m/s",
                    "as the moving start itself",
                )?,
            ],
        };
        Ok(release)
    }
}

impl GoalSpec {
    /// The goal: some targets (a number of stick-slip cycles at least 1), non-negative
    /// margins, a robustness in [0, 1], and edges shorter than half the `camera`'s recording.
    fn validate(&self, path: &Path, camera: &Camera) -> Result<Goal, SceneError> {
        let g = self;
        if g.targets.is_empty() {
            return Err(invalid(path, "goal.targets", "a non-empty list", "[]"));
        }
        if g.targets.contains(&Target::StickSlipCycles(0)) {
            return Err(invalid(
                path,
                "goal.targets.stick_slip_cycles",
                "at least 1",
                0,
            ));
        }
        let goal = Goal {
            targets: g.targets.clone(),
            min_slide_px: goal_count(path, "goal.min_slide_px", g.min_slide_px)?,
            min_frames: goal_count(path, "goal.min_frames", g.min_frames)?,
            edge_frames: goal_count(path, "goal.edge_frames", g.edge_frames)?,
            min_robustness: if (0.0..=1.0).contains(&g.min_robustness) {
                g.min_robustness
            } else {
                return Err(invalid(
                    path,
                    "goal.min_robustness",
                    "in [0, 1]",
                    g.min_robustness,
                ));
            },
        };
        if 2.0 * goal.edge_frames >= camera.duration * camera.frame_rate {
            return Err(invalid(
                path,
                "goal.edge_frames",
                "less than half the recording's frames",
                goal.edge_frames,
            ));
        }
        Ok(goal)
    }
}

/// A goal's count of pixels or frames: from 0 to [`MAX_GOAL_COUNT`].
fn goal_count(path: &Path, key: &str, v: f64) -> Result<f64, SceneError> {
    bounded(
        path,
        key,
        non_negative(path, key, v)?,
        [0.0, MAX_GOAL_COUNT],
        "",
        "a recording has at most 10^6 frames",
    )
}

impl SearchSpec {
    /// Each count within its range.
    fn check_counts(&self, path: &Path) -> Result<(), SceneError> {
        let s = self;
        for (key, v, lo) in [
            ("search.draws", s.draws, 1),
            ("search.verify_draws", s.verify_draws, 1),
            ("search.top", s.top, 1),
            ("search.grid_points", s.grid_points, 2),
        ] {
            if v < lo || v > 100_000 {
                return Err(invalid(path, key, &format!("in {lo}..=100000"), v));
            }
        }
        Ok(())
    }
}

impl PlanSpec {
    /// The simulations the search may run over the release grid: grid releases x (1 +
    /// draws), the refinement of up to four of them (Nelder-Mead, up to 30 iterations of a
    /// few evaluations each, every one with the draws), the fresh checks (up to 2 x top x
    /// verify_draws: a second round replaces releases failing the first) and, when nothing works, the nearest release's seven wider grids.
    /// Returns (grid releases, simulations).
    pub fn runs(&self) -> (f64, f64) {
        let s = &self.search;
        let release = &self.release;
        let axis = |r: [f64; 2], n: usize| if r[1] <= r[0] { 1 } else { n.max(2) };
        let grid_of = |n: usize, wide: bool| {
            let theta = if wide { n } else { axis(release.theta, n) };
            let push = if wide {
                n.div_ceil(3) * 2 - 1
            } else {
                axis(release.theta_dot, n.div_ceil(3) * 2 - 1)
            };
            (theta * push * axis(release.x_dot, n.div_ceil(2))) as f64
        };
        let draws = 1.0 + s.draws as f64;
        let grid = grid_of(s.grid_points, false);
        let refine = 4.0 * 60.0 * draws;
        let nearest = 7.0 * grid_of(s.grid_points.max(13) + 8, true) * 2.0;
        let checks = 2.0 * (s.top as f64) * (s.verify_draws as f64);
        let runs = grid * draws + checks + refine + nearest;
        (grid, runs)
    }

    /// Check the plan's work before it starts, in the units of work ([`MAX_PLAN_RUNS`]
    /// simulations, [`MAX_PLAN_WORK`] frames or steps over them): a run costs its frames
    /// or, for a fast rig over a long recording, its steps (about 10 per unit of the rig's
    /// fastest rate times the duration). `path` is the plan file, whose `[search]` and
    /// `[camera]` set the work; `after` names the fit whose values moved the rig, if any.
    pub fn check_work(&self, path: &Path, after: Option<&Path>) -> Result<(), SceneError> {
        let s = &self.search;
        let (grid, runs) = self.runs();
        if runs > MAX_PLAN_RUNS {
            return Err(invalid(
                path,
                "search",
                &format!(
                    "at most {MAX_PLAN_RUNS:e} simulations (grid releases x (1 + draws) + 2 x top x verify_draws + the refinement and the nearest release's grids; here {grid} x (1 + {}) + 2 x {} x {} and {:.0} more)",
                    s.draws,
                    s.top,
                    s.verify_draws,
                    runs - grid * (1.0 + s.draws as f64) - (2 * s.top * s.verify_draws) as f64
                ),
                runs,
            ));
        }
        let c = &self.camera;
        let frames = (c.duration * c.frame_rate).floor() + 1.0;
        let steps = 10.0 * rig_time_rate(&self.rig) * c.duration;
        let work = runs * frames.max(steps);
        if work.is_nan() || work > MAX_PLAN_WORK {
            let rig = match after {
                Some(fit) => format!(" (the rig with the values of {})", fit.display()),
                None => String::new(),
            };
            return Err(invalid(
                path,
                "search",
                &format!(
                    "at most {MAX_PLAN_WORK:e} frames (or integration steps) over all its simulations: {runs:.0} simulations x {:.0} {} each (camera.frame_rate x camera.duration{rig}); reduce search.grid_points, search.draws, search.verify_draws or the camera's frames",
                    frames.max(steps),
                    if steps > frames { "steps" } else { "frames" }
                ),
                work,
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_prior_prints_at_its_deviation_s_precision() {
        let fit = Uncertain::Normal {
            mean: 0.17997509399217101,
            sd: 0.00031744466801361996,
        };
        assert_eq!(fit.to_string(), "0.17998 +- 0.00032 (sd)");
        let typed = Uncertain::Normal {
            mean: 0.25,
            sd: 0.05,
        };
        assert_eq!(typed.to_string(), "0.250 +- 0.050 (sd)");
    }

    const GOOD: &str = r#"
[rig]
slider_mass = 0.1
bob_mass = 0.1
rod_length = 0.3
gravity = 9.81
[friction]
mu_kinetic = 0.35
mu_kinetic_sd = 0.05
[camera]
frame_rate = 500.0
metres_per_pixel = 2e-4
noise_px = 0.3
duration = 2.0
field_of_view = [-0.6, 0.6]
[release]
theta_deg = [0.0, 60.0]
rail = [-0.25, 0.25]
[goal]
targets = ["stick_to_slide", { stick_slip_cycles = 2 }]
"#;

    #[test]
    fn parses_targets_and_defaults() {
        let p = PlanSpec::from_toml(GOOD, Path::new("p.toml")).unwrap();
        assert_eq!(
            p.goal.targets,
            vec![Target::StickToSlide, Target::StickSlipCycles(2)]
        );
        assert_eq!(p.search, SearchSpec::default());
        assert!((p.camera.noise_m - 6e-5).abs() < 1e-15);
    }

    #[test]
    fn errors_name_file_and_key() {
        let bad = GOOD.replace("noise_px = 0.3", "noise_px = -1");
        let e = PlanSpec::from_toml(&bad, Path::new("p.toml"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("p.toml") && e.contains("camera.noise_px"), "{e}");
        let bad = GOOD.replace("rail = ", "rial = ");
        let e = PlanSpec::from_toml(&bad, Path::new("p.toml"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("rial"), "{e}");
        let bad = GOOD.replace("mu_kinetic_sd = 0.05", "mu_kinetic_range = [0.4, 0.5]");
        let e = PlanSpec::from_toml(&bad, Path::new("p.toml"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("friction.mu_kinetic_range"), "{e}");
        // A rig file's deviations, checked as a rig file's are.
        let bad = GOOD.replace("rod_length = 0.3", "rod_length = 0.3\nrod_length_sd = 0.2");
        let e = PlanSpec::from_toml(&bad, Path::new("p.toml"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("p.toml") && e.contains("rig.rod_length_sd"),
            "{e}"
        );
        let good = GOOD.replace(
            "rod_length = 0.3",
            "rod_length = 0.3\nrod_length_sd = 0.002",
        );
        let p = PlanSpec::from_toml(&good, Path::new("p.toml")).unwrap();
        assert_eq!(p.rig_file.rig_spec().rod_length_sd, Some(0.002));
    }

    #[test]
    fn uniform_draws_stay_in_range() {
        let u = Uncertain::Uniform { lo: 0.3, hi: 0.4 };
        for z in [-6.0, -1.0, 0.0, 1.0, 6.0] {
            let v = u.at(z);
            assert!((0.3..=0.4).contains(&v));
        }
        assert!((u.at(0.0) - 0.35).abs() < 1e-6);
    }
}
