"""Combining the shards of one Monte Carlo run into the analysis of one run."""

from __future__ import annotations

from os import PathLike
from typing import Any, Iterable, Protocol

from ._results import Analysis, Shard, _analysis
from ._util import _names


class _Merging(Protocol):
    """What :func:`merge` uses of a :class:`~modaltol.Model`: its native model."""

    _native: Any


def merge(
    model: _Merging,
    shards: Iterable[Shard | str | PathLike[str]],
    *,
    cases: str | Iterable[str] | None = None,
    threads: int | None = None,
    output: str | PathLike[str] | None = None,
    speed_unit: str = "rad/s",
    frequency_unit: str = "rad/s",
    campbell_case: str | None = None,
    target_yield: float | None = None,
) -> Analysis:
    """Combines shards ``1..N`` of one Monte Carlo run of ``model`` (:class:`Shard` objects, or
    paths of shard files, the command line's included) exactly as the command line's ``merge``
    does, refusing what it refuses (an edited or truncated shard, one of another model, other
    tolerance cases or other settings, a missing or repeated shard). ``cases`` must be those the
    shards were run with. The analysis is that of one run, bit for bit; ``output`` writes its
    result directory; ``target_yield`` replaces the model's as in :meth:`Model.analyze`."""
    parts = [s if isinstance(s, Shard) else Shard.read(s) for s in shards]
    d = model._native.merge(
        [(s.source or s.name, s.text) for s in parts],
        {
            "cases": _names(cases),
            "target_yield": None if target_yield is None else float(target_yield),
            "threads": threads,
            "output": None if output is None else str(output),
            "speed_unit": speed_unit,
            "frequency_unit": frequency_unit,
            "campbell_case": campbell_case,
        },
    )
    return _analysis(d)
