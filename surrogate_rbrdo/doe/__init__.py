"""Design of experiments: seeded, space-filling Latin hypercube designs over a box.

>>> import numpy as np
>>> X = lhs(5, [[0.0, 1.0], [10.0, 20.0]], rng=np.random.default_rng(0))
>>> X.shape
(5, 2)
"""

from surrogate_rbrdo.doe.lhs import (
    LHS_CRITERIA,
    check_bounds,
    from_unit,
    lhs,
    min_distance,
    phi_p,
    to_unit,
)

__all__ = ["LHS_CRITERIA", "check_bounds", "from_unit", "lhs", "min_distance", "phi_p", "to_unit"]
