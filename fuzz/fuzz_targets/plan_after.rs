//! Fuzz the fit JSON that `plan --after FIT.json` reads, structure-aware: the input builds a
//! fit's JSON (the rig's parameter names, their values and a covariance matrix, from values
//! near every edge: zero, subnormal, huge, negative, asymmetric, repeated names, rows of the
//! wrong length) rather than bytes, so most inputs reach the checks past the parser. Each is
//! read by `Prior::from_json` and applied to the campaign plan; whatever passes must leave a
//! rig and a covariance the planner can use (finite, in range, positive variances), and the
//! plan's work is checked again. Nothing is simulated, so an input takes microseconds.
#![no_main]

use appell::fit::Param;
use appell::plan::prior::Prior;
use appell::plan::PlanSpec;
use appell::scene::{check_rig, check_time_scale, RigOrigin};
use arbitrary::Arbitrary;
use libfuzzer_sys::fuzz_target;
use serde_json::{json, Value};
use std::path::Path;

const PLAN: &str = include_str!("../../configs/plan_campaign.toml");

/// A number from the edges a fit's JSON could hold, or any f64.
#[derive(Debug, Arbitrary)]
enum Num {
    Any(f64),
    Edge(u8),
    /// A plausible value times 10^k.
    Scaled(u8, i8),
    /// A number written as a string, null or a list where a number belongs.
    NotANumber(u8),
}

const EDGES: [f64; 14] = [
    0.0,
    -0.0,
    5e-324,
    2.2e-308,
    1e-300,
    1e-20,
    1e-9,
    1.0,
    -1.0,
    1e9,
    1e300,
    1e308,
    f64::MAX,
    -1e-9,
];

impl Num {
    fn json(&self, base: f64) -> Value {
        match *self {
            Num::Any(x) => json!(x),
            Num::Edge(i) => json!(EDGES[i as usize % EDGES.len()]),
            Num::Scaled(m, k) => json!(base * (1.0 + m as f64 / 64.0) * 10f64.powi(k as i32 / 8)),
            Num::NotANumber(i) => match i % 3 {
                0 => json!("0.1"),
                1 => Value::Null,
                _ => json!([1.0]),
            },
        }
    }
}

#[derive(Debug, Arbitrary)]
struct Entry {
    /// Index into Param::ALL, or (past it) a name that is no parameter.
    name: u8,
    value: Num,
}

#[derive(Debug, Arbitrary)]
struct FitJson {
    joint: bool,
    entries: Vec<Entry>,
    /// Covariance: a scale per parameter and correlations, then edits of single cells.
    sd: Vec<Num>,
    correlation: Vec<i8>,
    edits: Vec<(u8, u8, Num)>,
    /// Rows dropped or cells appended, for the shape checks.
    drop_row: bool,
    extra_cell: bool,
}

/// A parameter's name, or (4 in 23) a name that is none.
fn name(i: u8) -> String {
    let i = i as usize % (Param::ALL.len() + 4);
    match Param::ALL.get(i) {
        Some(q) => q.name().to_owned(),
        None => ["", "mu", "MU_KINETIC", "rod_length "][i % 4].to_owned(),
    }
}

fn build(f: &FitJson) -> Value {
    let n = f.entries.len().min(Param::ALL.len() + 2);
    let entries = &f.entries[..n];
    let names: Vec<String> = entries.iter().map(|e| name(e.name)).collect();
    let mut values = serde_json::Map::new();
    for (e, nm) in entries.iter().zip(&names) {
        values.insert(nm.clone(), json!({ "value": e.value.json(0.25) }));
    }
    let sd: Vec<f64> = (0..n)
        .map(|i| {
            f.sd.get(i)
                .and_then(|s| s.json(1e-4).as_f64())
                .unwrap_or(1e-4)
        })
        .collect();
    let mut m: Vec<Vec<Value>> = (0..n)
        .map(|i| {
            (0..n)
                .map(|j| {
                    let r = if i == j {
                        1.0
                    } else {
                        f.correlation
                            .get(i.max(j) * n + i.min(j))
                            .map_or(0.0, |&c| c as f64 / 128.0)
                    };
                    json!(r * sd[i] * sd[j])
                })
                .collect()
        })
        .collect();
    for (i, j, v) in &f.edits {
        if n > 0 {
            let (i, j) = (*i as usize % n, *j as usize % n);
            m[i][j] = v.json(sd[i] * sd[j]);
        }
    }
    if f.drop_row && !m.is_empty() {
        m.pop();
    }
    if f.extra_cell {
        if let Some(r) = m.first_mut() {
            r.push(json!(0.0));
        }
    }
    let section = if f.joint { "shared" } else { "parameters" };
    json!({
        section: values,
        "shared_covariance": { "names": names, "matrix": m },
    })
}

/// With `PLAN_AFTER_STAGES` set (replaying a corpus with `-runs=0`), say how far each input
/// got: `refused: MESSAGE`, `applied`, or `rig refused: MESSAGE`.
fn stage(what: &str) {
    if std::env::var_os("PLAN_AFTER_STAGES").is_some() {
        eprintln!("stage: {what}");
    }
}

fuzz_target!(|f: FitJson| {
    let v = build(&f);
    let path = Path::new("fuzz_fit.json");
    let prior = match Prior::from_json(&v, path) {
        Ok(p) => p,
        Err(e) => {
            stage(&format!("refused: {e}"));
            return;
        }
    };
    // What passed is a covariance the planner can invert and report.
    for i in 0..prior.names.len() {
        let var = prior.covariance[(i, i)];
        assert!(var.is_finite() && var > 0.0, "{var} passed");
        assert!(prior.information[(i, i)].is_finite(), "{v}");
    }
    let mut spec = PlanSpec::from_toml(PLAN, Path::new("plan_campaign.toml")).unwrap();
    if let Err(e) = prior.apply(&mut spec) {
        stage(&format!("rig refused: {e}"));
        return;
    }
    stage("applied");
    // The rig the fit's values made passes the one validation every rig passes.
    let origin = RigOrigin::File { friction: "rig" };
    check_rig(path, &spec.rig, origin).unwrap();
    check_time_scale(path, &spec.rig, origin).unwrap();
    assert!(spec.rig.mass_ratio().is_finite());
    if let appell::plan::Uncertain::Normal { mean, sd } = spec.mu_kinetic {
        assert!(mean.is_finite() && sd.is_finite() && mean + 10.0 * sd < 1e300);
    }
    let _ = spec.check_work(Path::new("plan_campaign.toml"), Some(path));
});
