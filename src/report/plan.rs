//! Output of `appell plan`: the ranked table, the JSON object, and the phase-plane figure of
//! the proposals over the stick region (drawn by the region figure of `appell regions`).

use super::plot::{Figure, PlotError};
use super::regions::{figure_window, impulse_times, RegionFigure, Trajectory};
use crate::model::regions::RegionMap;
use crate::plan::{PlanReport, Proposal};
use crate::sim::{Event, EventKind, Outcome};
use plotters::coord::Shift;
use plotters::prelude::*;
use serde_json::{json, Value};
use std::fmt::Write as _;

fn kind_name(k: EventKind) -> String {
    serde_json::to_value(k)
        .ok()
        .and_then(|v| v.as_str().map(str::to_owned))
        .unwrap_or_else(|| format!("{k:?}"))
}

fn event_json(e: &Event) -> Value {
    let mut v = json!({
        "t": e.t,
        "from": e.from.name(),
        "to": e.to.name(),
        "kind": kind_name(e.kind),
        "state": {"x": e.state[0], "theta": e.state[1], "x_dot": e.state[2], "theta_dot": e.state[3]},
    });
    if let Outcome::Indeterminate(alts) = &e.to {
        v["alternatives"] = json!(alts.iter().map(|m| m.name()).collect::<Vec<_>>());
    }
    v
}

/// The targets as one label, e.g. `stick_to_slide + slide_to_stick`.
pub fn target_label(report: &PlanReport) -> String {
    report
        .targets
        .iter()
        .map(|t| t.to_string())
        .collect::<Vec<_>>()
        .join(" + ")
}

fn finite(v: f64) -> Value {
    if v.is_finite() {
        json!(v)
    } else {
        Value::Null
    }
}

/// Every proposal with its label: the ranked ones `#1`, `#2`, ... then the unranked ones
/// `(a)`, `(b)`, ..., with whether it is ranked.
pub fn labelled(report: &PlanReport) -> Vec<(String, &Proposal, bool)> {
    let ranked = report
        .proposals
        .iter()
        .enumerate()
        .map(|(i, p)| (format!("#{}", i + 1), p, true));
    let letters = ('a'..='z').chain(std::iter::repeat('?'));
    let unranked = report
        .unranked
        .iter()
        .zip(letters)
        .map(|(p, c)| (format!("({c})"), p, false));
    ranked.chain(unranked).collect()
}

/// Why an unranked proposal is not ranked.
fn why_unranked(report: &PlanReport, p: &Proposal) -> String {
    if p.meets_min_robustness {
        "mu not identifiable from it (infinite predicted stderr)".to_owned()
    } else {
        format!(
            "below the plan's min_robustness {:.3}",
            report.min_robustness
        )
    }
}

fn proposal_json(report: &PlanReport, rank: Option<usize>, p: &Proposal) -> Value {
    let y = p.initial;
    let mut v = json!({
        "rank": rank,
        "initial": {"x": y[0], "theta": y[1], "x_dot": y[2], "theta_dot": y[3]},
        "theta_deg": y[1].to_degrees(),
        "target": target_label(report),
        "robustness": p.robustness,
        "meets_min_robustness": p.meets_min_robustness,
        "robustness_observed": p.robustness_observed,
        "draws": p.draws,
        "predicted_mu_stderr": finite(p.predicted_mu_stderr),
        "events": p.events.iter().map(event_json).collect::<Vec<_>>(),
        "margins": {
            "transitions": p.nominal.hits,
            "rail_margin_m": p.nominal.rail_margin_m,
            "fov_margin_m": p.nominal.fov_margin_m,
            "slider_range_m": p.nominal.slider_range,
        },
    });
    law_json(&mut v, p);
    // Only with --after: what the release adds to the earlier fit's knowledge.
    if let Some(prior) = report.prior_mu_stderr {
        v["prior_mu_stderr"] = finite(prior);
        v["shrinks_mu_stderr_by"] = finite(prior / p.predicted_mu_stderr);
    }
    v
}

/// A proposal's law fields: `pairs_resolved` (the expected number of the `pairs` a fit will
/// resolve), `worst_expected_delta_bic` and
/// `discrimination` (each pair, worst first) when the plan weighs laws; `predicted_stderr`
/// (law -> parameter -> predicted standard error) when it weighs laws or plans for a law
/// with parameters beyond mu.
fn law_json(v: &mut Value, p: &Proposal) {
    if !p.separation.is_nan() {
        v["pairs_resolved"] = finite(p.separation);
        v["pairs"] = json!(p.separations.len());
        v["worst_expected_delta_bic"] = finite(crate::plan::discriminate::Laws::worst(
            &p.separations.iter().cloned().map(Some).collect::<Vec<_>>(),
        ));
        v["discrimination"] = json!(p
            .separations
            .iter()
            .map(|s| json!({
                "truth": s.truth,
                "rival": s.rival,
                "lambda": finite(s.lambda),
                "expected_delta_bic": finite(s.expected_delta_bic),
                "probability": finite(s.probability),
            }))
            .collect::<Vec<_>>());
    }
    if !p.law_stderr.is_empty() {
        let mut m = serde_json::Map::new();
        let mut ranges = serde_json::Map::new();
        let mut mu_ranges = serde_json::Map::new();
        for e in &p.law_stderr {
            let se = m.entry(e.law.name()).or_insert_with(|| json!({}));
            se[e.param.name()] = finite(e.stderr);
            for (range, into) in [(e.range, &mut ranges), (e.mu_range, &mut mu_ranges)] {
                if let Some([lo, hi]) = range {
                    let r = into.entry(e.law.name()).or_insert_with(|| json!({}));
                    r[e.param.name()] = json!([finite(lo), finite(hi)]);
                }
            }
        }
        v["predicted_stderr"] = Value::Object(m);
        if !ranges.is_empty() {
            v["predicted_stderr_range"] = Value::Object(ranges);
        }
        if !mu_ranges.is_empty() {
            v["predicted_stderr_mu_range"] = Value::Object(mu_ranges);
        }
    }
}

/// The expected number of pairs of laws a fit of the proposal resolves (the sum of the
/// pairs' chances): what a plan weighing laws ranks by.
fn resolved(p: &Proposal) -> f64 {
    p.separations.iter().map(|s| s.probability).sum()
}

/// The lines of a proposal's law separation and the laws' predicted errors.
fn law_lines(s: &mut String, p: &Proposal) {
    use crate::numbers::significant;
    if !p.separations.is_empty() {
        let _ = writeln!(
            s,
            "   pairs of laws the fit is expected to resolve: {} of {}",
            significant(resolved(p), 2),
            p.separations.len()
        );
    }
    // Two digits: an expected chi-square's own spread, sqrt(2 (k + 2 lambda)), is larger.
    for sep in &p.separations {
        let margin = significant(sep.expected_delta_bic, 2);
        let _ = writeln!(
            s,
            "   {} (true) against {}: the rival's best fit leaves chi-square {} on average, expected BIC margin {}{margin}, chance the fit prefers {} {:.2}",
            sep.truth,
            sep.rival,
            significant(sep.lambda, 2),
            if sep.expected_delta_bic > 0.0 { "+" } else { "" },
            sep.truth,
            sep.probability
        );
    }
    let mut by_law: Vec<(crate::plan::law::Law, Vec<String>)> = Vec::new();
    let (mut ranged, mut mu_ranged) = (false, false);
    for e in &p.law_stderr {
        let q = e.param.name();
        let mut text = if e.stderr.is_finite() {
            format!("{q} {:.2e}", e.stderr)
        } else {
            format!("{q} not shown by this release")
        };
        if let Some([lo, hi]) = e.range {
            ranged = true;
            text += &match (lo.is_finite(), hi.is_finite()) {
                (true, true) => format!(" ({lo:.2e} to {hi:.2e})"),
                (true, false) => format!(" ({lo:.2e} to not shown)"),
                _ => " (not shown at any departure)".to_owned(),
            };
        }
        if let Some([lo, hi]) = e.mu_range {
            mu_ranged = true;
            let shown = |x: f64| {
                if x.is_finite() {
                    format!("{x:.2e}")
                } else {
                    "not shown".to_owned()
                }
            };
            text += &format!(" [mu +-1 sd: {} to {}]", shown(lo), shown(hi));
        }
        match by_law.iter_mut().find(|(l, _)| *l == e.law) {
            Some((_, v)) => v.push(text),
            None => by_law.push((e.law, vec![text])),
        }
    }
    for (law, v) in by_law {
        let _ = writeln!(s, "   predicted stderr under {law}: {}", v.join(", "));
    }
    if ranged {
        let scales = crate::plan::law::DEPARTURE_SCALES;
        let (a, b) = (scales[0], scales[scales.len() - 1]);
        let _ = writeln!(
            s,
            "   (at each law's reference departure; in brackets, from {a} to {b} times it: a law's errors depend on how far it departs, which the release will show)"
        );
    }
    if mu_ranged {
        let _ = writeln!(
            s,
            "   (in square brackets, with mu_kinetic one sd lower and higher: how long the release slides, so what it shows, moves with mu)"
        );
    }
}

/// The plan as one JSON object: `feasible`, `targets`, `min_robustness`, `release_box`,
/// `proposals` (ranked, best first, all meeting `min_robustness`), `unranked` (the others,
/// `rank` null, `meets_min_robustness` false unless mu is not identifiable), `at_limit`,
/// `nearest` (null when feasible), `notes`, `evaluated`.
pub fn plan_json(report: &PlanReport) -> Value {
    let [theta, theta_dot, x_dot] = report.release_box;
    json!({
        "feasible": report.feasible,
        "targets": report.targets.iter().map(|t| t.to_string()).collect::<Vec<_>>(),
        "min_robustness": report.min_robustness,
        "release_box": {
            "theta_deg": theta.map(f64::to_degrees),
            "theta_dot": theta_dot,
            "x_dot": x_dot,
        },
        "proposals": report
            .proposals
            .iter()
            .enumerate()
            .map(|(i, p)| proposal_json(report, Some(i + 1), p))
            .collect::<Vec<_>>(),
        "unranked": report
            .unranked
            .iter()
            .map(|p| {
                let mut v = proposal_json(report, None, p);
                v["why_unranked"] = json!(why_unranked(report, p));
                v
            })
            .collect::<Vec<_>>(),
        "at_limit": report.at_limit,
        "nearest": report.nearest.as_ref().map(|n| json!({
            "message": n.message,
            "release": n.release.map(|y| json!({"x": y[0], "theta": y[1], "x_dot": y[2], "theta_dot": y[3]})),
            "robustness": n.robustness,
        })),
        "notes": report.notes,
        "laws": {
            "weighed": report.laws,
            "criterion": if report.laws.is_empty() { "precision of mu" } else { "separation of the laws" },
            "notes": report.law_notes,
        },
        "evaluated": report.evaluated,
    })
}

/// The plan as a readable table: one row per proposal, then each proposal's timeline and
/// margins.
pub fn plan_table(report: &PlanReport) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "targets: {}", target_label(report));
    for n in report.law_notes.iter().chain(&report.notes) {
        let _ = writeln!(s, "note: {n}");
    }
    if let Some(n) = &report.nearest {
        let _ = writeln!(
            s,
            "{}: {}",
            if report.feasible {
                "note"
            } else {
                "NOT FEASIBLE"
            },
            n.message
        );
    }
    let all = labelled(report);
    if all.is_empty() {
        let _ = writeln!(
            s,
            "no proposals ({} releases tried at the nominal friction)",
            report.evaluated
        );
        return s;
    }
    if report.proposals.is_empty() {
        let _ = writeln!(
            s,
            "no ranked proposals: none reaches min_robustness {:.3}",
            report.min_robustness
        );
    }
    // The column the proposals are ranked by: mu's predicted error, or, when the plan weighs
    // laws, the pairs of laws a fit is expected to resolve.
    let weighs = !report.laws.is_empty();
    let _ = writeln!(
        s,
        "{:>4} {:>11} {:>13} {:>10} {:>11} {:>14} {:>10} {:>10}",
        "rank",
        "theta [deg]",
        "theta' [r/s]",
        "x' [m/s]",
        "robustness",
        if weighs { "pairs told" } else { "stderr(mu)" },
        "rail [mm]",
        "events"
    );
    for (k, (label, p, ranked)) in all.iter().enumerate() {
        if !ranked && (k == 0 || all[k - 1].2) {
            let _ = writeln!(
                s,
                "not ranked, listed apart (under min_robustness {:.3}, or mu not identifiable; do not count on these):",
                report.min_robustness
            );
        }
        let y = p.initial;
        let _ = writeln!(
            s,
            "{:>4} {:>11.2} {:>13.3} {:>10.4} {:>11} {:>14} {:>10.1} {:>10}",
            label,
            y[1].to_degrees(),
            y[3],
            y[2],
            format!("{:.3}", p.robustness),
            if weighs {
                format!("{:.2} of {}", resolved(p), p.separations.len())
            } else {
                format!("{:.3e}", p.predicted_mu_stderr)
            },
            1e3 * p.nominal.rail_margin_m,
            p.events.len()
        );
    }
    for (label, p, ranked) in &all {
        let _ = writeln!(
            s,
            "\n{label}{} robustness {:.3} (one-sided 95% bound; observed {:.3} of {} draws), predicted stderr(mu) {:.3e}{}",
            if *ranked {
                String::new()
            } else {
                format!(" NOT RANKED ({}):", why_unranked(report, p))
            },
            p.robustness,
            p.robustness_observed,
            p.draws,
            p.predicted_mu_stderr,
            report.prior_mu_stderr.map_or(String::new(), |prior| format!(
                // Three digits: each error is itself uncertain by more than a per cent.
                " with the earlier fit's {prior:.3e} (it shrinks mu's stderr by a factor {})",
                crate::numbers::significant(prior / p.predicted_mu_stderr, 3)
            ))
        );
        law_lines(&mut s, p);
        for h in p.nominal.hits.iter().flatten() {
            let _ = writeln!(
                s,
                "   {:<22} t = {:.4} s  window margin {:.0} frames, slide {:.0} px, {:.0} frames before, {:.0} after",
                h.target.to_string(),
                h.t,
                h.window_margin_frames,
                h.travel_px,
                h.frames_before,
                h.frames_after
            );
        }
        let _ = writeln!(
            s,
            "   slider {:+.4}..{:+.4} m (rail margin {:.1} mm, view margin {:.1} mm)",
            p.nominal.slider_range[0],
            p.nominal.slider_range[1],
            1e3 * p.nominal.rail_margin_m,
            1e3 * p.nominal.fov_margin_m
        );
        for e in &p.events {
            let _ = writeln!(
                s,
                "   {:>9.4} s  {:<7} -> {:<13} {:<12} theta {:>8.2} deg  x {:+.4} m",
                e.t,
                e.from.name(),
                e.to.to_string(),
                kind_name(e.kind),
                e.state[1].to_degrees(),
                e.state[0]
            );
        }
    }
    let _ = writeln!(s, "{}", crate::report::fit::TERMS);
    s
}

/// The proposals' nominal runs over the regions of `appell regions` (stick region and its
/// boundary |c| = mu_s |b|, both slide directions when there is a paradox band), coloured by
/// mode, with the release box the plan allows drawn dashed; each release labelled with its
/// rank (#1 the best, drawn thicker; unranked ones (a), (b), ...), and each proposal's
/// release, robustness and predicted stderr(mu) in the legend column.
pub struct PlanFigure<'a> {
    /// The plan.
    pub report: &'a PlanReport,
}

impl PlanFigure<'_> {
    fn trajectories(&self) -> Vec<Trajectory> {
        labelled(self.report)
            .into_iter()
            .map(|(_, p, _)| Trajectory {
                initial: p.initial,
                samples: p.samples.clone(),
                stopped_at_paradox: p
                    .events
                    .last()
                    .is_some_and(|e| e.kind == EventKind::Paradox),
                error: None,
                impulse_times: impulse_times(&p.events),
            })
            .collect()
    }

    /// One line per proposal: rank, release, robustness, predicted stderr(mu); the allowed
    /// box first.
    pub fn proposal_notes(&self) -> Vec<String> {
        let [theta, theta_dot, x_dot] = self.report.release_box;
        let push = if x_dot[1] > x_dot[0] {
            format!(
                "; x'0 {:.3}..{:.3} m/s (not shown in this plane)",
                x_dot[0], x_dot[1]
            )
        } else {
            String::new()
        };
        let mut out = vec![
            format!("targets: {}", target_label(self.report)),
            format!(
                "allowed releases (dashed box): theta0 {:.1}..{:.1} deg, theta'0 {:.2}..{:.2} rad/s{push}",
                theta[0].to_degrees(),
                theta[1].to_degrees(),
                theta_dot[0],
                theta_dot[1]
            ),
        ];
        out.extend(self.report.at_limit.iter().map(|a| {
            format!(
                "#1 is at the {} limit of {} ({:.3}): widen it if the rig allows",
                a.limit, a.quantity, a.bound
            )
        }));
        if self.report.proposals.is_empty() && self.report.unranked.is_empty() {
            out.push(format!(
                "no proposals{}",
                self.report
                    .nearest
                    .as_ref()
                    .map_or(String::new(), |n| format!(": {}", n.message))
            ));
        }
        for (label, p, ranked) in labelled(self.report) {
            let y = p.initial;
            let push = if y[2] == 0.0 {
                String::new()
            } else {
                format!(", x'0 = {:.3} m/s", y[2])
            };
            let why = if ranked {
                String::new()
            } else {
                format!(" not ranked ({});", why_unranked(self.report, p))
            };
            out.push(format!(
                "{label}:{why} theta0 = {:.1} deg, theta'0 = {:.2} rad/s{push}; robustness >= {:.3}, stderr(mu) = {:.2e}",
                y[1].to_degrees(),
                y[3],
                p.robustness,
                p.predicted_mu_stderr
            ));
        }
        out
    }
}

impl Figure for PlanFigure<'_> {
    fn size(&self) -> (u32, u32) {
        self.with_region_figure(|f| f.size())
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), PlotError> {
        self.with_region_figure(|f| f.draw(root))
    }
}

impl PlanFigure<'_> {
    /// Build the region figure of the plan's rig with the proposals and hand it to `f`.
    fn with_region_figure<R>(&self, f: impl FnOnce(&RegionFigure<'_>) -> R) -> R {
        let rig = &self.report.rig;
        let map = RegionMap::new(rig, &figure_window(rig));
        let trajectories = self.trajectories();
        let [theta, theta_dot, _] = self.report.release_box;
        let figure = RegionFigure {
            labels: labelled(self.report)
                .into_iter()
                .map(|(label, _, _)| label)
                .collect(),
            notes: self.proposal_notes(),
            emphasise_first: !self.report.proposals.is_empty(),
            release_box: Some([theta, theta_dot]),
            ..RegionFigure::new(rig, &map, &trajectories)
        };
        f(&figure)
    }
}
