#!/usr/bin/env python3
"""Recordings that measure the fit's judgement (issue 58): other friction laws, clean Coulomb
recordings over a wide range of rigs and cameras, and recordings with inexact timestamps.

Purpose
-------
An independent test bench for scripts/sweeps/judgement_sweep.py: does `appell fit` choose the right
friction law, does its 95 % interval cover the truth on well-specified recordings, how often
does it flag a recording that is fine, and what do inexact timestamps do. Synthetic camera
recordings (2 s each) with the rig TOML files the fit needs and a manifest.json that holds the
truth of each. Independent of the Rust simulator.

What it imports (nothing is copied)
  scripts/generators/friction_law_generator.py  (flg) importing it installs measured_rig_generator's and
      its own dispatchers into misspec_generator; used: make_model / release / law_truth for
      the direction and load laws, `slides` (sliding runs), `frame_forces` (per-frame N, F),
      `energy_check`, `describe_case` (energy and law checks of the direction / load runs).
  scripts/generators/measured_rig_generator.py  (mrg) POINT_RIGS (light m1/m2 = 1/3, equal 1, heavy 3.5:
      the ratios nearest 0.3, 1 and 3 the other generators use), make_rig, write_rig_toml (the
      point-pendulum rig file, flavour true_nosd: explicit rod_mass = 0, bob_radius = 0, no
      *_sd keys).
  scripts/generators/misspec_generator.py  (mg) Model (Newton-Euler rows), the hybrid stick/slide loop
      `simulate`, `sample_at`, `markers`, `write_csv`, `write_toml` (the rigid rig file:
      rod_mass and bob_radius, no *_sd keys), `energy_error`.
  scripts/generators/rigid_generator.py  (rg) Rig (a uniform rod plus a solid sphere bob; rod_mass =
      bob_radius = 0 is the point pendulum), RTOL / ATOL (DOP853 1e-11 / 1e-13).
The only new dynamics is the friction law with a static coefficient above the kinetic one
(JModel below): misspec_generator's rows and loop read the coefficient through the model's
`mu()`, which returns `mu_cur`; two thin dispatchers around mg.solve_stuck / mg.solve_sliding
set it (stuck solve: mu_s, so the stick test, the slip event and the cone ratio use mu_s;
sliding solve: mu_k, or Stribeck's mu(|x'|) at the state's own speed), the technique of
friction_law_generator's DirModel. Every other model passes through untouched.

Laws (docs/physics.md and docs/physics.md, "Friction laws"; N either sign, friction uses |N|)
  static    Coulomb with mu_s > mu_k: stuck while |F_needed| <= mu_s |N|; slides with
            F = -mu_k s |N|. mu_k = 0.20, mu_s / mu_k = 1.1, 1.2, 1.3.
  stribeck  sliding F = -mu(|x'|) s |N|, mu(v) = mu_k + (mu_s - mu_k) exp(-(v / v_s)^2);
            stuck as static. mu_k = 0.20, (mu_s / mu_k, v_s) = (1.2, 0.02 m/s), (1.3, 0.05),
            (1.15, 0.1).
  coulomb   controls: mu_k = mu_s = 0.15, 0.20, 0.25.
  direction, load: friction_law_generator's laws and parameters (0.24 / 0.20; 0.25 at the
            static load, exponent 0.8) and its standard releases, re-emitted here.

Sets (default --out /tmp/judgement; every recording 2 s, CSV `t,slider_x,slider_y,bob_x,bob_y`,
metres, rail frame y up, as misspec_generator.write_csv)
  laws   3 point rigs (light, equal, heavy) x {static 3, stribeck 3} x seeds 1-5 (90), coulomb
         controls 3 rigs x 3 mu x 5 seeds (45), direction and load 3 rigs x 5 seeds (30).
         1 kHz, noise 0.2 mm. Releases (x, theta, x', theta') chosen so that every static and
         Stribeck case sticks and slips again (at least 2 stick -> slip onsets in 2 s, checked):
           light (0, 0.8, -0.3, 4.0)  bob 0.8 rad below the rail on the +x side, slider pushed
                                      toward -x at 0.3 m/s, rod swinging down at 4 rad/s
           equal (0, -0.3, 0, -2.0)   bob 0.3 rad above the rail, swinging up at 2 rad/s
           heavy (0, 0, 0, 0)         rod horizontal at rest (the standard release)
         Direction / load use friction_law_generator's standard releases. The onsets of each
         recording are printed and stored in the manifest (`onsets`).
         Noise: default_rng([1, k, seed]).normal(0, 2e-4, (2001, 4)), k the trajectory's index.
  clean  320 Coulomb recordings, each its own random rig and release (default_rng([2, i])):
         m2 in 0.05-0.30 kg, m1/m2 log-uniform in 0.3-3, rod 0.20-0.45 m; 40 % rigid pendulums
         (rod mass 5-30 % of the bob, sphere radius 8-25 mm; rig file from mg.write_toml), the
         others point pendulums (mrg.write_rig_toml, explicit zeros); values rounded to 1 g /
         1 mm before simulating, so the rig file is the truth exactly. mu uniform in 0.10-0.35
         (at most half the rig's paradox bound mu*). Frame rate one of 240, 250, 300, 360, 400,
         480, 500, 600, 720, 960, 1000 fps; noise log-uniform 0.05-0.5 mm per coordinate.
         Release: theta in [-0.7, 1.2] rad or its mirror pi - theta, theta' in [-4, 4] rad/s, x'
         = 0 (70 %) or in [-0.3, 0.3] m/s; redrawn until the slider slides at least once by 1
         mm or more in total and stays within |x| <= 0.5 m. Noise: default_rng([2, i, 1]).
         Times are written with 9 decimals (misspec_generator.write_csv writes 3, which rounds
         frame times that are not whole milliseconds; its output is re-stamped here).
  time   30 Coulomb recordings at 240 fps, noise 0.2 mm, rigs and releases drawn as clean's
         (default_rng([3, i])): 15 whose timestamps are written rounded to whole milliseconds
         (mg.write_csv's %.3f; positions at the true frame times k / 240), 15 whose written
         timestamps carry Gaussian jitter of 0.3 ms (positions at the true frame times, written
         times k / 240 + e_k, e ~ default_rng([3, i, 2]).normal(0, 3e-4), kept increasing).

Rig files: rigs/<rig>.toml (the three point rigs), rigs/<case>.toml (clean, time): the true
values, no *_sd keys, no friction key (the law is the unknown), as friction_law_generator's.

Self-checks (the script exits 1 and says FAILED if one fails)
  energy   |E(t) - E(0) - W(t)| <= 1e-6 J at every frame, W the friction work integrated
           alongside (non-increasing), every simulated run (flg.energy_check / describe_case).
  law      JModel runs, every frame from its own solve: sliding -s F / |N| = mu_k or mu(|x'|)
           (1e-12); stuck |F_needed| <= mu_s |N| (+1e-12 N); at every slip event the stuck cone
           ratio |F_needed| / (mu_s |N|) is 1 (1e-6). Direction / load: flg.describe_case's.
  neutral  JModel with mu_s = mu_k (static, and Stribeck v_s = 0.05) against mg.Model Coulomb,
           each rig's release: the same events and states within 1e-10.
  onsets   every static / Stribeck trajectory has >= 2 stick -> slip onsets and >= 2 slides.
Generation runs in a multiprocessing pool (--jobs, default 2; fork), one task per trajectory;
the wall time is printed and stored in manifest.json.

Run (outside CI; Python 3 with numpy and scipy)
    python3 -m venv /tmp/venv-gen && /tmp/venv-gen/bin/pip install numpy scipy
    /tmp/venv-gen/bin/python scripts/generators/judgement_generator.py --out /tmp/judgement
Options: --jobs 2, --n-clean 320, --only laws|clean|time (repeatable; default all; the
manifest then lists only the sets made in that run).
"""

import sys

sys.dont_write_bytecode = True  # leave no __pycache__ in scripts/

import argparse  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import multiprocessing as mp  # noqa: E402
import os  # noqa: E402
import platform  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402
import scipy  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import friction_law_generator as flg  # noqa: E402  (installs its and mrg's dispatchers in mg)
import measured_rig_generator as mrg  # noqa: E402
import misspec_generator as mg  # noqa: E402
import rigid_generator as rg  # noqa: E402

DURATION = rg.DURATION
RIGS = list(mrg.POINT_RIGS)
LAW_NOISE = mrg.NOISE                      # 0.2 mm
LAW_FPS = 1000
SEEDS = [1, 2, 3, 4, 5]
MU_K = 0.20
STATIC_SETS = [1.1, 1.2, 1.3]                               # mu_s / mu_k
STRIBECK_SETS = [(1.2, 0.02), (1.3, 0.05), (1.15, 0.1)]     # (mu_s / mu_k, v_s m/s)
CONTROL_MU = [0.15, 0.20, 0.25]
LAW_RELEASES = {"light": (0.0, 0.8, -0.3, 4.0), "equal": (0.0, -0.3, 0.0, -2.0),
                "heavy": (0.0, 0.0, 0.0, 0.0)}
MIN_ONSETS, MIN_SLIDES = 2, 2

N_CLEAN = 320
FPS_CHOICES = [240, 250, 300, 360, 400, 480, 500, 600, 720, 960, 1000]
NOISE_RANGE = (0.05e-3, 0.5e-3)
MU_RANGE = (0.10, 0.35)
RIGID_FRACTION = 0.4
X_LIMIT = 0.5
MIN_SLIDE_M = 1e-3

N_TIME = 15
TIME_FPS, TIME_NOISE, JITTER = 240, 0.2e-3, 0.3e-3

TOL_ENERGY, TOL_LAW, TOL_CONE, TOL_NEUTRAL = 1e-6, 1e-12, 1e-6, 1e-10
SET_CODE = {"laws": 1, "clean": 2, "time": 3}


# --------------------------------------------------------------------------------------------
# Static above kinetic, and Stribeck: misspec_generator.Model with mu() = mu_cur
# --------------------------------------------------------------------------------------------
class JModel(mg.Model):
    """mg.Model (level rail, no extras) whose stick test uses mu_s and whose slides use mu_k
    (v_s None) or Stribeck's mu(|x'|). mu() returns mu_cur, set by the dispatchers below: in a
    stuck solve to mu_s, in a sliding solve to the law's value at the state's speed.
    misspec_generator calls mu() only after such a solve (stick test, slip event, cone ratio,
    sliding fold), so every use sees the right coefficient."""

    def __init__(self, rig, mu_s, mu_k, v_s=None):
        super().__init__(rig)
        self.mu_s, self.mu_k, self.v_s = mu_s, mu_k, v_s
        self.mu_cur = mu_s

    def mu(self, x):
        return self.mu_cur

    def mu_slide(self, v):
        if self.v_s is None:
            return self.mu_k
        return self.mu_k + (self.mu_s - self.mu_k) * math.exp(-(v / self.v_s) ** 2)


_PREV = dict(solve_stuck=mg.solve_stuck, solve_sliding=mg.solve_sliding)


def solve_stuck(md, y):
    if isinstance(md, JModel):
        md.mu_cur = md.mu_s
    return _PREV["solve_stuck"](md, y)


def solve_sliding(md, y, s):
    if isinstance(md, JModel):
        md.mu_cur = md.mu_slide(abs(y[2]))
    return _PREV["solve_sliding"](md, y, s)


# misspec_generator's loop, rows and helpers look these up in their module at call time.
mg.solve_stuck, mg.solve_sliding = solve_stuck, solve_sliding


# --------------------------------------------------------------------------------------------
# Simulation, checks, output
# --------------------------------------------------------------------------------------------
def frame_times(fps):
    return np.round(np.arange(int(round(DURATION * fps)) + 1) / fps, 12)


def simulate(md, rel, ts):
    segs, evs, _ = mg.simulate(md, rel, DURATION)
    Y = mg.sample_at(md, segs, rel, ts)
    return segs, evs, Y


def onsets(evs):
    """stick -> slip onsets: misspec_generator's `slip_+1` / `slip_-1` events."""
    return sum(e["kind"].startswith("slip_") for e in evs)


def motion_summary(segs, evs, Y):
    runs = flg.slides(segs)
    return dict(onsets=onsets(evs), slides=len(runs),
                slides_plus=sum(r["s"] > 0 for r in runs),
                slides_minus=sum(r["s"] < 0 for r in runs),
                slide_distance_m=float(sum(r["distance_m"] for r in runs)),
                slider_x_range_m=[float(Y[:, 0].min()), float(Y[:, 0].max())],
                timeline=flg.timeline(evs))


def energy_self_check(md, Y):
    err, work, rise = flg.energy_check(md, Y)
    return dict(energy_max_err_J=err, friction_work_J=work, work_max_rise_J=rise,
                ok=bool(err <= TOL_ENERGY and rise <= 1e-13))


def jmodel_law_check(md, segs, evs, ts, Y):
    N, F, S = flg.frame_forces(md, segs, ts, Y)
    sl = S != 0
    want = np.array([md.mu_slide(abs(v)) for v in Y[:, 2]])
    dev = (float(np.max(np.abs(-S[sl] * F[sl] / np.abs(N[sl]) - want[sl]))) if np.any(sl)
           else 0.0)
    st = ~sl
    excess = float(np.max(np.abs(F[st]) - md.mu_s * np.abs(N[st]))) if np.any(st) else -math.inf
    cone = [abs(e["cone_ratio"] - 1.0) for e in evs if e["kind"].startswith("slip_")]
    cone_dev = max(cone) if cone else 0.0
    return dict(sliding_max_coefficient_dev=dev, stuck_max_excess_N=excess,
                slip_cone_ratio_max_dev=cone_dev,
                ok=bool(dev <= TOL_LAW and excess <= TOL_LAW and cone_dev <= TOL_CONE))


def write_recording(path, ts_written, cols, decimals):
    """misspec_generator.write_csv; the time column re-stamped with `decimals` decimals when
    that is not its 3 (its cells unchanged)."""
    mg.write_csv(path, ts_written, cols)
    if decimals == 3:
        return
    with open(path) as fh:
        lines = fh.read().split("\n")
    out = [lines[0]]
    for t, ln in zip(ts_written, lines[1:]):
        out.append(f"{t:.{decimals}f}" + ln[ln.index(","):])
    out += lines[1 + len(ts_written):]
    with open(path, "w", newline="\n") as fh:
        fh.write("\n".join(out))


def header(path, lines):
    """Replace a rig file's leading comment lines by ours."""
    with open(path) as fh:
        body = [ln for ln in fh.read().split("\n")]
    k = 0
    while k < len(body) and body[k].startswith("#"):
        k += 1
    with open(path, "w", newline="\n") as fh:
        fh.write("\n".join([f"# {ln}" for ln in lines] + body[k:]))


def write_rig_file(out, name, rig, what):
    """rigs/<name>.toml, the true values, no *_sd keys, no friction key: a point rig by
    measured_rig_generator.write_rig_toml (true_nosd: explicit zeros), a rigid one by
    misspec_generator.write_toml (rod_mass, bob_radius)."""
    rel_path = os.path.join("rigs", f"{name}.toml")
    path = os.path.join(out, rel_path)
    if rig.m_r == 0.0 and rig.R == 0.0:
        mrg.write_rig_toml(path, name, rig, "true", "nosd", None)
        kind = "point pendulum (rod_mass = bob_radius = 0)"
    else:
        mg.write_toml(os.path.join(out, "rigs"), name, rig)
        os.replace(os.path.join(out, "rigs", f"{name}_measured.toml"), path)
        kind = "rigid pendulum: a uniform rod and a solid sphere bob"
    header(path, [f"Rig '{name}' of the judgement recordings, {kind}; the true values, no *_sd",
                  f"keys, no friction key ({what}; made by scripts/generators/judgement_generator.py, "
                  "truth in manifest.json)"])
    return rel_path


def noisy(md, Y, rng, sigma):
    clean = mg.markers(md, Y, "none")
    return clean + rng.normal(0.0, sigma, size=clean.shape)


# --------------------------------------------------------------------------------------------
# Tasks (one simulated trajectory each; run in the pool)
# --------------------------------------------------------------------------------------------
def law_truth(law, mu_s, mu_k, v_s):
    return dict(law=law, mu_kinetic=mu_k, mu_static=mu_s, stribeck_velocity=v_s,
                mu_static_over_kinetic=round(mu_s / mu_k, 12))


def task_law(t):
    """A static / Stribeck / Coulomb-control / direction / load trajectory on a point rig,
    written with 5 seeds of noise."""
    out, law, rig_name, k = t["out"], t["law"], t["rig"], t["k"]
    ts = frame_times(LAW_FPS)
    checks = {}
    if law in ("direction", "load"):
        md = flg.make_model(law, rig_name)
        rel = flg.release(rig_name, "std")
        segs, evs, Y = simulate(md, rel, ts)
        ent, _ = flg.describe_case(md, segs, evs, Y, ts, rel)
        sc = ent["self_check"]
        checks["energy"] = dict(energy_max_err_J=sc["energy_max_err_J"],
                                friction_work_J=sc["friction_work_J"], ok=sc["energy_ok"])
        checks["law"] = ent["law_check"]
        tr = flg.law_truth(law)
        truth = dict(law=law, mu_kinetic=tr["mu_at_static_load"] if law == "load"
                     else tr["mu_kinetic"], **{k_: v for k_, v in tr.items()
                                               if k_ != "mu_kinetic"})
        tag = law
    else:
        mu_k, ratio, v_s = t["mu_k"], t["ratio"], t.get("v_s")
        mu_s = round(mu_k * ratio, 12)
        rig = mrg.make_rig(rig_name, mu=mu_k)
        md = mg.Model(rig) if law == "coulomb" else JModel(rig, mu_s, mu_k, v_s)
        rel = LAW_RELEASES[rig_name]
        segs, evs, Y = simulate(md, rel, ts)
        checks["energy"] = energy_self_check(md, Y)
        if isinstance(md, JModel):
            checks["law"] = jmodel_law_check(md, segs, evs, ts, Y)
        truth = law_truth(law, mu_s, mu_k, v_s)
        tag = (f"{law}{ratio:g}" + (f"_vs{v_s:g}" if v_s is not None else "")
               if law != "coulomb" else f"coulomb{mu_k:g}")
    mot = motion_summary(segs, evs, Y)
    if law in ("static", "stribeck"):
        checks["onsets"] = dict(onsets=mot["onsets"], slides=mot["slides"],
                                ok=bool(mot["onsets"] >= MIN_ONSETS
                                        and mot["slides"] >= MIN_SLIDES))
    cases = []
    for seed in SEEDS:
        cid = f"laws_{tag}_{rig_name}_s{seed}"
        rec = f"{cid}.csv"
        rng = np.random.default_rng([SET_CODE["laws"], k, seed])
        write_recording(os.path.join(out, rec), ts, noisy(md, Y, rng, LAW_NOISE), 3)
        cases.append(dict(id=cid, set="laws", group=f"{law}/{rig_name}", law=law, rig=rig_name,
                          seed=seed, params=tag, recording=rec,
                          rig_file=os.path.join("rigs", f"{rig_name}.toml"), truth=truth,
                          truth_mu=truth["mu_kinetic"], fps=LAW_FPS, noise_m=LAW_NOISE,
                          pendulum="point", mass_ratio=mrg.POINT_RIGS[rig_name]["m1"]
                          / mrg.POINT_RIGS[rig_name]["m2"], release=list(rel),
                          noise_stream=[SET_CODE["laws"], k, seed],
                          **{k_: mot[k_] for k_ in ("onsets", "slides", "slide_distance_m")}))
    return dict(cases=cases, checks=checks, line=f"{tag:<22s} {rig_name:<5s}", motion=mot,
                key=f"laws/{tag}/{rig_name}")


def draw_rig_release(rng, fps_choices):
    m2 = round(float(rng.uniform(0.05, 0.30)), 3)
    r = math.exp(float(rng.uniform(math.log(0.3), math.log(3.0))))
    m1 = round(max(0.001, r * m2), 3)
    l = round(float(rng.uniform(0.20, 0.45)), 3)
    rigid = bool(rng.uniform() < RIGID_FRACTION)
    m_r = round(float(rng.uniform(0.05, 0.30)) * m2, 3) if rigid else 0.0
    R = round(float(rng.uniform(0.008, 0.025)), 3) if rigid else 0.0
    if rigid and m_r == 0.0:
        m_r = 0.001
    mu = round(float(rng.uniform(*MU_RANGE)), 3)
    rig = rg.Rig(m1, m2, l, R, m_r, 9.81, mu)
    fps = int(rng.choice(fps_choices))
    noise = math.exp(float(rng.uniform(math.log(NOISE_RANGE[0]), math.log(NOISE_RANGE[1]))))
    return rig, fps, noise


def draw_release(rng):
    th = float(rng.uniform(-0.7, 1.2))
    if rng.uniform() < 0.5:
        th = math.pi - th
    w = float(rng.uniform(-4.0, 4.0))
    xd = 0.0 if rng.uniform() < 0.7 else float(rng.uniform(-0.3, 0.3))
    return (0.0, round(th, 4), round(xd, 4), round(w, 4))


def task_coulomb(t):
    """A clean or time case: a random Coulomb rig and release that slides."""
    out, sname, i = t["out"], t["set"], t["i"]
    rng = np.random.default_rng([SET_CODE[sname], i])
    tries = []
    while True:
        if sname == "clean":
            rig, fps, noise = draw_rig_release(rng, FPS_CHOICES)
        else:
            rig, fps, _ = draw_rig_release(rng, [TIME_FPS])
            noise = TIME_NOISE
        rel = draw_release(rng)
        if rig.mu > 0.5 * rig.mu_star:
            tries.append("paradox bound")
            continue
        md = mg.Model(rig)
        ts = frame_times(fps)
        try:
            segs, evs, Y = simulate(md, rel, ts)
        except RuntimeError as e:
            tries.append(f"simulation: {e}"[:80])
            continue
        mot = motion_summary(segs, evs, Y)
        if mot["slides"] < 1 or mot["slide_distance_m"] < MIN_SLIDE_M:
            tries.append("no slide")
            continue
        if max(abs(v) for v in mot["slider_x_range_m"]) > X_LIMIT:
            tries.append("off the rail")
            continue
        break
    checks = dict(energy=energy_self_check(md, Y))
    cid = f"{sname}_{i:03d}"
    if sname == "time":
        cid += "_" + t["mode"]
    rig_file = write_rig_file(out, cid, rig, "Coulomb; friction is the unknown")
    nrng = np.random.default_rng([SET_CODE[sname], i, 1])
    cols = noisy(md, Y, nrng, noise)
    mode = t.get("mode", "exact")
    if mode == "ms":
        written, dec = ts, 3
    elif mode == "jitter":
        e = np.random.default_rng([SET_CODE[sname], i, 2]).normal(0.0, JITTER, len(ts))
        written, dec = ts + e, 9
        if np.any(np.diff(written) <= 0):
            raise RuntimeError(f"{cid}: jittered times not increasing")
    else:
        written, dec = ts, (3 if fps == 1000 else 9)
    rec = f"{cid}.csv"
    write_recording(os.path.join(out, rec), written, cols, dec)
    desc = rig.describe()
    stamp_err = np.array([float(f"{v:.{dec}f}") for v in written]) - ts
    case = dict(id=cid, set=sname, group=f"{sname}/{'rigid' if rig.m_r else 'point'}",
                law="coulomb", rig=cid, seed=i, recording=rec, rig_file=rig_file,
                truth=dict(law="coulomb", mu_kinetic=rig.mu, mu_static=rig.mu,
                           stribeck_velocity=None),
                truth_mu=rig.mu, fps=fps, noise_m=noise,
                pendulum="rigid" if rig.m_r else "point", mass_ratio=rig.m1 / rig.m2,
                rig_values=dict(m1=rig.m1, m2=rig.m2, rod_length=rig.l, rod_mass=rig.m_r,
                                bob_radius=rig.R, gravity=rig.g, mu_star=desc["mu_star"],
                                L=desc["L"], r_prime=desc["r_prime"]),
                release=list(rel), redraws=len(tries), redraw_reasons=tries,
                time_mode=mode, timestamp_error_s=dict(
                    rms=float(np.sqrt(np.mean(stamp_err ** 2))),
                    max_abs=float(np.max(np.abs(stamp_err)))),
                noise_stream=[SET_CODE[sname], i, 1],
                **{k_: mot[k_] for k_ in ("onsets", "slides", "slide_distance_m")})
    return dict(cases=[case], checks=checks, motion=mot, key=f"{sname}/{cid}",
                line=f"{cid:<16s} {case['pendulum']:<5s} r {case['mass_ratio']:.2f} "
                     f"mu {rig.mu:.3f} {fps} fps {noise * 1e3:.2f} mm")


def task_neutral(t):
    """JModel with mu_s = mu_k (static; Stribeck v_s = 0.05) against mg.Model Coulomb."""
    rig_name = t["rig"]
    ts = frame_times(LAW_FPS)
    rel = LAW_RELEASES[rig_name]
    ref = mg.Model(mrg.make_rig(rig_name, mu=MU_K))
    _, ec, Yc = simulate(ref, rel, ts)
    res = []
    for what, v_s in (("static mu_s = mu_k", None), ("stribeck mu_s = mu_k, v_s 0.05", 0.05)):
        md = JModel(mrg.make_rig(rig_name, mu=MU_K), MU_K, MU_K, v_s)
        _, e2, Y2 = simulate(md, rel, ts)
        same = [e["kind"] for e in e2] == [e["kind"] for e in ec]
        d = float(np.max(np.abs(Y2[:, :4] - Yc[:, :4])))
        dt = max(abs(a["t"] - b["t"]) for a, b in zip(e2, ec)) if same else None
        res.append(dict(rig=rig_name, case=what, max_state_diff=d, same_events=same,
                        max_event_time_diff_s=dt,
                        ok=bool(same and d <= TOL_NEUTRAL and dt <= TOL_NEUTRAL)))
    return dict(cases=[], checks=dict(neutral=res), key=f"neutral/{rig_name}", motion=None,
                line=f"neutral {rig_name}")


def run_task(t):
    t0 = time.process_time()
    try:
        r = dict(laws=task_law, coulomb=task_coulomb, neutral=task_neutral)[t["kind"]](t)
    except Exception as e:  # noqa: BLE001  (reported and failed below)
        r = dict(cases=[], checks=dict(error=dict(ok=False, message=repr(e))), motion=None,
                 key=t.get("key", str(t)), line=f"ERROR in {t}")
    r["cpu_s"] = time.process_time() - t0
    return r


# --------------------------------------------------------------------------------------------
# Main
# --------------------------------------------------------------------------------------------
def build_tasks(out, sets, n_clean):
    tasks = []
    if "laws" in sets:
        k = 0
        for rig_name in RIGS:
            tasks.append(dict(kind="neutral", rig=rig_name))
            for ratio in STATIC_SETS:
                tasks.append(dict(kind="laws", out=out, law="static", rig=rig_name, k=k,
                                  mu_k=MU_K, ratio=ratio))
                k += 1
            for ratio, v_s in STRIBECK_SETS:
                tasks.append(dict(kind="laws", out=out, law="stribeck", rig=rig_name, k=k,
                                  mu_k=MU_K, ratio=ratio, v_s=v_s))
                k += 1
            for mu in CONTROL_MU:
                tasks.append(dict(kind="laws", out=out, law="coulomb", rig=rig_name, k=k,
                                  mu_k=mu, ratio=1.0))
                k += 1
            for law in ("direction", "load"):
                tasks.append(dict(kind="laws", out=out, law=law, rig=rig_name, k=k))
                k += 1
    if "clean" in sets:
        tasks += [dict(kind="coulomb", out=out, set="clean", i=i) for i in range(n_clean)]
    if "time" in sets:
        tasks += [dict(kind="coulomb", out=out, set="time", i=i,
                       mode="ms" if i < N_TIME else "jitter") for i in range(2 * N_TIME)]
    return tasks


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", default="/tmp/judgement")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--n-clean", type=int, default=N_CLEAN)
    ap.add_argument("--only", action="append", choices=["laws", "clean", "time"])
    args = ap.parse_args(argv)
    sets = args.only or ["laws", "clean", "time"]
    out = args.out
    os.makedirs(os.path.join(out, "rigs"), exist_ok=True)
    wall0 = time.monotonic()
    if "laws" in sets:
        for name in RIGS:
            write_rig_file(out, name, mrg.make_rig(name), "point rig of the laws set")
    tasks = build_tasks(out, sets, args.n_clean)
    ok_all = True
    cases, checks, failures = [], {}, []
    ctx = mp.get_context("fork")
    with ctx.Pool(args.jobs) as pool:
        for t, r in zip(tasks, pool.imap(run_task, tasks)):
            bad = [k for k, v in r["checks"].items()
                   if (isinstance(v, list) and not all(x["ok"] for x in v))
                   or (isinstance(v, dict) and not v.get("ok", True))]
            ok_all &= not bad
            if bad:
                failures.append(dict(task=r["key"], checks=bad))
            checks[r["key"]] = r["checks"]
            cases += r["cases"]
            m = r["motion"]
            parts = []
            if "energy" in r["checks"]:
                parts.append(f"energy {r['checks']['energy']['energy_max_err_J']:.1e} J")
            if "law" in r["checks"]:
                lc = r["checks"]["law"]
                parts.append("law " + ("OK" if lc["ok"] else "FAIL"))
            if "neutral" in r["checks"]:
                parts += [f"{x['case']}: max diff {x['max_state_diff']:.1e}, same events "
                          f"{x['same_events']}" for x in r["checks"]["neutral"]]
            if "error" in r["checks"]:
                parts.append(r["checks"]["error"]["message"])
            mline = ""
            if m is not None:
                recs = [c["id"] for c in r["cases"]]
                mline = (f"onsets {m['onsets']}, slides {m['slides']} (+{m['slides_plus']} "
                         f"-{m['slides_minus']}, {m['slide_distance_m'] * 1e3:.1f} mm), "
                         f"{len(recs)} rec" + ("" if len(recs) == 1 else
                                               f" ({recs[0]} .. s{SEEDS[-1]})"))
            print(f"== {r['line']}: " + "; ".join(([mline] if mline else []) + parts)
                  + ("" if not bad else f"  FAIL {bad}"), flush=True)
    wall = time.monotonic() - wall0
    per_set = {s: sum(c["set"] == s for c in cases) for s in ("laws", "clean", "time")}
    onset_table = {}
    for c in cases:
        if c["set"] == "laws":
            onset_table.setdefault(f"{c['params']}/{c['rig']}", c["onsets"])
    manifest = dict(
        generator="scripts/generators/judgement_generator.py",
        based_on=["scripts/generators/friction_law_generator.py", "scripts/generators/measured_rig_generator.py",
                  "scripts/generators/misspec_generator.py", "scripts/generators/rigid_generator.py"],
        command=" ".join(["scripts/generators/judgement_generator.py"]
                         + (sys.argv[1:] if argv is None else list(argv))),
        python=platform.python_version(), numpy=np.__version__, scipy=scipy.__version__,
        solver=dict(method="DOP853", rtol=rg.RTOL, atol=rg.ATOL), duration_s=DURATION,
        paths="relative to this file's directory",
        frame="recordings: rail frame, y up (slider (x, 0), bob (x + l cos theta, -l sin "
              "theta)); releases (x, theta, x', theta') y down, theta = pi/2 hangs down",
        laws_releases={k: list(v) for k, v in LAW_RELEASES.items()},
        rigs={n: dict(m1=mrg.POINT_RIGS[n]["m1"], m2=mrg.POINT_RIGS[n]["m2"],
                      mass_ratio=mrg.POINT_RIGS[n]["m1"] / mrg.POINT_RIGS[n]["m2"],
                      rod_length=mrg.L_ROD) for n in RIGS},
        truth_keys=dict(law="coulomb, static, stribeck, direction, load",
                        mu_kinetic="kinetic coefficient (direction: mean of both ways; load: "
                                   "at the static load (m1 + m2) g)",
                        mu_static="static coefficient (stick test)",
                        stribeck_velocity="v_s, m/s",
                        split="direction: (mu+ - mu-) / 2", load_exponent="load: p"),
        onsets=onset_table, counts=per_set, generation_wall_s=wall, jobs=args.jobs,
        all_checks_passed=bool(ok_all), check_failures=failures, cases=cases)
    with open(os.path.join(out, "manifest.json"), "w", newline="\n") as fh:
        json.dump(manifest, fh, indent=1)
        fh.write("\n")
    with open(os.path.join(out, "checks.json"), "w", newline="\n") as fh:
        json.dump(checks, fh, indent=1)
        fh.write("\n")
    print(f"{len(cases)} recordings in {out} ({', '.join(f'{k} {v}' for k, v in per_set.items())}"
          f"); generation {wall:.1f} s wall with {args.jobs} workers")
    print("all checks", "PASSED" if ok_all else f"FAILED: {failures}")
    return 0 if ok_all else 1


if __name__ == "__main__":
    sys.exit(main())
