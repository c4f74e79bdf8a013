"""A large Monte Carlo of the governor on a Dask cluster, equal to one run bit for bit.

``Model.analyze(executor=client)`` splits the samples into shards, sends each to the cluster as
one task (the model travels as its TOML text) and merges them exactly as ``modaltol merge``
does: same seed, same numbers, the quantiles included, whatever the number of shards or
workers. Any object with ``submit(fn, *args)`` returning futures with ``result()`` works the
same way: a ``concurrent.futures.ProcessPoolExecutor``, a Dask ``Client`` (here a
``LocalCluster``; on a real cluster, ``Client("scheduler-address:8786")``), …

Run from the repository root (about a minute on 2 cores; ``--samples 200`` for a quick look)::

    python python/examples/dask_local_cluster.py --out governor_dask

It writes the result directory (tables, plots, report.html) into ``--out`` and, with
``--check``, compares ``tolerance.csv`` with a run in this process.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from distributed import Client, LocalCluster

import modaltol


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--model", default="examples/governor.toml")
    ap.add_argument("--speeds", default="0:5:0.1")
    ap.add_argument("--samples", type=int, default=2000)
    ap.add_argument("--shards", type=int, default=8)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--out", default="governor_dask")
    ap.add_argument("--check", action="store_true", help="also run in this process and compare")
    a = ap.parse_args()
    model = modaltol.load(a.model)
    with LocalCluster(
        n_workers=a.workers, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster, Client(cluster) as client:
        result = model.analyze(
            a.speeds, samples=a.samples, seed=1, executor=client, shards=a.shards, output=a.out
        )
    print(result.answer().head())
    if a.check:
        one = Path(a.out).with_name(Path(a.out).name + "_one")
        model.analyze(a.speeds, samples=a.samples, seed=1, output=one)
        same = (Path(a.out) / "tolerance.csv").read_bytes() == (one / "tolerance.csv").read_bytes()
        print("tolerance.csv equal to one run:", same)
        if not same:
            raise SystemExit(1)


if __name__ == "__main__":
    main()
