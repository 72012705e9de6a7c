//! Tracker project files (`.trk`, XML): the frames of each point-mass track, turned into world
//! coordinates through the project's coordinate system, with the clip's frame duration for
//! times. Model particles store formulas, not data: a project with only models is an error
//! that says so.

use super::{DataError, Parsed, Series};
use roxmltree::{Document, Node};
use std::path::Path;

/// The largest project file read (bytes): Tracker projects are kilobytes to a few megabytes.
pub const MAX_TRK_BYTES: usize = 64 << 20;

/// Tracker classes that hold no measured positions: models compute theirs from formulas.
const MODELS: [&str; 5] = [
    "DynamicParticle",
    "DynamicParticlePolar",
    "AnalyticParticle",
    "ParticleModel",
    "DynamicSystem",
];

fn class<'a>(n: &Node<'a, '_>) -> &'a str {
    n.attribute("class")
        .unwrap_or("")
        .rsplit('.')
        .next()
        .unwrap_or("")
}

/// The `<property name=NAME>` child of an object.
fn property<'a, 'b>(obj: Node<'a, 'b>, name: &str) -> Option<Node<'a, 'b>> {
    obj.children()
        .find(|c| c.has_tag_name("property") && c.attribute("name") == Some(name))
}

fn number(obj: Node, name: &str) -> Option<f64> {
    property(obj, name)?.text()?.trim().parse().ok()
}

fn string(obj: Node, name: &str) -> Option<String> {
    Some(property(obj, name)?.text()?.trim().to_string())
}

/// The objects inside an array property, with their `[n]` index.
fn indexed<'a, 'b>(array: Node<'a, 'b>) -> impl Iterator<Item = (usize, Node<'a, 'b>)> {
    array.children().filter_map(|p| {
        let n = p
            .attribute("name")?
            .strip_prefix('[')?
            .strip_suffix(']')?
            .parse()
            .ok()?;
        Some((n, p.children().find(|c| c.has_tag_name("object"))?))
    })
}

/// One frame's image-to-world transform: origin (px), angle (rad, x axis counterclockwise
/// from the image's horizontal), scales (px per unit).
#[derive(Clone, Copy)]
struct Coords {
    origin: [f64; 2],
    angle: f64,
    scale: [f64; 2],
}

impl Coords {
    fn world(&self, p: [f64; 2]) -> [f64; 2] {
        let (s, c) = self.angle.sin_cos();
        let (dx, dy) = (p[0] - self.origin[0], p[1] - self.origin[1]);
        [
            (dx * c - dy * s) / self.scale[0],
            (-dx * s - dy * c) / self.scale[1],
        ]
    }
}

/// Read a Tracker project's point-mass tracks.
pub(crate) fn read(bytes: &[u8], path: &Path) -> Result<Parsed, DataError> {
    let bad = |field: &str, expected: &str, found: String| {
        DataError::parse(path, "the project", field, expected, found)
    };
    if bytes.len() > MAX_TRK_BYTES {
        return Err(bad(
            "file",
            &format!("a Tracker project of at most {MAX_TRK_BYTES} bytes"),
            format!("{} bytes", bytes.len()),
        ));
    }
    let text = std::str::from_utf8(bytes).map_err(|e| bad("file", "UTF-8 XML", e.to_string()))?;
    super::xml_limits::check_attributes(text, path)?;
    let doc = Document::parse(text).map_err(|e| {
        DataError::parse(
            path,
            format!("line {}", e.pos().row),
            "XML",
            "a Tracker project (.trk)",
            e.to_string(),
        )
    })?;
    let root = doc.root_element();
    if !class(&root).ends_with("TrackerPanel") {
        return Err(bad(
            "root object",
            "org.opensourcephysics.cabrillo.tracker.TrackerPanel",
            format!("{:?}", root.attribute("class").unwrap_or("")),
        ));
    }
    let objects: Vec<Node> = root
        .descendants()
        .filter(|n| n.has_tag_name("object"))
        .collect();
    let (delta_t, start) = clip_timing(&objects);
    let coords = coord_frames(&objects);
    let unit = string(root, "length_unit");
    let (mut series, models) = point_masses(&objects, delta_t, start, &coords, &bad)?;
    if series.is_empty() {
        return Err(bad(
            "tracks",
            "a point-mass track with marked positions",
            if models.is_empty() {
                "no point-mass track".to_string()
            } else {
                format!(
                    "only model track(s) {}: a model stores formulas, not data; export the data from Tracker instead",
                    models.iter().map(|m| format!("{m:?}")).collect::<Vec<_>>().join(", ")
                )
            },
        ));
    }
    // Tracker stores frames in order; keep times strictly increasing regardless.
    for s in &mut series {
        sort_frames(s);
    }
    Ok(Parsed {
        series,
        scale: length_scale(unit.as_deref()),
        notes: vec![format!(
            "Tracker project: point-mass positions in world units through the project's coordinate system; t = frame x {} ms{}",
            delta_t.unwrap_or_default(),
            if models.is_empty() {
                String::new()
            } else {
                format!("; model track(s) {} skipped (formulas, not data)", models.join(", "))
            }
        )],
        ..Parsed::default()
    })
}

/// The clip's frame duration (`delta_t`, ms; `None` when missing or not positive) and its first
/// frame (`startframe`, 0 when missing).
fn clip_timing(objects: &[Node]) -> (Option<f64>, f64) {
    let delta_t = objects
        .iter()
        .filter(|o| class(o) == "StepperClipControl" || class(o).ends_with("ClipControl"))
        .find_map(|o| number(*o, "delta_t"))
        .filter(|d| d.is_finite() && *d > 0.0);
    let start = objects
        .iter()
        .find(|o| class(o) == "VideoClip")
        .and_then(|o| number(*o, "startframe"))
        .unwrap_or(0.0);
    (delta_t, start)
}

/// The coordinate system's frames: from each listed frame on, its image-to-world transform
/// (frames with a zero or non-finite scale are left out).
fn coord_frames(objects: &[Node]) -> Vec<(usize, Coords)> {
    objects
        .iter()
        .find(|o| class(o) == "ImageCoordSystem")
        .and_then(|o| property(*o, "framedata"))
        .map(|a| {
            indexed(a)
                .filter_map(|(n, f)| {
                    Some((
                        n,
                        Coords {
                            origin: [number(f, "xorigin")?, number(f, "yorigin")?],
                            angle: number(f, "angle").unwrap_or(0.0),
                            scale: [number(f, "xscale")?, number(f, "yscale")?],
                        },
                    ))
                })
                .filter(|(_, c)| c.scale.iter().all(|s| s.is_finite() && *s != 0.0))
                .collect()
        })
        .unwrap_or_default()
}

/// The point-mass tracks with marked positions, in world coordinates (through `coords`) and
/// seconds (frame from `start`, times `delta_t` ms), and the names of the model tracks skipped.
/// A point mass in a project without a frame duration is an error (`bad` makes it).
fn point_masses(
    objects: &[Node],
    delta_t: Option<f64>,
    start: f64,
    coords: &[(usize, Coords)],
    bad: &impl Fn(&str, &str, String) -> DataError,
) -> Result<(Vec<Series>, Vec<String>), DataError> {
    // The frames' coordinate systems are listed in file order, so the entry for frame n
    // (the last listed at or before n) is found from the suffix minima of the frame
    // numbers, which never decrease: a binary search instead of a scan per frame.
    let mut floor = vec![usize::MAX; coords.len()];
    for i in (0..coords.len()).rev() {
        floor[i] = coords[i]
            .0
            .min(floor.get(i + 1).copied().unwrap_or(usize::MAX));
    }
    let mut series = Vec::new();
    let mut models = Vec::new();
    for o in objects {
        let name = string(*o, "name").unwrap_or_else(|| "track".into());
        if MODELS.contains(&class(o)) {
            models.push(name);
            continue;
        }
        if class(o) != "PointMass" {
            continue;
        }
        let Some(dt) = delta_t else {
            return Err(bad(
                "delta_t",
                "the clip's frame duration (StepperClipControl delta_t, ms)",
                "none".into(),
            ));
        };
        let mut s = Series {
            name,
            ..Series::default()
        };
        let Some(frames) = property(*o, "framedata") else {
            continue;
        };
        for (n, f) in indexed(frames) {
            let (Some(x), Some(y)) = (number(f, "x"), number(f, "y")) else {
                continue;
            };
            // The coordinate system of this frame: its own entry, else the last before it.
            let c = match floor.partition_point(|&k| k <= n) {
                0 => coords.first(),
                i => coords.get(i - 1),
            };
            let p = match c {
                Some((_, c)) => c.world([x, y]),
                None => [x, -y],
            };
            s.times.push((n as f64 - start) * dt / 1000.0);
            s.points.push(Some(p));
        }
        if !s.times.is_empty() {
            series.push(s);
        }
    }
    Ok((series, models))
}

/// Sort a track's frames by time and keep the first of frames at the same time.
fn sort_frames(s: &mut Series) {
    let mut pairs: Vec<(f64, Option<[f64; 2]>)> = s
        .times
        .iter()
        .copied()
        .zip(s.points.iter().copied())
        .collect();
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
    pairs.dedup_by(|a, b| a.0 == b.0);
    s.times = pairs.iter().map(|p| p.0).collect();
    s.points = pairs.iter().map(|p| p.1).collect();
}

/// Metres per unit for the project's `length_unit` (m, cm, mm), with the wording for the
/// report; `None` for any other unit.
fn length_scale(unit: Option<&str>) -> Option<(f64, String)> {
    match unit {
        Some("m") => Some((1.0, "metres (the project's length_unit m)".to_string())),
        Some("cm") => Some((0.01, "centimetres (the project's length_unit)".to_string())),
        Some("mm") => Some((0.001, "millimetres (the project's length_unit)".to_string())),
        _ => None,
    }
}
