//! Taking a step: the starting step size of a mode and the helpers that judge a step's
//! result.

use crate::model::Scalar;
use crate::sim::rk::OdeSystem;
use crate::sim::{Options, Stats};

pub(super) fn re_vec<T: Scalar, const N: usize>(y: &[T; N]) -> [f64; N] {
    std::array::from_fn(|i| y[i].re())
}

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
