//! The stuck pendulum in closed form through Jacobi's elliptic functions (docs/physics.md,
//! "Pendulum model"): a reference independent of the integrator, and what the simulator uses
//! for a stick phase proven to last (nothing to integrate).

use crate::model::{Rig, Scalar};
use std::f64::consts::{FRAC_PI_2, PI, TAU};

/// Complete elliptic integral of the first kind K(k) (modulus k, 0 <= k < 1), by the
/// arithmetic-geometric mean.
pub fn elliptic_k(k: f64) -> f64 {
    let (mut a, mut b) = (1.0_f64, (1.0 - k * k).sqrt());
    // Quadratic convergence: five or six rounds below k = 0.995. The cap of 40 rounds, not
    // the test, ends a loop that rounding keeps from settling.
    for _ in 0..40 {
        if a - b <= 4.0 * f64::EPSILON * a {
            break;
        }
        (a, b) = (0.5 * (a + b), (a * b).sqrt());
    }
    PI / (a + b)
}

/// Jacobi elliptic functions (sn, cn, dn)(u, k) for modulus 0 <= k < 1, by the descending
/// Landen (AGM) scheme of Abramowitz and Stegun 16.4: accurate to rounding for every u.
pub fn jacobi_sn_cn_dn(u: f64, k: f64) -> (f64, f64, f64) {
    if k < 1e-300 {
        return (u.sin(), u.cos(), 1.0);
    }
    let mut a = vec![1.0_f64];
    let mut c = vec![k];
    let mut b = (1.0 - k * k).sqrt();
    while c[c.len() - 1].abs() > 1e-17 && a.len() < 40 {
        let an = a[a.len() - 1];
        c.push(0.5 * (an - b));
        a.push(0.5 * (an + b));
        b = (an * b).sqrt();
    }
    let n = a.len() - 1;
    let mut phi = 2f64.powi(n as i32) * a[n] * u;
    for j in (1..=n).rev() {
        phi = 0.5 * (phi + (c[j] / a[j] * phi.sin()).asin());
    }
    let (sn, cn) = phi.sin_cos();
    (sn, cn, (1.0 - k * k * sn * sn).sqrt())
}

/// The stuck pendulum (slider held, docs/physics.md "Pendulum (stuck) mode") released from rest at
/// amplitude `amplitude` (rad from hanging, below pi): the exact state (x = 0, theta, 0, w)
/// at time `t`, with theta = pi/2 - phi and sin(phi/2) = k sn(K - w0 t, k), k = sin(A/2).
pub fn stuck_pendulum(rig: &Rig<f64>, amplitude: f64, t: f64) -> [f64; 4] {
    let w0 = (rig.gravity / rig.rod_length).sqrt();
    let k = (0.5 * amplitude).sin();
    let kk = elliptic_k(k);
    let (sn, cn, _) = jacobi_sn_cn_dn(kk - w0 * t, k);
    let phi = 2.0 * (k * sn).asin();
    // phi' = -2 k w0 cn(K - w0 t), and theta' = -phi'.
    [0.0, FRAC_PI_2 - phi, 0.0, 2.0 * k * w0 * cn]
}

/// The exact period of the stuck pendulum of amplitude `amplitude`: 4 sqrt(l/g) K(sin(A/2)).
pub fn stuck_period(rig: &Rig<f64>, amplitude: f64) -> f64 {
    4.0 * (rig.rod_length / rig.gravity).sqrt() * elliptic_k((0.5 * amplitude).sin())
}

/// Carlson's symmetric elliptic integral R_F(x, y, z) by the duplication theorem (Carlson
/// 1995): the series is applied once every argument is within 1e-3 of their mean, which leaves
/// an error near 1e-18.
fn carlson_rf(mut x: f64, mut y: f64, mut z: f64) -> f64 {
    for _ in 0..100 {
        let lambda = (x * y).sqrt() + (y * z).sqrt() + (z * x).sqrt();
        x = 0.25 * (x + lambda);
        y = 0.25 * (y + lambda);
        z = 0.25 * (z + lambda);
        let a = (x + y + z) / 3.0;
        let (dx, dy, dz) = (1.0 - x / a, 1.0 - y / a, 1.0 - z / a);
        if dx.abs().max(dy.abs()).max(dz.abs()) < 1e-3 {
            let e2 = dx * dy - dz * dz;
            let e3 = dx * dy * dz;
            return (1.0 - e2 / 10.0 + e3 / 14.0 + e2 * e2 / 24.0 - 3.0 * e2 * e3 / 44.0)
                / a.sqrt();
        }
    }
    f64::NAN
}

/// Incomplete elliptic integral of the first kind F(psi, k) for |psi| <= pi/2.
pub fn elliptic_f(psi: f64, k: f64) -> f64 {
    let (s, c) = psi.sine_cosine();
    s * carlson_rf(c * c, 1.0 - k * k * s * s, 1.0)
}

/// The stuck pendulum from any librating state (theta, theta') after time `t`: the exact
/// (theta, theta'), or `None` when it goes over the top (modulus k >= 1) or so close to it
/// that the closed form loses accuracy ([`Swing::after`]).
pub fn stuck_state(rig: &Rig<f64>, theta: f64, theta_dot: f64, t: f64) -> Option<(f64, f64)> {
    Swing::new(rig, theta, theta_dot).map(|swing| swing.after(t))
}

/// A stuck pendulum's swing on its energy level, parametrised by Jacobi's amplitude
/// psi = am(u0 + w0 t, k) (w0 = sqrt(g/l)): with phi = theta - pi/2 the angle from hanging,
/// sin(phi/2) = k sin(psi) and theta' = 2 k w0 cos(psi), so the state is an elementary
/// function of psi, and psi grows with time at the rate w0 sqrt(1 - k^2 sin^2 psi) > 0. The
/// time to reach a psi is Legendre's incomplete integral: t = (F(psi, k) - F(psi0, k)) / w0.
/// A stick phase's guard is a function of the state alone, so its crossing is searched in
/// psi with no elliptic function per evaluation, and only the crossing's time needs F.
///
/// On a tilted rail (tilt alpha) the stuck rig is the same pendulum about the vertical shifted
/// by alpha: theta'' = (g/l) cos(theta + alpha). The swing works in theta + alpha and returns
/// theta.
#[derive(Debug, Clone, Copy)]
pub struct Swing {
    tilt: f64,
    w0: f64,
    k: f64,
    big_k: f64,
    /// pi/2 plus the whole turns of the start: theta = offset + phi.
    offset: f64,
    /// The start's amplitude and F there.
    psi0: f64,
    f0: f64,
}

impl Swing {
    /// The swing through (theta, theta'), or `None` over the top (modulus k >= 1) or so close
    /// to it (k^2 >= 0.99) that the closed form loses accuracy.
    pub fn new(rig: &Rig<f64>, theta: f64, theta_dot: f64) -> Option<Swing> {
        let tilt = rig.rail_tilt;
        let theta = theta + tilt;
        let w0 = (rig.gravity / rig.rod_length).sqrt();
        let turns = ((theta - FRAC_PI_2) / TAU).round();
        let offset = FRAC_PI_2 + TAU * turns;
        let half = (0.5 * (theta - offset)).sin();
        let v = theta_dot / (2.0 * w0);
        let k2 = half * half + v * v;
        if k2.is_nan() || k2 >= 0.99 {
            return None;
        }
        let k = k2.sqrt();
        // atan2 of both, not asin(half / k): exact in either quadrant and well conditioned at
        // the turning points, where asin's slope is unbounded.
        let psi0 = half.atan2(v);
        let mut swing = Swing {
            tilt,
            w0,
            k,
            big_k: elliptic_k(k),
            offset,
            psi0,
            f0: 0.0,
        };
        swing.f0 = swing.f(psi0);
        Some(swing)
    }

    /// The amplitude at the start.
    pub fn psi0(&self) -> f64 {
        self.psi0
    }

    /// (theta, theta') at amplitude `psi`.
    pub fn state(&self, psi: f64) -> (f64, f64) {
        let (s, c) = psi.sine_cosine();
        self.state_sn_cn(s, c)
    }

    /// (theta, theta') where sin(psi) = `sn` and cos(psi) = `cn`.
    fn state_sn_cn(&self, sn: f64, cn: f64) -> (f64, f64) {
        (
            self.offset - self.tilt + 2.0 * libm::asin(self.k * sn),
            2.0 * self.k * self.w0 * cn,
        )
    }

    /// Bounds on the time from the start to amplitude `psi` (>= psi0), from psi's rate
    /// w0 sqrt(1 - k^2 sin^2 psi), between w0 sqrt(1 - k^2) and w0: no elliptic integral.
    pub fn elapsed_bounds(&self, psi: f64) -> (f64, f64) {
        let d = (psi - self.psi0) / self.w0;
        (d, d / (1.0 - self.k * self.k).sqrt())
    }

    /// The slowest rate of psi, w0 sqrt(1 - k^2) (rad/s): a tolerance in time times it is
    /// one in psi.
    pub fn slowest_rate(&self) -> f64 {
        self.w0 * (1.0 - self.k * self.k).sqrt()
    }

    /// (theta, theta') a time `t` after the start, from Jacobi's functions: sin(psi) and
    /// cos(psi) are sn and cn of u = F(psi0, k) + w0 t.
    pub fn after(&self, t: f64) -> (f64, f64) {
        let u = (self.f0 + self.w0 * t).rem_euclid(4.0 * self.big_k);
        let (sn, cn, _) = jacobi_sn_cn_dn(u, self.k);
        self.state_sn_cn(sn, cn)
    }

    /// The time from the start to amplitude `psi` (>= psi0).
    pub fn elapsed(&self, psi: f64) -> f64 {
        (self.f(psi) - self.f0) / self.w0
    }

    /// F(psi, k) for any psi, by F(psi + n pi) = F(psi) + 2 n K.
    fn f(&self, psi: f64) -> f64 {
        let n = (psi / PI).round();
        2.0 * n * self.big_k + elliptic_f(psi - n * PI, self.k)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// F(pi/2, k) is the complete integral K(k), and F is odd in psi.
    #[test]
    fn incomplete_integral_meets_complete() {
        for k in [0.0, 0.3, 0.9, 0.99] {
            assert!(
                (elliptic_f(FRAC_PI_2, k) - elliptic_k(k)).abs() < 1e-14 * elliptic_k(k),
                "k {k}"
            );
            assert!((elliptic_f(-0.4, k) + elliptic_f(0.4, k)).abs() < 1e-16);
        }
    }

    /// From rest at an amplitude, the general form agrees with the release-from-rest form.
    #[test]
    fn general_state_matches_release_from_rest() {
        let rig = Rig::paper(1.0);
        for amp in [0.2, 1.0, 2.5] {
            for t in [0.0, 0.1, 0.37, 1.9] {
                let exact = stuck_pendulum(&rig, amp, t);
                let (th, w) = stuck_state(&rig, FRAC_PI_2 - amp, 0.0, t).unwrap();
                assert!(
                    (th - exact[1]).abs() < 1e-12 && (w - exact[3]).abs() < 1e-11,
                    "A {amp} t {t}: {th} {w} vs {exact:?}"
                );
            }
        }
    }

    /// The swing in psi retraces the closed form in time: at the time `elapsed(psi)` (Legendre's
    /// F) after the start, `after` (Jacobi's functions) is at the swing's state for psi, in
    /// both directions of motion, through the turning points and over more than a period.
    /// (`general_state_matches_release_from_rest` checks `after` against the release-from-rest
    /// form.)
    #[test]
    fn swing_in_amplitude_is_the_closed_form_in_time() {
        let rig = Rig::paper(1.0);
        for (theta, w) in [(0.0, 0.0), (0.3, 2.0), (2.2, -3.5), (1.5, 6.0), (-4.0, 1.0)] {
            let swing = Swing::new(&rig, theta, w).unwrap();
            let (th0, w0) = swing.state(swing.psi0());
            assert!((th0 - theta).abs() < 1e-14 && (w0 - w).abs() < 1e-13);
            assert_eq!(swing.elapsed(swing.psi0()), 0.0);
            let mut last = 0.0;
            for j in 1..=40 {
                let psi = swing.psi0() + 0.19 * f64::from(j);
                let t = swing.elapsed(psi);
                assert!(t > last, "time grows with psi");
                last = t;
                let (th, om) = swing.state(psi);
                let (th_t, om_t) = swing.after(t);
                assert!(
                    (th - th_t).abs() < 1e-12 && (om - om_t).abs() < 1e-11,
                    "({theta}, {w}) psi {psi}: ({th}, {om}) vs ({th_t}, {om_t})"
                );
            }
        }
        // On a tilted rail: the same swing about the shifted vertical.
        let tilted = Rig::paper(1.0).with_rail_tilt(0.05);
        let swing = Swing::new(&tilted, 0.3, 2.0).unwrap();
        let (th0, _) = swing.state(swing.psi0());
        assert!((th0 - 0.3).abs() < 1e-14);
        let psi = swing.psi0() + 1.3;
        let (th, om) = swing.state(psi);
        let (th_t, om_t) = swing.after(swing.elapsed(psi));
        assert!((th - th_t).abs() < 1e-12 && (om - om_t).abs() < 1e-11);
        let (th_l, _) = stuck_state(&rig, 0.35, 2.0, swing.elapsed(psi)).unwrap();
        assert!((th + 0.05 - th_l).abs() < 1e-12, "{th} vs {th_l}");
        // Over the top has no swing; hanging at rest stays there.
        assert!(Swing::new(&rig, 0.0, 20.0).is_none());
        let still = Swing::new(&rig, FRAC_PI_2, 0.0).unwrap();
        assert_eq!(still.after(1.7), (FRAC_PI_2, 0.0));
    }

    #[test]
    fn small_modulus_is_trigonometric_and_identities_hold() {
        let (sn, cn, dn) = jacobi_sn_cn_dn(0.7, 0.0);
        assert!((sn - 0.7f64.sin()).abs() < 1e-15 && (cn - 0.7f64.cos()).abs() < 1e-15);
        assert_eq!(dn, 1.0);
        for k in [0.1, 0.5, 0.9, 0.999] {
            let kk = elliptic_k(k);
            let (sn, cn, _) = jacobi_sn_cn_dn(kk, k);
            assert!(
                (sn - 1.0).abs() < 1e-12 && cn.abs() < 1e-7,
                "k={k}: {sn} {cn}"
            );
            for u in [0.3, 1.1, 2.5, -4.0] {
                let (sn, cn, dn2) = jacobi_sn_cn_dn(u, k);
                assert!((sn * sn + cn * cn - 1.0).abs() < 1e-14);
                assert!((dn2 * dn2 + k * k * sn * sn - 1.0).abs() < 1e-14);
            }
            // sn' = cn dn, by a central difference.
            let (u, h) = (0.8, 1e-5);
            let d = (jacobi_sn_cn_dn(u + h, k).0 - jacobi_sn_cn_dn(u - h, k).0) / (2.0 * h);
            let (_, cn, dn) = jacobi_sn_cn_dn(u, k);
            assert!((d - cn * dn).abs() < 1e-9, "k={k}");
        }
    }

    #[test]
    fn pendulum_solution_satisfies_its_equation_and_energy() {
        let rig = Rig::paper(2.5);
        let a = 1.2;
        let y0 = stuck_pendulum(&rig, a, 0.0);
        assert!((y0[1] - (FRAC_PI_2 - a)).abs() < 1e-14 && y0[3].abs() < 1e-14);
        let gl = rig.gravity / rig.rod_length;
        let e = |y: [f64; 4]| y[3] * y[3] - 2.0 * gl * y[1].sin();
        for t in [0.1, 0.37, 1.3] {
            let h = 1e-4;
            let (ym, y, yp) = (
                stuck_pendulum(&rig, a, t - h),
                stuck_pendulum(&rig, a, t),
                stuck_pendulum(&rig, a, t + h),
            );
            assert!((e(y) - e(y0)).abs() < 1e-11);
            let acc = (ym[1] - 2.0 * y[1] + yp[1]) / (h * h);
            assert!((acc - gl * y[1].cos()).abs() < 1e-5, "t={t}: {acc}");
        }
        let half = 0.5 * stuck_period(&rig, a);
        let y = stuck_pendulum(&rig, a, half);
        assert!((y[1] - (FRAC_PI_2 + a)).abs() < 1e-12 && y[3].abs() < 1e-10);
    }
}
