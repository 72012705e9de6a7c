//! Observability of a simulated release: does each target transition happen inside the
//! recording, away from its first and last frames, with slides long enough for the camera,
//! and does the slider stay on the rail and both markers in view? Every check carries its
//! margin so a report can say by how much it passed.

use super::spec::{PlanSpec, Target};
use crate::model::{Mode, Rig, Shorthands, State, X};
use crate::sim::{EventKind, Outcome, Solution};
use serde::Serialize;

/// A stretch of one mode between two transitions (merged across events that keep the mode,
/// such as a rail-reaction flip or an instantaneous continuation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Segment {
    /// Mode.
    pub mode: Mode,
    /// Start (s).
    pub t0: f64,
    /// End (s).
    pub t1: f64,
    /// Slider position at the start (m).
    pub x0: f64,
    /// Slider position at the end (m).
    pub x1: f64,
    /// State at the end (at the transition that ends it).
    pub end: State<f64>,
}

impl Segment {
    /// Slider travel (m): x is monotone while sliding and constant while stuck, so the ends
    /// say everything.
    pub fn travel(&self) -> f64 {
        (self.x1 - self.x0).abs()
    }
}

/// The run as segments of one mode, and whether it ended at a paradox (with the state there).
pub fn segments(y0: &State<f64>, sol: &Solution<f64>) -> (Vec<Segment>, Option<State<f64>>) {
    let mut mode = sol.events.first().map_or(sol.final_mode, |e| e.from);
    let (mut t0, mut x0) = (0.0, y0[X]);
    let mut out: Vec<Segment> = Vec::new();
    let mut paradox = None;
    let push = |out: &mut Vec<Segment>, seg: Segment| match out.last_mut() {
        Some(last) if last.mode == seg.mode => {
            last.t1 = seg.t1;
            last.x1 = seg.x1;
            last.end = seg.end;
        }
        _ => out.push(seg),
    };
    for e in &sol.events {
        push(
            &mut out,
            Segment {
                mode,
                t0,
                t1: e.t,
                x0,
                x1: e.state[X],
                end: e.state,
            },
        );
        (t0, x0) = (e.t, e.state[X]);
        match &e.to {
            Outcome::Mode(m) => mode = *m,
            _ => {
                paradox = Some(e.state);
                break;
            }
        }
    }
    if paradox.is_none() {
        push(
            &mut out,
            Segment {
                mode,
                t0,
                t1: sol.final_time,
                x0,
                x1: sol.final_state[X],
                end: sol.final_state,
            },
        );
    }
    (out, paradox)
}

/// One observed target transition with its margins.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Hit {
    /// Which target.
    #[serde(serialize_with = "ser_target")]
    pub target: Target,
    /// Time of the transition (s).
    pub t: f64,
    /// Distance to the nearer edge of the allowed window (frames; >= 0 when it passes).
    pub window_margin_frames: f64,
    /// Slider travel of the slide next to it (pixels; the smaller one for a reversal).
    pub travel_px: f64,
    /// Duration of the side before (frames).
    pub frames_before: f64,
    /// Duration of the side after (frames; the rest of the recording when it ends there).
    pub frames_after: f64,
}

fn ser_target<S: serde::Serializer>(t: &Target, s: S) -> Result<S::Ok, S::Error> {
    s.collect_str(t)
}

impl Hit {
    /// The tightest criterion as a ratio to its threshold (>= 1 passes): used to prefer the
    /// clearest of several qualifying transitions.
    fn score(&self, c: &Criteria) -> f64 {
        let r = |v: f64, min: f64| if min > 0.0 { v / min } else { f64::INFINITY };
        r(self.travel_px, c.min_slide_px)
            .min(r(self.frames_before.min(self.frames_after), c.min_frames))
            .min(1.0 + self.window_margin_frames.max(0.0))
    }
}

/// The checks of a plan, in the units the simulator gives (s, m).
#[derive(Debug, Clone, PartialEq)]
pub struct Criteria {
    /// Targets, all required.
    pub targets: Vec<Target>,
    /// Frame rate (Hz).
    pub frame_rate: f64,
    /// m per pixel.
    pub metres_per_pixel: f64,
    /// Allowed window for transitions (s).
    pub window: [f64; 2],
    /// Least slide travel (pixels).
    pub min_slide_px: f64,
    /// Least duration of each side (frames).
    pub min_frames: f64,
    /// Usable rail (m).
    pub rail: [f64; 2],
    /// Field of view (m).
    pub field_of_view: [f64; 2],
    /// Rod length (m): the bob is within l of the slider along the rail.
    pub rod_length: f64,
}

/// A slide ends "suddenly" when the sliding denominator's worst case D - mu |a| has shrunk
/// below this fraction of D: |N| is then several times its value far from the band.
pub const SUDDEN_STOP_BAND_FRACTION: f64 = 0.3;

impl Criteria {
    /// The checks of `spec`.
    pub fn new(spec: &PlanSpec) -> Self {
        let cam = &spec.camera;
        let edge = spec.goal.edge_frames / cam.frame_rate;
        Criteria {
            targets: spec.goal.targets.clone(),
            frame_rate: cam.frame_rate,
            metres_per_pixel: cam.metres_per_pixel,
            window: [edge, cam.duration - edge],
            min_slide_px: spec.goal.min_slide_px,
            min_frames: spec.goal.min_frames,
            rail: spec.release.rail,
            field_of_view: cam.field_of_view,
            rod_length: spec.rig.marker_length,
        }
    }

    fn frames(&self, dt: f64) -> f64 {
        dt * self.frame_rate
    }

    fn window_margin(&self, t: f64) -> f64 {
        self.frames((t - self.window[0]).min(self.window[1] - t))
    }

    fn passes(&self, h: &Hit) -> bool {
        h.window_margin_frames >= 0.0
            && h.travel_px >= self.min_slide_px
            && h.frames_before >= self.min_frames
            && h.frames_after >= self.min_frames
    }

    /// Check every criterion on one run from `y0` with friction `rig`.
    pub fn evaluate(&self, rig: &Rig<f64>, y0: &State<f64>, sol: &Solution<f64>) -> Evaluation {
        let (segs, paradox) = segments(y0, sol);
        let px = |m: f64| m / self.metres_per_pixel;
        // Every transition between two merged segments, classified.
        let mut found: Vec<(EventKind, Hit, State<f64>)> = Vec::new();
        for pair in segs.windows(2) {
            let (a, b) = (&pair[0], &pair[1]);
            let (kind, travel) = match (a.mode, b.mode) {
                (Mode::Stick, Mode::Slide(_)) => (EventKind::Slip, b.travel()),
                (Mode::Slide(_), Mode::Stick) => (EventKind::Stick, a.travel()),
                (Mode::Slide(_), Mode::Slide(_)) => {
                    (EventKind::Reversal, a.travel().min(b.travel()))
                }
                _ => continue,
            };
            found.push((
                kind,
                Hit {
                    target: Target::StickToSlide,
                    t: a.t1,
                    window_margin_frames: self.window_margin(a.t1),
                    travel_px: px(travel),
                    frames_before: self.frames(a.t1 - a.t0),
                    frames_after: self.frames(b.t1 - b.t0),
                },
                a.end,
            ));
        }
        let sudden = |h: &Hit, state: &State<f64>| {
            let sh = Shorthands::at(rig, state);
            let hard = sh.band_margin(rig.mu_kinetic) <= SUDDEN_STOP_BAND_FRACTION * sh.d;
            hard.then_some(*h)
        };
        let hits = self
            .targets
            .iter()
            .map(|&target| {
                let pick = |kind: EventKind| {
                    found
                        .iter()
                        .filter(|(k, h, _)| *k == kind && self.passes(h))
                        .map(|(_, h, _)| Hit { target, ..*h })
                        .max_by(|x, y| x.score(self).total_cmp(&y.score(self)))
                };
                match target {
                    Target::StickToSlide => pick(EventKind::Slip),
                    Target::SlideToStick => pick(EventKind::Stick),
                    Target::Reversal => pick(EventKind::Reversal),
                    Target::StickSlipCycles(n) => found
                        .iter()
                        .filter(|(k, h, _)| *k == EventKind::Stick && self.passes(h))
                        .nth(n as usize - 1)
                        .map(|(_, h, _)| Hit { target, ..*h }),
                    Target::SuddenStop => {
                        let mut best: Option<Hit> = None;
                        let mut consider = |h: Hit| {
                            if best.is_none_or(|b| h.score(self) > b.score(self)) {
                                best = Some(h);
                            }
                        };
                        for (kind, h, state) in &found {
                            if matches!(kind, EventKind::Stick | EventKind::Reversal)
                                && self.passes(h)
                            {
                                if let Some(h) = sudden(h, state) {
                                    consider(Hit { target, ..h });
                                }
                            }
                        }
                        // A run that ends at a paradox while sliding into the band: the slide
                        // before it is the observable part.
                        if let (Some(state), Some(last)) = (paradox, segs.last()) {
                            let h = Hit {
                                target,
                                t: last.t1,
                                window_margin_frames: self.window_margin(last.t1),
                                travel_px: px(last.travel()),
                                frames_before: self.frames(last.t1 - last.t0),
                                frames_after: self.min_frames,
                            };
                            if matches!(last.mode, Mode::Slide(_)) && self.passes(&h) {
                                if let Some(h) = sudden(&h, &state) {
                                    consider(h);
                                }
                            }
                        }
                        best
                    }
                }
            })
            .collect::<Vec<_>>();
        let (lo, hi) = segs
            .iter()
            .flat_map(|s| [s.x0, s.x1])
            .fold((y0[X], y0[X]), |(lo, hi), x| (lo.min(x), hi.max(x)));
        let rail_margin_m = (lo - self.rail[0]).min(self.rail[1] - hi);
        let fov_margin_m = (lo - self.rod_length - self.field_of_view[0])
            .min(self.field_of_view[1] - hi - self.rod_length);
        let ok = hits.iter().all(Option::is_some) && rail_margin_m >= 0.0 && fov_margin_m >= 0.0;
        Evaluation {
            hits,
            rail_margin_m,
            fov_margin_m,
            slider_range: [lo, hi],
            ok,
        }
    }
}

/// The verdict on one run.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Evaluation {
    /// Per target (in the plan's order), the clearest qualifying transition, if any.
    pub hits: Vec<Option<Hit>>,
    /// Least distance of the slider to the rail's ends (m; negative: it leaves the rail).
    pub rail_margin_m: f64,
    /// Least distance of either marker to the field of view's edges, counting the bob anywhere
    /// within a rod length of the slider (m).
    pub fov_margin_m: f64,
    /// Range of the slider's position (m).
    pub slider_range: [f64; 2],
    /// Every target shows and the rig stays on the rail and in view.
    pub ok: bool,
}
