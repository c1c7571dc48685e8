"""What is measured and where: channels (probe positions and directions) and sweeps of
operating points (spin speed and response frequency) with their unit loads.

A *sweep* is a list of operating points, each a spin speed ``Ω`` and a response frequency
``ω``: the steady 1x unbalance response has ``ω = Ω`` at every measured speed, an impact test at
standstill has ``Ω = 0`` and ``ω`` on the FRF's frequency lines.
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
        (``Ω = 0``; one unit force per excitation channel).
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
    def impact(cls, freqs_hz: Sequence[float], excitations: Sequence[Channel]) -> Sweep:
        """Impact test at standstill, FRF lines ``freqs_hz``, forces at ``excitations``."""
        w = 2 * np.pi * np.asarray(freqs_hz, dtype=float)
        return cls("impact", np.zeros_like(w), w, tuple(excitations))


def with_nodes_at(geometry: SpindleGeometry, positions_mm: Sequence[float]) -> SpindleGeometry:
    """The geometry with a mesh node at every position: zero-magnitude unbalances are added
    (the mesher puts a node at every unbalance position; a zero unbalance loads nothing)."""
    extra = tuple(Unbalance(float(p), 0.0) for p in positions_mm)
    return replace(geometry, unbalances=geometry.unbalances + extra)
