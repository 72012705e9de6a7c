//! The estimation problem: predicted minus observed marker positions at every frame with data,
//! weighted per marker, as a function of the free parameters (rig and initial state).
//!
//! The parameters' names ([`Param`]) live with the model, below scenes and the fit; `normal.rs` holds the exact normal equations by dual
//! numbers; this file holds the observations, the problem's layout, its parameter vector and
//! its residuals.

mod normal;

pub use crate::model::Param;

/// The most parameters a fit frees at once (the dual-number Jacobian is built for each count).
pub const MAX_FREE: usize = 12;

use crate::fit::priors::{Plausibility, Prior};
use crate::model::{markers, observed_markers, Camera, Rig, Scalar, State};
use crate::sim::{simulate_each, Options, Request, Sample, SimError};
use argmin::core::Error;
use nalgebra::DVector;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

/// Marker observations in the rail frame (metres, y up), times in seconds from the first frame.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Observations {
    /// Frame times (s), ascending, starting at 0.
    pub times: Vec<f64>,
    /// Slider position per frame, `None` where missing.
    pub slider: Vec<Option<[f64; 2]>>,
    /// Bob position per frame, `None` where missing.
    pub bob: Vec<Option<[f64; 2]>>,
}

impl Observations {
    /// The first `n` frames (all of them when there are fewer).
    pub fn prefix(&self, n: usize) -> Observations {
        let n = n.min(self.times.len());
        Observations {
            times: self.times[..n].to_vec(),
            slider: self.slider[..n].to_vec(),
            bob: self.bob[..n].to_vec(),
        }
    }
}

/// Which frames hold data, the requested sample times and the row count: fixed by the
/// observations, so a problem's many clones share one copy.
#[derive(Debug)]
struct Layout {
    /// Index into the observations of each frame with data.
    obs_index: Vec<usize>,
    /// Samples at the frame times with data, nothing else.
    request: Request,
    /// Residual rows: two per marker position present.
    n_rows: usize,
}

/// One residual row: which frame (among the frames with data), which marker (0 slider, 1 bob),
/// which coordinate, and the observed value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RowInfo {
    /// Frame index among the frames with data.
    pub frame: usize,
    /// 0 slider, 1 bob.
    pub marker: usize,
    /// 0 x, 1 y.
    pub coord: usize,
    /// Observed value (m).
    pub observed: f64,
}

/// The residual rows of a problem in order ([`TrajectoryProblem::rows`]): a plain loop over
/// (frame, marker, coordinate), since the rows are walked several times a fit and nested
/// iterator adapters cost several times as much per row.
#[derive(Debug, Clone)]
pub struct Rows<'a> {
    obs_index: &'a [usize],
    obs: &'a Observations,
    frame: usize,
    marker: usize,
    coord: usize,
}

impl Iterator for Rows<'_> {
    type Item = RowInfo;

    #[inline]
    fn next(&mut self) -> Option<RowInfo> {
        loop {
            let &i = self.obs_index.get(self.frame)?;
            let position = match self.marker {
                0 => self.obs.slider[i],
                1 => self.obs.bob[i],
                // Both markers done: the next frame.
                _ => {
                    (self.frame, self.marker) = (self.frame + 1, 0);
                    continue;
                }
            };
            match position {
                Some(p) => {
                    let row = RowInfo {
                        frame: self.frame,
                        marker: self.marker,
                        coord: self.coord,
                        observed: p[self.coord],
                    };
                    self.coord += 1;
                    if self.coord == 2 {
                        (self.marker, self.coord) = (self.marker + 1, 0);
                    }
                    return Some(row);
                }
                // A marker missing in this frame has no rows.
                None => self.marker += 1,
            }
        }
    }
}

/// The residual function of a fit: fixed values, free parameters, weights.
#[derive(Debug, Clone)]
pub struct TrajectoryProblem {
    obs: Arc<Observations>,
    /// Rig holding the values of parameters that are not free.
    pub rig: Rig<f64>,
    /// Initial state holding the values of parameters that are not free.
    pub initial: State<f64>,
    /// Camera and marker model holding the values of its parameters that are not free.
    pub camera: Camera<f64>,
    /// Free parameters, in the order of the parameter vector.
    pub free: Vec<Param>,
    /// Keep mu_static equal to mu_kinetic while mu_static is not free.
    pub tie_static: bool,
    /// Integrator settings for every prediction.
    pub options: Options,
    /// Noise scale per marker (slider, bob) in metres: residuals are divided by it.
    pub sigma: [f64; 2],
    /// Extra weight per row (robust loss, outliers at zero); `None` while every weight is one,
    /// so the common case stores nothing per row.
    weights: Option<Arc<Vec<f64>>>,
    /// The frame times' noise (s, [`crate::fit::noise::frame_time_noise`]): each row's noise
    /// is sigma and v times it in quadrature, v the marker's speed along the row's coordinate
    /// ([`Self::set_time_noise`]). 0: exact times.
    pub time_noise: f64,
    layout: Arc<Layout>,
    /// Evaluations of this problem and its clones, for the report.
    pub counters: Arc<Counters>,
    /// Gaussian priors on parameters (the rig file's measurements, the nuisances' plausible
    /// ranges): each free one adds ((value - centre) / sd)^2 to the chi-square, its cost and
    /// normal equations (a pseudo-observation); one not free adds nothing.
    pub priors: Arc<Vec<Prior>>,
    /// The nuisances' plausible ranges and the rig file's mass ratio, to judge a fitted
    /// model's values ([`crate::fit::implausible::implausible`]).
    pub plausible: Arc<Plausibility>,
}

/// How often a fit evaluated its residuals and its Jacobian (shared by a problem's clones).
#[derive(Debug, Default)]
pub struct Counters {
    /// Residual evaluations (one simulation each).
    pub residuals: AtomicU64,
    /// Jacobian evaluations (one simulation in dual numbers each).
    pub jacobians: AtomicU64,
}

impl TrajectoryProblem {
    /// A problem over `obs` with the given fixed values and free parameters.
    pub fn new(
        obs: Arc<Observations>,
        rig: Rig<f64>,
        initial: State<f64>,
        free: Vec<Param>,
        options: Options,
    ) -> Self {
        let len = obs.times.len();
        Self::window(obs, 0..len, 0.0, rig, initial, free, options)
    }

    /// [`Self::new`] over the frames `range` of `obs` only, sharing them (a long recording's
    /// fit of its first frames, a stretch of it fitted alone, need no copy of them), with
    /// time `t0` as the run's zero. Its residuals, normal equations and rows cover those
    /// frames; [`Self::observations`] still gives all of `obs` (a solver needs no more than
    /// the former).
    pub fn window(
        obs: Arc<Observations>,
        range: std::ops::Range<usize>,
        t0: f64,
        rig: Rig<f64>,
        initial: State<f64>,
        free: Vec<Param>,
        options: Options,
    ) -> Self {
        let end = range.end.min(obs.times.len());
        let start = range.start.min(end);
        // Sized once: a 10^6-frame recording would otherwise hold up to twice this while growing.
        let mut obs_index = Vec::with_capacity(end - start);
        let mut frames = Vec::with_capacity(end - start);
        let mut n_rows = 0;
        for i in start..end {
            let (s, b) = (&obs.slider[i], &obs.bob[i]);
            let present = usize::from(s.is_some()) + usize::from(b.is_some());
            if present > 0 {
                n_rows += 2 * present;
                obs_index.push(i);
                frames.push(obs.times[i] - t0);
            }
        }
        TrajectoryProblem {
            obs,
            rig,
            initial,
            camera: Camera::default(),
            free,
            tie_static: true,
            options,
            sigma: [1.0, 1.0],
            weights: None,
            time_noise: 0.0,
            layout: Arc::new(Layout {
                obs_index,
                // Markers need positions only (a lag, which needs velocities, asks again).
                request: Request {
                    sample_times: frames,
                    friction_work: false,
                    positions_only: true,
                },
                n_rows,
            }),
            counters: Arc::new(Counters::default()),
            priors: Arc::new(Vec::new()),
            plausible: Arc::new(Plausibility::default()),
        }
    }

    /// The prior on `q` when it acts: a rigid pendulum's equivalent mass ratio (its length
    /// free) is not the masses' ratio, so the masses' prior leaves it.
    pub fn prior_on(&self, q: Param) -> Option<&Prior> {
        self.prior_within(q, &self.free)
    }

    /// The prior on `q` in this model with `free` as its free parameters ([`Self::prior_on`]):
    /// the score test weighs each candidate's model without building it.
    pub fn prior_within(&self, q: Param, free: &[Param]) -> Option<&Prior> {
        if q == Param::MassRatio && free.contains(&Param::PendulumLength) {
            return None;
        }
        self.priors.iter().find(|pr| pr.param == q)
    }

    /// d(rod_length)/d(marker_length): how far the dynamics' length moves with the rod length
    /// while [`Param::PendulumLength`] is not free ([`Self::apply`]).
    pub fn length_ratio(&self) -> f64 {
        self.rig.rod_length / self.rig.marker_length
    }

    /// Each free parameter with a prior at `p`: its index, standardised distance from the
    /// centre and the prior's standard deviation.
    pub fn prior_rows<'a>(&'a self, p: &'a [f64]) -> impl Iterator<Item = (usize, f64, f64)> + 'a {
        self.free.iter().enumerate().filter_map(move |(i, &q)| {
            self.prior_on(q)
                .map(|pr| (i, (p[i] - pr.centre) / pr.sd, pr.sd))
        })
    }

    /// The priors' share of the chi-square at `p`.
    pub fn prior_chi2(&self, p: &[f64]) -> f64 {
        self.prior_rows(p).map(|(_, r, _)| r * r).sum()
    }

    /// The same model, values and settings over other observations (every row weight one;
    /// the counters stay shared).
    pub fn on(&self, obs: Arc<Observations>) -> TrajectoryProblem {
        let len = obs.times.len();
        self.on_prefix(obs, len)
    }

    /// [`Self::on`] over the first `len` frames of `obs`, shared, not copied
    /// ([`Self::window`]).
    pub fn on_prefix(&self, obs: Arc<Observations>, len: usize) -> TrajectoryProblem {
        let mut pr = TrajectoryProblem::window(
            obs,
            0..len,
            0.0,
            self.rig,
            self.initial,
            self.free.clone(),
            self.options,
        );
        pr.camera = self.camera;
        pr.priors = self.priors.clone();
        pr.plausible = self.plausible.clone();
        pr.tie_static = self.tie_static;
        pr.sigma = self.sigma;
        pr.counters = self.counters.clone();
        pr.set_time_noise(self.time_noise);
        pr
    }

    /// Take the frame times' noise `sigma_t` (s) into every row's weight: a position recorded
    /// at a time off by dt is off by v dt, v the marker's speed along the row's coordinate, so
    /// the row's noise is sqrt(sigma^2 + (v sigma_t)^2) with sigma the marker's (set
    /// [`Self::sigma`] first). v comes from the track itself (the positions about 5 ms either
    /// side, at least the neighbours), never from the model, so no misfit can hide in it. Rows
    /// whose weight would stay within a thousandth of one keep it, and a recording none of
    /// whose rows moves is left as it is (nothing stored). Returns whether any weight changed.
    pub fn set_time_noise(&mut self, sigma_t: f64) -> bool {
        self.time_noise = sigma_t;
        if sigma_t.is_nan() || sigma_t <= 0.0 {
            return false;
        }
        let obs = self.obs.clone();
        let step = frame_step(&obs.times);
        let span = ((0.005 / step).round() as usize).max(1);
        let speed = |marker: usize, coord: usize, i: usize| -> f64 {
            let track = if marker == 0 { &obs.slider } else { &obs.bob };
            let lo = i.saturating_sub(span);
            let hi = (i + span).min(track.len() - 1);
            match (track[lo], track[hi]) {
                (Some(a), Some(b)) if hi > lo => {
                    (b[coord] - a[coord]) / (obs.times[hi] - obs.times[lo])
                }
                _ => 0.0,
            }
        };
        let weights: Vec<f64> = self
            .rows()
            .map(|row| {
                let i = self.layout.obs_index[row.frame];
                let s = self.sigma[row.marker];
                let vt = speed(row.marker, row.coord, i) * sigma_t;
                s / (s * s + vt * vt).sqrt()
            })
            .collect();
        if weights.iter().all(|w| *w > 0.999) {
            return false;
        }
        let merged = (0..weights.len())
            .map(|r| self.row_weight(r) * weights[r])
            .collect();
        self.set_row_weights(merged);
        true
    }

    /// Every residual row in order: frame-major, the slider before the bob, x before y.
    pub fn rows(&self) -> Rows<'_> {
        Rows {
            obs_index: &self.layout.obs_index,
            obs: &self.obs,
            frame: 0,
            marker: 0,
            coord: 0,
        }
    }

    /// The observations.
    pub fn observations(&self) -> &Observations {
        &self.obs
    }

    /// The observations, shared.
    pub fn shared_observations(&self) -> &Arc<Observations> {
        &self.obs
    }

    /// Number of residual rows.
    pub fn n_rows(&self) -> usize {
        self.layout.n_rows
    }

    /// Extra weight of row `row` (1 unless a robust loss or an outlier set it).
    pub fn row_weight(&self, row: usize) -> f64 {
        self.weights.as_ref().map_or(1.0, |w| w[row])
    }

    /// Set every row's extra weight (`weights.len()` must be [`Self::n_rows`]).
    pub fn set_row_weights(&mut self, weights: Vec<f64>) {
        debug_assert_eq!(weights.len(), self.n_rows());
        self.weights = Some(Arc::new(weights));
    }

    /// Set the weight of some rows to zero (mis-tracked positions left out).
    pub fn drop_rows(&mut self, rows: impl IntoIterator<Item = usize>) {
        let n = self.n_rows();
        let w = Arc::make_mut(self.weights.get_or_insert_with(|| Arc::new(vec![1.0; n])));
        for r in rows {
            w[r] = 0.0;
        }
    }

    /// At each frame, whether the fit weighs the slider's and the bob's position: `false`
    /// where it is missing, left out as mis-tracked before the fit, or after it (its rows'
    /// weight zero).
    pub fn weighed_positions(&self) -> Vec<[bool; 2]> {
        let mut weighed = vec![[false; 2]; self.obs.times.len()];
        for (row, info) in self.rows().enumerate() {
            if self.row_weight(row) > 0.0 {
                weighed[self.layout.obs_index[info.frame]][info.marker] = true;
            }
        }
        weighed
    }

    /// Rows with a weight above zero.
    pub fn rows_used(&self) -> usize {
        self.weights
            .as_ref()
            .map_or(self.n_rows(), |w| w.iter().filter(|v| **v > 0.0).count())
    }

    /// Current values of the free parameters.
    pub fn values(&self) -> DVector<f64> {
        DVector::from_iterator(self.free.len(), self.free.iter().map(|&p| self.get(p)))
    }

    /// Value of any parameter (free ones as last set with [`Self::set_values`]).
    pub fn get(&self, p: Param) -> f64 {
        match p {
            Param::MuKinetic => self.rig.mu_kinetic,
            Param::MuStatic => self.rig.mu_static,
            Param::X => self.initial[0],
            Param::Theta => self.initial[1],
            Param::XDot => self.initial[2],
            Param::ThetaDot => self.initial[3],
            Param::RodLength => self.rig.marker_length,
            Param::PendulumLength => self.rig.rod_length,
            Param::MassRatio => self.rig.slider_mass / self.rig.bob_mass,
            Param::RailTilt => self.rig.rail_tilt,
            Param::PivotDamping => self.rig.pivot_damping,
            Param::ViscousFriction => self.rig.viscous_friction,
            Param::StribeckVelocity => self.rig.stribeck_velocity,
            Param::FrictionSplit => self.rig.kinetic_split,
            Param::LoadExponent => self.rig.load_exponent,
            Param::ScaleError => self.camera.scale_error,
            Param::BobAlong => self.camera.bob_along,
            Param::BobAcross => self.camera.bob_across,
            Param::SliderDx => self.camera.slider_dx,
            Param::SliderDy => self.camera.slider_dy,
            Param::Lag => self.camera.lag,
            Param::Gravity => self.rig.gravity,
        }
    }

    /// Store a parameter vector into the rig and initial state.
    pub fn set_values(&mut self, v: &DVector<f64>) {
        let (rig, y0, camera) = self.apply::<f64>(v.as_slice());
        self.rig = rig;
        self.initial = y0;
        self.camera = camera;
    }

    /// Rig, initial state and camera for a parameter vector, in any scalar.
    pub fn apply<T: Scalar>(&self, p: &[T]) -> (Rig<T>, State<T>, Camera<T>) {
        let mut rig: Rig<T> = self.rig.lift();
        let mut y0: State<T> = self.initial.map(T::from);
        let mut cam: Camera<T> = self.camera.lift();
        let pendulum_free = self.free.contains(&Param::PendulumLength);
        // A rod length moves a rigid pendulum's equivalent length with it, in proportion.
        let length_ratio = self.length_ratio();
        let total_mass = T::from(self.rig.slider_mass + self.rig.bob_mass);
        for (&param, &v) in self.free.iter().zip(p) {
            match param {
                Param::MuKinetic => rig.mu_kinetic = v,
                Param::MuStatic => rig.mu_static = v,
                Param::X => y0[0] = v,
                Param::Theta => y0[1] = v,
                Param::XDot => y0[2] = v,
                Param::ThetaDot => y0[3] = v,
                Param::RodLength => {
                    rig.marker_length = v;
                    if !pendulum_free {
                        rig.rod_length = if length_ratio == 1.0 {
                            v
                        } else {
                            v * length_ratio
                        };
                    }
                }
                Param::PendulumLength => rig.rod_length = v,
                Param::MassRatio => {
                    rig.bob_mass = total_mass / (v + 1.0);
                    rig.slider_mass = total_mass - rig.bob_mass;
                }
                Param::RailTilt => rig.rail_tilt = v,
                Param::PivotDamping => rig.pivot_damping = v,
                Param::ViscousFriction => rig.viscous_friction = v,
                Param::StribeckVelocity => rig.stribeck_velocity = v,
                // One split for both coefficients: the static ones differ as the kinetic.
                Param::FrictionSplit => {
                    rig.kinetic_split = v;
                    rig.static_split = v;
                }
                Param::LoadExponent => rig.load_exponent = v,
                Param::ScaleError => cam.scale_error = v,
                Param::BobAlong => cam.bob_along = v,
                Param::BobAcross => cam.bob_across = v,
                Param::SliderDx => cam.slider_dx = v,
                Param::SliderDy => cam.slider_dy = v,
                Param::Lag => cam.lag = v,
                Param::Gravity => rig.gravity = v,
            }
        }
        if self.tie_static && !self.free.contains(&Param::MuStatic) {
            rig.mu_static = rig.mu_kinetic;
        }
        (rig, y0, cam)
    }

    /// Simulate with parameters `p` and hand every residual row (predicted - observed, in
    /// metres) to `each(row, frame, marker, residual)` as the simulation passes its frame:
    /// nothing per frame is kept, so a million frames cost no more memory than ten.
    fn for_each_residual<T: Scalar + 'static>(
        &self,
        p: &[T],
        mut each: impl FnMut(usize, usize, usize, T),
    ) -> Result<(), SimError> {
        self.for_each_residual_at(
            p,
            false,
            |_| (),
            |row, frame, marker, _, d, _| each(row, frame, marker, d),
        )
    }

    /// [`Self::for_each_residual`] with a per-frame value: `at(sample)` once per frame, and
    /// `each(row, frame, marker, coord, residual, &value)` for each of its rows. The samples
    /// carry velocities when `velocities` is set or the camera has a lag.
    fn for_each_residual_at<T: Scalar + 'static, X>(
        &self,
        p: &[T],
        velocities: bool,
        mut at: impl FnMut(&Sample<T>) -> X,
        mut each: impl FnMut(usize, usize, usize, usize, T, &X),
    ) -> Result<(), SimError> {
        let (rig, y0, camera) = self.apply(p);
        let layout = &*self.layout;
        let obs = &*self.obs;
        let t_end = layout.request.sample_times.last().copied().unwrap_or(0.0);
        let (mut frame, mut row) = (0, 0);
        // Decided once a run: the ideal camera's positions skip its arithmetic at every frame.
        let ideal = camera.is_ideal();
        let mut sink = |s: Sample<T>| {
            let i = layout.obs_index[frame];
            let m = if ideal {
                markers(&rig, &s.state)
            } else {
                observed_markers(&rig, &camera, s.mode, &s.state)
            };
            let x = at(&s);
            for (marker, pos) in [(0, &obs.slider[i]), (1, &obs.bob[i])] {
                if let Some(o) = pos {
                    for (coord, &observed) in o.iter().enumerate() {
                        each(
                            row,
                            frame,
                            marker,
                            coord,
                            m[2 * marker + coord] - observed,
                            &x,
                        );
                        row += 1;
                    }
                }
            }
            frame += 1;
        };
        let full;
        let request = if velocities || !camera.lag.is_exact_zero() {
            full = Request {
                positions_only: false,
                ..layout.request.clone()
            };
            &full
        } else {
            &layout.request
        };
        let sol = simulate_each(&rig, &y0, t_end, &self.options, request, &mut sink)?;
        if frame < layout.obs_index.len() {
            return Err(SimError::InvalidInput(format!(
                "the model stops at t = {} s (Painleve paradox) before the recording ends",
                sol.final_time
            )));
        }
        Ok(())
    }

    /// Weighted residuals (predicted - observed) / sigma for parameters `p`.
    pub fn weighted<T: Scalar + 'static>(&self, p: &[T]) -> Result<Vec<T>, SimError> {
        let mut out = Vec::with_capacity(self.n_rows());
        self.for_each_residual(p, |row, _, marker, d| {
            out.push(d * (self.row_weight(row) / self.sigma[marker]))
        })?;
        Ok(out)
    }

    /// Each weighted residual (predicted - observed) / sigma at `p`, in row order, handed to
    /// `each(row, marker, coord, value)` as the simulation passes its frame (one simulation;
    /// nothing per row is kept).
    pub fn for_each_weighted(
        &self,
        p: &[f64],
        mut each: impl FnMut(usize, usize, usize, f64),
    ) -> Result<(), SimError> {
        self.counters.residuals.fetch_add(1, Ordering::Relaxed);
        self.for_each_residual_at(
            p,
            false,
            |_| (),
            |row, _, marker, coord, d, _| {
                each(
                    row,
                    marker,
                    coord,
                    d * (self.row_weight(row) / self.sigma[marker]),
                )
            },
        )
    }

    /// Weighted residuals as a vector (one simulation).
    pub fn residuals(&self, p: &DVector<f64>) -> Result<DVector<f64>, Error> {
        self.counters.residuals.fetch_add(1, Ordering::Relaxed);
        let r = self.weighted(p.as_slice()).map_err(to_err)?;
        Ok(DVector::from_vec(r))
    }

    /// The weighted sum of squares at `p`, summed as the simulation runs (nothing stored),
    /// with the priors' terms ([`Self::prior_chi2`]).
    pub fn chi2(&self, p: &DVector<f64>) -> Result<f64, Error> {
        let mut ss = self.prior_chi2(p.as_slice());
        self.for_each_weighted(p.as_slice(), |_, _, _, v| ss += v * v)
            .map_err(to_err)?;
        Ok(ss)
    }

    /// Unweighted residuals in metres, row by row (pair them with [`Self::rows`]).
    pub fn raw_residuals(&self, p: &DVector<f64>) -> Result<Vec<f64>, SimError> {
        let mut out = Vec::with_capacity(self.n_rows());
        self.for_each_residual(p.as_slice(), |_, _, _, d| out.push(d))?;
        Ok(out)
    }

    /// Frame times with data.
    pub fn frame_times(&self) -> &[f64] {
        &self.layout.request.sample_times
    }
}

/// Where `p` stands in `problem`'s parameter vector (`None` when it is not free).
pub(super) fn idx(problem: &TrajectoryProblem, p: Param) -> Option<usize> {
    problem.free.iter().position(|&f| f == p)
}

fn to_err(e: SimError) -> Error {
    Error::msg(e.to_string())
}

impl From<crate::data::Recording> for Observations {
    /// The recording's tracks moved, not copied (a million frames are 56 MB each way), and
    /// the reader's spare capacity given back.
    fn from(rec: crate::data::Recording) -> Self {
        let (mut times, mut slider, mut bob) = (rec.times, rec.slider, rec.bob);
        times.shrink_to_fit();
        slider.shrink_to_fit();
        bob.shrink_to_fit();
        Observations { times, slider, bob }
    }
}

impl From<&crate::data::Recording> for Observations {
    fn from(rec: &crate::data::Recording) -> Self {
        Observations {
            times: rec.times.clone(),
            slider: rec.slider.clone(),
            bob: rec.bob.clone(),
        }
    }
}

/// The median step between frame times (1 ms for a single frame).
pub fn frame_step(times: &[f64]) -> f64 {
    let mut steps: Vec<f64> = times.windows(2).map(|w| w[1] - w[0]).collect();
    if steps.is_empty() {
        1e-3
    } else {
        crate::data::calibrate::median(&mut steps)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The rows walk frame by frame, the slider before the bob and x before y, skipping a
    /// missing marker's rows, and agree with the row count the layout keeps.
    #[test]
    fn rows_skip_missing_markers_in_order() {
        let p = |v: f64| Some([v, v + 0.5]);
        let obs = Observations {
            times: vec![0.0, 0.001, 0.002, 0.003, 0.004],
            slider: vec![p(1.0), None, p(3.0), None, p(5.0)],
            bob: vec![p(10.0), p(20.0), None, None, p(50.0)],
        };
        let free = vec![Param::MuKinetic];
        let problem = TrajectoryProblem::new(
            Arc::new(obs),
            Rig::paper(0.3),
            [0.0; 4],
            free,
            Options::default(),
        );
        let rows: Vec<(usize, usize, usize, f64)> = problem
            .rows()
            .map(|r| (r.frame, r.marker, r.coord, r.observed))
            .collect();
        let expected = vec![
            (0, 0, 0, 1.0),
            (0, 0, 1, 1.5),
            (0, 1, 0, 10.0),
            (0, 1, 1, 10.5),
            (1, 1, 0, 20.0),
            (1, 1, 1, 20.5),
            (2, 0, 0, 3.0),
            (2, 0, 1, 3.5),
            (3, 0, 0, 5.0),
            (3, 0, 1, 5.5),
            (3, 1, 0, 50.0),
            (3, 1, 1, 50.5),
        ];
        assert_eq!(rows, expected);
        assert_eq!(rows.len(), problem.n_rows());
    }
}
