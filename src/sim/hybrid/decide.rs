//! Deciding the next mode: the transition rules of docs/physics.md applied at a located guard
//! crossing (or at the start), the impulsive stop that ends an impossible slide, and the
//! event recorded for the decision.

use super::guards::Guard;
use super::locate::Located;
use super::{Run, Segment};
use crate::model::{
    choose_at_rest, re_state, sign, Direction, Mode, RestChoice, Rig, Scalar, Shorthands, State,
    THETA, THETA_DOT, X_DOT,
};
use crate::sim::rk::Stepper;
use crate::sim::{Event, EventKind, Impulse, Outcome, RestRule, SimError, Solution};
use std::ops::ControlFlow;

/// How the state changes at an event.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Reset {
    /// Continuous state.
    None,
    /// x' is set to exactly zero (it crossed zero at the event).
    ZeroVelocity,
    /// An impulsive stop: x' -> 0 and theta' jumps (docs/physics.md, tangential impact).
    Impulsive,
}

/// The decision taken at a located guard crossing.
pub(super) struct Switch {
    pub(super) outcome: Outcome,
    pub(super) kind: EventKind,
    pub(super) sigma: f64,
    pub(super) reset: Reset,
    pub(super) alternatives: Vec<Mode>,
}

impl Switch {
    pub(super) fn new(outcome: Outcome, kind: EventKind, sigma: f64) -> Self {
        Switch {
            outcome,
            kind,
            sigma,
            reset: Reset::None,
            alternatives: Vec::new(),
        }
    }
}

/// The impulsive stop of docs/physics.md (tangential impact at the bilateral contact): x' -> 0,
/// theta' jumps by sin(theta) (0 - x') / l. Returns the new state and, in real parts, the
/// normal impulse a dx', the friction impulse D dx' and the energy lost D x'^2 / 2.
pub fn impulsive_stop<T: Scalar>(rig: &Rig<T>, y: &[T]) -> (State<T>, Impulse) {
    let dx = -y[X_DOT];
    let mut after = [y[0], y[1], y[2], y[3]];
    after[X_DOT] = T::from(0.0);
    after[THETA_DOT] = y[THETA_DOT] + y[THETA].sine() * dx / rig.rod_length;
    let sh = Shorthands::at(&rig.re(), &re_state(y));
    let dx = dx.re();
    let impulse = Impulse {
        x_dot_before: -dx,
        normal: sh.a * dx,
        friction: sh.d * dx,
        energy_lost: 0.5 * sh.d * dx * dx,
    };
    (after, impulse)
}

/// Relative size below which Q and the band margin count as zero together (a dynamic jam).
const JAM_TOL: f64 = 1e-7;

/// A slide whose denominator is below this fraction of m1 + m2 when it stops by itself is
/// reported as a sudden stop (|N| is then over a thousand times its scale (m1 + m2) g).
const SUDDEN_FRACTION: f64 = 1e-3;

/// Whether numerator Q and the band margin D - mu |a| vanish together: the singular point
/// where the sliding equation is 0/0 and the future is not unique.
fn is_jam(rig: &Rig<f64>, y: &State<f64>) -> bool {
    let sh = Shorthands::at(rig, y);
    let m = rig.slider_mass + rig.bob_mass;
    let mu = rig.friction_mu(sign(y[X_DOT]), y[X_DOT].abs());
    sh.band_margin(mu).abs() <= JAM_TOL * m
        && sh.q.abs() <= JAM_TOL * rig.slider_mass * m * rig.gravity
}

/// The branch sigma for a slide in `dir` from `y`. From rest it must accelerate in its own
/// direction (positive denominator preferred); while moving it is the consistent branch with
/// positive denominator. `None`: the sliding equation has no solution here.
fn slide_branch(rig: &Rig<f64>, y: &State<f64>, dir: Direction) -> Option<f64> {
    let sh = Shorthands::at(rig, y);
    let s = dir.sign();
    if y[X_DOT] == 0.0 {
        let b = rig.slide_branches(&sh, s, 0.0);
        let cands = [(b.plus, 1.0), (b.minus, -1.0)];
        let accelerating = |want_positive: bool| {
            cands.iter().find_map(|&(ok, sigma)| {
                let d = rig.slide(&sh, s, sigma, 0.0);
                (ok && s * d.x_ddot > 0.0 && (!want_positive || d.delta > 0.0)).then_some(sigma)
            })
        };
        if let Some(sigma) = accelerating(true).or_else(|| accelerating(false)) {
            return Some(sigma);
        }
    }
    rig.slide_sigma(&sh, s, y[X_DOT])
}

/// Mode and branch for a slide in `dir` starting at `y`; a moving state with no solution is
/// resolved by an impulsive stop (or ends in a dynamic jam).
pub(super) fn start_slide(
    rig: &Rig<f64>,
    y: &State<f64>,
    dir: Direction,
    kind: EventKind,
    rule: RestRule,
) -> Switch {
    if y[X_DOT] != 0.0 && is_jam(rig, y) {
        return Switch::new(
            Outcome::Indeterminate(Vec::new()),
            EventKind::DynamicJam,
            1.0,
        );
    }
    match slide_branch(rig, y, dir) {
        Some(sigma) => Switch::new(Outcome::Mode(Mode::Slide(dir)), kind, sigma),
        None if y[X_DOT] == 0.0 => Switch::new(Outcome::Inconsistent, EventKind::Paradox, 1.0),
        None => stop_impulsively(rig, y, EventKind::ImpulsiveStop, rule),
    }
}

/// End a slide by an impulsive stop and choose what follows from rest; a dynamic jam ends
/// the run instead.
fn stop_impulsively(rig: &Rig<f64>, y: &State<f64>, kind: EventKind, rule: RestRule) -> Switch {
    if is_jam(rig, y) {
        return Switch::new(
            Outcome::Indeterminate(Vec::new()),
            EventKind::DynamicJam,
            1.0,
        );
    }
    let (after, _) = impulsive_stop(rig, y);
    let c_dir = Direction::of(Shorthands::at(rig, &after).c);
    // A slide has just failed here: preferring one again would repeat the stop in ever
    // shorter slides (a Zeno sequence), so the stick is taken when admissible.
    let rule = match rule {
        RestRule::PreferSlide => RestRule::PreferStick,
        other => other,
    };
    let mut switch = from_rest(rig, &after, rule, c_dir, |_| kind, EventKind::Stick);
    // The stop names the event; an indeterminate choice after it shows in the alternatives.
    switch.kind = kind;
    switch.reset = Reset::Impulsive;
    switch
}

/// The motion from a state at rest: the unique consistent one, or the [`RestRule`]'s choice
/// among several (an `indeterminate` event). `slide_kind` names a unique slide by its
/// direction; `stick_kind` names a unique stick.
pub(super) fn from_rest(
    rig: &Rig<f64>,
    y: &State<f64>,
    rule: RestRule,
    c_dir: Direction,
    slide_kind: impl Fn(Direction) -> EventKind,
    stick_kind: EventKind,
) -> Switch {
    match choose_at_rest(rig, y) {
        RestChoice::Unique(Mode::Stick) => Switch::new(Outcome::Mode(Mode::Stick), stick_kind, 1.0),
        RestChoice::Unique(Mode::Slide(dir)) => start_slide(rig, y, dir, slide_kind(dir), rule),
        RestChoice::Indeterminate { alternatives } => {
            let mut switch = match rule.choose(&alternatives, c_dir) {
                Some(Mode::Stick) => {
                    Switch::new(Outcome::Mode(Mode::Stick), EventKind::Indeterminate, 1.0)
                }
                Some(Mode::Slide(dir)) => start_slide(rig, y, dir, EventKind::Indeterminate, rule),
                None => Switch::new(
                    Outcome::Indeterminate(alternatives.clone()),
                    EventKind::Paradox,
                    1.0,
                ),
            };
            switch.alternatives = alternatives;
            switch
        }
        RestChoice::Inconsistent => Switch::new(Outcome::Inconsistent, EventKind::Paradox, 1.0),
    }
}

/// Apply the transition rules of docs/physics.md at a located crossing of `guard`.
pub(super) fn decide(
    rig: &Rig<f64>,
    rule: RestRule,
    guard: Guard,
    mode: Mode,
    sigma: f64,
    y: &State<f64>,
    c_hint: f64,
) -> Switch {
    let dir_of_c = |c: f64| Direction::of(if c != 0.0 { c } else { c_hint });
    let sh = Shorthands::at(rig, y);
    match guard {
        Guard::StickMargin => {
            let mut switch = from_rest(
                rig,
                y,
                rule,
                dir_of_c(sh.c),
                |_| EventKind::Slip,
                EventKind::Stick,
            );
            // The root lies on the violated side, so a stick verdict only means the margin
            // is zero to rounding: the slider leaves the way friction-free motion goes.
            // The same holds when stick is one of several alternatives: choose among the slides.
            if switch.outcome == Outcome::Mode(Mode::Stick) {
                let slides: Vec<Mode> = switch
                    .alternatives
                    .iter()
                    .copied()
                    .filter(|m| *m != Mode::Stick)
                    .collect();
                let dir = match RestRule::PreferSlide.choose(&slides, dir_of_c(sh.c)) {
                    Some(Mode::Slide(dir)) => dir,
                    _ => dir_of_c(sh.c),
                };
                let kind = if slides.len() > 1 {
                    EventKind::Indeterminate
                } else {
                    EventKind::Slip
                };
                switch = start_slide(rig, y, dir, kind, rule);
                if slides.len() > 1 {
                    switch.alternatives = slides;
                }
            }
            switch
        }
        Guard::Stop => {
            let Mode::Slide(old) = mode else {
                unreachable!("stop guard only watches slides")
            };
            let mut switch = from_rest(
                rig,
                y,
                rule,
                dir_of_c(sh.c),
                |dir| {
                    if dir == old {
                        EventKind::Continuation
                    } else {
                        EventKind::Reversal
                    }
                },
                EventKind::Stick,
            );
            let delta = rig.slide(&sh, old.sign(), sigma, y[X_DOT]).delta;
            let m = rig.slider_mass + rig.bob_mass;
            if delta.abs() < SUDDEN_FRACTION * m && switch.kind != EventKind::Paradox {
                switch.kind = EventKind::SuddenStop;
            }
            switch.reset = Reset::ZeroVelocity;
            switch
        }
        Guard::NormalSign => {
            let Mode::Slide(dir) = mode else {
                unreachable!("slide guards only watch slides")
            };
            let branches = rig.slide_branches(&sh, dir.sign(), y[X_DOT]);
            let new_sigma = -sigma;
            let ok = if new_sigma > 0.0 {
                branches.plus
            } else {
                branches.minus
            };
            // Q passes through zero: N changes sign on the branch that stays well defined
            // (positive denominator). At Q = 0 to rounding both branches count as consistent,
            // and staying on the old one would fire the guard again at once.
            let positive = rig.slide(&sh, dir.sign(), new_sigma, y[X_DOT]).delta > 0.0;
            if ok && (branches.count() == 1 || positive) && !is_jam(rig, y) {
                Switch::new(Outcome::Mode(mode), EventKind::NormalFlip, new_sigma)
            } else {
                stop_impulsively(rig, y, EventKind::ImpulsiveStop, rule)
            }
        }
        Guard::Denominator => stop_impulsively(rig, y, EventKind::SuddenStop, rule),
    }
}

/// The motion at the start of a run from `y`, by the same rules as at any other instant: the
/// mode `y` is in (stick at rest, else a slide in the direction of x'), and the decision there.
pub(super) fn start(rig: &Rig<f64>, y: &State<f64>, rule: RestRule) -> (Mode, Switch) {
    let initial_mode = if y[X_DOT] == 0.0 {
        Mode::Stick
    } else {
        Mode::Slide(Direction::of(y[X_DOT]))
    };
    let start = match initial_mode {
        Mode::Stick => {
            let c_dir = Direction::of(Shorthands::at(rig, y).c);
            from_rest(rig, y, rule, c_dir, |_| EventKind::Slip, EventKind::Stick)
        }
        Mode::Slide(dir) => start_slide(rig, y, dir, EventKind::Slip, rule),
    };
    (initial_mode, start)
}

/// What a located crossing leads to, and what its event reports.
pub(super) struct Decision {
    pub(super) switch: Switch,
    /// The state at the event after its reset (x' zeroed at a stop, theta' jumped by an
    /// impulsive stop).
    pub(super) state: State<f64>,
    /// The impulsive stop applied, if any.
    pub(super) impulse: Option<Impulse>,
    /// |N| just before a sudden stop.
    pub(super) peak_normal: Option<f64>,
}

/// The decision at a crossing of `guard` located at `y` while in `mode` on branch `sigma`.
/// `c_hint`: c at the step's end, the direction to take where c is zero at the event;
/// `at_mode_start`: the crossing is at the instant the mode began.
pub(super) fn decide_at_crossing(
    rig: &Rig<f64>,
    rule: RestRule,
    guard: Guard,
    (mode, sigma): (Mode, f64),
    y: &State<f64>,
    c_hint: f64,
    at_mode_start: bool,
) -> Decision {
    let mut at_event = *y;
    if guard == Guard::Stop {
        at_event[X_DOT] = 0.0;
    }
    // A slide that stopped the instant it began falls back to the maximal-dissipation
    // choice: choosing it again would repeat the event forever.
    let rule_here = if at_mode_start && guard == Guard::Stop {
        RestRule::PreferStick
    } else {
        rule
    };
    let switch = decide(rig, rule_here, guard, mode, sigma, &at_event, c_hint);
    let impulse = (switch.reset == Reset::Impulsive).then(|| {
        let (after, impulse) = impulsive_stop(rig, y);
        at_event = after;
        impulse
    });
    let peak_normal = (switch.kind == EventKind::SuddenStop).then(|| {
        let Mode::Slide(dir) = mode else {
            return f64::NAN;
        };
        let sh = Shorthands::at(rig, y);
        rig.slide(&sh, dir.sign(), sigma, y[X_DOT]).normal.abs()
    });
    Decision {
        switch,
        state: at_event,
        impulse,
        peak_normal,
    }
}

impl<T: Scalar + 'static, const N: usize> Run<'_, '_, T, N> {
    /// Switch mode at a located event: decide what follows, record the event and carry the
    /// state across it. `y_after` is a state just past the event (the end of its step), whose
    /// friction-free direction sign(c) decides a slip where c vanishes at the event itself.
    /// `Break` when the run ends there.
    pub(super) fn switch_mode<M: Stepper<T, N>>(
        &mut self,
        seg: &Segment<'_, '_, T, M, N>,
        y_after: &[f64],
        event: Located<T, N>,
    ) -> Result<ControlFlow<Solution<T>>, SimError> {
        let (mode, sigma) = (self.mode, self.sigma);
        let rig_re = &self.ctx.rig_re;
        let c_hint = Shorthands::at(rig_re, &y_after[..4]).c;
        let Decision {
            switch,
            state,
            impulse,
            peak_normal,
        } = decide_at_crossing(
            rig_re,
            self.options.rest_rule,
            event.guard,
            (mode, sigma),
            &re_state(&event.y),
            c_hint,
            event.t == seg.t_start,
        );
        self.out.stats.events += 1;
        self.out.events.push(Event {
            t: event.t,
            from: mode,
            to: switch.outcome.clone(),
            kind: switch.kind,
            state,
            alternatives: switch.alternatives,
            impulse,
            peak_normal,
        });
        self.out.stats.rhs_evals += seg.stepper.rhs_evals();
        let Outcome::Mode(new_mode) = switch.outcome else {
            return Ok(ControlFlow::Break(self.out.finish(event.t, &event.y, mode)));
        };
        if self.out.stats.events >= self.options.max_events {
            return Err(SimError::TooManyEvents {
                t: event.t,
                max: self.options.max_events,
                state,
            });
        }
        self.y = self.carry_across(&event, (new_mode, switch.sigma), switch.reset);
        self.t = event.t;
        self.mode = new_mode;
        self.sigma = switch.sigma;
        Ok(ControlFlow::Continue(()))
    }
}
