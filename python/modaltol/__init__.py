"""modaltol: tolerance analysis of the modal characteristics of multibody systems in dynamic
equilibrium, from Python.

A mechanism is read from a TOML model file (the format of ``docs/model-format.md``)::

    import modaltol
    gov = modaltol.load("examples/governor.toml")
    sweep = gov.sweep("0:3:0.01")                       # pandas DataFrame, the CLI's columns
    point = gov.modal(1.595)                           # numpy M, C, K and a modes table
    res = gov.analyze(samples=3000)                    # tolerance, probabilities, summary

Large Monte Carlo runs scale out: ``analyze(executor=pool)`` splits the samples into shards,
runs them on any ``concurrent.futures``-like executor (a process pool, a Dask ``Client``, …) and
merges them exactly (the result equals one run bit for bit); ``analyze(shard=(k, n))`` runs one
shard anywhere (a Slurm array task, say) and :func:`merge` combines shards, those of the command
line's ``analyze --shard`` included.

Units are SI throughout: speeds and frequencies in rad/s, angles in rad, translations in m,
drive forces in N·m (revolute) or N (prismatic). Every table has the columns of the command
line's CSV file of the same name and the same numbers (see ``modaltol --help``).

Errors: an invalid model raises :class:`ModelError` (a ``ValueError``) whose message starts
with ``file:line:column``; a computation that fails at the operating point asked for raises
:class:`SolveError` (a ``RuntimeError``); bad arguments raise ``ValueError``. Long calls
release the GIL and stop on Ctrl-C (``KeyboardInterrupt``).
"""

from __future__ import annotations

from ._merge import merge
from ._modaltol import ModelError, SolveError, __version__
from ._model import Model, load, loads
from ._results import Analysis, ModalPoint, Shard

__all__ = [
    "Analysis",
    "Model",
    "ModalPoint",
    "ModelError",
    "Shard",
    "SolveError",
    "__version__",
    "load",
    "loads",
    "merge",
]
