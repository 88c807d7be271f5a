"""Campaigns in and out: NumPy arrays, pandas frames, dicts and CSV files
become the extension's ``Data``; ``read_campaign`` returns a DataFrame."""

from __future__ import annotations

import os
import re
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from . import _robokrige
from ._robokrige import RobokrigeError

#: Anything that names a file.
PathLike = Union[str, "os.PathLike[str]"]

_Q = re.compile(r"^q([1-9][0-9]*)$")
_DIR = re.compile(r"^dir([1-9][0-9]*)$")
_RESERVED = {"ex", "ey", "ez", "x", "y", "z", "id"}


def _bad(message: str) -> RobokrigeError:
    """The library's InvalidParameter message form."""
    return RobokrigeError(f"invalid parameter: {message}")


def _matrix(a: Any, name: str, cols: Optional[int] = None) -> np.ndarray:
    """``a`` as a 2-D float64 array (no copy when it already is one)."""
    try:
        arr = np.asarray(a, dtype=np.float64)
    except (TypeError, ValueError) as e:
        raise _bad(f"{name} must be numeric: {e}") from None
    if arr.ndim != 2:
        what = "m poses × n joints" if cols is None else f"m rows × {cols} columns"
        raise _bad(f"{name} must be a 2-D array ({what}); got shape {arr.shape}")
    if cols is not None and arr.shape[1] != cols:
        raise _bad(f"{name} must have {cols} columns; got shape {arr.shape}")
    return arr


def _vector(a: Any, name: str) -> np.ndarray:
    try:
        arr = np.asarray(a, dtype=np.float64)
    except (TypeError, ValueError) as e:
        raise _bad(f"covariate '{name}' must be numeric: {e}") from None
    if arr.ndim != 1:
        raise _bad(f"covariate '{name}' must be 1-D; got shape {arr.shape}")
    return arr


def _is_frame(x: Any) -> bool:
    return hasattr(x, "columns") and hasattr(x, "to_numpy")


def _columns(table: Any) -> Dict[str, Any]:
    """Name → column of a DataFrame or a mapping of columns."""
    if _is_frame(table):
        return {str(c): table[c] for c in table.columns}
    return {str(k): v for k, v in table.items()}


def _numeric(col: Any) -> Optional[np.ndarray]:
    """The column as float64 when it is numeric (bool excluded), else None."""
    arr = np.asarray(col)
    if arr.dtype.kind in "iuf":
        return arr.astype(np.float64, copy=False)
    if arr.dtype.kind == "O":
        try:
            return np.asarray(arr, dtype=np.float64)
        except (TypeError, ValueError):
            return None
    return None


def _stack(cols: Mapping[str, Any], names: Sequence[str], source: str) -> np.ndarray:
    """The named columns as an m × len(names) float64 array; an error
    naming the first that is not numeric."""
    values = []
    for n in names:
        v = _numeric(cols[n])
        if v is None:
            raise RobokrigeError(f"{source}: column '{n}' is not numeric")
        values.append(v)
    return np.column_stack(values)


def _numbered(cols: Mapping[str, Any], pattern: "re.Pattern[str]") -> List[str]:
    found = sorted((int(m.group(1)), name) for name in cols for m in [pattern.match(name)] if m)
    names = [n for _, n in found]
    for k, (j, _) in enumerate(found):
        if j != k + 1:
            prefix = "q" if pattern is _Q else "dir"
            raise _bad(f"columns {prefix}1..{prefix}N must be numbered contiguously; {prefix}{k + 1} is missing")
    return names


def _from_table(table: Any, source: str) -> "_robokrige.Data":
    """A measurement table (the CSV's columns: q1..qN, dir1..dirN, ex,ey,ez,
    x,y,z, id, covariates) as Data."""
    cols = _columns(table)
    qn = _numbered(cols, _Q)
    if not qn:
        raise RobokrigeError(f"{source}: no joint columns q1..qN (found: {', '.join(cols) or 'none'})")
    dn = _numbered(cols, _DIR)
    if dn and len(dn) != len(qn):
        raise RobokrigeError(f"{source}: {len(dn)} direction columns for {len(qn)} joints; give dir1..dir{len(qn)} or none")

    def triple(names: Tuple[str, str, str]) -> Optional[np.ndarray]:
        return _stack(cols, names, source) if all(n in cols for n in names) else None

    q = _stack(cols, qn, source)
    dirs = _stack(cols, dn, source) if dn else None
    errors = triple(("ex", "ey", "ez"))
    positions = triple(("x", "y", "z"))
    ids = [str(v) for v in cols["id"]] if "id" in cols else None
    covariates = []
    used = set(qn) | set(dn) | _RESERVED
    for name, col in cols.items():
        if name in used:
            continue
        values = _numeric(col)
        if values is not None and values.ndim == 1:
            covariates.append((name, values))
    return _robokrige.Data(q, dirs, errors, positions, covariates or None, ids, source)


def as_data(
    q: Any,
    dirs: Any = None,
    errors: Any = None,
    covariates: Any = None,
    *,
    source: str = "<memory>",
) -> "_robokrige.Data":
    """Campaign from any of the accepted forms.

    ``q`` is an m × n array of joint positions (degrees; mm for a prismatic
    joint), a pandas DataFrame or mapping with the measurement CSV's columns
    (``q1..qN``, ``dir1..dirN``, ``ex,ey,ez``, covariates), a path to a
    measurement CSV, or a ``Data``. With arrays, ``dirs`` (m × n, ±1) is
    derived from the row order when None, ``errors`` is m × 3 (mm), and
    ``covariates`` a mapping (or DataFrame) of name → m values.
    """
    if isinstance(q, _robokrige.Data):
        _only(dirs, errors, covariates, "a Data")
        return q
    if isinstance(q, (str, os.PathLike)):
        _only(dirs, errors, covariates, "a file")
        return _robokrige.Data.read_csv(os.fspath(q))
    if _is_frame(q) or isinstance(q, Mapping):
        _only(dirs, errors, covariates, "a table")
        return _from_table(q, source)
    qa = _matrix(q, "q")
    da = None if dirs is None else _matrix(dirs, "dirs", qa.shape[1])
    ea = None if errors is None else _matrix(errors, "errors", 3)
    cov: Optional[List[Tuple[str, np.ndarray]]] = None
    if covariates is not None:
        cov = [(name, _vector(v, name)) for name, v in _columns(covariates).items()]
    return _robokrige.Data(qa, da, ea, None, cov, None, source)


def derive_directions(q: Any) -> np.ndarray:
    """The directions λ (m × n, ±1) the poses ``q`` (m × n joints, in the
    order the robot visited them) are approached from, as the library
    derives them for a campaign without direction columns: the sign of each
    joint's last move, +1 for the first pose. Derive them once on the whole
    campaign, before a CV splitter or a train/test split picks rows, and
    give them to ``ErrorModel.fit(X, y)`` as the columns after the joints:
    ``X = np.hstack([q, derive_directions(q)])``."""
    dirs: np.ndarray = _robokrige.Data(_matrix(q, "q")).dirs
    return dirs


def _only(dirs: Any, errors: Any, covariates: Any, what: str) -> None:
    if dirs is not None or errors is not None or covariates is not None:
        raise _bad(f"with {what}, give dirs, errors and covariates as its columns, not as arguments")


def read_campaign(path: PathLike, *, as_frame: Optional[bool] = None) -> Any:
    """Read a measurement CSV exactly as the command line does.

    Returns a pandas DataFrame when pandas is installed (``as_frame=None``
    or True), else a dict of column name → NumPy array (text columns as
    lists). Columns come in the library's order: ``id``, ``q1..qN``,
    ``dir1..dirN`` (derived from the row order when the file has none),
    ``ex,ey,ez``, ``x,y,z``, covariates, text columns. A DataFrame's
    ``attrs`` record the source, where the directions came from
    (``"given"`` or ``"derived"``) and the reader's plausibility warnings.

    Bad files raise ``RobokrigeError`` naming the file, line and column.
    """
    data = _robokrige.Data.read_csv(os.fspath(path))
    return data_to_table(data, as_frame=as_frame)


def data_to_table(data: "_robokrige.Data", *, as_frame: Optional[bool] = None) -> Any:
    """``Data`` as a DataFrame (pandas) or a dict of columns."""
    cols = dict(data.columns())
    if as_frame is False:
        return cols
    try:
        import pandas as pd
    except ImportError:
        if as_frame:
            raise ImportError("read_campaign(as_frame=True) needs pandas: pip install pandas") from None
        return cols
    df = pd.DataFrame(cols)
    df.attrs["source"] = data.source
    df.attrs["dir_source"] = data.dir_source
    df.attrs["warnings"] = list(data.warnings())
    return df
