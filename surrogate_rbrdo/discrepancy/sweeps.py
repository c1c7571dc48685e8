"""What is measured and where: channels (probe positions and directions) and sweeps of
operating points (spin speed and response frequency) with their unit loads.

A *sweep* is a list of operating points, each a spin speed ``Ω`` and a response frequency
``ω``: the steady 1x unbalance response has ``ω = Ω`` at every measured speed, an impact test has
``ω`` on the FRF's frequency lines and ``Ω`` the speed it was taken at (0 at standstill). Off
the synchronous line (``ω ≠ Ω``) a bearing stiffness that varies with speed, the gyroscopic
coupling and a cross-coupled stiffness leave signatures that no mass, inertia or damping
change can copy — which the 1x response alone (``ω = Ω``) cannot tell apart.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from surrogate_rbrdo.core.validate import check_choice, check_finite
from surrogate_rbrdo.spindle.assembly import RPM
from surrogate_rbrdo.spindle.geometry import SpindleGeometry, Unbalance

DIRECTIONS = ("x", "y")


@dataclass(frozen=True)
class Channel:
    """A measured displacement: a probe at ``position_mm`` (from the tool tip) in ``x`` or ``y``.

    >>> Channel("tool_x", 0.0, "x").dof_offset
    0
    """

    name: str
    position_mm: float
    direction: str

    def __post_init__(self) -> None:
        check_finite(f"channels[{self.name}].position_mm", self.position_mm)
        check_choice(f"channels[{self.name}].direction", self.direction, DIRECTIONS)

    @property
    def dof_offset(self) -> int:
        return DIRECTIONS.index(self.direction)


@dataclass(frozen=True)
class Sweep:
    """Operating points of one kind of test and its unit loads.

    Attributes
    ----------
    kind : str
        ``"unbalance_1x"`` (``ω = Ω``; one unit unbalance per plane) or ``"impact"``
        (``ω`` the FRF lines at one spin speed ``Ω``, 0 at standstill; one unit force per
        excitation channel).
    spin_rad_s, freq_rad_s : ndarray (X,)
        Spin speed and response frequency of every point.
    excitations : tuple of Channel
        Where a unit force acts (impact tests only).
    """

    kind: str
    spin_rad_s: np.ndarray
    freq_rad_s: np.ndarray
    excitations: tuple[Channel, ...] = ()

    def __post_init__(self) -> None:
        check_choice("sweep.kind", self.kind, ("unbalance_1x", "impact"))
        s = np.asarray(self.spin_rad_s, dtype=float)
        w = np.asarray(self.freq_rad_s, dtype=float)
        if s.ndim != 1 or s.shape != w.shape or s.size == 0:
            raise ValueError(f"sweep.spin_rad_s / freq_rad_s have shapes {s.shape}, {w.shape}: "
                             "must be equal, one-dimensional and not empty")
        if not (np.all(np.isfinite(s)) and np.all(np.isfinite(w)) and np.all(w > 0)
                and np.all(s >= 0)):
            raise ValueError("sweep.freq_rad_s must be finite and > 0, spin_rad_s finite >= 0")
        if self.kind == "impact" and np.ptp(s) > 0:
            raise ValueError(f"sweep.spin_rad_s of an impact test spans {s.min()}..{s.max()}: "
                             "an FRF is taken at one spin speed (one block per speed)")
        if self.kind == "impact" and not self.excitations:
            raise ValueError("sweep.excitations = () is not allowed for an impact test: give "
                             "at least one excitation channel")
        object.__setattr__(self, "spin_rad_s", s)
        object.__setattr__(self, "freq_rad_s", w)

    @classmethod
    def unbalance(cls, speeds_rpm: Sequence[float]) -> Sweep:
        """Steady-state 1x unbalance response at ``speeds_rpm``.

        >>> Sweep.unbalance([6000.0]).freq_rad_s.round(3).tolist()
        [628.319]
        """
        w = np.asarray(speeds_rpm, dtype=float) * RPM
        return cls("unbalance_1x", w, w)

    @classmethod
    def impact(cls, freqs_hz: Sequence[float], excitations: Sequence[Channel],
               speed_rpm: float = 0.0) -> Sweep:
        """Impact test at spin speed ``speed_rpm`` (default standstill), FRF lines
        ``freqs_hz``, forces at ``excitations``.

        >>> sw = Sweep.impact([100.0, 200.0], (Channel("tool_x", 0.0, "x"),), 12000.0)
        >>> sw.spin_rad_s.round(2).tolist(), round(sw.speed_rpm, 6)
        ([1256.64, 1256.64], 12000.0)
        """
        check_finite("sweep.speed_rpm", speed_rpm)
        if speed_rpm < 0:
            raise ValueError(f"sweep.speed_rpm = {speed_rpm} is not allowed: must be >= 0")
        w = 2 * np.pi * np.asarray(freqs_hz, dtype=float)
        return cls("impact", np.full_like(w, float(speed_rpm) * RPM), w, tuple(excitations))

    @property
    def speed_rpm(self) -> float:
        """The spin speed (rpm) of an impact test (its points share one); NaN for a 1x sweep."""
        if self.kind != "impact":
            return float("nan")
        return float(self.spin_rad_s[0] / RPM)


def with_nodes_at(geometry: SpindleGeometry, positions_mm: Sequence[float]) -> SpindleGeometry:
    """The geometry with a mesh node at every position: zero-magnitude unbalances are added
    (the mesher puts a node at every unbalance position; a zero unbalance loads nothing)."""
    extra = tuple(Unbalance(float(p), 0.0) for p in positions_mm)
    return replace(geometry, unbalances=geometry.unbalances + extra)
