//! DeepLabCut's CSV: three or four header rows (scorer, \[individuals,\] bodyparts, coords),
//! then one row per frame or labelled image. The columns go through [`crate::data::dlc::Builder`],
//! shared with DeepLabCut's HDF5 reader.

use super::rows::Rows;
use crate::data::dlc::{Builder, Cells};
use crate::data::{DataError, Parsed, ReadOptions};
use std::io::Read;
use std::path::Path;

/// Read DeepLabCut's CSV: its header rows, then one row per frame (labelled images are
/// numbered).
pub(super) fn read_dlc(
    input: impl Read,
    path: &Path,
    opts: &ReadOptions,
) -> Result<Parsed, DataError> {
    let mut rows = Rows::new(input, path, b',');
    let scorer = rows.header("DeepLabCut header rows scorer, bodyparts, coords")?;
    if scorer.first().map(|s| s.to_lowercase()) != Some("scorer".into()) {
        return Err(rows.err(
            "first cell",
            "\"scorer\"",
            format!("{:?}", scorer.first().cloned().unwrap_or_default()),
        ));
    }
    let next_header = |rows: &mut Rows<_>, want: &[&str]| -> Result<Vec<String>, DataError> {
        if !rows.next()? {
            return Err(DataError::NoFrames {
                path: path.to_owned(),
                what: "an incomplete DeepLabCut header".into(),
            });
        }
        let row: Vec<String> = rows.rec.iter().map(|c| c.trim().to_string()).collect();
        let key = row.first().map(|c| c.to_lowercase()).unwrap_or_default();
        if !want.contains(&key.as_str()) {
            return Err(rows.err("first cell", want.join(" or "), format!("{key:?}")));
        }
        Ok(row)
    };
    let r1 = next_header(&mut rows, &["individuals", "bodyparts"])?;
    let (individuals, bodyparts) = if r1[0].eq_ignore_ascii_case("individuals") {
        (Some(r1), next_header(&mut rows, &["bodyparts"])?)
    } else {
        (None, r1)
    };
    let coords = next_header(&mut rows, &["coords"])?;
    // Index columns come first: the frame number, or (labelled data) the image path, in one
    // column or three.
    let first_data = (1..coords.len())
        .find(|&j| ["x", "y", "z", "likelihood"].contains(&coords[j].to_lowercase().as_str()))
        .unwrap_or(1);
    fn label(row: &[String], j: usize) -> &str {
        row.get(j).map_or("", |c| c.as_str())
    }
    let columns = (first_data..coords.len()).map(|j| {
        (
            j,
            individuals.as_ref().map(|ind| label(ind, j)),
            label(&bodyparts, j),
            coords[j].as_str(),
        )
    });
    let mut dlc = Builder::new(columns, path, opts, |field, expected, found| {
        rows.err(field, expected, found)
    })?;
    while rows.next()? {
        if rows.is_blank() {
            continue;
        }
        rows.width(coords.len())?;
        // Labelled data index rows by image path: number them instead.
        let frame = if first_data == 1 && rows.num(0, "frame index", false).is_ok() {
            rows.req(0, "frame index", false)?
        } else {
            dlc.frames() as f64
        };
        dlc.row(path, frame, &rows)?;
    }
    dlc.finish(path, "DeepLabCut header rows")
}

impl<R: Read> Cells for Rows<R> {
    fn number(&self, j: usize, field: &dyn Fn() -> String) -> Result<Option<f64>, DataError> {
        self.num_named(j, field, false)
    }

    fn error(&self, field: &str, expected: &str, found: String) -> DataError {
        self.err(field, expected, found)
    }

    fn at(&self) -> String {
        Rows::at(self)
    }
}
