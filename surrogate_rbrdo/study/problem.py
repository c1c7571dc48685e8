"""A reliability-based robust design problem of a spindle, as one object.

:class:`Problem` holds what the study needs to know about the physics: the parametric spindle
(design map ``x = [preload N, span mm, diameter mm]``), the random stiffness factors θ, the
limit state ``y > δ_lim``, what ``y`` is (:class:`~surrogate_rbrdo.spindle.evaluate.
ResponseSpec`) and the deterministic constraints (g_det and generic design constraints).
:func:`credible_problem` is the project's reference problem (docs/reference-spindle.md, "The
credible reference problem"); :func:`reference_problem` the synthetic rated-speed benchmark
kept for methodology comparisons (docs/paper-study.md: not a spindle result).

>>> p = reference_problem()
>>> p.response.label, round(p.limit.threshold * 1e6, 6), p.spindle.theta_bearings
('amplitude at 24000 rpm', 1.5, ('front', 'rear'))
>>> p.design_bounds.tolist()
[[1000.0, 3000.0], [300.0, 750.0], [50.0, 80.0]]
>>> c = credible_problem()
>>> c.theta_names, round(c.limit.threshold * 1e6, 6), len(c.constraints)
(('k_front', 'k_rear', 'u_frac[0]', 'u_frac[1]', 'phase_deg[1]'), 1.0, 9)
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from surrogate_rbrdo.core.protocols import LimitState
from surrogate_rbrdo.formulations import DesignConstraint, DeterministicOptions
from surrogate_rbrdo.spindle.assembly import RPM
from surrogate_rbrdo.spindle.evaluate import ResponseSpec
from surrogate_rbrdo.spindle.peak_response import PeakUnbalanceSpec, ThetaSpec
from surrogate_rbrdo.spindle.practice import PracticeSpec
from surrogate_rbrdo.spindle.reference import ReferenceSpindle, credible_spindle, reference_spindle
from surrogate_rbrdo.spindle.unbalance import (
    REFERENCE_TOLERANCES,
    PlaneTolerance,
    UnbalanceTolerances,
    permissible_unbalance,
)
from surrogate_rbrdo.study.constraints import spindle_constraints
from surrogate_rbrdo.uncertainty import MultivariateNormal
from surrogate_rbrdo.uncertainty.spindle_theta import theta_random_vector

#: Table 4 pooled CoVs of k_yy (front, rear): the scatter of the synthetic benchmark's stiffness
#: factors (it counts the speed trend as scatter: paper-notes §13)
TABLE4_STD = (0.0605, 0.0641)
#: scatter of the stiffness factors around the speed trend (Table 4 with its 50-speed trend
#: removed, paper-notes §13): the credible problem's default
RESIDUAL_STD = (0.015, 0.033)
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
        θ, columns ``response.theta_names(spindle)`` (the stiffness factors of
        ``spindle.theta_bearings``, then any unbalance and thermal columns).
    limit : LimitState
        Failure ``y > δ_lim`` (metres).
    response : ResponseSpec
        What ``y`` is (the peak over the speed range, or the amplitude at one speed).
    deterministic : DeterministicOptions
        Deterministic constraints ``g_det(x) <= 0`` (stress, resonance guard).
    baseline : ndarray
        A reference design for reports (inside the design box).
    constraints : tuple of DesignConstraint
        Further deterministic design constraints ``g(x) <= 0`` (practice checks, the exact
        separation guard, expressions), given to every formulation.
    design_theta : ndarray (k, m) or None
        The deterministic strategy's design basis: it minimises the largest ``y`` over these θ
        rows (:func:`unbalance_design_cases`: the API RP 684 unbalance arrangements at the ISO
        limit). ``None``: the image of ``u = 0`` (the mean stiffness factors).
    """

    spindle: ReferenceSpindle
    inputs: Any
    limit: LimitState
    response: ResponseSpec = field(default_factory=ResponseSpec)
    deterministic: DeterministicOptions = field(default_factory=DeterministicOptions)
    baseline: np.ndarray | None = None
    constraints: tuple[DesignConstraint, ...] = ()
    design_theta: np.ndarray | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.limit, LimitState):
            raise ValueError(f"limit = {self.limit!r} is not allowed: must be a LimitState")
        if not isinstance(self.response, ResponseSpec):
            raise ValueError(f"response = {self.response!r} is not allowed: must be a "
                             "ResponseSpec")
        if not isinstance(self.deterministic, DeterministicOptions):
            raise ValueError(f"deterministic = {self.deterministic!r} is not allowed: must be "
                             "a DeterministicOptions")
        names = self.theta_names
        if int(self.inputs.dim) != len(names):
            raise ValueError(f"inputs.dim = {self.inputs.dim} is not allowed: must be "
                             f"{len(names)}, the θ columns {list(names)} of the response")
        object.__setattr__(self, "constraints", tuple(self.constraints))
        for c in self.constraints:
            if not isinstance(c, DesignConstraint):
                raise ValueError(f"constraints entry {c!r} is not allowed: must be a "
                                 "DesignConstraint")
        cnames = [c.name for c in self.constraints]
        if len(set(cnames)) != len(cnames):
            raise ValueError(f"constraints: names {cnames} are not allowed: each name once")
        if self.design_theta is not None:
            dt = np.array(self.design_theta, dtype=float)
            if dt.ndim != 2 or dt.shape[1] != len(names) or not dt.shape[0] \
                    or not np.all(np.isfinite(dt)):
                raise ValueError(f"design_theta has shape {dt.shape}: must be finite (k >= 1, "
                                 f"{len(names)}), one row per design case, columns "
                                 f"{list(names)}")
            dt.flags.writeable = False
            object.__setattr__(self, "design_theta", dt)
        base = self.spindle.baseline if self.baseline is None else self.baseline
        object.__setattr__(self, "baseline",
                           self.spindle.design_map.check(np.asarray(base, dtype=float)))

    @property
    def theta_names(self) -> tuple[str, ...]:
        """The columns of θ."""
        return self.response.theta_names(self.spindle)

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


@dataclass(frozen=True)
class UnbalanceOptions:
    """The random residual unbalance (the ``[uncertainty.unbalance]`` table), ISO 21940-11.

    ``magnitude``: ``"disk"`` (uniform over each plane's tolerance disk, one θ column per
    plane) or ``"limit"`` (every plane at its permissible value); ``relative_phase``: phases
    of planes 2… relative to plane 1 (exact: a common rotation leaves the orbit unchanged);
    ``planes``: grade and balanced disks per plane (default: the tool holder in the tool
    plane, the rest of the rotor in the motor plane, G 2.5); ``speed_rpm``: service speed of
    the grades (default: the top speed).
    """

    magnitude: str = "disk"
    relative_phase: bool = True
    planes: tuple[PlaneTolerance, ...] | None = None
    speed_rpm: float | None = None

    @property
    def tolerances(self) -> UnbalanceTolerances:
        return UnbalanceTolerances(self.planes or REFERENCE_TOLERANCES.planes, self.speed_rpm)


def peak_unbalance_inputs(spindle: ReferenceSpindle, stiffness: Any, *, thermal_max: float = 0.0,
                          unbalance: UnbalanceOptions | None = None
                          ) -> tuple[Any, PeakUnbalanceSpec]:
    """θ and the response of the random-unbalance peak: ``stiffness`` (a random vector of the
    factors of ``spindle.theta_bearings``: normal or lognormal around the speed trend, or an
    identified model) followed by the thermal preload state (``thermal_max > 0``) and the
    unbalance magnitude fractions and phases (``uncertainty.spindle_theta``). The tolerances
    are checked against the spindle's unbalance planes and disks."""
    u = UnbalanceOptions() if unbalance is None else unbalance
    m = len(spindle.theta_bearings)
    if int(stiffness.dim) != m:
        raise ValueError(f"stiffness.dim = {stiffness.dim} is not allowed: need {m}, one "
                         f"factor per θ bearing {list(spindle.theta_bearings)}")
    std = tuple(float(v) for v in np.sqrt(np.diag(np.asarray(stiffness.cov, dtype=float))))
    tol = u.tolerances
    spec = ThetaSpec(bearings=spindle.theta_bearings, stiffness_std=std, thermal_max=thermal_max,
                     preload_bearing=spindle.design_map.preload_bearing,
                     n_planes=len(tol.planes), magnitude=u.magnitude,
                     relative_phase=u.relative_phase)
    permissible_unbalance(spindle.model(spindle.baseline), tol)   # planes and disks
    return theta_random_vector(spec, stiffness), PeakUnbalanceSpec(theta_spec=spec,
                                                                   tolerances=tol)


def unbalance_design_cases(inputs: Any, response: PeakUnbalanceSpec) -> np.ndarray:
    """The deterministic design basis of a random-unbalance problem: the median θ (the image
    of ``u = 0``: stiffness factors 1) with the unbalance arrangements of an API RP 684
    unbalance response analysis, every plane at its ISO 21940-11 limit, in phase and in
    couple (``ThetaSpec.unbalance_cases``).

    >>> c = credible_problem()
    >>> unbalance_design_cases(c.inputs, c.response).tolist()
    [[1.0, 1.0, 1.0, 1.0, 0.0], [1.0, 1.0, 1.0, 1.0, 180.0]]
    """
    if not isinstance(response, PeakUnbalanceSpec):
        raise ValueError(f"response = {response!r} is not allowed: unbalance design cases need "
                         "a PeakUnbalanceSpec (kind = 'peak_unbalance')")
    theta0 = np.asarray(inputs.from_standard(np.zeros((1, int(inputs.dim)))), dtype=float)[0]
    return response.theta_spec.unbalance_cases(theta0)


def credible_problem(*, delta_lim_um: float = 1.0) -> Problem:
    """The credible reference problem (docs/reference-spindle.md, each choice with its
    source): ``credible_spindle()`` (front preload 190–1 140 N, the catalogue classes of a
    7014 pair); y = the peak tool-tip amplitude over 1 000–24 000 rpm under a random residual
    unbalance (ISO 21940-11 G 2.5 per plane, uniform over the tolerance disk, random phase);
    θ = stiffness factors around the speed trend (CoV 1.5 % / 3.3 %) + unbalance fractions
    and relative phase; δ_lim = 1 µm (the permissible eccentricity G/Ω_max of G 2.5 at
    24 000 rpm); the stress check (σ_yield 930 MPa), the practice checks and the exact API
    separation guard. The deterministic strategy designs against the API RP 684 unbalance
    cases at the ISO limit (:func:`unbalance_design_cases`)."""
    sp = credible_spindle()
    inputs, response = peak_unbalance_inputs(sp, MultivariateNormal([1.0, 1.0],
                                                                    std=list(RESIDUAL_STD)))
    return Problem(
        spindle=sp, inputs=inputs, limit=LimitState(delta_lim_um * 1e-6), response=response,
        deterministic=DeterministicOptions(stress=True, yield_strength_pa=930e6,
                                           resonance="none",
                                           omega_max=sp.geometry.speed_max_rpm * RPM),
        baseline=sp.baseline,
        constraints=spindle_constraints(sp, practice=PracticeSpec(), resonance="separation"),
        design_theta=unbalance_design_cases(inputs, response))


__all__ = ["DESIGN_NAMES", "RESIDUAL_STD", "TABLE4_STD", "Problem", "credible_problem",
           "UnbalanceOptions", "peak_unbalance_inputs", "reference_problem",
           "unbalance_design_cases"]
