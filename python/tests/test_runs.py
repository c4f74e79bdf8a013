"""The package's long calls: Ctrl-C stops them, memory and settings are checked before they
start, the stubs name the native functions, the examples run."""

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

CTRL_C = """
import sys, time, modaltol
m = modaltol.load(sys.argv[1])
print("started", flush=True)
t = time.time()
try:
    m.analyze("0:6:0.01", samples=1_000_000, quadrature=False)
    print("finished", flush=True)
except KeyboardInterrupt:
    print(f"interrupted after {time.time() - t:.2f} s", flush=True)
"""


def test_ctrl_c_stops_analyze(tmp_path: Path) -> None:
    script = tmp_path / "run.py"
    script.write_text(CTRL_C)
    p = subprocess.Popen([sys.executable, str(script), str(PENDULUM)], stdout=subprocess.PIPE,
                         text=True)
    assert p.stdout is not None
    assert p.stdout.readline().strip() == "started"
    time.sleep(2.0)  # well inside the million-sample Monte Carlo
    sent = time.time()
    p.send_signal(signal.SIGINT)
    out, _ = p.communicate(timeout=60)
    stopped = time.time() - sent
    assert p.returncode == 0
    assert out.startswith("interrupted after"), out
    assert stopped < 20, f"took {stopped:.1f} s to stop"


CTRL_C_FRF = """
import sys, time, modaltol
m = modaltol.load(sys.argv[1])
print("started", flush=True)
t = time.time()
try:
    m.frf(1.0, "0:250:0.0001", wrt="L")
    print("finished", flush=True)
except KeyboardInterrupt:
    print(f"interrupted after {time.time() - t:.2f} s", flush=True)
"""


def test_ctrl_c_stops_frf(tmp_path: Path) -> None:
    script = tmp_path / "frf.py"
    script.write_text(CTRL_C_FRF)
    p = subprocess.Popen([sys.executable, str(script), str(PENDULUM)], stdout=subprocess.PIPE,
                         text=True)
    assert p.stdout is not None
    assert p.stdout.readline().strip() == "started"
    time.sleep(1.5)  # inside the 2.5·10⁶ frequencies (several seconds)
    sent = time.time()
    p.send_signal(signal.SIGINT)
    out, _ = p.communicate(timeout=60)
    assert out.startswith("interrupted after"), out
    assert time.time() - sent < 10


@pytest.mark.parametrize("call", [
    lambda m: m.sweep("0:999999999:1"),
    lambda m: m.sweep(np.zeros(30_000_000)),
    lambda m: m.frf(1.0, "0:999999999:1"),
    lambda m: m.analyze("0:999999999:1"),
])
def test_a_range_too_large_for_memory_is_refused_before_it_is_made(
    pendulum: modaltol.Model, call
) -> None:
    t = time.time()
    with pytest.raises(ValueError, match="more than"):
        call(pendulum)
    assert time.time() - t < 5


def test_settings_follow_the_command_line_rules(pendulum: modaltol.Model, cli: Path) -> None:
    # The same values refused by both, for the same reason.
    for threads in [0, 3000]:
        with pytest.raises(ValueError, match="threads") as e:
            pendulum.analyze("0:1:1", threads=threads, samples=10)
        r = subprocess.run([str(cli), "analyze", str(PENDULUM), "-o", "/nonexistent/x",
                            "--speed", "0:1:1", "--threads", str(threads)],
                           capture_output=True, text=True)
        assert r.returncode == 2
        reason = str(e.value).removeprefix("threads ")
        assert reason in r.stderr, (reason, r.stderr)
    # A negative count is a value refused, not an overflow of the binding.
    with pytest.raises(ValueError, match="at least 1"):
        pendulum.analyze("0:1:1", threads=-1, samples=10)
    for samples in [1, 10**10]:
        with pytest.raises(ValueError, match="samples must lie in"):
            pendulum.analyze("0:1:1", samples=samples)
    with pytest.raises(ValueError, match="named twice"):
        pendulum.modal(1.0, independent="hinge,hinge")
    with pytest.raises(ValueError, match="quadrature_nodes") as e:
        pendulum.analyze("0:1:1", quadrature_nodes=0, monte_carlo=False)
    r = subprocess.run([str(cli), "analyze", str(PENDULUM), "-o", "/nonexistent/x",
                        "--speed", "0:1:1", "--quadrature-nodes=0"],
                       capture_output=True, text=True)
    assert r.returncode == 2
    reason = str(e.value).removeprefix("quadrature_nodes ")
    assert reason in r.stderr, (reason, r.stderr)
    # A negative count is a value refused (the command line's parser refuses it too).
    with pytest.raises(ValueError, match="quadrature_nodes must be a number of nodes"):
        pendulum.analyze("0:1:1", quadrature_nodes=-3, monte_carlo=False)


def test_quadrature_nodes_cap_the_quadrature() -> None:
    # The 13-variable governor's quadrature, to a tolerance no rule meets, within 150 nodes
    # (the command line's --quadrature-nodes; tests/cli.rs checks the default budget).
    m = modaltol.load(EXAMPLES / "multi_arm_governor_13_variables.toml")
    a = m.analyze("1:2:0.5", monte_carlo=False, quadrature_tolerance=1e-9, quadrature_nodes=150)
    swept = [c["nodes_swept"] for c in a.summary["quadrature"]["cases"]]
    assert swept and all(80 < n <= 150 for n in swept), swept


def test_an_infinite_transfer_function_says_why(pendulum: modaltol.Model) -> None:
    undamped = modaltol.load(PENDULUM, {"c": 0.0})
    wn = float(undamped.modal(1.0).modes["natural_frequency"][0])
    frf = undamped.frf(1.0, [1.0, wn, 1e200])
    assert frf["magnitude"].isna().tolist() == [False, True, True]
    assert pd.isna(frf["message"][0])
    assert frf["message"][1].startswith("resonance") and frf["message"][2].startswith("overflow")
    sweep = undamped.sweep([1.0], transfer=f"input=hinge,output=hinge,order={wn!r}")
    assert sweep["transfer_magnitude"].isna().all()
    assert sweep["message"][0].startswith("resonance")


def test_type_stubs_name_the_native_functions() -> None:
    stub = (Path(modaltol.__file__).parent / "_modaltol.pyi").read_text()
    native = modaltol._modaltol
    for name in ["load", "loads"]:
        assert f"def {name}(" in stub and callable(getattr(native, name))
    for name in ["sweep", "modal", "sensitivity", "frf", "analyze", "parameters", "check"]:
        assert f"def {name}(" in stub and hasattr(native.NativeModel, name), name
    assert (Path(modaltol.__file__).parent / "py.typed").exists()


def test_the_paper_figures_example_runs(tmp_path: Path) -> None:
    example = Path(__file__).resolve().parents[1] / "examples" / "paper_figures.py"
    r = subprocess.run(
        [sys.executable, str(example), "--out", str(tmp_path), "--samples", "200",
         "--speeds", "0:6:0.1"],
        capture_output=True, text=True, env={**os.environ, "MPLBACKEND": "Agg"},
    )
    assert r.returncode == 0, r.stderr
    for f in ["fig2.png", "fig3.png", "fig4.png", "tolerance.csv"]:
        assert (tmp_path / f).stat().st_size > 1000, f


def test_the_package_under_test_is_the_installed_wheel() -> None:
    # Not the source tree: the tests must see what users install.
    assert "site-packages" in Path(modaltol.__file__).parts, modaltol.__file__


# Scale-out: shards, merge and executors.
