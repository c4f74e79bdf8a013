"""The Python package against the command line (same columns, same numbers) and against
independent checks (the eigenvalues of its own matrices, finite differences through parameter
overrides, an edited model file)."""

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

def test_model_description(governor: modaltol.Model) -> None:
    assert governor.name == "governor"
    assert governor.dof == 1
    p = governor.parameters
    assert list(p.columns) == ["name", "value", "tolerance", "distribution"]
    row = p.set_index("name").loc["spring_k"]
    assert row["value"] == 1000.0
    assert row["tolerance"] == pytest.approx(30.0)  # 3 % of 1000 N/m
    assert "k3" in governor.cases
    c = governor.coordinates
    assert set(c.columns) == {"name", "unit", "driven"}
    assert c["driven"].sum() == 1
    assert "is valid" in governor.check()


@pytest.mark.parametrize(
    "model,args",
    [
        (PENDULUM, ["--speed", "0:6:0.25"]),
        (
            GOVERNOR,
            ["--speed", "0.5:3:0.25", "--transfer", "input=slide,output=slide", "--sensitivity"],
        ),
        (PENDULUM, ["--speed", "3:4.5:0.05", "--transfer", "model", "--sensitivity"]),
    ],
)
def test_sweep_is_the_cli_sweep(cli: Path, model: Path, args: list[str]) -> None:
    m = modaltol.load(model)
    kw = dict(speeds=args[1])
    if "--transfer" in args:
        kw["transfer"] = args[args.index("--transfer") + 1]
    kw["sensitivity"] = "--sensitivity" in args
    assert_same_table(m.sweep(**kw), read_csv(run(cli, "sweep", model, *args)))


def test_speeds_as_values_or_range_agree(pendulum: modaltol.Model) -> None:
    a = pendulum.sweep("1:2:0.5")
    b = pendulum.sweep(np.array([1.0, 1.5, 2.0]))
    pd.testing.assert_frame_equal(a, b)


def test_modal_matrices_and_modes(cli: Path, governor: modaltol.Model) -> None:
    pt = governor.modal(1.595)
    j = json.loads(run(cli, "modal", GOVERNOR, "--speed", "1.595", "--format", "json"))
    for name in "MCK":
        assert np.array_equal(getattr(pt, name), np.array(j[name])), name
    cli_modes = read_csv(run(cli, "modal", GOVERNOR, "--speed", "1.595", "--format", "csv"))
    for name in ["damped_frequency", "natural_frequency", "damping_ratio", "eigen_re", "eigen_im"]:
        assert np.array_equal(pt.modes[name], cli_modes[name]), name
    for c in ["arm1", "arm2", "slide"]:
        z = pt.modes[f"shape:{c}"].to_numpy()
        assert np.array_equal(z.real, cli_modes[f"shape_re:{c}"])
        assert np.array_equal(z.imag, cli_modes[f"shape_im:{c}"])
    # The roots are those of det(λ²M + λC + K) = 0, found here by numpy from the matrices.
    M, C, K = pt.M, pt.C, pt.K
    n = M.shape[0]
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-np.linalg.solve(M, K), -np.linalg.solve(M, C)]])
    roots = np.linalg.eigvals(A)
    for _, mode in pt.modes.iterrows():
        lam = complex(mode["eigen_re"], mode["eigen_im"])
        assert np.min(np.abs(roots - lam)) < 1e-9 * max(1.0, abs(lam))
    assert pt.independent == j["independent"]
    assert pt.q == {c["name"]: c["value"] for c in j["equilibrium"]["coordinates"]}
    assert pt.drive == {d["name"]: d["force"] for d in j["equilibrium"]["drive"]}


def test_mode_shapes_as_motions_equal_the_clis(cli: Path) -> None:
    # The rotor: six modes, a floating housing, two ports. point.shapes holds, per mode, the
    # coordinates' shape, each body's centre-of-mass displacement and each port's, equal to the
    # CLI's modes table and its JSON.
    rotor = EXAMPLES / "rotor_on_rubber_mounts.toml"
    model = modaltol.load(rotor)
    pt = model.modal(100.0)
    cli_modes = read_csv(run(cli, "modal", rotor, "--speed", "100", "--format", "csv"))
    j = json.loads(run(cli, "modal", rotor, "--speed", "100", "--format", "json"))
    bodies = [b["name"] for b in j["modes"][0]["motion"]["bodies"]]
    ports = [p["name"] for p in j["modes"][0]["motion"]["ports"]]
    n = len(pt.modes)
    shapes = pt.shapes
    assert set(shapes["kind"]) == {"coordinate", "body", "port"}
    assert len(shapes[shapes["kind"] == "body"]) == 3 * len(bodies) * n
    assert len(shapes[shapes["kind"] == "port"]) == len(ports) * n == 2 * n
    for _, row in shapes[shapes["kind"] == "body"].iterrows():
        k = row["mode"] - 1
        z = complex(cli_modes[f"cm_re:{row['name']}.{row['component']}"][k],
                    cli_modes[f"cm_im:{row['name']}.{row['component']}"][k])
        assert row["value"] == z
        mj = j["modes"][k]["motion"]["bodies"][bodies.index(row["name"])]["displacement"]
        assert complex(**{"real": mj["xyz".index(row["component"])]["re"],
                          "imag": mj["xyz".index(row["component"])]["im"]}) == z
    for _, row in shapes[shapes["kind"] == "port"].iterrows():
        k = row["mode"] - 1
        mj = j["modes"][k]["motion"]["ports"][ports.index(row["name"])]
        assert row["value"] == complex(mj["re"], mj["im"])
    # The coordinates' rows are the modes' shape columns; each mode's largest is 1.
    for k in range(1, n + 1):
        c = shapes[(shapes["kind"] == "coordinate") & (shapes["mode"] == k)]
        assert np.isclose(np.max(np.abs(c["value"])), 1.0)
    # A mode moves something: some body's centre of mass moves in every mode.
    for k in range(1, n + 1):
        b = shapes[(shapes["kind"] == "body") & (shapes["mode"] == k)]
        assert np.max(np.abs(b["value"])) > 1e-6


def test_modal_of_the_pendulum_is_the_closed_form(pendulum: modaltol.Model) -> None:
    # Hanging rod on a spinning shaft, below the critical speed: θ = 0 and
    # (mL²/3) θ'' + c θ' + (mgL/2 − mL²Ω²/3) θ = 0.
    m, L, c, g, w = 3.0, 1.0, 3.0, 9.80665, 2.0
    pt = pendulum.modal(w)
    J = m * L * L / 3
    k = m * g * L / 2 - J * w * w
    assert pt.M[0, 0] == pytest.approx(J, rel=1e-12)
    assert pt.C[0, 0] == pytest.approx(c, rel=1e-12)
    assert pt.K[0, 0] == pytest.approx(k, rel=1e-12)
    wn = math.sqrt(k / J)
    zeta = c / (2 * math.sqrt(k * J))
    mode = pt.modes.iloc[0]
    assert mode["natural_frequency"] == pytest.approx(wn, rel=1e-12)
    assert mode["damping_ratio"] == pytest.approx(zeta, rel=1e-12)
    assert mode["damped_frequency"] == pytest.approx(wn * math.sqrt(1 - zeta**2), rel=1e-12)


def test_sensitivity_is_the_cli_table_and_matches_finite_differences(
    cli: Path, governor: modaltol.Model
) -> None:
    s = governor.sensitivity(1.595, transfer="input=slide,output=slide")
    cli_s = read_csv(
        run(cli, "sensitivity", GOVERNOR, "--speed", "1.595", "--format", "csv",
            "--transfer", "input=slide,output=slide")
    )
    assert_same_table(s, cli_s)
    # Independent check: central differences of the nominal ω_d, ζ through load(parameters=…).
    for _, row in s.iterrows():
        b, name = row["value"], row["parameter"]
        h = 1e-5 * abs(b)
        up = modaltol.load(GOVERNOR, {name: b + h}).modal(1.595).modes.iloc[0]
        dn = modaltol.load(GOVERNOR, {name: b - h}).modal(1.595).modes.iloc[0]
        for q in ["damped_frequency", "damping_ratio"]:
            fd = (up[q] - dn[q]) / (2 * h)
            assert row[f"d_{q}"] == pytest.approx(fd, rel=1e-6, abs=1e-9), (name, q)
            assert row[f"elasticity_{q}"] == pytest.approx(b / row[q] * row[f"d_{q}"], rel=1e-12)


def test_frf_is_the_cli_frf(cli: Path, governor: modaltol.Model) -> None:
    f = governor.frf(1.595, "0.5:5:0.5", transfer="input=slide,output=slide")
    cli_f = read_csv(
        run(cli, "frf", GOVERNOR, "--speed", "1.595", "--transfer", "input=slide,output=slide",
            "--freq", "0.5:5:0.5")
    )
    assert_same_table(f, cli_f)
    h = f["real"] + 1j * f["imag"]
    assert np.allclose(np.abs(h), f["magnitude"], rtol=1e-14)


def test_analyze_is_the_cli_analysis(cli: Path, tmp_path: Path, pendulum: modaltol.Model) -> None:
    args = dict(speeds="3.4:4.2:0.1", samples=300, seed=7, cases=["L3", "L6"])
    res = pendulum.analyze(**args, output=tmp_path / "py")
    run(cli, "analyze", PENDULUM, "-o", tmp_path / "cli", "--speed", args["speeds"],
        "--samples", "300", "--seed", "7", "--case", "L3", "--case", "L6")
    assert_same_table(res.tolerance, read_csv(tmp_path / "cli" / "tolerance.csv"))
    assert_same_table(res.probabilities, read_csv(tmp_path / "cli" / "probabilities.csv"))
    assert_same_table(res.peaks, read_csv(tmp_path / "cli" / "peaks.csv"))
    # The result directory written from Python is the CLI's: the same files, the tables and
    # plots byte for byte (report.html and summary.json differ only in their wall times).
    py_files = sorted(f.name for f in (tmp_path / "py").iterdir())
    assert py_files == sorted(f.name for f in (tmp_path / "cli").iterdir())
    for name in py_files:
        if name.endswith((".csv", ".svg")):
            same = (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes()
            assert same, name
    cli_summary = json.loads((tmp_path / "cli" / "summary.json").read_text())
    assert res.summary["cases"] == cli_summary["cases"]
    assert res.summary["partial"] is False
    answer = res.answer()
    assert set(answer["method"]) == {"analytic"}
    assert set(answer["case"]) == {"L3", "L6"}


def test_campbell_case_is_the_cli_one(cli: Path, tmp_path: Path) -> None:
    gov = modaltol.load(EXAMPLES / "governor.toml")
    gov.analyze(speeds="1:2:0.5", monte_carlo=False, campbell_case="k6", output=tmp_path / "py")
    run(cli, "analyze", EXAMPLES / "governor.toml", "-o", tmp_path / "cli", "--speed", "1:2:0.5",
        "--no-monte-carlo", "--campbell-case", "k6")
    for name in ("campbell.svg", "tolerance.csv"):
        assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes()
    assert "In short</h2><p>Case <b>k6</b>" in (tmp_path / "py" / "report.html").read_text()
    with pytest.raises(ValueError, match="campbell_case: no tolerance case 'all3' among the "
                       r"cases analysed \(k3\)"):
        gov.analyze(speeds="1:2:0.5", monte_carlo=False, cases=["k3"], campbell_case="all3")


def test_yield_is_the_cli_yield(cli: Path, tmp_path: Path) -> None:
    spec = EXAMPLES / "governor_specification.toml"
    gov = modaltol.load(spec)
    res = gov.analyze(speeds="1.4:2.1:0.1", samples=200, seed=3, cases=["k6"])
    run(cli, "analyze", spec, "-o", tmp_path / "cli", "--speed", "1.4:2.1:0.1",
        "--samples", "200", "--seed", "3", "--case", "k6")
    assert_same_table(res.yield_, read_csv(tmp_path / "cli" / "yield.csv"))
    every = res.yield_[(res.yield_["requirement"] == "all") & res.yield_["speed"].isna()]
    assert set(every["method"]) == {"quadrature", "monte_carlo"}
    assert res.summary["yield"]["target_yield"] == 0.9973
    # What the design meets at the target yield: the CLI's limits.csv, one row per method and
    # requirement, the reach a speed of the grid or empty.
    assert_same_table(res.limits, read_csv(tmp_path / "cli" / "limits.csv"))
    assert len(res.limits) == len(res.yield_[(res.yield_["requirement"] != "all")
                                             & res.yield_["speed"].isna()])
    grid = {round(1.4 + 0.1 * i, 9) for i in range(8)}
    assert all(pd.isna(w) or round(w, 9) in grid for w in res.limits["reach"])
    # Without requirements, an empty table.
    assert len(modaltol.load(EXAMPLES / "governor.toml").analyze(
        speeds="1:2:0.5", monte_carlo=False, cases=["k3"]).yield_) == 0


def test_allocation_and_sobol_are_the_cli_ones(cli: Path, tmp_path: Path) -> None:
    spec = EXAMPLES / "governor_specification.toml"
    gov = modaltol.load(spec)
    table, summary = gov.allocate("1.4:2.1:0.1")
    run(cli, "allocate", spec, "-o", tmp_path / "alloc", "--speed", "1.4:2.1:0.1")
    assert_same_table(table, read_csv(tmp_path / "alloc" / "allocation.csv"))
    assert summary["met"] is True
    assert summary["verified_yield"] - summary["verified_error"] >= 0.9973
    res = gov.analyze(speeds="1.5:2.0:0.5", monte_carlo=False, quadrature=False, cases=["all3"],
                      sobol=64, seed=5)
    run(cli, "analyze", spec, "-o", tmp_path / "sobol", "--speed", "1.5:2.0:0.5", "--no-monte-carlo",
        "--no-quadrature", "--case", "all3", "--sobol", "64", "--seed", "5")
    assert_same_table(res.sobol, read_csv(tmp_path / "sobol" / "sobol.csv"))
    assert set(res.sobol["variable"]) == {"ball_mass", "spring_k", "attach"}


def test_a_bad_model_raises_with_its_location(tmp_path: Path) -> None:
    text = PENDULUM.read_text()
    bad = text.replace('type = "revolute"', 'type = "revolutte"', 1)
    assert bad != text
    path = tmp_path / "bad.toml"
    path.write_text(bad)
    with pytest.raises(modaltol.ModelError) as e:
        modaltol.load(path)
    line = next(i for i, l in enumerate(bad.splitlines(), 1) if "revolutte" in l)
    assert e.value.file == str(path)
    assert e.value.line == line
    assert e.value.column is not None
    assert str(e.value).startswith(f"{path}:{line}:{e.value.column}: ")
    assert "revolutte" in str(e.value)
    assert isinstance(e.value, ValueError)
    with pytest.raises(modaltol.ModelError, match=r"^mine:\d+:\d+: "):
        modaltol.loads(bad, name="mine")
    with pytest.raises(modaltol.ModelError, match="cannot read"):
        modaltol.load(tmp_path / "missing.toml")


def test_a_parameter_override_is_the_edited_file(cli: Path, tmp_path: Path) -> None:
    text = PENDULUM.read_text()
    edited = re.sub(r"(?m)^L = \{ value = 1\.0", "L = { value = 1.07", text)
    assert edited != text, "the example's L line changed: update this test"
    path = tmp_path / "edited.toml"
    path.write_text(edited)
    cli_sweep = read_csv(run(cli, "sweep", path, "--speed", "0:6:0.5", "--transfer", "model"))
    py = modaltol.load(PENDULUM, parameters={"L": 1.07}).sweep(
        "0:6:0.5", transfer="model"
    )
    assert_same_table(py, cli_sweep)
    assert not py.equals(modaltol.load(PENDULUM).sweep("0:6:0.5", transfer="model"))
    # The same through loads, and through the CLI's --set.
    same = modaltol.loads(text, {"L": 1.07}).sweep("0:6:0.5", transfer="model")
    assert_same_table(same, cli_sweep)
    cli_set = read_csv(run(cli, "--set", "L=1.07", "sweep", PENDULUM, "--speed", "0:6:0.5",
                           "--transfer", "model"))
    assert_same_table(py, cli_set)
    with pytest.raises(modaltol.ModelError, match="no such parameter"):
        modaltol.load(PENDULUM, {"Lx": 1.0})
    with pytest.raises(modaltol.ModelError, match="not finite"):
        modaltol.load(PENDULUM, {"L": float("nan")})


def test_bad_arguments_are_value_errors(pendulum: modaltol.Model) -> None:
    with pytest.raises(ValueError, match="speeds"):
        pendulum.sweep("1:0:-")
    with pytest.raises(ValueError, match="wrt: unknown parameter 'nope'"):
        pendulum.sweep("1:2:1", sensitivity=True, wrt="nope")
    with pytest.raises(ValueError, match="transfer"):
        pendulum.sweep("1:2:1", transfer="input=nowhere,output=hinge")
    with pytest.raises(ValueError, match="samples"):
        pendulum.analyze("1:2:1", samples=-5)
    with pytest.raises(ValueError, match="cases"):
        pendulum.analyze("1:2:1", cases=["L99"])
    with pytest.raises(ValueError, match="derivatives"):
        pendulum.sensitivity(1.0, derivatives="symbolic")
    with pytest.raises(ValueError, match="finite"):
        pendulum.modal(float("inf"))
    with pytest.raises(ValueError, match="order"):
        pendulum.frf(1.0, "1:2:1", transfer="input=hinge,output=hinge,order=2")


def test_a_failed_point_raises_solve_error(tmp_path: Path) -> None:
    # A rod with no mass: the mass matrix is singular at every speed.
    text = PENDULUM.read_text()
    m = modaltol.loads(text, {"m": 0.0})
    with pytest.raises(modaltol.SolveError, match="rad/s failed"):
        m.modal(1.0)
    sweep = m.sweep("1:2:1")
    assert set(sweep["status"]) == {"failed"}
    assert sweep["message"].str.len().min() > 0


def test_a_flexible_rotor_whirls_at_rosss_frequencies() -> None:
    # Friswell et al. (2010) Example 5.9.1, six Timoshenko beams on spinning nodes: ROSS's
    # frequencies (rad/s) at 0 and 4000 rpm, and the roots numpy finds from the same M, C, K.
    rotor = modaltol.load(str(EXAMPLES / "friswell_5_9_1.toml"))
    published = {
        0.0: [86.66, 86.66, 274.31, 274.31, 650.41, 716.78],
        4000 * math.pi / 30: [85.39, 87.80, 251.78, 294.71, 600.18, 650.41],
    }
    for speed, ross in published.items():
        pt = rotor.modal(speed)
        w = np.sort(pt.modes["damped_frequency"].to_numpy())
        for x in ross:
            assert np.min(np.abs(w - x)) <= 1e-4 * x, (speed, x)
        M, C, K = pt.M, pt.C, pt.K
        n = M.shape[0]
        A = np.block(
            [[np.zeros((n, n)), np.eye(n)], [-np.linalg.solve(M, K), -np.linalg.solve(M, C)]]
        )
        roots = np.linalg.eigvals(A)
        # numpy's roots of the form carry ε ω_max²/ω (ω_max ≈ 6e4 rad/s): 4e-7 at the soft
        # coupling's 0.94 rad/s, 5e-9 at the first whirl; compared from the whirl modes up.
        for _, mode in pt.modes[pt.modes["damped_frequency"] > 10].iterrows():
            lam = complex(mode["eigen_re"], mode["eigen_im"])
            assert np.min(np.abs(roots - lam)) < 1e-8 * abs(lam)
        # Undamped and gyroscopic: every mode neutrally stable, none read as flutter.
        assert set(pt.modes["status"]) == {"undamped"}


def test_sweep_takes_the_model_s_transfer_unless_told_none(pendulum: modaltol.Model) -> None:
    # As the command line's sweep and sensitivity: the model's [analysis] transfer by default.
    swept = pendulum.sweep("3.2:3.2:1")
    assert "transfer_magnitude" in swept.columns
    at = pendulum.sensitivity(3.2)
    none = pendulum.sweep("3.2:3.2:1", transfer="none")
    assert "transfer_magnitude" not in none.columns
    assert "transfer_magnitude" in at.columns
    assert swept["transfer_magnitude"].iloc[0] == pytest.approx(
        at["transfer_magnitude"].iloc[0], rel=1e-12
    )


def test_shards_and_analyses_print_what_they_hold_not_their_text(
    pendulum: modaltol.Model,
) -> None:
    shard = pendulum.analyze("3:3.4:0.2", samples=20, seed=1, shard=(1, 2))
    assert isinstance(shard, modaltol.Shard)
    text = repr(shard)
    assert text.startswith("Shard('shard-1-of-2.json', ") and "bytes" in text
    assert len(text) < 120 < len(shard.text)
    a = pendulum.analyze("3:3.4:0.2", samples=20, seed=1, quadrature=False)
    text = repr(a)
    assert text.startswith("Analysis('rotating pendulum': cases [") and len(text) < 300
