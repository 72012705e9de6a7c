//! The rig file's measurements and the nuisances' plausible ranges set on a problem as priors
//! ([`apply_measured`]), before the base fit's doubling stages and after it.

use super::priors::{self, Plausibility};
use super::problem::{Param, TrajectoryProblem};
use super::settings::FitSettings;
use std::sync::Arc;

/// `stages::measured_rig`'s priors and freed parameters set on `problem` (frames `frame` s apart),
/// without the refit. Returns whether a parameter was freed. A long recording's base fit
/// takes them before its doubling stages, which then fit them on the way (`base.rs`).
pub(super) fn apply_measured(
    problem: &mut TrajectoryProblem,
    frame: f64,
    settings: &FitSettings,
) -> bool {
    let ranges = priors::plausible_ranges(&problem.rig, frame);
    let mut all = priors::nuisance_priors(&ranges);
    // A scale set from a measured length carries that measurement's error, not the range a
    // camera's scale may plausibly be off by.
    if let Some(sd) = settings.scale_sd {
        for pr in all.iter_mut().filter(|pr| pr.param == Param::ScaleError) {
            pr.sd = sd;
        }
    }
    let mut freed = false;
    if let Some(m) = &settings.measured {
        for pr in m.priors() {
            if pr.param == Param::RodLength && settings.fit_rod_length {
                continue;
            }
            all.push(pr);
            if !problem.free.contains(&pr.param) {
                problem.free.push(pr.param);
                freed = true;
            }
        }
    }
    let file_ratio = settings
        .measured
        .as_ref()
        .map_or(problem.rig.mass_ratio(), |m| m.mass_ratio.0);
    problem.priors = Arc::new(all);
    problem.plausible = Arc::new(Plausibility { ranges, file_ratio });
    freed
}
