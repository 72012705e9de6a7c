//! The recording options every command that reads a recording shares (inspect, convert, fit;
//! the Python package's keyword arguments), and the resolve step that checks them into the
//! readers' options with the CLI's messages.

use crate::data::{Format, Plane, ReadOptions};

/// The names `--format` takes.
pub const FORMAT_NAMES: [&str; 11] = [
    "wide", "long", "tracker", "dlc", "motive", "vicon", "sleap", "qualisys", "kinovea", "trex",
    "mcap",
];

/// Flags that say how to read a recording. Flatten into a command with
/// `#[command(flatten)] recording: RecordingArgs`.
#[derive(Debug, Clone, Default, clap::Args)]
pub struct RecordingArgs {
    /// Input format (default: detected from the header).
    #[arg(long, value_parser = FORMAT_NAMES)]
    pub format: Option<String>,
    /// Marker name of the slider (default: the one name containing "slider").
    #[arg(long, value_name = "NAME")]
    pub slider: Option<String>,
    /// Marker name of the bob (default: the one name containing "bob").
    #[arg(long, value_name = "NAME")]
    pub bob: Option<String>,
    /// Metres per file unit (pixels, or to override the file's units).
    #[arg(long, value_name = "M_PER_UNIT")]
    pub scale: Option<f64>,
    /// Frame rate for formats without times (DeepLabCut, frame columns).
    #[arg(long, value_name = "HZ")]
    pub fps: Option<f64>,
    /// Plane of motion of 3-D data (default: xy; xz for Vicon).
    #[arg(long, value_parser = ["xy", "xz", "yz"])]
    pub plane: Option<String>,
    /// The file's y axis points down (default: from the format; pixels point down).
    #[arg(long, conflicts_with = "y_up")]
    pub y_down: bool,
    /// The file's y axis points up.
    #[arg(long)]
    pub y_up: bool,
    /// Rotate and shift into the rail frame fitted to the slider's track.
    #[arg(long)]
    pub rail_frame: bool,
    /// Known rod length (m): the geometry check's reference, and the scale of unitless data.
    #[arg(long, value_name = "M")]
    pub rod_length: Option<f64>,
    /// DeepLabCut likelihood under which a point counts as missing.
    #[arg(long, default_value_t = 0.6, value_name = "P")]
    pub min_likelihood: f64,
    /// Drop frames whose slider-bob distance is far from the rod length.
    #[arg(long)]
    pub drop_outliers: bool,
    /// Keep frames from this time on (s from the first frame; times are re-zeroed).
    #[arg(long, value_name = "S")]
    pub t_start: Option<f64>,
    /// Keep frames up to this time (s from the first frame); MCAP is not decoded past it.
    #[arg(long, value_name = "S")]
    pub t_end: Option<f64>,
    /// MCAP: read only this channel (repeat for several; default: every marker channel).
    #[arg(long, value_name = "TOPIC")]
    pub topic: Vec<String>,
}

impl RecordingArgs {
    /// Check the values (no I/O) and build the library's read options.
    pub fn resolve(&self) -> Result<ReadOptions, String> {
        let positive = |flag: &str, v: Option<f64>| match v {
            Some(x) if !(x.is_finite() && x > 0.0) => {
                Err(format!("{flag} must be a finite number > 0, got {x}"))
            }
            _ => Ok(v),
        };
        if !(0.0..=1.0).contains(&self.min_likelihood) {
            return Err(format!(
                "--min-likelihood must be in [0, 1], got {}",
                self.min_likelihood
            ));
        }
        // clap checks the names on the command line; other callers (Python) get the message.
        let format = match self.format.as_deref() {
            None => None,
            Some(name) => Some(Format::from_name(name).ok_or_else(|| {
                format!(
                    "--format must be one of {}, got {name:?}",
                    FORMAT_NAMES.join(", ")
                )
            })?),
        };
        let plane = match self.plane.as_deref() {
            None => None,
            Some(name) => Some(
                Plane::from_name(name)
                    .ok_or_else(|| format!("--plane must be xy, xz or yz, got {name:?}"))?,
            ),
        };
        if self.y_down && self.y_up {
            return Err("--y-down and --y-up contradict each other: give one".into());
        }
        Ok(ReadOptions {
            format,
            slider: self.slider.clone(),
            bob: self.bob.clone(),
            scale: positive("--scale", self.scale)?,
            fps: positive("--fps", self.fps)?,
            plane,
            y_down: if self.y_down {
                Some(true)
            } else if self.y_up {
                Some(false)
            } else {
                None
            },
            rail_frame: self.rail_frame,
            rod_length: positive("--rod-length", self.rod_length)?,
            min_likelihood: self.min_likelihood,
            drop_outliers: self.drop_outliers,
            time_window: match (self.t_start, self.t_end) {
                (None, None) => None,
                (s, e) => {
                    let (s, e) = (s.unwrap_or(0.0), e.unwrap_or(f64::INFINITY));
                    if !(s >= 0.0 && e > s) {
                        return Err(format!(
                            "--t-start {s} and --t-end {e} must satisfy 0 <= start < end"
                        ));
                    }
                    Some((s, e))
                }
            },
            topics: self.topic.clone(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Debug, Parser)]
    struct Probe {
        #[command(flatten)]
        rec: RecordingArgs,
    }

    #[test]
    fn recording_flags_resolve_into_read_options() {
        let p = Probe::try_parse_from([
            "x",
            "--format",
            "dlc",
            "--fps",
            "240",
            "--scale",
            "0.001",
            "--plane",
            "xz",
            "--slider",
            "pivot",
            "--rail-frame",
            "--y-down",
        ])
        .unwrap();
        let o = p.rec.resolve().unwrap();
        assert_eq!(o.format, Some(Format::DeepLabCut));
        assert_eq!(o.fps, Some(240.0));
        assert_eq!(o.plane, Some(Plane::Xz));
        assert_eq!(o.slider.as_deref(), Some("pivot"));
        assert_eq!(o.y_down, Some(true));
        assert!(o.rail_frame);
    }

    #[test]
    fn bad_recording_flags_are_rejected() {
        assert!(Probe::try_parse_from(["x", "--format", "xls"]).is_err());
        assert!(Probe::try_parse_from(["x", "--y-up", "--y-down"]).is_err());
        let p = Probe::try_parse_from(["x", "--fps=-3"]).unwrap();
        assert!(p.rec.resolve().unwrap_err().contains("--fps"));
    }
}
