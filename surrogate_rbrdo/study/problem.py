"""A reliability-based robust design problem of a spindle, as one object.

:class:`Problem` holds what the study needs to know about the physics: the parametric spindle
(design map ``x = [preload N, span mm, diameter mm]``), the random stiffness factors θ, the
limit state ``y > δ_lim``, what ``y`` is (:class:`~surrogate_rbrdo.spindle.evaluate.
ResponseSpec`) and the deterministic constraints. :func:`reference_problem` is the project's
reference problem (docs/paper-study.md, "The rated-speed problem").

>>> p = reference_problem()
>>> p.response.label, round(p.limit.threshold * 1e6, 6), p.spindle.theta_bearings
('amplitude at 24000 rpm', 1.5, ('front', 'rear'))
>>> p.design_bounds.tolist()
[[1000.0, 3000.0], [300.0, 750.0], [50.0, 80.0]]
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from surrogate_rbrdo.core.protocols import LimitState
from surrogate_rbrdo.formulations import DeterministicOptions
from surrogate_rbrdo.spindle.assembly import RPM
from surrogate_rbrdo.spindle.evaluate import ResponseSpec
from surrogate_rbrdo.spindle.reference import ReferenceSpindle, reference_spindle
from surrogate_rbrdo.uncertainty import MultivariateNormal

#: Table 4 pooled CoVs of k_yy (front, rear): the default scatter of the stiffness factors
TABLE4_STD = (0.0605, 0.0641)
#: Design names (and units) of the reference spindle's design vector
DESIGN_NAMES = ("preload_N", "span_mm", "diameter_mm")


@dataclass(frozen=True, eq=False)
class Problem:
    """One design problem: spindle, θ distribution, limit state, response, g_det options.

    Attributes
    ----------
    spindle : ReferenceSpindle
        The parametric spindle (``spindle.model(x)`` is the FE model of design ``x``).
    inputs : RandomVector
        θ (one stiffness factor per bearing of ``spindle.theta_bearings``).
    limit : LimitState
        Failure ``y > δ_lim`` (metres).
    response : ResponseSpec
        What ``y`` is (the peak over the speed range, or the amplitude at one speed).
    deterministic : DeterministicOptions
        Deterministic constraints ``g_det(x) <= 0`` (stress, resonance guard).
    baseline : ndarray
        A reference design for reports (inside the design box).
    """

    spindle: ReferenceSpindle
    inputs: Any
    limit: LimitState
    response: ResponseSpec = field(default_factory=ResponseSpec)
    deterministic: DeterministicOptions = field(default_factory=DeterministicOptions)
    baseline: np.ndarray | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.limit, LimitState):
            raise ValueError(f"limit = {self.limit!r} is not allowed: must be a LimitState")
        if not isinstance(self.response, ResponseSpec):
            raise ValueError(f"response = {self.response!r} is not allowed: must be a "
                             "ResponseSpec")
        if not isinstance(self.deterministic, DeterministicOptions):
            raise ValueError(f"deterministic = {self.deterministic!r} is not allowed: must be "
                             "a DeterministicOptions")
        m = len(self.spindle.theta_bearings)
        if int(self.inputs.dim) != m:
            raise ValueError(f"inputs.dim = {self.inputs.dim} is not allowed: must be {m}, one "
                             f"factor per θ bearing {list(self.spindle.theta_bearings)}")
        base = self.spindle.baseline if self.baseline is None else self.baseline
        object.__setattr__(self, "baseline",
                           self.spindle.design_map.check(np.asarray(base, dtype=float)))

    @property
    def design_bounds(self) -> np.ndarray:
        """The design box ``(d, 2)``."""
        return np.asarray(self.spindle.design_map.bounds, dtype=float)

    def fe_response(self, method: str = "direct") -> Any:
        """The full-FE response ``y(x (P, d), θ (N, m)) -> (P, N)`` (metres)."""
        return self.response.fe_response(self.spindle, method)


def reference_problem() -> Problem:
    """The reference problem: the tool-tip amplitude at the rated speed 24 000 rpm,
    δ_lim = 1.5 µm, θ = the two bearing-stiffness factors ~ N(1, Table 4 CoVs), the stress
    constraint (σ_yield = 930 MPa), no resonance guard (the paper's guard never binds on the
    design box; docs/paper-study.md), baseline design [2000 N, 465.8 mm, 65 mm]."""
    sp = reference_spindle()
    return Problem(
        spindle=sp, inputs=MultivariateNormal([1.0, 1.0], std=list(TABLE4_STD)),
        limit=LimitState(1.5e-6), response=ResponseSpec("at_speed", 24000.0),
        deterministic=DeterministicOptions(stress=True, yield_strength_pa=930e6,
                                           resonance="none",
                                           omega_max=sp.geometry.speed_max_rpm * RPM),
        baseline=np.array([2000.0, 465.8, 65.0]))


__all__ = ["DESIGN_NAMES", "TABLE4_STD", "Problem", "reference_problem"]
