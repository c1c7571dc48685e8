"""Arrays to and from the plain lists of JSON files (``None`` stays ``None``).

>>> listed(np.eye(2)), arrayed([1, 2]).dtype, listed(None)
([[1.0, 0.0], [0.0, 1.0]], dtype('float64'), None)
"""

from __future__ import annotations

import numpy as np


def listed(a) -> list | None:
    """``a`` as nested lists, or ``None``."""
    return None if a is None else np.asarray(a).tolist()


def arrayed(a) -> np.ndarray | None:
    """``a`` as a float array, or ``None``."""
    return None if a is None else np.asarray(a, dtype=float)


__all__ = ["arrayed", "listed"]
