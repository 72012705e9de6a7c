use appell::model::*;
use appell::sim::*;
fn main() {
    let rig = Rig::new(0.5, 0.2, 0.3, 9.81, 0.12, None).unwrap();
    for m in Method::ALL {
        for rtol in [1e-8, 1e-10, 1e-12, 1e-13] {
            let o = Options {
                rtol,
                atol: rtol * 1e-2,
                method: m,
                ..Default::default()
            };
            let s = simulate(
                &rig,
                &[0.0, std::f64::consts::FRAC_PI_2 - 0.9, 0.0, 0.0],
                2.0,
                &o,
                &Request::default(),
            )
            .unwrap();
            println!(
                "{m:?} {rtol:e} {:?}",
                s.events
                    .iter()
                    .map(|e| format!("{:.9}", e.t))
                    .collect::<Vec<_>>()
            );
        }
    }
}
