#!/usr/bin/env python3
"""Campaigns: many releases of one rigid rig on one tilted rail, for testing `appell fit DIR --joint`.

Purpose
-------
A campaign is what a lab records in one session: the same rig released N times from different
states. Each release is one CSV. The friction coefficient mu and the rail's tilt are shared by
all releases (they are what a joint fit should find), the releases differ. This script writes
such campaigns with their ground truth, independently of the Rust code: it imports
scripts/generators/misspec_generator.py (which extends scripts/generators/rigid_generator.py's Newton-Euler rows with
a rail tilt) and uses its model, hybrid stick/slide loop, sampling, marker and file writers
unchanged. No dynamics are written here.

Physics
-------
The rigid 'paper' rig of rigid_generator.py / misspec_generator.py: slider m1 = 0.1 kg, bob
m2 = 0.1 kg (solid sphere, radius 0.02 m), uniform rod 0.02 kg, rod length (pivot to the bob's
centre) 0.3 m, g = 9.81 m/s^2. Coulomb friction mu = 0.25 (mu_static = mu_kinetic), rail tilt
alpha = +0.5 deg in misspec's `four` convention: gravity in the rail frame (y down) is
g (sin alpha, cos alpha), +x runs downhill, the stuck pendulum hangs at theta = pi/2 - alpha.
Bilateral rail, friction mu |N|.

Releases
--------
The slider starts at x = 0. A release is (theta_deg, theta_dot, x_dot) in docs/physics.md's
convention (theta from +x toward y DOWN, 90 deg hangs; theta_dot in rad/s; x_dot in m/s), i.e. the
initial state (x, theta, x', theta') = (0, radians(theta_deg), x_dot, theta_dot).
Drawn campaigns (numpy.random.default_rng(seed)): first the push directions, a permutation of
ceil(N/2) times +1 and floor(N/2) times -1; then release by release theta_deg ~ U(30, 150),
theta_dot ~ U(-3, 3), |x_dot| ~ U(0.3, 0.9) (in that order, rounded to 0.01 deg, 0.001 rad/s,
0.001 m/s so that `--release` reproduces them exactly), redrawn (same direction, next numbers of
the same generator) until the simulated 2 s have at least 60 frames sliding, at least one
slide-to-stick stop, the slider inside |x| < 0.4 m throughout, and no Painleve (paradox) or
event-limit error.

Noise: release k (1-based) of a campaign with seed S gets normal(0, 0.2 mm, (frames, 4)) from its
own generator numpy.random.default_rng([S, k]) (columns slider_x, slider_y, bob_x, bob_y), so a
drawn campaign and the same releases written with `--release ... --seed S` are byte-identical,
and the odd rail does not change the other releases' noise.

Outputs (per campaign directory)
--------------------------------
release_01.csv ... : misspec_generator.write_csv's format `t,slider_x,slider_y,bob_x,bob_y`,
    metres, 7 decimals, rail frame with y UP, slider marker at the pivot, bob marker at the bob's
    centre, 1 kHz, t = 0.000 .. duration.
rig_measured.toml : misspec's <rig>_measured.toml [rig] table (masses, rod, bob radius, g); no
    friction and no tilt (those are unknown).
truth.json : mu (per release too), tilt (rad, deg), rig, seed, releases (theta_deg, theta_dot,
    x_dot), per release sliding frames, transitions and stops, event timeline, x range,
    rejected draws, check figures, script hashes and python/numpy/scipy versions.

Run (outside CI; Python 3 with numpy and scipy)
---
    /tmp/venv-rigid/bin/python scripts/generators/campaign_generator.py --out /tmp/camp --campaigns 5 --releases 10 --seed-base 1 --check
        -> /tmp/camp/c01 .. c05 (seeds 1..5) and /tmp/camp/README.md
    ... --out DIR --seed 7 --releases 6              one drawn campaign, written into DIR itself
    ... --odd-rail 3                                 release 3 of every campaign has mu 0.30
    ... --out DIR --seed 1 --release 45,0,0.5 --release 120,-1.5,-0.7 [--tilt-deg 0.5] [--mu 0.25] [--name PREFIX]
        exactly these releases (no rejection; truth.json says which did not slide / stop);
        write a negative first number as --release=-20,1,0.5
Options: --duration (s, default 2.0), --check (energy balance of every simulated run within
1e-8 J; the none-equivalence with misspec_generator's `none` paper run at tilt 0; the tilted
equilibrium), --campaigns N or A..B, --seed-base (campaign c has seed seed_base + c - 1).
"""

import argparse
import hashlib
import json
import math
import os
import platform
import sys
import tempfile

import numpy as np
import scipy

sys.dont_write_bytecode = True  # leave no __pycache__ in scripts/
HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import misspec_generator as mg  # noqa: E402
import rigid_generator as rg  # noqa: E402

RIG = "paper"
MU = 0.25
ODD_FACTOR = 1.2            # "a different rail": mu 20 % higher (0.30 for 0.25)
TILT_DEG = 0.5
NOISE = mg.NOISE            # 0.2 mm per coordinate
FPS = mg.FPS                # 1 kHz
DURATION = 2.0
THETA_DEG_RANGE = (30.0, 150.0)
THETA_DOT_RANGE = (-3.0, 3.0)
XDOT_RANGE = (0.3, 0.9)
MIN_SLIDE_FRAMES = 60
X_LIMIT = 0.4
MAX_DRAWS = 200             # per release, before giving up
ENERGY_TOL = 1e-8           # J
STATE = ["x", "theta", "x_dot", "theta_dot"]


# --------------------------------------------------------------------------------------------
# Model and one release
# --------------------------------------------------------------------------------------------
def make_model(mu, tilt_rad):
    """misspec_generator.Model of the paper rig with Coulomb mu and a rail tilt (rad)."""
    return mg.Model(rg.make_rig(RIG, mu=mu), tilt=tilt_rad)


def initial_state(rel):
    theta_deg, theta_dot, x_dot = rel
    return (0.0, math.radians(theta_deg), x_dot, theta_dot)


def frame_times(duration):
    n = int(round(duration * FPS)) + 1
    return np.round(np.arange(n) / FPS, 12)


def frame_modes(segments, ts):
    """Mode of the segment each frame is sampled from (misspec_generator.sample_at's rule: a
    time on a boundary belongs to the earlier segment)."""
    starts = np.array([sg[0] for sg in segments])
    modes = []
    for tt in ts:
        k = max(0, int(np.searchsorted(starts, tt, side="left")) - 1)
        while k < len(segments) - 1 and tt > segments[k][1]:
            k += 1
        modes.append(segments[k][2])
    return np.array(modes)


def run_release(md, rel, ts):
    """Simulate one release; returns a dict with the samples and the figures the acceptance
    rule and truth.json need, or {'error': ...} on a Painleve / event-limit / solver error."""
    y0 = initial_state(rel)
    try:
        segs, evs, _ = mg.simulate(md, y0, float(ts[-1]))
        Y = mg.sample_at(md, segs, y0, ts)
    except (RuntimeError, ValueError, np.linalg.LinAlgError) as exc:
        return dict(error=f"{type(exc).__name__}: {exc}")
    modes = frame_modes(segs, ts)
    sliding = modes == "slide"
    runs, cur = [], 0
    for v in sliding:
        cur = cur + 1 if v else 0
        runs.append(cur)
    inner = evs[1:-1]
    return dict(
        Y=Y, segs=segs, events=evs,
        sliding_frames=int(sliding.sum()),
        longest_slide_frames=int(max(runs) if runs else 0),
        sliding_time_s=float(sum(sg[1] - sg[0] for sg in segs if sg[2] == "slide")),
        transitions=len(inner),
        stops=sum(1 for e in inner if e["kind"] == "stick"),
        x_min=float(Y[:, 0].min()), x_max=float(Y[:, 0].max()),
        slide_distance_m=float(np.abs(np.diff(Y[:, 0])).sum()),
    )


def rejection_reasons(r):
    if "error" in r:
        return [r["error"]]
    why = []
    if r["sliding_frames"] < MIN_SLIDE_FRAMES:
        why.append(f"{r['sliding_frames']} sliding frames < {MIN_SLIDE_FRAMES}")
    if r["stops"] < 1:
        why.append("no slide-to-stick stop")
    if max(-r["x_min"], r["x_max"]) >= X_LIMIT:
        why.append(f"slider leaves |x| < {X_LIMIT} m (x in [{r['x_min']:+.3f}, "
                   f"{r['x_max']:+.3f}])")
    return why


def energy_check(md, r):
    err, works = mg.energy_error(md, r["Y"])
    return float(err), float(works["friction"])


# --------------------------------------------------------------------------------------------
# Drawing a campaign
# --------------------------------------------------------------------------------------------
def draw_campaign(seed, n, mu, odd, odd_mu, tilt_rad, ts, check, log):
    rng = np.random.default_rng(seed)
    signs = rng.permutation([1.0] * ((n + 1) // 2) + [-1.0] * (n // 2))
    accepted, rejected = [], []
    for k in range(1, n + 1):
        mu_k = odd_mu if k == odd else mu
        md = make_model(mu_k, tilt_rad)
        for draw in range(1, MAX_DRAWS + 1):
            th = round(float(rng.uniform(*THETA_DEG_RANGE)), 2)
            w = round(float(rng.uniform(*THETA_DOT_RANGE)), 3)
            xd = round(float(signs[k - 1] * rng.uniform(*XDOT_RANGE)), 3)
            rel = (th, w, xd)
            r = run_release(md, rel, ts)
            why = rejection_reasons(r)
            if check and "error" not in r:
                r["energy_err"], r["friction_work"] = energy_check(md, r)
            if not why:
                break
            rejected.append(dict(release=k, draw=draw, theta_deg=th, theta_dot=w, x_dot=xd,
                                 reasons=why, energy_max_err_J=r.get("energy_err")))
            log(f"   reject release {k} draw {draw} ({th}, {w}, {xd}): {'; '.join(why)}")
        else:
            raise SystemExit(f"seed {seed}: release {k} found no acceptable draw in "
                             f"{MAX_DRAWS} draws")
        accepted.append((rel, mu_k, md, r, draw))
    return accepted, rejected


# --------------------------------------------------------------------------------------------
# Writing
# --------------------------------------------------------------------------------------------
def write_rig_toml(out):
    """misspec_generator.write_toml's [rig] table, under this script's own header."""
    with tempfile.TemporaryDirectory() as td:
        mg.write_toml(td, RIG, rg.make_rig(RIG, mu=MU))
        body = open(os.path.join(td, f"{RIG}_measured.toml")).read()
    body = body[body.index("[rig]"):]
    with open(os.path.join(out, "rig_measured.toml"), "w", newline="\n") as fh:
        fh.write(f"# The '{RIG}' rigid rig of this campaign's release CSVs as measured: a uniform "
                 f"rod and a solid sphere bob\n# (made by scripts/generators/campaign_generator.py, the same "
                 f"[rig] as tests/data/misspec/{RIG}_measured.toml;\n# what a fit must find is in "
                 f"truth.json)\n")
        fh.write(body)


def write_release_csv(path, md, r, ts, seed, k):
    noise = np.random.default_rng([seed, k]).normal(0.0, NOISE, size=(len(ts), 4))
    mg.write_csv(path, ts, mg.markers(md, r["Y"], "none") + noise)


def file_sha256(path):
    with open(path, "rb") as fh:
        return hashlib.sha256(fh.read()).hexdigest()


def versions():
    return dict(
        python=platform.python_version(), numpy=np.__version__, scipy=scipy.__version__,
        scripts={os.path.join("scripts", "generators", f): file_sha256(os.path.join(HERE, f))[:16]
                 for f in ("campaign_generator.py", "misspec_generator.py",
                           "rigid_generator.py")},
        solver=dict(method="DOP853", rtol=mg.RTOL, atol=mg.ATOL))


def release_entry(k, fname, rel, mu_k, r, drawn=None):
    th, w, xd = rel
    ent = dict(index=k, file=fname, theta_deg=th, theta_dot=w, x_dot=xd,
               theta_rad=math.radians(th),
               pushed=("+x (downhill)" if xd > 0 else "-x (uphill)" if xd < 0 else "not pushed"),
               mu=mu_k, mu_kinetic=mu_k, mu_static=mu_k)
    if drawn is not None:
        ent["accepted_at_draw"] = drawn
    if "error" in r:
        ent.update(error=r["error"], slid=None, meets_campaign_rule=False,
                   rule_failures=[r["error"]])
        return ent
    why = rejection_reasons(r)
    ent.update(slid=r["sliding_frames"] > 0, sliding_frames=r["sliding_frames"],
               longest_slide_frames=r["longest_slide_frames"],
               sliding_time_s=r["sliding_time_s"], transitions=r["transitions"],
               stops=r["stops"], slide_distance_m=r["slide_distance_m"],
               slider_x_range_m=[r["x_min"], r["x_max"]],
               meets_campaign_rule=not why, rule_failures=why,
               events=[dict(t=e["t"], kind=e["kind"], state=dict(zip(STATE, e["state"])),
                            stuck_cone_ratio=e["cone_ratio"]) for e in r["events"]])
    if "energy_err" in r:
        ent["self_check"] = dict(energy_max_err_J=r["energy_err"],
                                 friction_work_J=r["friction_work"])
    return ent


def write_campaign(out, seed, items, args, mu, tilt_rad, odd, odd_mu, ts, prefix, mode,
                   rejected=None):
    """items: list of (rel, mu_k, md, r, draw_or_None). Returns the truth dict."""
    os.makedirs(out, exist_ok=True)
    write_rig_toml(out)
    rig = rg.make_rig(RIG, mu=mu).describe()
    for key in ("mu", "mu_kinetic", "mu_static", "friction_law"):
        rig.pop(key, None)
    width = max(2, len(str(len(items))))
    rels = []
    for k, (rel, mu_k, md, r, draw) in enumerate(items, start=1):
        fname = f"{prefix}_{k:0{width}d}.csv"
        if "error" not in r:
            write_release_csv(os.path.join(out, fname), md, r, ts, seed, k)
        else:
            fname = None
        rels.append(release_entry(k, fname, rel, mu_k, r, draw))
    truth = dict(
        generator="scripts/generators/campaign_generator.py",
        based_on=["scripts/generators/misspec_generator.py", "scripts/generators/rigid_generator.py"],
        command_line="/tmp/venv-rigid/bin/python scripts/generators/campaign_generator.py "
                     + " ".join(args.argv),
        mode=mode, seed=seed, rig_name=RIG, rig=rig, rig_file="rig_measured.toml",
        mu=mu, mu_kinetic=mu, mu_static=mu, friction_law="coulomb (mu_static = mu_kinetic), "
                                                        "bilateral rail, friction mu |N|",
        odd_rail=(None if not odd else dict(release=odd, file=rels[odd - 1]["file"], mu=odd_mu,
                                            note="a different rail: mu 20 % higher; tilt "
                                                 "unchanged")),
        tilt_rad=tilt_rad, tilt_deg=math.degrees(tilt_rad),
        tilt_convention="gravity in the rail frame (y down) = g (sin a, cos a): +x downhill "
                        "for a > 0; stuck pendulum hangs at theta = pi/2 - a (misspec's "
                        "`four`; appell's rail_tilt_deg)",
        theta_convention="docs/physics.md: theta from +x toward y down, pi/2 hangs; release "
                         "(theta_deg, theta_dot rad/s, x_dot m/s) with the slider at x = 0",
        frame="CSV: rail frame, y up (slider at (x, 0), bob at (x + l cos theta, -l sin theta))",
        frame_rate_hz=FPS, duration_s=float(ts[-1]), frames=len(ts), noise_sigma_m=NOISE,
        noise_draw="release k: numpy.random.default_rng([seed, k]).normal(0, sigma, "
                   "(frames, 4)), columns slider_x, slider_y, bob_x, bob_y",
        releases=rels)
    if mode == "drawn":
        truth["draw_rule"] = dict(
            generator="numpy.random.default_rng(seed): directions = permutation of "
                      "ceil(N/2) x +1, floor(N/2) x -1; then per release theta_deg, theta_dot, "
                      "|x_dot| uniform, rounded to 0.01 deg, 0.001 rad/s, 0.001 m/s",
            theta_deg=list(THETA_DEG_RANGE), theta_dot=list(THETA_DOT_RANGE),
            abs_x_dot=list(XDOT_RANGE), min_sliding_frames=MIN_SLIDE_FRAMES,
            min_stops=1, x_limit_m=X_LIMIT,
            reject_on="fewer sliding frames, no stop, |x| >= limit, Painleve or event-limit "
                      "error")
        truth["draws_total"] = len(items) + len(rejected)
        truth["rejected"] = rejected
    truth["versions"] = versions()
    with open(os.path.join(out, "truth.json" if prefix == "release" else f"{prefix}_truth.json"),
              "w", newline="\n") as fh:
        json.dump(truth, fh, indent=2)
        fh.write("\n")
    return truth


def print_campaign(tag, truth, check):
    print(f"== {tag}: seed {truth['seed']}, mu {truth['mu']}, tilt {truth['tilt_deg']:g} deg"
          + (f", draws {truth['draws_total']} for {len(truth['releases'])} releases"
             if "draws_total" in truth else ""))
    for e in truth["releases"]:
        if "error" in e:
            print(f"   {e['index']:2d} ({e['theta_deg']}, {e['theta_dot']}, {e['x_dot']}) "
                  f"mu {e['mu']}: ERROR {e['error']}")
            continue
        tl = (", ".join(f"{ev['kind']} {ev['t']:.3f}" for ev in e["events"][1:-1])
              or "(no transitions: " + e["events"][0]["kind"] + " throughout)")
        print(f"   {e['index']:2d} theta {e['theta_deg']:7.2f} deg  w {e['theta_dot']:+6.3f}  "
              f"x' {e['x_dot']:+6.3f}  mu {e['mu']:.2f}: slide {e['sliding_frames']:4d} fr, "
              f"{e['stops']} stops, x [{e['slider_x_range_m'][0]:+.3f}, "
              f"{e['slider_x_range_m'][1]:+.3f}]"
              + (f", energy err {e['self_check']['energy_max_err_J']:.1e} J" if check else "")
              + ("" if e["meets_campaign_rule"] else
                 "  (outside the campaign rule: " + "; ".join(e["rule_failures"]) + ")")
              + f"\n      {tl}")


# --------------------------------------------------------------------------------------------
# Checks
# --------------------------------------------------------------------------------------------
def check_none_equivalence(duration):
    """Tilt 0, the paper release of misspec/rigid (rod horizontal, at rest): this script's path
    against misspec_generator's `none` paper run, before noise."""
    ts = frame_times(duration)
    mine = run_release(make_model(MU, math.radians(0.0)), (0.0, 0.0, 0.0), ts)
    md_ref = mg.make_model("none", RIG)
    y0 = rg.RIGS[RIG]["release"]
    segs, evs, _ = mg.simulate(md_ref, y0, float(ts[-1]))
    Yref = mg.sample_at(md_ref, segs, y0, ts)
    dstate = float(np.max(np.abs(mine["Y"][:, :4] - Yref[:, :4])))
    dmark = float(np.max(np.abs(mg.markers(md_ref, mine["Y"], "none")
                                - mg.markers(md_ref, Yref, "none"))))
    same_events = [(e["t"], e["kind"]) for e in mine["events"]] == [(e["t"], e["kind"])
                                                                     for e in evs]
    # With misspec's own noise draw (default_rng(1), first draw) the CSV is tests/data/misspec's.
    ref_csv = os.path.join(HERE, "..", "..", "tests", "data", "misspec", f"none_{RIG}.csv")
    csv_same = None
    if abs(duration - mg.DURATION) < 1e-12 and os.path.exists(ref_csv):
        with tempfile.TemporaryDirectory() as td:
            p = os.path.join(td, "a.csv")
            mg.write_csv(p, ts, mg.markers(md_ref, mine["Y"], "none")
                         + np.random.default_rng(1).normal(0.0, NOISE, (len(ts), 4)))
            csv_same = open(p, "rb").read() == open(ref_csv, "rb").read()
    good = dstate <= 1e-12 and dmark <= 1e-12 and same_events
    print(f"(check) none-equivalence [tilt 0, release (0 deg, 0, 0) = misspec's paper release]: "
          f"max |state diff| {dstate:.1e}, max |marker diff| {dmark:.1e} m, events identical "
          f"{same_events} ({len(evs) - 2} switches), CSV with misspec's seed-1 noise = "
          f"tests/data/misspec/none_{RIG}.csv: {csv_same}  {'OK' if good else 'FAIL'}")
    return good, dict(max_state_diff=dstate, max_marker_diff_m=dmark, events_identical=same_events,
                      misspec_csv_identical=csv_same)


def check_tilt(tilt_rad):
    md = make_model(MU, tilt_rad)
    y = np.zeros(md.n)
    y[1] = math.pi / 2 - tilt_rad
    sol = mg.solve_stuck(md, y)
    holds, _ = mg.stick_holds(md, y)
    good = abs(sol[1]) < 1e-12 and holds
    print(f"(check) tilt {math.degrees(tilt_rad):g} deg: stuck pendulum at theta = pi/2 - alpha "
          f"has theta'' = {sol[1]:.1e} rad/s^2, friction needed {sol[5]:+.5f} N "
          f"(|F|/(mu|N|) = {abs(sol[5]) / (MU * abs(sol[4])):.4f}, holds {holds})  "
          f"{'OK' if good else 'FAIL'}")
    return good


# --------------------------------------------------------------------------------------------
# README of a multi-campaign directory
# --------------------------------------------------------------------------------------------
def write_readme(out, truths, args, mu, tilt_deg, odd, odd_mu):
    n_rel = len(truths[0][1]["releases"])
    lines = [
        "# Synthetic campaigns: many releases of one rig on one rail",
        "",
        "Made by `scripts/generators/campaign_generator.py` (outside CI), which imports "
        "`scripts/generators/misspec_generator.py`'s",
        "Newton-Euler model (itself `scripts/generators/rigid_generator.py`'s rows plus a rail tilt); "
        "independent of the Rust code.",
        "",
        "    /tmp/venv-rigid/bin/python scripts/generators/campaign_generator.py " + " ".join(args.argv),
        "",
        f"Rig: the rigid 'paper' rig (slider 0.1 kg, bob 0.1 kg solid sphere r = 0.02 m, "
        f"uniform rod 0.02 kg, l = 0.3 m, g = 9.81),",
        f"Coulomb mu = {mu} (mu_static = mu_kinetic), rail tilt {tilt_deg:g} deg (+x downhill), "
        f"{args.duration:g} s at 1 kHz, noise 0.2 mm per coordinate.",
        "" if not odd else
        f"Odd rail: release {odd} of every campaign has mu = {odd_mu} (a different rail; "
        f"truth.json `odd_rail`).",
        "",
        "Each `cNN/` is one campaign (seed = seed_base + NN - 1):",
        "",
        f"- `release_01.csv` .. `release_{n_rel:02d}.csv`: `t,slider_x,slider_y,bob_x,bob_y`, "
        "metres, 7 decimals, rail frame with y up",
        "  (misspec/rigid format); the slider starts at x = 0, half pushed toward +x, half "
        "toward -x.",
        "- `rig_measured.toml`: the rig's `[rig]` table, without friction or tilt (the "
        "unknowns): `--rig` for the fit.",
        "- `truth.json`: mu, tilt (rad and deg), rig, seed, the releases (theta_deg, "
        "theta_dot rad/s, x_dot m/s;",
        "  docs/physics.md: theta from +x toward y down, 90 deg hangs), per release sliding "
        "frames, transitions, stops,",
        "  event timeline, x range; rejected draws and why; check figures; versions.",
        "",
        "Acceptance rule for a drawn release: >= 60 sliding frames, >= 1 slide-to-stick stop, "
        "|x| < 0.4 m, no Painleve or",
        "event-limit error; otherwise redrawn (same direction).",
        "",
        "| campaign | seed | draws | releases (theta_deg, theta_dot, x_dot) |",
        "|---|---|---|---|",
    ]
    for tag, t in truths:
        rels = "; ".join(f"({e['theta_deg']}, {e['theta_dot']}, {e['x_dot']})"
                         + (" odd" if odd and e["index"] == odd else "")
                         for e in t["releases"])
        lines.append(f"| {tag} | {t['seed']} | {t['draws_total']} | {rels} |")
    with open(os.path.join(out, "README.md"), "w", newline="\n") as fh:
        fh.write("\n".join(lines) + "\n")


# --------------------------------------------------------------------------------------------
# Main
# --------------------------------------------------------------------------------------------
def parse_release(s):
    try:
        a, b, c = (float(v) for v in s.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"--release wants THETA_DEG,THETA_DOT,X_DOT, got {s!r}")
    return (a, b, c)


def parse_campaigns(s):
    if ".." in s:
        a, b = s.split("..")
        lo, hi = int(a), int(b)
    else:
        lo, hi = 1, int(s)
    if lo < 1 or hi < lo:
        raise argparse.ArgumentTypeError(f"--campaigns wants N or A..B with 1 <= A <= B, got {s!r}")
    return lo, hi


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", required=True)
    ap.add_argument("--campaigns", type=parse_campaigns,
                    help="N (c01..cN) or A..B: several drawn campaigns, DIR/cNN/")
    ap.add_argument("--seed-base", type=int, default=1,
                    help="campaign c has seed seed_base + c - 1 (default 1)")
    ap.add_argument("--seed", type=int,
                    help="one campaign written into --out itself (drawn, or the --release list)")
    ap.add_argument("--releases", type=int, default=10, help="releases per drawn campaign")
    ap.add_argument("--release", type=parse_release, action="append",
                    help="THETA_DEG,THETA_DOT,X_DOT (repeatable): exactly these releases")
    ap.add_argument("--odd-rail", type=int, default=0, metavar="K",
                    help="release K of every campaign has mu x 1.2 (a different rail)")
    ap.add_argument("--mu", type=float, default=MU)
    ap.add_argument("--tilt-deg", type=float, default=TILT_DEG)
    ap.add_argument("--name", default="release", help="CSV prefix (default release)")
    ap.add_argument("--duration", type=float, default=DURATION)
    ap.add_argument("--check", action="store_true")
    args = ap.parse_args(argv)
    args.argv = argv

    if (args.campaigns is None) == (args.seed is None):
        ap.error("give either --campaigns (several drawn campaigns) or --seed (one campaign)")
    if args.release and args.campaigns is not None:
        ap.error("--release writes one campaign: use --seed, not --campaigns")
    n = len(args.release) if args.release else args.releases
    if n < 1:
        ap.error("at least one release")
    if args.odd_rail and not 1 <= args.odd_rail <= n:
        ap.error(f"--odd-rail must be in 1..{n}")
    if args.duration <= 0:
        ap.error("--duration must be positive")
    if not args.name or os.sep in args.name:
        ap.error("--name must be a plain file-name prefix")
    mu, tilt_rad = args.mu, math.radians(args.tilt_deg)
    odd, odd_mu = args.odd_rail, round(ODD_FACTOR * args.mu, 12)
    ts = frame_times(args.duration)
    rig = rg.make_rig(RIG, mu=max(mu, odd_mu if odd else mu))
    if rig.mu >= rig.mu_star:
        raise SystemExit(f"mu {rig.mu} >= mu* {rig.mu_star:.4f}: paradox regime")

    ok = True
    if args.check:
        good, _ = check_none_equivalence(args.duration)
        ok &= good
        ok &= check_tilt(tilt_rad)

    def energy_report(tag, truth, rejected):
        errs = [e["self_check"]["energy_max_err_J"] for e in truth["releases"]
                if "self_check" in e]
        errs += [r["energy_max_err_J"] for r in (rejected or []) if r["energy_max_err_J"]
                 is not None]
        worst = max(errs) if errs else float("nan")
        good = bool(errs) and worst <= ENERGY_TOL
        print(f"(check) energy balance [{tag}]: max |E - W_friction - E0| over {len(errs)} "
              f"simulated runs = {worst:.2e} J (tolerance {ENERGY_TOL:g} J)  "
              f"{'OK' if good else 'FAIL'}")
        return good, worst

    worst_all = 0.0
    if args.release:
        items = []
        for k, rel in enumerate(args.release, start=1):
            md = make_model(odd_mu if k == odd else mu, tilt_rad)
            r = run_release(md, rel, ts)
            if args.check and "error" not in r:
                r["energy_err"], r["friction_work"] = energy_check(md, r)
            items.append((rel, md.rig.mu, md, r, None))
        truth = write_campaign(args.out, args.seed, items, args, mu, tilt_rad, odd, odd_mu, ts,
                               args.name, "given")
        print_campaign(args.out, truth, args.check)
        bad = [e["index"] for e in truth["releases"] if not e["meets_campaign_rule"]]
        if bad:
            print(f"   note: releases {bad} do not meet the drawn-campaign rule (see truth.json "
                  f"rule_failures)")
        if any("error" in e for e in truth["releases"]):
            ok = False
        if args.check:
            good, worst = energy_report(args.out, truth, None)
            ok &= good
    else:
        camps = ([(None, args.seed)] if args.seed is not None else
                 [(c, args.seed_base + c - 1)
                  for c in range(args.campaigns[0], args.campaigns[1] + 1)])
        width = 2 if args.campaigns is None else max(2, len(str(args.campaigns[1])))
        truths = []
        n_draws = n_rej = 0
        for c, seed in camps:
            out = args.out if c is None else os.path.join(args.out, f"c{c:0{width}d}")
            tag = out
            items, rejected = draw_campaign(seed, n, mu, odd, odd_mu, tilt_rad, ts, args.check,
                                            lambda s: print(s))
            truth = write_campaign(out, seed, items, args, mu, tilt_rad, odd, odd_mu, ts,
                                   args.name, "drawn", rejected)
            print_campaign(tag, truth, args.check)
            n_draws += truth["draws_total"]
            n_rej += len(rejected)
            if args.check:
                good, worst = energy_report(tag, truth, rejected)
                ok &= good
                worst_all = max(worst_all, worst)
            truths.append((os.path.basename(out), truth))
        print(f"== {len(camps)} campaign(s): {n_draws} draws, {n_rej} rejected "
              f"({100.0 * n_rej / max(n_draws, 1):.0f} %)")
        if args.campaigns is not None:
            write_readme(args.out, truths, args, mu, args.tilt_deg, odd, odd_mu)
        if args.check and len(camps) > 1:
            print(f"(check) energy balance over all campaigns: max {worst_all:.2e} J")
    if args.check:
        print("all checks", "PASSED" if ok else "FAILED")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
