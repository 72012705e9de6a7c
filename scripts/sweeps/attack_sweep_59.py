#!/usr/bin/env python3
"""Input-safety sweep for issue 59, classes A-L (the CLI ones): about 10-30 small variants each.

    nice python3 scripts/sweeps/attack_sweep_59.py --appell /work/appell-new --out /tmp/s59.tsv \
        --workdir /tmp/s59 [--md scripts/sweeps/attack_sweep_59.md] [--only A,C] [--timeout 60] \
        [--maker BINARY]

Python 3 standard library only. The running, measuring and judging of each case (its own
session, TMPDIR, wall time, peak RSS, panic text, inputs hashed before and after, leftovers,
whether an exit-2 message names the file and field) and the TSV and summary are
`attack_sweep.py`'s (imported); this script only builds the cases of issue 59's classes A-L
(M-Q are the Python package's, covered by pytest in python/tests/).

Recordings the cases need that appell itself makes (steep-rail and frictionless scenes, an MCAP
with every frame dropped) are made once with --maker (default: the binary under test), so a
"before" run of an older binary can use the very inputs of the "after" run (--maker NEWER).

Acceptance per case as in attack_sweep.py (exit 0 with a correct result, 1 with a reason, or 2
naming the file and the field, within 20 s and 4 GiB; no input changed; no partial output; no
panic), plus each class's own check (see the class methods: e.g. every printed standard error
> 0 and mu within 5 standard errors of the recording's truth, exit 1 with mu null for a failed
fit, inspect's exit equal to convert's).
"""

import argparse
import json
import math
import os
import re
import shlex
import shutil
import subprocess
import sys
import time
import tomllib

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import attack_sweep as base  # noqa: E402
from attack_sweep import Case, DELETE, Sweep, dump_toml, edited, write  # noqa: E402

CLASS_TITLES = {
    "A": "rig `*_sd` keys tiny (1e-300 .. 1e-12 of the value) and sane: no standard error 0, mu right",
    "B": "direction-law keys (mu_*_positive/negative) out of range, NaN, a string: refusal names the key",
    "C": "rails near vertical (rail_tilt_deg 17 .. 89.99999) in fit, simulate, synth; mu 1e6",
    "D": "a forced law (--friction) on Coulomb recordings: no fitted standard error 0; plan --after reads the JSON",
    "E": "failed fits exit 1 with mu_kinetic null (one file and a directory)",
    "F": "a frictionless recording forced to Stribeck: mu within 5 SE of 0, not failed",
    "G": "inspect on files convert refuses (1.7e308 coordinates, --scale 1e300, every frame dropped)",
    "H": "inspect's times: stamps near 2^63 ns 1 ns apart, times 5e-324 apart",
    "I": "gravity left out of the rig: source default/latitude, not stated",
    "J": "two outputs naming one file (--plot and --friction-plot): exit 2 naming both, nothing written",
    "K": "a wide CSV naming a marker column twice: convert, inspect, fit exit 2 naming both columns",
    "L": "times in milliseconds read as seconds (200 and 2000 frames): exit 2 naming milliseconds",
}

# Truths of the shipped recordings (docs/formats.md for the example; tests/data/*/truth files).
MU_EXAMPLE = 0.12
FRICTION = "tests/data/friction"
RIGID = "tests/data/rigid"


def stderrs(obj, path=""):
    """Every (path, value) under a key "stderr" in a JSON value."""
    out = []
    if isinstance(obj, dict):
        for k, v in obj.items():
            p = f"{path}.{k}" if path else k
            if k == "stderr" and isinstance(v, (int, float)):
                out.append((p, v))
            else:
                out += stderrs(v, p)
    elif isinstance(obj, list):
        for i, v in enumerate(obj):
            out += stderrs(v, f"{path}[{i}]")
    return out


def json_lines(text):
    return [json.loads(ln) for ln in text.splitlines() if ln.strip().startswith("{")]


def mu_check(truth, need_zero_free=True):
    """exit 0: one JSON object, not failed, every standard error > 0, mu_kinetic within 5 of its
    standard errors of the truth. Other exits are left to the harness's rules."""
    def chk(r):
        if r["rc"] != 0:
            return None, ""
        d = json.loads(r["stdout_text"])
        if d.get("failed"):
            return False, f"exit 0 with failed: {str(d['failed'])[:120]}"
        bad = [f"{p}={v}" for p, v in stderrs(d) if not (v > 0)] if need_zero_free else []
        mu = d.get("mu_kinetic") or {}
        v, se = mu.get("value"), mu.get("stderr")
        if v is None or se is None:
            return False, "exit 0 without mu_kinetic value and stderr"
        z = (v - truth) / se if se > 0 else math.inf
        ok = not bad and abs(z) <= 5
        note = f"mu {v:.6f} +- {se:.3g} vs truth {truth} ({z:+.2f} SE)"
        if bad:
            note += "; standard error not > 0: " + ", ".join(bad[:4])
        return ok, note
    return chk


class Sweep59(Sweep):
    def __init__(self, appell, work, repo, timeout, maker):
        super().__init__(appell, work, repo, timeout)
        self.maker = os.path.abspath(maker)

    def make(self, args):
        """Run the maker binary (inputs the cases share, the same for every binary swept)."""
        p = subprocess.run([self.maker] + args, cwd=self.D, capture_output=True, timeout=300)
        if p.returncode != 0:
            raise RuntimeError(f"setup failed: {self.maker} {shlex.join(args)}\n{p.stderr.decode()[:2000]}")
        return p

    def prepare_data(self):
        if os.path.exists(self.D):
            shutil.rmtree(self.D)
        os.makedirs(self.D)
        os.makedirs(self.TMP, exist_ok=True)
        os.makedirs(self.IO, exist_ok=True)
        r = self.repo
        shutil.copytree(os.path.join(r, FRICTION), self.d("friction"))
        shutil.copytree(os.path.join(r, RIGID), self.d("rigid"))
        for rel in ["data/example_recording.mcap", "configs/rig_example.toml", "configs/plan_example.toml",
                    "configs/paper_rest_horizontal.toml", "tests/data/dlc_example.csv"]:
            shutil.copy(os.path.join(r, rel), self.d(os.path.basename(rel)))
        self.example_rig = tomllib.load(open(self.d("rig_example.toml"), "rb"))
        self.base_scene = tomllib.load(open(self.d("paper_rest_horizontal.toml"), "rb"))
        self.ftruth = json.load(open(self.d("friction", "truth.json")))
        self.rtruth = json.load(open(self.d("rigid", "rigid_truth.json")))

    def case_in(self, cls, name, files, argv, **kw):
        """A case run in its own directory holding files {name: text or bytes}."""
        cd = self.casedir(cls, name)
        for fn, text in files.items():
            write(os.path.join(cd, fn), text, "wb" if isinstance(text, bytes) else "w")
        c = Case(cls, name, argv, **kw)
        c.cwd = cd
        return self.add(c)

    def rows(self, rel):
        return open(self.d(rel)).read().splitlines()

    # ------------------------------------------------------------------------------------
    # A: *_sd keys
    # ------------------------------------------------------------------------------------
    def classA(self):
        cls = "A"
        ex = self.d("example_recording.mcap")
        rigid_csv = self.d("rigid", "rigid_heavy.csv")
        rigid_rig = tomllib.load(open(self.d("rigid", "rigid_heavy_measured.toml"), "rb"))
        mu_rigid = self.rtruth["rigs"]["heavy"]["mu_kinetic"]
        # key -> (rig, recording, truth, the key's value, a sane deviation)
        plan = {
            "rod_length_sd": (self.example_rig, ex, MU_EXAMPLE, "rod_length", 0.0005),
            "slider_mass_sd": (self.example_rig, ex, MU_EXAMPLE, "slider_mass", 0.003),
            "bob_mass_sd": (self.example_rig, ex, MU_EXAMPLE, "bob_mass", 0.002),
            "gravity_sd": (self.example_rig, ex, MU_EXAMPLE, "gravity", 0.01),
            "rod_mass_sd": (rigid_rig, rigid_csv, mu_rigid, "rod_mass", 0.0006),
            "bob_radius_sd": (rigid_rig, rigid_csv, mu_rigid, "bob_radius", 0.0005),
        }
        for key, (rig, rec, truth, vkey, sane) in plan.items():
            val = rig["rig"][vkey]
            for tag, sd in [("1e-300", 1e-300), ("1e-20", 1e-20), ("5e-324", 5e-324),
                            ("1e-12rel", 1e-12 * val), ("sane", sane)]:
                self.case_in(cls, f"{key}_{tag}", {"rig.toml": dump_toml(edited(rig, [("rig", key, sd)]))},
                             ["{A}", "fit", rec, "--rig", "rig.toml", "--json"], expect="any",
                             file_tok="rig.toml", field_toks=[key], ok_codes=(0, 2), check=mu_check(truth),
                             note=f"{key} = {sd!r}")

    # ------------------------------------------------------------------------------------
    # B: direction-law keys
    # ------------------------------------------------------------------------------------
    def classB(self):
        cls = "B"
        ex = self.d("example_recording.mcap")
        law = [("rig", "friction_law", "direction"), ("rig", "mu_kinetic_positive", 0.12),
               ("rig", "mu_kinetic_negative", 0.12), ("rig", "mu_static_positive", 0.15),
               ("rig", "mu_static_negative", 0.15)]
        for key in ["mu_kinetic_positive", "mu_kinetic_negative", "mu_static_positive", "mu_static_negative"]:
            for tag, v in [("1e10", 1e10), ("1.9e9", 1.9e9), ("neg1", -1.0), ("nan", math.nan), ("string", "0.2")]:
                doc = edited(self.example_rig, law + [("rig", key, v)])
                self.case_in(cls, f"fit_{key}_{tag}", {"rig.toml": dump_toml(doc)},
                             ["{A}", "fit", ex, "--rig", "rig.toml"], file_tok="rig.toml", field_toks=[key],
                             ok_codes=(2,), note=f"{key} = {v!r}")
        # The same keys in a scene (simulate).
        scene_law = [("rig", "friction_law", "direction"), ("rig", "mu_kinetic_positive", 0.3),
                     ("rig", "mu_kinetic_negative", 0.3), ("rig", "mu_kinetic", DELETE),
                     ("rig", "mu_static", DELETE)]
        for key, v in [("mu_kinetic_negative", 1.9e9), ("mu_static_positive", 1e10)]:
            doc = edited(self.base_scene, scene_law + [("rig", key, v)])
            self.case_in(cls, f"simulate_{key}_{v:g}", {"s.toml": dump_toml(doc)}, ["{A}", "simulate", "s.toml"],
                         file_tok="s.toml", field_toks=[key], ok_codes=(2,))

    # ------------------------------------------------------------------------------------
    # C: rails near vertical
    # ------------------------------------------------------------------------------------
    def classC(self):
        cls = "C"
        ex = self.d("example_recording.mcap")
        for tilt in [89.9, 89.99999, 45.0, 30.0, 17.0, -89.9]:
            doc = edited(self.example_rig, [("rig", "rail_tilt_deg", tilt)])
            # Beyond the fit's tilt search (0.3 rad, 17.19 deg) a fit holding the rail there cannot be
            # right on this horizontal-rail recording; 17 deg is inside it (any clean exit).
            self.case_in(cls, f"fit_tilt_{tilt!r}", {"rig.toml": dump_toml(doc)},
                         ["{A}", "fit", ex, "--rig", "rig.toml"], expect="any" if abs(tilt) < 17.19 else "invalid",
                         file_tok="rig.toml", field_toks=["rail_tilt_deg", "rail_tilt"])
        for tilt in [89.9, 89.99999, 45.0, -89.9]:
            sc = edited(self.base_scene, [("rig", "rail_tilt_deg", tilt), ("rig", "mu_kinetic", 1e6),
                                          ("rig", "mu_static", 1e6)])
            self.case_in(cls, f"simulate_tilt_{tilt!r}_mu1e6", {"s.toml": dump_toml(sc)},
                         ["{A}", "simulate", "s.toml"], expect="any", file_tok="s.toml",
                         field_toks=["rail_tilt_deg", "mu_kinetic", "mu_static"])
            self.case_in(cls, f"synth_tilt_{tilt!r}_mu1e6", {"s.toml": dump_toml(sc)},
                         ["{A}", "synth", "s.toml", "out.csv", "--noise", "2e-4"], expect="any", file_tok="s.toml",
                         field_toks=["rail_tilt_deg", "mu_kinetic", "mu_static"], outputs=["out.csv"])
        # An appell-made recording of an 89.99999 deg rail with mu 1e6, fitted with that rig.
        os.makedirs(self.d("steep"), exist_ok=True)
        sc = edited(self.base_scene, [("rig", "rail_tilt_deg", 89.99999), ("rig", "mu_kinetic", 1e6),
                                      ("rig", "mu_static", 1e6)])
        write(self.d("steep", "scene.toml"), dump_toml(sc))
        self.make(["synth", self.d("steep", "scene.toml"), self.d("steep", "steep.csv"), "--noise", "2e-4", "--seed", "5"])
        for tag, drop in [("stated", []), ("no_mu", [("rig", "mu_kinetic", DELETE), ("rig", "mu_static", DELETE)])]:
            rig = {"rig": dict(edited(sc, drop)["rig"])}
            self.case_in(cls, f"fit_steep_recording_{tag}", {"rig.toml": dump_toml(rig)},
                         ["{A}", "fit", self.d("steep", "steep.csv"), "--rig", "rig.toml"], expect="any",
                         file_tok="rig.toml", field_toks=["rail_tilt_deg", "rail_tilt", "mu_kinetic"])

    # ------------------------------------------------------------------------------------
    # D: a forced law on Coulomb recordings; plan --after its JSON
    # ------------------------------------------------------------------------------------
    def classD(self):
        cls = "D"

        def no_zero_se(r):
            if r["rc"] != 0 and not r["stdout_text"].strip():
                return None, ""
            d = json.loads(r["stdout_text"])
            fixed = set((d.get("fixed") or {}).keys())
            zero = [p for p, v in stderrs(d) if v == 0 and not any(f in p for f in fixed)]
            params = d.get("parameters") or {}
            zero += [f"parameters.{k}" for k, v in params.items() if isinstance(v, dict) and v.get("stderr") == 0]
            zero = sorted(set(zero))
            if zero:
                return False, "standard error exactly 0 for a fitted parameter: " + ", ".join(zero[:5])
            return True, f"law {((d.get('friction_law') or {}).get('chosen'))}, answer {d.get('answer')}"

        for rig in ["equal", "heavy", "light"]:
            rec = self.d("friction", f"coulomb_{rig}_s1.csv")
            rigf = self.d("friction", "rigs", f"{rig}.toml")
            # "static" is not a --friction law (static above kinetic is --mu-static / --with mu_static):
            # the static law is forced with --with mu_static.
            for law in ["stribeck", "static", "direction", "load"]:
                name = f"fit_{rig}_{law}"
                force = ["--with", "mu_static"] if law == "static" else ["--friction", law]
                self.add(Case(cls, name, ["{A}", "fit", rec, "--rig", rigf, *force, "--json"],
                              expect="any", check=no_zero_se, ok_codes=(0, 1)))
                fit_out = os.path.join(self.IO, f"c{cls}_{name}.stdout")

                def setup(c, src=fit_out):
                    shutil.copy(src, os.path.join(c.cwd, "FIT.json"))

                def plan_chk(r):
                    # The failure: a fitted parameter's covariance entry 0 refused. Another
                    # covariance refusal of appell's own JSON passes by this rule but is noted.
                    err = r["stderr"]
                    if r["rc"] == 2 and re.search(r"covariance", err, re.I):
                        if re.search(r"got (-?0(\.0+)?(e[+-]?0+)?|0)\b(?![.\d])", err):
                            return False, "plan refused a covariance entry 0 of appell's own JSON"
                        return None, "NOTE plan refuses appell's own JSON: " + err.strip().splitlines()[0][:200]
                    return None, ""
                cd = self.casedir(cls, f"plan_after_{rig}_{law}")
                shutil.copy(self.d("plan_example.toml"), os.path.join(cd, "plan.toml"))
                c = Case(cls, f"plan_after_{rig}_{law}", ["{A}", "plan", "plan.toml", "--after", "FIT.json"],
                         expect="any", file_tok="FIT.json", field_toks=["FIT.json"], ok_codes=(0, 2),
                         setup=setup, check=plan_chk, inputs=["FIT.json"])
                c.cwd = cd
                self.add(c)

    # ------------------------------------------------------------------------------------
    # E: failed fits exit 1 with mu null
    # ------------------------------------------------------------------------------------
    def classE(self):
        cls = "E"

        def failed_check(r):
            objs = json_lines(r["stdout_text"])
            if not objs:
                return (None, "") if r["rc"] != 0 else (False, "exit 0 without JSON")
            # A fit whose warnings say it failed counts as failed whatever its "failed" key says.
            failed = [o for o in objs if o.get("failed") or any("fit failed" in str(w) for w in o.get("warnings") or [])]
            if r["rc"] == 0 and failed:
                return False, f"exit 0 with {len(failed)} failed fit(s)"
            with_mu = [o for o in failed if o.get("mu_kinetic") is not None]
            if with_mu:
                return False, "failed fit keeps mu_kinetic: " + json.dumps(with_mu[0]["mu_kinetic"])[:120]
            if failed and r["rc"] != 1:
                return False, f"failed fit exits {r['rc']}"
            return True, f"{len(failed)} of {len(objs)} failed, exit {r['rc']}"

        for rig in ["heavy", "light", "paper"]:
            csv = self.d("rigid", f"rigid_{rig}.csv")
            lab = self.d("rigid", f"rigid_{rig}_lab.toml")
            ddir = self.d(f"dir_rigid_{rig}")
            os.makedirs(ddir, exist_ok=True)
            shutil.copy(csv, ddir)
            for tag, flags in [("with_stribeck_plain", ["--plain", "--no-profile", "--with", "stribeck"]),
                               ("friction_stribeck", ["--friction", "stribeck", "--no-profile"])]:
                for where, inp in [("file", csv), ("dir", ddir)]:
                    self.add(Case(cls, f"{rig}_{tag}_{where}", ["{A}", "fit", "--json", *flags, "--rig", lab, inp],
                                  expect="any", check=failed_check, ok_codes=(0, 1)))
        csv, lab, ddir = self.d("rigid", "rigid_heavy.csv"), self.d("rigid", "rigid_heavy_lab.toml"), self.d("dir_rigid_heavy")
        for tag, flags in [("fit_rod_length", ["--fit-rod-length"]), ("mu_static_tied", ["--mu-static", "tied"])]:
            for where, inp in [("file", csv), ("dir", ddir)]:
                self.add(Case(cls, f"heavy_with_stribeck_plain_{tag}_{where}",
                              ["{A}", "fit", "--json", "--plain", "--no-profile", "--with", "stribeck", *flags,
                               "--rig", lab, inp], expect="any", check=failed_check, ok_codes=(0, 1)))
        # A recording whose times are 5e-324 s apart (the fit says it failed in a warning).
        rows = self.rows("friction/coulomb_equal_s1.csv")
        text = "\n".join([rows[0]] + [f"{i * 5e-324!r}," + ",".join(r.split(",")[1:])
                                       for i, r in enumerate(rows[1:1001])]) + "\n"
        sdir = self.d("dir_sub")
        write(os.path.join(sdir, "r.csv"), text)
        for where, inp in [("file", os.path.join(sdir, "r.csv")), ("dir", sdir)]:
            self.add(Case(cls, f"times_5e-324_apart_{where}", ["{A}", "fit", "--json", "--rig",
                                                                self.d("friction", "rigs", "equal.toml"), inp],
                          expect="any", check=failed_check, ok_codes=(0, 1, 2),
                          file_tok="r.csv", field_toks=["time"]))

    # ------------------------------------------------------------------------------------
    # F: a frictionless rail forced to Stribeck
    # ------------------------------------------------------------------------------------
    def classF(self):
        cls = "F"
        os.makedirs(self.d("frictionless"), exist_ok=True)
        variants = [
            ("paper_rest_s1", {}, "2e-4", 1), ("paper_rest_s2", {}, "2e-4", 2), ("paper_rest_s3", {}, "2e-4", 3),
            ("paper_rest_quiet", {}, "5e-5", 4), ("paper_rest_noisy", {}, "5e-4", 5),
            ("paper_theta_0.5", {("initial", "theta"): 0.5}, "2e-4", 6),
            ("paper_swing", {("initial", "theta"): -0.4, ("initial", "theta_dot"): 3.0}, "2e-4", 7),
            ("heavy_slider", {("rig", "slider_mass"): 0.35}, "2e-4", 8),
            ("light_slider", {("rig", "slider_mass"): 0.05, ("rig", "bob_mass"): 0.15}, "2e-4", 9),
            ("paper_pushed", {("initial", "x_dot"): 0.3}, "2e-4", 10),
        ]
        for name, changes, noise, seed in variants:
            sc = edited(self.base_scene, [("rig", "mu_kinetic", 0.0), ("rig", "mu_static", 0.0)] +
                        [(s, k, v) for (s, k), v in changes.items()])
            write(self.d("frictionless", f"{name}.toml"), dump_toml(sc))
            rec = self.d("frictionless", f"{name}.csv")
            self.make(["synth", self.d("frictionless", f"{name}.toml"), rec, "--noise", noise, "--seed", str(seed)])
            rig = {"rig": {k: v for k, v in sc["rig"].items() if not k.startswith("mu_")}}
            self.case_in(cls, name, {"rig.toml": dump_toml(rig)},
                         ["{A}", "fit", rec, "--rig", "rig.toml", "--friction", "stribeck", "--json"],
                         expect="valid", ok_codes=(0,), check=mu_check(0.0, need_zero_free=False))

    # ------------------------------------------------------------------------------------
    # G, H: inspect against convert
    # ------------------------------------------------------------------------------------
    def inspect_pair(self, cls, name, files, in_args, span_from_convert=False, fit_rig=None):
        """convert then inspect (text and --json) on the same input; inspect's exit must be
        convert's, no inf/NaN measurement in its report; optionally the spans compared."""
        conv = self.case_in(cls, f"{name}_convert", files, ["{A}", "convert", in_args[0], "out.csv", *in_args[1:]],
                            expect="any", outputs=["out.csv"], file_tok=in_args[0],
                            field_toks=["time", "position", "scale", "slider", "bob", "marker", "frame", "--scale"])
        span_holder = {}

        def conv_check(r):
            self.shared[f"{name}_rc"] = r["rc"]
            if r["rc"] == 0 and span_from_convert:
                rows = open(os.path.join(r["cwd"], "out.csv")).read().splitlines()
                t = [float(x.split(",")[0]) for x in rows[1:] if x and x[0] not in "#"]
                span_holder["span"] = t[-1] - t[0]
            return None, ""
        conv.check = conv_check

        for tag, extra in [("text", []), ("json", ["--json"])]:
            def chk(r, tag=tag):
                want = self.shared.get(f"{name}_rc")
                out = r["stdout_text"]
                notes = []
                ok = True
                if r["rc"] != want:
                    ok = False
                    notes.append(f"inspect exit {r['rc']} but convert exit {want}")
                bad = re.findall(r"(?<![A-Za-z_])(inf|-inf|NaN|nan|Infinity)(?![A-Za-z_])", out)
                if bad:
                    ok = False
                    notes.append("inf/NaN printed: " + ",".join(sorted(set(bad))))
                if span_from_convert and "span" in span_holder and r["rc"] == 0:
                    cs = span_holder["span"]
                    if tag == "json":
                        tj = json_lines(out)[0]["time"]
                        # Older builds have no "span": their first and last times give it.
                        s = tj["span"] if "span" in tj else tj["last"] - tj["first"]
                    else:
                        m = re.search(r"frames\s+\d+ over ([0-9.eE+-]+) s", out)
                        s = float(m.group(1)) if m else math.nan
                    if not (abs(s - cs) <= 2e-3 * abs(cs)):
                        ok = False
                    notes.append(f"span {s:.6g} s vs convert's {cs:.6g} s")
                return ok, "; ".join(notes)
            # The files were written by the convert case's directory; inspect runs there too.
            c = Case(cls, f"{name}_inspect_{tag}", ["{A}", "inspect", *in_args, *extra], expect="any",
                     check=chk, file_tok=in_args[0],
                     field_toks=["time", "position", "scale", "slider", "bob", "marker", "frame", "--scale"])
            c.cwd = conv.cwd
            self.add(c)
        if fit_rig:
            c = Case(cls, f"{name}_fit", ["{A}", "fit", *in_args, "--rig", fit_rig], expect="invalid",
                     file_tok=in_args[0], field_toks=["time", "position", "scale", "slider", "bob", "marker", "frame"],
                     note="fitted")
            c.cwd = conv.cwd
            self.add(c)

    def classG(self):
        cls = "G"
        rows = self.rows("friction/coulomb_equal_s1.csv")
        eq = self.d("friction", "rigs", "equal.toml")

        def mapped(f, head=None, n=None):
            body = rows[1:n + 1] if n else rows[1:]
            out = [head or rows[0]]
            for r in body:
                p = r.split(",")
                out.append(",".join([p[0]] + [repr(f(float(v), j)) for j, v in enumerate(p[1:])]))
            return "\n".join(out) + "\n"

        self.inspect_pair(cls, "coords_x5e308", {"r.csv": mapped(lambda v, j: v * 5.4e308)}, ["r.csv"], fit_rig=eq)
        self.inspect_pair(cls, "coords_x1e308", {"r.csv": mapped(lambda v, j: v * 1e308)}, ["r.csv"])
        self.inspect_pair(cls, "coords_plus_1.7e308", {"r.csv": mapped(lambda v, j: v + 1.7e308)}, ["r.csv"])
        self.inspect_pair(cls, "coords_bob_1.7e308", {"r.csv": mapped(lambda v, j: v * 5.6e308 if j >= 2 else v)},
                          ["r.csv"])
        self.inspect_pair(cls, "scale_1e300_wide", {"r.csv": "\n".join(rows) + "\n"}, ["r.csv", "--scale", "1e300"])
        dlc = open(self.d("dlc_example.csv")).read()
        self.inspect_pair(cls, "scale_1e300_dlc", {"d.csv": dlc}, ["d.csv", "--scale", "1e300", "--fps", "100"])
        self.inspect_pair(cls, "scale_1e-300_dlc", {"d.csv": dlc}, ["d.csv", "--scale", "1e-300", "--fps", "100"])
        # MCAPs with every frame dropped (appell synth --dropout 1), and nearly every one.
        os.makedirs(self.d("mcap"), exist_ok=True)
        for tag, p in [("all", "1"), ("nearly_all", "0.995")]:
            self.make(["synth", self.d("paper_rest_horizontal.toml"), self.d("mcap", f"drop_{tag}.mcap"),
                       "--dropout", p, "--duration", "0.5", "--seed", "11"])
            self.inspect_pair(cls, f"mcap_dropped_{tag}", {"m.mcap": open(self.d("mcap", f"drop_{tag}.mcap"), "rb").read()},
                              ["m.mcap"], fit_rig=eq if tag == "all" else None)

    def classH(self):
        cls = "H"
        rows = self.rows("friction/coulomb_equal_s1.csv")
        eq = self.d("friction", "rigs", "equal.toml")

        def timed(times, head="t", n=1000):
            out = [f"{head},slider_x,slider_y,bob_x,bob_y"]
            for t, r in zip(times, rows[1:n + 1]):
                out.append(f"{t}," + ",".join(r.split(",")[1:]))
            return "\n".join(out) + "\n"

        top = 2 ** 63 - 1
        for name, n, step in [("ns_near_2^63_1ns", 1000, 1), ("ns_near_2^63_3ns", 1000, 3),
                              ("ns_near_2^63_1ns_200", 200, 1), ("ns_near_2^63_1us", 1000, 1000)]:
            t0 = top - (n - 1) * step
            self.inspect_pair(cls, name, {"r.csv": timed([t0 + i * step for i in range(n)], "t_ns", n)},
                              ["r.csv"], span_from_convert=True)
        self.inspect_pair(cls, "t_5e-324_apart", {"r.csv": timed([repr(i * 5e-324) for i in range(1000)])},
                          ["r.csv"], fit_rig=eq)
        self.inspect_pair(cls, "t_1e-320_apart", {"r.csv": timed([repr(i * 1e-320) for i in range(1000)])}, ["r.csv"])
        self.inspect_pair(cls, "t_1e-300_apart", {"r.csv": timed([repr(i * 1e-300) for i in range(1000)])}, ["r.csv"])

    # ------------------------------------------------------------------------------------
    # I: gravity left out
    # ------------------------------------------------------------------------------------
    def classI(self):
        cls = "I"

        def gravity_check(want_source):
            def chk(r):
                if r["rc"] != 0:
                    return False, "the fit did not run"
                d = json.loads(r["stdout_text"])
                keys = {k["key"]: k for k in d["rig_measured"]["keys"]}
                g = keys.get("gravity")
                if g is None:
                    # A typed gravity without gravity_sd is held as typed and not listed.
                    return want_source == "stated", "no gravity entry in rig_measured.keys"
                ok = g.get("stated") is (want_source == "stated") and (
                    g.get("source") == want_source if want_source != "latitude" else "latitude" in str(g.get("source")))
                return ok, f"gravity source {g.get('source')!r}, stated {g.get('stated')}"
            return chk

        no_g = edited(self.example_rig, [("rig", "gravity", DELETE)])
        ex = self.d("example_recording.mcap")
        for name, flags, want in [("none", [], "default"), ("lat0", ["--latitude", "0"], "latitude"),
                                  ("lat45", ["--latitude", "45"], "latitude"),
                                  ("lat-60", ["--latitude=-60"], "latitude"),
                                  ("lat90", ["--latitude", "90"], "latitude"),
                                  ("lat45_alt1000", ["--latitude", "45", "--altitude", "1000"], "latitude")]:
            self.case_in(cls, f"example_{name}", {"rig.toml": dump_toml(no_g)},
                         ["{A}", "fit", ex, "--rig", "rig.toml", "--json", *flags], expect="valid", ok_codes=(0,),
                         check=gravity_check(want))
        heavy = tomllib.load(open(self.d("friction", "rigs", "heavy.toml"), "rb"))
        rec = self.d("friction", "coulomb_heavy_s1.csv")
        for name, flags, want in [("none", [], "default"), ("lat51", ["--latitude", "51.5"], "latitude")]:
            self.case_in(cls, f"heavy_{name}", {"rig.toml": dump_toml(edited(heavy, [("rig", "gravity", DELETE)]))},
                         ["{A}", "fit", rec, "--rig", "rig.toml", "--json", *flags], expect="valid", ok_codes=(0,),
                         check=gravity_check(want))
        # Controls: gravity typed (stated), with and without --latitude (a file's gravity wins).
        for name, flags in [("stated", []), ("stated_lat45", ["--latitude", "45"])]:
            self.case_in(cls, f"example_{name}", {"rig.toml": dump_toml(self.example_rig)},
                         ["{A}", "fit", ex, "--rig", "rig.toml", "--json", *flags], expect="valid", ok_codes=(0,),
                         check=gravity_check("stated"))

    # ------------------------------------------------------------------------------------
    # J: two outputs naming one file
    # ------------------------------------------------------------------------------------
    def classJ(self):
        cls = "J"
        ex = self.d("example_recording.mcap")
        rig = self.d("rig_example.toml")

        def both_flags(r):
            if r["rc"] != 2:
                return None, ""
            ok = "--plot" in r["stderr"] and "--friction-plot" in r["stderr"]
            return ok, "" if ok else "exit 2 without naming both --plot and --friction-plot"

        def mk(name, plot, fplot, pre=None, inputs=()):
            cd = self.casedir(cls, name)
            if pre:
                pre(cd)
            c = Case(cls, name, ["{A}", "fit", ex, "--rig", rig, "--plot", plot, "--friction-plot", fplot],
                     expect="invalid", ok_codes=(2,), check=both_flags, inputs=list(inputs))
            c.cwd = cd
            self.add(c)

        def hard(cd):
            write(os.path.join(cd, "k.svg"), "<svg/>\n")
            os.link(os.path.join(cd, "k.svg"), os.path.join(cd, "h.svg"))

        def soft(cd):
            os.symlink("k.svg", os.path.join(cd, "l.svg"))

        def soft_existing(cd):
            write(os.path.join(cd, "k.svg"), "<svg/>\n")
            os.symlink("k.svg", os.path.join(cd, "l.svg"))

        def sub(cd):
            os.makedirs(os.path.join(cd, "d"))

        mk("same_name", "k.svg", "k.svg")
        mk("dot_slash", "k.svg", "./k.svg")
        mk("same_png", "k.png", "k.png")
        mk("dotdot", "k.svg", "d/../k.svg", pre=sub)
        mk("double_slash", "k.svg", ".//k.svg")
        mk("hard_link", "k.svg", "h.svg", pre=hard, inputs=["k.svg", "h.svg"])
        mk("symlink_missing_target", "k.svg", "l.svg", pre=soft, inputs=["l.svg"])
        mk("symlink_existing", "l.svg", "k.svg", pre=soft_existing, inputs=["k.svg", "l.svg"])
        mk("existing_same", "k.svg", "k.svg", pre=lambda cd: write(os.path.join(cd, "k.svg"), "<svg/>\n"),
           inputs=["k.svg"])
        cd = self.casedir(cls, "absolute")
        mk("absolute", os.path.join(cd, "k.svg"), "k.svg")

    # ------------------------------------------------------------------------------------
    # K: a marker column named twice
    # ------------------------------------------------------------------------------------
    def classK(self):
        cls = "K"
        rows = self.rows("friction/coulomb_equal_s1.csv")
        eq = self.d("friction", "rigs", "equal.toml")

        def dup(extra_cols, idx):
            out = [rows[0] + "," + ",".join(extra_cols)]
            for r in rows[1:]:
                p = r.split(",")
                out.append(r + "," + ",".join(p[i] for i in idx))
            return "\n".join(out) + "\n"

        variants = {
            "slider_x_twice": (["slider_x"], [1], "slider_x"),
            "bob_y_twice": (["bob_y"], [4], "bob_y"),
            "bob_pair_twice": (["bob_x", "bob_y"], [3, 4], "bob_x"),
            "slider_pair_twice_other_values": (["slider_x", "slider_y"], [3, 4], "slider_x"),
        }
        for name, (cols, idx, col) in variants.items():
            text = dup(cols, idx)
            for cmd, argv in [("convert", ["convert", "r.csv", "out.csv"]), ("inspect", ["inspect", "r.csv"]),
                              ("fit", ["fit", "r.csv", "--rig", eq])]:
                def both(r, col=col):
                    if r["rc"] != 2:
                        return None, ""
                    nums = re.findall(r"column\s+(\d+)", r["stderr"])
                    ok = col in r["stderr"] and len(set(nums)) >= 2
                    return ok, "" if ok else f"exit 2 without naming {col} and both its columns"
                self.case_in(cls, f"{name}_{cmd}", {"r.csv": text}, ["{A}", *argv], file_tok="r.csv",
                             field_toks=[col], ok_codes=(2,), check=both, outputs=["out.csv"])

    # ------------------------------------------------------------------------------------
    # L: milliseconds read as seconds
    # ------------------------------------------------------------------------------------
    def classL(self):
        cls = "L"
        rows = self.rows("friction/coulomb_equal_s1.csv")
        eq = self.d("friction", "rigs", "equal.toml")
        mu = self.ftruth["laws"]["coulomb"]["mu_kinetic"]

        def ms(n, head, factor=1000.0):
            out = [head + rows[0][1:]]
            for r in rows[1:n + 1]:
                p = r.split(",")
                out.append(f"{float(p[0]) * factor:.6f}," + ",".join(p[1:]))
            return "\n".join(out) + "\n"

        for n in (200, 2000):
            for head, what in [("t", "t"), ("t_ms", "t_ms")]:
                for cmd in ("fit", "inspect"):
                    name = f"{cmd}_{n}_{what}"
                    argv = ["fit", "r.csv", "--rig", eq] if cmd == "fit" else ["inspect", "r.csv"]
                    if cmd == "fit" and head == "t_ms":
                        argv.append("--json")
                    if head == "t":
                        # Values in ms under a header of seconds: refused naming milliseconds.
                        kw = dict(expect="invalid", ok_codes=(2,) if cmd == "fit" else (0, 2),
                                  field_toks=["millisecond"])
                        if cmd == "inspect":
                            def chk(r):
                                ok = "millisecond" in (r["stdout_text"] + r["stderr"])
                                return ok, "" if ok else "inspect does not say milliseconds"
                            kw.update(expect="any", check=chk)
                    else:
                        # ms under a t_ms header: read as ms, a right answer (or a refusal naming ms).
                        kw = dict(expect="any", field_toks=["millisecond", "t_ms"],
                                  check=mu_check(mu, need_zero_free=False) if cmd == "fit" else None)
                    self.case_in(cls, name, {"r.csv": ms(n, head)}, ["{A}", *argv], file_tok="r.csv", **kw)
        # 500 Hz in ms (every other frame) and 2000 frames of microsecond values under a t_ms header.
        half = [rows[0]] + rows[1::2]
        text = "\n".join([half[0]] + [f"{float(r.split(',')[0]) * 1000:.6f}," + ",".join(r.split(",")[1:])
                                      for r in half[1:]]) + "\n"
        self.case_in(cls, "fit_500Hz_t", {"r.csv": text}, ["{A}", "fit", "r.csv", "--rig", eq], file_tok="r.csv",
                     field_toks=["millisecond"], ok_codes=(2,))
        self.case_in(cls, "fit_2000_t_ms_in_us", {"r.csv": ms(2000, "t_ms", 1e6)}, ["{A}", "fit", "r.csv", "--rig", eq],
                     file_tok="r.csv", field_toks=["millisecond", "t_ms"], ok_codes=(2,))

    def build(self, only):
        for k in CLASS_TITLES:
            if only and k not in only:
                continue
            getattr(self, f"class{k}")()


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--appell", required=True)
    ap.add_argument("--maker", help="the binary that makes the shared recordings (default: --appell)")
    ap.add_argument("--out", required=True, help="TSV of every case")
    ap.add_argument("--workdir", required=True)
    ap.add_argument("--md", help="also write the per-class summary (Markdown) here")
    ap.add_argument("--only", help="comma-separated classes (A-L)")
    ap.add_argument("--timeout", type=float, default=60.0)
    ap.add_argument("--list", action="store_true", help="build the cases, print them, run nothing")
    ap.add_argument("--repo", default=os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
    args = ap.parse_args()
    if base.GNU_TIME and subprocess.run([base.GNU_TIME, "-f", "%M", "-o", os.devnull, "true"],
                                        capture_output=True).returncode != 0:
        base.GNU_TIME = None
    only = set(args.only.upper().split(",")) if args.only else None
    os.makedirs(args.workdir, exist_ok=True)
    sw = Sweep59(args.appell, args.workdir, args.repo, args.timeout, args.maker or args.appell)
    t_start = time.monotonic()
    sw.prepare_data()
    sw.build(only)
    print(f"{len(sw.cases)} cases", file=sys.stderr)
    if args.list:
        for c in sw.cases:
            print(f"{c.cls}\t{c.name}\t{c.expect}\t{shlex.join(c.argv)}")
        return 0
    results, total = base.run_cases(sw, args.out, t_start)
    if args.md:
        base.write_md(args.md, results, total, CLASS_TITLES, "# attack_sweep_59.py: issue 59 input-safety sweep (classes A-L)",
                      f"`python3 scripts/sweeps/attack_sweep_59.py --appell {args.appell} --out {args.out} "
                      f"--workdir {args.workdir}`")
    return 0


if __name__ == "__main__":
    sys.exit(main())
