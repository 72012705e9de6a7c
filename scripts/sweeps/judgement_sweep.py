#!/usr/bin/env python3
"""Run `appell fit` on scripts/generators/judgement_generator.py's recordings and tabulate the fit's
judgement (issue 58): the law it chose, its coverage, its flags.

For every case of --manifest (default /tmp/judgement/manifest.json) runs
    APPELL fit REC --rig RIG --json
with 2 workers (--jobs) and a timeout per fit (--timeout, 120 s), using run_one of
scripts/sweeps/measured_rig_sweep.py (CPU time of each child by os.wait4) and its `analyse` (mu_kinetic
value / stderr / ci95 / parts, covered, within 3 SE; flagged = `limited_by_model` non-empty,
`failed`, `implausible`, an error, a timeout or no mu). The binary is copied once at the start
(--no-snapshot runs it in place), so a rebuild during the sweep does not mix versions; a fit
that errors without JSON (not a timeout) is retried once after the binary is back.

Tables
  LAWS   per true law x rig: the laws chosen (the chosen model's friction terms from
         `nuisances`: direction, load, stribeck, mu_static -> static, viscous_friction ->
         viscous, joined by '+', none: coulomb; the tool's friction_law.chosen, which names one
         law and leaves out a free mu_static beside direction or load, is in the TSV); the true
         law chosen (exactly: 'direction+static' for a static rail is another law); every true
         parameter within 3 SE (mu_kinetic; mu_static under the static and Stribeck laws, from
         `parameters`, else friction_law.parameters, else the top-level mu_static;
         mu_kinetic_split under the direction law, load_exponent under the load law; the
         Stribeck speed's z is in the TSV, not gated); flagged; tie: a wrong law, unflagged,
         whose mu_kinetic ci95 holds the truth, where the fit states the true law fits about as
         well (|delta BIC| < 6 of the best converged `models` row with the chosen model's other
         nuisances plus the true law's; without such a row friction_law's evidence for the
         true law, or its note), shown with how many of them have a parameter beyond 3 SE;
         confidently wrong: unflagged, not a tie, and a wrong law or a gated parameter beyond 3
         SE (or missing); errors; median CPU. Coulomb controls: the fraction with Coulomb
         chosen.
  CLEAN  overall and per pendulum / frame rate / noise / mass ratio: false-flag rate, coverage of
         mu_kinetic.ci95, within 3 SE, confidently wrong (unflagged and beyond 3 SE), laws
         chosen; the widening of the interval, mu_kinetic.parts total / sqrt(noise^2 + rig^2)
         (1 when no model part was added), and the `interval` tags; which adequacy test flagged
         (parsed from limited_by_model: chi2, block (correlated residuals), runs, windows
         (slides disagree), capped (every free parameter taken), implausible, failed).
  TIME   per timestamp mode (whole ms; 0.3 ms jitter): flagged, coverage, within 3 SE, the tests
         and nuisances chosen.
  CPU    median CPU seconds per fit, per set and overall.

Standard library only. Usage:
    python3 scripts/sweeps/judgement_sweep.py --appell /work/iter/release/appell \\
        --manifest /tmp/judgement/manifest.json --tsv /tmp/judgement/sweep.tsv
Options: --only laws|clean|time (repeatable), --jobs 2, --timeout 120, --extra "ARGS",
--no-snapshot, --from-tsv FILE (tabulate an earlier --tsv instead of running).
"""

import argparse
import concurrent.futures as cf
import hashlib
import json
import os
import re
import shlex
import shutil
import statistics
import subprocess
import sys
import tempfile
import threading
import time

sys.dont_write_bytecode = True
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from measured_rig_sweep import analyse, run_one  # noqa: E402

NUISANCE_LAW = {"direction": "direction", "load": "load", "stribeck": "stribeck",
                "mu_static": "static", "viscous_friction": "viscous"}   # in this order
TRUE_NUISANCES = {"coulomb": set(), "static": {"mu_static"}, "stribeck": {"stribeck"},
                  "direction": {"direction"}, "load": {"load"}}
TIE_BIC = 6.0
TESTS = [("chi2", "chi-square is"), ("block", "correlated in time"),
         ("runs", "keep their sign"), ("windows", "fitted one by one, disagree"),
         ("capped", "took every free parameter"), ("implausible", "needs what no real rig"),
         ("failed", None), ("error", None)]


# --------------------------------------------------------------------------------------------
# Reading one fit
# --------------------------------------------------------------------------------------------
def chosen_law(js):
    """The friction terms of the chosen model, from `nuisances` (direction, load, stribeck,
    mu_static -> static, viscous_friction -> viscous, joined by '+'; none: coulomb); without
    `nuisances`, friction_law.chosen."""
    ns = js.get("nuisances")
    if ns is None:
        return (js.get("friction_law") or {}).get("chosen") or "?"
    laws = [law for n, law in NUISANCE_LAW.items() if n in ns]
    return "+".join(laws) if laws else "coulomb"


def param(js, name):
    """(value, stderr) of a parameter: `parameters`, friction_law.parameters, top level."""
    e = (js.get("parameters") or {}).get(name)
    if not e:
        for p in (js.get("friction_law") or {}).get("parameters") or []:
            if p.get("name") == name:
                e = p
                break
    if not e and isinstance(js.get(name), dict):
        e = js[name]
    if e and e.get("value") is not None and e.get("stderr") is not None:
        return e["value"], e["stderr"]
    return None


def gated(truth):
    law = truth["law"]
    out = [("mu_kinetic", truth["mu_kinetic"])]
    if law in ("static", "stribeck"):
        out.append(("mu_static", truth["mu_static"]))
    if law == "direction":
        out.append(("mu_kinetic_split", truth["split"]))
    if law == "load":
        out.append(("load_exponent", truth["load_exponent"]))
    return out


def zscore(js, name, true):
    p = param(js, name)
    if p is None or not p[1] or p[1] <= 0:
        return None
    return (p[0] - true) / p[1]


def tests_of(row, a):
    if row["error"]:
        return ["error"]
    text = a["limited"] or ""
    out = [k for k, needle in TESTS if needle and needle in text]
    if a["failed"]:
        out.append("failed")
    if a["mu"] is None and not out:
        out.append("no mu")
    if a["flagged"] and not out:
        out.append("other")
    return out


def tie_of(js, truth):
    """Whether the fit states that the true law fits about as well (|delta BIC| < 6): the
    best converged row of `models` whose nuisances are the chosen model's non-friction ones
    plus the true law's; without such a row, friction_law's evidence for the true law (not
    the chosen one) or a note that it fits as well. Returns (tie, delta_bic, source)."""
    ns = set(js.get("nuisances") or [])
    want = (ns - set(NUISANCE_LAW)) | TRUE_NUISANCES[truth["law"]]
    best = None
    for m in js.get("models") or []:
        if m.get("failed") or m.get("delta_bic") is None:
            continue
        names = set() if m.get("name") == "base" else set((m.get("name") or "").split("+"))
        if names == want and (best is None or m["delta_bic"] < best):
            best = m["delta_bic"]
    if best is not None:
        return abs(best) < TIE_BIC, best, "models"
    fl = js.get("friction_law") or {}
    for ev in fl.get("laws") or []:
        if (ev.get("law") == truth["law"] and ev.get("delta_bic") is not None
                and ev.get("status") != "chosen"):
            return abs(ev["delta_bic"]) < TIE_BIC, ev["delta_bic"], "friction_law"
    noted = any(f"The {truth['law']} law fits this recording about as well" in n
                for n in fl.get("notes") or [])
    return noted, None, "note" if noted else ""


def judge(case, row):
    a = analyse(row, case["truth_mu"])
    js = row["json"] or {}
    truth = case["truth"]
    law = chosen_law(js) if row["json"] is not None else "error"
    zs = {name: zscore(js, name, true) for name, true in gated(truth)}
    params_ok = all(z is not None and abs(z) <= 3.0 for z in zs.values())
    right_law = law == truth["law"]
    tie_stated, tie_dbic, tie_src = (tie_of(js, truth) if not right_law and law != "error"
                                     else (False, None, ""))
    tie = tie_stated and not a["flagged"] and a["covered"]
    cw = not a["flagged"] and not tie and (not params_ok or not right_law)
    if truth["law"] == "stribeck":
        zs_vs = zscore(js, "stribeck_velocity", truth["stribeck_velocity"])
    else:
        zs_vs = None
    parts = [a.get(f"se_{k}") for k in ("noise", "rig", "total")]
    widening = None
    if all(v is not None for v in parts):
        base = (parts[0] ** 2 + parts[1] ** 2) ** 0.5
        widening = parts[2] / base if base > 0 else None
    return dict(
        id=case["id"], set=case["set"], group=case["group"], law=truth["law"], rig=case["rig"],
        seed=case["seed"], pendulum=case.get("pendulum", ""), fps=case.get("fps"),
        noise_m=case.get("noise_m"), mass_ratio=case.get("mass_ratio"),
        time_mode=case.get("time_mode", ""), onsets=case.get("onsets"),
        truth_mu=case["truth_mu"], truth_mu_s=truth.get("mu_static"), chosen=law,
        chosen_tool=(js.get("friction_law") or {}).get("chosen", ""), right_law=right_law,
        tie_stated=tie_stated, tie_delta_bic=tie_dbic, tie_source=tie_src,
        z_mu_k=zs.get("mu_kinetic"), z_mu_s=zs.get("mu_static"),
        z_split=zs.get("mu_kinetic_split"), z_exponent=zs.get("load_exponent"), z_v_s=zs_vs,
        params_ok=params_ok, flagged=a["flagged"], tie=tie, confident_wrong=cw,
        covered=a["covered"], within3=a["within3"], mu=a["mu"], se=a["se"], lo=a["lo"],
        hi=a["hi"], se_noise=parts[0], se_rig=parts[1], se_model=a.get("se_model"),
        se_total=parts[2], widening=widening, interval=a["interval"],
        tests="+".join(tests_of(row, a)), limited=a["limited"], failed=a["failed"],
        nuisances=a["nuisances"], error=row["error"], rc=row["rc"], cpu_s=row["cpu_s"],
        wall_s=row["wall_s"], retried=row.get("retried", False),
        answer=(js or {}).get("answer", ""))


# --------------------------------------------------------------------------------------------
# Tables
# --------------------------------------------------------------------------------------------
def med(xs):
    xs = [x for x in xs if x is not None]
    return statistics.median(xs) if xs else None


def quantile(xs, q):
    xs = sorted(x for x in xs if x is not None)
    if not xs:
        return None
    k = min(len(xs) - 1, max(0, int(round(q * (len(xs) - 1)))))
    return xs[k]


def f(v, spec):
    return "-" if v is None else format(v, spec)


def pct(k, n):
    return f"{k}/{n} ({100.0 * k / n:.0f} %)" if n else "0/0"


def counts(xs):
    d = {}
    for x in xs:
        d[x] = d.get(x, 0) + 1
    return ", ".join(f"{k} {v}" for k, v in sorted(d.items(), key=lambda kv: -kv[1]))


def tests_count(rows):
    d = {}
    for r in rows:
        if r["flagged"]:
            for t in (r["tests"] or "other").split("+"):
                d[t] = d.get(t, 0) + 1
    return ", ".join(f"{k} {v}" for k, v in sorted(d.items(), key=lambda kv: -kv[1])) or "-"


def laws_tables(rows):
    out = ["## LAWS (true law x rig)", "",
           "| law | rig | n | laws chosen | true law chosen | params within 3 SE | flagged | "
           "tie (of which a param > 3 SE) | confidently wrong | errors | median CPU s |",
           "|---|---|---|---|---|---|---|---|---|---|---|"]
    order = ["static", "stribeck", "direction", "load", "coulomb"]
    keys = sorted({(r["law"], r["rig"]) for r in rows},
                  key=lambda k: (order.index(k[0]) if k[0] in order else 9, k[1]))
    for law, rig in keys:
        g = [r for r in rows if r["law"] == law and r["rig"] == rig]
        out.append(f"| {law} | {rig} | {len(g)} | {counts(r['chosen'] for r in g)} | "
                   f"{sum(r['right_law'] for r in g)} | {sum(r['params_ok'] for r in g)} | "
                   f"{sum(r['flagged'] for r in g)} | {sum(r['tie'] for r in g)} "
                   f"({sum(r['tie'] and not r['params_ok'] for r in g)}) | "
                   f"{sum(r['confident_wrong'] for r in g)} | {sum(bool(r['error']) for r in g)}"
                   f" | {f(med(r['cpu_s'] for r in g), '.2f')} |")
    out.append("")
    out += ["### LAWS per parameter set (all rigs)", "",
            "| law | params | n | true law chosen | params within 3 SE | flagged | tie | "
            "confidently wrong | median z mu_k | median z mu_s |",
            "|---|---|---|---|---|---|---|---|---|---|"]
    for law in order:
        for p in sorted({r["params"] for r in rows if r["law"] == law}):
            g = [r for r in rows if r["law"] == law and r["params"] == p]
            out.append(f"| {law} | {p} | {len(g)} | {sum(r['right_law'] for r in g)} | "
                       f"{sum(r['params_ok'] for r in g)} | {sum(r['flagged'] for r in g)} | "
                       f"{sum(r['tie'] for r in g)} | {sum(r['confident_wrong'] for r in g)} | "
                       f"{f(med(r['z_mu_k'] for r in g), '+.2f')} | "
                       f"{f(med(r['z_mu_s'] for r in g), '+.2f')} |")
    out.append("")
    ctl = [r for r in rows if r["law"] == "coulomb"]
    if ctl:
        n_c = sum(r["chosen"] == "coulomb" for r in ctl)
        per_rig = "; ".join(
            f"{rig} {sum(r['chosen'] == 'coulomb' for r in ctl if r['rig'] == rig)}"
            f"/{sum(r['rig'] == rig for r in ctl)}" for rig in sorted({r["rig"] for r in ctl}))
        out.append(f"Coulomb controls: Coulomb chosen {pct(n_c, len(ctl))}, flagged "
                   f"{sum(r['flagged'] for r in ctl)}, confidently wrong "
                   f"{sum(r['confident_wrong'] for r in ctl)}; per rig: {per_rig}")
    fl = [r for r in rows if r["flagged"]]
    out.append(f"flag tests (LAWS): {tests_count(fl)}")
    out.append("")
    return out


def coverage_table(title, key, rows, keys=None):
    out = [f"### {title}", "",
           "| group | n | flagged | covered (95 %) | within 3 SE | confidently wrong | "
           "widening median / p90 / max | widened > 1.05 | laws chosen | median CPU s |",
           "|---|---|---|---|---|---|---|---|---|---|"]
    groups = {}
    for r in rows:
        groups.setdefault(key(r), []).append(r)
    for k in (keys or sorted(groups)):
        g = groups.get(k, [])
        if not g:
            continue
        w = [r["widening"] for r in g]
        out.append(f"| {k} | {len(g)} | {pct(sum(r['flagged'] for r in g), len(g))} | "
                   f"{pct(sum(r['covered'] for r in g), len(g))} | "
                   f"{pct(sum(r['within3'] for r in g), len(g))} | "
                   f"{sum(not r['flagged'] and not r['within3'] for r in g)} | "
                   f"{f(med(w), '.3f')} / {f(quantile(w, 0.9), '.3f')} / "
                   f"{f(max([x for x in w if x is not None], default=None), '.2f')} | "
                   f"{sum((x or 0) > 1.05 for x in w)} | {counts(r['chosen'] for r in g)} | "
                   f"{f(med(r['cpu_s'] for r in g), '.2f')} |")
    return out + [""]


def band(v, edges, unit="", spec="g"):
    for lo, hi in zip(edges[:-1], edges[1:]):
        if lo <= v < hi:
            return f"{format(lo, spec)}-{format(hi, spec)}{unit}"
    return f">= {format(edges[-1], spec)}{unit}"


def clean_tables(rows):
    out = ["## CLEAN (well-specified Coulomb)", ""]
    n = len(rows)
    n_unf = sum(not r["flagged"] for r in rows)
    out.append(f"false-flag rate {pct(sum(r['flagged'] for r in rows), n)}; coverage of ci95 "
               f"{pct(sum(r['covered'] for r in rows), n)}; within 3 SE "
               f"{pct(sum(r['within3'] for r in rows), n)}; confidently wrong (unflagged, > 3 SE) "
               f"{sum(not r['flagged'] and not r['within3'] for r in rows)}; coverage among "
               f"unflagged {pct(sum(r['covered'] for r in rows if not r['flagged']), n_unf)}")
    out.append(f"which test flagged: {tests_count(rows)}")
    wide = [r for r in rows if (r["widening"] or 0) > 2.0 and not r["flagged"]]
    said = [r for r in wide if "other models fit about as well" in (r.get("answer") or "")]
    out.append(f"widened more than 2x without a flag: {len(wide)}, of which the answer line "
               f"states the models' widening: {len(said)}, covered {sum(r['covered'] for r in wide)}")
    out.append(f"interval tags: {counts(r['interval'] or '-' for r in rows)}")
    w = [r["widening"] for r in rows]
    out.append("widening total / sqrt(noise^2 + rig^2): " + ", ".join(
        f"p{int(q * 100)} {f(quantile(w, q), '.3f')}" for q in (0.1, 0.5, 0.9, 0.99))
        + f", max {f(max([x for x in w if x is not None], default=None), '.2f')}; flagged "
          f"median {f(med(r['widening'] for r in rows if r['flagged']), '.3f')}, unflagged "
          f"median {f(med(r['widening'] for r in rows if not r['flagged']), '.3f')}")
    out.append("")
    out += coverage_table("CLEAN all", lambda r: "all", rows)
    out += coverage_table("CLEAN per pendulum", lambda r: r["pendulum"], rows)
    out += coverage_table("CLEAN per frame rate", lambda r: f"{r['fps']:>4} fps", rows)
    out += coverage_table("CLEAN per noise (mm)",
                          lambda r: band(r["noise_m"] * 1e3, [0.05, 0.1, 0.2, 0.35, 0.5], " mm"),
                          rows)
    out += coverage_table("CLEAN per mass ratio m1/m2",
                          lambda r: band(r["mass_ratio"], [0.3, 0.6, 1.2, 2.0, 3.01]), rows)
    fl = [r for r in rows if r["flagged"]]
    if fl:
        out.append("flagged CLEAN fits:")
        for r in fl:
            out.append(f"  {r['id']} ({r['pendulum']}, r {r['mass_ratio']:.2f}, {r['fps']} fps, "
                       f"{r['noise_m'] * 1e3:.2f} mm): tests {r['tests']}; mu {f(r['mu'], '.5f')}"
                       f" truth {r['truth_mu']:.3f}, z {f(zof(r), '+.1f')}, widening "
                       f"{f(r['widening'], '.2f')}, nuisances [{r['nuisances']}]"
                       + (f", error {r['error'][:100]}" if r["error"] else ""))
    cw = [r for r in rows if not r["flagged"] and not r["within3"]]
    if cw:
        out.append("confidently wrong CLEAN fits:")
        for r in cw:
            out.append(f"  {r['id']} ({r['pendulum']}, r {r['mass_ratio']:.2f}, {r['fps']} fps,"
                       f" {r['noise_m'] * 1e3:.2f} mm): mu {f(r['mu'], '.5f')} se "
                       f"{f(r['se'], '.1e')} truth {r['truth_mu']:.3f} (z {f(zof(r), '+.1f')}),"
                       f" law {r['chosen']}, nuisances [{r['nuisances']}]")
    return out + [""]


def zof(r):
    if r["mu"] is None or not r["se"]:
        return None
    return (r["mu"] - r["truth_mu"]) / r["se"]


def time_tables(rows):
    out = ["## TIME (timestamps)", "",
           "| mode | n | flagged | covered (95 %) | within 3 SE | confidently wrong | tests | "
           "nuisances chosen | median |z| | median widening |",
           "|---|---|---|---|---|---|---|---|---|---|"]
    for mode in sorted({r["time_mode"] for r in rows}):
        g = [r for r in rows if r["time_mode"] == mode]
        nu = []
        for r in g:
            nu += [x for x in (r["nuisances"] or "").split(",") if x] or ["none"]
        out.append(f"| {mode} | {len(g)} | {sum(r['flagged'] for r in g)} | "
                   f"{sum(r['covered'] for r in g)} | {sum(r['within3'] for r in g)} | "
                   f"{sum(not r['flagged'] and not r['within3'] for r in g)} | "
                   f"{tests_count(g)} | {counts(nu)} | "
                   f"{f(med(abs(zof(r)) if zof(r) is not None else None for r in g), '.2f')} | "
                   f"{f(med(r['widening'] for r in g), '.3f')} |")
    return out + [""]


def report(rows, head):
    out = [head, ""]
    for s, fn in (("laws", laws_tables), ("clean", clean_tables), ("time", time_tables)):
        g = [r for r in rows if r["set"] == s]
        if g:
            out += fn(g)
    out.append("## CPU")
    out.append("median CPU s per fit: " + ", ".join(
        f"{s} {f(med(r['cpu_s'] for r in rows if r['set'] == s), '.2f')}"
        for s in ("laws", "clean", "time") if any(r["set"] == s for r in rows))
        + f", all {f(med(r['cpu_s'] for r in rows), '.2f')} (n {len(rows)}; errors "
          f"{sum(bool(r['error']) for r in rows)}, retried "
          f"{sum(bool(r['retried']) for r in rows)})")
    return out


# --------------------------------------------------------------------------------------------
# TSV
# --------------------------------------------------------------------------------------------
COLS = ["id", "set", "group", "law", "params", "rig", "seed", "pendulum", "fps", "noise_m",
        "mass_ratio", "time_mode", "onsets", "truth_mu", "truth_mu_s", "chosen", "chosen_tool",
        "right_law", "tie_stated", "tie_delta_bic", "tie_source", "z_mu_k", "z_mu_s",
        "z_split", "z_exponent", "z_v_s", "params_ok", "flagged", "tie",
        "confident_wrong", "covered", "within3", "mu", "se", "lo", "hi", "se_noise", "se_rig",
        "se_model", "se_total", "widening", "interval", "tests", "nuisances", "limited",
        "failed", "error", "rc", "cpu_s", "wall_s", "retried"]
BOOLS = {"right_law", "tie_stated", "params_ok", "flagged", "tie", "confident_wrong", "covered",
         "within3",
         "retried"}
INTS = {"seed", "fps", "onsets", "rc"}


def write_tsv(path, rows):
    with open(path, "w", newline="\n") as fh:
        fh.write("\t".join(COLS) + "\n")
        for r in rows:
            fh.write("\t".join("" if r.get(c) is None else
                               str(r[c]).replace("\t", " ").replace("\n", " ") for c in COLS)
                     + "\n")


def read_tsv(path):
    with open(path) as fh:
        lines = fh.read().splitlines()
    head = lines[0].split("\t")
    rows = []
    for ln in lines[1:]:
        r = dict(zip(head, ln.split("\t")))
        for k, v in list(r.items()):
            if k in BOOLS:
                r[k] = v == "True"
            elif k in INTS:
                r[k] = int(v) if v else None
            elif k in ("id", "set", "group", "law", "params", "rig", "pendulum", "time_mode",
                       "chosen", "chosen_tool", "tie_source", "interval", "tests",
                       "nuisances", "limited", "failed", "error"):
                pass
            else:
                r[k] = float(v) if v else None
        rows.append(r)
    return rows


# --------------------------------------------------------------------------------------------
# Main
# --------------------------------------------------------------------------------------------
def wait_for(path, limit=1200.0):
    t0 = time.monotonic()
    while not os.access(path, os.X_OK):
        if time.monotonic() - t0 > limit:
            return False
        time.sleep(10)
    return True


def snapshot(appell):
    d = tempfile.mkdtemp(prefix="judgement-appell-")
    dst = os.path.join(d, "appell")
    for _ in range(3):
        wait_for(appell)
        try:
            shutil.copy2(appell, dst)
            break
        except OSError:
            time.sleep(10)
    h = hashlib.sha256(open(dst, "rb").read()).hexdigest()[:16]
    return dst, h


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--appell", default="/work/iter/release/appell")
    ap.add_argument("--manifest", default="/tmp/judgement/manifest.json")
    ap.add_argument("--only", action="append", choices=["laws", "clean", "time"])
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--timeout", type=float, default=120.0)
    ap.add_argument("--extra", default="", help="extra arguments for `appell fit` (one string)")
    ap.add_argument("--tsv", help="write one row per fit here")
    ap.add_argument("--no-snapshot", action="store_true",
                    help="run the binary in place (default: a private copy made at the start)")
    ap.add_argument("--from-tsv", help="tabulate the rows of an earlier --tsv")
    args = ap.parse_args(argv)
    if args.from_tsv:
        rows = read_tsv(args.from_tsv)
        if args.only:
            rows = [r for r in rows if r["set"] in args.only]
        print("\n".join(report(rows, f"rows: {args.from_tsv}")))
        return 0
    base = os.path.dirname(os.path.abspath(args.manifest))
    with open(args.manifest) as fh:
        cases = json.load(fh)["cases"]
    if args.only:
        cases = [c for c in cases if c["set"] in args.only]
    if not cases:
        raise SystemExit("no cases selected")
    appell = os.path.abspath(args.appell)
    if not wait_for(appell):
        raise SystemExit(f"{appell} did not appear")
    mtime = time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(os.path.getmtime(appell)))
    if args.no_snapshot:
        binary, digest = appell, "in place"
    else:
        binary, digest = snapshot(appell)
    try:
        version = subprocess.run([binary, "--version"], capture_output=True, text=True,
                                 timeout=30).stdout.strip()
    except (OSError, subprocess.SubprocessError) as e:
        version = f"? ({e})"
    extra = shlex.split(args.extra)
    rows = [None] * len(cases)
    done = [0]
    lock = threading.Lock()
    t_start = time.monotonic()

    def work(k):
        c = cases[k]
        rec, rig = os.path.join(base, c["recording"]), os.path.join(base, c["rig_file"])
        res = run_one(binary, rec, rig, args.timeout, extra)
        retried = False
        if res["error"] and res["json"] is None and not res["error"].startswith("timeout"):
            wait_for(binary)
            time.sleep(2)
            res = run_one(binary, rec, rig, args.timeout, extra)
            retried = True
        res["retried"] = retried
        r = judge(c, res)
        r["params"] = c.get("params", "")
        rows[k] = r
        with lock:
            done[0] += 1
            print(f"[{done[0]}/{len(cases)} {time.monotonic() - t_start:.0f}s] {c['id']}: "
                  f"{r['chosen']} mu {f(r['mu'], '.5f')} se {f(r['se'], '.1e')} truth "
                  f"{c['truth_mu']:.4f} flag {int(r['flagged'])} cw {int(r['confident_wrong'])}"
                  f" cpu {r['cpu_s']:.2f}s" + (f" ERROR {r['error'][:120]}" if r["error"] else ""),
                  file=sys.stderr, flush=True)

    with cf.ThreadPoolExecutor(max_workers=args.jobs) as ex:
        list(ex.map(work, range(len(cases))))
    wall = time.monotonic() - t_start
    if args.tsv:
        write_tsv(args.tsv, rows)
    head = (f"appell: {appell} ({version}, mtime {mtime}, sha256 {digest}; run from "
            f"{'in place' if args.no_snapshot else 'a copy'})  manifest: {args.manifest}  "
            f"fits: {len(rows)}  jobs {args.jobs}  timeout {args.timeout:g} s  wall {wall:.0f} s"
            + (f"  extra: {args.extra}" if args.extra else ""))
    print("\n".join(report(rows, head)))
    if not args.no_snapshot:
        shutil.rmtree(os.path.dirname(binary), ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
