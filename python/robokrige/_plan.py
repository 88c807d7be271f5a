"""``plan``: which poses to measure next, in which order, and when to stop
(``robokrige plan``)."""

from __future__ import annotations

import json
import os
from typing import Any, Dict, NamedTuple, Optional, Sequence, Tuple, Union

import numpy as np

from . import _robokrige
from ._data import PathLike, _bad, as_data
from ._model import ErrorModel


class Plan(NamedTuple):
    """What ``plan`` returns: the moves in the order the robot makes them
    (poses to measure and pre-position via-points), the summary and the
    model the plan used."""

    #: Joints of every move (k × n, degrees; mm for prismatic joints).
    q: np.ndarray
    #: The direction each joint arrives from (k × n, ±1), realised by the order.
    dirs: np.ndarray
    #: Whether to measure at each move (False: a via-point, passed only).
    measure: np.ndarray
    #: The pool row (0-based) or candidate each measured pose came from; −1
    #: for a via-point.
    source: np.ndarray
    #: The command line's ``--json``: ``source`` (of the hyperparameters:
    #: "campaign", "prior", "spacefilling"), ``candidates``, ``chosen``,
    #: ``measure``, ``imse_curve_mm2`` (the region's integrated MSE before
    #: and after each chosen pose), ``unrealised``, ``notes``, ``forecast``
    #: (with a measured campaign: ``cv_mean_3d_mm`` at the campaign's poses,
    #: ``region_ratio``, ``floor_mean_3d_mm``, ``mean_3d_mm`` over the region
    #: now and after each planned pose), and ``text``, its report.
    summary: Dict[str, Any]
    #: The model whose hyperparameters the plan used (None for a
    #: space-filling first batch).
    model: Optional[ErrorModel]

    def frame(self) -> Any:
        """The moves as the plan CSV's table (pandas): ``id, q1..qN,
        dir1..dirN, measure, source`` (``source`` empty for a via-point)."""
        import pandas as pd

        n = self.q.shape[1]
        cols: Dict[str, Any] = {"id": np.arange(len(self.q))}
        cols.update({f"q{j + 1}": self.q[:, j] for j in range(n)})
        cols.update({f"dir{j + 1}": self.dirs[:, j] for j in range(n)})
        cols["measure"] = self.measure.astype(np.int64)
        cols["source"] = pd.array([int(s) if s >= 0 else None for s in self.source], dtype="Int64")
        return pd.DataFrame(cols)


def _xyz(v: Any, what: str) -> Tuple[float, float, float]:
    a = np.asarray(v, dtype=np.float64).ravel()
    if a.shape != (3,):
        raise _bad(f"{what} must be (x, y, z) in mm, not {v!r}")
    return (float(a[0]), float(a[1]), float(a[2]))


def _model_of(prior: Any) -> Optional["_robokrige.Model"]:
    if prior is None:
        return None
    if isinstance(prior, ErrorModel):
        return prior._fitted()
    if isinstance(prior, _robokrige.Model):
        return prior
    if isinstance(prior, (str, os.PathLike)):
        return _robokrige.Model.load(os.fspath(prior))
    raise _bad("prior must be a fitted ErrorModel or a model file")


def plan(
    robot: Union[str, PathLike],
    budget: int,
    *,
    campaign: Any = None,
    prior: Any = None,
    pool: Any = None,
    region: Any = None,
    tool: Optional[Tuple[float, float, float]] = None,
    first_batch: int = 50,
    candidates: int = 5000,
    region_points: int = 1000,
    via_step: float = 5.0,
    passes: int = 1,
    tracker: Optional[Sequence[float]] = None,
    max_range: Optional[float] = None,
    max_incidence: Optional[float] = None,
    target_mm: Optional[float] = None,
    seed: int = 1,
    output: Optional[PathLike] = None,
    format: str = "csv",
) -> Plan:
    """Plan ``budget`` poses to measure on ``robot`` (preset or robot file,
    ``tool`` replacing its TCP offset), as ``robokrige plan``: chosen to
    lower the error model's integrated prediction variance over the region
    that matters, each joint's approach direction planned too, in an order
    that realises the directions (with pre-position via-points where the
    direct move cannot).

    - ``campaign``: what has been measured so far (a DataFrame, CSV path or
      ``Data`` with ``ex,ey,ez``): the hyperparameters are re-estimated on
      it and the plan continues it; with ``target_mm`` the summary says how
      many more poses the held-out error forecast needs to reach it.
    - ``prior``: a model (``ErrorModel`` or model file) of a robot of the
      same type, whose hyperparameters are used until enough is measured.
      Without either, the first batch (at most ``first_batch`` poses)
      covers the region; measure it and plan again with ``campaign``.
    - ``pool``: choose among these poses only (their errors are ignored).
    - ``region``: a task's joint poses (DataFrame ``q1..qN`` or n-column
      array, a ``Data``) or a task file (joint poses or a TCP path);
      default: the pool's poses, else the robot's working ranges.
    - ``passes``: measure in that many passes over the region, each a
      tour of the next run of poses in the order chosen (default 1: one
      tour, the shortest path); more passes keep a slow change over the
      measurement from following the joint space, at a longer path.
    - ``tracker`` (x, y, z mm, robot base frame), ``max_range`` (mm),
      ``max_incidence`` (degrees): plan only poses the tracker sees.
    - ``output``: also write the plan (``format`` "csv", "urscript",
      "krl" or "rapid"), as the command line does.

    Runs on a worker thread with the interpreter released; Ctrl-C stops it
    within a second (KeyboardInterrupt). Returns a ``Plan``.
    """
    reg: Any = None
    if isinstance(region, (str, os.PathLike)):
        reg = os.fspath(region)
    elif region is not None:
        reg = as_data(region)
    t = None if tracker is None else _xyz(tracker, "tracker")
    q, dirs, measure, source, summary, model = _robokrige.plan(
        os.fspath(robot),
        int(budget),
        tool=None if tool is None else _xyz(tool, "tool"),
        campaign=None if campaign is None else as_data(campaign),
        prior=_model_of(prior),
        pool=None if pool is None else as_data(pool),
        region=reg,
        first_batch=int(first_batch),
        candidates=int(candidates),
        region_points=int(region_points),
        via_step=float(via_step),
        passes=int(passes),
        tracker_at=t,
        max_range=None if max_range is None else float(max_range),
        max_incidence=None if max_incidence is None else float(max_incidence),
        target_mm=None if target_mm is None else float(target_mm),
        seed=int(seed),
        output=None if output is None else os.fspath(output),
        format=format,
    )
    est = None if model is None else ErrorModel._wrap(model)
    return Plan(q, dirs, measure, source, json.loads(summary), est)
