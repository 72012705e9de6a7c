//! Reports: readable timelines, JSON objects and CSV tables, each written whole or not at all.

pub mod fit;
pub mod inspect;
pub mod joint;
pub mod overlay;
pub mod plan;
pub mod plot;
pub mod regions;
mod simulate;

pub use simulate::{closed_form_note, simulation_json, timeline, write_trajectory_csv};

/// A p-value as a report says it: `p = 0.226` from 0.001 up, `p = 3.0e-9` below, and
/// `p < 1e-16` below what double precision resolves (never `p = 0.0e0`).
pub fn p_is(p: f64) -> String {
    if p.is_nan() {
        "p = -".to_owned()
    } else if p < 1e-16 {
        "p < 1e-16".to_owned()
    } else if p < 1e-3 {
        format!("p = {p:.1e}")
    } else {
        format!("p = {p:.3}")
    }
}

/// The unit a report prints after a parameter's value: a tilt, fitted in radians, is also
/// given in degrees, the unit of the rig file's `rail_tilt_deg` a lab reads it against.
pub fn unit_of(q: crate::fit::Param, value: f64) -> String {
    if q == crate::fit::Param::RailTilt {
        format!("rad ({:.3} deg)", value.to_degrees())
    } else {
        q.unit().to_owned()
    }
}

/// A standard error as a percentage of its value with two significant digits (`0.0014%`,
/// `0.12%`, `3.4%`, `210%`; never `0.00%`), `-` for a value of zero.
pub fn percent_of(se: f64, value: f64) -> String {
    let pc = 100.0 * se / value.abs();
    if !pc.is_finite() {
        return "-".to_owned();
    }
    match two_digit_decimals(pc) {
        Some(d) => format!("{pc:.d$}%", d = d.min(10)),
        None => "0%".to_owned(),
    }
}

/// Decimal places that show `x` to two significant digits (none for 10 and up); `None` for
/// zero, a negative or a value that is not finite.
pub fn two_digit_decimals(x: f64) -> Option<usize> {
    (x.is_finite() && x > 0.0).then(|| (1.0 - x.log10().floor()).max(0.0) as usize)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn p_values_and_percentages_read_as_numbers() {
        assert_eq!(p_is(0.2261), "p = 0.226");
        assert_eq!(p_is(3.0e-9), "p = 3.0e-9");
        assert_eq!(p_is(0.0), "p < 1e-16");
        assert_eq!(percent_of(4.194e-6, 0.30000335), "0.0014%");
        assert_eq!(percent_of(4.932e-5, 0.11992163), "0.041%");
        assert_eq!(percent_of(2.701e-4, -0.000616), "44%");
        assert_eq!(percent_of(1e-3, 0.0), "-");
    }
}
