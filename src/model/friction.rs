//! The friction laws (docs/physics.md, "Friction laws"): the coefficient a slide meets, the
//! most friction a stuck slider holds, and the load law's normal force. Every simulator,
//! fit, plan and region computation takes friction from here.

use super::{sign, FrictionLaw, Rig, Scalar, Shorthands};

/// (|x'| / v_s)^2 past which the Stribeck hump, e^-(|x'|/v_s)^2 < 2e-22, is left out.
const STRIBECK_TAIL: f64 = 50.0;

/// Relative tolerance of the load law's normal force (the root of h(u) below).
const LOAD_ROOT_TOL: f64 = 1e-15;

/// Most iterations of the load law's safeguarded Newton search (bisection halves the
/// bracket each time Newton leaves it, so 200 always reach [`LOAD_ROOT_TOL`]).
const LOAD_ROOT_ITERS: usize = 200;

impl<T: Scalar> Rig<T> {
    /// 1 / v_s under Stribeck's law, zero under the others (where v_s is not used).
    #[inline]
    pub fn inverse_stribeck_velocity(&self) -> T {
        match self.friction_law {
            FrictionLaw::Stribeck => self.stribeck_velocity.recip(),
            _ => T::zero(),
        }
    }

    /// The sliding friction coefficient sliding in direction `s` (+1 or -1) at speed
    /// `speed` = |x'|: the load law's at the static load (its slides meet
    /// [`Rig::slide_mu`]).
    #[inline(always)]
    pub fn friction_mu(&self, s: f64, speed: T) -> T {
        self.friction_mu_on(s, speed, self.inverse_stribeck_velocity())
    }

    /// [`Rig::friction_mu`] with [`Rig::inverse_stribeck_velocity`] at hand (a caller that
    /// evaluates it many times keeps it in [`super::RigConstants`]).
    #[inline(always)]
    pub fn friction_mu_on(&self, s: f64, speed: T, inverse_stribeck_velocity: T) -> T {
        match self.friction_law {
            FrictionLaw::Coulomb | FrictionLaw::Load => self.mu_kinetic,
            FrictionLaw::Direction => self.mu_kinetic + self.kinetic_split * s,
            FrictionLaw::Stribeck => {
                let u = speed * inverse_stribeck_velocity;
                let u2 = u * u;
                if u2.re() > STRIBECK_TAIL {
                    // The hump is below e^-50 = 2e-22 of mu_s - mu_k here: mu_k to far
                    // below any friction measurement, without an exp on every evaluation
                    // of a fast slide.
                    return self.mu_kinetic;
                }
                self.mu_kinetic + (self.mu_static - self.mu_kinetic) * (-u2).exp()
            }
        }
    }

    /// The static coefficient that holds a stuck slider about to slip toward `s`.
    #[inline(always)]
    pub fn static_mu(&self, s: f64) -> T {
        match self.friction_law {
            FrictionLaw::Direction => self.mu_static + self.static_split * s,
            _ => self.mu_static,
        }
    }

    /// The static load N_0 = (m1 + m2) g of the load law: its coefficients are those at N_0.
    #[inline]
    pub fn static_load(&self) -> T {
        (self.slider_mass + self.bob_mass) * self.gravity
    }

    /// The load law's factor (|N| / N_0)^(n - 1) at the load ratio `u` = |N| / N_0: its
    /// coefficients at a load are those at the static load times this (exactly 1 at n = 1).
    #[inline(always)]
    pub fn load_factor(&self, u: T) -> T {
        ((self.load_exponent - 1.0) * u.ln()).exp()
    }

    /// The sliding coefficient |F| / |N| at the normal force `normal` (N; its size counts):
    /// mu_k (|N| / N_0)^(n - 1) under the load law, and [`Rig::mu_kinetic`] under the others,
    /// whose coefficient does not depend on the load.
    pub fn load_coefficient(&self, normal: T) -> T {
        match self.friction_law {
            FrictionLaw::Load => {
                self.mu_kinetic * self.load_factor(normal.abs() / self.static_load())
            }
            _ => self.mu_kinetic,
        }
    }

    /// Stick margin, positive while the pendulum model holds: the most friction the rail
    /// holds minus the friction needed, |c|. The slider would slip toward sign(c), so the
    /// direction law takes that direction's static coefficient; the load law holds
    /// mu_s N_0 (|b| / N_0)^n. Coulomb's and Stribeck's laws give mu_s |b| - |c|.
    #[inline(always)]
    pub fn stick_margin(&self, sh: &Shorthands<T>) -> T {
        match self.friction_law {
            FrictionLaw::Coulomb | FrictionLaw::Stribeck => sh.stick_margin(self.mu_static),
            FrictionLaw::Direction => sh.stick_margin(self.static_mu(sign(sh.c.re()))),
            FrictionLaw::Load => {
                let b = sh.b.abs();
                if b.re() == 0.0 {
                    return -sh.c.abs();
                }
                // mu_s |b| (|b| / N_0)^(n - 1): exactly mu_s |b| at n = 1.
                let factor = self.load_factor(b / self.static_load());
                sh.stick_margin(self.mu_static * factor)
            }
        }
    }

    /// The largest coefficient a slide toward `s` can meet: mu_s under Stribeck's law
    /// (reached as v -> 0), the direction's coefficient under the direction law, the
    /// coefficient at the static load under the load law. It decides where the Painleve
    /// paradox is possible.
    pub fn mu_slide_max_toward(&self, s: f64) -> T {
        match self.friction_law {
            FrictionLaw::Coulomb | FrictionLaw::Load => self.mu_kinetic,
            FrictionLaw::Stribeck => self.mu_static,
            FrictionLaw::Direction => self.mu_kinetic + self.kinetic_split * s,
        }
    }

    /// [`Rig::mu_slide_max_toward`], the larger of the two directions.
    pub fn mu_slide_max(&self) -> T {
        let (p, m) = (
            self.mu_slide_max_toward(1.0),
            self.mu_slide_max_toward(-1.0),
        );
        if m.re() > p.re() {
            m
        } else {
            p
        }
    }

    /// The friction coefficient |F| / |N| of a slide toward `s` on branch `sigma` = sign(N)
    /// at velocity `x_dot`, with the shorthands `sh` of its angle: [`Rig::friction_mu_on`],
    /// except under the load law, whose coefficient depends on the normal force it helps to
    /// make ([`Rig::load_mu`]).
    #[inline(always)]
    pub fn slide_mu(
        &self,
        sh: &Shorthands<T>,
        (s, sigma): (f64, f64),
        x_dot: T,
        inverse_stribeck_velocity: T,
    ) -> T {
        if self.friction_law != FrictionLaw::Load {
            return self.friction_mu_on(s, x_dot * s, inverse_stribeck_velocity);
        }
        let mut q = sh.q;
        if !self.viscous_friction.is_exact_zero() {
            q -= sh.a * self.viscous_friction * x_dot;
        }
        self.load_mu(sh.d, sh.a * (s * sigma), q * sigma)
    }

    /// The load law's coefficient mu_k u^(n - 1), u = |N| / N_0, on a branch where the
    /// normal force satisfies N (D + mu s sigma a) = Q_v (Q_v: Q less the viscous part):
    /// u solves h(u) = D u + (s sigma a) mu_k u^n - sigma Q_v / N_0 = 0. The root is found in
    /// real numbers and one Newton step in `T` carries its derivatives (the implicit function
    /// theorem). Where the branch has no positive root (sigma Q_v <= 0: the branch assumes
    /// the wrong sign of N, or N = 0), the coefficient at the static load, mu_k, is returned:
    /// the branch test then decides with it, and at N = 0 friction vanishes whatever the
    /// coefficient.
    pub fn load_mu(&self, d: T, a_s: T, q_sigma: T) -> T {
        let (mu, n) = (self.mu_kinetic, self.load_exponent);
        let rhs = q_sigma / self.static_load();
        let Some(u0) = load_root(d.re(), a_s.re() * mu.re(), n.re(), rhs.re()) else {
            return mu;
        };
        let u = T::from(u0);
        let h = d * u + a_s * mu * (n * u.ln()).exp() - rhs;
        let slope = d.re() + a_s.re() * mu.re() * n.re() * u0.powf(n.re() - 1.0);
        let u = u - h / slope;
        mu * self.load_factor(u)
    }
}

/// The positive root u of h(u) = d u + k u^n - rhs (k = s sigma a mu_k) with h(0) = -rhs < 0,
/// by Newton's method kept inside a bracket (bisection where it would leave it). `None` when
/// rhs <= 0 or no bracket is found: for k < 0 and n > 1, h may stay negative (the load law's
/// own paradox: no consistent normal force on this branch).
fn load_root(d: f64, k: f64, n: f64, rhs: f64) -> Option<f64> {
    if !(rhs > 0.0 && d > 0.0 && rhs.is_finite()) {
        return None;
    }
    let h = |u: f64| d * u + k * u.powf(n) - rhs;
    let (mut lo, mut hi) = (0.0, rhs / d);
    if k < 0.0 && n > 1.0 {
        // h rises to its peak at u* = (d / (-k n))^(1 / (n - 1)) and falls for ever after:
        // the root of the branch that meets Coulomb's is below u*, and there is none when
        // h(u*) <= 0 (doubling the bracket in search of it cost 64 powf a call).
        let peak = (d / (-k * n)).powf(1.0 / (n - 1.0));
        if !(peak.is_finite() && h(peak) > 0.0) {
            return None;
        }
        hi = peak;
    }
    // h(rhs / d) = k (rhs / d)^n >= 0 when k >= 0; otherwise widen.
    let mut widened = 0;
    while h(hi) <= 0.0 {
        widened += 1;
        if widened > 64 {
            return None;
        }
        hi *= 2.0;
    }
    // Start from Coulomb's solution (exact at n = 1) when it is inside the bracket.
    let coulomb = rhs / (d + k);
    let mut u = if coulomb > lo && coulomb < hi {
        coulomb
    } else {
        0.5 * hi
    };
    for _ in 0..LOAD_ROOT_ITERS {
        // One powf an iteration: u^n = u u^(n-1), and the slope needs u^(n-1) too.
        let un1 = u.powf(n - 1.0);
        let ku = k * u * un1;
        let hu = d * u + ku - rhs;
        // Zero to rounding (h's terms carry errors of a few ulps): no step can do better.
        if hu.abs() <= 4.0 * f64::EPSILON * (d * u + ku.abs() + rhs) {
            return Some(u);
        }
        if hu > 0.0 {
            hi = u;
        } else {
            lo = u;
        }
        let slope = d + k * n * un1;
        let mut next = u - hu / slope;
        if !(next > lo && next < hi) {
            next = 0.5 * (lo + hi);
        }
        if (next - u).abs() <= LOAD_ROOT_TOL * next {
            return Some(next);
        }
        u = next;
    }
    Some(u)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn load_root_solves_h_and_is_coulomb_at_exponent_one() {
        for (d, k, n, rhs) in [
            (0.15, 0.02, 0.8, 0.9),
            (0.15, -0.02, 0.8, 0.9),
            (0.4, -0.1, 0.5, 1e-6),
            (0.4, 0.3, 1.5, 3.0),
        ] {
            let u = load_root(d, k, n, rhs).expect("a root");
            let h = d * u + k * u.powf(n) - rhs;
            // Relative to the largest term: the two terms may nearly cancel.
            assert!(h.abs() <= 1e-14 * rhs.max(d * u), "h = {h} at u = {u}");
        }
        // k < 0 and n > 1: h peaks at u* = (d / (-k n))^2 = 7.1 for these, where it is
        // 0.65 above zero for rhs = 0.3 (the root is the one below u*) and under zero for
        // rhs = 2 (no root: the load law's own paradox).
        let u = load_root(0.4, -0.1, 1.5, 0.3).expect("a root below the peak");
        assert!(u < (0.4f64 / 0.15).powi(2));
        assert!((0.4 * u - 0.1 * u.powf(1.5) - 0.3).abs() <= 1e-14);
        assert_eq!(load_root(0.4, -0.1, 1.5, 2.0), None);
        let u = load_root(0.15, 0.03, 1.0, 0.9).unwrap();
        assert!((u - 0.9 / 0.18).abs() <= 1e-15 * u);
        assert_eq!(load_root(0.15, 0.03, 0.8, -0.1), None);
    }
}
