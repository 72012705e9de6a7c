//! The models' weights by the Bayesian information criterion and the spread of mu_kinetic
//! across the models they leave in play (the interval's share of model uncertainty).

use super::selection::ModelRow;

/// Each converged, plausible model's weight w_i = exp(-dBIC_i / (2 c)) / sum, the Bayesian information
/// criterion's approximation to the posterior probability of the model (Burnham and Anderson,
/// "Model selection and multimodel inference", 6.4), with the chi-squares divided by the
/// chosen model's reduced chi-square `c` (at least 1: their quasi-likelihood correction for
/// overdispersion). A model that misfits overstates every chi-square difference by that
/// factor, which would make one model look certain. A model fitted twice (the same
/// nuisances) counts once.
pub fn model_weights(rows: &mut [ModelRow], c: f64) {
    let mut seen = std::collections::HashSet::new();
    let mut total = 0.0;
    for r in rows.iter_mut() {
        r.weight = 0.0;
        let mut set: Vec<&str> = r.name.split('+').collect();
        set.sort_unstable();
        if r.failed.is_some()
            || (r.implausible && !r.chosen)
            || !r.delta_bic.is_finite()
            || !seen.insert(set.join("+"))
        {
            continue;
        }
        r.weight = (-0.5 * r.delta_bic / c).exp();
        total += r.weight;
    }
    if total > 0.0 {
        rows.iter_mut().for_each(|r| r.weight /= total);
    }
}

/// Occam's window: the least weight, relative to the best model's, that a model needs to count
/// in mu's spread across models (e^-3, a BIC 6 behind).
const OCCAM: f64 = 0.049_787_068_367_863_944;

/// [`OCCAM`]'s window in BIC: a model this far behind the best carries no weight in mu's
/// spread, and the report no longer calls it alike.
pub(super) const OCCAM_BIC: f64 = 6.0;

/// The spread of mu_kinetic across the models the weights leave in play (within [`OCCAM`]): sum w_i (mu_i -
/// mu)^2 around the chosen model's `mu`, and the models that carry it (the chosen one, and
/// each that gives a tenth of the sum or more).
/// Added in quadrature to the chosen model's variance it gives the unconditional standard
/// error (Burnham and Anderson, eq. 4.9, with the chosen model's value for the average).
pub fn model_spread(rows: &[ModelRow], mu: f64) -> (f64, Vec<String>) {
    // Occam's window (Madigan and Raftery): a model whose weight is below e^-3 of the best's
    // (6 in BIC, where the report stops calling two laws alike) is left out. Every law is now
    // weighed outright, and on clean recordings viscous friction or the direction law 6-9
    // units behind, whose mu_kinetic trades off against their own parameter, had widened
    // the interval 2-4 times.
    let best = rows.iter().map(|r| r.weight).fold(0.0, f64::max);
    let in_window = |r: &&ModelRow| r.weight >= best * OCCAM;
    let var = rows
        .iter()
        .filter(in_window)
        .filter(|r| r.weight > 0.0 && r.mu_kinetic.is_finite())
        .map(|r| r.weight * (r.mu_kinetic - mu).powi(2))
        .sum();
    let names = rows
        .iter()
        .filter(in_window)
        .filter(|r| r.weight > 0.0 && r.mu_kinetic.is_finite())
        .filter(|r| r.chosen || r.weight * (r.mu_kinetic - mu).powi(2) >= 0.1 * var)
        .map(|r| {
            format!(
                "{} (weight {:.2e}, mu_kinetic {:.6})",
                r.name, r.weight, r.mu_kinetic
            )
        })
        .collect();
    (var, names)
}

/// The models that describe the recording as well as the chosen one: converged, plausible,
/// no more parameters than it, and a chi-square (divided by the chosen one's reduced
/// chi-square `c` when above 1) no further above the chosen's than a likelihood-ratio test at
/// 1 % allows for the parameters they lack (one, for as many). Two explanations that fit
/// alike (a marker off the rod's line and a rail tilt) are both adequate, whatever the
/// criterion's small preference: mu's interval must hold both. Returns the largest distance
/// of their mu_kinetic from the chosen model's `mu`, and their names.
pub fn adequate_spread(rows: &[ModelRow], mu: f64, c: f64) -> (f64, Vec<String>) {
    use statrs::distribution::{ChiSquared, ContinuousCDF};
    let Some(chosen) = rows.iter().find(|r| r.chosen) else {
        return (0.0, Vec::new());
    };
    let (k, chi2) = (chosen.free.len(), chosen.chi2);
    let mut far = 0.0f64;
    let mut names = Vec::new();
    for r in rows {
        if r.chosen
            || r.failed.is_some()
            || r.implausible
            || !r.mu_kinetic.is_finite()
            || r.free.len() > k
        {
            continue;
        }
        let df = (k - r.free.len()).max(1) as f64;
        let limit = ChiSquared::new(df).map_or(f64::INFINITY, |d| d.inverse_cdf(0.99));
        if (r.chi2 - chi2) / c.max(1.0) <= limit {
            let d = (r.mu_kinetic - mu).abs();
            if d > 0.0 {
                names.push(format!("{} (mu_kinetic {:.6})", r.name, r.mu_kinetic));
            }
            far = far.max(d);
        }
    }
    (far, names)
}

#[cfg(test)]
mod tests {
    use super::{adequate_spread, model_spread, model_weights, ModelRow, OCCAM, OCCAM_BIC};

    /// The weight window and its BIC form are one rule: e^(-BIC/2) at the window's edge.
    #[test]
    fn occams_window_in_weight_and_in_bic_agree() {
        assert!(((-OCCAM_BIC / 2.0).exp() / OCCAM - 1.0).abs() < 1e-15);
    }

    fn row(name: &str, delta_bic: f64, mu: f64, chosen: bool) -> ModelRow {
        ModelRow {
            name: name.to_owned(),
            free: Vec::new(),
            chi2: 0.0,
            bic: delta_bic,
            delta_bic,
            chosen,
            mu_kinetic: mu,
            failed: None,
            weight: 0.0,
            path: false,
            implausible: false,
            stopped_early: false,
        }
    }

    /// Weights exp(-dBIC / 2c): equal criteria share, a model 10 units worse gets e^-5 of the
    /// best's weight (e^-2.5 under an overdispersion c = 2), a failed model and a second fit of
    /// the same nuisances get none; the spread is the weighted variance about the chosen mu.
    #[test]
    fn model_weights_follow_the_criterion() {
        let mut rows = vec![
            row("base", 10.0, 0.20, false),
            row("rail_tilt", 0.0, 0.25, true),
            row("rail_tilt+marker_lag", 0.0, 0.27, false),
            row("marker_lag+rail_tilt", 0.0, 0.27, false),
            ModelRow {
                failed: Some("did not converge".into()),
                ..row("pivot_damping", -50.0, 0.9, false)
            },
        ];
        model_weights(&mut rows, 1.0);
        let total = 2.0 + (-5.0f64).exp();
        assert!((rows[1].weight - 1.0 / total).abs() < 1e-12);
        assert!((rows[2].weight - rows[1].weight).abs() < 1e-12);
        assert!((rows[0].weight / rows[1].weight - (-5.0f64).exp()).abs() < 1e-12);
        assert_eq!(rows[3].weight, 0.0);
        assert_eq!(rows[4].weight, 0.0);
        // The base model, 10 behind, is outside Occam's window (6): its mu does not count.
        let (var, names) = model_spread(&rows, 0.25);
        let want = rows[2].weight * 0.02f64.powi(2);
        assert!((var - want).abs() < 1e-15);
        assert!(!names.iter().any(|n| n.starts_with("base")));
        assert!(names.iter().any(|n| n.starts_with("rail_tilt+marker_lag")));
        assert!(names.iter().any(|n| n.starts_with("rail_tilt ")));
        model_weights(&mut rows, 2.0);
        assert!((rows[0].weight / rows[1].weight - (-2.5f64).exp()).abs() < 1e-12);
        // Under a misfit (c = 2) it is 5 behind, inside the window.
        let (var, _) = model_spread(&rows, 0.25);
        let want = rows[0].weight * 0.05f64.powi(2) + rows[2].weight * 0.02f64.powi(2);
        assert!((var - want).abs() < 1e-15);
    }

    /// Adequate alternatives: as many parameters and a chi-square within the 1 % point of a
    /// one-degree likelihood-ratio test (6.63) count, whatever their weight; a worse one, an
    /// implausible one, or a larger model (which the weights hold) do not.
    #[test]
    fn adequate_alternatives_bound_the_model_spread() {
        let with = |name: &str, k: usize, chi2: f64, mu: f64, chosen: bool| ModelRow {
            free: vec!["p"; k],
            chi2,
            ..row(name, 0.0, mu, chosen)
        };
        let mut rows = vec![
            with("rail_tilt", 6, 1000.0, 0.25, true),
            with("bob_marker_across", 6, 1006.0, 0.26, false),
            with("camera_scale", 6, 1007.0, 0.30, false),
            with("rail_tilt+marker_lag", 7, 999.0, 0.40, false),
            ModelRow {
                implausible: true,
                ..with("rigid_pendulum", 6, 990.0, 0.50, false)
            },
        ];
        let (far, names) = adequate_spread(&rows, 0.25, 1.0);
        assert!((far - 0.01).abs() < 1e-12, "{far}");
        assert_eq!(names.len(), 1);
        // Under a misfit of reduced chi-square 2 the differences count half.
        let (far, _) = adequate_spread(&rows, 0.25, 2.0);
        assert!((far - 0.05).abs() < 1e-12, "{far}");
        rows[0].chosen = false;
        assert_eq!(adequate_spread(&rows, 0.25, 1.0).0, 0.0);
    }
}
