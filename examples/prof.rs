use appell::model::*;
use appell::sim::*;
fn main() {
    let rig = Rig::paper(0.35);
    let o = Options {
        rtol: 1e-10,
        atol: 1e-12,
        ..Default::default()
    };
    let n = 20000;
    let t0 = std::time::Instant::now();
    for _ in 0..n {
        std::hint::black_box(
            simulate(&rig, &[0.0, 0.0, 0.0, 0.0], 2.0, &o, &Request::default()).unwrap(),
        );
    }
    let mut v = vec![];
    for _ in 0..15 {
        let t0 = std::time::Instant::now();
        for _ in 0..500 {
            std::hint::black_box(
                simulate(&rig, &[0.0, 0.0, 0.0, 0.0], 2.0, &o, &Request::default()).unwrap(),
            );
        }
        v.push(t0.elapsed().as_secs_f64() / 500.0 * 1e6);
    }
    v.sort_by(|a, b| a.partial_cmp(b).unwrap());
    println!(
        "median {:.1} us (warm {:.1})",
        v[7],
        t0.elapsed().as_secs_f64() / n as f64 * 1e6
    );
}
