//! The quantities a fit can estimate ([`Param`]), with their names, units and kinds (the rig's,
//! a release's initial state, the camera's): the vocabulary scenes, the fit and the plan
//! speak. It lives with the model, below them all, because a scene names the parameters a fit
//! may free before any fit exists.

use serde::Serialize;

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
    /// Initial rod angle (rad, docs/physics.md convention).
    Theta,
    /// Initial slider velocity (m/s).
    XDot,
    /// Initial angular velocity (rad/s).
    ThetaDot,
    /// Rod length (m): the pivot to the bob's marker; a rigid pendulum's equivalent length
    /// moves with it in proportion (unless [`Param::PendulumLength`] is free).
    RodLength,
    /// Equivalent length L of a rigid pendulum (m): the dynamics' rod, the marker staying at
    /// the rod length (docs/physics.md, "The rigid pendulum").
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
    /// Half the difference of the kinetic coefficients by sliding direction,
    /// (mu_k(+x) - mu_k(-x)) / 2, under the direction law (mu_kinetic their mean); the static
    /// coefficients differ by the same amount.
    FrictionSplit,
    /// Exponent n of the load law, |F| = mu N_0 (|N| / N_0)^n.
    LoadExponent,
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
    /// Gravity (m/s^2): a measured value of the rig file's, like the rod and the masses.
    Gravity,
}

impl Param {
    /// Every parameter, in report order.
    pub const ALL: [Param; 22] = [
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
        Param::FrictionSplit,
        Param::LoadExponent,
        Param::ScaleError,
        Param::BobAlong,
        Param::BobAcross,
        Param::SliderDx,
        Param::SliderDy,
        Param::Lag,
        Param::Gravity,
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

    /// Whether it is one of the rig file's measured values, fitted with the file's deviation
    /// as its prior: the rod length, the mass ratio and gravity.
    pub fn is_measured(self) -> bool {
        matches!(self, Param::RodLength | Param::MassRatio | Param::Gravity)
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
            Param::FrictionSplit => "mu_kinetic_split",
            Param::LoadExponent => "load_exponent",
            Param::ScaleError => "camera_scale_error",
            Param::BobAlong => "bob_marker_along",
            Param::BobAcross => "bob_marker_across",
            Param::SliderDx => "slider_marker_dx",
            Param::SliderDy => "slider_marker_dy",
            Param::Lag => "marker_lag",
            Param::Gravity => "gravity",
        }
    }

    /// Unit of the parameter's value, for reports.
    pub fn unit(self) -> &'static str {
        match self {
            Param::MuKinetic
            | Param::MuStatic
            | Param::ScaleError
            | Param::MassRatio
            | Param::FrictionSplit
            | Param::LoadExponent => "",
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
            Param::Gravity => "m/s^2",
        }
    }
}

/// Parameters of the camera and marker model ([`Param::is_camera`]).
pub const CAMERA_PARAMS: usize = 6;
