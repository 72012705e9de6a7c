//! Emitting samples: the requested states handed to the sink as the run passes their times,
//! the events and counters collected on the way, and the solution they end in.

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

impl<T: Scalar> Output<'_, T> {
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
}

pub(super) fn finish<T: Scalar, const N: usize>(
    out: Output<'_, T>,
    t: f64,
    y: &[T; N],
    mode: Mode,
) -> Solution<T> {
    Solution {
        events: out.events,
        samples: Vec::new(),
        final_time: t,
        final_state: [y[0], y[1], y[2], y[3]],
        final_mode: mode,
        friction_work: (N > 4).then(|| y[4]),
        damping_work: (N > 5).then(|| y[5]),
        stats: out.stats,
    }
}
