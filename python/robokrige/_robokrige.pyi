"""Type stubs of the extension module ``robokrige._robokrige`` (Rust, PyO3).

Use the ``robokrige`` package's functions; this module is their engine."""

from os import PathLike
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple, Union, final

import numpy as np
import numpy.typing as npt

_F64 = npt.NDArray[np.float64]
_Path = Union[str, "PathLike[str]"]
_Progress = Optional[Callable[[int, int, str], Any]]

__all__ = [
    "Data",
    "Model",
    "PhysicsModel",
    "RobokrigeError",
    "build_target_cpu",
    "compensate",
    "cross_validate",
    "diagnose",
    "library_version",
    "plan",
]

class RobokrigeError(ValueError):
    """A robokrige failure; the message is the library's own."""

@final
class Data:
    """A measurement campaign (poses in visiting order, directions, errors,
    covariates)."""

    def __new__(
        cls,
        q: _F64,
        dirs: Optional[_F64] = None,
        errors: Optional[_F64] = None,
        positions: Optional[_F64] = None,
        covariates: Optional[Sequence[Tuple[str, _F64]]] = None,
        ids: Optional[Sequence[str]] = None,
        source: str = "<memory>",
    ) -> "Data": ...
    @staticmethod
    def read_csv(path: _Path) -> "Data": ...
    @property
    def n_rows(self) -> int: ...
    @property
    def n_joints(self) -> int: ...
    @property
    def source(self) -> str: ...
    @property
    def dir_source(self) -> str: ...
    @property
    def q(self) -> _F64: ...
    @property
    def dirs(self) -> _F64: ...
    @property
    def errors(self) -> Optional[_F64]: ...
    def warnings(self) -> List[str]: ...
    def columns(self) -> List[Tuple[str, Union[_F64, List[str]]]]: ...
    def __len__(self) -> int: ...

@final
class Model:
    """A fitted TCP error model (one universal-Kriging model per axis)."""

    @staticmethod
    def fit(data: Data, params: Dict[str, Any], progress: _Progress = None) -> "Model": ...
    def predict(self, data: Data, return_std: bool = True) -> Tuple[_F64, Optional[_F64]]: ...
    def coverage(
        self, data: Data, mean: _F64, std: Optional[_F64] = None
    ) -> List[Tuple[int, List[str]]]: ...
    def direction_sensitivity(self, q: Sequence[float], dir: Sequence[float]) -> float: ...
    def save(self, path: _Path) -> None: ...
    @staticmethod
    def load(path: _Path) -> "Model": ...
    def to_json(self) -> str: ...
    @staticmethod
    def from_json(text: str, source_name: str = "<memory>") -> "Model": ...
    @property
    def space(self) -> str: ...
    @property
    def n_joints(self) -> int: ...
    @property
    def n_rows(self) -> int: ...
    @property
    def input_names(self) -> List[str]: ...
    @property
    def families(self) -> List[str]: ...
    @property
    def nugget(self) -> bool: ...
    @property
    def corr_auto(self) -> bool: ...
    @property
    def periodic(self) -> List[int]: ...
    @property
    def extras(self) -> List[str]: ...
    def reports_json(self) -> str: ...
    def options_json(self) -> str: ...
    def robot_json(self) -> str: ...
    def noise_std(self) -> Tuple[float, float, float]: ...
    def calibration_json(self) -> str: ...
    def conditioning_warnings(self) -> List[str]: ...

@final
class PhysicsModel:
    """A physics-based TCP error model (the identified geometry and the
    joints' lookup tables), as ``robokrige physics identify`` writes it."""

    @staticmethod
    def load(path: _Path) -> "PhysicsModel": ...
    def save(self, path: _Path) -> None: ...
    def predict(self, data: Data) -> _F64: ...
    @property
    def description(self) -> str: ...
    @property
    def has_tables(self) -> bool: ...
    @property
    def n_joints(self) -> int: ...
    def robot_json(self) -> str: ...

def library_version() -> str: ...
def build_target_cpu() -> str: ...
def cross_validate(
    data: Data,
    params: Dict[str, Any],
    folds: int = 10,
    cv_seed: int = 1,
    mode: str = "refit",
    progress: _Progress = None,
) -> str: ...
def compensate(
    model: Union[Model, PhysicsModel, str],
    robot: str,
    *,
    path: Optional[str] = None,
    xyz: Optional[_F64] = None,
    rpy: Optional[_F64] = None,
    joints: Optional[_F64] = None,
    tool: Optional[Tuple[float, float, float]] = None,
    iterative: bool = True,
    tol: float = 1e-3,
    max_iter: int = 10,
    start: Optional[Sequence[float]] = None,
    orientation: Optional[Sequence[float]] = None,
    truth: Optional[str] = None,
    truth_seed: int = 1,
) -> str: ...
def diagnose(
    data: Data,
    method: str = "ejs",
    nugget: bool = True,
    folds: int = 10,
    seed: int = 1,
    permutations: int = 1999,
    fdr: float = 0.05,
    max_effects: int = 3,
    periodic: str = "none",
    robot: Optional[str] = None,
    progress: _Progress = None,
    refit_rows: Optional[int] = None,
    scan_rows: Optional[int] = None,
    calibrate: Optional[bool] = None,
) -> Tuple[str, Model]: ...
def plan(
    robot: str,
    budget: int,
    *,
    tool: Optional[Tuple[float, float, float]] = None,
    campaign: Optional[Data] = None,
    prior: Optional[Model] = None,
    pool: Optional[Data] = None,
    region: Union[Data, str, None] = None,
    first_batch: int = 50,
    candidates: int = 5000,
    region_points: int = 1000,
    via_step: float = 5.0,
    passes: int = 1,
    tracker_at: Optional[Tuple[float, float, float]] = None,
    max_range: Optional[float] = None,
    max_incidence: Optional[float] = None,
    target_mm: Optional[float] = None,
    seed: int = 1,
    output: Optional[str] = None,
    format: str = "csv",
) -> Tuple[_F64, _F64, npt.NDArray[np.bool_], npt.NDArray[np.int64], str, Optional[Model]]: ...
