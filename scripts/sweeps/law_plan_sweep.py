#!/usr/bin/env python3
"""Does the release `appell plan --after` proposes, when a first release left the friction law
open, tell the laws apart? Issue 60's acceptance, measured on independent recordings.

For each true law (static, Stribeck, direction, load) x rig (light, equal, heavy: slider/bob
0.3, 1, 3) x seed (scripts/generators/law_release_generator.py makes every recording; the
camera and errors are those of configs/plan_law_<rig>.toml):
  1. FIRST: a release the fit reads as Coulomb or calls a tie: the bob hanging at rest, the
     slider pushed toward +x at 0.25 m/s (one slide, one way, that never restarts, under a
     load that hardly varies: |N| within 2.5 % of the static load), executed with the plan's
     errors (stream 0);
  2. `appell fit FIRST --rig RIG --json` -> fit.json;
  3. `appell plan configs/plan_law_<rig>.toml --after fit.json --json`: the top proposal, the
     laws weighed and the predicted standard errors (and its CPU seconds; the same plan after
     the same fit with its `friction_law` section removed, which plans for mu's precision as
     before issue 60, for the CPU comparison);
  4. the proposal recorded with the true law, its execution errors drawn from the plan's
     stated ones and new noise (stream 1); (a) the first release repeated (stream 2); (b) a
     random release drawn uniformly from the plan's box (default_rng([seed, 99]); stream 3);
  5. `appell fit --joint --json --rig RIG --release FIRST --release X` for X in planned,
     repeat, random. **Identified**: the chosen model's friction terms are exactly the true
     law's (`nuisances`: mu_static -> static, stribeck, direction, load, viscous; as
     scripts/sweeps/judgement_sweep.py reads them) and every parameter of it is within 3 SE of
     the truth (mu_kinetic; mu_static for static and Stribeck; stribeck_velocity for
     Stribeck; mu_kinetic_split for direction; load_exponent for load), with no `failed` fit.
  6. the proposal's `predicted_stderr` under the true law against the joint fit's achieved
     standard error, per parameter (ratio predicted / achieved; within 20 % counted), and
     whether the achieved one lies in the proposal's `predicted_stderr_range` (the law over
     its departures; 20 % slack either side), with the joint fit's interval kind.
Plain Coulomb rails (3 rigs x the seeds): steps 1-3 only; does the plan weigh no law and
say it plans for mu's precision (`laws.weighed` empty, `laws.notes`)?
CPU: `appell plan configs/plan_example.toml` (3 runs) and every plan with and without laws.

Every step's output is cached in --work (a directory per binary: the first 12 hex digits of
its SHA-256), so a rerun only does what is missing. Cases run in a process pool (--jobs,
default 2). Python 3 with numpy and scipy (the generator is imported).

    /tmp/venv-gen/bin/python scripts/sweeps/law_plan_sweep.py --appell /work/appell-law \
        --seeds 1..5 --work /tmp/law_plan_sweep --md /tmp/law_plan_tables.md
Options: --laws static,stribeck,direction,load; --rigs light,equal,heavy; --no-coulomb;
--jobs 2; --timeout 900 (s, per command); --plan PATTERN (other plan files, {rig} in the
name; their own work directory); --baseline APPELL (another binary, e.g. main before issue
60: the same plans after the same fits and plan_example.toml, CPU seconds compared).
"""

import sys

sys.dont_write_bytecode = True  # leave no __pycache__ in scripts/

import argparse  # noqa: E402
import concurrent.futures as cf  # noqa: E402
import hashlib  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import os  # noqa: E402
import statistics  # noqa: E402
import subprocess  # noqa: E402
import tempfile  # noqa: E402
import threading  # noqa: E402
import time  # noqa: E402
import tomllib  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(ROOT, "scripts", "generators"))
from judgement_sweep import chosen_law  # noqa: E402
from judgement_sweep import param as single_param  # noqa: E402
import law_release_generator as lrg  # noqa: E402

import numpy as np  # noqa: E402

LAWS = ["static", "stribeck", "direction", "load"]
RIGS = ["light", "equal", "heavy"]
FIRST = (0.0, math.pi / 2, 0.25, 0.0)   # hanging at rest, a push toward +x at 0.25 m/s
# Coulomb rails' informative first releases (wide swings from rest or a small push: slides
# both ways, stick -> slip onsets, a normal force that varies by tens of %)
INFORMATIVE = {"light": (0.0, math.radians(-20.0), 0.0, 2.0),
               "equal": (0.0, math.radians(20.0), 0.0, 0.0),
               "heavy": (0.0, 0.0, 0.0, 0.0)}
FORCE = {"coulomb": ["--friction", "coulomb"], "static": ["--with", "mu_static"],
         "stribeck": ["--friction", "stribeck"], "direction": ["--friction", "direction"],
         "load": ["--friction", "load"]}
WITHIN = 0.20                           # predicted SE within 20 % of the achieved one
KINDS = ["planned", "repeat", "random"]
CASES = LAWS + ["coulomb-push", "coulomb-informative"]


# --------------------------------------------------------------------------------------------
# Running appell
# --------------------------------------------------------------------------------------------
def run(cmd, timeout):
    """Run cmd; (rc, stdout, stderr, cpu_s, wall_s, error). CPU from wait4's rusage."""
    t0 = time.monotonic()
    with tempfile.TemporaryFile() as fo, tempfile.TemporaryFile() as fe:
        p = subprocess.Popen(cmd, stdout=fo, stderr=fe)
        killed = []

        def kill():
            killed.append(1)
            p.kill()
        timer = threading.Timer(timeout, kill)
        timer.start()
        try:
            _, status, ru = os.wait4(p.pid, 0)
        finally:
            timer.cancel()
        p.returncode = os.waitstatus_to_exitcode(status)
        fo.seek(0)
        fe.seek(0)
        out = fo.read().decode("utf-8", "replace")
        err = fe.read().decode("utf-8", "replace")
    error = f"timeout after {timeout} s" if killed else ""
    return p.returncode, out, err, ru.ru_utime + ru.ru_stime, time.monotonic() - t0, error


def cached_json(path, cmd, timeout):
    """The command's JSON output with rc, CPU and stderr, cached in `path`."""
    if os.path.exists(path):
        with open(path) as fh:
            return json.load(fh)
    rc, out, err, cpu, wall, error = run(cmd, timeout)
    try:
        js = json.loads(out) if not error else None
    except json.JSONDecodeError as e:
        js = None
        error = error or f"no JSON: {e}"
    if rc not in (0, 1) and not error:
        error = f"exit {rc}"
    rec = dict(cmd=cmd, rc=rc, cpu_s=cpu, wall_s=wall, error=error,
               stderr=err.strip()[-2000:], json=js)
    with open(path + ".tmp", "w") as fh:
        json.dump(rec, fh)
    os.replace(path + ".tmp", path)
    return rec


def binary_id(path):
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for chunk in iter(lambda: fh.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()[:12]


# --------------------------------------------------------------------------------------------
# One case
# --------------------------------------------------------------------------------------------
PLAN_PATTERN = os.path.join(ROOT, "configs", "plan_law_{rig}.toml")


def plan_file(rig, pattern=PLAN_PATTERN):
    return pattern.format(rig=rig)


def release_errors(plan):
    r = plan["release"]
    return [r.get("theta_error_deg", 0.0), r.get("theta_dot_error", 0.0),
            r.get("x_dot_error", 0.0)]


def random_release(plan, seed):
    r = plan["release"]
    rng = np.random.default_rng([seed, 99])
    th = math.radians(float(rng.uniform(*r["theta_deg"])))
    w = float(rng.uniform(*r["theta_dot"]))
    v = float(rng.uniform(*r["x_dot"]))
    return (float(r.get("x", 0.0)), th, v, w)


def gen(d, law, rig, nominal, errors, seed, stream, name):
    path = os.path.join(d, f"{name}.json")
    if os.path.exists(path) and os.path.exists(os.path.join(d, f"{name}.csv")):
        with open(path) as fh:
            return json.load(fh)
    return lrg.generate(law, rig, nominal, errors, seed, stream, d, name)


def param(js, name):
    """(value, stderr): a single fit's `parameters` (judgement_sweep's lookup), else a joint
    fit's `shared`."""
    p = single_param(js, name)
    if p is None:
        e = (js.get("shared") or {}).get(name)
        if e and e.get("value") is not None and e.get("stderr") is not None:
            p = (e["value"], e["stderr"])
    return p


def zs_of(js, law):
    truth = lrg.law_truth(law)
    out = {}
    for name in lrg.gated(law):
        p = param(js, name)
        out[name] = (None if p is None or not p[1] or p[1] <= 0
                     else (p[0] - truth[name]) / p[1])
    return out


def judge_fit(rec, law):
    js = rec.get("json")
    if not js:
        return dict(chosen="error", tool_chosen="", identified=False, flagged=False,
                    zs={}, error=rec.get("error") or f"rc {rec.get('rc')}", cpu_s=rec["cpu_s"],
                    answer="")
    ch = chosen_law(js)
    zs = zs_of(js, law)
    failed = bool(js.get("failed"))
    flagged = bool(js.get("limited_by_model") or failed or js.get("implausible"))
    ok = (ch == law and not failed
          and all(z is not None and abs(z) <= 3.0 for z in zs.values()))
    fl = js.get("friction_law") or {}
    return dict(chosen=ch, tool_chosen=fl.get("chosen", ""), identified=bool(ok),
                flagged=flagged, failed=failed, zs=zs, error=rec.get("error", ""),
                cpu_s=rec["cpu_s"], answer=(js.get("answer") or "")[:200],
                notes=fl.get("notes") or [],
                se={n: (param(js, n) or (None, None))[1] for n in lrg.gated(law)},
                interval={n: ((js.get("shared") or {}).get(n) or {}).get("interval")
                          for n in lrg.gated(law)})


def strip_laws(src, dst):
    with open(src) as fh:
        js = json.load(fh)
    js.pop("friction_law", None)
    with open(dst, "w") as fh:
        json.dump(js, fh)


def run_case(c):
    """c: dict(law, rig, seed, appell, work, timeout, coulomb_only)."""
    law, rig, seed, appell, T = c["law"], c["rig"], c["seed"], c["appell"], c["timeout"]
    first_kind = c.get("first", "push")
    d = os.path.join(c["work"], f"{c['case']}_{rig}_s{seed}")
    os.makedirs(d, exist_ok=True)
    res_path = os.path.join(d, "result.json")
    if os.path.exists(res_path):
        with open(res_path) as fh:
            return json.load(fh)
    pattern = c.get("plan", PLAN_PATTERN)
    with open(plan_file(rig, pattern), "rb") as fh:
        plan_spec = tomllib.load(fh)
    errors = release_errors(plan_spec)
    rig_file = os.path.join(d, "rigs", f"{rig}.toml")
    out = dict(case=c["case"], law=law, rig=rig, seed=seed, first_kind=first_kind)
    first_nominal = FIRST if first_kind == "push" else INFORMATIVE[rig]
    first = gen(d, law, rig, first_nominal, errors, seed, 0, "first")
    out["first_motion"] = {k: first.get("motion", {}).get(k) for k in
                           ("slides_plus", "slides_minus", "onsets", "normal_over_static_load",
                            "slider_x_range_m")}
    out["first_actual"] = first["actual"]
    fit = cached_json(os.path.join(d, "fit_first.json"),
                      [appell, "fit", os.path.join(d, "first.csv"), "--rig", rig_file, "--json"],
                      T)
    out["first_fit"] = judge_fit(fit, law)
    if not fit.get("json"):
        out["error"] = "first fit: " + (fit.get("error") or fit.get("stderr", "")[-300:])
        return save(res_path, out)
    fit_js = os.path.join(d, "fit.json")
    with open(fit_js, "w") as fh:
        json.dump(fit["json"], fh)
    fl = fit["json"].get("friction_law") or {}
    out["first_fit"]["laws_table"] = [dict(law=r.get("law"), status=r.get("status"),
                                           delta_bic=r.get("delta_bic"))
                                      for r in fl.get("laws") or []]
    plan = cached_json(os.path.join(d, "plan.json"),
                       [appell, "plan", plan_file(rig, pattern), "--after", fit_js, "--json"], T)
    nolaw_js = os.path.join(d, "fit_nolaws.json")
    strip_laws(fit_js, nolaw_js)
    plan0 = cached_json(os.path.join(d, "plan_nolaws.json"),
                        [appell, "plan", plan_file(rig, pattern), "--after", nolaw_js,
                         "--json"], T)
    out["plan_cpu_s"], out["plan_nolaws_cpu_s"] = plan["cpu_s"], plan0["cpu_s"]
    out["plan_wall_s"], out["plan_nolaws_wall_s"] = plan.get("wall_s"), plan0.get("wall_s")
    pj = plan.get("json")
    if not pj:
        out["error"] = "plan: " + (plan.get("error") or plan.get("stderr", "")[-300:])
        return save(res_path, out)
    laws = pj.get("laws") or {}
    out["plan_laws"] = dict(weighed=laws.get("weighed"), criterion=laws.get("criterion"),
                            notes=laws.get("notes"))
    out["plan_notes"] = pj.get("notes")
    out["plan_feasible"] = pj.get("feasible")
    props = pj.get("proposals") or []
    if not props:
        props = pj.get("unranked") or []
        out["top_unranked"] = bool(props)
    if not props:
        out["error"] = "plan: no proposal"
        return save(res_path, out)
    top = props[0]
    keep = ("rank", "initial", "theta_deg", "robustness", "meets_min_robustness",
            "pairs_resolved", "pairs", "worst_expected_delta_bic", "discrimination",
            "predicted_stderr", "predicted_stderr_range", "predicted_stderr_mu_range",
            "predicted_mu_stderr",
            "shrinks_mu_stderr_by")
    out["top"] = {k: top.get(k) for k in keep if k in top}
    out["at_limit"] = pj.get("at_limit")
    out["top_at_limit"] = sorted({a.get("quantity", "?") + ":" + a.get("limit", "?")
                                  for a in (pj.get("at_limit") or [])})
    ini = top["initial"]
    planned_nominal = (ini["x"], ini["theta"], ini["x_dot"], ini["theta_dot"])
    nominal = dict(planned=planned_nominal, repeat=first_nominal,
                   random=random_release(plan_spec, seed))
    out["releases"] = {}
    for k, kind in enumerate(KINDS, start=1):
        t = gen(d, law, rig, nominal[kind], errors, seed, k, kind)
        ent = dict(nominal=dict(zip(["x", "theta", "x_dot", "theta_dot"], nominal[kind])),
                   actual=t.get("actual"), sim_error=t.get("error"),
                   motion={kk: (t.get("motion") or {}).get(kk) for kk in
                           ("slides_plus", "slides_minus", "onsets", "normal_over_static_load",
                            "slider_x_range_m", "slow_sliding_frames")},
                   checks_ok=t.get("ok"))
        if t.get("error"):
            ent["fit"] = dict(chosen="sim-error", identified=False)
            out["releases"][kind] = ent
            continue
        rec = cached_json(os.path.join(d, f"joint_{kind}.json"),
                          [appell, "fit", "--joint", "--json", "--rig", rig_file,
                           "--release", os.path.join(d, "first.csv"),
                           "--release", os.path.join(d, f"{kind}.csv")], T)
        ent["fit"] = judge_fit(rec, law)
        out["releases"][kind] = ent
    # predicted against achieved standard errors (planned release, true law): the joint fit
    # of first + planned (the brief's comparison), and the planned release fitted alone with
    # the true law forced (what `predicted_stderr` describes: a recording of this release)
    pse = ((out["top"].get("predicted_stderr") or {}).get(law)) or {}
    if not pse and law == "coulomb" and out["top"].get("predicted_mu_stderr"):
        # a plan that weighs no law predicts mu's standard error only (after the first fit)
        pse = {"mu_kinetic": out["top"]["predicted_mu_stderr"]}
    ach = out["releases"]["planned"]["fit"].get("se") or {}
    out["se_ratio"] = {n: (pse[n] / ach[n] if pse.get(n) and ach.get(n) else None)
                       for n in lrg.gated(law)}
    out["predicted_stderr_true_law"] = pse
    # the achieved error against the plan's range over the departures (within 20 % of it)
    rng = ((out["top"].get("predicted_stderr_range") or {}).get(law)) or {}
    out["se_in_range"] = {}
    for n in lrg.gated(law):
        lo_hi = rng.get(n)
        if lo_hi and ach.get(n) and None not in lo_hi:
            lo, hi = lo_hi
            out["se_in_range"][n] = (lo / (1 + WITHIN)) <= ach[n] <= hi * (1 + WITHIN)
    # ... within the range over mu one sd either side (predicted_stderr_mu_range), and within
    # either range (the smallest to the largest of both)
    mu_rng = ((out["top"].get("predicted_stderr_mu_range") or {}).get(law)) or {}
    out["se_in_mu_range"], out["se_in_either_range"] = {}, {}
    for n in lrg.gated(law):
        spans = [s for s in (rng.get(n), mu_rng.get(n)) if s and None not in s]
        if ach.get(n) and mu_rng.get(n) and None not in mu_rng[n]:
            lo, hi = mu_rng[n]
            out["se_in_mu_range"][n] = (lo / (1 + WITHIN)) <= ach[n] <= hi * (1 + WITHIN)
        if ach.get(n) and spans:
            lo, hi = min(s[0] for s in spans), max(s[1] for s in spans)
            out["se_in_either_range"][n] = (lo / (1 + WITHIN)) <= ach[n] <= hi * (1 + WITHIN)
    if not out["releases"]["planned"].get("sim_error"):
        alone = cached_json(os.path.join(d, "alone_planned.json"),
                            [appell, "fit", os.path.join(d, "planned.csv"), "--rig", rig_file,
                             "--json"] + FORCE[law], T)
        al = judge_fit(alone, law)
        out["alone_planned"] = dict(chosen=al["chosen"], se=al.get("se"), zs=al.get("zs"),
                                    error=al.get("error"))
        se1 = al.get("se") or {}
        out["se_ratio_alone"] = {n: (pse[n] / se1[n] if pse.get(n) and se1.get(n) else None)
                                 for n in lrg.gated(law)}
    return save(res_path, out)


def baseline_case(c):
    """The same plan after the same fit with another binary (--baseline): its CPU seconds."""
    d = os.path.join(c["work"], f"{c['case']}_{c['rig']}_s{c['seed']}")
    fit_js = os.path.join(d, "fit.json")
    if not os.path.exists(fit_js):
        return None
    rec = cached_json(os.path.join(d, f"plan_baseline_{c['baseline_id']}.json"),
                      [c["baseline"], "plan", plan_file(c["rig"], c.get("plan", PLAN_PATTERN)),
                       "--after", fit_js, "--json"], c["timeout"])
    return rec["cpu_s"] if rec.get("json") else None


def save(path, out):
    with open(path + ".tmp", "w") as fh:
        json.dump(out, fh, indent=1)
    os.replace(path + ".tmp", path)
    return out


def run_case_safe(c):
    try:
        return run_case(c)
    except Exception as e:  # a case's failure is a row, not the end of the sweep
        return dict(case=c["case"], law=c["law"], rig=c["rig"], seed=c["seed"],
                    first_kind=c.get("first", "push"), error=f"{type(e).__name__}: {e}")


# --------------------------------------------------------------------------------------------
# Tables
# --------------------------------------------------------------------------------------------
def med(xs):
    xs = [x for x in xs if x is not None]
    return statistics.median(xs) if xs else None


def f(v, spec=".2f"):
    return "-" if v is None else format(v, spec)


def first_verdict(r):
    """How the fit read the first release: 'coulomb', 'tie' (another law, the true one said
    to fit about as well or not identified), 'identified' (it already found the law)."""
    ff = r.get("first_fit") or {}
    if ff.get("identified"):
        return "identified"
    return "coulomb" if ff.get("chosen") == "coulomb" else ff.get("chosen", "?")


def count(rs, kind):
    return sum(bool(((r.get("releases") or {}).get(kind) or {}).get("fit", {}).get("identified"))
               for r in rs)


def tally(xs):
    out = {}
    for x in xs:
        out[x] = out.get(x, 0) + 1
    return " ".join(f"{k} {v}" for k, v in sorted(out.items()))


def case_law(case):
    return "coulomb" if case.startswith("coulomb") else case


def ratio_rows(rows, key, L):
    allr = []
    for case in CASES:
        for rig in RIGS:
            rs = [r for r in rows if r.get("case") == case and r["rig"] == rig]
            if not rs:
                continue
            n_all = len(rs)
            if key == "se_ratio":   # the joint fit's errors are its chosen model's: the true law
                rs = [r for r in rs if (((r.get("releases") or {}).get("planned") or {})
                                        .get("fit") or {}).get("chosen") == r["law"]]
            for name in lrg.gated(case_law(case)):
                v = [(r.get(key) or {}).get(name) for r in rs]
                v = [x for x in v if x is not None]
                if case in LAWS:
                    allr += v
                w = sum(abs(x - 1) <= WITHIN for x in v)
                L.append(f"| {case} | {rig} | {name} | {f(med(v))} | "
                         f"{f(min(v) if v else None)} | {f(max(v) if v else None)} | "
                         f"{w} of {len(v)} (of {n_all} cases) |")
    L.append(f"| **4 laws** | | | {f(med(allr))} | {f(min(allr) if allr else None)} | "
             f"{f(max(allr) if allr else None)} | {sum(abs(x - 1) <= WITHIN for x in allr)} of "
             f"{len(allr)} |")


def range_rows(rows, L):
    """The achieved error within the plan's range over departures (20 % slack), and how the
    joint fit made its interval (a block-widened one holds the model's misfit too)."""
    keys = ("se_in_range", "se_in_mu_range", "se_in_either_range")
    tot = {k: [0, 0] for k in keys}
    for case in LAWS:
        for rig in RIGS:
            rs = [r for r in rows if r.get("case") == case and r["rig"] == rig
                  and (((r.get("releases") or {}).get("planned") or {}).get("fit") or {})
                  .get("chosen") == r["law"]]
            for name in lrg.gated(case):
                cells = []
                for k in keys:
                    v = [(r.get(k) or {}).get(name) for r in rs]
                    v = [x for x in v if x is not None]
                    tot[k][0] += sum(v)
                    tot[k][1] += len(v)
                    cells.append(f"{sum(v)} of {len(v)}")
                kinds = [((r["releases"]["planned"]["fit"].get("interval") or {}).get(name)
                          or "?") for r in rs]
                L.append(f"| {case} | {rig} | {name} | {' | '.join(cells)} | {tally(kinds)} |")
    totals = " | ".join(f"**{tot[k][0]} of {tot[k][1]}**" for k in keys)
    L.append(f"| **4 laws** | | | {totals} | |")


def tables(rows, cpu_example, seeds, base=None):
    L = []
    L.append(f"Seeds {seeds}. Identified: the joint fit (first + the release) chose exactly the "
             "true law and every parameter of it is within 3 SE of the truth.")
    L.append("")
    L.append("| true law | rig | n | first fit chose | planned | repeat | random | top proposals "
             "at a box limit | top proposal, seed 1 (theta deg, theta' rad/s, x' m/s) |")
    L.append("|---|---|---|---|---|---|---|---|---|")
    tot = {k: 0 for k in KINDS}
    ntot = 0
    for case in CASES:
        if case == "coulomb-informative":
            continue
        for rig in RIGS:
            rs = [r for r in rows if r.get("case") == case and r["rig"] == rig]
            if not rs:
                continue
            cnt = {k: count(rs, k) for k in KINDS}
            if case in LAWS:
                ntot += len(rs)
                for k in KINDS:
                    tot[k] += cnt[k]
            r1 = min(rs, key=lambda r: r["seed"])
            ini = (r1.get("top") or {}).get("initial")
            tp = (f"{math.degrees(ini['theta']):.1f}, {ini['theta_dot']:.2f}, "
                  f"{ini['x_dot']:.3f}" if ini else "-")
            lim = sum(bool(r.get("top_at_limit")) for r in rs)
            L.append(f"| {case} | {rig} | {len(rs)} | "
                     f"{tally((r.get('first_fit') or {}).get('chosen', '?') for r in rs)} | "
                     f"{cnt['planned']} | {cnt['repeat']} | {cnt['random']} | {lim} | {tp} |")
        if case == LAWS[-1] and ntot:
            L.append(f"| **4 laws** | | {ntot} | | **{tot['planned']}** | **{tot['repeat']}** | "
                     f"**{tot['random']}** | | |")
    L.append("")
    L.append("The joint fits of the four laws' cases, by release: identified; flagged (limited by "
             "the model, failed or implausible); no JSON (the fit refused or failed, exit 1); "
             "another law unflagged; a parameter it reports beyond 3 SE, unflagged (mu_kinetic "
             "included; largest |z|):")
    L.append("")
    L.append("| release | n | identified | flagged | no JSON | another law, unflagged | beyond "
             "3 SE, unflagged | largest unflagged abs(z) |")
    L.append("|---|---|---|---|---|---|---|---|")
    for k in KINDS:
        es = [((r.get("releases") or {}).get(k) or {}).get("fit") or {}
              for r in rows if r.get("case") in LAWS]
        lw = [r["law"] for r in rows if r.get("case") in LAWS]
        n = len(es)
        ide = sum(bool(e.get("identified")) for e in es)
        fl = sum(bool(e.get("flagged")) for e in es)
        nj = sum(e.get("chosen") in ("error", "none", "sim-error", None) for e in es)
        ok = [e for e in es if not e.get("flagged") and e.get("chosen") not in
              ("error", "none", "sim-error", None)]
        other = sum(e["chosen"] != law for e, law in zip(es, lw) if e in ok)
        zmax = [max([abs(z) for z in (e.get("zs") or {}).values() if z is not None] or [0.0])
                for e in ok]
        beyond = sum(z > 3 for z in zmax)
        L.append(f"| {k} | {n} | {ide} | {fl} | {nj} | {other} | {beyond} | "
                 f"{f(max(zmax) if zmax else None, '.1f')} |")
    L.append("")
    L.append("Laws the joint fits chose ((flag): limited by the model, failed or implausible; "
             "error: no JSON):")
    L.append("")
    L.append("| true law | rig | planned | repeat | random |")
    L.append("|---|---|---|---|---|")
    for case in CASES:
        for rig in RIGS:
            rs = [r for r in rows if r.get("case") == case and r["rig"] == rig]
            if not rs or case == "coulomb-informative":
                continue
            cells = []
            for k in KINDS:
                names = []
                for r in rs:
                    e = ((r.get("releases") or {}).get(k) or {}).get("fit") or {}
                    names.append(e.get("chosen", "none") + ("(flag)" if e.get("flagged") else ""))
                cells.append(tally(names))
            L.append(f"| {case} | {rig} | " + " | ".join(cells) + " |")
    L.append("")
    L.append("Predicted / achieved standard error, the true law's parameters: `predicted_stderr` "
             "of the top proposal against the joint fit of first + planned, where that fit chose "
             "the true law (its errors are its chosen model's):")
    L.append("")
    L.append("| true law | rig | parameter | median | min | max | within 20 % |")
    L.append("|---|---|---|---|---|---|---|")
    ratio_rows(rows, "se_ratio", L)
    L.append("")
    L.append("The achieved error (the joint fit of first + planned, where it chose the true "
             "law) within the plan's `predicted_stderr_range` (the law at 0.5 to 4 times its "
             "reference departure), with 20 % slack either side; within "
             "`predicted_stderr_mu_range` (mu one sd either side); within either; and the "
             "joint fit's interval kinds:")
    L.append("")
    L.append("| true law | rig | parameter | in range | in the range over mu | in either "
             "| joint fit's interval |")
    L.append("|---|---|---|---|---|---|---|")
    range_rows(rows, L)
    L.append("")
    L.append("The same against the planned release fitted alone with the true law forced "
             "(`--friction LAW`, static: `--with mu_static`):")
    L.append("")
    L.append("| true law | rig | parameter | median | min | max | within 20 % |")
    L.append("|---|---|---|---|---|---|---|")
    ratio_rows(rows, "se_ratio_alone", L)
    L.append("")
    for case in ("coulomb-informative", "coulomb-push"):
        cr = [r for r in rows if r.get("case") == case]
        if not cr:
            continue
        L.append(f"Plain Coulomb rails, first release {case.split('-')[1]}: the laws the plan "
                 "weighed and its word for it")
        L.append("")
        L.append("| rig | n | first fit chose | plan weighed no law | criterion | joint fit with "
                 "the planned release chose | notes (seed 1) |")
        L.append("|---|---|---|---|---|---|---|")
        for rig in RIGS:
            rs = [r for r in cr if r["rig"] == rig]
            if not rs:
                continue
            none = sum(not ((r.get("plan_laws") or {}).get("weighed")) for r in rs)
            r1 = min(rs, key=lambda r: r["seed"])
            notes = "; ".join((r1.get("plan_laws") or {}).get("notes") or []) or "-"
            crit = tally(str((r.get("plan_laws") or {}).get("criterion")) for r in rs)
            jch = tally((((r.get("releases") or {}).get("planned") or {}).get("fit") or {})
                        .get("chosen", "none") for r in rs)
            L.append(f"| {rig} | {len(rs)} | "
                     f"{tally((r.get('first_fit') or {}).get('chosen', '?') for r in rs)} | "
                     f"{none} of {len(rs)} | {crit} | {jch} | {notes} |")
        L.append("")
    L.append("CPU seconds (user + sys of the child), median [max]; without laws: the same plan "
             "after the same fit with its `friction_law` section removed (the planner then ranks "
             "by mu's precision, as before issue 60):")
    L.append("")
    L.append("| what | n | with laws | without laws | ratio median [max] |")
    L.append("|---|---|---|---|---|")
    for rig in RIGS:
        rs = [r for r in rows if r["rig"] == rig and r.get("plan_cpu_s") is not None
              and r.get("plan_nolaws_cpu_s")]
        if not rs:
            continue
        a = [r["plan_cpu_s"] for r in rs]
        b = [r["plan_nolaws_cpu_s"] for r in rs]
        q = [x / y for x, y in zip(a, b)]
        L.append(f"| plan_law_{rig} --after | {len(rs)} | {f(med(a))} [{f(max(a))}] | "
                 f"{f(med(b))} [{f(max(b))}] | {f(med(q))} [{f(max(q))}] |")
    if cpu_example:
        L.append(f"| plan_example.toml | {len(cpu_example)} | {f(med(cpu_example), '.3f')} "
                 f"[{f(max(cpu_example), '.3f')}] | | |")
    fits = [((r.get("releases") or {}).get(k) or {}).get("fit", {}).get("cpu_s")
            for r in rows for k in KINDS]
    fits = [x for x in fits if x is not None]
    ff = [(r.get("first_fit") or {}).get("cpu_s") for r in rows]
    ff = [x for x in ff if x is not None]
    if fits:
        L.append(f"| fit --joint (two releases) | {len(fits)} | {f(med(fits))} "
                 f"[{f(max(fits))}] | | |")
    if ff:
        L.append(f"| fit (first release) | {len(ff)} | {f(med(ff))} [{f(max(ff))}] | | |")
    if base:
        L.append("")
        L.append(f"Against the baseline binary (SHA-256 {base['id']}), the same plan after the "
                 "same fit, CPU seconds median [max]:")
        L.append("")
        L.append("| what | n | this binary | baseline | ratio median [max] |")
        L.append("|---|---|---|---|---|")
        for rig in RIGS:
            rs = [r for r in rows if r["rig"] == rig and r.get("plan_cpu_s") is not None
                  and r.get("plan_baseline_cpu_s")]
            if not rs:
                continue
            a_ = [r["plan_cpu_s"] for r in rs]
            b_ = [r["plan_baseline_cpu_s"] for r in rs]
            q = [x / y for x, y in zip(a_, b_)]
            L.append(f"| plan_law_{rig} --after | {len(rs)} | {f(med(a_))} [{f(max(a_))}] | "
                     f"{f(med(b_))} [{f(max(b_))}] | {f(med(q))} [{f(max(q))}] |")
        be = base["example"]
        if cpu_example and be:
            L.append(f"| plan_example.toml | {len(be)} | {f(med(cpu_example), '.3f')} | "
                     f"{f(med(be), '.3f')} | {f(med(cpu_example) / med(be))} |")
    L.append("")
    badrec = [r for r in rows if r.get("recordings_failing_checks")]
    nrec = sum(1 + len(r.get("releases") or {}) for r in rows)
    L.append(f"Recordings whose generator self-checks failed: {sum(len(r['recordings_failing_checks']) for r in badrec)} of {nrec}"
             + ("".join(f"; {r.get('case')} {r['rig']} s{r['seed']}: "
                        + ",".join(r["recordings_failing_checks"]) for r in badrec)))
    L.append("")
    errs = [r for r in rows if r.get("error")]
    if errs:
        L.append("Cases that did not finish:")
        for r in errs:
            L.append(f"- {r.get('case')} {r['rig']} s{r['seed']}: {r['error'][:300]}")
        L.append("")
    return "\n".join(L)


def tsv(rows, path):
    head = ["case", "rig", "seed", "first_chosen", "first_tool", "first_answer", "weighed",
            "top_theta_deg", "top_theta_dot", "top_x_dot", "pairs_resolved",
            "worst_expected_delta_bic", "plan_cpu", "plan_nolaws_cpu"]
    for k in KINDS:
        head += [f"{k}_chosen", f"{k}_identified", f"{k}_z", f"{k}_slides", f"{k}_cpu"]
    head += ["se_ratio", "error"]
    lines = ["\t".join(head)]
    for r in sorted(rows, key=lambda r: (r.get("case", ""), r["rig"], r["seed"])):
        ff = r.get("first_fit") or {}
        top = r.get("top") or {}
        ini = top.get("initial") or {}
        row = [r.get("case", r["law"]), r["rig"], str(r["seed"]), ff.get("chosen", ""),
               ff.get("tool_chosen", ""), (ff.get("answer") or "")[:100],
               ",".join((r.get("plan_laws") or {}).get("weighed") or []),
               f(math.degrees(ini["theta"]) if ini else None, ".1f"),
               f(ini.get("theta_dot"), ".3f"), f(ini.get("x_dot"), ".3f"),
               str(top.get("pairs_resolved")), str(top.get("worst_expected_delta_bic")),
               f(r.get("plan_cpu_s")), f(r.get("plan_nolaws_cpu_s"))]
        for k in KINDS:
            e = (r.get("releases") or {}).get(k) or {}
            fi = e.get("fit") or {}
            m = e.get("motion") or {}
            row += [fi.get("chosen", ""), str(fi.get("identified", "")),
                    " ".join(f"{n}={f(z, '+.2f')}" for n, z in (fi.get("zs") or {}).items()),
                    f"+{m.get('slides_plus')}-{m.get('slides_minus')}/o{m.get('onsets')}",
                    f(fi.get("cpu_s"))]
        row += [" ".join(f"{n}={f(v)}" for n, v in (r.get("se_ratio") or {}).items()),
                r.get("error", "")]
        lines.append("\t".join(row))
    with open(path, "w") as fh:
        fh.write("\n".join(lines) + "\n")


def parse_seeds(s):
    if ".." in s:
        a, b = (int(x) for x in s.split(".."))
        return list(range(a, b + 1))
    return [int(x) for x in s.split(",")]


def set_reference_truth():
    """The generator's truth at the planner's reference departures (src/plan/law.rs,
    REFERENCE_*): what `--truth reference` simulates."""
    mu = lrg.MU_K
    lrg.set_truth(mu_s=round(1.1 * mu, 12), v_s=0.01, mu_pos=round(1.025 * mu, 12),
                  mu_neg=round(0.975 * mu, 12), load_exp=0.9)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--appell", required=True)
    ap.add_argument("--work", default="/tmp/law_plan_sweep")
    ap.add_argument("--seeds", default="1..5")
    ap.add_argument("--laws", default=",".join(LAWS))
    ap.add_argument("--rigs", default=",".join(RIGS))
    ap.add_argument("--no-coulomb", action="store_true")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--timeout", type=float, default=900.0)
    ap.add_argument("--md", default=None, help="write the tables (markdown) here")
    ap.add_argument("--baseline", default=None,
                    help="another appell binary (e.g. main before issue 60): the same plans "
                         "after the same fits and plan_example.toml, for the CPU comparison")
    ap.add_argument("--truth", choices=["default", "reference"], default="default",
                    help="reference: the true laws at the planner's reference departures from "
                         "mu_k = 0.22 (mu_s 1.1 mu_k, v_s 0.01 m/s, split 2.5 %% of mu, "
                         "exponent 0.9), in their own work directory")
    ap.add_argument("--plan", default=PLAN_PATTERN,
                    help="plan files, {rig} for the rig's name (default "
                         "configs/plan_law_{rig}.toml); another gets its own work directory")
    args = ap.parse_args(argv)
    appell = os.path.abspath(args.appell)
    bid = binary_id(appell)
    work = os.path.join(args.work, bid)
    if args.plan != PLAN_PATTERN:
        work += "_plan" + hashlib.sha256(args.plan.encode()).hexdigest()[:8]
    if args.truth == "reference":
        set_reference_truth()
        work += "_reftruth"
    os.makedirs(work, exist_ok=True)
    seeds = parse_seeds(args.seeds)
    laws, rigs = args.laws.split(","), args.rigs.split(",")
    t0 = time.monotonic()
    print(f"appell {appell} (sha256 {bid}, mtime "
          f"{time.strftime('%Y-%m-%d %H:%M:%S', time.gmtime(os.path.getmtime(appell)))} UTC); "
          f"work {work}", flush=True)
    cases = [dict(case=law, law=law, rig=rig, seed=s) for s in seeds for law in laws
             for rig in rigs]
    if not args.no_coulomb:
        cases += [dict(case=f"coulomb-{k}", law="coulomb", first=k, rig=rig, seed=s)
                  for s in seeds for k in ("informative", "push") for rig in rigs]
    for c in cases:
        c.update(appell=appell, work=work, timeout=args.timeout, plan=args.plan)
    rows = []
    with cf.ProcessPoolExecutor(args.jobs) as ex:
        futs = {ex.submit(run_case_safe, c): c for c in cases}
        for fu in cf.as_completed(futs):
            r = fu.result()
            rows.append(r)
            rel = r.get("releases") or {}
            ids = " ".join(f"{k}={'Y' if ((rel.get(k) or {}).get('fit') or {}).get('identified') else 'n'}"
                           f"({((rel.get(k) or {}).get('fit') or {}).get('chosen', '-')})"
                           for k in KINDS)
            print(f"[{time.monotonic() - t0:6.0f} s] {r.get('case', r['law']):<19s} {r['rig']:<5s} s{r['seed']}: "
                  f"first {first_verdict(r)}; weighed "
                  f"{','.join((r.get('plan_laws') or {}).get('weighed') or []) or 'none'}; {ids}"
                  + (f"; ERROR {r['error'][:200]}" if r.get("error") else ""), flush=True)
    # the generator's self-checks of every recording of every case
    for r in rows:
        d = os.path.join(work, f"{r.get('case')}_{r['rig']}_s{r['seed']}")
        bad = []
        for name in ["first"] + KINDS:
            path = os.path.join(d, f"{name}.json")
            if os.path.exists(path):
                with open(path) as fh:
                    if not json.load(fh).get("ok"):
                        bad.append(name)
        r["recordings_failing_checks"] = bad
    # the planner's example, three times, one at a time (and with --baseline, interleaved)
    def example(binary, path):
        if os.path.exists(path):
            return json.load(open(path))
        cpus = []
        for _ in range(3):
            rc, _, err, cpu, _, error = run([binary, "plan",
                                             os.path.join(ROOT, "configs", "plan_example.toml")],
                                            args.timeout)
            if rc == 0 and not error:
                cpus.append(cpu)
        json.dump(cpus, open(path, "w"))
        return cpus
    cpu_example = example(appell, os.path.join(work, "plan_example_cpu.json"))
    base = None
    if args.baseline:
        b_path = os.path.abspath(args.baseline)
        b_id = binary_id(b_path)
        base = dict(id=b_id, example=example(b_path, os.path.join(
            work, f"plan_example_cpu_baseline_{b_id}.json")))
        bcases = [dict(c, baseline=b_path, baseline_id=b_id) for c in cases]
        with cf.ProcessPoolExecutor(args.jobs) as ex:
            bc = list(ex.map(baseline_case, bcases))
        for r in rows:
            for c, v in zip(bcases, bc):
                if (c["case"], c["rig"], c["seed"]) == (r.get("case"), r["rig"], r["seed"]):
                    r["plan_baseline_cpu_s"] = v
    text = tables(rows, cpu_example, seeds, base)
    print()
    print(text)
    print(f"\nwall {time.monotonic() - t0:.0f} s")
    tsv(rows, os.path.join(work, "rows.tsv"))
    with open(os.path.join(work, "rows.json"), "w") as fh:
        json.dump(rows, fh, indent=1)
    if args.md:
        with open(args.md, "w") as fh:
            fh.write(text + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
