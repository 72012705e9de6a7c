//! Calibration into the rail frame: scale to metres, y up, the rail axis fitted from the
//! slider's own track, the origin, and the rod-length check that flags outlier frames.

use super::{Calibration, Geometry, ReadOptions, Recording};

/// The largest coordinate (metres) a calibrated recording may hold: far beyond any rig, small
/// enough that distances and their squares stay finite.
pub const MAX_METRES: f64 = 1e12;

/// How a [`Calibration::scale_source`] set from `--rod-length` begins: the scale is then a
/// ruler's reading, whose error the fit carries (`pipeline`'s scale prior).
pub const ROD_LENGTH_SCALE: &str = "from --rod-length";

/// Scale, flip and (with `opts.rail_frame`) rotate and shift a recording in file units into the
/// rail frame, then check the slider-bob distance. `file_scale` is the file's own metres per
/// unit, when it says. Errors are messages naming the flag that would fix them.
pub fn calibrate(
    rec: &mut Recording,
    file_scale: Option<(f64, String)>,
    file_y_down: bool,
    opts: &ReadOptions,
) -> Result<(), String> {
    let y_down = opts.y_down.unwrap_or(file_y_down);
    let (scale, source) = match (opts.scale, file_scale, opts.rod_length) {
        (Some(s), _, _) => (s, "--scale".to_string()),
        (None, Some((s, why)), _) => (s, why),
        (None, None, Some(l)) => {
            let mut d = distances(&rec.slider, &rec.bob);
            if d.is_empty() {
                return Err("no frame shows both markers, so --rod-length cannot set the scale: give --scale".into());
            }
            let m = median(&mut d);
            (
                l / m,
                format!(
                    "{ROD_LENGTH_SCALE} {l} m over a median of {} file units",
                    significant(m)
                ),
            )
        }
        (None, None, None) => {
            return Err("the file's positions have no units (pixels): give --scale METRES_PER_UNIT or --rod-length METRES".into())
        }
    };
    if !(scale.is_finite() && scale > 0.0) {
        return Err(format!(
            "the scale must be a finite number > 0, got {scale}"
        ));
    }
    let mut cal = Calibration {
        scale,
        scale_source: source,
        y_flipped: y_down,
        ..Calibration::default()
    };
    for p in rec.slider.iter_mut().chain(rec.bob.iter_mut()).flatten() {
        *p = cal.scaled(*p);
    }
    for (role, track) in [("slider", &rec.slider), ("bob", &rec.bob)] {
        if let Some((i, p)) = track.iter().enumerate().find_map(|(i, p)| {
            p.filter(|p| !p.iter().all(|v| v.abs() <= MAX_METRES))
                .map(|p| (i, p))
        }) {
            return Err(format!(
                "{role} position ({}, {}) m at t = {} s (frame {}, after scaling by {scale}): expected coordinates within +-{MAX_METRES:e} m",
                p[0], p[1], rec.times[i], i + 1
            ));
        }
    }
    if opts.rail_frame {
        let (angle, origin, rms) = fit_rail(rec)?;
        cal.rail_angle = Some(angle);
        cal.origin = Some(origin);
        cal.rail_rms = Some(rms);
        for p in rec.slider.iter_mut().chain(rec.bob.iter_mut()).flatten() {
            *p = cal.turned(*p);
        }
        rec.provenance.notes.push(format!(
            "rail axis fitted to {} slider positions: {:.4} deg from the file's x, rms off the line {:.3e} m",
            rec.slider.iter().flatten().count(),
            angle.to_degrees(),
            rms
        ));
    }
    rec.provenance.calibration = cal;
    rec.provenance.geometry = check_geometry(rec, opts.rod_length);
    if opts.drop_outliers {
        if let Some(g) = &rec.provenance.geometry {
            for &i in &g.outliers {
                rec.slider[i] = None;
                rec.bob[i] = None;
            }
            if !g.outliers.is_empty() {
                rec.provenance
                    .warnings
                    .push(format!("{} outlier frame(s) dropped", g.outliers.len()));
            }
        }
    }
    Ok(())
}

/// The calibration as a map between the file's units and the rail frame, both ways: one
/// formula for the readers ([`calibrate`]) and for what is written back in the file's units
/// (`fit --overlay FILE.csv`), so that the two cannot drift apart.
impl Calibration {
    /// The whole file units a metre holds, when the scale is their exact inverse (millimetres
    /// 1000, centimetres 100, or pixels at a whole number a metre): then dividing by it keeps
    /// decimal values exact where multiplying by 0.001 would not.
    fn whole_per_metre(&self) -> Option<f64> {
        let inv = (1.0 / self.scale).round();
        (inv > 1.0 && ((1.0 / self.scale) - inv).abs() < 1e-9 * inv).then_some(inv)
    }

    fn flip(&self) -> f64 {
        if self.y_flipped {
            -1.0
        } else {
            1.0
        }
    }

    /// A point in file units scaled to metres with y up (the first step of [`calibrate`]).
    pub fn scaled(&self, p: [f64; 2]) -> [f64; 2] {
        let flip = self.flip();
        match self.whole_per_metre() {
            Some(inv) => [p[0] / inv, flip * p[1] / inv],
            None => [p[0] * self.scale, flip * p[1] * self.scale],
        }
    }

    /// A scaled point (metres, y up) shifted to the rail's origin and turned onto its axis
    /// (the second step, with `--rail-frame`; the identity without it).
    pub fn turned(&self, p: [f64; 2]) -> [f64; 2] {
        let (Some(angle), Some(origin)) = (self.rail_angle, self.origin) else {
            return p;
        };
        let (s, c) = (-angle).sin_cos();
        let (dx, dy) = (p[0] - origin[0], p[1] - origin[1]);
        [c * dx - s * dy, s * dx + c * dy]
    }

    /// A point in file units in the rail frame (metres, x along the rail, y up): what the
    /// readers give.
    pub fn to_rail(&self, p: [f64; 2]) -> [f64; 2] {
        self.turned(self.scaled(p))
    }

    /// A rail-frame point (metres) back in the file's units and axes: the inverse of
    /// [`Calibration::to_rail`] (turned back, shifted back, y flipped back, unscaled), to
    /// rounding.
    pub fn to_file(&self, p: [f64; 2]) -> [f64; 2] {
        let q = match (self.rail_angle, self.origin) {
            (Some(angle), Some(origin)) => {
                let (s, c) = angle.sin_cos();
                [
                    c * p[0] - s * p[1] + origin[0],
                    s * p[0] + c * p[1] + origin[1],
                ]
            }
            _ => p,
        };
        let flip = self.flip();
        match self.whole_per_metre() {
            Some(inv) => [q[0] * inv, flip * q[1] * inv],
            None => [q[0] / self.scale, flip * q[1] / self.scale],
        }
    }
}

/// The rail line through the slider's positions (total least squares): its angle in
/// (-pi/2, pi/2], chosen with x reversed when that puts the bob below the rail; the origin is
/// the first slider position projected onto the line; and the rms distance off the line.
pub fn fit_rail(rec: &Recording) -> Result<(f64, [f64; 2], f64), String> {
    let pts: Vec<[f64; 2]> = rec.slider.iter().flatten().copied().collect();
    if pts.len() < 2 {
        return Err("the rail frame needs at least two slider positions".into());
    }
    let n = pts.len() as f64;
    let (mx, my) = pts
        .iter()
        .fold((0.0, 0.0), |(a, b), p| (a + p[0] / n, b + p[1] / n));
    let (mut sxx, mut syy, mut sxy) = (0.0, 0.0, 0.0);
    for p in &pts {
        let (dx, dy) = (p[0] - mx, p[1] - my);
        sxx += dx * dx;
        syy += dy * dy;
        sxy += dx * dy;
    }
    // Principal axis of the 2x2 covariance.
    let mut angle = 0.5 * (2.0 * sxy).atan2(sxx - syy);
    let spread = (sxx + syy).sqrt();
    if spread == 0.0 {
        return Err(
            "the slider never moves, so the rail axis cannot be fitted: drop --rail-frame".into(),
        );
    }
    // Put the bob below the rail (y up).
    let (s, c) = angle.sin_cos();
    let bob_side: f64 = rec
        .bob
        .iter()
        .flatten()
        .map(|b| -s * (b[0] - mx) + c * (b[1] - my))
        .sum();
    if bob_side > 0.0 {
        angle += std::f64::consts::PI;
    }
    let (s, c) = angle.sin_cos();
    let rms = (pts
        .iter()
        .map(|p| (-s * (p[0] - mx) + c * (p[1] - my)).powi(2))
        .sum::<f64>()
        / n)
        .sqrt();
    let p0 = pts[0];
    let along = c * (p0[0] - mx) + s * (p0[1] - my);
    let origin = [mx + along * c, my + along * s];
    Ok((angle, origin, rms))
}

/// The robust spread (1.4826 times the median absolute deviation, in the track's units) of a track's
/// positions across its own best straight line: the line through the coordinate-wise median
/// along the principal axis of the positions, found again from the positions within five
/// spreads of the first line (a few mis-tracked positions do not tilt it). `None` with fewer
/// than 10 positions.
pub fn off_line_spread(track: &[Option<[f64; 2]>]) -> Option<f64> {
    let mut pts: Vec<[f64; 2]> = Vec::with_capacity(track.len());
    pts.extend(track.iter().flatten());
    if pts.len() < 10 {
        return None;
    }
    // One scratch vector for every median (a million frames' track would otherwise page in
    // six more of its size); the distances across the line are taken again from the points
    // where they are needed, the same numbers.
    let mut scratch: Vec<f64> = Vec::with_capacity(pts.len());
    let mut median_of = |values: &mut dyn Iterator<Item = f64>| {
        scratch.clear();
        scratch.extend(values);
        median(&mut scratch)
    };
    let centre = [0, 1].map(|k| median_of(&mut pts.iter().map(|p| p[k])));
    let mut keep = vec![true; pts.len()];
    let mut spread = 0.0;
    for _ in 0..2 {
        let (mut sxx, mut syy, mut sxy) = (0.0, 0.0, 0.0);
        for (p, _) in pts.iter().zip(&keep).filter(|(_, k)| **k) {
            let (dx, dy) = (p[0] - centre[0], p[1] - centre[1]);
            sxx += dx * dx;
            syy += dy * dy;
            sxy += dx * dy;
        }
        let angle = 0.5 * (2.0 * sxy).atan2(sxx - syy);
        let (s, c) = angle.sin_cos();
        let across = |p: &[f64; 2]| -s * (p[0] - centre[0]) + c * (p[1] - centre[1]);
        let mid = median_of(&mut pts.iter().map(across));
        spread = 1.4826 * median_of(&mut pts.iter().map(|p| (across(p) - mid).abs()));
        for (k, p) in keep.iter_mut().zip(&pts) {
            *k = (across(p) - mid).abs() <= 5.0 * spread;
        }
    }
    Some(spread)
}

/// The slider-bob distance of every frame with both markers, in frame order.
fn distances(slider: &[Option<[f64; 2]>], bob: &[Option<[f64; 2]>]) -> Vec<f64> {
    slider
        .iter()
        .zip(bob)
        .filter_map(|(s, b)| {
            let (s, b) = (s.as_ref()?, b.as_ref()?);
            Some((b[0] - s[0]).hypot(b[1] - s[1]))
        })
        .collect()
}

/// The median of `v` (not empty), whose order it changes: the middle value (of the two middle
/// values, their mean) in `f64::total_cmp` order, found by selection rather than a sort.
pub(crate) fn median(v: &mut [f64]) -> f64 {
    let n = v.len();
    let (lower, mid, _) = v.select_nth_unstable_by(n / 2, f64::total_cmp);
    let mid = *mid;
    if n % 2 == 1 {
        mid
    } else {
        let below = lower
            .iter()
            .copied()
            .max_by(f64::total_cmp)
            .expect("an even count above zero has a lower half");
        0.5 * (below + mid)
    }
}

/// The slider-bob distance: median, standard deviation, and the frames farther from the
/// reference (`rod_length`, else the median) than five robust standard deviations (at least
/// 2 % of the length).
pub fn check_geometry(rec: &Recording, rod_length: Option<f64>) -> Option<Geometry> {
    geometry(&rec.slider, &rec.bob, rod_length)
}

/// [`check_geometry`] of two tracks of equal length (one entry per frame), in any unit.
pub fn geometry(
    slider: &[Option<[f64; 2]>],
    bob: &[Option<[f64; 2]>],
    rod_length: Option<f64>,
) -> Option<Geometry> {
    let vals = distances(slider, bob);
    if vals.is_empty() {
        return None;
    }
    let n = vals.len() as f64;
    // Sums in frame order, before the selections below reorder a copy.
    let mean = vals.iter().sum::<f64>() / n;
    let std = (vals.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n).sqrt();
    let mut work = vals.clone();
    let med = median(&mut work);
    let reference = rod_length.unwrap_or(med);
    for (w, v) in work.iter_mut().zip(&vals) {
        *w = (v - med).abs();
    }
    let mad = median(&mut work);
    drop(work);
    let spread = 1.4826 * mad;
    // A scatter wider than a rod allows does not widen the tolerance past 5 % (it did: a
    // distance scattering by 0.58 m on a 0.3 m rod left every frame within it).
    let tolerance = (5.0 * spread).clamp(0.02 * reference, 0.05 * reference);
    // Frames with both markers, in order, are the distances' frames.
    let both = slider
        .iter()
        .zip(bob)
        .enumerate()
        .filter(|(_, (s, b))| s.is_some() && b.is_some())
        .map(|(i, _)| i);
    let outliers = both
        .zip(&vals)
        .filter(|(_, v)| (*v - reference).abs() > tolerance)
        .map(|(i, _)| i)
        .collect();
    Some(Geometry {
        frames: vals.len(),
        median: med,
        std,
        reference,
        outliers,
        tolerance,
        spread,
        noise: distance_noise(slider, bob),
    })
}

/// The slider-bob distance's noise per frame (metres) from its third differences over runs of
/// four consecutive frames with both markers: for white noise of deviation s their variance is
/// 20 s^2, and the median of the squares over 0.4549 (the median of chi-square with one degree
/// of freedom) is robust to mis-tracked frames. 0 with no such run.
fn distance_noise(slider: &[Option<[f64; 2]>], bob: &[Option<[f64; 2]>]) -> f64 {
    let d: Vec<Option<f64>> = slider
        .iter()
        .zip(bob)
        .map(|(s, b)| {
            Some((b.as_ref()?[0] - s.as_ref()?[0]).hypot(b.as_ref()?[1] - s.as_ref()?[1]))
        })
        .collect();
    let mut third: Vec<f64> = d
        .windows(4)
        .filter_map(|w| Some((w[3]? - 3.0 * w[2]? + 3.0 * w[1]? - w[0]?).powi(2)))
        .collect();
    if third.is_empty() {
        return 0.0;
    }
    (median(&mut third) / 0.4549 / 20.0).sqrt()
}

/// `x` to seven significant digits, written as briefly as that allows (0.0006666666707 reads
/// 0.0006666667, 449.9999972682611 reads 450): a derived number carries no more.
pub fn significant(x: f64) -> String {
    let rounded: f64 = format!("{x:.6e}").parse().unwrap_or(x);
    format!("{rounded}")
}

#[cfg(test)]
mod tests {
    use super::median;
    use crate::data::{Calibration, ReadOptions, Recording};

    /// A pendulum's track in pixels, y down, on a camera rolled by 2 deg: the slider along a
    /// tilted line, the bob below it.
    fn pixels() -> Recording {
        let roll = 2f64.to_radians();
        let n = 50;
        let at = |x: f64, y: f64| {
            let (s, c) = roll.sin_cos();
            Some([600.0 + c * x - s * y, 300.0 + s * x + c * y])
        };
        Recording {
            times: (0..n).map(|i| i as f64 * 0.01).collect(),
            slider: (0..n).map(|i| at(i as f64, 0.0)).collect(),
            bob: (0..n)
                .map(|i| {
                    let a = 0.02 * i as f64;
                    at(i as f64 + 300.0 * a.sin(), 300.0 * a.cos())
                })
                .collect(),
            ..Recording::default()
        }
    }

    /// The calibration's two directions are one map and its inverse: what the reader made of a
    /// file's points is `to_rail` of them, and `to_file` gives the file's points back (to
    /// rounding), for pixels (y flipped, any scale) and millimetres (scale 1/1000, exact).
    #[test]
    fn to_file_inverts_what_the_reader_applied() {
        for (scale, y_down) in [(0.0008097282, true), (0.001, false), (1.0, false)] {
            let file = pixels();
            let mut rec = file.clone();
            let opts = ReadOptions {
                scale: Some(scale),
                rail_frame: true,
                ..ReadOptions::default()
            };
            super::calibrate(&mut rec, None, y_down, &opts).unwrap();
            let cal = &rec.provenance.calibration;
            assert!(cal.rail_angle.is_some());
            for (f, r) in file
                .slider
                .iter()
                .chain(&file.bob)
                .zip(rec.slider.iter().chain(&rec.bob))
            {
                let (f, r) = (f.unwrap(), r.unwrap());
                assert_eq!(cal.to_rail(f), r, "the reader's own map");
                let back = cal.to_file(r);
                for k in 0..2 {
                    assert!(
                        (back[k] - f[k]).abs() <= 1e-12 * f[k].abs().max(1.0),
                        "{scale}: {back:?} {f:?}"
                    );
                }
            }
        }
    }

    /// Pixels go the right way: in a y-down file the bob, below the rail, has the larger pixel
    /// y, and a rail-frame point lower down (y smaller) goes back to a larger pixel y; a point
    /// farther along the rail goes back farther along the file's rolled x.
    #[test]
    fn to_file_flips_y_back_down_and_turns_the_rail_back() {
        let mut rec = pixels();
        let opts = ReadOptions {
            scale: Some(0.001),
            rail_frame: true,
            ..ReadOptions::default()
        };
        super::calibrate(&mut rec, None, true, &opts).unwrap();
        let cal: &Calibration = &rec.provenance.calibration;
        // The bob hangs below the rail in the rail frame.
        assert!(rec.bob[0].unwrap()[1] < 0.0);
        let up = cal.to_file([0.0, 0.0]);
        let down = cal.to_file([0.0, -0.1]);
        assert!(down[1] > up[1], "{down:?} below {up:?} in pixels");
        let along = cal.to_file([0.1, 0.0]);
        // 100 px along the rail rolled by 2 deg: +99.94 px in x, +3.49 px in y (y down).
        let d = [along[0] - up[0], along[1] - up[1]];
        let roll = 2f64.to_radians();
        assert!((d[0] - 100.0 * roll.cos()).abs() < 1e-9, "{d:?}");
        assert!((d[1] - 100.0 * roll.sin()).abs() < 1e-9, "{d:?}");
    }

    /// The median by a full sort, as it was computed before selection.
    fn sorted_median(mut v: Vec<f64>) -> f64 {
        v.sort_by(f64::total_cmp);
        let n = v.len();
        if n % 2 == 1 {
            v[n / 2]
        } else {
            0.5 * (v[n / 2 - 1] + v[n / 2])
        }
    }

    #[test]
    fn selection_median_is_the_sorted_median_bit_for_bit() {
        let mut x = 0.3f64;
        for n in 1..200 {
            let v: Vec<f64> = (0..n)
                .map(|i| {
                    x = (x * 3.7 + 0.1).fract();
                    match i % 5 {
                        0 => 0.0,
                        1 => -0.0,
                        2 => (x * 8.0).floor(),
                        _ => x - 0.5,
                    }
                })
                .collect();
            let mut w = v.clone();
            assert_eq!(
                median(&mut w).to_bits(),
                sorted_median(v).to_bits(),
                "n = {n}"
            );
        }
    }
}
