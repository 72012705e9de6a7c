//! Simulation: a scene's rig and initial state is the problem, a Runge-Kutta method the
//! algorithm, and a run returns a [`Solution`] with its events, samples and statistics.

mod hybrid;
pub mod rk;
pub mod tableau;

pub use hybrid::{impulsive_stop, simulate, simulate_each};

use crate::model::{Direction, Mode, State};
use serde::Serialize;
use std::fmt;
use std::sync::atomic::{AtomicBool, Ordering};
use thiserror::Error;

/// The integration method of a run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Deserialize, Serialize)]
pub enum Method {
    /// Dormand-Prince 5(4) with 4th-order dense output.
    #[serde(rename = "dp5")]
    Dp5,
    /// DOP853, 8th order with 7th-order dense output (the default: cheapest at tight tolerances).
    #[default]
    #[serde(rename = "dop853")]
    Dop853,
}

impl Method {
    /// Every method, for benchmarks and convergence tests.
    pub const ALL: [Method; 2] = [Method::Dp5, Method::Dop853];

    /// The name used in scenes and reports.
    pub fn name(self) -> &'static str {
        match self {
            Method::Dp5 => "dp5",
            Method::Dop853 => "dop853",
        }
    }
}

/// How accurately and how far a run may go.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Options {
    /// Relative tolerance of the local error.
    pub rtol: f64,
    /// Absolute tolerance of the local error.
    pub atol: f64,
    /// Integration method.
    pub method: Method,
    /// Most steps (accepted and rejected) before the run fails.
    pub max_steps: usize,
    /// Most events before the run fails (guards against stick-slip chattering).
    pub max_events: usize,
    /// Which motion to take at rest where several are consistent (only above mu*).
    pub rest_rule: RestRule,
    /// Sudden-stop threshold: a slide whose denominator |D + mu s sigma a| falls below this
    /// fraction of m1 + m2 is ended by an impulsive stop (the convergence test
    /// `sudden_stop_converges_as_threshold_tightens` shows why 1e-9 is tight enough).
    pub stop_threshold: f64,
    /// The pendulum's closed forms for stick phases: on the ideal rig, skip slip monitoring
    /// in a stick phase whose energy level provably never reaches the friction cone
    /// (`model::regions::stick_holds_forever`); on any rig with an undamped pivot, take a
    /// stick phase of an `f64` run that samples nothing from its start on in closed form
    /// (`model::pendulum::Swing`: its slip located on the swing, its end time from an
    /// elliptic integral). Off only to measure what they save, or to test the integrator.
    pub prove_stick: bool,
    /// A flag another thread raises to stop the run between its steps (Ctrl-C in Python);
    /// the default never does.
    pub cancel: Cancel,
}

/// A request to stop runs early, raised by another thread: a run that sees it fails with
/// [`SimError::Cancelled`] at its next step, so a fit whose every run fails ends at once.
/// It holds a `'static` flag so that [`Options`] stays `Copy`: a caller keeps one flag per
/// thread that may cancel, and lowers it before each piece of work.
#[derive(Clone, Copy, Default)]
pub struct Cancel(Option<&'static AtomicBool>);

impl Cancel {
    /// Runs that stop once `flag` is raised.
    pub fn on(flag: &'static AtomicBool) -> Self {
        Cancel(Some(flag))
    }

    /// Whether the flag is raised.
    #[inline]
    pub fn is_raised(self) -> bool {
        self.0.is_some_and(|f| f.load(Ordering::Relaxed))
    }
}

impl PartialEq for Cancel {
    /// The same flag (or none): runs that stop on the same request.
    fn eq(&self, other: &Self) -> bool {
        match (self.0, other.0) {
            (Some(a), Some(b)) => std::ptr::eq(a, b),
            (a, b) => a.is_none() && b.is_none(),
        }
    }
}

impl fmt::Debug for Cancel {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(if self.0.is_some() {
            "Cancel(flag)"
        } else {
            "Cancel(never)"
        })
    }
}

/// The rule that picks one motion at rest when the Painleve paradox leaves several consistent
/// ones (stick and one or two slides). The choice is recorded in an `indeterminate` event
/// listing every alternative.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RestRule {
    /// Stick when sticking is admissible (the maximal-dissipation choice: no slide, no
    /// friction work); otherwise the slide in the direction s = sign(c) the slider would
    /// accelerate without friction, or else the other slide.
    #[default]
    PreferStick,
    /// Slide when a slide is consistent (direction sign(c) first), stick otherwise: the
    /// least-dissipating choice, for exploring the other future. After an impulsive stop, or
    /// a slide that ended the instant it began, the stick is taken when admissible (choosing
    /// the failed slide again would repeat the stop without end).
    PreferSlide,
    /// End the run with an `indeterminate` outcome (the behaviour before issue 6).
    Halt,
}

impl RestRule {
    /// Pick one of `alternatives` (stick listed first when present); `c_dir` is the
    /// friction-free direction sign(c). `None` under [`RestRule::Halt`].
    pub fn choose(self, alternatives: &[Mode], c_dir: Direction) -> Option<Mode> {
        let slide = [Mode::Slide(c_dir), Mode::Slide(c_dir.flipped())]
            .into_iter()
            .find(|m| alternatives.contains(m));
        let stick = alternatives.contains(&Mode::Stick).then_some(Mode::Stick);
        match self {
            RestRule::PreferStick => stick.or(slide),
            RestRule::PreferSlide => slide.or(stick),
            RestRule::Halt => None,
        }
    }
}

impl Default for Options {
    fn default() -> Self {
        Options {
            rtol: 1e-10,
            atol: 1e-12,
            method: Method::Dop853,
            max_steps: 1_000_000,
            max_events: 10_000,
            rest_rule: RestRule::PreferStick,
            stop_threshold: 1e-9,
            prove_stick: true,
            cancel: Cancel::default(),
        }
    }
}

/// What a run must produce besides its events and final state: nothing else is computed.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Request {
    /// Times (s, ascending, within the run) at which to sample the state.
    pub sample_times: Vec<f64>,
    /// Integrate the friction work and the pivot's damping work alongside the state (for
    /// energy balances).
    pub friction_work: bool,
    /// Only the positions (x, theta) are wanted at the samples: the velocities in them are
    /// NaN, and the dense output skips half its work (the fit's markers need no more).
    pub positions_only: bool,
}

/// Why an event happened.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum EventKind {
    /// Stick -> slide: the needed friction reached mu_s |N|.
    Slip,
    /// Slide -> stick: the slider stopped where static friction holds it.
    Stick,
    /// The slider stopped and slides back the other way.
    Reversal,
    /// The slider stopped for an instant and slides on in the same direction.
    Continuation,
    /// The rail reaction changed sign while sliding (the friction branch changes).
    NormalFlip,
    /// The sliding equation stopped having exactly one solution (Painleve paradox) and the
    /// run cannot go on (an inconsistent state at rest, or [`RestRule::Halt`]).
    Paradox,
    /// At rest with several consistent motions: the [`RestRule`] chose one (`to`), the others
    /// are listed in [`Event::alternatives`].
    Indeterminate,
    /// Sliding toward a band edge |N| grew without bound: the slider stopped there, by itself or
    /// by an impulsive stop of the small velocity left at the threshold ([`Event::impulse`]).
    SuddenStop,
    /// A sliding state with no consistent solution, resolved by a tangential impact that stops
    /// the slider ([`Event::impulse`]).
    ImpulsiveStop,
    /// Numerator and denominator of the sliding equation vanish together (Q = 0 on a band
    /// edge): the future is not unique and the run ends.
    DynamicJam,
}

impl EventKind {
    /// The name in timelines and JSON (`slip`, `sudden_stop`, ...).
    pub fn name(self) -> &'static str {
        match self {
            EventKind::Slip => "slip",
            EventKind::Stick => "stick",
            EventKind::Reversal => "reversal",
            EventKind::Continuation => "continuation",
            EventKind::NormalFlip => "normal_flip",
            EventKind::Paradox => "paradox",
            EventKind::Indeterminate => "indeterminate",
            EventKind::SuddenStop => "sudden_stop",
            EventKind::ImpulsiveStop => "impulsive_stop",
            EventKind::DynamicJam => "dynamic_jam",
        }
    }
}

/// An impulsive stop of the slider (docs/physics.md, tangential impact) taking x' from
/// `x_dot_before` to 0 in no time.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Impulse {
    /// Slider velocity just before the stop (m/s).
    pub x_dot_before: f64,
    /// Normal impulse P_N = a (x'+ - x'-) (N s).
    pub normal: f64,
    /// Friction impulse P_F = D (x'+ - x'-) (N s).
    pub friction: f64,
    /// Kinetic energy lost, D x'-^2 / 2 (J).
    pub energy_lost: f64,
}

/// What the rig moves into at an event.
#[derive(Debug, Clone, PartialEq)]
pub enum Outcome {
    /// A mode of motion.
    Mode(Mode),
    /// The sliding equation has no consistent solution here.
    Inconsistent,
    /// Several consistent motions exist here; the listed ones.
    Indeterminate(Vec<Mode>),
}

impl Outcome {
    /// The name in timelines and JSON (`stick`, `slide+`, `slide-`, `inconsistent`,
    /// `indeterminate`).
    pub fn name(&self) -> &'static str {
        match self {
            Outcome::Mode(m) => m.name(),
            Outcome::Inconsistent => "inconsistent",
            Outcome::Indeterminate(_) => "indeterminate",
        }
    }
}

impl fmt::Display for Outcome {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Outcome::Indeterminate(alts) => {
                let names: Vec<_> = alts.iter().map(|m| m.name()).collect();
                write!(f, "indeterminate ({})", names.join(" | "))
            }
            other => f.write_str(other.name()),
        }
    }
}

/// A located mode transition (or paradox), with the state where it happened.
#[derive(Debug, Clone, PartialEq)]
pub struct Event {
    /// Time (s).
    pub t: f64,
    /// Mode before the event.
    pub from: Mode,
    /// What follows.
    pub to: Outcome,
    /// Why.
    pub kind: EventKind,
    /// State (x, theta, x', theta') at the event, after any reset of x' (and of theta' by an
    /// impulsive stop).
    pub state: State<f64>,
    /// Every consistent motion when the event is an indeterminate choice at rest.
    pub alternatives: Vec<Mode>,
    /// The impulsive stop applied at this event, if any.
    pub impulse: Option<Impulse>,
    /// Largest |N| (N) reached just before a sudden stop.
    pub peak_normal: Option<f64>,
}

impl Event {
    /// Energy the event took out of the rig in an impulsive stop (J), zero otherwise.
    pub fn energy_lost(&self) -> f64 {
        self.impulse.map_or(0.0, |i| i.energy_lost)
    }
}

/// Work counters of a run.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct Stats {
    /// Accepted steps.
    pub steps: usize,
    /// Rejected steps.
    pub rejected: usize,
    /// Right-hand-side evaluations (stages, dense-output stages, initial-step probes).
    pub rhs_evals: usize,
    /// Events located.
    pub events: usize,
    /// Stick phases taken in the pendulum's closed form (no steps; see
    /// [`Options::prove_stick`]).
    pub closed_form: usize,
}

/// One requested sample of the state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample<T> {
    /// Time (s).
    pub t: f64,
    /// State (x, theta, x', theta').
    pub state: State<T>,
    /// Mode at that time.
    pub mode: Mode,
    /// Friction work done up to this time (J, <= 0; rail friction, Coulomb and viscous), when
    /// requested.
    pub friction_work: Option<T>,
    /// Work done by the pivot's damping torque up to this time (J, <= 0), when the friction
    /// work is requested: E(t) - E(0) = friction work + damping work - impulsive losses.
    pub damping_work: Option<T>,
}

/// The result of a run.
#[derive(Debug, Clone)]
pub struct Solution<T> {
    /// Events in time order.
    pub events: Vec<Event>,
    /// Requested samples, in the order of the requested times (times after an early stop are
    /// missing).
    pub samples: Vec<Sample<T>>,
    /// Time the run ended: the scene's duration, or an unresolved paradox.
    pub final_time: f64,
    /// State at `final_time`.
    pub final_state: State<T>,
    /// Mode at `final_time`.
    pub final_mode: Mode,
    /// Friction work over the run (J), when requested.
    pub friction_work: Option<T>,
    /// Work of the pivot's damping torque over the run (J, <= 0), when the friction work is
    /// requested.
    pub damping_work: Option<T>,
    /// Work counters.
    pub stats: Stats,
}

impl<T> Solution<T> {
    /// Energy taken out by every impulsive stop of the run (J): with the friction work this
    /// closes the energy balance E(t) - E(0) = W_friction - sum of losses.
    pub fn impulsive_losses(&self) -> f64 {
        self.events.iter().map(Event::energy_lost).sum()
    }

    /// Whether the run stopped early at a paradox it does not resolve.
    pub fn stopped_at_paradox(&self) -> bool {
        self.events
            .last()
            .is_some_and(|e| !matches!(e.to, Outcome::Mode(_)))
    }
}

/// A run that could not produce a trustworthy answer, with where it happened.
#[derive(Debug, Error, PartialEq)]
pub enum SimError {
    /// The step size fell below what f64 time can resolve.
    #[error("step size underflow (h = {h:e} s) at t = {t} s, state {state:?}; the motion is too stiff here (near the paradox band?) or the tolerances are too tight")]
    StepSizeUnderflow {
        /// Time of the failure.
        t: f64,
        /// Step size tried.
        h: f64,
        /// State (x, theta, x', theta').
        state: State<f64>,
    },
    /// More steps than allowed.
    #[error(
        "more than {max} steps by t = {t} s, state {state:?}; raise the step limit or loosen rtol"
    )]
    TooManySteps {
        /// Time of the failure.
        t: f64,
        /// The limit.
        max: usize,
        /// State.
        state: State<f64>,
    },
    /// More events than allowed (chattering between stick and slide).
    #[error(
        "more than {max} events by t = {t} s, state {state:?}: the rig chatters between modes"
    )]
    TooManyEvents {
        /// Time of the failure.
        t: f64,
        /// The limit.
        max: usize,
        /// State.
        state: State<f64>,
    },
    /// A state or derivative became NaN or infinite.
    #[error("non-finite value at t = {t} s, state {state:?}")]
    NonFinite {
        /// Time of the failure.
        t: f64,
        /// Last finite state.
        state: State<f64>,
    },
    /// The input state or duration is unusable.
    #[error("invalid run input: {0}")]
    InvalidInput(String),
    /// [`Options::cancel`] was raised: the run stopped at `t`.
    #[error("cancelled at t = {t} s")]
    Cancelled {
        /// Time of the stop.
        t: f64,
    },
}
