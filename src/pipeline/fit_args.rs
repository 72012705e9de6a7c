//! The fit's options as the CLI names them (`appell fit --robust huber ...`; the Python
//! package's keyword arguments), checked into [`FitSettings`] with the CLI's messages.

use crate::fit::{FitSettings, Loss, Nuisance, StaticMode};
use crate::model::FrictionLaw;

/// The names `--mu-static` takes.
pub const MU_STATIC_MODES: [&str; 3] = ["auto", "tied", "fixed"];

/// The names `--robust` takes.
pub const ROBUST_LOSSES: [&str; 2] = ["huber", "cauchy"];

/// How a recording is fitted: every `appell fit` flag that is not about reading the recording
/// or where the answer goes. Flatten into a command with `#[command(flatten)]`.
#[derive(Debug, Clone, clap::Args)]
pub struct FitArgs {
    /// The lab's latitude (deg, -90 to 90): a rig file without `gravity` takes Earth's normal
    /// gravity there instead of 9.81 m/s^2 (a file's `gravity` is used as written).
    #[arg(long, value_name = "DEG", allow_negative_numbers = true, value_parser = latitude)]
    pub latitude: Option<f64>,
    /// The lab's altitude (m) with --latitude (default 0, sea level).
    #[arg(long, value_name = "M", requires = "latitude", allow_negative_numbers = true, value_parser = altitude)]
    pub altitude: Option<f64>,
    /// Robust loss for mis-tracked frames.
    #[arg(long, value_parser = ROBUST_LOSSES)]
    pub robust: Option<String>,
    /// Also fit the rod length.
    #[arg(long)]
    pub fit_rod_length: bool,
    /// mu_static: freed when the recording shows a stick-to-slide onset (auto), always equal
    /// to mu_kinetic (tied), or held at the rig's value (fixed).
    #[arg(long, default_value = "auto", value_parser = MU_STATIC_MODES)]
    pub mu_static: String,
    /// Skip the profile intervals (faster; intervals are then value +- 1.96 stderr).
    #[arg(long)]
    pub no_profile: bool,
    /// Extra starting values of mu_kinetic for the multi-start search.
    #[arg(long, value_delimiter = ',', value_name = "MU,...")]
    pub starts: Vec<f64>,
    /// Known measurement noise per coordinate instead of the one measured from the tracks:
    /// one value for both markers or `SLIDER,BOB`, in metres, or in pixels with a `px` suffix
    /// (with --scale), e.g. `0.0002` or `0.5px,0.8px`.
    #[arg(long, value_delimiter = ',', value_name = "NOISE[,NOISE]")]
    pub noise: Vec<String>,
    /// The plain model only: no physics or camera nuisances and no check of the windows
    /// (faster; the chi-square against the measured noise still shows a misfit).
    #[arg(long)]
    pub plain: bool,
    /// Put these nuisances in the model whatever the data say (e.g. a rail known to be
    /// tilted): mu_static, stribeck, direction, load, rail_tilt, pivot_damping, viscous_friction, camera_scale,
    /// bob_marker_offset, bob_marker_across, slider_marker_offset, marker_lag, rigid_pendulum. With --plain, only these.
    #[arg(long, value_delimiter = ',', value_name = "NUISANCE,...", value_parser = nuisance)]
    pub with: Vec<Nuisance>,
    /// Force the rail's friction law instead of letting the data choose: coulomb, stribeck,
    /// direction (coefficients differ by sliding direction) or load (friction a power of the
    /// normal force). Static above kinetic is --mu-static.
    #[arg(long, value_name = "LAW", value_parser = friction_law)]
    pub friction: Option<FrictionLaw>,
}

/// The most extra starting values `--starts` takes.
pub const MAX_STARTS: usize = 20;

impl Default for FitArgs {
    /// The CLI's defaults (`appell fit` with no fit flags).
    fn default() -> Self {
        FitArgs {
            latitude: None,
            altitude: None,
            robust: None,
            fit_rod_length: false,
            mu_static: "auto".into(),
            no_profile: false,
            starts: Vec::new(),
            noise: Vec::new(),
            plain: false,
            with: Vec::new(),
            friction: None,
        }
    }
}

/// Parse a `--friction` law name.
pub fn friction_law(name: &str) -> Result<FrictionLaw, String> {
    FrictionLaw::ALL
        .into_iter()
        .find(|l| l.name() == name)
        .ok_or_else(|| {
            let names: Vec<&str> = FrictionLaw::ALL.iter().map(|l| l.name()).collect();
            format!("expected one of {}", names.join(", "))
        })
}

/// Parse one `--with` name.
pub fn nuisance(name: &str) -> Result<Nuisance, String> {
    Nuisance::ALL
        .into_iter()
        .find(|n| n.name() == name)
        .ok_or_else(|| {
            let names: Vec<&str> = Nuisance::ALL.iter().map(|n| n.name()).collect();
            format!("expected one of {}", names.join(", "))
        })
}

/// `v` within `[lo, hi]`, for `--latitude` and `--altitude`.
fn within(v: Option<f64>, [lo, hi]: [f64; 2], unit: &str) -> Result<f64, String> {
    match v {
        Some(v) if (lo..=hi).contains(&v) => Ok(v),
        _ => Err(format!("expected a number of {unit} from {lo} to {hi}")),
    }
}

/// `--latitude` (deg) checked.
fn latitude_value(v: Option<f64>) -> Result<f64, String> {
    within(v, crate::scene::LATITUDE_RANGE, "degrees")
}

/// `--altitude` (m) checked.
fn altitude_value(v: Option<f64>) -> Result<f64, String> {
    within(v, crate::scene::ALTITUDE_RANGE, "metres")
}

/// Parse `--latitude` (deg).
fn latitude(text: &str) -> Result<f64, String> {
    latitude_value(text.trim().parse().ok())
}

/// Parse `--altitude` (m).
fn altitude(text: &str) -> Result<f64, String> {
    altitude_value(text.trim().parse().ok())
}

impl FitArgs {
    /// The lab's site for Earth's normal gravity: (latitude deg, altitude m), checked (clap
    /// checks the command line; other callers get the same message here).
    pub fn site(&self) -> Result<Option<(f64, f64)>, String> {
        let check = |flag: &str, v: f64, range: fn(Option<f64>) -> Result<f64, String>| {
            range(Some(v)).map_err(|e| format!("{flag}: {e}, got {v}"))
        };
        match (self.latitude, self.altitude) {
            (None, None) => Ok(None),
            (None, Some(_)) => Err("--altitude needs --latitude".into()),
            (Some(lat), alt) => Ok(Some((
                check("--latitude", lat, latitude_value)?,
                check("--altitude", alt.unwrap_or(0.0), altitude_value)?,
            ))),
        }
    }

    /// `--noise`: metres, or pixels (`px` suffix) times the recording's `--scale`.
    fn noise(&self, scale: Option<f64>) -> Result<Option<[f64; 2]>, String> {
        if self.noise.is_empty() {
            return Ok(None);
        }
        if self.noise.len() > 2 {
            return Err(format!(
                "--noise takes one value or SLIDER,BOB, got {} values",
                self.noise.len()
            ));
        }
        let one = |text: &str| -> Result<f64, String> {
            let (num, px) = match text.trim().strip_suffix("px") {
                Some(n) => (n, true),
                None => (text.trim().strip_suffix('m').unwrap_or(text.trim()), false),
            };
            let v: f64 = num
                .trim()
                .parse()
                .map_err(|_| format!("--noise: expected a number of metres or pixels (e.g. 0.0002 or 0.5px), got {text:?}"))?;
            let v = if px {
                let scale = scale.ok_or_else(|| {
                    format!("--noise {text}: pixels need --scale (metres per pixel)")
                })?;
                v * scale
            } else {
                v
            };
            if v.is_finite() && v > 0.0 {
                Ok(v)
            } else {
                Err(format!("--noise must be positive and finite, got {text:?}"))
            }
        };
        let slider = one(&self.noise[0])?;
        let bob = match self.noise.get(1) {
            Some(b) => one(b)?,
            None => slider,
        };
        Ok(Some([slider, bob]))
    }

    /// The fit's settings, before the rig file's measurement is added
    /// ([`super::FitSetup`]); `scale` is the recording's `--scale` (pixel noise).
    pub fn settings(&self, scale: Option<f64>) -> Result<FitSettings, String> {
        let named = |flag: &str, v: &str, names: &[&str]| {
            if names.contains(&v) {
                Ok(())
            } else {
                Err(format!(
                    "{flag} must be one of {}, got {v:?}",
                    names.join(", ")
                ))
            }
        };
        named("--mu-static", &self.mu_static, &MU_STATIC_MODES)?;
        if let Some(r) = &self.robust {
            named("--robust", r, &ROBUST_LOSSES)?;
        }
        if let Some(bad) = self.starts.iter().find(|s| !(s.is_finite() && **s >= 0.0)) {
            return Err(format!(
                "--starts: each start must be a finite mu >= 0, got {bad}"
            ));
        }
        // Each start is a full solve: a bound keeps a long list from running for hours.
        if self.starts.len() > MAX_STARTS {
            return Err(format!(
                "--starts: at most {MAX_STARTS} extra starts, got {}",
                self.starts.len()
            ));
        }
        Ok(FitSettings {
            fit_rod_length: self.fit_rod_length,
            mu_static: match self.mu_static.as_str() {
                "tied" => StaticMode::Tied,
                "fixed" => StaticMode::Fixed,
                _ => StaticMode::Auto,
            },
            loss: match self.robust.as_deref() {
                Some("huber") => Loss::Huber(3.0),
                Some("cauchy") => Loss::Cauchy(3.0),
                _ => Loss::Squares,
            },
            extra_starts: self.starts.clone(),
            profile: !self.no_profile,
            noise: self.noise(scale)?,
            nuisances: !self.plain,
            windows: !self.plain,
            with: self.with.clone(),
            friction: self.friction,
            ..FitSettings::default()
        })
    }
}
