#!/usr/bin/env python3
"""`appell plan --after FIT.json` on pairs of a fit and a plan: how often the plan refuses a fit
of its own rig (false alarms) and how often it takes a fit of another rig (misses).

Every shipped recording with a rig file (tests/data/measured, friction, misspec, campaign37 and
data/campaign; the campaigns also fitted jointly) is fitted with its rig file. Each fit is paired
with plans whose [rig] is copied from a rig file (configs/plan_example.toml with its [rig]
replaced; the plan states no deviations):
- matched: the plan's rig is the rig the recording was made with: the fit's own rig file, and for
  tests/data/measured also the true rig when the fit's file is off (rod +2 mm, a mass +-3 %);
- other: a rig whose masses, rod or pendulum differ from the recording's true rig.
Standard library only.

    python3 scripts/sweeps/rig_match_sweep.py --appell target/release/appell
"""
import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
RIG_KEYS = ("slider_mass", "bob_mass", "rod_length", "rod_mass", "bob_radius", "gravity")


def rig_values(toml: Path) -> dict:
    """The [rig] section's plain numbers (the keys a plan's [rig] takes)."""
    out, inside = {}, False
    for line in toml.read_text().splitlines():
        line = line.split("#")[0].strip()
        if line.startswith("["):
            inside = line == "[rig]"
            continue
        m = re.match(r"(\w+)\s*=\s*([-+0-9.eE]+)$", line)
        if inside and m and m.group(1) in RIG_KEYS:
            out[m.group(1)] = float(m.group(2))
    return out


def same_rig(a: dict, b: dict) -> bool:
    return all(abs(a.get(k, 0.0) - b.get(k, 0.0)) <= 1e-12 for k in RIG_KEYS if k != "gravity")


def plan_text(rig: dict) -> str:
    base = (ROOT / "configs/plan_example.toml").read_text()
    head, rest = base.split("[rig]", 1)
    rest = rest[rest.index("[friction]"):]
    lines = "".join(f"{k} = {v!r}\n" for k, v in rig.items())
    return f"{head}[rig]\n{lines}\n{rest}"


def cases():
    """(label, recordings, rig file the fit uses, true rig values, joint)."""
    m = ROOT / "tests/data/measured"
    for rig in ("light", "equal", "heavy"):
        truth = rig_values(m / "rigs" / f"{rig}_true_nosd.toml")
        recs = sorted(m.glob(f"{rig}_s*.csv"))
        for rf in sorted((m / "rigs").glob(f"{rig}_*.toml")):
            for rec in recs[:1]:
                yield (f"measured/{rec.stem}+{rf.stem}", [rec], rf, truth, False)
    f = ROOT / "tests/data/friction"
    for rec in sorted(f.glob("*.csv")):
        rig = rec.stem.split("_")[2 if rec.stem.startswith("campaign") else 1]
        rf = f / "rigs" / f"{rig}.toml"
        yield (f"friction/{rec.stem}", [rec], rf, rig_values(rf), False)
    s = ROOT / "tests/data/misspec"
    for rec in sorted(s.glob("*.csv")):
        rf = s / f"{rec.stem.split('_')[-1]}_measured.toml"
        yield (f"misspec/{rec.stem}", [rec], rf, rig_values(rf), False)
    for d in sorted((ROOT / "tests/data/campaign37").iterdir()) + [ROOT / "data/campaign"]:
        if not d.is_dir():
            continue
        rf = d / ("rig_measured.toml")
        recs = sorted(d.glob("release_*.csv"))
        for rec in recs:
            yield (f"{d.name}/{rec.stem}", [rec], rf, rig_values(rf), False)
        if len(recs) > 1:
            yield (f"{d.name}/joint", [d], rf, rig_values(rf), True)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--appell", default=str(ROOT / "target/release/appell"))
    ap.add_argument("--out", help="write every pair's result as JSON lines here")
    args = ap.parse_args()
    tmp = Path(tempfile.mkdtemp(prefix="rig_match_"))
    all_cases = list(cases())
    rigs = []  # distinct true rigs, for the other-rig pairs
    for c in all_cases:
        if not any(same_rig(c[3], r) for r in rigs):
            rigs.append(c[3])
    counts = {"matched": [0, 0, 0], "other": [0, 0, 0]}  # pairs, refused, failed otherwise
    lines = []
    for k, (label, recs, rf, truth, joint) in enumerate(all_cases):
        fit = tmp / f"fit_{k}.json"
        cmd = [args.appell, "fit", *map(str, recs), "--rig", str(rf), "--json"]
        if joint:
            cmd.insert(3, "--joint")
        r = subprocess.run(cmd, capture_output=True, text=True)
        if r.returncode != 0 or not r.stdout.strip():
            print(f"{label}: fit failed ({r.returncode}): {r.stderr.strip()[:200]}", file=sys.stderr)
            continue
        fit.write_text(r.stdout)
        plans = [("matched", "own rig file", rig_values(rf))]
        if not same_rig(rig_values(rf), truth):
            plans.append(("matched", "true rig", truth))
        plans += [("other", "other rig", o) for o in rigs if not same_rig(o, truth)]
        for kind, what, rig in plans:
            p = tmp / f"plan_{k}.toml"
            p.write_text(plan_text(rig))
            r = subprocess.run([args.appell, "plan", str(p), "--after", str(fit)],
                               capture_output=True, text=True)
            refused = r.returncode == 2 and "another rig" in r.stderr
            failed = r.returncode != 0 and not refused
            counts[kind][0] += 1
            counts[kind][1] += refused
            counts[kind][2] += failed
            row = {"case": label, "pair": kind, "plan": what, "plan_rig": rig,
                   "exit": r.returncode, "refused": refused}
            if failed or (kind == "matched" and refused) or (kind == "other" and not refused):
                row["stderr"] = r.stderr.strip()[:600]
                print(json.dumps(row), file=sys.stderr)
            lines.append(row)
    for kind, (n, refused, failed) in counts.items():
        print(f"{kind}: {n} pairs, refused {refused}, other failures {failed}")
    if args.out:
        Path(args.out).write_text("".join(json.dumps(l) + "\n" for l in lines))


if __name__ == "__main__":
    main()
