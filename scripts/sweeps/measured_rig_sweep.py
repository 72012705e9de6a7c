#!/usr/bin/env python3
"""Run `appell fit` on every case of scripts/generators/measured_rig_generator.py's manifest and tabulate.

For each case (recording, rig file, true mu) of --manifest runs
    APPELL fit REC --rig RIG --json [EXTRA...]
with 2 workers (--jobs) and a timeout (120 s), measures each child's CPU time (os.wait4), and
compares mu_kinetic (`value`, `stderr`, `ci95`) with the case's true mu. Per group (rig x error
kind x flavour; effect x rig), per error size (kind x size x flavour, all rigs and seeds) and
overall:
  n, covered (truth inside the 95 % interval), within 3 SE, flagged, confident-wrong (neither
  within 3 SE nor flagged), errors (the run failed, timed out or printed no JSON), median 95 %
  half-width, median CPU s.
Flagged: the JSON's `limited_by_model` is non-empty, `failed` is set, a non-empty `implausible`
list (top level or in mu_kinetic), a warning that mentions "implausib", or the run errored /
timed out / printed no JSON / gave no mu_kinetic value. If mu_kinetic has `parts` (standard
errors {noise, rig, model, total}), their medians are printed per group too.

Standard library only. Usage:
    python3 scripts/sweeps/measured_rig_sweep.py --appell /tmp/appell-baseline \\
        --manifest /tmp/measured/manifest.json --tsv /tmp/measured/baseline.tsv
Options: --quick (the manifest's quick cases: seed 1, every group), --only GROUPS (comma list
of shell patterns on the group, e.g. 'light/rod/*,effect:*'), --extra "ARGS", --jobs 2,
--timeout 120.
"""

import argparse
import concurrent.futures as cf
import fnmatch
import json
import os
import shlex
import statistics
import subprocess
import sys
import tempfile
import threading
import time

PARTS = ("noise", "rig", "model", "total")


def run_one(appell, rec, rig, timeout, extra):
    cmd = [appell, "fit", rec, "--rig", rig, "--json"] + extra
    row = dict(error="", json=None, rc=None, cpu_s=0.0)
    t0 = time.monotonic()
    with tempfile.TemporaryFile() as fo, tempfile.TemporaryFile() as fe:
        try:
            p = subprocess.Popen(cmd, stdout=fo, stderr=fe)
        except OSError as e:
            row["error"] = f"cannot run: {e}"
            row["wall_s"] = time.monotonic() - t0
            return row
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
        p.returncode = os.waitstatus_to_exitcode(status)  # reaped here; Popen must not wait
        row["cpu_s"] = ru.ru_utime + ru.ru_stime
        row["rc"] = p.returncode
        fo.seek(0)
        fe.seek(0)
        out = fo.read().decode("utf-8", "replace")
        err = fe.read().decode("utf-8", "replace")
    if killed:
        row["error"] = f"timeout after {timeout} s"
    elif p.returncode != 0:
        lines = [ln for ln in err.strip().splitlines() if ln.strip()]
        row["error"] = f"exit {p.returncode}: " + " ".join(lines[-3:])[:300]
    if not killed:
        try:
            row["json"] = json.loads(out)
        except json.JSONDecodeError as e:
            if not row["error"]:
                row["error"] = f"no JSON: {e}"
    row["wall_s"] = time.monotonic() - t0
    return row


def analyse(row, mu_true):
    j = row["json"]
    out = dict(mu=None, se=None, lo=None, hi=None, halfwidth=None, limited="", failed="",
               implausible="", warnings="", nuisances="", interval="")
    out.update({f"se_{k}": None for k in PARTS})
    if j is not None:
        mk = j.get("mu_kinetic") or {}
        out["mu"] = mk.get("value")
        out["se"] = mk.get("stderr")
        ci = mk.get("ci95") or [None, None]
        out["lo"], out["hi"] = ci[0], ci[1]
        out["interval"] = mk.get("interval") or ""
        if out["lo"] is not None and out["hi"] is not None:
            out["halfwidth"] = 0.5 * (out["hi"] - out["lo"])
        parts = mk.get("parts") or {}
        if isinstance(parts, dict):
            for k in PARTS:
                v = parts.get(k)
                out[f"se_{k}"] = v if isinstance(v, (int, float)) else None
        lim = j.get("limited_by_model")
        out["limited"] = (json.dumps(lim) if isinstance(lim, (dict, list)) else (lim or ""))
        if lim in ([], {}):
            out["limited"] = ""
        out["failed"] = j.get("failed") or ""
        imp = []
        for src in (j, mk):
            v = src.get("implausible")
            if v:
                imp += v if isinstance(v, list) else [v]
        out["implausible"] = " | ".join(str(v) for v in imp)
        out["warnings"] = " | ".join(str(w) for w in (j.get("warnings") or []))
        out["nuisances"] = ",".join(str(n) for n in (j.get("nuisances") or []))
    flagged = bool(row["error"] or out["limited"] or out["failed"] or out["implausible"]
                   or "implausib" in out["warnings"].lower() or out["mu"] is None)
    covered = within3 = False
    if out["mu"] is not None and out["lo"] is not None and out["hi"] is not None:
        covered = out["lo"] <= mu_true <= out["hi"]
    if out["mu"] is not None and out["se"] is not None:
        within3 = abs(out["mu"] - mu_true) <= 3.0 * out["se"]
    out.update(flagged=flagged, covered=covered, within3=within3,
               confident_wrong=not within3 and not flagged)
    return out


def fmt(v, spec):
    return "" if v is None else format(v, spec)


def med(xs):
    xs = [x for x in xs if x is not None]
    return statistics.median(xs) if xs else None


def summarise(rows):
    return dict(n=len(rows), covered=sum(r["covered"] for r in rows),
                within3=sum(r["within3"] for r in rows),
                flagged=sum(r["flagged"] for r in rows),
                cw=sum(r["confident_wrong"] for r in rows),
                errors=sum(bool(r["error"]) for r in rows),
                hw=med(r["halfwidth"] for r in rows),
                cpu=med(r["cpu_s"] for r in rows),
                parts={k: med(r[f"se_{k}"] for r in rows) for k in PARTS})


def table(title, keyname, groups, show_parts):
    lines = [f"### {title}", "",
             f"| {keyname} | n | covered | within 3 SE | flagged | confident-wrong | errors | "
             "median 95% half-width | median CPU s |"
             + (" median SE noise / rig / model / total |" if show_parts else ""),
             "|---|---|---|---|---|---|---|---|---|" + ("---|" if show_parts else "")]
    for key, rows in groups:
        s = summarise(rows)
        ln = (f"| {key} | {s['n']} | {s['covered']} | {s['within3']} | {s['flagged']} | "
              f"{s['cw']} | {s['errors']} | {fmt(s['hw'], '.2e')} | {fmt(s['cpu'], '.2f')} |")
        if show_parts:
            ln += " " + " / ".join(fmt(s["parts"][k], ".1e") or "-" for k in PARTS) + " |"
        lines.append(ln)
    return lines + [""]


def size_key(c):
    e = c.get("error") or {}
    if c["kind"] == "effect":
        return f"effect {c['flavour']}"
    if c["kind"] == "true":
        return f"true ({c['flavour']})"
    if "delta_mm" in e:
        return f"rod {e['delta_mm']:+g} mm ({c['flavour']})"
    return f"{c['kind']} mass {e['delta_pct']:+g} % ({c['flavour']})"


BOOLS = ("covered", "within3", "flagged", "confident_wrong")
FLOATS = ("truth", "mu", "se", "lo", "hi", "halfwidth", "cpu_s", "wall_s") + tuple(
    f"se_{k}" for k in PARTS)


def read_tsv(path):
    with open(path) as fh:
        lines = fh.read().splitlines()
    head = lines[0].split("\t")
    rows = []
    for ln in lines[1:]:
        r = dict(zip(head, ln.split("\t")))
        for k in BOOLS:
            r[k] = r.get(k) == "True"
        for k in FLOATS:
            r[k] = float(r[k]) if r.get(k) else None
        rows.append(r)
    return rows


def matrix(rows):
    """Confident-wrong / flagged / covered of n, per error size (rows) and rig (columns)."""
    rigs = []
    for r in rows:
        if r["rig"] not in rigs:
            rigs.append(r["rig"])
    cells, sizes = {}, []
    for r in rows:
        if r["size"] not in sizes:
            sizes.append(r["size"])
        c = cells.setdefault((r["size"], r["rig"]), [0, 0, 0, 0])
        c[0] += 1
        c[1] += r["confident_wrong"]
        c[2] += r["flagged"]
        c[3] += r["covered"]
    lines = ["### confident-wrong / flagged / covered of n, per error size and rig", "",
             "| error | " + " | ".join(rigs) + " |", "|---|" + "---|" * len(rigs)]
    for sz in sizes:
        lines.append(f"| {sz} | " + " | ".join(
            (lambda c: f"{c[1]} / {c[2]} / {c[3]} of {c[0]}" if c else "-")(cells.get((sz, rg)))
            for rg in rigs) + " |")
    return lines + [""]


def report(rows, header):
    show_parts = any(r["se_total"] is not None for r in rows)

    def grouped(key, order=None):
        g = {}
        for r in rows:
            g.setdefault(key(r), []).append(r)
        keys = list(g) if order is None else order(g)
        return [(k, g[k]) for k in keys]

    out = [f"{header}  cases: {len(rows)}", ""]
    out += table("per group (rig x error kind x flavour; effect x rig)", "group",
                 grouped(lambda r: r["group"]), show_parts)
    out += table("per error size (all rigs and seeds)", "error",
                 grouped(lambda r: r["size"]), show_parts)
    out += table("per kind x flavour (all rigs, sizes and seeds)", "kind / flavour",
                 grouped(lambda r: f"{r['kind']} / {r['flavour']}"), show_parts)
    out += table("all", "all", [("all", rows)], show_parts)
    out += matrix(rows)
    cw = [r for r in rows if r["confident_wrong"]]
    out.append(f"confident-wrong: {len(cw)}")
    for r in cw:
        out.append(f"  {r['id']}: mu {r['mu']:.5f} se {r['se']:.2e} truth {r['truth']:.5f} "
                   f"({(r['mu'] - r['truth']) / r['se']:+.1f} SE) nuisances [{r['nuisances']}]")
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--appell", help="path of the appell binary")
    ap.add_argument("--manifest", default="/tmp/measured/manifest.json")
    ap.add_argument("--only", default="", help="comma list of group patterns (fnmatch)")
    ap.add_argument("--quick", action="store_true", help="only the manifest's quick cases")
    ap.add_argument("--tsv", help="write the per-case rows here")
    ap.add_argument("--extra", default="", help="extra arguments for `appell fit` (one string)")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--timeout", type=float, default=120.0)
    ap.add_argument("--from-tsv", help="tabulate the rows of an earlier --tsv instead of running")
    args = ap.parse_args(argv)
    if args.from_tsv:
        rows = read_tsv(args.from_tsv)
        print("\n".join(report(rows, f"rows: {args.from_tsv}")))
        return 0

    base = os.path.dirname(os.path.abspath(args.manifest))
    with open(args.manifest) as fh:
        cases = json.load(fh)["cases"]
    if args.quick:
        cases = [c for c in cases if c.get("quick")]
    if args.only:
        pats = [p.strip() for p in args.only.split(",") if p.strip()]
        cases = [c for c in cases if any(fnmatch.fnmatchcase(c["group"], p) for p in pats)]
    if not cases:
        raise SystemExit("no cases selected")
    extra = shlex.split(args.extra)
    if not args.appell:
        raise SystemExit("--appell is required (or --from-tsv)")
    appell = os.path.abspath(args.appell)

    rows = [None] * len(cases)
    done = [0]
    lock = threading.Lock()
    t_start = time.monotonic()

    def work(k):
        c = cases[k]
        res = run_one(appell, os.path.join(base, c["recording"]),
                      os.path.join(base, c["rig_file"]), args.timeout, extra)
        a = analyse(res, c["truth_mu"])
        a.update(id=c["id"], group=c["group"], rig=c["rig"], seed=c["seed"], kind=c["kind"],
                 flavour=c["flavour"], size=size_key(c), truth=c["truth_mu"],
                 error=res["error"], rc=res["rc"], cpu_s=res["cpu_s"], wall_s=res["wall_s"])
        rows[k] = a
        with lock:
            done[0] += 1
            print(f"[{done[0]}/{len(cases)} {time.monotonic() - t_start:.0f}s] {c['id']}: mu "
                  f"{fmt(a['mu'], '.5f')} se {fmt(a['se'], '.1e')} truth {c['truth_mu']:.5f} "
                  f"cov {int(a['covered'])} 3se {int(a['within3'])} flag {int(a['flagged'])} "
                  f"cpu {a['cpu_s']:.2f}s" + (f" ERROR {a['error'][:120]}" if a["error"] else ""),
                  file=sys.stderr, flush=True)

    with cf.ThreadPoolExecutor(max_workers=args.jobs) as ex:
        list(ex.map(work, range(len(cases))))

    cols = (["id", "group", "size", "rig", "seed", "kind", "flavour", "truth", "mu", "se", "lo",
             "hi", "halfwidth", "interval", "covered", "within3", "flagged", "confident_wrong",
             "limited", "failed", "implausible"] + [f"se_{k}" for k in PARTS]
            + ["nuisances", "warnings", "error", "rc", "cpu_s", "wall_s"])
    if args.tsv:
        with open(args.tsv, "w") as fh:
            fh.write("\t".join(cols) + "\n")
            for r in rows:
                fh.write("\t".join("" if r[c] is None else
                                   str(r[c]).replace("\t", " ").replace("\n", " ")
                                   for c in cols) + "\n")

    print("\n".join(report(rows, f"appell: {appell}  manifest: {args.manifest}"
                                  + (f"  extra: {args.extra}" if args.extra else ""))))
    return 0


if __name__ == "__main__":
    sys.exit(main())
