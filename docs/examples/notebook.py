# ---
# jupyter:
#   jupytext:
#     formats: py:percent
#   kernelspec:
#     display_name: Python 3
#     language: python
#     name: python3
# ---

# %% [markdown]
# # A lab's friction campaign with `appell`, from Python
#
# A pendulum hangs from a slider on a rough rail (the Painleve-Appell rig). From films of its
# releases, `appell` fits the rail's dry friction coefficient mu with an honest interval.
# This notebook tells one lab's story:
#
# 1. one release filmed and tracked with DeepLabCut: read the file, look at it, fit mu;
# 2. six releases of another rig fitted together (`fit_joint`): one mu and one rail tilt;
# 3. the next release to film, planned from what the joint fit already knows (`plan`);
# 4. the same six releases fitted one by one into a table (`fit_many`).
#
# It is a plain script in jupytext's "percent" format: open it as a notebook in Jupyter or
# VS Code, or run it from the repository's root with
#
#     python docs/examples/notebook.py [OUTDIR]
#
# The figures go to OUTDIR (default: a fresh temporary directory). The last cell checks the
# answers against the truth the test data were made with, so a run that fails there means
# the science broke.

# %%
import json
import os
import sys
import tempfile
from pathlib import Path

import appell

try:
    import pandas as pd

    pd.set_option("display.width", 120)
    pd.set_option("display.max_columns", 20)
    pd.set_option("display.float_format", "{:.6g}".format)
except ImportError:  # pandas is optional: tables are then printed as plain text
    pd = None


def repository_root() -> Path:
    """The checkout this notebook lives in (the data paths below are relative to it)."""
    here = Path(__file__).resolve().parent if "__file__" in globals() else Path.cwd()
    for d in (here, *here.parents):
        if (d / "data" / "campaign").is_dir() and (d / "tests" / "data" / "showcase").is_dir():
            return d
    raise SystemExit("run this from inside the appell repository")


# OUTDIR from the command line; under Jupyter, sys.argv is the kernel's, so it is not used.
args = sys.argv[1:] if Path(sys.argv[0]).name == "notebook.py" else []
OUTDIR = Path(args[0]).resolve() if args else Path(tempfile.mkdtemp(prefix="appell-notebook-"))
OUTDIR.mkdir(parents=True, exist_ok=True)
os.chdir(repository_root())  # paths as the CLI examples write them
print(f"appell {appell.__version__}; figures go to {OUTDIR}")

figures = []


def show(rows, columns):
    """A table: a DataFrame when pandas is installed (the notebook renders it), else text."""
    if pd is not None:
        table = pd.DataFrame(rows, columns=columns)
        print(table.to_string(index=False))
        return table
    cells = [list(columns)] + [[f"{v:.6g}" if isinstance(v, float) else str(v) for v in r] for r in rows]
    widths = [max(len(r[i]) for r in cells) for i in range(len(columns))]
    for r in cells:
        print("  ".join(v.rjust(w) for v, w in zip(r, widths)))
    return None


# %% [markdown]
# ## 1. One release, tracked with DeepLabCut
#
# `tests/data/showcase/showcase_dlc.csv` is a DeepLabCut CSV: pixels, y down, a camera rolled a
# little from the rail, and no time column. `appell inspect` on it suggests what it needs:
# the frame rate (`fps=100`), a length to set the scale (`rod_length=0.251`, the rod as the
# lab measured it) and `rail_frame=True` (turn the picture so that the slider's track is the
# x axis). The keyword arguments are the CLI's flags (`--fps 100 --rod-length 0.251
# --rail-frame`).

# %%
DLC = "tests/data/showcase/showcase_dlc.csv"
DLC_RIG = "tests/data/showcase/showcase_rig.toml"
DLC_OPTIONS = dict(fps=100, rod_length=0.251, rail_frame=True)

recording = appell.read_recording(DLC, **DLC_OPTIONS)
print(recording)
print(f"scale: {recording.metadata['scale']:.6g} m per pixel, {recording.metadata['scale_source']}")
for note in recording.metadata["notes"]:
    print("note:", note)
if pd is not None:
    print(recording.to_pandas().head())

# %% [markdown]
# The rig file gives what the lab measured (masses on a kitchen scale, the rod with a ruler)
# with their uncertainties; mu is the unknown. `appell.fit` reads the file with the same
# options and fits.

# %%
dlc = appell.fit(DLC, DLC_RIG, **DLC_OPTIONS)
print(dlc.answer)
for w in dlc.warnings:
    print("warning:", w)
dlc_table = show(
    [
        [name, p["value"], p.get("stderr"), *(p.get("ci95") or [None, None]), p.get("unit", "")]
        for name, p in dlc.parameters.items()
    ],
    ["parameter", "value", "stderr", "95 % low", "95 % high", "unit"],
)
print("models compared:", ", ".join(m["name"] for m in dlc.models if "name" in m) or len(dlc.models))
dlc.plot(OUTDIR / "fit_dlc.svg")
dlc.friction_plot(OUTDIR / "friction_dlc.svg")
figures += [OUTDIR / "fit_dlc.svg", OUTDIR / "friction_dlc.svg"]

# %% [markdown]
# In Jupyter, `dlc` alone in a cell shows the answer, the parameters with their units, the
# report (folded) and the figure inline (run as a script, the cell below does nothing). `dlc.report()` is the
# text `appell fit` prints; `dlc.to_dict()` is its `--json`.

# %%
dlc

# %% [markdown]
# ## 2. A campaign: six releases of one rig, fitted together
#
# `data/campaign` holds six releases of another rig (a rod with mass and a ball bob) on one
# rail, each pushed differently. Fitted jointly, they share mu, the rail's tilt and the
# pendulum; each release keeps its own initial state. This is `appell fit data/campaign
# --joint --rig data/campaign/rig_measured.toml`.

# %%
CAMPAIGN = "data/campaign"
CAMPAIGN_RIG = "data/campaign/rig_measured.toml"

joint = appell.fit_joint(CAMPAIGN, CAMPAIGN_RIG)
print(joint.answer)
print(joint.to_dict()["sentence"])
shared = joint.parameters  # the values every release shares, mu_kinetic first
show(
    [[name, p["value"], p["stderr"], *p["ci95"], p.get("unit", "")] for name, p in shared.items()],
    ["shared parameter", "value", "stderr", "95 % low", "95 % high", "unit"],
)
print(f"rail tilt: {shared['rail_tilt']['value'] * 180 / 3.141592653589793:.4f} deg")
show(
    [
        [
            Path(r["name"]).name,
            r["transitions"],
            r["own_mu"]["value"],
            r["own_mu"]["stderr"],
            round(r["z"], 2),
            r["agrees"],
            r["single_mu"]["value"],
        ]
        for r in joint.releases
    ],
    ["release", "transitions", "own mu", "stderr", "z", "agrees", "alone: mu"],
)
joint.plot(OUTDIR / "joint_campaign.svg")
figures.append(OUTDIR / "joint_campaign.svg")
joint  # in Jupyter: the answer, the shared values and the releases as tables, the report, the figure

# %% [markdown]
# "own mu" is each release's mu inside the joint fit (the tilt and pendulum shared), "z" how
# far it is from the joint value in its standard errors; "alone" is the release fitted on
# its own, with only what it can tell by itself. The releases with one slide (03, 05) say
# little about mu; the joint fit does not need them to.

# %% [markdown]
# ## 3. The next release
#
# `configs/plan_campaign.toml` plans a release of exactly this campaign's rig (its `[rig]`
# is `data/campaign/rig_measured.toml`'s, checked below): the same 1 kHz camera, a push
# either way, and the goal of a slide that comes to a stop. Given `after=joint`, the plan
# starts from what the campaign already knows (its mu, tilt and covariance) and ranks
# releases by how much each would shrink mu's standard error.

# %%
try:
    import tomllib
except ImportError:  # Python < 3.11: the [rig] tables here are plain "key = number" lines
    tomllib = None


def rig_table(path):
    text = Path(path).read_text()
    if tomllib is not None:
        return tomllib.loads(text)["rig"]
    rig, section = {}, None
    for line in text.splitlines():
        line = line.split("#")[0].strip()
        if line.startswith("["):
            section = line.strip("[]")
        elif "=" in line and section == "rig":
            key, value = (s.strip() for s in line.split("=", 1))
            rig[key] = float(value)
    return rig


PLAN = "configs/plan_campaign.toml"
assert rig_table(PLAN) == rig_table(CAMPAIGN_RIG), f"{PLAN}'s [rig] is not the campaign's"
print(f"{PLAN}: [rig] is the campaign's ({CAMPAIGN_RIG})")

next_release = appell.plan(PLAN, after=joint, plot=OUTDIR / "plan_next.svg")
plan_dict = next_release.to_dict()
print("feasible:", plan_dict["feasible"], "; targets:", ", ".join(map(str, plan_dict["targets"])))
proposals = next_release.proposals  # ranked, best first
show(
    [
        [
            p["rank"],
            round(p["theta_deg"], 2),
            round(p["initial"]["theta_dot"], 3),
            round(p["initial"]["x_dot"], 4),
            round(p["robustness"], 3),
            p["predicted_mu_stderr"],
            round(p["shrinks_mu_stderr_by"], 2),
        ]
        for p in proposals
    ],
    ["rank", "theta [deg]", "theta' [rad/s]", "x' [m/s]", "robustness", "stderr(mu)", "shrinks by"],
)
top = proposals[0]
print(
    f"top candidate: release the rod at {top['theta_deg']:.1f} deg (90 = hanging), "
    f"theta' = {top['initial']['theta_dot']:+.2f} rad/s, push the slider at "
    f"{top['initial']['x_dot']:+.3f} m/s: mu's standard error "
    f"{top['prior_mu_stderr']:.3g} -> {top['predicted_mu_stderr']:.3g} "
    f"(robustness >= {top['robustness']:.3f})"
)

figures.append(OUTDIR / "plan_next.svg")
next_release  # in Jupyter: the report and the figure

# %% [markdown]
# `next_release.report()` is `appell plan`'s text, with every proposal's timeline of
# transitions and its margins to the rail's ends and the camera's field of view.

# %% [markdown]
# ## 4. Each release on its own, as a table
#
# `fit_many` fits recordings independently and gathers one row per recording (a recording
# that cannot be fitted is a row with its error, never an exception). Without a Dask client
# it fits them here, one after another; with `client=Client(...)` each is a task on the
# cluster (see docs/python.md).

# %%
releases = sorted(str(p) for p in Path(CAMPAIGN).glob("release_*.csv"))
singles = appell.fit_many(releases, CAMPAIGN_RIG)
rows = singles.to_dict("records") if pd is not None else singles
show(
    [
        [Path(r["recording"]).name, r["mu_kinetic"], r["stderr"], r["ci95_low"], r["ci95_high"],
         r["limited_by_model"] or "adequate", r["error"] or ""]
        for r in rows
    ],
    ["recording", "mu_kinetic", "stderr", "95 % low", "95 % high", "model", "error"],
)

# %% [markdown]
# ## The figures, and a check of the science
#
# The test data were made by independent generators with a known truth:
# `tests/data/showcase/truth.json` (mu = 0.18) and `data/campaign/truth.json` (mu = 0.25, the
# rail tilted 0.5 deg). If these checks fail, the fit no longer finds what is there.

# %%
print(f"figures in {OUTDIR}:")
for f in figures:
    print(f"  {f.name} ({f.stat().st_size} bytes)")

showcase_truth = json.loads(Path("tests/data/showcase/truth.json").read_text())["rig"]["mu_kinetic"]
campaign_truth = json.loads(Path("data/campaign/truth.json").read_text())
lo, hi = dlc.interval
assert lo <= showcase_truth <= hi, f"DeepLabCut fit: {dlc.answer}; truth {showcase_truth}"
assert dlc.limited_by_model is None, dlc.answer
lo, hi = joint.interval
assert joint.failed is None and lo <= campaign_truth["mu_kinetic"] <= hi, joint.answer
tilt = shared["rail_tilt"]
assert tilt["ci95"][0] <= campaign_truth["tilt_rad"] <= tilt["ci95"][1], tilt
assert plan_dict["feasible"] and top["predicted_mu_stderr"] < joint.stderr, top
for r in rows:
    assert not r["error"], r["error"]
    assert abs(r["mu_kinetic"] - campaign_truth["mu_kinetic"]) < 4 * r["stderr"], r["answer"]
print(
    f"checks passed: DeepLabCut mu {dlc.mu:.5f} (truth {showcase_truth}), "
    f"joint mu {joint.mu:.6f} and tilt within their intervals (truth {campaign_truth['mu_kinetic']}, "
    f"{campaign_truth['tilt_deg']} deg), the plan shrinks mu's error, "
    f"{len(rows)} single fits within 4 standard errors"
)
