//! Shared fixtures and independent oracles for the integration tests.

use appell::model::{FrictionLaw, Rig, State};
use appell::sim::{simulate, Method, Options, Request, Solution};
use nalgebra::{Matrix3, Vector3};

/// Run a rig with given tolerance and method, asking for `request`.
pub fn run(
    rig: &Rig<f64>,
    y0: State<f64>,
    t_end: f64,
    rtol: f64,
    method: Method,
    request: &Request,
) -> Solution<f64> {
    let options = Options {
        rtol,
        atol: rtol * 1e-2,
        method,
        ..Options::default()
    };
    simulate(rig, &y0, t_end, &options, request).expect("simulation succeeds")
}

/// Complete elliptic integral of the first kind K(k) by the arithmetic-geometric mean.
pub fn elliptic_k(k: f64) -> f64 {
    let (mut a, mut b) = (1.0, (1.0 - k * k).sqrt());
    for _ in 0..40 {
        let (an, bn) = (0.5 * (a + b), (a * b).sqrt());
        a = an;
        b = bn;
    }
    std::f64::consts::PI / (2.0 * a)
}

/// The sliding-rod model written independently of the library: the generalised equations of
/// motion (docs/physics.md, "Real rigs") as a 3x3 linear system in (x'', theta'', N), written
/// from docs/physics.md without the library's shorthands:
///   (m1 + m2) x'' - m2 l (sin th th'' + cos th w^2) = F + (m1 + m2) g_x
///   l th'' - sin th x'' = g_y cos th - g_x sin th - c_p w / (m2 l)
///   N = m2 l (cos th th'' - sin th w^2) - (m1 + m2) g_y
/// with F = -mu(|x'|, s) s sigma N - c_v x' while sliding (Coulomb, Stribeck, direction). The
/// load law's F = -s mu_k N_0 (|N| / N_0)^n - c_v x' makes the system nonlinear in N: for a
/// trial |N| = u the friction is known and the linear system gives N(u); the consistent u
/// (sigma N(u) = u) is found by a scan and bisection. Returns (x'', theta'').
pub fn slide_accel_oracle(rig: &Rig<f64>, y: &State<f64>, s: f64) -> (f64, f64) {
    let (m1, m2, l) = (rig.slider_mass, rig.bob_mass, rig.rod_length);
    let m = m1 + m2;
    let (gx, gy) = (
        rig.gravity * rig.rail_tilt.sin(),
        rig.gravity * rig.rail_tilt.cos(),
    );
    let v = y[2].abs();
    let (th, w) = (y[1], y[3]);
    let (sn, cs) = th.sin_cos();
    let rhs = Vector3::new(
        m * gx + m2 * l * cs * w * w - rig.viscous_friction * y[2],
        gy * cs - gx * sn - rig.pivot_damping * w / (m2 * l),
        -m2 * l * sn * w * w - m * gy,
    );
    // The linear system with the friction's N-coefficient `k` (F = -k N + f0 on the
    // first row's left side moved right).
    let solve = |k: f64, f0: f64| {
        let a = Matrix3::new(m, -m2 * l * sn, k, -sn, l, 0.0, 0.0, -m2 * l * cs, 1.0);
        let mut r = rhs;
        r[0] += f0;
        a.lu().solve(&r).expect("regular system")
    };
    if rig.friction_law == FrictionLaw::Load {
        let n0 = m * rig.gravity;
        // On the consistent branch g > 0 for small u (N there has the branch's sign) and
        // the first crossing from above is the solution that continues Coulomb's; for n > 1
        // a second, spurious crossing at a huge |N| follows (the law's own paradox).
        let mut found = None;
        for sigma in [1.0, -1.0] {
            let g = |u: f64| {
                let f = -s * rig.mu_kinetic * n0 * (u / n0).powf(rig.load_exponent);
                sigma * solve(0.0, f)[2] - u
            };
            let grid: Vec<f64> = (0..=1200)
                .map(|i| n0 * 1e-9 * 10f64.powf(i as f64 / 100.0))
                .collect();
            if g(grid[0]) <= 0.0 {
                continue;
            }
            let Some(pair) = grid.windows(2).find(|p| g(p[1]) <= 0.0) else {
                continue;
            };
            let (mut a, mut b) = (pair[0], pair[1]);
            for _ in 0..200 {
                let c = 0.5 * (a + b);
                if g(c) > 0.0 {
                    a = c;
                } else {
                    b = c;
                }
            }
            let u = 0.5 * (a + b);
            let sol = solve(
                0.0,
                -s * rig.mu_kinetic * n0 * (u / n0).powf(rig.load_exponent),
            );
            assert!(found.is_none(), "two branches of the load law");
            found = Some((sol[0], sol[1]));
        }
        return found.expect("a consistent sliding solution");
    }
    let mu = match rig.friction_law {
        FrictionLaw::Coulomb => rig.mu_kinetic,
        FrictionLaw::Direction => rig.mu_kinetic + s * rig.kinetic_split,
        FrictionLaw::Stribeck => {
            rig.mu_kinetic
                + (rig.mu_static - rig.mu_kinetic) * (-(v / rig.stribeck_velocity).powi(2)).exp()
        }
        FrictionLaw::Load => unreachable!("solved above"),
    };
    let mut found = None;
    for sigma in [1.0, -1.0] {
        let sol = solve(mu * s * sigma, 0.0);
        if sol[2] * sigma >= 0.0 {
            assert!(found.is_none(), "two solutions: paradox regime");
            found = Some((sol[0], sol[1]));
        }
    }
    found.expect("a consistent sliding solution")
}

/// Classical fixed-step RK4 on the oracle's sliding model from `y0` until x' reaches zero;
/// the crossing is located on the cubic Hermite interpolant of x' (using x'' as slope).
pub fn oracle_slide_until_stop(rig: &Rig<f64>, y0: [f64; 4], s: f64, h: f64) -> (f64, [f64; 4]) {
    let f = |y: &[f64; 4]| {
        let (xdd, tdd) = slide_accel_oracle(rig, y, s);
        [y[2], y[3], xdd, tdd]
    };
    let add =
        |y: &[f64; 4], k: &[f64; 4], c: f64| std::array::from_fn::<f64, 4, _>(|i| y[i] + c * k[i]);
    let (mut t, mut y) = (0.0, y0);
    loop {
        let k1 = f(&y);
        let k2 = f(&add(&y, &k1, h / 2.0));
        let k3 = f(&add(&y, &k2, h / 2.0));
        let k4 = f(&add(&y, &k3, h));
        let y1: [f64; 4] =
            std::array::from_fn(|i| y[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]));
        if y1[2] * s <= 0.0 {
            let (v0, v1, a0, a1) = (y[2], y1[2], k1[2] * h, f(&y1)[2] * h);
            let hermite = |u: f64| {
                let (u2, u3) = (u * u, u * u * u);
                (2.0 * u3 - 3.0 * u2 + 1.0) * v0
                    + (u3 - 2.0 * u2 + u) * a0
                    + (-2.0 * u3 + 3.0 * u2) * v1
                    + (u3 - u2) * a1
            };
            let (mut lo, mut hi) = (0.0, 1.0);
            for _ in 0..80 {
                let mid = 0.5 * (lo + hi);
                if hermite(mid) * s > 0.0 {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            return (t + lo * h, y);
        }
        t += h;
        y = y1;
    }
}

/// A seeded standard normal generator (xorshift64* and Box-Muller): reproducible noise for
/// synthetic recordings without a dependency.
pub struct Normal(u64);

impl Normal {
    /// A generator from a non-zero seed.
    pub fn new(seed: u64) -> Self {
        Normal(seed.max(1))
    }

    fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
    }

    /// One draw from N(0, 1).
    pub fn sample(&mut self) -> f64 {
        let (a, b) = (self.uniform().max(1e-300), self.uniform());
        (-2.0 * a.ln()).sqrt() * (2.0 * std::f64::consts::PI * b).cos()
    }
}

/// A synthetic recording of `rig` from `y0`: markers at `rate` Hz for `duration` s with
/// Gaussian noise `sigma` (m), every `drop_every`-th frame's bob missing (0: none), and
/// `outliers` frames whose bob is displaced by 20 sigma.
#[allow(clippy::too_many_arguments)]
pub fn synthetic(
    rig: &Rig<f64>,
    y0: State<f64>,
    rate: f64,
    duration: f64,
    sigma: f64,
    drop_every: usize,
    outliers: usize,
    seed: u64,
) -> appell::fit::Observations {
    let times: Vec<f64> = (0..=(duration * rate).round() as usize)
        .map(|k| k as f64 / rate)
        .collect();
    let sol = run(
        rig,
        y0,
        duration,
        1e-12,
        Method::Dop853,
        &Request {
            sample_times: times.clone(),
            friction_work: false,
            positions_only: false,
        },
    );
    assert_eq!(sol.samples.len(), times.len());
    let mut rng = Normal::new(seed);
    let mut obs = appell::fit::Observations {
        times,
        slider: vec![],
        bob: vec![],
    };
    for (k, s) in sol.samples.iter().enumerate() {
        let m = appell::model::markers(rig, &s.state);
        let mut n = || sigma * rng.sample();
        obs.slider.push(Some([m[0] + n(), m[1] + n()]));
        let mut bob = [m[2] + n(), m[3] + n()];
        if outliers > 0 && k % (obs.times.len() / outliers).max(1) == 7 {
            bob[0] += 20.0 * sigma;
        }
        obs.bob.push(if drop_every > 0 && k % drop_every == 3 {
            None
        } else {
            Some(bob)
        });
    }
    obs
}

/// The text of an SVG figure: the content of its `<text>` elements joined by spaces, so that a
/// legend line wrapped over several elements reads as written.
pub fn svg_text(svg: &str) -> String {
    let mut out = Vec::new();
    for piece in svg.split("<text").skip(1) {
        let Some(start) = piece.find('>') else {
            continue;
        };
        let body = &piece[start + 1..];
        if let Some(end) = body.find("</text>") {
            out.push(body[..end].trim().to_owned());
        }
    }
    out.join(" ")
}

/// The energy of docs/physics.md with the tilted potential, written out here from the kinetic and
/// potential energies of slider and bob (not the library's `energy`).
pub fn energy_oracle(rig: &Rig<f64>, y: &State<f64>) -> f64 {
    let (m1, m2, l) = (rig.slider_mass, rig.bob_mass, rig.rod_length);
    let (gx, gy) = (
        rig.gravity * rig.rail_tilt.sin(),
        rig.gravity * rig.rail_tilt.cos(),
    );
    let (x, th, xd, w) = (y[0], y[1], y[2], y[3]);
    0.5 * (m1 + m2) * xd * xd - m2 * l * xd * w * th.sin() + 0.5 * m2 * l * l * w * w
        - (m1 + m2) * gx * x
        - m2 * gx * l * th.cos()
        - m2 * gy * l * th.sin()
}

/// The states the acceleration tests sweep: angles, angular velocities and slider velocities
/// (both directions), 6 x 5 x 4 of them.
pub fn slide_states() -> impl Iterator<Item = State<f64>> {
    [0.1, 0.7, 1.4, 2.2, 3.5, 5.0].into_iter().flat_map(|th| {
        [-4.0, -0.5, 0.0, 1.0, 3.0].into_iter().flat_map(move |w| {
            [-0.4f64, -0.02, 0.03, 0.5]
                .into_iter()
                .map(move |xd| [0.1, th, xd, w])
        })
    })
}

/// The library's sliding accelerations at `y` against [`slide_accel_oracle`], to `tol` of
/// the acceleration scale g (1 + w^2 l / g); `name` labels a failure.
pub fn assert_slide_matches_oracle(name: &str, r: &Rig<f64>, y: &State<f64>, tol: f64) {
    let (xd, w) = (y[2], y[3]);
    let s = xd.signum();
    let (xdd, tdd) = slide_accel_oracle(r, y, s);
    let sh = appell::model::Shorthands::at(r, y);
    let sigma = r.slide_sigma(&sh, s, xd).expect("one branch below mu*");
    let d = r.slide(&sh, s, sigma, xd);
    let scale = r.gravity * (1.0 + w * w * r.rod_length / r.gravity);
    assert!(
        (d.x_ddot - xdd).abs() < tol * scale
            && (d.theta_ddot - tdd).abs() < tol * scale / r.rod_length,
        "{name} at {y:?}: ({}, {}) vs ({xdd}, {tdd})",
        d.x_ddot,
        d.theta_ddot
    );
}

/// Release `r` from (0, 0.3, 0.4, 0) for 3 s at rtol 1e-12 with `method`, sampling the works
/// every 50 ms, and check the energy balance E(t) - E(0) = friction work + damping work with
/// [`energy_oracle`]: both works dissipative, the worst defect below 1e-9 of (m1 + m2) g l,
/// and the run both slides and sticks. Returns the run for the caller's own checks.
pub fn assert_energy_balance(name: &str, r: &Rig<f64>, method: Method) -> Solution<f64> {
    let y0 = [0.0, 0.3, 0.4, 0.0];
    let times: Vec<f64> = (0..=60).map(|k| k as f64 * 0.05).collect();
    let request = Request {
        sample_times: times,
        friction_work: true,
        positions_only: false,
    };
    let sol = run(r, y0, 3.0, 1e-12, method, &request);
    let unit = (r.slider_mass + r.bob_mass) * r.gravity * r.rod_length;
    let e0 = energy_oracle(r, &y0);
    let mut worst: f64 = 0.0;
    for s in &sol.samples {
        let (wf, wd) = (s.friction_work.unwrap(), s.damping_work.unwrap());
        assert!(wf <= 1e-12 && wd <= 1e-12, "{name}: works are dissipative");
        let de = energy_oracle(r, &s.state) - e0;
        worst = worst.max((de - wf - wd).abs() / unit);
    }
    assert!(worst < 1e-9, "{name} {method:?}: worst {worst:e}");
    assert!(
        sol.events
            .iter()
            .any(|e| e.kind == appell::sim::EventKind::Stick),
        "{name}: the run slides and sticks: {:?}",
        sol.events
    );
    sol
}
