#!/usr/bin/env python3
"""CPU seconds (user+sys, median of 5, interleaved) of `appell fit --json` on seven shipped recordings,
for two binaries: python3 scripts/bench/bench_fit_cpu.py OLD_BINARY NEW_BINARY. Run from the repository root."""
import resource, subprocess, statistics, sys
cases=[("data/example_recording.mcap","configs/rig_example.toml")]
for r in ["light","equal","heavy"]:
    cases.append((f"tests/data/measured/{r}_s1.csv", f"tests/data/measured/rigs/{r}_true_nosd.toml"))
for e in ["four_paper","drag_light","none_heavy"]:
    rig=e.split("_")[1]
    cases.append((f"tests/data/misspec/{e}.csv", f"tests/data/misspec/{rig}_measured.toml"))
def cpu(b,f,r):
    u0=resource.getrusage(resource.RUSAGE_CHILDREN); subprocess.run([b,"fit",f,"--rig",r,"--json"],capture_output=True)
    u1=resource.getrusage(resource.RUSAGE_CHILDREN); return (u1.ru_utime+u1.ru_stime)-(u0.ru_utime+u0.ru_stime)
bins=sys.argv[1:]
print("case", *bins)
tot={b:0 for b in bins}
for f,r in cases:
    res={b:[] for b in bins}
    for k in range(5):
        for b in bins: res[b].append(cpu(b,f,r))
    meds=[statistics.median(res[b]) for b in bins]
    for b,m in zip(bins,meds): tot[b]+=m
    print(f.split('/')[-1], *[f"{m:.3f}" for m in meds], f"ratio {meds[1]/meds[0]:.2f}")
print("total", *[f"{tot[b]:.3f}" for b in bins], f"ratio {tot[bins[1]]/tot[bins[0]]:.2f}")
