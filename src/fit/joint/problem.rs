//! The joint problem ([`JointProblem`]): the releases' problems with the rig's parameters tied,
//! its normal equations summed from theirs (in parallel), and its part in the forward
//! selection ([`Candidate`]).

use crate::fit::lm::{LeastSquares, Normal};
use crate::fit::problem::{Param, TrajectoryProblem};
use crate::fit::select::{self, Candidate, Nuisance};
use crate::model::State;
use argmin::core::Error;
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;

/// Whether a parameter is the rig's (one value for every release) rather than the release's.
/// The camera's parameters are the release's unless the camera is the same in all.
fn is_shared(q: Param, same_camera: bool) -> bool {
    q.is_rig() || (same_camera && q.is_camera() && q != Param::Lag)
}

/// Several releases' problems with their shared parameters tied: the parameter vector is the
/// shared parameters, then each release's own, release by release. Each release's problem
/// frees the shared parameters first, then its own.
#[derive(Debug, Clone)]
pub struct JointProblem {
    /// The releases' problems (their values are the current ones).
    pub parts: Vec<TrajectoryProblem>,
    /// The shared free parameters, in the order of the vector.
    pub shared: Vec<Param>,
    /// Camera and marker parameters shared by every release.
    pub same_camera: bool,
}

impl JointProblem {
    /// The releases' problems tied: each one's free parameters split into shared and own.
    pub fn new(mut parts: Vec<TrajectoryProblem>, same_camera: bool) -> Self {
        let mut shared: Vec<Param> = Vec::new();
        for part in &parts {
            for &q in &part.free {
                if is_shared(q, same_camera) && !shared.contains(&q) {
                    shared.push(q);
                }
            }
        }
        for (k, part) in parts.iter_mut().enumerate() {
            let own: Vec<Param> = part
                .free
                .iter()
                .copied()
                .filter(|&q| !is_shared(q, same_camera))
                .collect();
            part.free = shared.iter().copied().chain(own).collect();
            // The joint normal equations are the parts' summed: a prior on a shared parameter
            // (the rig's measured values, a tilt's range) is the first release's alone, so it
            // counts once; each release keeps the priors of its own parameters.
            if k > 0
                && part
                    .priors
                    .iter()
                    .any(|pr| is_shared(pr.param, same_camera))
            {
                let own: Vec<_> = part
                    .priors
                    .iter()
                    .copied()
                    .filter(|pr| !is_shared(pr.param, same_camera))
                    .collect();
                part.priors = std::sync::Arc::new(own);
            }
        }
        JointProblem {
            parts,
            shared,
            same_camera,
        }
    }

    /// Where each release's own parameters start in the vector.
    fn offsets(&self) -> Vec<usize> {
        let mut at = self.shared.len();
        self.parts
            .iter()
            .map(|p| {
                let o = at;
                at += p.free.len() - self.shared.len();
                o
            })
            .collect()
    }

    /// Indices in the joint vector of release `k`'s parameters, in its own order.
    fn index(&self, k: usize, offset: usize) -> Vec<usize> {
        let s = self.shared.len();
        (0..self.parts[k].free.len())
            .map(|j| if j < s { j } else { offset + j - s })
            .collect()
    }

    /// Every entry of the vector as (release, parameter); the release is `None` when shared.
    fn labels(&self) -> Vec<(Option<usize>, Param)> {
        let s = self.shared.len();
        let mut out: Vec<_> = self.shared.iter().map(|&q| (None, q)).collect();
        for (k, part) in self.parts.iter().enumerate() {
            out.extend(part.free[s..].iter().map(|&q| (Some(k), q)));
        }
        out
    }

    /// Release `k`'s part of the joint vector `p`.
    fn sub(&self, p: &DVector<f64>, idx: &[usize]) -> DVector<f64> {
        DVector::from_iterator(idx.len(), idx.iter().map(|&i| p[i]))
    }

    /// `f(k, part, q)` of every release `k` at its part `q` of the joint vector `p`, the
    /// releases in parallel, in release order with each one's indices in `p`.
    fn per_part<R: Send>(
        &self,
        p: &DVector<f64>,
        f: impl Fn(usize, &TrajectoryProblem, &DVector<f64>) -> Result<R, Error> + Sync,
    ) -> Result<Vec<(Vec<usize>, R)>, Error> {
        let offsets = self.offsets();
        (0..self.parts.len())
            .into_par_iter()
            .with_max_len(1)
            .map(|k| {
                let idx = self.index(k, offsets[k]);
                let r = f(k, &self.parts[k], &self.sub(p, &idx))?;
                Ok((idx, r))
            })
            .collect()
    }

    /// Each release's normal equations at `p` (in parallel), with their block sums when
    /// `block` gives each release's frames per block.
    fn part_normals(
        &self,
        p: &DVector<f64>,
        block: Option<&[usize]>,
    ) -> Result<Vec<(Vec<usize>, Normal)>, Error> {
        self.per_part(p, |k, part, q| {
            part.normal_equations_blocked(q, block.map(|b| b[k]))
        })
    }

    /// The releases' normal equations summed into the joint ones.
    fn assemble(&self, n: usize, parts: Vec<(Vec<usize>, Normal)>) -> Normal {
        let mut out = Normal {
            cost: 0.0,
            jtj: DMatrix::zeros(n, n),
            jtr: DVector::zeros(n),
            meat: None,
        };
        let mut meat: Option<DMatrix<f64>> = None;
        for (idx, part) in parts {
            out.cost += part.cost;
            for (a, &i) in idx.iter().enumerate() {
                out.jtr[i] += part.jtr[a];
                for (b, &j) in idx.iter().enumerate() {
                    out.jtj[(i, j)] += part.jtj[(a, b)];
                }
            }
            if let Some(m) = part.meat {
                let acc = meat.get_or_insert_with(|| DMatrix::zeros(n, n));
                for (a, &i) in idx.iter().enumerate() {
                    for (b, &j) in idx.iter().enumerate() {
                        acc[(i, j)] += m[(a, b)];
                    }
                }
            }
        }
        out.meat = meat;
        out
    }

    /// The joint normal equations with the block sums of each release's residuals (frames per
    /// block per release).
    pub fn normal_equations_blocked(
        &self,
        p: &DVector<f64>,
        block: Option<&[usize]>,
    ) -> Result<Normal, Error> {
        let parts = self.part_normals(p, block)?;
        Ok(self.assemble(p.len(), parts))
    }
}

impl LeastSquares for JointProblem {
    fn normal_equations(&self, p: &DVector<f64>) -> Result<Normal, Error> {
        self.normal_equations_blocked(p, None)
    }

    /// The releases' costs alone ([`TrajectoryProblem::half_chi2`]), added in the order
    /// [`Self::assemble`] adds theirs: the same number.
    fn cost(&self, p: &DVector<f64>) -> Option<Result<f64, Error>> {
        let costs = self.per_part(p, |_, part, q| part.half_chi2(q));
        Some(costs.map(|c| c.into_iter().fold(0.0, |sum, (_, c)| sum + c)))
    }

    fn project(&self, p: &mut DVector<f64>) {
        // Each release's bounds on its own slice; the shared entries come out the same from
        // every release (their bounds depend on shared values only).
        let offsets = self.offsets();
        for (k, part) in self.parts.iter().enumerate() {
            let idx = self.index(k, offsets[k]);
            let mut q = self.sub(p, &idx);
            part.project(&mut q);
            for (a, &i) in idx.iter().enumerate() {
                p[i] = q[a];
            }
        }
    }
}

impl Candidate for JointProblem {
    type Start = Vec<(State<f64>, f64)>;
    fn n_rows(&self) -> usize {
        self.parts.iter().map(|p| p.n_rows()).sum()
    }
    fn n_free(&self) -> usize {
        self.labels().len()
    }
    fn width(&self) -> usize {
        self.parts.iter().map(|p| p.free.len()).max().unwrap_or(0)
    }
    fn frees(&self, q: Param) -> bool {
        self.parts.iter().any(|p| p.free.contains(&q))
    }
    fn free_names(&self) -> Vec<&'static str> {
        let mut names: Vec<&'static str> = Vec::new();
        for (_, q) in self.labels() {
            if !names.contains(&q.name()) {
                names.push(q.name());
            }
        }
        names
    }
    fn values(&self) -> DVector<f64> {
        let s = self.shared.len();
        let mut v: Vec<f64> = self.shared.iter().map(|&q| self.parts[0].get(q)).collect();
        for part in &self.parts {
            v.extend(part.free[s..].iter().map(|&q| part.get(q)));
        }
        DVector::from_vec(v)
    }
    fn set_values(&mut self, v: &DVector<f64>) {
        let offsets = self.offsets();
        let idx: Vec<Vec<usize>> = (0..self.parts.len())
            .map(|k| self.index(k, offsets[k]))
            .collect();
        for (part, idx) in self.parts.iter_mut().zip(idx) {
            part.set_values(&DVector::from_iterator(
                idx.len(),
                idx.iter().map(|&i| v[i]),
            ));
        }
    }
    fn mu_kinetic(&self) -> f64 {
        self.parts[0].rig.mu_kinetic
    }
    fn mu_static(&self) -> f64 {
        self.parts[0].rig.mu_static
    }
    fn pendulum_given(&self) -> bool {
        self.parts[0].rig.pendulum.is_some()
    }
    fn implausible(&self) -> bool {
        self.parts
            .iter()
            .any(|p| !crate::fit::implausible::implausible(p).is_empty())
    }
    fn with_nuisance(&self, nu: Nuisance, mu_static: f64) -> Self {
        let parts = self
            .parts
            .iter()
            .map(|p| p.with_nuisance(nu, mu_static))
            .collect();
        JointProblem::new(parts, self.same_camera)
    }
    fn restarted(&self, start: &Self::Start) -> Self {
        let mut out = self.clone();
        for (part, s) in out.parts.iter_mut().zip(start) {
            *part = part.restarted(s);
        }
        out
    }
    fn static_tied(&self) -> Self {
        let parts = self.parts.iter().map(|p| p.static_tied()).collect();
        JointProblem::new(parts, self.same_camera)
    }
    fn coulomb(&self) -> Self {
        let parts = self.parts.iter().map(|p| p.coulomb()).collect();
        JointProblem::new(parts, self.same_camera)
    }
    fn static_near_tie(&self) -> Self {
        let mut out = self.clone();
        out.parts = out.parts.iter().map(|p| p.static_near_tie()).collect();
        out
    }
    fn stribeck_slow_start(&self) -> Option<Self> {
        let mut out = self.clone();
        out.parts = self
            .parts
            .iter()
            .map(|p| p.stribeck_slow_start())
            .collect::<Option<_>>()?;
        Some(out)
    }
    fn score_drops(&self, p: &DVector<f64>, candidates: &[Nuisance]) -> Vec<(Nuisance, f64)> {
        let mut at = self.clone();
        at.set_values(p);
        select::score_drops_by(&at, candidates, |nu| at.with_nuisance(nu, at.mu_static()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The joint cost alone is the joint normal equations' cost bit for bit: the releases'
    /// costs added in the order their normal equations are (the solver's cost-first trials
    /// take the joint path only if it is the same number).
    #[test]
    fn the_joint_cost_alone_is_the_normal_equations_cost_bit_for_bit() {
        let parts: Vec<TrajectoryProblem> = [11, 12, 13]
            .map(crate::fit::test_support::paper_problem)
            .into();
        let joint = JointProblem::new(parts, false);
        let p0 = joint.values();
        assert!(
            p0.len() > joint.parts[0].free.len(),
            "releases share mu only"
        );
        for i in 0..10 {
            let p = DVector::from_fn(p0.len(), |j, _| {
                p0[j] * (1.0 + 2e-3 * (((i * 5 + j * 3) % 7) as f64 - 3.0) / 3.0)
            });
            let alone = joint.cost(&p).expect("a cost alone").unwrap();
            let both = joint.normal_equations(&p).unwrap().cost;
            assert_eq!(alone.to_bits(), both.to_bits(), "{alone} against {both}");
        }
    }
}
