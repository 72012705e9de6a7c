//! How to read a recording: what the file does not say ([`ReadOptions`], built by the CLI or by
//! hand), and the plane of motion a 3-D recording is projected onto ([`Plane`]).

use super::recording::Format;

/// Which two axes of a 3-D recording form the plane of motion: the first becomes x (along the
/// rail), the second y (up).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Plane {
    /// x and y.
    Xy,
    /// x and z.
    Xz,
    /// y and z.
    Yz,
}

impl Plane {
    /// The name used by `--plane`.
    pub fn name(self) -> &'static str {
        match self {
            Plane::Xy => "xy",
            Plane::Xz => "xz",
            Plane::Yz => "yz",
        }
    }

    /// The plane named `name`.
    pub fn from_name(name: &str) -> Option<Plane> {
        [Plane::Xy, Plane::Xz, Plane::Yz]
            .into_iter()
            .find(|p| p.name() == name)
    }

    /// Project a 3-D point onto the plane.
    pub fn project(self, p: [f64; 3]) -> [f64; 2] {
        match self {
            Plane::Xy => [p[0], p[1]],
            Plane::Xz => [p[0], p[2]],
            Plane::Yz => [p[1], p[2]],
        }
    }
}

/// How to read a recording: what the file does not say. Built by the CLI's resolve step or by
/// hand; [`ReadOptions::default`] detects everything.
#[derive(Debug, Clone, PartialEq)]
pub struct ReadOptions {
    /// The format; `None` detects it from the header.
    pub format: Option<Format>,
    /// The slider's marker name; `None` takes the one name containing "slider".
    pub slider: Option<String>,
    /// The bob's marker name; `None` takes the one name containing "bob".
    pub bob: Option<String>,
    /// Metres per file unit; overrides the file's units.
    pub scale: Option<f64>,
    /// Frame rate (Hz) for formats that give frame numbers only.
    pub fps: Option<f64>,
    /// Plane of motion for 3-D formats (default: xy for Motive and MCAP, xz for Vicon).
    pub plane: Option<Plane>,
    /// Override whether the file's y axis points down.
    pub y_down: Option<bool>,
    /// Rotate and shift into the rail frame fitted from the slider's track.
    pub rail_frame: bool,
    /// Known rod length (m): the reference for the geometry check, and the scale when the file
    /// has no units and `scale` is not given.
    pub rod_length: Option<f64>,
    /// DeepLabCut likelihood under which a point counts as missing.
    pub min_likelihood: f64,
    /// Remove outlier frames (set both markers missing) instead of only flagging them.
    pub drop_outliers: bool,
    /// Keep only frames with start <= t <= end (seconds from the first frame), re-zeroed to
    /// start at 0; MCAP files are not decoded past the window.
    pub time_window: Option<(f64, f64)>,
    /// MCAP channels (topics) to read; empty reads every channel that carries markers.
    pub topics: Vec<String>,
}

impl Default for ReadOptions {
    fn default() -> Self {
        ReadOptions {
            format: None,
            slider: None,
            bob: None,
            scale: None,
            fps: None,
            plane: None,
            y_down: None,
            rail_frame: false,
            rod_length: None,
            min_likelihood: 0.6,
            drop_outliers: false,
            time_window: None,
            topics: Vec::new(),
        }
    }
}
