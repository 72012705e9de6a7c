//! Embedded explicit Runge-Kutta steppers with dense output. A stepper only knows how to take
//! one step, estimate its error and interpolate inside it; the hybrid loop owns step-size
//! control, events and outputs.

// Index loops over the state components read like the formulas they implement.
#![allow(clippy::needless_range_loop)]

use super::tableau::*;
use crate::model::Scalar;

/// An autonomous ODE y' = f(y) of dimension `N`.
pub trait OdeSystem<T, const N: usize> {
    /// Write f(y) into `dy`.
    fn rhs(&self, y: &[T; N], dy: &mut [T; N]);
}

/// One stepping method: init / step / accept / interpolate.
pub trait Stepper<T: Scalar, const N: usize> {
    /// Order of the error estimator; the step-size exponent is 1 / (order + 1).
    const ERROR_ORDER: i32;

    /// Start at `y`, as a fresh stepper (its evaluation count back to zero): evaluate f
    /// there. Every other stage is written by a step before it is read, so nothing else is
    /// cleared (a dual-number stepper is kilobytes, and a fit starts thousands of modes).
    fn reset<S: OdeSystem<T, N>>(&mut self, sys: &S, y: &[T; N]);

    /// Attempt a step of size `h` from `y`; returns the new state and the scaled error norm
    /// (accept when <= 1).
    fn try_step<S: OdeSystem<T, N>>(
        &mut self,
        sys: &S,
        y: &[T; N],
        h: f64,
        rtol: f64,
        atol: f64,
    ) -> ([T; N], f64);

    /// f at the start of the current step.
    fn f_start(&self) -> &[T; N];

    /// f at the end of the last attempted step (FSAL).
    fn f_end(&self) -> &[T; N];

    /// Make the last attempted step the current one (its end becomes the next start).
    fn accept(&mut self);

    /// Prepare the interpolant of the last attempted step, from `y0` to `y1` with size `h`.
    /// Costs extra f evaluations for some methods, so the loop calls it only when needed.
    fn prepare_dense<S: OdeSystem<T, N>>(&mut self, sys: &S, y0: &[T; N], y1: &[T; N], h: f64);

    /// The state at fraction `theta` in [0, 1] of the prepared step.
    fn interpolate(&self, theta: f64) -> [T; N];

    /// [`Stepper::interpolate`] of the positions (the first two components) only, the rest
    /// NaN: samples that feed marker positions need no more.
    fn interpolate_positions(&self, theta: f64) -> [T; N] {
        let mut y = self.interpolate(theta);
        y.iter_mut().skip(2).for_each(|v| *v = T::from(f64::NAN));
        y
    }

    /// Right-hand-side evaluations so far.
    fn rhs_evals(&self) -> usize;
}

#[inline]
fn zero<T: Scalar, const N: usize>() -> [T; N] {
    [T::from(0.0); N]
}

/// y0 + h * sum_j coef[j] k[j] over the first `n` stages.
#[inline]
fn combine<T: Scalar, const N: usize>(y0: &[T; N], h: f64, coef: &[f64], k: &[[T; N]]) -> [T; N] {
    // A weighted sum first, then one scaling by h: fewer operations than scaling each stage,
    // and branch-free so the compiler can vectorise over the state.
    let mut acc = [T::from(0.0); N];
    for (c, kj) in coef.iter().zip(k) {
        for i in 0..N {
            acc[i] += kj[i] * *c;
        }
    }
    let mut out = *y0;
    for i in 0..N {
        out[i] += acc[i] * h;
    }
    out
}

/// The argument y0 + h sum_{j < ST} row[j] k[j] of stage `ST` (a const, so the tableau row
/// is a compile-time constant and zero couplings drop out of the unrolled sum). The run is
/// latency-bound, each stage waiting for the one before: the older stages' part is summed and
/// added to y0 first, so the last stage's right-hand side is followed by one multiply and one
/// add (not a multiply, two adds and the scaling by h).
#[inline(always)]
fn stage_argument<T: Scalar, const N: usize, const ST: usize>(
    y0: &[T; N],
    h: f64,
    row: &[f64],
    k: &[[T; N]],
) -> [T; N] {
    let mut acc = [T::from(0.0); N];
    for j in 0..ST - 1 {
        let c = row[j];
        if c != 0.0 {
            for i in 0..N {
                acc[i] += k[j][i] * c;
            }
        }
    }
    let mut out = *y0;
    for i in 0..N {
        out[i] += acc[i] * h;
    }
    if row[ST - 1] != 0.0 {
        let last = row[ST - 1] * h;
        for i in 0..N {
            out[i] += k[ST - 1][i] * last;
        }
    }
    out
}

/// Scale of the mixed absolute/relative tolerance per component (real parts only, so a dual
/// run takes exactly the steps of the f64 run it differentiates).
#[inline]
fn scale<T: Scalar>(a: T, b: T, rtol: f64, atol: f64) -> f64 {
    atol + rtol * a.re().abs().max(b.re().abs())
}

/// Dormand-Prince 5(4) with Shampine's 4th-order dense output (free: no extra stages).
#[derive(Debug, Clone)]
pub struct Dp5<T, const N: usize> {
    k: [[T; N]; 7],
    y0: [T; N],
    h: f64,
    evals: usize,
}

impl<T: Scalar, const N: usize> Default for Dp5<T, N> {
    fn default() -> Self {
        Dp5 {
            k: [zero(); 7],
            y0: zero(),
            h: 0.0,
            evals: 0,
        }
    }
}

impl<T: Scalar, const N: usize> Stepper<T, N> for Dp5<T, N> {
    const ERROR_ORDER: i32 = 4;

    fn reset<S: OdeSystem<T, N>>(&mut self, sys: &S, y: &[T; N]) {
        sys.rhs(y, &mut self.k[0]);
        self.evals = 1;
    }

    fn try_step<S: OdeSystem<T, N>>(
        &mut self,
        sys: &S,
        y: &[T; N],
        h: f64,
        rtol: f64,
        atol: f64,
    ) -> ([T; N], f64) {
        for s in 1..7 {
            let ys = combine(y, h, &DP5_A[s][..s], &self.k[..s]);
            let (_, rest) = self.k.split_at_mut(s);
            sys.rhs(&ys, &mut rest[0]);
        }
        self.evals += 6;
        // Row 6 of A is b: the stage-7 argument is the new state (FSAL).
        let y1 = combine(y, h, &DP5_A[6], &self.k[..6]);
        let mut acc = 0.0;
        for i in 0..N {
            let mut e = T::from(0.0);
            for (j, ej) in DP5_E.iter().enumerate() {
                if *ej != 0.0 {
                    e += self.k[j][i] * *ej;
                }
            }
            let r = h * e.re() / scale(y[i], y1[i], rtol, atol);
            acc += r * r;
        }
        self.y0 = *y;
        self.h = h;
        (y1, (acc / N as f64).sqrt())
    }

    fn f_start(&self) -> &[T; N] {
        &self.k[0]
    }

    fn f_end(&self) -> &[T; N] {
        &self.k[6]
    }

    fn accept(&mut self) {
        self.k[0] = self.k[6];
    }

    fn prepare_dense<S: OdeSystem<T, N>>(&mut self, _: &S, y0: &[T; N], _: &[T; N], h: f64) {
        self.y0 = *y0;
        self.h = h;
    }

    fn interpolate(&self, theta: f64) -> [T; N] {
        let powers = [theta, theta * theta, theta.powi(3), theta.powi(4)];
        let mut coef = [0.0; 7];
        for (j, row) in DP5_P.iter().enumerate() {
            coef[j] = row.iter().zip(&powers).map(|(p, t)| p * t).sum();
        }
        combine(&self.y0, self.h, &coef, &self.k)
    }

    fn rhs_evals(&self) -> usize {
        self.evals
    }
}

/// DOP853: 8th order with a 5th/3rd-order error estimate and 7th-order dense output, which
/// costs three extra stages and so is built only for steps that need it.
#[derive(Debug, Clone)]
pub struct Dop853<T, const N: usize> {
    k: [[T; N]; 16],
    dense: [[T; N]; 7],
    y0: [T; N],
    evals: usize,
}

impl<T: Scalar, const N: usize> Default for Dop853<T, N> {
    fn default() -> Self {
        Dop853 {
            k: [zero(); 16],
            dense: [zero(); 7],
            y0: zero(),
            evals: 0,
        }
    }
}

impl<T: Scalar, const N: usize> Dop853<T, N> {
    /// Stage `ST`: f at its argument ([`stage_argument`]), written into `k[ST]`.
    #[inline(always)]
    fn stage<S: OdeSystem<T, N>, const ST: usize>(&mut self, sys: &S, y: &[T; N], h: f64) {
        let ys = stage_argument::<T, N, ST>(y, h, &DOP853_A[ST], &self.k);
        let (_, rest) = self.k.split_at_mut(ST);
        sys.rhs(&ys, &mut rest[0]);
    }
}

impl<T: Scalar, const N: usize> Stepper<T, N> for Dop853<T, N> {
    const ERROR_ORDER: i32 = 7;

    fn reset<S: OdeSystem<T, N>>(&mut self, sys: &S, y: &[T; N]) {
        sys.rhs(y, &mut self.k[0]);
        self.evals = 1;
    }

    fn try_step<S: OdeSystem<T, N>>(
        &mut self,
        sys: &S,
        y: &[T; N],
        h: f64,
        rtol: f64,
        atol: f64,
    ) -> ([T; N], f64) {
        self.stage::<S, 1>(sys, y, h);
        self.stage::<S, 2>(sys, y, h);
        self.stage::<S, 3>(sys, y, h);
        self.stage::<S, 4>(sys, y, h);
        self.stage::<S, 5>(sys, y, h);
        self.stage::<S, 6>(sys, y, h);
        self.stage::<S, 7>(sys, y, h);
        self.stage::<S, 8>(sys, y, h);
        self.stage::<S, 9>(sys, y, h);
        self.stage::<S, 10>(sys, y, h);
        self.stage::<S, 11>(sys, y, h);
        let y1 = stage_argument::<T, N, 12>(y, h, &DOP853_A[12], &self.k);
        let (_, rest) = self.k.split_at_mut(12);
        sys.rhs(&y1, &mut rest[0]);
        self.evals += 12;
        // The combined 5th/3rd-order estimate of dop853.f: robust when either alone is small.
        // Its weights on the last stage are zero and so skipped (as all zero weights): the
        // estimate and the step-size control that follows then need not wait for that
        // stage's right-hand side, and overlap with it (the run is latency-bound). A
        // non-finite last stage is caught by the caller's check of `f_end`.
        const { assert!(DOP853_E5[12] == 0.0 && DOP853_E3[12] == 0.0) };
        let (mut e5, mut e3) = (0.0, 0.0);
        for i in 0..N {
            let (mut a5, mut a3) = (0.0, 0.0);
            for j in 0..12 {
                let kj = self.k[j][i].re();
                if DOP853_E5[j] != 0.0 {
                    a5 += DOP853_E5[j] * kj;
                }
                if DOP853_E3[j] != 0.0 {
                    a3 += DOP853_E3[j] * kj;
                }
            }
            let sc = scale(y[i], y1[i], rtol, atol);
            e5 += (a5 / sc) * (a5 / sc);
            e3 += (a3 / sc) * (a3 / sc);
        }
        let err = if e5 == 0.0 && e3 == 0.0 {
            0.0
        } else {
            h.abs() * e5 / ((e5 + 0.01 * e3) * N as f64).sqrt()
        };
        (y1, err)
    }

    fn f_start(&self) -> &[T; N] {
        &self.k[0]
    }

    fn f_end(&self) -> &[T; N] {
        &self.k[12]
    }

    fn accept(&mut self) {
        self.k[0] = self.k[12];
    }

    fn prepare_dense<S: OdeSystem<T, N>>(&mut self, sys: &S, y0: &[T; N], y1: &[T; N], h: f64) {
        self.stage::<S, 13>(sys, y0, h);
        self.stage::<S, 14>(sys, y0, h);
        self.stage::<S, 15>(sys, y0, h);
        self.evals += 3;
        let mut dy = *y1;
        for i in 0..N {
            dy[i] -= y0[i];
        }
        let (f0, f1) = (&self.k[0], &self.k[12]);
        for i in 0..N {
            self.dense[0][i] = dy[i];
            self.dense[1][i] = f0[i] * h - dy[i];
            self.dense[2][i] = dy[i] * 2.0 - (f1[i] + f0[i]) * h;
        }
        for (r, drow) in DOP853_D.iter().enumerate() {
            self.dense[3 + r] = combine(&zero(), h, drow, &self.k);
        }
        self.y0 = *y0;
    }

    fn interpolate(&self, theta: f64) -> [T; N] {
        // Horner-like evaluation alternating theta and (1 - theta), as in dop853.f contd8.
        let mut y = zero::<T, N>();
        for (idx, f) in self.dense.iter().rev().enumerate() {
            let factor = if idx % 2 == 0 { theta } else { 1.0 - theta };
            for i in 0..N {
                y[i] = (y[i] + f[i]) * factor;
            }
        }
        for i in 0..N {
            y[i] += self.y0[i];
        }
        y
    }

    fn interpolate_positions(&self, theta: f64) -> [T; N] {
        let mut y = [T::from(f64::NAN); N];
        let mut acc = [T::from(0.0); 2];
        for (idx, f) in self.dense.iter().rev().enumerate() {
            let factor = if idx % 2 == 0 { theta } else { 1.0 - theta };
            for i in 0..2 {
                acc[i] = (acc[i] + f[i]) * factor;
            }
        }
        for i in 0..2 {
            y[i] = acc[i] + self.y0[i];
        }
        y
    }

    fn rhs_evals(&self) -> usize {
        self.evals
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// y'' = -y written as a system; exact solution (cos t, -sin t).
    struct Oscillator;
    impl OdeSystem<f64, 2> for Oscillator {
        fn rhs(&self, y: &[f64; 2], dy: &mut [f64; 2]) {
            dy[0] = y[1];
            dy[1] = -y[0];
        }
    }

    /// Error of one step of size h and of the interpolant inside it, against the exact flow.
    fn one_step<M: Stepper<f64, 2> + Default>(h: f64) -> (f64, f64) {
        let mut m = M::default();
        let y0 = [1.0, 0.0];
        m.reset(&Oscillator, &y0);
        let (y1, _) = m.try_step(&Oscillator, &y0, h, 1e-6, 1e-6);
        m.prepare_dense(&Oscillator, &y0, &y1, h);
        let step_err = (y1[0] - h.cos()).abs();
        let dense_err = (0..=10)
            .map(|k| {
                let th = k as f64 / 10.0;
                (m.interpolate(th)[0] - (th * h).cos()).abs()
            })
            .fold(0.0, f64::max);
        (step_err, dense_err)
    }

    /// Local errors shrink like h^(p+1): halving h divides the step error by about 2^(p+1)
    /// (order 5 and 8) and the dense error by 2^(q+1) (order 4 and 7).
    #[test]
    fn local_orders_of_steps_and_dense_output() {
        let ratio = |a: f64, b: f64| (a / b).log2();
        let (s1, d1) = one_step::<Dp5<f64, 2>>(0.2);
        let (s2, d2) = one_step::<Dp5<f64, 2>>(0.1);
        assert!(ratio(s1, s2) > 5.5, "dp5 step order {}", ratio(s1, s2));
        assert!(ratio(d1, d2) > 4.5, "dp5 dense order {}", ratio(d1, d2));
        let (s1, d1) = one_step::<Dop853<f64, 2>>(0.4);
        let (s2, d2) = one_step::<Dop853<f64, 2>>(0.2);
        assert!(ratio(s1, s2) > 8.5, "dop853 step order {}", ratio(s1, s2));
        assert!(ratio(d1, d2) > 7.5, "dop853 dense order {}", ratio(d1, d2));
    }

    /// The interpolant reproduces both ends of the step.
    #[test]
    fn dense_output_matches_step_ends() {
        let mut m = Dop853::<f64, 2>::default();
        let y0 = [1.0, 0.0];
        m.reset(&Oscillator, &y0);
        let (y1, _) = m.try_step(&Oscillator, &y0, 0.3, 1e-6, 1e-6);
        m.prepare_dense(&Oscillator, &y0, &y1, 0.3);
        for i in 0..2 {
            assert!((m.interpolate(0.0)[i] - y0[i]).abs() < 1e-15);
            assert!((m.interpolate(1.0)[i] - y1[i]).abs() < 1e-15);
        }
    }
}
