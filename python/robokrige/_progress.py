"""Progress reporting for long calls.

A ``progress`` argument is one of:

- ``None`` or ``False``: nothing is shown;
- ``True``: a tqdm bar when tqdm is installed, else one line per step on
  standard error;
- a callable ``progress(done, total, message)``: called from the worker
  threads (with the interpreter attached) after each step; ``total`` is 0
  when the number of steps is not known in advance. An exception it raises
  stops the computation (at the library's next check: a likelihood
  evaluation, a CV fold, a diagnose step) and is raised when the call
  returns.
"""

from __future__ import annotations

import sys
from typing import Any, Callable, Optional, Union

#: The type of a ``progress`` argument.
ProgressArg = Union[None, bool, Callable[[int, int, str], Any]]


class _Reporter:
    """A callable for the extension that draws a tqdm bar or prints lines."""

    def __init__(self, desc: str) -> None:
        self.desc = desc
        self.bar: Any = None
        try:
            import tqdm  # noqa: F401

            self.tqdm: Any = tqdm.tqdm
        except ImportError:
            self.tqdm = None

    def __call__(self, done: int, total: int, message: str) -> None:
        if self.tqdm is None:
            print(f"{self.desc}: {message}", file=sys.stderr, flush=True)
            return
        if self.bar is None:
            self.bar = self.tqdm(total=total or None, desc=self.desc, leave=False)
        self.bar.n = done
        self.bar.set_postfix_str(message, refresh=True)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
            self.bar = None


class progress_for:
    """Context manager: the callback to hand to the extension for ``arg``."""

    def __init__(self, arg: ProgressArg, desc: str) -> None:
        self.arg = arg
        self.desc = desc
        self.reporter: Optional[_Reporter] = None

    def __enter__(self) -> Optional[Callable[[int, int, str], Any]]:
        if self.arg is None or self.arg is False:
            return None
        if self.arg is True:
            self.reporter = _Reporter(self.desc)
            return self.reporter
        if callable(self.arg):
            return self.arg
        raise TypeError("progress must be None, a bool, or a callable(done, total, message)")

    def __exit__(self, *exc: Any) -> None:
        if self.reporter is not None:
            self.reporter.close()
