"""Output transforms of a Kriging of ``y``: fit ``t(y)``, predict ``t⁻¹``.

``"log"`` fits ``log y`` (``y > 0``; the response then returns ``exp(μ_log)``, the median of
the lognormal predictive distribution, a monotone map so ``P[y > δ] = P[μ_log > log δ]``);
``"none"`` fits ``y`` itself.

>>> import numpy as np
>>> float(inverse(forward(np.array(2.0), "log"), "log"))
2.0
>>> forward(np.array([1.0, 2.0]), "none").tolist()
[1.0, 2.0]
"""

from __future__ import annotations

import numpy as np

TRANSFORMS = ("log", "none")


def forward(y: np.ndarray, transform: str) -> np.ndarray:
    """``t(y)``: ``log y`` or ``y``."""
    y = np.asarray(y, dtype=float)
    return np.log(y) if transform == "log" else y


def inverse(t: np.ndarray, transform: str) -> np.ndarray:
    """``y = t⁻¹(t)``: ``exp t`` or ``t``."""
    return np.exp(t) if transform == "log" else np.asarray(t, dtype=float)


__all__ = ["TRANSFORMS", "forward", "inverse"]
