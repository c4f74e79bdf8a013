"""What the package's calls return: a modal point, an analysis, a shard."""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from os import PathLike
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from ._util import _frame

@dataclass(frozen=True)
class ModalPoint:
    """The dynamic equilibrium and the linearised system at one speed.

    ``M``, ``C``, ``K`` are M̂, Ĉ, K̂ in the independent coordinates (``independent``);
    ``modes`` has one row per mode (frequencies in rad/s, damping ratio, both roots) and its
    shape in the free coordinates as complex columns ``shape:<joint>`` (largest component 1).
    ``shapes`` has each mode's shape as motions, one row per mode and component (columns
    ``mode``, ``kind``, ``name``, ``component``, ``unit``, ``value`` complex): ``kind``
    ``"coordinate"`` (the free joint coordinates, rad or m), ``"body"`` (the displacement of each
    body's centre of mass along ground ``x``, ``y``, ``z``, m) and ``"port"`` (each port's
    displacement along its direction, m, or rotation, rad), all scaled as the ``shape:``
    columns (largest coordinate component 1).
    ``branch`` is ``"stable"``, ``"switched"`` (the equilibrium reached from the initial guess
    was unstable; a stable one found along its unstable modes is reported) or ``"unstable"``,
    and ``branch_reason`` says why in a sentence. A rigid-body mode (status ``rigid``: a zero
    root) has no damping ratio (NaN).
    """

    speed: float
    M: np.ndarray
    C: np.ndarray
    K: np.ndarray
    independent: list[str]
    q: dict[str, float]
    drive: dict[str, float]
    iterations: int
    note: str | None
    branch: str
    branch_reason: str
    modes: pd.DataFrame
    shapes: pd.DataFrame


@dataclass(frozen=True)
class Analysis:
    """A tolerance analysis: ``tolerance``, ``probabilities`` and ``yield_`` have the columns of
    the CLI's ``tolerance.csv``, ``probabilities.csv`` and ``yield.csv`` (the probability of
    meeting the model's ``[[requirements]]``; empty without requirements); ``limits`` has the
    columns of ``limits.csv`` (what the design meets at the target yield: the highest speed up
    to which each requirement holds, ``reach``, and the worst margin met, ``margin_at_target``);
    ``summary`` is its ``summary.json``; ``sobol`` has the columns of ``sobol.csv`` (with
    ``analyze(sobol=N)``; empty otherwise); ``peaks`` has the columns of ``peaks.csv`` (where
    the transfer function peaks along the speed, located between the swept speeds, with its API
    684 amplification factor and σ by first order; empty without ``[analysis] transfer``)."""

    tolerance: pd.DataFrame
    probabilities: pd.DataFrame
    yield_: pd.DataFrame
    limits: pd.DataFrame
    sobol: pd.DataFrame
    peaks: pd.DataFrame
    summary: dict[str, Any]

    def answer(self) -> pd.DataFrame:
        """The rows to read: method ``analytic`` (the quadrature where it ran)."""
        return self.tolerance[self.tolerance["method"] == "analytic"].reset_index(drop=True)

    def __repr__(self) -> str:
        # What it holds, not its tables (a notebook prints the repr of the last expression).
        cases = [c["name"] for c in self.summary.get("cases", [])]
        speeds = self.summary.get("speeds", {})
        return (
            f"Analysis({self.summary.get('model', '')!r}: cases {cases}, "
            f"{speeds.get('count', 0)} speeds, {len(self.tolerance)} tolerance rows, "
            f"{len(self.yield_)} yield rows)"
        )


@dataclass(frozen=True)
class Shard:
    """One share of a Monte Carlo run (``analyze(shard=(k, n))``, or read from a file the
    command line's ``analyze --shard K/N`` wrote): the shard file's ``text`` and its usual file
    ``name`` (``shard-K-of-N.json``). :func:`merge` combines shards ``1..N`` of one run,
    checking each (digest, fingerprint of the model and settings, layout) as the command line
    does. Plain strings, so a shard pickles and travels between processes and machines.
    ``source`` is the path it was read from (what a refusal names), empty for one made here."""

    name: str
    text: str
    source: str = ""

    def __repr__(self) -> str:
        # Its name and size, not its text (megabytes of JSON in a notebook).
        where = f", from {self.source!r}" if self.source else ""
        return f"Shard({self.name!r}, {len(self.text.encode('utf-8'))} bytes{where})"

    def write(self, directory: str | PathLike[str]) -> Path:
        """Writes the shard as ``directory/name`` (the command line's file); its path."""
        path = Path(directory) / self.name
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_name(path.name + ".tmp")
        tmp.write_text(self.text, encoding="utf-8")
        os.replace(tmp, path)
        return path

    @staticmethod
    def read(path: str | PathLike[str]) -> "Shard":
        """A shard file (as the command line or :meth:`write` wrote it)."""
        p = Path(path)
        return Shard(name=p.name, text=p.read_text(encoding="utf-8"), source=str(p))


def _analysis(d: dict[str, Any]) -> Analysis:
    return Analysis(
        tolerance=_frame(d["tolerance"]),
        probabilities=_frame(d["probabilities"]),
        yield_=_frame(d["yield"]),
        limits=_frame(d["limits"]),
        sobol=_frame(d["sobol"]),
        peaks=_frame(d["peaks"]),
        summary=json.loads(d["summary"]),
    )


def _allocation(d: dict[str, Any]) -> tuple[pd.DataFrame, dict[str, Any]]:
    return _frame(d["allocation"]), json.loads(d["summary"])
