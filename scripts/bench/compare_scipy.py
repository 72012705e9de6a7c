#!/usr/bin/env python3
"""Independent reference for `appell`: the paper scene solved with scipy's DOP853.

The stick and slide equations of docs/physics.md are written here again, in Python, and
integrated with `scipy.integrate.solve_ivp(method="DOP853")`; every mode switch is a terminal
event and the integration is restarted there in the new mode. The script times the whole run
(median of repeats) and prints the event timeline; with `--appell BIN` it also runs
`BIN simulate SCENE --json` and prints the differences of the event times.

Outside CI. Setup (see docs/performance.md, "Against scipy"):
    python3 -m venv .venv && .venv/bin/pip install scipy numpy
    .venv/bin/python scripts/bench/compare_scipy.py --appell target/release/appell
"""

import argparse
import json
import math
import statistics
import subprocess
import time

import numpy as np
from scipy.integrate import solve_ivp

# The paper scene (configs/paper_rest_horizontal.toml).
M1, M2, L, G, MU_K, MU_S = 0.1, 0.1, 0.30, 9.81, 0.35, 0.35
Y0 = [0.0, 0.0, 0.0, 0.0]  # x, theta (y down, 0 = rod horizontal), x', theta'
T_END = 2.0


def shorthands(theta, w):
    """D, a, b, c, Q of docs/physics.md."""
    s, c_ = math.sin(theta), math.cos(theta)
    d = M1 + M2 * c_ * c_
    a = M2 * s * c_
    b = -(M1 * G + M2 * G * s * s + M2 * L * w * w * s)
    c = M2 * c_ * (G * s + L * w * w)
    q = -M1 * ((M1 + M2) * G + M2 * L * w * w * s)
    return d, a, b, c, q


def stick_rhs(_t, y):
    return [0.0, y[3], 0.0, G / L * math.cos(y[1])]


def slide_rhs(s, sigma):
    def f(_t, y):
        d, a, b, c, _q = shorthands(y[1], y[3])
        xdd = (c - MU_K * s * sigma * b) / (d + MU_K * s * sigma * a)
        tdd = (G * math.cos(y[1]) + math.sin(y[1]) * xdd) / L
        return [y[2], y[3], xdd, tdd]

    return f


def terminal(fun, direction=-1.0):
    fun.terminal = True
    fun.direction = direction
    return fun


def stick_margin(_t, y):
    _d, _a, b, c, _q = shorthands(y[1], y[3])
    return MU_S * abs(b) - abs(c)


def sign(v):
    return -1.0 if v < 0 else 1.0


def simulate(rtol, atol):
    """The hybrid run: returns (events [(t, kind, theta)], final state, rhs evaluations)."""
    t, y = 0.0, list(Y0)
    events, nfev = [], 0
    _d, _a, b, c, q = shorthands(y[1], y[3])
    mode = "stick" if MU_S * abs(b) - abs(c) >= 0 else ("slide", sign(c))
    while t < T_END:
        if mode == "stick":
            sol = solve_ivp(stick_rhs, (t, T_END), y, method="DOP853", rtol=rtol, atol=atol,
                            events=[terminal(stick_margin)])
        else:
            s = mode[1]
            sigma = sign(shorthands(y[1], y[3])[4])
            stop = terminal(lambda _t, yy: s * yy[2])
            flip = terminal(lambda _t, yy: sigma * shorthands(yy[1], yy[3])[4])
            sol = solve_ivp(slide_rhs(s, sigma), (t, T_END), y, method="DOP853", rtol=rtol,
                            atol=atol, events=[stop, flip])
        nfev += sol.nfev
        if sol.status != 1:  # reached T_END
            return events, list(sol.y[:, -1]), nfev
        hit = [i for i, te in enumerate(sol.t_events) if len(te)][0]
        t = float(sol.t_events[hit][0])
        y = list(sol.y_events[hit][0])
        _d, _a, b, c, q = shorthands(y[1], y[3])
        if mode == "stick":  # slip, in the direction friction-free motion takes
            mode = ("slide", sign(c))
            kind = "slip"
        elif hit == 0:  # the slider stopped
            y[2] = 0.0
            if MU_S * abs(b) - abs(c) >= 0:
                mode, kind = "stick", "stick"
            else:
                kind = "continuation" if sign(c) == mode[1] else "reversal"
                mode = ("slide", sign(c))
        else:
            kind = "normal_flip"
        events.append((t, kind, y[1]))
    return events, y, nfev


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--rtol", type=float, default=1e-10)
    p.add_argument("--atol", type=float, default=1e-12)
    p.add_argument("--repeats", type=int, default=15)
    p.add_argument("--appell", help="path of the appell binary to compare with")
    p.add_argument("--scene", default="configs/paper_rest_horizontal.toml")
    p.add_argument("--json", action="store_true")
    args = p.parse_args()

    events, final, nfev = simulate(args.rtol, args.atol)
    times = []
    for _ in range(args.repeats):
        t0 = time.perf_counter()
        simulate(args.rtol, args.atol)
        times.append(time.perf_counter() - t0)
    result = {
        "solver": "scipy solve_ivp DOP853, terminal events, restarted at each switch",
        "rtol": args.rtol,
        "atol": args.atol,
        "median_seconds": statistics.median(times),
        "rhs_evals": nfev,
        "events": [{"t": t, "kind": k, "theta_deg": math.degrees(th)} for t, k, th in events],
        "final_state": final,
    }
    if args.appell:
        out = subprocess.run([args.appell, "simulate", args.scene, "--json"], check=True,
                             capture_output=True, text=True).stdout
        ours = json.loads(out)
        ours_t = [e["t"] for e in ours["events"]]
        result["appell_event_times"] = ours_t
        if len(ours_t) == len(events):
            result["max_event_time_difference_s"] = max(
                (abs(a - b[0]) for a, b in zip(ours_t, events)), default=0.0)
        else:
            result["event_count_mismatch"] = [len(ours_t), len(events)]
        f = ours["final"]["state"] if "state" in ours.get("final", {}) else ours["final"]
        ours_y = [f["x"], f["theta"], f["x_dot"], f["theta_dot"]]
        result["max_final_state_difference"] = float(np.max(np.abs(np.subtract(ours_y, final))))
    if args.json:
        print(json.dumps(result, indent=1))
        return
    print(f"scipy DOP853 rtol {args.rtol:g} atol {args.atol:g}: median "
          f"{result['median_seconds'] * 1e3:.2f} ms per run ({args.repeats} runs), {nfev} rhs evals")
    for i, (t, k, th) in enumerate(events):
        extra = ""
        if args.appell and i < len(result["appell_event_times"]):
            extra = f"   appell {result['appell_event_times'][i]:.12f}  diff {result['appell_event_times'][i] - t:+.2e}"
        print(f"  {t:.12f} s  {k:<12} theta {math.degrees(th):9.4f} deg{extra}")
    print("  final state", " ".join(f"{v:.10f}" for v in final))
    if "max_final_state_difference" in result:
        print(f"  max |final state difference| vs appell: {result['max_final_state_difference']:.2e}")


if __name__ == "__main__":
    main()
