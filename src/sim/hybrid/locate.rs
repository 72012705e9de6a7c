//! Locating the event: the one bracketing root finder, the golden-section search that finds
//! a guard's dip between the samples of a step, and the earliest crossing among a mode's
//! guards over a step, with its time and state on the dense output.

use super::guards::{Ctx, Guard, Interior, Watch};
use super::step::{re_vec, Step};
use super::{Run, Segment};
use crate::model::{Mode, Scalar};
use crate::sim::rk::Stepper;

/// What the guards say about an accepted step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Crossing {
    /// Every guard holds over the step: their values and rates at its end, in the order of
    /// the mode's guards (at most three).
    Clear([(f64, f64); 3]),
    /// The mode may end within a sixteenth of the step: retry it shorter.
    TooSoon,
    /// The earliest crossing, at fraction `th` of the step, of the mode's guard number
    /// `guard`.
    At { th: f64, guard: usize },
}

/// A located event: its time, the state there (before any reset) and the guard that
/// crossed.
pub(super) struct Located<T, const N: usize> {
    pub(super) t: f64,
    pub(super) y: [T; N],
    pub(super) guard: Guard,
}

/// Minimum of `g` on [a, b] by golden-section search, to `tol` in the argument.
pub(super) fn golden_min(mut a: f64, mut b: f64, tol: f64, g: impl Fn(f64) -> f64) -> (f64, f64) {
    let r = (5f64.sqrt() - 1.0) / 2.0;
    let (mut c, mut d) = (b - r * (b - a), a + r * (b - a));
    let (mut gc, mut gd) = (g(c), g(d));
    while b - a > tol {
        if gc < gd {
            b = d;
            d = c;
            gd = gc;
            c = b - r * (b - a);
            gc = g(c);
        } else {
            a = c;
            c = d;
            gc = gd;
            d = a + r * (b - a);
            gd = g(d);
        }
        if gc <= 0.0 {
            return (c, gc);
        }
        if gd <= 0.0 {
            return (d, gd);
        }
    }
    if gc < gd {
        (c, gc)
    } else {
        (d, gd)
    }
}

/// Bracketing root finder (Illinois variant of regula falsi): `g(a) > 0 >= g(b)`. Returns the
/// first point found on the violated side, within `tol` of the crossing.
pub(super) fn find_root(
    mut a: f64,
    mut ga: f64,
    mut b: f64,
    mut gb: f64,
    tol: f64,
    g: impl Fn(f64) -> f64,
) -> f64 {
    let mut side = 0;
    for _ in 0..200 {
        if b - a <= tol || gb == 0.0 {
            break;
        }
        let mut c = b - gb * (b - a) / (gb - ga);
        if !(c > a && c < b) {
            c = 0.5 * (a + b);
        }
        let gc = g(c);
        if gc <= 0.0 {
            b = c;
            gb = gc;
            if side == -1 {
                ga *= 0.5;
            }
            side = -1;
        } else {
            a = c;
            ga = gc;
            if side == 1 {
                gb *= 0.5;
            }
            side = 1;
        }
    }
    b
}

/// One guard inside the current step, on the stepper's dense output (real parts).
struct Inside<'r, 'a, 'm, T, M, const N: usize> {
    seg: &'r mut Segment<'a, 'm, T, M, N>,
    ctx: &'r Ctx<'a, T>,
    y0: &'r [T; N],
    step: &'r Step<T, N>,
    guard: Guard,
    mode: Mode,
    sigma: f64,
}

impl<T: Scalar, M: Stepper<T, N>, const N: usize> Interior for Inside<'_, '_, '_, T, M, N> {
    #[inline]
    fn prepare(&mut self) {
        self.seg.dense(self.y0, self.step);
    }

    #[inline]
    fn at(&self, th: f64) -> f64 {
        let ctx = self.ctx;
        self.guard.value(
            (&ctx.rig_re, &ctx.k_re),
            &re_vec(&self.seg.stepper.interpolate(th))[..4],
            (self.mode, self.sigma),
            ctx.thr,
            ctx.plain,
        )
    }
}

impl<'a, T: Scalar + 'static, const N: usize> Run<'a, '_, T, N> {
    /// Check every guard of the mode over an accepted step and locate the earliest crossing.
    #[inline]
    pub(super) fn check_guards<M: Stepper<T, N>>(
        &self,
        seg: &mut Segment<'a, '_, T, M, N>,
        step: &Step<T, N>,
    ) -> Crossing {
        let (mode, sigma) = (self.mode, self.sigma);
        // A mode that may end within a sixteenth of this step is resolved with a shorter
        // step rather than declared zero-length (short slips near a grazing onset).
        let long = step.len > 1e3 * step.h_min;
        // Earliest guard crossing in this step, as a fraction of the step.
        let mut hit: Option<(f64, usize)> = None;
        let mut retry = false;
        let mut ends = [(0.0, 0.0); 3];
        let n = seg.gs.len();
        for (gi, end) in ends[..n].iter_mut().enumerate() {
            let st = seg.gs[gi];
            let (g1, gdot1) = self
                .ctx
                .guard_with_rate(st.guard, &step.y1r, &step.f1r, mode, sigma);
            *end = (g1, gdot1);
            let th = match st.watch(g1, gdot1, long, || self.inside(seg, step, st.guard)) {
                Watch::Holds => continue,
                Watch::TooLong => {
                    retry = true;
                    continue;
                }
                Watch::AtOnce => 0.0,
                Watch::Bracket { a, ga, b, gb } => {
                    let mut inside = self.inside(seg, step, st.guard);
                    inside.prepare();
                    // About 1e-14 s, or the rounding of t itself late in a run.
                    let tol = (1e-14 + 4.0 * f64::EPSILON * step.t1.abs()) / step.len;
                    find_root(a, ga, b, gb, tol, |th| inside.at(th))
                }
            };
            if hit.is_none_or(|(best, _)| th < best) {
                hit = Some((th, gi));
            }
        }
        match hit {
            _ if retry && hit.is_none_or(|(th, _)| th > 0.0) => Crossing::TooSoon,
            Some((th, guard)) => Crossing::At { th, guard },
            None => Crossing::Clear(ends),
        }
    }

    /// Guard `guard` inside `step`, for the search of its sign change there.
    fn inside<'r, 'm, M>(
        &'r self,
        seg: &'r mut Segment<'a, 'm, T, M, N>,
        step: &'r Step<T, N>,
        guard: Guard,
    ) -> Inside<'r, 'a, 'm, T, M, N> {
        Inside {
            seg,
            ctx: self.ctx,
            y0: &self.y,
            step,
            guard,
            mode: self.mode,
            sigma: self.sigma,
        }
    }

    /// The event at fraction `th` of `step`, where the mode's guard number `guard` crossed:
    /// its time, and its state on the dense output.
    pub(super) fn locate_event<M: Stepper<T, N>>(
        &self,
        seg: &mut Segment<'_, '_, T, M, N>,
        step: &Step<T, N>,
        th: f64,
        guard: usize,
    ) -> Located<T, N> {
        let t = if th >= 1.0 {
            step.t1
        } else {
            self.t + th * step.len
        };
        if th > 0.0 {
            seg.dense(&self.y, step);
        }
        let y = if th == 0.0 {
            self.y
        } else if th >= 1.0 {
            step.y1
        } else {
            seg.stepper.interpolate(th)
        };
        Located {
            t,
            y,
            guard: seg.gs[guard].guard,
        }
    }
}
