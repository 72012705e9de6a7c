//! The friction law as a result (docs/fit.md, "Friction law"): which law the data chose,
//! the evidence for every law (its best model's criterion, or the score test's prediction
//! where it was not fitted), the law's parameters with intervals (each direction's
//! coefficient under the direction law), and plain sentences where this recording cannot
//! tell two explanations apart and what measurement would.

use super::estimate::Estimate;
use super::select::{ModelRow, Nuisance};
use crate::model::Param;
use nalgebra::DMatrix;
use serde::Serialize;

/// A difference in BIC below which two models are not told apart (Kass and Raftery's
/// "positive" evidence starts at 2; below 6 it is not strong).
const NOT_STRONG: f64 = 6.0;

/// A load exponent's standard error above which the recording barely measures it.
const LOOSE_EXPONENT: f64 = 0.1;

/// The laws a report compares, each with the nuisance that puts it in a model (Coulomb's
/// with one coefficient has none).
const LAWS: [(&str, Option<Nuisance>); 6] = [
    ("coulomb", None),
    ("static", Some(Nuisance::StaticFriction)),
    ("stribeck", Some(Nuisance::Stribeck)),
    ("viscous", Some(Nuisance::ViscousFriction)),
    ("direction", Some(Nuisance::Direction)),
    ("load", Some(Nuisance::Load)),
];

/// The friction section of a fit.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FrictionLawResult {
    /// The law chosen: `coulomb`, `static` (mu_static above mu_kinetic), `stribeck`,
    /// `direction` or `load`, with `+viscous` when viscous rail friction adds to it.
    pub chosen: String,
    /// Whether `--friction` forced it.
    pub forced: bool,
    /// Every law with its evidence.
    pub laws: Vec<LawEvidence>,
    /// The chosen law's parameters.
    pub parameters: Vec<LawParameter>,
    /// Plain sentences: what this recording cannot tell apart, and what would.
    pub notes: Vec<String>,
    /// What the recording could not test, a short phrase each for the answer line ("slides
    /// toward +x only: mu toward -x not measured").
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub untested: Vec<String>,
}

/// The evidence for one law.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LawEvidence {
    /// The law's name.
    pub law: &'static str,
    /// `chosen`, `fitted` (its best model's BIC against the chosen one's), `screened` (not
    /// fitted: the score test's predicted chi-square drop was below its BIC penalty) or
    /// `not tried` (the model described the recording without it, or a forced law left it
    /// out).
    pub status: &'static str,
    /// Its best model's BIC minus the chosen model's.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub delta_bic: Option<f64>,
    /// The predicted chi-square drop, and the penalty ln(n) per parameter it would pay.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub predicted_drop: Option<[f64; 2]>,
    /// Its best model's mu_kinetic.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mu_kinetic: Option<f64>,
}

/// One parameter of the chosen law.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LawParameter {
    /// Its name (`mu_kinetic_positive` and `_negative` are derived: each direction's).
    pub name: String,
    /// Its estimate.
    pub value: f64,
    /// Its standard error.
    pub stderr: f64,
    /// Its 95 % interval.
    pub ci95: [f64; 2],
}

/// What the section is built from: the fit's estimates and the selection's table.
pub struct LawInputs<'a> {
    /// The free parameters' estimates.
    pub params: &'a [(Param, Estimate)],
    /// Their correlation matrix (order of `params`).
    pub correlation: &'a DMatrix<f64>,
    /// Every model compared.
    pub models: &'a [ModelRow],
    /// The nuisances chosen.
    pub chosen: &'a [Nuisance],
    /// The score test at the chosen model.
    pub screening: &'a [(Nuisance, f64)],
    /// Residual rows (the criterion's n).
    pub n_rows: usize,
    /// Whether `--friction` forced the law.
    pub forced: bool,
}

/// The friction section.
pub fn friction_law(inp: &LawInputs) -> FrictionLawResult {
    let has = |nu: Nuisance| inp.chosen.contains(&nu);
    let mut chosen = LAWS
        .iter()
        .find(|(_, nu)| nu.is_some_and(|n| n.is_law() && has(n)))
        .map(|(name, _)| *name)
        .unwrap_or(
            if has(Nuisance::StaticFriction) || free(inp, Param::MuStatic) {
                "static"
            } else {
                "coulomb"
            },
        )
        .to_owned();
    let viscous = has(Nuisance::ViscousFriction);
    if viscous {
        chosen.push_str("+viscous");
    }
    let laws = LAWS
        .iter()
        .map(|&(law, nu)| evidence(inp, law, nu, &chosen, viscous))
        .collect::<Vec<_>>();
    let parameters = parameters(inp);
    let notes = notes(inp, &laws, &parameters);
    FrictionLawResult {
        chosen,
        forced: inp.forced,
        laws,
        parameters,
        notes,
        untested: Vec::new(),
    }
}

fn free(inp: &LawInputs, q: Param) -> bool {
    inp.params.iter().any(|(p, _)| *p == q)
}

/// The nuisances of a model row, from its name.
fn row_nuisances(row: &ModelRow) -> Vec<&str> {
    if row.name == "base" {
        Vec::new()
    } else {
        row.name.split('+').collect()
    }
}

/// The best converged row holding `nu` (or, for Coulomb's law, none of the friction terms).
fn best_row<'a>(inp: &'a LawInputs, nu: Option<Nuisance>) -> Option<&'a ModelRow> {
    // A row's nuisances that are not the rail's friction, in one order.
    let others = |ns: &[Nuisance]| -> Vec<&str> {
        let mut o: Vec<&str> = ns
            .iter()
            .filter(|n| !n.is_friction())
            .map(|n| n.name())
            .collect();
        o.sort_unstable();
        o
    };
    // The static law's rows hold mu_static and no law of their own: a law with mu_static
    // above mu_kinetic is that law's evidence, not the static law's.
    let holds = |ns: &[Nuisance]| match nu {
        Some(Nuisance::StaticFriction) => {
            ns.contains(&Nuisance::StaticFriction) && !ns.iter().any(|n| n.is_law())
        }
        Some(n) => ns.contains(&n),
        None => !ns.iter().any(|n| n.is_friction()),
    };
    let rows: Vec<(&ModelRow, Vec<Nuisance>)> = inp
        .models
        .iter()
        .filter(|r| r.failed.is_none())
        .map(|r| (r, row_set(r)))
        .filter(|(_, ns)| holds(ns))
        .collect();
    // The laws are weighed on the chosen model's other nuisances: a row fitted in an early
    // round without a nuisance found later is stale evidence (a Stribeck model without the
    // marker offset read as +1044.6 against the chosen one). Those rows count only when no
    // row on the final nuisances holds the law.
    let final_core = others(inp.chosen);
    let best = |on_final: bool| {
        rows.iter()
            .filter(|(_, ns)| !on_final || others(ns) == final_core)
            .map(|(r, _)| *r)
            .min_by(|a, b| a.delta_bic.total_cmp(&b.delta_bic))
    };
    best(true).or_else(|| best(false))
}

/// The nuisances of a model row, from its name.
fn row_set(row: &ModelRow) -> Vec<Nuisance> {
    row_nuisances(row)
        .into_iter()
        .filter_map(|name| Nuisance::ALL.into_iter().find(|n| n.name() == name))
        .collect()
}

fn evidence(
    inp: &LawInputs,
    law: &'static str,
    nu: Option<Nuisance>,
    chosen: &str,
    viscous: bool,
) -> LawEvidence {
    let is_chosen = chosen.split('+').next() == Some(law) || (law == "viscous" && viscous);
    let row = best_row(inp, nu);
    let status = if is_chosen {
        "chosen"
    } else if row.is_some() {
        "fitted"
    } else if nu.is_some_and(|n| inp.screening.iter().any(|(s, _)| *s == n)) {
        "screened"
    } else {
        "not tried"
    };
    let predicted_drop = nu.and_then(|n| {
        inp.screening
            .iter()
            .find(|(s, _)| *s == n)
            .map(|(_, d)| [*d, n.params().len() as f64 * (inp.n_rows as f64).ln()])
    });
    LawEvidence {
        law,
        status,
        delta_bic: row.map(|r| r.delta_bic),
        predicted_drop: (status == "screened").then_some(predicted_drop).flatten(),
        mu_kinetic: row.map(|r| r.mu_kinetic),
    }
}

/// The chosen law's parameters, and each direction's coefficient under the direction law
/// (mu_k +- the split, its variance from the correlation).
fn parameters(inp: &LawInputs) -> Vec<LawParameter> {
    let idx = |q: Param| inp.params.iter().position(|(p, _)| *p == q);
    let of = |i: usize| {
        let (q, e) = &inp.params[i];
        LawParameter {
            name: q.name().to_owned(),
            value: e.value,
            stderr: e.stderr,
            ci95: e.ci95,
        }
    };
    let mut out: Vec<LawParameter> = [
        Param::MuKinetic,
        Param::MuStatic,
        Param::FrictionSplit,
        Param::LoadExponent,
        Param::StribeckVelocity,
        Param::ViscousFriction,
    ]
    .into_iter()
    .filter_map(idx)
    .map(of)
    .collect();
    if let (Some(k), Some(d)) = (idx(Param::MuKinetic), idx(Param::FrictionSplit)) {
        let (ek, ed) = (&inp.params[k].1, &inp.params[d].1);
        let cov = inp.correlation[(k, d)] * ek.stderr * ed.stderr;
        for (name, s) in [("mu_kinetic_positive", 1.0), ("mu_kinetic_negative", -1.0)] {
            let value = ek.value + s * ed.value;
            let var = ek.stderr * ek.stderr + ed.stderr * ed.stderr + 2.0 * s * cov;
            let stderr = var.max(0.0).sqrt();
            out.push(LawParameter {
                name: name.to_owned(),
                value,
                stderr,
                // No direction's coefficient is below 0.
                ci95: [(value - 1.96 * stderr).max(0.0), value + 1.96 * stderr],
            });
        }
    }
    out
}

/// The sentences: laws the recording cannot tell apart from the chosen one, the direction
/// law against a rail tilt, a load exponent barely measured.
fn notes(inp: &LawInputs, laws: &[LawEvidence], params: &[LawParameter]) -> Vec<String> {
    let mut out = Vec::new();
    if inp.forced {
        out.push("The law was forced with --friction; the others were not fitted.".to_owned());
    }
    for l in laws.iter().filter(|l| l.status == "fitted") {
        if let Some(d) = l.delta_bic.filter(|d| d.abs() < NOT_STRONG) {
            out.push(format!(
                "The {} law fits this recording about as well as the chosen one (BIC {:+.1}): the recording cannot tell them apart. Releases that differ (the other direction, a larger swing, another slider mass) fitted together with --joint would.",
                l.law, d
            ));
        }
    }
    let tilt = best_row(inp, Some(Nuisance::RailTilt));
    let direction_chosen = inp.chosen.contains(&Nuisance::Direction);
    let tilt_chosen = inp.chosen.contains(&Nuisance::RailTilt);
    if direction_chosen && !tilt_chosen {
        let without_direction = tilt.filter(|r| !row_nuisances(r).contains(&"direction"));
        out.push(match without_direction {
            Some(r) if r.delta_bic < NOT_STRONG => format!(
                "A rail tilt explains this recording about as well as friction that differs by direction (BIC {:+.1}): with a nearly constant normal force the two are the same force. Level the rail and give its tilt as rail_tilt_deg, or fit releases with different swings together (--joint): that separates them.",
                r.delta_bic
            ),
            Some(r) => format!(
                "A rail tilt in place of the direction law was fitted and is worse by {:.0} in BIC: the recording tells direction-dependent friction from a tilted rail (the pendulum's hanging angle differs).",
                r.delta_bic
            ),
            None => "A rail tilt was not fitted in place of the direction law (the score test did not ask for it); on a heavy slider a tilt of about -split rad is the same force: level the rail, or fit with --with rail_tilt to compare.".to_owned(),
        });
    }
    if tilt_chosen && !direction_chosen {
        if let Some(l) = laws.iter().find(|l| l.law == "direction") {
            match (l.status, l.delta_bic) {
                ("fitted", Some(d)) if d >= NOT_STRONG => out.push(format!(
                    "Friction that differs by direction was fitted and is worse than the rail tilt by {d:.0} in BIC: the recording shows a tilt, not a direction-dependent rail."
                )),
                ("fitted", Some(_)) => {}
                _ => out.push("Friction that differs by direction was not fitted in place of the tilt; on a heavy slider it acts as a tilt does: fit with --friction direction to compare.".to_owned()),
            }
        }
    }
    if let Some(n) = params.iter().find(|p| p.name == "load_exponent") {
        if n.stderr > LOOSE_EXPONENT {
            out.push(format!(
                "The load exponent is barely measured (n = {:.2} +- {:.2}): the normal force varies little over these slides. A release with a larger swing, or a heavier bob against the slider, spreads the load and pins n down.",
                n.value, n.stderr
            ));
        }
    }
    out
}

/// One slide of a recording as the friction figure shows it: the coefficient |F| / |N| that
/// a Coulomb law fitted to its window alone finds (the data's own value, whatever the chosen
/// law), against the fitted motion's sliding speed there.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SlidePoint {
    /// The window's start and end (s).
    pub t: [f64; 2],
    /// Sliding direction (+1 toward +x, -1 toward -x): the one most of its frames slide in.
    pub direction: f64,
    /// The fitted motion's sliding speed |x'| over the slide's frames: mean, least, most (m/s).
    pub speed: [f64; 3],
    /// The mean normal force over the slide, relative to the static load (m1 + m2) g.
    pub load: f64,
    /// The chosen law's value of the same: the coefficient the same Coulomb fit finds on the
    /// chosen model's own motion (noise-free) in this window. Where the law is right, the
    /// slide's value scatters about it within its error.
    pub law_mu: f64,
    /// The window's coefficient and its standard error.
    pub mu: f64,
    /// Standard error of `mu`.
    pub stderr: f64,
}

/// Each slide's own friction coefficient ([`SlidePoint`]): the recording cut by its fitted
/// motion into windows of one slide each (as the windows' agreement test cuts it), each
/// window fitted with Coulomb's law, mu_kinetic and the window's start state free and
/// everything else held at the chosen model's values (viscous friction left out, so that the
/// coefficient is all the rail's friction); speeds and loads from the chosen model's motion,
/// and the chosen law's value from the same fit of that motion.
/// `problem` is one fitted problem: a single fit's chosen model (the report's `problem`), or
/// a release of a joint fit at the joint optimum.
pub fn slide_points_of(
    problem: &super::problem::TrajectoryProblem,
    settings: &super::settings::FitSettings,
) -> Vec<SlidePoint> {
    use crate::model::observed_markers;
    let obs = problem.observations();
    let Some(&t_end) = obs.times.last() else {
        return Vec::new();
    };
    let coulomb_of = |p: &super::problem::TrajectoryProblem| {
        let mut c = p.clone();
        c.rig.friction_law = crate::model::FrictionLaw::Coulomb;
        c.rig.kinetic_split = 0.0;
        c.rig.static_split = 0.0;
        c.rig.load_exponent = 1.0;
        c.rig.viscous_friction = 0.0;
        c
    };
    let request = crate::sim::Request {
        sample_times: obs.times.clone(),
        friction_work: false,
        positions_only: false,
    };
    let Ok(sol) = crate::sim::simulate(
        &problem.rig,
        &problem.initial,
        t_end,
        &problem.options,
        &request,
    ) else {
        return Vec::new();
    };
    if sol.samples.len() != obs.times.len() {
        return Vec::new();
    }
    let (bounds, _) = super::uncertainty::motion_bounds(&obs.times, &sol.events);
    // The chosen model's own motion as a noise-free recording, cut and fitted the same way:
    // its windows' coefficients are what the chosen law says each slide's value is.
    let (slider, bob) = sol
        .samples
        .iter()
        .map(|s| {
            let m = observed_markers(&problem.rig, &problem.camera, s.mode, &s.state);
            (Some([m[0], m[1]]), Some([m[2], m[3]]))
        })
        .unzip();
    let model_obs = super::problem::Observations {
        times: obs.times.clone(),
        slider,
        bob,
    };
    let mut model_problem = super::problem::TrajectoryProblem::new(
        std::sync::Arc::new(model_obs),
        problem.rig,
        problem.initial,
        problem.free.clone(),
        problem.options,
    );
    model_problem.camera = problem.camera;
    model_problem.sigma = problem.sigma;
    model_problem.tie_static = problem.tie_static;
    let data = super::uncertainty::windows(&coulomb_of(problem), &bounds, settings);
    let model = super::uncertainty::windows(&coulomb_of(&model_problem), &bounds, settings);
    let rig = &problem.rig;
    data.iter()
        .filter_map(|w| {
            let law = model.iter().find(|m| m.t_start == w.t_start)?;
            let slides: Vec<(f64, f64, f64)> = sol
                .samples
                .iter()
                .filter(|s| s.t >= w.t_start && s.t <= w.t_end)
                .filter_map(|s| slide_load(rig, s))
                .collect();
            if slides.is_empty() {
                return None;
            }
            let plus = slides.iter().filter(|p| p.0 > 0.0).count();
            let direction = if 2 * plus >= slides.len() { 1.0 } else { -1.0 };
            let own: Vec<&(f64, f64, f64)> = slides.iter().filter(|p| p.0 == direction).collect();
            let k = own.len() as f64;
            let (lo, hi) = own.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), p| {
                (lo.min(p.1), hi.max(p.1))
            });
            Some(SlidePoint {
                t: [w.t_start, w.t_end],
                direction,
                speed: [own.iter().map(|p| p.1).sum::<f64>() / k, lo, hi],
                load: own.iter().map(|p| p.2).sum::<f64>() / k,
                law_mu: law.mu_kinetic,
                mu: w.mu_kinetic,
                stderr: w.stderr,
            })
        })
        .collect()
}

/// A sample's slide: its direction (+1 or -1), speed |x'| and normal force over the static
/// load ([`crate::model::Rig::slide_load`]); `None` while stuck.
fn slide_load(
    rig: &crate::model::Rig<f64>,
    s: &crate::sim::Sample<f64>,
) -> Option<(f64, f64, f64)> {
    let crate::model::Mode::Slide(d) = s.mode else {
        return None;
    };
    let load = rig.slide_load(&s.state, d.sign())?;
    Some((d.sign(), s.state[crate::model::X_DOT].abs(), load))
}

/// The spread of the normal force over the static load within which a recording's slides do
/// not test a load law: the load law's exponent was then read as Coulomb's mu at that load,
/// 9 to 16 standard errors from a load-law rail's coefficient.
pub const LOAD_UNTESTED: f64 = 0.15;

/// What a motion whose slides' normal forces over the static load span `loads` (lowest,
/// highest) cannot test about the load: when they all stay within [`LOAD_UNTESTED`] of it,
/// mu is the coefficient at that load and a load-dependent rail cannot be told from this
/// recording.
pub fn load_untested_by(loads: Option<[f64; 2]>) -> Option<String> {
    let [lo, hi] = loads?;
    let spread = (hi - 1.0).max(1.0 - lo);
    (spread < LOAD_UNTESTED).then(|| {
        format!(
            "normal force within {:.0} % of its static value: mu's load dependence not measured",
            100.0 * spread
        )
    })
}

/// What a motion that slides in the directions `modes` (every mode it passes through) cannot
/// test: one direction only leaves the other's coefficient unmeasured, so mu_kinetic is that
/// direction's and a direction-dependent rail cannot be told from this recording.
pub fn untested_by(modes: &[crate::model::Mode]) -> Vec<String> {
    use crate::model::{Direction, Mode};
    let pos = modes.contains(&Mode::Slide(Direction::Positive));
    let neg = modes.contains(&Mode::Slide(Direction::Negative));
    match (pos, neg) {
        (true, false) => vec!["slides toward +x only: mu toward -x not measured".to_owned()],
        (false, true) => vec!["slides toward -x only: mu toward +x not measured".to_owned()],
        _ => Vec::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::untested_by;
    use crate::model::{Direction, Mode};

    /// Slides within 15 % of the static load leave the load law untested, and say by how
    /// much; a wider span, or no slide, leaves nothing to say.
    #[test]
    fn slides_at_one_load_say_the_load_law_was_not_measured() {
        let said = super::load_untested_by(Some([0.93, 1.08])).unwrap();
        assert!(said.starts_with("normal force within 8 % "), "{said}");
        assert!(super::load_untested_by(Some([0.8, 1.05])).is_none());
        assert!(super::load_untested_by(Some([0.95, 1.2])).is_none());
        assert!(super::load_untested_by(None).is_none());
    }

    /// One direction only leaves the other's coefficient unmeasured, and says which; both
    /// directions, or none, leave nothing to say.
    #[test]
    fn a_one_way_motion_says_which_direction_it_did_not_measure() {
        let (pos, neg) = (
            Mode::Slide(Direction::Positive),
            Mode::Slide(Direction::Negative),
        );
        assert_eq!(
            untested_by(&[Mode::Stick, neg, Mode::Stick]),
            vec!["slides toward -x only: mu toward +x not measured".to_owned()]
        );
        assert!(untested_by(&[pos, Mode::Stick])[0].contains("toward -x not measured"));
        assert!(untested_by(&[pos, Mode::Stick, neg]).is_empty());
        assert!(untested_by(&[Mode::Stick]).is_empty());
    }
}
