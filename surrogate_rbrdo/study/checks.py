"""FE checks of chosen designs that do not go through the optimiser's models.

:func:`campbell_critical_speeds`: the damped forward 1x critical speeds of each design from its
Campbell diagram (``spindle.modal.critical_speeds``: complex eigenvalues of the damped,
gyroscopic FE model on a speed grid, crossings refined by Brent's method). The exact
separation guard the optimiser sees (``spindle.separation``) solves a different, undamped
real eigenproblem, so agreement of the two is a check of both; a chosen design with a critical
speed inside the operating range is visible in the verification table (and its resonance is
in ``y``, the peak over the range).

>>> import numpy as np
>>> from surrogate_rbrdo.spindle.reference import credible_spindle
>>> sp = credible_spindle()
>>> crit = campbell_critical_speeds(sp, sp.baseline[None], n_speeds=12)
>>> np.round(crit[0], -1).tolist()                # inside 1 000–24 000 rpm
[21780.0]
"""

from __future__ import annotations

import numpy as np

from surrogate_rbrdo.core.validate import check_int, check_positive
from surrogate_rbrdo.spindle.modal import critical_speeds
from surrogate_rbrdo.spindle.reference import ReferenceSpindle


def campbell_critical_speeds(spindle: ReferenceSpindle, X: np.ndarray, *,
                             up_to_factor: float = 1.5, n_speeds: int = 24
                             ) -> list[np.ndarray]:
    """Damped forward critical speeds (rpm) of each design of ``X`` between the geometry's
    minimum speed and ``up_to_factor`` times its maximum, at nominal θ (``n_speeds`` grid
    points; each crossing refined to 1e-6)."""
    check_positive("up_to_factor", up_to_factor)
    check_int("n_speeds", n_speeds, minimum=2)
    g = spindle.geometry
    grid = np.linspace(g.speed_min_rpm, up_to_factor * g.speed_max_rpm, n_speeds)
    return [np.asarray(critical_speeds(spindle.model(x), grid), dtype=float)
            for x in np.atleast_2d(np.asarray(X, dtype=float))]


__all__ = ["campbell_critical_speeds"]
