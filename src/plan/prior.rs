//! What a fit already knows, for planning the next release (`appell plan --after FIT.json`):
//! the rig's parameters the fit estimated (mu, and the nuisances it chose: tilt, damping,
//! the pendulum's build), their values for the simulated rig, and their covariance, whose
//! inverse is the information the next release adds to.

use super::spec::{PlanSpec, Uncertain};
use crate::fit::Param;
use crate::model::FrictionLaw;
use crate::scene::SceneError;
use nalgebra::DMatrix;
use serde_json::Value;
use std::path::{Path, PathBuf};

/// The largest fit JSON read (a fit's report is tens of kilobytes; a joint one of many
/// releases a few hundred).
const MAX_FIT_JSON: u64 = 16 << 20;

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
        let text = crate::scene::read_text(path, MAX_FIT_JSON)?;
        let v: Value = serde_json::from_str(text.trim()).map_err(|e| SceneError::Parse {
            path: path.to_owned(),
            message: format!("not the JSON of `appell fit --json`: {e}"),
        })?;
        Prior::from_json(&v, path)
    }

    /// The prior in a fit's JSON `v` (read from `path`, for messages).
    pub fn from_json(v: &Value, path: &Path) -> Result<Prior, SceneError> {
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
        let mut params = Vec::with_capacity(n);
        for (i, name) in names.iter().enumerate() {
            let name = name.as_str().unwrap_or("");
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
        let value = |q: Param| -> Result<f64, SceneError> {
            let e = if v["shared"].is_object() {
                &v["shared"][q.name()]
            } else {
                &v["parameters"][q.name()]
            };
            e["value"]
                .as_f64()
                .filter(|x| x.is_finite())
                .ok_or_else(|| {
                    invalid(
                        path,
                        format!("{}.value: expected a finite number", q.name()),
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
        })
    }

    /// The fitted value and standard error of `q`, when known.
    pub fn get(&self, q: Param) -> Option<(f64, f64)> {
        let i = self.names.iter().position(|n| *n == q)?;
        Some((self.values[i], self.covariance[(i, i)].max(0.0).sqrt()))
    }

    /// The plan's rig with the fitted values (its friction law Stribeck's when the fit chose
    /// it), and mu's uncertainty for the robustness draws the fit's: mu_kinetic (and
    /// mu_static when fitted) normal about the values with their standard errors.
    pub fn apply(&self, spec: &mut PlanSpec) {
        use crate::fit::TrajectoryProblem;
        if self.names.contains(&Param::StribeckVelocity) {
            spec.rig.friction_law = FrictionLaw::Stribeck;
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
        spec.rig = p.rig;
        if let Some((mu, se)) = self.get(Param::MuKinetic) {
            spec.mu_kinetic = Uncertain::Normal { mean: mu, sd: se };
        }
        spec.mu_static = self
            .get(Param::MuStatic)
            .map(|(mean, sd)| Uncertain::Normal { mean, sd });
    }
}
