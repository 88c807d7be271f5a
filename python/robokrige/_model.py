"""``ErrorModel``: a scikit-learn regressor over the library's one fit API."""

from __future__ import annotations

import json
import os
import warnings
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np

from . import _robokrige
from ._robokrige import RobokrigeError
from ._data import PathLike, _bad, _is_frame, _Q, as_data
from ._layout import Layout, check_X, check_y, reject_sparse, resolve
from ._progress import ProgressArg, progress_for
from ._sklearn import EstimatorBase, NotFittedError


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
    joint_harmonics=True,
    backlash=False,
    method=None,
    n_joints=None,
    dirs="auto",
    covariates=None,
)

#: Model options a named method fixes itself: passed to the library only
#: when they differ from the defaults (the library refuses them with a
#: method, as ``robokrige fit --method`` does).
_METHOD_FIXES = ("space", "trend", "corr", "optimizer", "nugget", "starts", "periodic")

#: The library's model is three outputs (ex, ey, ez); other numbers of
#: outputs are fitted this many at a time.
_AXES = 3


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


def _same(a: Any, b: Any) -> bool:
    """A parameter equal to its default (arrays never are)."""
    if a is b:
        return True
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray) or type(a) is not type(b):
        return False
    return bool(a == b)


def _campaign_input(X: Any) -> bool:
    """Whether X is a campaign read by its column names or from a file: a
    path, a ``Data``, a mapping, or a DataFrame with joints ``q1..qN``
    (never a sparse matrix, which may be a dict)."""
    reject_sparse(X)
    if isinstance(X, (str, os.PathLike, _robokrige.Data, dict)):
        return True
    return _is_frame(X) and any(_Q.match(str(c)) for c in X.columns)


def r2_score(y_true: Any, y_pred: Any, sample_weight: Any = None) -> float:
    """R², as scikit-learn's ``r2_score`` (``multioutput="uniform_average"``,
    ``force_finite=True``): ``1 − Σ w(y − ŷ)² / Σ w(y − ȳ)²`` per output,
    averaged over the outputs; an output whose y is constant scores 1 if
    predicted exactly, else 0. NaN for fewer than two samples."""
    yt = np.asarray(y_true, dtype=np.float64)
    yp = np.asarray(y_pred, dtype=np.float64)
    yt = yt.reshape(len(yt), -1)
    yp = yp.reshape(len(yp), -1)
    if yt.shape != yp.shape:
        raise RobokrigeError(f"y_true and y_pred have different shapes: {yt.shape} and {yp.shape}")
    if yt.shape[0] < 2:
        warnings.warn("R² is not well-defined with less than two samples.", RobokrigeWarning, stacklevel=2)
        return float("nan")
    w = np.ones(yt.shape[0]) if sample_weight is None else np.asarray(sample_weight, dtype=np.float64).ravel()
    if w.shape != (yt.shape[0],):
        raise RobokrigeError(f"sample_weight has {w.size} values for {yt.shape[0]} samples")
    num = (w[:, None] * (yt - yp) ** 2).sum(axis=0)
    den = (w[:, None] * (yt - np.average(yt, axis=0, weights=w)) ** 2).sum(axis=0)
    scores = np.ones(yt.shape[1])
    valid = (den != 0) & (num != 0)
    scores[valid] = 1.0 - num[valid] / den[valid]
    scores[(num != 0) & (den == 0)] = 0.0
    return float(np.mean(scores))


class ErrorModel(EstimatorBase):
    """Universal-Kriging model of a robot's TCP error over the extended joint
    space ``[θ, λ]``: one model per axis (ex, ey, ez). A scikit-learn
    regressor: ``fit(X, y)``, ``predict(X)``, ``score`` (R²), and it works in
    ``Pipeline``, ``cross_val_score``, ``GridSearchCV``, ``clone`` and
    ``check_estimator``.

    The defaults are those of ``robokrige fit`` (the ``recommended`` method:
    EJS, constant trend, a nugget estimated, each axis's correlation family
    chosen by CV, BFGS, seed 1), so the same data gives the same model file
    as the command line.

    **Two ways to fit.** ``fit(X, y)`` is scikit-learn's: X's columns are
    the joints (degrees), then their directions λ (±1), then any covariates
    (see ``n_joints``, ``dirs``, ``covariates``; a DataFrame's are read by
    name), and y is n × 3 (ex, ey, ez, mm; other numbers of outputs work
    too). The campaign form ``fit(q, dirs, errors, covariates)``, or
    ``fit(campaign)`` with a DataFrame, mapping, CSV path or ``Data`` that
    holds ``ex,ey,ez``, fits exactly what ``robokrige fit`` fits on that
    campaign (its covariates are carried, not model inputs). A call is the
    campaign form when it passes ``errors``, ``covariates`` or ``dirs=``,
    or a campaign without y.

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
    joint_harmonics : bool
        With the calibration: also identify the joints' periodic (gear
        transmission) errors, each period added only when the residual
        noise cannot explain it. False: the MD-H, tool and base errors
        alone (``--geometric``).
    backlash : bool
        With the calibration: also identify each joint's backlash (a joint
        offset that follows the direction it approached from), the
        geometry fitted beside it (``--backlash``). Off by default: for
        robots whose gears have play.
    method : str, optional
        A named method instead ("recommended", "js-hj", "ejs-hj", "ejs-gps",
        "ejs-pca", "ejs-ga"): it fixes space, trend, corr, optimizer,
        nugget, starts and periodic itself.
    n_joints : int, optional
        ``fit(X, y)``: the joints are X's first ``n_joints`` columns. None:
        from ``dirs`` and the number of columns.
    dirs : {"auto", "columns", "derive", "none"}
        ``fit(X, y)``: where the directions λ come from. "columns": the
        ``n_joints`` columns after the joints. "derive": from the row order
        of X, as the command line derives them for a CSV without direction
        columns; right only when X's rows are the campaign in visiting
        order, so not under a CV splitter that picks rows (derive them once
        on the whole campaign with ``derive_directions`` and give them as
        columns instead). "none": no directions; the model is fitted in
        joint space. "auto" (default): "columns" when X has them (a
        DataFrame's ``dir1..dirN``, or as many ±1 columns after the joints),
        else "none", with a warning.
    covariates : list of str, optional
        ``fit(X, y)``: covariate columns (temperature, time, …) that enter
        the model as inputs, each with its own correlation length and a
        linear trend term. Arrays: the last ``len(covariates)`` columns, so
        named. A DataFrame: these columns; None: every column that is not a
        joint or a direction.

    Attributes
    ----------
    model_ : robokrige._robokrige.Model
        The fitted model (after ``fit`` or ``load``).
    models_ : tuple of robokrige._robokrige.Model
        The library's models: one for three outputs, one per three outputs
        otherwise (the last padded with zero outputs).
    n_outputs_ : int
        Outputs fitted (3 for ex, ey, ez).
    n_features_in_ : int
        Columns of X that ``predict(X)`` takes.
    feature_names_in_ : ndarray of str
        X's column names, when fitted on a DataFrame.
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
        joint_harmonics: bool = True,
        backlash: bool = False,
        method: Optional[str] = None,
        n_joints: Optional[int] = None,
        dirs: str = "auto",
        covariates: Optional[Sequence[str]] = None,
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
        self.joint_harmonics = joint_harmonics
        self.backlash = backlash
        self.method = method
        self.n_joints = n_joints
        self.dirs = dirs
        self.covariates = covariates

    # -- scikit-learn protocol -------------------------------------------

    def get_params(self, deep: bool = True) -> Dict[str, Any]:
        """The constructor's parameters, by name, as given."""
        return {k: getattr(self, k) for k in _DEFAULTS}

    def set_params(self, **params: Any) -> "ErrorModel":
        """Set constructor parameters; returns self. Values are checked by
        ``fit``."""
        for k, v in params.items():
            if k not in _DEFAULTS:
                raise _bad(f"ErrorModel has no parameter '{k}' (known: {', '.join(_DEFAULTS)})")
            setattr(self, k, v)
        return self

    def __sklearn_tags__(self) -> Any:
        """scikit-learn's tags: a regressor of one or several outputs (y n × 3
        for a TCP error), fitted on dense numeric X without NaN (the
        library refuses NaN and inf in joints, directions, covariates and
        y), deterministic for a given seed."""
        from sklearn.utils import InputTags, RegressorTags, Tags, TargetTags

        return Tags(
            estimator_type="regressor",
            target_tags=TargetTags(required=True, multi_output=True, single_output=True),
            regressor_tags=RegressorTags(),
            input_tags=InputTags(allow_nan=False, sparse=False),
        )

    def __sklearn_is_fitted__(self) -> bool:
        return getattr(self, "models_", None) is not None

    def _params(self) -> Dict[str, Any]:
        """The parameters as the extension reads them (checked types)."""
        p = {k: v for k, v in self.get_params().items() if k not in ("n_joints", "dirs", "covariates")}
        p["periodic"] = _periodic_spec(p["periodic"])
        for key in ("nugget", "kinematic", "calibrate", "joint_harmonics", "backlash"):
            if not isinstance(p[key], (bool, np.bool_)):
                raise _bad(f"{key} must be True or False, not {p[key]!r}")
            p[key] = bool(p[key])
        for key in ("space", "trend", "corr", "optimizer"):
            if not isinstance(p[key], str):
                raise _bad(f"{key} must be a string, not {p[key]!r}")
        if p["method"] is not None and not isinstance(p["method"], str):
            raise _bad(f"method must be a string or None, not {p['method']!r}")
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
            if _same(p[key], _DEFAULTS[key]):
                p[key] = None
        p["covariate_inputs"] = None
        return p

    # -- fit ---------------------------------------------------------------

    def fit(
        self,
        X: Any,
        y: Any = None,
        errors: Any = None,
        covariates: Any = None,
        *,
        dirs: Any = None,
        progress: ProgressArg = None,
    ) -> "ErrorModel":
        """Fit; returns self.

        ``fit(X, y)``: scikit-learn's form. X (array or DataFrame, n rows)
        holds the joints (degrees) in its first columns, then their
        directions λ (±1), then any covariates, as the constructor's
        ``n_joints``, ``dirs`` and ``covariates`` say (a DataFrame's columns
        by name: ``q1..qN``, ``dir1..dirN``, covariates); y is n × 3 (ex,
        ey, ez in mm), or 1-D, or n × k.

        The campaign form, as ``robokrige fit``: ``fit(q, dirs, errors,
        covariates)`` with ``q`` m × n joints in visiting order, ``errors``
        m × 3 mm, optional ``dirs`` (m × n ±1; derived from the row order
        when None) and ``covariates`` (name → m values, carried for
        ``diagnose``, not model inputs); or ``fit(campaign)`` with a
        DataFrame / mapping with the measurement CSV's columns, a CSV path
        or a ``Data``. It is recognised by ``errors``, ``covariates`` or
        ``dirs=`` given, or by a campaign without y.

        The fit runs on a worker thread with the interpreter released;
        Ctrl-C stops it within a second (KeyboardInterrupt). ``progress``
        reports GA generations (method "ejs-ga"): see
        ``robokrige._progress``.
        """
        reject_sparse(X)
        if errors is not None or covariates is not None or dirs is not None:
            if y is not None and dirs is not None:
                raise _bad("give the directions once: as the second argument or as dirs=")
            return self._fit_campaign(as_data(X, dirs if dirs is not None else y, errors, covariates), progress)
        if y is None:
            if _campaign_input(X):
                return self._fit_campaign(as_data(X), progress)
            raise RobokrigeError(f"{type(self).__name__} requires y to be passed, but the target y is None")
        if isinstance(X, (str, os.PathLike, _robokrige.Data, dict)):
            raise _bad("fit(X, y) takes X as an array or a DataFrame; a campaign (file, Data, mapping) holds its errors")
        return self._fit_xy(X, y, progress)

    def _fit_campaign(self, data: "_robokrige.Data", progress: ProgressArg) -> "ErrorModel":
        _warn_all(data.warnings())
        with progress_for(progress, "fit") as cb:
            model = _robokrige.Model.fit(data, self._params(), cb)
        _warn_all(model.conditioning_warnings())
        self._attach((model,), _AXES, False, Layout(model.n_joints, "columns", (), None))
        return self

    def _fit_xy(self, X: Any, y: Any, progress: ProgressArg) -> "ErrorModel":
        name = type(self).__name__
        layout, a = resolve(X, self.n_joints, self.dirs, self.covariates, name)
        yy, one_d = check_y(y, a.shape[0])
        params = self._params()
        k = yy.shape[1]
        if k != _AXES and params["robot"] is not None:
            raise _bad(
                f"y has {k} output(s): a robot's calibration and kinematic trend model the TCP error, "
                "three outputs (ex, ey, ez)"
            )
        if layout.dirs == "none":
            if params["method"] not in (None, "js-hj"):
                raise _bad(
                    f"method '{params['method']}' models the directions λ, and X has no direction columns: add "
                    "them (derive_directions(q) on the whole campaign) or set dirs='derive'"
                )
            if params["method"] is None:
                if params["space"] is None and self.dirs == "auto":
                    warnings.warn(
                        "X has no direction columns: the model is fitted over the joints alone (joint space); "
                        "give the directions as columns after the joints (derive_directions(q) derives them "
                        "from the visiting order) to model the backlash, or set space='js' or dirs='none'",
                        RobokrigeWarning,
                        stacklevel=3,
                    )
                params["space"] = "js"
        params["covariate_inputs"] = list(layout.covariates) or None
        models = []
        with progress_for(progress, "fit") as cb:
            for g in range(0, k, _AXES):
                block = np.zeros((yy.shape[0], _AXES))
                block[:, : min(_AXES, k - g)] = yy[:, g : g + _AXES]
                data = layout.data(a, block)
                if g == 0:
                    _warn_all(data.warnings())
                models.append(_robokrige.Model.fit(data, params, cb))
        for m in models:
            _warn_all(m.conditioning_warnings())
        self._attach(tuple(models), k, one_d, layout)
        return self

    def _attach(self, models: Tuple["_robokrige.Model", ...], n_outputs: int, one_d: bool, layout: Layout) -> None:
        """Set the fitted attributes."""
        self.model_ = models[0]
        self.models_ = models
        self.n_outputs_ = n_outputs
        self.n_features_in_ = layout.n_features
        if layout.names is not None:
            self.feature_names_in_ = np.asarray(layout.names, dtype=object)
        elif "feature_names_in_" in self.__dict__:
            del self.feature_names_in_
        self._layout = layout
        self._y_1d = one_d

    # -- predict and score -------------------------------------------------

    def predict(
        self,
        X: Any,
        dirs: Any = None,
        return_std: bool = False,
        *,
        covariates: Any = None,
        check_coverage: bool = False,
    ) -> Union[np.ndarray, Tuple[np.ndarray, np.ndarray]]:
        """Predicted TCP errors (n × 3, mm; as y's shape in ``fit``) at the
        poses of X, and with ``return_std`` their standard deviations √MSE:
        of the predicted error, a calibration's uncertainty included, the
        measurement noise not (add ``model_.noise_std()`` in quadrature for
        a new measurement's). Both are calibrated on the model's
        leave-one-out residuals, so that 95 % of them fall inside
        ``±1.96`` standard deviations of a new measurement.

        X as in ``fit(X, y)`` (``n_features_in_`` columns); or, the campaign
        form, joints ``q`` alone (``n_joints_`` columns) with ``dirs`` and
        ``covariates``, a DataFrame / mapping with ``q1..qN`` (and
        ``dir1..dirN``, covariates) or a CSV path. Without directions they
        are derived from the row order, the first pose taking +1 on every
        joint: a warning says how much that assumption is worth, as
        ``robokrige predict`` does. A model with effects added by
        ``diagnose`` needs their covariate columns.

        With ``check_coverage``, poses that leave what the training campaign
        covers are reported as warnings (a joint outside its range, a
        standard deviation near the prior, a wild trend).
        """
        models = self._models()
        if dirs is None and covariates is None and not _campaign_input(X):
            a = check_X(X, type(self).__name__, 1)
            layout: Layout = self._layout
            if a.shape[1] == layout.n_features and layout.names is None:
                data = layout.data(a)
            elif layout.names is not None and a.shape[1] == len(layout.names):
                # fitted on a DataFrame: the columns in its order
                data = as_data({name: a[:, i] for i, name in enumerate(layout.names)})
            elif a.shape[1] == self.model_.n_joints:
                data = as_data(a)
            else:
                raise RobokrigeError(
                    f"X has {a.shape[1]} features, but {type(self).__name__} is expecting {self.n_features_in_} "
                    "features as input."
                )
        else:
            data = as_data(X, dirs, None, covariates)
        results = [m.predict(data, return_std) for m in models]
        self._warn_derived(data)
        if check_coverage:
            self._warn_coverage(data, results[0])
        mean = self._outputs([r[0] for r in results])
        if not return_std:
            return mean
        return mean, self._outputs([r[1] for r in results])

    def _outputs(self, blocks: List[Any]) -> np.ndarray:
        """The fitted outputs of the models' n × 3 blocks, in y's shape."""
        out = blocks[0] if len(blocks) == 1 else np.hstack(blocks)
        out = out[:, : self.n_outputs_]
        return out[:, 0] if self._y_1d else out

    def _warn_derived(self, data: "_robokrige.Data") -> None:
        model = self.model_
        if data.dir_source == "derived" and model.space == "ejs" and len(data) > 0:
            d0 = data.dirs[0]
            worth = model.direction_sensitivity(data.q[0].tolist(), d0.tolist())
            if worth > 0.0:
                warnings.warn(
                    f"no directions given: λ is derived from the row order, and the first pose gets "
                    f"λ = +1 on every joint (assumed). Reversing it changes that pose's prediction by "
                    f"{worth:.3f} mm: give dirs, or put the pose the robot came from first.",
                    RobokrigeWarning,
                    stacklevel=3,
                )

    def _warn_coverage(self, data: "_robokrige.Data", first: Tuple[np.ndarray, Optional[np.ndarray]]) -> None:
        issues = self.model_.coverage(data, first[0], first[1])
        if issues:
            lines = [f"row {i + 1}: {'; '.join(msgs)}" for i, msgs in issues[:20]]
            warnings.warn(
                f"{len(issues)} of {len(data)} pose(s) leave what the training campaign covers; "
                "their predictions are extrapolations: " + " | ".join(lines),
                RobokrigeWarning,
                stacklevel=3,
            )

    def score(self, X: Any, y: Any, sample_weight: Any = None) -> float:
        """R² of ``predict(X)`` against y, as scikit-learn's regressors
        define it (``r2_score``, the outputs averaged): 1 is perfect, 0 is
        the mean of y. For the mean 3D error left after compensation, see
        ``mean_3d_error``."""
        return r2_score(y, self.predict(X), sample_weight)

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
    def _wrap(cls, model: "_robokrige.Model", **params: Any) -> "ErrorModel":
        """An estimator holding ``model``, its parameters read back from the
        model's options (``params`` override them)."""
        opts = json.loads(model.options_json())
        periodic = list(model.periodic)
        found: Dict[str, Any] = dict(
            space=model.space,
            trend=opts.get("trend", "constant"),
            nugget=model.nugget,
            corr="auto" if model.corr_auto else model.families[0],
            optimizer={"hooke-jeeves": "hj"}.get(opts.get("optimizer", "bfgs"), opts.get("optimizer", "bfgs")),
            seed=int(opts.get("seed", 1)),
            periodic=",".join(str(j + 1) for j in periodic) if periodic else "none",
        )
        found.update(params)
        est = cls(**found)
        est._attach((model,), _AXES, False, Layout(model.n_joints, "columns", (), None))
        return est

    # -- fitted attributes ---------------------------------------------------

    def _models(self) -> Tuple["_robokrige.Model", ...]:
        models: Optional[Tuple["_robokrige.Model", ...]] = getattr(self, "models_", None)
        if models is None:
            raise NotFittedError(
                f"This {type(self).__name__} instance is not fitted yet: call fit() or ErrorModel.load() first"
            )
        return models

    def _fitted(self) -> "_robokrige.Model":
        """The one library model of a fit of the TCP error's three outputs."""
        models = self._models()
        if self.n_outputs_ != _AXES:
            raise _bad(
                f"this ErrorModel was fitted on {self.n_outputs_} output(s); a model file, compensate and the "
                "model's reports hold the TCP error's three (ex, ey, ez)"
            )
        return models[0]

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
        """Extra inputs (covariates, effects added by ``diagnose``)."""
        return self._fitted().extras

    @property
    def reports_(self) -> List[Dict[str, Any]]:
        """Per-axis fit reports (ln ψ, ξ, nugget, trend terms, evaluations,
        the family table), as in the model file."""
        reports: List[Dict[str, Any]] = json.loads(self._fitted().reports_json())
        return reports

    @property
    def robot_(self) -> Optional[Dict[str, Any]]:
        """The robot the model records (name, table digest, tool), if any."""
        robot: Optional[Dict[str, Any]] = json.loads(self._fitted().robot_json())
        return robot

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, ErrorModel):
            return NotImplemented
        a, b = getattr(self, "models_", None), getattr(other, "models_", None)
        return a is not None and b is not None and a == b and self.n_outputs_ == other.n_outputs_

    __hash__ = None  # type: ignore[assignment]

    def __repr__(self) -> str:
        changed = {k: v for k, v in self.get_params().items() if not _same(v, _DEFAULTS[k])}
        args = ", ".join(f"{k}={v!r}" for k, v in changed.items())
        models = getattr(self, "models_", None)
        fitted = "" if models is None else f"  # fitted: {', '.join(repr(m) for m in models)}"
        return f"ErrorModel({args}){fitted}"


def mean_3d_error(model: ErrorModel, q: Any, dirs: Any = None, errors: Any = None, covariates: Any = None) -> float:
    """Mean 3D error (mm) left after subtracting ``model``'s prediction from
    the measured errors: what compensation would leave (lower is better;
    ``ErrorModel.score`` is scikit-learn's R²). The campaign as to
    ``ErrorModel.fit``'s campaign form."""
    data = as_data(q, dirs, errors, covariates)
    if data.errors is None:
        raise _bad("mean_3d_error needs measured errors (ex, ey, ez)")
    mean = model._fitted().predict(data, False)[0]
    return float(np.mean(np.linalg.norm(data.errors - mean, axis=1)))
