//! What a camera sees: marker positions in the rail frame (metres, x along the rail, y up).

use super::{Rig, Scalar, State, THETA, X};

/// Slider and bob positions `[slider_x, slider_y, bob_x, bob_y]` in the rail frame with y up:
/// the slider at (x, 0), the bob at (x + l cos(theta), -l sin(theta)) (the model's y-down
/// angle flipped once, here).
#[inline]
pub fn markers<T: Scalar>(rig: &Rig<T>, y: &State<T>) -> [T; 4] {
    let (sin, cos) = y[THETA].sin_cos();
    let l = rig.rod_length;
    [y[X], T::from(0.0), y[X] + l * cos, -(l * sin)]
}
