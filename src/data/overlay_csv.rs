//! A model's markers written back as a table in a recording's own units, axes and time column
//! (`appell fit --overlay FILE.csv`, docs/overlay.md), so that a lab lays the fit over its
//! video in the tool that tracked it. Each position goes back through the recording's
//! calibration ([`Calibration::to_file`], the inverse of what the reader applied); the table's
//! layout is the recording's tool's where that tool reads tables back ([`CsvStyle`]). Rows are
//! written as they come (no frame is kept), each in the shortest form that reads back to the
//! same `f64`, so `convert` reads the file again.

use super::{Calibration, Format, Plane, Provenance};
use std::fmt::Write as _;
use std::io::Write;

/// The table layouts an overlay is written in, chosen from the recording's format.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CsvStyle {
    /// Tracker's multi-track data export: `#multi:`, a row of track names, `t x y x y`,
    /// tab-separated, the file's seconds (Tracker recordings).
    Tracker,
    /// DeepLabCut's table: scorer, (individuals,) bodyparts and coords rows, the frame number
    /// first, `x,y,likelihood` a marker (DeepLabCut and SLEAP recordings, which both tools
    /// import as labels or predictions).
    DeepLabCut,
    /// OptiTrack Motive's CSV export (1.23 headers): `Frame,Time (Seconds),X,Y,Z` a marker in
    /// the take's length units, the plane's two axes filled and the third at the recorded
    /// marker's mean depth off the plane (Motive recordings).
    Motive,
    /// appell's wide CSV in the file's units: `t` (the file's seconds) or `t_ns` (an MCAP
    /// recording's nanosecond stamps), `NAME_x,NAME_y` a marker (every other format).
    Wide,
}

impl CsvStyle {
    /// The layout for a recording of `format` (`None`: arrays, no file): its tool's own where
    /// that tool reads a table back, else the wide CSV.
    pub fn of(format: Option<Format>) -> CsvStyle {
        match format {
            Some(Format::Tracker) => CsvStyle::Tracker,
            Some(Format::DeepLabCut | Format::Sleap) => CsvStyle::DeepLabCut,
            Some(Format::Motive) => CsvStyle::Motive,
            _ => CsvStyle::Wide,
        }
    }

    /// The name docs and messages use.
    pub fn name(self) -> &'static str {
        match self {
            CsvStyle::Tracker => "Tracker multi-track export",
            CsvStyle::DeepLabCut => "DeepLabCut table",
            CsvStyle::Motive => "Motive CSV",
            CsvStyle::Wide => "wide CSV",
        }
    }
}

/// Writes the model's markers row by row in a recording's own units and time column (see the
/// module's description); [`CsvOverlay::finish`] flushes the writer.
pub struct CsvOverlay<'w> {
    out: &'w mut dyn Write,
    style: CsvStyle,
    calibration: Calibration,
    plane: Option<Plane>,
    off_plane: [f64; 2],
    time_origin: f64,
    origin_ns: Option<i64>,
    frame_rate: Option<f64>,
    rows: u64,
    line: String,
}

/// A cell of a comma-separated header: quoted when it holds a comma, a quote or a line end.
fn csv_cell(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_owned()
    }
}

/// A track name in Tracker's tab-separated rows (no tab or line end inside).
fn tab_cell(s: &str) -> String {
    s.replace(['\t', '\n', '\r'], " ")
}

/// The name of Motive's `Length Units` for a scale (metres per unit), when it is one of its.
fn motive_units(scale: f64) -> Option<&'static str> {
    [
        (1.0, "Meters"),
        (0.01, "Centimeters"),
        (0.001, "Millimeters"),
    ]
    .into_iter()
    .find(|(s, _)| (scale - s).abs() <= 1e-12 * s)
    .map(|(_, name)| name)
}

impl<'w> CsvOverlay<'w> {
    /// Start an overlay of the recording `prov` describes on `out`: the header of its style.
    pub fn new(out: &'w mut dyn Write, prov: &Provenance) -> std::io::Result<Self> {
        let style = CsvStyle::of(prov.format);
        let mut o = CsvOverlay {
            out,
            style,
            calibration: prov.calibration.clone(),
            plane: prov.plane,
            off_plane: prov.off_plane.map(|d| d.unwrap_or(0.0)),
            time_origin: prov.time_origin,
            origin_ns: prov.time_origin_ns,
            frame_rate: prov.frame_rate.filter(|r| r.is_finite() && *r > 0.0),
            rows: 0,
            line: String::with_capacity(160),
        };
        o.header(&prov.slider_name, &prov.bob_name)?;
        Ok(o)
    }

    /// The layout being written.
    pub fn style(&self) -> CsvStyle {
        self.style
    }

    fn header(&mut self, slider: &str, bob: &str) -> std::io::Result<()> {
        let names = [slider, bob];
        let h = match self.style {
            CsvStyle::Tracker => {
                let [s, b] = names.map(tab_cell);
                format!("#multi:\n\t{s}\t\t{b}\t\nt\tx\ty\tx\ty\n")
            }
            CsvStyle::DeepLabCut => {
                // Multi-animal names (SLEAP's `track/node`) keep their individual in a row of
                // its own, as DeepLabCut's four-row header does, so they read back the same.
                let split: Vec<(&str, &str)> =
                    names.iter().filter_map(|n| n.split_once('/')).collect();
                let scorer = "appell_model";
                let mut rows = vec![format!("scorer{}", format!(",{scorer}").repeat(6))];
                if split.len() == 2 {
                    let ind: Vec<String> = split
                        .iter()
                        .map(|(i, _)| format!(",{0},{0},{0}", csv_cell(i)))
                        .collect();
                    rows.push(format!("individuals{}", ind.concat()));
                    let parts: Vec<String> = split
                        .iter()
                        .map(|(_, p)| format!(",{0},{0},{0}", csv_cell(p)))
                        .collect();
                    rows.push(format!("bodyparts{}", parts.concat()));
                } else {
                    let parts: Vec<String> = names
                        .iter()
                        .map(|p| format!(",{0},{0},{0}", csv_cell(p)))
                        .collect();
                    rows.push(format!("bodyparts{}", parts.concat()));
                }
                rows.push("coords,x,y,likelihood,x,y,likelihood".into());
                rows.join("\n") + "\n"
            }
            CsvStyle::Motive => {
                let mut meta = "Format Version,1.23,Take Name,appell model".to_owned();
                if let Some(r) = self.frame_rate {
                    write!(meta, ",Capture Frame Rate,{r:.6},Export Frame Rate,{r:.6}")
                        .expect("a String takes any write");
                }
                if let Some(u) = motive_units(self.calibration.scale) {
                    write!(meta, ",Length Units,{u}").expect("a String takes any write");
                }
                meta += ",Coordinate Space,Global";
                let [s, b] = names.map(csv_cell);
                format!(
                    "{meta}\n\n,Type,Marker,Marker,Marker,Marker,Marker,Marker\n,Name,{s},{s},{s},{b},{b},{b}\n,ID,1,1,1,2,2,2\n,,Position,Position,Position,Position,Position,Position\nFrame,Time (Seconds),X,Y,Z,X,Y,Z\n"
                )
            }
            CsvStyle::Wide => {
                let t = if self.origin_ns.is_some() {
                    "t_ns"
                } else {
                    "t"
                };
                let [s, b] = names.map(csv_cell);
                format!("{t},{s}_x,{s}_y,{b}_x,{b}_y\n")
            }
        };
        self.out.write_all(h.as_bytes())
    }

    /// The frame number of time `t` (s from the first frame) at the file's frame rate, else
    /// the row's index.
    fn frame_number(&self, t: f64) -> i64 {
        match self.frame_rate {
            Some(r) => ((self.time_origin + t) * r).round() as i64,
            None => self.rows as i64,
        }
    }

    /// Write the model's markers `[slider_x, slider_y, bob_x, bob_y]` (m, rail frame) at time
    /// `t` (s from the first frame); `None` leaves the frame's cells empty (a run that stopped).
    pub fn row(&mut self, t: f64, model: Option<[f64; 4]>) -> std::io::Result<()> {
        let points = model.map(|m| {
            [
                self.calibration.to_file([m[0], m[1]]),
                self.calibration.to_file([m[2], m[3]]),
            ]
        });
        let mut line = std::mem::take(&mut self.line);
        line.clear();
        let w = &mut line;
        // Writing to a String cannot fail.
        let ok = |r: std::fmt::Result| r.expect("a String takes any write");
        match self.style {
            CsvStyle::Tracker => {
                ok(write!(w, "{}", self.time_origin + t));
                for p in points.iter().flatten() {
                    ok(write!(w, "\t{}\t{}", p[0], p[1]));
                }
                if points.is_none() {
                    w.push_str("\t\t\t\t");
                }
            }
            CsvStyle::DeepLabCut => {
                ok(write!(w, "{}", self.frame_number(t)));
                for p in points.iter().flatten() {
                    ok(write!(w, ",{},{},1", p[0], p[1]));
                }
                if points.is_none() {
                    w.push_str(",,,,,,");
                }
            }
            CsvStyle::Motive => {
                let frame = self.frame_number(t);
                match self.frame_rate {
                    Some(r) => ok(write!(w, "{frame},{:.6}", frame as f64 / r)),
                    None => ok(write!(w, "{frame},{}", self.time_origin + t)),
                }
                for (p, depth) in points.iter().flatten().zip(self.off_plane) {
                    let xyz = match self.plane.unwrap_or(Plane::Xy) {
                        Plane::Xy => [p[0], p[1], depth],
                        Plane::Xz => [p[0], depth, p[1]],
                        Plane::Yz => [depth, p[0], p[1]],
                    };
                    ok(write!(w, ",{},{},{}", xyz[0], xyz[1], xyz[2]));
                }
                if points.is_none() {
                    w.push_str(",,,,,,");
                }
            }
            CsvStyle::Wide => {
                match self.origin_ns {
                    Some(ns) => ok(write!(w, "{}", ns.saturating_add((t * 1e9).round() as i64))),
                    None => ok(write!(w, "{}", self.time_origin + t)),
                }
                for p in points.iter().flatten() {
                    ok(write!(w, ",{},{}", p[0], p[1]));
                }
                if points.is_none() {
                    w.push_str(",,,,");
                }
            }
        }
        line.push('\n');
        let r = self.out.write_all(line.as_bytes());
        self.line = line;
        self.rows += 1;
        r
    }

    /// Flush what was written.
    pub fn finish(self) -> std::io::Result<()> {
        self.out.flush()
    }
}
