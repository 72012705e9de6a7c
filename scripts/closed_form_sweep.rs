// The closed-form stick phases against the integrator at rtol 1e-13 over 3000 random rigs and
// releases, a third on tilted rails and some of those under Stribeck's law (physics.md, "Stick
// phases in closed form"). Run outside CI: copy into examples/ (gitignored) and
// `cargo run --release --example closed_form_sweep`.
use appell::model::Rig;
use appell::sim::{simulate, Options, Request};
fn main() {
    // xorshift
    let mut s: u64 = 0x9E3779B97F4A7C15;
    let mut rnd = || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    let (mut n, mut bad, mut worst) = (0, 0, 0.0f64);
    let mut cf_total = 0;
    for _ in 0..3000 {
        let m1 = 0.05 + rnd() * 0.5;
        let m2 = 0.05 + rnd() * 0.3;
        let l = 0.1 + rnd() * 0.4;
        let mu = 0.05 + rnd() * 0.9;
        let Ok(mut rig) = Rig::new(m1, m2, l, 9.81, mu, Some(mu * (1.0 + 0.3 * rnd()))) else {
            continue;
        };
        // A third on tilted rails, a third of those under Stribeck's law.
        if rnd() < 0.33 {
            rig = rig.with_rail_tilt(0.06 * (rnd() - 0.5));
            if rnd() < 0.33 {
                rig = rig.with_stribeck(0.05);
            }
        }
        let y0 = [
            0.0,
            -1.0 + 4.0 * rnd(),
            (rnd() - 0.5) * 0.5 * if rnd() < 0.5 { 0.0 } else { 1.0 },
            (rnd() - 0.5) * 8.0,
        ];
        let t_end = 0.5 + 2.5 * rnd();
        let none = Request::default();
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
        let (Ok(a), Ok(b)) = (a, b) else { continue };
        n += 1;
        cf_total += a.stats.closed_form;
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
            if bad <= 10 {
                println!("mismatch: m1 {m1:.3} m2 {m2:.3} l {l:.3} mu {mu:.3} y0 {y0:?} t_end {t_end:.2}: {} vs {} events, dt {dt:.1e}", a.events.len(), b.events.len());
                for (x, y) in a.events.iter().zip(&b.events) {
                    println!("   {:?}@{:.12} vs {:?}@{:.12}", x.kind, x.t, y.kind, y.t);
                }
            }
        } else {
            worst = worst.max(dt);
        }
    }
    println!("{n} runs, {cf_total} closed-form phases, {bad} mismatches, worst event dt among matches {worst:.1e}");
}
