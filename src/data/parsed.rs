//! What every reader returns: marker series in file units ([`Series`]) and what the file says
//! about them ([`Parsed`]), before `data::read_recording` picks the slider and the bob, aligns
//! them and calibrates them.

use std::collections::BTreeMap;

/// One marker's samples as a reader found them: times in seconds (strictly increasing, as each
/// reader checks) and positions in file units, 2-D.
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct Series {
    pub name: String,
    pub times: Vec<f64>,
    pub points: Vec<Option<[f64; 2]>>,
}

/// What a reader returns: marker series in file units and what the file says about them.
#[derive(Debug, Clone, Default)]
pub(crate) struct Parsed {
    pub series: Vec<Series>,
    /// Metres per unit when the file says (with the wording for the report).
    pub scale: Option<(f64, String)>,
    /// Whether y points down in the file (pixels).
    pub y_down: bool,
    /// The file-clock time (seconds) that the series' times are relative to.
    pub time_base: f64,
    /// The same in integer nanoseconds when the file's clock is (MCAP's log times): exact
    /// where `time_base` is rounded to a fraction of a microsecond.
    pub time_base_ns: Option<i64>,
    pub notes: Vec<String>,
    pub warnings: Vec<String>,
    pub metadata: BTreeMap<String, String>,
    /// Names a reader joined into another series (a later name, the name it is kept under):
    /// asking for the later name selects the joined series.
    pub joined: Vec<(String, String)>,
    /// The plane a 3-D file's positions were projected onto (`None`: the file is 2-D).
    pub plane: Option<super::Plane>,
    /// The rate (Hz) the file's frame numbers were turned into times at, when they were
    /// (`t = frame / rate`): `--fps` for DeepLabCut and SLEAP, Motive's export rate.
    pub frame_rate: Option<f64>,
    /// A 3-D file's markers' mean coordinate off the plane (file units), by name, where the
    /// reader keeps it (Motive).
    pub off_plane: BTreeMap<String, f64>,
}
