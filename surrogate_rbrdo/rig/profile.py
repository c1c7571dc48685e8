"""Spin-speed profiles: constant, or linear between breakpoints; the exact shaft angle.

>>> p = SpeedProfile.ramp(1000.0, 2000.0, 1.0)
>>> round(float(p.angle(np.array([1.0]))[0] / (2 * np.pi)), 6)   # revolutions in the ramp
25.0
>>> p.breakpoints_between(-1.0, 2.0)
(0.0, 1.0)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from surrogate_rbrdo.core.validate import check_positive
from surrogate_rbrdo.spindle.assembly import RPM


@dataclass(frozen=True)
class SpeedProfile:
    """Spin speed linear between breakpoints ``(times_s, speeds_rpm)``; constant outside.

    The shaft angle ``φ(t) = phase0_rad + ∫Ω`` is integrated exactly (quadratic per piece).
    """

    times_s: tuple[float, ...]
    speeds_rpm: tuple[float, ...]
    phase0_rad: float = 0.0

    def __post_init__(self) -> None:
        t = np.asarray(self.times_s, float)
        s = np.asarray(self.speeds_rpm, float)
        if t.ndim != 1 or t.size < 1 or t.shape != s.shape or np.any(np.diff(t) <= 0):
            raise ValueError(f"SpeedProfile: times_s = {self.times_s} and speeds_rpm = "
                             f"{self.speeds_rpm} must be equal-length, times increasing")
        if not (np.all(np.isfinite(s)) and np.all(s >= 0)):
            raise ValueError(f"SpeedProfile.speeds_rpm = {self.speeds_rpm}: must be >= 0")
        object.__setattr__(self, "times_s", tuple(map(float, t)))
        object.__setattr__(self, "speeds_rpm", tuple(map(float, s)))

    @classmethod
    def constant(cls, speed_rpm: float, phase0_rad: float = 0.0) -> SpeedProfile:
        return cls((0.0,), (speed_rpm,), phase0_rad)

    @classmethod
    def ramp(cls, start_rpm: float, end_rpm: float, duration_s: float,
             phase0_rad: float = 0.0) -> SpeedProfile:
        check_positive("duration_s", duration_s)
        return cls((0.0, duration_s), (start_rpm, end_rpm), phase0_rad)

    @property
    def is_constant(self) -> bool:
        return len(set(self.speeds_rpm)) == 1

    def omega(self, t: np.ndarray) -> np.ndarray:
        """Spin speed (rad/s) at times ``t``."""
        return np.interp(t, self.times_s, self.speeds_rpm) * RPM

    def alpha(self, t: np.ndarray, side: str = "right") -> np.ndarray:
        """Angular acceleration (rad/s²) at times ``t`` (piecewise constant); at a breakpoint
        the value after it (``side="right"``) or before it (``"left"``)."""
        t = np.asarray(t, float)
        tb, sb = np.asarray(self.times_s), np.asarray(self.speeds_rpm) * RPM
        if tb.size == 1:
            return np.zeros_like(t)
        slope = np.diff(sb) / np.diff(tb)
        if side == "left":
            i = np.clip(np.searchsorted(tb, t, side="left") - 1, 0, slope.size - 1)
            return np.where((t > tb[0]) & (t <= tb[-1]), slope[i], 0.0)
        i = np.clip(np.searchsorted(tb, t, side="right") - 1, 0, slope.size - 1)
        return np.where((t >= tb[0]) & (t < tb[-1]), slope[i], 0.0)

    def angle(self, t: np.ndarray) -> np.ndarray:
        """Shaft angle (rad) at times ``t``: exact integral of the piecewise-linear speed."""
        t = np.asarray(t, float)
        tb, wb = np.asarray(self.times_s), np.asarray(self.speeds_rpm) * RPM
        cum = np.concatenate([[0.0], np.cumsum(0.5 * (wb[1:] + wb[:-1]) * np.diff(tb))])
        i = np.clip(np.searchsorted(tb, t, side="right") - 1, 0, tb.size - 1)
        dt = t - tb[i]
        w0 = wb[i]
        acc = np.where((i < tb.size - 1) & (t >= tb[0]), self.alpha(t), 0.0)
        before = t < tb[0]
        val = cum[i] + w0 * dt + 0.5 * acc * dt**2
        val = np.where(before, wb[0] * (t - tb[0]), val)
        return self.phase0_rad + val

    def breakpoints_between(self, t0: float, t1: float) -> tuple[float, ...]:
        """Breakpoint times strictly inside ``(t0, t1)`` (where the acceleration jumps)."""
        return tuple(t for t in self.times_s if t0 < t < t1)

    def constant_between(self, t0: float, t1: float) -> bool:
        """Whether the speed is the same over the whole of ``[t0, t1]``."""
        w = self.omega(np.array([t0, t1, *self.breakpoints_between(t0, t1)]))
        return bool(np.all(w == w[0]))

    def mean_rpm(self, t0: float, t1: float) -> float:
        """Time-averaged speed (rpm) over ``[t0, t1]``: revolutions per minute actually made."""
        a = self.angle(np.array([t0, t1]))
        return float((a[1] - a[0]) / (t1 - t0) / RPM)
