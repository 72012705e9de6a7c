//! The estimation problem: predicted minus observed marker positions at every frame with data,
//! weighted per marker, as a function of the free parameters (rig and initial state).

use super::lm::{LeastSquares, Normal};
use crate::model::{observed_markers, observed_markers_with, re_state, Camera, Rig, Scalar, State};
use crate::sim::{simulate_each, Options, Request, Sample, SimError};
use argmin::core::Error;
use nalgebra::{DMatrix, DVector, U1};
use num_dual::{Derivative, DualSVec64};
use serde::Serialize;
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

/// A quantity the fit can estimate.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Param {
    /// Kinetic friction coefficient.
    MuKinetic,
    /// Static friction coefficient.
    MuStatic,
    /// Initial slider position (m).
    X,
    /// Initial rod angle (rad, PHYSICS.md convention).
    Theta,
    /// Initial slider velocity (m/s).
    XDot,
    /// Initial angular velocity (rad/s).
    ThetaDot,
    /// Rod length (m): the pivot to the bob's marker; a rigid pendulum's equivalent length
    /// moves with it in proportion (unless [`Param::PendulumLength`] is free).
    RodLength,
    /// Equivalent length L of a rigid pendulum (m): the dynamics' rod, the marker staying at
    /// the rod length (PHYSICS.md, "Rigid pendulum").
    PendulumLength,
    /// Equivalent mass ratio r' = (m1 + m_p - m_e) / m_e of a rigid pendulum, with the total
    /// mass held (the motion depends on the masses through this ratio alone).
    MassRatio,
    /// Rail tilt alpha (rad, +x downhill).
    RailTilt,
    /// Viscous torque coefficient at the pivot (N m s).
    PivotDamping,
    /// Viscous rail friction (N s/m).
    ViscousFriction,
    /// Stribeck speed v_s (m/s).
    StribeckVelocity,
    /// Relative camera scale error (positions times 1 + this).
    ScaleError,
    /// Bob marker's offset along the rod from its end (m).
    BobAlong,
    /// Bob marker's offset across the rod (m).
    BobAcross,
    /// Slider marker's offset along the rail (m).
    SliderDx,
    /// Slider marker's offset perpendicular to the rail (m, y down).
    SliderDy,
    /// Lag of the bob's track behind the slider's (s).
    Lag,
}

impl Param {
    /// Every parameter, in report order.
    pub const ALL: [Param; 19] = [
        Param::MuKinetic,
        Param::MuStatic,
        Param::X,
        Param::Theta,
        Param::XDot,
        Param::ThetaDot,
        Param::RodLength,
        Param::PendulumLength,
        Param::MassRatio,
        Param::RailTilt,
        Param::PivotDamping,
        Param::ViscousFriction,
        Param::StribeckVelocity,
        Param::ScaleError,
        Param::BobAlong,
        Param::BobAcross,
        Param::SliderDx,
        Param::SliderDy,
        Param::Lag,
    ];

    /// Whether it belongs to the camera and marker model, which acts on the positions seen
    /// and not on the motion.
    pub fn is_camera(self) -> bool {
        matches!(
            self,
            Param::ScaleError
                | Param::BobAlong
                | Param::BobAcross
                | Param::SliderDx
                | Param::SliderDy
                | Param::Lag
        )
    }

    /// Whether it is part of a release's initial state.
    pub fn is_state(self) -> bool {
        matches!(
            self,
            Param::X | Param::Theta | Param::XDot | Param::ThetaDot
        )
    }

    /// Whether it describes the rig itself, the same in every release: neither a release's
    /// initial state nor the camera and marker model.
    pub fn is_rig(self) -> bool {
        !self.is_state() && !self.is_camera()
    }

    /// Name in reports and JSON.
    pub fn name(self) -> &'static str {
        match self {
            Param::MuKinetic => "mu_kinetic",
            Param::MuStatic => "mu_static",
            Param::X => "x",
            Param::Theta => "theta",
            Param::XDot => "x_dot",
            Param::ThetaDot => "theta_dot",
            Param::RodLength => "rod_length",
            Param::PendulumLength => "pendulum_length",
            Param::MassRatio => "equivalent_mass_ratio",
            Param::RailTilt => "rail_tilt",
            Param::PivotDamping => "pivot_damping",
            Param::ViscousFriction => "viscous_friction",
            Param::StribeckVelocity => "stribeck_velocity",
            Param::ScaleError => "camera_scale_error",
            Param::BobAlong => "bob_marker_along",
            Param::BobAcross => "bob_marker_across",
            Param::SliderDx => "slider_marker_dx",
            Param::SliderDy => "slider_marker_dy",
            Param::Lag => "marker_lag",
        }
    }

    /// Unit of the parameter's value, for reports.
    pub fn unit(self) -> &'static str {
        match self {
            Param::MuKinetic | Param::MuStatic | Param::ScaleError | Param::MassRatio => "",
            Param::X
            | Param::RodLength
            | Param::PendulumLength
            | Param::BobAlong
            | Param::BobAcross
            | Param::SliderDx
            | Param::SliderDy => "m",
            Param::Theta | Param::RailTilt => "rad",
            Param::XDot | Param::StribeckVelocity => "m/s",
            Param::ThetaDot => "rad/s",
            Param::PivotDamping => "N m s",
            Param::ViscousFriction => "N s/m",
            Param::Lag => "s",
        }
    }
}

/// The most parameters a fit frees at once (the dual-number Jacobian is built for each count).
pub const MAX_FREE: usize = 10;

/// Parameters of the camera and marker model ([`Param::is_camera`]).
pub const CAMERA_PARAMS: usize = 6;

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

/// Run `$body` with the const `$n` set to the dual width for `$k` free parameters, or give
/// an error beyond [`MAX_FREE`]. Each width is a full copy of the simulator in the binary:
/// widths 3, 4, 5, 6, 8 and 10 serve every size (a few derivative slots stay unused) and keep
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
fn seed<const N: usize>(p: &DVector<f64>) -> Vec<DualSVec64<N>> {
    (0..p.len())
        .map(|i| {
            DualSVec64::<N>::new(
                p[i],
                Derivative::derivative_generic(nalgebra::Const::<N>, U1, i),
            )
        })
        .collect()
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
    layout: Arc<Layout>,
    /// Evaluations of this problem and its clones, for the report.
    pub counters: Arc<Counters>,
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
        let mut obs_index = Vec::new();
        let mut frames = Vec::new();
        let mut n_rows = 0;
        for (i, (s, b)) in obs.slider.iter().zip(&obs.bob).enumerate() {
            let present = usize::from(s.is_some()) + usize::from(b.is_some());
            if present > 0 {
                n_rows += 2 * present;
                obs_index.push(i);
                frames.push(obs.times[i]);
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
        }
    }

    /// The same model, values and settings over other observations (every row weight one;
    /// the counters stay shared).
    pub fn on(&self, obs: Arc<Observations>) -> TrajectoryProblem {
        let mut pr =
            TrajectoryProblem::new(obs, self.rig, self.initial, self.free.clone(), self.options);
        pr.camera = self.camera;
        pr.tie_static = self.tie_static;
        pr.sigma = self.sigma;
        pr.counters = self.counters.clone();
        pr
    }

    /// Every residual row in order: frame-major, the slider before the bob, x before y.
    pub fn rows(&self) -> impl Iterator<Item = RowInfo> + '_ {
        self.layout
            .obs_index
            .iter()
            .enumerate()
            .flat_map(move |(frame, &i)| {
                [(0, self.obs.slider[i]), (1, self.obs.bob[i])]
                    .into_iter()
                    .filter_map(|(marker, pos)| pos.map(|p| (marker, p)))
                    .flat_map(move |(marker, p)| {
                        (0..2).map(move |coord| RowInfo {
                            frame,
                            marker,
                            coord,
                            observed: p[coord],
                        })
                    })
            })
    }

    /// The observations.
    pub fn observations(&self) -> &Observations {
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
            Param::ScaleError => self.camera.scale_error,
            Param::BobAlong => self.camera.bob_along,
            Param::BobAcross => self.camera.bob_across,
            Param::SliderDx => self.camera.slider_dx,
            Param::SliderDy => self.camera.slider_dy,
            Param::Lag => self.camera.lag,
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
        let length_ratio = self.rig.rod_length / self.rig.marker_length;
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
                Param::ScaleError => cam.scale_error = v,
                Param::BobAlong => cam.bob_along = v,
                Param::BobAcross => cam.bob_across = v,
                Param::SliderDx => cam.slider_dx = v,
                Param::SliderDy => cam.slider_dy = v,
                Param::Lag => cam.lag = v,
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
        let mut sink = |s: Sample<T>| {
            let i = layout.obs_index[frame];
            let m = observed_markers(&rig, &camera, s.mode, &s.state);
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

    /// Weighted residuals as a vector (one simulation).
    pub fn residuals(&self, p: &DVector<f64>) -> Result<DVector<f64>, Error> {
        self.counters.residuals.fetch_add(1, Ordering::Relaxed);
        let r = self.weighted(p.as_slice()).map_err(to_err)?;
        Ok(DVector::from_vec(r))
    }

    /// The weighted sum of squares at `p`, summed as the simulation runs (nothing stored).
    pub fn chi2(&self, p: &DVector<f64>) -> Result<f64, Error> {
        self.counters.residuals.fetch_add(1, Ordering::Relaxed);
        let mut ss = 0.0;
        self.for_each_residual(p.as_slice(), |row, _, marker, d: f64| {
            let v = d * (self.row_weight(row) / self.sigma[marker]);
            ss += v * v;
        })
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
                for b in 0..=a {
                    meat[a][b] += g[a] * g[b];
                }
            }
            *g = [0.0; N];
        };
        self.for_each_residual(&seeded, |row, frame, marker, d| {
            let v = d * (self.row_weight(row) / self.sigma[marker]);
            let r = v.re;
            let e = v.eps.unwrap_generic(nalgebra::Const::<N>, U1);
            ss += r * r;
            // Over the whole width N, a constant, so the loops unroll: the unseeded slots
            // only ever add zeros to entries nobody reads.
            for a in 0..N {
                jtr[a] += e[a] * r;
                for b in 0..=a {
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
    /// the Jacobian).
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
                let e = v.eps.unwrap_generic(nalgebra::Const::<N>, U1);
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
        let mut jtj = [[0.0; W]; W];
        let mut jtr = [0.0; W];
        // A lag among the extra parameters differentiates along the motion: velocities.
        self.for_each_residual_at(
            &seed::<N>(p),
            extra.contains(&Param::Lag),
            |s: &Sample<DualSVec64<N>>| {
                let y = re_state(&s.state);
                // The lag's accelerations in f64: nothing in them depends on the camera.
                let acc = (!cam_m.lag.is_exact_zero()).then(|| {
                    let (a, b) = at_p.rig.accelerations(s.mode, &y);
                    (DualSVec64::from(a), DualSVec64::from(b))
                });
                observed_markers_with(rig_m.marker_length, &cam_m, &y.map(DualSVec64::from), acc)
            },
            |row, _, marker, coord, d, cam| {
                let scale = self.row_weight(row) / self.sigma[marker];
                let r = d.re * scale;
                let e = d.eps.unwrap_generic(nalgebra::Const::<N>, U1);
                let c = cam[2 * marker + coord]
                    .eps
                    .unwrap_generic(nalgebra::Const::<M>, U1);
                let mut g = [0.0; W];
                g[..k]
                    .iter_mut()
                    .zip(e.iter())
                    .for_each(|(g, e)| *g = e * scale);
                g[k..k + m]
                    .iter_mut()
                    .zip(c.iter())
                    .for_each(|(g, c)| *g = c * scale);
                ss += r * r;
                for a in 0..k + m {
                    jtr[a] += g[a] * r;
                    for b in 0..=a {
                        jtj[a][b] += g[a] * g[b];
                    }
                }
            },
        )?;
        let kk = k + m;
        Ok(Normal {
            cost: 0.5 * ss,
            jtj: DMatrix::from_fn(kk, kk, |a, b| jtj[a.max(b)][a.min(b)]),
            jtr: DVector::from_fn(kk, |a, _| jtr[a]),
            meat: None,
        })
    }
}

/// Where `p` stands in `problem`'s parameter vector (`None` when it is not free).
pub(super) fn idx(problem: &TrajectoryProblem, p: Param) -> Option<usize> {
    problem.free.iter().position(|&f| f == p)
}

fn to_err(e: SimError) -> Error {
    Error::msg(e.to_string())
}

impl LeastSquares for TrajectoryProblem {
    fn normal_equations(&self, p: &DVector<f64>) -> Result<Normal, Error> {
        self.normal_equations_blocked(p, None)
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
        // A rigid pendulum's L lies between half and twice the bob's distance for any rod
        // and bob a lab builds (a bare uniform rod has L = 2l/3).
        let l = self.rig.marker_length;
        clamp(p, Param::PendulumLength, 0.5 * l, 2.0 * l);
        clamp(p, Param::MassRatio, 1e-4, 1e4);
        clamp(p, Param::PivotDamping, 0.0, f64::INFINITY);
        clamp(p, Param::ViscousFriction, 0.0, f64::INFINITY);
        clamp(p, Param::StribeckVelocity, 1e-4, 10.0);
        clamp(p, Param::RailTilt, -0.3, 0.3);
        clamp(p, Param::ScaleError, -0.5, 0.5);
        clamp(p, Param::Lag, -0.05, 0.05);
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
