//! The simulator against physics: energy balance, conservation laws, the exact pendulum,
//! mirror symmetry, closed forms and an independently computed event timeline.

use crate::helpers::*;
use appell::model::{energy, momentum, regions, Mode, Rig, Shorthands};
use appell::sim::{simulate, EventKind, Method, Options, Outcome, Request, SimError};
use std::f64::consts::{FRAC_PI_2, PI};

fn unequal_rig(mu: f64) -> Rig<f64> {
    Rig::new(0.5, 0.2, 0.3, 9.81, mu, Some(mu * 1.2)).unwrap()
}

/// dE/dt = F x' integrated: E(t) - E(0) equals the friction work along the whole run,
/// through every stick-slip transition, for both methods and several rigs.
#[test]
fn energy_change_equals_friction_work() {
    let cases = [
        (Rig::paper(0.35), [0.0, 0.0, 0.0, 0.0]),
        (unequal_rig(0.12), [0.0, FRAC_PI_2 - 0.9, 0.0, 0.0]),
        (Rig::paper(0.2), [0.01, 0.4, -0.3, 5.0]),
    ];
    for (rig, y0) in cases {
        for method in Method::ALL {
            let req = Request {
                sample_times: (0..=40).map(|k| k as f64 * 0.05).collect(),
                friction_work: true,
                positions_only: false,
            };
            let sol = run(&rig, y0, 2.0, 1e-12, method, &req);
            assert!(
                sol.events.len() >= 2,
                "the case should stick and slip: {:?}",
                sol.events
            );
            let e0 = energy(&rig, &y0);
            let work = sol.friction_work.unwrap();
            assert!(work < 0.0, "friction dissipates");
            for s in &sol.samples {
                let de = energy(&rig, &s.state) - e0;
                let w = s.friction_work.unwrap();
                assert!(
                    (de - w).abs() <= 1e-9 * work.abs().max(1e-3),
                    "{method:?} t={} dE={de} W={w}",
                    s.t
                );
            }
        }
    }
}

/// With mu = 0 the slider never sticks (except at equilibrium) and horizontal momentum is
/// conserved; energy is conserved too.
#[test]
fn frictionless_conserves_momentum_and_energy() {
    let rig = Rig::paper(0.0);
    for y0 in [
        [0.0, 0.3, 0.0, 0.0],
        [0.0, 0.0, 0.0, 0.0],
        [0.1, 1.0, 0.4, -3.0],
    ] {
        let req = Request {
            sample_times: (0..=100).map(|k| k as f64 * 0.03).collect(),
            friction_work: false,
            positions_only: false,
        };
        let sol = run(&rig, y0, 3.0, 1e-11, Method::Dop853, &req);
        let (p0, e0) = (momentum(&rig, &y0), energy(&rig, &y0));
        for s in &sol.samples {
            assert!(
                (momentum(&rig, &s.state) - p0).abs() < 1e-9,
                "t={} p={}",
                s.t,
                momentum(&rig, &s.state)
            );
            assert!((energy(&rig, &s.state) - e0).abs() < 1e-9);
            if s.t > 0.0 {
                assert!(
                    matches!(s.mode, Mode::Slide(_)),
                    "frictionless slider is never stuck (t={})",
                    s.t
                );
            }
        }
    }
}

/// A stuck pendulum released from rest at amplitude A reaches the mirror angle with zero
/// angular velocity after half its exact period 2 sqrt(l/g) K(sin(A/2)).
#[test]
fn stuck_pendulum_matches_elliptic_period() {
    // Friction well above the needed ratio (below mu* = 2.83 so no paradox): never slips.
    let rig = Rig::paper(2.5);
    for amplitude in [0.3_f64, 1.2, 2.5] {
        let half =
            2.0 * (rig.rod_length / rig.gravity).sqrt() * elliptic_k((amplitude / 2.0).sin());
        let y0 = [0.0, FRAC_PI_2 - amplitude, 0.0, 0.0];
        // The integrator is under test, so the closed-form shortcut for proven stick is off.
        let options = Options {
            rtol: 1e-12,
            atol: 1e-14,
            prove_stick: false,
            ..Options::default()
        };
        let sol = simulate(&rig, &y0, half, &options, &Request::default()).unwrap();
        assert!(sol.events.is_empty(), "A={amplitude}: {:?}", sol.events);
        assert_eq!(sol.final_mode, Mode::Stick);
        let y = sol.final_state;
        assert!(
            (y[1] - (FRAC_PI_2 + amplitude)).abs() < 1e-9,
            "A={amplitude}: theta={}",
            y[1]
        );
        assert!(y[3].abs() < 1e-8, "A={amplitude}: w={}", y[3]);
    }
}

/// (x, theta, x', w) -> (-x, pi - theta, -x', -w) maps motions to motions: the event times
/// agree and slide directions swap.
#[test]
fn mirror_symmetry_of_events() {
    for (rig, y0) in [
        (Rig::paper(0.3), [0.02, 0.2, 0.1, 2.0]),
        (unequal_rig(0.15), [0.0, 0.5, 0.0, -1.0]),
    ] {
        let a = run(&rig, y0, 2.0, 1e-11, Method::Dop853, &Request::default());
        let m = [-y0[0], PI - y0[1], -y0[2], -y0[3]];
        let b = run(&rig, m, 2.0, 1e-11, Method::Dop853, &Request::default());
        assert!(a.events.len() >= 3);
        assert_eq!(a.events.len(), b.events.len());
        for (ea, eb) in a.events.iter().zip(&b.events) {
            assert!((ea.t - eb.t).abs() < 1e-9, "{} vs {}", ea.t, eb.t);
            assert_eq!(ea.from.mirrored(), eb.from);
            let Outcome::Mode(ma) = ea.to else { panic!() };
            assert_eq!(Outcome::Mode(ma.mirrored()), eb.to);
            assert!((ea.state[0] + eb.state[0]).abs() < 1e-9);
            assert!((ea.state[1] - (PI - eb.state[1])).abs() < 1e-9);
        }
    }
}

/// mu* = 2 sqrt(r (1 + r)) equals the minimum over theta of D / |a| found numerically.
#[test]
fn critical_friction_matches_numerical_minimum() {
    for r in [0.05, 0.1, 0.5, 1.0, 2.0, 7.0] {
        let rig = Rig::new(r, 1.0, 0.3, 9.81, 0.0, None).unwrap();
        let ratio = |th: f64| {
            let sh = Shorthands::new(&rig, th, 0.0);
            sh.d / sh.a.abs()
        };
        // Coarse grid, then golden-section refinement.
        let n = 2000;
        let k = (1..n)
            .min_by(|&i, &j| {
                ratio(i as f64 / n as f64 * FRAC_PI_2)
                    .total_cmp(&ratio(j as f64 / n as f64 * FRAC_PI_2))
            })
            .unwrap();
        let (mut lo, mut hi) = (
            (k - 1) as f64 / n as f64 * FRAC_PI_2,
            (k + 1) as f64 / n as f64 * FRAC_PI_2,
        );
        let gr = (5f64.sqrt() - 1.0) / 2.0;
        for _ in 0..100 {
            let (c, d) = (hi - gr * (hi - lo), lo + gr * (hi - lo));
            if ratio(c) < ratio(d) {
                hi = d;
            } else {
                lo = c;
            }
        }
        let th = 0.5 * (lo + hi);
        assert!(
            (ratio(th) - regions::mu_critical(r)).abs() < 1e-10 * regions::mu_critical(r),
            "r={r}"
        );
        assert!((th - regions::theta_critical(r)).abs() < 1e-6, "r={r}");
    }
    assert!((regions::mu_critical(1.0) - 2.0 * 2f64.sqrt()).abs() < 1e-15);
}

/// The paper's rig from rest with the rod horizontal: slip near 0.0868 s (from the energy
/// integral of the stuck pendulum and the friction ratio, by quadrature) and the first stick
/// near 0.326 s (from an independent RK4 on the equations of motion solved as a linear system).
#[test]
fn paper_timeline_against_independent_solution() {
    let rig = Rig::paper(0.35);
    let (g, l, mu) = (rig.gravity, rig.rod_length, 0.35);
    // Stuck from rest at theta = 0: w^2 = 2 (g/l) sin(theta); the needed friction ratio is
    // |c| / |b| = 3 sin cos / (1 + 3 sin^2) for equal masses.
    let need = |th: f64| 3.0 * th.sin() * th.cos() / (1.0 + 3.0 * th.sin().powi(2)) - mu;
    let (mut lo, mut hi) = (1e-9, 0.46);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if need(mid) < 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let th_slip = 0.5 * (lo + hi);
    // t = int_0^th dtheta / sqrt(2 (g/l) sin theta), with theta = v^2 to remove the
    // endpoint singularity; composite Simpson.
    let vmax = th_slip.sqrt();
    let integrand = |v: f64| {
        if v == 0.0 {
            2.0 / (2.0 * g / l).sqrt()
        } else {
            2.0 * v / (2.0 * g / l * (v * v).sin()).sqrt()
        }
    };
    let n = 4000;
    let hv = vmax / n as f64;
    let simpson: f64 = (0..=n)
        .map(|i| {
            let wgt = if i == 0 || i == n {
                1.0
            } else if i % 2 == 1 {
                4.0
            } else {
                2.0
            };
            wgt * integrand(i as f64 * hv)
        })
        .sum::<f64>()
        * hv
        / 3.0;
    let t_slip = simpson;
    let w_slip = (2.0 * g / l * th_slip.sin()).sqrt();
    let (dt_stop, _) = oracle_slide_until_stop(&rig, [0.0, th_slip, 0.0, w_slip], 1.0, 2e-5);
    let t_stick = t_slip + dt_stop;

    let sol = run(
        &rig,
        [0.0; 4],
        0.5,
        1e-12,
        Method::Dop853,
        &Request::default(),
    );
    let ev = &sol.events;
    assert_eq!(
        (ev[0].from, &ev[0].to, ev[0].kind),
        (
            Mode::Stick,
            &Outcome::Mode(Mode::Slide(appell::model::Direction::Positive)),
            EventKind::Slip
        )
    );
    assert_eq!((ev[1].to.name(), ev[1].kind), ("stick", EventKind::Stick));
    assert!((t_slip - 0.0868).abs() < 5e-5, "oracle slip {t_slip}");
    assert!((t_stick - 0.326).abs() < 5e-4, "oracle stick {t_stick}");
    assert!(
        (ev[0].t - t_slip).abs() < 1e-9,
        "slip {} vs oracle {t_slip}",
        ev[0].t
    );
    assert!(
        (ev[1].t - t_stick).abs() < 1e-8,
        "stick {} vs oracle {t_stick}",
        ev[1].t
    );
    assert!((ev[0].state[1] - th_slip).abs() < 1e-8);
}

/// Event times converge as the tolerance tightens, for both methods, towards a reference
/// from the other method at the tightest tolerance; at rtol 1e-12 they agree to 1e-10 s.
#[test]
fn event_times_converge_with_tolerance() {
    let rig = unequal_rig(0.12);
    let y0 = [0.0, FRAC_PI_2 - 0.9, 0.0, 0.0];
    let reference = |m: Method| run(&rig, y0, 2.0, 1e-13, m, &Request::default());
    for method in Method::ALL {
        let other = if method == Method::Dp5 {
            Method::Dop853
        } else {
            Method::Dp5
        };
        let refr = reference(other);
        let mut errors = Vec::new();
        for rtol in [1e-6, 1e-8, 1e-10, 1e-12] {
            let sol = run(&rig, y0, 2.0, rtol, method, &Request::default());
            assert_eq!(
                sol.events.len(),
                refr.events.len(),
                "{method:?} rtol {rtol}"
            );
            let err = sol
                .events
                .iter()
                .zip(&refr.events)
                .map(|(a, b)| (a.t - b.t).abs())
                .fold(0.0, f64::max);
            errors.push(err);
        }
        assert!(
            errors.windows(2).all(|w| w[1] < w[0] || w[1] < 1e-11),
            "{method:?} not converging: {errors:?}"
        );
        assert!(
            errors[0] / errors[2].max(1e-13) > 100.0,
            "{method:?}: {errors:?}"
        );
        assert!(errors[3] < 1e-10, "{method:?}: {errors:?}");
    }
    // The example recording's stick onsets as its independent generator documented them (rig in
    // docs/formats.md): 0.3186, 0.8994, 1.4045 and 1.9210 s.
    let doc_rig = Rig::new(0.5, 0.2, 0.3, 9.81, 0.12, None).unwrap();
    let sol = run(
        &doc_rig,
        y0,
        2.0,
        1e-12,
        Method::Dop853,
        &Request::default(),
    );
    let sticks: Vec<f64> = sol
        .events
        .iter()
        .filter(|e| e.kind == EventKind::Stick)
        .map(|e| e.t)
        .collect();
    let documented = [0.3186, 0.8994, 1.4045, 1.9210];
    assert_eq!(sticks.len(), documented.len(), "{sticks:?}");
    for (a, b) in sticks.iter().zip(documented) {
        assert!((a - b).abs() < 1e-4, "{a} vs {b}");
    }
}

/// Above mu* the run goes on through the paradox and says what it did, by the sign rule of
/// docs/physics.md: a slide with no solution is stopped impulsively (with its impulses), a slide
/// with two takes the positive-denominator branch and runs on, also into the band.
#[test]
fn paradox_is_resolved_and_reported() {
    // Equal masses, mu = 3 > mu* = 2.83: the band is 45..63.43 deg (tan in (1, 2)).
    let rig = Rig::paper(3.0);
    let band = regions::paradox_band(1.0, 3.0).unwrap();
    assert!((band.0.tan() - 1.0).abs() < 1e-12 && (band.1.tan() - 2.0).abs() < 1e-12);
    let th = 50f64.to_radians();
    // Inside the band Q < 0 and a > 0: sliding with s a > 0 (s = +1) has no solution,
    // with s a < 0 (s = -1) two.
    let run_from =
        |y0: [f64; 4]| simulate(&rig, &y0, 1.0, &Options::default(), &Request::default()).unwrap();
    let sol = run_from([0.0, th, 0.5, 0.0]);
    let e = &sol.events[0];
    assert_eq!((e.t, e.kind), (0.0, EventKind::ImpulsiveStop));
    let imp = e.impulse.unwrap();
    let sh = Shorthands::new(&rig, th, 0.0);
    assert!((imp.friction + sh.d * 0.5).abs() < 1e-15 && (imp.normal + sh.a * 0.5).abs() < 1e-15);
    assert!(e.state[2] == 0.0 && (e.state[3] + th.sin() * 0.5 / rig.rod_length).abs() < 1e-15);
    assert!(!sol.stopped_at_paradox() && sol.final_time == 1.0);
    let sol = run_from([0.0, th, -0.5, 0.0]);
    assert!(
        sol.events.first().is_none_or(|e| e.t > 0.0),
        "{:?}",
        sol.events
    );
    assert!(!sol.stopped_at_paradox() && sol.final_time == 1.0);
    // Sliding (s = -1) from outside into the band: the branch keeps a positive denominator,
    // so nothing happens at the band edge (45 deg).
    let sol = run_from([0.0, 30f64.to_radians(), -3.0, 3.0]);
    assert!(sol
        .events
        .iter()
        .all(|e| (e.state[1] - band.0).abs() > 1e-3 || e.kind == EventKind::Stick));
    assert!(sol.final_time == 1.0);
}

/// Failures carry where they happened: a step limit is an error with the time and state.
#[test]
fn step_limit_is_an_error_with_state() {
    let rig = Rig::paper(0.35);
    let options = Options {
        max_steps: 10,
        ..Options::default()
    };
    let err = simulate(&rig, &[0.0; 4], 2.0, &options, &Request::default()).unwrap_err();
    let SimError::TooManySteps { t, max, state } = err else {
        panic!("{err}")
    };
    assert_eq!(max, 10);
    assert!(t > 0.0 && t < 2.0 && state[1] > 0.0);
}

/// A stick phase proven never to slip (its whole energy level stays inside the friction cone)
/// runs without slip monitoring; the proof is checked against runs that do monitor: no slip
/// where it holds, a slip where friction is a hair below the level's largest needed ratio,
/// and the same final state with and without the skip.
#[test]
fn proven_stick_skips_monitoring_without_changing_the_answer() {
    let y0 = [0.0, 0.4, 0.0, 0.0];
    // Largest needed ratio on this level, by brute force on the energy integral.
    let base = Rig::paper(0.5);
    let (g, l) = (base.gravity, base.rod_length);
    let peak = (0..200_000)
        .map(|k| 0.4 + (PI - 0.8) * k as f64 / 200_000.0)
        .map(|th: f64| {
            let w = (2.0 * g / l * (th.sin() - 0.4f64.sin())).max(0.0).sqrt();
            let sh = Shorthands::new(&base, th, w);
            sh.c.abs() / sh.b.abs()
        })
        .fold(0.0, f64::max);
    for (mu, holds) in [(peak * 1.001, true), (peak * 0.999, false)] {
        let rig = Rig::paper(mu);
        assert_eq!(
            regions::stick_holds_forever(&rig, y0[1], y0[3]),
            holds,
            "mu {mu}"
        );
        let monitored = simulate(
            &rig,
            &y0,
            3.0,
            &Options {
                prove_stick: false,
                ..Options::default()
            },
            &Request::default(),
        )
        .unwrap();
        assert_eq!(
            monitored.events.is_empty(),
            holds,
            "mu {mu}: {:?}",
            monitored.events
        );
        let skipped = simulate(&rig, &y0, 3.0, &Options::default(), &Request::default()).unwrap();
        assert_eq!(skipped.events.len(), monitored.events.len());
        // Where it holds, the skip ends in the pendulum's closed form once the phase has
        // lasted long enough to try the proof (far fewer steps than integrating 3 s), and the
        // integrated answer agrees with it to the integration tolerance.
        if holds {
            assert!(
                skipped.stats.steps * 2 < monitored.stats.steps,
                "{:?} vs {:?}",
                skipped.stats,
                monitored.stats
            );
        }
        for i in 0..4 {
            assert!(
                (skipped.final_state[i] - monitored.final_state[i]).abs() < 1e-8,
                "mu {mu}: {:?} vs {:?}",
                skipped.final_state,
                monitored.final_state
            );
        }
    }
}

/// On a small swing the needed friction ratio peaks at the turning points, the edge of the
/// angles the energy level reaches. A light slider (0.03 kg under a 0.1 kg bob) swinging 10 deg
/// needs |c|/|b| = m2 sin cos / (m1 + m2 sin^2) there, 1.6 % more than at the nearest angle of
/// the proof's grid; with friction 1 % below that it slips, and the run that may skip slip
/// monitoring must say so as the monitored run does (it once proved the stick instead).
#[test]
fn a_stick_that_slips_at_its_turning_point_is_not_proven() {
    let turn = FRAC_PI_2 - 10f64.to_radians();
    let pull = |mu: f64| {
        let rig = Rig::new(0.03, 0.1, 0.3, 9.81, mu, None).unwrap();
        let sh = Shorthands::new(&rig, turn, 0.0);
        (rig, sh.c.abs() / sh.b.abs())
    };
    let (_, peak) = pull(0.1);
    let (rig, _) = pull(0.99 * peak);
    // Mid-swing on the 10 deg level, moving toward the far turning point.
    let (g, l) = (rig.gravity, rig.rod_length);
    let th = FRAC_PI_2 - 2f64.to_radians();
    let y0 = [0.0, th, 0.0, (2.0 * g / l * (th.sin() - turn.sin())).sqrt()];
    let sh = Shorthands::new(&rig, y0[1], y0[3]);
    assert!(sh.c.abs() < rig.mu_static * sh.b.abs(), "starts stuck");
    assert!(!regions::stick_holds_forever(&rig, y0[1], y0[3]));
    let monitored = Options {
        prove_stick: false,
        ..Options::default()
    };
    for options in [monitored, Options::default()] {
        let run = simulate(&rig, &y0, 1.0, &options, &Request::default()).unwrap();
        assert!(
            !run.events.is_empty(),
            "prove_stick {}: no slip",
            options.prove_stick
        );
    }
}

/// Samples asked for positions only carry exactly the positions of a full run (same steps,
/// same dense output) and NaN velocities, so nothing can read a velocity it did not ask for;
/// both methods, through stick-slip events.
#[test]
fn positions_only_samples_are_the_full_runs_positions() {
    let rig = unequal_rig(0.12);
    let y0 = [0.0, FRAC_PI_2 - 0.9, 0.0, 0.0];
    for method in Method::ALL {
        let full = Request {
            sample_times: (0..=400).map(|k| k as f64 * 0.005).collect(),
            friction_work: false,
            positions_only: false,
        };
        let positions = Request {
            positions_only: true,
            ..full.clone()
        };
        let a = run(&rig, y0, 2.0, 1e-10, method, &full);
        let b = run(&rig, y0, 2.0, 1e-10, method, &positions);
        assert!(a.events.len() > 2, "{method:?}: stick-slip expected");
        assert_eq!(a.samples.len(), b.samples.len());
        for (s, p) in a.samples.iter().zip(&b.samples) {
            assert_eq!(s.mode, p.mode);
            assert_eq!(s.state[0].to_bits(), p.state[0].to_bits(), "x at {}", s.t);
            assert_eq!(
                s.state[1].to_bits(),
                p.state[1].to_bits(),
                "theta at {}",
                s.t
            );
            // At t = 0 and at events the state is known whole; between, velocities are NaN.
            assert!(p.t == 0.0 || p.state[2].is_nan() || s.state[2] == p.state[2]);
        }
        assert!(b.samples.iter().filter(|p| p.state[3].is_nan()).count() > 300);
    }
}

/// Stick phases taken in the pendulum's closed form (f64 runs with an undamped pivot that
/// sample nothing) end where the integrator at a far tighter tolerance ends them. With the
/// slides integrated at rtol 1e-12, the same events each within 1e-12 s and the final state
/// within 5e-12 of the integrator's at 1e-14, on releases that stick and slip both ways, start
/// at rest on a turning point, stick to the end, on tilted rails and under the Stribeck,
/// direction and load laws. The closed form is in use (fewer right-hand sides than the
/// integrator at the same tolerance), and it stays out of runs with a sample still to come or
/// a damped pivot: those are the integrator's, bit for bit.
#[test]
fn closed_form_stick_phases_match_the_tight_integrator() {
    let cases = [
        (Rig::paper(0.35), [0.0, 0.0, 0.0, 0.0], 2.0),
        (unequal_rig(0.12), [0.0, FRAC_PI_2 - 0.9, 0.0, 0.0], 2.0),
        (Rig::paper(0.5), [0.0, 0.3, 0.0, 1.0], 3.0),
        (Rig::paper(0.2), [0.01, 0.4, -0.3, 5.0], 2.0),
        // Ends 34 ms into its second stick phase.
        (Rig::paper(0.35), [0.0, 0.0, 0.0, 0.0], 0.36),
        // A tilted rail (the pendulum about the shifted vertical) and other friction laws,
        // which enter only through the slip guard.
        (
            Rig::paper(0.35).with_rail_tilt(0.02),
            [0.0, 0.0, 0.0, 0.0],
            2.0,
        ),
        (
            unequal_rig(0.2).with_stribeck(0.05).with_rail_tilt(-0.01),
            [0.0, 0.3, 0.0, 1.0],
            2.0,
        ),
        (
            Rig::paper(0.3).with_direction_split(0.04, 0.05),
            [0.0, 0.0, 0.0, 0.0],
            2.0,
        ),
        (
            Rig::paper(0.35).with_load_exponent(0.8),
            [0.0, 0.0, 0.0, 0.0],
            2.0,
        ),
    ];
    let closed = Options {
        rtol: 1e-12,
        atol: 1e-14,
        ..Options::default()
    };
    let integrated = Options {
        prove_stick: false,
        ..closed
    };
    let tight = Options {
        rtol: 1e-14,
        atol: 1e-16,
        ..integrated
    };
    for (rig, y0, t_end) in cases {
        let none = Request::default();
        let fast = simulate(&rig, &y0, t_end, &closed, &none).unwrap();
        let reference = simulate(&rig, &y0, t_end, &tight, &none).unwrap();
        let slow = simulate(&rig, &y0, t_end, &integrated, &none).unwrap();
        assert!(fast.events.len() >= 2, "{:?}", fast.events);
        assert!(
            fast.stats.rhs_evals < slow.stats.rhs_evals,
            "closed form unused: {:?} vs {:?}",
            fast.stats,
            slow.stats
        );
        assert_eq!(fast.final_mode, reference.final_mode);
        assert_eq!(fast.events.len(), reference.events.len());
        for (a, b) in fast.events.iter().zip(&reference.events) {
            assert_eq!((a.kind, &a.to), (b.kind, &b.to));
            assert!((a.t - b.t).abs() < 1e-12, "{} vs {}", a.t, b.t);
        }
        for i in 0..4 {
            let (a, b) = (fast.final_state[i], reference.final_state[i]);
            assert!((a - b).abs() < 5e-12, "{i}: {a} vs {b}");
        }
        // A sample still to come (here at the end): the integrator's run, unchanged.
        let frames = Request {
            sample_times: vec![t_end],
            ..Request::default()
        };
        let sampled = simulate(&rig, &y0, t_end, &closed, &frames).unwrap();
        let sampled_slow = simulate(&rig, &y0, t_end, &integrated, &frames).unwrap();
        assert_eq!(sampled.final_state, sampled_slow.final_state);
        assert_eq!(sampled.stats, sampled_slow.stats);
        // A damped pivot makes the stuck rig no conservative pendulum: no closed form.
        let damped = rig.with_pivot_damping(1e-4);
        let a = simulate(&damped, &y0, t_end, &closed, &none).unwrap();
        let b = simulate(&damped, &y0, t_end, &integrated, &none).unwrap();
        assert_eq!((a.final_state, a.stats), (b.final_state, b.stats));
    }
}

/// xorshift64: a fixed stream of uniform numbers in [0, 1) for the sweeps below.
fn uniform(state: &mut u64) -> f64 {
    *state ^= *state << 13;
    *state ^= *state >> 7;
    *state ^= *state << 17;
    (*state >> 11) as f64 / (1u64 << 53) as f64
}

/// The closed form finds the slips the integrator finds: over random rigs and releases (some
/// on tilted rails, some under Stribeck's law), and over releases whose friction is a hair
/// (1e-7 to 1e-2 relative) below the largest ratio their energy level needs, so that the stick
/// margin only grazes zero, the closed-form runs (slides at rtol 1e-12) have the event sequence
/// of the integrator at 1e-13, each event within 1e-9 s (a grazing slip's time is
/// ill-conditioned). Outside CI, `scripts/sweeps/closed_form_sweep.rs` runs 3000 and 1889 such
/// releases: among the grazing ones one sequence differs (where the integrator at 1e-12 also
/// misses slips, as it does in 3 more) and one slip is 1.4e-9 s off.
#[test]
fn closed_form_finds_the_integrators_slips_on_random_and_grazing_releases() {
    let mut state = 0x9E37_79B9_7F4A_7C15_u64;
    let closed = Options {
        rtol: 1e-12,
        atol: 1e-14,
        ..Options::default()
    };
    let tight = Options {
        rtol: 1e-13,
        atol: 1e-15,
        prove_stick: false,
        ..Options::default()
    };
    let (mut runs, mut phases) = (0, 0);
    for case in 0..400 {
        let mut u = || uniform(&mut state);
        let (m1, m2, l) = (0.05 + 0.5 * u(), 0.05 + 0.3 * u(), 0.1 + 0.4 * u());
        let (theta, w) = (-1.0 + 4.0 * u(), 6.0 * (u() - 0.5));
        let mu = if case % 2 == 0 {
            0.05 + 0.9 * u()
        } else {
            // Just below the level's largest needed ratio |c|/|b|.
            let base = Rig::new(m1, m2, l, 9.81, 0.5, None).unwrap();
            let gl = 9.81 / l;
            let energy = w * w - 2.0 * gl * theta.sin();
            let peak = (0..20_000)
                .map(|k| theta + 2.0 * PI * f64::from(k) / 20_000.0)
                .filter_map(|th: f64| {
                    let w2 = energy + 2.0 * gl * th.sin();
                    (w2 >= 0.0).then(|| {
                        let sh = Shorthands::new(&base, th, w2.sqrt());
                        sh.c.abs() / sh.b.abs()
                    })
                })
                .fold(0.0, f64::max);
            peak * (1.0 - 10f64.powf(-7.0 + 5.0 * u()))
        };
        let Ok(mut rig) = Rig::new(m1, m2, l, 9.81, mu, None) else {
            continue;
        };
        if !(mu > 0.02 && mu < 1.5) {
            continue;
        }
        if case % 4 == 0 {
            // A tilted rail, and every other time Stribeck's law.
            rig = rig.with_rail_tilt(0.06 * (u() - 0.5));
            if case % 8 == 0 {
                rig.mu_static = 1.2 * mu;
                rig = rig.with_stribeck(0.05);
            }
        }
        let y0 = [0.0, theta, 0.0, w];
        let none = Request::default();
        let (Ok(a), Ok(b)) = (
            simulate(&rig, &y0, 3.0, &closed, &none),
            simulate(&rig, &y0, 3.0, &tight, &none),
        ) else {
            continue;
        };
        runs += 1;
        phases += a.stats.closed_form;
        let kinds = |s: &appell::sim::Solution<f64>| -> Vec<EventKind> {
            s.events.iter().map(|e| e.kind).collect()
        };
        assert_eq!(kinds(&a), kinds(&b), "case {case}: mu {mu}, y0 {y0:?}");
        for (x, y) in a.events.iter().zip(&b.events) {
            assert!((x.t - y.t).abs() < 1e-9, "case {case}: {} vs {}", x.t, y.t);
        }
    }
    assert!(
        runs > 300 && phases > runs,
        "{runs} runs, {phases} closed-form phases"
    );
}
