//! Vicon Nexus' CSV export: its Trajectories section (frame rate, marker names, the
//! `Frame,Sub Frame,X,Y,Z` header, units), read up to the next section; z up.

use super::rows::Rows;
use super::xyz::{complete, group_xyz, read_xyz_rows, unit_scale};
use crate::data::{DataError, Parsed, Plane, ReadOptions};
use std::io::Read;
use std::path::Path;

/// Read a Vicon Nexus CSV export's Trajectories section.
pub(super) fn read_vicon(
    input: impl Read,
    path: &Path,
    opts: &ReadOptions,
) -> Result<Parsed, DataError> {
    let mut rows = Rows::new(input, path, b',');
    let mut any = false;
    loop {
        if !rows.next()? {
            return Err(if any {
                DataError::parse(
                    path,
                    format!("line {}", rows.line),
                    "section",
                    "a Trajectories section",
                    "end of file",
                )
            } else {
                DataError::Empty {
                    path: path.to_owned(),
                    expected: "a Vicon Nexus export with a Trajectories section".into(),
                }
            });
        }
        any = true;
        if rows.cell(0).trim().eq_ignore_ascii_case("trajectories") {
            break;
        }
    }
    let need = |rows: &mut Rows<_>, what: &str| -> Result<Vec<String>, DataError> {
        if !rows.next()? {
            return Err(DataError::NoFrames {
                path: path.to_owned(),
                what: format!("a Trajectories section without {what}"),
            });
        }
        Ok(rows.rec.iter().map(|c| c.trim().to_string()).collect())
    };
    need(&mut rows, "a frame rate")?;
    let rate = rows.req(0, "frame rate (Hz)", false)?;
    if rate <= 0.0 {
        return Err(rows.err("frame rate (Hz)", "a positive number", rate.to_string()));
    }
    let names = need(&mut rows, "marker names")?;
    let header = need(&mut rows, "a Frame,Sub Frame,X,Y,Z header")?;
    if !header
        .first()
        .is_some_and(|c| c.eq_ignore_ascii_case("frame"))
    {
        return Err(rows.err(
            "header",
            "Frame,Sub Frame,X,Y,Z,...",
            format!("{:?}", header.join(",")),
        ));
    }
    let units = need(&mut rows, "a units row")?;
    let mut current = String::new();
    let groups = group_xyz(
        (2..header.len()).map(|j| {
            if let Some(n) = names.get(j).filter(|n| !n.is_empty()) {
                current = n.clone();
            }
            (j, current.clone())
        }),
        &header,
    );
    let markers = complete(
        |e| rows.err("header", e, format!("{:?}", names.join(","))),
        groups,
    )?;
    let unit = units.get(markers[0].1[0]).cloned().unwrap_or_default();
    let scale = unit_scale(&unit);
    let plane = opts.plane.unwrap_or(Plane::Xz);
    let mut first = None;
    let series = read_xyz_rows(
        &mut rows,
        path,
        &markers,
        plane,
        |r| {
            let f = r.req(0, "Frame", false)?;
            let f0 = *first.get_or_insert(f);
            Ok((f - f0) / rate)
        },
        true,
    )?;
    Ok(Parsed {
        series,
        scale: Some(match scale {
            Some(s) => (s, format!("units {unit} from the file")),
            None => (0.001, format!("units {unit:?} not recognised: millimetres assumed")),
        }),
        notes: vec![format!(
            "Vicon: {rate} Hz, t = (frame - first frame) / rate; plane {} (Vicon's z is up; --plane to change)",
            plane.name()
        )],
        plane: Some(plane),
        ..Parsed::default()
    })
}
