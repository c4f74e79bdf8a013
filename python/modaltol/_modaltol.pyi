"""Type stubs of the native module (see modaltol/__init__.py for the documented API)."""

from typing import Any, TypedDict

__version__: str

class ModelError(ValueError):
    file: str
    line: int | None
    column: int | None
    reason: str

class SolveError(RuntimeError): ...

Columns = dict[str, list[Any]]

class SweepOptions(TypedDict):
    transfer: str | None
    sensitivity: bool
    wrt: list[str] | None
    derivatives: str
    independent: list[str] | None
    branch: str

class AnalyzeOptions(TypedDict):
    cases: list[str] | None
    samples: int | None
    seed: int | None
    sampling: str | None
    monte_carlo: bool
    quadrature: bool
    quadrature_tolerance: float
    quadrature_nodes: int | None
    threads: int | None
    output: str | None
    speed_unit: str
    frequency_unit: str
    campbell_case: str | None
    sobol: int | None
    shard: tuple[int, int] | None
    target_yield: float | None

class MergeOptions(TypedDict):
    cases: list[str] | None
    target_yield: float | None
    threads: int | None
    output: str | None
    speed_unit: str
    frequency_unit: str
    campbell_case: str | None

class NativeModel:
    @property
    def name(self) -> str: ...
    @property
    def dof(self) -> int: ...
    @property
    def samples(self) -> int: ...
    def parameters(self) -> Columns: ...
    def coordinates(self) -> Columns: ...
    def cases(self) -> list[str]: ...
    def check(self) -> str: ...
    def sweep(
        self, speeds: str | list[float] | None, options: SweepOptions
    ) -> Columns: ...
    def modal(
        self, speed: float, independent: list[str] | None = None, branch: str = "stable"
    ) -> dict[str, Any]: ...
    def sensitivity(
        self,
        speed: float,
        wrt: list[str] | None = None,
        transfer: str | None = None,
        derivatives: str = "ad",
    ) -> Columns: ...
    def frf(
        self,
        speed: float,
        freq: str | list[float],
        transfer: str | None = None,
        wrt: list[str] | None = None,
    ) -> Columns: ...
    def analyze(
        self, speeds: str | list[float] | None, options: AnalyzeOptions
    ) -> dict[str, Any]: ...
    def merge(
        self, shards: list[tuple[str, str]], options: MergeOptions
    ) -> dict[str, Any]: ...
    def allocate(
        self,
        speeds: str | None,
        target_yield: float | None,
        case: str | None,
        quadrature_tolerance: float,
        quadrature_nodes: int | None,
        threads: int | None,
    ) -> dict[str, Any]: ...

def load(path: str, parameters: dict[str, float] | None = None) -> NativeModel: ...
def loads(
    text: str, parameters: dict[str, float] | None = None, name: str = "<string>"
) -> NativeModel: ...
