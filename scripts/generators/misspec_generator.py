#!/usr/bin/env python3
"""Mis-specified recordings: the rigid rigs of rigid_generator.py with effects the fit does not model.

Purpose
-------
Writes synthetic camera recordings of the three rigid rigs of scripts/generators/rigid_generator.py (light,
paper, heavy; same rod mass, bob radius, releases, 2 s at 1 kHz, solver and tolerances, same
file format and noise) with one effect each that `appell fit`'s model does NOT describe, or
describes only as an optional nuisance, so that a sweep (scripts/sweeps/misspec_sweep.py) can check
that the tool either covers the true mu or says that the model limits the result, and is never
confidently wrong.

Effects (one file per effect per rig per seed)
  none           control: no effect (the same trajectory and noise as rigid_generator.py).
  drag           quadratic air drag on the bob, -c |v| v at the bob's centre (distance l along
                 the rod), c = 0.02 m2 g / 4 (2 % of the bob's weight at 2 m/s).
  lens           barrel distortion in the camera only: p -> c + (p - c)(1 - 0.01 (|p - c| /
                 R_edge)^2) about the centre c of the motion's bounding box (both markers, whole
                 run), R_edge = 1.1 x the largest marker distance from c; before the noise.
  four           rail tilted by 1 deg (alpha = +1 deg: gravity in the rail frame (y down) is
                 g (sin alpha, cos alpha), +x runs downhill, the stuck pendulum hangs at
                 theta = pi/2 - alpha, its bob 1 deg toward +x), pivot damping torque -c_d w on
                 the pendulum (logarithmic decrement 0.1 of stuck small swings: c_d = 2 J delta
                 / T, J about the pivot, T = 2 pi sqrt(J / (m_p g d))), camera scale 1.015 and
                 the bob marker 5 mm off the rod (e = +5 mm across it, toward increasing theta).
  friction_ramp  mu(x) = max(0.05, mu0 (1 + 2 x)), mu0 = 0.25, x in metres, for both the stick
                 test and sliding friction (mu is not defined: truth is mu0 and the slid-mean).
  jitter         frames captured at t_i = i/1000 + e_i, e_i ~ N(0, 0.1 ms), written at i/1000.
  occlusion      6 bursts of 15..60 frames hiding the bob, the slider or both (empty CSV
                 cells), the frame before each burst off by 5..20 mm on the vanishing marker(s).

Dynamics
--------
rigid_generator.py's Newton-Euler rows (unknowns x'', theta'', Hx, Hy, N and, while stuck, F),
extended with the effects' terms; no reduced or equivalent-rig formula is used. y DOWN, theta
from +x toward +y (docs/physics.md). D = (Dx, Dy) = drag on the bob at b = pivot + l (cos, sin):
  Slider, x:       m1 x'' = F - Hx + m1 gx
  Slider, y:       0      = N + m1 gy - Hy
  Pendulum, x:     m_p a_x = Hx + m_p gx + Dx
  Pendulum, y:     m_p a_y = Hy + m_p gy + Dy
  Pendulum, spin:  J_cm theta'' = (-d cos) Hy - (-d sin) Hx + (l - d)(cos Dy - sin Dx) - c_d w
(the damping couple's reaction acts on the slider as a torque only, taken by the rail; it is
in no force row). With every effect off the rows, their right-hand sides and the hybrid loop
are rigid_generator.py's operation for operation, so `none` is its output bit for bit (checked).
Energy: E = T + V with V = -m1 gx x - m_p (gx (x + d cos) + gy d sin) (y down); dE/dt = F x'
+ D . v_bob - c_d w^2; each work is integrated alongside as its own state.

Outputs
-------
<effect>_<rig>.csv (one seed) or <effect>_<rig>_s<seed>.csv (several): `t,slider_x,slider_y,
bob_x,bob_y`, metres, 7 decimals, rail frame with y UP (as rigid_generator.py writes it), noise
sigma 0.2 mm per coordinate from numpy.random.default_rng(seed) (one normal(0, sigma, (2001, 4))
draw first; jitter's offsets and occlusion's bursts are drawn after it from the same rng).
<rig>_measured.toml (the rig as measured, as tests/data/rigid) and misspec_truth.json.

Run (outside CI; Python 3 with numpy and scipy)
---
    /tmp/venv-rigid/bin/python scripts/generators/misspec_generator.py --out tests/data/misspec --seeds 1 --check
Options: --seeds 1 [2 ...], --effects all|name,..., --check (energy balance of every simulated
run, `none` against rigid_generator.py, damping decrement and tilted equilibrium).
"""

import argparse
import json
import math
import os
import platform
import sys
import tempfile

import numpy as np
import scipy
from scipy.integrate import solve_ivp

sys.dont_write_bytecode = True  # leave no __pycache__ in scripts/
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import rigid_generator as rg  # noqa: E402

RTOL, ATOL, FPS, DURATION = rg.RTOL, rg.ATOL, rg.FPS, rg.DURATION
NOISE = 0.0002
MU = 0.25
EFFECTS = ["none", "drag", "lens", "four", "friction_ramp", "jitter", "occlusion"]

# Effect parameters
DRAG_FRACTION, DRAG_SPEED = 0.02, 2.0           # drag = 2 % of m2 g at 2 m/s
LENS_K, LENS_EDGE = 0.01, 1.1                    # 1 % at R_edge = 1.1 x max radius
TILT_DEG, DECREMENT, SCALE, MARKER_E = 1.0, 0.1, 1.015, 0.005
RAMP_MU0, RAMP_SLOPE, RAMP_MIN = 0.25, 2.0, 0.05  # mu(x) = max(0.05, 0.25 (1 + 2 x))
JITTER_SIGMA = 1e-4
OCC_N, OCC_LEN, OCC_MARGIN, OCC_ERR = 6, (15, 60), 20, (0.005, 0.020)


# --------------------------------------------------------------------------------------------
# Model: a rigid_generator Rig plus the effects' physical terms
# --------------------------------------------------------------------------------------------
class Model:
    """rig: rigid_generator.Rig (masses, inertia, mu). Physical extras: tilt (rad), c_drag
    (kg/m, force -c |v| v at the bob's centre), c_damp (N m s, torque -c_d w at the pivot),
    mu_of_x (callable, or None for the constant rig.mu)."""

    def __init__(self, rig, tilt=0.0, c_drag=0.0, c_damp=0.0, mu_of_x=None):
        self.rig, self.tilt, self.c_drag, self.c_damp, self.mu_of_x = rig, tilt, c_drag, c_damp, mu_of_x
        self.gx = rig.g * math.sin(tilt)   # 0.0 and g exactly when tilt = 0
        self.gy = rig.g * math.cos(tilt)
        # Work channels integrated alongside (the first, friction, always: state index 4).
        self.works = ["friction"] + (["drag"] if c_drag else []) + (["damping"] if c_damp else [])
        self.slid = mu_of_x is not None  # also integrate mu(x)|x'| and |x'| (slid-mean)
        self.n = 4 + len(self.works) + (2 if self.slid else 0)

    def mu(self, x):
        return self.rig.mu if self.mu_of_x is None else self.mu_of_x(x)

    def drag(self, th, xd, w):
        """Drag force on the bob's centre and the bob's velocity (y down)."""
        l = self.rig.l
        vx = xd - l * math.sin(th) * w
        vy = l * math.cos(th) * w
        if not self.c_drag:
            return 0.0, 0.0, vx, vy
        sp = math.hypot(vx, vy)
        return -self.c_drag * sp * vx, -self.c_drag * sp * vy, vx, vy


# Unknown order: [xdd, thdd, Hx, Hy, N, F]; rigid_generator._rows extended term by term.
def _rows(md, y):
    rig = md.rig
    th, xd, w = y[1], y[2], y[3]
    m1, mp, d, J, l = rig.m1, rig.m_p, rig.d, rig.J_cm, rig.l
    gx, gy = md.gx, md.gy
    s_, c_ = math.sin(th), math.cos(th)
    Dx, Dy, _, _ = md.drag(th, xd, w)
    A = np.array([
        [m1, 0.0, 1.0, 0.0, 0.0, -1.0],              # m1 xdd + Hx - F = m1 gx
        [0.0, 0.0, 0.0, -1.0, 1.0, 0.0],             # N - Hy = -m1 gy
        [mp, -mp * d * s_, -1.0, 0.0, 0.0, 0.0],     # mp(xdd - d s thdd) - Hx = mp d c w^2 + mp gx + Dx
        [0.0, mp * d * c_, 0.0, -1.0, 0.0, 0.0],     # mp d c thdd - Hy = mp gy + mp d s w^2 + Dy
        [0.0, J, -d * s_, d * c_, 0.0, 0.0],         # J thdd - d s Hx + d c Hy = tau_drag - c_d w
    ])
    rhs = np.array([m1 * gx,
                    -m1 * gy,
                    mp * d * c_ * w * w + mp * gx + Dx,
                    mp * gy + mp * d * s_ * w * w + Dy,
                    (l - d) * (c_ * Dy - s_ * Dx) - md.c_damp * w])
    return A, rhs


def solve_stuck(md, y):
    A, rhs = _rows(md, y)
    A = np.vstack([A, [1.0, 0, 0, 0, 0, 0]])
    rhs = np.append(rhs, 0.0)
    return np.linalg.solve(A, rhs)


def solve_sliding_sigma(md, y, s, sigma):
    A, rhs = _rows(md, y)
    mu = md.mu(y[0])
    A = A.copy()
    A[0, 4] += mu * s * sigma
    A = A[:, :5]
    sol = np.linalg.solve(A, rhs)
    F = -mu * s * sigma * sol[4]
    return np.append(sol, F)


def solve_sliding(md, y, s):
    cands = []
    for sigma in (1.0, -1.0):
        sol = solve_sliding_sigma(md, y, s, sigma)
        if sol[4] * sigma >= 0.0:
            cands.append(sol)
    if not cands:
        raise RuntimeError(f"Painleve non-existence at y={list(y[:4])}, s={s}")
    if len(cands) == 2 and not np.allclose(cands[0], cands[1], rtol=1e-9, atol=1e-12):
        raise RuntimeError(f"Painleve non-uniqueness at y={list(y[:4])}, s={s}")
    return cands[0]


def rhs_fn(md, mode, s):
    def f(t, y):
        x, th, xd, w = y[0], y[1], y[2], y[3]
        sol = solve_stuck(md, y) if mode == "stick" else solve_sliding(md, y, s)
        xdd, thdd, F = sol[0], sol[1], sol[5]
        if mode == "stick":
            out = [0.0, w, 0.0, thdd, 0.0]
        else:
            out = [xd, w, xdd, thdd, F * xd]
        if "drag" in md.works:
            Dx, Dy, vx, vy = md.drag(th, xd, w)
            out.append(Dx * vx + Dy * vy)
        if "damping" in md.works:
            out.append(-md.c_damp * w * w)
        if md.slid:
            out += ([0.0, 0.0] if mode == "stick" else [md.mu(x) * abs(xd), abs(xd)])
        return out
    return f


def energy(md, y):
    rig = md.rig
    x, th, xd, w = y[0], y[1], y[2], y[3]
    vcx = xd - rig.d * math.sin(th) * w
    vcy = rig.d * math.cos(th) * w
    T = 0.5 * rig.m1 * xd ** 2 + 0.5 * rig.m_p * (vcx ** 2 + vcy ** 2) + 0.5 * rig.J_cm * w ** 2
    V = (-rig.m1 * md.gx * x
         - rig.m_p * (md.gx * (x + rig.d * math.cos(th)) + md.gy * rig.d * math.sin(th)))
    return T + V


def stick_holds(md, y):
    sol = solve_stuck(md, y)
    return abs(sol[5]) <= md.mu(y[0]) * abs(sol[4]), sol


def cone_ratio(md, y):
    sol = solve_stuck(md, y)
    mu = md.mu(y[0])
    return abs(sol[5]) / (mu * abs(sol[4])) if mu > 0 else math.inf


def slip_direction(md, y):
    sol = solve_stuck(md, y)
    s = -math.copysign(1.0, sol[5])
    A, rhs = _rows(md, y)
    free = np.linalg.solve(A[:, :5], rhs)
    if free[0] * s <= 0.0:
        raise RuntimeError(f"inconsistent slip direction at y={list(y[:4])}")
    sl = solve_sliding(md, y, s)
    if sl[0] * s < -1e-9 * (abs(free[0]) + md.rig.g):
        raise RuntimeError(f"sliding solution opposes the slip at y={list(y[:4])}")
    return s


def simulate(md, y0, t_end, max_events=1000):
    """rigid_generator.simulate with the model's rows. Returns (segments, events, y_end)."""
    y = np.zeros(md.n)
    y[:4] = y0
    t = 0.0
    if y0[2] != 0.0:
        mode, s = "slide", math.copysign(1.0, y0[2])
    else:
        ok, _ = stick_holds(md, y)
        if ok:
            mode, s = "stick", 0.0
        else:
            mode, s = "slide", slip_direction(md, y)
    events = [dict(t=0.0, kind="start_" + mode + ("" if mode == "stick" else f"_{int(s):+d}"),
                   state=y[:4].tolist(), cone_ratio=cone_ratio(md, y))]
    segments = []
    zero_len = 0
    n_dir_next = None
    while t < t_end:
        if len(events) > max_events:
            raise RuntimeError("too many events")
        f = rhs_fn(md, mode, s)
        if mode == "stick":
            def ev_slip(tt, yy):
                sol = solve_stuck(md, yy)
                return md.mu(yy[0]) * abs(sol[4]) - abs(sol[5])
            ev_slip.terminal = True
            ev_slip.direction = -1
            evs = [ev_slip]
        else:
            def ev_stop(tt, yy, s=s):
                return s * yy[2]
            ev_stop.terminal = True
            ev_stop.direction = -1

            def ev_n(tt, yy, s=s):
                return solve_sliding(md, yy, s)[4]
            ev_n.terminal = True
            if n_dir_next is not None:
                ev_n.direction = n_dir_next
            else:
                n0 = ev_n(t, y)
                ev_n.direction = -math.copysign(1.0, n0) if n0 != 0.0 else 0
            evs = [ev_stop, ev_n]
        res = solve_ivp(f, (t, t_end), y, method="DOP853", rtol=RTOL, atol=ATOL,
                        events=evs, dense_output=True, first_step=min(1e-6, t_end - t))
        if res.status < 0:
            raise RuntimeError(res.message)
        t1 = res.t[-1]
        segments.append((t, t1, mode, s, res.sol))
        if res.status == 0:
            t, y = t1, res.y[:, -1]
            break
        fired = [i for i, te in enumerate(res.t_events) if len(te) > 0]
        i = min(fired, key=lambda k: res.t_events[k][0])
        y = res.y_events[i][0].copy()
        te = res.t_events[i][0]
        if te - t < 1e-12:
            zero_len += 1
            if zero_len > 3:
                raise RuntimeError(f"zero-length mode loop at t={te}")
        else:
            zero_len = 0
        t = te
        if mode == "stick":
            y[2] = 0.0
            s = slip_direction(md, y)
            mode = "slide"
            kind = f"slip_{int(s):+d}"
        elif i == 0:
            y[2] = 0.0
            ok, _ = stick_holds(md, y)
            if ok:
                mode, s, kind = "stick", 0.0, "stick"
            else:
                s_new = slip_direction(md, y)
                kind = ("reverse" if s_new != s else "continue") + f"_{int(s_new):+d}"
                s = s_new
        else:
            kind = "normal_zero"
        n_dir_next = (-evs[1].direction if kind == "normal_zero" and evs[1].direction != 0
                      else None)
        events.append(dict(t=t, kind=kind, state=y[:4].tolist(), cone_ratio=cone_ratio(md, y)))
    events.append(dict(t=t, kind="end", state=y[:4].tolist(), cone_ratio=cone_ratio(md, y)))
    return segments, events, y


def sample_at(md, segments, y0, times):
    """State at arbitrary (not necessarily sorted) times. Before t = 0 (jitter's first frame
    only): second-order Taylor from the release, x(t) = x0 + t x0' + t^2/2 x0''."""
    starts = np.array([sg[0] for sg in segments])
    out = np.empty((len(times), md.n))
    y0v = np.zeros(md.n)
    y0v[:4] = y0
    mode0, s0 = segments[0][2], segments[0][3]
    sol0 = solve_stuck(md, y0v) if mode0 == "stick" else solve_sliding(md, y0v, s0)
    for i, tt in enumerate(times):
        if tt < 0.0:
            out[i] = y0v
            out[i, 0] = y0[0] + tt * y0[2] + 0.5 * tt * tt * sol0[0]
            out[i, 1] = y0[1] + tt * y0[3] + 0.5 * tt * tt * sol0[1]
            out[i, 2] = y0[2] + tt * sol0[0]
            out[i, 3] = y0[3] + tt * sol0[1]
            continue
        if tt > segments[-1][1] + 1e-12:
            raise ValueError(f"time {tt} beyond the simulated {segments[-1][1]}")
        k = max(0, int(np.searchsorted(starts, tt, side="left")) - 1)
        # rigid_generator.sample's rule: a time on a boundary belongs to the earlier segment.
        while k < len(segments) - 1 and tt > segments[k][1]:
            k += 1
        out[i] = segments[k][4](tt)
    return out


# --------------------------------------------------------------------------------------------
# Rigs, models, observation
# --------------------------------------------------------------------------------------------
def ramp_mu(x):
    return max(RAMP_MIN, RAMP_MU0 * (1.0 + RAMP_SLOPE * x))


def make_model(effect, name):
    rig = rg.make_rig(name, mu=MU)
    if effect == "drag":
        return Model(rig, c_drag=DRAG_FRACTION * rig.m2 * rig.g / DRAG_SPEED ** 2)
    if effect == "four":
        T = 2 * math.pi * math.sqrt(rig.J / (rig.m_p * rig.g * rig.d))
        return Model(rig, tilt=math.radians(TILT_DEG), c_damp=2 * rig.J * DECREMENT / T)
    if effect == "friction_ramp":
        return Model(rg.make_rig(name, mu=RAMP_MU0), mu_of_x=ramp_mu)
    return Model(rig)


def markers(md, Y, effect):
    """Clean marker positions, file frame (rail frame, y UP): columns sx, sy, bx, by."""
    l = md.rig.l
    x, th = Y[:, 0], Y[:, 1]
    e = MARKER_E if effect == "four" else 0.0
    if e:
        bx = x + l * np.cos(th) - e * np.sin(th)
        by = -(l * np.sin(th) + e * np.cos(th))
    else:  # rigid_generator.write_csv's expressions exactly
        bx = x + l * np.cos(th)
        by = -l * np.sin(th)
    cols = np.column_stack([x, np.zeros_like(x), bx, by])
    if effect == "four":
        cols = cols * SCALE
    return cols


def lens_distort(cols):
    pts = np.vstack([cols[:, 0:2], cols[:, 2:4]])
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    c = 0.5 * (lo + hi)
    r_edge = LENS_EDGE * np.max(np.hypot(pts[:, 0] - c[0], pts[:, 1] - c[1]))
    out = cols.copy()
    for j in (0, 2):
        p = cols[:, j:j + 2] - c
        r = np.hypot(p[:, 0], p[:, 1])
        out[:, j:j + 2] = c + p * (1.0 - LENS_K * (r / r_edge) ** 2)[:, None]
    shift = np.hypot(out[:, [0, 2]] - cols[:, [0, 2]], out[:, [1, 3]] - cols[:, [1, 3]])
    return out, dict(centre_m=c.tolist(), r_edge_m=float(r_edge),
                     max_shift_m=float(shift.max()), median_shift_m=float(np.median(shift)))


def draw_bursts(rng, n_frames):
    """6 non-overlapping bursts after OCC_MARGIN frames and before the last OCC_MARGIN frames,
    each with a visible frame before it (the gross error) that no other burst hides."""
    bursts = []
    tries = 0
    while len(bursts) < OCC_N:
        tries += 1
        if tries > 10000:
            raise RuntimeError("cannot place the occlusion bursts")
        length = int(rng.integers(OCC_LEN[0], OCC_LEN[1] + 1))
        start = int(rng.integers(OCC_MARGIN + 1, n_frames - OCC_MARGIN - length + 1))
        which = ["bob", "slider", "both"][int(rng.integers(0, 3))]
        lo, hi = start - 1, start + length - 1  # the error frame .. the last hidden frame
        if any(not (hi < b["start"] - 2 or lo > b["end"] + 1) for b in bursts):
            continue
        bursts.append(dict(start=start, end=start + length - 1, length=length, hides=which))
    bursts.sort(key=lambda b: b["start"])
    for b in bursts:  # gross errors, drawn after all positions, in time order
        errs = {}
        for m in (["slider", "bob"] if b["hides"] == "both" else [b["hides"]]):
            mag = float(rng.uniform(*OCC_ERR))
            ang = float(rng.uniform(0.0, 2 * math.pi))
            errs[m] = [mag * math.cos(ang), mag * math.sin(ang)]
        b["error_frame"] = b["start"] - 1
        b["gross_error_m"] = errs
    return bursts


def write_csv(path, ts, cols, mask=None):
    """rigid_generator.write_csv's format; mask[i, j] True writes an empty cell."""
    with open(path, "w", newline="\n") as fh:
        fh.write("t,slider_x,slider_y,bob_x,bob_y\n")
        for i, (t, row) in enumerate(zip(ts, cols)):
            cells = ["" if (mask is not None and mask[i, j]) else f"{round(v, 7) + 0.0:.7f}"
                     for j, v in enumerate(row)]
            fh.write(f"{t:.3f}," + ",".join(cells) + "\n")


def write_toml(out, name, rig):
    with open(os.path.join(out, f"{name}_measured.toml"), "w") as fh:
        fh.write(f"# The '{name}' rigid rig of the <effect>_{name}*.csv recordings as measured: a "
                 f"uniform rod and a solid sphere bob\n# (made by scripts/generators/misspec_generator.py, "
                 f"the same rig as tests/data/rigid/rigid_{name}_measured.toml; friction is the "
                 f"unknown,\n# see misspec_truth.json)\n[rig]\n")
        fh.write(f"slider_mass = {rig.m1!r}   # kg\n")
        fh.write(f"bob_mass = {rig.m2!r}      # kg\n")
        fh.write(f"rod_mass = {rig.m_r!r}      # kg, uniform rod from the pivot to the bob's centre\n")
        fh.write(f"bob_radius = {rig.R!r}    # m, solid sphere\n")
        fh.write(f"rod_length = {rig.l!r}     # m, pivot to the bob's centre\n")
        fh.write(f"gravity = {rig.g!r}      # m/s^2\n")


# --------------------------------------------------------------------------------------------
# Checks
# --------------------------------------------------------------------------------------------
def energy_error(md, Y):
    E = np.array([energy(md, y) for y in Y])
    W = Y[:, 4:4 + len(md.works)].sum(axis=1)
    err = np.max(np.abs(E - W - (E[0] - W[0])))
    return err, {k: float(Y[-1, 4 + i]) for i, k in enumerate(md.works)}


def check_none_vs_rigid(name, Y_none, ts, seed):
    rig = rg.make_rig(name)
    segs, evs, _ = rg.simulate(rig, rg.RIGS[name]["release"], DURATION)
    Yr = rg.sample(segs, ts)
    dmax = float(np.max(np.abs(Yr[:, :4] - Y_none[:, :4])))
    with tempfile.TemporaryDirectory() as td:
        pa, pb = os.path.join(td, "a.csv"), os.path.join(td, "b.csv")
        rg.write_csv(pa, ts, Yr, rig, seed, NOISE)
        md = Model(rig)
        write_csv(pb, ts, markers(md, Y_none, "none")
                  + np.random.default_rng(seed).normal(0.0, NOISE, (len(ts), 4)))
        same = open(pa, "rb").read() == open(pb, "rb").read()
    return dmax, same, len(evs)


def check_damping_and_tilt(name):
    """Stuck pendulum of the `four` model (tilt + damping): equilibrium at pi/2 - alpha and
    logarithmic decrement of small swings about it."""
    md = make_model("four", name)
    alpha = md.tilt
    th_eq = math.pi / 2 - alpha
    sol = solve_stuck(md, np.array([0.0, th_eq, 0.0, 0.0] + [0.0] * (md.n - 4)))
    acc_eq = abs(sol[1])
    amp = 1e-3
    segs, evs, _ = simulate(md, (0.0, th_eq + amp, 0.0, 0.0), 6.0)
    ts = np.linspace(0, 6.0, 60001)
    Y = sample_at(md, segs, (0.0, th_eq + amp, 0.0, 0.0), ts)
    u = Y[:, 1] - th_eq
    # successive maxima
    idx = [i for i in range(1, len(u) - 1) if u[i] > u[i - 1] and u[i] >= u[i + 1] and u[i] > 0]
    peaks = u[idx]
    dec = float(np.mean(np.log(peaks[:-1] / peaks[1:]))) if len(peaks) > 2 else float("nan")
    err, _ = energy_error(md, Y)
    return dict(stuck_throughout=len(evs) == 2, theta_dd_at_equilibrium=float(acc_eq),
                log_decrement=dec, n_peaks=len(peaks), energy_err=float(err))


# --------------------------------------------------------------------------------------------
# Main
# --------------------------------------------------------------------------------------------
def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", required=True)
    ap.add_argument("--seeds", type=int, nargs="+", default=[1])
    ap.add_argument("--effects", default="all")
    ap.add_argument("--check", action="store_true")
    args = ap.parse_args(argv)
    effects = EFFECTS if args.effects == "all" else args.effects.split(",")
    for e in effects:
        if e not in EFFECTS:
            raise SystemExit(f"unknown effect {e!r}; known: {','.join(EFFECTS)}")
    os.makedirs(args.out, exist_ok=True)
    n_frames = int(round(DURATION * FPS)) + 1
    ts = np.round(np.arange(n_frames) / FPS, 12)
    ok_all = True

    truth = dict(generator="scripts/generators/misspec_generator.py", based_on="scripts/generators/rigid_generator.py",
                 python=platform.python_version(), numpy=np.__version__, scipy=scipy.__version__,
                 solver=dict(method="DOP853", rtol=RTOL, atol=ATOL), frame_rate_hz=FPS,
                 duration_s=DURATION, noise_sigma_m=NOISE, seeds=args.seeds,
                 bob_marker="bob centre, at rod_length along the rod (four: plus 5 mm across)",
                 frame="rail frame, y up (bob at x + l cos theta, -l sin theta)",
                 theta_convention="docs/physics.md: from +x, y down, pi/2 hangs down",
                 effects={})
    for name in rg.RIGS:
        write_toml(args.out, name, rg.make_rig(name))

    cache = {}

    def run(effect, name, t_end=DURATION):
        key = (effect if effect in ("drag", "four", "friction_ramp") else "none", name, t_end)
        if key not in cache:
            md = make_model(key[0], name)
            segs, evs, yend = simulate(md, rg.RIGS[name]["release"], t_end)
            cache[key] = (md, segs, evs)
        return cache[key]

    for effect in effects:
        truth["effects"][effect] = {}
        for name in rg.RIGS:
            release = rg.RIGS[name]["release"]
            t_end = DURATION + 0.002 if effect == "jitter" else DURATION
            md, segs, evs = run(effect, name, t_end)
            Y = sample_at(md, segs, release, ts)
            rig = md.rig
            ent = dict(rig=rig.describe(), release=dict(zip(["x", "theta", "x_dot", "theta_dot"],
                                                            release)),
                       seeds=args.seeds, mu_defined=effect != "friction_ramp",
                       slider_x_range_m=[float(Y[:, 0].min()), float(Y[:, 0].max())],
                       events=[dict(t=e["t"], kind=e["kind"],
                                    state=dict(zip(["x", "theta", "x_dot", "theta_dot"],
                                                   e["state"])),
                                    stuck_cone_ratio=e["cone_ratio"]) for e in evs])
            params = {}
            if effect == "friction_ramp":
                I_mu, I_abs = Y[-1, -2], Y[-1, -1]
                ent.update(mu=None, mu0=RAMP_MU0, mu_slid_mean=float(I_mu / I_abs),
                           slide_distance_m=float(I_abs))
                ent["rig"].update(mu=None, mu_kinetic=None, mu_static=None,
                                  friction_law="coulomb, mu(x) = max(0.05, 0.25 (1 + 2 x))")
                params = dict(mu_of_x="max(0.05, mu0 * (1 + 2 * x)), x in m", mu0=RAMP_MU0,
                              slope_per_m=RAMP_SLOPE, mu_min=RAMP_MIN,
                              applies_to="stick test and sliding friction")
            else:
                ent.update(mu=MU, mu_kinetic=MU, mu_static=MU, friction_law="coulomb")
            if effect == "drag":
                spd = np.hypot(Y[:, 2] - rig.l * np.sin(Y[:, 1]) * Y[:, 3],
                               rig.l * np.cos(Y[:, 1]) * Y[:, 3])
                params = dict(c_kg_per_m=md.c_drag, law="-c |v| v at the bob's centre",
                              definition="0.02 m2 g / (2 m/s)^2",
                              max_bob_speed_m_s=float(spd.max()),
                              max_drag_over_bob_weight=float(md.c_drag * spd.max() ** 2
                                                             / (rig.m2 * rig.g)))
            if effect == "four":
                T = 2 * math.pi * math.sqrt(rig.J / (rig.m_p * rig.g * rig.d))
                params = dict(rail_tilt_deg=TILT_DEG, rail_tilt_rad=md.tilt,
                              tilt_convention="gravity in the rail frame (y down) = g (sin a, "
                                              "cos a): +x downhill; stuck pendulum hangs at "
                                              "theta = pi/2 - a (bob toward +x)",
                              pivot_damping_N_m_s=md.c_damp, log_decrement=DECREMENT,
                              stuck_period_s=T, camera_scale=SCALE,
                              bob_marker_across_m=MARKER_E,
                              bob_marker_convention="at l along the rod plus e across it toward "
                                                    "increasing theta: (x + l cos - e sin, "
                                                    "l sin + e cos) y down")
            if effect == "lens":
                params = dict(k=LENS_K, r_edge_factor=LENS_EDGE,
                              law="c + (p - c)(1 - k (|p - c| / R_edge)^2), before the noise")
            if effect == "jitter":
                params = dict(sigma_s=JITTER_SIGMA, written_times="nominal i/1000",
                              drawn="after the position noise, normal(0, sigma, 2001)",
                              before_t0="second-order Taylor from the release state")
            if effect == "occlusion":
                params = dict(n_bursts=OCC_N, length_frames=list(OCC_LEN),
                              margin_frames=OCC_MARGIN, gross_error_m=list(OCC_ERR),
                              per_seed={})
            if args.check and effect in ("none", "drag", "four", "friction_ramp", "jitter"):
                err, works = energy_error(md, Y)
                scale = rig.m_p * rig.g * rig.d
                good = err / scale < 1e-7
                ok_all &= good
                print(f"(check) energy [{effect} {name}]: max |E - W - E0| = {err:.2e} J "
                      f"({err / scale:.1e} of m_p g d), works "
                      + ", ".join(f"{k} {v:.5f} J" for k, v in works.items())
                      + f"  {'OK' if good else 'FAIL'}")
                ent.setdefault("self_check", {})["energy_max_err_J"] = float(err)
                ent["self_check"]["works_J"] = works
            ent["effect_parameters"] = params

            clean = markers(md, Y, effect)
            if effect == "lens":
                clean, info = lens_distort(clean)
                params.update(info)
            for seed in args.seeds:
                rng = np.random.default_rng(seed)
                noise = rng.normal(0.0, NOISE, size=clean.shape)
                cols, mask = clean, None
                if effect == "jitter":
                    e = rng.normal(0.0, JITTER_SIGMA, n_frames)
                    Yj = sample_at(md, segs, release, ts + e)
                    cols = markers(md, Yj, "none")
                    params.setdefault("per_seed", {})[str(seed)] = dict(
                        e_std_s=float(e.std()), e_max_abs_s=float(np.abs(e).max()),
                        max_position_shift_m=float(np.max(np.abs(cols - clean))))
                cols = cols + noise
                if effect == "occlusion":
                    bursts = draw_bursts(rng, n_frames)
                    cols = cols.copy()
                    mask = np.zeros(cols.shape, dtype=bool)
                    for b in bursts:
                        for m, err in b["gross_error_m"].items():
                            j = 0 if m == "slider" else 2
                            cols[b["error_frame"], j:j + 2] += err
                            mask[b["start"]:b["end"] + 1, j:j + 2] = True
                    params["per_seed"][str(seed)] = bursts
                fn = (f"{effect}_{name}.csv" if len(args.seeds) == 1
                      else f"{effect}_{name}_s{seed}.csv")
                write_csv(os.path.join(args.out, fn), ts, cols, mask)
                if args.check and effect == "none":
                    dmax, same, _ = check_none_vs_rigid(name, Y, ts, seed)
                    good = same or dmax <= 1e-12
                    ok_all &= good
                    print(f"(check) none vs rigid_generator [{name} seed {seed}]: max |state "
                          f"diff| = {dmax:.1e}, CSV bytes identical: {same}  "
                          f"{'OK' if good else 'FAIL'}")
                    ent.setdefault("self_check", {})[f"vs_rigid_generator_s{seed}"] = dict(
                        max_state_diff=dmax, csv_identical=same)
            nsw = len(evs) - 2
            print(f"== {effect:<13s} {name:<5s}: {nsw} switches, slider x "
                  f"[{Y[:, 0].min():+.4f}, {Y[:, 0].max():+.4f}] m"
                  + (f", mu slid-mean {ent['mu_slid_mean']:.5f}" if effect == "friction_ramp"
                     else "") + ": " + ", ".join(f"{e['kind']} {e['t']:.4f}"
                                                 for e in evs[1:-1]))
            truth["effects"][effect][name] = ent
        if args.check and effect == "four":
            for name in rg.RIGS:
                r = check_damping_and_tilt(name)
                good = (r["stuck_throughout"] and r["theta_dd_at_equilibrium"] < 1e-12
                        and abs(r["log_decrement"] / DECREMENT - 1) < 0.01)
                ok_all &= good
                print(f"(check) four [{name}] stuck pendulum: theta'' at pi/2 - alpha = "
                      f"{r['theta_dd_at_equilibrium']:.1e}, log decrement "
                      f"{r['log_decrement']:.5f} (target {DECREMENT}, {r['n_peaks']} peaks), "
                      f"energy err {r['energy_err']:.1e} J  {'OK' if good else 'FAIL'}")
                truth["effects"]["four"][name].setdefault("self_check", {})["stuck"] = r
    with open(os.path.join(args.out, "misspec_truth.json"), "w") as fh:
        json.dump(truth, fh, indent=2)
        fh.write("\n")
    if args.check:
        print("all checks", "PASSED" if ok_all else "FAILED")
    return 0 if ok_all else 1


if __name__ == "__main__":
    sys.exit(main())
