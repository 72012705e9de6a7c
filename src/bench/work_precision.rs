//! Work-precision: run time against error for each integrator over a ladder of tolerances, on
//! reference scenes whose reference solutions are computed independently of the run measured
//! (the other method at a much tighter tolerance, or a closed form where one exists).

use super::batch_seconds;
use super::exact;
use crate::model::{energy, markers, momentum, regions, Rig, State};
use crate::sim::{simulate, Event, Method, Options, Request, SimError, Solution};
use serde::Serialize;
use std::f64::consts::FRAC_PI_2;

/// Tolerance of the reference runs; errors below the reference's own disagreement (reported
/// per scene) are not resolved.
pub const REFERENCE_RTOL: f64 = 1e-13;

/// The default tolerance ladder.
pub const DEFAULT_RTOLS: [f64; 9] = [1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12];

/// atol as a fraction of rtol (the paper scene's 1e-10 / 1e-12 pairing).
pub const ATOL_PER_RTOL: f64 = 1e-2;

/// A closed form a scene can be checked against besides the other method.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ClosedForm {
    /// The slider never slips: the exact pendulum released from rest at this amplitude (rad).
    StuckPendulum {
        /// Amplitude from hanging (rad).
        amplitude: f64,
    },
    /// mu = 0: horizontal momentum is conserved.
    Momentum,
}

/// A reference scene of the work-precision benchmark.
#[derive(Debug, Clone, PartialEq)]
pub struct WpScene {
    /// Short name (`--scenes` selects by it).
    pub name: &'static str,
    /// What the scene exercises.
    pub about: &'static str,
    /// The rig.
    pub rig: Rig<f64>,
    /// State at t = 0.
    pub initial: State<f64>,
    /// Duration (s).
    pub duration: f64,
    /// Frame rate of the marker and energy checks (Hz).
    pub frame_rate: f64,
    /// A closed form, where one exists.
    pub closed_form: Option<ClosedForm>,
}

impl WpScene {
    /// Frame times 0, 1/rate, ..., duration.
    pub fn frame_times(&self) -> Vec<f64> {
        let n = (self.duration * self.frame_rate + 1e-9).floor() as usize;
        (0..=n).map(|k| k as f64 / self.frame_rate).collect()
    }
}

/// The reference scenes: equal and unequal masses, many stick-slip cycles, a full rotation,
/// near-critical mu, the stuck pendulum (exact) and mu = 0 (momentum integral).
pub fn reference_scenes() -> Vec<WpScene> {
    let stuck_amplitude = 1.2;
    let r1 = regions::mu_critical(1.0);
    vec![
        WpScene {
            name: "paper",
            about: "equal masses 0.1 kg, l = 0.30, mu = 0.35, from rest rod horizontal, 2 s (8 events)",
            rig: Rig::paper(0.35),
            initial: [0.0; 4],
            duration: 2.0,
            frame_rate: 100.0,
            closed_form: None,
        },
        WpScene {
            name: "unequal",
            about: "m1 = 0.5, m2 = 0.2, mu_k = 0.12, mu_s = 0.144, from rest 0.9 rad from hanging, 4 s (stick-slip cycles)",
            rig: Rig::new(0.5, 0.2, 0.3, 9.81, 0.12, Some(0.144)).expect("valid rig"),
            initial: [0.0, FRAC_PI_2 - 0.9, 0.0, 0.0],
            duration: 4.0,
            frame_rate: 100.0,
            closed_form: None,
        },
        WpScene {
            name: "rotation",
            about: "equal masses, mu = 0.1, spinning over the top: full rotations, N changes sign, 2 s",
            rig: Rig::paper(0.1),
            initial: [0.0, FRAC_PI_2, 0.5, 25.0],
            duration: 2.0,
            frame_rate: 100.0,
            closed_form: None,
        },
        WpScene {
            name: "near_critical",
            about: "equal masses, mu = 0.99 mu* = 2.80, sliding through theta* = 54.7 deg (stiff), 1 s",
            rig: Rig::paper(0.99 * r1),
            initial: [0.0, 0.2, 3.0, 4.0],
            duration: 1.0,
            frame_rate: 100.0,
            closed_form: None,
        },
        WpScene {
            name: "stuck",
            about: "mu = 2.5: never slips; exact pendulum (Jacobi sn/cn), amplitude 1.2 rad, 2 s",
            rig: Rig::paper(2.5),
            initial: [0.0, FRAC_PI_2 - stuck_amplitude, 0.0, 0.0],
            duration: 2.0,
            frame_rate: 100.0,
            closed_form: Some(ClosedForm::StuckPendulum {
                amplitude: stuck_amplitude,
            }),
        },
        WpScene {
            name: "frictionless",
            about: "mu = 0: slides throughout; momentum integral, 2 s",
            rig: Rig::paper(0.0),
            initial: [0.0, 0.3, 0.0, 0.0],
            duration: 2.0,
            frame_rate: 100.0,
            closed_form: Some(ClosedForm::Momentum),
        },
    ]
}

/// The other method: the reference for a method is never computed by itself.
pub fn other(method: Method) -> Method {
    match method {
        Method::Dp5 => Method::Dop853,
        Method::Dop853 => Method::Dp5,
    }
}

fn options(method: Method, rtol: f64) -> Options {
    Options {
        rtol,
        atol: rtol * ATOL_PER_RTOL,
        method,
        max_steps: 5_000_000,
        // The integrators are what is measured: no closed-form shortcut for stuck phases.
        prove_stick: false,
        ..Options::default()
    }
}

/// A reference solution: events, final state and states at the frame times.
#[derive(Debug, Clone)]
pub struct Reference {
    /// How it was computed.
    pub source: String,
    /// Events (empty for a closed form without events).
    pub events: Vec<Event>,
    /// State at the scene's end.
    pub final_state: State<f64>,
    /// States at the frame times.
    pub frames: Vec<State<f64>>,
}

impl Reference {
    /// `method` at [`REFERENCE_RTOL`].
    pub fn by_method(scene: &WpScene, method: Method) -> Result<Self, SimError> {
        let sol = simulate(
            &scene.rig,
            &scene.initial,
            scene.duration,
            &options(method, REFERENCE_RTOL),
            &Request {
                sample_times: scene.frame_times(),
                friction_work: false,
                positions_only: false,
            },
        )?;
        Ok(Reference {
            source: format!("{} at rtol {REFERENCE_RTOL:e}", method.name()),
            events: sol.events,
            final_state: sol.final_state,
            frames: sol.samples.iter().map(|s| s.state).collect(),
        })
    }

    /// The closed form of the scene, when it gives the whole state.
    pub fn closed_form(scene: &WpScene) -> Option<Self> {
        let Some(ClosedForm::StuckPendulum { amplitude }) = scene.closed_form else {
            return None;
        };
        let at = |t| exact::stuck_pendulum(&scene.rig, amplitude, t);
        Some(Reference {
            source: "exact pendulum (Jacobi elliptic functions)".into(),
            events: Vec::new(),
            final_state: at(scene.duration),
            frames: scene.frame_times().into_iter().map(at).collect(),
        })
    }
}

/// Largest difference of event times, when both runs have the same events (kind and order);
/// `None` when there are none to compare or they differ.
fn event_error(events: &[Event], reference: &[Event]) -> Option<f64> {
    if events.is_empty()
        || events.len() != reference.len()
        || events.iter().zip(reference).any(|(a, b)| a.kind != b.kind)
    {
        return None;
    }
    Some(
        events
            .iter()
            .zip(reference)
            .map(|(a, b)| (a.t - b.t).abs())
            .fold(0.0, f64::max),
    )
}

/// Max-norm of a state difference (m, rad, m/s, rad/s: all of order one on these rigs).
fn state_error(a: &State<f64>, b: &State<f64>) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| (p - q).abs())
        .fold(0.0, f64::max)
}

/// Largest distance (m) of either marker from its reference position over the frames.
fn marker_error(rig: &Rig<f64>, states: &[State<f64>], reference: &[State<f64>]) -> f64 {
    states
        .iter()
        .zip(reference)
        .map(|(y, r)| {
            let (m, n) = (markers(rig, y), markers(rig, r));
            let slider = (m[0] - n[0]).hypot(m[1] - n[1]);
            let bob = (m[2] - n[2]).hypot(m[3] - n[3]);
            slider.max(bob)
        })
        .fold(0.0, f64::max)
}

/// One point of the diagram: a method at a tolerance on a scene.
#[derive(Debug, Clone, Serialize)]
pub struct WpPoint {
    /// Scene name.
    pub scene: String,
    /// Method name.
    pub method: &'static str,
    /// Relative tolerance.
    pub rtol: f64,
    /// Absolute tolerance.
    pub atol: f64,
    /// Median wall time of one run (events and final state only), s.
    pub seconds: Option<f64>,
    /// Lower and upper quartile of the batch timings, s: the spread of `seconds` on this
    /// machine, which the goals take into account.
    pub seconds_quartiles: Option<[f64; 2]>,
    /// Largest event-time error (s) against the reference; null when the scene has no events
    /// or the event sequence differs from the reference's (see `events`).
    pub event_time_error_s: Option<f64>,
    /// Events found.
    pub events: usize,
    /// Events in the reference.
    pub reference_events: usize,
    /// Max-norm of the final-state error (m, rad, m/s, rad/s).
    pub state_error: Option<f64>,
    /// Largest marker-position error at the frame times (m).
    pub marker_error_m: Option<f64>,
    /// Largest |E(t) - E(0) - W_friction(t)| at the frame times, over m2 g l
    /// (dimensionless; from a run with friction_work on).
    pub energy_defect: Option<f64>,
    /// mu = 0 scenes: largest |p(t) - p(0)| at the frame times, over m2 sqrt(g l).
    pub momentum_defect: Option<f64>,
    /// Accepted steps.
    pub steps: usize,
    /// Right-hand-side evaluations.
    pub rhs_evals: usize,
    /// What the errors are measured against.
    pub reference: String,
    /// The run's error, when it failed.
    pub failure: Option<String>,
}

/// How well the two independent references of a scene agree: the floor below which errors
/// are not resolved.
#[derive(Debug, Clone, Serialize)]
pub struct ReferenceCheck {
    /// Scene name.
    pub scene: String,
    /// What the scene exercises.
    pub about: String,
    /// Largest event-time difference between DP5 and DOP853 at the reference tolerance (s).
    pub event_time_disagreement_s: Option<f64>,
    /// Final-state difference between them.
    pub state_disagreement: f64,
    /// Final-state difference of the DOP853 reference from the closed form, where one exists.
    pub closed_form_error: Option<f64>,
    /// Events in the reference.
    pub events: usize,
}

/// What to run.
#[derive(Debug, Clone)]
pub struct WpConfig {
    /// Scenes.
    pub scenes: Vec<WpScene>,
    /// Tolerance ladder.
    pub rtols: Vec<f64>,
    /// Methods.
    pub methods: Vec<Method>,
    /// Timed batches per point (the median is reported).
    pub batches: usize,
    /// Wall time to spend timing one point (s).
    pub seconds_per_point: f64,
}

impl Default for WpConfig {
    fn default() -> Self {
        WpConfig {
            scenes: reference_scenes(),
            rtols: DEFAULT_RTOLS.to_vec(),
            methods: Method::ALL.to_vec(),
            batches: 7,
            seconds_per_point: 0.03,
        }
    }
}

/// The whole benchmark's result.
#[derive(Debug, Clone, Serialize)]
pub struct WorkPrecision {
    /// Every point.
    pub work_precision: Vec<WpPoint>,
    /// Reference agreement per scene.
    pub references: Vec<ReferenceCheck>,
    /// The goals of issue 7, measured.
    pub goals: Vec<Goal>,
}

/// A goal measured on one scene and method (or a pair of methods).
#[derive(Debug, Clone, Serialize)]
pub struct Goal {
    /// Scene name.
    pub scene: String,
    /// The goal.
    pub goal: String,
    /// Whether it is met: null when the data cannot tell, including when the threshold lies
    /// within the spread of the timings (quartiles of the batches), so the verdict does not
    /// flip from run to run.
    pub met: Option<bool>,
    /// The figures behind the verdict.
    pub detail: String,
}

fn energy_and_momentum(
    scene: &WpScene,
    sol: &Solution<f64>,
) -> (Option<f64>, Option<f64>, Vec<State<f64>>) {
    let rig = &scene.rig;
    let (e0, p0) = (energy(rig, &scene.initial), momentum(rig, &scene.initial));
    let e_unit = rig.bob_mass * rig.gravity * rig.rod_length;
    let p_unit = rig.bob_mass * (rig.gravity * rig.rod_length).sqrt();
    let mut de = 0.0_f64;
    let mut dp = 0.0_f64;
    for s in &sol.samples {
        let w = s.friction_work.unwrap_or(0.0);
        de = de.max((energy(rig, &s.state) - e0 - w).abs() / e_unit);
        dp = dp.max((momentum(rig, &s.state) - p0).abs() / p_unit);
    }
    let momentum = (scene.closed_form == Some(ClosedForm::Momentum)).then_some(dp);
    (
        Some(de),
        momentum,
        sol.samples.iter().map(|s| s.state).collect(),
    )
}

/// Measure one point: time the plain run, then compute every error.
fn point(
    scene: &WpScene,
    method: Method,
    rtol: f64,
    reference: &Reference,
    config: &WpConfig,
) -> WpPoint {
    let opts = options(method, rtol);
    let mut p = WpPoint {
        scene: scene.name.into(),
        method: method.name(),
        rtol,
        atol: opts.atol,
        seconds: None,
        seconds_quartiles: None,
        event_time_error_s: None,
        events: 0,
        reference_events: reference.events.len(),
        state_error: None,
        marker_error_m: None,
        energy_defect: None,
        momentum_defect: None,
        steps: 0,
        rhs_evals: 0,
        reference: reference.source.clone(),
        failure: None,
    };
    let plain = Request::default();
    let run = || simulate(&scene.rig, &scene.initial, scene.duration, &opts, &plain);
    let sol = match run() {
        Ok(sol) => sol,
        Err(e) => {
            p.failure = Some(e.to_string());
            return p;
        }
    };
    p.events = sol.events.len();
    p.steps = sol.stats.steps;
    p.rhs_evals = sol.stats.rhs_evals;
    p.event_time_error_s = event_error(&sol.events, &reference.events);
    p.state_error = Some(state_error(&sol.final_state, &reference.final_state));
    if let Ok((times, _)) = batch_seconds(run, config.batches, config.seconds_per_point) {
        let n = times.len();
        p.seconds = Some(times[n / 2]);
        p.seconds_quartiles = Some([times[n / 4], times[(3 * n) / 4]]);
    }
    let sampled = simulate(
        &scene.rig,
        &scene.initial,
        scene.duration,
        &opts,
        &Request {
            sample_times: scene.frame_times(),
            friction_work: true,
            positions_only: false,
        },
    );
    match sampled {
        Ok(sol) => {
            let (de, dp, frames) = energy_and_momentum(scene, &sol);
            p.energy_defect = de;
            p.momentum_defect = dp;
            p.marker_error_m = Some(marker_error(&scene.rig, &frames, &reference.frames));
        }
        Err(e) => p.failure = Some(format!("with samples and friction work: {e}")),
    }
    p
}

/// Run the benchmark; `progress` is called with each finished point.
pub fn run(config: &WpConfig, mut progress: impl FnMut(&WpPoint)) -> WorkPrecision {
    let mut points = Vec::new();
    let mut references = Vec::new();
    for scene in &config.scenes {
        let refs: Vec<(Method, Result<Reference, SimError>)> = Method::ALL
            .iter()
            .map(|&m| (m, Reference::by_method(scene, m)))
            .collect();
        let closed = Reference::closed_form(scene);
        let get = |m: Method| refs.iter().find(|(k, _)| *k == m).map(|(_, r)| r);
        if let (Some(Ok(a)), Some(Ok(b))) = (get(Method::Dp5), get(Method::Dop853)) {
            references.push(ReferenceCheck {
                scene: scene.name.into(),
                about: scene.about.into(),
                event_time_disagreement_s: event_error(&a.events, &b.events),
                state_disagreement: state_error(&a.final_state, &b.final_state),
                closed_form_error: closed
                    .as_ref()
                    .map(|c| state_error(&b.final_state, &c.final_state)),
                events: b.events.len(),
            });
        }
        for &method in &config.methods {
            let reference = match (&closed, get(other(method))) {
                (Some(c), _) => c.clone(),
                (None, Some(Ok(r))) => r.clone(),
                (None, Some(Err(e))) => {
                    let p = WpPoint {
                        scene: scene.name.into(),
                        method: method.name(),
                        rtol: f64::NAN,
                        atol: f64::NAN,
                        seconds: None,
                        seconds_quartiles: None,
                        event_time_error_s: None,
                        events: 0,
                        reference_events: 0,
                        state_error: None,
                        marker_error_m: None,
                        energy_defect: None,
                        momentum_defect: None,
                        steps: 0,
                        rhs_evals: 0,
                        reference: format!("{} reference failed", other(method).name()),
                        failure: Some(e.to_string()),
                    };
                    progress(&p);
                    points.push(p);
                    continue;
                }
                (None, None) => unreachable!("a reference is computed for every method"),
            };
            for &rtol in &config.rtols {
                let p = point(scene, method, rtol, &reference, config);
                progress(&p);
                points.push(p);
            }
        }
    }
    let goals = goals(config, &points);
    WorkPrecision {
        work_precision: points,
        references,
        goals,
    }
}

/// Cheapest run of `method` on `scene` whose `error` is at most `target`: (rtol, median s,
/// quartiles of the batch timings).
fn cheapest(
    points: &[WpPoint],
    scene: &str,
    method: &str,
    target: f64,
    error: impl Fn(&WpPoint) -> Option<f64>,
) -> Option<(f64, f64, [f64; 2])> {
    points
        .iter()
        .filter(|p| p.scene == scene && p.method == method)
        .filter(|p| error(p).is_some_and(|e| e <= target))
        .filter_map(|p| {
            p.seconds
                .map(|s| (p.rtol, s, p.seconds_quartiles.unwrap_or([s, s])))
        })
        .min_by(|a, b| a.1.total_cmp(&b.1))
}

/// A verdict that does not flip with the machine's timing noise: met when even the pessimistic
/// end of `range` meets `met_below`, not met when even the optimistic end misses it, and
/// undecided (null) when the threshold lies within the spread.
fn robust_verdict(range: [f64; 2], met_below: f64) -> Option<bool> {
    if range[1] <= met_below {
        Some(true)
    } else if range[0] > met_below {
        Some(false)
    } else {
        None
    }
}

/// The two goals of issue 7, measured on every scene: event times to 1e-10 s at no more than
/// 3x the cost of rtol 1e-6, and DOP853 cheaper than DP5 for state errors below 1e-8.
fn goals(config: &WpConfig, points: &[WpPoint]) -> Vec<Goal> {
    let mut out = Vec::new();
    for scene in &config.scenes {
        let name = scene.name;
        for &method in &config.methods {
            let m = method.name();
            let base = points
                .iter()
                .find(|p| p.scene == name && p.method == m && p.rtol == 1e-6)
                .and_then(|p| {
                    p.seconds
                        .map(|s| (s, p.seconds_quartiles.unwrap_or([s, s])))
                });
            let best = cheapest(points, name, m, 1e-10, |p| p.event_time_error_s);
            let has_events = points
                .iter()
                .any(|p| p.scene == name && p.reference_events > 0);
            if !has_events {
                continue;
            }
            let (met, detail) = match (base, best) {
                (Some((b, bq)), Some((rtol, s, sq))) => {
                    // The ratio's spread: quartiles of both timings, the pessimistic pairing.
                    let spread = [sq[0] / bq[1], sq[1] / bq[0]];
                    (
                        robust_verdict(spread, 3.0),
                        format!(
                            "{m}: events to 1e-10 s first at rtol {rtol:e} in {:.1} us = {:.2} x (spread {:.2}..{:.2}) the {:.1} us of rtol 1e-6",
                            s * 1e6,
                            s / b,
                            spread[0],
                            spread[1],
                            b * 1e6
                        ),
                    )
                }
                (Some((b, _)), None) => (
                    Some(false),
                    format!(
                        "{m}: no tolerance of the ladder reached 1e-10 s (rtol 1e-6: {:.1} us)",
                        b * 1e6
                    ),
                ),
                _ => (None, format!("{m}: rtol 1e-6 not in the ladder or failed")),
            };
            out.push(Goal {
                scene: name.into(),
                goal: format!("{m}: event times to 1e-10 s at <= 3x the cost of rtol 1e-6"),
                met,
                detail,
            });
        }
        if config.methods.len() == 2 {
            for target in [1e-8, 1e-10] {
                let costs: Vec<_> = [Method::Dp5, Method::Dop853]
                    .iter()
                    .map(|m| cheapest(points, name, m.name(), target, |p| p.state_error))
                    .collect();
                let (met, detail) = match (costs[0], costs[1]) {
                    (Some(a), Some(b)) => (
                        // Cheaper beyond the timing spread: dop853's time over dp5's, from
                        // the most to the least favourable quartiles, below 1.
                        robust_verdict([b.2[0] / a.2[1], b.2[1] / a.2[0]], 1.0 - 1e-12),
                        format!(
                            "state error <= {target:e}: dp5 {:.1} us (rtol {:e}, quartiles {:.1}..{:.1}), dop853 {:.1} us (rtol {:e}, quartiles {:.1}..{:.1})",
                            a.1 * 1e6,
                            a.0,
                            a.2[0] * 1e6,
                            a.2[1] * 1e6,
                            b.1 * 1e6,
                            b.0,
                            b.2[0] * 1e6,
                            b.2[1] * 1e6
                        ),
                    ),
                    (None, Some(b)) => (
                        Some(true),
                        format!(
                            "state error <= {target:e}: dp5 never, dop853 {:.1} us (rtol {:e})",
                            b.1 * 1e6,
                            b.0
                        ),
                    ),
                    (a, None) => (
                        a.map(|_| false),
                        format!("state error <= {target:e}: dop853 never reached it"),
                    ),
                };
                out.push(Goal {
                    scene: name.into(),
                    goal: format!("dop853 cheaper than dp5 at state error {target:e}"),
                    met,
                    detail,
                });
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn event_error_needs_matching_sequences() {
        let rig = Rig::paper(0.35);
        let sol = |rtol| {
            simulate(
                &rig,
                &[0.0; 4],
                0.5,
                &options(Method::Dop853, rtol),
                &Request::default(),
            )
            .unwrap()
        };
        let (a, b) = (sol(1e-8), sol(1e-12));
        let e = event_error(&a.events, &b.events).unwrap();
        assert!(e > 0.0 && e < 1e-6, "{e}");
        assert_eq!(event_error(&a.events[..1], &b.events), None);
        assert_eq!(event_error(&[], &[]), None);
    }

    #[test]
    fn verdicts_within_the_timing_spread_are_undecided() {
        assert_eq!(robust_verdict([2.0, 2.9], 3.0), Some(true));
        assert_eq!(robust_verdict([3.1, 3.5], 3.0), Some(false));
        assert_eq!(robust_verdict([2.8, 3.2], 3.0), None);
    }

    #[test]
    fn tiny_benchmark_runs_and_reports_every_field() {
        let config = WpConfig {
            scenes: reference_scenes()
                .into_iter()
                .filter(|s| s.name == "paper" || s.name == "stuck")
                .collect(),
            rtols: vec![1e-6, 1e-8],
            methods: Method::ALL.to_vec(),
            batches: 1,
            seconds_per_point: 0.0,
        };
        let wp = run(&config, |_| {});
        assert_eq!(wp.work_precision.len(), 2 * 2 * 2);
        for p in &wp.work_precision {
            assert!(p.failure.is_none(), "{p:?}");
            assert!(p.seconds.unwrap() > 0.0);
            assert!(p.state_error.unwrap() < 1e-3, "{p:?}");
            assert!(p.energy_defect.unwrap() < 1e-3, "{p:?}");
            assert_eq!(p.event_time_error_s.is_some(), p.scene == "paper", "{p:?}");
        }
        let stuck = wp.references.iter().find(|r| r.scene == "stuck").unwrap();
        assert!(stuck.closed_form_error.unwrap() < 1e-10, "{stuck:?}");
        let json = serde_json::to_value(&wp).unwrap();
        let first = &json["work_precision"][0];
        for key in [
            "method",
            "rtol",
            "seconds",
            "seconds_quartiles",
            "event_time_error_s",
            "state_error",
        ] {
            assert!(first.get(key).is_some(), "{key}");
        }
    }
}
