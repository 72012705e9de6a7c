//! The estimation problem: predicted minus observed marker positions at every frame with data,
//! weighted per marker, as a function of the free parameters (rig and initial state).

use super::lm::LeastSquares;
use crate::model::{observed_markers, Camera, Rig, Scalar, State};
use crate::sim::{simulate, Options, Request, SimError};
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
    /// Rod length (m).
    RodLength,
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
    pub const ALL: [Param; 17] = [
        Param::MuKinetic,
        Param::MuStatic,
        Param::X,
        Param::Theta,
        Param::XDot,
        Param::ThetaDot,
        Param::RodLength,
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
            Param::MuKinetic | Param::MuStatic | Param::ScaleError => "",
            Param::X
            | Param::RodLength
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

/// One residual row: which frame, which marker (0 slider, 1 bob), which coordinate.
#[derive(Debug, Clone, Copy)]
struct Row {
    frame: usize,
    marker: usize,
    coord: usize,
    observed: f64,
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
    /// Extra weight per row (robust loss by iteratively reweighted least squares).
    pub row_weights: Vec<f64>,
    rows: Vec<Row>,
    times: Vec<f64>,
    /// Samples at the frame times, nothing else: built once, not per evaluation.
    request: Request,
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
        let mut rows = Vec::new();
        let mut frames = Vec::new();
        for (i, (s, b)) in obs.slider.iter().zip(&obs.bob).enumerate() {
            let mut any = false;
            for (marker, pos) in [(0, s), (1, b)] {
                if let Some(p) = pos {
                    any = true;
                    for (coord, &observed) in p.iter().enumerate() {
                        rows.push(Row {
                            frame: frames.len(),
                            marker,
                            coord,
                            observed,
                        });
                    }
                }
            }
            if any {
                frames.push(obs.times[i]);
            }
        }
        let n = rows.len();
        TrajectoryProblem {
            obs,
            rig,
            initial,
            camera: Camera::default(),
            free,
            tie_static: true,
            options,
            sigma: [1.0, 1.0],
            row_weights: vec![1.0; n],
            rows,
            request: Request {
                sample_times: frames.clone(),
                friction_work: false,
            },
            times: frames,
            counters: Arc::new(Counters::default()),
        }
    }

    /// Frame index (into the problem's frames with data) of each residual row.
    pub fn row_frames(&self) -> Vec<usize> {
        self.rows.iter().map(|r| r.frame).collect()
    }

    /// Observed value of each residual row (m).
    pub fn row_observed(&self) -> Vec<f64> {
        self.rows.iter().map(|r| r.observed).collect()
    }

    /// The observations.
    pub fn observations(&self) -> &Observations {
        &self.obs
    }

    /// Number of residual rows.
    pub fn n_rows(&self) -> usize {
        self.rows.len()
    }

    /// Marker (0 slider, 1 bob) of each residual row.
    pub fn row_markers(&self) -> Vec<usize> {
        self.rows.iter().map(|r| r.marker).collect()
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
            Param::RodLength => self.rig.rod_length,
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
        for (&param, &v) in self.free.iter().zip(p) {
            match param {
                Param::MuKinetic => rig.mu_kinetic = v,
                Param::MuStatic => rig.mu_static = v,
                Param::X => y0[0] = v,
                Param::Theta => y0[1] = v,
                Param::XDot => y0[2] = v,
                Param::ThetaDot => y0[3] = v,
                Param::RodLength => rig.rod_length = v,
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
    /// metres, with its marker) to `each`, without collecting intermediate vectors: the
    /// Jacobian path runs this tens of times per fit on thousands of frames.
    fn for_each_residual<T: Scalar + 'static>(
        &self,
        p: &[T],
        mut each: impl FnMut(usize, &Row, T),
    ) -> Result<(), SimError> {
        let (rig, y0, camera) = self.apply(p);
        let t_end = self.times.last().copied().unwrap_or(0.0);
        let sol = simulate(&rig, &y0, t_end, &self.options, &self.request)?;
        if sol.samples.len() < self.times.len() {
            return Err(SimError::InvalidInput(format!(
                "the model stops at t = {} s (Painleve paradox) before the recording ends",
                sol.final_time
            )));
        }
        let mut cached: Option<(usize, [T; 4])> = None;
        for (i, r) in self.rows.iter().enumerate() {
            let m = match cached {
                Some((f, m)) if f == r.frame => m,
                _ => {
                    let sample = &sol.samples[r.frame];
                    let m = observed_markers(&rig, &camera, sample.mode, &sample.state);
                    cached = Some((r.frame, m));
                    m
                }
            };
            each(i, r, m[2 * r.marker + r.coord] - r.observed);
        }
        Ok(())
    }

    /// Weighted residuals (predicted - observed) / sigma for parameters `p`.
    pub fn weighted<T: Scalar + 'static>(&self, p: &[T]) -> Result<Vec<T>, SimError> {
        let mut out = Vec::with_capacity(self.rows.len());
        self.for_each_residual(p, |i, r, d| {
            out.push(d * (self.row_weights[i] / self.sigma[r.marker]))
        })?;
        Ok(out)
    }

    /// Weighted residuals (as the solver sees them) back in metres, with each row's marker:
    /// saves simulating again when the weighted ones are at hand.
    pub fn unweighted(&self, weighted: &[f64]) -> Vec<(usize, f64)> {
        self.rows
            .iter()
            .zip(weighted)
            .zip(&self.row_weights)
            .map(|((r, v), w)| (r.marker, v * self.sigma[r.marker] / w))
            .collect()
    }

    /// Unweighted residuals in metres, with each row's marker.
    pub fn raw_residuals(&self, p: &DVector<f64>) -> Result<Vec<(usize, f64)>, SimError> {
        let mut out = Vec::with_capacity(self.rows.len());
        self.for_each_residual(p.as_slice(), |_, r, d| out.push((r.marker, d)))?;
        Ok(out)
    }

    /// Frame times with data.
    pub fn frame_times(&self) -> &[f64] {
        &self.times
    }

    fn jacobian_n<const N: usize>(
        &self,
        p: &DVector<f64>,
    ) -> Result<(DVector<f64>, DMatrix<f64>), SimError> {
        // Width N >= k = p.len(): slots k.. carry no seed and are not read back.
        let k = p.len();
        let seeded: Vec<DualSVec64<N>> = (0..k)
            .map(|i| {
                DualSVec64::<N>::new(
                    p[i],
                    Derivative::derivative_generic(nalgebra::Const::<N>, U1, i),
                )
            })
            .collect();
        let n = self.rows.len();
        let mut jac = DMatrix::zeros(n, k);
        let mut res = DVector::zeros(n);
        self.for_each_residual(&seeded, |row, r, d| {
            let v = d * (self.row_weights[row] / self.sigma[r.marker]);
            res[row] = v.re;
            let e = v.eps.unwrap_generic(nalgebra::Const::<N>, U1);
            for c in 0..k {
                jac[(row, c)] = e[c];
            }
        })?;
        Ok((res, jac))
    }
}

fn to_err(e: SimError) -> Error {
    Error::msg(e.to_string())
}

impl LeastSquares for TrajectoryProblem {
    fn residuals(&self, p: &DVector<f64>) -> Result<DVector<f64>, Error> {
        self.counters.residuals.fetch_add(1, Ordering::Relaxed);
        let r = self.weighted(p.as_slice()).map_err(to_err)?;
        Ok(DVector::from_vec(r))
    }

    /// Exact Jacobian by forward-mode dual numbers through the integrator, with event times
    /// differentiated implicitly at every mode switch.
    fn residuals_jacobian(&self, p: &DVector<f64>) -> Result<(DVector<f64>, DMatrix<f64>), Error> {
        self.counters.jacobians.fetch_add(1, Ordering::Relaxed);
        // Each dual width is a full copy of the simulator in the binary: widths 3, 4, 5, 6,
        // 8 and 10 serve every size (a few derivative slots stay unused) and keep the build
        // time down.
        match p.len() {
            0..=3 => self.jacobian_n::<3>(p),
            4 => self.jacobian_n::<4>(p),
            5 => self.jacobian_n::<5>(p),
            6 => self.jacobian_n::<6>(p),
            7 | 8 => self.jacobian_n::<8>(p),
            9 | 10 => self.jacobian_n::<10>(p),
            n => {
                return Err(Error::msg(format!(
                    "at most {MAX_FREE} free parameters, got {n}"
                )))
            }
        }
        .map_err(to_err)
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
