//! The rig's modes of motion and their names as they appear in reports and JSON.

use std::fmt;

/// Direction of a slide along the rail.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Direction {
    /// x' > 0.
    Positive,
    /// x' < 0.
    Negative,
}

impl Direction {
    /// The sign s = sign(x') as +1 or -1.
    pub fn sign(self) -> f64 {
        match self {
            Direction::Positive => 1.0,
            Direction::Negative => -1.0,
        }
    }

    /// Direction of a signed quantity (zero counts as positive).
    pub fn of(v: f64) -> Self {
        if v < 0.0 {
            Direction::Negative
        } else {
            Direction::Positive
        }
    }

    /// The opposite direction (used by mirror symmetry).
    pub fn flipped(self) -> Self {
        match self {
            Direction::Positive => Direction::Negative,
            Direction::Negative => Direction::Positive,
        }
    }
}

/// Which model governs the motion: the pendulum (slider stuck) or the sliding rod.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Mode {
    /// Slider at rest on the rail (pendulum model).
    Stick,
    /// Slider sliding in the given direction (sliding-rod model).
    Slide(Direction),
}

impl Mode {
    /// The name used in timelines and JSON: `stick`, `slide+`, `slide-`.
    pub fn name(self) -> &'static str {
        match self {
            Mode::Stick => "stick",
            Mode::Slide(Direction::Positive) => "slide+",
            Mode::Slide(Direction::Negative) => "slide-",
        }
    }

    /// The mode seen in the mirror (x, theta) -> (-x, pi - theta).
    pub fn mirrored(self) -> Self {
        match self {
            Mode::Stick => Mode::Stick,
            Mode::Slide(d) => Mode::Slide(d.flipped()),
        }
    }
}

impl fmt::Display for Mode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}
