"""simulate, synth, plan and regions from Python against the command line and physics."""

import numpy as np
import pytest

import appell


def test_simulate_is_the_cli_and_closes_the_energy_balance(cli_json, cli, tmp_path):
    scene = "configs/paradox_light_slider.toml"
    sim = appell.simulate(scene)
    # Python samples at 1000 Hz where the scene names no rate, as `--out` does.
    assert sim.to_dict() == cli_json("simulate", scene, "--out", tmp_path / "t.csv")
    table = np.genfromtxt(tmp_path / "t.csv", delimiter=",", names=True, dtype=None, encoding="utf-8")
    np.testing.assert_allclose(sim["theta"], table["theta"], rtol=1e-14, atol=1e-300)
    assert list(sim["mode"][:3]) == list(table["mode"][:3])
    # Physics, not our output: the slider marker is the cart's x, and the energy lost is the
    # friction and damping work at every sample, less the impulsive losses of jumps.
    np.testing.assert_allclose(sim["slider_x"], sim["x"], atol=1e-15)
    d = sim.to_dict()
    balance = sim["energy"] - sim["energy"][0] - sim["friction_work"] - sim["damping_work"]
    scale = np.nanmax(np.abs(sim["energy"]))
    assert d["impulsive_losses"] == 0.0
    assert np.nanmax(np.abs(balance)) < 1e-8 * scale
    assert abs(d["energy_change"] - d["friction_work"] - d["damping_work"]) < 1e-8 * scale
    assert d["friction_work"] < -0.1 * scale  # friction did work: the check is not vacuous

def test_synth_then_fit_recovers_the_known_mu(tmp_path):
    rec = appell.synth("configs/paper_rest_horizontal.toml", tmp_path / "s.csv", fps=500, noise=2e-4, seed=7)
    truth = rec.metadata["truth"]["mu_kinetic"]
    fitted = appell.fit(tmp_path / "s.csv", "configs/rig_paper.toml", no_profile=True)
    assert abs(fitted.mu - truth) < 3 * fitted.stderr
    # The arrays returned are the file written.
    again = appell.read_recording(tmp_path / "s.csv")
    np.testing.assert_array_equal(again.bob, rec.bob)


def test_plan_after_a_fit_is_the_cli(cli_json, tmp_path):
    rig = "data/campaign/rig_measured.toml"
    joint = appell.fit_joint("data/campaign", rig)
    (tmp_path / "fit.json").write_text(joint._inner.json())
    spec = "configs/plan_campaign.toml"
    from_result = appell.plan(spec, after=joint, plot=tmp_path / "plan.svg").to_dict()
    assert (tmp_path / "plan.svg").read_text().startswith("<svg")
    from_file = appell.plan(spec, after=tmp_path / "fit.json").to_dict()
    assert from_result == from_file == cli_json("plan", spec, "--after", tmp_path / "fit.json")
    assert from_result["proposals"]


def test_regions_are_the_cli(cli_json, tmp_path):
    r = appell.regions("configs/rig_paradox.toml", trajectories=3, duration=1.0, plot=tmp_path / "r.png")
    assert r.to_dict() == cli_json("regions", "configs/rig_paradox.toml", "--trajectories", "3", "--duration", "1")
    assert "<svg" in r.svg()
    assert (tmp_path / "r.png").read_bytes()[:4] == b"\x89PNG"
    with pytest.raises(ValueError, match="--trajectories must be at most 1000"):
        appell.regions("configs/rig_paradox.toml", trajectories=10**6)
    with pytest.raises(ValueError):
        appell.regions("configs/rig_paradox.toml", plot="configs/rig_paradox.toml")


def test_the_stubs_name_every_function_of_the_extension(root):
    import ast

    from appell import _appell

    tree = ast.parse((root / "python/appell/_appell.pyi").read_text())
    stubbed = {n.name for n in tree.body if isinstance(n, (ast.FunctionDef, ast.ClassDef))}
    public = {n for n in dir(_appell) if not n.startswith("_")}
    assert stubbed == public
