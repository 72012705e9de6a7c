#!/usr/bin/env python3
"""Run `appell fit` on the recordings of scripts/generators/friction_law_generator.py and tabulate the
friction law each fit chose against the law that made the recording (issue 36).

For every single-release case of --manifest (default /tmp/friction/manifest.json, laws
coulomb, direction, load, tilt on the light, equal and heavy rigs, seeds 1-5) runs
    APPELL fit REC --rig RIG --json
and reads the chosen nuisances (`nuisances`), the flag (`limited_by_model`, `failed`,
`implausible`) and the estimates of mu_kinetic, mu_kinetic_split, load_exponent and
rail_tilt. A fit is **right** when the law it chose is the recording's (coulomb: no direction,
load or tilt; tilt: rail_tilt) and every parameter of that law is within 3 standard errors of
the truth (mu_kinetic is the mean of both directions, or the coefficient at the static load
under the load law). **Confidently wrong**: a parameter it reports more than 3 standard errors
off, or another law, without a flag. Flagged fits are counted apart.

With --campaign it also fits each seed's heavy-rig campaign jointly (`--joint`, the four
releases std, mirror, wide, wide_mirror) for the direction and the tilt rail, and reports the
law chosen and the parameters. Standard library only; imports run_one from
scripts/sweeps/measured_rig_sweep.py. Usage:
    python3 scripts/sweeps/friction_law_sweep.py --appell target/release/appell [--campaign]
"""

import argparse
import concurrent.futures as cf
import json
import os
import shutil
import statistics
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from measured_rig_sweep import run_one  # noqa: E402

LAWS = {"direction": "direction", "load": "load", "rail_tilt": "tilt", "stribeck": "stribeck"}


def chosen_law(js):
    ns = js.get("nuisances") or []
    laws = [LAWS[n] for n in ns if n in LAWS]
    return "+".join(laws) if laws else "coulomb"


def flagged(js):
    return bool(js.get("limited_by_model") or js.get("failed") or js.get("implausible"))


def checks(js, truth, law):
    """(name, z) of each parameter of the chosen law against the truth."""
    P = js.get("parameters", {})
    out = []

    def z(name, true):
        e = P.get(name)
        if e and e.get("stderr", 0) > 0:
            out.append((name, (e["value"] - true) / e["stderr"]))
    mu_true = truth["mu_at_static_load"] if "load" in law else truth["mu_kinetic"]
    z("mu_kinetic", mu_true)
    if "direction" in law:
        z("mu_kinetic_split", truth["split"])
    if "load" in law:
        z("load_exponent", truth["load_exponent"])
    if "tilt" in law:
        z("rail_tilt", truth["rail_tilt_rad"])
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--appell", default="target/release/appell")
    ap.add_argument("--manifest", default="/tmp/friction/manifest.json")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--timeout", type=float, default=120)
    ap.add_argument("--campaign", action="store_true")
    ap.add_argument("--tsv", default=None)
    ap.add_argument("--joint-extra", default="", help="more flags for the joint fits")
    ap.add_argument("--skip-singles", action="store_true")
    a = ap.parse_args()
    m = json.load(open(a.manifest))
    base = os.path.dirname(os.path.abspath(a.manifest))
    cases = [c for c in m["cases"] if c["group"] == "law" and not a.skip_singles]

    def fit(c):
        row = run_one(a.appell, os.path.join(base, c["recording"]),
                      os.path.join(base, c["rig_file"]), a.timeout, [])
        return c, row
    rows = []
    with cf.ThreadPoolExecutor(a.jobs) as ex:
        for c, row in ex.map(fit, cases):
            js = row.get("json")
            if not js:
                rows.append((c, "error", True, [], row.get("cpu_s", 0), row.get("error", "")))
                continue
            law = chosen_law(js)
            rows.append((c, law, flagged(js), checks(js, c["truth"], law), row.get("cpu_s", 0),
                         js.get("answer", "")[:120]))
    groups = {}
    lines = []
    for c, law, fl, zs, cpu, answer in rows:
        right_law = law == c["law"]
        within = all(abs(z) < 3 for _, z in zs) and law != "error"
        wrong = (not fl) and (not right_law or not within)
        g = groups.setdefault((c["law"], c["rig"]), dict(n=0, right=0, flagged=0, wrong=0,
                                                          laws={}, cpu=[]))
        g["n"] += 1
        g["right"] += right_law and within
        g["flagged"] += fl
        g["wrong"] += wrong
        g["laws"][law] = g["laws"].get(law, 0) + 1
        g["cpu"].append(cpu)
        zt = " ".join(f"{n}={z:+.2f}" for n, z in zs)
        lines.append(f"{c['id']}\t{law}\t{'flagged' if fl else ''}\t{'WRONG' if wrong else ''}\t{zt}\t{cpu:.2f}\t{answer}")
    print("law\trig\tn\tright\tflagged\tconfidently_wrong\tlaws_chosen\tmedian_cpu_s")
    tot = dict(n=0, right=0, flagged=0, wrong=0)
    for (law, rig), g in sorted(groups.items()):
        print(f"{law}\t{rig}\t{g['n']}\t{g['right']}\t{g['flagged']}\t{g['wrong']}\t{g['laws']}\t{statistics.median(g['cpu']):.2f}")
        for k in tot:
            tot[k] += g[k]
    print(f"all\t\t{tot['n']}\t{tot['right']}\t{tot['flagged']}\t{tot['wrong']}")
    if a.tsv:
        with open(a.tsv, "w") as f:
            f.write("\n".join(lines) + "\n")
    if a.campaign:
        campaign(a, m, base)


def campaign(a, m, base):
    print("\ncampaign (heavy rig, joint fit of std, mirror, wide, wide_mirror)")
    seeds = sorted({c["seed"] for c in m["cases"] if c["group"] != "law"})
    for law in ("direction", "tilt"):
        for seed in seeds:
            recs = [os.path.join(base, f"campaign_{law}_heavy_{r}_s{seed}.csv")
                    for r in ("std", "mirror", "wide", "wide_mirror")]
            if not all(os.path.exists(r) for r in recs):
                continue
            # A directory of the four releases (copies: the joint fit reads a directory).
            d = os.path.join(base, f"joint_{law}_heavy_s{seed}")
            os.makedirs(d, exist_ok=True)
            for r in recs:
                shutil.copy(r, d)
            row = run_one(a.appell, d, os.path.join(base, "rigs/heavy.toml"),
                          a.timeout * 4, ["--joint"] + a.joint_extra.split())
            js = row.get("json")
            if not js:
                print(f"{law}\ts{seed}\terror {row.get('error', '')[:200]}")
                continue
            print(f"{law}\ts{seed}\t{chosen_law(js)}\t{'flagged' if flagged(js) else ''}\t"
                  f"{js.get('answer', '')[:160]}\t{row.get('cpu_s', 0):.1f} s")


if __name__ == "__main__":
    main()
