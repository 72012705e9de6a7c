//! A stick phase in the pendulum's closed form: while the slider is stuck on a rig with an
//! undamped pivot, the rig is the conservative pendulum of `model::pendulum`, whose state is
//! an elementary function of Jacobi's amplitude psi ([`Swing`]). The slip guard is watched and
//! its crossing located in psi with the integrator's own guard logic (`GuardState::watch`,
//! `find_root`); only the crossing's time needs an elliptic integral.

use super::guards::{Guard, Interior, Watch};
use super::locate::{find_root, Located};
use super::step::re_vec;
use super::{is_f64, Run, Segment};
use crate::model::pendulum::Swing;
use crate::model::{Mode, Scalar, THETA, THETA_DOT};
use crate::sim::rk::Stepper;
use crate::sim::{SimError, Solution};
use std::ops::ControlFlow;

/// The span of psi watched at once: 64 to a period, about the integrator's steps on the
/// paper scene's stick phases (0.08 rad of psi), so that a guard's narrow dip between two
/// ends is caught by their rates as it is between two steps. An eighth of a period missed a
/// slip where friction is 0.1 % below the swing's largest needed ratio.
const SPAN: f64 = std::f64::consts::PI / 32.0;

/// Stretches to a period of the swing.
const PER_PERIOD: u32 = 64;

/// The slip guard along a stretch [a, a + SPAN] of the swing, for the sign-change search.
#[derive(Clone, Copy)]
struct Along<'r> {
    swing: &'r Swing,
    a: f64,
    value: &'r dyn Fn(f64) -> f64,
}

impl Interior for Along<'_> {
    fn prepare(&mut self) {}

    fn at(&self, th: f64) -> f64 {
        (self.value)(self.a + th * SPAN)
    }
}

impl Along<'_> {
    /// The state's angle and rate at fraction `th` of the stretch.
    fn state(&self, th: f64) -> (f64, f64) {
        self.swing.state(self.a + th * SPAN)
    }
}

impl<'a, T: Scalar + 'static, const N: usize> Run<'a, '_, T, N> {
    /// Take the stick phase that has just begun in closed form, when it applies: an `f64` run
    /// (no derivatives to carry) of a rig with an undamped pivot (a conservative pendulum,
    /// level or tilted; any friction law) that samples nothing from here on, with the slip
    /// guard positive at the start, on a swing below the top. Returns `None` otherwise (the
    /// integrator takes the phase), or what the phase ended in: the next mode (`Continue`)
    /// or the end of the run (`Break`).
    pub(super) fn closed_stick<M: Stepper<T, N>>(
        &mut self,
        seg: &mut Segment<'a, '_, T, M, N>,
    ) -> Result<Option<ControlFlow<Solution<T>>>, SimError> {
        let ctx = self.ctx;
        let rig = &ctx.rig_re;
        // An undamped pivot keeps the stuck rig conservative (on a tilted rail, the pendulum
        // about the shifted vertical); the friction law enters only through the guard.
        if self.mode != Mode::Stick
            || !self.options.prove_stick
            || !is_f64::<T>()
            || rig.pivot_damping != 0.0
            || self.out.next_sample < self.request.sample_times.len()
        {
            return Ok(None);
        }
        let [mut st] = seg.gs[..] else {
            return Ok(None);
        };
        if st.guard != Guard::StickMargin || !st.armed {
            return Ok(None);
        }
        let y = re_vec(&self.y);
        let Some(swing) = Swing::new(rig, y[THETA], y[THETA_DOT]) else {
            return Ok(None);
        };
        let sigma = self.sigma;
        let at = |theta: f64, w: f64| {
            let mut s = y;
            s[THETA] = theta;
            s[THETA_DOT] = w;
            s
        };
        let value = |psi: f64| {
            let (theta, w) = swing.state(psi);
            Guard::StickMargin.value(
                (rig, &ctx.k_re),
                &at(theta, w)[..4],
                (Mode::Stick, sigma),
                ctx.thr,
                ctx.plain,
            )
        };
        let span = self.t_end - self.t;
        // A whole period at most: the swing then repeats, and a guard that held over it
        // holds for ever.
        for j in 0..PER_PERIOD {
            let a = swing.psi0() + f64::from(j) * SPAN;
            let along = Along {
                swing: &swing,
                a,
                value: &value,
            };
            let (theta, w) = along.state(1.0);
            let y1 = at(theta, w);
            let mut f1 = [0.0; 4];
            f1[THETA] = w;
            f1[THETA_DOT] = rig.stick_angular_acceleration(theta, w);
            let (g1, gdot1) = ctx.guard_with_rate(st.guard, &y1[..4], &f1, Mode::Stick, sigma);
            let th = match st.watch(g1, gdot1, false, || along) {
                Watch::Bracket {
                    a: ta,
                    ga,
                    b: tb,
                    gb,
                } => {
                    // The integrator's tolerance: about 1e-14 s, or the rounding of t, in psi
                    // at its slowest rate.
                    let t_b = swing.elapsed_bounds(a + SPAN).1;
                    let tol_s = 1e-14 + 4.0 * f64::EPSILON * (self.t + t_b).abs();
                    let tol = tol_s * swing.slowest_rate() / SPAN;
                    find_root(ta, ga, tb, gb, tol, |th| along.at(th))
                }
                Watch::Holds => {
                    let (early, late) = swing.elapsed_bounds(a + SPAN);
                    if early >= span || late >= span && swing.elapsed(a + SPAN) >= span {
                        break;
                    }
                    st.advance((g1, gdot1));
                    continue;
                }
                // An armed guard is bracketed or holds.
                Watch::AtOnce | Watch::TooLong => return Ok(None),
            };
            let dt = swing.elapsed(a + th * SPAN);
            if dt >= span {
                break;
            }
            let (theta, w) = along.state(th);
            let mut y_event = self.y;
            y_event[THETA] = T::from(theta);
            y_event[THETA_DOT] = T::from(w);
            let event = Located {
                t: self.t + dt,
                y: y_event,
                guard: st.guard,
            };
            self.out.stats.closed_form += 1;
            return self.switch_mode(seg, &y1, event).map(Some);
        }
        // No slip before the end: the state there from Jacobi's functions.
        let (theta, w) = swing.after(span);
        self.out.stats.closed_form += 1;
        self.y[THETA] = T::from(theta);
        self.y[THETA_DOT] = T::from(w);
        self.t = self.t_end;
        Ok(Some(ControlFlow::Break(self.end(seg))))
    }
}
