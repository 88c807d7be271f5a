"""``ErrorModel``: the estimator (scikit-learn shape) over the library's one
fit API."""

from __future__ import annotations

import json
import os
import warnings
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np

from . import _robokrige
from ._data import PathLike, _bad, as_data
from ._progress import ProgressArg, progress_for


class RobokrigeWarning(UserWarning):
    """A plausibility or coverage warning (the command line prints these on
    standard error)."""


_DEFAULTS: Dict[str, Any] = dict(
    space="ejs",
    trend="constant",
    nugget=True,
    corr="auto",
    optimizer="bfgs",
    starts=None,
    seed=1,
    periodic="auto",
    robot=None,
    tool=None,
    kinematic=False,
    calibrate=True,
    method=None,
)

#: Model options a named method fixes itself: passed to the library only
#: when they differ from the defaults (the library refuses them with a
#: method, as ``robokrige fit --method`` does).
_METHOD_FIXES = ("space", "trend", "corr", "optimizer", "nugget", "starts", "periodic")


def _periodic_spec(p: Union[str, Sequence[int]]) -> str:
    if isinstance(p, str):
        return p
    try:
        return ",".join(str(int(j)) for j in p)
    except (TypeError, ValueError):
        raise _bad(f"periodic {p!r}: expected 'auto', 'none' or a list of joint numbers (1-based)") from None


def _warn_all(messages: Sequence[str]) -> None:
    for w in messages:
        warnings.warn(w, RobokrigeWarning, stacklevel=3)


class ErrorModel:
    """Universal-Kriging model of a robot's TCP error over the extended joint
    space ``[θ, λ]``: one model per axis (ex, ey, ez).

    The defaults are those of ``robokrige fit`` (the ``recommended`` method:
    EJS, constant trend, a nugget estimated, each axis's correlation family
    chosen by CV, BFGS, seed 1), so the same data gives the same model file
    as the command line.

    Parameters
    ----------
    space : {"ejs", "js"}
        Extended joint space ``[θ, λ]`` or joint space ``[θ]``.
    trend : {"constant", "linear", "quadratic"}
        Trend in the normalised inputs.
    nugget : bool
        Estimate a nugget (measurement noise); False interpolates, as the
        papers' Kriging.
    corr : {"auto", "gaussian", "matern52", "matern32", "exponential"}
        Correlation family; "auto" chooses each axis's by closed-form CV.
    optimizer : {"bfgs", "gps", "hj"}
        Hyperparameter search.
    starts : int, optional
        Starting points (default 8 for BFGS, 4 for GPS).
    seed : int
        Seed of the starting points (and of a method's search).
    periodic : "auto", "none" or list of int
        Joints entered as (sin θ, cos θ): "auto" (range over 180°), "none",
        or 1-based joint numbers.
    robot : str, optional
        The measured robot, a preset name or a robot file; the model records
        it and ``compensate`` refuses another.
    tool : (x, y, z), optional
        TCP offset in the flange frame (mm), replacing the robot's tool.
    kinematic : bool
        Add the robot's kinematic-error Jacobian to the trend (needs robot;
        that fit calibrates inside the Kriging, so no separate calibration).
    calibrate : bool
        With a robot (and not ``kinematic``): calibrate it first (MD-H, tool
        and base errors on the directions the campaign sees), then fit
        Kriging to what the calibration leaves; the model holds both, as
        ``robokrige fit --robot``. False: Kriging of the raw error
        (``--no-calibrate``).
    method : str, optional
        A named method instead ("recommended", "js-hj", "ejs-hj", "ejs-gps",
        "ejs-pca", "ejs-ga"): it fixes space, trend, corr, optimizer,
        nugget, starts and periodic itself.

    Attributes
    ----------
    model_ : robokrige._robokrige.Model
        The fitted model (after ``fit`` or ``load``).
    """

    def __init__(
        self,
        space: str = "ejs",
        trend: str = "constant",
        nugget: bool = True,
        corr: str = "auto",
        optimizer: str = "bfgs",
        starts: Optional[int] = None,
        seed: int = 1,
        periodic: Union[str, Sequence[int]] = "auto",
        robot: Optional[str] = None,
        tool: Optional[Tuple[float, float, float]] = None,
        kinematic: bool = False,
        calibrate: bool = True,
        method: Optional[str] = None,
    ) -> None:
        self.space = space
        self.trend = trend
        self.nugget = nugget
        self.corr = corr
        self.optimizer = optimizer
        self.starts = starts
        self.seed = seed
        self.periodic = periodic
        self.robot = robot
        self.tool = tool
        self.kinematic = kinematic
        self.calibrate = calibrate
        self.method = method

    # -- scikit-learn protocol -------------------------------------------

    def get_params(self, deep: bool = True) -> Dict[str, Any]:
        """The constructor's parameters, by name."""
        return {k: getattr(self, k) for k in _DEFAULTS}

    def set_params(self, **params: Any) -> "ErrorModel":
        """Set constructor parameters; returns self."""
        for k, v in params.items():
            if k not in _DEFAULTS:
                raise _bad(f"ErrorModel has no parameter '{k}' (known: {', '.join(_DEFAULTS)})")
            setattr(self, k, v)
        return self

    def _params(self) -> Dict[str, Any]:
        """The parameters as the extension reads them (checked types)."""
        p = self.get_params()
        p["periodic"] = _periodic_spec(p["periodic"])
        for key in ("nugget", "kinematic", "calibrate"):
            if not isinstance(p[key], (bool, np.bool_)):
                raise _bad(f"{key} must be True or False, not {p[key]!r}")
            p[key] = bool(p[key])
        for key in ("space", "trend", "corr", "optimizer"):
            if not isinstance(p[key], str):
                raise _bad(f"{key} must be a string, not {p[key]!r}")
        if p["starts"] is not None:
            if isinstance(p["starts"], bool) or int(p["starts"]) != p["starts"] or p["starts"] < 0:
                raise _bad(f"starts must be a positive integer, not {p['starts']!r}")
            p["starts"] = int(p["starts"])
        if isinstance(p["seed"], bool) or not isinstance(p["seed"], (int, np.integer)) or p["seed"] < 0:
            raise _bad(f"seed must be an integer ≥ 0, not {p['seed']!r}")
        p["seed"] = int(p["seed"])
        if p["robot"] is not None:
            p["robot"] = os.fspath(p["robot"])
        if p["tool"] is not None:
            t = np.asarray(p["tool"], dtype=np.float64).ravel()
            if t.shape != (3,):
                raise _bad(f"tool must be (x, y, z) in mm, not {p['tool']!r}")
            p["tool"] = (float(t[0]), float(t[1]), float(t[2]))
        # left at its default: not given (the library applies its default,
        # and a named method refuses only what was given)
        for key in _METHOD_FIXES:
            if p[key] == _DEFAULTS[key]:
                p[key] = None
        return p

    # -- fit and predict ---------------------------------------------------

    def fit(
        self,
        q: Any,
        dirs: Any = None,
        errors: Any = None,
        covariates: Any = None,
        *,
        progress: ProgressArg = None,
    ) -> "ErrorModel":
        """Fit on a campaign; returns self.

        ``q`` is an m × n array of joint positions (degrees) in the order
        the robot visited them, with ``errors`` (m × 3, mm) and optional
        ``dirs`` (m × n, ±1; derived from the row order when None) and
        ``covariates`` (name → m values); or a DataFrame / mapping with the
        measurement CSV's columns, or a path to a measurement CSV.

        The fit runs with the interpreter released; ``progress`` reports
        GA generations (method "ejs-ga"): see ``robokrige._progress``.
        """
        data = as_data(q, dirs, errors, covariates)
        _warn_all(data.warnings())
        params = self._params()
        with progress_for(progress, "fit") as cb:
            self.model_ = _robokrige.Model.fit(data, params, cb)
        _warn_all(self.model_.conditioning_warnings())
        return self

    def predict(
        self,
        q: Any,
        dirs: Any = None,
        return_std: bool = False,
        *,
        covariates: Any = None,
        check_coverage: bool = False,
    ) -> Union[np.ndarray, Tuple[np.ndarray, np.ndarray]]:
        """Predicted TCP errors (m × 3, mm) at poses ``q`` approached in
        directions ``dirs``, and with ``return_std`` their standard
        deviations √MSE (m × 3): of the predicted error, a calibration's
        uncertainty included, the measurement noise not (add
        ``model_.noise_std()`` in quadrature for a new measurement's).

        ``q`` may also be a DataFrame / mapping with ``q1..qN`` (and
        ``dir1..dirN``, covariates) or a path to a CSV. Without directions
        they are derived from the row order, the first pose taking +1 on
        every joint: a warning says how much that assumption is worth, as
        ``robokrige predict`` does. A model with effects added by
        ``diagnose`` needs their covariate columns.

        With ``check_coverage``, poses that leave what the training campaign
        covers are reported as warnings (a joint outside its range, a
        standard deviation near the prior, a wild trend).
        """
        model = self._fitted()
        data = as_data(q, dirs, None, covariates)
        mean, std = model.predict(data, return_std)
        if data.dir_source == "derived" and model.space == "ejs" and len(data) > 0:
            d0 = data.dirs[0]
            worth = model.direction_sensitivity(data.q[0].tolist(), d0.tolist())
            if worth > 0.0:
                warnings.warn(
                    f"no directions given: λ is derived from the row order, and the first pose gets "
                    f"λ = +1 on every joint (assumed). Reversing it changes that pose's prediction by "
                    f"{worth:.3f} mm: give dirs, or put the pose the robot came from first.",
                    RobokrigeWarning,
                    stacklevel=2,
                )
        if check_coverage:
            issues = model.coverage(data, mean, std)
            if issues:
                lines = [f"row {i + 1}: {'; '.join(msgs)}" for i, msgs in issues[:20]]
                warnings.warn(
                    f"{len(issues)} of {len(data)} pose(s) leave what the training campaign covers; "
                    "their predictions are extrapolations: " + " | ".join(lines),
                    RobokrigeWarning,
                    stacklevel=2,
                )
        return (mean, std) if return_std else mean

    def score(self, q: Any, dirs: Any = None, errors: Any = None, covariates: Any = None) -> float:
        """Mean 3D error (mm) left after subtracting the prediction from the
        measured ``errors`` (lower is better; not scikit-learn's R²)."""
        data = as_data(q, dirs, errors, covariates)
        if data.errors is None:
            raise _bad("score needs measured errors (ex, ey, ez)")
        mean = self._fitted().predict(data, False)[0]
        return float(np.mean(np.linalg.norm(data.errors - mean, axis=1)))

    # -- files -------------------------------------------------------------

    def save(self, path: PathLike) -> None:
        """Write the model file: the JSON of ``robokrige fit -o``, loadable
        by the command line (``predict``, ``compensate``) and by ``load``."""
        self._fitted().save(os.fspath(path))

    @classmethod
    def load(cls, path: PathLike) -> "ErrorModel":
        """Read a model file written by ``save`` or by ``robokrige fit``.
        The parameters are read back from the model's options."""
        return cls._wrap(_robokrige.Model.load(os.fspath(path)))

    def to_json(self) -> str:
        """The model file's JSON text."""
        return self._fitted().to_json()

    @classmethod
    def from_json(cls, text: str) -> "ErrorModel":
        """A model from model-file JSON text."""
        return cls._wrap(_robokrige.Model.from_json(text))

    @classmethod
    def _wrap(cls, model: "_robokrige.Model") -> "ErrorModel":
        opts = json.loads(model.options_json())
        periodic = list(model.periodic)
        est = cls(
            space=model.space,
            trend=opts.get("trend", "constant"),
            nugget=model.nugget,
            corr="auto" if model.corr_auto else model.families[0],
            optimizer={"hooke-jeeves": "hj"}.get(opts.get("optimizer", "bfgs"), opts.get("optimizer", "bfgs")),
            seed=int(opts.get("seed", 1)),
            periodic=",".join(str(j + 1) for j in periodic) if periodic else "none",
        )
        est.model_ = model
        return est

    # -- fitted attributes ---------------------------------------------------

    def _fitted(self) -> "_robokrige.Model":
        model = getattr(self, "model_", None)
        if model is None:
            raise _bad("this ErrorModel is not fitted yet: call fit() or ErrorModel.load()")
        return model

    @property
    def space_(self) -> str:
        """"ejs" or "js"."""
        return self._fitted().space

    @property
    def n_joints_(self) -> int:
        """Joints of the robot."""
        return self._fitted().n_joints

    @property
    def n_rows_(self) -> int:
        """Training rows."""
        return self._fitted().n_rows

    @property
    def families_(self) -> List[str]:
        """Correlation family of each axis (ex, ey, ez)."""
        return self._fitted().families

    @property
    def input_names_(self) -> List[str]:
        """Name of every input column (space encoding, then extras)."""
        return self._fitted().input_names

    @property
    def extras_(self) -> List[str]:
        """Extra inputs (effects added by ``diagnose``)."""
        return self._fitted().extras

    @property
    def reports_(self) -> List[Dict[str, Any]]:
        """Per-axis fit reports (ln ψ, ξ, nugget, trend terms, evaluations,
        the family table), as in the model file."""
        return json.loads(self._fitted().reports_json())

    @property
    def robot_(self) -> Optional[Dict[str, Any]]:
        """The robot the model records (name, table digest, tool), if any."""
        return json.loads(self._fitted().robot_json())

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, ErrorModel):
            return NotImplemented
        a, b = getattr(self, "model_", None), getattr(other, "model_", None)
        return a is not None and b is not None and a == b

    __hash__ = None  # type: ignore[assignment]

    def __repr__(self) -> str:
        changed = {k: v for k, v in self.get_params().items() if v != _DEFAULTS[k]}
        args = ", ".join(f"{k}={v!r}" for k, v in changed.items())
        fitted = "" if getattr(self, "model_", None) is None else f"  # fitted: {self.model_!r}"
        return f"ErrorModel({args}){fitted}"
