//! Which motion follows a state with the slider at rest (docs/physics.md, "Transitions between the modes"): at t = 0,
//! after a slide stops, and (by the loop) when a stick ends.

use super::{sign, Direction, Mode, Rig, Shorthands, State};

/// The relative size (of g) below which a slide's onset acceleration counts as zero.
const ONSET_ROUNDING: f64 = 1e-9;

/// The motions consistent with a state whose slider is at rest.
#[derive(Debug, Clone, PartialEq)]
pub enum RestChoice {
    /// Exactly one consistent motion.
    Unique(Mode),
    /// Several consistent motions (only above mu*): the future is not unique.
    Indeterminate {
        /// Every consistent motion, stick first when it is one of them.
        alternatives: Vec<Mode>,
    },
    /// No consistent motion was found (a state on the edge of the paradox band).
    Inconsistent,
}

/// Choose the motion from rest: stick while the needed friction is within what the rail holds
/// ([`Rig::stick_margin`]: |c| <= mu_s |b| under Coulomb's law); otherwise slide in the direction s = sign(c) the slider accelerates
/// without friction. Above mu* every candidate is checked for consistency (a slide from rest
/// must accelerate in its own direction on a consistent branch).
pub fn choose_at_rest(rig: &Rig<f64>, y: &State<f64>) -> RestChoice {
    let sh = Shorthands::at(rig, y);
    let stick_ok = rig.stick_margin(&sh) >= 0.0;
    // A slide from rest meets mu(0): mu_k under Coulomb, mu_s under Stribeck, the larger
    // direction's under the direction law.
    let mu_rest = rig.friction_mu(1.0, 0.0).max(rig.friction_mu(-1.0, 0.0));
    let paradox_possible = sh.band_margin(mu_rest) < 0.0;
    // Below mu* a slide that leaves at zero acceleration is still the motion (Stribeck
    // friction meets mu_s at v = 0, so the onset starts from x'' = 0 exactly). The load law
    // computes its stick threshold and its sliding friction by different routes (a power of
    // |b|, a root for |N|), so at the located onset x'' may be a rounding below zero: below
    // mu* the slide is then still the only motion.
    let onset_floor = if paradox_possible {
        0.0
    } else {
        -ONSET_ROUNDING * rig.gravity
    };
    let slide_ok = |dir: Direction| {
        let s = dir.sign();
        let b = rig.slide_branches(&sh, s, 0.0);
        [(b.plus, 1.0), (b.minus, -1.0)].iter().any(|&(ok, sigma)| {
            let acc = s * rig.slide(&sh, s, sigma, 0.0).x_ddot;
            ok && (acc > 0.0 || (!paradox_possible && acc >= onset_floor))
        })
    };
    if !paradox_possible {
        if stick_ok {
            return RestChoice::Unique(Mode::Stick);
        }
        let dir = Direction::of(sign(sh.c));
        return if slide_ok(dir) {
            RestChoice::Unique(Mode::Slide(dir))
        } else {
            RestChoice::Inconsistent
        };
    }
    let mut alternatives = Vec::new();
    if stick_ok {
        alternatives.push(Mode::Stick);
    }
    for dir in [Direction::Positive, Direction::Negative] {
        if slide_ok(dir) {
            alternatives.push(Mode::Slide(dir));
        }
    }
    match alternatives.len() {
        0 => RestChoice::Inconsistent,
        1 => RestChoice::Unique(alternatives[0]),
        _ => RestChoice::Indeterminate { alternatives },
    }
}
