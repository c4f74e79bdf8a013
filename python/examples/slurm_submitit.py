"""A large Monte Carlo as a Slurm job array through submitit, merged in Python.

Each array task runs one shard (``Model.analyze(shard=(k, n))``, the command line's
``analyze --shard k/n``) and returns it; :func:`modaltol.merge` combines them into exactly one
run's result (checking every shard's digest, model and settings, as ``modaltol merge`` does).
Shards written by the command line (``shard-K-of-N.json``) merge with these too.

Needs ``pip install submitit`` and a Slurm cluster; run from the repository root on the login
node::

    python python/examples/slurm_submitit.py --partition compute --shards 16 --out results

(``--local`` runs the tasks on this machine with submitit's local executor, to try it.)
"""

from __future__ import annotations

import argparse

import submitit

import modaltol


def run_shard(model_path: str, speeds: str, samples: int, k: int, n: int) -> modaltol.Shard:
    """One array task: shard k of n (a Shard pickles back to the submitting process)."""
    return modaltol.load(model_path).analyze(speeds, samples=samples, seed=1, shard=(k, n))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--model", default="examples/governor.toml")
    ap.add_argument("--speeds", default="0:5:0.05")
    ap.add_argument("--samples", type=int, default=100_000)
    ap.add_argument("--shards", type=int, default=16)
    ap.add_argument("--partition", default=None)
    ap.add_argument("--local", action="store_true")
    ap.add_argument("--out", default="results")
    a = ap.parse_args()
    executor = (
        submitit.LocalExecutor(folder="submitit_logs")
        if a.local
        else submitit.AutoExecutor(folder="submitit_logs")
    )
    params = {"timeout_min": 120, "cpus_per_task": 4}
    if a.partition and not a.local:
        params["slurm_partition"] = a.partition
    executor.update_parameters(**params)
    n = a.shards
    # One Slurm array job of n tasks.
    jobs = executor.map_array(
        run_shard,
        [a.model] * n,
        [a.speeds] * n,
        [a.samples] * n,
        list(range(1, n + 1)),
        [n] * n,
    )
    shards = [job.result() for job in jobs]
    result = modaltol.merge(modaltol.load(a.model), shards, output=a.out)
    print(result.answer().head())


if __name__ == "__main__":
    main()
