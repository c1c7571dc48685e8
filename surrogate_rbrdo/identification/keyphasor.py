"""A keyphasor phase refined by the pulse's own shape, with its standard error.

Synchronous demodulation takes the shaft angle from the keyphasor's rising edges (threshold at
mid-swing, interpolated between samples; ``rig.demod``). When a revolution spans a whole number
of samples (10 kHz at 24 000 rpm: 25), every edge falls at the same place between two samples,
the interpolation error is the same in every revolution and does not average out: the 1×
phase of the whole record is off by up to a few degrees (``docs/rig.md``), which moves the
identified damping by several times its value and the stiffness at second order.

The pulse's shape does not depend on speed: folded over the estimated angle, the keyphasor
samples of all records whose sample positions drift through the revolution (a fractional number
of samples per revolution) trace it at a fine angular resolution (:func:`pulse_template`).
Each record's phase is then refined by least squares of its own samples on that template,
``v_n ≈ P(φ_n + Δ)`` (Gauss–Newton on the offset ``Δ``; :func:`refine_phase`), which uses
every sample on either edge instead of a threshold crossing; its standard error
``σ_v / √Σ P'(φ_n + Δ)²`` says how well the record's samples pin the phase (large when no
sample falls on an edge).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from scipy.interpolate import CubicSpline

from surrogate_rbrdo.rig.records import RecordError

TWO_PI = 2.0 * np.pi
#: records whose sample positions leave a gap wider than this (in samples) within the sample
#: interval over their revolutions do not feed the template and have their phase searched
MAX_GAP = 0.1
#: records whose gap exceeds this (samples per revolution near an integer or a simple
#: fraction) have their phase searched over ± ``SEARCH_RAD``: the edge interpolation can then be
#: off by a few degrees, more than Gauss–Newton on a 10° edge recovers from
SEARCH_GAP = 0.2
SEARCH_RAD = 0.12


@dataclass(frozen=True, eq=False)
class PulseTemplate:
    """The keyphasor voltage as a periodic function of the shaft angle (rad): a periodic cubic
    spline, and a table of it every ``2π/65536`` for fast scans."""

    spline: CubicSpline
    n_samples: int
    table: np.ndarray
    active: np.ndarray
    residual_rms: float = 0.0

    def __call__(self, phi: np.ndarray, nu: int = 0) -> np.ndarray:
        return self.spline(np.mod(phi, TWO_PI), nu)

    def fast(self, phi: np.ndarray, nu: int = 0) -> np.ndarray:
        """Linear interpolation in the table (``nu = 1``: its slope); within ~1e-6 of the
        spline's swing for a 10° edge."""
        n = self.table.size
        x = np.mod(phi, TWO_PI) * (n / TWO_PI)
        i = x.astype(int) % n
        a, b = self.table[i], self.table[(i + 1) % n]
        if nu == 1:
            return (b - a) * (n / TWO_PI)
        f = x - np.floor(x)
        return a + f * (b - a)

    def near_pulse(self, phi: np.ndarray, margin_rad: float) -> np.ndarray:
        """Samples within ``margin_rad`` of where the pulse departs from its baseline."""
        n = self.active.size
        k = np.floor(np.mod(phi, TWO_PI) / TWO_PI * n).astype(int) % n
        return _dilate(self.active.tobytes(), int(np.ceil(max(margin_rad, 0.0) / TWO_PI * n)))[k]


def sample_phase_gap(speed_rpm: float, sample_rate_hz: float, n_revolutions: int) -> float:
    """Largest gap (in samples) between the sub-sample positions at which the revolutions of a
    record start: ~1/n_rev when they drift through the sample interval, 1 when the samples per
    revolution are an integer (they repeat), 1/2 for a half-integer, …"""
    spr = sample_rate_hz * 60.0 / speed_rpm
    f = np.sort(np.mod(np.arange(max(int(n_revolutions), 1)) * spr, 1.0))
    return float(np.max(np.diff(np.r_[f, f[0] + 1.0])))


def pulse_template(volts: list[np.ndarray], angles: list[np.ndarray], *,
                   n_bins: int = 8192) -> PulseTemplate:
    """Fold keyphasor samples over their (edge-based) shaft angles into bins and fit a periodic
    cubic spline through the bin means (empty bins skipped)."""
    v = np.concatenate(volts)
    a = np.mod(np.concatenate(angles), TWO_PI)
    k = np.minimum((a / TWO_PI * n_bins).astype(int), n_bins - 1)
    cnt = np.bincount(k, minlength=n_bins)
    if np.count_nonzero(cnt) < n_bins // 4:
        raise ValueError(f"pulse_template: samples cover {np.count_nonzero(cnt)} of {n_bins} "
                         "angle bins; need records with fractional samples per revolution")
    sa = np.bincount(k, a, minlength=n_bins)
    sv = np.bincount(k, v, minlength=n_bins)
    ok = cnt > 0
    x, y = sa[ok] / cnt[ok], sv[ok] / cnt[ok]
    x = np.r_[x, x[0] + TWO_PI]
    y = np.r_[y, y[0]]
    spline = CubicSpline(x, y, bc_type="periodic")
    table = spline(np.arange(65536) * (TWO_PI / 65536))
    lo, hi = np.percentile(table, [1, 99])
    active = np.abs(table - lo) > 0.02 * (hi - lo)
    tpl = PulseTemplate(spline, int(v.size), table, active[::32])   # 2048 cells
    near = tpl.near_pulse(a, 0.0)
    rms = float(np.sqrt(np.mean((v[near] - spline(a[near])) ** 2))) if near.any() else 0.0
    return PulseTemplate(spline, int(v.size), table, tpl.active, rms)


@functools.lru_cache(maxsize=16)
def _dilate(mask_bytes: bytes, k: int) -> np.ndarray:
    """Periodic dilation by ``k`` cells of a boolean mask (given as bytes, so it caches)."""
    mask = np.frombuffer(mask_bytes, dtype=bool)
    out = mask.copy()
    for s in range(1, k + 1):
        out |= np.roll(mask, s) | np.roll(mask, -s)
    return out


class PhaseFit(NamedTuple):
    """A record's refined phase: the offset ``Δ`` (rad), its standard error and the fitted
    rate ``ρ`` (rad over the half record)."""

    offset: float
    se: float
    rate: float


def refine_phase(v: np.ndarray, phi: np.ndarray, template: PulseTemplate, *,
                 search_rad: float = 0.0, iterations: int = 8) -> PhaseFit:
    """Offset ``Δ`` (rad) at the record's middle with ``v ≈ P(φ + Δ + ρ τ)`` (``τ`` the
    normalised time from the middle, ``ρ`` a small rate: the edge-based speed can be off too)
    and its standard error: the true angle is ``φ + Δ`` there, so a phasor demodulated on
    ``φ`` is corrected by ``e^{−iΔ}``.

    Only the samples near the pulse (where the template departs from its baseline, widened by
    ``search_rad``) are used. ``search_rad > 0`` first scans ``Δ`` over ``±search_rad`` (the
    least-squares objective of a sharp pulse sampled a few times per edge has local minima),
    then Gauss–Newton with steps limited to the scan's resolution. A record whose samples miss
    the pulse's edges gets an infinite standard error (its phase is not determined).
    """
    tau = np.linspace(-1.0, 1.0, phi.size)
    near = template.near_pulse(phi, search_rad + 0.02)
    v, phi, tau = v[near], phi[near], tau[near]
    p = np.zeros(2)
    sd_scan = 0.0
    if search_rad > 0:
        coarse = np.linspace(-search_rad, search_rad, int(np.ceil(search_rad / 2e-3)) * 2 + 1)
        c0 = np.array([float(np.sum((v - template.fast(phi + g)) ** 2)) for g in coarse])
        fine = coarse[int(np.argmin(c0))] + np.linspace(-2e-3, 2e-3, 9)
        c1 = np.array([float(np.sum((v - template.fast(phi + g)) ** 2)) for g in fine])
        grid, cost = np.r_[coarse, fine], np.r_[c0, c1]
        p[0] = grid[int(np.argmin(cost))]
        # offsets the data cannot tell from the best (Δχ² < 4 with the noise, or the
        # template's own error when the data are noise-free): an ambiguity interval
        s2 = max(cost.min() / max(v.size - 2, 1), template.residual_rms**2, 1e-300)
        amb = grid[cost <= cost.min() + 4.0 * s2]
        sd_scan = 0.25 * float(amb.max() - amb.min())
    for _ in range(iterations):
        r = v - template.fast(phi + p[0] + p[1] * tau)
        dP = template.fast(phi + p[0] + p[1] * tau, 1)
        J = np.column_stack([dP, dP * tau])
        JJ = J.T @ J
        if v.size < 3 or np.linalg.cond(JJ) > 1e12:
            return PhaseFit(float(p[0]), np.inf, float(p[1]))
        step = np.linalg.solve(JJ, J.T @ r)
        p += np.clip(step, -5e-4, 5e-4) if search_rad > 0 else step
        if np.all(np.abs(step) < 1e-9):
            break
    r = v - template.fast(phi + p[0] + p[1] * tau)
    sigma2 = float(r @ r) / max(v.size - 2, 1)
    cov = sigma2 * np.linalg.inv(JJ)
    se = max(float(np.sqrt(max(cov[0, 0], 0.0))), sd_scan)
    return PhaseFit(float(p[0]), se, float(p[1]))


def template_crossing(template: PulseTemplate, polarity: str,
                      source: str = "the records") -> float:
    """Angle (rad, in ``(−π, π]``) where the template's leading edge crosses mid-swing — the
    keyphasor's angular reference (threshold half-way between the 1st and 99th percentiles,
    as :func:`~surrogate_rbrdo.rig.keyphasor.edges_of` takes it): the rising edge of a
    positive pulse, the falling edge of a negative one. Refined on the spline by Newton.
    A template that does not cross once raises :class:`~surrogate_rbrdo.rig.records.RecordError`
    naming ``source`` (the records it was folded from).

    >>> from scipy.interpolate import CubicSpline

from surrogate_rbrdo.rig.records import RecordError
    >>> x = np.linspace(0.0, TWO_PI, 4097)
    >>> v = 0.5 * (1 + np.tanh(20 * np.sin(x - 0.3)))            # rises through 0.5 at 0.3
    >>> tpl = PulseTemplate(CubicSpline(x, v, bc_type="periodic"), 0, np.zeros(0),
    ...                     np.zeros(0, bool))
    >>> round(template_crossing(tpl, "positive"), 9)
    0.3
    """
    a = np.arange(65536) * (TWO_PI / 65536)
    v = template(a)
    if polarity == "negative":
        v = -v
    lo, hi = np.percentile(v, [1, 99])
    thr = 0.5 * (lo + hi)
    k = np.flatnonzero((v < thr) & (np.roll(v, -1) >= thr))
    if k.size != 1:
        raise RecordError(f"keyphasor pulse template of {source}", "keyphasor",
                          f"the folded pulse crosses mid-swing upwards {k.size} times per "
                          "revolution: not one keyphasor pulse")
    sign = -1.0 if polarity == "negative" else 1.0
    x = a[k[0]] + TWO_PI / 65536 * (thr - v[k[0]]) / (v[(k[0] + 1) % 65536] - v[k[0]])
    for _ in range(4):
        x -= (sign * template(np.array([x]))[0] - thr) / (sign * template(np.array([x]), 1)[0])
    return float(np.angle(np.exp(1j * x)))


__all__ = ["MAX_GAP", "SEARCH_GAP", "SEARCH_RAD", "PhaseFit", "PulseTemplate", "pulse_template",
           "refine_phase", "sample_phase_gap", "template_crossing"]
