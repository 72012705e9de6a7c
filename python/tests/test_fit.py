"""Fits from Python against the command line: the same numbers to the last digit, the same
errors, and the arrays path equal to the file path."""

import json

import numpy as np
import pytest

import appell

EXAMPLE = ("data/example_recording.mcap", "configs/rig_example.toml")
SHOWCASE_DLC = "tests/data/showcase/showcase_dlc.csv"
SHOWCASE_RIG = "tests/data/showcase/showcase_rig.toml"
DLC_OPTS = {"fps": 100, "rod_length": 0.251, "rail_frame": True}


def test_fit_to_dict_is_the_cli_json(cli_json):
    result = appell.fit(*EXAMPLE)
    assert result.to_dict() == cli_json("fit", EXAMPLE[0], "--rig", EXAMPLE[1])
    # The properties read the same JSON: a value inside its own interval, from the table.
    lo, hi = result.interval
    assert lo < result.mu < hi
    assert result.answer.startswith("mu_kinetic = ")
    assert result.parameters["mu_kinetic"]["value"] == result.mu


def test_fit_with_reading_and_fit_options_is_the_cli_json(cli_json):
    result = appell.fit(SHOWCASE_DLC, SHOWCASE_RIG, no_profile=True, robust="huber", **DLC_OPTS)
    expected = cli_json(
        "fit", SHOWCASE_DLC, "--rig", SHOWCASE_RIG, "--no-profile", "--robust", "huber",
        "--fps", "100", "--rod-length", "0.251", "--rail-frame",
    )
    assert result.to_dict() == expected


def test_report_is_the_cli_text(cli):
    code, out, _ = cli("fit", EXAMPLE[0], "--rig", EXAMPLE[1])
    assert code == 0
    assert appell.fit(*EXAMPLE).report() == out


def test_arrays_fit_as_the_file_does():
    rec = appell.read_recording(EXAMPLE[0])
    from_file = appell.fit(*EXAMPLE).to_dict()
    from_arrays = appell.fit(rec, appell.Rig.from_toml(EXAMPLE[1])).to_dict()
    # Only the provenance differs: arrays were not read from a file.
    assert from_arrays["inputs"] == []
    for key in ("inputs",):
        from_file.pop(key), from_arrays.pop(key)
    assert from_arrays == from_file


def test_rig_from_keys_fits_as_its_file(tmp_path):
    keys = dict(slider_mass=0.30, bob_mass=0.15, rod_length=0.251, rod_length_sd=0.001)
    text = "[rig]\n" + "".join(f"{k} = {v}\n" for k, v in keys.items())
    (tmp_path / "rig.toml").write_text(text)
    a = appell.fit(SHOWCASE_DLC, appell.Rig(**keys), no_profile=True, **DLC_OPTS).to_dict()
    b = appell.fit(SHOWCASE_DLC, tmp_path / "rig.toml", no_profile=True, **DLC_OPTS).to_dict()
    a.pop("rig_file"), b.pop("rig_file")
    # Notes name the rig by its label; the numbers are the same.
    assert a["mu_kinetic"] == b["mu_kinetic"] and a["parameters"] == b["parameters"]


def test_bad_input_is_a_value_error_with_the_cli_message(cli, tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("t,slider_x,slider_y,bob_x,bob_y\n0,0,0,0.3,zero\n")
    code, _, err = cli("fit", bad, "--rig", EXAMPLE[1])
    assert code == 2
    with pytest.raises(ValueError) as e:
        appell.fit(bad, EXAMPLE[1])
    # The CLI prints "error: MESSAGE" and its causes; Python joins the same messages.
    first = err.splitlines()[0].removeprefix("error: ")
    assert str(e.value).startswith(first)
    with pytest.raises(ValueError, match="--mu-static must be one of auto, tied, fixed"):
        appell.fit(*EXAMPLE, mu_static="sometimes")
    with pytest.raises(ValueError, match="--fps must be a finite number > 0"):
        appell.fit(SHOWCASE_DLC, SHOWCASE_RIG, fps=-1)
    with pytest.raises(ValueError, match="with: \"tilt\""):
        appell.fit(*EXAMPLE, with_=["tilt"])
    with pytest.raises(TypeError, match="unexpected keyword argument 'fsp'"):
        appell.fit(SHOWCASE_DLC, SHOWCASE_RIG, fsp=100)
    with pytest.raises(ValueError, match="bob_mass"):
        appell.Rig(slider_mass=0.3, bob_mass=-1.0, rod_length=0.25)
    with pytest.raises(ValueError, match="t, slider and bob"):
        appell.Recording([0.0, 0.1], [[0, 0]], [[0.3, 0], [0.3, 0]])


def test_html_shows_the_answer_the_table_and_the_figure():
    import base64
    import re

    page = appell.fit(*EXAMPLE, no_profile=True)._repr_html_()
    assert "mu_kinetic = " in page and "<table>" in page
    # The figure is the SVG, as an image that shrinks to the notebook's width.
    data = re.search(r"src='data:image/svg\+xml;base64,([^']+)'", page).group(1)
    assert base64.b64decode(data).decode().startswith("<svg")
    assert "max-width:100%" in page


def test_figures_are_written_and_never_over_an_input(tmp_path):
    result = appell.fit(*EXAMPLE, no_profile=True)
    result.plot(tmp_path / "fit.svg")
    result.friction_plot(tmp_path / "friction.png")
    assert (tmp_path / "fit.svg").read_text().startswith("<svg")
    assert (tmp_path / "friction.png").read_bytes()[:4] == b"\x89PNG"
    with pytest.raises(ValueError):
        result.plot(EXAMPLE[0])


def test_read_recording_is_what_convert_writes(cli, tmp_path):
    out = tmp_path / "out.csv"
    code, _, err = cli("convert", SHOWCASE_DLC, out, "--fps", "100", "--rod-length", "0.251", "--rail-frame")
    assert code == 0, err
    table = np.genfromtxt(out, delimiter=",", names=True)
    rec = appell.read_recording(SHOWCASE_DLC, **DLC_OPTS)
    assert rec.metadata["format"] == "dlc"
    np.testing.assert_array_equal(rec.t, table["t"])
    np.testing.assert_array_equal(rec.slider[:, 0], table["slider_x"])
    np.testing.assert_array_equal(rec.bob[:, 1], table["bob_y"])
    df = rec.to_pandas()
    assert list(df.columns) == ["t", "slider_x", "slider_y", "bob_x", "bob_y"]


def test_joint_fit_is_the_cli_json(cli_json):
    rig = "data/campaign/rig_measured.toml"
    joint = appell.fit_joint("data/campaign", rig)
    assert joint.to_dict() == cli_json("fit", "data/campaign", "--joint", "--rig", rig)
    assert joint.failed is None and len(joint.releases) == 6


def test_inspect_is_the_cli(cli_json, cli):
    ins = appell.inspect(SHOWCASE_DLC)
    assert ins.to_dict() == cli_json("inspect", SHOWCASE_DLC)
    code, out, _ = cli("inspect", SHOWCASE_DLC)
    assert code == 0 and ins.report() == out
    with pytest.raises(ValueError, match="nope.csv"):
        appell.inspect("nope.csv")
