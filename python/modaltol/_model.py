"""A validated mechanism and what it computes; how it is read."""

from __future__ import annotations

import numbers
from os import PathLike
from pathlib import Path
from typing import Any, Iterable, Mapping

import numpy as np
import pandas as pd

from . import _modaltol
from ._merge import merge
from ._results import Analysis, ModalPoint, Shard, _allocation, _analysis
from ._util import Speeds, _frame, _names, _speeds

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
        ``transfer``: ``"input=NAME,output=NAME[,order=K]"`` adds |H| and its phase; default
        the model's ``[analysis] transfer`` where it has one, ``"none"`` leaves it out.
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
        quadrature_nodes: int | None = None,
        threads: int | None = None,
    ) -> tuple[pd.DataFrame, dict[str, Any]]:
        """Tolerance allocation (the CLI's ``allocate``): the tolerances of ``case``'s variables
        (default the model's ``[allocation] case``, else the parameters' own) that minimise the
        cost of the ``[allocation]`` table while every requirement is met at ``target_yield``
        (default the model's), verified by the quadrature. Returns the table of
        ``allocation.csv`` and the document of ``allocation.json`` (its ``met`` says whether the
        verified yield reaches the target). ``quadrature_tolerance`` and ``quadrature_nodes``
        are :meth:`analyze`'s."""
        return _allocation(
            self._native.allocate(
                speeds, target_yield, case, quadrature_tolerance, quadrature_nodes, threads
            )
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
        quadrature_nodes: int | None = None,
        threads: int | None = None,
        output: str | PathLike[str] | None = None,
        speed_unit: str = "rad/s",
        frequency_unit: str = "rad/s",
        campbell_case: str | None = None,
        sobol: int | None = None,
        shard: tuple[int, int] | None = None,
        executor: Any = None,
        shards: int | None = None,
        target_yield: float | None = None,
    ) -> Analysis | Shard:
        """The tolerance analysis of the CLI's ``analyze``: every mode's ω_d and ζ and |H|
        per tolerance case, by first and second order, the quadrature (``analytic``: the
        answer to read) and Monte Carlo (``samples``, ``seed``, ``sampling`` = ``"random"``,
        ``"lhs"`` or ``"sobol"``; default the model's). With ``output``, also writes the CLI's
        result directory (CSV, plots, report.html, summary.json), its plots and report with
        speeds in ``speed_unit`` and frequencies in ``frequency_unit`` (``"rad/s"``, ``"hz"``,
        ``"rpm"``; the tables stay in rad/s), the Campbell diagram's bands and the report's "In
        short" of the case ``campbell_case`` (default: the one with the most toleranced
        variables). At most 10⁵ speeds; ``threads`` from 1 to 1024
        (``None``: one per core), the command line's rules. Ctrl-C stops it. The yield of the
        model's ``[[requirements]]`` is in ``yield_``; ``sobol=N`` adds the Sobol indices
        (``N`` base samples, ``N·(d+2)`` sweeps) in ``sobol``; ``target_yield`` replaces the
        model's ``[allocation] target_yield`` (what ``limits`` is met at and ``yield_`` is judged
        against). The quadrature (``quadrature=False`` skips it) refines until its error
        estimates meet ``quadrature_tolerance`` (relative to each output's σ) or it has swept
        ``quadrature_nodes`` designs per case (the command line's ``--quadrature-nodes``;
        default its rule's own budget: 300 with five or more variables). Returns an
        :class:`Analysis`.

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
                "quadrature_nodes": quadrature_nodes,
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
                campbell_case=campbell_case,
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
                "quadrature_nodes": quadrature_nodes,
                "threads": threads,
                "output": None if output is None else str(output),
                "speed_unit": speed_unit,
                "frequency_unit": frequency_unit,
                "campbell_case": campbell_case,
                "sobol": sobol,
                "shard": None if shard is None else _shard_pair(shard),
                "target_yield": None if target_yield is None else float(target_yield),
            },
        )
        if shard is not None:
            return Shard(name=d["name"], text=d["shard"])
        return _analysis(d)


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
