//! Contact forces and accelerations of both models (PHYSICS.md, "Equations of motion").
//!
//! All functions are generic over [`Scalar`] so that the same formulas serve the simulator in
//! `f64` and the fit in dual numbers.

use super::{sign, Rig, Scalar, State, THETA, THETA_DOT, X_DOT};

/// The shorthands D, a, b, c, Q of PHYSICS.md at one (theta, theta'), with sin and cos kept
/// because every acceleration needs them again.
#[derive(Debug, Clone, Copy)]
pub struct Shorthands<T> {
    /// D = m1 + m2 cos^2(theta) > 0.
    pub d: T,
    /// a = m2 sin(theta) cos(theta).
    pub a: T,
    /// b = -(m1 g + m2 g sin^2(theta) + m2 l w^2 sin(theta)): the normal force while stuck.
    pub b: T,
    /// c = m2 cos(theta) (g sin(theta) + l w^2): minus the friction needed to stay stuck.
    pub c: T,
    /// Q = a c + b D: the numerator of the normal force while sliding.
    pub q: T,
    /// sin(theta).
    pub sin: T,
    /// cos(theta).
    pub cos: T,
}

impl<T: Scalar> Shorthands<T> {
    /// Evaluate the shorthands at angle `theta` and angular velocity `w`.
    #[inline]
    pub fn new(rig: &Rig<T>, theta: T, w: T) -> Self {
        let (sin, cos) = theta.sin_cos();
        let (m1, m2, l, g) = (rig.slider_mass, rig.bob_mass, rig.rod_length, rig.gravity);
        let lw2 = l * w * w;
        let d = m1 + m2 * cos * cos;
        let a = m2 * sin * cos;
        let b = -(m1 * g + m2 * sin * (g * sin + lw2));
        let c = m2 * cos * (g * sin + lw2);
        let q = rig.normal_numerator_sin(sin, w);
        Shorthands {
            d,
            a,
            b,
            c,
            q,
            sin,
            cos,
        }
    }

    /// Evaluate at a state's angle and angular velocity.
    #[inline]
    pub fn at(rig: &Rig<T>, y: &[T]) -> Self {
        Self::new(rig, y[THETA], y[THETA_DOT])
    }

    /// Stick margin mu_s |b| - |c|: positive while the pendulum model holds.
    #[inline]
    pub fn stick_margin(&self, mu_static: T) -> T {
        mu_static * self.b.abs() - self.c.abs()
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
    /// Q = a c + b D, the numerator of the normal force while sliding. It simplifies to
    /// -m1 ((m1 + m2) g + m2 l w^2 sin(theta)); the closed form avoids cancellation near Q = 0,
    /// where the normal force changes sign, and needs only sin(theta) (the guard on N's sign
    /// evaluates it every step).
    #[inline]
    pub fn normal_numerator(&self, theta: T, w: T) -> T {
        self.normal_numerator_sin(theta.sin(), w)
    }

    #[inline]
    fn normal_numerator_sin(&self, sin: T, w: T) -> T {
        let (m1, m2) = (self.slider_mass, self.bob_mass);
        -m1 * ((m1 + m2) * self.gravity + m2 * self.rod_length * w * w * sin)
    }

    /// Angular acceleration of the pendulum model: theta'' = (g / l) cos(theta).
    #[inline]
    pub fn stick_theta_ddot(&self, sh: &Shorthands<T>) -> T {
        self.gravity * sh.cos / self.rod_length
    }

    /// The sliding-rod model on the branch sigma = sign(N), sliding in direction `s`
    /// (both +1 or -1): x'' = (c - mu s sigma b) / (D + mu s sigma a), N = Q / (same).
    #[inline]
    pub fn slide(&self, sh: &Shorthands<T>, s: f64, sigma: f64) -> SlideDynamics<T> {
        let ms = self.mu_kinetic * (s * sigma);
        let delta = sh.d + ms * sh.a;
        let l_delta = self.rod_length * delta;
        // One division for both accelerations: x'' = num / delta, theta'' = (...) / l.
        let num = sh.c - ms * sh.b;
        let inv = l_delta.recip();
        let x_ddot = num * self.rod_length * inv;
        let theta_ddot = (self.gravity * sh.cos * delta + sh.sin * num) * inv;
        SlideDynamics {
            x_ddot,
            theta_ddot,
            normal: sh.q * self.rod_length * inv,
            delta,
        }
    }

    /// The self-consistent branches of the sliding equation in direction `s`: a branch is
    /// consistent when the N it produces has the sign sigma it assumed. Outside the paradox
    /// band exactly sigma = sign(Q) is; inside it two or none are.
    pub fn slide_branches(&self, sh: &Shorthands<T>, s: f64) -> SlideBranches {
        let consistent = |sigma: f64| {
            let dynamics = self.slide(sh, s, sigma);
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
    pub fn slide_sigma(&self, sh: &Shorthands<T>, s: f64) -> Option<f64> {
        let branches = self.slide_branches(sh, s);
        let positive = |sigma: f64| self.slide(sh, s, sigma).delta.re() > 0.0;
        match (branches.plus, branches.minus) {
            (true, true) => Some(if positive(1.0) { 1.0 } else { -1.0 }),
            (true, false) => Some(1.0),
            (false, true) => Some(-1.0),
            (false, false) => None,
        }
    }

    /// Power of friction F x' while sliding on branch sigma: F = -mu_k s |N|.
    #[inline]
    pub fn friction_power(&self, dynamics: &SlideDynamics<T>, x_dot: T, s: f64, sigma: f64) -> T {
        -(self.mu_kinetic * dynamics.normal * x_dot) * (s * sigma)
    }
}

/// Mechanical energy E = 1/2 (m1 + m2) x'^2 - m2 l x' w sin(theta) + 1/2 m2 l^2 w^2
/// - m2 g l sin(theta) (zero at rest with the rod horizontal).
pub fn energy<T: Scalar>(rig: &Rig<T>, y: &State<T>) -> T {
    let (m1, m2, l, g) = (rig.slider_mass, rig.bob_mass, rig.rod_length, rig.gravity);
    let (xd, w, sin) = (y[X_DOT], y[THETA_DOT], y[THETA].sin());
    (m1 + m2) * xd * xd * 0.5 - m2 * l * xd * w * sin + m2 * l * l * w * w * 0.5 - m2 * g * l * sin
}

/// Horizontal momentum (m1 + m2) x' - m2 l w sin(theta): conserved when mu = 0.
pub fn momentum<T: Scalar>(rig: &Rig<T>, y: &State<T>) -> T {
    (rig.slider_mass + rig.bob_mass) * y[X_DOT]
        - rig.bob_mass * rig.rod_length * y[THETA_DOT] * y[THETA].sin()
}
