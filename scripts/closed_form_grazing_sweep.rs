// The closed-form stick phases against the integrator at rtol 1e-13 over 2000 releases whose
// friction is 1e-7 to 1e-2 below the largest ratio their level needs (grazing slips), with the
// integrator at 1e-12 against 1e-13 as the baseline. Run outside CI: copy into examples/
// (gitignored) and `cargo run --release --example closed_form_grazing_sweep`.
use appell::model::{Rig, Shorthands};
use appell::sim::{simulate, Options, Request};
use std::f64::consts::TAU;
fn main() {
    let mut s: u64 = 0x1234567887654321;
    let mut rnd = || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    let (mut n, mut bad, mut worst, mut cf, mut base_bad) = (0, 0, 0.0f64, 0, 0);
    for _ in 0..2000 {
        let (m1, m2, l) = (0.05 + rnd() * 0.5, 0.05 + rnd() * 0.3, 0.1 + rnd() * 0.4);
        let base = Rig::new(m1, m2, l, 9.81, 0.5, None).unwrap();
        let th0 = -1.0 + 4.0 * rnd();
        let w0 = (rnd() - 0.5) * 6.0;
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
        let eps = 10f64.powf(-7.0 + 5.0 * rnd());
        let mu = peak * (1.0 - eps);
        let Ok(rig) = Rig::new(m1, m2, l, 9.81, mu, None) else {
            continue;
        };
        let y0 = [0.0, th0, 0.0, w0];
        let none = Request::default();
        let t_end = 3.0;
        let a = simulate(
            &rig,
            &y0,
            t_end,
            &Options {
                rtol: 1e-12,
                atol: 1e-14,
                ..Options::default()
            },
            &none,
        );
        let b = simulate(
            &rig,
            &y0,
            t_end,
            &Options {
                rtol: 1e-13,
                atol: 1e-15,
                prove_stick: false,
                ..Options::default()
            },
            &none,
        );
        let c = simulate(
            &rig,
            &y0,
            t_end,
            &Options {
                rtol: 1e-12,
                atol: 1e-14,
                prove_stick: false,
                ..Options::default()
            },
            &none,
        );
        let (Ok(a), Ok(b), Ok(c)) = (a, b, c) else {
            continue;
        };
        let same_c = c.events.len() == b.events.len()
            && c.events
                .iter()
                .zip(&b.events)
                .all(|(x, y)| x.kind == y.kind);
        if !same_c {
            base_bad += 1;
        }
        n += 1;
        cf += a.stats.closed_form;
        let same = a.events.len() == b.events.len()
            && a.events
                .iter()
                .zip(&b.events)
                .all(|(x, y)| x.kind == y.kind);
        let dt = a
            .events
            .iter()
            .zip(&b.events)
            .map(|(x, y)| (x.t - y.t).abs())
            .fold(0.0, f64::max);
        if !same || dt > 1e-9 {
            bad += 1;
            if bad <= 8 {
                println!("mismatch eps {eps:.1e}: m1 {m1:.3} m2 {m2:.3} l {l:.3} mu {mu:.4} y0 {y0:?}: {} vs {} events, dt {dt:.1e}", a.events.len(), b.events.len());
                for (x, y) in a.events.iter().zip(&b.events).take(3) {
                    println!("   {:?}@{:.12} vs {:?}@{:.12}", x.kind, x.t, y.kind, y.t);
                }
            }
        } else {
            worst = worst.max(dt);
        }
    }
    println!("{n} near-grazing runs, {cf} closed-form phases, {bad} mismatches, worst event dt among matches {worst:.1e}; the integrator at 1e-12 vs 1e-13: {base_bad} event-sequence mismatches");
}
