//! What a camera sees: marker positions in the rail frame (metres, x along the rail, y up),
//! for ideal markers ([`markers`]) and through the observation model of docs/physics.md ("What a
//! camera adds": marker offsets, camera scale, a lag between the markers; [`Camera`]).

use super::{Mode, Rig, Scalar, State, THETA, THETA_DOT, X, X_DOT};

/// Slider and bob positions `[slider_x, slider_y, bob_x, bob_y]` in the rail frame with y up:
/// the slider at (x, 0), the bob at (x + l cos(theta), -l sin(theta)) (the model's y-down
/// angle flipped once, here), with l the bob's centre ([`Rig::marker_length`]; a rigid
/// pendulum's dynamics use its equivalent length instead).
#[inline]
pub fn markers<T: Scalar>(rig: &Rig<T>, y: &State<T>) -> [T; 4] {
    let (sin, cos) = y[THETA].sine_cosine();
    let l = rig.marker_length;
    [y[X], T::from(0.0), y[X] + l * cos, -(l * sin)]
}

/// How the camera and the markers differ from the ideal: every field zero (and the scale one)
/// is the ideal camera of [`markers`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera<T> {
    /// Relative scale error: every position is multiplied by 1 + `scale_error`.
    pub scale_error: T,
    /// Bob marker's offset along the rod from the rod's end (m): it sits at l + `bob_along`.
    pub bob_along: T,
    /// Bob marker's offset across the rod, toward increasing theta (m).
    pub bob_across: T,
    /// Slider marker's offset from the pivot along the rail (m).
    pub slider_dx: T,
    /// Slider marker's offset from the pivot perpendicular to the rail, y down (m).
    pub slider_dy: T,
    /// Lag of the bob's track behind the slider's (s): the bob seen at frame time t was at
    /// t - `lag`.
    pub lag: T,
}

impl<T: Scalar> Default for Camera<T> {
    fn default() -> Self {
        let z = T::from(0.0);
        Camera {
            scale_error: z,
            bob_along: z,
            bob_across: z,
            slider_dx: z,
            slider_dy: z,
            lag: z,
        }
    }
}

impl<T: Scalar> Camera<T> {
    /// Every field exactly zero, derivatives included: the ideal camera, whose positions are
    /// [`markers`]' (the same numbers, without the camera's arithmetic).
    pub fn is_ideal(&self) -> bool {
        [
            self.scale_error,
            self.bob_along,
            self.bob_across,
            self.slider_dx,
            self.slider_dy,
            self.lag,
        ]
        .iter()
        .all(Scalar::is_exact_zero)
    }
}

impl Camera<f64> {
    /// The same camera in another scalar type (derivative parts zero).
    pub fn lift<T: Scalar>(&self) -> Camera<T> {
        Camera {
            scale_error: T::from(self.scale_error),
            bob_along: T::from(self.bob_along),
            bob_across: T::from(self.bob_across),
            slider_dx: T::from(self.slider_dx),
            slider_dy: T::from(self.slider_dy),
            lag: T::from(self.lag),
        }
    }
}

/// Marker positions `[slider_x, slider_y, bob_x, bob_y]` (rail frame, y up) as `camera` sees
/// the rig in `mode` at state `y` (docs/physics.md, "What a camera sees"). A lag is applied to the
/// bob by a second-order Taylor step back along the motion (lags are milliseconds, so the
/// third-order term is far below any camera's noise).
pub fn observed_markers<T: Scalar>(
    rig: &Rig<T>,
    camera: &Camera<T>,
    mode: Mode,
    y: &State<T>,
) -> [T; 4] {
    // A lag that is zero but being differentiated must still take the Taylor path.
    let accelerations = (!camera.lag.is_exact_zero()).then(|| rig.accelerations(mode, y));
    observed_markers_with(rig.marker_length, camera, y, accelerations)
}

/// [`observed_markers`] with the bob's centre at `marker_length` from the pivot and the accelerations (x'', theta'') at `y` given, as the lag needs
/// them (`None`: no lag): a caller differentiating by the camera's parameters alone computes
/// them once in f64.
pub fn observed_markers_with<T: Scalar>(
    marker_length: T,
    camera: &Camera<T>,
    y: &State<T>,
    accelerations: Option<(T, T)>,
) -> [T; 4] {
    let k = T::from(1.0) + camera.scale_error;
    let (sin, cos) = y[THETA].sine_cosine();
    let lb = marker_length + camera.bob_along;
    let e = camera.bob_across;
    // Bob relative to the slider, y down, and its first two angular derivatives' factors.
    let along = lb * cos - e * sin; // d(bx)/d(theta) = -across_y
    let across = lb * sin + e * cos; // by (y down); d(by)/d(theta) = along
    let mut bx = y[X] + along;
    let mut by = across;
    if let Some((x_dd, th_dd)) = accelerations {
        let w = y[THETA_DOT];
        let vx = y[X_DOT] - across * w;
        let vy = along * w;
        let ax = x_dd - across * th_dd - along * w * w;
        let ay = along * th_dd - across * w * w;
        let tau = camera.lag;
        let half_tau2 = tau * tau * 0.5;
        bx = bx - tau * vx + half_tau2 * ax;
        by = by - tau * vy + half_tau2 * ay;
    }
    [
        k * (y[X] + camera.slider_dx),
        -(k * camera.slider_dy),
        k * bx,
        -(k * by),
    ]
}
