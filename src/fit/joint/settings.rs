//! What a joint fit is given: the releases ([`Release`]) and its settings beyond a single
//! fit's ([`JointSettings`]).

use crate::fit::problem::Observations;

/// One release of a joint fit: its name and its tracks.
#[derive(Debug, Clone)]
pub struct Release {
    /// The recording's name (its file, for messages and the table).
    pub name: String,
    /// Its tracks.
    pub obs: Observations,
}

/// Settings of a joint fit beyond the single fit's.
#[derive(Debug, Clone, Default)]
pub struct JointSettings {
    /// One camera for every release: its scale and marker offsets shared.
    pub same_camera: bool,
    /// Fit the other releases when one fails (it is named); otherwise a failure ends the fit.
    pub keep_going: bool,
}
