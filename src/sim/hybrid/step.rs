//! Taking a step: a mode's start (a fresh stepper, the starting step size, the guards' first
//! values), one attempted step with its rejection, and the step-size control after an
//! accepted one.

use super::guards::{GuardState, PROOF_AFTER_STEPS};
use super::system::ModeSystem;
use super::{Run, Segment};
use crate::model::{re_state, Mode, Scalar};
use crate::sim::rk::{OdeSystem, Stepper};
use crate::sim::{Options, SimError, Stats};

/// An accepted step from the run's time `t` to `t1`, not yet committed: the guards may still
/// cut it at an event.
pub(super) struct Step<T, const N: usize> {
    /// End time and length (`t1 - t`).
    pub(super) t1: f64,
    pub(super) len: f64,
    /// The state at the end, and the real parts of it and of its rate (for the guards).
    pub(super) y1: [T; N],
    pub(super) y1r: [f64; N],
    pub(super) f1r: [f64; N],
    /// The scaled error norm (<= 1).
    pub(super) err: f64,
    /// The shortest step f64 time resolves at `t`.
    pub(super) h_min: f64,
}

/// How much a rejected step shrinks: to the size whose error would just meet the tolerance
/// under err ~ h^(q+1) (`exponent` = -1/(q+1)), with a 0.9 margin so that the retry passes,
/// and no less than 1/5 (an outlier error is not trusted that far); by 1/4 when the step
/// produced no finite error at all.
#[inline(always)]
pub(super) fn shrink_factor(err: f64, exponent: f64) -> f64 {
    if err.is_finite() {
        (0.9 * err.powf(exponent)).clamp(0.2, 1.0)
    } else {
        0.25
    }
}

/// The next step's growth after an accepted one, and ln(err) for the next call: a light PI
/// control (Gustafsson, beta = 0.05): measured on stick-slip scenes it saves about 5% of the
/// right-hand-side evaluations over plain control.
#[inline(always)]
pub(super) fn pi_factor(err: f64, ln_err_prev: f64, exponent: f64) -> (f64, f64) {
    let err_c = err.max(1e-10);
    // err^e * err_prev^(-0.05 e) as one exponential of logarithms: cheaper than two
    // powers on every step.
    let ln_err = err_c.ln();
    let factor = (0.85 * (exponent * (ln_err - 0.05 * ln_err_prev)).exp()).clamp(0.2, 6.0);
    (factor, ln_err)
}

impl<T: Scalar, M: Stepper<T, N>, const N: usize> Segment<'_, '_, T, M, N> {
    /// Attempt a step of size `h` from `y`, on the plain copy of the system when there is one.
    #[inline(always)]
    fn try_step(&mut self, y: &[T; N], h: f64, options: &Options) -> ([T; N], f64) {
        match &self.plain {
            Some(plain) => self
                .stepper
                .try_step(plain, y, h, options.rtol, options.atol),
            None => self
                .stepper
                .try_step(&self.sys, y, h, options.rtol, options.atol),
        }
    }

    /// The stepper with its dense output prepared for `step` from `y0` (once a step).
    #[inline]
    pub(super) fn dense(&mut self, y0: &[T; N], step: &Step<T, N>) -> &M {
        if !self.dense_ready {
            match &self.plain {
                Some(plain) => self.stepper.prepare_dense(plain, y0, &step.y1, step.len),
                None => self
                    .stepper
                    .prepare_dense(&self.sys, y0, &step.y1, step.len),
            }
            self.dense_ready = true;
        }
        self.stepper
    }
}

impl<'a, T: Scalar + 'static, const N: usize> Run<'a, '_, T, N> {
    /// Start integrating the current mode from the current state: a fresh stepper, the step
    /// size capped by the new dynamics, the guards' first values.
    pub(super) fn begin_mode<'m, M: Stepper<T, N>>(
        &mut self,
        stepper: &'m mut M,
    ) -> Segment<'a, 'm, T, M, N> {
        let (mode, sigma) = (self.mode, self.sigma);
        let sys = ModeSystem::new(self.ctx.rig, mode, sigma);
        // The plain rig's own copy of the stepper, for f64 runs (see Scalar::SPECIALISE_PLAIN).
        let fast = T::SPECIALISE_PLAIN && sys.plain;
        let plain = fast.then(|| sys.as_plain());
        stepper.reset(&sys, &self.y);
        // A new mode has new dynamics: the step carried over from the old one is only an upper
        // bound (an overlong first step after a slip costs a rejected 12-stage step).
        let h_start = initial_step(
            &sys,
            &self.y,
            stepper.f_start(),
            M::ERROR_ORDER,
            self.options,
            self.t_end.max(1e-300),
            &mut self.out.stats,
        );
        self.h = if self.h.is_nan() {
            h_start
        } else {
            self.h.min(h_start)
        };
        // A stick phase that has lasted this many steps is worth a proof that it never ends
        // (stick-slip phases are over long before and never pay for it).
        // The proof and the closed form assume the conservative, level pendulum.
        let proof_due =
            (mode == Mode::Stick && self.options.prove_stick && self.ctx.rig_re.is_ideal())
                .then_some(self.out.stats.steps + PROOF_AFTER_STEPS);
        let (yr, fr) = (re_vec(&self.y), re_vec(stepper.f_start()));
        let gs = GuardState::start(self.ctx, mode, sigma, &yr, &fr);
        Segment {
            sys,
            plain,
            stepper,
            dense_ready: false,
            gs,
            t_start: self.t,
            proof_due,
            exponent: -1.0 / f64::from(M::ERROR_ORDER + 1),
            ln_err_prev: 1e-4_f64.ln(),
        }
    }

    /// Fail once the run has spent its steps (accepted and rejected), or when its caller
    /// cancels it.
    pub(super) fn check_step_budget(&self) -> Result<(), SimError> {
        if self.options.cancel.is_raised() {
            return Err(SimError::Cancelled { t: self.t });
        }
        if self.out.stats.steps + self.out.stats.rejected >= self.options.max_steps {
            return Err(SimError::TooManySteps {
                t: self.t,
                max: self.options.max_steps,
                state: re_state(&self.y),
            });
        }
        Ok(())
    }

    /// Attempt a step of size h from (t, y), cut to land exactly on `t_end`. A rejected
    /// attempt shrinks h and gives `None`, or fails once h is below what f64 time resolves.
    #[inline]
    pub(super) fn take_step<M: Stepper<T, N>>(
        &mut self,
        seg: &mut Segment<'a, '_, T, M, N>,
    ) -> Result<Option<Step<T, N>>, SimError> {
        let t = self.t;
        let h_min = 16.0 * f64::EPSILON * t.abs().max(self.t_end);
        let last = t + self.h >= self.t_end;
        if last {
            self.h = self.t_end - t;
        }
        let (y1, err) = seg.try_step(&self.y, self.h, self.options);
        // A step whose end state or end rate is not finite has no usable error: it shrinks
        // as one that produced none (the estimate does not see the rate at the end).
        let finite_step = finite(&y1) && finite(seg.stepper.f_end());
        let err = if finite_step { err } else { f64::NAN };
        if !err.is_finite() || err > 1.0 {
            self.out.stats.rejected += 1;
            if cfg!(debug_assertions) {
                use std::io::Write as _;
                let _ = writeln!(
                    std::io::stderr(),
                    "reject t={t} h={} err={err} mode={}",
                    self.h,
                    self.mode
                );
            }
            self.h *= shrink_factor(err, seg.exponent);
            if self.h < h_min {
                let (h, state) = (self.h, re_state(&self.y));
                return Err(if err.is_finite() {
                    SimError::StepSizeUnderflow { t, h, state }
                } else {
                    SimError::NonFinite { t, state }
                });
            }
            return Ok(None);
        }
        self.out.stats.steps += 1;
        seg.dense_ready = false;
        let t1 = if last { self.t_end } else { t + self.h };
        Ok(Some(Step {
            t1,
            len: t1 - t,
            y1r: re_vec(&y1),
            f1r: re_vec(seg.stepper.f_end()),
            y1,
            err,
            h_min,
        }))
    }

    /// Take back an accepted step in which the mode may end within a sixteenth: it is
    /// resolved with a shorter step rather than declared zero-length (short slips near a
    /// grazing onset).
    pub(super) fn retry_shorter(&mut self, step: &Step<T, N>) {
        self.out.stats.steps -= 1;
        self.out.stats.rejected += 1;
        self.h = step.len / 16.0;
    }

    /// Commit an accepted step with no event: the guards' values at its end (`ends`, in the
    /// order of the mode's guards), the stepper's state and the run's time and state.
    pub(super) fn accept<M: Stepper<T, N>>(
        &mut self,
        seg: &mut Segment<'a, '_, T, M, N>,
        step: Step<T, N>,
        ends: &[(f64, f64)],
    ) {
        for (st, &end) in seg.gs.iter_mut().zip(ends) {
            st.advance(end);
        }
        seg.stepper.accept();
        self.y = step.y1;
        self.t = step.t1;
    }

    /// The next step's size after an accepted step of scaled error `err`.
    pub(super) fn adapt_step<M>(&mut self, seg: &mut Segment<'a, '_, T, M, N>, err: f64) {
        let (factor, ln_err) = pi_factor(err, seg.ln_err_prev, seg.exponent);
        self.h *= factor;
        seg.ln_err_prev = ln_err;
    }
}

/// Real parts of a state, for the guards and the decisions.
pub(super) fn re_vec<T: Scalar, const N: usize>(y: &[T; N]) -> [f64; N] {
    std::array::from_fn(|i| y[i].re())
}

/// Whether every component of a state is finite (a step that is not is rejected).
pub(super) fn finite<T: Scalar, const N: usize>(y: &[T; N]) -> bool {
    y.iter().all(|v| v.re().is_finite())
}

/// Hairer's starting step: from the sizes of y, f and a probe of f's rate of change.
pub(super) fn initial_step<T: Scalar, S: OdeSystem<T, N>, const N: usize>(
    sys: &S,
    y0: &[T; N],
    f0: &[T; N],
    order: i32,
    options: &Options,
    span: f64,
    stats: &mut Stats,
) -> f64 {
    let sc: [f64; N] = std::array::from_fn(|i| options.atol + options.rtol * y0[i].re().abs());
    let rms = |v: &dyn Fn(usize) -> f64| {
        ((0..N).map(|i| (v(i) / sc[i]).powi(2)).sum::<f64>() / N as f64).sqrt()
    };
    let d0 = rms(&|i| y0[i].re());
    let d1 = rms(&|i| f0[i].re());
    let h0 = if d0 < 1e-5 || d1 < 1e-5 {
        1e-6
    } else {
        0.01 * d0 / d1
    };
    let h0 = h0.min(span);
    let y1: [T; N] = std::array::from_fn(|i| y0[i] + f0[i] * h0);
    let mut f1 = *f0;
    sys.rhs(&y1, &mut f1);
    stats.rhs_evals += 1;
    let d2 = rms(&|i| f1[i].re() - f0[i].re()) / h0;
    let h1 = if d1.max(d2) <= 1e-15 {
        (h0 * 1e-3).max(1e-6)
    } else {
        (0.01 / d1.max(d2)).powf(1.0 / f64::from(order + 1))
    };
    (100.0 * h0).min(h1).min(span)
}
