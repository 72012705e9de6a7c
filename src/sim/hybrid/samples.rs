//! Emitting samples: the requested states handed to the sink as the run passes their times,
//! the events and counters collected on the way, and the solution they end in.

use super::step::Step;
use super::{Run, Segment};
use crate::model::{Mode, Scalar};
use crate::sim::rk::Stepper;
use crate::sim::{Event, Sample, Solution, Stats};

/// The state at fraction `theta` of the stepper's prepared step, or only its positions when
/// that is all the samples need.
#[inline]
pub(super) fn dense_at<T: Scalar, M: Stepper<T, N>, const N: usize>(
    stepper: &M,
    theta: f64,
    positions_only: bool,
) -> [T; N] {
    if positions_only {
        stepper.interpolate_positions(theta)
    } else {
        stepper.interpolate(theta)
    }
}

/// Bookkeeping shared by the steps of a run.
pub(super) struct Output<'s, T> {
    pub(super) events: Vec<Event>,
    pub(super) sink: &'s mut dyn FnMut(Sample<T>),
    pub(super) next_sample: usize,
    pub(super) stats: Stats,
}

impl<'s, T: Scalar> Output<'s, T> {
    /// Nothing emitted, recorded or counted yet.
    pub(super) fn new(sink: &'s mut dyn FnMut(Sample<T>)) -> Self {
        Output {
            events: Vec::new(),
            sink,
            next_sample: 0,
            stats: Stats::default(),
        }
    }

    /// Emit requested samples with times in (t_lo, t_hi] (or [0, t_hi] at the start).
    pub(super) fn emit<const N: usize>(
        &mut self,
        times: &[f64],
        t_lo: f64,
        t_hi: f64,
        mode: Mode,
        at: impl Fn(f64) -> [T; N],
    ) {
        while let Some(&ts) = times.get(self.next_sample) {
            if ts > t_hi {
                break;
            }
            if ts >= t_lo {
                let y = at(ts);
                (self.sink)(Sample {
                    t: ts,
                    state: [y[0], y[1], y[2], y[3]],
                    mode,
                    friction_work: (N > 4).then(|| y[4]),
                    damping_work: (N > 5).then(|| y[5]),
                });
            }
            self.next_sample += 1;
        }
    }

    /// The solution of a run that ended at `t` in state `y` and `mode`, with the events
    /// recorded so far (taken: the run is over).
    pub(super) fn finish<const N: usize>(&mut self, t: f64, y: &[T; N], mode: Mode) -> Solution<T> {
        Solution {
            events: std::mem::take(&mut self.events),
            samples: Vec::new(),
            final_time: t,
            final_state: [y[0], y[1], y[2], y[3]],
            final_mode: mode,
            friction_work: (N > 4).then(|| y[4]),
            damping_work: (N > 5).then(|| y[5]),
            stats: self.stats,
        }
    }
}

impl<T: Scalar + 'static, const N: usize> Run<'_, '_, T, N> {
    /// Hand the sink every requested sample in (t, t_hi] of an accepted step, from the step's
    /// dense output (prepared only when a sample falls inside). Inlined: the test runs on
    /// every step.
    #[inline(always)]
    pub(super) fn emit_samples<M: Stepper<T, N>>(
        &mut self,
        seg: &mut Segment<'_, '_, T, M, N>,
        step: &Step<T, N>,
        t_hi: f64,
    ) {
        let times = &self.request.sample_times;
        if times
            .get(self.out.next_sample)
            .is_some_and(|&ts| ts <= t_hi)
        {
            let (t, positions_only) = (self.t, self.request.positions_only);
            let stepper = seg.dense(&self.y, step);
            self.out.emit(times, t, t_hi, self.mode, |ts| {
                dense_at(stepper, ((ts - t) / step.len).min(1.0), positions_only)
            });
        }
    }

    /// End the run at the current time and state, counting the mode's last evaluations.
    pub(super) fn end<M: Stepper<T, N>>(&mut self, seg: &Segment<'_, '_, T, M, N>) -> Solution<T> {
        self.out.stats.rhs_evals += seg.stepper.rhs_evals();
        self.out.finish(self.t, &self.y, self.mode)
    }
}
