//! The joint fit's report: the rail's parameters with their intervals, the releases' table
//! and their agreement, as text, JSON and a figure of each release's own mu against the
//! joint band.

use super::plot::{data_range, draw_key, Figure, PlotError, Swatch};
use crate::fit::joint::JointReport;
use crate::fit::Estimate;
use plotters::coord::Shift;
use plotters::prelude::*;
use serde_json::{json, Value};
use std::fmt::Write as _;

/// The joint fit's one-line answer, in the single fit's words: `mu_kinetic = V +- E (95 %: LO
/// to HI) from N releases (K set aside), ...` with the verdict (the releases agree, or the
/// interval holds their disagreement, or the joint model needs what no rig has), or why there
/// is no value.
pub fn joint_answer(rep: &JointReport) -> String {
    let n = rep.releases.len();
    let aside = match rep.set_aside.len() {
        0 => String::new(),
        k => format!(", {k} set aside"),
    };
    if let Some(why) = &rep.failed {
        return format!(
            "mu_kinetic not measured, the joint fit of {n} releases{aside} failed: {why}"
        );
    }
    let e = &rep.mu_kinetic;
    let head = format!(
        "mu_kinetic = {} from {n} releases{aside}",
        crate::report::fit::with_interval(e)
    );
    // The agreement's p-value is in the sentence that follows the answer.
    if !rep.implausible.is_empty() {
        let needs: Vec<&str> = rep
            .implausible
            .iter()
            .map(|s| s.split(" is beyond").next().unwrap_or(s))
            .collect();
        format!(
            "{head}, limited by the model: needs {}; check on the rig what it names (below)",
            needs.join(", needs ")
        )
    } else if e.interval.contains("releases") {
        format!("{head}, limited by the releases' disagreement; the interval holds their spread")
    } else {
        format!("{head}, the releases agree")
    }
}

fn estimate_json(e: &Estimate) -> Value {
    json!({"value": e.value, "stderr": e.stderr, "ci95": e.ci95, "interval": e.interval})
}

/// The joint fit as one JSON object: `mu_kinetic` (of the releases kept; `null` with `failed`
/// the reason when the fit failed), `shared` (each shared parameter), the `shared_covariance`
/// (names and matrix: what the releases know, for `plan --after`), the `releases` kept, those
/// `set_aside` with their own values and z, the agreement tests and the models compared.
pub fn joint_json(rep: &JointReport) -> Value {
    let shared: serde_json::Map<String, Value> = rep
        .shared
        .iter()
        .map(|(q, e)| {
            let mut v = estimate_json(e);
            v["unit"] = json!(q.unit());
            (q.name().to_owned(), v)
        })
        .collect();
    let names: Vec<&str> = rep.shared.iter().map(|(q, _)| q.name()).collect();
    let cov: Vec<Vec<f64>> = (0..rep.shared_covariance.nrows())
        .map(|i| rep.shared_covariance.row(i).iter().copied().collect())
        .collect();
    json!({
        "joint": true,
        "mu_kinetic": if rep.failed.is_some() { Value::Null } else { estimate_json(&rep.mu_kinetic) },
        "failed": rep.failed,
        "shared": shared,
        "shared_covariance": {"names": names, "matrix": cov},
        "nuisances": rep.nuisances.iter().map(|n| n.name()).collect::<Vec<_>>(),
        "friction_law": rep.friction,
        "implausible": rep.implausible,
        "rig_measured": {
            "keys": rep.rig_keys.iter().map(|(k, v, sd, source)| json!({"key": k, "value": v, "sd": sd, "stated": *source == "stated", "source": source})).collect::<Vec<_>>(),
        },
        "releases": rep.releases,
        "set_aside": rep.set_aside,
        "left_out": rep.left_out.iter().map(|(n, w)| json!({"recording": n, "error": w})).collect::<Vec<_>>(),
        "consistency_p_value": rep.consistency_p,
        "consistency_p_value_all": rep.consistency_p_all,
        "disagreeing": rep.disagreeing,
        "adequacy": {"chi2": rep.chi2, "dof": rep.dof, "reduced_chi2": rep.reduced_chi2},
        "n_params": rep.n_params,
        "models": rep.models,
        "sentence": agreement_sentence(rep),
        "answer": joint_answer(rep),
        "warnings": rep.warnings,
        "iterations": rep.iterations,
    })
}

/// The joint fit as text: the shared parameters, the plain sentence, the releases' table.
pub fn joint_text(rep: &JointReport) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "{}", joint_answer(rep));
    if rep.failed.is_some() {
        let _ = writeln!(s, "FAILED: no value for mu_kinetic.");
    }
    let _ = writeln!(s, "{}", agreement_sentence(rep));
    if !rep.implausible.is_empty() {
        let _ = writeln!(
            s,
            "The joint model needs what no real rig has, so the result is limited by the model, not by the noise: {}",
            rep.implausible.join("; ")
        );
    }
    let _ = writeln!(
        s,
        "shared by every release{}:",
        if rep.set_aside.is_empty() {
            ""
        } else {
            " kept"
        }
    );
    // mu_kinetic is the answer line's; the table has the rest.
    for (q, e) in rep
        .shared
        .iter()
        .filter(|(q, _)| *q != crate::fit::Param::MuKinetic)
    {
        // Digits from the standard error, as in the answer line; the values in one column.
        let d = crate::report::two_digit_decimals(e.stderr).map_or(6, |d| d.min(12));
        let line = format!(
            "  {:<22} {:>24}  (95 %: {:.d$} to {:.d$}) [{}] {}",
            q.name(),
            crate::report::fit::value_pm(e.value, e.stderr),
            e.ci95[0],
            e.ci95[1],
            e.interval,
            crate::report::unit_of(*q, e.value)
        );
        let _ = writeln!(s, "{}", line.trim_end());
    }
    let nuis: Vec<&str> = rep.nuisances.iter().map(|n| n.name()).collect();
    let _ = writeln!(
        s,
        "nuisances: {}; chi-square {:.1} on {:.0} degrees of freedom (reduced {:.3}), {} parameters",
        if nuis.is_empty() {
            "none".to_owned()
        } else {
            nuis.join(", ")
        },
        rep.chi2,
        rep.dof,
        rep.reduced_chi2,
        rep.n_params
    );
    super::fit::friction_law_text(&mut s, &rep.friction);
    let w = rep
        .releases
        .iter()
        .map(|r| r.name.chars().count())
        .max()
        .unwrap_or(0)
        .max(7);
    let _ = writeln!(
        s,
        "{:<w$} {:>6} {:>5} {:>22} {:>10} {:>8} {:>7}  single fit (its own nuisances)",
        "release", "frames", "trans", "own mu +- se", "rms (m)", "chi2/n", "z"
    );
    for (i, r) in rep.releases.iter().chain(&rep.set_aside).enumerate() {
        if i == rep.releases.len() {
            let _ = writeln!(
                s,
                "set aside (own mu and z under the kept releases' model, chosen without them):"
            );
        }
        let own = r.own_mu.map_or("-".to_owned(), |e| {
            format!("{:.5} +- {:.1e}", e.value, e.stderr)
        });
        let single = r.single_mu.map_or("-".to_owned(), |e| {
            format!(
                "{:.5} +- {:.1e} ({})",
                e.value,
                e.stderr,
                if r.single_nuisances.is_empty() {
                    "no nuisance".to_owned()
                } else {
                    r.single_nuisances.join("+")
                }
            )
        });
        let _ = writeln!(
            s,
            "{:<w$} {:>6} {:>5} {:>22} {:>10.2e} {:>8.3} {:>7.2}{} {}",
            r.name,
            r.frames,
            r.transitions,
            own,
            r.rms_residual_m,
            r.chi2 / r.n_residuals.max(1) as f64,
            r.z,
            if r.agrees { " " } else { "!" },
            single
        );
    }
    for (n, why) in &rep.left_out {
        let _ = writeln!(s, "left out: {n}: {why}");
    }
    for w in &rep.warnings {
        let _ = writeln!(s, "warning: {w}");
    }
    let _ = writeln!(s, "{}", crate::report::fit::TERMS);
    s
}

/// Each release's own mu with its 95 % interval against the joint estimate's band.
pub struct JointFigure<'a> {
    /// The joint fit.
    pub report: &'a JointReport,
}

impl Figure for JointFigure<'_> {
    fn size(&self) -> (u32, u32) {
        (
            1000,
            280 + 40 * (self.report.releases.len() + self.report.set_aside.len()).min(40) as u32,
        )
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), PlotError> {
        let rep = self.report;
        // The releases kept, then those set aside (red).
        let rows: Vec<&crate::fit::joint::ReleaseRow> =
            rep.releases.iter().chain(&rep.set_aside).collect();
        let n = rows.len();
        let mu = &rep.mu_kinetic;
        // A strip below the chart for its key, where it covers nothing.
        let (w, h) = root.dim_in_pixel();
        let (root, strip) = root.split_vertically(h - 30);
        let x_range = data_range(
            rows.iter()
                .filter_map(|r| r.own_mu)
                .flat_map(|e| [e.value - 1.96 * e.stderr, e.value + 1.96 * e.stderr])
                .chain(mu.ci95),
            0.08,
        );
        let mut chart = ChartBuilder::on(&root)
            .caption(
                format!(
                    "mu_kinetic of each release (95 %) and the joint {:.6} [{:.6}, {:.6}]{}",
                    mu.value,
                    mu.ci95[0],
                    mu.ci95[1],
                    if rep.set_aside.is_empty() {
                        String::new()
                    } else {
                        format!(" of the {} kept (red: set aside)", rep.releases.len())
                    }
                ),
                ("sans-serif", 20),
            )
            .margin(14)
            .x_label_area_size(45)
            .y_label_area_size(210)
            .build_cartesian_2d(x_range, -0.5f64..(n as f64 - 0.5))?;
        // File names only: the directory is the same for every release.
        let names: Vec<String> = rows
            .iter()
            .map(|r| {
                r.name
                    .split(',')
                    .map(|f| {
                        std::path::Path::new(f)
                            .file_name()
                            .map_or(f.to_owned(), |n| n.to_string_lossy().into_owned())
                    })
                    .collect::<Vec<_>>()
                    .join(",")
            })
            .collect();
        chart
            .configure_mesh()
            .disable_y_mesh()
            .light_line_style(WHITE)
            .y_labels(n.max(1))
            .y_label_formatter(&|y| {
                let i = y.round();
                if (y - i).abs() < 1e-6 && i >= 0.0 && (i as usize) < names.len() {
                    names[n - 1 - i as usize].clone()
                } else {
                    String::new()
                }
            })
            .x_desc("mu_kinetic")
            .label_style(("sans-serif", 14))
            .draw()?;
        let band = RGBColor(120, 160, 220);
        let mut key = vec![
            (
                Swatch::Dot(BLACK),
                "a release's own mu, 95 % bar".to_owned(),
            ),
            // The band's colour at 30 % over white, as it is drawn.
            (
                Swatch::Fill(RGBColor(214, 226, 244)),
                "joint 95 % interval".to_owned(),
            ),
            (Swatch::Line(band, 2), "joint value".to_owned()),
        ];
        if !rep.set_aside.is_empty() {
            key.push((Swatch::Dot(RED), "set aside".to_owned()));
        }
        draw_key(&strip, &key, (w as i32 - 20, 12), 14)?;
        chart.draw_series(std::iter::once(Rectangle::new(
            [(mu.ci95[0], -0.5), (mu.ci95[1], n as f64 - 0.5)],
            band.mix(0.3).filled(),
        )))?;
        chart.draw_series(std::iter::once(PathElement::new(
            vec![(mu.value, -0.5), (mu.value, n as f64 - 0.5)],
            band.stroke_width(2),
        )))?;
        for (i, r) in rows.iter().enumerate() {
            let Some(e) = r.own_mu else { continue };
            let y = (n - 1 - i) as f64;
            let color = if r.agrees { BLACK } else { RED };
            let (lo, hi) = (e.value - 1.96 * e.stderr, e.value + 1.96 * e.stderr);
            chart.draw_series(std::iter::once(PathElement::new(
                vec![(lo, y), (hi, y)],
                color.stroke_width(2),
            )))?;
            chart.draw_series(std::iter::once(Circle::new(
                (e.value, y),
                5,
                color.filled(),
            )))?;
        }
        Ok(())
    }
}

/// The plain sentence on what the joint interval holds: every release agrees; some were set
/// aside (each with its own mu and z under the others' model) and the rest agree; or the
/// releases disagree and no few of them account for it.
pub fn agreement_sentence(rep: &JointReport) -> String {
    let n_kept = rep.releases.len();
    let (kept_p, all_p, aside) = (rep.consistency_p, rep.consistency_p_all, &rep.set_aside);
    let p = |p: Option<f64>| crate::report::p_is(p.unwrap_or(f64::NAN));
    if rep.unresolved {
        return format!(
            "The releases disagree ({}), and no set of at most half of them, set aside, leaves releases that agree: the interval is widened by the releases' spread, and is the rail's only if every release ran on one rail.",
            p(all_p)
        );
    }
    if aside.is_empty() {
        return format!(
            "The {n_kept} releases agree ({}); the interval is what they support together.",
            p(kept_p)
        );
    }
    let named: Vec<String> = aside
        .iter()
        .map(|r| {
            r.own_mu.map_or(r.name.clone(), |e| {
                format!(
                    "{} (own mu {:.5} +- {:.1e}, z {:+.1})",
                    r.name, e.value, e.stderr, r.z
                )
            })
        })
        .collect();
    format!(
        "The releases disagree ({}); {} {} set aside: {} off the other {n_kept} under a model chosen without {}. The result is the {n_kept} releases kept, which agree ({}).",
        p(all_p),
        named.join(", "),
        if aside.len() == 1 { "is" } else { "are" },
        if aside.len() == 1 { "it lies" } else { "each lies" },
        if aside.len() == 1 { "it" } else { "them" },
        p(kept_p)
    )
}
