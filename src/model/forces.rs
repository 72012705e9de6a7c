//! Contact forces and accelerations of both models (docs/physics.md, "Equations of motion").
//!
//! All functions are generic over [`Scalar`] so that the same formulas serve the simulator in
//! `f64` and the fit in dual numbers.

use super::{sign, Mode, Rig, RigConstants, Scalar, State, THETA, THETA_DOT, X, X_DOT};

/// The shorthands D, a, b, c, Q and A of docs/physics.md at one (theta, theta'), with sin and cos
/// kept because every acceleration needs them again. With tilt and pivot damping they are the
/// generalised forms of "Real rigs"; on the ideal rig they reduce to the paper's.
#[derive(Debug, Clone, Copy)]
pub struct Shorthands<T> {
    /// D = m1 + m2 cos^2(theta) > 0.
    pub d: T,
    /// a = m2 sin(theta) cos(theta).
    pub a: T,
    /// b = m2 cos(theta) A - m2 l w^2 sin(theta) - (m1 + m2) g_y: the normal force while stuck.
    pub b: T,
    /// c = m2 sin(theta) A + m2 l w^2 cos(theta) + (m1 + m2) g_x: minus the friction needed to
    /// stay stuck.
    pub c: T,
    /// Q = a c + b D: the normal force times the denominator while sliding (without the
    /// viscous rail term, which depends on x').
    pub q: T,
    /// A = g_y cos(theta) - g_x sin(theta) - c_p w / (m2 l): l theta'' while stuck.
    pub pend: T,
    /// sin(theta).
    pub sin: T,
    /// cos(theta).
    pub cos: T,
}

impl<T: Scalar> Shorthands<T> {
    /// Evaluate the shorthands at angle `theta` and angular velocity `w`.
    #[inline(always)]
    pub fn new(rig: &Rig<T>, theta: T, w: T) -> Self {
        Self::new_on(rig, theta, w, false, &rig.constants())
    }

    /// [`Shorthands::new`] for a caller that already knows whether the rig is plain
    /// ([`Rig::is_plain`]) and has the rig's constants ([`Rig::constants`]) at hand:
    /// `plain = true` skips the per-call tests of tilt and damping, and the tilt's sine and
    /// cosine and the damping's divisions are not recomputed, which the simulator's inner
    /// loop would otherwise do on every right-hand side.
    #[inline(always)]
    pub fn new_on(rig: &Rig<T>, theta: T, w: T, plain: bool, k: &RigConstants<T>) -> Self {
        let (sin, cos) = theta.sine_cosine();
        let (m1, m2, l) = (rig.slider_mass, rig.bob_mass, rig.rod_length);
        let lw2 = l * w * w;
        let d = m1 + m2 * cos * cos;
        let a = m2 * sin * cos;
        if plain || (rig.rail_tilt.is_exact_zero() && rig.pivot_damping.is_exact_zero()) {
            // The ideal rig: the paper's forms, one test for the whole evaluation.
            let g = rig.gravity;
            return Shorthands {
                d,
                a,
                b: -(m1 * g + m2 * sin * (g * sin + lw2)),
                c: m2 * cos * (g * sin + lw2),
                q: -m1 * ((m1 + m2) * g + m2 * l * w * w * sin),
                pend: g * cos,
                sin,
                cos,
            };
        }
        // The ideal rig's forms, which keep full precision for a light slider (b never
        // subtracts (m1 + m2) g from m2 g cos^2), plus the drive of tilt and damping.
        let (gx, gy) = (k.gx, k.gy);
        let e = rig.extra_drive(sin, w, k);
        let b = -(m1 * gy + m2 * sin * (gy * sin + lw2)) + m2 * cos * e;
        let c = m2 * cos * (gy * sin + lw2) + m2 * sin * e + (m1 + m2) * gx;
        let q = rig.normal_numerator_sc(sin, cos, w, k);
        Shorthands {
            d,
            a,
            b,
            c,
            q,
            pend: gy * cos + e,
            sin,
            cos,
        }
    }

    /// Evaluate at a state's angle and angular velocity.
    #[inline]
    pub fn at(rig: &Rig<T>, y: &[T]) -> Self {
        Self::new(rig, y[THETA], y[THETA_DOT])
    }

    /// Stick margin mu_s |b| - |c| for one static coefficient (Coulomb's law; the rig's law
    /// is [`Rig::stick_margin`]): positive while the pendulum model holds.
    #[inline]
    pub fn stick_margin(&self, mu_static: T) -> T {
        mu_static * self.b.abs() - self.c.abs()
    }

    /// The pull |c| / |b|: the friction coefficient a stuck slider needs to stay put
    /// (infinite where the normal force vanishes).
    #[inline]
    pub fn pull(&self) -> T {
        self.c.abs() / self.b.abs()
    }

    /// Paradox margin D - mu |a|: positive outside the paradox band, where the sliding
    /// equation has exactly one solution.
    #[inline]
    pub fn band_margin(&self, mu: T) -> T {
        self.d - mu * self.a.abs()
    }
}

/// Accelerations and normal force of the sliding-rod model on one branch.
#[derive(Debug, Clone, Copy)]
pub struct SlideDynamics<T> {
    /// Slider acceleration x''.
    pub x_ddot: T,
    /// Angular acceleration theta''.
    pub theta_ddot: T,
    /// Rail reaction N on the slider (y down convention).
    pub normal: T,
    /// Denominator D + mu s sigma a of the branch.
    pub delta: T,
    /// The friction coefficient mu(|x'|) the slide meets at this speed.
    pub mu: T,
}

/// The rail's forces on the slider at one instant ([`Rig::contact`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Contact<T> {
    /// Rail reaction N (N, y down convention as in [`SlideDynamics::normal`]).
    pub normal: T,
    /// Friction force along the rail (N, positive toward +x).
    pub friction: T,
    /// The friction coefficient in use: the law's mu while sliding, |F| / |N| while stuck.
    pub mu: T,
}

/// Which normal-force signs sigma give a self-consistent sliding motion.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SlideBranches {
    /// sigma = +1 is consistent (N >= 0 results).
    pub plus: bool,
    /// sigma = -1 is consistent (N <= 0 results).
    pub minus: bool,
}

impl SlideBranches {
    /// How many consistent solutions the sliding equation has (0, 1 or 2).
    pub fn count(&self) -> usize {
        usize::from(self.plus) + usize::from(self.minus)
    }
}

impl<T: Scalar> Rig<T> {
    /// The numerator of the normal force while sliding, N (D + mu s sigma a) = Q - a c_v x',
    /// at state `y`. Q = a c + b D simplifies to
    /// -m1 ((m1 + m2) g_y + m2 l w^2 sin(theta)) - (m1 + m2) c_p w cos(theta) / l; the closed
    /// form avoids cancellation near Q = 0, where the normal force changes sign (the guard on
    /// N's sign evaluates it every step).
    #[inline]
    pub fn normal_numerator(&self, y: &[T]) -> T {
        self.normal_numerator_on(y, false, &self.constants())
    }

    /// [`Rig::normal_numerator`] with the plain-rig tests hoisted out (`plain = true` only on
    /// a [`Rig::is_plain`] rig) and the rig's constants at hand.
    #[inline(always)]
    pub fn normal_numerator_on(&self, y: &[T], plain: bool, k: &RigConstants<T>) -> T {
        let (theta, w) = (y[THETA], y[THETA_DOT]);
        if plain {
            return self.normal_numerator_sc(theta.sine(), T::zero(), w, k);
        }
        if self.pivot_damping.is_exact_zero() && self.viscous_friction.is_exact_zero() {
            // Only sin(theta) is needed: half the trigonometry.
            return self.normal_numerator_sc(theta.sine(), T::zero(), w, k);
        }
        let (sin, cos) = theta.sine_cosine();
        let q = self.normal_numerator_sc(sin, cos, w, k);
        if self.viscous_friction.is_exact_zero() {
            q
        } else {
            q - self.bob_mass * sin * cos * self.viscous_friction * y[X_DOT]
        }
    }

    /// Q from sin and cos of theta (cos is unused on a rig without pivot damping).
    #[inline(always)]
    fn normal_numerator_sc(&self, sin: T, cos: T, w: T, k: &RigConstants<T>) -> T {
        let (m1, m2) = (self.slider_mass, self.bob_mass);
        let q = -m1 * ((m1 + m2) * k.gy + m2 * self.rod_length * w * w * sin);
        if self.pivot_damping.is_exact_zero() {
            q
        } else {
            q - k.damping_normal * w * cos
        }
    }

    /// The part of A = g_y cos(theta) - g_x sin(theta) - c_p w / (m2 l) that a level, undamped
    /// rail lacks: -g_x sin(theta) - c_p w / (m2 l).
    #[inline(always)]
    fn extra_drive(&self, sin: T, w: T, k: &RigConstants<T>) -> T {
        let mut e = T::zero();
        if !self.rail_tilt.is_exact_zero() {
            e -= k.gx * sin;
        }
        if !self.pivot_damping.is_exact_zero() {
            e -= k.damping_drive * w;
        }
        e
    }

    /// Angular acceleration of the pendulum model at (theta, w), theta'' = A / l, without the
    /// other shorthands (the stick phase's right-hand side needs nothing else).
    #[inline(always)]
    pub fn stick_angular_acceleration(&self, theta: T, w: T) -> T {
        self.stick_angular_acceleration_on(theta, w, false, &self.constants())
    }

    /// [`Rig::stick_angular_acceleration`] with the plain-rig test hoisted out (`plain =
    /// true` only on a [`Rig::is_plain`] rig) and the rig's constants at hand.
    #[inline(always)]
    pub fn stick_angular_acceleration_on(
        &self,
        theta: T,
        w: T,
        plain: bool,
        k: &RigConstants<T>,
    ) -> T {
        let tilted = !plain && !self.rail_tilt.is_exact_zero();
        let damped = !plain && !self.pivot_damping.is_exact_zero();
        // g_y cos(theta) - g_x sin(theta) = g cos(theta + alpha): one cosine, no sine.
        let mut a = if tilted {
            self.gravity * (theta + self.rail_tilt).cosine()
        } else {
            self.gravity * theta.cosine()
        };
        if damped {
            a -= k.damping_drive * w;
        }
        a / self.rod_length
    }

    /// Angular acceleration of the pendulum model: theta'' = A / l.
    #[inline]
    pub fn stick_theta_ddot(&self, sh: &Shorthands<T>) -> T {
        sh.pend / self.rod_length
    }

    /// The sliding-rod model on the branch sigma = sign(N), sliding in direction `s`
    /// (both +1 or -1) at velocity `x_dot`: with mu the law's coefficient ([`Rig::slide_mu`]),
    /// x'' = (c - mu s sigma b - c_v x') / (D + mu s sigma a), N = b + a x''
    /// = (Q - a c_v x') / (same), l theta'' = A + sin(theta) x''.
    #[inline(always)]
    pub fn slide(&self, sh: &Shorthands<T>, s: f64, sigma: f64, x_dot: T) -> SlideDynamics<T> {
        self.slide_on(
            sh,
            (s, sigma),
            x_dot,
            false,
            self.inverse_stribeck_velocity(),
        )
    }

    /// [`Rig::slide`] with the plain-rig tests hoisted out: `plain = true` (only on a
    /// [`Rig::is_plain`] rig) skips the friction law and the viscous term;
    /// `inverse_stribeck_velocity` is [`RigConstants::inverse_stribeck_velocity`].
    #[inline(always)]
    pub fn slide_on(
        &self,
        sh: &Shorthands<T>,
        (s, sigma): (f64, f64),
        x_dot: T,
        plain: bool,
        inverse_stribeck_velocity: T,
    ) -> SlideDynamics<T> {
        let mu = if plain {
            self.mu_kinetic
        } else {
            self.slide_mu(sh, (s, sigma), x_dot, inverse_stribeck_velocity)
        };
        let ms = mu * (s * sigma);
        let delta = sh.d + ms * sh.a;
        let l_delta = self.rod_length * delta;
        // One division for both accelerations: x'' = num / delta, theta'' = (...) / l.
        let mut num = sh.c - ms * sh.b;
        let mut q = sh.q;
        if !plain && !self.viscous_friction.is_exact_zero() {
            let drag = self.viscous_friction * x_dot;
            num -= drag;
            q -= sh.a * drag;
        }
        let inv = l_delta.recip();
        let x_ddot = num * self.rod_length * inv;
        let theta_ddot = (sh.pend * delta + sh.sin * num) * inv;
        SlideDynamics {
            x_ddot,
            theta_ddot,
            normal: q * self.rod_length * inv,
            delta,
            mu,
        }
    }

    /// The self-consistent branches of the sliding equation in direction `s` at velocity
    /// `x_dot`: a branch is consistent when the N it produces has the sign sigma it assumed.
    /// Outside the paradox band exactly sigma = sign(Q) is; inside it two or none are.
    pub fn slide_branches(&self, sh: &Shorthands<T>, s: f64, x_dot: T) -> SlideBranches {
        let consistent = |sigma: f64| {
            let dynamics = self.slide(sh, s, sigma, x_dot);
            let n = dynamics.normal.re();
            // Q = 0 gives N = 0, consistent with either sign: keep only the branch with a
            // positive denominator so the count stays one there.
            if n == 0.0 {
                dynamics.delta.re() > 0.0
            } else {
                sign(n) == sigma
            }
        };
        SlideBranches {
            plus: consistent(1.0),
            minus: consistent(-1.0),
        }
    }

    /// The branch sigma used while sliding in direction `s`: the consistent one with a
    /// positive denominator (the only one below mu*), or `None` when no branch is consistent.
    pub fn slide_sigma(&self, sh: &Shorthands<T>, s: f64, x_dot: T) -> Option<f64> {
        let branches = self.slide_branches(sh, s, x_dot);
        let positive = |sigma: f64| self.slide(sh, s, sigma, x_dot).delta.re() > 0.0;
        match (branches.plus, branches.minus) {
            (true, true) => Some(if positive(1.0) { 1.0 } else { -1.0 }),
            (true, false) => Some(1.0),
            (false, true) => Some(-1.0),
            (false, false) => None,
        }
    }

    /// |N| / N_0, the normal force over the static load (m1 + m2) g, of a slide toward `s`
    /// at state `y` on its branch ([`Rig::slide_sigma`]); `None` where no branch is
    /// consistent. How far a motion's slides move it from 1 is what they can say of a load
    /// law.
    pub fn slide_load(&self, y: &[T], s: f64) -> Option<T> {
        let sh = Shorthands::at(self, y);
        let x_dot = y[X_DOT];
        let sigma = self.slide_sigma(&sh, s, x_dot)?;
        Some(self.slide(&sh, s, sigma, x_dot).normal.abs() / self.static_load())
    }

    /// Power of friction F x' while sliding on branch sigma: F = -mu s |N| - c_v x'.
    #[inline]
    pub fn friction_power(&self, dynamics: &SlideDynamics<T>, x_dot: T, s: f64, sigma: f64) -> T {
        let coulomb = -(dynamics.mu * dynamics.normal * x_dot) * (s * sigma);
        if self.viscous_friction.is_exact_zero() {
            coulomb
        } else {
            coulomb - self.viscous_friction * x_dot * x_dot
        }
    }

    /// Accelerations (x'', theta'') of the model that governs `mode` at state `y` (the
    /// consistent branch with positive denominator while sliding).
    pub fn accelerations(&self, mode: Mode, y: &[T]) -> (T, T) {
        match mode {
            Mode::Stick => (
                T::zero(),
                self.stick_angular_acceleration(y[THETA], y[THETA_DOT]),
            ),
            Mode::Slide(dir) => {
                let (d, _) = self.slide_at(dir.sign(), y);
                (d.x_ddot, d.theta_ddot)
            }
        }
    }

    /// The sliding model's dynamics toward `s` at state `y` on the branch the simulator takes
    /// (the consistent one with a positive denominator, else sigma = sign(Q)), with that sigma.
    fn slide_at(&self, s: f64, y: &[T]) -> (SlideDynamics<T>, f64) {
        let sh = Shorthands::at(self, y);
        let sigma = self
            .slide_sigma(&sh, s, y[X_DOT])
            .unwrap_or_else(|| sign(sh.q.re()));
        (self.slide(&sh, s, sigma, y[X_DOT]), sigma)
    }

    /// The rail's forces on the slider in `mode` at state `y` (docs/physics.md): while stuck
    /// N = b and the friction that holds the slider, F = -c, with `mu` the share |F| / |N| it
    /// uses; while sliding toward s the branch's N, F = -mu s |N| - c_v x' and the law's mu at
    /// that speed and load.
    pub fn contact(&self, mode: Mode, y: &[T]) -> Contact<T> {
        match mode {
            Mode::Stick => {
                let sh = Shorthands::at(self, y);
                let friction = -sh.c;
                Contact {
                    normal: sh.b,
                    friction,
                    mu: friction.abs() / sh.b.abs(),
                }
            }
            Mode::Slide(dir) => {
                let s = dir.sign();
                let (d, sigma) = self.slide_at(s, y);
                let mut friction = -(d.mu * d.normal) * (s * sigma);
                if !self.viscous_friction.is_exact_zero() {
                    friction -= self.viscous_friction * y[X_DOT];
                }
                Contact {
                    normal: d.normal,
                    friction,
                    mu: d.mu,
                }
            }
        }
    }

    /// Power of the pivot's damping torque, -c_p w^2 (zero on an undamped rig).
    #[inline]
    pub fn damping_power(&self, w: T) -> T {
        -(self.pivot_damping * w * w)
    }
}

/// Mechanical energy with the tilted potential,
/// E = 1/2 (m1 + m2) x'^2 - m2 l x' w sin(theta) + 1/2 m2 l^2 w^2 - (m1 + m2) g_x x
/// − m2 g_x l cos(theta) − m2 g_y l sin(theta), zero at rest at x = 0 with the rod
/// horizontal on a level rail; dE/dt = F x' - c_p w^2. On a rigid pendulum's equivalent rig
/// this is the rigid body's energy (docs/physics.md, "The rigid pendulum": m_e L = m_p d, m_e L^2 = J).
pub fn energy<T: Scalar>(rig: &Rig<T>, y: &State<T>) -> T {
    let (m1, m2, l) = (rig.slider_mass, rig.bob_mass, rig.rod_length);
    let (gx, gy) = rig.gravity_components();
    let (xd, w) = (y[X_DOT], y[THETA_DOT]);
    let (sin, cos) = y[THETA].sine_cosine();
    (m1 + m2) * xd * xd * 0.5 - m2 * l * xd * w * sin + m2 * l * l * w * w * 0.5
        - m2 * gy * l * sin
        - gx * ((m1 + m2) * y[X] + m2 * l * cos)
}

/// Horizontal momentum (m1 + m2) x' - m2 l w sin(theta): conserved when mu = 0 on a level rail
/// without rail friction. On a rigid pendulum's equivalent rig it is
/// (m1 + m_p) x' - m_p d w sin(theta).
pub fn momentum<T: Scalar>(rig: &Rig<T>, y: &State<T>) -> T {
    (rig.slider_mass + rig.bob_mass) * y[X_DOT]
        - rig.bob_mass * rig.rod_length * y[THETA_DOT] * y[THETA].sine()
}
