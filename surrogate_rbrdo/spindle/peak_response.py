"""The credible reference response: peak tool-tip amplitude over the operating range with
random multi-plane unbalance, for designs × θ samples.

θ (:class:`ThetaSpec`, columns in this order):

* bearing stiffness factors (one per θ bearing; nominal 1, scatter around the speed trend);
* optionally the thermal preload state ``τ`` of the preload bearing: its operating preload is
  ``F (1 + τ)``, so its stiffness factor is multiplied by ``(1 + τ)^e`` (``e`` the Hertz
  exponent of its preload law, 1/3);
* the magnitude of each plane's residual unbalance as a fraction ``r_j ∈ [0, 1]`` of the
  plane's permissible value (ISO 21940-11, :mod:`~surrogate_rbrdo.spindle.unbalance`);
  absent when every plane sits at its limit (``magnitude = "limit"``);
* the phases (degrees): of planes 2…P relative to plane 1 (``relative_phase``, default: the
  orbit amplitude does not change when every phase turns by the same angle, so this drops
  one exact dimension), or of every plane.

The response is linear in the unbalance phasors ``U_j = U_per,j r_j e^{iφ_j}``; each design's
peak over the speed range is solved by the exact coupling of
:mod:`~surrogate_rbrdo.spindle.peak_coupling` (``method = "coupled"``) or, as the reference,
by the FE model's peak search per sample (``"direct"``).

>>> import numpy as np
>>> from surrogate_rbrdo.spindle.reference import reference_spindle
>>> spec = ThetaSpec()
>>> spec.names
('k_front', 'k_rear', 'u_frac[0]', 'u_frac[1]', 'phase_deg[1]')
>>> resp = PeakUnbalanceResponse(reference_spindle(), spec)
>>> th = np.array([[1.0, 1.0, 1.0, 1.0, 0.0], [1.0, 1.0, 1.0, 1.0, 180.0]])
>>> y = resp(np.array([[3000.0, 350.0, 80.0]]), th)
>>> y.shape, bool(y[0, 0] != y[0, 1])
((1, 2), True)
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from surrogate_rbrdo.core.validate import check_choice, check_int, check_positive
from surrogate_rbrdo.spindle.coupling import theta_grid
from surrogate_rbrdo.spindle.evaluate import FE_METHODS, ResponseSpec
from surrogate_rbrdo.spindle.geometry import PreloadLaw
from surrogate_rbrdo.spindle.peak_coupling import (
    CoupledPeakOptions,
    peak_tool_amplitude_coupled,
    peak_tool_amplitude_unbalance,
)
from surrogate_rbrdo.spindle.reference import ReferenceSpindle
from surrogate_rbrdo.spindle.unbalance import (
    REFERENCE_TOLERANCES,
    UnbalanceTolerances,
    permissible_unbalance,
)

MAGNITUDE_LAWS = ("disk", "limit")
PEAK_METHODS = ("coupled", "direct")


@dataclass(frozen=True)
class ThetaSpec:
    """The columns of θ and the parameters of their distributions (module docstring).

    Defaults are the reference problem's (docs/reference-spindle.md states each source):
    stiffness scatter around the speed trend CoV 1.5 % front, 3.3 % rear (the paper's Table 4
    with its 50-speed trend removed, paper-notes §13), independent; no thermal column;
    unbalance uniform over each plane's tolerance disk; relative phases.
    """

    bearings: tuple[str, ...] = ("front", "rear")
    stiffness_std: tuple[float, ...] = (0.015, 0.033)
    stiffness_corr: tuple[tuple[float, ...], ...] | None = None
    thermal_max: float = 0.0
    preload_bearing: str = "front"
    n_planes: int = 2
    magnitude: str = "disk"
    relative_phase: bool = True

    def __post_init__(self) -> None:
        object.__setattr__(self, "bearings", tuple(self.bearings))
        object.__setattr__(self, "stiffness_std", tuple(float(s) for s in self.stiffness_std))
        if len(self.stiffness_std) != len(self.bearings):
            raise ValueError(f"stiffness_std = {list(self.stiffness_std)} is not allowed: give "
                             f"one standard deviation per bearing {list(self.bearings)}")
        for i, s in enumerate(self.stiffness_std):
            check_positive(f"stiffness_std[{i}]", s)
        if self.stiffness_corr is not None:
            c = np.asarray(self.stiffness_corr, dtype=float)
            m = len(self.bearings)
            if c.shape != (m, m) or not np.allclose(c, c.T) or not np.allclose(np.diag(c), 1):
                raise ValueError(f"stiffness_corr = {self.stiffness_corr!r} is not allowed: "
                                 f"must be a symmetric ({m}, {m}) correlation matrix")
        check_positive("thermal_max", self.thermal_max, allow_zero=True)
        if self.thermal_max > 0 and self.preload_bearing not in self.bearings:
            raise ValueError(f"preload_bearing = {self.preload_bearing!r} is not allowed with "
                             f"thermal_max > 0: must be one of {list(self.bearings)}")
        check_int("n_planes", self.n_planes, minimum=1)
        check_choice("magnitude", self.magnitude, MAGNITUDE_LAWS)

    @property
    def thermal(self) -> bool:
        return self.thermal_max > 0

    @property
    def names(self) -> tuple[str, ...]:
        out = tuple(f"k_{b}" for b in self.bearings)
        out += ("thermal_preload",) if self.thermal else ()
        if self.magnitude == "disk":
            out += tuple(f"u_frac[{j}]" for j in range(self.n_planes))
        first = 1 if self.relative_phase else 0
        return out + tuple(f"phase_deg[{j}]" for j in range(first, self.n_planes))

    @property
    def dim(self) -> int:
        return len(self.names)

    def unbalance_cases(self, theta0: np.ndarray) -> np.ndarray:
        """The deterministic design basis: the unbalance arrangements of an API RP 684 / API
        617 unbalance response analysis, each plane at its ISO 21940-11 permissible value.

        Rows ``(k, dim)``: ``theta0`` (the other columns, e.g. the median θ) with every
        magnitude fraction 1 and the phases of (a) every plane in phase (the static unbalance
        that excites the first, translatory/bending mode) and (b) alternate planes at 180°
        (the couple unbalance that excites the conical/pivotal mode; absent with one plane).
        API RP 684 (2nd ed., 2005) §2.6 and API 617 §2.6.2.7 place the unbalance to excite
        each mode in turn and check the response of every arrangement; a deterministic design
        is then judged by the worse of the two. For two planes the worse of (a) and (b) is at
        least the root-sum-square of the single-plane responses at every speed
        (|a + b|² + |a − b|² = 2|a|² + 2|b|²), so no design can pass it by a cancellation of
        the planes, and at most √2 below the worst relative phase (|a| + |b|).

        >>> ThetaSpec().unbalance_cases(np.array([1.0, 1.0, 0.7, 0.7, 180.0])).tolist()
        [[1.0, 1.0, 1.0, 1.0, 0.0], [1.0, 1.0, 1.0, 1.0, 180.0]]
        """
        t0 = np.asarray(theta0, dtype=float).reshape(-1)
        if t0.shape != (self.dim,) or not np.all(np.isfinite(t0)):
            raise ValueError(f"theta0 has shape {np.shape(theta0)}: must be finite ({self.dim},)"
                             f" with columns {list(self.names)}")
        P, names = self.n_planes, self.names
        phases = [np.zeros(P)] + ([np.where(np.arange(P) % 2 == 1, 180.0, 0.0)] if P > 1
                                  else [])
        first = 1 if self.relative_phase else 0
        rows = []
        for ph in phases:
            row = t0.copy()
            if self.magnitude == "disk":
                row[[names.index(f"u_frac[{j}]") for j in range(P)]] = 1.0
            row[[names.index(f"phase_deg[{j}]") for j in range(first, P)]] = ph[first:]
            rows.append(row)
        return np.array(rows)

    def split(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray | None, np.ndarray,
                                                np.ndarray]:
        """Stiffness factors ``(N, m)``, thermal state ``(N,)`` or None, magnitude fractions
        ``(N, P)`` and phases in radians ``(N, P)`` from θ ``(N, dim)``."""
        th = np.atleast_2d(np.asarray(theta, dtype=float))
        if th.ndim != 2 or th.shape[1] != self.dim or not np.all(np.isfinite(th)):
            raise ValueError(f"theta has shape {np.shape(theta)}: must be finite (N, "
                             f"{self.dim}) with columns {list(self.names)}")
        m, P, N = len(self.bearings), self.n_planes, th.shape[0]
        k, c = th[:, :m], m
        tau = None
        if self.thermal:
            tau, c = th[:, c], c + 1
            if np.any(tau < 0):
                raise ValueError("theta: thermal_preload < 0 is not allowed (a relative rise "
                                 "of the preload, >= 0)")
        if self.magnitude == "disk":
            r, c = th[:, c:c + P], c + P
            if np.any((r < 0) | (r > 1)):
                raise ValueError("theta: u_frac outside [0, 1] is not allowed (a fraction of "
                                 "the permissible unbalance)")
        else:
            r = np.ones((N, P))
        phi = np.zeros((N, P))
        first = 1 if self.relative_phase else 0
        phi[:, first:] = np.deg2rad(th[:, c:])
        return k, tau, r, phi


@dataclass(frozen=True)
class PeakUnbalanceResponse:
    """Peak tool-tip amplitude (m) over the speed range, designs ``(P, 3)`` × θ ``(N, dim)``.

    ``speed_range_rpm`` defaults to the geometry's range. ``method``: ``"coupled"`` (exact
    coupling, ~1e-4 of the FE peak search; ``benchmarks/bench_peak_coupling.py``) or
    ``"direct"`` (the FE peak search per sample, ~10 ms per sample).
    """

    spindle: ReferenceSpindle
    theta_spec: ThetaSpec = field(default_factory=ThetaSpec)
    tolerances: UnbalanceTolerances = REFERENCE_TOLERANCES
    method: str = "coupled"
    options: CoupledPeakOptions = field(default_factory=CoupledPeakOptions)
    speed_range_rpm: tuple[float, float] | None = None

    def __post_init__(self) -> None:
        check_choice("method", self.method, PEAK_METHODS)
        if tuple(self.theta_spec.bearings) != tuple(self.spindle.theta_bearings):
            raise ValueError(f"theta_spec.bearings = {list(self.theta_spec.bearings)} is not "
                             f"allowed: must be the spindle's θ bearings "
                             f"{list(self.spindle.theta_bearings)}")
        if self.theta_spec.n_planes != len(self.tolerances.planes):
            raise ValueError(f"theta_spec.n_planes = {self.theta_spec.n_planes} is not allowed: "
                             f"the tolerances give {len(self.tolerances.planes)} planes")

    @property
    def n_theta(self) -> int:
        return self.theta_spec.dim

    def unbalance(self, model, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Effective stiffness factors ``(N, m)`` and unbalance phasors ``(N, P)`` (kg m) of
        ``model`` for θ rows."""
        k, unit = self.split(theta)
        return k, permissible_unbalance(model, self.tolerances) * unit

    def split(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Effective stiffness factors ``(N, m)`` and unit phasors ``r e^{iφ}`` ``(N, P)``
        for θ rows: the same for every design (the thermal state enters through the preload
        law's exponent, which the design does not change); times each design's permissible
        unbalance they are its phasors (:meth:`unbalance`)."""
        spec = self.theta_spec
        k, tau, r, phi = spec.split(theta)
        if tau is not None:
            law = self.spindle.geometry.bearing(spec.preload_bearing).law
            e = law.exponent if isinstance(law, PreloadLaw) else 0.0
            k = k.copy()
            k[:, spec.bearings.index(spec.preload_bearing)] *= (1.0 + tau) ** e
        return k, r * np.exp(1j * phi)

    def _peaks(self, X: np.ndarray, theta: np.ndarray) -> list:
        """The peak (amplitudes and speeds) of every design for the θ rows: θ is mapped once
        and its interpolation grid built once for all designs."""
        X = np.atleast_2d(np.asarray(X, dtype=float))
        theta = np.atleast_2d(np.asarray(theta, dtype=float))
        out, k, unit, grid = [], None, None, None
        for x in X:
            model = self.spindle.model(x)
            if k is None:
                k, unit = self.split(theta)
                grid = theta_grid(k)
            U = permissible_unbalance(model, self.tolerances) * unit
            if self.method == "direct":
                out.append(peak_tool_amplitude_unbalance(
                    model, k, U, speed_range_rpm=self.speed_range_rpm))
            else:
                out.append(peak_tool_amplitude_coupled(
                    model, k, U, speed_range_rpm=self.speed_range_rpm, options=self.options,
                    grid=grid))
        return out

    def __call__(self, x: np.ndarray, theta: np.ndarray) -> np.ndarray:
        peaks = self._peaks(x, theta)
        return np.stack([p.amplitude for p in peaks])

    def peak_speeds(self, x: np.ndarray, theta: np.ndarray) -> np.ndarray:
        """Speed (rpm) of each sample's peak, ``(P, N)``."""
        return np.stack([p.speed_rpm for p in self._peaks(x, theta)])

    def point(self, z: np.ndarray) -> float:
        """``y`` at one joint point ``z = [x, θ]``."""
        z = np.asarray(z, dtype=float)
        d = len(self.spindle.design_map.names)
        return float(self(z[None, :d], z[None, d:])[0, 0])


@dataclass(frozen=True)
class PointwisePeakUnbalance:
    """``f(z) -> y`` for one joint point ``z = [x, θ]`` (metres), for DOE sampling in worker
    processes."""

    response: PeakUnbalanceResponse

    def __call__(self, z: np.ndarray) -> float:
        return self.response.point(z)


@dataclass(frozen=True)
class PeakUnbalanceSpec(ResponseSpec):
    """``[response] kind = "peak_unbalance"`` with its θ columns and unbalance tolerances.

    The study's response object for the random-unbalance peak (the runner builds it from
    ``[uncertainty]``): ``fe_response(spindle, "direct")`` is the FE model's peak search per
    sample, ``"condensed"`` the exact coupling of :mod:`~surrogate_rbrdo.spindle.
    peak_coupling` (condensation + θ polynomials, ≤ 3e-5 from the FE peak search).

    >>> from surrogate_rbrdo.spindle.reference import credible_spindle
    >>> spec = PeakUnbalanceSpec()
    >>> spec.label, spec.theta_names(credible_spindle())[2:]
    ('peak amplitude, random unbalance', ('u_frac[0]', 'u_frac[1]', 'phase_deg[1]'))
    """

    kind: str = "peak_unbalance"
    theta_spec: ThetaSpec = field(default_factory=ThetaSpec)
    tolerances: UnbalanceTolerances = REFERENCE_TOLERANCES

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.kind != "peak_unbalance":
            raise ValueError(f"kind = {self.kind!r} is not allowed: PeakUnbalanceSpec is "
                             "kind = 'peak_unbalance'")
        if self.theta_spec.n_planes != len(self.tolerances.planes):
            raise ValueError(f"theta_spec.n_planes = {self.theta_spec.n_planes} is not allowed:"
                             f" the tolerances give {len(self.tolerances.planes)} planes")

    def theta_names(self, spindle: ReferenceSpindle) -> tuple[str, ...]:
        return self.theta_spec.names

    def _response(self, spindle: ReferenceSpindle, method: str) -> PeakUnbalanceResponse:
        check_choice("method", method, FE_METHODS)
        return PeakUnbalanceResponse(spindle, self.theta_spec, self.tolerances,
                                     method="coupled" if method == "condensed" else "direct")

    def fe_response(self, spindle: ReferenceSpindle, method: str = "direct"):
        return self._response(spindle, method)

    def pointwise(self, spindle: ReferenceSpindle):
        return PointwisePeakUnbalance(self._response(spindle, "direct"))


__all__ = ["MAGNITUDE_LAWS", "PEAK_METHODS", "PeakUnbalanceResponse", "PeakUnbalanceSpec",
           "PointwisePeakUnbalance", "ThetaSpec"]
