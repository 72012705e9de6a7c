//! The one recording type every reader produces: frame times and two marker tracks in the rail
//! frame (metres, x along the rail, y up), with what was inferred on the way.

use std::collections::BTreeMap;
use std::fmt;
use std::io::Write;
use std::path::PathBuf;

/// A marker position `[x, y]` in metres, or `None` where the marker was not seen.
pub type Track = Vec<Option<[f64; 2]>>;

/// The formats the readers know.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// Plain wide CSV: a time column and `NAME_x`, `NAME_y` pairs (`t,slider_x,...`).
    Wide,
    /// Long (tidy) CSV: one row per marker per frame (`t,marker,x,y`).
    Long,
    /// Open Source Physics Tracker export: one file per marker.
    Tracker,
    /// DeepLabCut CSV (3 or 4 header rows) or HDF5 (its pandas DataFrame): pixels, frame index.
    DeepLabCut,
    /// OptiTrack Motive CSV export.
    Motive,
    /// Vicon Nexus CSV (Trajectories section).
    Vicon,
    /// SLEAP analysis CSV or HDF5 (`track,frame_idx,...,NODE.x,NODE.y`).
    Sleap,
    /// Qualisys QTM TSV export (`NAME X`, `NAME Y`, `NAME Z` columns, millimetres).
    Qualisys,
    /// Kinovea trajectory text export (`#Kinovea Trajectory data export`).
    Kinovea,
    /// TRex per-individual CSV (`X (cm)`, `Y (cm)`, `timestamp`).
    Trex,
    /// MCAP (JSON, ROS 2 CDR messages).
    Mcap,
}

impl Format {
    /// Every format, in the order detection tries them.
    pub const ALL: [Format; 11] = [
        Format::Wide,
        Format::Long,
        Format::Tracker,
        Format::DeepLabCut,
        Format::Motive,
        Format::Vicon,
        Format::Sleap,
        Format::Qualisys,
        Format::Kinovea,
        Format::Trex,
        Format::Mcap,
    ];

    /// The name used by `--format`.
    pub fn name(self) -> &'static str {
        match self {
            Format::Wide => "wide",
            Format::Long => "long",
            Format::Tracker => "tracker",
            Format::DeepLabCut => "dlc",
            Format::Motive => "motive",
            Format::Vicon => "vicon",
            Format::Sleap => "sleap",
            Format::Qualisys => "qualisys",
            Format::Kinovea => "kinovea",
            Format::Trex => "trex",
            Format::Mcap => "mcap",
        }
    }

    /// The format named `name` (as in `--format`).
    pub fn from_name(name: &str) -> Option<Format> {
        Format::ALL.into_iter().find(|f| f.name() == name)
    }

    /// The names of all formats, comma separated (for messages).
    pub fn names() -> String {
        Format::ALL.map(|f| f.name()).join(", ")
    }
}

impl fmt::Display for Format {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// How the file's coordinates were turned into rail-frame metres.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Calibration {
    /// Metres per file unit.
    pub scale: f64,
    /// Where the scale came from (`file`, `--scale`, `rod length`, `assumed`).
    pub scale_source: String,
    /// Whether the file's y axis pointed down and was flipped.
    pub y_flipped: bool,
    /// The rail axis angle in the (flipped, scaled) file frame, radians, when `--rail-frame`
    /// rotated the data.
    pub rail_angle: Option<f64>,
    /// The file-frame point (metres) that became the origin, when `--rail-frame` shifted it.
    pub origin: Option<[f64; 2]>,
    /// RMS distance of the slider from the fitted rail line (metres), when fitted.
    pub rail_rms: Option<f64>,
}

/// The slider-bob distance over the frames where both were seen.
#[derive(Debug, Clone, PartialEq)]
pub struct Geometry {
    /// Frames with both markers.
    pub frames: usize,
    /// Median distance (metres).
    pub median: f64,
    /// Standard deviation of the distance (metres).
    pub std: f64,
    /// The reference length: `--rod-length` when given, else the median.
    pub reference: f64,
    /// Frames whose distance is far from the reference (indices into the recording).
    pub outliers: Vec<usize>,
    /// The tolerance that made a frame an outlier (metres): five robust standard deviations
    /// of the distance, but never below 2 % nor above 5 % of the reference (a distance that
    /// scatters more is not a rod's, [`Geometry::rigid`], and its frames are not excused).
    pub tolerance: f64,
    /// Robust spread of the distance (metres): 1.4826 times its median absolute deviation.
    pub spread: f64,
    /// The distance's noise from frame to frame (metres), from its third differences over
    /// consecutive frames with both markers (smooth changes cancel); 0 with too few frames.
    pub noise: f64,
}

impl Geometry {
    /// The share of the median distance a rigid rod's markers may spread by, besides the
    /// noise: the camera (lens distortion, 0.1-2 %), the markers off the pivot and the bob's
    /// centre (a few mm, which the swing turns into a varying distance) and a stretching thread.
    pub const RIGID_SHARE: f64 = 0.05;
    /// Noise deviations the spread may hold besides [`Geometry::RIGID_SHARE`].
    pub const RIGID_NOISE: f64 = 5.0;

    /// The largest spread a rigid rod's markers show: five noise deviations plus 5 % of the
    /// median distance.
    pub fn rigid_limit(&self) -> f64 {
        Self::RIGID_NOISE * self.noise + Self::RIGID_SHARE * self.median
    }

    /// The distance is as constant as a rod's: its robust spread within [`Self::rigid_limit`].
    pub fn rigid(&self) -> bool {
        self.spread <= self.rigid_limit()
    }
}

/// Where a recording came from and what was inferred while reading it.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Provenance {
    /// The files read.
    pub sources: Vec<PathBuf>,
    /// The format read.
    pub format: Option<Format>,
    /// Whether the format was detected (`false`: given by `--format`).
    pub detected: bool,
    /// The file's name for the slider marker.
    pub slider_name: String,
    /// The file's name for the bob marker.
    pub bob_name: String,
    /// The file's time of the first frame (seconds in the file's clock).
    pub time_origin: f64,
    /// The same in integer nanoseconds, exact, when the file's clock counts them (MCAP).
    pub time_origin_ns: Option<i64>,
    /// The rate the file numbers its frames at (Hz), when it numbers them: DeepLabCut's and
    /// SLEAP's `--fps`, Motive's `Export Frame Rate`; a frame's number is its file time
    /// ([`Provenance::time_origin`] + t) times this rate.
    pub frame_rate: Option<f64>,
    /// The plane a 3-D file's positions were projected onto (`None`: the file is 2-D).
    pub plane: Option<super::Plane>,
    /// The slider's and the bob's mean coordinate off that plane (file units, unscaled), where
    /// the reader keeps it (Motive): a table written back in the file's three axes puts the
    /// model's markers at that depth.
    pub off_plane: [Option<f64>; 2],
    /// Scale, flip and rail-frame transform.
    pub calibration: Calibration,
    /// Rod length check.
    pub geometry: Option<Geometry>,
    /// Human-readable notes on what was inferred.
    pub notes: Vec<String>,
    /// Problems that did not stop the reading (a truncated file, dropped samples).
    pub warnings: Vec<String>,
    /// Key-value metadata stored in the file (an MCAP `truth` record, for instance).
    pub metadata: BTreeMap<String, String>,
}

/// A recording: frame times and the two marker tracks, in the rail frame, y up, metres.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Recording {
    /// Frame times, seconds from the first frame, strictly increasing.
    pub times: Vec<f64>,
    /// The slider (pivot) track, one entry per frame.
    pub slider: Track,
    /// The bob track, one entry per frame.
    pub bob: Track,
    /// Where it came from and what was inferred.
    pub provenance: Provenance,
}

/// The canonical wide CSV header.
pub const CANONICAL_HEADER: &str = "t,slider_x,slider_y,bob_x,bob_y";

impl Provenance {
    /// The first frame's stamp in the file's own clock (ns): the file's integer stamp when it
    /// has one (MCAP), else its time origin in seconds rounded to the nanosecond; a clock
    /// before zero (MCAP's stamps have none) starts at zero. An overlay's frames are stamped
    /// from it.
    pub fn origin_ns(&self) -> u64 {
        let ns = self
            .time_origin_ns
            .unwrap_or_else(|| (self.time_origin * 1e9).round() as i64);
        ns.max(0) as u64
    }
}

impl Recording {
    /// Number of frames.
    pub fn len(&self) -> usize {
        self.times.len()
    }

    /// Whether there are no frames.
    pub fn is_empty(&self) -> bool {
        self.times.is_empty()
    }

    /// Frames where the slider, and where the bob, was seen.
    pub fn seen(&self) -> (usize, usize) {
        (
            self.slider.iter().flatten().count(),
            self.bob.iter().flatten().count(),
        )
    }

    /// Write the canonical wide CSV (`t,slider_x,slider_y,bob_x,bob_y`; seconds and metres,
    /// empty cells for missing samples). Numbers are written in the shortest form that reads
    /// back to the same `f64`.
    pub fn write_csv(&self, w: &mut dyn Write) -> std::io::Result<()> {
        writeln!(w, "{CANONICAL_HEADER}")?;
        for i in 0..self.times.len() {
            write!(w, "{}", self.times[i])?;
            for p in [self.slider[i], self.bob[i]] {
                match p {
                    Some([x, y]) => write!(w, ",{x},{y}")?,
                    None => write!(w, ",,")?,
                }
            }
            writeln!(w)?;
        }
        Ok(())
    }

    /// A readable summary of what was read and inferred, one item per line.
    pub fn summary(&self) -> String {
        let p = &self.provenance;
        let mut s = String::new();
        let files: Vec<String> = p.sources.iter().map(|f| f.display().to_string()).collect();
        let format = p.format.map_or("?", |f| f.name());
        s += &format!(
            "read {} ({} format, {})\n",
            files.join(", "),
            format,
            if p.detected { "detected" } else { "given" }
        );
        let (ns, nb) = self.seen();
        let span = self.times.last().copied().unwrap_or(0.0);
        s += &format!(
            "frames: {} over {:.6} s; slider \"{}\" seen in {}, bob \"{}\" seen in {}\n",
            self.len(),
            span,
            p.slider_name,
            ns,
            p.bob_name,
            nb
        );
        let c = &p.calibration;
        s += &format!(
            "scale: {} m per file unit ({}); y {}\n",
            super::calibrate::significant(c.scale),
            c.scale_source,
            if c.y_flipped {
                "down in the file, flipped to up"
            } else {
                "up"
            }
        );
        if let (Some(a), Some(o)) = (c.rail_angle, c.origin) {
            s += &format!(
                "rail frame: axis at {:.4} deg from the file's x, origin at ({:.6}, {:.6}) m, slider rms off the line {:.3e} m\n",
                a.to_degrees(),
                o[0],
                o[1],
                c.rail_rms.unwrap_or(f64::NAN)
            );
        }
        if let Some(g) = &p.geometry {
            s += &format!(
                "rod: slider-bob distance median {:.6} m, std {:.3e} m over {} frames; {} outlier frame(s) beyond {:.3e} m of {:.6} m\n",
                g.median,
                g.std,
                g.frames,
                g.outliers.len(),
                g.tolerance,
                g.reference
            );
            if !g.rigid() {
                s += &format!(
                    "rod: the distance is not constant: robust spread {:.3e} m (1.4826 MAD), beyond the {:.3e} m a rigid rod's markers show (5 noise deviations of {:.2e} m plus 5 % of the median): not this rig, or the markers are not the slider and the bob\n",
                    g.spread,
                    g.rigid_limit(),
                    g.noise
                );
            }
        }
        if !p.metadata.is_empty() {
            let kv: Vec<String> = p.metadata.iter().map(|(k, v)| format!("{k}={v}")).collect();
            s += &format!("metadata: {}\n", kv.join(", "));
        }
        for n in &p.notes {
            s += &format!("note: {n}\n");
        }
        for w in &p.warnings {
            s += &format!("warning: {w}\n");
        }
        s
    }
}

/// The fewest frames a swing of the rig's pendulum must span for a fit to follow the motion:
/// fewer, and the recording cannot tell one swing from the next (two a swing is the Nyquist
/// limit). A lab's recordings have tens to thousands (a 0.3 m pendulum swings in 1.1 s, filmed
/// at 25 to 1000 Hz); times in milliseconds read as seconds leave about one.
pub const MIN_FRAMES_PER_SWING: f64 = 4.0;
