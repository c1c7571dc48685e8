"""Random-number conventions: explicit generators, children by ``spawn``.

>>> rng = make_rng(42)
>>> a, b = rng.spawn(2)
>>> float(a.random()) != float(b.random())
True
"""

from __future__ import annotations

import numpy as np


def make_rng(seed: int | np.random.SeedSequence) -> np.random.Generator:
    """Turn an integer seed into a ``Generator`` (only the runner should call this)."""
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer, np.random.SeedSequence)):
        raise ValueError(f"seed = {seed!r} is not allowed: must be a non-negative integer")
    return np.random.default_rng(seed)


def require_rng(rng: object, name: str = "rng") -> np.random.Generator:
    """Raise unless ``rng`` is a ``numpy.random.Generator`` (``None`` never means global)."""
    if not isinstance(rng, np.random.Generator):
        raise ValueError(
            f"{name} = {rng!r} is not allowed: pass a numpy.random.Generator "
            "(e.g. numpy.random.default_rng(seed))"
        )
    return rng
