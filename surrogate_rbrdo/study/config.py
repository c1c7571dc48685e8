"""The problem tables of a study config and the objects they describe: ``[uncertainty]``
(θ, :func:`build_theta`), ``[limit]`` and ``[deterministic]``.

Each table is a frozen dataclass checked by :func:`~surrogate_rbrdo.core.schema.parse`; the
builders raise ``ValueError`` naming the dotted path of the field.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any

import numpy as np
from pydantic import AliasChoices, Field

from surrogate_rbrdo.core.magnitudes import check_displacement_limit
from surrogate_rbrdo.core.protocols import LimitState
from surrogate_rbrdo.core.validate import check_choice, check_positive, check_range
from surrogate_rbrdo.formulations import DeterministicOptions
from surrogate_rbrdo.identification.study import stiffness_block_from
from surrogate_rbrdo.spindle.assembly import RPM
from surrogate_rbrdo.spindle.evaluate import ResponseSpec
from surrogate_rbrdo.spindle.practice import PracticeSpec
from surrogate_rbrdo.spindle.reference import ReferenceSpindle
from surrogate_rbrdo.study.constraints import spindle_constraints
from surrogate_rbrdo.study.problem import (
    RESIDUAL_STD,
    TABLE4_STD,
    UnbalanceOptions,
    peak_unbalance_inputs,
    unbalance_design_cases,
)
from surrogate_rbrdo.uncertainty import stiffness_factors

#: what the deterministic strategy designs against (``[deterministic] design_basis``)
DESIGN_BASES = ("unbalance_cases", "median")

#: speeds at which an identified θ is evaluated for a peak over the speed range (evenly
#: spaced over its identified part; θ is their moment-matched mixture,
#: identification.stiffness_block_from)
PEAK_THETA_SPEEDS = 25


#: the range of a stiffness factor's mean: θ scales a bearing's nominal stiffness, and a bearing
#: ten times softer or stiffer than its law is another bearing (change the law), not an
#: uncertainty about it; identified factors lie within 0.5-2 (docs/identification.md)
FACTOR_MEAN_RANGE = (0.1, 10.0)
#: the largest coefficient of variation of a stiffness factor (100 %)
FACTOR_MAX_COV = 1.0
#: the largest relative thermal preload growth τ (F(1 + τ)): measured growth at top speed is
#: at most a few hundred percent (e.g. Li & Shin 2004)
THERMAL_MAX = 5.0


def check_factor_moments(mean: tuple[float, ...] | None, std: tuple[float, ...] | None
                         ) -> None:
    """The stiffness factors' means within :data:`FACTOR_MEAN_RANGE` and their standard
    deviations at most :data:`FACTOR_MAX_COV` times the mean (1 where not given).

    >>> try:
    ...     check_factor_moments((1.0, 1e300), None)
    ... except ValueError as exc:
    ...     print(str(exc)[:82])
    mean[1] = 1e+300 is not allowed: a stiffness factor's mean must lie in [0.1, 10.0]
    """
    lo, hi = FACTOR_MEAN_RANGE
    for i, m in enumerate(mean or ()):
        if m > 0 and not lo <= m <= hi:     # m <= 0: stiffness_factors says why
            raise ValueError(f"mean[{i}] = {m!r} is not allowed: a stiffness factor's mean must "
                             f"lie in [{lo}, {hi}] (θ scales the bearing's nominal stiffness; a "
                             "bearing 10 times softer or stiffer is another bearing law)")
    for i, s in enumerate(std or ()):
        m = mean[i] if mean is not None and i < len(mean) else 1.0
        if m > 0 and s > FACTOR_MAX_COV * m:    # m <= 0: the mean is the error
            raise ValueError(f"std[{i}] = {s!r} is not allowed: must be at most "
                             f"{FACTOR_MAX_COV:g} x the mean ({FACTOR_MAX_COV * m:g}): a "
                             "stiffness factor's coefficient of variation above 100 %")


@dataclass(frozen=True)
class UncertaintyTable:
    """``[uncertainty]``: θ. The stiffness block, one factor per θ bearing: ``distribution``
    (``"normal"`` or ``"lognormal"``: positive support, ``uncertainty.stiffness_factors``),
    ``mean`` (default 1), ``std`` (default: the scatter around the speed trend, 1.5 % / 3.3 %,
    with ``response.kind = "peak_unbalance"``; the paper's pooled Table 4 CoVs otherwise, the
    synthetic benchmarks), ``corr`` — or ``from = "<identification run folder or its
    uncertainty.json>"``: the identified model (trend at the response's speed(s), physical
    scatter and the trend's uncertainty; ``identification.stiffness_block_from``), instead of
    ``mean``/``std``/``corr``; a relative path is taken from the working directory (where
    ``results/`` is). With ``kind = "peak_unbalance"`` θ continues with the thermal preload
    state (``thermal_max > 0``: τ ~ U(0, thermal_max), the preload bearing at F(1 + τ)) and
    the unbalance columns of ``[uncertainty.unbalance]`` (``UnbalanceOptions``), with or
    without ``from``."""

    distribution: str = "normal"
    from_: Annotated[str | None, Field(validation_alias=AliasChoices("from", "from_"))] = None
    mean: tuple[float, ...] | None = None
    std: tuple[float, ...] | None = None
    corr: tuple[tuple[float, ...], ...] | None = None
    thermal_max: float = 0.0
    unbalance: UnbalanceOptions | None = None

    def __post_init__(self) -> None:
        check_factor_moments(self.mean, self.std)
        check_range("thermal_max", self.thermal_max, 0.0, THERMAL_MAX)
        if self.from_ is None:
            return
        if not self.from_.strip():
            raise ValueError(f"from = {self.from_!r} is not allowed: give an identification run "
                             "folder or its uncertainty.json")
        given = [k for k in ("mean", "std", "corr") if getattr(self, k) is not None]
        if given:
            v = np.asarray(getattr(self, given[0])).tolist()
            raise ValueError(f"{given[0]} = {v} is not allowed with from = {self.from_!r}: the "
                             f"identified model gives θ's mean and covariance (remove "
                             f"{', '.join(given)}, or from)")


def identified_inputs(t: UncertaintyTable, theta_bearings: tuple[str, ...],
                      at: Mapping[str, Any] | None) -> tuple[Any, dict[str, Any]]:
    """The stiffness block of ``[uncertainty] from`` where θ applies (``at``:
    :func:`response_speeds`) and its provenance."""
    where = f"uncertainty.from = {t.from_!r}"
    if at is None:
        raise ValueError(f"{where} is not allowed here: this kind has no response speed to "
                         "evaluate the identified trend at (use it in a study)")
    if not Path(t.from_).exists():
        raise ValueError(f"{where} is not allowed: no such file or folder; give an "
                         "identification run folder or its uncertainty.json")
    try:
        return stiffness_block_from(t.from_, theta_bearings, **at,
                                    distribution=t.distribution)
    except ValueError as exc:
        msg = str(exc)
        raise ValueError(f"uncertainty.from{msg[len('source'):]}" if msg.startswith("source =")
                         else f"{where}: {msg}") from None


def response_speeds(response: ResponseSpec, spindle: ReferenceSpindle) -> dict[str, Any]:
    """Where θ applies, as ``stiffness_block_from`` keywords: the rated speed of
    ``at_speed``, else the spindle's speed range (a peak over it), :data:`PEAK_THETA_SPEEDS`
    speeds."""
    if response.kind == "at_speed":
        return {"speeds_rpm": [float(response.speed_rpm)]}
    g = spindle.geometry
    return {"speed_range_rpm": (g.speed_min_rpm, g.speed_max_rpm),
            "n_speeds": PEAK_THETA_SPEEDS}


def build_inputs(t: UncertaintyTable, theta_bearings: tuple[str, ...], *,
                 default_std: tuple[float, ...] = TABLE4_STD,
                 at: Mapping[str, Any] | None = None) -> Any:
    """The stiffness block of a ``[uncertainty]`` table: one positive factor per θ bearing
    (``uncertainty.stiffness_factors``; with ``from``, the identified model where θ applies,
    ``at``: :func:`response_speeds`, :func:`identified_inputs`)."""
    if t.from_ is not None:
        return identified_inputs(t, theta_bearings, at)[0]
    m = len(theta_bearings)
    mean = [1.0] * m if t.mean is None else list(t.mean)
    std = list(default_std[:m]) if t.std is None else list(t.std)
    for name, v in (("mean", mean), ("std", std)):
        if len(v) != m:
            raise ValueError(f"uncertainty.{name} = {v} is not allowed: need {m} values, one "
                             f"per θ bearing {list(theta_bearings)}")
    try:
        return stiffness_factors(mean, std, None if t.corr is None else np.asarray(t.corr),
                                 distribution=t.distribution)
    except ValueError as exc:
        raise ValueError(f"uncertainty.{exc}") from None


def build_theta(t: UncertaintyTable, spindle: ReferenceSpindle, response: ResponseSpec
                ) -> tuple[Any, ResponseSpec, dict[str, Any] | None]:
    """θ of a ``[uncertainty]`` table for ``response``, the response (for
    ``kind = "peak_unbalance"`` the ``PeakUnbalanceSpec`` carrying θ's columns) and, with
    ``from``, the identified model's provenance (for ``meta.json``; else ``None``)."""
    if t.from_ is not None:
        block, source = identified_inputs(t, spindle.theta_bearings,
                                          response_speeds(response, spindle))
    else:
        block, source = None, None
    if response.kind != "peak_unbalance":
        for key, given in (("unbalance", t.unbalance is not None),
                           ("thermal_max", t.thermal_max != 0.0)):
            if given:
                raise ValueError(f"uncertainty.{key} is not allowed with response.kind = "
                                 f"{response.kind!r}: θ is the stiffness factors (the geometry's "
                                 "unbalance is fixed); use kind = 'peak_unbalance'")
        if block is None:
            block = build_inputs(t, spindle.theta_bearings)
        return block, response, source
    if block is None:
        block = build_inputs(t, spindle.theta_bearings, default_std=RESIDUAL_STD)
    try:
        return (*peak_unbalance_inputs(spindle, block, thermal_max=t.thermal_max,
                                       unbalance=t.unbalance), source)
    except ValueError as exc:
        key = str(exc).split(" ", 1)[0]
        where = {"thermal_max": "uncertainty.", "magnitude": "uncertainty.unbalance.",
                 "relative_phase": "uncertainty.unbalance."}.get(key)
        raise ValueError(f"{where}{exc}" if where else f"uncertainty.unbalance: {exc}") from None


@dataclass(frozen=True)
class LimitTable:
    """``[limit]``: failure when ``y > delta_lim_um`` (µm)."""

    delta_lim_um: float = 19.5

    def __post_init__(self) -> None:
        check_displacement_limit("delta_lim_um", self.delta_lim_um)

    def limit(self) -> LimitState:
        return LimitState(self.delta_lim_um * 1e-6)


@dataclass(frozen=True)
class DeterministicTable:
    """``[deterministic]``: the deterministic constraints. ``stress`` (σ_VM/σ_yield ≤ 1,
    design model), ``resonance``: ``"paper"`` (f_n1 ≥ ``factor`` · ``omega_max_rpm``/60,
    design model), ``"separation"`` (API 617 / API RP 684: every critical speed with AF ≥ 2.5
    outside the operating range by the API margins, from the exact forward critical speeds of
    each design up to ``search_factor`` × the top speed) or ``"none"``; ``practice``: the
    checks a spindle designer imposes (``spindle.practice``: bearing speed capability, ISO 281
    life, ISO 76 static safety, motor length against span, run-up time), with
    ``[deterministic.practice_spec]`` (``PracticeSpec`` fields) replacing their data.
    ``design_basis``: what the deterministic strategy designs against, ``"unbalance_cases"``
    (the API RP 684 unbalance arrangements, every plane at its ISO 21940-11 limit, in phase
    and in couple: ``study.unbalance_design_cases``; the default with a random unbalance) or
    ``"median"`` (the image of u = 0; the default otherwise)."""

    stress: bool = True
    yield_strength_pa: float = 930e6
    resonance: str = "paper"
    factor: float = 1.2
    omega_max_rpm: float | None = None
    search_factor: float = 1.5
    practice: bool = False
    practice_spec: PracticeSpec | None = None
    design_basis: str | None = None

    def __post_init__(self) -> None:
        if self.design_basis is not None:
            check_choice("design_basis", self.design_basis, DESIGN_BASES)
        # f_n1 >= factor x top speed: API RP 684 asks margins of 10-26 %; 10 x is no guard
        check_range("factor", self.factor, 0.0, 10.0, inclusive=False)
        check_range("search_factor", self.search_factor, 1.0, 10.0)

    def design_theta(self, inputs: Any, response: ResponseSpec) -> np.ndarray | None:
        """The deterministic strategy's design-basis θ rows (``None``: the image of u = 0)."""
        unbalance = response.kind == "peak_unbalance"
        basis = self.design_basis or ("unbalance_cases" if unbalance else "median")
        if basis == "median":
            return None
        if not unbalance:
            raise ValueError(f"deterministic.design_basis = {basis!r} is not allowed with "
                             f"response.kind = {response.kind!r}: the unbalance is not random "
                             "(use 'median' or kind = 'peak_unbalance')")
        return unbalance_design_cases(inputs, response)

    def options(self, speed_max_rpm: float) -> DeterministicOptions:
        """The g_det of the design model (the separation guard is a design constraint);
        ``speed_max_rpm``: the top of the speeds the response is taken at, which
        ``omega_max_rpm`` (the top operating speed the resonance guard protects) must cover."""
        if self.omega_max_rpm is not None:
            check_positive("deterministic.omega_max_rpm", self.omega_max_rpm)
            if self.omega_max_rpm < speed_max_rpm:
                raise ValueError(f"deterministic.omega_max_rpm = {self.omega_max_rpm:g} is not "
                                 f"allowed: must be at least {speed_max_rpm:g} rpm, the top of "
                                 "the response's speed range (the resonance guard must cover "
                                 "every speed the spindle is assessed at)")
        top = speed_max_rpm if self.omega_max_rpm is None else self.omega_max_rpm
        try:
            return DeterministicOptions(
                stress=self.stress, yield_strength_pa=self.yield_strength_pa,
                resonance="none" if self.resonance == "separation" else self.resonance,
                factor=self.factor, omega_max=top * RPM)
        except ValueError as exc:
            raise ValueError(f"deterministic.{exc}") from None

    def constraints(self, spindle: ReferenceSpindle) -> tuple[Any, ...]:
        """The practice checks and the exact separation guard, as design constraints."""
        if self.practice_spec is not None and not self.practice:
            raise ValueError("deterministic.practice_spec is not allowed with practice = false: "
                             "set practice = true")
        spec = self.practice_spec or PracticeSpec(speed_max_rpm=spindle.geometry.speed_max_rpm)
        try:
            return spindle_constraints(spindle, practice=spec if self.practice else None,
                                       resonance="none" if self.resonance != "separation"
                                       else "separation", search_factor=self.search_factor)
        except ValueError as exc:
            raise ValueError(f"deterministic.{str(exc).replace('practice:', 'practice_spec:')}"
                             ) from None


__all__ = ["DESIGN_BASES", "FACTOR_MAX_COV", "FACTOR_MEAN_RANGE", "PEAK_THETA_SPEEDS",
           "THERMAL_MAX", "DeterministicTable", "LimitTable", "UncertaintyTable", "build_inputs",
           "build_theta", "check_factor_moments", "identified_inputs", "response_speeds"]
