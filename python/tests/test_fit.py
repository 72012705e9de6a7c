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


def _html_table(page, first_header):
    """The rows of the HTML table whose first header cell is `first_header`, as lists of cells."""
    import re

    for table in re.findall(r"<table>(.*?)</table>", page, flags=re.S):
        rows = re.findall(r"<tr>(.*?)</tr>", table, flags=re.S)
        cells = [re.findall(r"<t[hd]>(.*?)</t[hd]>", r, flags=re.S) for r in rows]
        if cells and cells[0][0] == first_header:
            return cells
    raise AssertionError(f"no table headed {first_header!r}")


def test_html_table_has_each_parameters_unit():
    result = appell.fit(*EXAMPLE, no_profile=True)
    rows = _html_table(result._repr_html_(), "parameter")
    assert rows[0] == ["parameter", "value", "stderr", "95 %", "unit"]
    by_name = {r[0]: r for r in rows[1:]}
    # Every fitted value is a row, with the unit the JSON gives it (none: dimensionless).
    values = {k: p for k, p in result.parameters.items() if "value" in p}
    assert set(by_name) == set(values)
    for name, p in values.items():
        assert by_name[name][4] == (p.get("unit") or appell.NO_UNIT)
    assert by_name["rod_length"][4] == "m" and by_name["theta"][4] == "rad"


def test_joint_html_shows_the_shared_values_and_the_releases():
    joint = appell.fit_joint("data/campaign", "data/campaign/rig_measured.toml", no_profile=True)
    page = joint._repr_html_()
    shared = _html_table(page, "parameter")
    names = [r[0] for r in shared[1:]]
    assert names[0] == "mu_kinetic" and set(names) == set(joint.to_dict()["shared"])
    units = {r[0]: r[4] for r in shared[1:]}
    assert units["rail_tilt"] == "rad" and units["mu_kinetic"] == appell.NO_UNIT
    # The table's mu is the headline's, to the digits of its error.
    assert float(shared[1][1]) == pytest.approx(joint.mu, abs=joint.stderr)
    releases = _html_table(page, "release")
    assert [r[0] for r in releases[1:]] == [r["name"] for r in joint.releases]
    # The tables come before the folded report.
    assert page.index("<th>release</th>") < page.index("<details>")


def test_fps_given_to_a_file_with_times_is_said_not_used():
    timed = "data/campaign/release_01.csv"  # a wide CSV with a time column
    with pytest.warns(UserWarning, match=r"fps=100 is not used: data/campaign/release_01\.csv holds its own frame times"):
        result = appell.fit(timed, "data/campaign/rig_measured.toml", fps=100, plain=True, no_profile=True)
    assert any("fps=100 is not used" in n for n in result.notes)
    # The fit is the one without fps: the file's times were read.
    plain = appell.fit(timed, "data/campaign/rig_measured.toml", plain=True, no_profile=True)
    assert result.to_dict()["mu_kinetic"] == plain.to_dict()["mu_kinetic"]
    with pytest.warns(UserWarning, match="fps=100 is not used"):
        appell.read_recording(timed, fps=100)


def test_fps_used_by_the_file_gives_no_warning():
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        result = appell.fit(SHOWCASE_DLC, SHOWCASE_RIG, no_profile=True, **DLC_OPTS)
        appell.read_recording(SHOWCASE_DLC, **DLC_OPTS)
    assert not any("is not used" in n for n in result.notes)
