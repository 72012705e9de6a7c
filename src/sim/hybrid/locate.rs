//! Locating an event: the one bracketing root finder, and the golden-section search that
//! finds a guard's dip between the samples of a step.

/// Minimum of `g` on [a, b] by golden-section search, to `tol` in the argument.
pub(super) fn golden_min(mut a: f64, mut b: f64, tol: f64, g: impl Fn(f64) -> f64) -> (f64, f64) {
    let r = (5f64.sqrt() - 1.0) / 2.0;
    let (mut c, mut d) = (b - r * (b - a), a + r * (b - a));
    let (mut gc, mut gd) = (g(c), g(d));
    while b - a > tol {
        if gc < gd {
            b = d;
            d = c;
            gd = gc;
            c = b - r * (b - a);
            gc = g(c);
        } else {
            a = c;
            c = d;
            gc = gd;
            d = a + r * (b - a);
            gd = g(d);
        }
        if gc <= 0.0 {
            return (c, gc);
        }
        if gd <= 0.0 {
            return (d, gd);
        }
    }
    if gc < gd {
        (c, gc)
    } else {
        (d, gd)
    }
}

/// Bracketing root finder (Illinois variant of regula falsi): `g(a) > 0 >= g(b)`. Returns the
/// first point found on the violated side, within `tol` of the crossing.
pub(super) fn find_root(
    mut a: f64,
    mut ga: f64,
    mut b: f64,
    mut gb: f64,
    tol: f64,
    g: impl Fn(f64) -> f64,
) -> f64 {
    let mut side = 0;
    for _ in 0..200 {
        if b - a <= tol || gb == 0.0 {
            break;
        }
        let mut c = b - gb * (b - a) / (gb - ga);
        if !(c > a && c < b) {
            c = 0.5 * (a + b);
        }
        let gc = g(c);
        if gc <= 0.0 {
            b = c;
            gb = gc;
            if side == -1 {
                ga *= 0.5;
            }
            side = -1;
        } else {
            a = c;
            ga = gc;
            if side == 1 {
                gb *= 0.5;
            }
            side = 1;
        }
    }
    b
}
