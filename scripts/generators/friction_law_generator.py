#!/usr/bin/env python3
"""Point-pendulum recordings whose rail friction follows different friction laws.

Purpose
-------
A test bench for the fit's choice of friction law: synthetic camera recordings of the three
point-pendulum rigs of scripts/generators/measured_rig_generator.py (light, equal, heavy; rod 0.30 m,
g = 9.81, their standard releases, 2 s at 1 kHz, noise 0.2 mm per coordinate) on rails whose
friction is Coulomb, direction-dependent, load-dependent, or Coulomb on a tilted rail, plus a
heavy-rig campaign (releases and their mirror images) that a joint fit can use to tell a
direction-dependent rail from a tilted one. Independent of the Rust simulator.

It imports scripts/generators/measured_rig_generator.py (rigs, its Ext model with load-dependent friction
and its dispatchers, energy), scripts/generators/misspec_generator.py (Model with rail tilt, hybrid
stick/slide loop `simulate`, `sample_at`, `markers`, `write_csv`, energy) and, through them,
scripts/generators/rigid_generator.py (Newton-Euler rows); nothing is copied. The only new dynamics is the
direction-dependent coefficient (DirModel below), which enters misspec_generator's unchanged
rows and loop through the model's `mu()` and two thin dispatchers around `solve_stuck` /
`solve_sliding` (other models pass through untouched).

Conventions (docs/physics.md, as the imported scripts)
  Dynamics in the rail frame, y DOWN; theta from +x toward +y, theta = pi/2 hangs down.
  Recordings: rail frame, y UP: slider (x, 0), bob (x + l cos theta, -l sin theta), metres.
  Mirror image (x -> -x): (x, theta, x', theta') -> (-x, pi - theta, -x', -theta').
  F is the rail's friction force on the slider along +x; N the rail's normal force (either sign,
  bilateral rail; friction uses |N|); s = sign(x') while sliding.

Laws (true values)
  coulomb    mu_k = mu_s = 0.22 both ways: F = -0.22 s |N|; stuck while |F_needed| <= 0.22 |N|.
  direction  coefficient mu+ = 0.24 while the slider slides toward +x, mu- = 0.20 toward -x,
             static = kinetic in each direction:
               sliding:  F = -mu+ |N| (s = +1),  F = +mu- |N| (s = -1);
               stuck while  -mu+ |N| <= F_needed <= +mu- |N|,
             F_needed the friction that holds the slider (x'' = 0). A slider that would break
             away toward +x (its friction-free acceleration > 0, so F_needed < 0) is held by up
             to mu+ |N|; one that would break away toward -x (F_needed > 0) by up to mu- |N|.
             The breakaway direction is the sign of the friction-free acceleration (= -sign
             F_needed; misspec_generator.slip_direction checks the two agree). Implemented by
             mu() returning mu_cur, set to mu+ or mu- by the sign of F_needed in every stuck
             solve and by s in every sliding solve. mean mu = 0.22, split = (mu+ - mu-)/2 = 0.02.
  load       F = -s c |N|^0.8 sliding, stuck while |F_needed| <= c |N|^0.8,
             c = 0.25 ((m1 + m2) g)^0.2: mu = 0.25 at the static load (measured_rig_generator's
             Ext with load_exp = 0.8).
  tilt       Coulomb mu = 0.22 on a rail tilted by alpha = -asin(0.02) = -1.1459 deg
             (misspec_generator's tilt: gravity in the rail frame, y down, is g (sin alpha,
             cos alpha); +x is downhill for alpha > 0, so here +x is UPHILL; the stuck
             pendulum hangs at theta = pi/2 - alpha, its bob 1.15 deg toward -x). Gravity's
             rail component on the whole rig, (m1 + m2) g sin alpha = -0.02 (m1 + m2) g, adds
             to friction: sliding toward +x the rail-direction force is -(0.22 |N| + 0.02 M g),
             toward -x +(0.22 |N| - 0.02 M g): at |N| = M g (M = m1 + m2) the direction law's
             0.24 / 0.20. The generator measures how far that holds (tilt equivalence).

Releases: the standard ones of measured_rig_generator (light (0, -0.5, 0, 4.0), equal and heavy
(0, 0, 0, 0): rod horizontal at rest). Campaign (heavy rig, laws direction and tilt):
  std (0, 0, 0, 0), mirror (0, pi, 0, 0), wide (0, -0.6, 0, 0): released at rest with the bob
  0.6 rad ABOVE the rail on the +x side (a larger swing: a wider normal-force range), and
  wide_mirror (0, pi + 0.6, 0, 0).

Self-checks (always run; the script exits 1 and says FAILED if one fails)
  energy    E(t) - E(0) = W(t), W = integral F x' dt = -integral |F| |x'| dt (integrated
            alongside; W checked non-increasing), max error <= 1e-6 J, every simulated run.
  mirror    the direction rail (0.24 / 0.20) released mirrored equals the swapped rail (0.20
            toward +x, 0.24 toward -x) released normally, mirrored: state difference <= 1e-8 at
            every frame, same events mirrored; every rig's standard release and the heavy wide
            release. Also tilt alpha mirrored = tilt -alpha mirrored (heavy, both releases).
  neutral   direction law with mu+ = mu- = 0.22, and load law with exponent 1.0 and mu 0.22,
            against coulomb 0.22, every rig: marker positions (what a recording holds) within
            1e-10 m at every frame, the same events at times within 1e-10 s. The direction one
            is identical bit for bit; the load one solves its friction by brentq, a different
            path, so its state differs at the integrator's rtol (velocities up to ~2e-10 rad/s
            on swings of 8-16 rad/s; recorded in truth.json, not gated).
  law       at every frame, from the frame's own solve: sliding, -s F / |N| is the law's
            coefficient for that direction (to 1e-12); stuck, -mu+ |N| <= F_needed <= mu- |N|.
  campaign  every campaign release has at least 4 slides.
  Event timelines, slides per direction (a direction law is identifiable only with slides both
  ways), slide distances and the normal-force range per case go to truth.json.
Tilt equivalence (information, printed and in truth.json): over the tilt run's sliding frames,
  mu_eff = -s (F + M g sin alpha) / |N| per direction (speed-weighted mean and range) against
  0.24 / 0.20, and the largest slider and bob differences between the tilt and direction runs.

Outputs (default --out /tmp/friction; with --ci, seed 1 only into tests/data/friction)
  <law>_<rig>_s<seed>.csv                       4 laws x 3 rigs
  campaign_<law>_heavy_<release>_s<seed>.csv    laws direction, tilt; releases std, mirror,
                                                wide, wide_mirror
  rigs/<rig>.toml        [rig] as measured_rig_generator's <rig>_true_nosd.toml (no friction:
                         the law is the unknown)
  manifest.json, truth.json
  Noise: numpy.random.default_rng(seed).normal(0, 0.0002, (2001, 4)) for <law>_<rig> files and
  the campaign's std release (so campaign_<law>_heavy_std_s<seed>.csv is byte-identical to
  <law>_heavy_s<seed>.csv); default_rng([seed, k]) for campaign release k = 1 (mirror),
  2 (wide), 3 (wide_mirror), as scripts/generators/campaign_generator.py draws release k.

Run (outside CI; Python 3 with numpy and scipy)
    python3 -m venv /tmp/venv-gen && /tmp/venv-gen/bin/pip install numpy scipy
    /tmp/venv-gen/bin/python scripts/generators/friction_law_generator.py                # /tmp/friction
    /tmp/venv-gen/bin/python scripts/generators/friction_law_generator.py --ci           # tests/data/friction
"""

import sys

sys.dont_write_bytecode = True  # leave no __pycache__ in scripts/

import argparse  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import os  # noqa: E402
import platform  # noqa: E402

import numpy as np  # noqa: E402
import scipy  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import measured_rig_generator as mrg  # noqa: E402  (installs its dispatchers into mg)
import misspec_generator as mg  # noqa: E402
import rigid_generator as rg  # noqa: E402

RTOL, ATOL, FPS, DURATION = rg.RTOL, rg.ATOL, rg.FPS, rg.DURATION
NOISE = mrg.NOISE
SEEDS = mrg.SEEDS
RIGS = list(mrg.POINT_RIGS)
REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # scripts/generators/..
CI_OUT = os.path.join(REPO, "tests", "data", "friction")

MU_C = 0.22                              # coulomb, tilt
MU_POS, MU_NEG = 0.24, 0.20              # direction: toward +x, toward -x
MU_LOAD, LOAD_EXP = 0.25, 0.80           # load: mu at the static load, exponent
TILT = -math.asin(0.02)                  # rad; +x uphill
LAWS = ["coulomb", "direction", "load", "tilt"]

WIDE_THETA = -0.6
CAMPAIGN_LAWS = ["direction", "tilt"]
CAMPAIGN_RIG = "heavy"
CAMPAIGN_RELEASES = ["std", "mirror", "wide", "wide_mirror"]   # noise stream k = index

TOL_ENERGY, TOL_MIRROR, TOL_NEUTRAL = 1e-6, 1e-8, 1e-10


# --------------------------------------------------------------------------------------------
# Direction-dependent rail: misspec_generator.Model whose mu() follows the direction
# --------------------------------------------------------------------------------------------
class DirModel(mg.Model):
    """mg.Model (optionally tilted) with coefficient mu_pos toward +x and mu_neg toward -x,
    static = kinetic per direction. mu() returns mu_cur, which the dispatchers below set: in a
    stuck solve from the sign of F_needed (F < 0: the slider would go +x, held by mu_pos),
    in a sliding solve from s. misspec_generator calls mu() only after such a solve (stick
    test, cone ratio, slip event, sliding fold), so every use sees the right direction."""

    def __init__(self, rig, mu_pos, mu_neg, tilt=0.0):
        super().__init__(rig, tilt=tilt)
        self.mu_pos, self.mu_neg = mu_pos, mu_neg
        self.mu_cur = mu_pos

    def mu(self, x):
        return self.mu_cur


_PREV = dict(solve_stuck=mg.solve_stuck, solve_sliding=mg.solve_sliding)


def solve_stuck(md, y):
    sol = _PREV["solve_stuck"](md, y)
    if isinstance(md, DirModel):
        md.mu_cur = md.mu_pos if sol[5] < 0.0 else md.mu_neg
    return sol


def solve_sliding(md, y, s):
    if isinstance(md, DirModel):
        md.mu_cur = md.mu_pos if s > 0 else md.mu_neg
    return _PREV["solve_sliding"](md, y, s)


# misspec_generator's loop, rows and helpers look these up in their module at call time.
mg.solve_stuck, mg.solve_sliding = solve_stuck, solve_sliding


# --------------------------------------------------------------------------------------------
# Models, releases, simulation and its figures
# --------------------------------------------------------------------------------------------
def make_model(law, rig_name, **kw):
    """kw overrides: mu_pos, mu_neg (direction), exp, mu (load / coulomb), tilt (tilt)."""
    if law == "coulomb":
        return mg.Model(mrg.make_rig(rig_name, mu=kw.get("mu", MU_C)))
    if law == "direction":
        mp_, mn_ = kw.get("mu_pos", MU_POS), kw.get("mu_neg", MU_NEG)
        return DirModel(mrg.make_rig(rig_name, mu=0.5 * (mp_ + mn_)), mp_, mn_,
                        tilt=kw.get("tilt", 0.0))
    if law == "load":
        return mrg.Ext(mrg.make_rig(rig_name, mu=kw.get("mu", MU_LOAD)),
                       load_exp=kw.get("exp", LOAD_EXP))
    if law == "tilt":
        return mg.Model(mrg.make_rig(rig_name, mu=kw.get("mu", MU_C)), tilt=kw.get("tilt", TILT))
    raise ValueError(law)


def mirror_state(st):
    x, th, xd, w = st[:4]
    return (0.0 - x, math.pi - th, 0.0 - xd, 0.0 - w)


def release(rig_name, name):
    std = tuple(float(v) for v in mrg.POINT_RIGS[rig_name]["release"])
    wide = (0.0, WIDE_THETA, 0.0, 0.0)
    return {"std": std, "mirror": mirror_state(std), "wide": wide,
            "wide_mirror": mirror_state(wide)}[name]


def run(md, rel, ts):
    segs, evs, _ = mg.simulate(md, rel, DURATION)
    Y = mg.sample_at(md, segs, rel, ts)
    return segs, evs, Y


def frame_forces(md, segs, ts, Y):
    """Per frame: mode ('stick' / 'slide'), s, N and F (the solves of the frame's segment,
    sample_at's rule: a frame on a boundary belongs to the earlier segment)."""
    starts = np.array([sg[0] for sg in segs])
    N, F, S = np.empty(len(ts)), np.empty(len(ts)), np.zeros(len(ts))
    for i, tt in enumerate(ts):
        k = max(0, int(np.searchsorted(starts, tt, side="left")) - 1)
        while k < len(segs) - 1 and tt > segs[k][1]:
            k += 1
        mode, s = segs[k][2], segs[k][3]
        sol = mg.solve_stuck(md, Y[i]) if mode == "stick" else mg.solve_sliding(md, Y[i], s)
        N[i], F[i], S[i] = sol[4], sol[5], (0.0 if mode == "stick" else s)
    return N, F, S


def slides(segs):
    """Maximal sliding runs (segments split only by a sign change of N are merged)."""
    runs = []
    for t0, t1, mode, s, sol in segs:
        if mode != "slide":
            continue
        x0, x1 = float(sol(t0)[0]), float(sol(t1)[0])
        if runs and runs[-1]["s"] == s and abs(runs[-1]["t1"] - t0) < 1e-12:
            runs[-1].update(t1=t1, x1=x1)
        else:
            runs.append(dict(s=int(s), t0=t0, t1=t1, x0=x0, x1=x1))
    for r in runs:
        r["distance_m"] = abs(r["x1"] - r["x0"])
    return runs


def energy_check(md, Y):
    if isinstance(md, mrg.Ext):
        err, works = mrg.energy_error(md, Y)
    else:
        err, works = mg.energy_error(md, Y)
    W = Y[:, 4]
    rise = float(np.max(np.diff(W))) if len(W) > 1 else 0.0
    return float(err), float(works["friction"]), rise


def describe_case(md, segs, evs, Y, ts, rel):
    N, F, S = frame_forces(md, segs, ts, Y)
    runs = slides(segs)
    M = md.rig.m1 + md.rig.m_p
    err, work, rise = energy_check(md, Y)
    ent = dict(
        release=dict(zip(["x", "theta", "x_dot", "theta_dot"], rel)),
        events=[dict(t=float(e["t"]), kind=e["kind"],
                     state=dict(zip(["x", "theta", "x_dot", "theta_dot"],
                                    [float(v) for v in e["state"]])),
                     stuck_cone_ratio=float(e["cone_ratio"])) for e in evs],
        slides=[dict(direction=f"{r['s']:+d}", t_start=float(r["t0"]), t_end=float(r["t1"]),
                     distance_m=float(r["distance_m"])) for r in runs],
        slides_plus=sum(r["s"] > 0 for r in runs), slides_minus=sum(r["s"] < 0 for r in runs),
        slide_distance_plus_m=float(sum(r["distance_m"] for r in runs if r["s"] > 0)),
        slide_distance_minus_m=float(sum(r["distance_m"] for r in runs if r["s"] < 0)),
        sliding_frames_plus=int(np.sum(S > 0)), sliding_frames_minus=int(np.sum(S < 0)),
        slider_x_range_m=[float(Y[:, 0].min()), float(Y[:, 0].max())],
        normal_force_over_static_load=[float(np.min(np.abs(N)) / (M * md.rig.g)),
                                       float(np.max(np.abs(N)) / (M * md.rig.g))],
        normal_force_over_static_load_sliding=(
            [float(np.min(np.abs(N[S != 0])) / (M * md.rig.g)),
             float(np.max(np.abs(N[S != 0])) / (M * md.rig.g))] if np.any(S != 0) else None),
        self_check=dict(energy_max_err_J=err, friction_work_J=work,
                        friction_work_max_rise_per_frame_J=rise,
                        energy_ok=bool(err <= TOL_ENERGY and rise <= 1e-13)))
    ent["law_check"] = law_check(md, N, F, S)
    if isinstance(md, mrg.Ext) and md.slid:
        I = Y[-1, -4:]
        ent["load"] = dict(c=md.c_load, mu_slid_mean=float(I[0] / I[1]),
                           mu_work_weighted=float(I[2] / I[3]))
    return ent, (N, F, S)


def coefficients(md, N):
    """(mu toward +x, mu toward -x) the law prescribes at normal force N (array)."""
    if isinstance(md, DirModel):
        return np.full_like(N, md.mu_pos), np.full_like(N, md.mu_neg)
    if isinstance(md, mrg.Ext) and md.load_exp:
        m = md.c_load * np.abs(N) ** (md.load_exp - 1.0)
        return m, m
    return np.full_like(N, md.rig.mu), np.full_like(N, md.rig.mu)


def law_check(md, N, F, S):
    """The law at every frame, from the frame's own solve: sliding, -s F / |N| equals the
    prescribed coefficient of that direction; stuck, -mu+ |N| <= F <= mu- |N| (the frame's
    F_needed inside the direction-dependent band)."""
    mp_, mn_ = coefficients(md, N)
    sl = S != 0
    want = np.where(S > 0, mp_, mn_)
    dev = (float(np.max(np.abs(-S[sl] * F[sl] / np.abs(N[sl]) - want[sl]))) if np.any(sl)
           else 0.0)
    st = ~sl
    excess = (float(np.max(np.maximum(-mp_[st] * np.abs(N[st]) - F[st],
                                      F[st] - mn_[st] * np.abs(N[st]))))
              if np.any(st) else -math.inf)
    return dict(sliding_max_coefficient_dev=dev, stuck_max_band_excess_N=excess,
                ok=bool(dev <= 1e-12 and excess <= 1e-12))


def timeline(evs):
    return ", ".join(f"{e['kind']} {e['t']:.4f}" for e in evs[1:-1])


# --------------------------------------------------------------------------------------------
# Truth per law
# --------------------------------------------------------------------------------------------
def law_truth(law):
    if law == "direction":
        mp_, mn_, ex, mus, tilt = MU_POS, MU_NEG, 1.0, 0.5 * (MU_POS + MU_NEG), 0.0
    elif law == "load":
        mp_, mn_, ex, mus, tilt = MU_LOAD, MU_LOAD, LOAD_EXP, MU_LOAD, 0.0
    elif law == "tilt":
        mp_, mn_, ex, mus, tilt = MU_C, MU_C, 1.0, MU_C, math.degrees(TILT)
    else:
        mp_, mn_, ex, mus, tilt = MU_C, MU_C, 1.0, MU_C, 0.0
    return dict(mu_kinetic_positive=mp_, mu_kinetic_negative=mn_,
                mu_kinetic=round(0.5 * (mp_ + mn_), 12), split=round(0.5 * (mp_ - mn_), 12),
                load_exponent=ex,
                mu_at_static_load=mus, rail_tilt_deg=tilt, rail_tilt_rad=math.radians(tilt),
                mu_static_equals_kinetic=True)


LAW_TEXT = dict(
    coulomb="F = -0.22 s |N| sliding; stuck while |F_needed| <= 0.22 |N|",
    direction="F = -0.24 |N| sliding toward +x, +0.20 |N| toward -x; stuck while "
              "-0.24 |N| <= F_needed <= +0.20 |N| (breakaway toward +x held by 0.24 |N|, "
              "toward -x by 0.20 |N|; breakaway direction = sign of the friction-free x'')",
    load="F = -s c |N|^0.8 sliding; stuck while |F_needed| <= c |N|^0.8; "
         "c = 0.25 ((m1 + m2) g)^0.2 (mu 0.25 at the static load)",
    tilt="Coulomb 0.22 (as coulomb) on a rail tilted by alpha = -asin(0.02) = -1.1459 deg: "
         "gravity in the rail frame (y down) g (sin alpha, cos alpha), +x uphill",
)


# --------------------------------------------------------------------------------------------
# Rig files
# --------------------------------------------------------------------------------------------
def write_rig(out, name):
    """measured_rig_generator.write_rig_toml's true_nosd file, its provenance comment
    replaced."""
    path = os.path.join(out, "rigs", f"{name}.toml")
    mrg.write_rig_toml(path, name, mrg.make_rig(name), "true", "nosd", None)
    with open(path) as fh:
        lines = fh.read().split("\n")
    assert lines[0].startswith("#") and lines[1].startswith("#"), lines[:2]
    lines[0:2] = [f"# Point-pendulum rig '{name}' of the friction-law recordings, the true "
                  f"values; no friction key:",
                  "# the law is the unknown (made by scripts/generators/friction_law_generator.py; "
                  "truth in truth.json)"]
    with open(path, "w", newline="\n") as fh:
        fh.write("\n".join(lines))
    return os.path.join("rigs", f"{name}.toml")


# --------------------------------------------------------------------------------------------
# Checks
# --------------------------------------------------------------------------------------------
def mirror_diff(Ya, Yb):
    """Max |state_a - mirror(state_b)| over frames (x, theta, x', theta')."""
    Mb = np.column_stack([-Yb[:, 0], math.pi - Yb[:, 1], -Yb[:, 2], -Yb[:, 3]])
    return float(np.max(np.abs(Ya[:, :4] - Mb)))


def mirrored_kinds(evs):
    out = []
    for e in evs:
        k = e["kind"]
        out.append(k.replace("+1", "#").replace("-1", "+1").replace("#", "-1"))
    return out


def tilt_equivalence(md_tilt, segs, Y, ts, Y_dir, evs_tilt, evs_dir):
    """How close tilt (Coulomb 0.22, alpha = -asin 0.02) is to the direction rail 0.24 / 0.20:
    per direction, the effective coefficient of the whole rig's along-rail external force
    during the tilt run's slides, mu_eff = -s (F + M g sin alpha) / |N|, M = m1 + m2."""
    N, F, S = frame_forces(md_tilt, segs, ts, Y)
    M = md_tilt.rig.m1 + md_tilt.rig.m_p
    Ftot = F + M * md_tilt.gx
    out = {}
    for s, nm, target in ((1.0, "plus", MU_POS), (-1.0, "minus", MU_NEG)):
        sel = S == s
        if not np.any(sel):
            out[nm] = None
            continue
        me = -s * Ftot[sel] / np.abs(N[sel])
        wgt = np.abs(Y[sel, 2])
        out[nm] = dict(direction_law_value=target, frames=int(sel.sum()),
                       mu_eff_speed_weighted=float(np.sum(me * wgt) / np.sum(wgt)),
                       mu_eff_frame_mean=float(me.mean()),
                       mu_eff_min=float(me.min()), mu_eff_max=float(me.max()),
                       N_over_Mg_min=float(np.abs(N[sel]).min() / (M * md_tilt.rig.g)),
                       N_over_Mg_max=float(np.abs(N[sel]).max() / (M * md_tilt.rig.g)))
    l = md_tilt.rig.l
    bob = lambda Z: np.column_stack([Z[:, 0] + l * np.cos(Z[:, 1]), -l * np.sin(Z[:, 1])])  # noqa
    out["max_slider_x_diff_m"] = float(np.max(np.abs(Y[:, 0] - Y_dir[:, 0])))
    out["max_bob_diff_m"] = float(np.max(np.hypot(*(bob(Y) - bob(Y_dir)).T)))
    out["timeline_tilt"] = timeline(evs_tilt)
    out["timeline_direction"] = timeline(evs_dir)
    return out


# --------------------------------------------------------------------------------------------
# Main
# --------------------------------------------------------------------------------------------
def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", default=None, help="default /tmp/friction, with --ci "
                                                "tests/data/friction")
    ap.add_argument("--seeds", type=int, nargs="+", default=SEEDS)
    ap.add_argument("--ci", action="store_true", help="seed 1 only, into tests/data/friction")
    args = ap.parse_args(argv)
    out = args.out or (CI_OUT if args.ci else "/tmp/friction")
    seeds = [1] if args.ci else args.seeds
    os.makedirs(os.path.join(out, "rigs"), exist_ok=True)
    n_frames = int(round(DURATION * FPS)) + 1
    ts = np.round(np.arange(n_frames) / FPS, 12)
    ok_all = True
    checks = dict(energy={}, mirror=[], neutral=[])

    def verdict(good):
        nonlocal ok_all
        ok_all &= bool(good)
        return "OK" if good else "FAIL"

    truth = dict(generator="scripts/generators/friction_law_generator.py",
                 based_on=["scripts/generators/measured_rig_generator.py", "scripts/generators/misspec_generator.py",
                           "scripts/generators/rigid_generator.py"],
                 command=" ".join(["scripts/generators/friction_law_generator.py"]
                                  + (sys.argv[1:] if argv is None else list(argv))),
                 python=platform.python_version(), numpy=np.__version__,
                 scipy=scipy.__version__, solver=dict(method="DOP853", rtol=RTOL, atol=ATOL),
                 frame_rate_hz=FPS, duration_s=DURATION, noise_sigma_m=NOISE, seeds=seeds,
                 frame="recordings: rail frame, y up (slider (x, 0), bob (x + l cos theta, "
                       "-l sin theta)); events' states: y down",
                 theta_convention="docs/physics.md: from +x toward y down, pi/2 hangs down",
                 mirror="(x, theta, x', theta') -> (-x, pi - theta, -x', -theta')",
                 sign_conventions="F: rail friction on the slider along +x; s = sign(x'); "
                                  "direction law stuck while -mu+ |N| <= F_needed <= mu- |N|",
                 tilt_convention="gravity in the rail frame (y down) = g (sin alpha, cos alpha);"
                                 " alpha > 0: +x downhill; here alpha < 0: +x uphill",
                 noise="default_rng(seed).normal(0, sigma, (2001, 4)) for <law>_<rig> and the "
                       "campaign's std release; default_rng([seed, k]) for campaign release "
                       "k = 1 mirror, 2 wide, 3 wide_mirror",
                 laws={law: dict(formula=LAW_TEXT[law], **law_truth(law)) for law in LAWS},
                 rigs={}, cases={}, campaign={}, tilt_equivalence={}, self_checks=checks)
    for law in LAWS:
        if law == "load":
            truth["laws"][law]["c_per_rig"] = {
                r: MU_LOAD * ((mrg.POINT_RIGS[r]["m1"] + mrg.POINT_RIGS[r]["m2"]) * mrg.G)
                ** (1.0 - LOAD_EXP) for r in RIGS}
    cases = []
    rig_files = {}
    for name in RIGS:
        rig_files[name] = write_rig(out, name)
        truth["rigs"][name] = dict(m1=mrg.POINT_RIGS[name]["m1"], m2=mrg.POINT_RIGS[name]["m2"],
                                   rod_length=mrg.L_ROD, gravity=mrg.G, rig_file=rig_files[name],
                                   std_release=list(release(name, "std")))

    def write_rec(fname, md, Y, seed, k):
        clean = mg.markers(md, Y, "none")
        rng = np.random.default_rng(seed if k == 0 else [seed, k])
        noise = rng.normal(0.0, NOISE, size=clean.shape)
        mg.write_csv(os.path.join(out, fname), ts, clean + noise)

    def energy_line(key, ent):
        sc = ent["self_check"]
        checks["energy"][key] = dict(max_err_J=sc["energy_max_err_J"],
                                     friction_work_J=sc["friction_work_J"])
        lc = ent["law_check"]
        return (f"energy |E - E0 - W| max {sc['energy_max_err_J']:.1e} J (W "
                f"{sc['friction_work_J'] * 1e3:.3f} mJ) {verdict(sc['energy_ok'])}; law: "
                f"sliding coefficient dev {lc['sliding_max_coefficient_dev']:.1e}, stuck band "
                f"excess {lc['stuck_max_band_excess_N']:.1e} N {verdict(lc['ok'])}")

    # ---- laws x rigs ----------------------------------------------------------------------
    runs = {}
    for law in LAWS:
        for name in RIGS:
            md = make_model(law, name)
            rel = release(name, "std")
            segs, evs, Y = run(md, rel, ts)
            runs[(law, name, "std")] = (md, segs, evs, Y)
            ent, _ = describe_case(md, segs, evs, Y, ts, rel)
            key = f"{law}/{name}"
            truth["cases"][key] = ent
            extra = (f", mu slid-mean {ent['load']['mu_slid_mean']:.5f}" if "load" in ent else "")
            print(f"== {law:<9s} {name:<5s}: slides +{ent['slides_plus']} -{ent['slides_minus']}"
                  f" (+{ent['slide_distance_plus_m'] * 1e3:.1f} / -"
                  f"{ent['slide_distance_minus_m'] * 1e3:.1f} mm), |N|/Mg "
                  f"{ent['normal_force_over_static_load'][0]:.3f}.."
                  f"{ent['normal_force_over_static_load'][1]:.3f}{extra}; "
                  + energy_line(key, ent) + "\n   " + timeline(evs))
            for seed in seeds:
                rec = f"{law}_{name}_s{seed}.csv"
                write_rec(rec, md, Y, seed, 0)
                cases.append(dict(id=f"{law}_{name}_s{seed}", group="law", law=law, rig=name,
                                  seed=seed, release="std",
                                  release_state=list(rel), recording=rec,
                                  rig_file=rig_files[name], truth=law_truth(law),
                                  slides_plus=ent["slides_plus"],
                                  slides_minus=ent["slides_minus"]))

    # ---- campaign ---------------------------------------------------------------------------
    for law in CAMPAIGN_LAWS:
        truth["campaign"][law] = {}
        for k, rname in enumerate(CAMPAIGN_RELEASES):
            rel = release(CAMPAIGN_RIG, rname)
            if (law, CAMPAIGN_RIG, rname) in runs:
                md, segs, evs, Y = runs[(law, CAMPAIGN_RIG, rname)]
            else:
                md = make_model(law, CAMPAIGN_RIG)
                segs, evs, Y = run(md, rel, ts)
                runs[(law, CAMPAIGN_RIG, rname)] = (md, segs, evs, Y)
            ent, _ = describe_case(md, segs, evs, Y, ts, rel)
            key = f"campaign/{law}/{CAMPAIGN_RIG}/{rname}"
            truth["campaign"][law][rname] = ent
            print(f"== campaign {law:<9s} {rname:<11s}: slides +{ent['slides_plus']} "
                  f"-{ent['slides_minus']} (+{ent['slide_distance_plus_m'] * 1e3:.2f} / -"
                  f"{ent['slide_distance_minus_m'] * 1e3:.2f} mm), |N|/Mg "
                  f"{ent['normal_force_over_static_load'][0]:.3f}.."
                  f"{ent['normal_force_over_static_load'][1]:.3f}; "
                  + energy_line(key, ent) + "\n   " + timeline(evs))
            if ent["slides_plus"] + ent["slides_minus"] < 4:
                print(f"   FAIL: fewer than 4 slides in {key}")
                ok_all = False
            for seed in seeds:
                rec = f"campaign_{law}_{CAMPAIGN_RIG}_{rname}_s{seed}.csv"
                write_rec(rec, md, Y, seed, k)
                cases.append(dict(id=f"campaign_{law}_{CAMPAIGN_RIG}_{rname}_s{seed}",
                                  group=f"campaign:{law}", law=law, rig=CAMPAIGN_RIG,
                                  seed=seed, release=rname, release_state=list(rel),
                                  noise_stream=(seed if k == 0 else [seed, k]),
                                  recording=rec, rig_file=rig_files[CAMPAIGN_RIG],
                                  truth=law_truth(law), slides_plus=ent["slides_plus"],
                                  slides_minus=ent["slides_minus"]))

    # ---- mirror symmetry -------------------------------------------------------------------
    mirror_cases = [(n, "std", "mirror") for n in RIGS] + [(CAMPAIGN_RIG, "wide", "wide_mirror")]
    for name, rn, rm in mirror_cases:
        a = make_model("direction", name)
        sa, ea, Ya = run(a, release(name, rm), ts)
        b = make_model("direction", name, mu_pos=MU_NEG, mu_neg=MU_POS)
        sb, eb, Yb = run(b, release(name, rn), ts)
        d = mirror_diff(Ya, Yb)
        same_ev = [e["kind"] for e in ea] == mirrored_kinds(eb)
        dt = max(abs(x["t"] - y["t"]) for x, y in zip(ea, eb)) if same_ev else None
        good = d <= TOL_MIRROR and same_ev
        checks["mirror"].append(dict(law="direction", rig=name, release=rm,
                                     against=f"swapped rail ({MU_NEG} toward +x, {MU_POS} toward"
                                             f" -x), release {rn}, mirrored",
                                     max_state_diff=d, events_mirror=same_ev,
                                     max_event_time_diff_s=dt, ok=bool(good)))
        print(f"(check) mirror direction {name} {rm}: max |state - mirror(swapped {rn})| "
              f"{d:.1e}, events mirrored {same_ev}"
              + (f" (max time diff {dt:.1e} s)" if dt is not None else "") + f"  {verdict(good)}")
    for rn, rm in (("std", "mirror"), ("wide", "wide_mirror")):
        md_a, sa, ea, Ya = runs[("tilt", CAMPAIGN_RIG, rm)]
        b = make_model("tilt", CAMPAIGN_RIG, tilt=-TILT)
        sb, eb, Yb = run(b, release(CAMPAIGN_RIG, rn), ts)
        d = mirror_diff(Ya, Yb)
        same_ev = [e["kind"] for e in ea] == mirrored_kinds(eb)
        good = d <= TOL_MIRROR and same_ev
        checks["mirror"].append(dict(law="tilt", rig=CAMPAIGN_RIG, release=rm,
                                     against=f"tilt -alpha (+x downhill), release {rn}, mirrored",
                                     max_state_diff=d, events_mirror=same_ev, ok=bool(good)))
        print(f"(check) mirror tilt {CAMPAIGN_RIG} {rm}: max |state - mirror(tilt -alpha {rn})| "
              f"{d:.1e}, events mirrored {same_ev}  {verdict(good)}")

    # ---- neutral values --------------------------------------------------------------------
    for name in RIGS:
        _, _, ec, Yc = runs[("coulomb", name, "std")]
        rel = release(name, "std")
        for what, md in (("direction mu+ = mu- = 0.22",
                          make_model("direction", name, mu_pos=MU_C, mu_neg=MU_C)),
                         ("load exponent 1.0, mu 0.22", make_model("load", name, exp=1.0,
                                                                   mu=MU_C))):
            s2, e2, Y2 = run(md, rel, ts)
            dpos = float(np.max(np.abs(mg.markers(md, Y2, "none") - mg.markers(md, Yc, "none"))))
            dst = np.max(np.abs(Y2[:, :4] - Yc[:, :4]), axis=0)
            rel_d = float(np.max(dst / np.max(np.abs(Yc[:, :4]), axis=0)))
            same = [e["kind"] for e in e2] == [e["kind"] for e in ec]
            dt = max(abs(a["t"] - b["t"]) for a, b in zip(e2, ec)) if same else None
            good = dpos <= TOL_NEUTRAL and same and dt <= TOL_NEUTRAL
            checks["neutral"].append(dict(
                rig=name, case=what, against="coulomb 0.22", max_marker_diff_m=dpos,
                max_state_diff=dict(zip(["x_m", "theta_rad", "x_dot_m_s", "theta_dot_rad_s"],
                                        [float(v) for v in dst])),
                max_state_diff_relative_to_range=rel_d, same_events=same,
                max_event_time_diff_s=dt, ok=bool(good)))
            print(f"(check) neutral {name}: {what} vs coulomb: max |marker diff| {dpos:.1e} m, "
                  f"max |state diff| {float(dst.max()):.1e} ({rel_d:.1e} of the component's "
                  f"largest value), same events {same}  {verdict(good)}")

    # ---- tilt equivalence ------------------------------------------------------------------
    for name, rn in [(n, "std") for n in RIGS] + [(CAMPAIGN_RIG, r) for r in CAMPAIGN_RELEASES
                                                  if r != "std"]:
        md_t, st, et, Yt = runs[("tilt", name, rn)]
        if ("direction", name, rn) in runs:
            _, _, ed, Yd = runs[("direction", name, rn)]
        else:
            _, ed, Yd = run(make_model("direction", name), release(name, rn), ts)
        eq = tilt_equivalence(md_t, st, Yt, ts, Yd, et, ed)
        truth["tilt_equivalence"][f"{name}/{rn}"] = eq
        parts = []
        for nm in ("plus", "minus"):
            q = eq[nm]
            parts.append(f"{nm}: none" if q is None else
                         f"{nm} mu_eff {q['mu_eff_speed_weighted']:.4f} (vs "
                         f"{q['direction_law_value']}; {q['mu_eff_min']:.4f}..{q['mu_eff_max']:.4f}"
                         f", |N|/Mg {q['N_over_Mg_min']:.2f}..{q['N_over_Mg_max']:.2f})")
        print(f"(info) tilt vs direction {name} {rn}: " + "; ".join(parts)
              + f"; max |dx| {eq['max_slider_x_diff_m'] * 1e3:.3f} mm, max |d bob| "
                f"{eq['max_bob_diff_m'] * 1e3:.2f} mm")

    # ---- write ------------------------------------------------------------------------------
    truth["all_checks_passed"] = bool(ok_all)
    with open(os.path.join(out, "truth.json"), "w", newline="\n") as fh:
        json.dump(truth, fh, indent=1)
        fh.write("\n")
    with open(os.path.join(out, "manifest.json"), "w", newline="\n") as fh:
        json.dump(dict(generator="scripts/generators/friction_law_generator.py", truth="truth.json",
                       paths="relative to this file's directory",
                       truth_keys=dict(
                           mu_kinetic_positive="coefficient while sliding toward +x (static = "
                                               "kinetic); load law: at the static load",
                           mu_kinetic_negative="coefficient while sliding toward -x",
                           mu_kinetic="mean of the two",
                           split="(mu_kinetic_positive - mu_kinetic_negative) / 2",
                           load_exponent="p in F = c |N|^p (1: Coulomb)",
                           mu_at_static_load="c ((m1 + m2) g)^(p - 1); the mean for p = 1",
                           rail_tilt_deg="alpha: gravity in the rail frame (y down) g (sin a, "
                                         "cos a), alpha > 0: +x downhill"),
                       cases=cases), fh, indent=1)
        fh.write("\n")
    print(f"{len(cases)} recordings in {out}")
    print("all checks", "PASSED" if ok_all else "FAILED")
    return 0 if ok_all else 1


if __name__ == "__main__":
    sys.exit(main())
