//! Region analysis against docs/physics.md: closed forms of mu*, theta* and the band, a numerical
//! minimisation, brute-force root counting of the sliding equation, and simulated trajectories.

use appell::model::regions::{
    band_edges, in_stick_region, max_mass_ratio_for_paradox, mu_critical, paradox_band,
    paradox_band_deg, q_zero_curve, slide_count_intervals, slide_solution_count, stick_boundary,
    stick_intervals, theta_critical, PlaneWindow,
};
use appell::model::{Direction, Mode, Rig, Shorthands};
use appell::report::regions::{phase_portrait, PortraitOptions};
use appell::scene::RigFile;
use std::f64::consts::PI;
use std::path::Path;

/// D and a of docs/physics.md, written out here again so the tests do not trust the library.
fn d_a(rig: &Rig<f64>, theta: f64) -> (f64, f64) {
    let (s, c) = theta.sin_cos();
    (rig.slider_mass + rig.bob_mass * c * c, rig.bob_mass * s * c)
}

/// b and c of docs/physics.md, written out independently.
fn b_c(rig: &Rig<f64>, theta: f64, w: f64) -> (f64, f64) {
    let (m1, m2, l, g) = (rig.slider_mass, rig.bob_mass, rig.rod_length, rig.gravity);
    let (s, c) = theta.sin_cos();
    (
        -(m1 * g + m2 * g * s * s + m2 * l * w * w * s),
        m2 * c * (g * s + l * w * w),
    )
}

fn rig_with(m1: f64, m2: f64, mu: f64) -> Rig<f64> {
    Rig::new(m1, m2, 0.3, 9.81, mu, None).unwrap()
}

/// A small deterministic generator (xorshift64*), uniform in [0, 1).
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
    }
    fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }
}

#[test]
fn mu_critical_and_theta_critical_match_physics_md() {
    // (r, mu*, theta* in degrees) as printed in docs/physics.md.
    for (r, mu, theta) in [
        (0.5, 1.732, 60.0),
        (2.0, 4.899, 50.8),
        (0.1, 0.663, 73.2),
        (0.05, 0.458, 77.7),
        (1.0, 2.828, 54.74),
    ] {
        assert!(
            (mu_critical(r) - mu).abs() < 1e-3,
            "r = {r}: {}",
            mu_critical(r)
        );
        let t = theta_critical(r).to_degrees();
        assert!((t - theta).abs() < 0.06, "r = {r}: theta* = {t}");
    }
}

#[test]
fn mu_critical_is_the_minimum_of_d_over_abs_a() {
    for r in [0.02, 0.05, 0.1, 0.5, 1.0, 2.0, 7.0] {
        let rig = rig_with(r, 1.0, 0.3);
        let f = |t: f64| {
            let (d, a) = d_a(&rig, t);
            d / a.abs()
        };
        // Coarse grid, then golden-section search on the bracket around the best grid point.
        let n = 2000;
        let k = (1..n)
            .min_by(|&i, &j| {
                let ti = PI / 2.0 * i as f64 / n as f64;
                let tj = PI / 2.0 * j as f64 / n as f64;
                f(ti).total_cmp(&f(tj))
            })
            .unwrap();
        let (mut lo, mut hi) = (
            PI / 2.0 * (k - 1) as f64 / n as f64,
            PI / 2.0 * (k + 1) as f64 / n as f64,
        );
        let g = (5f64.sqrt() - 1.0) / 2.0;
        for _ in 0..100 {
            let (x1, x2) = (hi - g * (hi - lo), lo + g * (hi - lo));
            if f(x1) < f(x2) {
                hi = x2;
            } else {
                lo = x1;
            }
        }
        let t_min = 0.5 * (lo + hi);
        assert!(
            (f(t_min) - mu_critical(r)).abs() < 1e-9 * mu_critical(r),
            "r = {r}: numerical {} vs {}",
            f(t_min),
            mu_critical(r)
        );
        assert!((t_min - theta_critical(r)).abs() < 1e-6, "r = {r}");
        // And the inverse: at exactly mu*(r) the largest ratio is r.
        assert!((max_mass_ratio_for_paradox(mu_critical(r)) - r).abs() < 1e-9 * (1.0 + r));
    }
}

#[test]
fn equal_mass_band_edges_match_physics_md_and_zero_the_margin() {
    let rig = rig_with(0.1, 0.1, 1.0);
    for (mu, lo_deg, hi_deg) in [(3.0, 45.0, 63.43), (4.0, 30.4, 73.7), (5.0, 23.7, 77.6)] {
        let (lo, hi) = paradox_band(1.0, mu).unwrap();
        assert!(
            (lo.to_degrees() - lo_deg).abs() < 0.06,
            "mu = {mu}: lo = {}",
            lo.to_degrees()
        );
        assert!(
            (hi.to_degrees() - hi_deg).abs() < 0.06,
            "mu = {mu}: hi = {}",
            hi.to_degrees()
        );
        for edge in [lo, hi, PI - lo, PI - hi, PI + lo, -hi] {
            let (d, a) = d_a(&rig, edge);
            assert!((d - mu * a.abs()).abs() < 1e-12, "mu = {mu}: edge {edge}");
        }
        let (d, a) = d_a(&rig, 0.5 * (lo + hi));
        assert!(
            d - mu * a.abs() < 0.0,
            "inside the band the margin is negative"
        );
        for outside in [0.9 * lo, hi + 0.1 * (PI / 2.0 - hi)] {
            let (d, a) = d_a(&rig, outside);
            assert!(d - mu * a.abs() > 0.0);
        }
        // Every edge in a full turn: four per quadrant pair, eight in (0, 2 pi).
        let edges = band_edges(1.0, mu, 0.0, 2.0 * PI);
        assert_eq!(edges.len(), 8);
        for e in edges {
            let (d, a) = d_a(&rig, e);
            assert!((d - mu * a.abs()).abs() < 1e-12);
        }
    }
}

#[test]
fn paradox_band_in_degrees_is_empty_below_mu_star_and_mirrored_above() {
    assert!(paradox_band_deg(&rig_with(0.1, 0.1, 2.8)).is_empty());
    let band = paradox_band_deg(&rig_with(0.1, 0.1, 3.0));
    assert_eq!(band.len(), 2);
    assert!((band[0][0] - 45.0).abs() < 1e-9 && (band[0][1] - 63.43).abs() < 0.01);
    assert!((band[1][0] - (180.0 - band[0][1])).abs() < 1e-9);
    assert!((band[1][1] - (180.0 - band[0][0])).abs() < 1e-9);
    let paradox = rig_with(0.01, 0.2, 0.6);
    let band = paradox_band_deg(&paradox);
    assert!(band[0][0] < 77.7 && 77.7 < band[0][1]);
}

/// Solve the equations of motion for x'', theta'', N on the friction branch sigma = sign(N),
/// sliding in direction s (F = -mu s sigma N), by Gaussian elimination of the 3x3 system:
///   (m1 + m2) x'' - m2 l sin(theta) theta'' + mu s sigma N = m2 l cos(theta) w^2
///   -sin(theta) x'' + l theta''                            = g cos(theta)
///   -m2 l cos(theta) theta'' + N                           = -m2 l sin(theta) w^2 - (m1 + m2) g
fn solve_branch(rig: &Rig<f64>, theta: f64, w: f64, s: f64, sigma: f64) -> Option<[f64; 3]> {
    let (m1, m2, l, g, mu) = (
        rig.slider_mass,
        rig.bob_mass,
        rig.rod_length,
        rig.gravity,
        rig.mu_kinetic,
    );
    let (sn, cs) = theta.sin_cos();
    let mut m = [
        [m1 + m2, -m2 * l * sn, mu * s * sigma, m2 * l * cs * w * w],
        [-sn, l, 0.0, g * cs],
        [0.0, -m2 * l * cs, 1.0, -m2 * l * sn * w * w - (m1 + m2) * g],
    ];
    for col in 0..3 {
        let p = (col..3)
            .max_by(|&i, &j| m[i][col].abs().total_cmp(&m[j][col].abs()))
            .unwrap();
        if m[p][col].abs() < 1e-14 {
            return None;
        }
        m.swap(col, p);
        for row in 0..3 {
            if row != col {
                let pivot = m[col];
                let f = m[row][col] / pivot[col];
                for (v, p) in m[row].iter_mut().zip(pivot).skip(col) {
                    *v -= f * p;
                }
            }
        }
    }
    Some([m[0][3] / m[0][0], m[1][3] / m[1][1], m[2][3] / m[2][2]])
}

/// Count consistent branches by brute force; `None` when the state is too close to a
/// degenerate curve (N near 0 or a near-singular system) for the count to be robust.
fn brute_force_count(rig: &Rig<f64>, theta: f64, w: f64, s: f64) -> Option<usize> {
    let mut count = 0;
    for sigma in [1.0, -1.0] {
        let [_, _, n] = solve_branch(rig, theta, w, s, sigma)?;
        let scale = (rig.slider_mass + rig.bob_mass) * rig.gravity;
        if n.abs() < 1e-6 * scale {
            return None;
        }
        if n * sigma > 0.0 {
            count += 1;
        }
    }
    Some(count)
}

#[test]
fn sign_rule_counts_match_brute_force_root_counting() {
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    let rigs = [
        rig_with(0.1, 0.1, 0.35),
        rig_with(0.1, 0.1, 3.5),
        rig_with(0.01, 0.2, 0.6),
        rig_with(0.01, 0.2, 2.0),
        rig_with(0.3, 0.1, 5.0),
    ];
    let mut seen = [0usize; 3];
    for rig in &rigs {
        let w_scale = 4.0 * (rig.gravity / rig.rod_length).sqrt();
        for _ in 0..20_000 {
            let theta = rng.uniform(-PI, PI);
            let w = rng.uniform(-w_scale, w_scale);
            let s = if rng.next() < 0.5 { 1.0 } else { -1.0 };
            let (d, a) = d_a(rig, theta);
            if (d - rig.mu_kinetic * a.abs()).abs() < 1e-6 * d {
                continue; // on a band edge
            }
            let Some(expected) = brute_force_count(rig, theta, w, s) else {
                continue;
            };
            let got = slide_solution_count(rig, theta, w, s);
            assert_eq!(got, expected, "theta {theta}, w {w}, s {s}, rig {rig:?}");
            // The simulator's own branch test must agree too.
            let branches = rig.slide_branches(&Shorthands::new(rig, theta, w), s, 0.0);
            assert_eq!(
                branches.count(),
                expected,
                "slide_branches at theta {theta}, w {w}"
            );
            seen[got] += 1;
        }
    }
    // The sample must have exercised non-existence and non-uniqueness, not only uniqueness.
    assert!(seen.iter().all(|&n| n > 100), "counts seen: {seen:?}");
}

#[test]
fn stick_boundary_points_satisfy_abs_c_equals_mu_abs_b() {
    for rig in [
        rig_with(0.1, 0.1, 0.35),
        rig_with(0.01, 0.2, 0.6),
        Rig::new(0.2, 0.1, 0.5, 9.81, 0.2, Some(0.5)).unwrap(),
    ] {
        let window = PlaneWindow::for_rig(&rig);
        let curves = stick_boundary(&rig, &window);
        assert!(!curves.is_empty());
        let mut n = 0;
        for curve in &curves {
            for &[theta, w] in &curve.points {
                let (b, c) = b_c(&rig, theta, w);
                let scale = rig.mu_static * b.abs() + c.abs() + 1e-3;
                assert!(
                    (c.abs() - rig.mu_static * b.abs()).abs() < 1e-9 * scale,
                    "{}: theta {theta}, w {w}: |c| = {}, mu|b| = {}",
                    curve.label,
                    c.abs(),
                    rig.mu_static * b.abs()
                );
                assert!(w.abs() <= window.w_max * (1.0 + 1e-12));
                n += 1;
            }
        }
        assert!(n > 500, "only {n} boundary points");
    }
}

#[test]
fn q_zero_curve_points_satisfy_its_equation() {
    let rig = rig_with(0.01, 0.2, 0.6);
    let window = PlaneWindow::for_rig(&rig);
    let curves = q_zero_curve(&rig, &window);
    assert!(!curves.is_empty());
    for c in &curves {
        for &[theta, w] in &c.points {
            let lhs = rig.bob_mass * rig.rod_length * w * w * theta.sin();
            let rhs = -(rig.slider_mass + rig.bob_mass) * rig.gravity;
            assert!((lhs - rhs).abs() < 1e-9 * rhs.abs(), "theta {theta}, w {w}");
            assert!(theta.sin() < 0.0, "Q = 0 only with the bob above the rail");
        }
    }
}

#[test]
fn region_intervals_agree_with_pointwise_tests() {
    let mut rng = Rng(12345);
    for rig in [
        rig_with(0.1, 0.1, 0.35),
        rig_with(0.01, 0.2, 0.6),
        rig_with(0.1, 0.1, 4.0),
    ] {
        let w_max = 3.0 * (rig.gravity / rig.rod_length).sqrt();
        for _ in 0..3000 {
            let theta = rng.uniform(0.0, 2.0 * PI);
            let w = rng.uniform(-w_max, w_max);
            let (b, c) = b_c(&rig, theta, w);
            let margin = rig.mu_static * b.abs() - c.abs();
            if margin.abs() > 1e-9 {
                let inside = stick_intervals(&rig, theta, w_max)
                    .iter()
                    .any(|&(lo, hi)| lo <= w && w <= hi);
                assert_eq!(inside, margin > 0.0, "theta {theta}, w {w}");
                assert_eq!(in_stick_region(&rig, theta, w), margin > 0.0);
            }
            for s in [1.0, -1.0] {
                let intervals = slide_count_intervals(&rig, theta, s, w_max);
                let Some(&(_, _, n)) = intervals.iter().find(|&&(lo, hi, _)| lo <= w && w <= hi)
                else {
                    panic!("w = {w} not covered by {intervals:?}");
                };
                assert_eq!(n, slide_solution_count(&rig, theta, w, s));
            }
        }
    }
}

#[test]
fn release_from_horizontal_stays_in_stick_region_exactly_when_mu_s_at_least_three_quarters() {
    // docs/physics.md: equal masses released from rest with the rod horizontal slip exactly when
    // mu_s < 0.75 (the ratio |c|/|b| along the pendulum motion peaks at 0.75).
    let stays = |mu: f64| {
        let rig = rig_with(0.1, 0.1, mu);
        (0..=900).all(|k| {
            let theta = (k as f64 / 10.0).to_radians();
            let w = (2.0 * rig.gravity / rig.rod_length * theta.sin()).sqrt();
            in_stick_region(&rig, theta, w)
        })
    };
    assert!(stays(0.7501));
    assert!(!stays(0.7499));
}

fn shipped(name: &str) -> Rig<f64> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("configs")
        .join(name);
    RigFile::load(&path).unwrap()
}

#[test]
fn simulated_modes_lie_in_their_regions() {
    for (name, expect_paradox) in [("rig_paper.toml", false), ("rig_paradox.toml", true)] {
        let rig = shipped(name);
        assert_eq!(!paradox_band_deg(&rig).is_empty(), expect_paradox, "{name}");
        let runs = phase_portrait(&rig, &PortraitOptions::default());
        let mut modes = std::collections::HashSet::new();
        let mut checked = 0;
        for run in &runs {
            for sample in &run.samples {
                let [_, theta, _, w] = sample.state;
                modes.insert(sample.mode);
                match sample.mode {
                    Mode::Stick => {
                        let (b, c) = b_c(&rig, theta, w);
                        let margin = rig.mu_static * b.abs() - c.abs();
                        assert!(
                            margin >= -1e-7 * (b.abs() + c.abs()),
                            "{name}: stick sample at t {} outside the stick region (margin {margin})",
                            sample.t
                        );
                    }
                    Mode::Slide(dir) => {
                        let s = dir.sign();
                        assert!(
                            slide_solution_count(&rig, theta, w, s) >= 1,
                            "{name}: slide sample at t {} where sliding has no solution",
                            sample.t
                        );
                    }
                }
                checked += 1;
            }
        }
        assert!(checked > 1000, "{name}: only {checked} samples");
        assert!(modes.contains(&Mode::Stick), "{name}: {modes:?}");
        assert!(
            modes.contains(&Mode::Slide(Direction::Positive))
                || modes.contains(&Mode::Slide(Direction::Negative)),
            "{name}: {modes:?}"
        );
    }
}

/// The region figure says that on a level rig the s = -1 panel is the s = +1 panel mirrored,
/// (theta, theta') -> (180 deg - theta, -theta'): the reflection x -> -x of the rig. Checked
/// pointwise, with the stick region mapped onto itself; with tilt the mirror breaks.
#[test]
fn level_rig_slide_directions_are_mirror_images_and_tilt_breaks_the_mirror() {
    let rig = shipped("rig_paradox.toml");
    assert_eq!(rig.rail_tilt, 0.0);
    let w_max = 3.0 * (rig.gravity / rig.rod_length).sqrt();
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    let mut in_band = 0;
    for _ in 0..20_000 {
        let theta = rng.uniform(-PI / 2.0, 1.5 * PI);
        let w = rng.uniform(-w_max, w_max);
        let plus = slide_solution_count(&rig, theta, w, 1.0);
        assert_eq!(
            plus,
            slide_solution_count(&rig, PI - theta, -w, -1.0),
            "theta {theta}, w {w}"
        );
        assert_eq!(
            in_stick_region(&rig, theta, w),
            in_stick_region(&rig, PI - theta, -w)
        );
        in_band += usize::from(plus != 1);
    }
    assert!(in_band > 100, "the band is sampled ({in_band} points)");
    let mut tilted = rig;
    tilted.rail_tilt = 2f64.to_radians();
    let mut differ = 0;
    for _ in 0..20_000 {
        let theta = rng.uniform(-PI / 2.0, 1.5 * PI);
        let w = rng.uniform(-w_max, w_max);
        differ += usize::from(
            slide_solution_count(&tilted, theta, w, 1.0)
                != slide_solution_count(&tilted, PI - theta, -w, -1.0)
                || in_stick_region(&tilted, theta, w) != in_stick_region(&tilted, PI - theta, -w),
        );
    }
    assert!(differ > 0, "a tilted rig is not mirror-symmetric");
}

/// The band of friction `mu` at mass ratio `r` within 0..180 degrees from docs/physics.md's
/// closed form, written out here: |tan theta| between (mu -+ sqrt(mu^2 - 4 r (1 + r))) / (2 r).
fn band_closed_form(r: f64, mu: f64) -> Vec<[f64; 2]> {
    let disc = mu * mu - 4.0 * r * (1.0 + r);
    if disc <= 0.0 {
        return Vec::new();
    }
    let lo = ((mu - disc.sqrt()) / (2.0 * r)).atan().to_degrees();
    let hi = ((mu + disc.sqrt()) / (2.0 * r)).atan().to_degrees();
    vec![[lo, hi], [180.0 - hi, 180.0 - lo]]
}

fn assert_bands_eq(a: &[[f64; 2]], b: &[[f64; 2]], what: &str) {
    assert_eq!(a.len(), b.len(), "{what}: {a:?} against {b:?}");
    for (x, y) in a.iter().zip(b) {
        assert!(
            (x[0] - y[0]).abs() < 1e-9 && (x[1] - y[1]).abs() < 1e-9,
            "{what}: {a:?} against {b:?}"
        );
    }
}

/// The bands `appell regions` draws for a rig's law, by label.
fn law_bands_of(rig: &Rig<f64>) -> Vec<(String, f64, Vec<[f64; 2]>)> {
    use appell::model::regions::law_bands;
    let window = appell::report::regions::figure_window(rig);
    law_bands(rig, &window)
        .into_iter()
        .map(|b| (b.label.to_owned(), b.mu, b.paradox_band_deg))
        .collect()
}

fn coulomb_band(m1: f64, m2: f64, mu: f64) -> Vec<[f64; 2]> {
    paradox_band_deg(&rig_with(m1, m2, mu))
}

#[test]
fn direction_law_draws_the_coulomb_band_of_each_direction_and_its_mirror_swaps_them() {
    let (m1, m2) = (0.01, 0.2);
    for (plus, minus) in [(0.65, 0.5), (0.5, 0.65), (0.3, 0.7), (0.47, 0.43)] {
        let mean = 0.5 * (plus + minus);
        let rig = rig_with(m1, m2, mean).with_direction_split(0.5 * (plus - minus), 0.0);
        let bands = law_bands_of(&rig);
        assert_eq!(bands.len(), 2);
        for ((label, mu, band), want) in bands.iter().zip([plus, minus]) {
            assert!((mu - want).abs() < 1e-15, "{label}: {mu} against {want}");
            assert_bands_eq(band, &coulomb_band(m1, m2, want), label);
            assert_bands_eq(band, &band_closed_form(m1 / m2, want), label);
        }
        assert_eq!((bands[0].0.as_str(), bands[1].0.as_str()), ("+x", "-x"));
        // Mirrored (the split's sign flipped): the bands swap directions.
        let mirror = rig_with(m1, m2, mean).with_direction_split(0.5 * (minus - plus), 0.0);
        let m = law_bands_of(&mirror);
        assert_bands_eq(&m[0].2, &bands[1].2, "mirror +x");
        assert_bands_eq(&m[1].2, &bands[0].2, "mirror -x");
        // And the solution counts the panels shade: a slide toward s on the rig at (theta, w)
        // counts as the mirrored slide on the mirrored rig at (pi - theta, -w).
        for k in 0..=180 {
            let theta = (k as f64).to_radians();
            for w in [-6.0, -1.0, 0.0, 2.5, 9.0] {
                for s in [1.0, -1.0] {
                    assert_eq!(
                        slide_solution_count(&rig, theta, w, s),
                        slide_solution_count(&mirror, PI - theta, -w, -s),
                        "theta {k} deg, w {w}, s {s}, split {plus}/{minus}"
                    );
                }
            }
        }
    }
}

#[test]
fn stribeck_draws_the_coulomb_bands_at_rest_and_sliding_fast() {
    let (m1, m2) = (0.01, 0.2);
    let mut rig = rig_with(m1, m2, 0.5).with_stribeck(0.05);
    rig.mu_static = 0.65;
    let bands = law_bands_of(&rig);
    let labels: Vec<&str> = bands.iter().map(|b| b.0.as_str()).collect();
    assert_eq!(labels, ["at rest", "sliding fast"]);
    assert_bands_eq(&bands[0].2, &coulomb_band(m1, m2, 0.65), "at rest");
    assert_bands_eq(&bands[1].2, &coulomb_band(m1, m2, 0.5), "sliding fast");
    assert_bands_eq(&bands[1].2, &band_closed_form(0.05, 0.5), "sliding fast");
}

#[test]
fn load_law_draws_the_bands_of_the_loads_a_swing_meets() {
    use appell::model::regions::swing_loads;
    let (m1, m2, l, g) = (0.01, 0.2, 0.3, 9.81);
    let n0 = (m1 + m2) * g;
    // Exponent 1 is Coulomb's law: every load's band is the Coulomb rig's.
    let one = rig_with(m1, m2, 0.6).with_load_exponent(1.0);
    let bands = law_bands_of(&one);
    assert_eq!(bands.len(), 3);
    for (label, mu, band) in &bands {
        assert_eq!(*mu, 0.6, "{label}");
        assert_bands_eq(band, &coulomb_band(m1, m2, 0.6), label);
    }
    // n = 0.8: the loads of a level undamped rig with the bob below the rail are m1 g (the rod
    // along the rail, at rest) to (m1 + m2) g + m2 l w_max^2 (hanging at the window's fastest
    // swing), and the coefficient there is mu_k (|N| / N_0)^(n - 1).
    let rig = rig_with(m1, m2, 0.42).with_load_exponent(0.8);
    let window = appell::report::regions::figure_window(&rig);
    let [lo, hi] = swing_loads(&rig, &window);
    let want_hi = n0 + m2 * l * window.w_max * window.w_max;
    assert!((lo - m1 * g).abs() < 1e-12 * n0, "{lo}");
    assert!(
        (hi - want_hi).abs() < 1e-12 * want_hi,
        "{hi} against {want_hi}"
    );
    let bands = law_bands_of(&rig);
    let labels: Vec<&str> = bands.iter().map(|b| b.0.as_str()).collect();
    assert_eq!(labels, ["smallest load", "static load", "largest load"]);
    for ((label, mu, band), load) in bands.iter().zip([m1 * g, n0, want_hi]) {
        let want = 0.42 * (load / n0).powf(-0.2);
        assert!((mu - want).abs() < 1e-12, "{label}: {mu} against {want}");
        assert_bands_eq(band, &band_closed_form(m1 / m2, want), label);
    }
    // The light load opens a band the static load does not (0.77 and 0.42 against mu* 0.458).
    assert!(!bands[0].2.is_empty() && bands[1].2.is_empty() && bands[2].2.is_empty());
}

#[test]
fn load_coefficient_is_the_load_laws_and_constant_under_the_others() {
    let rig = rig_with(0.1, 0.1, 0.3).with_load_exponent(0.85);
    let n0 = rig.static_load();
    assert_eq!(rig.load_coefficient(n0), 0.3);
    for u in [0.1f64, 0.5, 2.0, 7.0] {
        let want = 0.3 * u.powf(-0.15);
        assert!((rig.load_coefficient(u * n0) - want).abs() < 1e-14);
        // The sign of N does not count, only its size.
        assert_eq!(rig.load_coefficient(-u * n0), rig.load_coefficient(u * n0));
        assert_eq!(rig_with(0.1, 0.1, 0.3).load_coefficient(u * n0), 0.3);
    }
}
