#!/usr/bin/env python3
"""Fit every campaign of a campaign_sweep_generator.py suite with `appell fit --joint` and score it.

Purpose
-------
The test bench's second half (issue 37): runs

    APPELL fit CAMPAIGN --joint --rig CAMPAIGN/rig_measured.toml --json

for every campaign of a manifest written by scripts/generators/campaign_sweep_generator.py, measures the
child's CPU time (user + sys, from os.wait4's resource usage of that child alone) and wall time,
and compares the fit with the truth in the manifest: does the headline cover the rail's mu, are
the releases it names (sets aside, or calls disagreeing) exactly the odd one (none in a clean
campaign), and does the result of the releases it keeps cover the rail's mu.

Physics / truth
---------------
The true mu is the campaign's (the clean releases' rail); an odd release has mu off by 6..10 %
(odd_mu) or another rail tilt (odd_tilt) and should be set aside. z = (estimate - true mu) /
stderr, covered = |z| <= 1.96; 'within 3 SE' = |z| <= 3.

JSON read (both schemas)
------------------------
Current binary: `mu_kinetic` (all releases, widened by their spread), `disagreeing` (file
names), `mu_without_disagreeing` ({value, stderr, ci95, interval} or null), `releases` (rows
with name, own_mu, single_mu, z, agrees). Next version: `mu_kinetic` is the result of the
releases kept, `set_aside` lists objects with at least `name`, and `failed` may be a reason
string. Rule: if `set_aside` exists, the named releases come from it and the kept result is
`mu_kinetic`; else the names come from `disagreeing` and the kept result is
`mu_without_disagreeing` when non-null, else `mu_kinetic`. A non-null `failed` string counts the
campaign as 'reported failed', not as a wrong value. Names are compared by file name (the
binary prints the paths it was given).
se_ratio = kept stderr / median over the release rows of single_mu's stderr (how much the
joint fit gains over one release).

Run (outside CI; Python 3, standard library only)
---
    /tmp/venv-gen/bin/python scripts/sweeps/campaign_sweep.py --appell /tmp/appell-3f7fccd \\
        --manifest /tmp/camp37/manifest.json --tsv /tmp/camp37/baseline.tsv
Options: --jobs N (campaigns fitted at once, default 1), --timeout S (per campaign, default
300; the child is killed after it), --only NAME[,NAME], --json-dir DIR (keep every fit's stdout
and stderr there), --extra-arg ARG (repeatable, appended to the fit's command line).

Outputs
-------
--tsv FILE: one row per campaign (columns in COLUMNS). Stdout: the same as a table, then the
summary: clean campaigns within 3 SE and covered (headline; none named); odd campaigns with the
odd release named alone, and their kept results within 3 SE; reported failures, exit codes and
timeouts; median CPU seconds for clean and for odd campaigns.
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor

sys.dont_write_bytecode = True  # leave no __pycache__ in scripts/

COLUMNS = ["name", "kind", "pendulum", "rig", "damping", "tilt_deg", "odd_release",
           "true_mu", "headline_mu", "headline_se", "headline_z", "covered", "within_3se",
           "named", "n_named", "odd_named_alone", "kept_source", "kept_mu", "kept_se",
           "kept_z", "kept_within_3se", "median_single_se", "se_ratio", "nuisances",
           "schema", "reported_failed", "cpu_s", "wall_s", "exit", "failure"]


def run_fit(appell, cdir, rig, timeout, extra, keep_dir, name):
    """Run one fit; returns (stdout text, stderr text, exit code or None, cpu s, wall s,
    failure string or None). CPU time is the child's own (os.wait4)."""
    cmd = [appell, "fit", cdir, "--joint", "--rig", rig, "--json"] + list(extra)
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        t0 = time.monotonic()
        proc = subprocess.Popen(cmd, stdout=out, stderr=err, stdin=subprocess.DEVNULL)
        failure = None
        while True:
            pid, status, ru = os.wait4(proc.pid, os.WNOHANG)
            if pid == proc.pid:
                break
            if time.monotonic() - t0 > timeout:
                proc.kill()
                pid, status, ru = os.wait4(proc.pid, 0)
                failure = f"timeout after {timeout:g} s (killed)"
                break
            time.sleep(0.05)
        wall = time.monotonic() - t0
        code = os.waitstatus_to_exitcode(status)
        proc.returncode = code  # reaped here; keep Popen from waiting again
        cpu = ru.ru_utime + ru.ru_stime
        out.seek(0)
        err.seek(0)
        so = out.read().decode("utf-8", "replace")
        se = err.read().decode("utf-8", "replace")
    if keep_dir:
        with open(os.path.join(keep_dir, f"{name}.json"), "w") as fh:
            fh.write(so)
        with open(os.path.join(keep_dir, f"{name}.stderr"), "w") as fh:
            fh.write(se)
    if failure is None and code != 0:
        last = [ln for ln in se.strip().splitlines() if ln.strip()]
        failure = f"exit {code}" + (f": {last[-1][:200]}" if last else "")
    return so, se, (None if failure and failure.startswith("timeout") else code), cpu, wall, \
        failure


def est(d):
    """(value, stderr) of an estimate object, or (None, None)."""
    if not isinstance(d, dict):
        return None, None
    v, s = d.get("value"), d.get("stderr")
    return (float(v) if v is not None else None), (float(s) if s is not None else None)


def zval(v, s, truth):
    if v is None or s is None or not s > 0:
        return None
    return (v - truth) / s


def score(entry, so, code, cpu, wall, failure):
    truth = entry["mu"]
    odd_file = entry.get("odd_file")
    row = dict(name=entry["name"], kind=entry["kind"], pendulum=entry["pendulum"],
               rig=entry["rig"], damping="yes" if entry["effects"]["pivot_damping"] else "no",
               tilt_deg=entry["tilt_deg"], odd_release=entry.get("odd_release"),
               true_mu=truth, cpu_s=round(cpu, 2), wall_s=round(wall, 2), exit=code,
               failure=failure, reported_failed=False)
    d = None
    if so.strip():
        try:
            d = json.loads(so)
        except json.JSONDecodeError as exc:
            row["failure"] = (failure + "; " if failure else "") + f"JSON: {exc}"
    elif failure is None:
        row["failure"] = "empty stdout"
    if not isinstance(d, dict):
        return row
    rf = d.get("failed")
    if isinstance(rf, str) and rf:
        row["reported_failed"] = True
        row["failure"] = (row["failure"] + "; " if row["failure"] else "") + f"failed: {rf}"
    hv, hs = est(d.get("mu_kinetic"))
    if "set_aside" in d:
        row["schema"] = "set_aside"
        names = [os.path.basename(str(x.get("name") if isinstance(x, dict) else x))
                 for x in (d.get("set_aside") or [])]
        kept, row["kept_source"] = d.get("mu_kinetic"), "mu_kinetic"
    else:
        row["schema"] = "disagreeing"
        names = [os.path.basename(str(x)) for x in (d.get("disagreeing") or [])]
        if d.get("mu_without_disagreeing") is not None:
            kept, row["kept_source"] = d["mu_without_disagreeing"], "mu_without_disagreeing"
        else:
            kept, row["kept_source"] = d.get("mu_kinetic"), "mu_kinetic"
    kv, ks = est(kept)
    row.update(headline_mu=hv, headline_se=hs, headline_z=zval(hv, hs, truth),
               named=",".join(names), n_named=len(names), kept_mu=kv, kept_se=ks,
               kept_z=zval(kv, ks, truth))
    for k in ("headline", "kept"):
        z = row[f"{k}_z"]
        if k == "headline":
            row["covered"] = None if z is None else abs(z) <= 1.96
            row["within_3se"] = None if z is None else abs(z) <= 3.0
        else:
            row["kept_within_3se"] = None if z is None else abs(z) <= 3.0
    row["odd_named_alone"] = (names == [odd_file]) if odd_file else (len(names) == 0)
    singles = [est(r.get("single_mu"))[1] for r in (d.get("releases") or [])
               if isinstance(r, dict)]
    singles = [s for s in singles if s is not None and s > 0]
    if singles:
        row["median_single_se"] = statistics.median(singles)
        if ks:
            row["se_ratio"] = ks / row["median_single_se"]
    nu = d.get("nuisances")
    row["nuisances"] = "+".join(nu) if isinstance(nu, list) and nu else ("none" if
                                                                        nu == [] else None)
    return row


def fmt(v, spec=""):
    if v is None:
        return "-"
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, float) and spec:
        return format(v, spec)
    return str(v)


def tsv_cell(v):
    if v is None:
        return ""
    if isinstance(v, bool):
        return "1" if v else "0"
    if isinstance(v, float):
        return repr(v)
    return str(v).replace("\t", " ").replace("\n", " ")


def print_table(rows):
    hdr = (f"{'campaign':<26s} {'kind':<8s} {'true mu':>7s} {'headline':>9s} {'se':>8s} "
           f"{'z':>8s} {'named':<16s} {'odd?':>4s} {'kept':>9s} {'kept se':>8s} "
           f"{'kept z':>7s} {'se/1':>5s} {'CPU s':>6s} {'wall s':>6s} nuisances / failure")
    print(hdr)
    for r in rows:
        named = (r.get("named") or "").replace("release_", "r").replace(".csv", "")
        odd = ("-" if r.get("odd_named_alone") is None else
               ("yes" if r["odd_named_alone"] else "NO"))
        extra = r.get("nuisances") or ""
        if r.get("failure"):
            extra = (extra + "  " if extra else "") + "FAILURE: " + r["failure"]
        print(f"{r['name']:<26s} {r['kind']:<8s} {r['true_mu']:7.4f} "
              f"{fmt(r.get('headline_mu'), '.5f'):>9s} {fmt(r.get('headline_se'), '.1e'):>8s} "
              f"{fmt(r.get('headline_z'), '+.2f'):>8s} {named or '(none)':<16s} {odd:>4s} "
              f"{fmt(r.get('kept_mu'), '.5f'):>9s} {fmt(r.get('kept_se'), '.1e'):>8s} "
              f"{fmt(r.get('kept_z'), '+.2f'):>7s} {fmt(r.get('se_ratio'), '.2f'):>5s} "
              f"{r['cpu_s']:6.1f} {r['wall_s']:6.1f} {extra}")


def summary(rows):
    def count(sel, key):
        vals = [r.get(key) for r in sel]
        return sum(1 for v in vals if v is True), sum(1 for v in vals if v is not None)

    lines = []
    clean = [r for r in rows if r["kind"] == "clean"]
    odd = [r for r in rows if r["kind"] != "clean"]
    ok_clean = [r for r in clean if not r.get("reported_failed")]
    if clean:
        a, n = count(ok_clean, "within_3se")
        b, _ = count(ok_clean, "covered")
        c, m = count(ok_clean, "odd_named_alone")
        k, kn = count(ok_clean, "kept_within_3se")
        lines.append(f"clean campaigns ({len(clean)}; {len(clean) - len(ok_clean)} reported "
                     f"failed): headline within 3 SE {a}/{n}, covered (|z| <= 1.96) {b}/{n}; "
                     f"no release named {c}/{m}; kept result within 3 SE {k}/{kn}")
    for kind in ("odd_mu", "odd_tilt", None):
        sel = [r for r in odd if kind is None or r["kind"] == kind]
        if not sel:
            continue
        ok = [r for r in sel if not r.get("reported_failed")]
        a, n = count(ok, "odd_named_alone")
        wrong = sum(1 for r in ok if r.get("n_named") and not r.get("odd_named_alone"))
        none = sum(1 for r in ok if r.get("n_named") == 0)
        k, kn = count(ok, "kept_within_3se")
        h, hn = count(ok, "within_3se")
        lines.append(f"{kind or 'all odd'} campaigns ({len(sel)}; {len(sel) - len(ok)} reported "
                     f"failed): odd release named alone {a}/{n} (other or more named {wrong}, "
                     f"none named {none}); kept result within 3 SE {k}/{kn}; headline within "
                     f"3 SE {h}/{hn}")
    fails = [r for r in rows if r.get("failure")]
    lines.append(f"failures: {len(fails)} ("
                 + (", ".join(f"{r['name']}: {r['failure'][:120]}" for r in fails) or "none")
                 + f"); reported failed {sum(1 for r in rows if r.get('reported_failed'))}; "
                 f"non-zero exit {sum(1 for r in rows if r.get('exit') not in (0,))}")
    for lab, sel in (("clean", clean), ("odd", odd)):
        cpus = [r["cpu_s"] for r in sel]
        walls = [r["wall_s"] for r in sel]
        if cpus:
            lines.append(f"median CPU {lab}: {statistics.median(cpus):.1f} s (max "
                         f"{max(cpus):.1f}, total {sum(cpus):.1f}); median wall "
                         f"{statistics.median(walls):.1f} s")
    ratios = [r["se_ratio"] for r in rows if r.get("se_ratio") is not None]
    if ratios:
        lines.append(f"kept stderr / median single-release stderr: median "
                     f"{statistics.median(ratios):.2f} (range {min(ratios):.2f} .. "
                     f"{max(ratios):.2f})")
    return lines


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--appell", required=True)
    ap.add_argument("--manifest", default="/tmp/camp37/manifest.json")
    ap.add_argument("--tsv", required=True)
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--timeout", type=float, default=300.0)
    ap.add_argument("--only", help="comma-separated campaign names")
    ap.add_argument("--json-dir", help="keep every fit's stdout (NAME.json) and stderr here")
    ap.add_argument("--extra-arg", action="append", default=[],
                    help="appended to the fit's command line (repeatable)")
    args = ap.parse_args(argv)
    if args.jobs < 1:
        ap.error("--jobs must be >= 1")
    appell = os.path.abspath(args.appell)
    if not os.access(appell, os.X_OK):
        ap.error(f"{appell} is not executable")
    base = os.path.dirname(os.path.abspath(args.manifest))
    with open(args.manifest) as fh:
        man = json.load(fh)
    camps = man["campaigns"]
    if args.only:
        want = set(args.only.split(","))
        camps = [c for c in camps if c["name"] in want]
        if len(camps) != len(want):
            ap.error(f"unknown campaigns in --only: {sorted(want - {c['name'] for c in camps})}")
    if args.json_dir:
        os.makedirs(args.json_dir, exist_ok=True)

    def one(c):
        cdir = os.path.join(base, c["dir"])
        so, se, code, cpu, wall, failure = run_fit(
            appell, cdir, os.path.join(cdir, "rig_measured.toml"), args.timeout,
            args.extra_arg, args.json_dir, c["name"])
        r = score(c, so, code, cpu, wall, failure)
        print(f"  {c['name']}: exit {code}, CPU {cpu:.1f} s, wall {wall:.1f} s"
              + (f", named {r.get('named') or '(none)'}" if "named" in r else "")
              + (f", FAILURE {r['failure']}" if r.get("failure") else ""), flush=True)
        return r

    print(f"fitting {len(camps)} campaign(s) with {appell} (jobs {args.jobs}, timeout "
          f"{args.timeout:g} s)", flush=True)
    with ThreadPoolExecutor(max_workers=args.jobs) as ex:
        rows = list(ex.map(one, camps))
    with open(args.tsv, "w", newline="\n") as fh:
        fh.write("\t".join(COLUMNS) + "\n")
        for r in rows:
            fh.write("\t".join(tsv_cell(r.get(k)) for k in COLUMNS) + "\n")
    print()
    print_table(rows)
    print()
    for ln in summary(rows):
        print(ln)
    print(f"TSV: {args.tsv}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
