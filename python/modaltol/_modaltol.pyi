"""Type stubs of the native module (see modaltol/__init__.py for the documented API)."""

from typing import Any

__version__: str

class ModelError(ValueError):
    file: str
    line: int | None
    column: int | None
    reason: str

class SolveError(RuntimeError): ...

Columns = dict[str, list[Any]]

class NativeModel:
    @property
    def name(self) -> str: ...
    @property
    def dof(self) -> int: ...
    def parameters(self) -> Columns: ...
    def coordinates(self) -> Columns: ...
    def cases(self) -> list[str]: ...
    def check(self) -> str: ...
    def sweep(
        self,
        speeds: str | list[float] | None = None,
        transfer: str | None = None,
        sensitivity: bool = False,
        wrt: list[str] | None = None,
        derivatives: str = "ad",
        independent: list[str] | None = None,
        branch: str = "stable",
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
        self,
        speeds: str | list[float] | None = None,
        cases: list[str] | None = None,
        samples: int | None = None,
        seed: int | None = None,
        sampling: str | None = None,
        monte_carlo: bool = True,
        quadrature: bool = True,
        quadrature_tolerance: float = 1e-3,
        threads: int | None = None,
        output: str | None = None,
        speed_unit: str = "rad/s",
        frequency_unit: str = "rad/s",
    ) -> dict[str, Any]: ...

def load(path: str, parameters: dict[str, float] | None = None) -> NativeModel: ...
def loads(
    text: str, parameters: dict[str, float] | None = None, name: str = "<string>"
) -> NativeModel: ...
