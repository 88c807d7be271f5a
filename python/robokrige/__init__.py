"""robokrige: universal-Kriging models of an industrial robot's TCP error
over the extended joint space ``[θ, λ]`` (joint angles and the direction each
joint last moved), in Python.

The same engine as the ``robokrige`` command line (a Rust library), with its
defaults: the same data and settings give the same model file, and model
files load in either.

>>> import robokrige as rk
>>> df = rk.read_campaign("datasets/comau_lhs.csv")         # doctest: +SKIP
>>> model = rk.ErrorModel().fit(df)                          # doctest: +SKIP
>>> X, y = df[[f"q{j}" for j in range(1, 7)] + [f"dir{j}" for j in range(1, 7)]], df[["ex", "ey", "ez"]]  # doctest: +SKIP
>>> rk.ErrorModel().fit(X, y).score(X, y)                    # R², scikit-learn's  # doctest: +SKIP
>>> cv = rk.cross_validate(rk.ErrorModel(), df)              # doctest: +SKIP
>>> out = rk.compensate(model, "comau-nj220", "datasets/comau_circle.csv")  # doctest: +SKIP
>>> effects, improved, report = rk.diagnose(rk.read_campaign("datasets/comau_tracker_step.csv"))  # doctest: +SKIP
"""

from ._robokrige import Data, PhysicsModel, RobokrigeError, build_target_cpu, library_version
from ._data import as_data, derive_directions, read_campaign
from ._model import ErrorModel, RobokrigeWarning, mean_3d_error, r2_score
from ._plan import Plan, plan
from ._sklearn import NotFittedError
from ._studies import Diagnosis, compensate, cross_validate, diagnose

try:
    from importlib.metadata import version as _version

    __version__ = _version("robokrige")
except Exception:  # pragma: no cover - running from a source tree
    __version__ = library_version().split()[-1]

__all__ = [
    "Data",
    "Diagnosis",
    "ErrorModel",
    "NotFittedError",
    "PhysicsModel",
    "Plan",
    "RobokrigeError",
    "RobokrigeWarning",
    "as_data",
    "build_target_cpu",
    "compensate",
    "cross_validate",
    "derive_directions",
    "diagnose",
    "library_version",
    "mean_3d_error",
    "plan",
    "r2_score",
    "read_campaign",
]
