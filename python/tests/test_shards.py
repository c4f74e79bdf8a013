"""Scale-out: executors, Dask and shards give one run's results, bit for bit, and refuse what
the command line refuses."""

from __future__ import annotations

import json
import math
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import modaltol
from conftest import EXAMPLES, GOVERNOR, PENDULUM, assert_same_table, read_csv, run

def _files(directory: Path) -> dict[str, bytes]:
    return {n: (directory / n).read_bytes() for n in ("tolerance.csv", "probabilities.csv")}


def test_an_executor_gives_one_runs_results(tmp_path: Path) -> None:
    # A process pool: the samples split into 5 shards, run in other processes and merged give
    # one run's tolerance.csv and probabilities.csv, byte for byte (quantiles included).
    from concurrent.futures import ProcessPoolExecutor

    pendulum = modaltol.load(PENDULUM)
    one = pendulum.analyze("0:6:0.5", samples=300, seed=5, output=tmp_path / "one")
    with ProcessPoolExecutor(2) as pool:
        par = pendulum.analyze(
            "0:6:0.5", samples=300, seed=5, executor=pool, shards=5, output=tmp_path / "par"
        )
    assert _files(tmp_path / "one") == _files(tmp_path / "par")
    pd.testing.assert_frame_equal(one.tolerance, par.tolerance)
    mc = par.tolerance[par.tolerance["method"] == "monte_carlo"]
    assert mc["q50"].notna().any()
    # A multi-mode model (the rotor: six modes, |H|), two cases, three shards.
    rotor = modaltol.load(EXAMPLES / "rotor_on_rubber_mounts.toml")
    kw = dict(samples=120, seed=2, quadrature=False)
    one = rotor.analyze("90:110:10", **kw)
    with ProcessPoolExecutor(2) as pool:
        par = rotor.analyze("90:110:10", executor=pool, shards=3, **kw)
    pd.testing.assert_frame_equal(one.tolerance, par.tolerance)
    pd.testing.assert_frame_equal(one.probabilities, par.probabilities)


def test_a_dask_cluster_gives_one_runs_results(tmp_path: Path) -> None:
    distributed = pytest.importorskip("distributed")
    pendulum = modaltol.load(PENDULUM)
    pendulum.analyze("0:6:0.5", samples=300, seed=5, output=tmp_path / "one")
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster, distributed.Client(cluster) as client:
        pendulum.analyze(
            "0:6:0.5", samples=300, seed=5, executor=client, shards=4, output=tmp_path / "dask"
        )
    assert _files(tmp_path / "one") == _files(tmp_path / "dask")


def test_python_shards_merge_with_the_clis(cli: Path, tmp_path: Path) -> None:
    # Shard 1 by the command line, shard 2 by Python: merged by Python and by the command line,
    # both are the command line's one run.
    args = ["--speed", "0:6:0.5", "--samples", "300", "--seed", "5"]
    run(cli, "analyze", PENDULUM, "-o", tmp_path / "whole", *args)
    run(cli, "analyze", PENDULUM, "-o", tmp_path / "s1", "--shard", "1/2", *args)
    pendulum = modaltol.load(PENDULUM)
    s2 = pendulum.analyze("0:6:0.5", samples=300, seed=5, shard=(2, 2))
    assert isinstance(s2, modaltol.Shard) and s2.name == "shard-2-of-2.json"
    path2 = s2.write(tmp_path / "s2")
    modaltol.merge(pendulum, [tmp_path / "s1" / "shard-1-of-2.json", s2], output=tmp_path / "py")
    run(cli, "merge", "--model", PENDULUM, "-o", tmp_path / "cli",
        tmp_path / "s1" / "shard-1-of-2.json", path2)
    whole = _files(tmp_path / "whole")
    assert _files(tmp_path / "py") == whole
    assert _files(tmp_path / "cli") == whole


def test_merge_refuses_what_the_cli_refuses(tmp_path: Path) -> None:
    pendulum = modaltol.load(PENDULUM)
    shards = [pendulum.analyze("0:6:1", samples=200, seed=1, shard=(k, 2)) for k in (1, 2)]
    edited = modaltol.Shard(shards[1].name, shards[1].text.replace('"seed":1', '"seed":2'))
    with pytest.raises(ValueError, match="digest"):
        modaltol.merge(pendulum, [shards[0], edited])
    with pytest.raises(ValueError, match="once each"):
        modaltol.merge(pendulum, [shards[0]])
    other = pendulum.analyze("0:6:1", samples=200, seed=2, shard=(2, 2))
    with pytest.raises(ValueError, match="other settings"):
        modaltol.merge(pendulum, [shards[0], other])
    governor = modaltol.load(GOVERNOR)
    with pytest.raises(ValueError, match="another model"):
        modaltol.merge(governor, shards)
    with pytest.raises(ValueError, match="not both"):
        pendulum.analyze("0:6:1", shard=(1, 2), executor=object())
    # The merge of the two is one run.
    one = pendulum.analyze("0:6:1", samples=200, seed=1)
    pd.testing.assert_frame_equal(one.tolerance, modaltol.merge(pendulum, shards).tolerance)


def test_the_dask_example_runs_and_equals_one_run(tmp_path: Path) -> None:
    pytest.importorskip("distributed")
    example = Path(__file__).resolve().parents[1] / "examples" / "dask_local_cluster.py"
    r = subprocess.run(
        [sys.executable, str(example), "--model", str(GOVERNOR), "--speeds", "1:2:0.5",
         "--samples", "120", "--shards", "3", "--out", str(tmp_path / "out"), "--check"],
        capture_output=True, text=True, timeout=600,
    )
    assert r.returncode == 0, r.stderr
    assert "tolerance.csv equal to one run: True" in r.stdout


def test_the_slurm_example_compiles() -> None:
    # It needs submitit and a cluster: checked for syntax here, its calls are analyze(shard=)
    # and merge, tested above.
    example = Path(__file__).resolve().parents[1] / "examples" / "slurm_submitit.py"
    compile(example.read_text(), str(example), "exec")


# Scale-out and specification requests at their hostile edges.


def test_a_shard_read_from_a_path_is_written_into_the_directory_given(tmp_path: Path) -> None:
    pendulum = modaltol.load(PENDULUM)
    s = pendulum.analyze("0:6:1", samples=20, seed=1, shard=(1, 2))
    first = s.write(tmp_path / "a")
    back = modaltol.Shard.read(first)
    assert back.name == "shard-1-of-2.json" and back.source == str(first)
    again = back.write(tmp_path / "b")
    assert again == tmp_path / "b" / "shard-1-of-2.json" and again.read_text() == s.text
    assert first.read_text() == s.text


@pytest.mark.parametrize(
    "shard", [(1.5, 2), (1, 2, 3), ("1", "2"), (True, 2), [1], 3, "1/2"]
)
def test_a_malformed_shard_is_refused(shard: object) -> None:
    pendulum = modaltol.load(PENDULUM)
    with pytest.raises(ValueError, match=r"shard must be \(k, n\)"):
        pendulum.analyze("0:6:1", samples=20, shard=shard)


def test_shards_and_sobol_and_a_bad_target_are_refused_as_on_the_command_line() -> None:
    pendulum = modaltol.load(PENDULUM)
    with pytest.raises(ValueError, match="sobol is not split across shards"):
        pendulum.analyze("0:6:1", samples=20, shard=(1, 2), sobol=8)
    for y in (0.0, 1.0, 1.5, -1.0, float("nan")):
        with pytest.raises(ValueError, match="target_yield must be a probability"):
            pendulum.analyze("0:6:1", samples=20, target_yield=y)
    # More shards than samples, refused before any task is submitted.
    class Counting:
        submitted = 0

        def submit(self, fn, *args):  # noqa: ANN001, ANN202
            Counting.submitted += 1
            raise AssertionError("nothing is submitted")

    with pytest.raises(ValueError, match="would leave shards without a sample"):
        pendulum.analyze("0:6:1", samples=20, executor=Counting(), shards=10**9)
    with pytest.raises(ValueError, match="shards must be a whole number"):
        pendulum.analyze("0:6:1", samples=20, executor=Counting(), shards=2.5)
    assert Counting.submitted == 0


def test_the_target_yield_given_is_what_limits_and_the_summary_use(tmp_path: Path) -> None:
    text = PENDULUM.read_text() + (
        '\n[[requirements]]\nname = "clear"\nkind = "frequency"\nmode = 1\nmin = 2.0\n'
        "speeds = [4, 5]\n"
    )
    m = modaltol.loads(text)
    res = m.analyze("4:5:0.5", samples=64, seed=3, target_yield=0.9, output=tmp_path / "o")
    assert set(res.limits["target"]) == {0.9}
    assert res.summary["yield"]["target_yield"] == 0.9
    # Unbounded ends are blank with a reason, never inf or NaN on disk.
    few = m.analyze("4:5:0.5", samples=64, seed=3, target_yield=1e-300, output=tmp_path / "t")
    disk = (tmp_path / "t" / "limits.csv").read_text().lower()
    assert "inf" not in disk and "nan" not in disk
    blank = few.limits["margin_low"].isna() | few.limits["margin_high"].isna()
    assert blank.any()
    assert few.limits.loc[blank, "reason"].str.len().min() > 0


class _Raising:
    """An executor whose submit raises."""

    def submit(self, fn, *args):  # noqa: ANN001, ANN202
        raise RuntimeError("the cluster is down")


class _Wrong:
    """An executor whose futures return something else than the task's result."""

    class _F:
        def result(self) -> str:
            return "not a shard"

    def submit(self, fn, *args):  # noqa: ANN001, ANN202
        return _Wrong._F()


class _Failing:
    """An executor whose tasks fail in the worker (the future raises)."""

    cancelled = 0

    class _F:
        def result(self) -> None:
            raise OSError("worker lost")

        def cancel(self) -> bool:
            _Failing.cancelled += 1
            return True

    def submit(self, fn, *args):  # noqa: ANN001, ANN202
        return _Failing._F()


def _die() -> None:
    os._exit(3)


class _Dying:
    """A process pool whose workers die in the task."""

    def __init__(self, pool: object) -> None:
        self.pool = pool

    def submit(self, fn, *args):  # noqa: ANN001, ANN202
        return self.pool.submit(_die)  # type: ignore[attr-defined]


def test_executors_that_raise_return_the_wrong_thing_or_die_leave_no_result(
    tmp_path: Path,
) -> None:
    from concurrent.futures import ProcessPoolExecutor
    from concurrent.futures.process import BrokenProcessPool

    pendulum = modaltol.load(PENDULUM)
    kw = dict(samples=40, seed=1, shards=4)
    with pytest.raises(RuntimeError, match="cluster is down"):
        pendulum.analyze("0:6:1", executor=_Raising(), output=tmp_path / "a", **kw)
    with pytest.raises(TypeError, match="returned str, not a Shard"):
        pendulum.analyze("0:6:1", executor=_Wrong(), output=tmp_path / "b", **kw)
    with pytest.raises(OSError, match="worker lost"):
        pendulum.analyze("0:6:1", executor=_Failing(), output=tmp_path / "c", **kw)
    assert _Failing.cancelled == 4, "the other tasks are withdrawn"
    with ProcessPoolExecutor(2) as pool, pytest.raises(BrokenProcessPool):
        pendulum.analyze("0:6:1", executor=_Dying(pool), output=tmp_path / "d", **kw)
    assert not any((tmp_path / d).exists() for d in "abcd")


CTRL_C_EXECUTOR = """
import sys, time, modaltol
from concurrent.futures import ThreadPoolExecutor
m = modaltol.load(sys.argv[1])
print("started", flush=True)
t = time.time()
try:
    with ThreadPoolExecutor(1) as pool:
        m.analyze("0:6:0.1", samples=400_000, quadrature=False, executor=pool, shards=40,
                  output=sys.argv[2])
    print("finished", flush=True)
except KeyboardInterrupt:
    print(f"interrupted after {time.time() - t:.2f} s", flush=True)
"""


def test_ctrl_c_stops_analyze_on_an_executor(tmp_path: Path) -> None:
    script = tmp_path / "ex.py"
    script.write_text(CTRL_C_EXECUTOR)
    out = tmp_path / "out"
    p = subprocess.Popen([sys.executable, str(script), str(PENDULUM), str(out)],
                         stdout=subprocess.PIPE, text=True)
    assert p.stdout is not None
    assert p.stdout.readline().strip() == "started"
    time.sleep(2.0)
    p.send_signal(signal.SIGINT)
    # The task running finishes its shard (a worker's own run is not interrupted from here);
    # the 39 others are withdrawn.
    got, _ = p.communicate(timeout=120)
    assert got.startswith("interrupted after"), got
    assert not out.exists()
