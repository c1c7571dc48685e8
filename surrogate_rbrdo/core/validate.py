"""Small validation helpers used in ``__post_init__`` of option dataclasses.

Every helper raises :class:`ValueError` naming the field, the value and what is allowed.

>>> check_positive("length_mm", 2.0)
2.0
>>> check_positive("length_mm", -1.0)
Traceback (most recent call last):
...
ValueError: length_mm = -1.0 is not allowed: must be a finite number > 0
>>> check_range("p_target", 1.5, 0.0, 1.0, inclusive=False)
Traceback (most recent call last):
...
ValueError: p_target = 1.5 is not allowed: must lie in (0.0, 1.0)
>>> check_range("a", "0.1", 0.0, 0.9)
Traceback (most recent call last):
...
ValueError: a = '0.1' is not allowed: must be a number in [0.0, 0.9]
>>> check_label("design", "../x")  # doctest: +ELLIPSIS
Traceback (most recent call last):
...
ValueError: design = '../x' is not allowed: a label must be 1-64 letters, digits, spaces or ...
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable, Mapping
from typing import Any

import numpy as np

#: a label: names a design, variant or curve, and files and CSV columns made from it
LABEL = re.compile(r"[\w+=,()%#-][\w .+=,()%#-]{0,63}")


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool)


def _not_a_number(name: str, value: Any, what: str) -> None:
    """Raise ``must be a number ...`` for a value of the wrong type (a string, a bool, ...)."""
    if not _is_number(value):
        raise ValueError(f"{name} = {value!r} is not allowed: must be a number {what}".rstrip())


def check_finite(name: str, value: Any) -> float:
    """Return ``float(value)`` if it is a finite real number."""
    if not _is_number(value) or not math.isfinite(float(value)):
        raise ValueError(f"{name} = {value!r} is not allowed: must be a finite number")
    return float(value)


def check_positive(name: str, value: Any, *, allow_zero: bool = False) -> float:
    """Return ``float(value)`` if it is finite and > 0 (or >= 0 with ``allow_zero``)."""
    _not_a_number(name, value, ">= 0" if allow_zero else "> 0")
    ok = _is_number(value) and math.isfinite(float(value))
    ok = ok and (float(value) >= 0 if allow_zero else float(value) > 0)
    if not ok:
        rel = ">= 0" if allow_zero else "> 0"
        raise ValueError(f"{name} = {value!r} is not allowed: must be a finite number {rel}")
    return float(value)


def check_range(
    name: str, value: Any, lo: float, hi: float, *, inclusive: bool = True
) -> float:
    """Return ``float(value)`` if it lies in ``[lo, hi]`` (or ``(lo, hi)``)."""
    _not_a_number(name, value, f"in [{lo}, {hi}]" if inclusive else f"in ({lo}, {hi})")
    ok = _is_number(value) and math.isfinite(float(value))
    if ok:
        v = float(value)
        ok = lo <= v <= hi if inclusive else lo < v < hi
    if not ok:
        interval = f"[{lo}, {hi}]" if inclusive else f"({lo}, {hi})"
        raise ValueError(f"{name} = {value!r} is not allowed: must lie in {interval}")
    return float(value)


def check_int(name: str, value: Any, *, minimum: int = 0) -> int:
    """Return ``int(value)`` if it is an integer >= ``minimum``."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < minimum:
        raise ValueError(f"{name} = {value!r} is not allowed: must be an integer >= {minimum}")
    return int(value)


def check_text(name: str, value: Any) -> str:
    """Return ``value`` if it is a non-empty string without leading or trailing spaces."""
    if not isinstance(value, str) or not value or value != value.strip():
        raise ValueError(f"{name} = {value!r} is not allowed: must be a non-empty string "
                         "without leading or trailing spaces")
    return value


def check_label(name: str, value: Any) -> str:
    """Return ``value`` if it is a label that can name a file and a CSV column: 1-64
    letters, digits, spaces or ``._+-=,()%#``, not starting with ``.`` or a space, not
    ending with a space (so never ``..``, a path or a control character)."""
    if not isinstance(value, str) or not LABEL.fullmatch(value) or value != value.rstrip():
        raise ValueError(f"{name} = {value!r} is not allowed: a label must be 1-64 letters, "
                         "digits, spaces or ._+-=,()%#, not starting with '.' or a space (it "
                         "names files and columns)")
    return value


def check_choice(name: str, value: Any, choices: Iterable[str]) -> str:
    """Return ``value`` if it is one of ``choices``."""
    choices = list(choices)
    if value not in choices:
        raise ValueError(f"{name} = {value!r} is not allowed: must be one of {choices}")
    return value


def check_keys(where: str, data: Mapping[str, Any], allowed: Iterable[str]) -> None:
    """Raise if ``data`` has a key not in ``allowed`` (catches typos in configs)."""
    allowed = set(allowed)
    unknown = sorted(set(data) - allowed)
    if unknown:
        raise ValueError(
            f"unknown key(s) {unknown} in {where}; allowed: {sorted(allowed)}"
        )


def check_finite_array(name: str, value: Any, *, ndim: int | None = None) -> np.ndarray:
    """Return ``value`` as a float array, raising if it has NaN/inf or the wrong ``ndim``."""
    arr = np.asarray(value, dtype=float)
    if ndim is not None and arr.ndim != ndim:
        raise ValueError(f"{name} has shape {arr.shape}: must be {ndim}-dimensional")
    if not np.all(np.isfinite(arr)):
        bad = np.argwhere(~np.isfinite(arr))[0].tolist()
        raise ValueError(f"{name} contains a non-finite value at index {bad}: must be finite")
    return arr
