//! DeepLabCut's HDF5 output: a pandas DataFrame that `DataFrame.to_hdf` stores through PyTables,
//! read with the pure-Rust `hdf5-reader` crate (no C library).
//!
//! DeepLabCut writes analysed videos with `to_hdf(path, key="df_with_missing", format="table",
//! mode="w")` and labelled frames converted from CSV in pandas' default "fixed" format; other
//! tools keep the layout under other keys (`tracks` after stitching tracklets, `keypoints` in
//! napari-deeplabcut). The DataFrame sits in a group named by the key, its columns labelled
//! (scorer, \[individuals,\] bodyparts, coords), one row per frame (or labelled image):
//! - table format (`pandas_type` `frame_table`): a compound dataset `table` with fields `index`
//!   (the frame number, or the image path) and `values_block_0` (the row's values); the column
//!   labels are that dataset's attribute `values_block_0_kind`, a list of tuples that PyTables
//!   pickles with protocol 0 (decoded by `serde-pickle`, after a check that the pickle is that
//!   list and nothing else, so that no attribute expands without bound: `pickle.rs`);
//! - fixed format (`pandas_type` `frame`): `block0_values` (rows x columns), the column labels
//!   as per-level names and codes `block0_items_level{i}`/`block0_items_label{i}`, the row index
//!   in `axis1` (or `axis1_level{i}`/`axis1_label{i}` for image paths split into parts).
//!
//! The columns then go through the DeepLabCut CSV reader's own rules
//! ([`crate::data::dlc::Builder`]): the same marker names, `--min-likelihood`, pixels with y
//! down, t = frame / `--fps`. NaN is missing; a numeric row index gives the frame numbers, image
//! paths number the rows.

use super::io::{number, numeric, raw, Src};
use super::pickle::unpickle_labels;
use crate::data::dlc::{Builder, Cells};
use crate::data::{DataError, Parsed, ReadOptions, Resource};
use hdf5_reader::group::Group;
use hdf5_reader::{Dataset, Datatype, Hdf5File};
use std::path::Path;

/// The key DeepLabCut writes its DataFrame under.
const DLC_KEY: &str = "df_with_missing";

/// The key of the pandas DataFrame in `f`, if it holds one: `df_with_missing`, else the one
/// top-level group that pandas marked with a `pandas_type`.
pub(super) fn pandas_key(f: &Hdf5File) -> Option<String> {
    let groups = f.root_group().and_then(|r| r.groups()).ok()?;
    let pandas: Vec<String> = groups
        .iter()
        .filter(|g| pandas_type(g).is_some())
        .map(|g| g.name().trim_start_matches('/').to_string())
        .collect();
    match &pandas[..] {
        [only] => Some(only.clone()),
        _ => pandas.into_iter().find(|k| k == DLC_KEY),
    }
}

fn pandas_type(g: &Group) -> Option<String> {
    g.attribute("pandas_type")
        .and_then(|a| a.read_string())
        .ok()
}

/// A DataFrame's numbers: column labels, values row by row, frame numbers when the row index
/// is numeric.
struct Frame {
    labels: Vec<Vec<String>>,
    values: Vec<f64>,
    frames: Option<Vec<f64>>,
    /// Where the labels are, for errors.
    labels_at: String,
    /// Where the values are, for errors.
    at: String,
}

/// Read the DataFrame DeepLabCut wrote under `key` in `f` (the file `src`).
pub(super) fn read(
    f: &Hdf5File,
    key: &str,
    src: &Src,
    opts: &ReadOptions,
) -> Result<Parsed, DataError> {
    let path = src.path;
    let bad = |at: &str, field: &str, expected: &str, found: String| {
        DataError::parse(path, at, field, expected, found)
    };
    let group = f
        .group(key)
        .map_err(|e| bad("the HDF5 file", key, "a group", e.to_string()))?;
    let at = format!("/{key}");
    let frame = match pandas_type(&group).as_deref() {
        Some("frame_table") => read_table(&group, &format!("{at}/table"), src)?,
        Some("frame") => read_fixed(&group, &at, src)?,
        other => {
            return Err(DataError::Unsupported {
                path: path.to_owned(),
                what: format!("pandas storage of {at}"),
                found: other.unwrap_or("(none)").into(),
                supported:
                    "a DataFrame in the table format (frame_table) or the fixed format (frame)"
                        .into(),
            })
        }
    };
    // Every position kept takes at least two of the values (x and y): charged before the
    // series are built, as the SLEAP reader charges its declared shape.
    src.charge(Resource::Samples, (frame.values.len() / 2) as u64)?;
    build(frame, path, opts)
}

/// Turn a DataFrame into DeepLabCut's series.
fn build(frame: Frame, path: &Path, opts: &ReadOptions) -> Result<Parsed, DataError> {
    let width = frame.labels.len();
    for l in &frame.labels {
        if !(3..=4).contains(&l.len()) {
            return Err(DataError::parse(
                path,
                &frame.labels_at,
                "column labels",
                "DeepLabCut's (scorer, bodyparts, coords) or (scorer, individuals, bodyparts, coords)",
                format!("{} level(s): {l:?}", l.len()),
            ));
        }
    }
    let columns = frame.labels.iter().enumerate().map(|(j, l)| match &l[..] {
        [_, ind, part, coord] => (j, Some(ind.as_str()), part.as_str(), coord.as_str()),
        _ => (j, None, l[1].as_str(), l[2].as_str()),
    });
    let mut dlc = Builder::new(columns, path, opts, |field, expected, found| {
        DataError::parse(path, &frame.labels_at, field, expected, found)
    })?;
    for (r, values) in frame.values.chunks_exact(width.max(1)).enumerate() {
        let number = frame.frames.as_ref().map_or(r as f64, |f| f[r]);
        let row = Row {
            values,
            r,
            at: &frame.at,
            path,
        };
        dlc.row(path, number, &row)?;
    }
    dlc.finish(path, &format!("column labels in {} but no rows", frame.at))
}

/// One row of values; NaN is missing.
struct Row<'a> {
    values: &'a [f64],
    r: usize,
    at: &'a str,
    path: &'a Path,
}

impl Cells for Row<'_> {
    fn number(&self, j: usize, field: &dyn Fn() -> String) -> Result<Option<f64>, DataError> {
        match self.values.get(j) {
            Some(v) if v.is_nan() => Ok(None),
            Some(v) if v.is_finite() => Ok(Some(*v)),
            v => Err(self.error(&field(), "a finite number or NaN", format!("{v:?}"))),
        }
    }

    fn error(&self, field: &str, expected: &str, found: String) -> DataError {
        DataError::parse(self.path, self.at(), field, expected, found)
    }

    fn at(&self) -> String {
        format!("row {} of {}", self.r, self.at)
    }
}

/// The table format: one compound row per frame.
fn read_table(group: &Group, at: &str, src: &Src) -> Result<Frame, DataError> {
    let path = src.path;
    let bad = |field: &str, expected: &str, found: String| {
        DataError::parse(path, at, field, expected, found)
    };
    let table = group
        .dataset("table")
        .map_err(|e| bad("table", "a dataset", e.to_string()))?;
    let Datatype::Compound { size, fields } = table.dtype().clone() else {
        return Err(bad(
            "table",
            "a compound dataset (PyTables' table)",
            format!("{:?}", table.dtype()),
        ));
    };
    let blocks: Vec<&str> = fields
        .iter()
        .map(|f| f.name.as_str())
        .filter(|n| n.starts_with("values_block_"))
        .collect();
    let values = match (
        &blocks[..],
        fields.iter().find(|f| f.name == "values_block_0"),
    ) {
        ([_], Some(v)) => v,
        _ => {
            return Err(bad(
                "fields",
                "one block of values, values_block_0 (DeepLabCut's floats)",
                format!("{blocks:?}"),
            ))
        }
    };
    let (width, base) = match &values.datatype {
        Datatype::Array { base, dims } if dims.len() == 1 => (dims[0] as usize, base.as_ref()),
        other if numeric(other) => (1, other),
        other => {
            return Err(bad(
                "values_block_0",
                "an array of floats per row",
                format!("{other:?}"),
            ))
        }
    };
    let Datatype::FloatingPoint { size: cell, .. } = base else {
        return Err(bad(
            "values_block_0",
            "floats (DeepLabCut writes float64)",
            format!("{base:?}"),
        ));
    };
    let (size, offset, cell) = (size as usize, values.byte_offset as usize, *cell as usize);
    if width
        .checked_mul(cell)
        .and_then(|w| w.checked_add(offset))
        .is_none_or(|end| end > size)
    {
        return Err(bad(
            "values_block_0",
            &format!("{width} values within the row's {size} bytes"),
            format!("offset {offset}"),
        ));
    }
    let index = fields
        .iter()
        .find(|f| f.name == "index" && numeric(&f.datatype));
    let kind = table
        .attribute("values_block_0_kind")
        .map_err(|e| bad("values_block_0_kind", "the column labels", e.to_string()))?;
    let labels = unpickle_labels(&kind.raw_data, |n| src.charge(Resource::DecodedBytes, n))?
        .map_err(|found| {
            bad(
                "values_block_0_kind",
                "a protocol-0 pickle of a list of column labels, as PyTables writes",
                found,
            )
        })?;
    if labels.len() != width {
        return Err(bad(
            "values_block_0_kind",
            &format!("{width} column labels, one per value"),
            format!("{}", labels.len()),
        ));
    }
    let bytes = raw(&table, at, src)?;
    let rows = bytes.len() / size.max(1);
    let mut out = Vec::with_capacity(rows * width);
    let mut frames = index.map(|_| Vec::with_capacity(rows));
    for row in bytes.chunks_exact(size.max(1)) {
        for c in 0..width {
            out.push(number(&row[offset + c * cell..], base).unwrap_or(f64::NAN));
        }
        if let (Some(frames), Some(ix)) = (&mut frames, index) {
            let cell = row.get(ix.byte_offset as usize..);
            frames.push(
                cell.and_then(|c| number(c, &ix.datatype))
                    .unwrap_or(f64::NAN),
            );
        }
    }
    Ok(Frame {
        labels,
        values: out,
        frames,
        labels_at: format!("{at} attribute values_block_0_kind"),
        at: at.into(),
    })
}

/// The fixed format: a 2-D block of values, labels as levels and codes.
fn read_fixed(group: &Group, at: &str, src: &Src) -> Result<Frame, DataError> {
    let path = src.path;
    let bad = |field: &str, expected: &str, found: String| {
        DataError::parse(path, at, field, expected, found)
    };
    let int_attr = |name: &str| {
        group
            .attribute(name)
            .ok()
            .and_then(|a| number(&a.raw_data, &a.datatype))
    };
    let nblocks = int_attr("nblocks");
    if nblocks != Some(1.0) {
        return Err(bad(
            "nblocks",
            "one block of values (DeepLabCut's floats)",
            format!("{nblocks:?}"),
        ));
    }
    let dataset = |name: &str| {
        group
            .dataset(name)
            .map_err(|e| bad(name, "a dataset", e.to_string()))
    };
    let block = dataset("block0_values")?;
    // Column labels: one name per level, indexed by one code per column (as many as the
    // values' declared columns).
    let nlevels = int_attr("block0_items_nlevels").unwrap_or(1.0);
    let width = columns(&block);
    let labels = fixed_labels(nlevels, width, at, src, &bad, &dataset)?;
    let (values, rows) = fixed_values(&block, labels.len(), at, src, &bad)?;
    let frames = fixed_frames(group, rows, at, src, &bad)?;
    Ok(Frame {
        labels,
        values,
        frames,
        labels_at: format!("{at}/block0_items_level*"),
        at: format!("{at}/block0_values"),
    })
}

/// The fixed format's column labels: per level (`nlevels` of them, at most 8) the names
/// `block0_items_level{i}` indexed by one code per column `block0_items_label{i}`; one level
/// is the names `block0_items`. `dataset(name)` opens a dataset of the group. Every level must
/// hold `width` codes, one per column of the values (checked from the declared shape, before
/// any code is read), and the strings the labels come to are charged before they are made.
fn fixed_labels(
    nlevels: f64,
    width: usize,
    at: &str,
    src: &Src,
    bad: &impl Fn(&str, &str, String) -> DataError,
    dataset: &impl Fn(&str) -> Result<Dataset, DataError>,
) -> Result<Vec<Vec<String>>, DataError> {
    // What one label string costs besides its text.
    const STRING: u64 = std::mem::size_of::<String>() as u64;
    let names = |name: &str| -> Result<Vec<String>, DataError> {
        let ds = dataset(name)?;
        src.charge_declared(&ds, at)?;
        ds.read_strings()
            .map_err(|e| bad(name, "strings", e.to_string()))
    };
    if nlevels > 1.0 {
        let mut levels = Vec::new();
        for i in 0..(nlevels as usize).min(8) {
            let names = names(&format!("block0_items_level{i}"))?;
            let codes_ds = dataset(&format!("block0_items_label{i}"))?;
            let declared: u64 = codes_ds.shape().iter().product();
            if declared != width as u64 {
                return Err(bad(
                    codes_ds.name(),
                    &format!("{width} codes, one per column of block0_values"),
                    format!("{declared}"),
                ));
            }
            // Each code becomes a string: their headers are charged before the codes are
            // read, their text once the codes say which names they are.
            src.charge(Resource::DecodedBytes, declared.saturating_mul(STRING))?;
            let codes = raw(&codes_ds, at, src)?;
            let step = codes_ds.raw_element_size().unwrap_or(1).max(1);
            let level: Vec<usize> = codes
                .chunks_exact(step)
                .map(|c| {
                    number(c, codes_ds.dtype())
                        .filter(|&k| k >= 0.0 && (k as usize) < names.len())
                        .map(|k| k as usize)
                        .ok_or_else(|| {
                            bad(
                                codes_ds.name(),
                                &format!("codes of the {} names in level {i}", names.len()),
                                format!("{c:?}"),
                            )
                        })
                })
                .collect::<Result<_, _>>()?;
            let bytes = level
                .iter()
                .fold(0u64, |n, &k| n.saturating_add(names[k].len() as u64));
            src.charge(Resource::DecodedBytes, bytes)?;
            levels.push((names, level));
        }
        let n = levels[0].1.len();
        if levels.iter().any(|l| l.1.len() != n) {
            return Err(bad(
                "block0_items_label",
                "as many codes in every level",
                format!("{:?}", levels.iter().map(|l| l.1.len()).collect::<Vec<_>>()),
            ));
        }
        Ok((0..n)
            .map(|j| {
                levels
                    .iter()
                    .map(|(names, codes)| names[codes[j]].clone())
                    .collect()
            })
            .collect())
    } else {
        let names = names("block0_items")?;
        Ok(names.into_iter().map(|n| vec![n]).collect())
    }
}

/// Whether `block0_values` is stored rows x columns: pandas writes the block transposed and
/// says so; older files did not.
fn transposed(block: &Dataset) -> bool {
    block
        .attribute("transposed")
        .ok()
        .and_then(|a| a.raw_data.first().copied())
        .is_some_and(|b| b != 0)
}

/// How many columns `block0_values` declares (0 when it is not 2-D).
fn columns(block: &Dataset) -> usize {
    match (block.shape(), transposed(block)) {
        ([_, c], true) | ([c, _], false) => *c as usize,
        _ => 0,
    }
}

/// The fixed format's values `block0_values`, row by row (`width` columns), and the number of
/// rows.
fn fixed_values(
    block: &Dataset,
    width: usize,
    at: &str,
    src: &Src,
    bad: &impl Fn(&str, &str, String) -> DataError,
) -> Result<(Vec<f64>, usize), DataError> {
    let transposed = transposed(block);
    let shape: Vec<usize> = block.shape().iter().map(|&d| d as usize).collect();
    let rows = match (&shape[..], transposed) {
        ([r, c], true) if *c == width => *r,
        ([c, r], false) if *c == width => *r,
        _ => {
            return Err(bad(
                "block0_values",
                &format!("{width} columns, one per label"),
                format!("shape {shape:?}"),
            ))
        }
    };
    if !matches!(block.dtype(), Datatype::FloatingPoint { size: 4 | 8, .. }) {
        return Err(bad(
            "block0_values",
            "floats (DeepLabCut writes float64)",
            format!("{:?}", block.dtype()),
        ));
    }
    let cell = block.raw_element_size().unwrap_or(8).max(1);
    let bytes = raw(block, at, src)?;
    let want = rows.checked_mul(width).and_then(|n| n.checked_mul(cell));
    if want != Some(bytes.len()) {
        return Err(bad(
            "block0_values",
            &format!("{rows} x {width} values of {cell} bytes"),
            format!("{} bytes", bytes.len()),
        ));
    }
    let value = |r: usize, c: usize| {
        let k = if transposed {
            r * width + c
        } else {
            c * rows + r
        };
        number(&bytes[k * cell..], block.dtype()).unwrap_or(f64::NAN)
    };
    let values = (0..rows)
        .flat_map(|r| (0..width).map(move |c| (r, c)))
        .map(|(r, c)| value(r, c))
        .collect();
    Ok((values, rows))
}

/// The fixed format's frame numbers (`rows` of them): the row index `axis1` when it is numeric.
fn fixed_frames(
    group: &Group,
    rows: usize,
    at: &str,
    src: &Src,
    bad: &impl Fn(&str, &str, String) -> DataError,
) -> Result<Option<Vec<f64>>, DataError> {
    // A numeric row index holds frame numbers; image paths (strings, or levels) do not.
    Ok(match group.dataset("axis1") {
        Ok(axis) if numeric(axis.dtype()) => {
            let step = axis.raw_element_size().unwrap_or(8).max(1);
            let ix = raw(&axis, at, src)?;
            let frames: Vec<f64> = ix
                .chunks_exact(step)
                .map(|c| number(c, axis.dtype()).unwrap_or(f64::NAN))
                .collect();
            if frames.len() != rows {
                return Err(bad(
                    "axis1",
                    &format!("{rows} frame numbers, one per row"),
                    format!("{}", frames.len()),
                ));
            }
            Some(frames)
        }
        _ => None,
    })
}
