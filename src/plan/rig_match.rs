//! Whether an earlier fit (`plan --after FIT.json`) is of the plan's rig: the masses, the rod
//! and the pendulum of the fit's rig file (its JSON's `rig_measured.keys`; a JSON without them
//! is compared by the rod length and mass ratio it fitted) against the plan's `[rig]`, each
//! difference in the two sides' combined standard deviations. A fit of another rig is
//! refused: its mu and its covariance describe another rig, and the plan's promise ("shrinks
//! mu's error by a factor 42.76") would be about neither.
//!
//! Each side's deviations are its file's `_sd` keys or the defaults of a ruler and a kitchen
//! scale ([`RigMeasurement::from_spec`]); a fitted value's, its standard error.

use super::spec::PlanRigSpec;
use crate::fit::priors::RigMeasurement;
use crate::numbers::value_pm;
use crate::scene::SceneError;
use serde_json::Value;
use std::path::Path;

/// Differences beyond this many combined standard deviations are another rig: one rig measured
/// twice differs by more than 5 sd with probability 6e-7 (normal errors), while a slider of
/// twice the mass is 15 sd of a kitchen scale away (docs/plan.md gives the counts measured).
pub const MAX_SD_APART: f64 = 5.0;

/// One measured quantity of a rig as a file gives it.
#[derive(Debug, Clone, PartialEq)]
struct Measured {
    /// The quantity (`slider_mass`, `rod_length`, `mass ratio`, ...).
    what: &'static str,
    /// Where it is in its file (`rig.slider_mass`, `parameters.rod_length`).
    field: String,
    value: f64,
    sd: f64,
    /// Where the deviation came from (`stated`, `default`, `fitted`).
    source: String,
    unit: &'static str,
}

impl Measured {
    fn text(&self) -> String {
        if self.sd == 0.0 && self.value == 0.0 {
            return format!("none ({})", self.source);
        }
        let unit = if self.unit.is_empty() {
            String::new()
        } else {
            format!(" {}", self.unit)
        };
        format!(
            "{}{unit} ({}, {})",
            value_pm(self.value, self.sd),
            self.field,
            self.source
        )
    }
}

/// A quantity the two rigs differ in.
#[derive(Debug, Clone, PartialEq)]
pub struct Mismatch {
    /// The quantity compared.
    pub what: &'static str,
    /// The fit's value, its deviation and field, in words.
    pub fit: String,
    /// The plan's.
    pub plan: String,
    /// How many combined standard deviations apart (infinite for exact values that differ).
    pub sd_apart: f64,
}

fn unit_of(what: &str) -> &'static str {
    match what {
        "slider_mass" | "bob_mass" | "rod_mass" => "kg",
        "rod_length" | "bob_radius" => "m",
        _ => "",
    }
}

/// The plan's `[rig]` as the fit would take it: every value with its stated deviation (`_sd`)
/// or that of a ruler and a kitchen scale.
fn plan_measurement(rig: &PlanRigSpec) -> RigMeasurement {
    RigMeasurement::from_spec(&rig.rig_spec())
}

/// The pendulum as a rig file describes it, in words.
fn pendulum_kind(rod_mass: f64, bob_radius: f64, body: bool) -> &'static str {
    if body {
        "a rigid pendulum (pendulum_mass, pendulum_com, pendulum_inertia)"
    } else if rod_mass > 0.0 || bob_radius > 0.0 {
        "a rigid pendulum (a rod with mass or a bob with size)"
    } else {
        "a point bob on a light rod or thread"
    }
}

/// The rod length and the mass ratio the fit's recording fitted (a fit's JSON without its rig
/// file's keys: an earlier version's), each against the plan's. A rigid pendulum the data
/// found (the fit's `pendulum`) changes the equivalent ratio and the plan takes it over from
/// the fit: the ratio is not compared then.
fn fitted_pairs(
    fit: &Value,
    pm: &RigMeasurement,
    plan_key: &dyn Fn(&'static str) -> Option<Measured>,
    pairs: &mut Vec<(Measured, Measured)>,
) {
    let section = if fit["shared"].is_object() {
        "shared"
    } else {
        "parameters"
    };
    let found_pendulum = !fit["pendulum"].is_null() || !fit[section]["pendulum_length"].is_null();
    let fitted = |name: &str| -> Option<(f64, f64)> {
        let e = &fit[section][name];
        let v = e["value"].as_f64().filter(|v| v.is_finite())?;
        let se = e["stderr"]
            .as_f64()
            .filter(|v| v.is_finite() && *v >= 0.0)?;
        Some((v, se))
    };
    if let (Some((v, se)), Some(p)) = (fitted("rod_length"), plan_key("rod_length")) {
        pairs.push((
            Measured {
                what: "rod_length",
                field: format!("{section}.rod_length"),
                value: v,
                sd: se,
                source: "fitted to its recording".into(),
                unit: "m",
            },
            p,
        ));
    }
    let (r, sd) = pm.mass_ratio;
    if let (false, Some((v, se)), true) = (
        found_pendulum,
        fitted("equivalent_mass_ratio"),
        r.is_finite(),
    ) {
        pairs.push((
            Measured {
                what: "mass ratio",
                field: format!("{section}.equivalent_mass_ratio"),
                value: v,
                sd: se,
                source: "fitted to its recording".into(),
                unit: "",
            },
            Measured {
                what: "mass ratio",
                field: "rig.slider_mass / rig.bob_mass".into(),
                value: r,
                sd,
                source: "as the dynamics use it, default sd".into(),
                unit: "",
            },
        ));
    }
}

/// The rigs of the fit's JSON `fit` (read from `fit_path`) and of the plan's `[rig]` (from
/// `plan_path`) compared quantity by quantity: the differences beyond [`MAX_SD_APART`]
/// combined standard deviations, largest first, and notes on what the JSON does not say.
pub fn compare(fit: &Value, plan: &PlanRigSpec) -> (Vec<Mismatch>, Vec<String>) {
    let pm = plan_measurement(plan);
    let plan_key = |what: &'static str| -> Option<Measured> {
        let found = pm.keys.iter().find(|k| k.0 == what);
        let (value, sd, source) = match (found, what) {
            (Some(k), _) => (k.1, k.2, format!("{} sd", k.3)),
            // A plan without a rod mass or a bob radius gives them as zero.
            (None, "rod_mass") => (
                plan.rod_mass.unwrap_or(0.0),
                0.0,
                "not in the plan's [rig]".into(),
            ),
            (None, "bob_radius") => (
                plan.bob_radius.unwrap_or(0.0),
                0.0,
                "not in the plan's [rig]".into(),
            ),
            _ => return None,
        };
        Some(Measured {
            what,
            field: format!("rig.{what}"),
            value,
            sd,
            source,
            unit: unit_of(what),
        })
    };
    let mut pairs: Vec<(Measured, Measured)> = Vec::new();
    let mut notes = Vec::new();
    // The fit's rig file as it listed it: the rig the lab described, whatever the recording
    // then made of the rod and the ratio (a misfitting model may pull a fitted ratio 12 of
    // the file's deviations away on the rig the file describes).
    let keys = fit["rig_measured"]["keys"]
        .as_array()
        .filter(|k| !k.is_empty());
    if let Some(keys) = keys {
        let fit_key = |what: &'static str| -> Option<Measured> {
            let (i, k) = keys
                .iter()
                .enumerate()
                .find(|(_, k)| k["key"].as_str() == Some(what))?;
            let value = k["value"].as_f64().filter(|v| v.is_finite())?;
            let sd = k["sd"].as_f64().filter(|v| v.is_finite() && *v >= 0.0)?;
            let source = k["source"].as_str().unwrap_or("default");
            Some(Measured {
                what,
                field: format!("rig_measured.keys[{i}]"),
                value,
                sd,
                source: format!("its rig file's {what}, {source} sd"),
                unit: unit_of(what),
            })
        };
        for what in [
            "slider_mass",
            "bob_mass",
            "rod_length",
            "rod_mass",
            "bob_radius",
        ] {
            let f = fit_key(what).or_else(|| {
                // The fit lists a rod mass and a bob radius only when they are not zero.
                matches!(what, "rod_mass" | "bob_radius").then(|| Measured {
                    what,
                    field: "rig_measured.keys".into(),
                    value: 0.0,
                    sd: 0.0,
                    source: format!("its rig file gives no {what}"),
                    unit: unit_of(what),
                })
            });
            if let (Some(f), Some(p)) = (f, plan_key(what)) {
                pairs.push((f, p));
            }
        }
    } else {
        fitted_pairs(fit, &pm, &plan_key, &mut pairs);
        notes.push(
            "the fit's JSON does not list its rig file's values (rig_measured.keys): the rod length and the mass ratio it fitted are compared with the plan's instead"
                .to_owned(),
        );
    }
    if pairs.is_empty() {
        notes.push(
            "the fit's JSON says nothing of its rig (no rig_measured.keys, no fitted rod_length or equivalent_mass_ratio): it is not compared with the plan's"
                .to_owned(),
        );
    }
    let fit_kind = keys.map(|_| {
        let get = |w| {
            pairs
                .iter()
                .find(|(f, _)| f.what == w)
                .map_or(0.0, |(f, _)| f.value)
        };
        pendulum_kind(get("rod_mass"), get("bob_radius"), false)
    });
    let plan_kind = pendulum_kind(
        plan.rod_mass.unwrap_or(0.0),
        plan.bob_radius.unwrap_or(0.0),
        plan.pendulum_mass.is_some(),
    );
    let mut out: Vec<Mismatch> = pairs
        .into_iter()
        .filter_map(|(f, p)| {
            let combined = f.sd.hypot(p.sd);
            let diff = (f.value - p.value).abs();
            let apart = if combined > 0.0 {
                diff / combined
            } else if diff > 1e-9 * f.value.abs().max(p.value.abs()) {
                f64::INFINITY
            } else {
                0.0
            };
            if apart <= MAX_SD_APART {
                return None;
            }
            let (mut fit_text, mut plan_text) = (f.text(), p.text());
            if let (true, Some(k)) = (matches!(f.what, "rod_mass" | "bob_radius"), fit_kind) {
                fit_text = format!("{fit_text}: {k}");
                plan_text = format!("{plan_text}: {plan_kind}");
            }
            Some(Mismatch {
                what: f.what,
                fit: fit_text,
                plan: plan_text,
                sd_apart: apart,
            })
        })
        .collect();
    out.sort_by(|a, b| b.sd_apart.total_cmp(&a.sd_apart));
    (out, notes)
}

/// [`compare`], refusing a fit of another rig: the error names both files, each quantity,
/// both values with their deviations and how far apart they are.
pub fn check(
    fit: &Value,
    fit_path: &Path,
    plan: &PlanRigSpec,
    plan_path: &Path,
) -> Result<Vec<String>, SceneError> {
    let (mismatches, notes) = compare(fit, plan);
    if mismatches.is_empty() {
        return Ok(notes);
    }
    let what: Vec<String> = mismatches
        .iter()
        .map(|m| {
            let apart = if m.sd_apart.is_finite() {
                format!("{:.1} combined sd apart", m.sd_apart)
            } else {
                "different, both stated exact".to_owned()
            };
            format!(
                "{}: the fit's {} against the plan's {} in {} ({apart})",
                m.what,
                m.fit,
                m.plan,
                plan_path.display()
            )
        })
        .collect();
    Err(SceneError::Invalid {
        path: fit_path.to_owned(),
        message: format!(
            "the fit is of another rig than the plan's (more than {MAX_SD_APART} combined standard deviations apart): {}. Plan after a fit of a recording made on the plan's rig, or make the plan's [rig] the rig the fit measured",
            what.join("; ")
        ),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn plan(m1: f64, m2: f64, l: f64) -> PlanRigSpec {
        PlanRigSpec {
            slider_mass: m1,
            bob_mass: Some(m2),
            rod_length: l,
            rod_mass: None,
            bob_radius: None,
            pendulum_mass: None,
            pendulum_com: None,
            pendulum_inertia: None,
            gravity: None,
            rod_length_sd: None,
            slider_mass_sd: None,
            bob_mass_sd: None,
            rod_mass_sd: None,
            bob_radius_sd: None,
            gravity_sd: None,
        }
    }

    fn fit(m1: f64, m2: f64, l: f64) -> Value {
        json!({
            "rig_measured": {"keys": [
                {"key": "rod_length", "value": l, "sd": 0.001, "source": "default"},
                {"key": "slider_mass", "value": m1, "sd": 0.03 * m1, "source": "default"},
                {"key": "bob_mass", "value": m2, "sd": 0.02 * m2, "source": "default"},
            ]},
            "parameters": {
                "rod_length": {"value": l + 2e-6, "stderr": 4e-6},
                "equivalent_mass_ratio": {"value": m1 / m2, "stderr": 1e-3},
            },
        })
    }

    #[test]
    fn the_same_rig_passes_and_another_is_named() {
        let (m, notes) = compare(&fit(0.1, 0.1, 0.3), &plan(0.1, 0.1, 0.3));
        assert!(m.is_empty() && notes.is_empty(), "{m:?} {notes:?}");
        // The pair: slider/bob 2.0 against the plan's 1.0.
        let (m, _) = compare(&fit(0.2, 0.1, 0.3), &plan(0.1, 0.1, 0.3));
        let names: Vec<&str> = m.iter().map(|m| m.what).collect();
        assert_eq!(names, ["slider_mass"]);
        assert!(!names.contains(&"bob_mass") && !names.contains(&"rod_length"));
        // A rod 3 mm longer is 2.1 sd of a ruler apart on each side: the same rig.
        assert!(compare(&fit(0.1, 0.1, 0.303), &plan(0.1, 0.1, 0.3))
            .0
            .is_empty());
        // 10 mm is another rod (7 sd).
        let (m, _) = compare(&fit(0.1, 0.1, 0.31), &plan(0.1, 0.1, 0.3));
        assert_eq!(m[0].what, "rod_length");
    }

    #[test]
    fn the_plans_stated_deviations_are_counted() {
        // 0.13 kg against 0.10 kg: 6.1 combined sd with a kitchen scale's 3 % on both sides.
        let (m, _) = compare(&fit(0.13, 0.1, 0.3), &plan(0.1, 0.1, 0.3));
        assert_eq!(m.len(), 1, "{m:?}");
        assert!(
            m[0].sd_apart > 5.0 && m[0].plan.contains("default"),
            "{m:?}"
        );
        // The plan's slider weighed on a rough scale (10 g): 2.8 sd, the same rig.
        let rough = PlanRigSpec {
            slider_mass_sd: Some(0.01),
            ..plan(0.1, 0.1, 0.3)
        };
        assert!(compare(&fit(0.13, 0.1, 0.3), &rough).0.is_empty());
        // A precise rod (0.1 mm) on the plan's side cannot hide a ruler's 7 sd on the fit's.
        let precise = PlanRigSpec {
            rod_length_sd: Some(1e-4),
            ..plan(0.1, 0.1, 0.3)
        };
        let (m, _) = compare(&fit(0.1, 0.1, 0.31), &precise);
        assert_eq!(m.len(), 1, "{m:?}");
        assert!(m[0].plan.contains("stated"), "{m:?}");
    }

    #[test]
    fn a_rod_with_mass_is_another_pendulum() {
        let p = PlanRigSpec {
            rod_mass: Some(0.02),
            ..plan(0.1, 0.1, 0.3)
        };
        let mut f = fit(0.1, 0.1, 0.3);
        f["parameters"] = json!({});
        let (m, _) = compare(&f, &p);
        assert_eq!(m.len(), 1, "{m:?}");
        assert_eq!(m[0].what, "rod_mass");
        assert!(m[0].plan.contains("rigid") && m[0].fit.contains("point"));
    }

    #[test]
    fn a_joint_fit_is_compared_by_what_it_fitted() {
        let f = json!({"shared": {
            "rod_length": {"value": 0.3, "stderr": 1e-5},
            "equivalent_mass_ratio": {"value": 2.0, "stderr": 1e-3},
        }});
        let (m, notes) = compare(&f, &plan(0.1, 0.1, 0.3));
        assert_eq!(m.len(), 1);
        assert_eq!(m[0].what, "mass ratio");
        assert_eq!(notes.len(), 1);
        let err = check(
            &f,
            Path::new("fit.json"),
            &plan(0.1, 0.1, 0.3),
            Path::new("plan.toml"),
        )
        .unwrap_err()
        .to_string();
        assert!(
            err.contains("fit.json") && err.contains("plan.toml"),
            "{err}"
        );
        assert!(err.contains("shared.equivalent_mass_ratio"), "{err}");
        assert!(err.contains("2.0000 +- 0.0010"), "{err}");
    }
}
