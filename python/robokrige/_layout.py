"""scikit-learn's ``fit(X, y)`` / ``predict(X)``: X and y checked as
scikit-learn checks them (its messages where its tools test for them), and
X's columns read as joints, directions and covariates (``_Layout``)."""

from __future__ import annotations

import sys
from dataclasses import dataclass
from typing import Any, List, Optional, Tuple

import numpy as np

from . import _robokrige
from ._data import _DIR, _Q, _RESERVED, _bad, _columns, _is_frame, _numbered, _stack
from ._robokrige import RobokrigeError

#: The values of ``ErrorModel(dirs=...)``.
DIRS_MODES = ("auto", "columns", "derive", "none")


def reject_sparse(X: Any) -> None:
    """TypeError for a SciPy sparse matrix or array (without importing
    SciPy: one is loaded if X is one)."""
    sparse = sys.modules.get("scipy.sparse")
    if sparse is not None and sparse.issparse(X):
        raise TypeError(
            "sparse input is not supported: X holds joint angles, directions and covariates as dense "
            "columns (X.toarray())"
        )


def check_X(X: Any, estimator: str, min_samples: int) -> np.ndarray:
    """X as a 2-D float64 array (no copy when it already is one), checked
    as scikit-learn's ``check_array`` checks it, with its messages
    (``RobokrigeError``, a ``ValueError``; a ``TypeError`` for sparse data
    and for elements that are not numbers): no sparse or complex data, 2-D,
    at least ``min_samples`` rows and one column. Values (NaN, inf) are the
    library's to check."""
    reject_sparse(X)
    a = _numeric(X, "X")
    if a.ndim != 2:
        raise RobokrigeError(
            f"Expected a 2D array, got a {a.ndim}D array of shape {a.shape} instead. Reshape your data "
            "either using array.reshape(-1, 1) if your data has a single feature or array.reshape(1, -1) "
            "if it contains a single sample."
        )
    n, p = a.shape
    _check_rows(n, a.shape, estimator, min_samples)
    if p < 1:
        raise RobokrigeError(
            f"Found array with {p} feature(s) (shape={a.shape}) while a minimum of 1 is required by {estimator}."
        )
    return a


def _numeric(values: Any, name: str) -> np.ndarray:
    """``values`` as float64: complex data refused; object or text converted
    by float() of every element (a dict raises TypeError, as in NumPy's
    conversion, which scikit-learn checks for; a word raises this error)."""
    a = np.asarray(values)
    if np.iscomplexobj(a):
        raise RobokrigeError("Complex data not supported")
    try:
        return np.asarray(a, dtype=np.float64)
    except ValueError as e:
        raise RobokrigeError(f"{name} must be numeric: {e}") from None


def _check_rows(n: int, shape: Tuple[int, ...], estimator: str, min_samples: int) -> None:
    if n < min_samples:
        raise RobokrigeError(
            f"Found array with {n} sample(s) (shape={shape}) while a minimum of {min_samples} is "
            f"required by {estimator}."
        )


def check_y(y: Any, n: int) -> Tuple[np.ndarray, bool]:
    """y as an n × k float64 array, and whether it was 1-D."""
    a = _numeric(y, "y")
    one_d = a.ndim == 1
    if one_d:
        a = a.reshape(-1, 1)
    if a.ndim != 2 or a.shape[1] < 1:
        raise RobokrigeError(f"y must be 1-D (one output) or n × k (k outputs, e.g. ex, ey, ez); got shape {a.shape}")
    if a.shape[0] != n:
        raise RobokrigeError(f"Found input variables with inconsistent numbers of samples: [{n}, {a.shape[0]}]")
    return a, one_d


@dataclass(frozen=True)
class Layout:
    """Where the joints, directions and covariates are among X's columns.

    ``dirs``: "columns" (the n columns after the joints, ±1), "derive"
    (from the row order of X: X is the campaign in visiting order) or
    "none" (no directions: the model is fitted in joint space).
    ``names``: X's column names when X was a DataFrame whose joints are
    named ``q1..qN`` (columns are then read by name), else None (by
    position: joints, then directions, then the covariates, last).
    """

    n_joints: int
    dirs: str
    covariates: Tuple[str, ...]
    names: Optional[Tuple[str, ...]]

    @property
    def n_features(self) -> int:
        """Columns of X."""
        if self.names is not None:
            return len(self.names)
        return self.n_joints * (2 if self.dirs == "columns" else 1) + len(self.covariates)

    def data(self, X: np.ndarray, errors: Optional[np.ndarray] = None, source: str = "X") -> "_robokrige.Data":
        """The campaign of X's rows (positional layout), with ``errors``."""
        n, c = self.n_joints, len(self.covariates)
        q = X[:, :n]
        dirs = X[:, n : 2 * n] if self.dirs == "columns" else None
        p = X.shape[1]
        cov = [(name, np.ascontiguousarray(X[:, p - c + j])) for j, name in enumerate(self.covariates)]
        return _robokrige.Data(q, dirs, errors, None, cov or None, None, source)


def _covariate_names(covariates: Any) -> Optional[List[str]]:
    if covariates is None:
        return None
    try:
        if isinstance(covariates, (str, bytes)):
            raise TypeError
        names = [str(c) for c in covariates]
    except TypeError:
        raise _bad(f"covariates must be a list of column names, not {covariates!r}") from None
    if len(set(names)) != len(names):
        raise _bad(f"covariates {names}: a column is named twice")
    return names


def _is_direction_block(block: np.ndarray) -> bool:
    return block.size > 0 and bool(np.all((block == 1.0) | (block == -1.0)))


def resolve(X: Any, n_joints: Any, dirs: Any, covariates: Any, estimator: str) -> Tuple[Layout, np.ndarray]:
    """The layout of X for ``fit(X, y)`` (from the constructor's
    ``n_joints``, ``dirs`` and ``covariates``, or from a DataFrame's column
    names) and X's values as joints, directions, covariates (in that order,
    by position)."""
    if dirs not in DIRS_MODES:
        raise _bad(f"dirs {dirs!r}: expected one of {', '.join(map(repr, DIRS_MODES))}")
    if n_joints is not None and (isinstance(n_joints, bool) or not isinstance(n_joints, (int, np.integer)) or n_joints < 1):
        raise _bad(f"n_joints must be a positive integer or None, not {n_joints!r}")
    cov = _covariate_names(covariates)
    if _is_frame(X) and any(_Q.match(str(c)) for c in X.columns):
        return _by_name(X, n_joints, dirs, cov, estimator)
    a = check_X(X, estimator, 3)
    p = a.shape[1]
    cov = cov or []
    rest = p - len(cov)
    if rest < 1:
        raise _bad(f"X has {p} columns: the {len(cov)} covariates leave none for the joints")
    if n_joints is not None:
        n = int(n_joints)
        fits = {"columns": rest == 2 * n, "derive": rest == n, "none": rest == n}
        if dirs == "auto":
            dirs = "columns" if fits["columns"] and _is_direction_block(a[:, n : 2 * n]) else "none"
        if not fits[dirs]:
            raise _bad(
                f"X has {p} columns: {n} joints{' and their directions' if dirs == 'columns' else ''}"
                f"{f' and {len(cov)} covariates' if cov else ''} need {n * (2 if dirs == 'columns' else 1) + len(cov)}"
            )
    elif dirs == "columns":
        if rest % 2:
            raise _bad(f"X has {rest} columns before the covariates: joints and as many directions need an even number")
        n = rest // 2
    elif dirs == "auto" and rest % 2 == 0 and _is_direction_block(a[:, rest // 2 : rest]):
        n, dirs = rest // 2, "columns"
    else:
        n, dirs = rest, "none" if dirs == "auto" else dirs
    return Layout(n, dirs, tuple(cov), None), a


def _by_name(X: Any, n_joints: Any, dirs: str, cov: Optional[List[str]], estimator: str) -> Tuple[Layout, np.ndarray]:
    """A DataFrame's layout from its column names: ``q1..qN``, ``dir1..dirN``
    and covariates (the listed ones, or every other column)."""
    _check_rows(len(X), X.shape, estimator, 3)
    cols = _columns(X)
    qn = _numbered(cols, _Q)
    dn = _numbered(cols, _DIR)
    n = len(qn)
    if n_joints is not None and int(n_joints) != n:
        raise _bad(f"n_joints is {n_joints} but X has {n} joint columns (q1..q{n})")
    if dn and len(dn) != n:
        raise _bad(f"X has {len(dn)} direction columns for {n} joints; give dir1..dir{n} or none")
    if dirs == "auto":
        dirs = "columns" if dn else "none"
    elif dirs == "columns" and not dn:
        raise _bad(f"dirs='columns' but X has no direction columns dir1..dir{n}")
    elif dirs in ("derive", "none") and dn:
        raise _bad(f"dirs={dirs!r} but X has direction columns dir1..dir{n}: drop them, or use dirs='columns'")
    reserved = [c for c in cols if c in _RESERVED]
    if reserved:
        raise _bad(
            f"X has columns {reserved}, which a campaign reserves for row labels, measured errors and TCP "
            "positions: drop them (y holds the errors)"
        )
    taken = set(qn) | set(dn)
    others = [c for c in cols if c not in taken]
    if cov is None:
        cov = others
    else:
        missing = [c for c in cov if c not in cols]
        if missing:
            raise _bad(f"covariates {missing} are not columns of X")
        unused = [c for c in others if c not in cov]
        if unused:
            raise _bad(
                f"X has columns {unused} that are neither joints (q1..q{n}), directions nor covariates: "
                "drop them, or list them in covariates"
            )
    a = _stack(cols, qn + dn + cov, "X")
    names = tuple(str(c) for c in X.columns)
    return Layout(n, dirs, tuple(cov), names), a
