#!/usr/bin/env python3
"""How far each profile-interval end of two binaries lies from the exact profile end, in
standard errors, over the shipped example, 5 measured-rig, 21 misspecified and 4 showcase
recordings: python3 scripts/checks/profile_ends_check.py OLD NEW EXACT, where EXACT is a build with
PROFILE_RISE_TOL = 1e-9 (src/fit/uncertainty.rs). Run from the repository root."""
import glob, json, subprocess, sys
# The binaries: before, after, and a reference built with PROFILE_RISE_TOL = 1e-9 in
# src/fit/uncertainty.rs (the profile ends searched to the solver's accuracy).
bins = {"old": sys.argv[1], "new": sys.argv[2], "exact": sys.argv[3]}
cases = [(["data/example_recording.mcap"], "configs/rig_example.toml", [])]
for r in ["light_s1", "equal_s1", "heavy_s1", "heavy_s2", "heavy_s3"]:
    rig = r.split("_")[0]
    cases.append(([f"tests/data/measured/{r}.csv"], f"tests/data/measured/rigs/{rig}_true_nosd.toml", []))
for f in sorted(glob.glob("tests/data/misspec/*.csv")):
    rig = f.split("_")[-1].replace(".csv", "")
    cases.append(([f], f"tests/data/misspec/{rig}_measured.toml", []))
S = "tests/data/showcase/"
cases += [([S+"showcase_dlc.csv"], S+"showcase_rig.toml", "--fps 100 --rod-length 0.251 --rail-frame".split()),
          ([S+"showcase_sleap.csv"], S+"showcase_rig.toml", "--fps 200 --scale 0.00104 --rail-frame".split()),
          ([S+"showcase_motive.csv"], S+"showcase_rig.toml", ["--slider", "Unlabeled 1001", "--bob", "Unlabeled 1002", "--rail-frame"]),
          ([S+"showcase_tracker_slider.txt", S+"showcase_tracker_bob.txt"], S+"showcase_rig.toml", ["--rail-frame"])]
worst = {"old": 0, "new": 0}
n = 0
for files, rig, extra in cases:
    out = {}
    for k, b in bins.items():
        p = subprocess.run([b, "fit", *files, "--rig", rig, "--json", *extra], capture_output=True, text=True)
        try:
            out[k] = json.loads(p.stdout)
        except Exception:
            out[k] = None
    if not all(out.values()):
        print(files[0], "no json"); continue
    rows = []
    def ests(d):
        e = {}
        for name, v in d.get("parameters", {}).items():
            if isinstance(v, dict) and "ci95" in v: e[name] = v
        if isinstance(d.get("mu_static"), dict) and "ci95" in d["mu_static"]: e["mu_static"] = d["mu_static"]
        return e
    eo, en, ex = ests(out["old"]), ests(out["new"]), ests(out["exact"])
    for name in ex:
        if "profile" not in str(ex[name].get("interval")): continue
        se = ex[name]["stderr"] or 1e-300
        for side in (0, 1):
            t = ex[name]["ci95"][side]
            do = abs(eo[name]["ci95"][side] - t) / se
            dn = abs(en[name]["ci95"][side] - t) / se
            worst["old"] = max(worst["old"], do); worst["new"] = max(worst["new"], dn); n += 1
            rows.append(f"{name}[{side}] old {do:.4f} new {dn:.4f} SE")
    print(files[0].split("/")[-1], "| mu value same:", (out["old"].get("parameters") or {}).get("mu_kinetic", {}).get("value") == (out["new"].get("parameters") or {}).get("mu_kinetic", {}).get("value"), "|", "; ".join(rows))
print("ends compared", n, "worst distance from the exact end: old %.4f SE, new %.4f SE" % (worst["old"], worst["new"]))
