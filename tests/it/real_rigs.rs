//! Real rigs (docs/physics.md, "Real rigs"): rail tilt, pivot damping, viscous and Stribeck
//! friction, checked against oracles written here from the equations of motion, the energy
//! balance with the tilted potential, closed forms and limits.

use super::helpers::{assert_energy_balance, assert_slide_matches_oracle, run, slide_states};
use appell::model::{pendulum::stuck_period, Direction, Mode, Rig, Scalar, Shorthands, State};
use appell::sim::{simulate, EventKind, Method, Options, Request, Solution};
use num_dual::Dual64;
use std::f64::consts::{FRAC_PI_2, PI};

/// Three rigs: the paper's, a heavy slider, a light slider (below mu* in every case).
fn rigs(mu_k: f64, mu_s: f64) -> Vec<Rig<f64>> {
    [(0.1, 0.1, 0.3), (0.5, 0.2, 0.3), (0.05, 0.2, 0.45)]
        .into_iter()
        .map(|(m1, m2, l)| Rig::new(m1, m2, l, 9.81, mu_k, Some(mu_s)).unwrap())
        .collect()
}

/// Every combination of the new terms worth testing alone and together.
fn variants(rig: Rig<f64>) -> Vec<(&'static str, Rig<f64>)> {
    vec![
        ("tilt", rig.with_rail_tilt(2f64.to_radians())),
        ("tilt-", rig.with_rail_tilt(-3f64.to_radians())),
        ("damping", rig.with_pivot_damping(2e-3)),
        ("viscous", rig.with_viscous_friction(0.05)),
        ("stribeck", rig.with_stribeck(0.05)),
        (
            "all",
            rig.with_rail_tilt(1.5f64.to_radians())
                .with_pivot_damping(1e-3)
                .with_viscous_friction(0.02)
                .with_stribeck(0.1),
        ),
    ]
}

#[test]
fn accelerations_match_the_equations_of_motion_for_every_term() {
    let mut n = 0;
    for rig in rigs(0.3, 0.45) {
        for (name, r) in variants(rig) {
            for y in slide_states() {
                assert_slide_matches_oracle(name, &r, &y, 1e-12);
                // The stick model: theta'' from the pendulum row alone.
                let (th, w) = (y[1], y[3]);
                let scale = r.gravity * (1.0 + w * w * r.rod_length / r.gravity);
                let pend = (r.gravity * r.rail_tilt.cos() * th.cos()
                    - r.gravity * r.rail_tilt.sin() * th.sin()
                    - r.pivot_damping * w / (r.bob_mass * r.rod_length))
                    / r.rod_length;
                assert!((r.stick_angular_acceleration(th, w) - pend).abs() < 1e-12 * scale);
                n += 1;
            }
        }
    }
    assert_eq!(n, 3 * 6 * 6 * 5 * 4);
}

/// Energy balance E(t) - E(0) = friction work + damping work (both <= 0), with the tilted
/// potential, to 1e-9 of the energy scale at rtol 1e-12: each term alone and all together,
/// on three rigs, both methods; runs through stick-slip events.
#[test]
fn energy_balance_closes_with_friction_and_damping_work() {
    for rig in rigs(0.3, 0.4) {
        for (name, r) in variants(rig) {
            for method in Method::ALL {
                let sol = assert_energy_balance(name, &r, method);
                let unit = (r.slider_mass + r.bob_mass) * r.gravity * r.rod_length;
                let wd = sol.damping_work.unwrap();
                if r.pivot_damping > 0.0 {
                    assert!(wd < -1e-6 * unit, "{name}: damping does work");
                } else {
                    assert_eq!(wd, 0.0, "{name}: no damping, no damping work");
                }
            }
        }
    }
}

/// Times where theta' changes sign from + to - (the swing's turning points on the high side),
/// found on the samples by linear interpolation.
fn turning_points(sol: &Solution<f64>) -> Vec<(f64, f64)> {
    sol.samples
        .windows(2)
        .filter(|p| p[0].state[3] > 0.0 && p[1].state[3] <= 0.0)
        .map(|p| {
            let (w0, w1) = (p[0].state[3], p[1].state[3]);
            let u = w0 / (w0 - w1);
            (
                p[0].t + u * (p[1].t - p[0].t),
                p[0].state[1] + u * (p[1].state[1] - p[0].state[1]),
            )
        })
        .collect()
}

/// A stuck pendulum on a tilted rail swings about theta = pi/2 - alpha with the untilted
/// period (the closed form of the level pendulum for the same amplitude).
#[test]
fn tilted_stuck_pendulum_swings_about_gravity_with_the_level_period() {
    for alpha_deg in [-5.0f64, 3.0, 10.0] {
        let alpha = alpha_deg.to_radians();
        let rig = Rig::new(0.5, 0.2, 0.3, 9.81, 5.0, None)
            .unwrap()
            .with_rail_tilt(alpha);
        let amplitude = 0.4;
        let centre = FRAC_PI_2 - alpha;
        let y0 = [0.0, centre + amplitude, 0.0, 0.0];
        let level = Rig::new(0.5, 0.2, 0.3, 9.81, 5.0, None).unwrap();
        let period = stuck_period(&level, amplitude);
        let times: Vec<f64> = (0..=40_000).map(|k| k as f64 * 1e-4).collect();
        let sol = run(
            &rig,
            y0,
            4.0,
            1e-12,
            Method::Dop853,
            &Request {
                sample_times: times,
                friction_work: false,
                positions_only: false,
            },
        );
        assert!(sol.events.is_empty(), "stays stuck: {:?}", sol.events);
        // Lowest and highest angles are symmetric about the centre.
        let (lo, hi) = sol
            .samples
            .iter()
            .fold((f64::MAX, f64::MIN), |(lo, hi), s| {
                (lo.min(s.state[1]), hi.max(s.state[1]))
            });
        assert!(
            (0.5 * (lo + hi) - centre).abs() < 1e-6,
            "alpha {alpha_deg}: centre {} vs {centre}",
            0.5 * (lo + hi)
        );
        // Turning points at the start angle, one period apart (the first at t = 0 is not
        // sampled as a sign change, so the k-th is at k periods).
        let turns = turning_points(&sol);
        assert!(turns.len() >= 3);
        for (k, (t, th)) in turns.iter().enumerate() {
            let want = (k + 1) as f64 * period;
            assert!(
                (t - want).abs() < 1e-6,
                "alpha {alpha_deg}: turn {k} at {t}, period {period}"
            );
            assert!((th - (centre + amplitude)).abs() < 1e-6);
        }
    }
}

/// Small swings of a stuck pendulum with pivot damping decay as exp(-c_p t / (2 m2 l^2)).
#[test]
fn damped_stuck_pendulum_decays_at_the_closed_form_rate() {
    for (m2, l, c_p) in [(0.2, 0.3, 2e-3), (0.1, 0.5, 5e-4)] {
        let rig = Rig::new(0.5, m2, l, 9.81, 5.0, None)
            .unwrap()
            .with_pivot_damping(c_p);
        let a0 = 1e-3;
        let y0 = [0.0, FRAC_PI_2 + a0, 0.0, 0.0];
        let times: Vec<f64> = (0..=60_000).map(|k| k as f64 * 1e-4).collect();
        let sol = run(
            &rig,
            y0,
            6.0,
            1e-12,
            Method::Dop853,
            &Request {
                sample_times: times,
                friction_work: false,
                positions_only: false,
            },
        );
        assert!(sol.events.is_empty());
        let rate = c_p / (2.0 * m2 * l * l);
        let turns = turning_points(&sol);
        assert!(turns.len() >= 4);
        for (t, th) in turns {
            let amp = th - FRAC_PI_2;
            let want = a0 * (-rate * t).exp();
            assert!(
                ((amp / want).ln()).abs() < 2e-3,
                "m2 {m2}: at {t} amplitude {amp} vs {want}"
            );
        }
    }
}

/// A rig at rest with the bob hanging in equilibrium (theta = pi/2 - alpha) is a block on a
/// slope: it slides downhill exactly when tan(alpha) > mu_s; both sides of the threshold, and
/// both tilt signs.
#[test]
fn rig_at_rest_slides_downhill_exactly_above_the_friction_angle() {
    for mu_s in [0.1f64, 0.3] {
        for side in [1.0, -1.0] {
            for (factor, slides) in [(1.001, true), (0.999, false)] {
                let alpha = side * (mu_s * factor).atan();
                let rig = Rig::new(0.3, 0.2, 0.3, 9.81, 0.8 * mu_s, Some(mu_s))
                    .unwrap()
                    .with_rail_tilt(alpha);
                let y0 = [0.0, FRAC_PI_2 - alpha, 0.0, 0.0];
                let sol = run(&rig, y0, 0.5, 1e-12, Method::Dop853, &Request::default());
                if slides {
                    assert!(
                        sol.final_state[0] * side > 1e-3,
                        "mu_s {mu_s} side {side}: x {}",
                        sol.final_state[0]
                    );
                    let downhill = Mode::Slide(Direction::of(side));
                    assert_eq!(sol.final_mode, downhill, "mu_s {mu_s} side {side}");
                } else {
                    assert_eq!(sol.final_state[0], 0.0, "mu_s {mu_s} side {side}");
                    assert_eq!(sol.final_mode, Mode::Stick);
                    assert!(sol.events.is_empty());
                }
            }
        }
    }
}

/// First event times of a run.
fn event_times(sol: &Solution<f64>, n: usize) -> Vec<f64> {
    sol.events.iter().take(n).map(|e| e.t).collect()
}

/// Stribeck friction tends to Coulomb with mu_k as v_s -> 0 and to Coulomb with mu_s as
/// v_s -> infinity: the event times converge (the error shrinks along the ladder and ends
/// small).
#[test]
fn stribeck_limits_are_coulomb_with_mu_k_and_with_mu_s() {
    let base = Rig::new(0.1, 0.1, 0.3, 9.81, 0.3, Some(0.4)).unwrap();
    let y0 = [0.0, 0.0, 0.0, 0.0];
    let t_end = 1.2;
    let opts = |rig: &Rig<f64>| run(rig, y0, t_end, 1e-11, Method::Dop853, &Request::default());
    let kinetic = opts(&base);
    let static_only = opts(&Rig::new(0.1, 0.1, 0.3, 9.81, 0.4, None).unwrap());
    let n = 3;
    let (tk, ts) = (event_times(&kinetic, n), event_times(&static_only, n));
    assert_eq!(tk.len(), n);
    assert_eq!(ts.len(), n);
    let err = |a: &[f64], b: &[f64]| {
        a.iter()
            .zip(b)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max)
    };
    // Small v_s: the slip time is mu_s's (static friction holds until then), the later events
    // approach Coulomb with mu_k.
    let mut prev = f64::INFINITY;
    for v_s in [1e-2, 1e-3, 1e-4] {
        let sol = opts(&base.with_stribeck(v_s));
        let t = event_times(&sol, n);
        assert_eq!(sol.events[0].kind, EventKind::Slip);
        let e = err(&t[1..], &tk[1..]);
        assert!(e < prev, "v_s {v_s}: {e} not below {prev}");
        prev = e;
    }
    assert!(prev < 1e-3, "v_s 1e-4: {prev}");
    let mut prev = f64::INFINITY;
    for v_s in [1e1, 1e2, 1e3] {
        let t = event_times(&opts(&base.with_stribeck(v_s)), n);
        let e = err(&t, &ts);
        assert!(e < prev, "v_s {v_s}: {e} not below {prev}");
        prev = e;
    }
    assert!(prev < 1e-6, "v_s 1e3: {prev}");
}

/// The mirror (x, theta) -> (-x, pi - theta) maps a rig tilted by alpha onto one tilted by
/// -alpha: the same event times with mirrored modes and states, with every term on.
#[test]
fn tilt_sign_mirrors_the_timeline() {
    let mirror = |y: &State<f64>| [-y[0], PI - y[1], -y[2], -y[3]];
    for rig in rigs(0.25, 0.3) {
        let r = rig
            .with_rail_tilt(4f64.to_radians())
            .with_pivot_damping(1e-3)
            .with_stribeck(0.05)
            .with_viscous_friction(0.01);
        let m = r.with_rail_tilt(-r.rail_tilt);
        let y0 = [0.02, 0.4, 0.1, -1.0];
        let a = run(&r, y0, 2.0, 1e-12, Method::Dop853, &Request::default());
        let b = run(
            &m,
            mirror(&y0),
            2.0,
            1e-12,
            Method::Dop853,
            &Request::default(),
        );
        assert!(a.events.len() >= 2);
        assert_eq!(a.events.len(), b.events.len());
        for (ea, eb) in a.events.iter().zip(&b.events) {
            assert!((ea.t - eb.t).abs() < 1e-9, "{} vs {}", ea.t, eb.t);
            assert_eq!(ea.kind, eb.kind);
            assert_eq!(ea.from.mirrored(), eb.from);
        }
        let (fa, fb) = (mirror(&a.final_state), b.final_state);
        for i in 0..4 {
            assert!((fa[i] - fb[i]).abs() < 1e-7, "{i}: {} vs {}", fa[i], fb[i]);
        }
    }
}

/// Which new parameter a derivative is taken for.
#[derive(Clone, Copy, Debug)]
enum NewParam {
    Tilt,
    Damping,
    Viscous,
    StribeckSpeed,
}

fn set<T: Scalar>(rig: &mut Rig<T>, p: NewParam, v: T) {
    match p {
        NewParam::Tilt => rig.rail_tilt = v,
        NewParam::Damping => rig.pivot_damping = v,
        NewParam::Viscous => rig.viscous_friction = v,
        NewParam::StribeckSpeed => rig.stribeck_velocity = v,
    }
}

fn get(rig: &Rig<f64>, p: NewParam) -> f64 {
    match p {
        NewParam::Tilt => rig.rail_tilt,
        NewParam::Damping => rig.pivot_damping,
        NewParam::Viscous => rig.viscous_friction,
        NewParam::StribeckSpeed => rig.stribeck_velocity,
    }
}

/// Dual-number derivatives of sampled states with respect to each new parameter match central
/// finite differences through stick/slip events.
#[test]
fn dual_derivatives_of_new_parameters_match_finite_differences() {
    let rig = Rig::new(0.1, 0.1, 0.3, 9.81, 0.3, Some(0.38))
        .unwrap()
        .with_rail_tilt(2f64.to_radians())
        .with_pivot_damping(1e-3)
        .with_viscous_friction(0.02)
        .with_stribeck(0.08);
    dual_matches_finite_differences(
        &rig,
        &[
            NewParam::Tilt,
            NewParam::Damping,
            NewParam::Viscous,
            NewParam::StribeckSpeed,
        ],
    );
}

/// The same at the ideal rig, where each term is exactly zero: a fit frees these parameters
/// at zero, so skipping a zero term must not drop its derivative (num-dual's `is_zero`
/// ignores derivatives; this test fails if the model uses it to skip terms).
#[test]
fn dual_derivatives_at_zero_terms_are_not_lost() {
    let rig = Rig::new(0.1, 0.1, 0.3, 9.81, 0.3, Some(0.38)).unwrap();
    dual_matches_finite_differences(
        &rig,
        &[NewParam::Tilt, NewParam::Damping, NewParam::Viscous],
    );
}

fn dual_matches_finite_differences(rig: &Rig<f64>, params: &[NewParam]) {
    let rig = *rig;
    let y0 = [0.0, 0.0, 0.0, 0.0];
    let times: Vec<f64> = (1..=24).map(|k| k as f64 * 0.05).collect();
    let req = Request {
        sample_times: times.clone(),
        friction_work: false,
        positions_only: false,
    };
    let opts = Options {
        rtol: 1e-12,
        atol: 1e-14,
        ..Options::default()
    };
    let base = simulate(&rig, &y0, 1.25, &opts, &req).unwrap();
    let kinds: Vec<EventKind> = base.events.iter().map(|e| e.kind).collect();
    assert!(kinds.contains(&EventKind::Slip) && kinds.contains(&EventKind::Stick));
    for &p in params {
        let v = get(&rig, p);
        let mut rd: Rig<Dual64> = rig.lift();
        set(&mut rd, p, Dual64::new(v, 1.0));
        let y0d = y0.map(Dual64::from);
        let dual = simulate(&rd, &y0d, 1.25, &opts, &req).unwrap();
        // A step relative to the parameter's typical size: at zero, 1e-5 of a tiny floor
        // would drown the difference in the integrator's own error.
        let typical = match p {
            NewParam::Tilt => 0.03,
            NewParam::Damping => 1e-3,
            NewParam::Viscous => 0.02,
            NewParam::StribeckSpeed => 0.05,
        };
        let h = 1e-5 * v.abs().max(typical);
        let shifted = |d: f64| {
            let mut r = rig;
            set(&mut r, p, v + d);
            simulate(&r, &y0, 1.25, &opts, &req).unwrap()
        };
        let (plus, minus) = (shifted(h), shifted(-h));
        assert_eq!(plus.events.len(), base.events.len(), "{p:?}: same events");
        assert_eq!(minus.events.len(), base.events.len(), "{p:?}: same events");
        let mut largest: f64 = 0.0;
        for (k, t) in times.iter().enumerate() {
            for i in 0..4 {
                let fd = (plus.samples[k].state[i] - minus.samples[k].state[i]) / (2.0 * h);
                let ad = dual.samples[k].state[i].eps;
                let scale = fd.abs().max(ad.abs()).max(1e-3);
                largest = largest.max(fd.abs());
                assert!(
                    (fd - ad).abs() < 2e-4 * scale,
                    "{p:?} t {t} state {i}: dual {ad} vs fd {fd}"
                );
            }
        }
        // The parameter matters: a zero derivative everywhere would pass the comparison
        // above only if finite differences were zero too.
        assert!(largest > 1e-3, "{p:?}: derivatives all below 1e-3");
    }
}

/// Rigs without the new terms give exactly the results they gave before the terms existed:
/// a rig built with every new term at zero is the ideal rig, bit for bit.
#[test]
fn zero_terms_are_the_ideal_rig_bit_for_bit() {
    let ideal = Rig::paper(0.35);
    let zeroed = ideal
        .with_rail_tilt(0.0)
        .with_pivot_damping(0.0)
        .with_viscous_friction(0.0);
    let stribeck_equal = ideal.with_stribeck(0.05); // mu_s = mu_k: no speed dependence
    let y0 = [0.0, 0.0, 0.0, 0.0];
    let a = run(&ideal, y0, 2.0, 1e-10, Method::Dop853, &Request::default());
    for r in [zeroed, stribeck_equal] {
        let b = run(&r, y0, 2.0, 1e-10, Method::Dop853, &Request::default());
        assert_eq!(event_times(&a, 100), event_times(&b, 100));
        assert_eq!(a.final_state, b.final_state);
    }
    // The seed paper's slip time (docs/physics.md transitions) is untouched.
    assert!((a.events[0].t - 0.086825360601).abs() < 1e-9);
}

/// The paradox bound follows the largest mu a law reaches: Stribeck with mu_s above mu* opens
/// the band even with mu_k below it.
#[test]
fn stribeck_paradox_band_uses_mu_static() {
    use appell::model::regions::{mu_critical, paradox_band_deg};
    let r = 0.05;
    let mu_star = mu_critical(r);
    let rig = Rig::new(0.01, 0.2, 0.3, 9.81, 0.8 * mu_star, Some(1.3 * mu_star)).unwrap();
    assert!(paradox_band_deg(&rig).is_empty());
    assert!(!paradox_band_deg(&rig.with_stribeck(0.05)).is_empty());
}

/// Tilt breaks the mirror symmetry of the stick region: at theta and pi - theta with w and
/// -w the needed ratios differ, and they agree again for the mirrored tilt.
#[test]
fn tilted_stick_region_is_the_mirror_of_the_opposite_tilt() {
    use appell::model::regions::stick_intervals;
    let rig = Rig::paper(0.35).with_rail_tilt(5f64.to_radians());
    let other = rig.with_rail_tilt(-rig.rail_tilt);
    let mut differ = false;
    for k in 0..90 {
        let th = 0.07 * k as f64;
        let a = stick_intervals(&rig, th, 15.0);
        let b = stick_intervals(&other, PI - th, 15.0);
        let mirrored: Vec<(f64, f64)> = b.iter().rev().map(|&(lo, hi)| (-hi, -lo)).collect();
        assert_eq!(a.len(), mirrored.len(), "theta {th}");
        for (p, q) in a.iter().zip(&mirrored) {
            assert!((p.0 - q.0).abs() < 1e-9 && (p.1 - q.1).abs() < 1e-9);
        }
        let same_rig_mirror = stick_intervals(&rig, PI - th, 15.0);
        differ |= same_rig_mirror.len() != a.len()
            || same_rig_mirror
                .iter()
                .rev()
                .zip(&a)
                .any(|(q, p)| (p.0 + q.1).abs() > 1e-6);
    }
    assert!(differ, "tilt must break the level rig's mirror symmetry");
}

/// With pivot damping the stick boundary is no longer symmetric in w: the intervals found by
/// the quadratic in w agree with a brute-force scan of the margin.
#[test]
fn damped_stick_intervals_match_a_brute_force_scan() {
    use appell::model::regions::stick_intervals;
    let rig = Rig::paper(0.3).with_pivot_damping(0.05);
    for k in 0..60 {
        let th = 0.1 * k as f64 + 0.01;
        let iv = stick_intervals(&rig, th, 12.0);
        for j in 0..=400 {
            let w = -12.0 + 24.0 * j as f64 / 400.0;
            let margin = Shorthands::new(&rig, th, w).stick_margin(rig.mu_static);
            if margin.abs() < 1e-9 {
                continue;
            }
            let inside = iv.iter().any(|&(lo, hi)| w >= lo && w <= hi);
            assert_eq!(inside, margin > 0.0, "theta {th} w {w}");
        }
    }
}

/// The Stribeck law written out here, mu_k + (mu_s - mu_k) exp(-(v/v_s)^2), against the
/// model's, which leaves the exponential out far in the tail: at every speed across the cut
/// the two agree to rounding, in value and in the derivative with respect to mu_s.
#[test]
fn stribeck_tail_left_out_only_where_it_is_below_rounding() {
    let v_s = 0.05;
    let rig = Rig::new(0.1, 0.1, 0.3, 9.81, 0.3, Some(0.9))
        .unwrap()
        .with_stribeck(v_s);
    let mut dual = rig.lift::<Dual64>();
    dual.mu_static = Dual64::new(0.9, 1.0);
    for i in 0..=400 {
        let v = v_s * 10.0 * f64::from(i) / 400.0;
        let u = v / v_s;
        let oracle = 0.3 + 0.6 * (-u * u).exp();
        let mu = rig.friction_mu(1.0, v);
        assert!(
            (mu - oracle).abs() <= 2.0 * f64::EPSILON * oracle,
            "v {v}: {mu} vs {oracle}"
        );
        let d = dual.friction_mu(1.0, Dual64::from(v));
        // exp magnifies the rounding of u^2 by u^2.
        let e = (-u * u).exp();
        assert!(
            (d.eps - e).abs() <= 4.0 * (1.0 + u * u) * f64::EPSILON * e + 1e-21,
            "v {v}: d/dmu_s {} vs {e}",
            d.eps
        );
    }
}
