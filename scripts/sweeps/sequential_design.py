#!/usr/bin/env python3
"""Sequential design, measured: does the release `appell plan --after` proposes shrink mu's
interval more than repeating the better of the releases already made?

For each seed (outside CI; Python 3 with numpy and scipy for the generator):
  1. two releases of the tilted rigid paper rig (scripts/generators/campaign_generator.py --seed S
     --releases 2: mu 0.25, tilt 0.5 deg, drawn releases pushed either way);
  2. `appell fit DIR --joint --json` of the two -> FIT.json;
  3. `appell plan configs/plan_campaign.toml --after FIT.json --json`: the top proposal;
  4. the proposal recorded by the generator (`--release`, new noise), and the better of the
     first two (smaller own standard error of mu in the joint fit) recorded again with new
     noise (the same release, repeated);
  5. the joint fit of {1, 2, proposal} and of {1, 2, repeat}: mu's 95 % half-width of each.
Prints a TSV row per seed and the median ratio half-width(proposal) / half-width(repeat)
(below 1: the proposal shrinks the interval more), and whether each interval covers 0.25.

    /tmp/venv-rigid/bin/python scripts/sweeps/sequential_design.py --appell target/release/appell \
        --seeds 1..10 --work /tmp/seq --tsv /tmp/seq.tsv
"""
import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
# This script is in scripts/sweeps/, the generator it runs in scripts/generators/.
ROOT = os.path.dirname(os.path.dirname(HERE))
GEN = os.path.join(ROOT, "scripts", "generators", "campaign_generator.py")
PLAN = os.path.join(ROOT, "configs", "plan_campaign.toml")


def run(cmd):
    out = subprocess.run(cmd, capture_output=True, text=True)
    if out.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)}: exit {out.returncode}: {out.stderr.strip()}")
    return out.stdout


def generate(out, seed, releases=None, count=None, name="release"):
    cmd = [sys.executable, GEN, "--out", out, "--seed", str(seed)]
    if releases:
        for r in releases:
            cmd.append("--release=" + ",".join(f"{v:.6f}" for v in r))
        cmd += ["--name", name]
    else:
        cmd += ["--releases", str(count)]
    run(cmd)


def joint(appell, files, rig):
    cmd = [appell, "fit", "--joint", "--json", "--rig", rig]
    for f in files:
        cmd += ["--release", f]
    return json.loads(run(cmd))


def half_width(j):
    lo, hi = j["mu_kinetic"]["ci95"]
    return 0.5 * (hi - lo), lo <= 0.25 <= hi


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--appell", required=True)
    ap.add_argument("--seeds", default="1..10")
    ap.add_argument("--work", default="/tmp/seq")
    ap.add_argument("--tsv", default=None)
    a = ap.parse_args(argv)
    lo, hi = (int(x) for x in a.seeds.split(".."))
    rows = []
    header = "seed\thw_two\thw_proposal\thw_repeat\tratio\tpredicted_shrink\tproposal\trepeated\tcovers_two\tcovers_proposal\tcovers_repeat"
    print(header)
    for seed in range(lo, hi + 1):
        d = os.path.join(a.work, f"s{seed:02d}")
        shutil.rmtree(d, ignore_errors=True)
        two = os.path.join(d, "two")
        generate(two, seed, count=2)
        rig = os.path.join(two, "rig_measured.toml")
        firsts = [os.path.join(two, f"release_0{i}.csv") for i in (1, 2)]
        j2 = joint(a.appell, firsts, rig)
        fit_json = os.path.join(d, "two.json")
        with open(fit_json, "w") as f:
            json.dump(j2, f)
        plan = json.loads(run([a.appell, "plan", PLAN, "--after", fit_json, "--json"]))
        best = plan["proposals"][0]
        y = best["initial"]
        proposal = (best["theta_deg"], y["theta_dot"], y["x_dot"])
        generate(os.path.join(d, "proposal"), 1000 + seed, releases=[proposal], name="proposal")
        truth = json.load(open(os.path.join(two, "truth.json")))
        own = [r["own_mu"]["stderr"] if r["own_mu"] else float("inf") for r in j2["releases"]]
        k = own.index(min(own))
        r = truth["releases"][k]
        repeat = (r["theta_deg"], r["theta_dot"], r["x_dot"])
        generate(os.path.join(d, "repeat"), 2000 + seed, releases=[repeat], name="repeat")
        jp = joint(a.appell, firsts + [os.path.join(d, "proposal", "proposal_01.csv")], rig)
        jr = joint(a.appell, firsts + [os.path.join(d, "repeat", "repeat_01.csv")], rig)
        (h2, c2), (hp, cp), (hr, cr) = half_width(j2), half_width(jp), half_width(jr)
        row = (
            f"{seed}\t{h2:.3e}\t{hp:.3e}\t{hr:.3e}\t{hp / hr:.3f}\t{best.get('shrinks_mu_stderr_by')}"
            f"\t{proposal[0]:.2f},{proposal[1]:.3f},{proposal[2]:.3f}\t{repeat[0]:.2f},{repeat[1]:.3f},{repeat[2]:.3f}"
            f"\t{c2}\t{cp}\t{cr}"
        )
        print(row, flush=True)
        rows.append((hp / hr, row))
    ratios = [r for r, _ in rows]
    print(f"median ratio {statistics.median(ratios):.3f}; proposal better in {sum(r < 1 for r in ratios)}/{len(ratios)}")
    if a.tsv:
        with open(a.tsv, "w") as f:
            f.write(header + "\n" + "\n".join(r for _, r in rows) + "\n")


if __name__ == "__main__":
    main()
