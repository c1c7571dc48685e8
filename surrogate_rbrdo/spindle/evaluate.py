"""The spindle as a response ``y(x, θ)``: peak tool-tip amplitude, and per-design quantities.

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

from surrogate_rbrdo.spindle.harmonic import PeakOptions, peak_tool_amplitude
from surrogate_rbrdo.spindle.modal import critical_speeds, first_natural_frequency
from surrogate_rbrdo.spindle.reference import ReferenceSpindle
from surrogate_rbrdo.spindle.stress import max_von_mises


@dataclass(frozen=True)
class PeakAmplitudeResponse:
    """Peak tool-tip amplitude (m) over the speed range, for designs × θ samples."""

    spindle: ReferenceSpindle
    options: PeakOptions = field(default_factory=PeakOptions)

    @property
    def n_theta(self) -> int:
        return len(self.spindle.theta_bearings)

    def __call__(self, x: np.ndarray, theta: np.ndarray) -> np.ndarray:
        x = np.atleast_2d(np.asarray(x, dtype=float))
        theta = np.atleast_2d(np.asarray(theta, dtype=float))
        out = np.empty((x.shape[0], theta.shape[0]))
        for i, xi in enumerate(x):
            model = self.spindle.model(xi)
            out[i] = peak_tool_amplitude(model, theta, options=self.options).amplitude
        return out


@dataclass(frozen=True)
class PointwisePeak:
    """``f(z) -> y`` for one joint point ``z = [x (3), θ (m)]`` (metres)."""

    spindle: ReferenceSpindle
    options: PeakOptions = field(default_factory=PeakOptions)

    def __call__(self, z: np.ndarray) -> float:
        z = np.asarray(z, dtype=float)
        d = len(self.spindle.design_map.names)
        model = self.spindle.model(z[:d])
        return float(peak_tool_amplitude(model, z[None, d:], options=self.options).amplitude[0])


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
    yield_Pa = min(g.materials[s.material].yield_Pa for s in g.sections)
    return DesignQuantities(
        rotor_mass_kg=model.rotor_mass_kg,
        first_natural_frequency_hz=first_natural_frequency(model, 0.0, theta),
        critical_speeds_rpm=critical_speeds(model, grid, theta),
        peak_amplitude_m=float(peak.amplitude[0]),
        peak_speed_rpm=float(peak.speed_rpm[0]),
        max_von_mises_Pa=stress.max_von_mises_Pa,
        stress_ratio=stress.max_von_mises_Pa / yield_Pa,
    )
