"""scikit-learn, when it is installed: the estimator's base classes and the
exception it expects of an unfitted estimator.

``ErrorModel`` implements scikit-learn's estimator protocol itself
(``get_params``, ``set_params``, ``__sklearn_tags__``, ``score`` as R²,
``n_features_in_``), so it behaves the same with or without scikit-learn;
with it, it also inherits ``BaseEstimator`` and ``RegressorMixin`` (for
``isinstance`` checks, the notebook display and pickles that record the
scikit-learn version). Without it, the package needs NumPy only.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Tuple

from ._robokrige import RobokrigeError

if TYPE_CHECKING:  # scikit-learn ships no type information

    class EstimatorBase:
        """The estimator's base classes."""

    class _NotFittedBase(ValueError, AttributeError):
        pass

else:
    try:
        from sklearn.base import BaseEstimator, RegressorMixin
        from sklearn.exceptions import NotFittedError as _NotFittedBase

        # RegressorMixin before BaseEstimator: scikit-learn's required order
        _BASES: Tuple[type, ...] = (RegressorMixin, BaseEstimator)
    except ImportError:
        _NotFittedBase = AttributeError
        _BASES = (object,)

    EstimatorBase = type("EstimatorBase", _BASES, {"__doc__": "The estimator's base classes.", "__module__": __name__})


class NotFittedError(RobokrigeError, _NotFittedBase):
    """Raised by a method that needs a fitted model (``predict``, ``save``,
    a fitted attribute) before ``fit``. A ``RobokrigeError`` (a
    ``ValueError``), an ``AttributeError``, and scikit-learn's
    ``NotFittedError`` when scikit-learn is installed."""
