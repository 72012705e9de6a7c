#!/usr/bin/env python3
"""Input-safety sweep for `appell` (issue 35): re-runs the attack classes as many small variants.

    nice python3 scripts/sweeps/attack_sweep.py --appell /tmp/appell-35 --out /tmp/sweep.tsv \
        --workdir /tmp/sweep [--md scripts/sweeps/attack_sweep.md] [--only 1,3] [--timeout 60]

Python 3 standard library only. Every case runs the binary as a user would (its own session,
stdin closed, TMPDIR inside the work directory) and records: class, case, exit code, wall
seconds, peak RSS (GNU time's %M for the command alone; os.wait4's figure without it), panic text in its streams, whether an input
changed (SHA-256 before/after), whether a partial or temporary output was left behind, and
whether an exit-2 message names the file and the field (a heuristic: the expected file name
and one of the expected field tokens appear on stderr). A case is killed after --timeout
seconds (TIMEOUT).

Acceptance per case: exit 0 with a correct result, 1 with a reason, or 2 naming the file and
the field, within 20 s and 4 GiB; no input changed; no partial output; no panic text. Exit 0
on a clearly invalid input is a FAIL unless the case's own check says the output is correct.

Nothing under the repository is written: every input is copied into WORKDIR/_data first and
the attacks run on the copies, each in its own directory WORKDIR/cN/NAME.
"""

import argparse
import copy
import hashlib
import json
import math
import os
import re
import resource
import shlex
import shutil
import signal
import stat
import statistics
import subprocess
import sys
import threading
import time
import tomllib

PANIC_MARKERS = ("panicked", "RUST_BACKTRACE", "thread 'main'")
LIMIT_S = 20.0
LIMIT_RSS_KIB = 4 * 1024 * 1024
DELETE = object()

CLASS_TITLES = {
    1: "plan --after FIT.json: fitted values and covariance go into the rig checked",
    2: "plan [rig]/[camera]/[release]/[goal]/[search] ranges and the work bound",
    3: "fit --joint: one file named twice; disagreeing releases (4/8/16) in time",
    4: "recordings in which nothing moves; a mis-tracked filter that drops everything",
    5: "bench flags bounded; bench --read's temporary directory after a signal",
    6: "streams: stderr/stdout on /dev/full, closed pipes, --out - and /dev/stdout",
    7: "temporary output names; outputs onto inputs, links, /dev/null, FIFOs",
    8: "stiff rigs (damping, equivalent length) and run tolerances in every command",
    9: "a derived-mass error names the bad key (rig.rod_mass and the pendulum keys)",
    10: "own additions: device inputs, size caps, recording flags, synth/regions sizes",
}


# Variants the generators make that repeat another case's point; left out to keep the sweep
# near 300 cases (drop a name here to run it again).
TRIMMED = {
    1: {"cov_var_1e13", "cov_var_subnormal_rod", "cov_shape_extra_row", "cov_entry_string_nan",
        "single_mu_kinetic_neg1", "single_rail_tilt_10", "plot_rod_length_0", "value_null",
        "cov_infinity_literal", "file_empty", "value_pendulum_length_0", "value_stribeck_velocity_neg1",
        "value_mu_static_neg1", "cov_var_zero"},
    2: {"rig_slider_mass_1e+300", "rig_rod_length_1eneg12", "friction_mu_kinetic_sd_nan", "camera_duration_neg1",
        "camera_field_of_view_nan_0.6", "release_rail_neg1e+300_1e+300", "release_theta_error_deg_1e+300",
        "search_top_0", "goal_1_min_frames", "products_mu1e9_sd"},
    5: {"read_frames_0", "batches_10^9", "spp_neg", "lengths_nan"},
    6: {"stdout_devfull_sim_json", "stdout_closed_sim_json", "stdout_devfull_synth_dash", "stdout_closed_synth_dash"},
    7: {"onto_input_dot", "onto_symlink_simulate", "tmpnames_fail_synth_mcap"},
    8: {"sim_pivot_damping_1e+06", "run_rtol_0.5", "run_atol_1", "regions_viscous_1e4"},
    9: {"scene_rod_mass_1e+10"},
    10: {"csv_time_1e300", "fit_t_end_neg", "synth_duration_1e9", "regions_duration_neg", "toml_many_keys"},
}


# ----------------------------------------------------------------------------------------
# small helpers
# ----------------------------------------------------------------------------------------

class Raw(str):
    """A TOML literal written as is (an integer beyond i64, a broken value)."""


def toml_val(v):
    if isinstance(v, Raw):
        return str(v)
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, list):
        return "[" + ", ".join(toml_val(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{k} = {toml_val(x)}" for k, x in v.items()) + " }"
    raise TypeError(v)


def dump_toml(doc):
    out = []
    for sec, kv in doc.items():
        out.append(f"[{sec}]")
        for k, v in kv.items():
            out.append(f"{k} = {toml_val(v)}")
        out.append("")
    return "\n".join(out)


def edited(doc, changes):
    d = copy.deepcopy(doc)
    for sec, key, val in changes:
        if val is DELETE:
            d.get(sec, {}).pop(key, None)
        else:
            d.setdefault(sec, {})[key] = val
    return d


def sha(path):
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def snapshot(paths):
    """path -> (kind, digest) for regular files, recursively for directories; links recorded
    by their target so a replaced link shows."""
    snap = {}

    def add(p):
        try:
            st = os.lstat(p)
        except FileNotFoundError:
            snap[p] = ("missing", "")
            return
        if stat.S_ISLNK(st.st_mode):
            snap[p] = ("link", os.readlink(p))
        elif stat.S_ISDIR(st.st_mode):
            for name in sorted(os.listdir(p)):
                add(os.path.join(p, name))
        elif stat.S_ISREG(st.st_mode):
            snap[p] = ("file", sha(p))
        elif stat.S_ISFIFO(st.st_mode):
            snap[p] = ("fifo", "")
        elif stat.S_ISCHR(st.st_mode):
            snap[p] = ("chr", "")
        else:
            snap[p] = ("other", "")

    for p in paths:
        add(p)
    return snap


def listing(d):
    """Every path under d (files, links, dirs), relative."""
    out = set()
    if not os.path.isdir(d):
        return out
    for root, dirs, files in os.walk(d):
        for n in dirs + files:
            out.add(os.path.relpath(os.path.join(root, n), d))
    return out


def write(path, text, mode="w"):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, mode) as f:
        f.write(text)
    return path


# ----------------------------------------------------------------------------------------
# cases
# ----------------------------------------------------------------------------------------

class Case:
    def __init__(self, cls, name, argv, expect="invalid", file_tok=None, field_toks=(),
                 check=None, inputs=(), outputs=(), allow_new=(), mode="plain", sig=None,
                 sig_delay=1.0, fsize=None, ok_codes=(0, 1, 2), env=None, note="",
                 setup=None, after=None, cwd=None, strict=False):
        self.cls, self.name, self.argv = cls, name, argv
        self.expect = expect            # invalid | valid | any
        self.file_tok = file_tok        # a file name the exit-2 message must contain
        self.field_toks = tuple(field_toks)  # one of these must appear (field / flag)
        self.check = check              # f(result) -> (ok or None, note)
        self.inputs = list(inputs)      # extra paths to hash (argv paths are added)
        self.outputs = list(outputs)    # paths the command may write (relative to cwd)
        self.allow_new = list(allow_new)
        self.mode = mode
        self.sig, self.sig_delay = sig, sig_delay
        self.fsize = fsize
        self.ok_codes = tuple(ok_codes)
        self.env = env or {}
        self.note = note
        self.setup = setup              # f(case) run just before, in cwd
        self.after = after              # f(case) cleanup after the run
        self.cwd = cwd
        # Keys without their section ("pivot_damping" for "rig.pivot_damping") count as
        # naming the field unless strict (then only with a TOML parse error quoting the line).
        self.strict = strict
        self.bare = tuple(t.split(".")[-1] for t in self.field_toks if "." in t and not t.startswith("."))


class Sweep:
    def __init__(self, appell, work, repo, timeout):
        self.A = os.path.abspath(appell)
        self.W = os.path.abspath(work)
        self.repo = repo
        self.timeout = timeout
        self.D = os.path.join(self.W, "_data")
        self.TMP = os.path.join(self.W, "_tmp")
        self.IO = os.path.join(self.W, "_io")
        self.cases = []
        self.shared = {}   # results other cases compare against

    # -- paths ---------------------------------------------------------------------------
    def d(self, *p):
        return os.path.join(self.D, *p)

    def casedir(self, cls, name):
        p = os.path.join(self.W, f"c{cls}", name)
        if os.path.exists(p):
            shutil.rmtree(p)
        os.makedirs(p)
        return p

    def add(self, case):
        if case.name in TRIMMED.get(case.cls, ()):
            return case
        if case.cwd is None:
            case.cwd = self.casedir(case.cls, case.name)
        self.cases.append(case)
        return case

    def run_app(self, args, cwd=None, check=True):
        p = subprocess.run([self.A] + args, cwd=cwd or self.D, capture_output=True,
                           timeout=300)
        if check and p.returncode != 0:
            raise RuntimeError(f"setup failed: appell {' '.join(args)}\n{p.stderr.decode()[:2000]}")
        return p

    # -- data ----------------------------------------------------------------------------
    def prepare_data(self):
        if os.path.exists(self.D):
            shutil.rmtree(self.D)
        os.makedirs(self.D)
        os.makedirs(self.TMP, exist_ok=True)
        os.makedirs(self.IO, exist_ok=True)
        r = self.repo
        for rel in ["data/campaign", "tests/data/campaign", "tests/data/campaign37/c12_rigid_heavy_odd_mu",
                    "tests/data/campaign37/c16_rigid_light_odd_tilt"]:
            shutil.copytree(os.path.join(r, rel), self.d(rel.replace("/", "_")))
        for rel in ["data/example_recording.mcap", "configs/plan_example.toml",
                    "configs/plan_campaign.toml", "configs/rig_example.toml",
                    "configs/paper_rest_horizontal.toml", "configs/rig_paper.toml",
                    "configs/rigid_rig.toml", "configs/markers_example.toml",
                    "tests/data/tracker_slider.txt", "tests/data/tracker_bob.txt",
                    "tests/data/dlc_example.csv", "tests/data/markers_json_zstd.mcap"]:
            shutil.copy(os.path.join(r, rel), self.d(os.path.basename(rel)))
        # The fits plan --after starts from (also recorded as valid cases of class 1).
        p = self.run_app(["fit", self.d("data_campaign"), "--joint", "--rig",
                          self.d("data_campaign", "rig_measured.toml"), "--json"])
        write(self.d("joint_fit.json"), p.stdout.decode())
        p = self.run_app(["fit", self.d("example_recording.mcap"), "--rig",
                          self.d("rig_example.toml"), "--json"])
        write(self.d("single_fit.json"), p.stdout.decode())
        self.joint_fit = json.loads(open(self.d("joint_fit.json")).read())
        self.single_fit = json.loads(open(self.d("single_fit.json")).read())
        # Releases of the rigid paper rig on other rails (mu 0.28 and 0.31, same tilt), from
        # appell synth, to mix with the campaigns' mu 0.25 releases (same rig file).
        states = [(57.02, -1.199, -0.824), (30.63, 1.927, 0.778), (86.15, -1.182, 0.467),
                  (60.58, -0.33, -0.603), (96.42, 2.973, 0.776), (104.66, 2.934, -0.429),
                  (45.0, 1.5, 0.6), (120.0, -2.0, -0.7)]
        for mu, tag in [(0.28, "mu28"), (0.31, "mu31")]:
            os.makedirs(self.d(tag))
            for i, (td, tdot, xd) in enumerate(states):
                sc = self.rigid_scene(mu, math.radians(td), tdot, xd)
                write(self.d(tag, "scene.toml"), dump_toml(sc))
                self.run_app(["synth", self.d(tag, "scene.toml"), self.d(tag, f"r{i + 1:02d}.csv"),
                              "--noise", "2e-4", "--seed", str(100 + i)])
            os.remove(self.d(tag, "scene.toml"))
        # Still recordings (a pendulum hanging at rest) and a zig-zag track.
        self.still_csv(self.d("still_noisy.csv"), 2001, 2e-4, seed=1)
        self.still_csv(self.d("still_exact.csv"), 2001, 0.0, seed=1)
        self.still_csv(self.d("still_short.csv"), 12, 2e-4, seed=2)
        self.still_csv(self.d("still_drift.csv"), 2001, 2e-4, seed=3, drift=1e-4)
        self.base_scene = tomllib.load(open(self.d("paper_rest_horizontal.toml"), "rb"))
        self.base_plan = tomllib.load(open(self.d("plan_example.toml"), "rb"))
        self.base_rig = tomllib.load(open(self.d("rig_paper.toml"), "rb"))
        self.example_rig = tomllib.load(open(self.d("rig_example.toml"), "rb"))

    @staticmethod
    def rigid_scene(mu, theta, theta_dot, x_dot):
        return {"rig": {"slider_mass": 0.1, "bob_mass": 0.1, "rod_mass": 0.02, "bob_radius": 0.02,
                        "rod_length": 0.3, "gravity": 9.81, "mu_kinetic": mu, "rail_tilt_deg": 0.5},
                "initial": {"x": 0.0, "theta": theta, "x_dot": x_dot, "theta_dot": theta_dot},
                "run": {"duration": 2.0}}

    @staticmethod
    def still_csv(path, n, noise, seed, drift=0.0):
        import random
        rng = random.Random(seed)
        lines = ["t,slider_x,slider_y,bob_x,bob_y"]
        for i in range(n):
            g = (lambda: rng.gauss(0, noise)) if noise > 0 else (lambda: 0.0)
            dx = drift * i / max(n - 1, 1)
            lines.append(f"{i / 1000:.3f},{dx + g():.7f},{g():.7f},{dx + g():.7f},{-0.3 + g():.7f}")
        write(path, "\n".join(lines) + "\n")

    # ------------------------------------------------------------------------------------
    # running one case
    # ------------------------------------------------------------------------------------
    def execute(self, c):
        argv = [self.A if a == "{A}" else a for a in c.argv]
        cwd = c.cwd
        if c.setup:
            c.setup(c)
        # Inputs: every argv item that exists outside the declared outputs, plus the listed ones.
        outs = {os.path.normpath(os.path.join(cwd, o)) for o in c.outputs}
        watch = []
        for a in argv[1:] + c.inputs:
            for part in str(a).split(","):
                p = os.path.normpath(os.path.join(cwd, part))
                if p in outs or p.startswith("/dev/") or p == os.path.normpath(cwd):
                    continue
                if os.path.lexists(p) and p not in watch:
                    watch.append(p)
        before = snapshot(watch)
        before_out = snapshot(sorted(outs))
        list_before = listing(cwd)
        tmp_before = listing(self.TMP)
        out_path = os.path.join(self.IO, f"c{c.cls}_{c.name}.stdout")
        err_path = os.path.join(self.IO, f"c{c.cls}_{c.name}.stderr")
        env = dict(os.environ)
        env.pop("RUST_BACKTRACE", None)
        env["TMPDIR"] = self.TMP
        env.update(c.env)

        fsize = c.fsize

        def pre():
            os.setsid()
            signal.signal(signal.SIGPIPE, signal.SIG_DFL)
            if fsize is not None:
                signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
                resource.setrlimit(resource.RLIMIT_FSIZE, (fsize, fsize))
            # A safety net far above the 4 GiB acceptance bound (the machine is shared).
            resource.setrlimit(resource.RLIMIT_AS, (16 << 30, 16 << 30))

        stdin = subprocess.DEVNULL
        errf = open("/dev/full", "w") if c.mode == "devfull_stderr" else open(err_path, "wb")
        reader = None
        captured = bytearray()
        closed_w = None
        if c.mode == "devfull_stdout":
            outf = open("/dev/full", "w")
        elif c.mode == "closed_pipe":
            r, w = os.pipe()
            os.close(r)
            outf = w
            closed_w = w
        elif c.mode in ("pipe", "head1"):
            r, w = os.pipe()
            outf = w
            closed_w = w

            def read_all(fd=r, head=(c.mode == "head1")):
                with os.fdopen(fd, "rb") as f:
                    if head:
                        captured.extend(f.readline())
                        return
                    while True:
                        b = f.read(65536)
                        if not b:
                            break
                        captured.extend(b)
            reader = threading.Thread(target=read_all, daemon=True)
            reader.start()
        else:
            outf = open(out_path, "wb")
        # Peak RSS: a child forked from this Python process keeps the parent's high-water mark
        # across exec (Linux), so wait4 alone reports at least the harness's own RSS. GNU time
        # forks the command from a small process and reports its maximum alone (%M).
        time_path = os.path.join(self.IO, f"c{c.cls}_{c.name}.time")
        if os.path.exists(time_path):
            os.remove(time_path)
        run_argv = ([GNU_TIME, "-f", "%M %x", "-o", time_path] + argv) if GNU_TIME else argv
        t0 = time.monotonic()
        proc = subprocess.Popen(run_argv, cwd=cwd, stdin=stdin, stdout=outf, stderr=errf, env=env,
                                preexec_fn=pre, close_fds=True)
        if closed_w is not None:
            os.close(closed_w)
        elif hasattr(outf, "close"):
            outf.close()
        errf.close()
        timed_out = False
        sent = False
        status = None
        rusage = None
        while True:
            pid, st, ru = os.wait4(proc.pid, os.WNOHANG)
            if pid:
                status, rusage = st, ru
                break
            el = time.monotonic() - t0
            if c.sig is not None and not sent and el >= c.sig_delay:
                target = child_of(proc.pid) if GNU_TIME else proc.pid
                if target is not None:
                    try:
                        os.kill(target, c.sig)
                    except ProcessLookupError:
                        pass
                    sent = True
            if el > self.timeout:
                timed_out = True
                try:
                    os.killpg(proc.pid, signal.SIGKILL)
                except ProcessLookupError:
                    pass
                pid, st, ru = os.wait4(proc.pid, 0)
                status, rusage = st, ru
                break
            time.sleep(0.005 if el < 1 else 0.02)
        wall = time.monotonic() - t0
        rc = os.waitstatus_to_exitcode(status)
        proc.returncode = rc
        rss_kib = rusage.ru_maxrss
        rss_exact = False
        if GNU_TIME and not timed_out:
            try:
                lines = open(time_path).read().strip().splitlines()
                m, x = lines[-1].split()
                rss_kib, rss_exact = int(m), True
                sig_line = [ln for ln in lines if ln.startswith("Command terminated by signal")]
                rc = -int(sig_line[0].split()[-1]) if sig_line else int(x)
            except (OSError, ValueError, IndexError):
                pass
        # Any process left in its session (none expected) is ended.
        try:
            os.killpg(proc.pid, signal.SIGKILL)
        except (ProcessLookupError, PermissionError):
            pass
        if reader is not None:
            reader.join(5)
        if c.mode in ("pipe", "head1"):
            stdout = bytes(captured)
        elif c.mode in ("plain",):
            stdout = open(out_path, "rb").read()
        else:
            stdout = b""
        stderr = b"" if c.mode == "devfull_stderr" else open(err_path, "rb").read()
        if c.after:
            c.after(c)
        after = snapshot(watch)
        after_out = snapshot(sorted(outs))
        list_after = listing(cwd)
        tmp_after = listing(self.TMP)
        res = {
            "case": c, "rc": rc, "wall": wall, "rss_kib": rss_kib, "rss_exact": rss_exact, "timed_out": timed_out,
            "stdout": stdout, "stderr": stderr.decode("utf-8", "replace"),
            "stdout_text": stdout.decode("utf-8", "replace"), "cwd": cwd, "argv": argv,
        }
        changed = [p for p in before if before[p] != after.get(p)]
        res["input_changed"] = changed
        # Leftovers: new paths in the case directory that are not declared outputs of a
        # successful run, new paths in TMPDIR, and any new *.tmp file.
        allowed = {os.path.normpath(o) for o in c.outputs + c.allow_new} if rc == 0 else {
            os.path.normpath(o) for o in c.allow_new}
        new = sorted(p for p in list_after - list_before if os.path.normpath(p) not in allowed)
        new += [os.path.join("$TMPDIR", p) for p in sorted(tmp_after - tmp_before)]
        res["leftovers"] = new
        # A failed run must leave its declared outputs as they were.
        if rc != 0:
            clobbered = [p for p in before_out if before_out[p] != after_out.get(p)]
            res["input_changed"] += [p + " (output of a failed run changed)" for p in clobbered]
        text = res["stderr"] + "\n" + res["stdout_text"]
        res["panic"] = rc == 101 or any(m in text for m in PANIC_MARKERS)
        low = res["stderr"]
        res["names_file"] = None if c.file_tok is None else (c.file_tok in low)
        res["names_field"] = None if not c.field_toks else any(t in low for t in c.field_toks)
        res["bare_only"] = False
        if res["names_field"] is False and c.bare:
            parse = "parse error" in low
            if any(b in low for b in c.bare) and (parse or not c.strict):
                res["names_field"] = True
                res["bare_only"] = not parse
        self.judge(res)
        return res

    def judge(self, res):
        c = res["case"]
        rc = res["rc"]
        reasons = []
        notes = [c.note] if c.note else []
        if res.get("bare_only"):
            notes.append("names the key without its section")
        chk_ok, chk_note = (None, "")
        if c.check is not None and not res["timed_out"]:
            try:
                chk_ok, chk_note = c.check(res)
            except Exception as e:  # a check that cannot read the output fails the case
                chk_ok, chk_note = False, f"check raised {type(e).__name__}: {e}"
        if chk_note:
            notes.append(chk_note)
        if res["timed_out"]:
            res["verdict"] = "TIMEOUT"
            res["reason"] = f"killed after {self.timeout:.0f} s"
            res["notes"] = "; ".join(notes)
            return
        if res["panic"]:
            reasons.append("panic text or exit 101")
        # The signal a case sends ends a run that has made no temporary yet by its default
        # action (the cleanup handler is installed just before the first temporary, since
        # cbded02); the case's own check still says nothing was left behind.
        if rc < 0 and not (c.sig is not None and -rc == int(c.sig)):
            reasons.append(f"killed by signal {-rc}")
        if res["wall"] > LIMIT_S:
            reasons.append(f"took {res['wall']:.1f} s (> {LIMIT_S:.0f} s)")
        if res["rss_kib"] > LIMIT_RSS_KIB:
            reasons.append(f"peak RSS {res['rss_kib'] / 1024:.0f} MiB (> 4 GiB)")
        if res["input_changed"]:
            reasons.append("input changed: " + ", ".join(res["input_changed"][:3]))
        if res["leftovers"]:
            reasons.append("left behind: " + ", ".join(res["leftovers"][:4]))
        if rc >= 0 and rc not in c.ok_codes:
            reasons.append(f"exit {rc} not in {sorted(c.ok_codes)}")
        if rc == 0 and c.expect == "invalid" and chk_ok is not True:
            reasons.append("exit 0 on an invalid input" + ("" if chk_ok is None else " (output not correct)"))
        elif chk_ok is False:
            reasons.append("check failed: " + chk_note)
        if rc == 1 and c.mode != "devfull_stderr" and len(res["stderr"].strip()) < 10:
            reasons.append("exit 1 without a reason on stderr")
        if rc == 2 and c.mode != "devfull_stderr":
            if res["names_file"] is False:
                reasons.append(f"exit 2 but the message does not name the file ({c.file_tok})")
            if res["names_field"] is False:
                reasons.append("exit 2 but the message names none of " + "/".join(c.field_toks))
        res["verdict"] = "FAIL" if reasons else "PASS"
        res["reason"] = "; ".join(reasons)
        res["notes"] = "; ".join(n for n in notes if n)

    # ------------------------------------------------------------------------------------
    # class 1: plan --after FIT.json
    # ------------------------------------------------------------------------------------
    def class1(self):
        cls = 1
        J, S = self.joint_fit, self.single_fit
        pc, pe = self.d("plan_campaign.toml"), self.d("plan_example.toml")

        def ok_plan(res):
            t = res["stdout_text"]
            return ("rank" in t or "feasible" in t or "NOT FEASIBLE" in t), "plan printed"

        for tag, fit, plan in [("joint", "joint_fit.json", pc), ("single", "single_fit.json", pe)]:
            self.add(Case(cls, f"valid_{tag}", ["{A}", "plan", plan, "--after", self.d(fit)],
                          expect="valid", ok_codes=(0,), check=ok_plan))
            cd = self.casedir(cls, f"valid_{tag}_plot")
            self.add(Case(cls, f"valid_{tag}_plot", ["{A}", "plan", plan, "--after", self.d(fit),
                                                     "--json", "--plot", "plan.svg"],
                          expect="valid", ok_codes=(0,), outputs=["plan.svg"],
                          check=lambda r: (os.path.getsize(os.path.join(r["cwd"], "plan.svg")) > 100
                                           and json.loads(r["stdout_text"]) is not None, "svg + json"), cwd=cd))

        def section(d):
            return "shared" if isinstance(d.get("shared"), dict) else "parameters"

        def set_value(name, v):
            def f(d):
                d[section(d)][name]["value"] = v
            return f

        def add_param(name, value, var=1e-8):
            def f(d):
                cov = d["shared_covariance"]
                if name in cov["names"]:
                    i = cov["names"].index(name)
                    d[section(d)][name]["value"] = value
                    return
                n = len(cov["names"])
                cov["names"].append(name)
                for row in cov["matrix"]:
                    row.append(0.0)
                cov["matrix"].append([0.0] * n + [var])
                d[section(d)][name] = {"value": value, "stderr": math.sqrt(var), "unit": ""}
            return f

        def mut_case(name, base, plan, mutate, field_toks, expect="invalid", plot=False,
                     raw=None, note=""):
            cd = self.casedir(cls, name)
            if raw is not None:
                write(os.path.join(cd, "fit.json"), raw)
            else:
                d = copy.deepcopy(base)
                mutate(d)
                write(os.path.join(cd, "fit.json"), json.dumps(d, indent=1))
            argv = ["{A}", "plan", plan, "--after", "fit.json"]
            outs = []
            if plot:
                argv += ["--plot", "plan.svg"]
                outs = ["plan.svg"]
            c = Case(cls, name, argv, expect=expect, file_tok="fit.json", field_toks=field_toks,
                     outputs=outs, note=note, strict=True)
            c.cwd = cd
            self.add(c)

        # Values the fit computed.
        value_attacks = [
            ("rod_length", -0.3, False), ("rod_length", 0.0, False), ("rod_length", 1e300, False),
            ("pendulum_length", -0.3, True), ("pendulum_length", 0.0, True),
            ("equivalent_mass_ratio", -1.0, False), ("equivalent_mass_ratio", 1e30, False),
            ("mu_kinetic", -1.0, False), ("mu_kinetic", 1e300, False),
            ("mu_static", 0.1, True), ("mu_static", -1.0, True),
            ("rail_tilt", 10.0, False), ("rail_tilt", math.pi / 2, False),
            ("pivot_damping", -1.0, True), ("pivot_damping", 1e3, True), ("pivot_damping", 10.0, True),
            ("viscous_friction", 1e3, True),
            ("stribeck_velocity", 0.0, True), ("stribeck_velocity", -1.0, True),
            ("load_exponent", 5.0, True), ("mu_kinetic_split", 10.0, True),
        ]
        for pname, v, need_add in value_attacks:
            name = f"value_{pname}_{v:g}".replace("-", "neg").replace("+", "")
            mut = add_param(pname, v) if need_add else set_value(pname, v)
            mut_case(name, J, pc, mut, [f"shared.{pname}"])
        # Valid but unusual values: must end correctly either way.
        mut_case("value_stribeck_velocity_1e-6", J, pc, add_param("stribeck_velocity", 1e-6),
                 ["stribeck_velocity"], expect="any")
        mut_case("value_mu_kinetic_0", J, pc, set_value("mu_kinetic", 0.0), ["mu_kinetic"], expect="any")
        # The same on a single fit (section `parameters`), and with --plot.
        for pname, v, need_add in [("rod_length", -0.3, False), ("equivalent_mass_ratio", -1.0, False),
                                   ("mu_kinetic", -1.0, False), ("rail_tilt", 10.0, True),
                                   ("pivot_damping", -1.0, True)]:
            mut = add_param(pname, v) if need_add else set_value(pname, v)
            mut_case(f"single_{pname}_{v:g}".replace("-", "neg"), S, pe, mut,
                     [f"parameters.{pname}"])
        for pname, v in [("rod_length", -0.3), ("rod_length", 0.0), ("mu_kinetic", -1.0)]:
            mut_case(f"plot_{pname}_{v:g}".replace("-", "neg"), J, pc, set_value(pname, v),
                     [f"shared.{pname}"], plot=True)
        mut_case("plot_single_rod_0", S, pe, set_value("rod_length", 0.0),
                 ["parameters.rod_length"], plot=True)
        # Value of the wrong type or missing.
        for name, mut in [
            ("value_string", lambda d: d["shared"]["rod_length"].__setitem__("value", "0.3")),
            ("value_null", lambda d: d["shared"]["rod_length"].__setitem__("value", None)),
            ("value_missing", lambda d: d["shared"]["rod_length"].pop("value")),
            ("value_section_missing", lambda d: d.pop("shared")),
        ]:
            mut_case(name, J, pc, mut, ["rod_length", "shared", "parameters"])

        # The covariance.
        def cov_set(i, j, v, sym=False):
            def f(d):
                d["shared_covariance"]["matrix"][i][j] = v
                if sym:
                    d["shared_covariance"]["matrix"][j][i] = v
            return f

        def asym(scale):
            def f(d):
                m = d["shared_covariance"]["matrix"]
                m[0][1] = m[1][0] + scale * math.sqrt(m[0][0] * m[1][1])
            return f

        def not_pd(d):
            m = d["shared_covariance"]["matrix"]
            m[0][1] = m[1][0] = 2.0 * math.sqrt(m[0][0] * m[1][1])

        def names_set(i, v):
            def f(d):
                d["shared_covariance"]["names"][i] = v
            return f

        def drop_row(d):
            d["shared_covariance"]["matrix"].pop()

        def short_row(d):
            d["shared_covariance"]["matrix"][0].pop()

        def extra_row(d):
            m = d["shared_covariance"]["matrix"]
            m.append([0.0] * len(m[0]))

        def names_only_one(d):
            d["shared_covariance"]["names"] = d["shared_covariance"]["names"][:1]

        def empty_cov(d):
            d["shared_covariance"] = {"names": [], "matrix": []}

        def many_names(d):
            n = 40
            d["shared_covariance"] = {"names": ["mu_kinetic"] * n,
                                      "matrix": [[1e-8 if i == j else 0.0 for j in range(n)] for i in range(n)]}

        def drop_mu(d):
            cov = d["shared_covariance"]
            i = cov["names"].index("mu_kinetic")
            cov["names"].pop(i)
            cov["matrix"].pop(i)
            for row in cov["matrix"]:
                row.pop(i)

        def k(key):
            def f(d):
                d["shared_covariance"].pop(key)
            return f

        cov_attacks = [
            ("var_1e308", cov_set(0, 0, 1e308)), ("var_1e13", cov_set(0, 0, 1e13)),
            ("var_subnormal", cov_set(0, 0, 5e-324)), ("var_subnormal_rod", cov_set(1, 1, 1e-310)),
            ("var_zero", cov_set(0, 0, 0.0)), ("var_negative", cov_set(0, 0, -1e-9)),
            ("asymmetric", asym(1e-3)), ("not_positive_definite", not_pd),
            ("name_twice", names_set(1, "mu_kinetic")), ("name_twice_last", names_set(3, "rod_length")),
            ("name_unknown", names_set(1, "foo")), ("name_number", names_set(1, 123)),
            ("shape_row_missing", drop_row), ("shape_short_row", short_row),
            ("shape_extra_row", extra_row), ("shape_empty", empty_cov), ("shape_40_names", many_names),
            ("mu_not_in_names", drop_mu), ("cov_missing", lambda d: d.pop("shared_covariance")),
            ("entry_string_nan", cov_set(0, 1, "NaN")),
        ]
        for name, mut in cov_attacks:
            mut_case(f"cov_{name}", J, pc, mut, ["shared_covariance"])
        for name, mut in [("var_1e308", cov_set(0, 0, 1e308)), ("asymmetric", asym(1e-3))]:
            mut_case(f"single_cov_{name}", S, pe, mut, ["shared_covariance"])
        # A tiny asymmetry, as rounding gives: accepted.
        mut_case("cov_asymmetric_rounding", J, pc, asym(1e-9), ["shared_covariance"], expect="any")
        # NaN and infinity as JSON can write them (non-standard literals), and out-of-range numbers.
        base = json.dumps(J, indent=1)
        m0 = repr(J["shared_covariance"]["matrix"][0][0])
        for name, lit in [("nan_literal", "NaN"), ("infinity_literal", "Infinity"), ("number_1e999", "1e999")]:
            raw = base.replace(m0, lit, 1)
            mut_case(f"cov_{name}", J, pc, None, ["shared_covariance", "line", "column"], raw=raw)
        rod = repr(J["shared"]["rod_length"]["value"])
        mut_case("value_nan_literal", J, pc, None, ["rod_length", "line", "column"],
                 raw=base.replace(rod, "NaN", 1))
        # The file itself.
        mut_case("failed_fit", J, pc, lambda d: d.__setitem__("failed", "the releases disagree"),
                 ["failed"])
        mut_case("file_truncated", J, pc, None, ["line", "column", "JSON", "EOF"], raw=base[: len(base) // 2])
        mut_case("file_empty", J, pc, None, ["JSON", "line", "EOF"], raw="")
        mut_case("file_deep_nesting", J, pc, None, ["JSON", "recursion", "line"],
                 raw="[" * 200000 + "]" * 200000)
        mut_case("file_17MiB", J, pc, None, ["16777216", "bytes", "too large", "MiB", "larger"],
                 raw=base[:-1] + " " * (17 << 20) + "}")

    # ------------------------------------------------------------------------------------
    # class 2: plan file ranges and work
    # ------------------------------------------------------------------------------------
    def class2(self):
        cls = 2
        P = self.base_plan

        def plan_case(name, changes, field_toks, expect="invalid", note="", extra=()):
            cd = self.casedir(cls, name)
            write(os.path.join(cd, "plan.toml"), dump_toml(edited(P, changes)))
            c = Case(cls, name, ["{A}", "plan", "plan.toml", *extra], expect=expect,
                     file_tok="plan.toml", field_toks=field_toks, note=note)
            c.cwd = cd
            self.add(c)

        R = "rig"
        rig_attacks = [
            ("rod_mass", 1e300), ("rod_mass", float("nan")), ("rod_mass", 1e-300),
            ("slider_mass", 1e-300), ("slider_mass", 1e300), ("bob_mass", -0.1), ("rod_length", 1e-12),
            ("gravity", 0.0), ("bob_radius", 1e300), ("pivot_damping", 1e3),
        ]
        for key, v in rig_attacks:
            plan_case(f"rig_{key}_{v:g}".replace("-", "neg"), [(R, key, v)], [f"rig.{key}"])
        friction = [("mu_kinetic", -1.0), ("mu_kinetic_sd", 1e300), ("mu_kinetic_sd", float("nan"))]
        for key, v in friction:
            plan_case(f"friction_{key}_{v:g}".replace("-", "neg"), [("friction", key, v)],
                      [f"friction.{key}"])
        plan_case("friction_range_huge", [("friction", "mu_kinetic_sd", DELETE),
                                          ("friction", "mu_kinetic_range", [0.0, 1e300])],
                  ["friction.mu_kinetic_range"])
        camera = [("frame_rate", 1e300), ("frame_rate", 1e6), ("metres_per_pixel", 1e-300),
                  ("noise_px", 0.0), ("duration", 1e300), ("duration", -1.0),
                  ("field_of_view", [-1e300, 1e300]), ("field_of_view", [float("nan"), 0.6])]
        for key, v in camera:
            tag = f"{v:g}" if not isinstance(v, list) else "_".join(f"{x:g}" for x in v)
            plan_case(f"camera_{key}_{tag}".replace("-", "neg"), [("camera", key, v)],
                      [f"camera.{key}"] + (["camera.duration"] if key == "frame_rate" else []))
        release = [("theta_deg", [-1e300, 1e300]), ("theta_dot", [-1e300, 1e300]),
                   ("x_dot", [1e300, 1e300]), ("rail", [-1e300, 1e300]),
                   ("theta_error_deg", 1e300), ("theta_dot", [2.0, -2.0])]
        for key, v in release:
            tag = f"{v:g}" if not isinstance(v, list) else "_".join(f"{x:g}" for x in v)
            plan_case(f"release_{key}_{tag}".replace("-", "neg"), [("release", key, v)], [f"release.{key}"])
        goal = [("min_slide_px", 1e300), ("min_frames", 10 ** 12), ("min_robustness", 2.0),
                ("targets", [{"stick_slip_cycles": 10 ** 18}]), ("targets", [])]
        for i, (key, v) in enumerate(goal):
            plan_case(f"goal_{i}_{key}", [("goal", key, v)], [f"goal.{key}", "goal"])
        search = [("draws", 10 ** 9), ("verify_draws", Raw("18446744073709551615")),
                  ("grid_points", 100000), ("top", 0)]
        for key, v in search:
            plan_case(f"search_{key}_{v}", [("search", key, v)], [f"search.{key}", "search"])
        # Products that overflow or are meaningless: individually in range, together large.
        plan_case("products_mpp1_slide1e6", [("camera", "metres_per_pixel", 1.0),
                                             ("goal", "min_slide_px", 1e6)],
                  ["goal", "camera", "release"], expect="any")
        plan_case("products_fr1e6_minframes1e6", [("camera", "frame_rate", 1e6), ("camera", "duration", 1.0),
                                                  ("goal", "min_frames", 10 ** 6)],
                  ["goal", "camera", "search"], expect="any")
        plan_case("products_push100_fov1000", [("release", "theta_dot", [-100.0, 100.0]),
                                               ("release", "x_dot", [-100.0, 100.0]),
                                               ("release", "rail", [-1000.0, 1000.0]),
                                               ("camera", "field_of_view", [-1000.0, 1000.0]),
                                               ("camera", "metres_per_pixel", 1e-7)],
                  ["release", "camera", "search"], expect="any")
        plan_case("products_mu1e9_sd", [("friction", "mu_kinetic", 1e9), ("friction", "mu_kinetic_sd", 4e8)],
                  ["friction", "rig"], expect="any")
        # A fine grid with a 10^6-frame camera: the work bound (frames x runs).
        for name, ch in [
            ("work_1e6frames_grid100", [("camera", "frame_rate", 1e6), ("camera", "duration", 1.0),
                                        ("search", "grid_points", 100)]),
            ("work_1e6frames_default_grid", [("camera", "frame_rate", 1e6), ("camera", "duration", 1.0)]),
            ("work_1e5fps_10s_grid50", [("camera", "frame_rate", 1e5), ("camera", "duration", 10.0),
                                        ("search", "grid_points", 50)]),
            ("work_draws_100000", [("search", "draws", 100000), ("search", "verify_draws", 100000)]),
        ]:
            plan_case(name, ch, ["search", "camera"])
        # The file itself.
        cd = self.casedir(cls, "file_2MiB")
        write(os.path.join(cd, "plan.toml"), dump_toml(P) + "#" + "x" * (2 << 20) + "\n")
        c = Case(cls, "file_2MiB", ["{A}", "plan", "plan.toml"], file_tok="plan.toml",
                 field_toks=["1048576", "MiB", "bytes", "large"])
        c.cwd = cd
        self.add(c)
        plan_case("unknown_key", [("camera", "shutter", 1.0)], ["camera.shutter", "shutter"])

    # ------------------------------------------------------------------------------------
    # class 3: joint fits
    # ------------------------------------------------------------------------------------
    def class3(self):
        cls = 3
        C = self.d("data_campaign")
        rig = os.path.join(C, "rig_measured.toml")

        def mu_of(res):
            return json.loads(res["stdout_text"])["mu_kinetic"]

        # Reference: releases 01, 02, 03 once each (a copy in the case dir).
        def ref_check(key):
            def f(res):
                m = mu_of(res)
                self.shared[key] = m
                return True, f"reference stderr {m['stderr']:.3e}"
            return f

        def dedup_check(key):
            def f(res):
                ref = self.shared.get(key)
                if res["rc"] != 0:
                    return None, ""
                m = mu_of(res)
                note_ok = ("counted once" in res["stderr"]) or ("same file" in res["stderr"])
                if ref is None:
                    return False, "no reference"
                ratio = m["stderr"] / ref["stderr"]
                ok = note_ok and abs(ratio - 1) < 0.02 and abs(m["value"] - ref["value"]) < 1e-9
                return ok, f"stderr ratio to reference {ratio:.4f}, note {'yes' if note_ok else 'NO'}"
            return f

        def stage(name, files, links=()):
            cd = self.casedir(cls, name)
            os.makedirs(os.path.join(cd, "D"))
            for f in files:
                shutil.copy(os.path.join(C, f), os.path.join(cd, "D", f))
            for kind, src, dst in links:
                if kind == "sym":
                    os.symlink(src, os.path.join(cd, "D", dst))
                elif kind == "hard":
                    os.link(os.path.join(cd, "D", src), os.path.join(cd, "D", dst))
                else:
                    shutil.copy(os.path.join(cd, "D", src), os.path.join(cd, "D", dst))
            return cd

        three = ["release_01.csv", "release_02.csv", "release_03.csv"]
        two = ["release_01.csv", "release_02.csv"]
        cd = stage("ref_three", three)
        self.add(Case(cls, "ref_three", ["{A}", "fit", "--joint", "--rig", rig, "--json", "D"],
                      expect="valid", ok_codes=(0,), check=ref_check("three"), cwd=cd))
        cd = stage("ref_two", two)
        self.add(Case(cls, "ref_two", ["{A}", "fit", "--joint", "--rig", rig, "--json",
                                       "--release", "D/release_01.csv", "--release", "D/release_02.csv"],
                      expect="valid", ok_codes=(0,), check=ref_check("two"), cwd=cd))
        variants = [
            ("dup_dot_slash", two, (), ["--release", "D/release_01.csv", "--release", "D/./release_01.csv",
                                        "--release", "D/release_02.csv"], "two"),
            ("dup_dotdot", two, (), ["--release", "D/release_01.csv", "--release", "D/../D/release_01.csv",
                                     "--release", "D/release_02.csv"], "two"),
            ("dup_abs_rel", two, (), ["--release", "D/release_01.csv", "--release", "@ABS@/D/release_01.csv",
                                      "--release", "D/release_02.csv"], "two"),
            ("dup_three_times", two, (), ["--release", "D/release_01.csv", "--release", "D/./release_01.csv",
                                          "--release", "D//release_01.csv", "--release", "D/release_02.csv"], "two"),
            ("dup_symlink_in_dir", three, [("sym", "release_01.csv", "link_01.csv")], ["D"], "three"),
            ("dup_hardlink_in_dir", three, [("hard", "release_01.csv", "zz_hard_01.csv")], ["D"], "three"),
            ("dup_abs_symlink_in_dir", three, [("sym", "@ABS@/D/release_02.csv", "a_link_02.csv")], ["D"], "three"),
        ]
        for name, files, links, args, ref in variants:
            cd = self.casedir(cls, name)
            links = [(k, s.replace("@ABS@", cd), d) for k, s, d in links]
            shutil.rmtree(cd)
            cd = stage(name, files, links)
            args = [a.replace("@ABS@", cd) for a in args]
            c = Case(cls, name, ["{A}", "fit", "--joint", "--rig", rig, "--json", *args],
                     expect="valid", ok_codes=(0,), check=dedup_check(ref))
            c.cwd = cd
            self.add(c)
        # A byte-identical copy is another file (another inode): not covered by the
        # same-file rule; recorded, judged only on the general criteria.
        cd = stage("copy_in_dir_info", three, [("copy", "release_01.csv", "copy_01.csv")])

        def copy_info(res):
            ref = self.shared.get("three")
            if res["rc"] != 0 or ref is None:
                return None, ""
            m = mu_of(res)
            return None, (f"byte-identical copy: stderr ratio {m['stderr'] / ref['stderr']:.3f} to the "
                          f"3-release reference, note {'yes' if 'counted once' in res['stderr'] else 'no'}")
        c = Case(cls, "copy_in_dir_info", ["{A}", "fit", "--joint", "--rig", rig, "--json", "D"],
                 expect="any", check=copy_info)
        c.cwd = cd
        self.add(c)
        # One file named twice and nothing else: fewer than two releases.
        cd = stage("dup_only_one_file", ["release_01.csv"])
        c = Case(cls, "dup_only_one_file", ["{A}", "fit", "--joint", "--rig", rig, "--release",
                                            "D/release_01.csv", "--release", "D/./release_01.csv"],
                 expect="invalid", file_tok="release_01.csv", field_toks=["release", "two"])
        c.cwd = cd
        self.add(c)

        # Disagreeing releases: the mu 0.25 campaigns mixed with the mu 0.28 / 0.31 ones.
        a25 = [os.path.join(C, f"release_{i:02d}.csv") for i in range(1, 7)] + \
              [self.d("tests_data_campaign", f"release_{i:02d}.csv") for i in range(1, 5)]
        b28 = [self.d("mu28", f"r{i:02d}.csv") for i in range(1, 9)]
        c31 = [self.d("mu31", f"r{i:02d}.csv") for i in range(1, 9)]
        truth = {}
        for f in a25:
            truth[os.path.basename(os.path.dirname(f)) + "_" + os.path.basename(f)] = 0.25
        for f in b28:
            truth["mu28_" + os.path.basename(f)] = 0.28
        for f in c31:
            truth["mu31_" + os.path.basename(f)] = 0.31

        def mix_check(res):
            if res["rc"] != 0:
                return None, res["stderr"].strip().splitlines()[0][:120] if res["stderr"].strip() else ""
            d = json.loads(res["stdout_text"])
            kept = [os.path.basename(r["name"]) for r in d["releases"]]
            mus = sorted({truth[k] for k in kept if k in truth})
            ci = d["mu_kinetic"]["ci95"]
            ok = all(ci[0] - 2e-3 <= m <= ci[1] + 2e-3 for m in mus)
            return ok, (f"mu {d['mu_kinetic']['value']:.5f} ci [{ci[0]:.5f}, {ci[1]:.5f}], kept rails {mus}, "
                        f"set aside {len(d['set_aside'])}")

        def mix(name, files):
            cd = self.casedir(cls, name)
            os.makedirs(os.path.join(cd, "D"))
            for f in files:
                tag = os.path.basename(os.path.dirname(f))
                shutil.copy(f, os.path.join(cd, "D", tag + "_" + os.path.basename(f)))
            c = Case(cls, name, ["{A}", "fit", "--joint", "--rig", rig, "--json", "D"], expect="any",
                     check=mix_check)
            c.cwd = cd
            self.add(c)

        mix("mix4_2x025_2x028", a25[:2] + b28[:2])
        mix("mix8_4x025_4x028", a25[:4] + b28[:4])
        mix("mix16_8x025_8x028", a25[:8] + b28[:8])
        mix("mix16_10x025_6x028", a25[:10] + b28[:6])
        mix("mix12_3_rails", a25[:4] + b28[:4] + c31[:4])
        mix("mix10_clean_two_campaigns", a25[:10])
        # The shipped odd campaigns (issue 37).
        for name, sub in [("c12_odd_mu", "tests_data_campaign37_c12_rigid_heavy_odd_mu"),
                          ("c16_odd_tilt", "tests_data_campaign37_c16_rigid_light_odd_tilt")]:
            c = Case(cls, name, ["{A}", "fit", "--joint", "--rig", self.d(sub, "rig_measured.toml"),
                                 self.d(sub)], expect="any")
            self.add(c)
        c = Case(cls, "campaign_odd4", ["{A}", "fit", "--joint", "--rig",
                                        self.d("tests_data_campaign", "odd", "rig_measured.toml"),
                                        self.d("tests_data_campaign", "odd")], expect="any")
        self.add(c)
        # Releases of two rigs: refused (exit 2 naming the files).
        cd = self.casedir(cls, "two_rigs")
        os.makedirs(os.path.join(cd, "D"))
        for sub in ["tests_data_campaign37_c12_rigid_heavy_odd_mu", "tests_data_campaign37_c16_rigid_light_odd_tilt"]:
            for i in (1, 2, 3):
                shutil.copy(self.d(sub, f"release_{i:02d}.csv"), os.path.join(cd, "D", f"{sub[-8:]}_{i}.csv"))
        c = Case(cls, "two_rigs", ["{A}", "fit", "--joint", "--rig",
                                   self.d("tests_data_campaign37_c12_rigid_heavy_odd_mu", "rig_measured.toml"), "D"],
                 expect="any", file_tok=".csv", field_toks=["rig", "distance", "release"])
        c.cwd = cd
        self.add(c)
        # A still release among good ones, with and without --keep-going.
        for kg in (False, True):
            name = "still_release_keep_going" if kg else "still_release"
            cd = stage(name, two)
            shutil.copy(self.d("still_noisy.csv"), os.path.join(cd, "D", "still.csv"))
            c = Case(cls, name, ["{A}", "fit", "--joint", "--rig", rig, "D"] + (["--keep-going"] if kg else []),
                     expect="any",
                     check=lambda r: ((r["rc"] != 0 or "still" in r["stderr"] + r["stdout_text"]),
                                      "still release named" if "still" in r["stderr"] + r["stdout_text"] else "still release not named"))
            c.cwd = cd
            self.add(c)

    # ------------------------------------------------------------------------------------
    # class 4: nothing moves; the mis-tracked filter
    # ------------------------------------------------------------------------------------
    def class4(self):
        cls = 4
        rig = self.d("data_campaign", "rig_measured.toml")
        erig = self.d("rig_example.toml")

        def still_check(res):
            t = res["stderr"] + res["stdout_text"]
            said = ("nothing moves" in t) or ("not identifiable" in t)
            return (res["rc"] != 0 and said) or None, ("says nothing moves" if said else "does not say nothing moves")

        for name, rec, extra in [
            ("still_noisy", "still_noisy.csv", []), ("still_exact", "still_exact.csv", []),
            ("still_noisy_json", "still_noisy.csv", ["--json"]), ("still_plain", "still_noisy.csv", ["--plain"]),
            ("still_drift", "still_drift.csv", []), ("still_given_noise", "still_noisy.csv", ["--noise", "2e-4"]),
            ("still_exact_given_noise", "still_exact.csv", ["--noise", "1e-4"]),
            ("still_with_tilt", "still_noisy.csv", ["--with", "rail_tilt,pivot_damping"]),
            ("still_huber", "still_noisy.csv", ["--robust", "huber"]),
            ("still_example_rig", "still_noisy.csv", ["--rig", erig]),
            ("still_short", "still_short.csv", []),
            ("still_no_profile_mu_static", "still_noisy.csv", ["--no-profile", "--mu-static", "fixed"]),
        ]:
            argv = ["{A}", "fit", self.d(rec), "--rig", rig] + extra
            if "--rig" in extra:
                argv = ["{A}", "fit", self.d(rec)] + extra
            self.add(Case(cls, name, argv, expect="invalid", check=still_check))

        def filter_check(res):
            t = res["stderr"]
            if res["rc"] == 0:
                return None, ""
            if "too few frames" in t and "mis-tracked" not in t:
                return False, "says 'too few frames' without the filter"
            return ("mis-tracked" in t or "dropped" in t), ("names the filter" if "mis-tracked" in t else "no filter named")

        rel = self.d("data_campaign", "release_01.csv")
        for name, extra in [("filter_noise_1e-9", ["--noise", "1e-9"]), ("filter_noise_1e-12_pair", ["--noise", "1e-12,1e-12"]),
                            ("filter_noise_bob_only", ["--noise", "2e-4,1e-10"]),
                            ("filter_noise_px", ["--noise", "0.000001px", "--scale", "1"])]:
            self.add(Case(cls, name, ["{A}", "fit", rel, "--rig", rig] + extra, expect="invalid", check=filter_check))
        # A track that jumps every frame by 5 cm (every position mis-tracked).
        cd = self.casedir(cls, "filter_zigzag")
        lines = ["t,slider_x,slider_y,bob_x,bob_y"]
        rows = open(rel).read().splitlines()[1:]
        for i, row in enumerate(rows):
            t, sx, sy, bx, by = row.split(",")
            j = 0.05 if i % 2 else -0.05
            lines.append(f"{t},{float(sx) + j:.7f},{sy},{float(bx) + j:.7f},{by}")
        write(os.path.join(cd, "zig.csv"), "\n".join(lines) + "\n")
        c = Case(cls, "filter_zigzag", ["{A}", "fit", "zig.csv", "--rig", rig], expect="invalid",
                 check=lambda r: (None, "zig-zag: " + (r["stderr"].strip().splitlines() or [""])[-1][:90]))
        c.cwd = cd
        self.add(c)

    # ------------------------------------------------------------------------------------
    # class 5: bench flags and bench --read's temporary directory
    # ------------------------------------------------------------------------------------
    def class5(self):
        cls = 5
        C = self.d("data_campaign")
        flags = [
            ("read_frames_1e12", ["--read", "--frames", "1e12"], ["--frames"]),
            ("read_frames_10^12", ["--read", "--frames", "1000000000000"], ["--frames"]),
            ("read_frames_u64max", ["--read", "--frames", "18446744073709551615"], ["--frames"]),
            ("read_frames_u64max+1", ["--read", "--frames", "18446744073709551616"], ["--frames"]),
            ("read_frames_0", ["--read", "--frames", "0"], ["--frames"]),
            ("read_frames_neg", ["--read", "--frames=-5"], ["--frames"]),
            ("batches_u64max", ["--batches", "18446744073709551615"], ["--batches"]),
            ("batches_1e9", ["--batches", "1e9"], ["--batches"]),
            ("batches_10^9", ["--batches", "1000000000"], ["--batches"]),
            ("batches_0", ["--batches", "0"], ["--batches"]),
            ("wp_batches_u64max", ["--work-precision", "--batches", "18446744073709551615"], ["--batches"]),
            ("spp_1e300", ["--work-precision", "--seconds-per-point", "1e300"], ["--seconds-per-point"]),
            ("spp_nan", ["--work-precision", "--seconds-per-point", "nan"], ["--seconds-per-point"]),
            ("spp_neg", ["--work-precision", "--seconds-per-point=-1"], ["--seconds-per-point"]),
            ("rtols_1e-300", ["--work-precision", "--rtols", "1e-300"], ["--rtols"]),
            ("rtols_33", ["--work-precision", "--rtols", ",".join(["1e-6"] * 33)], ["--rtols"]),
            ("lengths_huge", ["--fit", "--lengths", "1e9@1e9"], ["--lengths"]),
            ("lengths_nan", ["--fit", "--lengths", "nan@1000"], ["--lengths"]),
            ("counts_1e6", ["--joint", C, "--rig", os.path.join(C, "rig_measured.toml"), "--counts", "1000000"], ["--counts"]),
            ("joint_batches_1e9", ["--joint", C, "--rig", os.path.join(C, "rig_measured.toml"), "--batches",
                                   "1000000000"], ["--batches"]),
        ]
        for name, args, toks in flags:
            self.add(Case(cls, name, ["{A}", "bench", *args], expect="invalid", field_toks=toks))
        # Valid small ones end quickly.
        self.add(Case(cls, "read_frames_2", ["{A}", "bench", "--read", "--frames", "2", "--batches", "1"],
                      expect="valid", ok_codes=(0,)))
        self.add(Case(cls, "wp_small", ["{A}", "bench", "--work-precision", "--scenes", "paper", "--rtols",
                                        "1e-6", "--seconds-per-point", "0", "--batches", "1"],
                      expect="valid", ok_codes=(0,)))

        # Signals during bench --read: its temporary directory must be gone (TMPDIR observed).
        def no_tmp(res):
            left = os.listdir(self.TMP)
            return (not left), ("tmp dir empty" if not left else f"left in TMPDIR: {left}")
        for sig, sname in [(signal.SIGINT, "INT"), (signal.SIGTERM, "TERM"), (signal.SIGHUP, "HUP")]:
            for delay in (0.3, 1.0):
                self.add(Case(cls, f"read_sig{sname}_{delay}s", ["{A}", "bench", "--read"], expect="any",
                              sig=sig, sig_delay=delay, ok_codes=(130, 0), check=no_tmp))

    # ------------------------------------------------------------------------------------
    # class 6: streams
    # ------------------------------------------------------------------------------------
    def class6(self):
        cls = 6
        scene = self.d("paper_rest_horizontal.toml")
        rel = self.d("data_campaign", "release_01.csv")
        cmds = {
            "sim": ["simulate", scene],
            "sim_json": ["simulate", scene, "--json"],
            "sim_out_dash": ["simulate", scene, "--out", "-"],
            "fit": ["fit", self.d("example_recording.mcap"), "--rig", self.d("rig_example.toml")],
            "fit_json": ["fit", self.d("example_recording.mcap"), "--rig", self.d("rig_example.toml"), "--json"],
            "plan_json": ["plan", self.d("plan_example.toml"), "--json"],
            "regions": ["regions", self.d("rig_paper.toml"), "--trajectories", "2"],
            "convert_dash": ["convert", rel, "-"],
            "synth_dash": ["synth", scene, "-"],
            "bench_wp": ["bench", "--work-precision", "--scenes", "paper", "--rtols", "1e-6,1e-8",
                         "--seconds-per-point", "0.001", "--batches", "1"],
            "bench": ["bench", "--batches", "3"],
        }

        def full_reason(res):
            t = res["stderr"]
            return ("No space" in t or "writing" in t), ("reason given" if t.strip() else "no reason")

        def quiet(res):
            t = res["stderr"].lower()
            bad = "broken pipe" in t or "error" in t
            return (not bad), ("quiet" if not bad else "stderr: " + res["stderr"].strip()[:100])

        for k, args in cmds.items():
            if k in ("regions", "bench", "fit"):
                continue
            self.add(Case(cls, f"stdout_devfull_{k}", ["{A}", *args], expect="any", ok_codes=(1,),
                          mode="devfull_stdout", check=full_reason))
            self.add(Case(cls, f"stdout_closed_{k}", ["{A}", *args], expect="any", ok_codes=(0,),
                          mode="closed_pipe", check=quiet))
        for k in ["sim", "fit_json", "plan_json", "bench_wp"]:
            self.add(Case(cls, f"stderr_devfull_{k}", ["{A}", *cmds[k]], expect="any", ok_codes=(0,),
                          mode="devfull_stderr"))
        for k, args in [("bad_scene", ["simulate", "/nonexistent/scene.toml"]),
                        ("bad_flag", ["bench", "--batches", "0"])]:
            self.add(Case(cls, f"stderr_devfull_{k}", ["{A}", *args], expect="invalid", ok_codes=(2,),
                          mode="devfull_stderr"))
        for k in ["bench_wp", "sim_out_dash", "convert_dash", "fit"]:
            self.add(Case(cls, f"head1_{k}", ["{A}", *cmds[k]], expect="any", ok_codes=(0,), mode="head1",
                          check=quiet))
        self.add(Case(cls, "head1_bench_wp_full", ["{A}", "bench", "--work-precision", "--batches", "1",
                                                    "--seconds-per-point", "0.001"],
                      expect="any", ok_codes=(0,), mode="head1", check=quiet))

        def csv_whole(n_rows, header):
            def f(res):
                lines = res["stdout_text"].splitlines()
                ok = len(lines) == n_rows + 1 and lines[0].startswith(header)
                return ok, f"{len(lines)} lines on stdout"
            return f

        for name, args, chk in [
            ("pipe_out_dash", ["simulate", scene, "--out", "-"], csv_whole(2001, "t,")),
            ("pipe_out_devstdout", ["simulate", scene, "--out", "/dev/stdout"], csv_whole(2001, "t,")),
            ("pipe_convert_dash", ["convert", rel, "-"], csv_whole(2001, "t,slider_x")),
            ("pipe_convert_devstdout", ["convert", rel, "/dev/stdout"], csv_whole(2001, "t,slider_x")),
            ("pipe_synth_dash", ["synth", scene, "-", "--fps", "100"], csv_whole(201, "t,slider_x")),
        ]:
            self.add(Case(cls, name, ["{A}", *args], expect="valid", ok_codes=(0,), mode="pipe", check=chk))

    # ------------------------------------------------------------------------------------
    # class 7: temporary names and outputs onto inputs
    # ------------------------------------------------------------------------------------
    def class7(self):
        cls = 7
        rel = self.d("data_campaign", "release_01.csv")
        scene = self.d("paper_rest_horizontal.toml")
        guesses = [".{o}.tmp", ".{o}.0.tmp", ".{o}.1.tmp", ".{o}.12345.tmp", ".{o}.XXXXXX.tmp",
                   ".{o}.000000.tmp", "{o}.tmp", "{o}~", ".{o}.swp", ".{o}.{pid}.tmp"]

        def plant(out, old=True):
            def f(c):
                for g in guesses:
                    for pid in range(os.getpid() + 1, os.getpid() + 40):
                        p = os.path.join(c.cwd, g.format(o=out, pid=pid))
                        with open(p, "w") as fh:
                            fh.write("someone else's file\n")
                        if "{pid}" not in g:
                            break
                if old:
                    with open(os.path.join(c.cwd, out), "w") as fh:
                        fh.write("the old output\n")
            return f

        def guesses_intact(out):
            def f(res):
                bad = []
                for n in os.listdir(res["cwd"]):
                    if n == out:
                        continue
                    p = os.path.join(res["cwd"], n)
                    if os.path.isfile(p) and open(p).read() != "someone else's file\n":
                        bad.append(n)
                n_guess = sum(1 for n in os.listdir(res["cwd"]) if n != out)
                ok = not bad and n_guess >= len(guesses)
                return ok, f"{n_guess} planted files present, {len(bad)} altered"
            return f

        writers = {
            "convert": (["convert", rel, "out.csv"], "out.csv"),
            "synth_csv": (["synth", scene, "out.csv"], "out.csv"),
            "synth_mcap": (["synth", scene, "out.mcap"], "out.mcap"),
            "simulate_out": (["simulate", scene, "--out", "out.csv"], "out.csv"),
            "fit_plot": (["fit", self.d("example_recording.mcap"), "--rig", self.d("rig_example.toml"),
                          "--plot", "out.svg"], "out.svg"),
            "plan_plot": (["plan", self.d("plan_example.toml"), "--plot", "out.svg"], "out.svg"),
            "regions_plot_png": (["regions", self.d("rig_paper.toml"), "--trajectories", "2", "--plot", "out.png"],
                                 "out.png"),
        }
        for k, (args, out) in writers.items():
            # Fails while writing (RLIMIT_FSIZE: the temporary cannot grow): the planted files
            # and the old output survive, no temporary is left.
            c = Case(cls, f"tmpnames_fail_{k}", ["{A}", *args], expect="any", ok_codes=(1,), fsize=2048,
                     outputs=[out], setup=plant(out), check=guesses_intact(out),
                     note="RLIMIT_FSIZE 2 KiB makes the write fail")
            self.add(c)
        for k in ["convert", "simulate_out"]:
            args, out = writers[k]
            c = Case(cls, f"tmpnames_ok_{k}", ["{A}", *args], expect="valid", ok_codes=(0,), outputs=[out],
                     setup=plant(out), check=guesses_intact(out))
            self.add(c)
        # SIGINT while a long recording is written: temporary removed, old output intact.
        c = Case(cls, "tmpnames_sigint_synth", ["{A}", "synth", scene, "out.csv", "--fps", "16000",
                                                "--duration", "600"],
                 expect="any", ok_codes=(130, 0), outputs=["out.csv"], sig=signal.SIGINT, sig_delay=1.5,
                 setup=plant("out.csv"), check=lambda r: (guesses_intact("out.csv")(r)[0] and (
                     r["rc"] == 0 or open(os.path.join(r["cwd"], "out.csv")).read() == "the old output\n"),
                     "planted files and old output intact"))
        self.add(c)

        # Outputs onto inputs.
        def onto(name, argv, files, links=(), field_toks=("input", "refus"), file_tok=None, expect="invalid"):
            cd = self.casedir(cls, name)
            for src, dst in files:
                shutil.copy(src, os.path.join(cd, dst))
            for kind, src, dst in links:
                if kind == "sym":
                    os.symlink(src, os.path.join(cd, dst))
                else:
                    os.link(os.path.join(cd, src), os.path.join(cd, dst))
            c = Case(cls, name, ["{A}", *argv], expect=expect, field_toks=field_toks, file_tok=file_tok,
                     inputs=[os.path.join(cd, f[1]) for f in files])
            c.cwd = cd
            self.add(c)

        onto("onto_input_convert", ["convert", "a.csv", "a.csv"], [(rel, "a.csv")], file_tok="a.csv")
        onto("onto_input_dot", ["convert", "a.csv", "./a.csv"], [(rel, "a.csv")], file_tok="a.csv")
        onto("onto_input_dotdot", ["convert", "a.csv", "../onto_input_dotdot/a.csv"], [(rel, "a.csv")],
             file_tok="a.csv")
        onto("onto_symlink_convert", ["convert", "a.csv", "link.csv"], [(rel, "a.csv")], [("sym", "a.csv", "link.csv")],
             file_tok="link.csv")
        onto("onto_hardlink_convert", ["convert", "a.csv", "hard.csv"], [(rel, "a.csv")], [("hard", "a.csv", "hard.csv")],
             file_tok="hard.csv")
        onto("onto_tracker_second", ["convert", "s.txt", "b.txt", "b.txt"],
             [(self.d("tracker_slider.txt"), "s.txt"), (self.d("tracker_bob.txt"), "b.txt")], file_tok="b.txt")
        onto("onto_input_synth", ["synth", "scene.toml", "scene.toml"], [(scene, "scene.toml")], file_tok="scene.toml")
        onto("onto_input_simulate", ["simulate", "scene.toml", "--out", "scene.toml"], [(scene, "scene.toml")],
             file_tok="scene.toml")
        onto("onto_symlink_simulate", ["simulate", "scene.toml", "--out", "l.csv"], [(scene, "scene.toml")],
             [("sym", "scene.toml", "l.csv")], file_tok="l.csv")
        onto("onto_recording_fit_plot", ["fit", "rec.mcap", "--rig", "rig.toml", "--plot", "rec.mcap"],
             [(self.d("example_recording.mcap"), "rec.mcap"), (self.d("rig_example.toml"), "rig.toml")], file_tok="rec.mcap")
        onto("onto_rig_fit_plot", ["fit", "rec.mcap", "--rig", "rig.toml", "--plot", "rig.toml"],
             [(self.d("example_recording.mcap"), "rec.mcap"), (self.d("rig_example.toml"), "rig.toml")], file_tok="rig.toml")
        onto("onto_rig_friction_plot", ["fit", "rec.mcap", "--rig", "rig.toml", "--friction-plot", "l.svg"],
             [(self.d("example_recording.mcap"), "rec.mcap"), (self.d("rig_example.toml"), "rig.toml")],
             [("sym", "rig.toml", "l.svg")], file_tok="l.svg")
        onto("onto_joint_release_plot", ["fit", "--joint", "--rig", "rig.toml", "--release", "a.csv", "--release",
                                         "b.csv", "--plot", "b.csv"],
             [(rel, "a.csv"), (self.d("data_campaign", "release_02.csv"), "b.csv"),
              (self.d("data_campaign", "rig_measured.toml"), "rig.toml")], file_tok="b.csv")
        onto("onto_plan_plot", ["plan", "p.toml", "--plot", "p.toml"], [(self.d("plan_example.toml"), "p.toml")],
             file_tok="p.toml")
        onto("onto_after_plot", ["plan", "p.toml", "--after", "f.json", "--plot", "f.json"],
             [(self.d("plan_campaign.toml"), "p.toml"), (self.d("joint_fit.json"), "f.json")], file_tok="f.json")
        onto("onto_rig_regions_plot", ["regions", "rig.toml", "--plot", "rig.toml"], [(self.d("rig_paper.toml"), "rig.toml")],
             file_tok="rig.toml")

        # Special outputs: /dev/null stays a device; a directory; a missing directory.
        def devnull_intact(res):
            st = os.stat("/dev/null")
            ok = stat.S_ISCHR(st.st_mode)
            return ok, ("/dev/null still a character device" if ok else "/dev/null REPLACED")

        for name, argv in [("devnull_convert", ["convert", rel, "/dev/null"]),
                           ("devnull_simulate", ["simulate", scene, "--out", "/dev/null"]),
                           ("devnull_synth", ["synth", scene, "/dev/null"])]:
            self.add(Case(cls, name, ["{A}", *argv], expect="any", check=devnull_intact,
                          note="README: devices and pipes are written directly"))
        cd = self.casedir(cls, "out_is_directory")
        os.makedirs(os.path.join(cd, "dir.csv"))
        c = Case(cls, "out_is_directory", ["{A}", "convert", rel, "dir.csv"], expect="invalid",
                 file_tok="dir.csv", field_toks=["directory"])
        c.cwd = cd
        self.add(c)
        self.add(Case(cls, "out_missing_dir", ["{A}", "convert", rel, "no/such/dir/out.csv"], expect="invalid",
                      file_tok="out.csv", field_toks=["No such", "directory", "cannot"]))

        # A FIFO as output: with a reader it receives the whole file and stays a FIFO; without
        # one the open blocks (the tool waits for a reader).
        def fifo_setup(with_reader):
            def f(c):
                p = os.path.join(c.cwd, "fifo.csv")
                os.mkfifo(p)
                c._got = bytearray()
                if with_reader:
                    def rd():
                        with open(p, "rb") as fh:
                            c._got.extend(fh.read())
                    c._thr = threading.Thread(target=rd, daemon=True)
                    c._thr.start()
            return f

        def fifo_after(c):
            p = os.path.join(c.cwd, "fifo.csv")
            t = getattr(c, "_thr", None)
            if t is not None and t.is_alive():
                try:  # release a reader that never saw a writer
                    fd = os.open(p, os.O_WRONLY | os.O_NONBLOCK)
                    os.close(fd)
                except OSError:
                    pass
                t.join(2)

        def fifo_check(res):
            c = res["case"]
            p = os.path.join(res["cwd"], "fifo.csv")
            is_fifo = stat.S_ISFIFO(os.lstat(p).st_mode)
            n = bytes(c._got).count(b"\n")
            if res["rc"] == 0:
                return is_fifo and n == 2002, f"fifo kept: {is_fifo}, reader got {n} lines"
            return is_fifo, f"fifo kept: {is_fifo}"

        c = Case(cls, "fifo_with_reader", ["{A}", "simulate", scene, "--out", "fifo.csv"], expect="any",
                 outputs=["fifo.csv"], setup=fifo_setup(True), after=fifo_after, check=fifo_check)
        self.add(c)
        c = Case(cls, "fifo_without_reader", ["{A}", "simulate", scene, "--out", "fifo.csv"], expect="any",
                 outputs=["fifo.csv"], setup=fifo_setup(False), after=fifo_after, check=fifo_check,
                 note="nobody reads the FIFO")
        self.add(c)

    # ------------------------------------------------------------------------------------
    # class 8: stiff rigs, tolerances
    # ------------------------------------------------------------------------------------
    def class8(self):
        cls = 8
        S = self.base_scene
        rigid_eq = {"pendulum_mass": 0.1, "pendulum_com": 1e-9, "pendulum_inertia": 1e-19}

        def scene_case(name, changes, toks, cmd="simulate", expect="invalid", extra=(), drop_bob=False):
            cd = self.casedir(cls, name)
            doc = edited(S, changes)
            if drop_bob:
                doc["rig"].pop("bob_mass", None)
            write(os.path.join(cd, "scene.toml"), dump_toml(doc))
            argv = ["{A}", cmd, "scene.toml", *extra]
            c = Case(cls, name, argv, expect=expect, file_tok="scene.toml", field_toks=toks,
                     outputs=[e for e in extra if e.endswith((".csv", ".svg", ".png", ".mcap"))])
            c.cwd = cd
            self.add(c)

        for v in [1e3, 1e6, 10.0]:
            scene_case(f"sim_pivot_damping_{v:g}", [("rig", "pivot_damping", v)], ["rig.pivot_damping"])
        scene_case("sim_pivot_damping_1e10", [("rig", "pivot_damping", 1e10)], ["rig.pivot_damping"])
        scene_case("sim_viscous_1e3", [("rig", "viscous_friction", 1e3)], ["rig.viscous_friction"])
        scene_case("sim_rod_length_1e-9", [("rig", "rod_length", 1e-9)], ["rig.rod_length"])
        scene_case("sim_equiv_length_1e-9", [("rig", k, v) for k, v in rigid_eq.items()],
                   ["equivalent length", "rig.rod_length", "pendulum"], drop_bob=True)
        scene_case("synth_pivot_damping_1e3", [("rig", "pivot_damping", 1e3)], ["rig.pivot_damping"],
                   cmd="synth", extra=("out.csv",))
        scene_case("synth_equiv_length_1e-9", [("rig", k, v) for k, v in rigid_eq.items()],
                   ["equivalent length", "pendulum"], cmd="synth", extra=("out.csv",), drop_bob=True)
        scene_case("sim_damping_near_bound", [("rig", "pivot_damping", 0.0015)], ["rig.pivot_damping"],
                   expect="any", extra=("--out", "traj.csv"))
        for key, v in [("rtol", 0.9), ("rtol", 0.5), ("rtol", -1.0), ("atol", 1e300), ("atol", -1.0),
                       ("atol", 1.0), ("max_steps", 1e12), ("duration", 1e300), ("duration", -1.0)]:
            tag = v if isinstance(v, str) else f"{v:g}"
            scene_case(f"run_{key}_{tag}".replace("-", "neg"), [("run", key, v)], [f"run.{key}"])
        scene_case("synth_rtol_0.9", [("run", "rtol", 0.9)], ["run.rtol"], cmd="synth", extra=("out.csv",))
        # A long run is bounded by max_steps (exit 1 naming where it stopped) or ends in time.
        scene_case("run_duration_1e6", [("run", "duration", 1e6)], ["run.duration", "max_steps"], expect="any")

        # fit and regions with stiff rig files
        rec = self.d("example_recording.mcap")
        E = self.example_rig

        def rig_case(name, changes, toks, cmd="fit", expect="invalid", drop_bob=False):
            cd = self.casedir(cls, name)
            doc = edited(E if cmd == "fit" else self.base_rig, changes)
            if drop_bob:
                doc["rig"].pop("bob_mass", None)
            write(os.path.join(cd, "rig.toml"), dump_toml(doc))
            argv = ["{A}", "fit", rec, "--rig", "rig.toml"] if cmd == "fit" else ["{A}", "regions", "rig.toml"]
            c = Case(cls, name, argv, expect=expect, file_tok="rig.toml", field_toks=toks)
            c.cwd = cd
            self.add(c)

        for cmd in ("fit", "regions"):
            for v in [1e3]:
                rig_case(f"{cmd}_pivot_damping_{v:g}", [("rig", "pivot_damping", v)], ["rig.pivot_damping"], cmd)
            rig_case(f"{cmd}_viscous_1e4", [("rig", "viscous_friction", 1e4)], ["rig.viscous_friction"], cmd)
            rig_case(f"{cmd}_rod_length_1e-9", [("rig", "rod_length", 1e-9)], ["rig.rod_length"], cmd)
            rig_case(f"{cmd}_equiv_length_1e-9", [("rig", k, v) for k, v in rigid_eq.items()],
                     ["equivalent length", "pendulum", "rig.rod_length"], cmd, drop_bob=True)
        rig_case("fit_damping_near_bound", [("rig", "pivot_damping", 0.005)], ["rig.pivot_damping"], "fit",
                 expect="any")
        rig_case("regions_damping_near_bound", [("rig", "pivot_damping", 0.0015)], ["rig.pivot_damping"], "regions",
                 expect="any")
        # The plan's rig.
        cd = self.casedir(cls, "plan_pivot_damping_1e3")
        write(os.path.join(cd, "plan.toml"), dump_toml(edited(self.base_plan, [("rig", "pivot_damping", 1e3)])))
        c = Case(cls, "plan_pivot_damping_1e3", ["{A}", "plan", "plan.toml"], file_tok="plan.toml",
                 field_toks=["rig.pivot_damping"])
        c.cwd = cd
        self.add(c)
        # A fit that is asked for pivot damping on a damped, near-bound rig ends in time.
        self.add(Case(cls, "fit_with_damping_rigid", ["{A}", "fit", self.d("data_campaign", "release_01.csv"), "--rig",
                                                      self.d("data_campaign", "rig_measured.toml"), "--with",
                                                      "pivot_damping,viscous_friction,rigid_pendulum"],
                      expect="any"))

    # ------------------------------------------------------------------------------------
    # class 9: derived masses name the key
    # ------------------------------------------------------------------------------------
    def class9(self):
        cls = 9
        S = self.base_scene
        attacks = [
            ("rod_mass", 1e300, ["rig.rod_mass"]), ("rod_mass", 1e10, ["rig.rod_mass"]),
            ("rod_mass", -1.0, ["rig.rod_mass"]), ("rod_mass", float("nan"), ["rig.rod_mass"]),
            ("bob_radius", 1e300, ["rig.bob_radius"]),
        ]
        for where in ("scene", "rigfile_regions", "rigfile_fit", "plan"):
            for key, v, toks in attacks:
                if where != "scene" and v != 1e300:
                    continue
                name = f"{where}_{key}_{v:g}".replace("-", "neg")
                cd = self.casedir(cls, name)
                if where == "scene":
                    write(os.path.join(cd, "f.toml"), dump_toml(edited(S, [("rig", key, v)])))
                    argv = ["{A}", "simulate", "f.toml"]
                elif where == "rigfile_regions":
                    write(os.path.join(cd, "f.toml"), dump_toml(edited(self.base_rig, [("rig", key, v)])))
                    argv = ["{A}", "regions", "f.toml"]
                elif where == "rigfile_fit":
                    write(os.path.join(cd, "f.toml"),
                          dump_toml(edited(self.d_rig_measured(), [("rig", key, v)])))
                    argv = ["{A}", "fit", self.d("data_campaign", "release_01.csv"), "--rig", "f.toml"]
                else:
                    write(os.path.join(cd, "f.toml"), dump_toml(edited(self.base_plan, [("rig", key, v)])))
                    argv = ["{A}", "plan", "f.toml"]
                c = Case(cls, name, argv, file_tok="f.toml", field_toks=toks)
                c.cwd = cd
                self.add(c)
        # The general body keys, and a rod with a tiny bob (equivalents from rod_mass).
        body = {"pendulum_mass": 0.12, "pendulum_com": 0.275, "pendulum_inertia": 0.009616}
        for key, v in [("pendulum_mass", 1e300), ("pendulum_com", 1e300), ("pendulum_inertia", 1e300),
                       ("pendulum_inertia", 1e-300)]:
            name = f"body_{key}_{v:g}"
            cd = self.casedir(cls, name)
            doc = edited(S, [("rig", k, x) for k, x in body.items()] + [("rig", key, v)])
            doc["rig"].pop("bob_mass")
            write(os.path.join(cd, "f.toml"), dump_toml(doc))
            c = Case(cls, name, ["{A}", "simulate", "f.toml"], file_tok="f.toml", field_toks=[f"rig.{key}"])
            c.cwd = cd
            self.add(c)
        for name, ch, toks, exp in [
            ("rod_heavy_bob_light", [("rig", "slider_mass", 1e-9), ("rig", "bob_mass", 1e-9), ("rig", "rod_mass", 1e9)],
             ["rig.rod_mass", "rig.slider_mass", "rig.bob_mass"], "any"),
            ("rod_sd_1e300", [("rig", "rod_mass", 0.02), ("rig", "rod_mass_sd", 1e300)], ["rig.rod_mass_sd"], "invalid"),
            # A point rig written with rod_mass = 0 and bob_radius = 0, masses 1e18 apart: the
            # bad keys are the masses (their ratio sets the swing's rate).
            ("point_rig_ratio_1e18", [("rig", "slider_mass", 1e-9), ("rig", "bob_mass", 1e9), ("rig", "rod_mass", 0.0),
                                      ("rig", "bob_radius", 0.0)],
             ["rig.slider_mass", "rig.bob_mass", "mass ratio"], "invalid"),
            ("cancel_bob_1e9_slider_1e-9", [("rig", "slider_mass", 1e-9), ("rig", "bob_mass", 1e9),
                                             ("rig", "rod_mass", 1e-9), ("rig", "bob_radius", 1e-9)],
             ["rig.slider_mass", "rig.bob_mass", "rig.rod_mass", "rig.bob_radius", "equivalent"], "any"),
        ]:
            cd = self.casedir(cls, name)
            write(os.path.join(cd, "f.toml"), dump_toml(edited(S, ch)))
            c = Case(cls, name, ["{A}", "simulate", "f.toml"], expect=exp, file_tok="f.toml", field_toks=toks)
            c.cwd = cd
            self.add(c)

    def d_rig_measured(self):
        return tomllib.load(open(self.d("data_campaign", "rig_measured.toml"), "rb"))

    # ------------------------------------------------------------------------------------
    # class 10: own additions
    # ------------------------------------------------------------------------------------
    def class10(self):
        cls = 10
        rel = self.d("data_campaign", "release_01.csv")
        rig = self.d("data_campaign", "rig_measured.toml")
        scene = self.d("paper_rest_horizontal.toml")
        # Device inputs: bounded by the size caps.
        for name, argv, toks in [
            ("scene_dev_zero", ["simulate", "/dev/zero"], ["1048576", "bytes", "large", "/dev/zero"]),
            ("scene_dev_urandom", ["simulate", "/dev/urandom"], ["1048576", "bytes", "large", "/dev/urandom", "UTF", "TOML"]),
            ("recording_dev_zero", ["fit", "/dev/zero", "--rig", rig], ["/dev/zero"]),
            ("recording_dev_urandom", ["convert", "/dev/urandom", "out.csv"], ["/dev/urandom"]),
            ("after_dev_zero", ["plan", self.d("plan_example.toml"), "--after", "/dev/zero"], ["/dev/zero"]),
            ("recording_dir_empty", ["fit", ".", "--rig", rig], ["recording", "no ", "empty"]),
        ]:
            self.add(Case(cls, name, ["{A}", *argv], expect="invalid", field_toks=toks, file_tok=None,
                          outputs=["out.csv"]))
        # Recording content.
        rows = open(rel).read().splitlines()

        def rec_case(name, text, toks, extra=(), expect="invalid", cmd="fit", file_tok="r.csv"):
            cd = self.casedir(cls, name)
            write(os.path.join(cd, "r.csv"), text)
            argv = ["{A}", "fit", "r.csv", "--rig", rig, *extra] if cmd == "fit" else ["{A}", "convert", "r.csv", "o.csv", *extra]
            c = Case(cls, name, argv, expect=expect, file_tok=file_tok, field_toks=toks, outputs=["o.csv"])
            c.cwd = cd
            self.add(c)

        rec_case("csv_value_1e300", "\n".join(rows[:500] + [rows[500].rsplit(",", 1)[0] + ",1e300"] + rows[501:]) + "\n",
                 ["line", "bob_y", "row", "frame"], expect="any")
        rec_case("csv_value_nan", "\n".join(rows[:500] + [rows[500].rsplit(",", 1)[0] + ",NaN"] + rows[501:]) + "\n",
                 ["line", "bob_y", "row", "frame"], expect="any")
        rec_case("csv_time_backwards", "\n".join([rows[0]] + rows[1:][::-1]) + "\n", ["line", "time", "t"])
        rec_case("csv_header_only", rows[0] + "\n", ["frames", "line", "rows", "empty"], expect="invalid")
        rec_case("csv_long_line", rows[0] + "\n" + "1" * (8 << 20) + "\n", ["line", "field", "column", "long"])
        rec_case("csv_time_1e300", "\n".join(rows[:1000] + ["1e300" + rows[1000][rows[1000].index(","):]] + rows[1001:]) + "\n",
                 ["line", "time", "t"], expect="any")
        rec_case("convert_fps_1e-300", open(self.d("dlc_example.csv")).read(), ["--fps", "time"],
                 extra=("--fps", "1e-300"), cmd="convert")
        rec_case("convert_scale_neg", open(self.d("dlc_example.csv")).read(), ["--scale"],
                 extra=("--scale=-1", "--fps", "100"), cmd="convert", file_tok=None)
        # Recording flags on fit.
        for name, extra, toks in [
            ("fit_t_start_1e300", ["--t-start", "1e300"], ["--t-start", "time window"]),
            ("fit_t_end_neg", ["--t-end=-1"], ["--t-end"]),
            ("fit_noise_0", ["--noise", "0"], ["--noise", "noise"]),
            ("fit_noise_1e300", ["--noise", "1e300"], ["--noise", "noise"]),
            ("fit_noise_px_no_scale", ["--noise", "1px"], ["--noise", "--scale", "px"]),
            ("fit_starts_nan", ["--json", "--starts", "nan,1e300"], ["--starts"]),
            ("fit_min_likelihood_2", ["--min-likelihood", "2"], ["--min-likelihood"]),
            ("fit_scale_1e300", ["--scale", "1e300"], ["--scale", "scaling"]),
        ]:
            chk = None
            if name == "fit_starts_nan":
                # Accepted starts of NaN and 1e300: exit 0 is right only if the fit's answer is
                # the recording's (mu 0.25, data/campaign/truth.json).
                def chk(r):
                    if r["rc"] != 0:
                        return None, ""
                    ci = json.loads(r["stdout_text"])["mu_kinetic"]["ci95"]
                    ok = ci[0] - 1e-3 <= 0.25 <= ci[1] + 1e-3
                    return ok, f"starts NaN,1e300 accepted; mu ci [{ci[0]:.5f}, {ci[1]:.5f}] vs truth 0.25"
            self.add(Case(cls, name, ["{A}", "fit", rel, "--rig", rig, *extra], expect="invalid", field_toks=toks,
                          check=chk))
        # Stribeck velocity 1e-6 in a fit (the rig file's law) and a forced Stribeck law.
        cd = self.casedir(cls, "fit_stribeck_1e-6")
        doc = edited(self.example_rig, [("rig", "friction_law", "stribeck"), ("rig", "stribeck_velocity", 1e-6),
                                        ("rig", "mu_kinetic", 0.12), ("rig", "mu_static", 0.2)])
        write(os.path.join(cd, "rig.toml"), dump_toml(doc))
        c = Case(cls, "fit_stribeck_1e-6", ["{A}", "fit", self.d("example_recording.mcap"), "--rig", "rig.toml"],
                 expect="any", file_tok="rig.toml", field_toks=["stribeck"])
        c.cwd = cd
        self.add(c)
        self.add(Case(cls, "fit_forced_stribeck", ["{A}", "fit", self.d("example_recording.mcap"), "--rig",
                                                   self.d("rig_example.toml"), "--friction", "stribeck"], expect="any"))
        cd = self.casedir(cls, "sim_stribeck_1e-9")
        write(os.path.join(cd, "s.toml"), dump_toml(edited(self.base_scene, [
            ("rig", "friction_law", "stribeck"), ("rig", "stribeck_velocity", 1e-9), ("rig", "mu_static", 0.5)])))
        c = Case(cls, "sim_stribeck_1e-9", ["{A}", "simulate", "s.toml"], expect="any", file_tok="s.toml",
                 field_toks=["stribeck"])
        c.cwd = cd
        self.add(c)
        # synth sizes
        for name, extra, toks in [
            ("synth_fps_1e9", ["--fps", "1e9"], ["--fps"]),
            ("synth_duration_1e9", ["--duration", "1e9"], ["--duration", "--fps"]),
            ("synth_noise_neg", ["--noise=-1"], ["--noise"]),
            ("synth_noise_1e300", ["--noise", "1e300"], ["--noise"]),
            ("synth_outliers_nan", ["--outliers", "nan"], ["--outliers"]),
            ("synth_outlier_size_1e300", ["--outliers", "0.1", "--outlier-size", "1e300"], ["--outlier-size"]),
            ("synth_max_frames", ["--fps", "16666", "--duration", "600"], ["--fps"]),
        ]:
            expect = "any" if name == "synth_max_frames" else "invalid"
            self.add(Case(cls, name, ["{A}", "synth", scene, "out.csv", *extra], expect=expect,
                          field_toks=toks, outputs=["out.csv"]))
        # regions sizes
        for name, extra, toks in [
            ("regions_traj_huge", ["--trajectories", "1000000000"], ["--trajectories"]),
            ("regions_duration_1e300", ["--duration", "1e300"], ["--duration"]),
            ("regions_duration_neg", ["--duration=-1"], ["--duration"]),
            ("regions_product_1e4", ["--trajectories", "1000", "--duration", "10", "--plot", "r.png"], ["--trajectories"]),
            ("regions_product_over", ["--trajectories", "1000", "--duration", "11"], ["--trajectories", "--duration"]),
        ]:
            expect = "any" if name == "regions_product_1e4" else "invalid"
            self.add(Case(cls, name, ["{A}", "regions", self.d("rig_paper.toml"), *extra], expect=expect,
                          field_toks=toks, outputs=["r.png"]))
        # Deeply nested TOML and many keys (under the 1 MiB cap).
        cd = self.casedir(cls, "toml_deep_nesting")
        write(os.path.join(cd, "s.toml"), dump_toml(self.base_scene) + "\n[extra]\nx = " + "[" * 100000 + "]" * 100000 + "\n")
        c = Case(cls, "toml_deep_nesting", ["{A}", "simulate", "s.toml"], file_tok="s.toml",
                 field_toks=["extra", "line", "nest", "recursion"])
        c.cwd = cd
        self.add(c)
        cd = self.casedir(cls, "toml_many_keys")
        write(os.path.join(cd, "s.toml"), dump_toml(self.base_scene) + "\n[extra]\n" +
              "".join(f"k{i} = {i}\n" for i in range(60000)))
        c = Case(cls, "toml_many_keys", ["{A}", "simulate", "s.toml"], file_tok="s.toml", field_toks=["extra", "k0", "unknown"])
        c.cwd = cd
        self.add(c)
        # A truncated MCAP.
        cd = self.casedir(cls, "mcap_truncated")
        data = open(self.d("example_recording.mcap"), "rb").read()
        write(os.path.join(cd, "t.mcap"), data[: len(data) // 3], "wb")
        c = Case(cls, "mcap_truncated", ["{A}", "fit", "t.mcap", "--rig", self.d("rig_example.toml")], expect="any",
                 file_tok="t.mcap", field_toks=["mcap", "MCAP", "record", "truncated", "offset"])
        c.cwd = cd
        self.add(c)
        # bench --joint on a directory with a file named twice (a link).
        cd = self.casedir(cls, "bench_joint_with_link")
        os.makedirs(os.path.join(cd, "D"))
        for i in (1, 2, 3):
            shutil.copy(self.d("data_campaign", f"release_{i:02d}.csv"), os.path.join(cd, "D"))
        os.symlink("release_01.csv", os.path.join(cd, "D", "link.csv"))
        c = Case(cls, "bench_joint_with_link", ["{A}", "bench", "--joint", "D", "--rig", rig, "--counts", "2,3",
                                                "--batches", "1"], expect="any")
        c.cwd = cd
        self.add(c)

    # ------------------------------------------------------------------------------------
    def build(self, only):
        for k in range(1, 11):
            if only and k not in only:
                continue
            getattr(self, f"class{k}")()


GNU_TIME = shutil.which("time", path="/usr/bin:/bin") if os.path.exists("/usr/bin/time") else None


def child_of(pid):
    """The first child process of pid (the command under GNU time), or None."""
    try:
        kids = open(f"/proc/{pid}/task/{pid}/children").read().split()
        if kids:
            return int(kids[0])
    except OSError:
        pass
    for d in os.listdir("/proc"):
        if d.isdigit():
            try:
                fields = open(f"/proc/{d}/stat").read().rsplit(")", 1)[1].split()
                if int(fields[1]) == pid:
                    return int(d)
            except (OSError, IndexError, ValueError):
                continue
    return None


def command_line(res):
    return f"cd {shlex.quote(res['cwd'])} && " + shlex.join(res["argv"]) + {
        "devfull_stdout": " > /dev/full", "devfull_stderr": " 2> /dev/full",
        "closed_pipe": " | (exec 0<&-)  # stdout's reader already closed", "head1": " | head -1",
        "pipe": " | cat", "plain": ""}[res["case"].mode] + (
        f"  # RLIMIT_FSIZE={res['case'].fsize}" if res["case"].fsize else "") + (
        f"  # signal {res['case'].sig} after {res['case'].sig_delay} s" if res["case"].sig else "")


def run_cases(sw, out, t_start):
    """Run every case of sw in order, writing the TSV to out and the summary to stderr;
    returns (results, total wall seconds since t_start). Shared by the other attack sweeps."""
    data_before = snapshot([sw.D])
    results = []
    cols = ["class", "case", "verdict", "exit", "wall_s", "peak_rss_mib", "panic", "input_changed", "leftovers",
            "names_file", "names_field", "expect", "reason", "notes", "command", "stderr_head"]
    with open(out, "w") as tsv:
        tsv.write("\t".join(cols) + "\n")
        for i, c in enumerate(sw.cases):
            # TMPDIR is per sweep; empty it of anything a previous case left (recorded there).
            res = sw.execute(c)
            for n in os.listdir(sw.TMP):
                p = os.path.join(sw.TMP, n)
                shutil.rmtree(p) if os.path.isdir(p) and not os.path.islink(p) else os.remove(p)
            results.append(res)
            head = " | ".join(res["stderr"].strip().splitlines()[:3])[:400]
            fmt = lambda b: "" if b is None else ("yes" if b else "no")
            row = [str(c.cls), c.name, res["verdict"], str(res["rc"]), f"{res['wall']:.3f}",
                   f"{res['rss_kib'] / 1024:.1f}", fmt(res["panic"]), ";".join(res["input_changed"]),
                   ";".join(res["leftovers"]), fmt(res["names_file"]), fmt(res["names_field"]), c.expect,
                   res["reason"], res["notes"], command_line(res), head]
            tsv.write("\t".join(x.replace("\t", " ").replace("\n", " ") for x in row) + "\n")
            tsv.flush()
            print(f"[{i + 1}/{len(sw.cases)}] c{c.cls} {c.name}: {res['verdict']} exit {res['rc']} "
                  f"{res['wall']:.2f}s {res['rss_kib'] / 1024:.0f}MiB {res['reason']}", file=sys.stderr)
    data_after = snapshot([sw.D])
    changed = [p for p in data_before if data_before[p] != data_after.get(p)]
    if changed:
        print("SHARED INPUTS CHANGED: " + ", ".join(changed), file=sys.stderr)
    total = time.monotonic() - t_start
    n_pass = sum(r["verdict"] == "PASS" for r in results)
    print(f"\n{len(results)} cases, {n_pass} pass, {len(results) - n_pass} fail/timeout, {total:.0f} s", file=sys.stderr)
    for r in results:
        if r["verdict"] != "PASS":
            print(f"\n{r['verdict']} c{r['case'].cls} {r['case'].name}: exit {r['rc']}, {r['wall']:.2f} s: {r['reason']}\n"
                  f"  $ {command_line(r)}\n  " + "\n  ".join(r["stderr"].strip().splitlines()[:4]), file=sys.stderr)
    return results, total


def write_md(path, results, total, titles, title, command):
    """The per-class summary (Markdown) of results: classes in the order of titles."""
    n_pass = sum(r["verdict"] == "PASS" for r in results)
    lines = [title, "",
             command,
             f"({len(results)} cases, {n_pass} pass, {total:.0f} s wall for the whole sweep incl. setup).", "",
             "Acceptance per case: exit 0 with a correct result, 1 with a reason, or 2 naming the file and "
             "field, within 20 s and 4 GiB peak RSS; no input changed; no partial output; no panic text.", "",
             "| class | what it covers | cases | pass | median wall s | max wall s | max RSS MiB |",
             "|---|---|---|---|---|---|---|"]
    for k in titles:
        rs = [r for r in results if r["case"].cls == k]
        if not rs:
            continue
        walls = [r["wall"] for r in rs]
        lines.append(f"| {k} | {titles[k]} | {len(rs)} | {sum(r['verdict'] == 'PASS' for r in rs)} | "
                     f"{statistics.median(walls):.3f} | {max(walls):.2f} | "
                     f"{max(r['rss_kib'] for r in rs) / 1024:.0f} |")
    fails = [r for r in results if r["verdict"] != "PASS"]
    lines += ["", "## Not passing", ""]
    if not fails:
        lines.append("None.")
    for r in fails:
        lines.append(f"- **{r['verdict']}** class {r['case'].cls} `{r['case'].name}`: exit {r['rc']}, "
                     f"{r['wall']:.2f} s; {r['reason']}  ")
        lines.append(f"  `{command_line(r)}`")
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--appell", required=True)
    ap.add_argument("--out", required=True, help="TSV of every case")
    ap.add_argument("--workdir", required=True)
    ap.add_argument("--md", help="also write the per-class summary (Markdown) here")
    ap.add_argument("--only", help="comma-separated classes (1-10)")
    ap.add_argument("--timeout", type=float, default=60.0)
    ap.add_argument("--list", action="store_true", help="build the cases, print them, run nothing")
    # The repository root: this script is in scripts/sweeps/.
    ap.add_argument("--repo", default=os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
    args = ap.parse_args()
    global GNU_TIME
    if GNU_TIME and subprocess.run([GNU_TIME, "-f", "%M", "-o", os.devnull, "true"],
                                   capture_output=True).returncode != 0:
        GNU_TIME = None  # not GNU time: wait4's figure (a floor of this process's RSS) is used
    only = {int(x) for x in args.only.split(",")} if args.only else None
    os.makedirs(args.workdir, exist_ok=True)
    sw = Sweep(args.appell, args.workdir, args.repo, args.timeout)
    t_start = time.monotonic()
    sw.prepare_data()
    sw.build(only)
    print(f"{len(sw.cases)} cases", file=sys.stderr)
    if args.list:
        for c in sw.cases:
            print(f"{c.cls}\t{c.name}\t{c.expect}\t{shlex.join(c.argv)}")
        return 0
    results, total = run_cases(sw, args.out, t_start)
    if args.md:
        write_md(args.md, results, total, CLASS_TITLES, "# attack_sweep.py: issue 35 input-safety sweep",
                 f"`python3 scripts/sweeps/attack_sweep.py --appell {args.appell} --out {args.out} --workdir {args.workdir}`")
    return 0


if __name__ == "__main__":
    sys.exit(main())
