//! How to fit ([`FitSettings`]): the loss, mu_static's mode, the solver's budgets and the
//! nuisances forced or excluded. The vocabulary every stage of the fit reads.

use super::priors;
use super::select::Nuisance;
use crate::model::FrictionLaw;
use crate::sim::Options;

/// Loss applied to the standardised residuals.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Loss {
    /// Plain least squares (mis-tracked frames are dropped before the fit and after it).
    #[default]
    Squares,
    /// Huber loss with threshold k (in noise standard deviations): mis-tracked frames count
    /// linearly, not quadratically.
    Huber(f64),
    /// Cauchy loss with scale k: outliers are down-weighted further.
    Cauchy(f64),
}

/// Whether mu_static is estimated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum StaticMode {
    /// A candidate model when the recording shows a stick-to-slide onset; the data choose.
    #[default]
    Auto,
    /// Always equal to mu_kinetic.
    Tied,
    /// Fixed at the rig's value.
    Fixed,
}

/// How to fit.
#[derive(Debug, Clone, PartialEq)]
pub struct FitSettings {
    /// Also estimate the rod length.
    pub fit_rod_length: bool,
    /// Treatment of mu_static.
    pub mu_static: StaticMode,
    /// Loss on standardised residuals.
    pub loss: Loss,
    /// Extra starting values of mu_kinetic (besides the data's, the rig's and a low one).
    pub extra_starts: Vec<f64>,
    /// Compute the profile-likelihood interval for mu_kinetic.
    pub profile: bool,
    /// Integrator settings for predictions.
    pub options: Options,
    /// Most Levenberg-Marquardt iterations per fit.
    pub max_iters: u64,
    /// Iterations a start of a candidate model gets before those far behind the round's best
    /// are left where they stopped (0: every candidate fitted to the end, the laws too, with
    /// no out-of-reach stop; see the selection).
    pub first_iters: u64,
    /// Known noise per marker (slider, bob), m; `None`: measured from the tracks.
    pub noise: Option<[f64; 2]>,
    /// Let the data add physics and camera nuisances (tilt, damping, friction laws, scale,
    /// marker offsets, lag); off: the plain model only (faster).
    pub nuisances: bool,
    /// Fit the recording's windows (cut by the motion, a slide each) and widen the interval
    /// when they disagree.
    pub windows: bool,
    /// Nuisances put in the model whatever the data say (a rail known to be tilted); the
    /// selection adds others on top.
    pub with: Vec<Nuisance>,
    /// The friction law the user forces (`--friction LAW`): the other laws are not offered.
    /// `None`: the data choose among Coulomb's, static above kinetic, Stribeck's, the
    /// direction and the load law.
    pub friction: Option<FrictionLaw>,
    /// A recording with more than twice this many frames is long: its starts and candidate
    /// models are fitted on these first frames and the winner carried over the rest by
    /// doubling the length; its profile intervals are checked at the Wald ends first.
    pub long_prefix: usize,
    /// The rig file as a measurement: its rod length and mass ratio are fitted with these
    /// priors (errors in variables). `None`: the rig is taken as exact.
    pub measured: Option<priors::RigMeasurement>,
    /// The camera scale set from a length the lab measured (`--rod-length`, a ruler in view),
    /// as the relative standard deviation of that measurement: the camera scale is then
    /// fitted with this prior, so the ruler's millimetre reaches mu's interval. `None`: the
    /// scale is taken as the file or `--scale` gives it.
    pub scale_sd: Option<f64>,
}

impl FitSettings {
    /// The nuisances forced: `--with`'s, the law of `--friction`, and the camera scale when
    /// it was set from a measured length ([`FitSettings::scale_sd`]).
    pub fn forced(&self) -> Vec<Nuisance> {
        let mut forced = self.with.clone();
        if self.scale_sd.is_some() && !forced.contains(&Nuisance::CameraScale) {
            forced.push(Nuisance::CameraScale);
        }
        if let Some(nu) = self
            .friction
            .and_then(|law| Nuisance::ALL.into_iter().find(|n| n.law() == Some(law)))
        {
            if !forced.contains(&nu) {
                forced.push(nu);
            }
        }
        forced
    }

    /// The nuisances never offered: with `--friction`, every other law.
    pub fn excluded(&self) -> Vec<Nuisance> {
        match self.friction {
            None => Vec::new(),
            Some(law) => Nuisance::ALL
                .into_iter()
                .filter(|n| n.law().is_some_and(|l| l != law))
                .collect(),
        }
    }
}

impl Default for FitSettings {
    fn default() -> Self {
        FitSettings {
            fit_rod_length: false,
            mu_static: StaticMode::Auto,
            loss: Loss::Squares,
            extra_starts: Vec::new(),
            profile: true,
            options: Options {
                rtol: 1e-9,
                atol: 1e-11,
                ..Options::default()
            },
            max_iters: 60,
            first_iters: 15,
            noise: None,
            nuisances: true,
            windows: true,
            with: Vec::new(),
            friction: None,
            long_prefix: PREFIX_FRAMES,
            measured: None,
            scale_sd: None,
        }
    }
}

/// The default [`FitSettings::long_prefix`]: frames a long recording's starts and candidate
/// models are fitted on (recordings up to twice this are fitted whole from every start).
pub const PREFIX_FRAMES: usize = 8000;
