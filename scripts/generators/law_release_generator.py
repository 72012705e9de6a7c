#!/usr/bin/env python3
"""Recordings of one release of a point-pendulum rig on a rail with a given friction law,
the release executed with a plan's stated errors (issue 60's acceptance measurement).

Purpose
-------
An independent generator for scripts/sweeps/law_plan_sweep.py: given a rig (slider/bob mass
ratio 0.3, 1 or 3), a true friction law (Coulomb, static above kinetic, Stribeck, direction,
load) and a NOMINAL release (x, theta, x', theta'), it draws the release actually made from
the plan's execution errors (uniform +- theta_error_deg, theta_dot_error, x_dot_error, as
docs/plan.md states them), simulates it with its own Newton-Euler equations (not the Rust
code), adds camera noise and writes the recording, the rig file a fit needs and the truth.

What it imports (nothing is copied)
  scripts/generators/judgement_generator.py  (jg) JModel: static above kinetic and Stribeck (its
      dispatchers set mu_s in stuck solves, mu_k or mu(|x'|) in sliding ones); its
      jmodel_law_check.
  scripts/generators/friction_law_generator.py  (flg) DirModel (a coefficient per sliding
      direction, static = kinetic per direction); frame_forces, slides, law_check,
      energy_check, mirror_diff, mirrored_kinds, timeline.
  scripts/generators/measured_rig_generator.py  (mrg) Ext with load_exp (F = c |N|^n, c = mu
      ((m1 + m2) g)^(1 - n)); write_rig_toml (point rig file, flavour true_nosd).
  scripts/generators/misspec_generator.py  (mg) Model (Coulomb), the hybrid stick/slide loop
      `simulate`, `sample_at`, `markers`, `write_csv`.
  scripts/generators/rigid_generator.py  (rg) Rig (rod_mass = bob_radius = 0: point pendulum),
      RTOL / ATOL (DOP853 1e-11 / 1e-13).
Every law this sweep needs already has a thin model in those generators (static and Stribeck
in judgement_generator, direction in friction_law_generator, load in measured_rig_generator),
so no new dynamics is written here.

Conventions (docs/physics.md)
  Dynamics in the rail frame, y DOWN; theta from +x toward +y, theta = pi/2 hangs down (the
  plan's theta_deg is the same angle in degrees, 90 hanging). Recording: rail frame, y UP:
  slider (x, 0), bob (x + l cos theta, -l sin theta), metres, `t,slider_x,slider_y,bob_x,bob_y`.
  Mirror image: (x, theta, x', theta') -> (-x, pi - theta, -x', -theta').

Rigs (point pendulum, rod 0.30 m, g = 9.81; rigs/<rig>.toml, the true values, no *_sd keys,
no friction key: the law is the unknown)
  light  m1 = 0.045, m2 = 0.150 kg (m1/m2 = 0.3)   camera 1000 Hz
  equal  m1 = 0.100, m2 = 0.100 kg (1)             camera  500 Hz
  heavy  m1 = 0.300, m2 = 0.100 kg (3)             camera 1000 Hz
  Noise 0.2 mm per coordinate (1 px at 0.2 mm/px), 2 s.

Laws (true values; the fit's parameter names)
  coulomb    mu_kinetic = mu_static = 0.22
  static     mu_kinetic 0.22, mu_static 0.26 (stuck while |F_needed| <= 0.26 |N|)
  stribeck   mu(v) = 0.22 + 0.04 exp(-(v / v_s)^2), v_s = 0.02 m/s (--stribeck-velocity);
             stuck as static with 0.26
  direction  0.24 sliding toward +x, 0.20 toward -x (static = kinetic per direction):
             mu_kinetic 0.22 (the mean), mu_kinetic_split 0.02
  load       F = c |N|^0.8, c = 0.22 ((m1 + m2) g)^0.2: mu_kinetic 0.22 at the static load,
             load_exponent 0.8

Execution errors and noise (one release = a seed and a stream number k)
  actual = nominal + (u_theta theta_error, u_w theta_dot_error, u_v x_dot_error) (x exact),
  u ~ default_rng([seed, k, 1]).uniform(-1, 1, 3); noise default_rng([seed, k, 2]).normal(0,
  sigma, (frames, 4)).

Self-checks (each recording: energy and law; --check: also mirror and neutral, every law and
rig; the script exits 1 and says FAILED if one fails)
  energy   |E(t) - E(0) - W(t)| <= 1e-6 J at every frame, W the friction work integrated
           alongside (non-increasing)  (flg.energy_check).
  law      every frame from its own solve: sliding -s F / |N| is the law's coefficient for the
           direction, speed or load (1e-12); stuck F_needed inside the law's band (1e-12 N)
           (jg.jmodel_law_check for static / Stribeck, flg.law_check otherwise); at every slip
           of a JModel run the cone ratio is 1 (1e-6).
  mirror   a release and its mirror image: the mirrored run equals the run mirrored (the
           direction law: on the swapped rail, 0.20 toward +x and 0.24 toward -x), state within
           1e-8 at every frame, the same events mirrored.
  neutral  static and Stribeck with mu_s = mu_k, direction with no split, load with exponent 1
           against Coulomb 0.22: markers within 1e-10 m, the same events at times within
           1e-10 s (the load law 1e-9 s: it solves its friction by brentq, another path, and
           its events move at the integrator's rtol; seen 1.0e-10 s on the light rig).

Outputs (in --out)
  <name>.csv, <name>.json (truth: law, parameters, nominal and actual release, the drawn
  errors, events, slides per direction, stick -> slip onsets, normal-force range, slider range,
  self-checks), rigs/<rig>.toml

Run (outside CI; Python 3 with numpy and scipy)
    python3 -m venv /tmp/venv-gen && /tmp/venv-gen/bin/pip install numpy scipy
    /tmp/venv-gen/bin/python scripts/generators/law_release_generator.py --check
    /tmp/venv-gen/bin/python scripts/generators/law_release_generator.py --law static \
        --rig heavy --release 0,1.5708,0.3,0 --errors 1.0,0.1,0.02 --seed 1 --stream 0 \
        --out /tmp/lawrel --name first
  (--release is x [m], theta [rad], x' [m/s], theta' [rad/s]; --release-deg takes theta in
  degrees; --errors theta_error_deg, theta_dot_error, x_dot_error; --exact: no errors.)
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
import judgement_generator as jg  # noqa: E402  (installs flg's, mrg's and its dispatchers)
import friction_law_generator as flg  # noqa: E402
import measured_rig_generator as mrg  # noqa: E402
import misspec_generator as mg  # noqa: E402
import rigid_generator as rg  # noqa: E402

# Event detection: misspec_generator's loop finds a slip where mu |N| - |F_needed| changes sign
# between two of the integrator's steps; in a long stuck phase the steps grow to tens of ms, and
# a slip cone touched only briefly (a fast swing through the bottom, a turning point) is missed
# (seen: 4 of 680 recordings failing the law check, a stuck slider held up to 0.011 N beyond
# mu_s |N|). Its solve_ivp is wrapped here with a step of at most MAX_STEP (this process only).
MAX_STEP = 5e-4
_SOLVE_IVP = mg.solve_ivp


def _solve_ivp(*args, **kw):
    kw.setdefault("max_step", MAX_STEP)
    return _SOLVE_IVP(*args, **kw)


mg.solve_ivp = _solve_ivp

L_ROD, G = 0.30, 9.81
NOISE = 0.0002
DURATION = 2.0
RIGS = {"light": dict(m1=0.045, m2=0.150, fps=1000),
        "equal": dict(m1=0.100, m2=0.100, fps=500),
        "heavy": dict(m1=0.300, m2=0.100, fps=1000)}
MU_K, MU_S, V_S = 0.22, 0.26, 0.02
MU_POS, MU_NEG = 0.24, 0.20
LOAD_EXP = 0.8
LAWS = ["coulomb", "static", "stribeck", "direction", "load"]
TOL_ENERGY, TOL_MIRROR, TOL_NEUTRAL = 1e-6, 1e-8, 1e-10
TOL_NEUTRAL_LOAD_EVENT = 1e-9   # s: the load law solves its friction by brentq (another path)


def make_rig(rig_name, mu=MU_K):
    p = RIGS[rig_name]
    return rg.Rig(p["m1"], p["m2"], L_ROD, 0.0, 0.0, G, mu)


def set_truth(mu_s=None, v_s=None, mu_pos=None, mu_neg=None, load_exp=None):
    """Other true values for every later recording of this process (e.g. the planner's
    reference departures); None keeps a value."""
    global MU_S, V_S, MU_POS, MU_NEG, LOAD_EXP
    MU_S = MU_S if mu_s is None else mu_s
    V_S = V_S if v_s is None else v_s
    MU_POS = MU_POS if mu_pos is None else mu_pos
    MU_NEG = MU_NEG if mu_neg is None else mu_neg
    LOAD_EXP = LOAD_EXP if load_exp is None else load_exp


def make_model(law, rig_name, v_s=None, **kw):
    """The law's model on the rig; kw overrides mu_k, mu_s, mu_pos, mu_neg, exp."""
    v_s = V_S if v_s is None else v_s
    mu_k, mu_s = kw.get("mu_k", MU_K), kw.get("mu_s", MU_S)
    if law == "coulomb":
        return mg.Model(make_rig(rig_name, mu_k))
    if law == "static":
        return jg.JModel(make_rig(rig_name, mu_k), mu_s, mu_k, None)
    if law == "stribeck":
        return jg.JModel(make_rig(rig_name, mu_k), mu_s, mu_k, v_s)
    if law == "direction":
        mp_, mn_ = kw.get("mu_pos", MU_POS), kw.get("mu_neg", MU_NEG)
        return flg.DirModel(make_rig(rig_name, 0.5 * (mp_ + mn_)), mp_, mn_)
    if law == "load":
        return mrg.Ext(make_rig(rig_name, mu_k), load_exp=kw.get("exp", LOAD_EXP))
    raise ValueError(law)


def law_truth(law, v_s=None):
    """The true values under the fit's parameter names (docs/fit.md, "The friction law")."""
    v_s = V_S if v_s is None else v_s
    t = dict(law=law, mu_kinetic=MU_K, mu_static=MU_K)
    if law in ("static", "stribeck"):
        t["mu_static"] = MU_S
    if law == "stribeck":
        t["stribeck_velocity"] = v_s
    if law == "direction":
        t.update(mu_kinetic=round(0.5 * (MU_POS + MU_NEG), 12),
                 mu_kinetic_split=round(0.5 * (MU_POS - MU_NEG), 12),
                 mu_kinetic_positive=MU_POS, mu_kinetic_negative=MU_NEG)
        t["mu_static"] = t["mu_kinetic"]
    if law == "load":
        t["load_exponent"] = LOAD_EXP
    return t


def gated(law):
    """The parameters of the law a fit must find within 3 SE (mu_kinetic always)."""
    return {"coulomb": ["mu_kinetic"], "static": ["mu_kinetic", "mu_static"],
            "stribeck": ["mu_kinetic", "mu_static", "stribeck_velocity"],
            "direction": ["mu_kinetic", "mu_kinetic_split"],
            "load": ["mu_kinetic", "load_exponent"]}[law]


def frame_times(fps, duration=DURATION):
    return np.round(np.arange(int(round(duration * fps)) + 1) / fps, 12)


def actual_release(nominal, errors, seed, stream):
    """The release made: nominal + uniform errors (theta in degrees in `errors`)."""
    x, th, xd, w = (float(v) for v in nominal)
    e_th, e_w, e_v = (float(v) for v in errors)
    u = np.random.default_rng([seed, stream, 1]).uniform(-1.0, 1.0, 3)
    d = (math.radians(e_th) * float(u[0]), e_w * float(u[1]), e_v * float(u[2]))
    return (x, th + d[0], xd + d[2], w + d[1]), dict(theta_rad=d[0], theta_dot=d[1], x_dot=d[2])


def run(md, rel, ts):
    segs, evs, _ = mg.simulate(md, rel, float(ts[-1]))
    Y = mg.sample_at(md, segs, rel, ts)
    return segs, evs, Y


def checks_of(md, segs, evs, ts, Y):
    err, work, rise = flg.energy_check(md, Y)
    out = dict(energy=dict(max_err_J=err, friction_work_J=work, max_rise_J=rise,
                           ok=bool(err <= TOL_ENERGY and rise <= 1e-13)))
    if isinstance(md, jg.JModel):
        out["law"] = jg.jmodel_law_check(md, segs, evs, ts, Y)
    else:
        N, F, S = flg.frame_forces(md, segs, ts, Y)
        out["law"] = flg.law_check(md, N, F, S)
    return out


def motion(md, segs, evs, ts, Y):
    runs = flg.slides(segs)
    N, _, S = flg.frame_forces(md, segs, ts, Y)
    W = (md.rig.m1 + md.rig.m_p) * md.rig.g
    sl = S != 0
    return dict(
        onsets=sum(e["kind"].startswith("slip_") for e in evs),
        slides=len(runs), slides_plus=sum(r["s"] > 0 for r in runs),
        slides_minus=sum(r["s"] < 0 for r in runs),
        slide_distance_plus_m=float(sum(r["distance_m"] for r in runs if r["s"] > 0)),
        slide_distance_minus_m=float(sum(r["distance_m"] for r in runs if r["s"] < 0)),
        sliding_frames=int(sl.sum()),
        slider_x_range_m=[float(Y[:, 0].min()), float(Y[:, 0].max())],
        normal_over_static_load=[float(np.abs(N).min() / W), float(np.abs(N).max() / W)],
        normal_over_static_load_sliding=([float(np.abs(N[sl]).min() / W),
                                          float(np.abs(N[sl]).max() / W)] if sl.any() else None),
        slow_sliding_frames=int(np.sum(sl & (np.abs(Y[:, 2]) < 2 * V_S))),
        timeline=flg.timeline(evs))


def write_rig(out, rig_name):
    path = os.path.join(out, "rigs", f"{rig_name}.toml")
    os.makedirs(os.path.dirname(path), exist_ok=True)
    mrg.write_rig_toml(path, rig_name, make_rig(rig_name), "true", "nosd", None)
    jg.header(path, [f"Point-pendulum rig '{rig_name}' of the law-release recordings, the true "
                     "values, no *_sd keys, no",
                     "friction key: the law is the unknown (made by scripts/generators/"
                     "law_release_generator.py)"])
    return path


def generate(law, rig_name, nominal, errors, seed, stream, out, name, fps=None,
             duration=DURATION, noise=NOISE, v_s=None, exact=False):
    """Simulate one release (its errors drawn unless `exact`), write <out>/<name>.csv, .json
    and rigs/<rig>.toml; return the truth dict (with `ok`: every self-check passed)."""
    os.makedirs(out, exist_ok=True)
    v_s = V_S if v_s is None else v_s
    fps = fps or RIGS[rig_name]["fps"]
    ts = frame_times(fps, duration)
    if exact:
        rel, drawn = tuple(float(v) for v in nominal), dict(theta_rad=0.0, theta_dot=0.0,
                                                            x_dot=0.0)
    else:
        rel, drawn = actual_release(nominal, errors, seed, stream)
    md = make_model(law, rig_name, v_s=v_s)
    truth = dict(generator="scripts/generators/law_release_generator.py", law=law, rig=rig_name,
                 m1=RIGS[rig_name]["m1"], m2=RIGS[rig_name]["m2"], rod_length=L_ROD, gravity=G,
                 parameters=law_truth(law, v_s), gated=gated(law), fps=fps, duration_s=duration,
                 noise_m=noise, seed=seed, stream=stream,
                 nominal=dict(zip(["x", "theta", "x_dot", "theta_dot"], map(float, nominal))),
                 errors=dict(zip(["theta_error_deg", "theta_dot_error", "x_dot_error"],
                                 map(float, errors))),
                 drawn_error=drawn, actual=dict(zip(["x", "theta", "x_dot", "theta_dot"], rel)),
                 recording=f"{name}.csv", rig_file=os.path.relpath(write_rig(out, rig_name),
                                                                   out))
    try:
        segs, evs, Y = run(md, rel, ts)
    except RuntimeError as e:  # Painleve cases, too many events: say so, write nothing else
        truth.update(ok=False, error=str(e)[:300])
        with open(os.path.join(out, f"{name}.json"), "w", newline="\n") as fh:
            json.dump(truth, fh, indent=1)
        return truth
    truth["motion"] = motion(md, segs, evs, ts, Y)
    truth["self_check"] = checks_of(md, segs, evs, ts, Y)
    truth["ok"] = all(c["ok"] for c in truth["self_check"].values())
    clean = mg.markers(md, Y, "none")
    cols = clean + np.random.default_rng([seed, stream, 2]).normal(0.0, noise, clean.shape)
    mg.write_csv(os.path.join(out, f"{name}.csv"), ts, cols)
    truth["python"], truth["numpy"], truth["scipy"] = (platform.python_version(),
                                                       np.__version__, scipy.__version__)
    with open(os.path.join(out, f"{name}.json"), "w", newline="\n") as fh:
        json.dump(truth, fh, indent=1)
        fh.write("\n")
    return truth


# --------------------------------------------------------------------------------------------
# --check: mirror and neutral over every law and rig
# --------------------------------------------------------------------------------------------
CHECK_RELEASES = {"light": (0.0, math.radians(70.0), 0.2, 1.5),
                  "equal": (0.0, math.radians(60.0), 0.0, -1.0),
                  "heavy": (0.0, math.radians(75.0), 0.25, 1.0)}


def mirror(st):
    return flg.mirror_state(st)


def full_check(duration=1.0):
    ok_all = True
    lines = []
    for rig_name in RIGS:
        ts = frame_times(RIGS[rig_name]["fps"], duration)
        rel = CHECK_RELEASES[rig_name]
        base = {}
        for law in LAWS:
            md = make_model(law, rig_name)
            segs, evs, Y = run(md, rel, ts)
            c = checks_of(md, segs, evs, ts, Y)
            m = motion(md, segs, evs, ts, Y)
            base[law] = (evs, Y, md)
            # mirror: the mirrored release (direction: on the swapped rail)
            kw = dict(mu_pos=MU_NEG, mu_neg=MU_POS) if law == "direction" else {}
            mb = make_model(law, rig_name, **kw)
            sb, eb, Yb = run(mb, mirror(rel), ts)
            d = flg.mirror_diff(Yb, Y)
            same = [e["kind"] for e in eb] == flg.mirrored_kinds(evs)
            good_m = d <= TOL_MIRROR and same
            good = all(v["ok"] for v in c.values()) and good_m
            ok_all &= good
            lines.append(f"{rig_name:<5s} {law:<9s} energy {c['energy']['max_err_J']:.1e} J, law "
                         f"{'ok' if c['law']['ok'] else 'FAIL'}, mirror {d:.1e} events "
                         f"{'mirrored' if same else 'DIFFER'}  slides +{m['slides_plus']} "
                         f"-{m['slides_minus']}, onsets {m['onsets']}  "
                         f"{'OK' if good else 'FAIL'}")
        evc, Yc, mdc = base["coulomb"]
        for what, md in (("static mu_s = mu_k", make_model("static", rig_name, mu_s=MU_K)),
                         ("stribeck mu_s = mu_k", make_model("stribeck", rig_name, mu_s=MU_K)),
                         ("direction no split", make_model("direction", rig_name, mu_pos=MU_K,
                                                           mu_neg=MU_K)),
                         ("load exponent 1", make_model("load", rig_name, exp=1.0))):
            s2, e2, Y2 = run(md, rel, ts)
            dpos = float(np.max(np.abs(mg.markers(md, Y2, "none") - mg.markers(mdc, Yc, "none"))))
            same = [e["kind"] for e in e2] == [e["kind"] for e in evc]
            dt = max(abs(a["t"] - b["t"]) for a, b in zip(e2, evc)) if same else math.inf
            tol_t = TOL_NEUTRAL_LOAD_EVENT if what.startswith("load") else TOL_NEUTRAL
            good = dpos <= TOL_NEUTRAL and same and dt <= tol_t
            ok_all &= good
            lines.append(f"{rig_name:<5s} neutral {what:<22s} vs coulomb: markers {dpos:.1e} m, "
                         f"events {'same' if same else 'DIFFER'} ({dt:.1e} s)  "
                         f"{'OK' if good else 'FAIL'}")
    return ok_all, lines


def parse_release(s, deg):
    v = [float(t) for t in s.split(",")]
    if len(v) != 4:
        raise SystemExit("--release takes x,theta,x_dot,theta_dot")
    if deg:
        v[1] = math.radians(v[1])
    return tuple(v)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--check", action="store_true", help="mirror and neutral checks, every law "
                                                         "and rig")
    ap.add_argument("--law", choices=LAWS)
    ap.add_argument("--rig", choices=list(RIGS))
    ap.add_argument("--release", help="x,theta,x_dot,theta_dot (theta in rad)")
    ap.add_argument("--release-deg", help="x,theta_deg,x_dot,theta_dot")
    ap.add_argument("--errors", default="0,0,0",
                    help="theta_error_deg,theta_dot_error,x_dot_error (+-, uniform)")
    ap.add_argument("--exact", action="store_true", help="no execution errors")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--stream", type=int, default=0)
    ap.add_argument("--fps", type=float, default=None)
    ap.add_argument("--duration", type=float, default=DURATION)
    ap.add_argument("--noise", type=float, default=NOISE)
    ap.add_argument("--stribeck-velocity", type=float, default=None, help=f"default {V_S}")
    ap.add_argument("--out", default="/tmp/lawrel")
    ap.add_argument("--name", default="release")
    a = ap.parse_args(argv)
    if a.check:
        ok, lines = full_check()
        print("\n".join(lines))
        print("all checks", "PASSED" if ok else "FAILED")
        return 0 if ok else 1
    if not (a.law and a.rig and (a.release or a.release_deg)):
        ap.error("--law, --rig and --release (or --release-deg) are needed without --check")
    nominal = parse_release(a.release or a.release_deg, a.release is None)
    errors = [float(t) for t in a.errors.split(",")]
    t = generate(a.law, a.rig, nominal, errors, a.seed, a.stream, a.out, a.name, fps=a.fps,
                 duration=a.duration, noise=a.noise, v_s=a.stribeck_velocity, exact=a.exact)
    if "error" in t:
        print(f"simulation failed: {t['error']}")
        return 1
    m = t["motion"]
    print(f"{a.name}: {a.law} {a.rig} actual release {tuple(round(v, 5) for v in t['actual'].values())}"
          f": slides +{m['slides_plus']} -{m['slides_minus']}, onsets {m['onsets']}, |N|/W "
          f"{m['normal_over_static_load'][0]:.3f}..{m['normal_over_static_load'][1]:.3f}, x "
          f"{m['slider_x_range_m'][0] * 1e3:.1f}..{m['slider_x_range_m'][1] * 1e3:.1f} mm; "
          f"checks {'OK' if t['ok'] else 'FAILED'}\n  {m['timeline']}")
    return 0 if t["ok"] else 1


if __name__ == "__main__":
    sys.exit(main())
