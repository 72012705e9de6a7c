//! The one hybrid loop: integrate the current mode, watch its guards on the dense output,
//! locate the first crossing with a bracketing root finder, switch mode there and restart.
//!
//! [`run`] tells the story; each chapter has a file, with the functions that do the work
//! (tested alone in `tests.rs`) and the methods of the loop's state [`Run`] that call them:
//! - `mod.rs`: the entry points, the input checks, the loop and its state ([`Run`] for the
//!   whole run, [`Segment`] for one mode).
//! - `system.rs`: the right-hand side of one mode (and its copy for plain rigs).
//! - `step.rs`: taking a step: a mode's start and starting step size, one attempted step,
//!   the step-size control.
//! - `guards.rs`: checking the guards: the guard functions of each mode, their values over a
//!   step and the bracket of a sign change; the proof that a stick phase never ends.
//! - `locate.rs`: locating the event: the root finder, the search for a grazing dip, and the
//!   earliest crossing of a step with its time and state.
//! - `decide.rs`: deciding the next mode: the transition rules, the impulsive stop, the
//!   decision at the start and at a crossing, and the event recorded.
//! - `jump.rs`: crossing the event: the state's reset and the sensitivities' jump.
//! - `samples.rs`: emitting samples, and the solution the run ends in.

mod closed;
mod decide;
mod guards;
mod jump;
mod locate;
mod samples;
mod step;
mod system;
#[cfg(test)]
mod tests;

pub use decide::impulsive_stop;

use super::rk::{Dop853, Dp5, Stepper};
use super::{Event, EventKind, Method, Options, Outcome, Request, Sample, SimError, Solution};
use crate::model::{re_state, Mode, Rig, Scalar, State};
use decide::Reset;
use guards::{Ctx, GuardState};
use locate::Crossing;
use samples::Output;
use std::any::TypeId;
use std::ops::ControlFlow;
use system::ModeSystem;

/// Simulate `rig` from `y0` at t = 0 to `t_end`, computing only what `request` asks for.
///
/// Mode transitions are located to about 1e-13 s on the dense output; for dual-number
/// scalars the event times are differentiated implicitly, so sampled states carry exact
/// derivatives through every switch. Above mu* the run goes on through the Painleve paradox:
/// at rest [`Options::rest_rule`] picks among several consistent motions (an `indeterminate`
/// event), a slide whose normal force blows up near a band edge ends in a `sudden_stop`, and
/// a sliding state with no solution in an `impulsive_stop`; only a dynamic jam (or the
/// [`RestRule::Halt`] rule) ends the run early.
pub fn simulate<T: Scalar + 'static>(
    rig: &Rig<T>,
    y0: &State<T>,
    t_end: f64,
    options: &Options,
    request: &Request,
) -> Result<Solution<T>, SimError> {
    let mut samples = Vec::with_capacity(request.sample_times.len());
    let mut sol = simulate_each(rig, y0, t_end, options, request, &mut |s: Sample<T>| {
        samples.push(s)
    })?;
    sol.samples = samples;
    Ok(sol)
}

/// [`simulate`] handing each requested sample to `sink` as the run passes its time, in time
/// order, instead of collecting them: a fit over a million frames keeps no per-frame state.
/// The returned solution's `samples` is empty.
pub fn simulate_each<T: Scalar + 'static>(
    rig: &Rig<T>,
    y0: &State<T>,
    t_end: f64,
    options: &Options,
    request: &Request,
    sink: &mut dyn FnMut(Sample<T>),
) -> Result<Solution<T>, SimError> {
    // The sink is a trait object so that each scalar type has one copy of the run, whatever
    // the callers do with their samples.
    match (options.method, request.friction_work) {
        (Method::Dp5, false) => run::<T, Dp5<T, 4>, 4>(rig, y0, t_end, options, request, sink),
        (Method::Dp5, true) => run::<T, Dp5<T, 6>, 6>(rig, y0, t_end, options, request, sink),
        (Method::Dop853, false) => {
            run::<T, Dop853<T, 4>, 4>(rig, y0, t_end, options, request, sink)
        }
        (Method::Dop853, true) => run::<T, Dop853<T, 6>, 6>(rig, y0, t_end, options, request, sink),
    }
}

/// One run: the input checked, the start decided, then mode after mode until `t_end` or an
/// event that ends the run. Each pass of the inner loop is one step.
fn run<T, M, const N: usize>(
    rig: &Rig<T>,
    y0: &State<T>,
    t_end: f64,
    options: &Options,
    request: &Request,
    sink: &mut dyn FnMut(Sample<T>),
) -> Result<Solution<T>, SimError>
where
    T: Scalar + 'static,
    M: Stepper<T, N> + Default,
{
    validate(y0, t_end, options, request)?;
    let ctx = Ctx::new(rig, options);
    let mut run = match Run::<T, N>::start(&ctx, y0, t_end, options, request, sink) {
        ControlFlow::Continue(run) => run,
        // A paradox at rest ends the run at t = 0.
        ControlFlow::Break(solution) => return Ok(solution),
    };
    let mut stepper = M::default();
    loop {
        // A mode, from its start to the event that ends it.
        let mut seg = run.begin_mode(&mut stepper);
        match run.closed_stick(&mut seg)? {
            Some(ControlFlow::Continue(())) => continue,
            Some(ControlFlow::Break(solution)) => return Ok(solution),
            None => {}
        }
        loop {
            if run.t >= t_end {
                return Ok(run.end(&seg));
            }
            run.check_step_budget()?;
            // Take a step.
            let Some(step) = run.take_step(&mut seg)? else {
                continue; // rejected: h has shrunk
            };
            // Check the guards over it.
            let ends = match run.check_guards(&mut seg, &step) {
                Crossing::Clear(ends) => ends,
                Crossing::TooSoon => {
                    run.retry_shorter(&step);
                    continue;
                }
                // Locate the event, emit the samples before it, decide the next mode.
                Crossing::At { th, guard } => {
                    let event = run.locate_event(&mut seg, &step, th, guard);
                    run.emit_samples(&mut seg, &step, event.t);
                    match run.switch_mode(&seg, &step.y1r, event)? {
                        ControlFlow::Continue(()) => break,
                        ControlFlow::Break(solution) => return Ok(solution),
                    }
                }
            };
            // No event: emit the step's samples and go on from its end.
            run.emit_samples(&mut seg, &step, step.t1);
            let err = step.err;
            run.accept(&mut seg, step, &ends);
            if let ControlFlow::Break(solution) = run.prove_stick(&mut seg) {
                return Ok(solution);
            }
            run.adapt_step(&mut seg, err);
        }
    }
}

/// Refuse input the loop cannot run on, before any work.
fn validate<T: Scalar>(
    y0: &State<T>,
    t_end: f64,
    options: &Options,
    request: &Request,
) -> Result<(), SimError> {
    if !(t_end.is_finite() && t_end >= 0.0) {
        return Err(SimError::InvalidInput(format!(
            "duration must be finite and >= 0, got {t_end}"
        )));
    }
    if !y0.iter().all(|v| v.re().is_finite()) {
        return Err(SimError::InvalidInput(format!(
            "initial state must be finite, got {:?}",
            re_state(y0)
        )));
    }
    if !(options.rtol > 0.0 && options.atol > 0.0) {
        return Err(SimError::InvalidInput(
            "rtol and atol must be positive".into(),
        ));
    }
    let times = &request.sample_times;
    if times
        .windows(2)
        .any(|w| w[0].partial_cmp(&w[1]) == Some(std::cmp::Ordering::Greater))
        || times.iter().any(|t| !t.is_finite())
    {
        return Err(SimError::InvalidInput(
            "sample times must be finite and ascending".into(),
        ));
    }
    Ok(())
}

/// Whether the run's scalar is plain `f64`: no derivatives to carry, so a reset is applied as
/// it is and a proven stick phase may end in its closed form.
fn is_f64<T: 'static>() -> bool {
    TypeId::of::<T>() == TypeId::of::<f64>()
}

/// The loop's state over the whole run: what is fixed for it, where it is, and what it has
/// produced so far.
struct Run<'a, 's, T, const N: usize> {
    /// The run's context, kept apart from the loop's moving parts (the guards' calls are
    /// then handed no pointer into them).
    ctx: &'a Ctx<'a, T>,
    options: &'a Options,
    request: &'a Request,
    t_end: f64,
    out: Output<'s, T>,
    /// Time and state at the start of the next step (with the friction and damping work as
    /// a fifth and sixth component when they are requested).
    t: f64,
    y: [T; N],
    /// The current mode and its branch sigma = sign(N).
    mode: Mode,
    sigma: f64,
    /// The next step's size (NaN before the first).
    h: f64,
}

impl<'a, 's, T: Scalar + 'static, const N: usize> Run<'a, 's, T, N> {
    /// The run's state at t = 0, after the start's decision (an event of its own when it is
    /// a choice, an impulse or a paradox); `Break` when the run ends there.
    fn start(
        ctx: &'a Ctx<'a, T>,
        y0: &State<T>,
        t_end: f64,
        options: &'a Options,
        request: &'a Request,
        sink: &'s mut dyn FnMut(Sample<T>),
    ) -> ControlFlow<Solution<T>, Self> {
        let mut y: [T; N] = std::array::from_fn(|i| if i < 4 { y0[i] } else { T::from(0.0) });
        let mut out = Output::new(sink);
        let (initial_mode, start) = decide::start(&ctx.rig_re, &re_state(&y), options.rest_rule);
        if !matches!(
            start.kind,
            EventKind::Slip | EventKind::Stick | EventKind::NormalFlip
        ) {
            // A choice, an impulse or a paradox at t = 0 is an event of its own.
            let impulse = (start.reset == Reset::Impulsive).then(|| {
                let (after, impulse) = impulsive_stop(ctx.rig, &y[..4]);
                y[..4].copy_from_slice(&after);
                impulse
            });
            out.events.push(Event {
                t: 0.0,
                from: initial_mode,
                to: start.outcome.clone(),
                kind: start.kind,
                state: re_state(&y),
                alternatives: start.alternatives.clone(),
                impulse,
                peak_normal: None,
            });
            out.stats.events = 1;
        }
        let times = &request.sample_times;
        let Outcome::Mode(mode) = start.outcome else {
            out.emit(times, 0.0, 0.0, initial_mode, |_| y);
            return ControlFlow::Break(out.finish(0.0, &y, initial_mode));
        };
        out.emit(times, 0.0, 0.0, mode, |_| y);
        ControlFlow::Continue(Run {
            ctx,
            options,
            request,
            t_end,
            out,
            t: 0.0,
            y,
            mode,
            sigma: start.sigma,
            h: f64::NAN,
        })
    }
}

/// The loop's state over one mode, from its start to the event that ends it.
struct Segment<'a, 'm, T, M, const N: usize> {
    sys: ModeSystem<'a, T>,
    /// The plain rig's own copy of the system, for f64 runs (see Scalar::SPECIALISE_PLAIN).
    plain: Option<ModeSystem<'a, T, true>>,
    /// The run's stepper, made fresh for each mode (kept by the run so that its stages, a few
    /// kilobytes for dual numbers, are not moved with the segment).
    stepper: &'m mut M,
    /// Whether the stepper's dense output is prepared for the current step (it may cost
    /// evaluations, so only when a guard or a sample looks inside the step).
    dense_ready: bool,
    /// The mode's guards, with their values at the start of the next step.
    gs: Vec<GuardState>,
    /// When the mode began: a slide that stops at that instant failed at once.
    t_start: f64,
    /// The accepted-step count at which to try the proof that a stick phase never ends.
    proof_due: Option<usize>,
    /// Step-size exponent -1 / (error order + 1), and the last accepted step's ln(error)
    /// (the memory of the PI control).
    exponent: f64,
    ln_err_prev: f64,
}
