//! What skipping unrequested work saves: each case times the same run with the skip and with
//! the work done anyway.

use super::median_seconds;
use crate::model::dual::Dual;
use crate::model::{Rig, State};
use crate::sim::{simulate, Options, Request};
use serde::Serialize;

/// One skip and its measured saving.
#[derive(Debug, Clone, Serialize)]
pub struct SkipCase {
    /// What is skipped.
    pub case: &'static str,
    /// Median run time with the skip (s).
    pub with_skip_s: f64,
    /// Median run time doing the work anyway (s).
    pub without_skip_s: f64,
}

/// Time every skip on the paper rig (2 s scenes) and a stuck pendulum (10 s).
pub fn skip_benchmark(batches: usize) -> Vec<SkipCase> {
    let paper = Rig::paper(0.35);
    let rest: State<f64> = [0.0; 4];
    let opts = Options::default();
    let time = |rig: &Rig<f64>, y0: &State<f64>, t: f64, o: &Options, r: &Request| {
        median_seconds(|| simulate(rig, y0, t, o, r), batches, 0.3).unwrap_or(f64::NAN)
    };
    let frames = Request {
        sample_times: (0..=2000).map(|k| k as f64 / 1000.0).collect(),
        friction_work: false,
        positions_only: false,
    };
    let stuck = Rig::paper(2.5);
    let swing: State<f64> = [0.0, 0.4, 0.0, 0.0];
    let dual_time = {
        let rig = paper.lift::<Dual<5>>();
        let y0 = rest.map(Dual::<5>::from);
        median_seconds(
            || simulate(&rig, &y0, 2.0, &opts, &Request::default()),
            batches,
            0.3,
        )
        .unwrap_or(f64::NAN)
    };
    vec![
        SkipCase {
            case:
                "monitoring and integrating a stick phase proven never to slip (closed form; 10 s)",
            with_skip_s: time(&stuck, &swing, 10.0, &opts, &Request::default()),
            without_skip_s: time(
                &stuck,
                &swing,
                10.0,
                &Options {
                    prove_stick: false,
                    ..opts
                },
                &Request::default(),
            ),
        },
        SkipCase {
            case: "integrating the stick phases that end in a slip (closed form; paper scene)",
            with_skip_s: time(&paper, &rest, 2.0, &opts, &Request::default()),
            without_skip_s: time(
                &paper,
                &rest,
                2.0,
                &Options {
                    prove_stick: false,
                    ..opts
                },
                &Request::default(),
            ),
        },
        SkipCase {
            case: "dense samples when only events are asked (paper scene vs 1000 Hz frames)",
            with_skip_s: time(&paper, &rest, 2.0, &opts, &Request::default()),
            without_skip_s: time(&paper, &rest, 2.0, &opts, &frames),
        },
        SkipCase {
            case: "friction work when no energy is asked (paper scene)",
            with_skip_s: time(&paper, &rest, 2.0, &opts, &Request::default()),
            without_skip_s: time(
                &paper,
                &rest,
                2.0,
                &opts,
                &Request {
                    friction_work: true,
                    ..Request::default()
                },
            ),
        },
        SkipCase {
            case: "sensitivities outside fitting (paper scene, f64 vs 5 dual directions)",
            with_skip_s: time(&paper, &rest, 2.0, &opts, &Request::default()),
            without_skip_s: dual_time,
        },
    ]
}
