#!/usr/bin/env python3
"""Point-pendulum recordings with rig files that carry measurement errors, and invented effects.

Purpose
-------
A test bench for issue 34 (rig values with uncertainties, nuisances with plausibility priors).
Writes synthetic camera recordings of three POINT-pendulum rigs (no rod mass, no bob radius)
and, for each, rig files whose rod length or masses are off by a known amount, with and without
the new `*_sd` keys, plus recordings with four effects that no nuisance of `appell fit`
describes. A manifest lists every (recording, rig file, true mu, error) case for
scripts/sweeps/measured_rig_sweep.py.

It reuses scripts/generators/rigid_generator.py (the rig, the Newton-Euler rows, the hybrid stick/slide
loop, the CSV writer) and scripts/generators/misspec_generator.py (its Model, whose hybrid loop `simulate`
and helpers are used unchanged) by import; nothing is copied. The effects' terms enter through
this module's own rows: misspec_generator's module-level `_rows`, `solve_stuck`,
`solve_sliding` and `rhs_fn` are replaced by dispatchers that call this module's versions for
an `Ext` model and the original ones for every other model (so misspec_generator's own output
is unchanged in the same process).

Rigs (point pendulum: rod_mass = 0, bob_radius = 0; rod 0.30 m, g = 9.81, Coulomb mu = 0.25)
  light  m1 = 0.05, m2 = 0.15 kg (m1/m2 = 1/3), release bob 0.5 rad above the rail swung down
         at 4 rad/s (rigid_generator's light release): 8 switches in 2 s, slides over 0.37 m.
  equal  m1 = m2 = 0.10 kg, rod horizontal at rest (the paper's rig and release): 7 switches.
  heavy  m1 = 0.35, m2 = 0.10 kg (m1/m2 = 3.5), rod horizontal at rest: 12 switches, slides
         only within [-3.1, +3.9] mm.
rigid_generator.Rig with m_r = 0 and R = 0 gives d = l exactly and J_cm = 0 (checked); the
pendulum's spin row then says the pivot force is along the rod, which is the point pendulum.

Rig files (per rig; rigs/<rig>_<case>.toml)
  rod_length off by -5 -2 -1 -0.5 +0.5 +1 +2 +5 mm; slider_mass and bob_mass off by
  -5 -3 -1 +1 +3 +5 % (of the true value). Flavours:
    sd    with the `*_sd` key of the erroneous value equal to the error's size (rod 2 mm ->
          rod_length_sd = 0.002; mass 3 % -> slider_mass_sd = 0.03 x the WRITTEN mass), the
          other values without sd keys (their default);
    nosd  no `*_sd` key at all (the fit's defaults);
    omit  no `*_sd` key and no rod_mass / bob_radius keys (rod +-1, +-2 mm and masses +-3 %
          only): the fit may then look for a rigid pendulum (a nuisance that can absorb a
          rod-length error).
  Every sd and nosd file states rod_mass = 0.0 and bob_radius = 0.0 explicitly: the lab says
  "point pendulum", and the current fit reads written zeros as "the pendulum is known".
  True values: true_tight (rod_length_sd = 1e-6 m, slider/bob_mass_sd = 1e-6 x the mass,
  rod_mass_sd = bob_radius_sd = 0 not written), true_nosd (explicit zeros, no sd) and
  true_omit (no rod_mass / bob_radius keys, no sd).

Effects (no nuisance of the fit describes them; Newton-Euler rows, y DOWN as docs/physics.md)
  pin      plain-pin pivot: Coulomb friction torque tau = -mu_pin r_pin |H| tanh(w / w0) on
           the pendulum (H the pivot force; reaction couple on the slider taken by the rail),
           mu_pin = 0.2, r_pin = 2 mm, w0 = 1e-3 rad/s (smoothed sign; |H| enters the rows, so
           each solve is a fixed-point iteration on |H|, contraction ~ r_pin mu_pin / l).
           The pivot would stick only where |gravity torque| < mu_pin r_pin |H|, i.e. within
           about 1.3e-3 rad of hanging; the truth file lists, at every turning point of the
           pendulum (w = 0), |theta - pi/2| and the needed torque over the friction torque.
  shutter  rolling shutter (camera only): image rows read top to bottom over T = 10 ms; the
           image spans the markers' bounding box (clean run, y up) padded by 10 % of its
           height above and below; a marker in frame i is sampled at t_i + T f, f = (y_top -
           y) / (y_top - y_bottom) its row fraction, solved by fixed-point iteration (the bob's
           height depends on the sampled time; the slider's f is constant: 0.08, or 0.35 on
           the light rig, whose bob rises above the rail); times
           written are the nominal i / 1000. Simulated to 2.012 s.
  sag      a sagging rail: height (y up) k x^2, lowest at x = 0 (in PHYSICS' y-down frame
           y_rail(x) = -k x^2), k = 0.5 mm / (0.4 m)^2 = 0.003125 1/m (an 0.8 m rail between
           supports at x = +-0.4 m, 0.5 mm lower at its centre). The slider moves on the curve
           (its y marker follows it); the slider's force balance is written along the rail's
           tangent and normal, so N is the normal force and friction F = -mu s |N| acts along
           the tangent; gravity has a tangential component -m g y'/q. The camera frame is the
           tangent at x = 0.
  load     load-dependent rail friction F = -s c |N|^0.85 while sliding, stuck while |F_needed|
           <= c |N|^0.85, c = 0.25 ((m1 + m2) g)^0.15 (0.25 N at the static load). Each sliding
           solve finds F by brentq on F + s c |N(F)|^0.85 = 0 (N is affine in F). mu is not
           a constant: the truth for the sweep is the slid-weighted mean of mu_eff = |F|/|N|,
           integral mu_eff |v| dt / integral |v| dt (v the speed along the rail), integrated
           alongside; the truth file also gives the work-weighted integral |F||v| / integral
           |N||v| and mu at the static load (0.25).
Energy: E = 1/2 m1 q^2 x'^2 + 1/2 m_p |v_cm|^2 - m1 g y_r - m_p g (y_r + d sin theta) (q^2 = 1 +
y_r'^2, y_r = 0 except sag); dE/dt = F q x' + tau w; each work is integrated alongside.

Outputs (default --out /tmp/measured)
  <rig>_s<seed>.csv                    the true rig (rigid_generator.write_csv: same format,
                                        noise draw and bytes as rigid_generator would write)
  effect_<effect>_<rig>_s<seed>.csv    the effects (noise: one default_rng(seed).normal(0,
                                        0.0002, (2001, 4)) draw, the same as the true file's)
  rigs/<rig>_<case>.toml, manifest.json, measured_truth.json
With --ci: only the subset committed in tests/data/measured (seed 1, see its README).

Run (outside CI; Python 3 with numpy and scipy)
    python3 -m venv /tmp/venv-gen && /tmp/venv-gen/bin/pip install numpy scipy
    /tmp/venv-gen/bin/python scripts/generators/measured_rig_generator.py --out /tmp/measured --check
    /tmp/venv-gen/bin/python scripts/generators/measured_rig_generator.py --out tests/data/measured --ci
Options: --seeds 1 2 3 4 5 (default), --ci, --check (energy balance of every simulated run with
every work, the no-effect Ext model against rigid_generator, point-rig limits).
"""

import argparse
import json
import math
import os
import platform
import sys

import numpy as np
import scipy
from scipy.optimize import brentq

sys.dont_write_bytecode = True  # leave no __pycache__ in scripts/
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import rigid_generator as rg  # noqa: E402
import misspec_generator as mg  # noqa: E402

RTOL, ATOL, FPS, DURATION = rg.RTOL, rg.ATOL, rg.FPS, rg.DURATION
NOISE = 0.0002
MU = 0.25
L_ROD, G = 0.30, 9.81
SEEDS = [1, 2, 3, 4, 5]

POINT_RIGS = {
    "light": dict(m1=0.05, m2=0.15, release=(0.0, -0.5, 0.0, 4.0)),
    "equal": dict(m1=0.10, m2=0.10, release=(0.0, 0.0, 0.0, 0.0)),
    "heavy": dict(m1=0.35, m2=0.10, release=(0.0, 0.0, 0.0, 0.0)),
}

ROD_ERRORS_MM = [-5.0, -2.0, -1.0, -0.5, 0.5, 1.0, 2.0, 5.0]
MASS_ERRORS_PCT = [-5.0, -3.0, -1.0, 1.0, 3.0, 5.0]
OMIT_ROD_MM = [-2.0, -1.0, 1.0, 2.0]
OMIT_MASS_PCT = [-3.0, 3.0]
TIGHT = 1e-6

EFFECTS = ["pin", "shutter", "sag", "load"]
PIN_MU, PIN_R, PIN_W0 = 0.2, 0.002, 1e-3
SHUTTER_T, SHUTTER_PAD = 0.010, 0.10
SAG_DEPTH, SAG_HALF_SPAN = 0.0005, 0.4
SAG_K = SAG_DEPTH / SAG_HALF_SPAN ** 2
LOAD_EXP = 0.85

# CI subset (tests/data/measured): seed 1; the true recording of each rig, the effects on the
# equal rig; a few rig files per rig.
CI_EFFECT_RIG = "equal"
CI_RIG_CASES = ["true_tight", "true_nosd", "true_omit", "rod+2mm_sd", "rod+2mm_nosd",
                "slider+3pct_sd", "slider+3pct_nosd", "bob-3pct_sd", "bob-3pct_nosd"]
# Quick subset of the manifest (--quick in the sweep): seed 1, per rig these rig cases and
# every effect.
QUICK_RIG_CASES = ["true_nosd", "rod+2mm_sd", "rod+2mm_nosd", "rod-1mm_omit",
                   "slider+3pct_sd", "slider+3pct_nosd", "bob-3pct_sd", "bob-3pct_nosd"]


def make_rig(name, mu=MU):
    p = POINT_RIGS[name]
    return rg.Rig(p["m1"], p["m2"], L_ROD, 0.0, 0.0, G, mu)


# --------------------------------------------------------------------------------------------
# Model with the effects' terms
# --------------------------------------------------------------------------------------------
class Ext(mg.Model):
    """misspec_generator.Model (no tilt, drag, damping) plus: pin friction torque, rail sag
    (y_rail = -k x^2, y down), load-dependent friction c |N|^p."""

    def __init__(self, rig, pin=False, sag_k=0.0, load_exp=None):
        super().__init__(rig)
        self.pin, self.k, self.load_exp = pin, sag_k, load_exp
        self.c_load = (rig.mu * ((rig.m1 + rig.m_p) * rig.g) ** (1.0 - load_exp)
                       if load_exp else None)
        self.works = ["friction"] + (["pin"] if pin else [])
        self.slid = load_exp is not None  # integrate mu_eff |v|, |v|, |F||v|, |N||v|
        self.n = 4 + len(self.works) + (4 if self.slid else 0)
        self.Habs = 0.0        # |H| in the pin-torque row, set by the solvers' iteration
        self.mu_cur = rig.mu   # mu the stick test multiplies |N| by (load: c |N|^(p-1))

    def mu(self, x):
        return self.mu_cur

    def rail(self, x):
        """y_rail (y down), its slope p and curvature y''."""
        return -self.k * x * x, -2.0 * self.k * x, -2.0 * self.k

    def pin_torque(self, Habs, w):
        return -PIN_MU * PIN_R * Habs * math.tanh(w / PIN_W0) if self.pin else 0.0


def ext_rows(md, y):
    """Unknowns [xdd, thdd, Hx, Hy, N, F]. Rows 0 and 1 are the slider's balance along the
    rail's tangent t = (1, p)/q and normal n = (-p, 1)/q (flat rail: rigid_generator's rows 0
    and 1 exactly in value), so F sits in row 0 only, as misspec_generator's sliding fold
    expects."""
    rig = md.rig
    x, th, xd, w = y[0], y[1], y[2], y[3]
    m1, mp, d, J, g = rig.m1, rig.m_p, rig.d, rig.J_cm, rig.g
    s_, c_ = math.sin(th), math.cos(th)
    _, p, ypp = md.rail(x)
    q = math.sqrt(1.0 + p * p)
    A = np.array([
        [m1 * q, 0.0, 1.0 / q, p / q, 0.0, -1.0],     # tangent: m1 a.t + H.t - F = m1 g t_y
        [0.0, 0.0, p / q, -1.0 / q, 1.0, 0.0],        # normal:  N - H.n = m1 a.n - m1 g n_y
        [mp, -mp * d * s_, -1.0, 0.0, 0.0, 0.0],
        [mp * p, mp * d * c_, 0.0, -1.0, 0.0, 0.0],
        [0.0, J, -d * s_, d * c_, 0.0, 0.0],
    ])
    rhs = np.array([m1 * g * p / q - m1 * p * ypp * xd * xd / q,
                    m1 * ypp * xd * xd / q - m1 * g / q,
                    mp * d * c_ * w * w,
                    mp * g + mp * d * s_ * w * w - mp * ypp * xd * xd,
                    md.pin_torque(md.Habs, w)])
    return A, rhs


_MG = dict(rows=mg._rows, solve_stuck=mg.solve_stuck, solve_sliding=mg.solve_sliding,
           rhs_fn=mg.rhs_fn)


def _pin_iterate(md, solve):
    """Fixed point on |H| for the pin torque (one plain solve without a pin)."""
    if not md.pin:
        return solve()
    sol = solve()
    for _ in range(100):
        h = math.hypot(sol[2], sol[3])
        if abs(h - md.Habs) <= 1e-13 * (1.0 + h):
            return sol
        md.Habs = h
        sol = solve()
    raise RuntimeError("pin torque iteration did not converge")


def _load_sliding(md, y, s):
    """Sliding with F = -s c |N|^p: N is affine in F (N = N0 + N1 F); brentq on F."""
    A, rhs = mg._rows(md, y)
    A5 = A[:, :5]
    base = np.linalg.solve(A5, rhs)
    dF = np.linalg.solve(A5, -A[:, 5])
    c, pe = md.c_load, md.load_exp

    def h(F):
        return F + s * c * abs(base[4] + dF[4] * F) ** pe

    big = 1.0
    while h(-s * big) * s > 0.0:   # h(0) has the sign of s; find the other side
        big *= 2.0
        if big > 1e6:
            raise RuntimeError("load friction: no root")
    lo, hi = sorted((0.0, -s * big))
    F = brentq(h, lo, hi, xtol=1e-300, rtol=4 * np.finfo(float).eps, maxiter=500)
    sol = base + dF * F
    return np.append(sol, F)


def solve_stuck(md, y):
    if not isinstance(md, Ext):
        return _MG["solve_stuck"](md, y)
    sol = _pin_iterate(md, lambda: _MG["solve_stuck"](md, y))
    if md.load_exp:
        md.mu_cur = md.c_load * max(abs(sol[4]), 1e-300) ** (md.load_exp - 1.0)
    return sol


def solve_sliding(md, y, s):
    if not isinstance(md, Ext):
        return _MG["solve_sliding"](md, y, s)
    if md.load_exp:
        return _pin_iterate(md, lambda: _load_sliding(md, y, s))
    return _pin_iterate(md, lambda: _MG["solve_sliding"](md, y, s))


def _rows(md, y):
    return ext_rows(md, y) if isinstance(md, Ext) else _MG["rows"](md, y)


def rhs_fn(md, mode, s):
    if not isinstance(md, Ext):
        return _MG["rhs_fn"](md, mode, s)

    def f(t, y):
        x, th, xd, w = y[0], y[1], y[2], y[3]
        sol = solve_stuck(md, y) if mode == "stick" else solve_sliding(md, y, s)
        xdd, thdd, N, F = sol[0], sol[1], sol[4], sol[5]
        q = math.sqrt(1.0 + md.rail(x)[1] ** 2)
        if mode == "stick":
            out = [0.0, w, 0.0, thdd, 0.0]
        else:
            out = [xd, w, xdd, thdd, F * q * xd]
        if md.pin:
            out.append(md.pin_torque(math.hypot(sol[2], sol[3]), w) * w)
        if md.slid:
            v = q * abs(xd)
            out += ([0.0] * 4 if mode == "stick"
                    else [abs(F) / abs(N) * v if N != 0.0 else 0.0, v, abs(F) * v, abs(N) * v])
        return out
    return f


# misspec_generator's hybrid loop looks these names up in its module at call time.
mg._rows, mg.solve_stuck, mg.solve_sliding, mg.rhs_fn = _rows, solve_stuck, solve_sliding, rhs_fn


def ext_energy(md, y):
    rig = md.rig
    x, th, xd, w = y[0], y[1], y[2], y[3]
    yr, p, _ = md.rail(x)
    vcx = xd - rig.d * math.sin(th) * w
    vcy = p * xd + rig.d * math.cos(th) * w
    T = (0.5 * rig.m1 * (1.0 + p * p) * xd ** 2 + 0.5 * rig.m_p * (vcx ** 2 + vcy ** 2)
         + 0.5 * rig.J_cm * w ** 2)
    V = -rig.m1 * rig.g * yr - rig.m_p * rig.g * (yr + rig.d * math.sin(th))
    return T + V


def energy_error(md, Y):
    E = np.array([ext_energy(md, y) for y in Y])
    W = Y[:, 4:4 + len(md.works)].sum(axis=1)
    err = float(np.max(np.abs(E - W - (E[0] - W[0]))))
    return err, {k: float(Y[-1, 4 + i]) for i, k in enumerate(md.works)}


def make_model(effect, name):
    rig = make_rig(name)
    if effect == "pin":
        return Ext(rig, pin=True)
    if effect == "sag":
        return Ext(rig, sag_k=SAG_K)
    if effect == "load":
        return Ext(rig, load_exp=LOAD_EXP)
    return Ext(rig)


def markers(md, Y):
    """Clean marker positions in the file frame (y up): sx, sy, bx, by."""
    l = md.rig.l
    x, th = Y[:, 0], Y[:, 1]
    yr = -md.k * x * x
    return np.column_stack([x, -yr + 0.0, x + l * np.cos(th), -(yr + l * np.sin(th))])


def rolling_shutter(md, segs, release, ts):
    """Markers sampled at t_i + T f(y), f the row fraction (0 top .. 1 bottom), y up."""
    clean = markers(md, mg.sample_at(md, segs, release, ts))
    ys = np.concatenate([clean[:, 1], clean[:, 3]])
    top, bot = ys.max(), ys.min()
    pad = SHUTTER_PAD * (top - bot)
    top, bot = top + pad, bot - pad
    out = np.empty_like(clean)
    info = dict(y_top_m=float(top), y_bottom_m=float(bot), readout_s=SHUTTER_T)
    for j in (0, 2):
        tt = ts.copy()
        for it in range(50):
            M = markers(md, mg.sample_at(md, segs, release, tt))
            t_new = ts + SHUTTER_T * (top - M[:, j + 1]) / (top - bot)
            ch = float(np.max(np.abs(t_new - tt)))
            tt = t_new
            if ch < 1e-14:
                break
        else:
            raise RuntimeError("rolling shutter iteration did not converge")
        M = markers(md, mg.sample_at(md, segs, release, tt))
        out[:, j:j + 2] = M[:, j:j + 2]
        delay = tt - ts
        info["slider_delay_s" if j == 0 else "bob_delay_s"] = [float(delay.min()),
                                                               float(delay.max())]
    info["max_position_shift_m"] = float(np.max(np.abs(out - clean)))
    return out, info


def pin_turning_points(md, segs, Y, ts):
    """At each sign change of w: |theta - pi/2| and the torque needed to hold the pendulum
    over the largest pin friction torque (> 1: the pivot does not stick)."""
    rows = []
    w = Y[:, 3]
    for i in range(1, len(w) - 1):  # (frame 0: the releases at rest have H = 0)
        if w[i] == 0.0 or w[i] * w[i + 1] < 0.0:
            y = Y[i].copy()
            y[3] = 0.0
            sol = solve_stuck(md, y)
            habs = math.hypot(sol[2], sol[3])
            need = abs(md.rig.m_p * md.rig.g * md.rig.d * math.cos(y[1]))
            rows.append(dict(t=float(ts[i]), theta_minus_half_pi=float(y[1] - math.pi / 2),
                             needed_over_friction=float(need / (PIN_MU * PIN_R * habs))))
    return rows


# --------------------------------------------------------------------------------------------
# Rig files and the manifest
# --------------------------------------------------------------------------------------------
def rig_cases():
    """(case name, kind, flavour, error dict or None)."""
    out = [("true_tight", "true", "tight", None), ("true_nosd", "true", "nosd", None),
           ("true_omit", "true", "omit", None)]
    for dmm in ROD_ERRORS_MM:
        for fl in ("sd", "nosd") + (("omit",) if dmm in OMIT_ROD_MM else ()):
            out.append((f"rod{dmm:+g}mm_{fl}", "rod", fl,
                        dict(key="rod_length", delta_m=dmm / 1000.0, delta_mm=dmm)))
    for kind, key in (("slider", "slider_mass"), ("bob", "bob_mass")):
        for pct in MASS_ERRORS_PCT:
            for fl in ("sd", "nosd") + (("omit",) if pct in OMIT_MASS_PCT else ()):
                out.append((f"{kind}{pct:+g}pct_{fl}", kind, fl,
                            dict(key=key, relative=pct / 100.0, delta_pct=pct)))
    return out


def write_rig_toml(path, name, rig, kind, flavour, err):
    vals = dict(slider_mass=rig.m1, bob_mass=rig.m2, rod_length=rig.l)
    sd = {}
    if err is not None:
        if "delta_m" in err:
            vals["rod_length"] = round(rig.l + err["delta_m"], 12)
            if flavour == "sd":
                sd["rod_length_sd"] = abs(err["delta_m"])
        else:
            k = err["key"]
            vals[k] = round(vals[k] * (1.0 + err["relative"]), 12)
            if flavour == "sd":
                sd[k + "_sd"] = round(abs(err["relative"]) * vals[k], 12)
    if flavour == "tight":
        sd = dict(rod_length_sd=TIGHT, slider_mass_sd=TIGHT * rig.m1,
                  bob_mass_sd=TIGHT * rig.m2)
    what = ("the true values" if err is None else
            f"{err['key']} off by {err.get('delta_mm', err.get('delta_pct'))}"
            f"{' mm' if 'delta_mm' in err else ' %'}")
    with open(path, "w", newline="\n") as fh:
        fh.write(f"# Point-pendulum rig '{name}' as measured, {what}; flavour '{flavour}'\n"
                 f"# (made by scripts/generators/measured_rig_generator.py; truth in measured_truth.json)\n"
                 f"[rig]\n")
        fh.write(f"slider_mass = {vals['slider_mass']!r}   # kg\n")
        fh.write(f"bob_mass = {vals['bob_mass']!r}      # kg\n")
        if flavour != "omit":
            fh.write("rod_mass = 0.0      # kg: point pendulum\n")
            fh.write("bob_radius = 0.0    # m: point pendulum\n")
        fh.write(f"rod_length = {vals['rod_length']!r}     # m, pivot to the bob's centre\n")
        fh.write(f"gravity = {rig.g!r}      # m/s^2\n")
        for k, v in sd.items():
            fh.write(f"{k} = {v!r}\n")
    return dict(values=vals, sd=sd)


# --------------------------------------------------------------------------------------------
# Main
# --------------------------------------------------------------------------------------------
def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", default="/tmp/measured")
    ap.add_argument("--seeds", type=int, nargs="+", default=SEEDS)
    ap.add_argument("--ci", action="store_true", help="write only the tests/data/measured subset")
    ap.add_argument("--check", action="store_true")
    args = ap.parse_args(argv)
    seeds = [1] if args.ci else args.seeds
    os.makedirs(os.path.join(args.out, "rigs"), exist_ok=True)
    n_frames = int(round(DURATION * FPS)) + 1
    ts = np.round(np.arange(n_frames) / FPS, 12)
    ok_all = True
    truth = dict(generator="scripts/generators/measured_rig_generator.py",
                 based_on=["scripts/generators/rigid_generator.py", "scripts/generators/misspec_generator.py"],
                 command=" ".join(["scripts/generators/measured_rig_generator.py"]
                                  + (sys.argv[1:] if argv is None else list(argv))),
                 python=platform.python_version(), numpy=np.__version__,
                 scipy=scipy.__version__, solver=dict(method="DOP853", rtol=RTOL, atol=ATOL),
                 frame_rate_hz=FPS, duration_s=DURATION, noise_sigma_m=NOISE, seeds=seeds,
                 frame="rail frame, y up (bob at x + l cos theta, -l sin theta)",
                 theta_convention="docs/physics.md: from +x, y down, pi/2 hangs down",
                 mu_true=MU, rigs={}, effects={})
    cases = []

    def case(cid, group, rig, seed, kind, flavour, rec, rigf, mu, err=None, quick=False,
             defined=True):
        cases.append(dict(id=cid, group=group, rig=rig, seed=seed, kind=kind, flavour=flavour,
                          recording=rec, rig_file=rigf, truth_mu=mu, truth_defined=defined,
                          error=err, quick=quick))

    for name in POINT_RIGS:
        rig = make_rig(name)
        rel = POINT_RIGS[name]["release"]
        segs, evs, _ = rg.simulate(rig, rel, DURATION)
        Y = rg.sample(segs, ts)
        ent = rig.describe()
        ent.update(release=dict(zip(["x", "theta", "x_dot", "theta_dot"], rel)),
                   d_equals_l=rig.d == rig.l, J_cm=rig.J_cm,
                   slider_x_range_m=[float(Y[:, 0].min()), float(Y[:, 0].max())],
                   events=[dict(t=e["t"], kind=e["kind"],
                                state=dict(zip(["x", "theta", "x_dot", "theta_dot"],
                                               e["state"])),
                                stuck_cone_ratio=e["cone_ratio"]) for e in evs])
        print(f"== {name}: m1 {rig.m1} m2 {rig.m2} l {rig.l} (d == l: {rig.d == rig.l}, "
              f"J_cm {rig.J_cm}), {len(evs) - 2} switches, x in [{Y[:, 0].min():+.4f}, "
              f"{Y[:, 0].max():+.4f}] m: "
              + ", ".join(f"{e['kind']} {e['t']:.4f}" for e in evs[1:-1]))
        if args.check:
            E = np.array([rg.energy(rig, y) for y in Y])
            err = float(np.max(np.abs(E - Y[:, 4] - E[0])))
            scale = rig.m_p * rig.g * rig.d
            good = err / scale < 1e-7
            ok_all &= good
            # The no-effect Ext model through misspec_generator's loop.
            md = Ext(rig)
            s2, e2, _ = mg.simulate(md, rel, DURATION)
            Y2 = mg.sample_at(md, s2, rel, ts)
            dmax = float(np.max(np.abs(Y2[:, :4] - Y[:, :4])))
            good2 = dmax < 1e-8 and len(e2) == len(evs)
            ok_all &= good2
            print(f"(check) energy [{name}]: max |E - W - E0| = {err:.2e} J ({err / scale:.1e} "
                  f"of m_p g d)  {'OK' if good else 'FAIL'}; Ext without effects vs "
                  f"rigid_generator: max |state diff| {dmax:.1e}, {len(e2) - 2} switches  "
                  f"{'OK' if good2 else 'FAIL'}")
            ent["self_check"] = dict(energy_max_err_J=err, ext_vs_rigid_max_state_diff=dmax)
        truth["rigs"][name] = ent
        rc_list = rig_cases()
        ci_rc = set(CI_RIG_CASES)
        rig_files = {}
        for cname, kind, fl, err in rc_list:
            if args.ci and cname not in ci_rc:
                continue
            rel_path = os.path.join("rigs", f"{name}_{cname}.toml")
            info = write_rig_toml(os.path.join(args.out, rel_path), name, rig, kind, fl, err)
            rig_files[cname] = (rel_path, kind, fl, err, info)
        ent["rig_files"] = {k: dict(file=v[0], kind=v[1], flavour=v[2], error=v[3], **v[4])
                            for k, v in rig_files.items()}
        for seed in seeds:
            rec = f"{name}_s{seed}.csv"
            rg.write_csv(os.path.join(args.out, rec), ts, Y, rig, seed, NOISE)
            for cname, (rel_path, kind, fl, err, _) in rig_files.items():
                group = f"{name}/true_{fl}" if kind == "true" else f"{name}/{kind}/{fl}"
                case(f"{name}_s{seed}/{cname}", group, name, seed, kind, fl, rec, rel_path, MU,
                     err, quick=(seed == 1 and cname in QUICK_RIG_CASES))

    for effect in EFFECTS:
        truth["effects"][effect] = {}
        for name in POINT_RIGS:
            if args.ci and name != CI_EFFECT_RIG:
                continue
            rel = POINT_RIGS[name]["release"]
            md = make_model(effect, name)
            t_end = DURATION + 0.012 if effect == "shutter" else DURATION
            segs, evs, _ = mg.simulate(md, rel, t_end)
            Y = mg.sample_at(md, segs, rel, ts)
            ent = dict(rig_name=name,
                       release=dict(zip(["x", "theta", "x_dot", "theta_dot"], rel)),
                       slider_x_range_m=[float(Y[:, 0].min()), float(Y[:, 0].max())],
                       events=[dict(t=e["t"], kind=e["kind"],
                                    state=dict(zip(["x", "theta", "x_dot", "theta_dot"],
                                                   e["state"])),
                                    stuck_cone_ratio=e["cone_ratio"]) for e in evs])
            mu_truth, extra = MU, ""
            if effect == "pin":
                tp = pin_turning_points(md, segs, Y, ts)
                ent["parameters"] = dict(mu_pin=PIN_MU, r_pin_m=PIN_R, tanh_width_rad_s=PIN_W0,
                                         law="tau = -mu_pin r_pin |H| tanh(w / w0)",
                                         turning_points=tp)
                extra = (f", turning points {len(tp)}, min needed/friction torque "
                         f"{min(r['needed_over_friction'] for r in tp):.0f}" if tp else "")
            if effect == "sag":
                ent["parameters"] = dict(k_per_m=SAG_K, depth_m=SAG_DEPTH,
                                         supports_x_m=[-SAG_HALF_SPAN, SAG_HALF_SPAN],
                                         rail="height (y up) k x^2; y down y_rail = -k x^2",
                                         max_slope=float(2 * SAG_K * np.abs(Y[:, 0]).max()),
                                         max_rail_height_m=float(SAG_K * (Y[:, 0] ** 2).max()))
                extra = (f", max slope {ent['parameters']['max_slope']:.2e}, max rail height "
                         f"{ent['parameters']['max_rail_height_m'] * 1e3:.3f} mm")
            if effect == "load":
                I = Y[-1, -4:]
                mu_slid = float(I[0] / I[1])
                ent["parameters"] = dict(exponent=LOAD_EXP, c=md.c_load,
                                         law="F = -s c |N|^0.85; stuck while |F_needed| <= "
                                             "c |N|^0.85; c = 0.25 ((m1 + m2) g)^0.15",
                                         static_load_N=(md.rig.m1 + md.rig.m_p) * G,
                                         mu_at_static_load=MU,
                                         mu_slid_mean=mu_slid,
                                         mu_work_weighted=float(I[2] / I[3]),
                                         slide_distance_m=float(I[1]))
                mu_truth = mu_slid
                extra = (f", mu slid-mean {mu_slid:.5f}, work-weighted {I[2] / I[3]:.5f}, "
                         f"slid {I[1]:.4f} m")
            ent["mu_truth"] = mu_truth
            ent["mu_truth_definition"] = ("slid-weighted mean of |F|/|N|" if effect == "load"
                                          else "Coulomb mu_k = mu_s")
            if args.check:
                err, works = energy_error(md, Y)
                scale = md.rig.m_p * G * md.rig.d
                good = err / scale < 1e-7
                ok_all &= good
                print(f"(check) energy [{effect} {name}]: max |E - W - E0| = {err:.2e} J "
                      f"({err / scale:.1e} of m_p g d), works "
                      + ", ".join(f"{k} {v:.5f} J" for k, v in works.items())
                      + f"  {'OK' if good else 'FAIL'}")
                ent["self_check"] = dict(energy_max_err_J=err, works_J=works)
            clean = markers(md, Y)
            if effect == "shutter":
                clean, info = rolling_shutter(md, segs, rel, ts)
                ent["parameters"] = dict(
                    rule="marker sampled at t_i + T (y_top - y) / (y_top - y_bottom), y up; "
                         "image = markers' bounding box padded by 10 % of its height",
                    **info)
                extra = (f", bob delay {info['bob_delay_s'][0] * 1e3:.2f}.."
                         f"{info['bob_delay_s'][1] * 1e3:.2f} ms, slider "
                         f"{info['slider_delay_s'][0] * 1e3:.2f} ms, max shift "
                         f"{info['max_position_shift_m'] * 1e3:.2f} mm")
            print(f"== {effect:<7s} {name}: {len(evs) - 2} switches, x in "
                  f"[{Y[:, 0].min():+.4f}, {Y[:, 0].max():+.4f}] m{extra}: "
                  + ", ".join(f"{e['kind']} {e['t']:.4f}" for e in evs[1:-1]))
            rigf = os.path.join("rigs", f"{name}_true_nosd.toml")
            for seed in seeds:
                rec = f"effect_{effect}_{name}_s{seed}.csv"
                noise = np.random.default_rng(seed).normal(0.0, NOISE, size=clean.shape)
                mg.write_csv(os.path.join(args.out, rec), ts, clean + noise)
                case(f"effect_{effect}_{name}_s{seed}", f"effect:{effect}/{name}", name, seed,
                     "effect", effect, rec, rigf, mu_truth, dict(effect=effect),
                     quick=seed == 1)
            truth["effects"][effect][name] = ent

    with open(os.path.join(args.out, "measured_truth.json"), "w") as fh:
        json.dump(truth, fh, indent=1)
        fh.write("\n")
    with open(os.path.join(args.out, "manifest.json"), "w") as fh:
        json.dump(dict(generator="scripts/generators/measured_rig_generator.py", truth="measured_truth.json",
                       paths="relative to this file's directory", cases=cases), fh, indent=1)
        fh.write("\n")
    print(f"{len(cases)} cases ({sum(c['quick'] for c in cases)} quick) in "
          f"{os.path.join(args.out, 'manifest.json')}")
    if args.check:
        print("all checks", "PASSED" if ok_all else "FAILED")
    return 0 if ok_all else 1


if __name__ == "__main__":
    sys.exit(main())
