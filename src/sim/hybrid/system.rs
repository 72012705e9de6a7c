//! The problem of one mode: the right-hand side the stepper integrates while the rig sticks
//! or slides, with a copy compiled for plain rigs (the f64 fast path).

use crate::model::{Mode, Rig, RigConstants, Scalar, Shorthands};
use crate::sim::rk::OdeSystem;

/// The right-hand side of one mode; a fifth and sixth component, when present, are the
/// friction work and the pivot's damping work. `PLAIN = true` only on a [`Rig::is_plain`]
/// rig: the real-rig tests are then compiled out of every evaluation (in the unrolled stages
/// they cost the plain paper scene 3 % of its run time even when never taken).
pub(super) struct ModeSystem<'a, T, const PLAIN: bool = false> {
    rig: &'a Rig<T>,
    mode: Mode,
    sigma: f64,
    /// [`Rig::is_plain`], tested once here rather than in every right-hand side.
    pub(super) plain: bool,
    /// The rig's constants (a tilt's sine and cosine and the damping and Stribeck factors,
    /// once per mode rather than in every right-hand side).
    constants: RigConstants<T>,
}

impl<'a, T: Scalar> ModeSystem<'a, T> {
    pub(super) fn new(rig: &'a Rig<T>, mode: Mode, sigma: f64) -> Self {
        ModeSystem {
            rig,
            mode,
            sigma,
            plain: rig.is_plain(),
            constants: rig.constants(),
        }
    }

    /// The same system compiled for a plain rig; only called when `self.plain` holds.
    pub(super) fn as_plain(&self) -> ModeSystem<'a, T, true> {
        debug_assert!(self.plain);
        ModeSystem {
            rig: self.rig,
            mode: self.mode,
            sigma: self.sigma,
            plain: true,
            constants: self.constants,
        }
    }
}

impl<T: Scalar, const N: usize, const PLAIN: bool> OdeSystem<T, N> for ModeSystem<'_, T, PLAIN> {
    #[inline(always)]
    fn rhs(&self, y: &[T; N], dy: &mut [T; N]) {
        let plain = PLAIN || self.plain;
        dy[0] = y[2];
        dy[1] = y[3];
        match self.mode {
            Mode::Stick => {
                // x' stays exactly zero; only the pendulum equation is left.
                dy[2] = T::from(0.0);
                dy[3] = self
                    .rig
                    .stick_angular_acceleration_on(y[1], y[3], plain, &self.constants);
                if N > 4 {
                    dy[4] = T::from(0.0);
                    dy[5] = self.rig.damping_power(y[3]);
                }
            }
            Mode::Slide(dir) => {
                let s = dir.sign();
                let k = &self.constants;
                let sh = Shorthands::new_on(self.rig, y[1], y[3], plain, k);
                let dynamics = self.rig.slide_on(
                    &sh,
                    (s, self.sigma),
                    y[2],
                    plain,
                    k.inverse_stribeck_velocity,
                );
                dy[2] = dynamics.x_ddot;
                dy[3] = dynamics.theta_ddot;
                if N > 4 {
                    dy[4] = self.rig.friction_power(&dynamics, y[2], s, self.sigma);
                    dy[5] = self.rig.damping_power(y[3]);
                }
            }
        }
    }
}
