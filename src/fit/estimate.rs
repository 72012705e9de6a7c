//! An estimated value and its interval ([`Estimate`]), mu_kinetic's error in its parts
//! ([`MuParts`]) and a rig value taken as a measurement ([`RigValue`]).

use super::priors;
use super::problem::Param;

/// An estimated parameter.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Estimate {
    /// Best-fit value.
    pub value: f64,
    /// Standard error: from the Jacobian scaled by max(1, reduced chi-square), or from the
    /// block covariance when that is larger.
    pub stderr: f64,
    /// 95% interval (how it was computed: [`Estimate::interval`]).
    pub ci95: [f64; 2],
    /// How the interval was computed: `profile`, `wald` (value +- 1.96 stderr), with
    /// `+block` when widened for correlated residuals and `+windows` when widened to cover
    /// the windows' values, and `+models` when it carries the spread of close models.
    pub interval: &'static str,
}

impl Estimate {
    /// A Wald estimate: `value` +- 1.96 `stderr`.
    pub fn wald(value: f64, stderr: f64) -> Estimate {
        Estimate {
            value,
            stderr,
            ci95: [value - 1.96 * stderr, value + 1.96 * stderr],
            interval: "wald",
        }
    }
}

/// mu_kinetic's standard error in its parts, each a standard deviation; the total is their
/// root sum of squares (the reported standard error).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct MuParts {
    /// From the recording's noise, the rig's measured values held (its correlation in time
    /// included).
    pub noise: f64,
    /// From the rig file's measurement errors the recording cannot correct.
    pub rig: f64,
    /// From the model: the spread of adequate and close models, the windows, the path.
    pub model: f64,
    /// The whole standard error.
    pub total: f64,
}

/// A rig value the fit took as a measurement: what the file says and what the fit found.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct RigValue {
    /// The parameter (`rod_length`, `equivalent_mass_ratio`).
    pub param: &'static str,
    /// The rig file's value.
    pub file: f64,
    /// Its standard deviation (stated, or the default).
    pub sd: f64,
    /// The fitted value.
    pub value: f64,
    /// Its standard error.
    pub stderr: f64,
    /// (value - file) / sd: how far the recording moved it, in the file's deviations.
    pub z: f64,
}

impl RigValue {
    /// The rig file's measured values among fitted `params` (the rod length and the mass
    /// ratio), `prior_on` giving the file's prior on each.
    pub(crate) fn of<'a>(
        params: &[(Param, Estimate)],
        prior_on: impl Fn(Param) -> Option<&'a priors::Prior>,
    ) -> Vec<RigValue> {
        params
            .iter()
            .filter(|(q, _)| q.is_measured())
            .filter_map(|(q, e)| {
                let pr = prior_on(*q)?;
                Some(RigValue {
                    param: q.name(),
                    file: pr.centre,
                    sd: pr.sd,
                    value: e.value,
                    stderr: e.stderr,
                    z: (e.value - pr.centre) / pr.sd,
                })
            })
            .collect()
    }

    /// Whether the data moved it beyond 3 of the file's deviations: worth a warning.
    pub(crate) fn off(&self) -> bool {
        self.z.abs() > 3.0
    }

    /// What `who` ("the recording puts") says of it, for warnings.
    pub(crate) fn said(&self, who: &str) -> String {
        format!(
            "{who} {} at {:.6} +- {:.1e}, {:.1} of the rig file's deviations from its {:.6} +- {:.1e}",
            self.param, self.value, self.stderr, self.z, self.file, self.sd
        )
    }
}
