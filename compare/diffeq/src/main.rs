//! Standalone benchmark: appell's paper scene solved with the `differential-equations` crate.
//!
//! The stick/slide equations, the friction-cone test and the switching events are ported from
//! `scripts/bench/compare_scipy.py` (itself an independent re-derivation of `docs/physics.md`), and
//! the hybrid run is integrated with `differential-equations` 0.7's DOP853 (rtol 1e-10,
//! atol 1e-12). Every mode switch is a terminal event detected by the crate's `EventSolout`;
//! the integration is restarted there in the new mode, exactly as the scipy script does with
//! `solve_ivp`.
//!
//! Two defects of the crate 0.7.0 bear on this scene (see NOTES.md for the details):
//!
//! 1. **Dense output.** `Interpolation::interpolate` of the Dormand-Prince family evaluates the
//!    degree-7 correction of DOP853 with `s` and `1 - s` swapped (`conpar` of Hairer's `CONTD8`
//!    is evaluated at `1 - s`). The interpolant is exact at both ends of a step and wrong
//!    inside it, by far more than the tolerance.
//! 2. **Event root finding.** Its Brent-Dekker loop overwrites the contrapoint with the last
//!    iterate (`a = b; ... c = a`), so the bracket is lost after the first iteration; the loop is
//!    then an unguarded secant/bisection between the last two iterates and stops when they are
//!    close, which need not be at a root (and returns `None`, silently dropping the event, after
//!    50 iterations).
//!
//! The `fixed` variant (the one timed against appell) keeps the crate's integration and its
//! step-wise event *detection* (the crate stops the solve at the end of the step in which the
//! event function changed sign), and then, inside that last step only:
//!
//! * rebuilds the correct DOP853 interpolant from the crate's wrong one: with `Q` the cubic
//!   Hermite part and `W(s) = s^2 (1-s)^2` (symmetric in `s <-> 1-s`), the crate returns
//!   `P_bad(s) = Q(s) + W(s) C(1-s)` where the true interpolant is `P(s) = Q(s) + W(s) C(s)`,
//!   so `P(s) = Q(s) - Q(1-s) + P_bad(1-s)`; `Q` needs the derivatives at both step ends (two
//!   extra right-hand-side evaluations per event, counted in the statistics);
//! * locates the earliest falling zero of every event function of the mode with a correct
//!   Brent root finder on that interpolant (the crate's own root is discarded).
//!
//! The `as-is` variant uses the crate's event times and states unchanged, to show the effect.
//!
//! Usage: `diffeq-compare [--appell BIN] [--scene TOML] [--batches N] [--batch-seconds S]
//! [--json] [--no-bench] [--dense-check]`.

use std::hint::black_box;
use std::process::Command;
use std::time::Instant;

use differential_equations::methods::{DormandPrince, Ordinary};
use differential_equations::ode::{solve_ode, OrdinaryNumericalMethod};
use differential_equations::prelude::*;
use differential_equations::solout::{EventSolout, EventWrappedSolout};

/// State: x, theta (y down, 0 = rod horizontal), x', theta'.
type Y4 = [f64; 4];
/// The crate's DOP853 on a 4-vector.
type Dop853 = ExplicitRungeKutta<Ordinary, DormandPrince, f64, Y4, 8, 12, 16>;

// The paper scene (configs/paper_rest_horizontal.toml), as in compare_scipy.py.
const M1: f64 = 0.1;
const M2: f64 = 0.1;
const L: f64 = 0.30;
const G: f64 = 9.81;
const MU_K: f64 = 0.35;
const MU_S: f64 = 0.35;
const Y0: Y4 = [0.0, 0.0, 0.0, 0.0];
const T_END: f64 = 2.0;
const RTOL: f64 = 1e-10;
const ATOL: f64 = 1e-12;

/// sin and cos of the physics: std's (glibc's) by default, or with `--features libm-trig`
/// the libm crate's (musl's kernels), which appell's own physics uses since issue 40, so that
/// the two can be compared with the same trigonometry.
#[inline(always)]
fn sin_cos(x: f64) -> (f64, f64) {
    #[cfg(feature = "libm-trig")]
    return libm::sincos(x);
    #[cfg(not(feature = "libm-trig"))]
    return x.sin_cos();
}

/// cos, as [`sin_cos`].
#[inline(always)]
fn cos(x: f64) -> f64 {
    #[cfg(feature = "libm-trig")]
    return libm::cos(x);
    #[cfg(not(feature = "libm-trig"))]
    return x.cos();
}

/// D, a, b, c, Q of physics.md.
#[inline]
fn shorthands(theta: f64, w: f64) -> (f64, f64, f64, f64, f64) {
    let (s, c_) = sin_cos(theta);
    let d = M1 + M2 * c_ * c_;
    let a = M2 * s * c_;
    let b = -(M1 * G + M2 * G * s * s + M2 * L * w * w * s);
    let c = M2 * c_ * (G * s + L * w * w);
    let q = -M1 * ((M1 + M2) * G + M2 * L * w * w * s);
    (d, a, b, c, q)
}

fn sign(v: f64) -> f64 {
    if v < 0.0 {
        -1.0
    } else {
        1.0
    }
}

/// Friction-cone margin: >= 0 while static friction can hold the slider.
fn stick_margin(y: &Y4) -> f64 {
    let (_, _, b, c, _) = shorthands(y[1], y[3]);
    MU_S * b.abs() - c.abs()
}

/// Slider held: only the pendulum about a fixed pivot.
struct Stick;
impl ODE<f64, Y4> for Stick {
    fn diff(&self, _t: f64, y: &Y4, dy: &mut Y4) {
        *dy = [0.0, y[3], 0.0, G / L * cos(y[1])];
    }
}

/// Slider sliding in direction `s`, normal force of sign `sigma`.
struct Slide {
    s: f64,
    sigma: f64,
}
impl ODE<f64, Y4> for Slide {
    fn diff(&self, _t: f64, y: &Y4, dy: &mut Y4) {
        let (sn, cs) = sin_cos(y[1]);
        let (d, a, b, c, _) = shorthands(y[1], y[3]);
        let k = MU_K * self.s * self.sigma;
        let xdd = (c - k * b) / (d + k * a);
        let tdd = (G * cs + sn * xdd) / L;
        *dy = [y[2], y[3], xdd, tdd];
    }
}

/// The event functions; all terminal, falling direction (like the scipy script).
#[derive(Clone, Copy)]
enum Ev {
    /// Stick: the friction-cone margin.
    Slip,
    /// Slide: `s * x'` (the slider stops).
    Stop { s: f64 },
    /// Slide: `sigma * Q` (the normal force changes sign).
    Flip { sigma: f64 },
}
impl Ev {
    fn g(&self, y: &Y4) -> f64 {
        match *self {
            Ev::Slip => stick_margin(y),
            Ev::Stop { s } => s * y[2],
            Ev::Flip { sigma } => sigma * shorthands(y[1], y[3]).4,
        }
    }
}
impl Event<f64, Y4> for Ev {
    fn config(&self) -> EventConfig {
        EventConfig::new(CrossingDirection::Negative, Some(1))
    }
    fn event(&self, _t: f64, y: &Y4) -> f64 {
        self.g(y)
    }
}

#[derive(Clone, Copy, PartialEq, Debug)]
enum Mode {
    Stick,
    Slide(f64),
}

/// How event times are obtained.
#[derive(Clone, Copy, PartialEq)]
enum Variant {
    /// The crate's event time and interpolated state, unchanged.
    AsIs,
    /// Crate detection; root re-found on the repaired interpolant (see the module doc).
    Fixed,
}

#[derive(Clone, Debug)]
struct EventRec {
    t: f64,
    kind: &'static str,
    state: Y4,
    /// The event time the crate itself reported for this switch.
    t_crate: f64,
    /// Diagnostics (only with `Run::diagnose`): the crate's root-finding loop (a verbatim
    /// copy) on the repaired interpolant, and a correct Brent on the crate's interpolant.
    t_crate_root_repaired_dense: f64,
    t_good_root_crate_dense: f64,
}

#[derive(Clone, Debug, Default)]
struct Run {
    events: Vec<EventRec>,
    final_state: Y4,
    rhs_evals: usize,
    accepted: usize,
    rejected: usize,
    /// Extra right-hand-side evaluations of the workaround (included in `rhs_evals`).
    extra_evals: usize,
    /// Fill the diagnostic fields of the events (not in timed runs).
    diagnose: bool,
    /// Diagnostics of the last event: (crate root on repaired dense, good root on crate dense).
    diag: (f64, f64),
}

/// Cubic Hermite part of the DOP853 interpolant (`cont[0..3]` of Hairer's CONTD8).
fn hermite(y0: &Y4, y1: &Y4, f0: &Y4, f1: &Y4, h: f64, s: f64) -> Y4 {
    let s1 = 1.0 - s;
    let mut out = [0.0; 4];
    for i in 0..4 {
        let c1 = y1[i] - y0[i];
        let c2 = h * f0[i] - c1;
        let c3 = c1 - h * f1[i] - c2;
        out[i] = y0[i] + s * (c1 + s1 * (c2 + s * c3));
    }
    out
}

/// The last accepted step of the crate's solver, with the repaired dense output.
struct Step<'a> {
    m: &'a mut Dop853,
    tp: f64,
    tc: f64,
    yp: Y4,
    yc: Y4,
    fp: Y4,
    fc: Y4,
}
impl Step<'_> {
    /// Correct DOP853 dense output: `Q(s) - Q(1-s) + P_bad(1-s)`.
    fn y(&mut self, t: f64) -> Y4 {
        let h = self.tc - self.tp;
        if t <= self.tp {
            return self.yp;
        }
        if t >= self.tc {
            return self.yc;
        }
        let s = (t - self.tp) / h;
        let tm = (self.tp + (1.0 - s) * h).clamp(self.tp, self.tc);
        let sm = (tm - self.tp) / h;
        let bad = self.m.interpolate(tm).expect("inside the step");
        let q = hermite(&self.yp, &self.yc, &self.fp, &self.fc, h, s);
        let qm = hermite(&self.yp, &self.yc, &self.fp, &self.fc, h, sm);
        std::array::from_fn(|i| q[i] - qm[i] + bad[i])
    }
}

/// Brent's method (as in Brent 1973 / Numerical Recipes `zbrent`) on a bracket with
/// `f(a) * f(b) <= 0`; converges to the bracket's width of a few ulps of `t`.
fn brent(mut f: impl FnMut(f64) -> f64, mut a: f64, mut b: f64, mut fa: f64, mut fb: f64) -> f64 {
    if fa == 0.0 {
        return a;
    }
    if fb == 0.0 {
        return b;
    }
    let (mut c, mut fc) = (b, fb);
    let (mut d, mut e) = (b - a, b - a);
    for _ in 0..200 {
        if (fb > 0.0) == (fc > 0.0) {
            c = a;
            fc = fa;
            d = b - a;
            e = d;
        }
        if fc.abs() < fb.abs() {
            a = b;
            b = c;
            c = a;
            fa = fb;
            fb = fc;
            fc = fa;
        }
        let tol = 2.0 * f64::EPSILON * b.abs() + 0.5e-15;
        let xm = 0.5 * (c - b);
        if xm.abs() <= tol || fb == 0.0 {
            return b;
        }
        if e.abs() >= tol && fa.abs() > fb.abs() {
            let s = fb / fa;
            let (mut p, mut q);
            if a == c {
                p = 2.0 * xm * s;
                q = 1.0 - s;
            } else {
                let qq = fa / fc;
                let r = fb / fc;
                p = s * (2.0 * xm * qq * (qq - r) - (b - a) * (r - 1.0));
                q = (qq - 1.0) * (r - 1.0) * (s - 1.0);
            }
            if p > 0.0 {
                q = -q;
            }
            p = p.abs();
            let min1 = 3.0 * xm * q - (tol * q).abs();
            let min2 = (e * q).abs();
            if 2.0 * p < min1.min(min2) {
                e = d;
                d = p / q;
            } else {
                d = xm;
                e = d;
            }
        } else {
            d = xm;
            e = d;
        }
        a = b;
        fa = fb;
        b += if d.abs() > tol { d } else { tol.copysign(xm) };
        fb = f(b);
    }
    b
}

/// Verbatim port (to f64 and a closure) of the crate 0.7.0's `EventSolout::brent_dekker`,
/// bug included (the contrapoint `c` is overwritten by the previous iterate), for diagnosis.
fn crate_brent(
    mut f: impl FnMut(f64) -> f64,
    mut a: f64,
    mut b: f64,
    mut fa: f64,
    mut fb: f64,
) -> Option<f64> {
    if fa.abs() < fb.abs() {
        std::mem::swap(&mut a, &mut b);
        std::mem::swap(&mut fa, &mut fb);
    }
    let (mut c, mut fc) = (a, fa);
    let mut d = b - a;
    let mut e = d;
    let (rel_tol, abs_tol) = (1e-12, 1e-14);
    for _ in 0..50 {
        if fb == 0.0 {
            return Some(b);
        }
        if fa.signum() == fb.signum() {
            a = c;
            fa = fc;
            c = b;
            fc = fb;
            d = b - a;
            e = d;
        }
        if fa.abs() < fb.abs() {
            c = b;
            b = a;
            a = c;
            fc = fb;
            fb = fa;
            fa = fc;
        }
        let tol = f64::max(abs_tol, rel_tol * b.abs());
        let m = 0.5 * (a - b);
        if m.abs() <= tol || fb == 0.0 {
            return Some(b);
        }
        let mut use_bisection = true;
        if e.abs() > tol && fa.abs() > fb.abs() {
            let s = fb / fa;
            let (p, q) = if a == c {
                (2.0 * m * s, 1.0 - s)
            } else {
                let q1 = fa / fc;
                let r = fb / fc;
                (
                    s * (2.0 * m * q1 * (q1 - r) - (b - a) * (r - 1.0)),
                    (q1 - 1.0) * (r - 1.0) * (s - 1.0),
                )
            };
            let (mut p, mut q) = (p, q);
            if q > 0.0 {
                p = -p;
            } else {
                q = -q;
            }
            if (2.0 * p).abs() < (3.0 * m * q - (tol * q).abs()) && p < (e * 0.5 * q).abs() {
                e = d;
                d = p / q;
                use_bisection = false;
            }
        }
        if use_bisection {
            d = m;
            e = m;
        }
        a = b;
        fa = fb;
        b += if d.abs() > tol { d } else { tol.copysign(m) };
        fb = f(b);
        c = a;
        fc = fa;
    }
    None
}

/// Solves one mode from `(t, y)` until `T_END` or the first terminal event.
/// Returns `Some((t_event, y_event, index of the event, crate's t))` or `None` at `T_END`.
fn solve_phase(
    m: &mut Dop853,
    t: f64,
    y: &Y4,
    mode: Mode,
    sigma: f64,
    variant: Variant,
    run: &mut Run,
) -> Option<(f64, Y4, usize, f64)> {
    m.h0 = 0.0; // otherwise `init` reuses the previous phase's initial step
    let stick = Stick;
    let slide = match mode {
        Mode::Slide(s) => Slide { s, sigma },
        Mode::Stick => Slide { s: 1.0, sigma },
    };
    let evs: Vec<Ev> = match mode {
        Mode::Stick => vec![Ev::Slip],
        Mode::Slide(s) => vec![Ev::Stop { s }, Ev::Flip { sigma }],
    };
    let ode: &dyn ODE<f64, Y4> = match mode {
        Mode::Stick => &stick,
        Mode::Slide(_) => &slide,
    };
    let sol = match mode {
        Mode::Stick => {
            let mut so = EventSolout::new(&evs[0], t, T_END);
            solve_ode(m, ode, t, T_END, y, &mut so)
        }
        Mode::Slide(_) => {
            let base = EventSolout::new(&evs[0], t, T_END);
            let mut so = EventWrappedSolout::new(base, &evs[1], t, T_END);
            solve_ode(m, ode, t, T_END, y, &mut so)
        }
    }
    .expect("crate's DOP853 failed");
    run.rhs_evals += sol.evals.function;
    run.accepted += sol.steps.accepted;
    run.rejected += sol.steps.rejected;
    if !matches!(sol.status, Status::Interrupted) {
        run.final_state = *m.y();
        return None;
    }
    let (&t_crate, &y_crate) = sol.last().expect("an event point");
    if variant == Variant::AsIs {
        // Which event: the one nearest zero at the crate's point.
        let i = (0..evs.len())
            .min_by(|&i, &j| {
                evs[i]
                    .g(&y_crate)
                    .abs()
                    .total_cmp(&evs[j].g(&y_crate).abs())
            })
            .unwrap();
        return Some((t_crate, y_crate, i, t_crate));
    }
    // Fixed: the crate stopped at the end of the step with the sign change.
    let (tp, tc, yp, yc) = (m.t_prev(), m.t(), *m.y_prev(), *m.y());
    let (mut fp, mut fc) = ([0.0; 4], [0.0; 4]);
    ode.diff(tp, &yp, &mut fp);
    ode.diff(tc, &yc, &mut fc);
    run.rhs_evals += 2;
    run.extra_evals += 2;
    let mut step = Step {
        m,
        tp,
        tc,
        yp,
        yc,
        fp,
        fc,
    };
    let mut best: Option<(f64, usize)> = None;
    for (i, ev) in evs.iter().enumerate() {
        let (ga, gb) = (ev.g(&yp), ev.g(&yc));
        if ga > 0.0 && gb <= 0.0 {
            let te = brent(|tt| ev.g(&step.y(tt)), tp, tc, ga, gb);
            if best.is_none_or(|(tb, _)| te < tb) {
                best = Some((te, i));
            }
        }
    }
    let (te, i) = best.expect("the crate stopped without a sign change in its last step");
    if run.diagnose {
        let ev = evs[i];
        let (ga, gb) = (ev.g(&yp), ev.g(&yc));
        let t1 = crate_brent(|tt| ev.g(&step.y(tt)), tp, tc, ga, gb).unwrap_or(f64::NAN);
        let t2 = brent(|tt| ev.g(&step.m.interpolate(tt).unwrap()), tp, tc, ga, gb);
        run.diag = (t1, t2);
    }
    Some((te, step.y(te), i, t_crate))
}

/// The hybrid run, restarted at each switch (the logic of compare_scipy.py's `simulate`).
///
/// A fresh solver per run: the crate's `init` does not reset the solver's step counter, so a
/// solver reused over many runs ends in `Error::MaxSteps` (see NOTES.md).
fn simulate(variant: Variant, diagnose: bool) -> Run {
    let m = &mut new_solver();
    let mut run = Run {
        diagnose,
        diag: (f64::NAN, f64::NAN),
        ..Run::default()
    };
    let (mut t, mut y) = (0.0, Y0);
    let (_, _, b, c, _) = shorthands(y[1], y[3]);
    let mut mode = if MU_S * b.abs() - c.abs() >= 0.0 {
        Mode::Stick
    } else {
        Mode::Slide(sign(c))
    };
    while t < T_END {
        let sigma = sign(shorthands(y[1], y[3]).4);
        let Some((te, ye, hit, t_crate)) = solve_phase(m, t, &y, mode, sigma, variant, &mut run)
        else {
            return run;
        };
        t = te;
        y = ye;
        let (_, _, b, c, _) = shorthands(y[1], y[3]);
        let kind = match mode {
            Mode::Stick => {
                mode = Mode::Slide(sign(c));
                "slip"
            }
            Mode::Slide(s) if hit == 0 => {
                y[2] = 0.0;
                if MU_S * b.abs() - c.abs() >= 0.0 {
                    mode = Mode::Stick;
                    "stick"
                } else {
                    let k = if sign(c) == s {
                        "continuation"
                    } else {
                        "reversal"
                    };
                    mode = Mode::Slide(sign(c));
                    k
                }
            }
            Mode::Slide(_) => "normal_flip",
        };
        run.events.push(EventRec {
            t,
            kind,
            state: y,
            t_crate,
            t_crate_root_repaired_dense: run.diag.0,
            t_good_root_crate_dense: run.diag.1,
        });
        if run.events.len() > 1000 {
            panic!("too many events");
        }
    }
    run.final_state = y;
    run
}

fn new_solver() -> Dop853 {
    ExplicitRungeKutta::dop853()
        .rtol(RTOL)
        .atol(ATOL)
        .max_steps(1_000_000)
}

/// Median wall time per scene over `batches` batches of about `batch_s` seconds each.
/// Returns (median, min, max) in microseconds and the runs per batch.
fn bench(variant: Variant, batches: usize, batch_s: f64) -> (f64, f64, f64, usize) {
    // Calibrate.
    let t0 = Instant::now();
    let mut n = 0usize;
    while t0.elapsed().as_secs_f64() < 0.05 {
        black_box(simulate(variant, false));
        n += 1;
    }
    let per = t0.elapsed().as_secs_f64() / n as f64;
    let runs = ((batch_s / per).ceil() as usize).max(1);
    let mut us: Vec<f64> = (0..batches)
        .map(|_| {
            let t0 = Instant::now();
            for _ in 0..runs {
                black_box(simulate(black_box(variant), false));
            }
            t0.elapsed().as_secs_f64() / runs as f64 * 1e6
        })
        .collect();
    us.sort_by(f64::total_cmp);
    (us[us.len() / 2], us[0], us[us.len() - 1], runs)
}

/// appell's events and final state from `BIN simulate --json SCENE`.
fn appell_reference(bin: &str, scene: &str) -> Result<(Vec<(f64, String)>, Y4), String> {
    let out = Command::new(bin)
        .args(["simulate", "--json", scene])
        .output()
        .map_err(|e| format!("running {bin}: {e}"))?;
    if !out.status.success() {
        return Err(format!(
            "{bin} failed: {}",
            String::from_utf8_lossy(&out.stderr)
        ));
    }
    let v: serde_json::Value =
        serde_json::from_slice(&out.stdout).map_err(|e| format!("appell JSON: {e}"))?;
    let events = v["events"]
        .as_array()
        .ok_or("no events array")?
        .iter()
        .map(|e| {
            (
                e["t"].as_f64().unwrap_or(f64::NAN),
                e["kind"].as_str().unwrap_or("?").to_string(),
            )
        })
        .collect();
    let f = &v["final"];
    let fin = ["x", "theta", "x_dot", "theta_dot"].map(|k| f[k].as_f64().unwrap_or(f64::NAN));
    Ok((events, fin))
}

/// Demonstrates the dense-output defect on a problem with a known solution: the harmonic
/// oscillator x'' = -x, x(0) = 1, integrated over one step; prints the largest interpolation
/// error of the crate's `interpolate` and of the repaired interpolant inside that step.
fn dense_check() -> serde_json::Value {
    struct Osc;
    impl ODE<f64, Y4> for Osc {
        fn diff(&self, _t: f64, y: &Y4, dy: &mut Y4) {
            *dy = [y[1], -y[0], 0.0, 0.0];
        }
    }
    struct AtT(f64);
    impl Event<f64, Y4> for AtT {
        fn config(&self) -> EventConfig {
            EventConfig::new(CrossingDirection::Both, Some(1))
        }
        fn event(&self, t: f64, _y: &Y4) -> f64 {
            t - self.0
        }
    }
    // Stop after the first step that passes t = 0.05; look at that last step.
    let mut m = new_solver();
    let ev = AtT(0.05);
    let mut so = EventSolout::new(&ev, 0.0, 10.0);
    let y0 = [1.0, 0.0, 0.0, 0.0];
    let _ = solve_ode(&mut m, &Osc, 0.0, 10.0, &y0, &mut so);
    let (tp, tc, yp, yc) = (m.t_prev(), m.t(), *m.y_prev(), *m.y());
    let (mut fp, mut fc) = ([0.0; 4], [0.0; 4]);
    Osc.diff(tp, &yp, &mut fp);
    Osc.diff(tc, &yc, &mut fc);
    let mut e_crate = 0.0f64;
    let mut e_fixed = 0.0f64;
    let mut e_end = ((yc[0] - tc.cos()).abs()).max((yc[1] + tc.sin()).abs());
    e_end = e_end.max((yp[0] - tp.cos()).abs());
    let mut step = Step {
        m: &mut m,
        tp,
        tc,
        yp,
        yc,
        fp,
        fc,
    };
    for k in 1..100 {
        let t = tp + (tc - tp) * k as f64 / 100.0;
        let bad = step.m.interpolate(t).unwrap();
        let good = step.y(t);
        e_crate = e_crate.max((bad[0] - t.cos()).abs().max((bad[1] + t.sin()).abs()));
        e_fixed = e_fixed.max((good[0] - t.cos()).abs().max((good[1] + t.sin()).abs()));
    }
    serde_json::json!({
        "problem": "x'' = -x, x(0)=1, x'(0)=0; the step containing t = 0.05, 99 interior points",
        "step": [tp, tc],
        "max_error_at_step_ends": e_end,
        "max_error_crate_interpolate": e_crate,
        "max_error_repaired_interpolant": e_fixed,
    })
}

fn fmt_events(run: &Run, reference: Option<&[(f64, String)]>) {
    for (i, e) in run.events.iter().enumerate() {
        let extra = match reference.and_then(|r| r.get(i)) {
            Some((ta, ka)) => format!(
                "  appell {ta:.12} {ka:<6} diff {:+.2e}; crate's t {:+.2e}, crate root on repaired dense {:+.2e}, good root on crate dense {:+.2e}",
                e.t - ta,
                e.t_crate - ta,
                e.t_crate_root_repaired_dense - ta,
                e.t_good_root_crate_dense - ta,
            ),
            None => String::new(),
        };
        println!(
            "  {:.12} s  {:<12} theta {:9.4} deg{extra}",
            e.t,
            e.kind,
            e.state[1].to_degrees()
        );
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let opt = |name: &str| {
        args.iter()
            .position(|a| a == name)
            .and_then(|i| args.get(i + 1).cloned())
    };
    let flag = |name: &str| args.iter().any(|a| a == name);
    let appell = opt("--appell").unwrap_or_else(|| "target/release/appell".into());
    let scene = opt("--scene").unwrap_or_else(|| "configs/paper_rest_horizontal.toml".into());
    let batches: usize = opt("--batches").map_or(7, |s| s.parse().expect("--batches N"));
    let batch_s: f64 = opt("--batch-seconds").map_or(0.2, |s| s.parse().expect("--batch-seconds"));
    let json = flag("--json");

    let reference = match appell_reference(&appell, &scene) {
        Ok(r) => Some(r),
        Err(e) => {
            eprintln!("no appell reference: {e}");
            None
        }
    };
    let mut result = serde_json::json!({
        "crate": "differential-equations 0.7.0, ExplicitRungeKutta::dop853",
        "rtol": RTOL, "atol": ATOL,
    });
    for variant in [Variant::AsIs, Variant::Fixed] {
        let name = if variant == Variant::AsIs {
            "as_is"
        } else {
            "fixed"
        };
        let run = simulate(variant, true);
        let mut v = serde_json::json!({
            "rhs_evals": run.rhs_evals,
            "extra_rhs_evals_of_workaround": run.extra_evals,
            "steps_accepted": run.accepted,
            "steps_rejected": run.rejected,
            "events": run.events.iter().map(|e| serde_json::json!({
                "t": e.t, "kind": e.kind, "t_crate": e.t_crate, "state": e.state,
                "t_crate_root_on_repaired_dense": e.t_crate_root_repaired_dense,
                "t_good_root_on_crate_dense": e.t_good_root_crate_dense,
            })).collect::<Vec<_>>(),
            "final_state": run.final_state,
        });
        if let Some((ev, fin)) = &reference {
            let same_kinds = ev.len() == run.events.len()
                && ev.iter().zip(&run.events).all(|(a, b)| a.1 == b.kind);
            let dt = ev
                .iter()
                .zip(&run.events)
                .map(|(a, b)| (a.0 - b.t).abs())
                .fold(0.0, f64::max);
            let dfin = (0..4)
                .map(|i| (fin[i] - run.final_state[i]).abs())
                .fold(0.0, f64::max);
            v["appell_event_count"] = ev.len().into();
            v["same_event_kinds_as_appell"] = same_kinds.into();
            v["max_event_time_difference_s"] = dt.into();
            v["max_final_state_difference"] = dfin.into();
        }
        if !json {
            println!(
                "{name}: {} events, {} rhs evals ({} for the workaround), {} steps accepted, {} rejected",
                run.events.len(),
                run.rhs_evals,
                run.extra_evals,
                run.accepted,
                run.rejected
            );
            fmt_events(&run, reference.as_ref().map(|r| r.0.as_slice()));
            println!(
                "  final state {}",
                run.final_state.map(|v| format!("{v:.12}")).join(" ")
            );
            if reference.is_some() {
                println!(
                    "  vs appell: same kinds {}, max |dt_event| {:.2e} s, max |d final state| {:.2e}",
                    v["same_event_kinds_as_appell"],
                    v["max_event_time_difference_s"].as_f64().unwrap(),
                    v["max_final_state_difference"].as_f64().unwrap()
                );
            }
        }
        if !flag("--no-bench") {
            let (med, lo, hi, runs) = bench(variant, batches, batch_s);
            v["median_us_per_scene"] = med.into();
            v["batch_min_us"] = lo.into();
            v["batch_max_us"] = hi.into();
            v["batches"] = batches.into();
            v["runs_per_batch"] = runs.into();
            if !json {
                println!(
                    "  time: median {med:.2} us per scene ({batches} batches of {runs} runs; batches {lo:.2} .. {hi:.2} us)"
                );
            }
        }
        result[name] = v;
    }
    if flag("--dense-check") {
        let d = dense_check();
        if !json {
            println!("dense output check: {d}");
        }
        result["dense_check"] = d;
    }
    if let Some((ev, fin)) = &reference {
        result["appell"] = serde_json::json!({"events": ev, "final_state": fin});
    }
    if json {
        println!("{}", serde_json::to_string_pretty(&result).unwrap());
    }
}
