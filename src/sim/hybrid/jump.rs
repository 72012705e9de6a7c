//! Crossing an event: the reset of the state, and for dual scalars the jump of the
//! sensitivities through the event time's derivative.

use super::decide::{impulsive_stop, Reset};
use super::guards::{Ctx, Guard};
use super::locate::Located;
use super::step::re_vec;
use super::system::ModeSystem;
use super::Run;
use crate::model::{Mode, Rig, Scalar, X_DOT};
use crate::sim::rk::OdeSystem;

/// The state after an event for dual scalars: the event time's derivative follows from
/// implicit differentiation of the guard (dt* = -dg / g'), and the state is carried to the
/// common real time t* along the old flow, reset, and carried back along the new one
/// (the jump condition of forward sensitivities).
pub(super) fn jump_with_sensitivity<T: Scalar, const N: usize>(
    ctx: &Ctx<'_, T>,
    guard: Guard,
    (old_mode, old_sigma): (Mode, f64),
    (new_mode, new_sigma): (Mode, f64),
    reset: Reset,
    y_star: &[T; N],
) -> [T; N] {
    let old = ModeSystem::new(ctx.rig, old_mode, old_sigma);
    let new = ModeSystem::new(ctx.rig, new_mode, new_sigma);
    let mut f_old = *y_star;
    OdeSystem::<T, N>::rhs(&old, y_star, &mut f_old);
    let g = guard.value(
        (ctx.rig, &ctx.k),
        &y_star[..4],
        (old_mode, old_sigma),
        ctx.thr,
        ctx.plain,
    );
    let (_, gdot) = ctx.guard_with_rate(
        guard,
        &re_vec(y_star)[..4],
        &re_vec(&f_old)[..4],
        old_mode,
        old_sigma,
    );
    let dt = if gdot != 0.0 && gdot.is_finite() {
        (g - T::from(g.re())) * (-1.0 / gdot)
    } else {
        T::from(0.0)
    };
    let mut ym: [T; N] = std::array::from_fn(|i| y_star[i] + f_old[i] * dt);
    // The reset map in dual arithmetic: an impulsive stop carries d(theta')/dp through
    // theta'+ = theta'- - sin(theta) x'- / l.
    apply_reset(ctx.rig, reset, &mut ym);
    let mut f_new = ym;
    OdeSystem::<T, N>::rhs(&new, &ym, &mut f_new);
    std::array::from_fn(|i| ym[i] - f_new[i] * dt)
}

/// Apply an event's reset to a state (the friction work, when carried, is continuous).
pub(super) fn apply_reset<T: Scalar, const N: usize>(rig: &Rig<T>, reset: Reset, y: &mut [T; N]) {
    match reset {
        Reset::None => {}
        Reset::ZeroVelocity => y[X_DOT] = T::from(0.0),
        Reset::Impulsive => {
            let (after, _) = impulsive_stop(rig, &y[..4]);
            y[..4].copy_from_slice(&after);
        }
    }
}

impl<T: Scalar + 'static, const N: usize> Run<'_, '_, T, N> {
    /// The state the `next` mode (and branch) starts from after `event`: the event's state
    /// with its reset applied, in f64 as it is, for dual scalars with the sensitivities' jump.
    pub(super) fn carry_across(
        &self,
        event: &Located<T, N>,
        next: (Mode, f64),
        reset: Reset,
    ) -> [T; N] {
        if super::is_f64::<T>() {
            let mut y = event.y;
            apply_reset(self.ctx.rig, reset, &mut y);
            y
        } else {
            jump_with_sensitivity(
                self.ctx,
                event.guard,
                (self.mode, self.sigma),
                next,
                reset,
                &event.y,
            )
        }
    }
}
