//! Where each model holds: the critical friction mu*, its angle theta*, the paradox band where
//! the sliding equation has two solutions or none (docs/physics.md, "The Painlevé paradox"), and the
//! regions of both models in the (theta, theta') plane.
//!
//! At fixed theta the shorthands b, c and Q are quadratic in w (affine in w^2 without pivot
//! damping), so every boundary in the plane is a closed form: the roots of the stick boundary
//! |c| = mu_s |b| (two branches), of the curve Q = 0, and the band edges (lines of constant
//! theta where mu |a| = D). With tilt, the slide directions and the two sides of the plane
//! differ.

use super::{sign, FrictionLaw, Rig, Scalar, Shorthands};
use serde::Serialize;
use std::f64::consts::PI;

/// Critical friction mu* = 2 sqrt(r (1 + r)) for mass ratio r = m1 / m2: below it the sliding
/// equation has exactly one solution at every angle.
pub fn mu_critical(mass_ratio: f64) -> f64 {
    2.0 * (mass_ratio * (1.0 + mass_ratio)).sqrt()
}

/// The angle theta* in (0, pi/2) where the band opens first: tan^2(theta*) = (1 + r) / r.
pub fn theta_critical(mass_ratio: f64) -> f64 {
    ((1.0 + mass_ratio) / mass_ratio).sqrt().atan()
}

/// The paradox band in the first quadrant, (lo, hi) in radians, where mu |a| > D; `None` when
/// mu <= mu*. The band repeats in every quadrant (|tan theta| is what matters).
pub fn paradox_band(mass_ratio: f64, mu: f64) -> Option<(f64, f64)> {
    let r = mass_ratio;
    let disc = mu * mu - 4.0 * r * (1.0 + r);
    if disc <= 0.0 {
        return None;
    }
    let root = disc.sqrt();
    Some((
        ((mu - root) / (2.0 * r)).atan(),
        ((mu + root) / (2.0 * r)).atan(),
    ))
}

/// The largest mass ratio r = m1 / m2 at which friction `mu` exceeds mu*(r): the inverse of
/// [`mu_critical`], r = (sqrt(1 + mu^2) - 1) / 2.
pub fn max_mass_ratio_for_paradox(mu: f64) -> f64 {
    ((1.0 + mu * mu).sqrt() - 1.0) / 2.0
}

/// Paradox margins below this (relative to D) count as on the band edge, not inside it.
const EDGE_TOL: f64 = 1e-12;

/// The paradox band of `rig` within 0..180 degrees, as `[lo, hi]` pairs in degrees: the band
/// of the first quadrant and its mirror in the second, for the largest mu the friction law
/// reaches (mu_s under Stribeck). Empty when that mu <= mu*.
pub fn paradox_band_deg(rig: &Rig<f64>) -> Vec<[f64; 2]> {
    band_deg(rig.mass_ratio(), rig.mu_slide_max())
}

/// The band of friction `mu` at mass ratio `r` within 0..180 degrees, `[lo, hi]` pairs.
fn band_deg(r: f64, mu: f64) -> Vec<[f64; 2]> {
    paradox_band_intervals(r, mu, 0.0, PI)
        .into_iter()
        .map(|(lo, hi)| [lo.to_degrees(), hi.to_degrees()])
        .collect()
}

/// Every interval of theta in [theta_min, theta_max] where mu |a| > D: the first-quadrant band
/// (lo, hi) of [`paradox_band`] repeated as (k pi + lo, k pi + hi) and (k pi - hi, k pi - lo),
/// clipped to the range and sorted. Empty when mu <= mu*.
pub fn paradox_band_intervals(
    mass_ratio: f64,
    mu: f64,
    theta_min: f64,
    theta_max: f64,
) -> Vec<(f64, f64)> {
    let Some((lo, hi)) = paradox_band(mass_ratio, mu) else {
        return Vec::new();
    };
    let mut out = Vec::new();
    let k0 = (theta_min / PI).floor() as i64 - 1;
    let k1 = (theta_max / PI).ceil() as i64 + 1;
    for k in k0..=k1 {
        let base = k as f64 * PI;
        for (a, b) in [(base + lo, base + hi), (base - hi, base - lo)] {
            let (a, b) = (a.max(theta_min), b.min(theta_max));
            if a < b {
                out.push((a, b));
            }
        }
    }
    out.sort_by(|p, q| p.0.total_cmp(&q.0));
    out
}

/// The band edges (where mu |a| = D) inside [theta_min, theta_max], sorted: the vertical
/// lines of the region plots.
pub fn band_edges(mass_ratio: f64, mu: f64, theta_min: f64, theta_max: f64) -> Vec<f64> {
    let mut edges: Vec<f64> = paradox_band_intervals(mass_ratio, mu, theta_min, theta_max)
        .into_iter()
        .flat_map(|(a, b)| [a, b])
        .filter(|&t| t > theta_min && t < theta_max)
        .collect();
    edges.sort_by(f64::total_cmp);
    edges
}

/// The shorthands that depend on w, b, c and Q, as quadratics v0 + v1 w + v2 w^2 at a fixed
/// theta (v1 is zero without pivot damping: then they are affine in w^2). Built from three
/// evaluations of [`Shorthands`] (w = 0, 1, -1), so the formulas stay in one place; each is
/// exactly quadratic in w.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct QuadraticInW {
    /// (b0, b1, b2): the normal force while stuck.
    pub b: [f64; 3],
    /// (c0, c1, c2): minus the friction needed to stay stuck.
    pub c: [f64; 3],
    /// (Q0, Q1, Q2): the numerator of N while sliding (at x' = 0).
    pub q: [f64; 3],
}

impl QuadraticInW {
    /// The quadratic forms at angle `theta`.
    pub fn new(rig: &Rig<f64>, theta: f64) -> Self {
        let s0 = Shorthands::new(rig, theta, 0.0);
        let sp = Shorthands::new(rig, theta, 1.0);
        let sm = Shorthands::new(rig, theta, -1.0);
        let fit = |f0: f64, fp: f64, fm: f64| [f0, 0.5 * (fp - fm), 0.5 * (fp + fm) - f0];
        QuadraticInW {
            b: fit(s0.b, sp.b, sm.b),
            c: fit(s0.c, sp.c, sm.c),
            q: fit(s0.q, sp.q, sm.q),
        }
    }
}

/// Evaluate v0 + v1 w + v2 w^2.
fn eval(v: [f64; 3], w: f64) -> f64 {
    v[0] + w * (v[1] + w * v[2])
}

/// The real roots of v0 + v1 w + v2 w^2, ascending (none, one or two; a degenerate quadratic
/// is solved as a line). The stable form of the quadratic formula: no cancellation.
fn real_roots(v: [f64; 3]) -> Vec<f64> {
    let [v0, v1, v2] = v;
    let mut roots = if v2 == 0.0 {
        if v1 == 0.0 {
            Vec::new()
        } else {
            vec![-v0 / v1]
        }
    } else {
        let disc = v1 * v1 - 4.0 * v2 * v0;
        if disc < 0.0 {
            Vec::new()
        } else {
            let q = -0.5 * (v1 + sign(v1) * disc.sqrt());
            if q == 0.0 {
                vec![0.0]
            } else {
                vec![q / v2, v0 / q]
            }
        }
    };
    roots.retain(|r| r.is_finite());
    roots.sort_by(f64::total_cmp);
    roots
}

/// The stick boundary branch c = `branch` * mu_s * b (`branch` = +1 or -1) at angle `theta`:
/// the values of w on it, ascending (the two roots of a quadratic in w; +-sqrt(u(theta)) on an
/// undamped rig). Empty where the branch does not cross this theta.
///
/// ```
/// use appell::model::{regions::stick_boundary_w, Rig, Shorthands};
/// let rig = Rig::paper(0.35);
/// let theta = 50f64.to_radians();
/// let w = stick_boundary_w(&rig, theta, -1.0);
/// assert_eq!(w.len(), 2);
/// let sh = Shorthands::new(&rig, theta, w[1]);
/// assert!((sh.c.abs() - 0.35 * sh.b.abs()).abs() < 1e-12);
/// ```
pub fn stick_boundary_w(rig: &Rig<f64>, theta: f64, branch: f64) -> Vec<f64> {
    let f = QuadraticInW::new(rig, theta);
    match rig.friction_law {
        FrictionLaw::Coulomb | FrictionLaw::Stribeck => {
            let mu = branch * rig.mu_static;
            real_roots(std::array::from_fn(|i| f.c[i] - mu * f.b[i]))
        }
        FrictionLaw::Direction => {
            // Each direction's coefficient holds where the slider would slip that way
            // (sign(c) = s): the roots of each quadratic on its own side.
            let mut roots = Vec::new();
            for s in [1.0, -1.0] {
                let mu = branch * rig.static_mu(s);
                let side = real_roots(std::array::from_fn(|i| f.c[i] - mu * f.b[i]));
                roots.extend(side.into_iter().filter(|&w| sign(eval(f.c, w)) == s));
            }
            roots.sort_by(f64::total_cmp);
            roots
        }
        FrictionLaw::Load => load_stick_boundary_w(rig, &f, branch),
    }
}

/// [`stick_boundary_w`] under the load law, c = branch mu_s |b| (|b| / N_0)^(n - 1) sign(b),
/// which is no quadratic: its sign changes on a grid of w out to twice the largest root of
/// Coulomb's boundary (or a swing of 8 sqrt(g / l)), each refined by bisection.
fn load_stick_boundary_w(rig: &Rig<f64>, f: &QuadraticInW, branch: f64) -> Vec<f64> {
    let coulomb = real_roots(std::array::from_fn(|i| {
        f.c[i] - branch * rig.mu_static * f.b[i]
    }));
    let reach = 8.0 * (rig.gravity / rig.rod_length).sqrt();
    let w_max = coulomb.iter().fold(reach, |m, w| m.max(2.0 * w.abs()));
    let n0 = rig.static_load();
    let g = |w: f64| {
        let b = eval(f.b, w);
        let held = rig.mu_static * b * (b.abs() / n0).powf(rig.load_exponent - 1.0);
        eval(f.c, w) - branch * held
    };
    let n = 512;
    let mut roots = Vec::new();
    let (mut w0, mut g0) = (-w_max, g(-w_max));
    for k in 1..=n {
        let w1 = -w_max + 2.0 * w_max * k as f64 / n as f64;
        let g1 = g(w1);
        if g0 == 0.0 {
            roots.push(w0);
        } else if g0 * g1 < 0.0 {
            let (mut a, mut b, mut ga) = (w0, w1, g0);
            for _ in 0..80 {
                let m = 0.5 * (a + b);
                let gm = g(m);
                if gm * ga <= 0.0 {
                    b = m;
                } else {
                    a = m;
                    ga = gm;
                }
            }
            roots.push(0.5 * (a + b));
        }
        (w0, g0) = (w1, g1);
    }
    roots
}

/// The curve Q = 0 at angle `theta`: the w where the rail reaction of a slide changes sign
/// (w^2 = -(m1 + m2) g_y / (m2 l sin(theta)) without damping); none with the bob below the
/// rail on an undamped rig.
pub fn q_zero_w(rig: &Rig<f64>, theta: f64) -> Vec<f64> {
    let mut roots = real_roots(QuadraticInW::new(rig, theta).q);
    roots.retain(|&w| w != 0.0);
    roots
}

/// Whether the pendulum (stick) model holds at (theta, w): |c| <= mu_s |b|.
pub fn in_stick_region(rig: &Rig<f64>, theta: f64, w: f64) -> bool {
    rig.stick_margin(&Shorthands::new(rig, theta, w)) >= 0.0
}

/// Whether (theta, w) lies strictly inside the paradox band, mu |a| > D, with the largest mu
/// the friction law reaches.
pub fn in_paradox_band(rig: &Rig<f64>, theta: f64) -> bool {
    let sh = Shorthands::new(rig, theta, 0.0);
    sh.band_margin(rig.mu_slide_max()) < -EDGE_TOL * sh.d
}

/// Number of solutions (0, 1 or 2) of the sliding equation at (theta, w) sliding in
/// direction `s` (+1 or -1) as x' -> 0 (friction mu(0)), by the sign rule of docs/physics.md: one
/// outside the paradox band; inside it two when sign(Q) = sign(s a) and none when the signs
/// are opposite. On the curves themselves (band edge, Q = 0) the count is the limit from the
/// side where the margin is positive (band edge: one) or where Q > 0 (Q = 0, with
/// [`super::sign`]'s zero-is-plus).
///
/// ```
/// use appell::model::{regions::slide_solution_count, Rig};
/// // A light slider under a heavy bob at mu = 0.6 > mu* = 0.458, at rest at 75 deg (inside
/// // the band, bob below the rail so Q < 0, a > 0): sliding toward +x has no solution,
/// // toward -x two; at 30 deg (outside the band) exactly one either way.
/// let rig = Rig::new(0.01, 0.2, 0.3, 9.81, 0.6, None).unwrap();
/// let t = 75f64.to_radians();
/// assert_eq!(slide_solution_count(&rig, t, 0.0, 1.0), 0);
/// assert_eq!(slide_solution_count(&rig, t, 0.0, -1.0), 2);
/// assert_eq!(slide_solution_count(&rig, 30f64.to_radians(), 0.0, 1.0), 1);
/// ```
pub fn slide_solution_count(rig: &Rig<f64>, theta: f64, w: f64, s: f64) -> usize {
    let sh = Shorthands::new(rig, theta, w);
    if sh.band_margin(rig.friction_mu(s, 0.0)) >= -EDGE_TOL * sh.d {
        1
    } else if sign(sh.q) == sign(s * sh.a) {
        2
    } else {
        0
    }
}

/// Split [-w_max, w_max] at the given breakpoints and return the pieces with the value of
/// `classify` at each piece's midpoint, merging neighbours of equal value.
fn pieces_in_w<V: PartialEq + Copy>(
    w_max: f64,
    breaks: impl IntoIterator<Item = f64>,
    classify: impl Fn(f64) -> V,
) -> Vec<(f64, f64, V)> {
    let mut cuts: Vec<f64> = breaks
        .into_iter()
        .filter(|&w| w > -w_max && w < w_max)
        .collect();
    cuts.push(-w_max);
    cuts.push(w_max);
    cuts.sort_by(f64::total_cmp);
    cuts.dedup();
    let mut out: Vec<(f64, f64, V)> = Vec::new();
    for pair in cuts.windows(2) {
        let v = classify(0.5 * (pair[0] + pair[1]));
        match out.last_mut() {
            Some(last) if last.2 == v => last.1 = pair[1],
            _ => out.push((pair[0], pair[1], v)),
        }
    }
    out
}

/// The intervals of w in [-w_max, w_max] where the pendulum model holds at angle `theta`
/// (|c| <= mu_s |b|), exact: the margin is piecewise quadratic in w with kinks where b or c
/// vanish and zeros on the two boundary branches.
pub fn stick_intervals(rig: &Rig<f64>, theta: f64, w_max: f64) -> Vec<(f64, f64)> {
    let f = QuadraticInW::new(rig, theta);
    let mut breaks = stick_boundary_w(rig, theta, 1.0);
    breaks.extend(stick_boundary_w(rig, theta, -1.0));
    breaks.extend(real_roots(f.b));
    breaks.extend(real_roots(f.c));
    let pieces = pieces_in_w(w_max, breaks, |w| in_stick_region(rig, theta, w));
    pieces
        .into_iter()
        .filter(|p| p.2)
        .map(|(lo, hi, _)| (lo, hi))
        .collect()
}

/// The intervals of w in [-w_max, w_max] at angle `theta` with their number of sliding
/// solutions in direction `s` ([`slide_solution_count`]): the count changes only across the
/// curve Q = 0 (and across band edges, which are lines of constant theta).
pub fn slide_count_intervals(
    rig: &Rig<f64>,
    theta: f64,
    s: f64,
    w_max: f64,
) -> Vec<(f64, f64, usize)> {
    pieces_in_w(w_max, q_zero_w(rig, theta), |w| {
        slide_solution_count(rig, theta, w, s)
    })
}

/// A window of the (theta, theta') plane for region maps: theta range (rad), |theta'| up to
/// `w_max` (rad/s), and the number of theta samples along each curve.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PlaneWindow {
    /// Smallest theta (rad).
    pub theta_min: f64,
    /// Largest theta (rad).
    pub theta_max: f64,
    /// Largest |theta'| shown (rad/s).
    pub w_max: f64,
    /// Theta samples per curve.
    pub samples: usize,
}

impl PlaneWindow {
    /// The default window for a rig: theta in [0, 2 pi] (bob below the rail in the first half,
    /// above it in the second), |theta'| up to 3 sqrt(g / l), 721 samples (every half degree).
    pub fn for_rig(rig: &Rig<f64>) -> Self {
        PlaneWindow {
            theta_min: 0.0,
            theta_max: 2.0 * PI,
            w_max: 3.0 * (rig.gravity / rig.rod_length).sqrt(),
            samples: 721,
        }
    }

    /// The theta samples, evenly spaced including both ends.
    pub fn thetas(&self) -> impl Iterator<Item = f64> + '_ {
        let n = self.samples.max(2);
        (0..n).map(move |i| {
            self.theta_min + (self.theta_max - self.theta_min) * i as f64 / (n - 1) as f64
        })
    }

    /// Wrap an angle into [theta_min, theta_min + 2 pi).
    pub fn wrap(&self, theta: f64) -> f64 {
        self.theta_min + (theta - self.theta_min).rem_euclid(2.0 * PI)
    }
}

/// A curve in the (theta, theta') plane: a label and its points `[theta, theta']` (rad, rad/s).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Curve {
    /// What the curve is, e.g. `c = +mu_s b, w > 0`.
    pub label: String,
    /// Points `[theta, theta']`, ordered by theta.
    pub points: Vec<[f64; 2]>,
}

/// Trace w = `w_of(theta)` over the window, split into pieces where it exists and
/// |w| <= w_max; each piece's ends are refined by bisection onto the edge where it stops.
fn trace(window: &PlaneWindow, label: &str, w_of: impl Fn(f64) -> Option<f64>) -> Vec<Curve> {
    let valid = |t: f64| w_of(t).filter(|&v| v.abs() <= window.w_max);
    // The last valid theta between a valid `good` and an invalid `bad`.
    let edge = |mut good: f64, mut bad: f64| {
        for _ in 0..60 {
            let mid = 0.5 * (good + bad);
            if valid(mid).is_some() {
                good = mid;
            } else {
                bad = mid;
            }
        }
        good
    };
    let mut curves = Vec::new();
    let mut current: Vec<[f64; 2]> = Vec::new();
    let mut prev: Option<(f64, bool)> = None;
    for t in window.thetas() {
        let v = valid(t);
        match (prev, v) {
            (Some((tp, false)), Some(_)) => {
                let te = edge(t, tp);
                current.push([te, valid(te).unwrap_or(0.0)]);
            }
            (Some((tp, true)), None) => {
                let te = edge(tp, t);
                current.push([te, valid(te).unwrap_or(0.0)]);
                curves.push(Curve {
                    label: label.to_owned(),
                    points: std::mem::take(&mut current),
                });
            }
            _ => {}
        }
        if let Some(v) = v {
            current.push([t, v]);
        }
        prev = Some((t, v.is_some()));
    }
    if !current.is_empty() {
        curves.push(Curve {
            label: label.to_owned(),
            points: current,
        });
    }
    curves.retain(|c| c.points.len() >= 2);
    curves
}

/// The larger (`upper`) or smaller root of a quadratic's roots, where it has two (a single
/// root of a degenerate one counts as either).
fn pick(roots: &[f64], upper: bool) -> Option<f64> {
    if upper {
        roots.last().copied()
    } else {
        roots.first().copied()
    }
}

/// The boundary |c| = mu_s |b| of the pendulum model's region within the window: both
/// branches c = +mu_s b and c = -mu_s b, each with its upper root (w > 0 on an undamped rig)
/// and its lower root (w < 0), as continuous pieces.
pub fn stick_boundary(rig: &Rig<f64>, window: &PlaneWindow) -> Vec<Curve> {
    let mut out = Vec::new();
    for (branch, name) in [(1.0, "+"), (-1.0, "-")] {
        for (upper, wname) in [(true, "w > 0"), (false, "w < 0")] {
            let label = format!("c = {name}mu_s b, {wname}");
            out.extend(trace(window, &label, |t| {
                pick(&stick_boundary_w(rig, t, branch), upper)
            }));
        }
    }
    out
}

/// The curve Q = 0 (m2 l w^2 sin(theta) = -(m1 + m2) g on a level undamped rig) within the
/// window, upper and lower root: where the rail reaction of a slide changes sign.
pub fn q_zero_curve(rig: &Rig<f64>, window: &PlaneWindow) -> Vec<Curve> {
    let mut out = Vec::new();
    for (upper, wname) in [(true, "w > 0"), (false, "w < 0")] {
        out.extend(trace(window, &format!("Q = 0, {wname}"), |t| {
            pick(&q_zero_w(rig, t), upper)
        }));
    }
    out
}

/// The numbers that say whether and where a rig meets the Painleve paradox.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RegionSummary {
    /// Mass ratio r = m1 / m2 of the point rig the dynamics use: for a rigid pendulum the
    /// equivalent r' = (m1 + m_p - m_e) / m_e (docs/physics.md, "The rigid pendulum").
    pub mass_ratio: f64,
    /// The rig's kinetic friction (the sliding model's mu).
    pub mu_kinetic: f64,
    /// The rig's static friction (the stick region's mu).
    pub mu_static: f64,
    /// mu* = 2 sqrt(r (1 + r)).
    pub mu_critical: f64,
    /// theta* (degrees), where the band opens first.
    pub theta_critical_deg: f64,
    /// The paradox band within 0..180 degrees, `[lo, hi]` pairs; empty below mu*.
    pub paradox_band_deg: Vec<[f64; 2]>,
    /// The largest m1 / m2 at which the rig's mu_k exceeds mu*.
    pub max_mass_ratio_for_paradox: f64,
    /// For a rigid pendulum whose mu* differs from the point rig's with the same masses: that
    /// point rig's mu* (r = m1 / m_p, everything that swings at the bob), for comparison.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub point_rig_mu_critical: Option<f64>,
    /// The rail's friction law (docs/physics.md, "Friction laws").
    pub friction_law: &'static str,
    /// Under the direction law: each direction's coefficients and paradox band (a slide toward
    /// +x meets the band of mu_k+, one toward -x that of mu_k-).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub by_direction: Vec<DirectionBand>,
}

/// One sliding direction's friction and paradox band under the direction law.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DirectionBand {
    /// `+x` or `-x`.
    pub direction: &'static str,
    /// The kinetic coefficient sliding that way.
    pub mu_kinetic: f64,
    /// The static coefficient holding a slider about to slip that way.
    pub mu_static: f64,
    /// The band within 0..180 degrees for slides that way; empty when its mu <= mu*.
    pub paradox_band_deg: Vec<[f64; 2]>,
}

impl RegionSummary {
    /// The summary of `rig`.
    pub fn of(rig: &Rig<f64>) -> Self {
        let r = rig.mass_ratio();
        RegionSummary {
            mass_ratio: r,
            mu_kinetic: rig.mu_kinetic,
            mu_static: rig.mu_static,
            mu_critical: mu_critical(r),
            theta_critical_deg: theta_critical(r).to_degrees(),
            paradox_band_deg: paradox_band_deg(rig),
            max_mass_ratio_for_paradox: max_mass_ratio_for_paradox(rig.mu_slide_max()),
            point_rig_mu_critical: rig
                .pendulum
                .map(|p| mu_critical(p.point_mass_ratio()))
                .filter(|&m| m != mu_critical(r)),
            friction_law: rig.friction_law.name(),
            by_direction: if rig.friction_law == FrictionLaw::Direction {
                [("+x", 1.0), ("-x", -1.0)]
                    .into_iter()
                    .map(|(direction, s)| DirectionBand {
                        direction,
                        mu_kinetic: rig.mu_slide_max_toward(s),
                        mu_static: rig.static_mu(s),
                        paradox_band_deg: band_deg(r, rig.mu_slide_max_toward(s)),
                    })
                    .collect()
            } else {
                Vec::new()
            },
        }
    }

    /// Whether the rig's kinetic friction exceeds mu* (the band is not empty).
    pub fn paradox_possible(&self) -> bool {
        !self.paradox_band_deg.is_empty()
    }
}

/// The normal loads a swing meets in `window` with the bob below the rail (theta in 0..180
/// degrees, |theta'| up to the window's `w_max`): the least and the largest |b|, the stuck
/// pendulum's normal force, over a grid of the half plane (every half degree, 121 values of
/// theta'). On a level undamped rig these are m1 g (the rod along the rail, at rest) and
/// (m1 + m2) g + m2 l w_max^2 (hanging, at the window's fastest swing). With the bob above the
/// rail |N| falls to zero on the curve Q = 0, where no coefficient of the load law is bounded.
pub fn swing_loads(rig: &Rig<f64>, window: &PlaneWindow) -> [f64; 2] {
    let (nt, nw) = (361, 121);
    let mut lo = f64::INFINITY;
    let mut hi = 0.0f64;
    for i in 0..nt {
        let theta = PI * i as f64 / (nt - 1) as f64;
        for j in 0..nw {
            let w = window.w_max * (2.0 * j as f64 / (nw - 1) as f64 - 1.0);
            let b = Shorthands::new(rig, theta, w).b.abs();
            lo = lo.min(b);
            hi = hi.max(b);
        }
    }
    [lo, hi]
}

/// One coefficient of the rig's friction law and the paradox band it opens: each direction's
/// under the direction law, at rest and sliding fast under Stribeck's, at the smallest, the
/// static and the largest load a swing meets under the load law ([`swing_loads`]), the one
/// coefficient under Coulomb's.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LawBand {
    /// Which coefficient: `coulomb`, `+x`, `-x`, `at rest`, `sliding fast`, `smallest load`,
    /// `static load`, `largest load`.
    pub label: &'static str,
    /// The slide direction it applies to (`+x` or `-x`), or `None` for both.
    pub direction: Option<&'static str>,
    /// The sliding coefficient mu.
    pub mu: f64,
    /// The normal load |N| it is taken at (N), under the load law.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub normal_load: Option<f64>,
    /// Its band within 0..180 degrees, `[lo, hi]` pairs (mu |a| > D); empty when mu <= mu*.
    pub paradox_band_deg: Vec<[f64; 2]>,
}

impl LawBand {
    /// Whether it applies to slides in direction `s` (+1 or -1).
    pub fn applies_to(&self, s: f64) -> bool {
        match self.direction {
            Some(d) => (d == "+x") == (s > 0.0),
            None => true,
        }
    }
}

/// The paradox bands of `rig`'s friction law, one per coefficient it has ([`LawBand`]), the
/// load law's at the loads of `window` ([`swing_loads`]). Every coefficient comes from the
/// model's friction functions; every band from [`paradox_band`].
pub fn law_bands(rig: &Rig<f64>, window: &PlaneWindow) -> Vec<LawBand> {
    let r = rig.mass_ratio();
    let band = |label, direction, mu: f64, normal_load| LawBand {
        label,
        direction,
        mu,
        normal_load,
        paradox_band_deg: band_deg(r, mu),
    };
    match rig.friction_law {
        FrictionLaw::Coulomb => vec![band("coulomb", None, rig.friction_mu(1.0, 0.0), None)],
        FrictionLaw::Direction => vec![
            band("+x", Some("+x"), rig.friction_mu(1.0, 0.0), None),
            band("-x", Some("-x"), rig.friction_mu(-1.0, 0.0), None),
        ],
        FrictionLaw::Stribeck => vec![
            band("at rest", None, rig.friction_mu(1.0, 0.0), None),
            band(
                "sliding fast",
                None,
                rig.friction_mu(1.0, f64::INFINITY),
                None,
            ),
        ],
        FrictionLaw::Load => {
            let [lo, hi] = swing_loads(rig, window);
            let n0 = rig.static_load();
            [
                ("smallest load", lo),
                ("static load", n0),
                ("largest load", hi),
            ]
            .into_iter()
            .map(|(label, n)| band(label, None, rig.load_coefficient(n), Some(n)))
            .collect()
        }
    }
}

/// Everything a region plot shows, as data: the summary, the window, the stick boundary, the
/// curve Q = 0 and the band edges (theta, rad) inside the window.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RegionMap {
    /// mu*, theta*, the band, the largest mass ratio.
    pub summary: RegionSummary,
    /// The plane window the curves were traced in.
    pub window: PlaneWindow,
    /// Pieces of |c| = mu_s |b|.
    pub stick_boundary: Vec<Curve>,
    /// Pieces of Q = 0.
    pub q_zero: Vec<Curve>,
    /// Band edges inside the window (rad), where mu_k |a| = D.
    pub band_edges: Vec<f64>,
    /// The bands of each coefficient of the friction law ([`law_bands`]).
    pub law_bands: Vec<LawBand>,
}

impl RegionMap {
    /// The region map of `rig` in `window`.
    pub fn new(rig: &Rig<f64>, window: &PlaneWindow) -> Self {
        RegionMap {
            summary: RegionSummary::of(rig),
            window: *window,
            stick_boundary: stick_boundary(rig, window),
            q_zero: q_zero_curve(rig, window),
            band_edges: band_edges(
                rig.mass_ratio(),
                rig.mu_slide_max(),
                window.theta_min,
                window.theta_max,
            ),
            law_bands: law_bands(rig, window),
        }
    }
}

/// The stuck pendulum's energy level w^2 - 2 (g/l) sin(theta) at (theta, w): constant while
/// the slider is held on a level, undamped rig (2 E / (m2 l^2) of [`super::forces::energy`]
/// with the slider at rest), and falling under any friction or damping.
pub fn stuck_level(rig: &Rig<f64>, theta: f64, w: f64) -> f64 {
    w * w - 2.0 * rig.gravity / rig.rod_length * theta.sine()
}

/// The friction ratio |c|/|b| a stuck slider needs at angle `th` on energy level `level`, the
/// pendulum moving with w >= 0 (the ratio is even in w without damping); 0 where the level
/// does not reach `th`.
fn level_ratio(rig: &Rig<f64>, level: f64, th: f64) -> f64 {
    let w2 = level + 2.0 * rig.gravity / rig.rod_length * th.sine();
    if w2 < 0.0 {
        return 0.0;
    }
    Shorthands::new(rig, th, w2.sqrt()).pull()
}

/// The largest friction ratio along one energy level: a scan of 2048 angles and a
/// golden-section refinement of the largest. Returns as soon as a coarse pass of 64 angles
/// reaches `enough` (a stick-slip run finds its slip angle within a few evaluations).
fn level_peak_ratio(rig: &Rig<f64>, level: f64, enough: f64) -> f64 {
    let ratio = |th: f64| level_ratio(rig, level, th);
    // The turning points first, exactly: on a small swing the pull peaks there, at the edge
    // of the reachable angles, where a grid lands only beside it (a light slider's 10 degree
    // swing pulls 1.6 % more at its turning point than at the nearest of 2048 angles).
    let sin_turn = -level * rig.rod_length / (2.0 * rig.gravity);
    let turning = if sin_turn.abs() <= 1.0 {
        let th = sin_turn.asin();
        [th, PI - th]
            .map(|th| Shorthands::new(rig, th, 0.0).pull())
            .into_iter()
            .fold(0.0, f64::max)
    } else {
        0.0
    };
    if turning >= enough || turning.is_nan() {
        return turning;
    }
    let coarse = 64;
    if let Some(r) = (0..coarse)
        .map(|k| ratio(k as f64 * std::f64::consts::TAU / coarse as f64))
        .find(|r| *r >= enough || r.is_nan())
    {
        return r;
    }
    let n = 2048;
    let step = std::f64::consts::TAU / n as f64;
    let (k_max, r_max) = (0..n)
        .map(|k| (k, ratio(k as f64 * step)))
        .fold(
            (0, 0.0),
            |a, b| if b.1 > a.1 || b.1.is_nan() { b } else { a },
        );
    if r_max.is_nan() || r_max >= enough {
        return r_max;
    }
    // Refine the largest ratio between its grid neighbours.
    let (mut a, mut b) = ((k_max as f64 - 1.0) * step, (k_max as f64 + 1.0) * step);
    let gr = (5f64.sqrt() - 1.0) / 2.0;
    for _ in 0..60 {
        let (c, d) = (b - gr * (b - a), a + gr * (b - a));
        if ratio(c) > ratio(d) {
            b = d;
        } else {
            a = c;
        }
    }
    ratio(0.5 * (a + b)).max(r_max).max(turning)
}

/// Whether a stuck pendulum at (theta, w) can never slip: along its whole energy level
/// ([`stuck_level`], every angle it can reach) the needed friction ratio |c|/|b| stays below
/// mu_s. Then the stick phase lasts for ever and the simulator need not watch for slip. A
/// dense scan of the level and a golden-section refinement of its largest ratio, with a
/// relative margin of 1e-6: a level that comes closer than that is not proven.
pub fn stick_holds_forever(rig: &Rig<f64>, theta: f64, w: f64) -> bool {
    // The energy level is the conservative, level pendulum's: nothing is proven for a tilted
    // or damped rig.
    if !rig.is_ideal() {
        return false;
    }
    let peak = level_peak_ratio(rig, stuck_level(rig, theta, w), rig.mu_static);
    peak.is_finite() && peak * (1.0 + 1e-6) < rig.mu_static
}

/// The largest pull of the pendulum on a stuck slider, |c|/|b| (the friction coefficient the
/// slider needs to stay put), at any state whose energy level ([`stuck_level`]) is at most
/// `level`: no stuck slider on such a level slips, and none at rest starts to, under any law
/// whose coefficient at rest is above it. Infinite when the normal force can vanish.
///
/// Friction and damping only lower the level, so the level of the most energetic release a
/// box allows bounds every stick phase that follows it. `None` on a tilted rail (the level
/// then depends on where the slider sticks) or a damped pivot (the ratio is then no function
/// of w^2 alone).
///
/// Why two curves suffice: at a fixed angle b and c are affine in w^2, so |c|/|b| is monotone
/// in w^2 between the turning points (w = 0) and the top level, unless b changes sign in
/// between (then the ratio is unbounded).
pub fn largest_stuck_pull(rig: &Rig<f64>, level: f64) -> Option<f64> {
    if !rig.rail_tilt.is_exact_zero() || !rig.pivot_damping.is_exact_zero() {
        return None;
    }
    let top = level_peak_ratio(rig, level, f64::INFINITY);
    let n = 2048;
    let g_l = rig.gravity / rig.rod_length;
    let mut peak = top;
    for k in 0..n {
        let th = k as f64 * std::f64::consts::TAU / n as f64;
        let w2 = level + 2.0 * g_l * th.sine();
        if w2 < 0.0 {
            continue; // no level up to `level` reaches this angle
        }
        let rest = Shorthands::new(rig, th, 0.0);
        let fast = Shorthands::new(rig, th, w2.sqrt());
        if rest.b.signum() != fast.b.signum() || rest.b == 0.0 {
            return Some(f64::INFINITY);
        }
        // The turning points: a level below `level` whose bob is at rest here.
        peak = peak.max(rest.pull());
    }
    Some(peak)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The pull |F| / N a stuck slider feels along the exact pendulum released from rest at
    /// `amplitude` (model::pendulum's closed form), from Newton's law for the whole rig: the
    /// rail's friction F = m2 x_bob'' and normal force N = (m1 + m2) g + m2 y_bob'' (y up),
    /// the bob's accelerations by central differences. No shorthand is used.
    fn newton_pull(rig: &Rig<f64>, amplitude: f64) -> f64 {
        use crate::model::pendulum::{stuck_pendulum, stuck_period};
        let (m1, m2, l, g) = (rig.slider_mass, rig.bob_mass, rig.rod_length, rig.gravity);
        let bob = |t: f64| {
            let th = stuck_pendulum(rig, amplitude, t)[1];
            [l * th.cos(), -l * th.sin()]
        };
        let (h, period) = (1e-4, stuck_period(rig, amplitude));
        (0..4000)
            .map(|k| {
                let t = period * k as f64 / 4000.0;
                let (a, b, c) = (bob(t - h), bob(t), bob(t + h));
                let acc = |i: usize| (a[i] - 2.0 * b[i] + c[i]) / (h * h);
                (m2 * acc(0)).abs() / ((m1 + m2) * g + m2 * acc(1)).abs()
            })
            .fold(0.0, f64::max)
    }

    /// The largest pull over the levels up to a release's own is the pull the exact swing
    /// reaches (1e-5 relative, the differences' and the time grid's error), on the light, equal
    /// and heavy rigs of the law sweeps at small and large amplitudes; and a level a little
    /// lower never pulls more.
    #[test]
    fn the_largest_stuck_pull_is_what_the_exact_swing_reaches() {
        for m1 in [0.03, 0.1, 0.3] {
            let rig = Rig::new(m1, 0.1, 0.3, 9.81, 0.2, None).unwrap();
            for deg in [10.0, 40.0, 75.0, 120.0] {
                let amp = f64::to_radians(deg);
                let level = stuck_level(&rig, std::f64::consts::FRAC_PI_2 - amp, 0.0);
                let bound = largest_stuck_pull(&rig, level).unwrap();
                let swing = newton_pull(&rig, amp);
                assert!(
                    (bound - swing).abs() <= 1e-5 * swing,
                    "m1 {m1}, {deg} deg: bound {bound}, exact swing {swing}"
                );
                let lower = largest_stuck_pull(&rig, level - 0.05 * level.abs()).unwrap();
                assert!(lower <= bound, "m1 {m1}, {deg} deg: {lower} > {bound}");
            }
        }
    }

    /// Nothing is claimed where the level is not conserved.
    #[test]
    fn no_pull_bound_on_a_tilted_or_damped_rig() {
        let rig = Rig::paper(0.2);
        assert!(largest_stuck_pull(&rig.with_rail_tilt(0.01), 0.0).is_none());
        assert!(largest_stuck_pull(&rig.with_pivot_damping(1e-3), 0.0).is_none());
    }

    #[test]
    fn inverse_of_mu_critical() {
        for r in [0.01, 0.05, 0.3, 1.0, 4.0] {
            let mu = mu_critical(r);
            assert!((max_mass_ratio_for_paradox(mu) - r).abs() < 1e-12 * (1.0 + r));
        }
    }
}
