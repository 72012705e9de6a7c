//! Checking the guards: each mode's guard functions (positive while the mode holds), their
//! last values, and the context fixed for a run that evaluates them.

use crate::model::{Mode, Rig, RigConstants, Scalar, Shorthands, THETA, THETA_DOT, X_DOT};
use num_dual::Dual64;

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
            Guard::StickMargin => Shorthands::new_on(rig, y[THETA], y[THETA_DOT], plain, k)
                .stick_margin(rig.mu_static),
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
                let delta = sh.d
                    + sh.a
                        * (rig.friction_mu_on(y[X_DOT] * s, k.inverse_stribeck_velocity)
                            * (s * sigma));
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

impl<T: Scalar> Ctx<'_, T> {
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

    pub(super) fn guards(&self, mode: Mode) -> &'static [Guard] {
        match (mode, self.paradox_possible) {
            (Mode::Stick, _) => &[Guard::StickMargin],
            (Mode::Slide(_), false) => &[Guard::Stop, Guard::NormalSign],
            (Mode::Slide(_), true) => &[Guard::Stop, Guard::NormalSign, Guard::Denominator],
        }
    }
}
