//! The search over the feasible release set: a coarse grid screened by the nominal run and a
//! few common draws, then Nelder-Mead (argmin) on the predicted standard error of mu with the
//! robustness as a penalty, then a fresh Monte Carlo check of the best points.

use super::criteria::{Criteria, Evaluation};
use super::spec::{PlanSpec, Uncertain};
use crate::fit::lm::LeastSquares;
use crate::fit::{Observations, Param, TrajectoryProblem};
use crate::model::{Rig, State};
use crate::sim::{simulate, Options, Request, Solution};
use argmin::core::{CostFunction, Error, Executor};
use argmin::solver::neldermead::NelderMead;
use indicatif::ProgressBar;
use nalgebra::DMatrix;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use rayon::prelude::*;
use std::sync::{Arc, Mutex};

/// Standard draws of the uncertain quantities, shared by every candidate of a search so that
/// the robustness is a smooth-ish function of the release (common random numbers).
#[derive(Debug, Clone, PartialEq)]
pub struct Draws {
    /// Standard normal draws for mu_kinetic.
    pub mu_kinetic: Vec<f64>,
    /// Standard normal draws for mu_static.
    pub mu_static: Vec<f64>,
    /// Uniform draws in [-1, 1] for the execution errors of (theta, theta', x').
    pub release: Vec<[f64; 3]>,
    /// Standard normal draws for the law's other parameters (a stream of their own, so that
    /// a plan without them draws what it drew before they existed).
    pub law: Vec<[f64; 2]>,
}

impl Draws {
    /// `n` draws from `seed`.
    pub fn new(n: usize, seed: u64) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut d = Draws {
            mu_kinetic: Vec::with_capacity(n),
            mu_static: Vec::with_capacity(n),
            release: Vec::with_capacity(n),
            law: Vec::with_capacity(n),
        };
        let mut law_rng = ChaCha8Rng::seed_from_u64(seed ^ 0x1a55_1a55);
        for _ in 0..n {
            d.law
                .push(std::array::from_fn(|_| law_rng.sample(StandardNormal)));
            d.mu_kinetic.push(rng.sample(StandardNormal));
            d.mu_static.push(rng.sample(StandardNormal));
            d.release
                .push(std::array::from_fn(|_| rng.random_range(-1.0..=1.0)));
        }
        d
    }

    /// Number of draws.
    pub fn len(&self) -> usize {
        self.mu_kinetic.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.mu_kinetic.is_empty()
    }
}

/// A sample of the plan's frames (observations of zeros) and the noise that weights each
/// sampled row as the frames it stands for: every k-th frame, its rows weighted by k. A
/// Jacobian's sums over such a sample are the whole recording's to a few per cent (tested in
/// [`super::discriminate`]) at a fraction of the cost.
pub struct Frames {
    /// The sampled frames.
    pub obs: Arc<Observations>,
    /// The camera's noise divided by the square root of the stride.
    pub noise: f64,
}

impl Frames {
    /// At most `max_frames` of `ev`'s frames (all of them when there are no more).
    pub fn new(ev: &Evaluator, max_frames: usize) -> Frames {
        let all = ev.placeholder();
        let n = all.times.len();
        let stride = n.div_ceil(max_frames.max(1)).max(1);
        if stride == 1 {
            return Frames {
                obs: all,
                noise: ev.spec.camera.noise_m,
            };
        }
        let pick = |v: &[Option<[f64; 2]>]| v.iter().step_by(stride).copied().collect();
        let obs = Observations {
            times: all.times.iter().step_by(stride).copied().collect(),
            slider: pick(&all.slider),
            bob: pick(&all.bob),
        };
        let weight = n as f64 / obs.times.len() as f64;
        Frames {
            obs: Arc::new(obs),
            noise: ev.spec.camera.noise_m / weight.sqrt(),
        }
    }
}

/// The search's relative tolerance ([`Evaluator::searching`]).
pub const SEARCH_RTOL: f64 = 1e-6;

/// A release the mechanism can set: (theta rad, theta' rad/s, x' m/s); x is the plan's.
pub type ReleaseValues = [f64; 3];

/// Everything needed to judge releases of one plan: the criteria, simulator settings, the
/// frame times and a placeholder recording for the Fisher information.
#[derive(Clone)]
pub struct Evaluator<'a> {
    /// The plan.
    pub spec: &'a PlanSpec,
    /// Its checks.
    pub criteria: Criteria,
    /// Simulator settings of the planner (looser than a fit's: decisions need ~1e-8; the
    /// search's own copy, [`Evaluator::searching`], looser still).
    pub options: Options,
    /// The laws to tell apart, when the plan weighs laws ([`super::discriminate`]): releases
    /// are then ranked by how surely they separate them.
    pub laws: Option<super::discriminate::Laws>,
    obs: Arc<Observations>,
}

impl<'a> Evaluator<'a> {
    /// The evaluator of `spec`.
    pub fn new(spec: &'a PlanSpec) -> Self {
        let times = spec.camera.frame_times();
        let n = times.len();
        // The Jacobian does not depend on the observed values: zeros will do.
        let obs = Arc::new(Observations {
            times,
            slider: vec![Some([0.0; 2]); n],
            bob: vec![Some([0.0; 2]); n],
        });
        Evaluator {
            spec,
            criteria: Criteria::new(spec),
            options: Options {
                rtol: 1e-8,
                atol: 1e-10,
                max_steps: 200_000,
                max_events: 400,
                ..Options::default()
            },
            laws: None,
            obs,
        }
    }

    /// The evaluator a law plan's search ranks releases with: the same, simulated at rtol
    /// 1e-6 and atol 1e-8 ([`SEARCH_RTOL`]). A ranking by the laws' separation needs less
    /// than a report: the grid's robustness, mu's error and the separation agree with the
    /// reporting tolerance's to within the scatter of mirror-image releases, at two thirds
    /// of the cost. What a plan reports (the fresh check, the proposals) keeps `self`'s.
    pub fn searching(&self) -> Evaluator<'a> {
        let mut ev = self.clone();
        ev.options.rtol = SEARCH_RTOL;
        ev.options.atol = SEARCH_RTOL * 1e-2;
        ev
    }

    /// Observations of zeros at the plan's frames (a Jacobian does not depend on them).
    pub fn placeholder(&self) -> Arc<Observations> {
        self.obs.clone()
    }

    /// A candidate judged on `draws`: its robustness, mu's predicted standard error and,
    /// when the plan weighs laws and the release can be ranked, its separation.
    pub fn candidate(&self, p: &ReleaseValues, draws: &Draws) -> Candidate {
        let robustness = self.passes(p, draws) as f64 / draws.len() as f64;
        // Under laws mu's error only breaks ties: the sampled frames will do (a proposal's
        // printed error is every frame's, [`super::checked`]).
        let stderr = match &self.laws {
            Some(laws) => self.mu_stderr_on(&Frames::new(self, laws.max_frames), p),
            None => self.mu_stderr(p),
        };
        // Releases far from robust are priced out by the penalty anyway: no rival fits.
        let separations = match &self.laws {
            Some(laws) if robustness >= 0.5 * self.spec.goal.min_robustness => {
                Some(laws.separations(self, &self.initial(p)))
            }
            _ => None,
        };
        let separation = match (&self.laws, &separations) {
            (Some(_), Some(s)) => super::discriminate::Laws::score(s),
            (Some(_), None) => f64::NEG_INFINITY,
            (None, _) => f64::NAN,
        };
        Candidate {
            release: *p,
            robustness,
            stderr,
            separation,
            saturated: separations.is_some_and(|s| {
                super::discriminate::Laws::worst(&s) >= super::discriminate::MARGIN_CAP
            }),
        }
    }

    /// The initial state of a release.
    pub fn initial(&self, p: &ReleaseValues) -> State<f64> {
        [self.spec.release.x, p[0], p[2], p[1]]
    }

    /// The rig of draw `i` of `draws` (mu_static never below mu_kinetic).
    pub fn rig_of(&self, draws: &Draws, i: usize) -> Rig<f64> {
        let mut rig = self.spec.rig;
        rig.mu_kinetic = self.spec.mu_kinetic.at(draws.mu_kinetic[i]);
        rig.mu_static = match &self.spec.mu_static {
            Some(u) => u.at(draws.mu_static[i]).max(rig.mu_kinetic),
            None => rig.mu_kinetic,
        };
        for (k, (q, u)) in self.spec.law_uncertain.iter().enumerate().take(2) {
            let z = draws.law[i][k];
            match (q, u) {
                // A split may take either sign: no clamp at zero.
                (Param::FrictionSplit, Uncertain::Normal { mean, sd }) => {
                    rig.kinetic_split = mean + sd * z;
                    rig.static_split = rig.kinetic_split;
                }
                (Param::StribeckVelocity, u) => rig.stribeck_velocity = u.at(z).max(1e-9),
                (Param::LoadExponent, u) => rig.load_exponent = u.at(z),
                _ => {}
            }
        }
        rig
    }

    /// Simulate and judge one run; a run the simulator cannot finish counts as a failure.
    pub fn run(
        &self,
        rig: &Rig<f64>,
        y0: &State<f64>,
        request: &Request,
    ) -> Option<(Solution<f64>, Evaluation)> {
        let sol = simulate(rig, y0, self.spec.camera.duration, &self.options, request).ok()?;
        let ev = self.criteria.evaluate(rig, y0, &sol);
        Some((sol, ev))
    }

    /// Whether the release passes every criterion at the nominal friction.
    pub fn nominal_ok(&self, p: &ReleaseValues) -> bool {
        self.run(&self.spec.rig, &self.initial(p), &Request::default())
            .is_some_and(|(_, e)| e.ok)
    }

    /// Number of draws (friction and execution error) in which the release passes.
    pub fn passes(&self, p: &ReleaseValues, draws: &Draws) -> usize {
        let err = self.spec.release.error;
        (0..draws.len())
            .filter(|&i| {
                let u = draws.release[i];
                let q = [
                    p[0] + err[0] * u[0],
                    p[1] + err[1] * u[1],
                    p[2] + err[2] * u[2],
                ];
                let rig = self.rig_of(draws, i);
                self.run(&rig, &self.initial(&q), &Request::default())
                    .is_some_and(|(_, e)| e.ok)
            })
            .count()
    }

    /// Predicted standard error of mu_kinetic from a recording of this release with the
    /// plan's camera: sqrt of the (mu, mu) element of (J^T J)^-1, J the Jacobian of the
    /// noise-weighted marker residuals with respect to mu and the whole initial state (the
    /// nuisance), at the nominal friction. With an earlier fit's knowledge (`prior`), J also
    /// holds the rig's parameters that fit estimated; the release's information about them,
    /// its own initial state marginalised (a Schur complement), is added to the fit's, and
    /// the error is mu's after both. Infinite when mu is not identifiable.
    pub fn mu_stderr(&self, p: &ReleaseValues) -> f64 {
        self.mu_stderr_on(&self.all_frames(), p)
    }

    /// [`Evaluator::mu_stderr`] from the frames `frames`.
    pub fn mu_stderr_on(&self, frames: &Frames, p: &ReleaseValues) -> f64 {
        let extra: &[Param] = match (&self.spec.prior, &self.spec.mu_static) {
            (None, Some(_)) => &[Param::MuStatic],
            _ => &[],
        };
        self.stderrs_on(frames, &self.spec.rig, &self.initial(p), extra)
            .and_then(|v| v.into_iter().find(|(q, _)| *q == Param::MuKinetic))
            .map_or(f64::INFINITY, |(_, se)| se)
    }

    /// Every frame of the plan's camera.
    fn all_frames(&self) -> Frames {
        Frames {
            obs: self.obs.clone(),
            noise: self.spec.camera.noise_m,
        }
    }

    /// Predicted standard errors of the rig's parameters (mu_kinetic, an earlier fit's
    /// parameters, and `extra`) from a recording of release `y0` of `rig`, the release's own
    /// initial state marginalised and an earlier fit's knowledge added; infinite for one
    /// the recording cannot pin down, `None` when the run fails.
    pub fn stderrs(
        &self,
        rig: &Rig<f64>,
        y0: &State<f64>,
        extra: &[Param],
    ) -> Option<Vec<(Param, f64)>> {
        self.stderrs_on(&self.all_frames(), rig, y0, extra)
    }

    /// [`Evaluator::stderrs`] from the frames `frames`.
    fn stderrs_on(
        &self,
        frames: &Frames,
        rig: &Rig<f64>,
        y0: &State<f64>,
        extra: &[Param],
    ) -> Option<Vec<(Param, f64)>> {
        self.stderrs_with(frames, rig, y0, None, extra)
    }

    /// [`Evaluator::stderrs_on`], with the recording already made (`before`, its release,
    /// recorded with the plan's camera) fitted jointly under `rig` when given: each release's
    /// information about the rig's parameters, its own initial state marginalised, summed.
    /// The earlier fit then adds only what it knew of the rig's measured build, not its mu:
    /// that fit's mu is the coefficient of the law it chose (Coulomb's, read from slides one
    /// way, say), which under another law is a combination of that law's parameters (mu
    /// plus the split toward the way it slid); the earlier recording's own information under
    /// `rig` says which.
    fn stderrs_with(
        &self,
        frames: &Frames,
        rig: &Rig<f64>,
        y0: &State<f64>,
        before: Option<&State<f64>>,
        extra: &[Param],
    ) -> Option<Vec<(Param, f64)>> {
        let state = [Param::X, Param::Theta, Param::XDot, Param::ThetaDot];
        let mut free: Vec<Param> = match &self.spec.prior {
            Some(prior) => prior.names.clone(),
            None => vec![Param::MuKinetic],
        };
        let known = free.len();
        free.extend(
            extra
                .iter()
                .filter(|q| !free.contains(q))
                .collect::<Vec<_>>(),
        );
        let rig_params = free.len();
        free.extend(state);
        let infinite = || {
            free[..rig_params]
                .iter()
                .map(|&q| (q, f64::INFINITY))
                .collect()
        };
        // One release's information about the rig's parameters, its state marginalised
        // (a Schur complement); `Some(None)` when its state is not identifiable.
        let release_info = |y: &State<f64>| -> Option<Option<DMatrix<f64>>> {
            let mut problem =
                TrajectoryProblem::new(frames.obs.clone(), *rig, *y, free.clone(), self.options);
            problem.tie_static = !free.contains(&Param::MuStatic);
            let noise = frames.noise;
            problem.sigma = [noise, noise];
            let normal = problem.normal_equations(&problem.values()).ok()?;
            let k = free.len();
            let a = normal.jtj.view((0, 0), (rig_params, rig_params));
            let b = normal
                .jtj
                .view((0, rig_params), (rig_params, k - rig_params));
            let c = normal
                .jtj
                .view((rig_params, rig_params), (k - rig_params, k - rig_params))
                .into_owned();
            Some(c.cholesky().map(|ch| a - b * ch.inverse() * b.transpose()))
        };
        let Some(mut info) = release_info(y0)? else {
            return Some(infinite());
        };
        if let Some(y) = before {
            match release_info(y)? {
                Some(i) => info += i,
                None => return Some(infinite()),
            }
        }
        if let Some(prior) = &self.spec.prior {
            let mut prior_info = prior.information.clone();
            if before.is_some() {
                // The earlier recording counts through its own information; the fit adds the
                // rig's build (mu's row and column out).
                if let Some(i) = prior.names.iter().position(|&q| q == Param::MuKinetic) {
                    prior_info.row_mut(i).fill(0.0);
                    prior_info.column_mut(i).fill(0.0);
                }
            }
            let mut block = info.view_mut((0, 0), (known, known));
            block += &prior_info;
        }
        let Some(ch) = info.cholesky() else {
            return Some(infinite());
        };
        let cov = ch.inverse();
        Some(
            free[..rig_params]
                .iter()
                .enumerate()
                .map(|(i, &q)| {
                    let var = cov[(i, i)];
                    (
                        q,
                        if var.is_finite() && var > 0.0 {
                            var.sqrt()
                        } else {
                            f64::INFINITY
                        },
                    )
                })
                .collect(),
        )
    }

    /// The laws whose errors a plan predicts, each on its rig: the weighed laws at their
    /// reference departures (or given values); without laws to weigh, the plan's own law when
    /// it has parameters beyond mu.
    fn law_rigs(&self) -> Vec<(super::law::Law, Rig<f64>)> {
        use super::law::{reference_rig, Law};
        match &self.laws {
            Some(l) => l.candidates.clone(),
            None => {
                let own = Law::of_rig(&self.spec.rig);
                if own == Law::Coulomb {
                    return Vec::new();
                }
                vec![(own, reference_rig(&self.spec.rig, own))]
            }
        }
    }

    /// One law's predicted standard errors on `rig` from a recording of `y0` (with the
    /// recording already made, when its release is known, under each law but the one its fit
    /// chose: that one's mu is the fit's knowledge already).
    fn law_se(
        &self,
        frames: &Frames,
        y0: &State<f64>,
        law: super::law::Law,
        rig: &Rig<f64>,
    ) -> Option<Vec<(Param, f64)>> {
        let chosen = super::law::Law::of_rig(&self.spec.rig);
        let before = self.laws.as_ref().and_then(|l| l.before_release);
        let before = before.as_ref().filter(|_| law != chosen);
        self.stderrs_with(frames, rig, y0, before, law.params())
    }

    /// Predicted standard errors of each weighed law's parameters (mu_kinetic and its own,
    /// at its reference departure, with their range over [`super::law::DEPARTURE_SCALES`])
    /// from a recording of this release; without laws to weigh, those of the plan's own law
    /// when it has parameters beyond mu. The ranges over mu
    /// ([`super::law::LawError::mu_range`]) are left out: [`Evaluator::add_mu_ranges`] adds
    /// them to the best proposal a plan reports.
    pub fn law_stderr(&self, p: &ReleaseValues) -> Vec<super::law::LawError> {
        use super::law::{departure_rig, Law, LawError, DEPARTURE_SCALES};
        let y0 = self.initial(p);
        let frames = self.all_frames();
        let chosen = Law::of_rig(&self.spec.rig);
        let mut out = Vec::new();
        for (law, rig) in self.law_rigs() {
            let se = |r: &Rig<f64>| self.law_se(&frames, &y0, law, r);
            let Some(ses) = se(&rig) else {
                continue;
            };
            // A law at a reference departure (not the plan's or the fit's own values, and
            // with a departure at all): its errors at the other departures too.
            let referenced = law != Law::Coulomb && chosen != law;
            let others: Vec<Vec<(Param, f64)>> = match referenced {
                true => DEPARTURE_SCALES
                    .iter()
                    // A departure the release cannot be run at shows nothing.
                    .map(|&k| se(&departure_rig(&self.spec.rig, law, k)).unwrap_or_default())
                    .collect(),
                false => Vec::new(),
            };
            for (q, se) in ses {
                if q == Param::MuKinetic || law.params().contains(&q) {
                    out.push(LawError {
                        law,
                        param: q,
                        stderr: se,
                        range: referenced.then(|| span_of(q, se, &others)),
                        mu_range: None,
                    });
                }
            }
        }
        out
    }

    /// Fill in each error's range over mu ([`super::law::LawError::mu_range`]): the law's
    /// coefficients scaled by mu_kinetic one standard deviation either side of the plan's.
    /// Two more predictions per law, paid only by the best proposal a plan reports; nothing
    /// when mu is given exactly.
    pub fn add_mu_ranges(&self, p: &ReleaseValues, errors: &mut [super::law::LawError]) {
        let (mu, sd) = self.spec.mu_kinetic.mean_sd();
        if errors.is_empty() || sd <= 0.0 || mu <= 0.0 {
            return;
        }
        let factors = [((mu - sd) / mu).max(0.0), (mu + sd) / mu];
        let y0 = self.initial(p);
        let frames = self.all_frames();
        for (law, rig) in self.law_rigs() {
            let at_mu: Vec<Vec<(Param, f64)>> = factors
                .iter()
                .map(|&k| {
                    self.law_se(&frames, &y0, law, &super::law::scaled_friction(&rig, k))
                        .unwrap_or_default()
                })
                .collect();
            for e in errors.iter_mut().filter(|e| e.law == law) {
                e.mu_range = Some(span_of(e.param, e.stderr, &at_mu));
            }
        }
    }
}

/// The smallest and largest of `se` and parameter `q`'s errors in `of` (infinite where one
/// does not show it).
fn span_of(q: Param, se: f64, of: &[Vec<(Param, f64)>]) -> [f64; 2] {
    of.iter()
        .map(|v| {
            v.iter()
                .find(|(p, _)| *p == q)
                .map_or(f64::INFINITY, |(_, s)| *s)
        })
        .fold([se, se], |[lo, hi], s| [lo.min(s), hi.max(s)])
}

/// A release judged by the search.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Candidate {
    /// The release.
    pub release: ReleaseValues,
    /// Fraction of the search's draws that pass.
    pub robustness: f64,
    /// Predicted standard error of mu.
    pub stderr: f64,
    /// When the plan weighs laws, the expected number of pairs of laws a fit will resolve
    /// ([`super::discriminate::Laws::score`]); NaN when it does not.
    pub separation: f64,
    /// Whether the plan weighs laws and every pair's expected margin reaches
    /// [`super::discriminate::MARGIN_CAP`]: a release that moves can then only trade mu's
    /// precision against margins that buy nothing.
    pub saturated: bool,
}

/// One pair of laws told apart, in the units of [`Candidate::objective`]: a hundred
/// e-folds of mu's standard error.
pub const PAIR: f64 = 100.0;

impl Candidate {
    /// What the search minimises: log stderr, or, when the plan weighs laws, log stderr
    /// minus a hundred times the separation (so releases that tell the laws apart equally
    /// well are ranked by mu's precision, and a tenth of a pair outweighs any precision a box
    /// offers); plus a steep penalty for every bit of robustness missing (a constraint
    /// softened so Nelder-Mead can feel its way back), worth twenty units of the ranking
    /// (twenty e-folds of stderr, or twenty pairs).
    pub fn objective(&self, min_robustness: f64) -> f64 {
        let missing = (min_robustness - self.robustness).max(0.0);
        if self.separation.is_nan() {
            return self.stderr.ln() + 20.0 * missing;
        }
        // A separation never computed (-inf) ranks last, but finitely.
        PAIR * (20.0 * missing - self.separation.max(-1e6)) + self.stderr.ln().clamp(-1e3, 1e3)
    }

    /// Whether the search can use it: mu identifiable, and under a law plan its separation
    /// computed.
    pub fn usable(&self) -> bool {
        self.stderr.is_finite() && self.separation != f64::NEG_INFINITY
    }
}

/// The grid of the release box: `n` points along theta, fewer along the push and the moving
/// start, one along any range of zero width.
pub fn grid(ranges: &[[f64; 2]; 3], n: usize) -> Vec<ReleaseValues> {
    let counts = [n, n.div_ceil(3) * 2 - 1, n.div_ceil(2)];
    let axis = |k: usize| -> Vec<f64> {
        let [lo, hi] = ranges[k];
        if hi <= lo {
            return vec![lo];
        }
        let m = counts[k].max(2);
        (0..m)
            .map(|i| lo + (hi - lo) * i as f64 / (m - 1) as f64)
            .collect()
    };
    let (a, b, c) = (axis(0), axis(1), axis(2));
    let mut out = Vec::with_capacity(a.len() * b.len() * c.len());
    for &t in &a {
        for &w in &b {
            for &v in &c {
                out.push([t, w, v]);
            }
        }
    }
    out
}

/// Judge releases on the nominal run, then (passing ones) on the draws and the Fisher
/// information. Releases failing the nominal run are dropped.
pub fn screen(
    ev: &Evaluator,
    points: &[ReleaseValues],
    draws: &Draws,
    bar: &ProgressBar,
) -> Vec<Candidate> {
    points
        .par_iter()
        .filter_map(|p| {
            let ok = ev.nominal_ok(p);
            let out = ok.then(|| ev.candidate(p, draws));
            bar.inc(1);
            out
        })
        .collect()
}

/// The release box as ranges (theta, theta', x').
pub fn release_box(spec: &PlanSpec) -> [[f64; 2]; 3] {
    let r = &spec.release;
    [r.theta, r.theta_dot, r.x_dot]
}

/// The release values of an initial state (x, theta, x', theta'): (theta, theta', x').
pub fn release_values(y: &State<f64>) -> ReleaseValues {
    [y[1], y[3], y[2]]
}

/// How far apart proposals must be, as a fraction of the release box's diagonal (see
/// [`box_distance`]): one eighth, so that no two proposals are near-copies (the old rule let
/// five releases sit 0.5 rad/s apart on one edge of a 4 rad/s range) while a box still holds
/// several.
pub const MIN_SEPARATION: f64 = 0.125;

/// The distance between two releases as a fraction of the release box's diagonal: each varied
/// quantity's difference divided by its allowed range, then the Euclidean length divided by
/// sqrt(number of varied quantities), so opposite corners are 1 apart. Quantities the plan
/// fixes (a range of zero width) do not count; with none varied every distance is 0.
pub fn box_distance(ranges: &[[f64; 2]; 3], a: &ReleaseValues, b: &ReleaseValues) -> f64 {
    let (sum, varied) = ranges
        .iter()
        .zip(a.iter().zip(b))
        .filter(|([lo, hi], _)| hi > lo)
        .fold((0.0, 0usize), |(sum, n), ([lo, hi], (x, y))| {
            (sum + ((x - y) / (hi - lo)).powi(2), n + 1)
        });
    if varied == 0 {
        0.0
    } else {
        (sum / varied as f64).sqrt()
    }
}

/// Nelder-Mead's cost: the objective over the box scaled to the unit cube, with releases
/// outside the box (or failing at the nominal friction) priced out.
struct Refine<'e, 'a> {
    ev: &'e Evaluator<'a>,
    draws: &'e Draws,
    ranges: [[f64; 2]; 3],
    dims: Vec<usize>,
    base: ReleaseValues,
    /// When the plan weighs laws: how many evaluations in a row may fail to better the best
    /// release before the refinement stops simulating ([`Refine::cost`]).
    patience: Option<usize>,
    /// The best cost so far and the evaluations since it.
    stall: Mutex<(f64, usize)>,
}

/// The cost of every step once a refinement has stalled: above any release's.
const STALLED: f64 = 1e12;

impl Refine<'_, '_> {
    fn release(&self, u: &[f64]) -> (ReleaseValues, f64) {
        let mut p = self.base;
        let mut outside = 0.0;
        for (&k, &v) in self.dims.iter().zip(u) {
            let c = v.clamp(0.0, 1.0);
            outside += (v - c).abs();
            let [lo, hi] = self.ranges[k];
            p[k] = lo + (hi - lo) * c;
        }
        (p, outside)
    }

    fn unit(&self, p: &ReleaseValues) -> Vec<f64> {
        self.dims
            .iter()
            .map(|&k| {
                let [lo, hi] = self.ranges[k];
                (p[k] - lo) / (hi - lo)
            })
            .collect()
    }

    fn candidate(&self, u: &[f64]) -> Option<Candidate> {
        let (p, _) = self.release(u);
        self.ev
            .nominal_ok(&p)
            .then(|| self.ev.candidate(&p, self.draws))
    }
}

impl CostFunction for Refine<'_, '_> {
    type Param = Vec<f64>;
    type Output = f64;

    /// The objective, with releases outside the box priced by their distance to it. Once
    /// `patience` evaluations in a row have not bettered the best, every further step costs
    /// [`STALLED`] without a simulation: Nelder-Mead then ends on the best release it found.
    /// (Under laws the objective moves in steps of a pair's chance. On three heavy-rig plans
    /// the best grid release never gained in sixty evaluations, and the others' gains never
    /// overtook it: the proposals came out the same, for a fifth less CPU.)
    fn cost(&self, u: &Vec<f64>) -> Result<f64, Error> {
        let stalled = |s: &(f64, usize)| self.patience.is_some_and(|n| s.1 >= n);
        if self.stall.lock().is_ok_and(|s| stalled(&s)) {
            return Ok(STALLED);
        }
        let (_, outside) = self.release(u);
        let min_rob = self.ev.spec.goal.min_robustness;
        let value = match self.candidate(u) {
            Some(c) if c.usable() => c.objective(min_rob),
            _ => 1e6,
        } + 1e3 * outside;
        if let Ok(mut s) = self.stall.lock() {
            *s = if value < s.0 {
                (value, 0)
            } else {
                (s.0, s.1 + 1)
            };
        }
        Ok(value)
    }
}

/// Refine a grid candidate by Nelder-Mead within the box; returns the better of the start
/// and the end.
pub fn refine(ev: &Evaluator, draws: &Draws, start: &Candidate, iters: u64) -> Candidate {
    let ranges = release_box(ev.spec);
    let dims: Vec<usize> = (0..3).filter(|&k| ranges[k][1] > ranges[k][0]).collect();
    if dims.is_empty() {
        return *start;
    }
    // Under laws: about four Nelder-Mead iterations' worth of steps (the simplex's size).
    let patience = ev.laws.is_some().then_some(4 * (dims.len() + 1));
    let problem = |patience| Refine {
        ev,
        draws,
        ranges,
        dims: dims.clone(),
        base: start.release,
        patience,
        stall: Mutex::new((f64::INFINITY, 0)),
    };
    let moving = problem(patience);
    let u0 = moving.unit(&start.release);
    // A simplex of about one grid cell around the start.
    let step = 1.0 / (ev.spec.search.grid_points.max(2) - 1) as f64;
    let mut simplex = vec![u0.clone()];
    for i in 0..dims.len() {
        let mut v = u0.clone();
        v[i] += if v[i] + step <= 1.0 { step } else { -step };
        simplex.push(v);
    }
    let solver = NelderMead::new(simplex)
        .with_sd_tolerance(1e-3)
        .expect("a positive tolerance");
    let best = Executor::new(moving, solver)
        .configure(|s| s.max_iters(iters))
        .run()
        .ok()
        .and_then(|r| r.state.best_param.clone());
    let min_rob = ev.spec.goal.min_robustness;
    best.and_then(|u| problem(None).candidate(&u))
        .filter(|c| c.usable() && c.objective(min_rob) < start.objective(min_rob))
        .unwrap_or(*start)
}

/// One-sided 95% Wilson lower bound of a pass fraction: what a proposal claims, so that an
/// independent Monte Carlo with more draws sees at least that much.
pub fn robustness_lower_bound(passed: usize, n: usize) -> f64 {
    if n == 0 {
        return 0.0;
    }
    let z: f64 = 1.645;
    let nf = n as f64;
    let p = passed as f64 / nf;
    let z2 = z * z;
    let centre = p + z2 / (2.0 * nf);
    let half = z * (p * (1.0 - p) / nf + z2 / (4.0 * nf * nf)).sqrt();
    ((centre - half) / (1.0 + z2 / nf)).clamp(0.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wilson_bound_is_below_the_fraction_and_tightens() {
        assert!(robustness_lower_bound(400, 400) > 0.99);
        assert!(robustness_lower_bound(400, 400) < 1.0);
        let a = robustness_lower_bound(90, 100);
        let b = robustness_lower_bound(900, 1000);
        assert!(a < b && b < 0.9);
    }

    #[test]
    fn box_distance_is_a_fraction_of_the_diagonal() {
        let ranges = [[0.0, 2.0], [-1.0, 1.0], [0.5, 0.5]];
        let corner = box_distance(&ranges, &[0.0, -1.0, 0.5], &[2.0, 1.0, 0.5]);
        assert!((corner - 1.0).abs() < 1e-12);
        // A fixed quantity does not count; half of one of two ranges is sqrt(1/8) of the diagonal.
        let half = box_distance(&ranges, &[1.0, 0.0, 0.5], &[1.0, 1.0, 9.0]);
        assert!((half - 0.125f64.sqrt()).abs() < 1e-12);
        assert_eq!(box_distance(&[[1.0, 1.0]; 3], &[0.0; 3], &[5.0; 3]), 0.0);
    }

    #[test]
    fn grid_collapses_zero_width_ranges() {
        let g = grid(&[[0.0, 1.0], [0.0, 0.0], [0.0, 0.0]], 13);
        assert_eq!(g.len(), 13);
        let g = grid(&[[0.0, 1.0], [-1.0, 1.0], [0.0, 0.0]], 13);
        assert_eq!(g.len(), 13 * 9);
    }
}
