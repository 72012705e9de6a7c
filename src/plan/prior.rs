//! What a fit already knows, for planning the next release (`appell plan --after FIT.json`):
//! the rig's parameters the fit estimated (mu, and the nuisances it chose: tilt, damping,
//! the pendulum's build), their values for the simulated rig, and their covariance, whose
//! inverse is the information the next release adds to.

use super::spec::{PlanSpec, Uncertain};
use crate::fit::Param;
use crate::model::FrictionLaw;
use crate::scene::{check_rig, check_time_scale, RigOrigin, SceneError};
use nalgebra::DMatrix;
use serde_json::Value;
use std::path::{Path, PathBuf};

/// The largest fit JSON read (a fit's report is tens of kilobytes; a joint one of many
/// releases a few hundred).
const MAX_FIT_JSON: u64 = 16 << 20;

/// The standard errors a fit's covariance may give (the square roots of its diagonal): from
/// 1e-20 to 1e6 in the parameter's unit. A fit of noise-free data reports errors near 1e-12;
/// below 1e-20 the information (1 / variance) loses the release's part to rounding, and a
/// subnormal variance made it infinite (every predicted error null, the verdict "not
/// feasible"); above 1e6 nothing was measured, and the robustness draws of mu would leave
/// the rig's ranges (1e308 printed "+- inf").
pub const STDERR_RANGE: [f64; 2] = [1e-20, 1e6];

/// How far a covariance may be from symmetric: |C_ij - C_ji| at most this times
/// sqrt(C_ii C_jj). A fit's own matrix is symmetric to about 1e-11 of that (its inverse is
/// computed in floating point); a larger difference is an edited or a different matrix.
pub const SYMMETRY_TOLERANCE: f64 = 1e-6;

/// Check a fit's covariance (`shared_covariance.matrix`, finite numbers, square): standard
/// errors within [`STDERR_RANGE`], symmetric within [`SYMMETRY_TOLERANCE`], and positive
/// definite (its correlation matrix has a Cholesky factor, so its scale does not decide).
fn check_covariance(path: &Path, m: &DMatrix<f64>) -> Result<(), SceneError> {
    let [lo, hi] = STDERR_RANGE;
    let n = m.nrows();
    for i in 0..n {
        let var = m[(i, i)];
        let se = var.sqrt();
        if !(var > 0.0 && (lo..=hi).contains(&se)) {
            return Err(invalid(
                path,
                format!(
                    "shared_covariance.matrix[{i}][{i}]: expected a variance whose square root, a standard error, is between {lo:e} and {hi:e}, got {var:e}"
                ),
            ));
        }
    }
    for i in 0..n {
        for j in 0..i {
            let (a, b) = (m[(i, j)], m[(j, i)]);
            if (a - b).abs() > SYMMETRY_TOLERANCE * (m[(i, i)] * m[(j, j)]).sqrt() {
                return Err(invalid(
                    path,
                    format!(
                        "shared_covariance.matrix[{i}][{j}] = {a:e} and [{j}][{i}] = {b:e}: expected a symmetric matrix (within {SYMMETRY_TOLERANCE:e} of sqrt(C_ii C_jj))"
                    ),
                ));
            }
        }
    }
    let scale = m.diagonal().map(|v| 1.0 / v.sqrt());
    let correlation = DMatrix::from_fn(n, n, |i, j| {
        0.5 * (m[(i, j)] + m[(j, i)]) * scale[i] * scale[j]
    });
    if correlation.cholesky().is_none() {
        return Err(invalid(
            path,
            "shared_covariance.matrix: expected a positive definite matrix (a covariance: its correlations have no Cholesky factor, so some combination of the parameters has a variance <= 0)".into(),
        ));
    }
    Ok(())
}

/// A fit's knowledge of the rig's parameters.
#[derive(Debug, Clone, PartialEq)]
pub struct Prior {
    /// The file it came from.
    pub path: PathBuf,
    /// The parameters known (the rig's; a release's state and camera are not carried over).
    pub names: Vec<Param>,
    /// Their fitted values.
    pub values: Vec<f64>,
    /// Their covariance, mu_kinetic's variance from its reported (widened) standard error.
    pub covariance: DMatrix<f64>,
    /// Its inverse: what is known.
    pub information: DMatrix<f64>,
    /// Where the values are in the JSON: `shared` (a joint fit) or `parameters`.
    pub section: &'static str,
    /// What the fit said about the friction laws (for a plan that tells them apart).
    pub laws: Option<super::law::LawTable>,
}

/// A fit's JSON (`appell fit --json`, single or `--joint`), read whole (at most 16 MiB).
pub fn read_json(path: &Path) -> Result<Value, SceneError> {
    let text = crate::scene::read_text(path, MAX_FIT_JSON)?;
    serde_json::from_str(text.trim()).map_err(|e| SceneError::Parse {
        path: path.to_owned(),
        message: format!("not the JSON of `appell fit --json`: {e}"),
    })
}

fn invalid(path: &Path, message: String) -> SceneError {
    SceneError::Invalid {
        path: path.to_owned(),
        message,
    }
}

impl Prior {
    /// Read the JSON of `appell fit --json` (one recording) or `appell fit --joint --json`.
    pub fn from_path(path: &Path) -> Result<Prior, SceneError> {
        Prior::from_json(&read_json(path)?, path)
    }

    /// The prior in a fit's JSON `v` (read from `path`, for messages).
    pub fn from_json(v: &Value, path: &Path) -> Result<Prior, SceneError> {
        // A fit that failed gave no value: what it knows is no prior.
        if let Some(why) = v["failed"].as_str() {
            return Err(invalid(
                path,
                format!("failed: the fit gave no value for mu ({why}); plan from a fit that did"),
            ));
        }
        let cov = &v["shared_covariance"];
        let names = cov["names"].as_array().ok_or_else(|| {
            invalid(
                path,
                "shared_covariance.names: expected the list of the rig's fitted parameters (a fit's JSON from this version)".into(),
            )
        })?;
        let rows = cov["matrix"].as_array().ok_or_else(|| {
            invalid(
                path,
                "shared_covariance.matrix: expected a square matrix".into(),
            )
        })?;
        let n = names.len();
        if rows.len() != n || n == 0 || n > Param::ALL.len() {
            return Err(invalid(
                path,
                format!(
                    "shared_covariance: expected {n} rows for {n} names (1 to {}), got {}",
                    Param::ALL.len(),
                    rows.len()
                ),
            ));
        }
        let mut params: Vec<Param> = Vec::with_capacity(n);
        for (i, name) in names.iter().enumerate() {
            let name = name.as_str().unwrap_or("");
            if let Some(j) = params.iter().position(|q| q.name() == name) {
                return Err(invalid(
                    path,
                    format!(
                        "shared_covariance.names[{i}]: expected each parameter once, got {name:?} again (it is names[{j}])"
                    ),
                ));
            }
            let q = Param::ALL
                .into_iter()
                .find(|q| q.name() == name)
                .ok_or_else(|| {
                    invalid(
                        path,
                        format!(
                            "shared_covariance.names[{i}]: expected a parameter name, got {name:?}"
                        ),
                    )
                })?;
            params.push(q);
        }
        let mut m = DMatrix::zeros(n, n);
        for (i, row) in rows.iter().enumerate() {
            let row = row.as_array().filter(|r| r.len() == n).ok_or_else(|| {
                invalid(
                    path,
                    format!("shared_covariance.matrix[{i}]: expected {n} numbers"),
                )
            })?;
            for (j, x) in row.iter().enumerate() {
                m[(i, j)] = x.as_f64().filter(|x| x.is_finite()).ok_or_else(|| {
                    invalid(
                        path,
                        format!("shared_covariance.matrix[{i}][{j}]: expected a finite number"),
                    )
                })?;
            }
        }
        check_covariance(path, &m)?;
        let section = if v["shared"].is_object() {
            "shared"
        } else {
            "parameters"
        };
        let value = |q: Param| -> Result<f64, SceneError> {
            v[section][q.name()]["value"]
                .as_f64()
                .filter(|x| x.is_finite())
                .ok_or_else(|| {
                    invalid(
                        path,
                        format!("{section}.{}.value: expected a finite number", q.name()),
                    )
                })
        };
        // The rig's parameters only: the marginal covariance of a subset is its block.
        let keep: Vec<usize> = (0..n).filter(|&i| params[i].is_rig()).collect();
        if !keep.iter().any(|&i| params[i] == Param::MuKinetic) {
            return Err(invalid(
                path,
                "shared_covariance: mu_kinetic is not among the fitted parameters (the fit did not measure it)".into(),
            ));
        }
        let covariance = m.select_rows(&keep).select_columns(&keep);
        // Symmetric within SYMMETRY_TOLERANCE (checked): the rounding is averaged away.
        let covariance = (&covariance + covariance.transpose()) * 0.5;
        let information = covariance
            .clone()
            .cholesky()
            .map(|c| c.inverse())
            .ok_or_else(|| {
                invalid(
                    path,
                    "shared_covariance: expected a positive definite matrix".into(),
                )
            })?;
        let names: Vec<Param> = keep.iter().map(|&i| params[i]).collect();
        let values = names.iter().map(|&q| value(q)).collect::<Result<_, _>>()?;
        Ok(Prior {
            path: path.to_owned(),
            names,
            values,
            covariance,
            information,
            section,
            laws: super::law::LawTable::from_json(v),
        })
    }

    /// The fitted value and standard error of `q`, when known.
    pub fn get(&self, q: Param) -> Option<(f64, f64)> {
        let i = self.names.iter().position(|n| *n == q)?;
        Some((self.values[i], self.covariance[(i, i)].max(0.0).sqrt()))
    }

    /// The plan's rig with the fitted values (its friction law the fit's: Stribeck's, the
    /// direction or the load law when the fit chose it), and mu's uncertainty for the robustness draws the fit's: mu_kinetic (and
    /// mu_static when fitted) normal about the values with their standard errors. The rig
    /// they make is checked as any rig ([`check_rig`], [`check_time_scale`]), the errors
    /// naming the fit's JSON and the field its value came from, and so is the plan's work
    /// with it (`plan` names the plan file for that).
    pub fn apply(&self, spec: &mut PlanSpec) -> Result<(), SceneError> {
        use crate::fit::TrajectoryProblem;
        // The law the fit chose: its parameter names it (a split is the direction law's, an
        // exponent the load law's), so that the plan simulates the rail the fit found.
        for (q, law) in [
            (Param::StribeckVelocity, FrictionLaw::Stribeck),
            (Param::FrictionSplit, FrictionLaw::Direction),
            (Param::LoadExponent, FrictionLaw::Load),
        ] {
            if self.names.contains(&q) {
                spec.rig.friction_law = law;
            }
        }
        // The values go in through the fit's own parameter map.
        let mut p = TrajectoryProblem::new(
            Default::default(),
            spec.rig,
            [0.0; 4],
            self.names.clone(),
            Default::default(),
        );
        p.tie_static = !self.names.contains(&Param::MuStatic);
        p.set_values(&nalgebra::DVector::from_column_slice(&self.values));
        let origin = RigOrigin::Fit {
            section: self.section,
            names: &self.names,
            values: &self.values,
        };
        check_rig(&self.path, &p.rig, origin)?;
        check_time_scale(&self.path, &p.rig, origin)?;
        spec.rig = p.rig;
        if let Some((mu, se)) = self.get(Param::MuKinetic) {
            spec.mu_kinetic = Uncertain::Normal { mean: mu, sd: se };
        }
        spec.mu_static = self
            .get(Param::MuStatic)
            .map(|(mean, sd)| Uncertain::Normal { mean, sd });
        Ok(())
    }
}
