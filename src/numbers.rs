//! Numbers as a report prints them: a value with its uncertainty to the digits the
//! uncertainty carries ([`value_pm`]), a derived number to seven significant digits
//! ([`plain`]), never the seventeen digits of an `f64` (0.44999999999999996). JSON keeps full
//! precision; these are for text.

/// The decimal exponent of `x` as its shortest decimal form writes it (1e-4 is -4, not the
/// -4.000001 a floating log10 may give).
fn exponent(x: f64) -> i32 {
    format!("{:e}", x.abs())
        .split('e')
        .nth(1)
        .and_then(|e| e.parse().ok())
        .unwrap_or(0)
}

/// `value +- sd` at the precision the uncertainty gives: `sd` to two significant digits and
/// `value` rounded to the same decimal place (0.2500075936848947 +- 0.00003547460156057993
/// reads `0.250008 +- 0.000035`; 12345.6 +- 230 reads `12350 +- 230`). Numbers below 1e-4 or
/// from 1e6 up share one power of ten: `(3.142 +- 0.026)e-7`. Without a usable deviation
/// (zero, infinite, not a number) both numbers are printed as [`plain`] gives them.
///
/// ```
/// use appell::numbers::value_pm;
/// assert_eq!(value_pm(0.2500075936848947, 0.00003547460156057993), "0.250008 +- 0.000035");
/// assert_eq!(value_pm(3.14159e-7, 2.6e-9), "(3.142 +- 0.026)e-7");
/// assert_eq!(value_pm(0.25, 0.0), "0.25 +- 0");
/// ```
pub fn value_pm(value: f64, sd: f64) -> String {
    if !(value.is_finite() && sd.is_finite() && sd > 0.0) {
        return format!("{} +- {}", plain(value), plain(sd));
    }
    // Two significant digits (9.96e-5 rounds to 1.0e-4: its exponent is taken after that).
    let sd2: f64 = format!("{sd:.1e}").parse().unwrap_or(sd);
    let last = exponent(sd2) - 1;
    // Rounded to that place through its decimal text (1000 * 1e-7 is 9.999999999999999e-5,
    // "0.0001000" parses to 1e-4).
    let mut v = if last < 0 {
        let d = (-last) as usize;
        format!("{value:.d$}").parse().unwrap_or(value)
    } else {
        let scale = 10f64.powi(last);
        (value / scale).round() * scale
    };
    if v == 0.0 {
        v = 0.0; // not -0
    }
    let top = exponent(v.abs().max(sd2));
    if (-4..6).contains(&top) {
        let d = (-last).max(0) as usize;
        format!("{v:.d$} +- {sd2:.d$}")
    } else {
        let d = (top - last).max(0) as usize;
        let m = 10f64.powi(top);
        format!("({:.d$} +- {:.d$})e{top}", v / m, sd2 / m)
    }
}

/// A number without an uncertainty to seven significant digits, as briefly as that allows
/// (0.44999999999999996 reads `0.45`, 449.9999972682611 reads `450`), in scientific notation
/// below 1e-4 and from 1e6 up (`2.5e-7`); `0`, `inf` and `NaN` as they are.
///
/// ```
/// use appell::numbers::plain;
/// assert_eq!(plain(0.44999999999999996), "0.45");
/// assert_eq!(plain(2.5e-7), "2.5e-7");
/// ```
pub fn plain(x: f64) -> String {
    significant(x, 7)
}

/// A number to `digits` significant digits (at least one), as briefly as that allows, in the
/// notation of [`plain`]: for a derived figure whose own spread is a few per cent (an
/// expected chi-square, a chance), where seven digits would claim a precision it lacks.
///
/// ```
/// use appell::numbers::significant;
/// assert_eq!(significant(1234.5678, 2), "1200");
/// assert_eq!(significant(0.0123456, 2), "0.012");
/// assert_eq!(significant(3.0e7, 2), "3e7");
/// ```
pub fn significant(x: f64, digits: usize) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{}", if x == 0.0 { 0.0 } else { x });
    }
    let d = digits.max(1) - 1;
    let rounded: f64 = format!("{x:.d$e}").parse().unwrap_or(x);
    if (-4..6).contains(&exponent(rounded)) {
        format!("{rounded}")
    } else {
        format!("{rounded:e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_uncertainty_sets_the_digits() {
        // The issue's example, and the fit's (docs' README answer line).
        assert_eq!(
            value_pm(0.2500075936848947, 0.00003547460156057993),
            "0.250008 +- 0.000035"
        );
        assert_eq!(value_pm(0.11992163, 4.932e-5), "0.119922 +- 0.000049");
        assert_eq!(value_pm(0.2517570, 0.0424), "0.252 +- 0.042");
        assert_eq!(value_pm(0.25, 0.05), "0.250 +- 0.050");
        // A deviation that rounds up into a new digit: 0.0996 is 0.10 to two digits.
        assert_eq!(value_pm(0.31234, 0.0996), "0.31 +- 0.10");
        // Errors of 10 and more: the value rounded to the tens, no decimal point.
        assert_eq!(value_pm(12345.6, 230.0), "12350 +- 230");
        assert_eq!(value_pm(12345.6, 23.0), "12346 +- 23");
        // An error larger than the value.
        assert_eq!(value_pm(0.127, 7.1), "0.1 +- 7.1");
        assert_eq!(value_pm(-0.0004, 0.2), "0.00 +- 0.20");
        assert_eq!(value_pm(-0.25, 0.05), "-0.250 +- 0.050");
    }

    #[test]
    fn very_large_and_small_numbers_share_a_power_of_ten() {
        assert_eq!(value_pm(3.14159e-7, 2.6e-9), "(3.142 +- 0.026)e-7");
        assert_eq!(value_pm(6.02214e23, 1.2e20), "(6.0221 +- 0.0012)e23");
        assert_eq!(value_pm(2.0e-9, 3.0e-7), "(0.0 +- 3.0)e-7");
        // 1e-4 and 999999 are still written out; the exponent is the decimal one, exactly.
        assert_eq!(value_pm(1.0e-4, 1.0e-6), "0.0001000 +- 0.0000010");
        assert_eq!(value_pm(999_999.0, 12.0), "999999 +- 12");
        assert_eq!(value_pm(1_000_000.0, 12.0), "(1.000000 +- 0.000012)e6");
    }

    #[test]
    fn without_a_usable_deviation_the_numbers_are_plain() {
        assert_eq!(value_pm(0.25, 0.0), "0.25 +- 0");
        assert_eq!(value_pm(0.44999999999999996, f64::INFINITY), "0.45 +- inf");
        assert_eq!(value_pm(0.12, f64::NAN), "0.12 +- NaN");
        assert_eq!(value_pm(f64::NAN, 0.1), "NaN +- 0.1");
    }

    #[test]
    fn plain_numbers_carry_seven_digits() {
        assert_eq!(plain(0.44999999999999996), "0.45");
        assert_eq!(plain(449.9999972682611), "450");
        assert_eq!(plain(0.0006666666707), "0.0006666667");
        assert_eq!(plain(2.5e-7), "2.5e-7");
        assert_eq!(plain(1.23456789e9), "1.234568e9");
        assert_eq!(plain(-0.0), "0");
        assert_eq!(plain(0.3), "0.3");
    }
}
