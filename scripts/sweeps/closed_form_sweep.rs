// The closed-form stick phases (slides at rtol 1e-12) against the integrator at rtol 1e-13
// (physics.md, "Stick phases in closed form"), over two sweeps:
// - 3000 random rigs and releases, a third on tilted rails and some of those under
//   Stribeck's law;
// - 2000 releases whose friction is 1e-7 to 1e-2 below the largest ratio their energy level
//   needs (grazing slips), with the integrator at 1e-12 against 1e-13 as the baseline.
// Run outside CI: copy into examples/ (gitignored) and
// `cargo run --release --example closed_form_sweep`.
use appell::model::{Rig, Shorthands};
use appell::sim::{simulate, Options, Request, Solution};
use std::f64::consts::TAU;

/// Mismatched event sequences and the largest event-time difference among the matched ones.
#[derive(Default)]
struct Tally {
    runs: usize,
    phases: usize,
    mismatches: usize,
    /// Of them, where the integrator at 1e-12 found the tight sequence (the closed form alone
    /// missed it).
    closed_only: usize,
    worst: f64,
    baseline_mismatches: usize,
}

fn same_sequence(a: &Solution<f64>, b: &Solution<f64>) -> bool {
    a.events.len() == b.events.len()
        && a.events
            .iter()
            .zip(&b.events)
            .all(|(x, y)| x.kind == y.kind)
}

impl Tally {
    /// Run `rig` from `y0` closed-form, tight, and (the baseline) integrated at 1e-12.
    fn compare(&mut self, rig: &Rig<f64>, y0: [f64; 4], t_end: f64, what: &str) {
        let none = Request::default();
        let closed = Options {
            rtol: 1e-12,
            atol: 1e-14,
            ..Options::default()
        };
        let integrated = Options {
            prove_stick: false,
            ..closed
        };
        let tight = Options {
            rtol: 1e-13,
            atol: 1e-15,
            ..integrated
        };
        let (Ok(a), Ok(b), Ok(c)) = (
            simulate(rig, &y0, t_end, &closed, &none),
            simulate(rig, &y0, t_end, &tight, &none),
            simulate(rig, &y0, t_end, &integrated, &none),
        ) else {
            return;
        };
        self.runs += 1;
        self.phases += a.stats.closed_form;
        self.baseline_mismatches += usize::from(!same_sequence(&c, &b));
        let dt = a
            .events
            .iter()
            .zip(&b.events)
            .map(|(x, y)| (x.t - y.t).abs())
            .fold(0.0, f64::max);
        if !same_sequence(&a, &b) || dt > 1e-9 {
            self.mismatches += 1;
            self.closed_only += usize::from(same_sequence(&c, &b));
            if self.mismatches <= 10 {
                println!(
                    "mismatch ({what}) y0 {y0:?}: {} vs {} events, dt {dt:.1e}",
                    a.events.len(),
                    b.events.len()
                );
            }
        } else {
            self.worst = self.worst.max(dt);
        }
    }

    fn report(&self, name: &str) {
        println!(
            "{name}: {} runs, {} closed-form phases, {} mismatches ({} where the integrator at \
             1e-12 had none), largest event difference {:.1e} s; the integrator at 1e-12 against \
             1e-13: {} event-sequence mismatches",
            self.runs,
            self.phases,
            self.mismatches,
            self.closed_only,
            self.worst,
            self.baseline_mismatches
        );
    }
}

fn main() {
    let mut s: u64 = 0x9E3779B97F4A7C15;
    let mut rnd = || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut random = Tally::default();
    for _ in 0..3000 {
        let (m1, m2, l, mu) = (
            0.05 + rnd() * 0.5,
            0.05 + rnd() * 0.3,
            0.1 + rnd() * 0.4,
            0.05 + rnd() * 0.9,
        );
        let Ok(mut rig) = Rig::new(m1, m2, l, 9.81, mu, Some(mu * (1.0 + 0.3 * rnd()))) else {
            continue;
        };
        if rnd() < 0.33 {
            rig = rig.with_rail_tilt(0.06 * (rnd() - 0.5));
            if rnd() < 0.33 {
                rig = rig.with_stribeck(0.05);
            }
        }
        let pushed = if rnd() < 0.5 { 0.0 } else { 1.0 };
        let y0 = [
            0.0,
            -1.0 + 4.0 * rnd(),
            (rnd() - 0.5) * 0.5 * pushed,
            (rnd() - 0.5) * 8.0,
        ];
        random.compare(&rig, y0, 0.5 + 2.5 * rnd(), "random");
    }
    random.report("random");
    let mut grazing = Tally::default();
    for _ in 0..2000 {
        let (m1, m2, l) = (0.05 + rnd() * 0.5, 0.05 + rnd() * 0.3, 0.1 + rnd() * 0.4);
        let base = Rig::new(m1, m2, l, 9.81, 0.5, None).unwrap();
        let (th0, w0) = (-1.0 + 4.0 * rnd(), (rnd() - 0.5) * 6.0);
        let gl = 9.81 / l;
        let e = w0 * w0 - 2.0 * gl * th0.sin();
        let peak = (0..100_000)
            .map(|k| th0 + TAU * k as f64 / 100_000.0)
            .filter_map(|th: f64| {
                let w2 = e + 2.0 * gl * th.sin();
                (w2 >= 0.0).then(|| {
                    let sh = Shorthands::new(&base, th, w2.sqrt());
                    sh.c.abs() / sh.b.abs()
                })
            })
            .fold(0.0, f64::max);
        if !(peak > 0.02 && peak < 1.5) {
            continue;
        }
        let mu = peak * (1.0 - 10f64.powf(-7.0 + 5.0 * rnd()));
        if let Ok(rig) = Rig::new(m1, m2, l, 9.81, mu, None) {
            grazing.compare(&rig, [0.0, th0, 0.0, w0], 3.0, "grazing");
        }
    }
    grazing.report("grazing");
}
