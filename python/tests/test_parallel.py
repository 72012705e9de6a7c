"""Threads and clusters: fits release the GIL, give the same numbers in parallel, and map
over a Dask cluster one task per recording."""

import glob
import threading
import time

import pytest

import appell

EXAMPLE = ("data/example_recording.mcap", "configs/rig_example.toml")


def test_a_fit_releases_the_gil():
    # While another thread fits, this one keeps running Python. Held, the GIL would stop it
    # for the whole fit (the Rust code never hands it over); released, it never waits long.
    window = {}

    def work():
        window["start"] = time.perf_counter()
        for _ in range(3):
            appell.fit(*EXAMPLE)
        window["end"] = time.perf_counter()

    ticks = []
    worker = threading.Thread(target=work)
    worker.start()
    while worker.is_alive():
        ticks.append(time.perf_counter())
    worker.join()
    inside = [t for t in ticks if window["start"] <= t <= window["end"]]
    span = window["end"] - window["start"]
    assert len(inside) > 2
    gaps = [b - a for a, b in zip(inside, inside[1:])]
    # Three fits of about 40 ms each: a held GIL leaves gaps of a whole fit.
    assert max(gaps) < span / 6, (max(gaps), span)


def test_threads_fit_the_same_numbers():
    files = sorted(glob.glob("data/campaign/release_0*.csv"))[:2]
    rig = "data/campaign/rig_measured.toml"
    alone = [appell.fit(f, rig, no_profile=True).to_dict() for f in files]
    together = [None, None]

    def work(i):
        # Each on a pool of its own (as fit_many's tasks): the same numbers as the shared pool.
        together[i] = appell.fit(files[i], rig, no_profile=True, threads=1).to_dict()

    threads = [threading.Thread(target=work, args=(i,)) for i in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert together == alone


def test_fit_many_on_a_local_cluster_is_each_fit(tmp_path):
    distributed = pytest.importorskip("distributed")
    files = sorted(glob.glob("data/campaign/release_0*.csv"))
    bad = tmp_path / "bad.csv"
    bad.write_text("not a recording\n")
    rig = "data/campaign/rig_measured.toml"
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster, distributed.Client(cluster) as client:
        table = appell.fit_many(files + [str(bad)], rig, client=client, no_profile=True)
    assert list(table["recording"]) == files + [str(bad)]
    for f, row in zip(files, table.itertuples()):
        single = appell.fit(f, rig, no_profile=True)
        # pandas shows a missing error as None or NaN (its string column).
        assert row.mu_kinetic == single.mu and not isinstance(row.error, str)
        assert row.ci95_low < row.mu_kinetic < row.ci95_high
    last = table.iloc[-1]
    assert last["mu_kinetic"] != last["mu_kinetic"] or last["mu_kinetic"] is None
    assert "bad.csv" in last["error"]
    # Without a client: the same rows, fitted here.
    here = appell.fit_many(files[:2], rig, no_profile=True, as_pandas=False)
    assert [r["mu_kinetic"] for r in here] == list(table["mu_kinetic"][:2])
