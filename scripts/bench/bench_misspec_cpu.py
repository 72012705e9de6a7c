#!/usr/bin/env python3
"""CPU seconds (user+sys, median of 3, interleaved) of `appell fit --json` on the 21 shipped
misspecified recordings (tests/data/misspec), for one or more binaries, and the median per binary.
python3 scripts/bench/bench_misspec_cpu.py OLD_BINARY NEW_BINARY. Run from the repository root."""
import glob, resource, statistics, subprocess, sys
bins = sys.argv[1:]
files = sorted(glob.glob("tests/data/misspec/*.csv"))
def cpu(b, f, r):
    u0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run([b, "fit", f, "--rig", r, "--json"], capture_output=True)
    u1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (u1.ru_utime + u1.ru_stime) - (u0.ru_utime + u0.ru_stime)
meds = {b: [] for b in bins}
for f in files:
    rig = f"tests/data/misspec/{f.split('_')[-1].replace('.csv','')}_measured.toml"
    res = {b: [] for b in bins}
    for k in range(3):
        for b in bins: res[b].append(cpu(b, f, rig))
    for b in bins: meds[b].append(statistics.median(res[b]))
    print(f.split("/")[-1], *[f"{statistics.median(res[b]):.3f}" for b in bins])
for b in bins:
    print(b, "median over", len(files), "files: %.3f s CPU, max %.3f" % (statistics.median(meds[b]), max(meds[b])))
