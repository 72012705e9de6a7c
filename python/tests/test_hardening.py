"""No value crashes, hangs or fools a call (issue 59, classes M to Q): bad input is a
ValueError or TypeError naming the argument and the fix, quickly; Ctrl-C stops a fit."""

import os
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest

import appell

RELEASE = "data/campaign/release_01.csv"
RIG = "data/campaign/rig_measured.toml"


def _columns():
    """release_01's columns: t, slider (n, 2), bob (n, 2)."""
    data = np.genfromtxt(RELEASE, delimiter=",", names=True)
    return (
        data["t"],
        np.column_stack([data["slider_x"], data["slider_y"]]),
        np.column_stack([data["bob_x"], data["bob_y"]]),
    )


def _write(path, t, slider, bob, time_format="%.6g"):
    rows = np.column_stack([t, slider, bob])
    np.savetxt(path, rows, delimiter=",", header="t,slider_x,slider_y,bob_x,bob_y",
               comments="", fmt=[time_format] + ["%.9g"] * 4)


def _refused(call, within=5.0):
    """The ValueError `call` raises, and that it came at once."""
    started = time.monotonic()
    with pytest.raises(ValueError) as e:
        call()
    assert time.monotonic() - started < within
    return str(e.value)


# Class M: arrays pass the checks a file passes.
@pytest.mark.parametrize(
    "name, change, words",
    [
        ("x10", lambda t, s, b: (t, 10 * s, 10 * b), ["rod_length", "median slider-bob"]),
        ("x1e4", lambda t, s, b: (t, 1e4 * s, 1e4 * b), ["rod_length", "median slider-bob"]),
        ("swapped", lambda t, s, b: (t, b, s), ["swapped", "Recording(t, bob, slider)"]),
        ("upside", lambda t, s, b: (t, s * [1, -1], b * [1, -1]), ["upside down", "y"]),
        ("ms", lambda t, s, b: ((1000 * t).round().astype(np.int64), s, b), ["milliseconds"]),
    ],
)
def test_arrays_are_checked_as_the_file_is(tmp_path, name, change, words):
    t, s, b = change(*_columns())
    path = tmp_path / f"{name}.csv"
    _write(path, t, s, b, "%d" if t.dtype.kind == "i" else "%.6g")
    from_file = _refused(lambda: appell.fit(str(path), RIG))
    from_arrays = _refused(lambda: appell.fit(appell.Recording(t, s, b), RIG))
    for word in words:
        assert word in from_arrays, from_arrays
    # The file's message names the file's fix, the arrays' the arrays'.
    assert str(path) in from_file and "Recording" in from_arrays


# Class N: a recording larger than any reader keeps is refused before it is copied.
def test_a_recording_beyond_the_frame_bound_is_refused_without_copying():
    n = 30_000_000
    t = np.broadcast_to(np.float64(0.0), (n,))  # views: no memory behind them
    xy = np.broadcast_to(np.float64(0.0), (n, 2))
    message = _refused(lambda: appell.Recording(t, xy, xy), within=2.0)
    assert "frames" in message and "30000000" in message
    rec = appell.Recording(*_columns())
    message = _refused(lambda: setattr(rec, "t", t), within=2.0)
    assert "t" in message and "frames" in message


# Class O: Ctrl-C stops a fit between its steps.
SLOW_FIT = textwrap.dedent(
    """
    import sys, time, appell
    rec = appell.synth("configs/paper_rest_horizontal.toml", fps=20000, noise=2e-4, seed=1)
    print("fitting", flush=True)
    started = time.monotonic()
    try:
        appell.fit(rec, "configs/rig_paper.toml", friction="stribeck",
                   with_=["rail_tilt", "marker_lag", "pivot_damping"])
    except KeyboardInterrupt:
        print("interrupted", flush=True)
        sys.exit(0)
    print("finished after", time.monotonic() - started, flush=True)
    """
)


def test_ctrl_c_interrupts_a_fit(root):
    p = subprocess.Popen(
        [sys.executable, "-c", SLOW_FIT], cwd=root, stdout=subprocess.PIPE, text=True
    )
    try:
        assert p.stdout.readline().strip() == "fitting"
        time.sleep(1.0)  # well inside the fit (17 s uninterrupted, 2026-12-06)
        sent = time.monotonic()
        p.send_signal(signal.SIGINT)
        out, _ = p.communicate(timeout=60)
        latency = time.monotonic() - sent
    finally:
        if p.poll() is None:
            p.kill()
    assert out.strip() == "interrupted" and p.returncode == 0, out
    assert latency < 3.0, latency


# Class P: shapes and dtypes checked where arrays cross, at construction and at use.
def test_a_track_of_the_wrong_shape_names_the_argument_and_the_shape():
    t, s, b = _columns()
    message = str(pytest.raises(ValueError, appell.Recording, t, s.T, b).value)
    assert "slider" in message and "(n, 2)" in message and "slider.T" in message
    message = str(pytest.raises(ValueError, appell.Recording, t, s, b[:-1]).value)
    assert "bob" in message and str(len(t)) in message
    message = str(pytest.raises(ValueError, appell.Recording, np.column_stack([t, t]), s, b).value)
    assert message.startswith("t:") and "(n,)" in message
    for bad in (np.full(s.shape, "left", dtype=object), s.astype(complex), s > 0):
        message = str(pytest.raises(TypeError, appell.Recording, t, bad, b).value)
        assert message.startswith("slider:") and "dtype" in message


def test_arrays_assigned_after_construction_are_converted_or_refused():
    t, s, b = _columns()
    expected = appell.fit(appell.Recording(t, s, b), RIG, no_profile=True).mu
    rec = appell.Recording(t, s, b)
    rec.slider = s.tolist()  # a list
    rec.bob = b.astype(np.float64)
    rec.t = list(t)
    assert appell.fit(rec, RIG, no_profile=True).mu == expected
    rec.bob = b.astype(np.float32)  # read as its values, not its bytes
    assert abs(appell.fit(rec, RIG, no_profile=True).mu - expected) < 1e-3
    with pytest.raises(ValueError, match="slider"):
        rec.slider = s.T
    rec = appell.Recording(t, s, b)
    rec.__dict__["_bob"] = b[:-5]  # behind the property's back: still checked at use
    with pytest.raises(ValueError, match="bob"):
        appell.fit(rec, RIG)


# Class Q: paths as bytes or os.PathLike, a client as an address, and a TypeError otherwise.
def test_paths_may_be_bytes_or_pathlike(tmp_path):
    import pathlib

    expected = appell.fit(RELEASE, RIG, no_profile=True).mu
    assert appell.fit(os.fsencode(RELEASE), os.fsencode(RIG), no_profile=True).mu == expected
    assert appell.fit(pathlib.Path(RELEASE), pathlib.Path(RIG), no_profile=True).mu == expected
    assert len(appell.read_recording(os.fsencode(RELEASE))) == 2001
    appell.fit(RELEASE, RIG, no_profile=True).plot(os.fsencode(str(tmp_path / "fit.svg")))
    assert (tmp_path / "fit.svg").exists()
    for call in (
        lambda: appell.fit(42, RIG),
        lambda: appell.fit(RELEASE, 42),
        lambda: appell.read_recording(None),
    ):
        message = str(pytest.raises(TypeError, call).value)
        assert "path" in message and "int" in message or "NoneType" in message, message


def test_fit_many_takes_a_scheduler_address():
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(
        n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None
    ) as cluster:
        table = appell.fit_many([RELEASE], RIG, client=cluster.scheduler_address,
                                no_profile=True, as_pandas=False)
    assert table[0]["mu_kinetic"] == appell.fit(RELEASE, RIG, no_profile=True).mu
    message = str(pytest.raises(TypeError, appell.fit_many, [RELEASE], RIG, client=42).value)
    assert "client" in message and "Client" in message
