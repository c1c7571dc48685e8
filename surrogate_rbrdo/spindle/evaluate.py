"""The spindle as a response ``y(x, θ)``: peak tool-tip amplitude (or the amplitude at one
operating speed, :class:`ResponseSpec`), and per-design quantities.

:class:`PeakAmplitudeResponse` implements the core ``Response`` protocol (designs ``(P, 3)`` ×
θ ``(N, m)`` → ``(P, N)`` amplitudes in metres); it builds one FE model per design and solves all
θ samples of that design in one vectorised pass. :class:`PointwisePeak` evaluates one joint
point ``[x, θ]`` (for DOE sampling in worker processes; it pickles cheaply).
:func:`design_quantities` gives the deterministic quantities of the constraints.

>>> import numpy as np
>>> from surrogate_rbrdo.spindle.reference import reference_spindle
>>> resp = PeakAmplitudeResponse(reference_spindle())
>>> y = resp(np.array([[3000.0, 300.0, 80.0]]), np.array([[1.0, 1.0], [0.9, 1.1]]))
>>> y.shape, bool(np.all((y > 1e-7) & (y < 1e-4)))
((1, 2), True)
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import brentq

from surrogate_rbrdo.core.errors import ModelError
from surrogate_rbrdo.core.validate import check_choice, check_positive
from surrogate_rbrdo.spindle.coupling import tool_amplitude_condensed
from surrogate_rbrdo.spindle.harmonic import PeakOptions, peak_tool_amplitude, tool_amplitude
from surrogate_rbrdo.spindle.modal import (
    critical_speeds,
    first_natural_frequency,
    modal_analysis,
)
from surrogate_rbrdo.spindle.reference import ReferenceSpindle
from surrogate_rbrdo.spindle.stress import max_von_mises

#: how ``AtSpeedAmplitudeResponse`` solves the FE model
FE_METHODS = ("direct", "condensed")


class _PerDesign:
    """Designs × θ by one FE model per design: subclasses give ``_amplitudes(model, θ)``."""

    spindle: ReferenceSpindle

    def _amplitudes(self, model, theta: np.ndarray) -> np.ndarray:  # pragma: no cover
        raise NotImplementedError

    @property
    def n_theta(self) -> int:
        return len(self.spindle.theta_bearings)

    def __call__(self, x: np.ndarray, theta: np.ndarray) -> np.ndarray:
        x = np.atleast_2d(np.asarray(x, dtype=float))
        theta = np.atleast_2d(np.asarray(theta, dtype=float))
        out = np.empty((x.shape[0], theta.shape[0]))
        for i, xi in enumerate(x):
            out[i] = self._amplitudes(self.spindle.model(xi), theta)
        return out

    def point(self, z: np.ndarray) -> float:
        """``y`` at one joint point ``z = [x, θ]``."""
        z = np.asarray(z, dtype=float)
        d = len(self.spindle.design_map.names)
        return float(self._amplitudes(self.spindle.model(z[:d]), z[None, d:])[0])


@dataclass(frozen=True)
class PeakAmplitudeResponse(_PerDesign):
    """Peak tool-tip amplitude (m) over the speed range, for designs × θ samples."""

    spindle: ReferenceSpindle
    options: PeakOptions = field(default_factory=PeakOptions)

    def _amplitudes(self, model, theta: np.ndarray) -> np.ndarray:
        return peak_tool_amplitude(model, theta, options=self.options).amplitude


@dataclass(frozen=True)
class PointwisePeak:
    """``f(z) -> y`` for one joint point ``z = [x (3), θ (m)]`` (metres)."""

    spindle: ReferenceSpindle
    options: PeakOptions = field(default_factory=PeakOptions)

    def __call__(self, z: np.ndarray) -> float:
        return PeakAmplitudeResponse(self.spindle, self.options).point(z)


@dataclass(frozen=True)
class AtSpeedAmplitudeResponse(_PerDesign):
    """Tool-tip orbit amplitude (m) at one operating speed, for designs × θ samples.

    The response of a spindle that runs at a rated speed (the paper validates at 24 000 rpm,
    its Table 7): unlike the peak over the range, it sees the tool-tip *cancellation notch* of
    the fixed in-phase unbalance planes, which the design can tune to the operating speed
    (docs/paper-study.md, synthetic "rated-speed problem": not a spindle result).

    ``method`` says how the FE model is solved, both exactly: ``"direct"`` (default) solves
    the whole system once per θ (``harmonic.tool_amplitude``); ``"condensed"`` condenses the
    rotor once per design and couples the θ sample through ``3^m`` node solves
    (``coupling.tool_amplitude_condensed``; 12–17x faster for 1 000 θ, equal to 1e-11:
    ``benchmarks/bench_spindle.py``).
    The FE verification of a study keeps ``"direct"``, independent of the surrogate's algebra.

    >>> import numpy as np
    >>> from surrogate_rbrdo.spindle.reference import reference_spindle
    >>> sp = reference_spindle()
    >>> r = AtSpeedAmplitudeResponse(sp, 24000.0)
    >>> y = r(np.array([[3000.0, 600.0, 80.0]]), np.array([[1.0, 1.0]]))
    >>> bool(y[0, 0] <= PeakAmplitudeResponse(sp)(np.array([[3000.0, 600.0, 80.0]]),
    ...                                           np.array([[1.0, 1.0]]))[0, 0])
    True
    """

    spindle: ReferenceSpindle
    speed_rpm: float = 24000.0
    method: str = "direct"

    def __post_init__(self) -> None:
        object.__setattr__(self, "speed_rpm", check_positive("speed_rpm", self.speed_rpm))
        check_choice("method", self.method, FE_METHODS)

    def _amplitudes(self, model, theta: np.ndarray) -> np.ndarray:
        if self.method == "condensed":
            return tool_amplitude_condensed(model, self.speed_rpm, theta)
        return tool_amplitude(model, np.array([self.speed_rpm]), theta)[:, 0]


@dataclass(frozen=True)
class PointwiseAtSpeed:
    """``f(z) -> y`` at one operating speed for one joint point ``z = [x, θ]`` (metres)."""

    spindle: ReferenceSpindle
    speed_rpm: float = 24000.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "speed_rpm", check_positive("speed_rpm", self.speed_rpm))

    def __call__(self, z: np.ndarray) -> float:
        return AtSpeedAmplitudeResponse(self.spindle, self.speed_rpm).point(z)


RESPONSE_KINDS = ("peak", "at_speed", "peak_unbalance")


@dataclass(frozen=True)
class ResponseSpec:
    """Which tool-tip amplitude ``y`` is: the config's ``[response]`` table.

    ``kind = "peak"`` (default, the paper's definition): the peak over the speed range of the
    geometry, under the geometry's fixed unbalance; θ = the bearing stiffness factors.
    ``kind = "at_speed"``: the amplitude at ``speed_rpm`` (the rated speed), same θ.
    ``kind = "peak_unbalance"``: the peak over the speed range under a random residual
    unbalance (ISO 21940-11 magnitude and random phase per plane), whose columns join θ:
    :class:`~surrogate_rbrdo.spindle.peak_response.PeakUnbalanceSpec` carries them (the
    runner builds it from ``[uncertainty]``).

    >>> ResponseSpec("at_speed", 24000.0).label
    'amplitude at 24000 rpm'
    >>> try:
    ...     ResponseSpec("at_speed")
    ... except ValueError as exc:
    ...     print(str(exc)[:41])
    response.speed_rpm = None is not allowed:
    """

    kind: str = "peak"
    speed_rpm: float | None = None

    def __post_init__(self) -> None:
        check_choice("response.kind", self.kind, RESPONSE_KINDS)
        if self.kind != "at_speed" and self.speed_rpm is not None:
            raise ValueError(f"response.speed_rpm = {self.speed_rpm!r} is not allowed with kind "
                             f"= {self.kind!r} (the peak is over the geometry's speed range)")
        if self.kind == "at_speed":
            try:
                object.__setattr__(self, "speed_rpm",
                                   check_positive("response.speed_rpm", self.speed_rpm))
            except ValueError as exc:
                raise ValueError(f"{exc} (required with kind = 'at_speed')") from None

    @property
    def label(self) -> str:
        if self.kind == "peak_unbalance":
            return "peak amplitude, random unbalance"
        return ("peak amplitude" if self.kind == "peak"
                else f"amplitude at {self.speed_rpm:.0f} rpm")

    def theta_names(self, spindle: ReferenceSpindle) -> tuple[str, ...]:
        """The columns of θ (here the stiffness factors of the θ bearings)."""
        self._check_kind()
        return tuple(f"k_{b}" for b in spindle.theta_bearings)

    def _check_kind(self) -> None:
        if self.kind == "peak_unbalance":
            raise ValueError("response.kind = 'peak_unbalance' needs its θ columns and "
                             "unbalance tolerances: use spindle.peak_response.PeakUnbalanceSpec "
                             "(the runner builds it from [uncertainty])")

    def fe_response(self, spindle: ReferenceSpindle, method: str = "direct"):
        """The full-FE ``Response`` (designs × θ → metres); ``method`` as
        :class:`AtSpeedAmplitudeResponse` (the peak response has only ``"direct"``)."""
        self._check_kind()
        check_choice("method", method, FE_METHODS)
        if self.kind == "peak":
            if method != "direct":
                raise ValueError(f"method = {method!r} is not allowed with the peak response: "
                                 "only 'direct' (the peak is searched over speed per θ)")
            return PeakAmplitudeResponse(spindle)
        return AtSpeedAmplitudeResponse(spindle, self.speed_rpm, method)

    def pointwise(self, spindle: ReferenceSpindle):
        """The one-point FE function ``f([x, θ]) -> y`` used for DOE sampling."""
        self._check_kind()
        if self.kind == "peak":
            return PointwisePeak(spindle)
        return PointwiseAtSpeed(spindle, self.speed_rpm)


@dataclass(frozen=True)
class DesignQuantities:
    """Deterministic quantities of one design at nominal θ (SI units)."""

    rotor_mass_kg: float
    first_natural_frequency_hz: float
    critical_speeds_rpm: np.ndarray
    peak_amplitude_m: float
    peak_speed_rpm: float
    max_von_mises_Pa: float
    stress_ratio: float

    def to_dict(self) -> dict[str, object]:
        return {k: (v.tolist() if isinstance(v, np.ndarray) else v)
                for k, v in self.__dict__.items()}


def design_quantities(
    spindle: ReferenceSpindle, x: np.ndarray, *, theta: np.ndarray | None = None,
    crit_grid_rpm: np.ndarray | None = None,
) -> DesignQuantities:
    """Mass, first natural frequency (at standstill), 1x critical speeds in the speed range,
    nominal peak amplitude and the maximum von Mises stress at the peak speed."""
    model = spindle.model(np.asarray(x, dtype=float))
    g = model.geometry
    grid = crit_grid_rpm if crit_grid_rpm is not None else np.linspace(
        g.speed_min_rpm, g.speed_max_rpm, 24)
    peak = peak_tool_amplitude(model, theta)
    stress = max_von_mises(model, float(peak.speed_rpm[0]), theta)
    yield_Pa = g.min_yield_Pa
    return DesignQuantities(
        rotor_mass_kg=model.rotor_mass_kg,
        first_natural_frequency_hz=first_natural_frequency(model, 0.0, theta),
        critical_speeds_rpm=critical_speeds(model, grid, theta),
        peak_amplitude_m=float(peak.amplitude[0]),
        peak_speed_rpm=float(peak.speed_rpm[0]),
        max_von_mises_Pa=stress.max_von_mises_Pa,
        stress_ratio=stress.max_von_mises_Pa / yield_Pa,
    )


@dataclass(frozen=True)
class ResonanceQuantities:
    """Smooth ingredients of the peak amplitude, for physics-structured surrogates (SI units).

    ``critical_rpm``: the first forward 1x critical speed (fixed point ``n = 60 f_fw,1(n)`` of
    the lowest forward-whirl frequency), also when it lies above the operating range;
    ``amp_res_m``: the peak tool amplitude within ±``window`` of it (the resonance's height);
    ``amp_top_m``: the amplitude at ``n_max``; ``peak_m``: the peak over ``[n_min, n_max]``
    (the response ``y``). Arrays over θ. Where the critical speed lies in range,
    ``peak_m ≈ amp_res_m``; above it the peak is the flank value ``amp_top_m``: a near-step in
    (x, θ) that the smooth ``critical_rpm`` locates.
    """

    critical_rpm: np.ndarray
    amp_res_m: np.ndarray
    amp_top_m: np.ndarray
    peak_m: np.ndarray


def first_critical_speed(model, theta: np.ndarray | None = None, *, rtol: float = 1e-7,
                         max_iter: int = 60) -> float:
    """First forward 1x critical speed (rpm): the root of ``h(n) = 60 f_fw,1(n) − n``.

    Two fixed-point iterates ``n0 = n_max``, ``n1 = 60 f_fw,1(n0)`` bracket the root whenever
    ``f_fw,1`` is monotone in ``n`` (speed softening, gyroscopic stiffening), and Brent's method
    finishes in a few modal analyses; otherwise the fixed-point iteration is continued. Raises
    ``ModelError`` if neither converges.
    """
    seen: dict[float, float] = {}   # the bracket ends are asked for again by brentq

    def f(n: float) -> float:
        if n not in seen:
            fw = modal_analysis(model, n, theta).forward()
            if fw.size == 0:
                raise ModelError("no forward-whirl mode found")
            seen[n] = 60.0 * float(fw[0])
        return seen[n]

    n0 = model.geometry.speed_max_rpm
    n1 = f(n0)
    a, b = min(n0, n1), max(n0, n1)
    if a == b:
        return n1
    ha, hb = f(a) - a, f(b) - b
    if ha >= 0 >= hb:
        return float(brentq(lambda n: f(n) - n, a, b, rtol=rtol))
    n = n1
    for _ in range(max_iter):
        n_new = f(n)
        if abs(n_new - n) <= rtol * n_new:
            return n_new
        n = n_new
    raise ModelError(f"first critical speed: no convergence (last {n:.6g} rpm)")


def resonance_quantities(
    spindle: ReferenceSpindle, x: np.ndarray, theta: np.ndarray, *, window: float = 0.03,
    options: PeakOptions | None = None,
) -> ResonanceQuantities:
    """:class:`ResonanceQuantities` of design ``x`` for every row of ``theta``."""
    if not 0.0 < window < 0.5:
        raise ValueError(f"window = {window} is not allowed: must lie in (0, 0.5)")
    opts = options or PeakOptions()
    model = spindle.model(np.asarray(x, dtype=float))
    th = model.check_theta(theta)
    g = model.geometry
    crit = np.array([first_critical_speed(model, t) for t in th])
    res = np.array([
        peak_tool_amplitude(model, t, speed_range_rpm=(c * (1 - window), c * (1 + window)),
                            options=opts).amplitude[0] for t, c in zip(th, crit, strict=True)
    ])
    peak = peak_tool_amplitude(model, th, options=opts)
    top = tool_amplitude(model, np.array([g.speed_max_rpm]), th)[:, 0]
    return ResonanceQuantities(crit, res, top, peak.amplitude)


@dataclass(frozen=True)
class PointwiseResonance:
    """``f(z) -> [critical_rpm, amp_res_m, amp_top_m, peak_m]`` for one joint point
    ``z = [x, θ]`` (for DOE sampling in worker processes)."""

    spindle: ReferenceSpindle
    window: float = 0.03
    options: PeakOptions = field(default_factory=PeakOptions)

    def __call__(self, z: np.ndarray) -> np.ndarray:
        z = np.asarray(z, dtype=float)
        d = len(self.spindle.design_map.names)
        q = resonance_quantities(self.spindle, z[:d], z[None, d:], window=self.window,
                                 options=self.options)
        return np.array([q.critical_rpm[0], q.amp_res_m[0], q.amp_top_m[0], q.peak_m[0]])
