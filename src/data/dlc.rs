//! DeepLabCut's layout, shared by its CSV reader and its HDF5 reader: data columns labelled
//! (scorer, \[individuals,\] bodyparts, coords) with coords x, y (z) and likelihood, one row per
//! frame, pixels with y down. Markers are named `bodypart`, or `individual/bodypart` for
//! multi-animal files; a point whose likelihood is under `--min-likelihood` counts as missing.

use super::table::rows::{all_or_none, Clock};
use super::{DataError, Parsed, Plane, ReadOptions, Series};
use std::collections::HashMap;
use std::path::Path;

/// One row's cells, as the CSV and HDF5 readers hold them.
pub(crate) trait Cells {
    /// Cell `j` as a number: `None` when missing (an empty CSV cell, a NaN in HDF5); an error
    /// (naming `field()`) when it is not a finite number.
    fn number(&self, j: usize, field: &dyn Fn() -> String) -> Result<Option<f64>, DataError>;
    /// An error about this row.
    fn error(&self, field: &str, expected: &str, found: String) -> DataError;
    /// Where this row is (`line N`, `row N of /df_with_missing/table`).
    fn at(&self) -> String;
}

/// One marker's cells: x, y, likelihood, z.
type Slots = [Option<usize>; 4];

/// DeepLabCut's markers being read, row by row, into series.
pub(crate) struct Builder {
    markers: Vec<(usize, usize, Option<usize>, Option<usize>)>,
    series: Vec<Series>,
    times: Vec<f64>,
    clock: Clock,
    dropped: usize,
    three_d: bool,
    plane: Plane,
    fps: f64,
    min_likelihood: f64,
}

impl Builder {
    /// Group the data columns by marker: `columns` gives each column's cell index, individual
    /// (`None` without an individuals level), bodypart and coord. `bad(field, expected, found)`
    /// makes a header error where the caller's header is. Needs `--fps` (frames have no times).
    pub(crate) fn new<'a>(
        columns: impl IntoIterator<Item = (usize, Option<&'a str>, &'a str, &'a str)>,
        path: &Path,
        opts: &ReadOptions,
        bad: impl Fn(String, String, String) -> DataError,
    ) -> Result<Builder, DataError> {
        let mut grouped: Vec<(String, Slots)> = Vec::new();
        // Each marker's place in `grouped`: wide headers are grouped in linear time.
        let mut index: HashMap<String, usize> = HashMap::new();
        for (j, individual, part, coord) in columns {
            let name = match individual {
                Some(ind) if !(ind.is_empty() || ind == "single") => format!("{ind}/{part}"),
                _ => part.to_string(),
            };
            let k = *index.entry(name.clone()).or_insert_with(|| {
                grouped.push((name, [None; 4]));
                grouped.len() - 1
            });
            let slot = match coord.to_lowercase().as_str() {
                "x" => 0,
                "y" => 1,
                "likelihood" => 2,
                "z" => 3,
                other => {
                    return Err(bad(
                        format!("coords column {}", j + 1),
                        "x, y, z or likelihood".into(),
                        format!("{other:?}"),
                    ))
                }
            };
            grouped[k].1[slot] = Some(j);
        }
        let mut markers = Vec::new();
        for (name, [x, y, l, z]) in &grouped {
            let (Some(x), Some(y)) = (x, y) else {
                return Err(bad(
                    "coords".into(),
                    format!("x and y columns for {name:?}"),
                    "only some".into(),
                ));
            };
            markers.push((*x, *y, *l, *z));
        }
        let fps = opts.fps.ok_or_else(|| DataError::Options {
            path: path.to_owned(),
            message:
                "DeepLabCut files have no time column: give the video's frame rate with --fps HZ"
                    .into(),
        })?;
        Ok(Builder {
            three_d: markers.iter().any(|m| m.3.is_some()),
            markers,
            series: grouped
                .into_iter()
                .map(|(name, _)| Series {
                    name,
                    ..Series::default()
                })
                .collect(),
            times: Vec::new(),
            clock: Clock::default(),
            dropped: 0,
            plane: opts.plane.unwrap_or(Plane::Xy),
            fps,
            min_likelihood: opts.min_likelihood,
        })
    }

    /// How many rows were added.
    pub(crate) fn frames(&self) -> usize {
        self.times.len()
    }

    /// Add the row of frame `frame`: each marker's point, missing where its cells are, or where
    /// its likelihood is under the threshold.
    pub(crate) fn row(
        &mut self,
        path: &Path,
        frame: f64,
        cells: &impl Cells,
    ) -> Result<(), DataError> {
        let t = frame / self.fps;
        self.clock.check(path, || cells.at(), t)?;
        self.times.push(t);
        for (k, &(x, y, l, z)) in self.markers.iter().enumerate() {
            let name = &self.series[k].name;
            let coord = |j: usize, axis: &str| cells.number(j, &|| format!("{name} {axis}"));
            let (xy, zv) = ([coord(x, "x")?, coord(y, "y")?], z.map(|z| coord(z, "z")));
            let filled = |present: usize, n: usize| {
                cells.error(
                    name,
                    "all coordinates or none",
                    format!("{present} of {n} cells filled"),
                )
            };
            let mut p = match zv {
                Some(zv) => all_or_none([xy[0], xy[1], zv?])
                    .map_err(|present| filled(present, 3))?
                    .map(|p| self.plane.project(p)),
                None => all_or_none(xy).map_err(|present| filled(present, 2))?,
            };
            if let (Some(_), Some(l)) = (p, l) {
                if cells.number(l, &|| "likelihood".into())?.unwrap_or(0.0) < self.min_likelihood {
                    p = None;
                    self.dropped += 1;
                }
            }
            self.series[k].points.push(p);
        }
        Ok(())
    }

    /// The series read, or `NoFrames` when no row was; `what` says what the file had instead.
    pub(crate) fn finish(mut self, path: &Path, what: &str) -> Result<Parsed, DataError> {
        if self.times.is_empty() {
            return Err(DataError::NoFrames {
                path: path.to_owned(),
                what: what.into(),
            });
        }
        for s in &mut self.series {
            s.times = self.times.clone();
        }
        Ok(Parsed {
            series: self.series,
            scale: None,
            // 3-D triangulations are in the calibration's frame, not image pixels.
            y_down: !self.three_d,
            notes: vec![format!(
                "DeepLabCut: pixels with y down, t = frame / {} Hz; {} point(s) under likelihood {} counted as missing",
                self.fps, self.dropped, self.min_likelihood
            )],
            plane: self.three_d.then_some(self.plane),
            frame_rate: Some(self.fps),
            ..Parsed::default()
        })
    }
}
