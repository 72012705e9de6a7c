#!/usr/bin/env python3
"""Run `appell fit` on the mis-specified recordings of scripts/generators/misspec_generator.py and tabulate.

For each `<effect>_<rig>[_s<seed>].csv` in --dir, runs
    APPELL fit FILE --rig <rig>_measured.toml --json
(the rig file from --rigs, default the recordings' directory) with a timeout, measures the
child's CPU time (resource.getrusage(RUSAGE_CHILDREN) before and after), and compares mu_kinetic
with misspec_truth.json. Per effect x rig and per effect:
  n, covered (truth inside the 95 % interval), within 3 SE, flagged (limited_by_model set, the
  fit reported `failed`, or the run errored / timed out / printed no JSON), confident-wrong
  (not within 3 SE and not flagged), median 95 % half-width, median and max CPU s.
friction_ramp has no true mu: its slid-mean (integral mu(x)|x'| / integral |x'|) is used as the
truth for the coverage columns for information only, and its rows count as "truth undefined"
(never as confident-wrong).

Standard library only. Usage:
    python3 scripts/sweeps/misspec_sweep.py --appell /tmp/appell-base --dir /tmp/misspec --tsv rows.tsv
"""

import argparse
import json
import os
import re
import resource
import statistics
import subprocess
import sys
import time

NAME = re.compile(r"^(?P<effect>.+)_(?P<rig>light|paper|heavy)(?:_s(?P<seed>\d+))?\.csv$")


def child_cpu():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def run_one(appell, csv, rig_toml, timeout, extra):
    cmd = [appell, "fit", csv, "--rig", rig_toml, "--json"] + extra
    c0, w0 = child_cpu(), time.monotonic()
    row = dict(error="", json=None)
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
        row["rc"] = p.returncode
        if p.returncode != 0:
            row["error"] = f"exit {p.returncode}: " + (p.stderr.strip().splitlines() or [""])[-1][:200]
        try:
            row["json"] = json.loads(p.stdout)
        except json.JSONDecodeError as e:
            if not row["error"]:
                row["error"] = f"no JSON: {e}"
    except subprocess.TimeoutExpired:
        row["rc"] = None
        row["error"] = f"timeout after {timeout} s"
    except OSError as e:
        row["rc"] = None
        row["error"] = f"cannot run: {e}"
    # A killed child is reaped by subprocess.run, so its CPU is counted too.
    row["cpu_s"] = child_cpu() - c0
    row["wall_s"] = time.monotonic() - w0
    return row


def truth_for(truth, effect, rig):
    ent = truth["effects"][effect][rig]
    if ent.get("mu_defined", True):
        return ent["mu_kinetic"], True
    return ent["mu_slid_mean"], False


def analyse(row, mu_true, defined):
    j = row["json"]
    out = dict(mu=None, se=None, lo=None, hi=None, halfwidth=None, limited="", failed="",
               nuisances="", warnings="", interval="", identifiable="")
    if j is not None:
        mk = j.get("mu_kinetic") or {}
        out["mu"] = mk.get("value")
        out["se"] = mk.get("stderr")
        ci = mk.get("ci95") or [None, None]
        out["lo"], out["hi"] = ci[0], ci[1]
        out["interval"] = mk.get("interval") or ""
        if out["lo"] is not None and out["hi"] is not None:
            out["halfwidth"] = 0.5 * (out["hi"] - out["lo"])
        out["limited"] = j.get("limited_by_model") or ""
        out["failed"] = j.get("failed") or ""
        out["nuisances"] = ",".join(j.get("nuisances") or [])
        out["warnings"] = " | ".join(j.get("warnings") or [])
        out["identifiable"] = j.get("identifiable")
    flagged = bool(row["error"] or out["limited"] or out["failed"] or out["mu"] is None)
    covered = within3 = False
    if out["mu"] is not None and out["lo"] is not None:
        covered = out["lo"] <= mu_true <= out["hi"]
    if out["mu"] is not None and out["se"] is not None:
        within3 = abs(out["mu"] - mu_true) <= 3.0 * out["se"]
    out.update(flagged=flagged, covered=covered, within3=within3, truth=mu_true,
               truth_defined=defined,
               confident_wrong=defined and not within3 and not flagged)
    return out


def fmt(v, spec):
    return "" if v is None else format(v, spec)


def summarise(rows):
    n = len(rows)
    defined = [r for r in rows if r["truth_defined"]]
    hw = [r["halfwidth"] for r in rows if r["halfwidth"] is not None]
    cpu = [r["cpu_s"] for r in rows]
    return dict(n=n, covered=sum(r["covered"] for r in rows),
                within3=sum(r["within3"] for r in rows),
                flagged=sum(r["flagged"] for r in rows),
                cw=sum(r["confident_wrong"] for r in defined),
                undefined=n - len(defined),
                errors=sum(bool(r["error"]) for r in rows),
                hw=statistics.median(hw) if hw else None,
                cpu_med=statistics.median(cpu) if cpu else None,
                cpu_max=max(cpu) if cpu else None)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--appell", required=True, help="path of the appell binary")
    ap.add_argument("--dir", required=True, help="directory of <effect>_<rig>[_s<seed>].csv")
    ap.add_argument("--rigs", help="directory of <rig>_measured.toml (default: --dir)")
    ap.add_argument("--truth", help="misspec_truth.json (default: in --dir)")
    ap.add_argument("--tsv", help="write the per-file rows here")
    ap.add_argument("--timeout", type=float, default=60.0)
    ap.add_argument("--effects", default="all", help="all or a comma list")
    ap.add_argument("--extra", default="", help="extra arguments for `appell fit` (one string)")
    args = ap.parse_args(argv)

    rigs_dir = args.rigs or args.dir
    with open(args.truth or os.path.join(args.dir, "misspec_truth.json")) as fh:
        truth = json.load(fh)
    files = []
    for fn in sorted(os.listdir(args.dir)):
        m = NAME.match(fn)
        if not m:
            continue
        if args.effects != "all" and m["effect"] not in args.effects.split(","):
            continue
        files.append((m["effect"], m["rig"], int(m["seed"]) if m["seed"] else None, fn))
    if not files:
        raise SystemExit(f"no recordings in {args.dir}")

    rows = []
    for k, (effect, rig, seed, fn) in enumerate(files):
        path = os.path.join(args.dir, fn)
        toml = os.path.join(rigs_dir, f"{rig}_measured.toml")
        res = run_one(args.appell, path, toml, args.timeout, args.extra.split())
        if effect not in truth["effects"] or rig not in truth["effects"][effect]:
            res["error"] = (res["error"] + "; " if res["error"] else "") + "no truth"
            mu_true, defined = float("nan"), False
        else:
            mu_true, defined = truth_for(truth, effect, rig)
        a = analyse(res, mu_true, defined)
        a.update(file=fn, effect=effect, rig=rig, seed=seed, error=res["error"],
                 cpu_s=res["cpu_s"], wall_s=res["wall_s"])
        rows.append(a)
        print(f"[{k + 1}/{len(files)}] {fn}: mu {fmt(a['mu'], '.5f')} se {fmt(a['se'], '.2e')}"
              f" truth {mu_true:.5f} cov {int(a['covered'])} 3se {int(a['within3'])} "
              f"flag {int(a['flagged'])} cpu {a['cpu_s']:.2f}s"
              + (f" ERROR {a['error']}" if a["error"] else ""), file=sys.stderr)

    cols = ["file", "effect", "rig", "seed", "truth", "truth_defined", "mu", "se", "lo", "hi",
            "halfwidth", "interval", "covered", "within3", "flagged", "confident_wrong",
            "limited", "failed", "identifiable", "nuisances", "warnings", "error", "cpu_s",
            "wall_s"]
    if args.tsv:
        with open(args.tsv, "w") as fh:
            fh.write("\t".join(cols) + "\n")
            for r in rows:
                fh.write("\t".join("" if r[c] is None else
                                   str(r[c]).replace("\t", " ").replace("\n", " ")
                                   for c in cols) + "\n")

    order = []
    for r in rows:
        if r["effect"] not in order:
            order.append(r["effect"])
    print("| effect | rig | n | covered | within 3 SE | flagged | confident-wrong | "
          "truth undefined | errors | median 95% half-width | median CPU s | max CPU s |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")

    def line(eff, rig, s):
        print(f"| {eff} | {rig} | {s['n']} | {s['covered']} | {s['within3']} | {s['flagged']} | "
              f"{s['cw']} | {s['undefined']} | {s['errors']} | {fmt(s['hw'], '.2e')} | "
              f"{fmt(s['cpu_med'], '.2f')} | {fmt(s['cpu_max'], '.2f')} |")

    for eff in order:
        sub = [r for r in rows if r["effect"] == eff]
        for rig in ("light", "paper", "heavy"):
            rr = [r for r in sub if r["rig"] == rig]
            if rr:
                line(eff, rig, summarise(rr))
        line(f"**{eff}**", "all", summarise(sub))
    line("**all**", "all", summarise(rows))

    cw = [r for r in rows if r["confident_wrong"]]
    print(f"\nconfident-wrong: {len(cw)}")
    for r in cw:
        print(f"  {r['file']}: mu {r['mu']:.5f} se {r['se']:.2e} truth {r['truth']:.5f} "
              f"({(r['mu'] - r['truth']) / r['se']:+.1f} SE) nuisances [{r['nuisances']}]")
    return 0


if __name__ == "__main__":
    sys.exit(main())
