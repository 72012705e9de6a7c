#!/usr/bin/env python3
"""The fit benchmark's baseline: the same hybrid stick/slide model in SciPy (solve_ivp DOP853
with terminal events, restarted at every mode switch) fitted with scipy.optimize.least_squares
(finite-difference Jacobian), on the shipped example recording, from a start 30% off in mu.

Outside CI. Setup and run (from the repo root):
    python3 -m venv /tmp/venv-scipy && /tmp/venv-scipy/bin/pip install scipy numpy
    /tmp/venv-scipy/bin/python scripts/bench/compare_scipy_fit.py [RECORDING.csv] [--appell target/release/appell]
With --appell, the same recording is also fitted by `appell fit --json --no-profile` and both
results are printed. Compare with: cargo run --release -- bench --fit
"""
import argparse
import csv
import json
import subprocess
import time

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import least_squares

M1, M2, L, G = 0.5, 0.2, 0.30, 9.81  # the example recording's rig (docs/formats.md), mu = 0.12


def shorthands(th, w):
    s, c = np.sin(th), np.cos(th)
    d = M1 + M2 * c * c
    a = M2 * s * c
    b = -(M1 * G + M2 * G * s * s + M2 * L * w * w * s)
    cc = M2 * c * (G * s + L * w * w)
    q = -M1 * ((M1 + M2) * G + M2 * L * w * w * s)
    return s, c, d, a, b, cc, q


def rhs_stick(t, y, mu):
    return [0.0, y[3], 0.0, G / L * np.cos(y[1])]


def rhs_slide(t, y, mu, sdir):
    s, c, d, a, b, cc, q = shorthands(y[1], y[3])
    sigma = 1.0 if q >= 0 else -1.0
    xdd = (cc - mu * sdir * sigma * b) / (d + mu * sdir * sigma * a)
    return [y[2], y[3], xdd, (G * c + s * xdd) / L]


def simulate(mu, y0, t_eval, rtol=1e-8, atol=1e-10):
    t, y = 0.0, np.array(y0, float)
    t_end = t_eval[-1]
    out = np.empty((len(t_eval), 4))
    filled = 0

    def at_rest_mode(y):
        s, c, d, a, b, cc, q = shorthands(y[1], y[3])
        return 0 if abs(cc) <= mu * abs(b) else (1 if cc > 0 else -1)

    mode = at_rest_mode(y) if y[2] == 0.0 else (1 if y[2] > 0 else -1)
    for _ in range(200):
        if mode == 0:
            def ev(t, y, mu):
                s, c, d, a, b, cc, q = shorthands(y[1], y[3])
                return mu * abs(b) - abs(cc)
            fun = rhs_stick
            args = (mu,)
        else:
            sd = float(mode)

            def ev(t, y, mu, sd=sd):
                return sd * y[2]
            fun = lambda t, y, mu, sd=sd: rhs_slide(t, y, mu, sd)
            args = (mu,)
        ev.terminal = True
        ev.direction = -1
        sol = solve_ivp(fun, (t, t_end), y, method="DOP853", rtol=rtol, atol=atol,
                        events=ev, args=args, dense_output=True)
        t_stop = sol.t[-1]
        k = filled
        while k < len(t_eval) and t_eval[k] <= t_stop:
            k += 1
        if k > filled:
            out[filled:k] = sol.sol(t_eval[filled:k]).T
            filled = k
        if sol.status != 1 or filled == len(t_eval):
            break
        t, y = t_stop, sol.y[:, -1].copy()
        if mode == 0:
            s, c, d, a, b, cc, q = shorthands(y[1], y[3])
            mode = 1 if cc > 0 else -1
        else:
            y[2] = 0.0
            mode = at_rest_mode(y)
    out[filled:] = out[filled - 1] if filled else y
    return out


def markers(states):
    x, th = states[:, 0], states[:, 1]
    return np.column_stack([x, np.zeros_like(x), x + L * np.cos(th), -L * np.sin(th)])


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("recording", nargs="?", default="tests/data/markers_reference.csv")
    ap.add_argument("--appell", help="path of the appell binary to compare with")
    ap.add_argument("--rig", default="configs/rig_example.toml", help="rig file for --appell")
    args = ap.parse_args()
    path = args.recording
    rows = list(csv.DictReader(open(path)))
    t = np.array([float(r["t"]) for r in rows])
    obs = np.array([[float(r[k]) for k in ("slider_x", "slider_y", "bob_x", "bob_y")] for r in rows])
    th0 = np.arctan2(-(obs[0, 3] - obs[0, 1]), obs[0, 2] - obs[0, 0])
    p0 = np.array([0.12 * 1.3, obs[0, 0], th0, 0.0, 0.0])  # mu 30% off; state from frame 0

    def residuals(p):
        pred = markers(simulate(p[0], p[1:], t))
        return (pred - obs).ravel()

    times = []
    for _ in range(3):
        t0 = time.perf_counter()
        res = least_squares(residuals, p0, x_scale="jac", xtol=1e-10, ftol=1e-10)
        times.append(time.perf_counter() - t0)
    j = res.jac
    s2 = 2 * res.cost / (len(res.fun) - len(p0))
    se = np.sqrt(np.diag(np.linalg.inv(j.T @ j)) * s2)
    print(f"scipy least_squares + solve_ivp DOP853 with events: mu = {res.x[0]:.6f} +- {se[0]:.2e} "
          f"(truth 0.12), rms {np.sqrt(np.mean(res.fun**2)):.3e} m, {res.nfev} residual evaluations, "
          f"median {sorted(times)[1]:.3f} s")
    if args.appell:
        cmd = [args.appell, "fit", path, "--rig", args.rig, "--json", "--no-profile"]
        t0 = time.perf_counter()
        out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
        wall = time.perf_counter() - t0
        mu = json.loads(out)["mu_kinetic"]
        print(f"appell fit (whole process, --no-profile): mu = {mu['value']:.6f} +- {mu['stderr']:.2e}, "
              f"{wall:.3f} s wall")


if __name__ == "__main__":
    main()
