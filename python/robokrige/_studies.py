"""Cross-validation, compensation and diagnosis, with the command line's
defaults (``robokrige cv``, ``compensate``, ``diagnose``)."""

from __future__ import annotations

import json
import os
import warnings
from typing import Any, Dict, NamedTuple, Optional, Sequence, Tuple, Union

import numpy as np

from . import _robokrige
from ._data import PathLike, _bad, _columns, _is_frame, _matrix, _numbered, _Q, _stack, as_data
from ._model import ErrorModel, RobokrigeWarning
from ._progress import ProgressArg, progress_for


def _estimator(model: Any) -> ErrorModel:
    if model is None:
        return ErrorModel()
    if isinstance(model, ErrorModel):
        return model
    if isinstance(model, dict):
        return ErrorModel(**model)
    raise _bad("model must be an ErrorModel (its parameters are used), a dict of its parameters, or None")


def cross_validate(
    model: Any,
    q: Any,
    dirs: Any = None,
    errors: Any = None,
    covariates: Any = None,
    *,
    folds: int = 10,
    cv_seed: int = 1,
    mode: str = "refit",
    as_frame: bool = False,
    progress: ProgressArg = None,
) -> Any:
    """K-fold cross-validation of a model choice, as ``robokrige cv``.

    ``model`` is an ``ErrorModel`` whose parameters are cross-validated (it
    is not fitted or changed), a dict of them, or None for the defaults.
    The campaign is given as to ``ErrorModel.fit``. ``mode`` is "refit"
    (hyperparameters re-optimised on every training fold: honest) or
    "closed-form" (one fit's ξ, fold residuals from the bordered system:
    fast, optimistic). The fold partition is seeded by ``cv_seed``.

    Returns a dict: ``folds``, ``seed``, ``mode``, ``fold`` (fold of every
    row), ``residuals`` (m × 3 out-of-fold δ − δ̂, mm), ``summary``
    (``rms_mm`` per axis, ``mean_3d_mm``, ``std_3d_mm``, ``min_3d_mm``,
    ``max_3d_mm``, ``mean_mm``, ``box_3d_mm``, ``n``) and ``seconds``.
    With ``as_frame`` (pandas), a DataFrame with one row per pose (fold,
    residuals, 3D error) whose ``attrs`` hold the rest.
    """
    est = _estimator(model)
    data = as_data(q, dirs, errors, covariates)
    with progress_for(progress, "cv") as cb:
        text = _robokrige.cross_validate(data, est._params(), int(folds), int(cv_seed), mode, cb)
    res = json.loads(text)
    res["fold"] = np.asarray(res["fold"], dtype=np.int64)
    res["residuals"] = np.asarray(res["residuals"], dtype=np.float64).reshape(-1, 3)
    if not as_frame:
        return res
    import pandas as pd

    r = res["residuals"]
    df = pd.DataFrame(
        {
            "fold": res["fold"],
            "res_ex": r[:, 0],
            "res_ey": r[:, 1],
            "res_ez": r[:, 2],
            "res_3d": np.linalg.norm(r, axis=1),
        }
    )
    df.attrs.update({k: v for k, v in res.items() if k not in ("fold", "residuals")})
    return df


def _targets(targets: Any) -> Dict[str, Any]:
    """The keyword arguments that name the targets for the extension."""
    if isinstance(targets, (str, os.PathLike)):
        return {"path": os.fspath(targets)}
    if _is_frame(targets) or isinstance(targets, dict):
        cols = _columns(targets)
        qn = _numbered(cols, _Q)
        if qn:
            return {"joints": _stack(cols, qn, "targets")}
        if not all(c in cols for c in ("x", "y", "z")):
            raise _bad("targets need columns x, y, z (mm) or q1..qN (joint poses)")
        out: Dict[str, Any] = {"xyz": _stack(cols, ("x", "y", "z"), "targets")}
        rpy = ("roll_deg", "pitch_deg", "yaw_deg")
        if all(c in cols for c in rpy):
            out["rpy"] = _stack(cols, rpy, "targets")
        elif any(c in cols for c in rpy):
            raise _bad("give all of roll_deg, pitch_deg, yaw_deg or none")
        return out
    a = _matrix(targets, "targets")
    if a.shape[1] == 3:
        return {"xyz": a}
    if a.shape[1] == 6:
        return {"xyz": np.ascontiguousarray(a[:, :3]), "rpy": np.ascontiguousarray(a[:, 3:])}
    raise _bad(
        f"targets array must be k × 3 (x, y, z mm) or k × 6 (with roll, pitch, yaw deg); got shape {a.shape}; "
        "joint poses go in a DataFrame with q1..qN columns"
    )


def compensate(
    model: Union[ErrorModel, "_robokrige.Model", "_robokrige.PhysicsModel", PathLike],
    robot: Union[str, PathLike],
    targets: Any,
    iterative: bool = True,
    *,
    tol: float = 1e-3,
    max_iter: int = 10,
    start: Optional[Sequence[float]] = None,
    orientation: Optional[Sequence[float]] = None,
    tool: Optional[Tuple[float, float, float]] = None,
    truth: Optional[PathLike] = None,
    truth_seed: int = 1,
) -> Dict[str, Any]:
    """Pre-compensate a trajectory for ``robot`` with a fitted ``model``
    (feed-forward), as ``robokrige compensate``.

    ``model`` is a fitted ``ErrorModel``, a ``PhysicsModel`` (``robokrige
    physics identify``'s lookup-table model, ``PhysicsModel.load``), or a
    model file of either kind (read as ``compensate --model`` reads it).

    ``robot`` is a preset name or a robot file; it must be the robot the
    model records. ``targets`` is a trajectory CSV or pose-list CSV path, a
    DataFrame with ``x,y,z`` (and ``roll_deg,pitch_deg,yaw_deg``) or with
    ``q1..qN`` (joint poses, whose nominal TCP poses become the targets), or
    an array k × 3 (x, y, z mm) or k × 6 (with roll, pitch, yaw degrees).
    Position-only targets of a six-axis robot keep ``orientation`` (roll,
    pitch, yaw degrees), else the start pose's. ``iterative`` runs seed 004's
    loop (to ``tol`` mm, at most ``max_iter`` iterations), else the single
    step of seed 003. With ``truth`` (a simulator truth file) the nominal
    and compensated commands are also run on the simulated robot.

    Returns a dict: ``model`` ("kriging" or "physics"), ``xyz`` and ``rpy``
    (the corrected commands: k × 3 mm,
    k × 3 degrees or None), ``joints`` and ``dirs`` (their nominal IK joints
    and directions), ``predicted`` (k × 3 δ̂ there), ``history`` (one dict
    per iteration), ``converged``, ``stop``, ``unsettled``, ``coverage`` and
    ``seconds``; with ``truth``, ``evaluation`` (``summary`` and the
    measured ``before`` / ``after`` errors, k × 3).
    """
    m: Union["_robokrige.Model", "_robokrige.PhysicsModel", str]
    if isinstance(model, ErrorModel):
        m = model._fitted()
    elif isinstance(model, (_robokrige.Model, _robokrige.PhysicsModel)):
        m = model
    elif isinstance(model, (str, os.PathLike)):
        m = os.fspath(model)
    else:
        raise _bad("model must be a fitted ErrorModel, a PhysicsModel or a model file")
    kw = _targets(targets)
    if tool is not None:
        t = np.asarray(tool, dtype=np.float64).ravel()
        if t.shape != (3,):
            raise _bad(f"tool must be (x, y, z) in mm, not {tool!r}")
        kw["tool"] = (float(t[0]), float(t[1]), float(t[2]))
    if start is not None:
        kw["start"] = [float(v) for v in start]
    if orientation is not None:
        kw["orientation"] = [float(v) for v in orientation]
    if truth is not None:
        kw["truth"] = os.fspath(truth)
    text = _robokrige.compensate(
        m,
        os.fspath(robot),
        iterative=bool(iterative),
        tol=float(tol),
        max_iter=int(max_iter),
        truth_seed=int(truth_seed),
        **kw,
    )
    res: Dict[str, Any] = json.loads(text)
    k = len(res["xyz"])
    res["xyz"] = np.asarray(res["xyz"], dtype=np.float64).reshape(k, 3)
    if res["rpy"] is not None:
        res["rpy"] = np.asarray(res["rpy"], dtype=np.float64).reshape(k, 3)
    res["joints"] = np.asarray(res["joints"], dtype=np.float64).reshape(k, -1)
    res["dirs"] = np.asarray(res.pop("dir"), dtype=np.float64).reshape(k, -1)
    res["predicted"] = np.asarray(res["predicted"], dtype=np.float64).reshape(k, 3)
    ev = res.get("evaluation")
    if ev is not None:
        ev["before"] = np.asarray(ev["before"], dtype=np.float64).reshape(k, 3)
        ev["after"] = np.asarray(ev["after"], dtype=np.float64).reshape(k, 3)
    if res["coverage"]:
        warnings.warn(
            f"{len(res['coverage'])} of {k} compensated pose(s) leave what the training campaign covers",
            RobokrigeWarning,
            stacklevel=2,
        )
    if res["stop"] == "stalled":
        warnings.warn(
            f"the change stalled above {tol} mm at direction reversals; λ still switching at points "
            f"{res['unsettled'][:20]}",
            RobokrigeWarning,
            stacklevel=2,
        )
    elif res["stop"] == "max-iterations":
        warnings.warn(
            f"the change did not fall below {tol} mm in {max_iter} iterations", RobokrigeWarning, stacklevel=2
        )
    return res


class Diagnosis(NamedTuple):
    """What ``diagnose`` returns: unpack as ``effects, model, report``."""

    #: Every candidate of every round (DataFrame with pandas, else a list of
    #: dicts): round, kind, label, score, p_value, q_value, significant,
    #: accepted, note, …
    effects: Any
    #: The model with the accepted effects, refitted on all rows (the
    #: base model when nothing was added).
    model: ErrorModel
    #: The whole diagnosis: ``before``, ``after`` and ``steps`` (CV
    #: statistics), ``before_residuals`` / ``after_residuals`` (m × 3),
    #: ``extras``, ``dropped_covariates``, settings, ``seconds``.
    report: Dict[str, Any]


def diagnose(
    q: Any,
    dirs: Any = None,
    errors: Any = None,
    covariates: Any = None,
    *,
    method: str = "ejs",
    nugget: bool = True,
    folds: int = 10,
    seed: int = 1,
    permutations: int = 1999,
    fdr: float = 0.05,
    max_effects: int = 3,
    periodic: Union[str, Sequence[int]] = "none",
    robot: Optional[str] = None,
    refit_rows: Optional[int] = None,
    scan_rows: Optional[int] = None,
    calibrate: Optional[bool] = None,
    as_frame: Optional[bool] = None,
    progress: ProgressArg = None,
) -> Diagnosis:
    """Find what the model still gets wrong, trace it to an effect, add it
    and re-validate, as ``robokrige diagnose`` (same defaults).

    The campaign (``q`` … ``covariates``, or a DataFrame / path) needs
    measured errors; every numeric covariate column is a candidate.
    ``method`` is the base model: "ejs", "js", "js-hj", "ejs-hj" or
    "ejs-gps". ``robot`` adds joint cross-talk candidates. Above
    ``refit_rows`` rows (None: the library's default, 1 200) every CV is
    closed-form and every fit converges ξ on a subset of that many rows;
    above ``scan_rows`` (None: 3 000) the candidates are scanned on that
    many rows spread evenly over the campaign (the models compared still
    use all rows; ``report["scanned_rows"]`` of ``report["rows"]``).
    With a ``robot``, the residual of a D-H calibration of the robot is
    diagnosed and the improved model holds that calibration, as
    ``robokrige diagnose --robot`` (``calibrate=None``, the default, or
    True); ``calibrate=False`` diagnoses the raw error, as
    ``--no-calibrate``.

    Returns ``Diagnosis(effects, model, report)``: the effects table (a
    DataFrame when pandas is installed and ``as_frame`` is not False), the
    improved model (the accepted effects added, refitted on all rows) and
    the whole report.
    """
    data = as_data(q, dirs, errors, covariates)
    if isinstance(periodic, str):
        pspec = periodic
    else:
        pspec = ",".join(str(int(j)) for j in periodic)
    with progress_for(progress, "diagnose") as cb:
        text, m = _robokrige.diagnose(
            data,
            method,
            bool(nugget),
            int(folds),
            int(seed),
            int(permutations),
            float(fdr),
            int(max_effects),
            pspec,
            None if robot is None else os.fspath(robot),
            cb,
            None if refit_rows is None else int(refit_rows),
            None if scan_rows is None else int(scan_rows),
            None if calibrate is None else bool(calibrate),
        )
    report = json.loads(text)
    for key in ("before_residuals", "after_residuals"):
        report[key] = np.asarray(report[key], dtype=np.float64).reshape(-1, 3)
    est = ErrorModel._wrap(
        m,
        space="js" if method.startswith("js") else "ejs",
        corr="gaussian",
        nugget=bool(nugget),
        optimizer={"js-hj": "hj", "ejs-hj": "hj", "ejs-gps": "gps"}.get(method, "bfgs"),
        seed=int(seed),
        periodic=pspec,
    )
    effects: Any = report["effects"]
    if as_frame is not False:
        try:
            import pandas as pd

            effects = pd.DataFrame(effects)
        except ImportError:
            if as_frame:
                raise ImportError("diagnose(as_frame=True) needs pandas: pip install pandas") from None
    return Diagnosis(effects, est, report)
