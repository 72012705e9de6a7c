//! The exact derivatives of the residual function: forward-mode dual numbers through the
//! integrator, summed into the normal equations as the simulation runs (the fit never holds
//! the Jacobian), at one of a few fixed dual widths ([`by_width`]).

use super::{to_err, Param, TrajectoryProblem, MAX_FREE};
use crate::fit::lm::{LeastSquares, Normal};
use crate::model::dual::Dual;
use crate::model::CAMERA_PARAMS;
use crate::model::{
    observed_markers_with, re_state, Scalar as _, LOAD_EXPONENT_MAX, LOAD_EXPONENT_MIN,
};
use crate::sim::{Sample, SimError};
use argmin::core::Error;
use nalgebra::{DMatrix, DVector};
use std::sync::atomic::Ordering;

/// Run `$body` with the const `$n` set to the dual width for `$k` free parameters, or give
/// an error beyond [`MAX_FREE`]. Each width is a full copy of the simulator in the binary:
/// widths 3, 4, 5, 6, 8, 10 and 12 serve every size (a few derivative slots stay unused) and keep
/// the build time down.
macro_rules! by_width {
    ($k:expr, $n:ident => $body:expr) => {
        match $k {
            0..=3 => {
                const $n: usize = 3;
                $body
            }
            4 => {
                const $n: usize = 4;
                $body
            }
            5 => {
                const $n: usize = 5;
                $body
            }
            6 => {
                const $n: usize = 6;
                $body
            }
            7 | 8 => {
                const $n: usize = 8;
                $body
            }
            9 | 10 => {
                const $n: usize = 10;
                $body
            }
            11 | 12 => {
                const $n: usize = 12;
                $body
            }
            n => {
                return Err(Error::msg(format!(
                    "at most {MAX_FREE} free parameters, got {n}"
                )))
            }
        }
    };
}

/// `p` as dual numbers of width `N` >= `p.len()`, parameter i seeded in slot i (the slots
/// beyond carry no seed).
fn seed<const N: usize>(p: &DVector<f64>) -> Vec<Dual<N>> {
    (0..p.len()).map(|i| Dual::<N>::variable(p[i], i)).collect()
}

impl TrajectoryProblem {
    /// Half the chi-square at `p` from one run without derivatives, the cost
    /// [`Self::normal_n`] gives bit for bit: dual numbers of width 0 take the same arithmetic
    /// (an f64 run differs by about 1e-13 relative, since dual numbers divide through a
    /// reciprocal), and the sum runs as its does (the data's rows in order, then the priors).
    pub fn half_chi2(&self, p: &DVector<f64>) -> Result<f64, Error> {
        self.counters.residuals.fetch_add(1, Ordering::Relaxed);
        let mut ss = 0.0;
        self.for_each_residual(&seed::<0>(p), |row, _, marker, d| {
            let r = (d * (self.row_weight(row) / self.sigma[marker])).re;
            ss += r * r;
        })
        .map_err(to_err)?;
        for (_, r, _) in self.prior_rows(p.as_slice()) {
            ss += r * r;
        }
        Ok(0.5 * ss)
    }

    /// The normal equations at `p` with dual numbers of width `N` >= `p.len()` (slots beyond
    /// carry no seed), and the block sums over `block` frames when asked for.
    fn normal_n<const N: usize>(
        &self,
        p: &DVector<f64>,
        block: Option<usize>,
    ) -> Result<Normal, SimError> {
        let k = p.len();
        let seeded = seed::<N>(p);
        let mut ss = 0.0;
        let mut jtj = [[0.0; N]; N];
        let mut jtr = [0.0; N];
        let mut meat = [[0.0; N]; N];
        let mut g = [0.0; N];
        let mut current = usize::MAX;
        let flush = |g: &mut [f64; N], meat: &mut [[f64; N]; N]| {
            for a in 0..k {
                for b in 0..a + 1 {
                    meat[a][b] += g[a] * g[b];
                }
            }
            *g = [0.0; N];
        };
        self.for_each_residual(&seeded, |row, frame, marker, d| {
            let v = d * (self.row_weight(row) / self.sigma[marker]);
            let r = v.re;
            let e = v.eps;
            ss += r * r;
            // A row no parameter moves (the slider's height on an ideal camera) adds nothing
            // to the sums: one row in four of every frame.
            if e.iter().all(|&x| x == 0.0) {
                return;
            }
            // Over the whole width N, a constant, so the loops unroll: the unseeded slots
            // only ever add zeros to entries nobody reads.
            for a in 0..N {
                jtr[a] += e[a] * r;
                for b in 0..a + 1 {
                    jtj[a][b] += e[a] * e[b];
                }
            }
            if let Some(len) = block {
                let b = frame / len;
                if b != current {
                    flush(&mut g, &mut meat);
                    current = b;
                }
                for a in 0..N {
                    g[a] += e[a] * r;
                }
            }
        })?;
        flush(&mut g, &mut meat);
        // The priors, one pseudo-observation each: in the block sums too, as an independent
        // observation of its own.
        for (a, r, sd) in self.prior_rows(p.as_slice()) {
            ss += r * r;
            jtr[a] += r / sd;
            jtj[a][a] += 1.0 / (sd * sd);
            meat[a][a] += 1.0 / (sd * sd);
        }
        let sym = |m: &[[f64; N]; N]| DMatrix::from_fn(k, k, |a, b| m[a.max(b)][a.min(b)]);
        Ok(Normal {
            cost: 0.5 * ss,
            jtj: sym(&jtj),
            jtr: DVector::from_fn(k, |a, _| jtr[a]),
            meat: block.map(|_| sym(&meat)),
        })
    }

    /// Residuals and the whole Jacobian (rows x parameters) at `p`, by the same dual-number
    /// run as the normal equations: for tests and small problems only (the fit never holds
    /// the Jacobian). The data's rows only: the priors are no rows here.
    pub fn jacobian(&self, p: &DVector<f64>) -> Result<(DVector<f64>, DMatrix<f64>), Error> {
        fn dense<const N: usize>(
            pr: &TrajectoryProblem,
            p: &DVector<f64>,
        ) -> Result<(DVector<f64>, DMatrix<f64>), SimError> {
            let k = p.len();
            let seeded = seed::<N>(p);
            let n = pr.n_rows();
            let (mut res, mut jac) = (DVector::zeros(n), DMatrix::zeros(n, k));
            pr.for_each_residual(&seeded, |row, _, marker, d| {
                let v = d * (pr.row_weight(row) / pr.sigma[marker]);
                res[row] = v.re;
                let e = v.eps;
                for c in 0..k {
                    jac[(row, c)] = e[c];
                }
            })?;
            Ok((res, jac))
        }
        by_width!(p.len(), N => dense::<N>(self, p)).map_err(to_err)
    }

    /// Exact normal equations by forward-mode dual numbers through the integrator, with event
    /// times differentiated implicitly at every mode switch; with `block`, also the block sums
    /// of the block covariance (frames per block).
    pub fn normal_equations_blocked(
        &self,
        p: &DVector<f64>,
        block: Option<usize>,
    ) -> Result<Normal, Error> {
        self.counters.jacobians.fetch_add(1, Ordering::Relaxed);
        by_width!(p.len(), N => self.normal_n::<N>(p, block)).map_err(to_err)
    }
}

impl TrajectoryProblem {
    /// The normal equations over the free parameters followed by `extra`, camera parameters
    /// that are not free (at most [`CAMERA_PARAMS`]): their columns come from differentiating
    /// the observation model alone at each frame's state, since they do not enter the motion.
    /// The score test screens the camera's nuisances this way in the same pass as the rig's,
    /// with dual numbers no wider than the rig's parameters need.
    pub fn normal_equations_observed(
        &self,
        p: &DVector<f64>,
        extra: &[Param],
    ) -> Result<Normal, Error> {
        if let Some(q) = extra
            .iter()
            .find(|q| !q.is_camera() || self.free.contains(q))
        {
            return Err(Error::msg(format!(
                "{} is not a camera parameter held fixed",
                q.name()
            )));
        }
        if extra.len() > CAMERA_PARAMS {
            return Err(Error::msg(format!(
                "at most {CAMERA_PARAMS} camera parameters, got {}",
                extra.len()
            )));
        }
        if extra.is_empty() {
            return self.normal_equations(p);
        }
        self.counters.jacobians.fetch_add(1, Ordering::Relaxed);
        by_width!(p.len(), N => self.normal_observed_n::<N>(p, extra)).map_err(to_err)
    }

    fn normal_observed_n<const N: usize>(
        &self,
        p: &DVector<f64>,
        extra: &[Param],
    ) -> Result<Normal, SimError> {
        const M: usize = CAMERA_PARAMS;
        const W: usize = MAX_FREE + CAMERA_PARAMS;
        let (k, m) = (p.len(), extra.len());
        // The rig and camera at p, with the extra camera parameters seeded.
        let mut at_p = self.clone();
        at_p.set_values(p);
        at_p.free = extra.to_vec();
        let values = at_p.values();
        let (rig_m, _, cam_m) = at_p.apply(&seed::<M>(&values));
        let mut ss = 0.0;
        // Slots 0..N the motion's (k of them seeded), N..N + M the camera's (m of them): the
        // loops below run over the constant N + M, so they unroll; the unseeded slots only
        // add zeros to entries nobody reads.
        let mut jtj = [[0.0; W]; W];
        let mut jtr = [0.0; W];
        // A lag among the extra parameters differentiates along the motion: velocities.
        self.for_each_residual_at(
            &seed::<N>(p),
            extra.contains(&Param::Lag),
            |s: &Sample<Dual<N>>| {
                let y = re_state(&s.state);
                // The lag's accelerations in f64: nothing in them depends on the camera.
                let acc = (!cam_m.lag.is_exact_zero()).then(|| {
                    let (a, b) = at_p.rig.accelerations(s.mode, &y);
                    (Dual::from(a), Dual::from(b))
                });
                observed_markers_with(rig_m.marker_length, &cam_m, &y.map(Dual::from), acc)
            },
            |row, _, marker, coord, d, cam| {
                let scale = self.row_weight(row) / self.sigma[marker];
                let r = d.re * scale;
                let mut g = [0.0; W];
                for (g, e) in g[..N].iter_mut().zip(d.eps.iter()) {
                    *g = e * scale;
                }
                for (g, c) in g[N..N + M]
                    .iter_mut()
                    .zip(cam[2 * marker + coord].eps.iter())
                {
                    *g = c * scale;
                }
                ss += r * r;
                // A row the motion does not move (the slider's height) has only camera
                // columns: its products with the motion's are zeros, skipped (the sums are
                // the same to the bit: a sum started at +0 never becomes -0).
                let from = if g[..N].iter().all(|&x| x == 0.0) {
                    N
                } else {
                    0
                };
                for a in from..N + M {
                    jtr[a] += g[a] * r;
                    for b in from..a + 1 {
                        jtj[a][b] += g[a] * g[b];
                    }
                }
            },
        )?;
        // The augmented equations' column i in the slots: the free parameters', then the
        // extra camera parameters'.
        let slot = |i: usize| if i < k { i } else { N + i - k };
        // The priors: the free parameters' at p, and the extra camera parameters' at their
        // values (a score test's candidate pays its prior's curvature).
        for (a, r, sd) in self.prior_rows(p.as_slice()) {
            ss += r * r;
            jtr[a] += r / sd;
            jtj[a][a] += 1.0 / (sd * sd);
        }
        for (j, &q) in extra.iter().enumerate() {
            if let Some(pr) = self.prior_on(q) {
                let r = (values[j] - pr.centre) / pr.sd;
                let a = slot(k + j);
                ss += r * r;
                jtr[a] += r / pr.sd;
                jtj[a][a] += 1.0 / (pr.sd * pr.sd);
            }
        }
        let kk = k + m;
        Ok(Normal {
            cost: 0.5 * ss,
            jtj: DMatrix::from_fn(kk, kk, |a, b| {
                let (a, b) = (slot(a), slot(b));
                jtj[a.max(b)][a.min(b)]
            }),
            jtr: DVector::from_fn(kk, |a, _| jtr[slot(a)]),
            meat: None,
        })
    }
}

impl LeastSquares for TrajectoryProblem {
    fn normal_equations(&self, p: &DVector<f64>) -> Result<Normal, Error> {
        self.normal_equations_blocked(p, None)
    }

    /// One run without derivatives ([`Self::half_chi2`]): a quarter of the run in dual numbers
    /// of width 6 (46 against 179 us on the paper scene), less at the wider ones.
    fn cost(&self, p: &DVector<f64>) -> Option<Result<f64, Error>> {
        Some(self.half_chi2(p))
    }

    fn project(&self, p: &mut DVector<f64>) {
        let idx = |q: Param| self.free.iter().position(|&f| f == q);
        if let Some(i) = idx(Param::MuKinetic) {
            p[i] = p[i].max(0.0);
        }
        let mu_k = idx(Param::MuKinetic).map_or(self.rig.mu_kinetic, |i| p[i]);
        if let Some(i) = idx(Param::MuStatic) {
            p[i] = p[i].max(mu_k);
        }
        // Physical ranges: the solver steps back inside them rather than simulating nonsense.
        let clamp = |p: &mut DVector<f64>, q: Param, lo: f64, hi: f64| {
            if let Some(i) = idx(q) {
                p[i] = p[i].clamp(lo, hi);
            }
        };
        clamp(p, Param::RodLength, 1e-6, f64::INFINITY);
        let [g_lo, g_hi] = crate::scene::GRAVITY_RANGE;
        clamp(p, Param::Gravity, g_lo, g_hi);
        // A rigid pendulum's L lies between half and twice the bob's distance for any rod
        // and bob a lab builds (a bare uniform rod has L = 2l/3).
        let l = self.rig.marker_length;
        clamp(p, Param::PendulumLength, 0.5 * l, 2.0 * l);
        // Inside the time-scale bound every command checks before integrating
        // (`scene::MAX_RIG_RATE`): a fit that stepped its own values into a stiffer rig (a
        // pivot damping of 1e3, a bob a thousand times the slider) took the integrator
        // minutes per iteration.
        let rate = crate::scene::MAX_RIG_RATE;
        let (m1, m2) = (self.rig.slider_mass, self.rig.bob_mass);
        let len = self.rig.rod_length;
        let swing = rate * rate * len / self.rig.gravity - 1.0;
        let r_min = if swing > 0.0 { 1.0 / swing } else { 1e4 };
        clamp(p, Param::MassRatio, r_min.max(1e-4), 1e4);
        clamp(
            p,
            Param::PivotDamping,
            0.0,
            rate * m2 * len * len / (1.0 + m2 / m1),
        );
        clamp(p, Param::ViscousFriction, 0.0, rate * m1);
        clamp(p, Param::StribeckVelocity, 1e-4, 10.0);
        // Each direction's coefficient at least 0; an exponent within the rig's range.
        clamp(p, Param::FrictionSplit, -mu_k, mu_k);
        clamp(p, Param::LoadExponent, LOAD_EXPONENT_MIN, LOAD_EXPONENT_MAX);
        let tilt = crate::fit::priors::TILT_SEARCH;
        clamp(p, Param::RailTilt, -tilt, tilt);
        clamp(p, Param::ScaleError, -0.5, 0.5);
        clamp(p, Param::Lag, -0.05, 0.05);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::priors::Prior;
    use std::sync::Arc;

    /// The cost alone (one run without derivatives) is the normal equations' cost bit for bit,
    /// the priors' terms included: the solver decides on it alone where it tries a cost first,
    /// and takes the same path only if it is the same number.
    #[test]
    fn the_cost_alone_is_the_normal_equations_cost_bit_for_bit() {
        let mut problem = crate::fit::test_support::paper_problem(11);
        problem.free.extend([Param::RodLength, Param::MassRatio]);
        let (l, r) = (problem.get(Param::RodLength), problem.get(Param::MassRatio));
        problem.priors = Arc::new(vec![
            Prior {
                param: Param::RodLength,
                centre: 1.001 * l,
                sd: 1e-3,
            },
            Prior {
                param: Param::MassRatio,
                centre: r,
                sd: 0.03 * r,
            },
        ]);
        let p0 = problem.values();
        for i in 0..20 {
            let p = DVector::from_fn(p0.len(), |j, _| {
                p0[j] * (1.0 + 2e-3 * (((i * 7 + j * 3) % 11) as f64 - 5.0) / 5.0)
            });
            let alone = problem.cost(&p).expect("a cost alone").unwrap();
            let both = problem.normal_equations(&p).unwrap().cost;
            assert_eq!(
                alone.to_bits(),
                both.to_bits(),
                "at {p}: {alone} against {both}"
            );
        }
    }
}
