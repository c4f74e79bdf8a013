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

import json
import numbers
import os
from dataclasses import dataclass
from os import PathLike
from pathlib import Path
from typing import Any, Iterable, Mapping, Sequence, Union

import numpy as np
import pandas as pd

from . import _modaltol
from ._modaltol import ModelError, SolveError, __version__

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

#: Speeds or frequencies: ``"FROM:TO:STEP"`` in rad/s (TO included) or a sequence of values.
Speeds = Union[str, Sequence[float], np.ndarray]


def _frame(columns: Mapping[str, list]) -> pd.DataFrame:
    return pd.DataFrame(dict(columns), columns=list(columns))


def _speeds(speeds: Speeds | None) -> Any:
    if speeds is None or isinstance(speeds, str):
        return speeds
    # `tolist` makes the Python floats in C, several times faster than a comprehension.
    return np.asarray(speeds, dtype=float).ravel().tolist()


def _names(names: str | Iterable[str] | None) -> list[str] | None:
    if names is None:
        return None
    if isinstance(names, str):
        return [n.strip() for n in names.split(",")]
    return list(names)


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
    ``analyze(sobol=N)``; empty otherwise)."""

    tolerance: pd.DataFrame
    probabilities: pd.DataFrame
    yield_: pd.DataFrame
    limits: pd.DataFrame
    sobol: pd.DataFrame
    summary: dict[str, Any]

    def answer(self) -> pd.DataFrame:
        """The rows to read: method ``analytic`` (the quadrature where it ran)."""
        return self.tolerance[self.tolerance["method"] == "analytic"].reset_index(drop=True)


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


def _shard_pair(shard: Any) -> tuple[int, int]:
    """``shard=(k, n)`` as two whole numbers, refused otherwise (the range is checked later,
    as the command line's ``--shard K/N`` is)."""
    if (
        not isinstance(shard, (tuple, list))
        or len(shard) != 2
        or not all(isinstance(x, numbers.Integral) and not isinstance(x, bool) for x in shard)
    ):
        raise ValueError(f"shard must be (k, n), two whole numbers: shard k of n, got {shard!r}")
    return int(shard[0]), int(shard[1])


def _run_shard(
    recipe: tuple[str, dict[str, float] | None, str],
    speeds: str | None,
    options: dict[str, Any],
    shard: tuple[int, int],
) -> Shard:
    """Runs one shard in a worker (what ``analyze(executor=...)`` submits): rebuilds the model
    from its text and runs ``analyze(shard=...)``."""
    text, parameters, name = recipe
    return loads(text, parameters, name=name).analyze(speeds, shard=shard, **options)


class Model:
    """A validated mechanism. Made by :func:`load` or :func:`loads`."""

    def __init__(
        self,
        native: _modaltol.NativeModel,
        recipe: tuple[str, dict[str, float] | None, str] | None = None,
    ) -> None:
        self._native = native
        # The model's text, parameter overrides and name, to rebuild it in other processes.
        self._recipe = recipe

    def __reduce__(self) -> tuple[Any, ...]:
        if self._recipe is None:
            raise TypeError("this model cannot be pickled (it was not made by load or loads)")
        return (_rebuild, (self._recipe,))

    def __repr__(self) -> str:
        return f"<modaltol.Model {self.name!r}: {self.dof} degree(s) of freedom>"

    @property
    def name(self) -> str:
        """The model's name."""
        return self._native.name

    @property
    def dof(self) -> int:
        """Degrees of freedom."""
        return self._native.dof

    @property
    def parameters(self) -> pd.DataFrame:
        """Parameters: name, nominal value, tolerance (absolute, in the parameter's unit; NaN
        where none) and distribution."""
        return _frame(self._native.parameters())

    @property
    def coordinates(self) -> pd.DataFrame:
        """Generalised coordinates: name, unit (rad or m), driven."""
        return _frame(self._native.coordinates())

    @property
    def cases(self) -> list[str]:
        """The tolerance cases :meth:`analyze` runs by default."""
        return self._native.cases()

    def check(self) -> str:
        """The summary ``modaltol check`` prints."""
        return self._native.check()

    def sweep(
        self,
        speeds: Speeds | None = None,
        *,
        transfer: str | None = None,
        sensitivity: bool = False,
        wrt: str | Iterable[str] | None = None,
        derivatives: str = "ad",
        independent: str | Iterable[str] | None = None,
        branch: str = "stable",
    ) -> pd.DataFrame:
        """Sweep the operating speed: one row per (speed, mode), the CLI's ``sweep`` columns.

        ``speeds``: ``"FROM:TO:STEP"`` (rad/s) or values; default the model's ``[analysis]``.
        ``transfer``: ``"input=NAME,output=NAME[,order=K]"`` adds |H| and its phase.
        ``sensitivity``: add d(…)/d(P) for the design variables ``wrt`` (default: those with a
        tolerance), computed ``"ad"`` (exact) or ``"fd"``. A failed speed has status
        ``failed`` and its reason in ``message``. ``branch``: ``"stable"`` switches to a stable
        equilibrium where the one followed loses its stability, ``"as-given"`` follows it
        (the ``branch`` column says which, ``message`` why). The table is held in memory: one
        of more than 2·10⁷ cells (rows × columns) raises ``ValueError`` before anything is
        computed (the command line's ``sweep -o FILE`` streams any length). Ctrl-C stops it.
        """
        return _frame(
            self._native.sweep(
                _speeds(speeds),
                {
                    "transfer": transfer,
                    "sensitivity": sensitivity,
                    "wrt": _names(wrt),
                    "derivatives": derivatives,
                    "independent": _names(independent),
                    "branch": branch,
                },
            )
        )

    def modal(
        self,
        speed: float,
        *,
        independent: str | Iterable[str] | None = None,
        branch: str = "stable",
    ) -> ModalPoint:
        """Equilibrium, M̂, Ĉ, K̂ and the damped modes at ``speed`` (rad/s), Newton starting
        from the model's initial guess; ``branch="as-given"`` reports the equilibrium reached
        even where it is unstable (default ``"stable"``: a stable one is looked for)."""
        d = self._native.modal(float(speed), _names(independent), branch)
        modes = _frame(d["modes"])
        rows: list[tuple[int, str, str, str, str, complex]] = []
        units = dict(zip(self.coordinates["name"], self.coordinates["unit"]))
        for name in d["free"]:
            re, im = f"shape_re:{name}", f"shape_im:{name}"
            modes[f"shape:{name}"] = modes.pop(re) + 1j * modes.pop(im)
            rows += [(int(k), "coordinate", name, name, units.get(name, ""), v)
                     for k, v in zip(modes["mode"], modes[f"shape:{name}"])]
        for column in [c for c in modes.columns if c.startswith("cm_re:")]:
            target = column[len("cm_re:"):]
            value = modes.pop(column) + 1j * modes.pop(f"cm_im:{target}")
            body, axis = target.rsplit(".", 1)
            rows += [(int(k), "body", body, axis, "m", v) for k, v in zip(modes["mode"], value)]
        for column in [c for c in modes.columns if c.startswith("port_re:")]:
            port = column[len("port_re:"):]
            value = modes.pop(column) + 1j * modes.pop(f"port_im:{port}")
            rows += [(int(k), "port", port, "along", "m/rad", v) for k, v in zip(modes["mode"], value)]
        shapes = pd.DataFrame(rows, columns=["mode", "kind", "name", "component", "unit", "value"])
        return ModalPoint(
            speed=float(speed),
            M=np.array(d["M"], dtype=float),
            C=np.array(d["C"], dtype=float),
            K=np.array(d["K"], dtype=float),
            independent=d["independent"],
            q=d["q"],
            drive=d["drive"],
            iterations=d["iterations"],
            note=d["note"],
            branch=d["branch"],
            branch_reason=d["branch_reason"],
            modes=modes,
            shapes=shapes,
        )

    def sensitivity(
        self,
        speed: float,
        *,
        wrt: str | Iterable[str] | None = None,
        transfer: str | None = None,
        derivatives: str = "ad",
    ) -> pd.DataFrame:
        """Derivatives of every mode's ω_d, ω_n, ζ (and |H|) with respect to the design
        variables at ``speed``: one row per (mode, parameter), per unit of the parameter
        (``d_…``) and normalised (``elasticity_…`` = (P/f)·df/dP). The CLI's
        ``sensitivity --format csv`` columns."""
        return _frame(
            self._native.sensitivity(float(speed), _names(wrt), transfer, derivatives)
        )

    def frf(
        self,
        speed: float,
        freq: Speeds,
        *,
        transfer: str | None = None,
        wrt: str | Iterable[str] | None = None,
    ) -> pd.DataFrame:
        """Frequency response H(jω) at ``speed`` over the excitation frequencies ``freq``
        (rad/s), from ``transfer = "input=NAME,output=NAME"`` (default the model's), with
        d|H|/dP. The CLI's ``frf`` columns; at most 2·10⁷ cells, as :meth:`sweep`. Ctrl-C
        stops it."""
        return _frame(
            self._native.frf(float(speed), _speeds(freq), transfer, _names(wrt))
        )

    def allocate(
        self,
        speeds: str | None = None,
        *,
        target_yield: float | None = None,
        case: str | None = None,
        quadrature_tolerance: float = 1e-3,
        threads: int | None = None,
    ) -> tuple[pd.DataFrame, dict[str, Any]]:
        """Tolerance allocation (the CLI's ``allocate``): the tolerances of ``case``'s variables
        (default the model's ``[allocation] case``, else the parameters' own) that minimise the
        cost of the ``[allocation]`` table while every requirement is met at ``target_yield``
        (default the model's), verified by the quadrature. Returns the table of
        ``allocation.csv`` and the document of ``allocation.json`` (its ``met`` says whether the
        verified yield reaches the target)."""
        return _allocation(
            self._native.allocate(speeds, target_yield, case, quadrature_tolerance, threads)
        )

    def analyze(
        self,
        speeds: Speeds | None = None,
        *,
        cases: str | Iterable[str] | None = None,
        samples: int | None = None,
        seed: int | None = None,
        sampling: str | None = None,
        monte_carlo: bool = True,
        quadrature: bool = True,
        quadrature_tolerance: float = 1e-3,
        threads: int | None = None,
        output: str | PathLike[str] | None = None,
        speed_unit: str = "rad/s",
        frequency_unit: str = "rad/s",
        sobol: int | None = None,
        shard: tuple[int, int] | None = None,
        executor: Any = None,
        shards: int | None = None,
        target_yield: float | None = None,
    ) -> Any:
        """The tolerance analysis of the CLI's ``analyze``: every mode's ω_d and ζ and |H|
        per tolerance case, by first and second order, the quadrature (``analytic``: the
        answer to read) and Monte Carlo (``samples``, ``seed``, ``sampling`` = ``"random"``,
        ``"lhs"`` or ``"sobol"``; default the model's). With ``output``, also writes the CLI's
        result directory (CSV, plots, report.html, summary.json), its plots and report with
        speeds in ``speed_unit`` and frequencies in ``frequency_unit`` (``"rad/s"``, ``"hz"``,
        ``"rpm"``; the tables stay in rad/s). At most 10⁵ speeds; ``threads`` from 1 to 1024
        (``None``: one per core), the command line's rules. Ctrl-C stops it. The yield of the
        model's ``[[requirements]]`` is in ``yield_``; ``sobol=N`` adds the Sobol indices
        (``N`` base samples, ``N·(d+2)`` sweeps) in ``sobol``; ``target_yield`` replaces the
        model's ``[allocation] target_yield`` (what ``limits`` is met at and ``yield_`` is judged
        against). Returns an :class:`Analysis`.

        Scale-out (speeds then as ``"FROM:TO:STEP"`` or the model's):

        * ``shard=(k, n)`` runs shard ``k`` of ``n`` of the Monte Carlo (the command line's
          ``--shard k/n``) and returns it as a :class:`Shard`; :func:`merge` combines them.
        * ``executor=`` any object with ``submit(fn, *args)`` returning futures with
          ``result()`` (a ``concurrent.futures`` executor, a Dask ``Client``, …): the run is
          split into ``shards`` shards (default 8), each submitted as one task (the model
          travels as its text), and merged here: the result equals one run bit for bit,
          whatever the split and the executor."""
        if shard is not None and executor is not None:
            raise ValueError("give shard= (one shard) or executor= (all of them), not both")
        if executor is not None:
            if sobol:
                raise ValueError("sobol= runs in one process; it is not split across an executor")
            if not monte_carlo:
                raise ValueError("executor= splits the Monte Carlo: monte_carlo=False leaves none")
            if speeds is not None and not isinstance(speeds, str):
                raise ValueError('executor=: speeds as "FROM:TO:STEP" (or the model\'s)')
            if self._recipe is None:
                raise ValueError("this model cannot travel to an executor's workers")
            if shards is not None and (
                not isinstance(shards, numbers.Integral) or isinstance(shards, bool)
            ):
                raise ValueError(f"shards must be a whole number, got {shards!r}")
            n = 8 if shards is None else int(shards)
            if n < 1:
                raise ValueError(f"shards must be at least 1, got {n}")
            # Refused before any task is submitted (as the command line's --shard K/N is).
            total = self._native.samples if samples is None else samples
            if isinstance(total, numbers.Integral) and n > total:
                raise ValueError(
                    f"shard {n} shards of {total} samples would leave shards without a sample; "
                    f"use at most {total} shards"
                )
            options = {
                "cases": cases,
                "samples": samples,
                "seed": seed,
                "sampling": sampling,
                "quadrature": quadrature,
                "quadrature_tolerance": quadrature_tolerance,
            }
            futures = []
            try:
                for k in range(1, n + 1):
                    futures.append(
                        executor.submit(_run_shard, self._recipe, speeds, options, (k, n))
                    )
                parts = [f.result() for f in futures]
            except BaseException:
                # Interrupted, or a task failed: the tasks not started are withdrawn.
                for f in futures:
                    cancel = getattr(f, "cancel", None)
                    if callable(cancel):
                        cancel()
                raise
            for k, p in enumerate(parts, start=1):
                if not isinstance(p, Shard):
                    raise TypeError(
                        f"the executor's task for shard {k} of {n} returned "
                        f"{type(p).__name__}, not a Shard: executor= needs submit(fn, *args) "
                        "whose future's result() is fn(*args)"
                    )
            return merge(
                self,
                parts,
                cases=cases,
                target_yield=target_yield,
                threads=threads,
                output=output,
                speed_unit=speed_unit,
                frequency_unit=frequency_unit,
            )
        if shards is not None:
            raise ValueError("shards= is the split of executor=; give executor= too")
        d = self._native.analyze(
            _speeds(speeds),
            {
                "cases": _names(cases),
                "samples": samples,
                "seed": seed,
                "sampling": sampling,
                "monte_carlo": monte_carlo,
                "quadrature": quadrature,
                "quadrature_tolerance": quadrature_tolerance,
                "threads": threads,
                "output": None if output is None else str(output),
                "speed_unit": speed_unit,
                "frequency_unit": frequency_unit,
                "sobol": sobol,
                "shard": None if shard is None else _shard_pair(shard),
                "target_yield": None if target_yield is None else float(target_yield),
            },
        )
        if shard is not None:
            return Shard(name=d["name"], text=d["shard"])
        return _analysis(d)


def _analysis(d: dict[str, Any]) -> Analysis:
    return Analysis(
        tolerance=_frame(d["tolerance"]),
        probabilities=_frame(d["probabilities"]),
        yield_=_frame(d["yield"]),
        limits=_frame(d["limits"]),
        sobol=_frame(d["sobol"]),
        summary=json.loads(d["summary"]),
    )


def merge(
    model: Model,
    shards: Iterable[Shard | str | PathLike[str]],
    *,
    cases: str | Iterable[str] | None = None,
    threads: int | None = None,
    output: str | PathLike[str] | None = None,
    speed_unit: str = "rad/s",
    frequency_unit: str = "rad/s",
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
        },
    )
    return _analysis(d)


def _allocation(d: dict[str, Any]) -> tuple[pd.DataFrame, dict[str, Any]]:
    return _frame(d["allocation"]), json.loads(d["summary"])


def _rebuild(recipe: tuple[str, dict[str, float] | None, str]) -> Model:
    text, parameters, name = recipe
    return loads(text, parameters, name=name)


def load(
    path: str | PathLike[str], parameters: Mapping[str, float] | None = None
) -> Model:
    """Read and validate a model file. ``parameters`` replaces nominal values (name → value,
    in the parameter's unit), exactly as editing the file would."""
    overrides = dict(parameters) if parameters else None
    native = _modaltol.load(str(path), overrides)
    # Read after it validated (so it is UTF-8): the text rebuilds it in worker processes.
    return Model(native, (Path(path).read_text(encoding="utf-8"), overrides, str(path)))


def loads(
    text: str,
    parameters: Mapping[str, float] | None = None,
    *,
    name: str = "<string>",
) -> Model:
    """Validate a model given as TOML text (``name`` names it in error messages);
    ``parameters`` as in :func:`load`."""
    overrides = dict(parameters) if parameters else None
    return Model(_modaltol.loads(text, overrides, name), (text, overrides, name))
