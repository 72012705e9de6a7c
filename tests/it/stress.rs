//! Numerical stress tests: each drives the simulator to an edge (stiff sliding near mu*,
//! grazing the stick boundary, chattering, long runs, extreme mass ratios, rotations with
//! N changing sign, mu = 0 and mu = 1e6, theta at 0 and pi/2, extreme unit scales) and
//! asserts an invariant there, never a snapshot.

use crate::helpers::*;
use appell::bench::exact;
use appell::model::{energy, momentum, regions, Mode, Rig, State};
use appell::sim::{simulate, EventKind, Method, Options, Request, SimError, Solution};
use std::f64::consts::{FRAC_PI_2, PI};
use std::time::Duration;

/// Frame times 0, dt, ... up to `t_end`.
fn frames(t_end: f64, n: usize) -> Vec<f64> {
    (0..=n).map(|k| t_end * k as f64 / n as f64).collect()
}

/// Largest |E(t) - E(0) - W(t)| over the samples, over m2 g l.
fn energy_defect(rig: &Rig<f64>, y0: &State<f64>, sol: &Solution<f64>) -> f64 {
    let e0 = energy(rig, y0);
    let unit = rig.bob_mass * rig.gravity * rig.rod_length;
    sol.samples
        .iter()
        .map(|s| (energy(rig, &s.state) - e0 - s.friction_work.unwrap()).abs() / unit)
        .fold(0.0, f64::max)
}

fn with_work(t_end: f64, n: usize) -> Request {
    Request {
        sample_times: frames(t_end, n),
        friction_work: true,
        positions_only: false,
    }
}

/// Sliding through theta* with mu = 0.9, 0.99, 0.999 mu*: the denominator D - mu |a| nearly
/// vanishes and |N| spikes (the stiff "sudden stopping" regime). The run must finish, never
/// report a paradox below mu*, and keep the energy balance.
#[test]
fn stiff_sliding_near_critical_mu() {
    for r in [1.0, 0.1] {
        for frac in [0.9, 0.99, 0.999] {
            let mu = frac * regions::mu_critical(r);
            let rig = Rig::new(r * 0.1, 0.1, 0.3, 9.81, mu, None).unwrap();
            let th_star = regions::theta_critical(r);
            for method in Method::ALL {
                // Sliding towards +x (s a > 0 below the rail: the branch whose denominator
                // shrinks near theta*), the rod turning through theta*.
                let y0 = [0.0, th_star - 0.4, 3.0, 4.0];
                let sol = run(&rig, y0, 1.0, 1e-10, method, &with_work(1.0, 200));
                assert!(
                    sol.events.iter().all(|e| e.kind != EventKind::Paradox),
                    "r={r} mu/mu*={frac} {method:?}: {:?}",
                    sol.events
                );
                assert_eq!(sol.final_time, 1.0);
                let defect = energy_defect(&rig, &y0, &sol);
                assert!(
                    defect < 1e-7,
                    "r={r} mu/mu*={frac} {method:?}: energy defect {defect:e}"
                );
            }
        }
    }
}

/// The stuck pendulum started at the bottom with angular velocity v (docs/physics.md energy
/// integral l w^2 = l v^2 - 2 g (1 - sin theta)): the largest friction ratio |c| / |b| over
/// the swing, and where it is reached (equal masses). Independent of the simulator.
fn max_ratio_on_swing(rig: &Rig<f64>, v: f64) -> (f64, f64) {
    let (g, l) = (rig.gravity, rig.rod_length);
    let (m1, m2) = (rig.slider_mass, rig.bob_mass);
    let ratio = |th: f64| {
        let lw2 = l * v * v - 2.0 * g * (1.0 - th.sin());
        let (s, c) = th.sin_cos();
        (m2 * c * (g * s + lw2)).abs() / (m1 * g + m2 * g * s * s + m2 * lw2 * s)
    };
    // The swing covers theta in [pi/2, pi - theta_turn]; sample it, then refine by golden
    // section around the best sample.
    let turn = (1.0 - l * v * v / (2.0 * g)).max(-1.0).asin();
    let (lo, hi) = (FRAC_PI_2, PI - turn);
    let n = 4000;
    let k = (0..=n)
        .max_by(|&i, &j| {
            let at = |i: usize| ratio(lo + (hi - lo) * i as f64 / n as f64);
            at(i).total_cmp(&at(j))
        })
        .unwrap();
    let step = (hi - lo) / n as f64;
    let (mut a, mut b) = (
        (lo + step * (k as f64 - 1.0)).max(lo),
        (lo + step * (k as f64 + 1.0)).min(hi),
    );
    let gr = (5f64.sqrt() - 1.0) / 2.0;
    for _ in 0..120 {
        let (c, d) = (b - gr * (b - a), a + gr * (b - a));
        if ratio(c) > ratio(d) {
            b = d;
        } else {
            a = c;
        }
    }
    let th = 0.5 * (a + b);
    (ratio(th), th)
}

/// A trajectory tangent to the stick boundary |c| = mu_s |b|: the launch speed v* from the
/// bottom at which the largest friction ratio over the swing equals mu, found by bisection on
/// the closed-form energy integral. Just below v* the slider never slips (no event, over two
/// periods); just above it slips once near the tangency angle, exactly once per crossing.
#[test]
fn grazing_the_stick_boundary_is_neither_missed_nor_doubled() {
    grazing(&[1e-3]);
}

/// The same closer to tangency (eps = 1e-5, 1e-7): the dip below the stick boundary is
/// narrower than a sixteenth of a step (the loop samples a grazing guard at 16 points per
/// step), and the slip is missed: DOP853 at eps = 1e-5, DP5 at eps = 1e-7 (rtol 1e-10).
#[test]
fn grazing_the_stick_boundary_narrow_dip() {
    grazing(&[1e-5, 1e-7]);
}

fn grazing(epsilons: &[f64]) {
    let mu = 0.5;
    let rig = Rig::paper(mu);
    // The ratio grows with v; the bob stays below the rail for v^2 < 2 g / l.
    let (mut lo, mut hi) = (1.0, (2.0 * rig.gravity / rig.rod_length).sqrt() * 0.999);
    assert!(max_ratio_on_swing(&rig, lo).0 < mu && max_ratio_on_swing(&rig, hi).0 > mu);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if max_ratio_on_swing(&rig, mid).0 < mu {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let v_star = 0.5 * (lo + hi);
    let (_, th_star) = max_ratio_on_swing(&rig, v_star);
    // Turning angle above the horizontal, then the amplitude from hanging.
    let theta_turn = (1.0 - rig.rod_length * v_star * v_star / (2.0 * rig.gravity)).asin();
    let period = exact::stuck_period(&rig, FRAC_PI_2 - theta_turn);
    for method in Method::ALL {
        for &eps in epsilons {
            // Below: four tangencies in two periods, none may produce an event.
            let below = run(
                &rig,
                [0.0, FRAC_PI_2, 0.0, v_star * (1.0 - eps)],
                2.0 * period,
                1e-10,
                method,
                &Request::default(),
            );
            assert!(
                below.events.is_empty(),
                "{method:?} eps={eps}: spurious events {:?}",
                below.events
            );
            // Above: the first event is a slip near the tangency angle, and no crossing is
            // reported twice.
            let above = run(
                &rig,
                [0.0, FRAC_PI_2, 0.0, v_star * (1.0 + eps)],
                0.5 * period,
                1e-10,
                method,
                &Request::default(),
            );
            let first = above
                .events
                .first()
                .unwrap_or_else(|| panic!("{method:?} eps={eps}: the slip was missed"));
            assert_eq!(first.kind, EventKind::Slip, "{method:?} eps={eps}");
            assert!(
                (first.state[1] - th_star).abs() < 30.0 * eps.sqrt(),
                "{method:?} eps={eps}: slip at {} rad, tangency at {th_star} rad",
                first.state[1]
            );
            for w in above.events.windows(2) {
                assert!(
                    w[1].t - w[0].t > 1e-12 && w[0].kind != w[1].kind,
                    "{method:?} eps={eps}: doubled event {:?}",
                    above.events
                );
            }
        }
    }
}

/// Run `f` on another thread and fail the test if it does not finish in `limit`: a hang is a
/// failure of its own, not a stuck CI job.
fn within<T: Send + 'static>(limit: Duration, f: impl FnOnce() -> T + Send + 'static) -> T {
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(f());
    });
    rx.recv_timeout(limit)
        .expect("the simulation hung (no answer within the time limit)")
}

/// Rapid stick-slip: friction just below the largest ratio the resting rig needs, released at
/// that angle, so every stop is followed almost at once by a slip. The run either completes
/// or ends with TooManyEvents; it never hangs, and its work stays bounded.
#[test]
fn chattering_ends_or_is_reported_with_bounded_work() {
    // At rest, equal masses: |c| / |b| = cos s / (1 + s^2), s = sin(theta); its maximum
    // 1 / (2 sqrt 2) = 0.35355 is at sin(theta) = 1 / sqrt 3.
    let th = (1.0 / 3f64.sqrt()).asin();
    for (mu_k, mu_s) in [(0.3535, 0.3535), (0.30, 0.3535), (0.3535, 0.35355)] {
        let rig = Rig::new(0.1, 0.1, 0.3, 9.81, mu_k, Some(mu_s)).unwrap();
        for method in Method::ALL {
            let options = Options {
                rtol: 1e-10,
                atol: 1e-12,
                method,
                max_steps: 200_000,
                max_events: 200,
                ..Options::default()
            };
            let result = within(Duration::from_secs(20), move || {
                simulate(
                    &rig,
                    &[0.0, th, 0.0, 0.0],
                    5.0,
                    &options,
                    &Request::default(),
                )
            });
            match result {
                Ok(sol) => {
                    assert_eq!(sol.final_time, 5.0);
                    assert!(
                        sol.stats.rhs_evals < 13 * 200_000 + 20 * 200,
                        "{:?}",
                        sol.stats
                    );
                }
                Err(SimError::TooManyEvents { t, max, .. }) => {
                    assert_eq!(max, 200);
                    assert!(t > 0.0 && t <= 5.0);
                }
                Err(e) => panic!("mu_k {mu_k} mu_s {mu_s} {method:?}: {e}"),
            }
        }
    }
}

/// 10^4 periods of the stuck pendulum (about 1.1e4 s): the energy integral
/// w^2 - 2 (g/l) sin(theta) drifts by less than 1e-7 of its scale and the phase stays on the
/// exact elliptic solution (about 0.1 s in release).
#[test]
fn ten_thousand_periods_stuck() {
    let rig = Rig::paper(2.5);
    let amplitude = 1.0;
    let period = exact::stuck_period(&rig, amplitude);
    let t_end = 1e4 * period;
    let y0 = [0.0, FRAC_PI_2 - amplitude, 0.0, 0.0];
    let options = Options {
        rtol: 1e-12,
        atol: 1e-14,
        method: Method::Dop853,
        max_steps: 50_000_000,
        // Long-run stability of the integrator is the point: no closed-form shortcut.
        prove_stick: false,
        ..Options::default()
    };
    let req = Request {
        sample_times: (0..=100).map(|k| t_end * k as f64 / 100.0).collect(),
        friction_work: false,
        positions_only: false,
    };
    let sol = simulate(&rig, &y0, t_end, &options, &req).unwrap();
    assert!(sol.events.is_empty());
    let gl = rig.gravity / rig.rod_length;
    let integral = |y: &State<f64>| y[3] * y[3] - 2.0 * gl * y[1].sin();
    let drift = sol
        .samples
        .iter()
        .map(|s| (integral(&s.state) - integral(&y0)).abs() / (2.0 * gl))
        .fold(0.0, f64::max);
    assert!(drift < 1e-7, "energy drift {drift:e}");
    // After 10^4 whole periods the pendulum is back at its release point.
    let y = sol.final_state;
    assert!(
        (y[1] - y0[1]).abs() < 1e-5,
        "phase error: theta {} vs {}",
        y[1],
        y0[1]
    );
}

/// Mass ratios m1/m2 = 1e-3 (mu* = 0.063: a feather slider) and 1e3 (a heavy slider that
/// barely moves): runs finish, stay below the paradox and keep the energy balance.
#[test]
fn extreme_mass_ratios_keep_the_energy_balance() {
    for (r, mu, y0) in [
        (1e-3, 0.03, [0.0, 0.3, 0.0, 0.0]),
        (1e-3, 0.03, [0.0, FRAC_PI_2 - 0.5, 0.0, 0.0]),
        (1e3, 0.35, [0.0, 0.0, 0.0, 0.0]),
        (1e3, 0.01, [0.0, 0.0, 0.05, 6.0]),
    ] {
        assert!(mu < regions::mu_critical(r));
        let rig = Rig::new(r * 0.1, 0.1, 0.3, 9.81, mu, None).unwrap();
        for method in Method::ALL {
            let sol = run(&rig, y0, 2.0, 1e-10, method, &with_work(2.0, 200));
            assert!(
                sol.events.iter().all(|e| e.kind != EventKind::Paradox),
                "r={r}: {:?}",
                sol.events
            );
            let defect = energy_defect(&rig, &y0, &sol);
            assert!(
                defect < 1e-8,
                "r={r} {method:?} y0={y0:?}: defect {defect:e}"
            );
        }
    }
}

/// Full rotations over the top with the normal force changing sign (the bob above the rail,
/// spinning fast): normal_flip events are found, the rod turns more than once, the energy
/// balance holds across every flip.
#[test]
fn rotations_with_normal_flips_keep_the_energy_balance() {
    let rig = Rig::paper(0.1);
    let y0 = [0.0, FRAC_PI_2, 0.5, 25.0];
    for method in Method::ALL {
        let sol = run(&rig, y0, 2.0, 1e-10, method, &with_work(2.0, 400));
        let flips = sol
            .events
            .iter()
            .filter(|e| e.kind == EventKind::NormalFlip)
            .count();
        assert!(flips >= 2, "{method:?}: {:?}", sol.events);
        assert!(
            (sol.final_state[1] - y0[1]).abs() > 2.0 * PI,
            "{method:?}: no full turn"
        );
        let defect = energy_defect(&rig, &y0, &sol);
        assert!(defect < 1e-8, "{method:?}: defect {defect:e}");
    }
}

/// mu = 0 through full rotations: the slider slides throughout and momentum and energy are
/// conserved (the normal force flips do not matter without friction).
#[test]
fn frictionless_rotation_conserves_momentum() {
    let rig = Rig::paper(0.0);
    let y0 = [0.0, FRAC_PI_2, 0.3, 25.0];
    let sol = run(
        &rig,
        y0,
        2.0,
        1e-11,
        Method::Dop853,
        &Request {
            sample_times: frames(2.0, 400),
            friction_work: false,
            positions_only: false,
        },
    );
    let (p0, e0) = (momentum(&rig, &y0), energy(&rig, &y0));
    for s in &sol.samples {
        assert!((momentum(&rig, &s.state) - p0).abs() < 1e-9, "t={}", s.t);
        assert!((energy(&rig, &s.state) - e0).abs() < 1e-9, "t={}", s.t);
    }
    assert!((sol.final_state[1] - y0[1]).abs() > 2.0 * PI);
}

/// mu = 1e6 (far above mu*): from the bottom with the slider at rest, stick holds forever and
/// the motion is the exact pendulum (Jacobi sn/cn), with no paradox reported.
#[test]
fn huge_friction_is_the_exact_pendulum() {
    let rig = Rig::paper(1e6);
    let w0 = (rig.gravity / rig.rod_length).sqrt();
    for v in [2.0, 6.0] {
        // Launched from the bottom at v: amplitude A with 2 w0 sin(A/2) = v, a quarter period
        // after the release from rest.
        let amplitude = 2.0 * (v / (2.0 * w0)).asin();
        let quarter = 0.25 * exact::stuck_period(&rig, amplitude);
        let y0 = [0.0, FRAC_PI_2, 0.0, v];
        let req = Request {
            sample_times: frames(3.0, 60),
            friction_work: false,
            positions_only: false,
        };
        let sol = run(&rig, y0, 3.0, 1e-11, Method::Dop853, &req);
        assert!(sol.events.is_empty(), "v={v}: {:?}", sol.events);
        for s in &sol.samples {
            assert_eq!(s.mode, Mode::Stick);
            let e = exact::stuck_pendulum(&rig, amplitude, s.t + quarter);
            assert!(
                (s.state[1] - e[1]).abs() < 1e-8 && (s.state[3] - e[3]).abs() < 1e-7,
                "v={v} t={}: {:?} vs exact {e:?}",
                s.t,
                s.state
            );
        }
    }
}

/// theta at the edges: released a hair from hanging (pi/2 - 1e-9) the slider sticks and
/// the pendulum oscillates harmonically; released a hair from horizontal (+-1e-12), the
/// timeline is that of the exactly horizontal release to within the perturbation.
#[test]
fn theta_near_hanging_and_near_horizontal() {
    let rig = Rig::paper(0.35);
    let eps = 1e-9;
    let sol = run(
        &rig,
        [0.0, FRAC_PI_2 - eps, 0.0, 0.0],
        2.0,
        1e-10,
        Method::Dop853,
        &Request {
            sample_times: frames(2.0, 40),
            friction_work: false,
            positions_only: false,
        },
    );
    assert!(sol.events.is_empty());
    let w0 = (rig.gravity / rig.rod_length).sqrt();
    for s in &sol.samples {
        let small = FRAC_PI_2 - eps * (w0 * s.t).cos();
        assert!(
            (s.state[1] - small).abs() < 1e-3 * eps,
            "t={}: {} off the harmonic solution",
            s.t,
            s.state[1] - small
        );
        assert_eq!(s.state[0], 0.0);
    }
    let base = run(
        &rig,
        [0.0; 4],
        2.0,
        1e-11,
        Method::Dop853,
        &Request::default(),
    );
    for th in [1e-12, -1e-12] {
        let sol = run(
            &rig,
            [0.0, th, 0.0, 0.0],
            2.0,
            1e-11,
            Method::Dop853,
            &Request::default(),
        );
        assert_eq!(sol.events.len(), base.events.len(), "theta0={th}");
        for (a, b) in sol.events.iter().zip(&base.events) {
            assert_eq!(a.kind, b.kind);
            assert!((a.t - b.t).abs() < 1e-8, "theta0={th}: {} vs {}", a.t, b.t);
        }
    }
}

/// Units: the same rig built in millimetres and in kilometres (l and g scaled, masses too)
/// gives the same dimensionless motion: event times in units of sqrt(l/g), x in units of l,
/// and x' in units of sqrt(g l) agree with the metre rig's.
#[test]
fn unit_scaling_gives_the_same_dimensionless_answer() {
    let base = Rig::paper(0.35);
    let (l0, g0) = (base.rod_length, base.gravity);
    let t0 = (l0 / g0).sqrt();
    let dimless = |rig: &Rig<f64>, y0: State<f64>| {
        let tau = (rig.rod_length / rig.gravity).sqrt();
        let options = Options {
            rtol: 1e-11,
            // atol in the rig's own units: scaled with l for positions.
            atol: 1e-13 * rig.rod_length.min(1.0),
            ..Options::default()
        };
        let sol = simulate(rig, &y0, 2.0 * tau / t0, &options, &Request::default()).unwrap();
        let times: Vec<f64> = sol.events.iter().map(|e| e.t / tau).collect();
        let kinds: Vec<EventKind> = sol.events.iter().map(|e| e.kind).collect();
        let y = sol.final_state;
        let v = (rig.gravity * rig.rod_length).sqrt();
        (
            times,
            kinds,
            [y[0] / rig.rod_length, y[1], y[2] / v, y[3] * tau],
        )
    };
    let reference = dimless(&base, [0.0; 4]);
    assert!(reference.0.len() >= 6);
    // (length scale, gravity scale, mass scale): mm with lunar-ish g, km with 1000 g, ...
    for (ls, gs, ms) in [
        (1e-3, 1.0, 1e-3),
        (1e3, 1.0, 1e3),
        (1e3, 1e3, 1.0),
        (1e-3, 0.165, 1e6),
    ] {
        let rig = Rig::new(0.1 * ms, 0.1 * ms, l0 * ls, g0 * gs, 0.35, None).unwrap();
        let got = dimless(&rig, [0.0; 4]);
        assert_eq!(got.1, reference.1, "scale l x{ls} g x{gs}");
        for (a, b) in got.0.iter().zip(&reference.0) {
            assert!((a - b).abs() < 1e-8, "scale l x{ls} g x{gs}: {a} vs {b}");
        }
        for (a, b) in got.2.iter().zip(&reference.2) {
            assert!(
                (a - b).abs() < 1e-7,
                "scale l x{ls} g x{gs}: {:?} vs {:?}",
                got.2,
                reference.2
            );
        }
    }
}
