//! Checking the guards: each mode's guard functions (positive while the mode holds), what a
//! guard did over a step (the bracket of its sign change, found on the dense output), the
//! context fixed for a run that evaluates them, and the proof that lets a stick phase drop
//! its guard.

use super::locate::golden_min;
use super::{Run, Segment};
use crate::model::{
    pendulum, re_state, regions, FrictionLaw, Mode, Rig, RigConstants, Scalar, Shorthands, THETA,
    THETA_DOT, X_DOT,
};
use crate::sim::rk::Stepper;
use crate::sim::{Options, Solution};
use num_dual::Dual64;
use std::ops::ControlFlow;

/// Accepted steps of a stick phase after which the simulator tries to prove it never ends.
pub(super) const PROOF_AFTER_STEPS: usize = 24;

/// A guard: a function positive while the current mode holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Guard {
    /// Stick: mu_s |b| - |c|.
    StickMargin,
    /// Slide: s x'.
    Stop,
    /// Slide: sigma Q (the normal force keeps its sign).
    NormalSign,
    /// Slide above mu*: |D + mu s sigma a| - threshold (m1 + m2): the branch's denominator
    /// stays clear of zero, where |N| grows without bound (the sudden stop).
    Denominator,
}

impl Guard {
    /// The guard's value; `plain` is [`Rig::is_plain`] of the run's rig, tested once per run.
    /// Inlined so that each call site keeps only its guard's formula (the event search calls
    /// it hundreds of times a run).
    #[inline(always)]
    pub(super) fn value<S: Scalar>(
        self,
        (rig, k): (&Rig<S>, &RigConstants<S>),
        y: &[S],
        (mode, sigma): (Mode, f64),
        thr: f64,
        plain: bool,
    ) -> S {
        match self {
            Guard::StickMargin => {
                rig.stick_margin(&Shorthands::new_on(rig, y[THETA], y[THETA_DOT], plain, k))
            }
            Guard::Stop => {
                let s = match mode {
                    Mode::Slide(d) => d.sign(),
                    Mode::Stick => 1.0,
                };
                y[X_DOT] * s
            }
            Guard::NormalSign => rig.normal_numerator_on(y, plain, k) * sigma,
            Guard::Denominator => {
                let s = match mode {
                    Mode::Slide(d) => d.sign(),
                    Mode::Stick => 1.0,
                };
                let sh = Shorthands::new_on(rig, y[THETA], y[THETA_DOT], plain, k);
                let mu = rig.slide_mu(&sh, (s, sigma), y[X_DOT], k.inverse_stribeck_velocity);
                let delta = sh.d + sh.a * (mu * (s * sigma));
                delta.abs() - (rig.slider_mass + rig.bob_mass) * thr
            }
        }
    }
}

/// A guard's last value, its time derivative and whether it has been seen positive (a
/// guard starting at zero, like x' at the start of a slide, fires only after it has risen).
#[derive(Debug, Clone, Copy)]
pub(super) struct GuardState {
    pub(super) guard: Guard,
    pub(super) g: f64,
    pub(super) gdot: f64,
    pub(super) armed: bool,
}

/// What a guard did over one step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Watch {
    /// It stayed positive, or (not yet armed) it rose without falling again.
    Holds,
    /// It changed sign inside [a, b] (fractions of the step): `ga > 0` at a, `gb <= 0` at b.
    Bracket { a: f64, ga: f64, b: f64, gb: f64 },
    /// Never positive, in a step too short to shorten: the mode ends the instant it starts.
    AtOnce,
    /// Never positive, in a step long enough to shorten: the mode may end within a
    /// sixteenth of it, so the step is retried shorter.
    TooLong,
}

/// A guard's values inside the current step, for the search of a sign change there.
pub(super) trait Interior {
    /// Make the values inside the step available (the dense output may cost evaluations, so
    /// only when a search needs them).
    fn prepare(&mut self);
    /// The guard at fraction `th` of the step (after [`Interior::prepare`]).
    fn at(&self, th: f64) -> f64;
}

impl GuardState {
    /// The guards of `mode`, with their values and rates at the mode's start (`y`, `f`: real
    /// parts of the state and its rate). A guard that starts at zero is not armed.
    pub(super) fn start<T: Scalar>(
        ctx: &Ctx<'_, T>,
        mode: Mode,
        sigma: f64,
        y: &[f64],
        f: &[f64],
    ) -> Vec<GuardState> {
        ctx.guards(mode)
            .iter()
            .map(|&guard| {
                let (g, gdot) = ctx.guard_with_rate(guard, y, f, mode, sigma);
                GuardState {
                    guard,
                    g,
                    gdot,
                    armed: g > 0.0,
                }
            })
            .collect()
    }

    /// Take the value and rate `(g, gdot)` at the end of an accepted step with no event.
    pub(super) fn advance(&mut self, (g, gdot): (f64, f64)) {
        self.g = g;
        self.gdot = gdot;
        self.armed |= g > 0.0;
    }

    /// What the guard did over a step that ends with value `g1` and rate `gdot1`. `inside`
    /// makes its values within the step, called only when the ends do not tell (it costs a
    /// few stores on every step otherwise): a guard starting at zero must rise before it can
    /// fall, and a grazing guard (falling at the start, rising at the end, positive at both)
    /// may dip below zero in between. `long`: the step is long enough to be retried shorter.
    #[inline]
    pub(super) fn watch<I: Interior>(
        &self,
        g1: f64,
        gdot1: f64,
        long: bool,
        inside: impl FnOnce() -> I,
    ) -> Watch {
        let st = self;
        let grazing = st.armed && g1 > 0.0 && st.gdot < 0.0 && gdot1 > 0.0;
        if st.armed && g1 <= 0.0 {
            return Watch::Bracket {
                a: 0.0,
                ga: st.g,
                b: 1.0,
                gb: g1,
            };
        }
        if !(!st.armed && g1 <= 0.0 || grazing) {
            return Watch::Holds;
        }
        // Look inside the step, at sixteen points.
        let mut inside = inside();
        inside.prepare();
        let k = 16;
        let mut prev = (0.0, if st.armed { st.g } else { f64::NAN });
        let mut found = None;
        let mut lowest = (0.0, if st.armed { st.g } else { f64::INFINITY });
        for j in 1..=k {
            let th = j as f64 / k as f64;
            let gj = if j == k { g1 } else { inside.at(th) };
            if gj < lowest.1 {
                lowest = (th, gj);
            }
            if gj > 0.0 {
                prev = (th, gj);
            } else if prev.1 > 0.0 {
                found = Some((prev.0, prev.1, th, gj));
                break;
            }
        }
        if found.is_none() && grazing {
            // A dip narrower than the sampling: minimise the guard around its
            // lowest sample (golden section; the dip is a single minimum there)
            // and bracket the crossing if the minimum is below zero.
            let h = 1.0 / k as f64;
            let (lo, hi) = ((lowest.0 - h).max(0.0), (lowest.0 + h).min(1.0));
            let (th_min, g_min) = golden_min(lo, hi, 1e-10, |th| inside.at(th));
            if g_min <= 0.0 {
                let g_lo = if lo == 0.0 { st.g } else { inside.at(lo) };
                if g_lo > 0.0 {
                    found = Some((lo, g_lo, th_min, g_min));
                }
            }
        }
        match found {
            Some((a, ga, b, gb)) => Watch::Bracket { a, ga, b, gb },
            // Never positive: the mode is left the instant it starts.
            None if !st.armed && long => Watch::TooLong,
            None if !st.armed => Watch::AtOnce,
            None => Watch::Holds,
        }
    }
}

/// Everything fixed for one run.
pub(super) struct Ctx<'a, T> {
    pub(super) rig: &'a Rig<T>,
    pub(super) rig_re: Rig<f64>,
    pub(super) rig_dual: Rig<Dual64>,
    pub(super) paradox_possible: bool,
    /// Sudden-stop threshold of the denominator guard, relative to m1 + m2.
    pub(super) thr: f64,
    /// [`Rig::is_plain`] of `rig`: the guards skip the real-rig terms' tests.
    pub(super) plain: bool,
    /// [`Rig::constants`] of `rig`, `rig_re` and `rig_dual`, for the guards.
    pub(super) k: RigConstants<T>,
    /// See `k`.
    pub(super) k_re: RigConstants<f64>,
    /// See `k`.
    pub(super) k_dual: RigConstants<Dual64>,
}

impl<'a, T: Scalar> Ctx<'a, T> {
    /// The context of a run of `rig` with `options`.
    pub(super) fn new(rig: &'a Rig<T>, options: &Options) -> Self {
        let rig_re = rig.re();
        let rig_dual = rig_re.lift();
        Ctx {
            rig,
            rig_re,
            rig_dual,
            k: rig.constants(),
            k_re: rig_re.constants(),
            k_dual: rig_dual.constants(),
            // The load law's coefficient grows without bound as |N| -> 0 for n < 1: its
            // denominator is watched on every rig.
            paradox_possible: rig_re.friction_law == FrictionLaw::Load
                || rig_re.mu_slide_max() > regions::mu_critical(rig_re.mass_ratio()),
            thr: options.stop_threshold,
            plain: rig.is_plain(),
        }
    }

    /// Guard value and its rate along the flow, from one dual evaluation at (y, f).
    pub(super) fn guard_with_rate(
        &self,
        guard: Guard,
        y: &[f64],
        f: &[f64],
        mode: Mode,
        sigma: f64,
    ) -> (f64, f64) {
        let yd: [Dual64; 4] = std::array::from_fn(|i| Dual64::new(y[i], f[i]));
        let g = guard.value(
            (&self.rig_dual, &self.k_dual),
            &yd,
            (mode, sigma),
            self.thr,
            self.plain,
        );
        (g.re, g.eps)
    }

    /// The guards that watch `mode` (the denominator only where the paradox is possible).
    pub(super) fn guards(&self, mode: Mode) -> &'static [Guard] {
        match (mode, self.paradox_possible) {
            (Mode::Stick, _) => &[Guard::StickMargin],
            (Mode::Slide(_), false) => &[Guard::Stop, Guard::NormalSign],
            (Mode::Slide(_), true) => &[Guard::Stop, Guard::NormalSign, Guard::Denominator],
        }
    }
}

impl<T: Scalar + 'static, const N: usize> Run<'_, '_, T, N> {
    /// Once a stick phase has lasted [`PROOF_AFTER_STEPS`], try to prove it never ends: if
    /// so its guard is dropped, and when nothing is sampled from here on and no derivatives
    /// are carried, the run ends at once in the pendulum's closed form (`Break`).
    pub(super) fn prove_stick<M: Stepper<T, N>>(
        &mut self,
        seg: &mut Segment<'_, '_, T, M, N>,
    ) -> ControlFlow<Solution<T>> {
        if seg.proof_due.is_none_or(|due| self.out.stats.steps < due) {
            return ControlFlow::Continue(());
        }
        seg.proof_due = None;
        let y_re = re_state(&self.y);
        let rig_re = &self.ctx.rig_re;
        if !regions::stick_holds_forever(rig_re, y_re[1], y_re[3]) {
            return ControlFlow::Continue(());
        }
        // The energy level never reaches the friction cone: nothing to watch, and when
        // nothing is sampled from here on and no derivatives are carried, the rest is the
        // pendulum's closed form.
        seg.gs.clear();
        if super::is_f64::<T>() && self.out.next_sample >= self.request.sample_times.len() {
            if let Some((theta, w)) =
                pendulum::stuck_state(rig_re, y_re[1], y_re[3], self.t_end - self.t)
            {
                self.y[1] = T::from(theta);
                self.y[3] = T::from(w);
                self.t = self.t_end;
                return ControlFlow::Break(self.end(seg));
            }
        }
        ControlFlow::Continue(())
    }
}
