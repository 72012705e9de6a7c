#!/usr/bin/env python3
"""Independent reference simulator: a RIGID pendulum on a sliding pivot with Coulomb friction.

Purpose
-------
Generates the synthetic recordings in tests/data/rigid/ and their ground truth, to test the
`appell` tool's rigid-pendulum support (docs/physics.md, "The rigid pendulum"). The Rust code reduces a
rigid pendulum to an "equivalent point rig" (slider m1 + m_p - m_e, bob m_e, length L). This
script deliberately does NOT use that mapping: it integrates the two bodies by Newton-Euler, so
an agreement between the two is evidence that the mapping (and its implementation) is right.

This script is outside CI: it needs Python 3 with numpy and scipy, and is run by hand.

Rig and conventions (docs/physics.md)
--------------------------------
Rail = x axis, y points DOWN, gravity +g along y. Slider (mass m1) at (x, 0), translating along
x only, on a bilateral rail: the rail's normal force N (its y component on the slider) may have
either sign; friction uses |N|. theta is the angle from +x to the rod (y down); theta = pi/2
hangs straight down. The pendulum is a uniform rod (mass m_r, from the pivot to the bob's
centre, length l) plus a solid sphere bob (mass m2, radius R) centred at distance l. Its mass
m_p, centre-of-mass distance d and inertia about its own centre of mass J_cm are summed from
the parts here (rod m_r l^2/12 about its middle, sphere 2/5 m2 R^2 about its centre, parallel
axis to the common CM).

Derivation (Newton-Euler, unknowns x'', theta'', Hx, Hy, N and, while stuck, F)
-------------------------------------------------------------------------------
H = (Hx, Hy): force of the slider on the pendulum at the pivot. w = theta'.
CM of the pendulum: (x + d cos theta, d sin theta), so its acceleration is
    a_x = x'' - d sin(theta) theta'' - d cos(theta) w^2
    a_y =       d cos(theta) theta'' - d sin(theta) w^2
Slider, x:       m1 x'' = F - Hx
Slider, y:       0      = N + m1 g - Hy             (it does not leave the rail)
Pendulum, x:     m_p a_x = Hx
Pendulum, y:     m_p a_y = Hy + m_p g
Pendulum, spin:  J_cm theta'' = torque of H about the CM
                             = (-d cos theta) Hy - (-d sin theta) Hx
                 (the pivot sits at -d (cos theta, sin theta) from the CM; z = x cross y is
                  the direction of increasing theta)
Stuck: x'' = 0 and F is an unknown (6 x 6 linear system).
Sliding with s = sign(x'): F = -mu s |N| = -mu s sigma N with sigma = sign(N); both sigma = +1
and -1 are tried and the self-consistent one kept (5 x 5 linear system each).
Each system is solved with numpy.linalg.solve at every right-hand-side evaluation.

Hybrid loop (scipy.integrate.solve_ivp, DOP853, rtol 1e-11, atol 1e-13, terminal events)
  stick -> slide  when |F_needed| reaches mu |N|; the slider starts in the direction
                  s = -sign(F_needed) (opposite to the friction that was needed, i.e. the
                  friction-free acceleration; checked against the sliding solution).
  slide -> stick  when x' reaches 0 and |F_needed| <= mu |N| there; otherwise it keeps
                  sliding in the direction -sign(F_needed) (reversal or continuation).
  slide, N = 0    restart (sigma flips; friction is continuous there).
The friction work W (W' = F x') is integrated alongside for the energy check.

Run
---
    python3 -m venv /tmp/venv-rigid && /tmp/venv-rigid/bin/pip install numpy scipy
    /tmp/venv-rigid/bin/python scripts/generators/rigid_generator.py --out tests/data/rigid --check
Options: --seeds 1 [2 3 ...] (several seeds write rigid_<rig>_s<seed>.csv instead of
rigid_<rig>.csv, for a coverage sweep), --noise 0.0002 (marker noise sigma, m), --check (self
checks: energy balance, momentum at mu = 0, small-swing period, and for information the
agreement with docs/physics.md's reduced formulas).
"""

import argparse
import json
import math
import os
import platform
import sys

import numpy as np
import scipy
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

RTOL = 1e-11
ATOL = 1e-13
FPS = 1000
DURATION = 2.0


# --------------------------------------------------------------------------------------------
# Rig
# --------------------------------------------------------------------------------------------
class Rig:
    def __init__(self, m1, m2, l, R, m_r, g, mu):
        self.m1, self.m2, self.l, self.R, self.m_r, self.g, self.mu = m1, m2, l, R, m_r, g, mu
        # Pendulum = rod (CM at l/2) + sphere (CM at l), summed here from the parts.
        self.m_p = m2 + m_r
        self.d = (m2 * l + m_r * l / 2.0) / self.m_p
        j_rod_cm = m_r * l * l / 12.0 + m_r * (l / 2.0 - self.d) ** 2
        j_sph_cm = 0.4 * m2 * R * R + m2 * (l - self.d) ** 2
        self.J_cm = j_rod_cm + j_sph_cm
        self.J = self.J_cm + self.m_p * self.d ** 2  # about the pivot
        # Derived quantities, for information and for the truth file only (not used in the
        # dynamics).
        self.L = self.J / (self.m_p * self.d)
        self.m_e = (self.m_p * self.d) ** 2 / self.J
        self.r_prime = (m1 + self.m_p - self.m_e) / self.m_e
        self.mu_star = 2.0 * math.sqrt(self.r_prime * (1.0 + self.r_prime))

    def describe(self):
        return dict(m1=self.m1, m2=self.m2, rod_mass=self.m_r, rod_length=self.l,
                    bob_radius=self.R, gravity=self.g, mu=self.mu, mu_kinetic=self.mu,
                    mu_static=self.mu, friction_law="coulomb", m_p=self.m_p, d=self.d,
                    J_cm=self.J_cm, J=self.J, L=self.L, m_e=self.m_e, r_prime=self.r_prime,
                    mu_star=self.mu_star,
                    stuck_period=2 * math.pi * math.sqrt(self.J / (self.m_p * self.g * self.d)))


# --------------------------------------------------------------------------------------------
# Newton-Euler
# --------------------------------------------------------------------------------------------
# Unknown order: [xdd, thdd, Hx, Hy, N, F]
def _rows(rig, th, w):
    m1, mp, d, g, J = rig.m1, rig.m_p, rig.d, rig.g, rig.J_cm
    s_, c_ = math.sin(th), math.cos(th)
    A = np.array([
        [m1, 0.0, 1.0, 0.0, 0.0, -1.0],              # m1 xdd + Hx - F = 0
        [0.0, 0.0, 0.0, -1.0, 1.0, 0.0],             # N - Hy = -m1 g
        [mp, -mp * d * s_, -1.0, 0.0, 0.0, 0.0],     # mp(xdd - d s thdd) - Hx = mp d c w^2
        [0.0, mp * d * c_, 0.0, -1.0, 0.0, 0.0],     # mp d c thdd - Hy = mp g + mp d s w^2
        [0.0, J, -d * s_, d * c_, 0.0, 0.0],         # J thdd - d s Hx + d c Hy = 0
    ])
    rhs = np.array([0.0, -m1 * g, mp * d * c_ * w * w, mp * g + mp * d * s_ * w * w, 0.0])
    return A, rhs


def solve_stuck(rig, th, w):
    """Returns (xdd, thdd, Hx, Hy, N, F) with x'' = 0."""
    A, rhs = _rows(rig, th, w)
    A = np.vstack([A, [1.0, 0, 0, 0, 0, 0]])
    rhs = np.append(rhs, 0.0)
    return np.linalg.solve(A, rhs)


def solve_sliding_sigma(rig, th, w, s, sigma):
    A, rhs = _rows(rig, th, w)
    # F = -mu s sigma N: fold into row 0, drop the F column.
    A = A.copy()
    A[0, 4] += rig.mu * s * sigma
    A = A[:, :5]
    sol = np.linalg.solve(A, rhs)
    F = -rig.mu * s * sigma * sol[4]
    return np.append(sol, F)


def solve_sliding(rig, th, w, s):
    """Sliding in direction s; sigma = sign(N) chosen self-consistently."""
    cands = []
    for sigma in (1.0, -1.0):
        sol = solve_sliding_sigma(rig, th, w, s, sigma)
        if sol[4] * sigma >= 0.0:
            cands.append(sol)
    if not cands:
        raise RuntimeError("Painleve non-existence: no consistent sliding solution "
                           f"at theta={th}, w={w}, s={s}")
    if len(cands) == 2 and not np.allclose(cands[0], cands[1], rtol=1e-9, atol=1e-12):
        raise RuntimeError(f"Painleve non-uniqueness at theta={th}, w={w}, s={s}")
    return cands[0]


def accel(rig, mode, s, y):
    x, th, xd, w, W = y
    sol = solve_stuck(rig, th, w) if mode == "stick" else solve_sliding(rig, th, w, s)
    return sol


def rhs_fn(rig, mode, s):
    def f(t, y):
        x, th, xd, w, W = y
        sol = accel(rig, mode, s, y)
        xdd, thdd, F = sol[0], sol[1], sol[5]
        if mode == "stick":
            return [0.0, w, 0.0, thdd, 0.0]
        return [xd, w, xdd, thdd, F * xd]
    return f


def energy(rig, y):
    x, th, xd, w, W = y
    vcx = xd - rig.d * math.sin(th) * w
    vcy = rig.d * math.cos(th) * w
    T = 0.5 * rig.m1 * xd ** 2 + 0.5 * rig.m_p * (vcx ** 2 + vcy ** 2) + 0.5 * rig.J_cm * w ** 2
    V = -rig.m_p * rig.g * rig.d * math.sin(th)  # y down: V = -m g y_cm
    return T + V


def momentum(rig, y):
    x, th, xd, w, W = y
    return (rig.m1 + rig.m_p) * xd - rig.m_p * rig.d * w * math.sin(th)


# --------------------------------------------------------------------------------------------
# Hybrid simulation
# --------------------------------------------------------------------------------------------
def stick_holds(rig, th, w):
    sol = solve_stuck(rig, th, w)
    return abs(sol[5]) <= rig.mu * abs(sol[4]), sol


def cone_ratio(rig, th, w):
    """|F_needed| / (mu |N|) for the stuck state: <= 1 inside the friction cone."""
    sol = solve_stuck(rig, th, w)
    return abs(sol[5]) / (rig.mu * abs(sol[4])) if rig.mu > 0 else math.inf


def slip_direction(rig, th, w):
    """Direction the slider takes when sticking fails: opposite to the needed friction.
    Checked: the sliding solution in that direction must accelerate that way."""
    sol = solve_stuck(rig, th, w)
    s = -math.copysign(1.0, sol[5])
    # Friction-free acceleration (same system, mu = 0): must point along s.
    A, rhs = _rows(rig, th, w)
    free = np.linalg.solve(A[:, :5], rhs)
    if free[0] * s <= 0.0:
        raise RuntimeError(f"inconsistent slip direction at theta={th}, w={w}: "
                           f"F_needed={sol[5]}, friction-free xdd={free[0]}")
    # The sliding solution that way may not decelerate (x'' = 0 exactly on the cone's edge).
    sl = solve_sliding(rig, th, w, s)
    if sl[0] * s < -1e-9 * (abs(free[0]) + rig.g):
        raise RuntimeError(f"sliding solution opposes the slip at theta={th}, w={w}: "
                           f"xdd({s})={sl[0]}")
    return s


def simulate(rig, y0, t_end, max_events=1000, verbose=False):
    """Returns (segments, events). segments: list of (t0, t1, mode, s, OdeSolution).
    events: list of dicts (t, kind, state)."""
    x0, th0, xd0, w0 = y0
    y = np.array([x0, th0, xd0, w0, 0.0])
    t = 0.0
    if xd0 != 0.0:
        mode, s = "slide", math.copysign(1.0, xd0)
    else:
        ok, _ = stick_holds(rig, th0, w0)
        if ok:
            mode, s = "stick", 0.0
        else:
            mode, s = "slide", slip_direction(rig, th0, w0)
    events = [dict(t=0.0, kind="start_" + mode + ("" if mode == "stick" else f"_{int(s):+d}"),
                   state=y[:4].tolist(), cone_ratio=cone_ratio(rig, th0, w0))]
    segments = []
    zero_len = 0
    n_dir_next = None
    while t < t_end:
        if len(events) > max_events:
            raise RuntimeError("too many events")
        f = rhs_fn(rig, mode, s)
        if mode == "stick":
            def ev_slip(tt, yy):
                sol = solve_stuck(rig, yy[1], yy[3])
                return rig.mu * abs(sol[4]) - abs(sol[5])
            ev_slip.terminal = True
            ev_slip.direction = -1
            evs = [ev_slip]
        else:
            def ev_stop(tt, yy, s=s):
                return s * yy[2]
            ev_stop.terminal = True
            ev_stop.direction = -1

            def ev_n(tt, yy, s=s):
                return solve_sliding(rig, yy[1], yy[3], s)[4]
            ev_n.terminal = True
            # The next sign change of N: away from its sign at the start, or, if the segment
            # starts at N = 0, back from the side it just crossed to.
            if n_dir_next is not None:
                ev_n.direction = n_dir_next
            else:
                n0 = ev_n(t, y)
                ev_n.direction = -math.copysign(1.0, n0) if n0 != 0.0 else 0
            evs = [ev_stop, ev_n]
        # A segment starts where its event function is zero (x' = 0, or the cone's edge): a
        # small first step keeps the root finder off the bracket [t0, t1] with g(t0) = 0,
        # which would report a zero-length segment when the state turns within one step.
        res = solve_ivp(f, (t, t_end), y, method="DOP853", rtol=RTOL, atol=ATOL,
                        events=evs, dense_output=True, first_step=min(1e-6, t_end - t))
        if res.status < 0:
            raise RuntimeError(res.message)
        t1 = res.t[-1]
        segments.append((t, t1, mode, s, res.sol))
        if res.status == 0:
            t, y = t1, res.y[:, -1]
            break
        # Which event fired?
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
            s = slip_direction(rig, y[1], y[3])
            mode = "slide"
            kind = f"slip_{int(s):+d}"
        elif i == 0:  # x' = 0
            y[2] = 0.0
            ok, _ = stick_holds(rig, y[1], y[3])
            if ok:
                mode, s, kind = "stick", 0.0, "stick"
            else:
                s_new = slip_direction(rig, y[1], y[3])
                kind = "reverse" if s_new != s else "continue"
                kind += f"_{int(s_new):+d}"
                s = s_new
        else:
            kind = "normal_zero"
        # The rail's normal force changed sign: its next crossing goes back.
        n_dir_next = (-evs[1].direction if kind == "normal_zero" and evs[1].direction != 0
                      else None)
        events.append(dict(t=t, kind=kind, state=y[:4].tolist(),
                           cone_ratio=cone_ratio(rig, y[1], y[3])))
        if verbose:
            print(f"    t = {t:.6f} s  {kind}")
    events.append(dict(t=t, kind="end", state=y[:4].tolist(),
                       cone_ratio=cone_ratio(rig, y[1], y[3])))
    return segments, events, y


def sample(segments, times):
    out = np.empty((len(times), 5))
    k = 0
    for i, tt in enumerate(times):
        while k < len(segments) - 1 and tt > segments[k][1]:
            k += 1
        out[i] = segments[k][4](tt)
    return out


# --------------------------------------------------------------------------------------------
# Rigs and releases
# --------------------------------------------------------------------------------------------
# Releases (x0, theta0, x_dot0, theta_dot0), chosen for several stick/slide transitions in 2 s
# with centimetres of sliding and no paradox (mu = 0.25 is far below mu* for all three):
#   light: bob 0.5 rad above the rail, swung down at 4 rad/s (from rest, this light slider
#          slides almost all the time: only 2-4 stick/slide switches); 8 switches.
#   paper, heavy: the classic, rod horizontal, at rest; 7 switches each.
RIGS = {
    "light": dict(m1=0.05, m2=0.15, m_r=0.02, release=(0.0, -0.5, 0.0, 4.0)),
    "paper": dict(m1=0.10, m2=0.10, m_r=0.02, release=(0.0, 0.0, 0.0, 0.0)),
    "heavy": dict(m1=0.40, m2=0.20, m_r=0.03, release=(0.0, 0.0, 0.0, 0.0)),
}
COMMON = dict(l=0.30, R=0.02, g=9.81, mu=0.25)


def make_rig(name, mu=None):
    p = RIGS[name]
    return Rig(p["m1"], p["m2"], COMMON["l"], COMMON["R"], p["m_r"], COMMON["g"],
               COMMON["mu"] if mu is None else mu)


# --------------------------------------------------------------------------------------------
# Self-checks
# --------------------------------------------------------------------------------------------
def reduced_formulas(rig, th, w, s=None):
    """docs/physics.md's reduced (equivalent point rig) formulas, for an informational comparison
    only; the simulation never uses them."""
    me, M = rig.m_e, rig.m1 + rig.m_p
    D = M - me * math.sin(th) ** 2
    a = me * math.sin(th) * math.cos(th)
    b = me * math.cos(th) * rig.g * math.cos(th) - rig.m_p * rig.d * w * w * math.sin(th) - M * rig.g
    c = me * math.sin(th) * rig.g * math.cos(th) + rig.m_p * rig.d * w * w * math.cos(th)
    if s is None:
        xdd, N, F = 0.0, b, -c
    else:
        sol = None
        for sigma in (1.0, -1.0):
            xdd = (c - rig.mu * s * sigma * b) / (D + rig.mu * s * sigma * a)
            N = b + a * xdd
            if N * sigma >= 0:
                sol = (xdd, N)
                break
        xdd, N = sol
        F = -rig.mu * s * abs(N)
    thdd = (rig.g * math.cos(th) + math.sin(th) * xdd) / rig.L
    return np.array([xdd, thdd, N, F])


def run_checks():
    print("== Self-checks ==")
    ok_all = True

    # (0) docs/physics.md's worked example, from our own inertia sums.
    ex = Rig(0.10, 0.10, 0.30, 0.02, 0.02, 9.81, 0.35)
    T = 2 * math.pi * math.sqrt(ex.J / (ex.m_p * ex.g * ex.d))
    print(f"(info) docs/physics.md example: L = {ex.L:.5f} m (0.29139), m_e = {ex.m_e:.5f} kg "
          f"(0.11325), equivalent slider {ex.m1 + ex.m_p - ex.m_e:.5f} kg (0.10675), "
          f"stuck period {T:.4f} s (1.0829)")

    # (info) Point-rig limit (no rod mass, no radius) against configs/paper_rest_horizontal.toml
    # (mu = 0.35, rod horizontal at rest: slip near 0.0868 s, first stick near 0.326 s).
    pt = Rig(0.10, 0.10, 0.30, 0.0, 0.0, 9.81, 0.35)
    _, pev, _ = simulate(pt, (0.0, 0.0, 0.0, 0.0), DURATION)
    print("(info) point-rig limit, paper rig, mu = 0.35, rod horizontal: "
          + ", ".join(f"{e['kind']} {e['t']:.4f}" for e in pev[1:4])
          + " s (paper_rest_horizontal.toml: slip 0.0868, stick 0.326)")

    # (info) Newton-Euler against the reduced formulas at random states.
    rng = np.random.default_rng(12345)
    worst = 0.0
    for name in RIGS:
        rig = make_rig(name)
        for _ in range(200):
            th = rng.uniform(-math.pi, math.pi)
            w = rng.uniform(-10, 10)
            ne = solve_stuck(rig, th, w)
            rf = reduced_formulas(rig, th, w)
            worst = max(worst, np.max(np.abs(ne[[0, 1, 4, 5]] - rf)))
            for s in (1.0, -1.0):
                ne = solve_sliding(rig, th, w, s)
                rf = reduced_formulas(rig, th, w, s)
                worst = max(worst, np.max(np.abs(ne[[0, 1, 4, 5]] - rf)))
    print(f"(info) Newton-Euler vs docs/physics.md reduced formulas (x'', theta'', N, F), "
          f"1200 random states: max |diff| = {worst:.2e}")

    # (1) Energy balance over 2 s with slides.
    for name in RIGS:
        rig = make_rig(name)
        segs, evs, _ = simulate(rig, RIGS[name]["release"], DURATION)
        ts = np.linspace(0, DURATION, 2001)
        Y = sample(segs, ts)
        E = np.array([energy(rig, y) for y in Y])
        err = np.max(np.abs(E - Y[:, 4] - E[0]))
        scale = rig.m_p * rig.g * rig.d
        nsl = sum(1 for e in evs if e["kind"].startswith("slip"))
        good = err / scale < 1e-7
        ok_all &= good
        print(f"(1) energy balance [{name}]: max |E - W - E0| = {err:.2e} J, "
              f"relative to m_p g d = {scale:.4f} J: {err / scale:.2e}; "
              f"friction work {Y[-1, 4]:.5f} J; {nsl} slips  {'OK' if good else 'FAIL'}")

    # (2) mu = 0: horizontal momentum conserved.
    for name in RIGS:
        rig = make_rig(name, mu=0.0)
        segs, evs, _ = simulate(rig, (0.0, 0.3, 0.0, 0.0), DURATION)
        ts = np.linspace(0, DURATION, 2001)
        Y = sample(segs, ts)
        P = np.array([momentum(rig, y) for y in Y])
        E = np.array([energy(rig, y) for y in Y])
        scale = rig.m_p * rig.d * np.max(np.abs(Y[:, 3]))
        drift = np.max(np.abs(P - P[0]))
        good = drift / scale < 1e-8
        ok_all &= good
        print(f"(2) mu = 0 momentum [{name}]: max |p - p0| = {drift:.2e} kg m/s "
              f"(relative to m_p d max|w| = {drift / scale:.2e}), energy drift "
              f"{np.max(np.abs(E - E[0])):.2e} J, {len(evs) - 2} reversals  "
              f"{'OK' if good else 'FAIL'}")

    # (3) Small-swing stuck period.
    for name in RIGS:
        rig = make_rig(name)
        amp = 1e-3
        segs, evs, _ = simulate(rig, (0.0, math.pi / 2 + amp, 0.0, 0.0), 12.0)
        assert len(evs) == 2 and evs[0]["kind"] == "start_stick", evs
        sol = segs[0][4]
        ts = np.linspace(0, 12.0, 24001)
        th = np.array([sol(t)[1] for t in ts]) - math.pi / 2
        roots = []
        for i in range(len(ts) - 1):
            if th[i] == 0 or th[i] * th[i + 1] < 0:
                roots.append(brentq(lambda t: sol(t)[1] - math.pi / 2, ts[i], ts[i + 1],
                                    xtol=1e-15, rtol=1e-15))
        roots = np.array(roots)
        n = len(roots) - 1
        T_meas = 2 * (roots[-1] - roots[0]) / n
        T_th = 2 * math.pi * math.sqrt(rig.J / (rig.m_p * rig.g * rig.d))
        rel = abs(T_meas / T_th - 1)
        good = rel < 1e-6
        ok_all &= good
        print(f"(3) stuck period [{name}]: measured {T_meas:.9f} s, 2 pi sqrt(J/(m_p g d)) "
              f"= {T_th:.9f} s, rel. error {rel:.2e} (amplitude {amp} rad, {n} half periods)"
              f"  {'OK' if good else 'FAIL'}")
    print("all checks", "PASSED" if ok_all else "FAILED")
    return ok_all


# --------------------------------------------------------------------------------------------
# Outputs
# --------------------------------------------------------------------------------------------
def write_csv(path, ts, Y, rig, seed, noise):
    x, th = Y[:, 0], Y[:, 1]
    cols = np.column_stack([x, np.zeros_like(x), x + rig.l * np.cos(th), -rig.l * np.sin(th)])
    rng = np.random.default_rng(seed)
    cols = cols + rng.normal(0.0, noise, size=cols.shape)
    with open(path, "w", newline="\n") as fh:
        fh.write("t,slider_x,slider_y,bob_x,bob_y\n")
        for t, row in zip(ts, cols):
            # round first, then + 0.0, so that no "-0.0000000" appears
            fh.write(f"{t:.3f}," + ",".join(f"{round(v, 7) + 0.0:.7f}" for v in row) + "\n")


def write_tomls(out, name, rig):
    with open(os.path.join(out, f"rigid_{name}_measured.toml"), "w") as fh:
        fh.write(f"# The '{name}' rigid rig of rigid_{name}.csv as measured: a uniform rod "
                 f"and a solid sphere bob\n# (made by scripts/generators/rigid_generator.py; friction "
                 f"is the unknown, see rigid_truth.json)\n[rig]\n")
        fh.write(f"slider_mass = {rig.m1!r}   # kg\n")
        fh.write(f"bob_mass = {rig.m2!r}      # kg\n")
        fh.write(f"rod_mass = {rig.m_r!r}      # kg, uniform rod from the pivot to the bob's centre\n")
        fh.write(f"bob_radius = {rig.R!r}    # m, solid sphere\n")
        fh.write(f"rod_length = {rig.l!r}     # m, pivot to the bob's centre\n")
        fh.write(f"gravity = {rig.g!r}      # m/s^2\n")
    with open(os.path.join(out, f"rigid_{name}_lab.toml"), "w") as fh:
        fh.write(f"# The '{name}' rigid rig as a lab would write it down: the masses and the "
                 f"rod length only\n# (no rod mass, no bob radius; a point-bob model of "
                 f"rigid_{name}.csv)\n[rig]\n")
        fh.write(f"slider_mass = {rig.m1!r}   # kg\n")
        fh.write(f"bob_mass = {rig.m2!r}      # kg\n")
        fh.write(f"rod_length = {rig.l!r}     # m\n")
        fh.write(f"gravity = {rig.g!r}      # m/s^2\n")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", required=True)
    ap.add_argument("--seeds", type=int, nargs="+", default=[1])
    ap.add_argument("--check", action="store_true")
    ap.add_argument("--noise", type=float, default=0.0002)
    args = ap.parse_args(argv)

    if args.check and not run_checks():
        return 1

    os.makedirs(args.out, exist_ok=True)
    ts = np.round(np.arange(int(round(DURATION * FPS)) + 1) / FPS, 12)
    truth = dict(generator="scripts/generators/rigid_generator.py", python=platform.python_version(),
                 numpy=np.__version__,
                 scipy=scipy.__version__, solver=dict(method="DOP853", rtol=RTOL, atol=ATOL),
                 frame_rate_hz=FPS, duration_s=DURATION, noise_sigma_m=args.noise,
                 seeds=args.seeds, bob_marker="bob centre, at rod_length along the rod",
                 frame="rail frame, y up (bob at x + l cos theta, -l sin theta)",
                 theta_convention="docs/physics.md: from +x, y down, pi/2 hangs down",
                 rigs={})
    for name in RIGS:
        rig = make_rig(name)
        x0, th0, xd0, w0 = RIGS[name]["release"]
        print(f"== rig {name}: m1={rig.m1} m2={rig.m2} rod={rig.m_r} l={rig.l} R={rig.R} "
              f"mu={rig.mu}")
        print(f"   m_p={rig.m_p:.5f} d={rig.d:.6f} J_cm={rig.J_cm:.6e} J={rig.J:.6e} "
              f"L={rig.L:.6f} m_e={rig.m_e:.6f} r'={rig.r_prime:.5f} mu*={rig.mu_star:.4f}"
              f" ({'below' if rig.mu < rig.mu_star else 'ABOVE'} mu*)")
        if rig.mu >= rig.mu_star:
            raise SystemExit(f"rig {name}: mu >= mu*")
        print(f"   release: x0={x0} theta0={th0} x_dot0={xd0} theta_dot0={w0}")
        segs, evs, yend = simulate(rig, (x0, th0, xd0, w0), DURATION, verbose=False)
        for e in evs:
            st = e["state"]
            print(f"    t = {e['t']:.6f} s  {e['kind']:<12s} x={st[0]:+.5f} "
                  f"theta={st[1]:+.5f} x'={st[2]:+.5f} w={st[3]:+.5f} "
                  f"|F|/(mu|N|)={e['cone_ratio']:.4f}")
        Y = sample(segs, ts)
        print(f"   slider x range [{Y[:, 0].min():+.4f}, {Y[:, 0].max():+.4f}] m, "
              f"mode switches {len(evs) - 2}")
        if len(evs) - 2 < 3:
            print(f"   WARNING: fewer than 3 mode switches for rig {name}")
        for seed in args.seeds:
            fn = f"rigid_{name}.csv" if len(args.seeds) == 1 else f"rigid_{name}_s{seed}.csv"
            write_csv(os.path.join(args.out, fn), ts, Y, rig, seed, args.noise)
        write_tomls(args.out, name, rig)
        d = rig.describe()
        d.update(initial=dict(x=x0, theta=th0, x_dot=xd0, theta_dot=w0),
                 noise_sigma_m=args.noise, seeds=args.seeds,
                 slider_x_range_m=[float(Y[:, 0].min()), float(Y[:, 0].max())],
                 events=[dict(t=e["t"], kind=e["kind"],
                              state=dict(zip(["x", "theta", "x_dot", "theta_dot"],
                                             e["state"])),
                              stuck_cone_ratio=e["cone_ratio"]) for e in evs])
        truth["rigs"][name] = d
    with open(os.path.join(args.out, "rigid_truth.json"), "w") as fh:
        json.dump(truth, fh, indent=2)
        fh.write("\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
