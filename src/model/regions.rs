//! Where each model holds: the critical friction mu*, its angle theta*, and the paradox band
//! where the sliding equation has two solutions or none (PHYSICS.md, "The Painleve paradox").

/// Critical friction mu* = 2 sqrt(r (1 + r)) for mass ratio r = m1 / m2: below it the sliding
/// equation has exactly one solution at every angle.
pub fn mu_critical(mass_ratio: f64) -> f64 {
    2.0 * (mass_ratio * (1.0 + mass_ratio)).sqrt()
}

/// The angle theta* in (0, pi/2) where the band opens first: tan^2(theta*) = (1 + r) / r.
pub fn theta_critical(mass_ratio: f64) -> f64 {
    ((1.0 + mass_ratio) / mass_ratio).sqrt().atan()
}

/// The paradox band in the first quadrant, (lo, hi) in radians, where mu |a| > D; `None` when
/// mu <= mu*. The band repeats in every quadrant (|tan theta| is what matters).
pub fn paradox_band(mass_ratio: f64, mu: f64) -> Option<(f64, f64)> {
    let r = mass_ratio;
    let disc = mu * mu - 4.0 * r * (1.0 + r);
    if disc <= 0.0 {
        return None;
    }
    let root = disc.sqrt();
    Some((
        ((mu - root) / (2.0 * r)).atan(),
        ((mu + root) / (2.0 * r)).atan(),
    ))
}

/// The largest mass ratio r = m1 / m2 at which friction `mu` exceeds mu*(r): the inverse of
/// [`mu_critical`], r = (sqrt(1 + mu^2) - 1) / 2.
pub fn max_mass_ratio_for_paradox(mu: f64) -> f64 {
    ((1.0 + mu * mu).sqrt() - 1.0) / 2.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inverse_of_mu_critical() {
        for r in [0.01, 0.05, 0.3, 1.0, 4.0] {
            let mu = mu_critical(r);
            assert!((max_mass_ratio_for_paradox(mu) - r).abs() < 1e-12 * (1.0 + r));
        }
    }
}
