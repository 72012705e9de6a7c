//! Output of `appell simulate`: the event timeline, the JSON object and the trajectory CSV.

use crate::model::{energy, markers, Rig};
use crate::scene::Scene;
use crate::sim::{Outcome, Solution, Stats};
use serde_json::{json, Value};
use std::fmt::Write as _;
use std::io::Write;

/// A readable event timeline with the final state and run statistics.
pub fn timeline(scene: &Scene, sol: &Solution<f64>) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{:>14}  {:<8} {:<14} {:<13} {:>12} {:>12}",
        "t [s]", "from", "to", "kind", "theta [deg]", "x [m]"
    );
    for e in &sol.events {
        let _ = writeln!(
            s,
            "{:>14.10}  {:<8} {:<14} {:<13} {:>12.4} {:>12.6}",
            e.t,
            e.from.name(),
            e.to.to_string(),
            e.kind.name(),
            e.state[1].to_degrees(),
            e.state[0]
        );
        // Paradox details on a line of their own, under the event they belong to.
        if !e.alternatives.is_empty() && matches!(e.to, Outcome::Mode(_)) {
            let names: Vec<_> = e.alternatives.iter().map(|m| m.name()).collect();
            let _ = writeln!(s, "{:>16}chosen among {}", "", names.join(" | "));
        }
        if let Some(n) = e.peak_normal {
            let _ = writeln!(s, "{:>16}peak |N| = {n:.6e} N", "");
        }
        if let Some(i) = e.impulse {
            let _ = writeln!(
                s,
                "{:>16}impulsive stop from x' = {:.6e} m/s: P_N = {:.6e} N s, P_F = {:.6e} N s, energy lost {:.6e} J",
                "", i.x_dot_before, i.normal, i.friction, i.energy_lost
            );
        }
    }
    if sol.events.is_empty() {
        let _ = writeln!(s, "(no events: {} throughout)", sol.final_mode);
    }
    let y = sol.final_state;
    let _ = writeln!(
        s,
        "final at t = {} s ({}): x = {:.9} m, theta = {:.9} rad, x' = {:.9} m/s, theta' = {:.9} rad/s",
        sol.final_time, sol.final_mode, y[0], y[1], y[2], y[3]
    );
    if sol.final_time < scene.duration {
        let _ = writeln!(s, "stopped early: the motion past the last event is not unique or does not exist (Painleve paradox, or a dynamic jam)");
    }
    let st = sol.stats;
    let _ = writeln!(
        s,
        "{}: rtol {:e}, atol {:e}; {} steps, {} rejected, {} rhs evaluations, {} event{}{}",
        scene.options.method.name(),
        scene.options.rtol,
        scene.options.atol,
        st.steps,
        st.rejected,
        st.rhs_evals,
        st.events,
        if st.events == 1 { "" } else { "s" },
        closed_form_note(&st)
    );
    s
}

/// ", N stick phases in closed form" when there were any, for the statistics line.
pub fn closed_form_note(st: &Stats) -> String {
    match st.closed_form {
        0 => String::new(),
        1 => ", 1 stick phase in closed form".into(),
        n => format!(", {n} stick phases in closed form"),
    }
}

fn state_json(y: &[f64; 4]) -> Value {
    json!({"x": y[0], "theta": y[1], "x_dot": y[2], "theta_dot": y[3]})
}

/// The JSON object of `appell simulate --json`.
pub fn simulation_json(scene: &Scene, sol: &Solution<f64>) -> Value {
    let events: Vec<Value> = sol
        .events
        .iter()
        .map(|e| {
            let mut v = json!({
                "t": e.t,
                "from": e.from.name(),
                "to": e.to.name(),
                "kind": e.kind,
                "state": state_json(&e.state),
            });
            if let Outcome::Indeterminate(alts) = &e.to {
                v["alternatives"] = json!(alts.iter().map(|m| m.name()).collect::<Vec<_>>());
            }
            if !e.alternatives.is_empty() {
                v["alternatives"] =
                    json!(e.alternatives.iter().map(|m| m.name()).collect::<Vec<_>>());
            }
            if let Some(i) = e.impulse {
                v["impulse"] = json!(i);
            }
            if let Some(n) = e.peak_normal {
                v["peak_normal"] = json!(n);
            }
            v
        })
        .collect();
    let mut out = json!({
        "events": events,
        "final": state_json(&sol.final_state),
        "final_time": sol.final_time,
        "final_mode": sol.final_mode.name(),
        "completed": sol.final_time >= scene.duration,
        "stats": sol.stats,
        "method": scene.options.method.name(),
        "rtol": scene.options.rtol,
        "atol": scene.options.atol,
    });
    if let Some(w) = sol.friction_work {
        out["friction_work"] = json!(w);
        out["energy_change"] =
            json!(energy(&scene.rig, &sol.final_state) - energy(&scene.rig, &scene.initial));
        out["damping_work"] = json!(sol.damping_work.unwrap_or(0.0));
        // Closes the balance: energy_change = friction_work + damping_work - impulsive_losses.
        out["impulsive_losses"] = json!(sol.impulsive_losses());
    }
    out
}

/// The sampled trajectory as CSV: t, mode, state, and markers/energy when the scene asks.
pub fn write_trajectory_csv(
    w: &mut dyn Write,
    rig: &Rig<f64>,
    scene: &Scene,
    sol: &Solution<f64>,
) -> std::io::Result<()> {
    let mut wr = csv::Writer::from_writer(w);
    let mut header = vec!["t", "mode", "x", "theta", "x_dot", "theta_dot"];
    if scene.output.markers {
        header.extend(["slider_x", "slider_y", "bob_x", "bob_y"]);
    }
    if scene.output.energy {
        header.extend(["energy", "friction_work", "damping_work"]);
    }
    wr.write_record(&header)?;
    for s in &sol.samples {
        let mut row = vec![format!("{}", s.t), s.mode.name().to_owned()];
        row.extend(s.state.iter().map(|v| format!("{v:.15e}")));
        if scene.output.markers {
            row.extend(markers(rig, &s.state).iter().map(|v| format!("{v:.15e}")));
        }
        if scene.output.energy {
            row.push(format!("{:.15e}", energy(rig, &s.state)));
            row.push(format!("{:.15e}", s.friction_work.unwrap_or(f64::NAN)));
            row.push(format!("{:.15e}", s.damping_work.unwrap_or(f64::NAN)));
        }
        wr.write_record(&row)?;
    }
    wr.flush()
}
