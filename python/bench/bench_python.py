"""Benchmarks of the Python package (issue 39's targets; outside CI, numbers in
docs/performance.md and docs/python.md).

    .venv/bin/python python/bench/bench_python.py [--recordings 1000] [--repeats 21]

1. Overhead per call: appell.fit's wall time in Python minus the time spent in Rust (read,
   check, fit), median over repeats, on the shipped example (default fit) and a plain fit.
2. Two threads: one fit alone against two recordings fitted in two Python threads at once
   (alternated runs, medians), each fit on a pool of its own (threads=1) and on the shared
   pool (threads=None, the default: a lone fit already uses both cores).
3. fit_many: N short recordings (0.5 s at 400 Hz, synthesized with known mu into a temporary
   directory) on a LocalCluster of 1 worker and of 2 workers (1 thread each), alternated.
"""

import argparse
import os
import statistics
import tempfile
import threading
import time

import appell

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def overhead(repeats):
    for label, kwargs in [("default fit", {}), ("plain fit", {"plain": True, "no_profile": True})]:
        walls, inner = [], []
        for _ in range(repeats):
            t0 = time.perf_counter()
            r = appell.fit("data/example_recording.mcap", "configs/rig_example.toml", **kwargs)
            walls.append(time.perf_counter() - t0)
            inner.append(r._inner.seconds())
        over = [w - i for w, i in zip(walls, inner)]
        print(
            f"{label}: wall median {statistics.median(walls) * 1e3:.2f} ms, in Rust "
            f"{statistics.median(inner) * 1e3:.2f} ms, overhead median "
            f"{statistics.median(over) * 1e3:.3f} ms (max {max(over) * 1e3:.3f} ms)"
        )


def two_threads(repeats):
    files = ["data/campaign/release_01.csv", "data/campaign/release_02.csv"]
    rig = "data/campaign/rig_measured.toml"
    for threads in (1, None):

        def one(f):
            appell.fit(f, rig, threads=threads)

        alone, par = [], []
        for _ in range(repeats):
            for f in files:
                t0 = time.perf_counter()
                one(f)
                alone.append(time.perf_counter() - t0)
            workers = [threading.Thread(target=one, args=(f,)) for f in files]
            t0 = time.perf_counter()
            for t in workers:
                t.start()
            for t in workers:
                t.join()
            par.append(time.perf_counter() - t0)
        a, p = statistics.median(alone), statistics.median(par)
        print(
            f"threads={threads}: one fit alone {a * 1e3:.1f} ms, two fits in two Python threads "
            f"{p * 1e3:.1f} ms ({p / a:.2f}x one fit; {2 * a / p:.2f}x the throughput)"
        )


def cluster(n, rounds, batch):
    from distributed import Client, LocalCluster

    with tempfile.TemporaryDirectory() as d:
        paths = []
        for k in range(n):
            p = os.path.join(d, f"r{k:04d}.csv")
            appell.synth("configs/paper_rest_horizontal.toml", p, fps=400, duration=0.5,
                         noise=2e-4, seed=k)
            paths.append(p)
        times = {1: [], 2: []}
        for _ in range(rounds):
            for workers in (1, 2):
                with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as lc, Client(lc) as client:
                    client.run(lambda: __import__("appell"))  # import before the clock
                    t0 = time.perf_counter()
                    table = appell.fit_many(paths, "configs/rig_paper.toml", client=client,
                                            batch=batch)
                    times[workers].append(time.perf_counter() - t0)
                    failed = table["error"].notna().sum()
        one, two = statistics.median(times[1]), statistics.median(times[2])
        print(
            f"fit_many of {n} recordings (batch={batch}): 1 worker {one:.2f} s, 2 workers {two:.2f} s "
            f"({two / one:.2f} of one worker; {failed} failed)"
        )


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--recordings", type=int, default=1000)
    ap.add_argument("--repeats", type=int, default=21)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--only", choices=["overhead", "threads", "cluster"])
    ap.add_argument("--batch", type=int, help="recordings per task (default: fit_many's)")
    a = ap.parse_args()
    os.chdir(ROOT)
    if a.only in (None, "overhead"):
        overhead(a.repeats)
    if a.only in (None, "threads"):
        two_threads(a.repeats)
    if a.only in (None, "cluster"):
        cluster(a.recordings, a.rounds, a.batch)


if __name__ == "__main__":
    main()
