"""Options shared by the structures whose DOE is over the joint (x, θ) box.

>>> o = JointDOEOptions(theta_box="bounds", theta_bounds=(0.8, 1.2))
>>> o.theta_bounds
(0.8, 1.2)
>>> JointDOEOptions(n_doe=3)
Traceback (most recent call last):
...
ValueError: n_doe = 3 is not allowed: must be an integer >= 7
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from surrogate_rbrdo.core.validate import check_choice, check_int, check_positive
from surrogate_rbrdo.doe.infill import THETA_BOXES, joint_bounds
from surrogate_rbrdo.surrogates.registry import SURROGATES
from surrogate_rbrdo.surrogates.structured.base import SamplingOptions, kriging_bytes
from surrogate_rbrdo.uncertainty.box import marginal_box


@dataclass(frozen=True)
class JointDOEOptions(SamplingOptions):
    """A static maximin-LHS DOE of ``n_doe`` points in the joint (x, θ) box, Kriging fits.

    Attributes
    ----------
    n_doe : int
        Size of the space-filling DOE (maximin LHS in the joint (x, θ) box), >= 7.
    surrogate : str
        Name in ``SURROGATES`` (``krg_se``, ``krg_matern52``, ``gpr``).
    theta_box : {"sigma", "bounds"}
        θ part of the DOE box: each component's marginal quantiles at ``Φ(∓theta_sigmas)``
        (:func:`~surrogate_rbrdo.uncertainty.box.marginal_box`; ``mean ± theta_sigmas·std``
        for a normal component, default ±4σ: the Monte Carlo samples live there; within the
        support of a bounded one, e.g. an unbalance phase) or ``theta_bounds`` for every
        component.
    theta_sigmas : float
    theta_bounds : (float, float)
    n_start : int
        Multistarts of the hyperparameter optimisation (smt ``n_start`` / sklearn restarts
        + 1).
    """

    n_doe: int = 200
    surrogate: str = "krg_se"
    theta_box: str = "sigma"
    theta_sigmas: float = 4.0
    theta_bounds: tuple[float, float] = (0.5, 1.5)
    n_start: int = 5

    def __post_init__(self) -> None:
        super().__post_init__()
        check_int("n_doe", self.n_doe, minimum=7)
        check_choice("surrogate", self.surrogate, sorted(SURROGATES))
        check_choice("theta_box", self.theta_box, THETA_BOXES)
        check_positive("theta_sigmas", self.theta_sigmas)
        tb = tuple(self.theta_bounds) if isinstance(self.theta_bounds, (list, tuple)) else None
        if tb is None or len(tb) != 2 or not all(
                isinstance(v, (int, float)) and not isinstance(v, bool) for v in tb) \
                or not 0 < tb[0] < tb[1] or not np.isfinite(tb[1]):
            raise ValueError(f"theta_bounds = {self.theta_bounds!r} is not allowed: must be "
                             "(lower, upper) with 0 < lower < upper")
        object.__setattr__(self, "theta_bounds", (float(tb[0]), float(tb[1])))
        check_int("n_start", self.n_start, minimum=1)

    def memory_bytes(self) -> dict[str, float]:
        """Peak bytes (``core.memory``): a Kriging fit holds ~10 ``n × n`` matrices of its
        ``n`` training points (smt KRG; as ``DesignModelOptions``) and a few values per point.

        >>> JointDOEOptions(n_doe=10 ** 7).memory_bytes()["n_doe"] > 1e15
        True
        """
        return {"n_doe": kriging_bytes(self.n_doe)}

    def bounds(self, spindle: Any, inputs: Any) -> np.ndarray:
        """The (d + m, 2) joint DOE box of ``spindle``'s designs and the θ of ``inputs``."""
        if self.theta_box == "sigma":
            return np.vstack([np.asarray(spindle.design_map.bounds, dtype=float),
                              marginal_box(inputs, self.theta_sigmas)])
        std = np.sqrt(np.diag(np.asarray(inputs.cov, dtype=float)))
        return joint_bounds(spindle.design_map.bounds, inputs.mean, std,
                            theta_box=self.theta_box, theta_bounds=self.theta_bounds)


__all__ = ["JointDOEOptions"]
