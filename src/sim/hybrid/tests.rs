//! Unit tests of the loop's steps, each against an oracle of its own: closed forms of
//! docs/physics.md (the slip angle of a released pendulum, the normal force's sign change, the
//! paradox band's edge, the impulsive stop), the jump condition of forward sensitivities
//! written out, and synthetic guard curves whose roots are known.

use super::decide::{self, decide_at_crossing, Decision, Reset};
use super::guards::{Ctx, Guard, GuardState, Interior, Watch};
use super::jump::jump_with_sensitivity;
use super::locate::{find_root, golden_min};
use super::samples::Output;
use super::step::{pi_factor, shrink_factor};
use crate::model::{Direction, Mode, Rig, Shorthands, State, X_DOT};
use crate::sim::{simulate, EventKind, Options, Outcome, Request, RestRule, Sample};
use num_dual::Dual64;
use std::f64::consts::{FRAC_PI_2, PI};

/// A guard curve with a known shape, standing in for the dense output of a step.
struct Curve<F> {
    g: F,
    prepared: bool,
}

impl<F: Fn(f64) -> f64> Curve<F> {
    fn new(g: F) -> Self {
        Curve { g, prepared: false }
    }
}

impl<F: Fn(f64) -> f64> Interior for Curve<F> {
    fn prepare(&mut self) {
        self.prepared = true;
    }

    fn at(&self, th: f64) -> f64 {
        assert!(self.prepared, "looked inside the step before preparing it");
        (self.g)(th)
    }
}

/// The state of a guard at the start of a step that follows `curve` (g(0) and g'(0) by a
/// central difference), armed as given.
fn start_of(curve: &impl Fn(f64) -> f64, armed: bool) -> GuardState {
    let e = 1e-7;
    GuardState {
        guard: Guard::Stop,
        g: curve(0.0),
        gdot: (curve(e) - curve(-e)) / (2.0 * e),
        armed,
    }
}

/// What `watch` makes of a whole step along `curve`, whether it looked inside the step, and
/// the root it brackets (found as the loop finds it).
fn watch_and_locate(
    curve: impl Fn(f64) -> f64 + Copy,
    armed: bool,
    long: bool,
) -> (Watch, bool, f64) {
    let st = start_of(&curve, armed);
    let e = 1e-7;
    let (g1, gdot1) = (curve(1.0), (curve(1.0 + e) - curve(1.0 - e)) / (2.0 * e));
    let looked = std::cell::Cell::new(false);
    let watch = st.watch(g1, gdot1, long, || {
        looked.set(true);
        Curve::new(curve)
    });
    let root = match watch {
        Watch::Bracket { a, ga, b, gb } => {
            let mut inside = Curve::new(curve);
            inside.prepare();
            find_root(a, ga, b, gb, 1e-14, |th| inside.at(th))
        }
        _ => f64::NAN,
    };
    (watch, looked.get(), root)
}

// --- locating: the root finder and the dip search -----------------------------------------

#[test]
fn root_finder_lands_on_the_closed_form_root_on_the_violated_side() {
    // exp(-3 th) = 0.4 at th = ln(2.5) / 3.
    let g = |th: f64| (-3.0 * th).exp() - 0.4;
    let root = 2.5f64.ln() / 3.0;
    let th = find_root(0.0, g(0.0), 1.0, g(1.0), 1e-14, g);
    assert!((th - root).abs() <= 1e-14, "{th} vs {root}");
    assert!(g(th) <= 0.0, "the root is reported on the violated side");
}

#[test]
fn root_finder_converges_fast_on_a_lopsided_guard() {
    // Plain regula falsi keeps one end fixed on a convex curve and creeps; the Illinois
    // halving must reach 1e-14 in a few dozen evaluations.
    let calls = std::cell::Cell::new(0);
    let g = |th: f64| {
        calls.set(calls.get() + 1);
        0.5 - th.powi(12)
    };
    let root = 0.5f64.powf(1.0 / 12.0);
    let th = find_root(0.0, 0.5, 1.0, -0.5, 1e-14, g);
    assert!((th - root).abs() <= 1e-14, "{th} vs {root}");
    assert!(calls.get() < 40, "{} evaluations", calls.get());
}

#[test]
fn golden_section_finds_a_dip_and_stops_once_it_is_below_zero() {
    let (th, g) = golden_min(0.0, 1.0, 1e-10, |th| (th - 0.3).powi(2) + 0.01);
    assert!(
        (th - 0.3).abs() < 1e-7 && (g - 0.01).abs() < 1e-14,
        "{th} {g}"
    );
    // A dip below zero: any point there will do (the crossing is bracketed from it).
    let (th, g) = golden_min(0.0, 1.0, 1e-10, |th| (th - 0.3).powi(2) - 0.01);
    assert!(g <= 0.0 && (th - 0.3).abs() <= 0.1, "{th} {g}");
}

// --- checking the guards over a step -----------------------------------------------------

#[test]
fn an_armed_guard_negative_at_the_end_brackets_the_step_without_looking_inside() {
    let st = GuardState {
        guard: Guard::Stop,
        g: 0.7,
        gdot: -1.0,
        armed: true,
    };
    // The dense output costs evaluations: the ends decide here.
    let watch = st.watch(-0.2, -1.0, true, || -> Curve<fn(f64) -> f64> {
        panic!("no need to look inside")
    });
    assert_eq!(
        watch,
        Watch::Bracket {
            a: 0.0,
            ga: 0.7,
            b: 1.0,
            gb: -0.2
        }
    );
}

#[test]
fn a_guard_positive_at_both_ends_and_not_grazing_holds_without_looking_inside() {
    // Rising at both ends (a falling start would be a graze).
    let (watch, looked, _) = watch_and_locate(|th| 0.1 + th * th, true, true);
    assert_eq!((watch, looked), (Watch::Holds, false));
}

#[test]
fn a_grazing_dip_between_the_samples_is_found_and_its_first_root_located() {
    // Below zero only on (0.52, 0.54): no sample at k/16 lands there (0.5 and 0.5625 are
    // positive); golden section must find the dip and the root finder its first crossing.
    let (watch, _, root) = watch_and_locate(|th| (th - 0.53).powi(2) - 1e-4, true, true);
    assert!(matches!(watch, Watch::Bracket { .. }), "{watch:?}");
    assert!((root - 0.52).abs() < 1e-12, "{root}");
}

#[test]
fn a_grazing_guard_that_stays_positive_holds() {
    let (watch, looked, _) = watch_and_locate(|th| (th - 0.53).powi(2) + 1e-6, true, true);
    assert_eq!((watch, looked), (Watch::Holds, true));
}

#[test]
fn a_guard_starting_at_zero_fires_only_after_it_has_risen() {
    // x' at the start of a slide: zero, up, then down through zero at th = 0.7.
    let (watch, _, root) = watch_and_locate(|th| th * (0.7 - th), false, true);
    assert!(matches!(watch, Watch::Bracket { .. }), "{watch:?}");
    assert!((root - 0.7).abs() < 1e-12, "{root}");
    // Rising and staying up: the mode holds.
    let (watch, _, _) = watch_and_locate(|th| th * (1.5 - th), false, true);
    assert_eq!(watch, Watch::Holds);
}

#[test]
fn a_guard_never_positive_is_retried_shorter_or_left_at_once() {
    let (watch, _, _) = watch_and_locate(|th| -th, false, true);
    assert_eq!(watch, Watch::TooLong);
    let (watch, _, _) = watch_and_locate(|th| -th, false, false);
    assert_eq!(watch, Watch::AtOnce);
}

// --- the guards' physics -----------------------------------------------------------------

/// The guard `guard` of a plain f64 rig at state `y`.
fn guard_value(rig: &Rig<f64>, guard: Guard, y: &State<f64>, mode: Mode, sigma: f64) -> f64 {
    let k = rig.constants();
    guard.value((rig, &k), y, (mode, sigma), 1e-9, rig.is_plain())
}

/// The slip angle of the paper's rig released from rest with the rod horizontal: with
/// w^2 = 2 (g / l) sin(theta), |c| / |b| = 3 sin cos / (1 + 3 sin^2) = 3 tan / (1 + 4 tan^2)
/// = mu, the smaller root of 4 mu tan^2 - 3 tan + mu = 0 (docs/physics.md: the ratio peaks at
/// 0.75, at tan = 1/2).
fn slip_angle(mu: f64) -> f64 {
    ((3.0 - (9.0 - 16.0 * mu * mu).sqrt()) / (8.0 * mu)).atan()
}

/// The stuck pendulum's state at angle `theta` after release from rest at 0.
fn released(rig: &Rig<f64>, theta: f64) -> State<f64> {
    let w = (2.0 * rig.gravity / rig.rod_length * theta.sin()).sqrt();
    [0.0, theta, 0.0, w]
}

#[test]
fn stick_margin_changes_sign_at_the_closed_form_slip_angle() {
    let rig = Rig::paper(0.5);
    let th = slip_angle(0.5);
    let g = |theta: f64| {
        guard_value(
            &rig,
            Guard::StickMargin,
            &released(&rig, theta),
            Mode::Stick,
            1.0,
        )
    };
    assert!(g(th).abs() < 1e-12, "{}", g(th));
    assert!(g(th - 1e-6) > 0.0 && g(th + 1e-6) < 0.0);
}

#[test]
fn normal_sign_guard_fires_where_the_normal_force_changes_sign() {
    // Bob straight above the rail (theta = -pi/2) spinning: Q = -m1 ((m1 + m2) g - m2 l w^2)
    // vanishes at w^2 = (m1 + m2) g / (m2 l); below it N < 0 (sigma = -1 holds).
    let rig = Rig::paper(0.3);
    let w0 =
        ((rig.slider_mass + rig.bob_mass) * rig.gravity / (rig.bob_mass * rig.rod_length)).sqrt();
    let mode = Mode::Slide(Direction::Positive);
    let g = |w: f64| {
        guard_value(
            &rig,
            Guard::NormalSign,
            &[0.0, -FRAC_PI_2, 0.1, w],
            mode,
            -1.0,
        )
    };
    assert!(g(w0 * (1.0 - 1e-6)) > 0.0 && g(w0 * (1.0 + 1e-6)) < 0.0);
    assert!(g(w0).abs() < 1e-12, "{}", g(w0));
}

#[test]
fn denominator_guard_is_minus_the_threshold_at_the_band_edge() {
    // Equal masses, mu = 3: the band's lower edge is tan(theta) = (mu - sqrt(mu^2 - 8)) / 2
    // = 1, where D = mu |a|; on the branch with s sigma a < 0 the denominator vanishes.
    let rig = Rig::paper(3.0);
    let thr = 1e-9;
    let k = rig.constants();
    let y = [0.0, PI / 4.0, 0.2, 0.0];
    let g = Guard::Denominator.value(
        (&rig, &k),
        &y,
        (Mode::Slide(Direction::Positive), -1.0),
        thr,
        true,
    );
    let want = -(rig.slider_mass + rig.bob_mass) * thr;
    assert!((g - want).abs() < 1e-15, "{g} vs {want}");
}

// --- deciding the next mode --------------------------------------------------------------

/// The decision at a crossing of `guard` at `y`, in the middle of a mode, under the default
/// rest rule.
fn decide_here(rig: &Rig<f64>, guard: Guard, from: (Mode, f64), y: &State<f64>) -> Decision {
    decide_at_crossing(rig, RestRule::PreferStick, guard, from, y, 0.0, false)
}

#[test]
fn a_stop_inside_the_friction_cone_sticks_and_zeroes_the_velocity() {
    // Bob hanging, swinging slowly: c = m2 cos(theta) (g sin(theta) + l w^2) is near zero,
    // far inside mu_s |b|.
    let rig = Rig::paper(0.3);
    let y = [0.1, FRAC_PI_2 - 0.05, -1e-12, 0.2];
    let d = decide_here(
        &rig,
        Guard::Stop,
        (Mode::Slide(Direction::Positive), -1.0),
        &y,
    );
    assert_eq!(d.switch.outcome, Outcome::Mode(Mode::Stick));
    assert_eq!(d.switch.kind, EventKind::Stick);
    assert_eq!(d.switch.reset, Reset::ZeroVelocity);
    assert_eq!(d.state[X_DOT], 0.0);
    assert!(d.impulse.is_none());
}

#[test]
fn a_stop_outside_the_cone_slides_on_in_the_direction_of_c() {
    // Rod 0.3 rad below horizontal at rest: |c| / |b| = sin cos / (1 + sin^2) = 0.26 > 0.1,
    // c > 0; in the mirror (pi - theta) c < 0.
    let rig = Rig::paper(0.1);
    for (theta, dir) in [(0.3, Direction::Positive), (PI - 0.3, Direction::Negative)] {
        let y = [0.0, theta, 0.0, 0.0];
        for (from, kind) in [
            (dir, EventKind::Continuation),
            (dir.flipped(), EventKind::Reversal),
        ] {
            let sigma = Shorthands::at(&rig, &y).q.signum();
            let d = decide_here(&rig, Guard::Stop, (Mode::Slide(from), sigma), &y);
            assert_eq!(d.switch.outcome, Outcome::Mode(Mode::Slide(dir)), "{theta}");
            assert_eq!(d.switch.kind, kind, "{theta} from {from:?}");
        }
    }
}

#[test]
fn the_stick_margin_crossing_slips_the_way_c_points() {
    let rig = Rig::paper(0.5);
    let th = slip_angle(0.5) + 1e-9;
    let d = decide_here(
        &rig,
        Guard::StickMargin,
        (Mode::Stick, 1.0),
        &released(&rig, th),
    );
    assert_eq!(
        d.switch.outcome,
        Outcome::Mode(Mode::Slide(Direction::Positive))
    );
    assert_eq!(d.switch.kind, EventKind::Slip);
    assert_eq!(d.switch.reset, Reset::None);
}

#[test]
fn a_sudden_stop_is_an_impulsive_stop_with_the_closed_form_jump() {
    // docs/physics.md, tangential impact: w+ = w- - sin(theta) x'- / l, energy lost D x'^2 / 2.
    let rig = Rig::paper(3.0);
    let y = [0.0, 0.8, 0.05, -0.4];
    let d = decide_here(
        &rig,
        Guard::Denominator,
        (Mode::Slide(Direction::Positive), -1.0),
        &y,
    );
    assert_eq!(d.switch.kind, EventKind::SuddenStop);
    assert_eq!(d.switch.reset, Reset::Impulsive);
    let w_after = -0.4 - 0.8f64.sin() * 0.05 / rig.rod_length;
    assert_eq!(d.state[X_DOT], 0.0);
    assert!((d.state[3] - w_after).abs() < 1e-15);
    let dd = rig.slider_mass + rig.bob_mass * 0.8f64.cos().powi(2);
    let lost = d.impulse.expect("an impulse").energy_lost;
    assert!((lost - 0.5 * dd * 0.05 * 0.05).abs() < 1e-15, "{lost}");
    assert!(d.peak_normal.is_some_and(|n| n.is_finite() && n > 0.0));
}

#[test]
fn the_start_from_rest_sticks_inside_the_cone_and_slips_outside() {
    // Rod 0.5 rad below horizontal at rest: |c| / |b| = sin cos / (1 + sin^2) = 0.342.
    let y = [0.0, 0.5, 0.0, 0.0];
    let (mode, switch) = decide::start(&Rig::paper(0.5), &y, RestRule::PreferStick);
    assert_eq!(mode, Mode::Stick);
    assert_eq!(
        (switch.outcome, switch.kind),
        (Outcome::Mode(Mode::Stick), EventKind::Stick)
    );
    let (_, switch) = decide::start(&Rig::paper(0.3), &y, RestRule::PreferStick);
    assert_eq!(
        (switch.outcome, switch.kind),
        (
            Outcome::Mode(Mode::Slide(Direction::Positive)),
            EventKind::Slip
        )
    );
}

// --- crossing the event ------------------------------------------------------------------

#[test]
fn the_sensitivity_jump_at_a_stop_into_stick_follows_the_jump_condition() {
    // At a stop (guard x'), dt*/dp = -(dx'/dp) / x''_old, and every sensitivity jumps by
    // (f_old - f_new) dt*/dp; the new x' is exactly zero with no sensitivity (stuck).
    let rig = Rig::paper(0.3);
    let (theta, w) = (1.0, -2.0);
    let sh = Shorthands::at(&rig, &[0.0, theta, 0.0, w]);
    let sigma = rig.slide_sigma(&sh, 1.0, 0.0).expect("a consistent slide");
    let old = rig.slide(&sh, 1.0, sigma, 0.0);
    assert!(old.x_ddot.abs() > 1e-3, "the stop must be transversal");
    let new_theta_ddot = rig.stick_angular_acceleration(theta, w);
    let (dx, dtheta, dxd, dw) = (0.2, 0.1, 0.3, 0.05);
    let y_star = [
        Dual64::new(0.01, dx),
        Dual64::new(theta, dtheta),
        Dual64::new(0.0, dxd),
        Dual64::new(w, dw),
    ];
    let rig_dual: Rig<Dual64> = rig.lift();
    let ctx = Ctx::new(&rig_dual, &Options::default());
    let after = jump_with_sensitivity(
        &ctx,
        Guard::Stop,
        (Mode::Slide(Direction::Positive), sigma),
        (Mode::Stick, 1.0),
        Reset::ZeroVelocity,
        &y_star,
    );
    let dt = -dxd / old.x_ddot;
    let want = [
        (0.01, dx),
        (theta, dtheta),
        (0.0, 0.0),
        (w, dw + (old.theta_ddot - new_theta_ddot) * dt),
    ];
    for (i, (got, (re, eps))) in after.iter().zip(want).enumerate() {
        assert!(
            (got.re - re).abs() < 1e-15,
            "component {i}: {} vs {re}",
            got.re
        );
        assert!(
            (got.eps - eps).abs() < 1e-12,
            "component {i}: {} vs {eps}",
            got.eps
        );
    }
}

// --- taking a step -----------------------------------------------------------------------

#[test]
fn a_rejected_step_shrinks_enough_to_pass_under_the_error_model() {
    // Local error ~ h^(q+1): after shrinking by f the error is err f^(q+1), which must fall
    // below 1 (with the 0.9 safety) unless the 1/5 floor binds.
    for order in [4, 7] {
        let e = -1.0 / f64::from(order + 1);
        for err in [1.01, 3.0, 50.0] {
            let f = shrink_factor(err, e);
            assert!(
                f < 1.0 && err * f.powi(order + 1) < 1.0,
                "{order} {err} {f}"
            );
        }
        let f = shrink_factor(1e12, e);
        assert!((f - 0.2).abs() < 1e-15, "the floor: {f}");
        assert!(shrink_factor(f64::NAN, e) < 1.0 && shrink_factor(f64::INFINITY, e) < 1.0);
    }
}

#[test]
fn the_next_step_aims_just_under_the_tolerance() {
    // Under err ~ h^(q+1) the next step's error is err f^(q+1): the control must aim below
    // 1 (accepted) but not far below (wasted steps), whatever the error it starts from,
    // shrinking the step after large errors and growing it after small ones.
    let (q1, prev) = (8, 0.5f64.ln());
    let e = -1.0 / f64::from(q1);
    let mut last = f64::INFINITY;
    for err in [1e-6, 1e-3, 0.1, 0.99] {
        let (f, ln_err) = pi_factor(err, prev, e);
        let next = err * f.powi(q1);
        assert!(
            next > 0.1 && next < 1.0,
            "err {err}: factor {f}, next error {next}"
        );
        assert!(f < last, "a larger error must not grow the step more");
        assert!((ln_err - err.ln()).abs() < 1e-15);
        last = f;
    }
    assert!(last < 1.0 && pi_factor(1e-6, prev, e).0 > 1.0);
    // No error at all must not blow the step up without bound.
    assert!(pi_factor(0.0, prev, e).0 <= 6.0);
}

#[test]
fn the_last_step_lands_exactly_on_the_end_time() {
    let rig = Rig::paper(0.5);
    let t_end = 0.1 + 0.2; // not a float sum that a sequence of steps would hit by itself
    let request = Request {
        sample_times: vec![t_end],
        ..Request::default()
    };
    let sol = simulate(&rig, &[0.0; 4], t_end, &Options::default(), &request).unwrap();
    assert_eq!(sol.final_time.to_bits(), t_end.to_bits());
    assert_eq!(sol.samples.len(), 1);
    assert_eq!(sol.samples[0].t.to_bits(), t_end.to_bits());
}

// --- the whole loop against a closed form, and the samples around an event ----------------

#[test]
fn the_slip_is_located_at_the_closed_form_angle() {
    for mu in [0.3, 0.5, 0.7] {
        let rig = Rig::paper(mu);
        let sol = simulate(
            &rig,
            &[0.0; 4],
            0.5,
            &Options::default(),
            &Request::default(),
        )
        .unwrap();
        let slip = &sol.events[0];
        assert_eq!((slip.kind, slip.from), (EventKind::Slip, Mode::Stick));
        let want = slip_angle(mu);
        assert!(
            (slip.state[1] - want).abs() < 1e-9,
            "mu {mu}: {} vs {want}",
            slip.state[1]
        );
    }
}

#[test]
fn samples_are_emitted_once_each_in_time_order_across_events() {
    let times = [-0.1, 0.0, 0.05, 0.1, 0.25, 0.3, 0.4, 0.5];
    let mut got: Vec<(f64, Mode)> = Vec::new();
    let mut sink = |s: Sample<f64>| {
        assert_eq!(s.state[0], s.t, "sampled at its own time");
        got.push((s.t, s.mode));
    };
    let mut out = Output::new(&mut sink);
    let at = |ts: f64| [ts, 0.0, 0.0, 0.0];
    let slide = Mode::Slide(Direction::Positive);
    out.emit(&times, 0.0, 0.0, Mode::Stick, at); // the start
    out.emit(&times, 0.0, 0.1, Mode::Stick, at); // a step ending on a sample time
    out.emit(&times, 0.1, 0.25, Mode::Stick, at); // up to an event at 0.25
    out.emit(&times, 0.25, 0.4, slide, at); // the next mode, from the event
    drop(out);
    let stick = Mode::Stick;
    assert_eq!(
        got,
        [
            (0.0, stick),
            (0.05, stick),
            (0.1, stick),
            (0.25, stick),
            (0.3, slide),
            (0.4, slide)
        ]
    );
}

#[test]
fn a_sample_at_an_event_time_is_emitted_once_in_the_mode_before_it() {
    let rig = Rig::paper(0.5);
    // Without samples the stick phases would be taken in closed form (events within the
    // tolerance of the integrator's, not bit for bit): the integrator runs both here.
    let opts = Options {
        prove_stick: false,
        ..Options::default()
    };
    let t_end = 0.6;
    let first = simulate(&rig, &[0.0; 4], t_end, &opts, &Request::default()).unwrap();
    let slip = &first.events[0];
    let times = vec![slip.t / 2.0, slip.t, slip.t, (slip.t + t_end) / 2.0];
    let request = Request {
        sample_times: times.clone(),
        ..Request::default()
    };
    let sol = simulate(&rig, &[0.0; 4], t_end, &opts, &request).unwrap();
    assert_eq!(sol.events, first.events, "sampling does not change the run");
    let t: Vec<f64> = sol.samples.iter().map(|s| s.t).collect();
    assert_eq!(t, times, "each requested time once, repeats included");
    let at_slip = &sol.samples[1];
    assert_eq!(at_slip.mode, Mode::Stick);
    assert!((at_slip.state[1] - slip.state[1]).abs() < 1e-12);
    // After the slip, the mode the events say.
    let later = sol.samples[3].t;
    let mode_then = first
        .events
        .iter()
        .take_while(|e| e.t < later)
        .last()
        .map(|e| e.to.clone());
    assert_eq!(mode_then, Some(Outcome::Mode(sol.samples[3].mode)));
}

// --- numerics that fail: errors with the time and state, never a hang ------------------------

/// A state whose rate overflows (theta'^2 beyond f64) gives no finite step at any size: the
/// run ends in `NonFinite` with the time and state, after the halving steps (each a quarter)
/// reach what f64 time resolves, not at the step limit.
#[test]
fn an_overflowing_rate_is_a_non_finite_error_not_a_step_limit() {
    use crate::sim::SimError;
    let rig = Rig::paper(0.3);
    let y0 = [0.0, 1.0, 1e155, 1e155];
    let opts = Options::default();
    match simulate(&rig, &y0, 1.0, &opts, &Request::default()) {
        Err(SimError::NonFinite { t, state }) => {
            assert_eq!(t, 0.0);
            assert_eq!(state, y0);
        }
        other => panic!("expected NonFinite, got {other:?}"),
    }
}
