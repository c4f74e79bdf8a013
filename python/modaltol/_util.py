"""Argument and table conversions shared by the package's modules."""

from __future__ import annotations

from typing import Any, Iterable, Mapping, Sequence, Union

import numpy as np
import pandas as pd

#: Speeds or frequencies: ``"FROM:TO:STEP"`` in rad/s (TO included) or a sequence of values.
Speeds = Union[str, Sequence[float], np.ndarray]


def _frame(columns: Mapping[str, list]) -> pd.DataFrame:
    return pd.DataFrame(dict(columns), columns=list(columns))


def _speeds(speeds: Speeds | None) -> Any:
    if speeds is None or isinstance(speeds, str):
        return speeds
    # One flat float array: the native side checks its length before it makes the Python
    # floats (by `tolist`, in C: several times faster than a comprehension).
    return np.asarray(speeds, dtype=float).ravel()


def _names(names: str | Iterable[str] | None) -> list[str] | None:
    if names is None:
        return None
    if isinstance(names, str):
        return [n.strip() for n in names.split(",")]
    return list(names)
