#!/usr/bin/env python3
"""Check, with the independent generator, the plan's claim that a release box cannot make a
stuck slider slip (src/plan/reach.rs; model::regions::largest_stuck_pull).

`appell plan` on configs/plan_law_heavy.toml (slider/bob 3, releases within 30 deg of hanging,
swings of 2 rad/s, pushes of 0.3 m/s), asked to tell static friction from Coulomb's law, says:
no release in the box lets the pendulum pull more than P of the normal force, below
mu_kinetic; a release from rest at least A deg from hanging would pull as hard. Here:
  1. the box's 8 corners (execution errors added outward) and N uniform draws inside it are
     simulated by scripts/generators/law_release_generator.py with the static law
     (mu_k 0.22, mu_s 0.26) for 2 s: every one must show no slip from stick (`onsets` 0), and
     the largest |friction| / |normal force| the generator's own frame forces show while the
     slider is stuck must stay at or below P;
  2. releases from rest at A - 2 and A + 2 deg from hanging under Coulomb's law with
     mu = mu_kinetic: the first must never slide, the second must.

    /work/venv/bin/python scripts/sweeps/restart_bound_check.py --appell BIN [--draws 24]
Exit 1 when a claim fails. Python 3 with numpy and scipy (the generator is imported).
"""

import sys

sys.dont_write_bytecode = True  # leave no __pycache__ in scripts/

import argparse  # noqa: E402
import concurrent.futures as cf  # noqa: E402
import itertools  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import os  # noqa: E402
import re  # noqa: E402
import subprocess  # noqa: E402
import tempfile  # noqa: E402
import tomllib  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "scripts", "generators"))
import law_release_generator as lrg  # noqa: E402
import friction_law_generator as flg  # noqa: E402

import numpy as np  # noqa: E402

PLAN = os.path.join(ROOT, "configs", "plan_law_heavy.toml")


def claim(appell, work):
    """The plan's note: (pull bound, mu_kinetic, angle from hanging in degrees)."""
    with open(PLAN) as fh:
        text = fh.read()
    # the laws named in the plan file: no earlier fit needed; mu known to 2 %
    text = text.replace("mu_kinetic_sd = 0.04", 'mu_kinetic_sd = 0.004\n'
                        'discriminate = ["coulomb", "static"]')
    path = os.path.join(work, "plan.toml")
    with open(path, "w") as fh:
        fh.write(text)
    out = subprocess.run([appell, "plan", path, "--json"], capture_output=True, text=True,
                         check=True)
    notes = [n for n in json.loads(out.stdout).get("notes", [])
             if n.startswith("no release in the box can make a stuck slider slip")]
    if not notes:
        sys.exit("the plan makes no claim about restarting the slider")
    note = notes[0]
    pull = float(re.search(r"pull at most ([0-9.]+)", note).group(1))
    angle = float(re.search(r"at least ([0-9.]+) deg from hanging", note).group(1))
    with open(path, "rb") as fh:
        spec = tomllib.load(fh)
    return note, pull, spec["friction"]["mu_kinetic"], angle, spec


def stuck_pull(law, nominal, name, mu_k=None):
    """Simulate one exact release; its motion and the largest |F| / |N| while stuck."""
    md = (lrg.make_model(law, "heavy") if mu_k is None
          else lrg.make_model(law, "heavy", mu_k=mu_k))
    ts = lrg.frame_times(1000, lrg.DURATION)
    segs, evs, Y = lrg.run(md, nominal, ts)
    N, F, S = flg.frame_forces(md, segs, ts, Y)
    stuck = S == 0
    pull = float(np.max(np.abs(F[stuck]) / np.abs(N[stuck]))) if stuck.any() else 0.0
    m = lrg.motion(md, segs, evs, ts, Y)
    return dict(name=name, release=list(nominal), onsets=m["onsets"], slides=m["slides"],
                stuck_pull=pull)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--appell", required=True)
    ap.add_argument("--draws", type=int, default=24)
    ap.add_argument("--jobs", type=int, default=2)
    opts = ap.parse_args(argv)
    with tempfile.TemporaryDirectory() as work:
        note, bound, mu, angle, spec = claim(os.path.abspath(opts.appell), work)
    print("appell:", note)
    r = spec["release"]
    e_th, e_w, e_v = (r["theta_error_deg"], r["theta_dot_error"], r["x_dot_error"])
    th = [math.radians(r["theta_deg"][0] - e_th), math.radians(r["theta_deg"][1] + e_th)]
    ws = [r["theta_dot"][0] - e_w, r["theta_dot"][1] + e_w]
    vs = [r["x_dot"][0] - e_v, r["x_dot"][1] + e_v]
    box = [(0.0, t, v, w) for t, v, w in itertools.product(th, vs, ws)]
    rng = np.random.default_rng(7)
    box += [(0.0, float(rng.uniform(*th)), float(rng.uniform(*vs)), float(rng.uniform(*ws)))
            for _ in range(opts.draws)]
    jobs = [("static", b, f"box{k}", None) for k, b in enumerate(box)]
    below, above = math.radians(90.0 - (angle - 2.0)), math.radians(90.0 - (angle + 2.0))
    jobs += [("coulomb", (0.0, below, 0.0, 0.0), "from rest at A - 2 deg", mu),
             ("coulomb", (0.0, above, 0.0, 0.0), "from rest at A + 2 deg", mu)]
    with cf.ProcessPoolExecutor(opts.jobs) as ex:
        runs = list(ex.map(stuck_pull, *zip(*jobs)))
    boxes, (lo, hi) = runs[:-2], runs[-2:]
    worst = max(boxes, key=lambda b: b["stuck_pull"])
    ok = True
    onsets = sum(b["onsets"] for b in boxes)
    print(f"box: {len(boxes)} releases (8 corners, {opts.draws} draws), static law "
          f"(mu_s {lrg.MU_S}): slips from stick {onsets}; largest stuck pull "
          f"{worst['stuck_pull']:.4f} (appell's bound {bound}) at {worst['release']}")
    ok &= onsets == 0 and worst["stuck_pull"] <= bound + 0.005
    print(f"from rest, Coulomb mu {mu}: {angle - 2:.0f} deg slides {lo['slides']}, "
          f"{angle + 2:.0f} deg slides {hi['slides']} (appell: at least {angle:g} deg)")
    ok &= lo["slides"] == 0 and hi["slides"] >= 1
    print("every claim holds" if ok else "A CLAIM FAILS")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
