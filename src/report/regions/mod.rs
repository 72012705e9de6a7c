//! Output of `appell regions`: the phase portrait runs, the readable summary, the JSON object
//! and the region figure in the (theta, theta') plane.
//!
//! `figure.rs` draws the region figure; this file runs the phase portrait and writes the
//! summary and the JSON object.

mod figure;

pub use figure::{figure_window, mode_color, RegionFigure};

use crate::model::regions::{slide_solution_count, Curve, RegionMap};
use crate::model::{FrictionLaw, Mode, Rig, State, THETA, THETA_DOT};
use crate::numbers::plain;
use crate::sim::{simulate, Options, Request, Sample};
use serde_json::{json, Value};
use std::f64::consts::PI;
use std::fmt::Write as _;

/// How the phase portrait is computed: how many runs, how long, sampled how often.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PortraitOptions {
    /// Number of trajectories (initial states from [`portrait_initial_states`]).
    pub trajectories: usize,
    /// Duration of each run (s).
    pub duration: f64,
    /// Sampling rate of each run (Hz).
    pub frame_rate: f64,
}

impl Default for PortraitOptions {
    /// Eight runs of 3 s at 1000 Hz (smooth curves at the figure's scale).
    fn default() -> Self {
        PortraitOptions {
            trajectories: 8,
            duration: 3.0,
            frame_rate: 1000.0,
        }
    }
}

/// The initial states of a phase portrait of `n` runs: about half released from rest at angles
/// spread over -30..80 degrees (one side of the hanging position only: a stuck release at
/// theta swings to 180 deg - theta, so a release from the other side would retrace the same
/// curve), the rest starting from the hanging position theta = 90 deg with angular velocities
/// +1.0, -1.6, +2.2, -2.8, ... sqrt(g / l) (alternating signs, growing, so no two runs are
/// mirror images of each other).
pub fn portrait_initial_states(rig: &Rig<f64>, n: usize) -> Vec<State<f64>> {
    let n_rest = n.div_ceil(2);
    let n_spin = n - n_rest;
    let (lo, hi) = (-30f64.to_radians(), 80f64.to_radians());
    let mut out = Vec::with_capacity(n);
    for k in 0..n_rest {
        let theta = if n_rest == 1 {
            0.0
        } else {
            lo + (hi - lo) * k as f64 / (n_rest - 1) as f64
        };
        out.push([0.0, theta, 0.0, 0.0]);
    }
    let unit = (rig.gravity / rig.rod_length).sqrt();
    for k in 0..n_spin {
        let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
        let w0 = sign * unit * (1.0 + 0.6 * k as f64);
        out.push([0.0, PI / 2.0, 0.0, w0]);
    }
    out
}

/// One run of a phase portrait.
#[derive(Debug, Clone)]
pub struct Trajectory {
    /// Its initial state (x, theta, x', theta').
    pub initial: State<f64>,
    /// Samples at the frame rate (fewer when the run stopped early).
    pub samples: Vec<Sample<f64>>,
    /// The run stopped at a Painleve paradox event (no unique continuation).
    pub stopped_at_paradox: bool,
    /// Why the simulator failed, when it did (the samples are then empty).
    pub error: Option<String>,
    /// Times of impulsive stops (s): theta' jumps there, so the figure does not join the
    /// samples on either side as if the rig moved between them.
    pub impulse_times: Vec<f64>,
}

/// Simulate the runs of a phase portrait with [`crate::sim::simulate`] (rtol 1e-8). A run
/// that fails is kept with its error and no samples, so one stiff start cannot hide the rest.
pub fn phase_portrait(rig: &Rig<f64>, options: &PortraitOptions) -> Vec<Trajectory> {
    let sim_options = Options {
        rtol: 1e-8,
        atol: 1e-10,
        ..Options::default()
    };
    let n = (options.duration * options.frame_rate + 1e-9).floor() as usize;
    let request = Request {
        sample_times: (0..=n).map(|k| k as f64 / options.frame_rate).collect(),
        friction_work: false,
        positions_only: false,
    };
    portrait_initial_states(rig, options.trajectories)
        .into_iter()
        .map(
            |y0| match simulate(rig, &y0, options.duration, &sim_options, &request) {
                Ok(sol) => Trajectory {
                    initial: y0,
                    stopped_at_paradox: sol.stopped_at_paradox(),
                    impulse_times: impulse_times(&sol.events),
                    samples: sol.samples,
                    error: None,
                },
                Err(e) => Trajectory {
                    initial: y0,
                    samples: Vec::new(),
                    stopped_at_paradox: false,
                    error: Some(e.to_string()),
                    impulse_times: Vec::new(),
                },
            },
        )
        .collect()
}

/// The times of the events that apply an impulsive stop.
pub fn impulse_times(events: &[crate::sim::Event]) -> Vec<f64> {
    events
        .iter()
        .filter(|e| e.impulse.is_some())
        .map(|e| e.t)
        .collect()
}

fn curves_json(curves: &[Curve]) -> Value {
    json!(curves)
}

/// The JSON object of `appell regions --json`: the summary fields at the top level
/// (`mu_critical`, `theta_critical_deg`, `paradox_band_deg`, `max_mass_ratio_for_paradox`,
/// ...), the boundary curves as point lists `[theta, theta']` (rad, rad/s), the band edges
/// and, per trajectory, its start, how many samples each mode has and how it ended.
pub fn regions_json(map: &RegionMap, trajectories: &[Trajectory]) -> Value {
    let mut out = json!(map.summary);
    out["window"] = json!(map.window);
    out["stick_boundary"] = curves_json(&map.stick_boundary);
    out["q_zero"] = curves_json(&map.q_zero);
    out["law_bands"] = json!(map.law_bands);
    out["band_edges_deg"] = json!(map
        .band_edges
        .iter()
        .map(|t| t.to_degrees())
        .collect::<Vec<_>>());
    out["trajectories"] = json!(trajectories
        .iter()
        .map(|t| {
            let count = |m: Mode| t.samples.iter().filter(|s| s.mode == m).count();
            json!({
                "theta0_deg": t.initial[THETA].to_degrees(),
                "theta_dot0": t.initial[THETA_DOT],
                "samples": {
                    "stick": count(Mode::Stick),
                    "slide+": count(Mode::Slide(crate::model::Direction::Positive)),
                    "slide-": count(Mode::Slide(crate::model::Direction::Negative)),
                },
                "end_time": t.samples.last().map(|s| s.t),
                "stopped_at_paradox": t.stopped_at_paradox,
                "error": t.error,
            })
        })
        .collect::<Vec<_>>());
    out
}

/// The readable summary of `appell regions`.
pub fn regions_summary(rig: &Rig<f64>, map: &RegionMap, trajectories: &[Trajectory]) -> String {
    let s = &map.summary;
    let mut out = String::new();
    let friction = friction_words(rig);
    match rig.pendulum {
        Some(p) => {
            let _ = writeln!(
                out,
                "rig: m1 = {} kg, rigid pendulum m_p = {} kg, d = {} m, J = {} kg m^2, l = {} m (bob centre), g = {} m/s^2, {friction}",
                plain(p.slider_mass), plain(p.mass), plain(p.com), plain(p.inertia), plain(rig.marker_length), plain(rig.gravity)
            );
            let _ = writeln!(
                out,
                "equivalent point rig: slider {} kg, bob m_e = {} kg, L = {} m (r' = {})",
                plain(rig.slider_mass),
                plain(rig.bob_mass),
                plain(rig.rod_length),
                plain(s.mass_ratio)
            );
        }
        None => {
            let _ = writeln!(
                out,
                "rig: m1 = {} kg, m2 = {} kg (r = m1/m2 = {}), l = {} m, g = {} m/s^2, {friction}",
                plain(rig.slider_mass),
                plain(rig.bob_mass),
                plain(s.mass_ratio),
                plain(rig.rod_length),
                plain(rig.gravity)
            );
        }
    }
    paradox_lines(&mut out, rig, map);
    trajectory_lines(&mut out, trajectories);
    out
}

/// The critical friction, the paradox band (and each slide's solution counts at rest inside
/// it), the largest mass ratio with a band, and the curves of the map.
fn paradox_lines(out: &mut String, rig: &Rig<f64>, map: &RegionMap) {
    let s = &map.summary;
    let point = match (rig.pendulum, s.point_rig_mu_critical) {
        (Some(p), Some(m)) => format!(
            " (rigid pendulum, r' = {:.4}; the point rig with the same masses, r = m1/m_p = {:.4}, has mu* = {m:.4})",
            s.mass_ratio,
            p.point_mass_ratio()
        ),
        _ => String::new(),
    };
    let _ = writeln!(
        out,
        "critical friction mu* = {:.4} at theta* = {:.2} deg{point}",
        s.mu_critical, s.theta_critical_deg
    );
    law_band_lines(out, rig, map);
    if s.paradox_possible() {
        let bands: Vec<String> = s
            .paradox_band_deg
            .iter()
            .map(|[lo, hi]| format!("{lo:.2}..{hi:.2} deg"))
            .collect();
        let _ = writeln!(
            out,
            "paradox band at the largest coefficient a slide meets, mu = {} (mu |a| > D): {} (and the same |tan theta| in every quadrant)",
            plain(rig.mu_slide_max()),
            bands.join(" and ")
        );
        let _ = writeln!(
            out,
            "  inside it a slide in direction s has two solutions where sign(Q) = sign(s a), none where they differ;"
        );
        for [lo, hi] in &s.paradox_band_deg {
            let mid = (0.5 * (lo + hi)).to_radians();
            let _ = writeln!(
                out,
                "  at rest in {lo:.2}..{hi:.2} deg: slide+ has {} solutions, slide- has {}",
                slide_solution_count(rig, mid, 0.0, 1.0),
                slide_solution_count(rig, mid, 0.0, -1.0)
            );
        }
    } else {
        let _ = writeln!(
            out,
            "paradox band: none (the largest coefficient a slide meets, mu = {}, <= mu* = {:.4}): the sliding equation has exactly one solution everywhere",
            plain(rig.mu_slide_max()), s.mu_critical
        );
    }
    let ratio = if rig.pendulum.is_some_and(|p| !p.is_point()) {
        "equivalent ratio r'"
    } else {
        "m1/m2"
    };
    let _ = writeln!(
        out,
        "largest {ratio} with a paradox band at mu = {}: {:.4}",
        plain(rig.mu_slide_max()),
        s.max_mass_ratio_for_paradox
    );
    let _ = writeln!(
        out,
        "stick boundary |c| = mu_s |b|: {} curve pieces; Q = 0 (N changes sign while sliding): {} pieces; window theta {:.0}..{:.0} deg, |theta'| <= {:.2} rad/s",
        map.stick_boundary.len(),
        map.q_zero.len(),
        map.window.theta_min.to_degrees(),
        map.window.theta_max.to_degrees(),
        map.window.w_max
    );
}

/// The friction law and its coefficients in words, numbers at seven significant digits.
fn friction_words(rig: &Rig<f64>) -> String {
    let (k, st) = (plain(rig.mu_kinetic), plain(rig.mu_static));
    match rig.friction_law {
        FrictionLaw::Coulomb => format!("mu_k = {k}, mu_s = {st}"),
        FrictionLaw::Stribeck => format!(
            "Stribeck's law: mu_k = {k} sliding fast, mu_s = {st} at rest, v_s = {} m/s",
            plain(rig.stribeck_velocity)
        ),
        FrictionLaw::Direction => format!(
            "direction law: toward +x mu_k+ = {}, mu_s+ = {}; toward -x mu_k- = {}, mu_s- = {} (means {k} and {st})",
            plain(rig.friction_mu(1.0, 0.0)),
            plain(rig.static_mu(1.0)),
            plain(rig.friction_mu(-1.0, 0.0)),
            plain(rig.static_mu(-1.0))
        ),
        FrictionLaw::Load => format!(
            "load law: mu_k = {k}, mu_s = {st} at the static load N_0 = (m1 + m2) g = {} N, exponent n = {}",
            plain(rig.static_load()),
            plain(rig.load_exponent)
        ),
    }
}

/// One line per coefficient of the friction law with the paradox band it opens, and what the
/// load law's loads are.
fn law_band_lines(out: &mut String, rig: &Rig<f64>, map: &RegionMap) {
    let s = &map.summary;
    if rig.friction_law == FrictionLaw::Load {
        let [lo, hi] = crate::model::regions::swing_loads(rig, &map.window);
        let _ = writeln!(
            out,
            "load law: the coefficient mu_k (|N| / N_0)^(n - 1) at the loads a swing meets in the window with the bob below the rail (the stuck normal force |b| for |theta'| <= {:.2} rad/s): {} to {} N, N_0 = {} N; with the bob above the rail |N| falls to 0 where Q = 0",
            map.window.w_max,
            plain(lo),
            plain(hi),
            plain(rig.static_load())
        );
    }
    for b in &map.law_bands {
        let what = match (rig.friction_law, b.label) {
            (FrictionLaw::Coulomb, _) => "Coulomb, mu_k".to_owned(),
            (FrictionLaw::Direction, d) => format!("sliding toward {d}, mu_k{}", &d[..1]),
            (FrictionLaw::Stribeck, "at rest") => "at rest (v -> 0), mu_s".to_owned(),
            (FrictionLaw::Stribeck, _) => "sliding fast (v >> v_s), mu_k".to_owned(),
            (FrictionLaw::Load, label) => format!(
                "{label} |N| = {} N, mu",
                plain(b.normal_load.unwrap_or(f64::NAN))
            ),
        };
        let band = if b.paradox_band_deg.is_empty() {
            format!("no paradox band (mu <= mu* = {:.4})", s.mu_critical)
        } else {
            let parts: Vec<String> = b
                .paradox_band_deg
                .iter()
                .map(|[lo, hi]| format!("{lo:.2}..{hi:.2} deg"))
                .collect();
            format!("paradox band {}", parts.join(" and "))
        };
        let _ = writeln!(out, "{what} = {}: {band}", plain(b.mu));
    }
}

/// One line per trajectory: its release, its modes in turn (the first eight of a long
/// timeline) and how it ended.
fn trajectory_lines(out: &mut String, trajectories: &[Trajectory]) {
    if !trajectories.is_empty() {
        let _ = writeln!(out, "trajectories:");
        for t in trajectories {
            let mut modes: Vec<&str> = Vec::new();
            for sample in &t.samples {
                let name = sample.mode.name();
                if modes.last() != Some(&name) {
                    modes.push(name);
                }
            }
            let end = match (&t.error, t.stopped_at_paradox) {
                (Some(e), _) => format!("failed: {e}"),
                (None, true) => format!(
                    "stopped at a paradox at t = {:.3} s",
                    t.samples.last().map_or(0.0, |s| s.t)
                ),
                (None, false) => "completed".to_owned(),
            };
            let mut timeline = modes.join(" > ");
            if modes.len() > 8 {
                timeline = format!(
                    "{} > ... ({} mode changes)",
                    modes[..8].join(" > "),
                    modes.len() - 1
                );
            }
            let _ = writeln!(
                out,
                "  theta0 = {:7.2} deg, theta'0 = {:6.2} rad/s: {timeline}; {end}",
                t.initial[THETA].to_degrees(),
                t.initial[THETA_DOT],
            );
        }
    }
}
