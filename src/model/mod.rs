//! The rig and its physics: parameters, modes, contact forces and the regions where each
//! model holds. Every formula of `docs/physics.md` lives here once; the integrator, the
//! fit, the planner and the region analysis all call these functions.

pub mod dual;
mod forces;
mod friction;
mod markers;
mod mode;
mod param;
pub mod pendulum;
pub mod regions;
mod rig;
mod transition;

pub use forces::{energy, momentum, Contact, Shorthands, SlideBranches, SlideDynamics};
pub use markers::{markers, observed_markers, observed_markers_with, Camera};
pub use mode::{Direction, Mode};
pub use param::{Param, CAMERA_PARAMS};
pub use rig::{
    FrictionLaw, PendulumKeys, Rig, RigConstants, RigError, RigidPendulum, LOAD_EXPONENT_MAX,
    LOAD_EXPONENT_MIN,
};
pub use transition::{choose_at_rest, RestChoice};

use num_dual::DualNum;

/// A scalar the physics can be evaluated in: `f64`, or a dual number when the fit
/// differentiates a run with respect to its parameters.
pub trait Scalar: DualNum<f64> + Copy + Send + Sync {
    /// Zero in value and in every derivative. A real-rig term whose coefficient is exactly
    /// zero is skipped for speed, but a fit that frees the coefficient at zero needs its
    /// derivative: num-dual's `is_zero` looks at the value only, so it must not decide.
    fn is_exact_zero(&self) -> bool;

    /// sin and cos together. Every formula of the physics takes its trigonometry from here:
    /// the `libm` crate's (musl's) kernels, not glibc's, whose sin and cos save and restore
    /// the floating-point rounding mode on every call. That measured 7.8 against 3.6 ns a
    /// sine here and was half of a simulation's time. Both are within one ulp.
    fn sine_cosine(self) -> (Self, Self);

    /// sin, as [`Scalar::sine_cosine`] (a dual number's derivative needs the cosine anyway).
    #[inline]
    fn sine(self) -> Self {
        self.sine_cosine().0
    }

    /// cos, as [`Scalar::sine_cosine`].
    #[inline]
    fn cosine(self) -> Self {
        self.sine_cosine().1
    }

    /// True for `f64` only. The simulator compiles a second copy of its stepper for plain
    /// rigs, with the real-rig tests gone from the right-hand side, for this type alone: the
    /// dual types' runs are few and their copies would only lengthen the build.
    const SPECIALISE_PLAIN: bool = false;
}

impl Scalar for f64 {
    const SPECIALISE_PLAIN: bool = true;

    #[inline(always)]
    fn is_exact_zero(&self) -> bool {
        *self == 0.0
    }

    #[inline(always)]
    fn sine_cosine(self) -> (f64, f64) {
        libm::sincos(self)
    }

    #[inline(always)]
    fn sine(self) -> f64 {
        libm::sin(self)
    }

    #[inline(always)]
    fn cosine(self) -> f64 {
        libm::cos(self)
    }
}

impl Scalar for num_dual::Dual64 {
    #[inline]
    fn is_exact_zero(&self) -> bool {
        self.re == 0.0 && self.eps == 0.0
    }

    #[inline]
    fn sine_cosine(self) -> (Self, Self) {
        let (s, c) = libm::sincos(self.re);
        (Self::new(s, c * self.eps), Self::new(c, -s * self.eps))
    }
}

impl<const N: usize> Scalar for dual::Dual<N> {
    #[inline]
    fn is_exact_zero(&self) -> bool {
        self.re == 0.0 && self.eps.iter().all(|&d| d == 0.0)
    }

    #[inline]
    fn sine_cosine(self) -> (Self, Self) {
        let (s, c) = libm::sincos(self.re);
        (Self::new(s, self.eps * c), Self::new(c, self.eps * -s))
    }
}

/// The state (x, theta, x', theta') in the paper's convention (y down, radians).
pub type State<T> = [T; 4];

/// Index of the slider position x in a [`State`].
pub const X: usize = 0;
/// Index of the rod angle theta in a [`State`].
pub const THETA: usize = 1;
/// Index of the slider velocity x' in a [`State`].
pub const X_DOT: usize = 2;
/// Index of the angular velocity theta' in a [`State`].
pub const THETA_DOT: usize = 3;

/// Real parts of a state, for reports and for decisions that must not depend on derivatives.
pub fn re_state<T: Scalar>(y: &[T]) -> State<f64> {
    [y[0].re(), y[1].re(), y[2].re(), y[3].re()]
}

/// Sign as +1/-1 with +1 for zero: the convention for sigma = sign(N) and s = sign(x').
#[inline]
pub fn sign(v: f64) -> f64 {
    if v < 0.0 {
        -1.0
    } else {
        1.0
    }
}
