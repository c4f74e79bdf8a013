"""Shared fixtures: the repository's examples (the pendulum and governor models loaded once
per module) and the command-line binary the package is compared with (``MODALTOL_BIN``,
default ``target/release/modaltol``)."""

from __future__ import annotations

import io
import os
import subprocess
from pathlib import Path

import pandas as pd
import pytest

import modaltol

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "examples"
PENDULUM = EXAMPLES / "rotating_pendulum.toml"
GOVERNOR = EXAMPLES / "governor.toml"


@pytest.fixture(scope="module")
def pendulum() -> modaltol.Model:
    return modaltol.load(PENDULUM)


@pytest.fixture(scope="module")
def governor() -> modaltol.Model:
    return modaltol.load(GOVERNOR)


@pytest.fixture(scope="session")
def cli() -> Path:
    path = Path(os.environ.get("MODALTOL_BIN", ROOT / "target" / "release" / "modaltol"))
    if not path.exists():
        pytest.fail(f"the modaltol binary is missing at {path}: run `cargo build --release`")
    return path


def run(cli: Path, *args: str) -> str:
    """Runs the CLI; its stdout."""
    r = subprocess.run([str(cli), *map(str, args)], capture_output=True, text=True, check=False)
    assert r.returncode == 0, f"modaltol {' '.join(map(str, args))} failed:\n{r.stderr}"
    return r.stdout


def read_csv(text_or_path: str | Path) -> pd.DataFrame:
    """A CLI CSV, with no type guessing beyond numbers (empty cells stay empty strings in text
    columns)."""
    if isinstance(text_or_path, Path):
        text_or_path = text_or_path.read_text()
    return pd.read_csv(
        io.StringIO(text_or_path),
        keep_default_na=False,
        na_values=[""],
        # Exact reading of the CLI's shortest round-trip decimals (pandas ≥ 3 always reads so).
        **({} if int(pd.__version__.split(".")[0]) >= 3 else {"float_precision": "round_trip"}),
    )


def assert_same_table(got: pd.DataFrame, cli_table: pd.DataFrame) -> None:
    """The package's DataFrame holds the CLI's table: same columns in the same order, numbers
    equal bit for bit (NaN where the CLI left a cell empty), text equal."""
    import numpy as np

    assert list(got.columns) == list(cli_table.columns)
    assert len(got) == len(cli_table)
    for c in got.columns:
        a, b = got[c], cli_table[c]
        if pd.api.types.is_numeric_dtype(a) and pd.api.types.is_numeric_dtype(b):
            x, y = a.to_numpy(dtype=float), b.to_numpy(dtype=float)
            assert np.array_equal(x, y, equal_nan=True), f"column {c}: {x} != {y}"
        else:
            x = a.astype(object).where(a.notna(), "").astype(str).tolist()
            y = b.astype(object).where(b.notna(), "").astype(str).tolist()
            assert x == y, f"column {c}"
