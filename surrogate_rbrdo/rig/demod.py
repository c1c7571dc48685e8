"""1x amplitude and phase by synchronous demodulation with the keyphasor; run-up tracking and
critical speeds.

The keyphasor gives the shaft angle: its counter timestamps (``record.events["keyphasor"]``)
when the record has them, else the leading edges of the sampled keyphasor channel
(:func:`~.keyphasor.edges_of`, corrected for the channel's known delay). At (nominally) constant
speed the angle is a least-squares quadratic through the edges (``2πk`` at edge ``k``): constant
speed and a slow linear drift are both exact, and the edges' jitter is averaged; on ramps it is
interpolated between consecutive edges. A channel's samples, taken at their own times
``t_n + delay``, are fitted by least squares with ``a₀ + Σ_h Re(X_h e^{ihφ})`` (``h = 1`` and
optionally higher orders): the fit is exact for a DC offset and the fitted orders, whatever the
number of samples per revolution (a plain DFT over a non-integer number of samples per
revolution leaks the probe gap's DC into 1x). The phasor convention is the FE model's:
``x(t) = Re(X e^{iφ(t)})``, ``φ = 0`` at the keyphasor's leading edge.

>>> import numpy as np
>>> fs, f = 10_000.0, 123.4
>>> t = np.arange(10_000) / fs
>>> ang = 2 * np.pi * f * t + 0.3
>>> y = 2.0 + np.real((1.5 - 0.5j) * np.exp(1j * ang))
>>> X, res = fit_orders(y, ang, orders=(1, 2))
>>> np.round(X[0], 10)
np.complex128(1.5-0.5j)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.signal import find_peaks

from surrogate_rbrdo.rig.keyphasor import edges_of
from surrogate_rbrdo.rig.records import Record, RecordError


def keyphasor_edges(record: Record, channel: str = "keyphasor", *,
                    source: str | None = None, events: bool = True) -> np.ndarray:
    """Times (s, on the record's time axis) of the keyphasor's leading edges: the record's
    ``events[channel]`` if it has them (and ``events``), else from the sampled channel."""
    src = source or f"record {record.id!r}"
    if events and channel in record.events:
        return record.events[channel]
    if channel not in record.channel_names:
        raise RecordError(src, f"channel {channel!r}", "missing: no keyphasor channel or "
                                                       "keyphasor events")
    v = record.values(channel)
    if not np.ptp(v) > 0:
        raise RecordError(src, f"channel {channel!r}", "flat keyphasor signal: no pulses")
    spec = record.channel(channel)
    try:
        return edges_of(v, record.sample_rate_hz, spec.delay_s, spec.info.get("polarity"))
    except ValueError as exc:
        raise RecordError(src, f"channel {channel!r}", str(exc)) from None


@dataclass(frozen=True)
class ShaftAngle:
    """Shaft angle from the keyphasor: edge times and the angle at any time (a quadratic fit
    through the edges at constant speed, else interpolation between them)."""

    edges_s: np.ndarray
    constant_speed: bool

    @property
    def speed_rpm(self) -> float:
        """Mean speed (rpm) between the first and the last edge."""
        return 60.0 * (self.edges_s.size - 1) / (self.edges_s[-1] - self.edges_s[0])

    def angle(self, t: np.ndarray) -> np.ndarray:
        """Shaft angle (rad) at times ``t``, ``2πk`` at edge ``k``."""
        k = np.arange(self.edges_s.size)
        if self.constant_speed:
            e0, span = self.edges_s[0], self.edges_s[-1] - self.edges_s[0]
            deg = 2 if k.size > 3 else 1
            c = np.polyfit((self.edges_s - e0) / span, k, deg)
            return 2 * np.pi * np.polyval(c, (np.asarray(t) - e0) / span)
        return 2 * np.pi * np.interp(t, self.edges_s, k, left=np.nan, right=np.nan)


def shaft_angle(record: Record, *, constant_speed: bool | None = None,
                source: str | None = None) -> ShaftAngle:
    """The shaft angle of ``record`` (constant speed for ``steady`` and ``soak`` records by
    default)."""
    e = keyphasor_edges(record, source=source)
    if e.size < 3:
        raise RecordError(source or f"record {record.id!r}", "keyphasor",
                          f"only {e.size} pulses: need at least 3 revolutions")
    cs = record.kind in ("steady", "soak") if constant_speed is None else constant_speed
    return ShaftAngle(e, cs)


def fit_orders(y: np.ndarray, angle: np.ndarray, orders: tuple[int, ...] = (1,)
               ) -> tuple[np.ndarray, np.ndarray]:
    """Least-squares ``y ≈ a₀ + Σ Re(X_h e^{i h φ})``, for one signal (``y``, ``angle`` of shape
    (N,)) or many at once ((C, N)); returns ``X`` (..., len(orders)) and the residual RMS (...).

    Solved by the normal equations: over whole revolutions the columns are nearly orthogonal,
    so they are well conditioned."""
    y = np.asarray(y, float)
    ang = np.broadcast_to(angle, y.shape)
    cols = [np.ones_like(y)]
    for h in orders:
        cols += [np.cos(h * ang), -np.sin(h * ang)]
    A = np.stack(cols, axis=-1)                                   # (..., N, k)
    At = np.swapaxes(A, -1, -2)
    coef = np.linalg.solve(At @ A, At @ y[..., None])               # (..., k, 1)
    X = coef[..., 1::2, 0] + 1j * coef[..., 2::2, 0]
    res = y - (A @ coef)[..., 0]
    return X, np.sqrt(np.mean(res**2, axis=-1))


@dataclass(frozen=True)
class Phasors:
    """1x (and higher-order) phasors of a steady record, per channel."""

    record_id: str
    speed_rpm: float
    channels: tuple[str, ...]
    orders: tuple[int, ...]
    X: np.ndarray            # (n_channels, n_orders), complex, channel units
    residual_rms: np.ndarray  # (n_channels,)
    n_revolutions: int

    def get(self, channel: str, order: int = 1) -> complex:
        return complex(self.X[self.channels.index(channel), self.orders.index(order)])


#: revolutions a steady record (or a ramp) must hold: then at least 4 whole revolutions lie
#: between keyphasor pulses whatever the initial shaft angle, one more than the 3
#: :func:`demodulate` needs (a pulse at the record's edge may be lost); a ramp gives one
#: tracking block of :func:`track_1x`'s 4 revolutions
MIN_RECORD_REVOLUTIONS = 5
#: samples per revolution at the top speed: the 1x and 2x orders below the Nyquist frequency
MIN_SAMPLES_PER_REVOLUTION = 4
#: shortest impact record: a frequency resolution 1/T of 20 Hz, the half-power bandwidth
#: 2ζf of a 500 Hz spindle mode with ζ = 2 % (the FRF must resolve its peak)
MIN_IMPACT_DURATION_S = 0.05


def check_record_lengths(duration_s: float, speeds_rpm: tuple[float, ...],
                         sample_rate_hz: float | None,
                         runup: tuple[float, float, float] | None = None,
                         impact_duration_s: float = 1.0, *, ramp_field: str = "runup") -> None:
    """Refuse records too short or sampled too slowly to analyse (``ValueError`` naming
    ``duration_s``, ``runup``, ``impact_duration_s`` or ``sensors.daq.sample_rate_hz``):
    steady records need :data:`MIN_RECORD_REVOLUTIONS` at the lowest speed and
    :data:`MIN_SAMPLES_PER_REVOLUTION` at the top speed (of the steady speeds and the ramp);
    a ramp ``(start_rpm, end_rpm, duration_s)`` needs :data:`MIN_RECORD_REVOLUTIONS` in all;
    an impact record :data:`MIN_IMPACT_DURATION_S`. ``ramp_field`` names the ramp in the
    error (``"runup"``: the triple; another name: its duration). ``sample_rate_hz = None``
    skips the sampling check (the sensors are not known yet).

    >>> check_record_lengths(1e-3, (6000.0,), 10_000.0)
    Traceback (most recent call last):
    ...
    ValueError: duration_s = 0.001 is not allowed: a steady record must hold at least 5 \
revolutions at the lowest speed (6000 rpm), i.e. >= 0.05 s (demodulation needs 3 whole \
revolutions between keyphasor pulses)
    """
    lo = min(speeds_rpm) / 60.0     # rev/s
    hi = max([*speeds_rpm, *([] if runup is None else runup[:2])]) / 60.0
    n = MIN_RECORD_REVOLUTIONS
    if duration_s * lo < n:
        raise ValueError(f"duration_s = {duration_s:g} is not allowed: a steady record must "
                         f"hold at least {n} revolutions at the lowest speed ({60 * lo:g} rpm), "
                         f"i.e. >= {n / lo:.3g} s (demodulation needs 3 whole revolutions "
                         "between keyphasor pulses)")
    if runup is not None and runup[2] * (runup[0] + runup[1]) / 120.0 < n:
        shown = list(runup) if ramp_field == "runup" else f"{runup[2]:g}"
        raise ValueError(f"{ramp_field} = {shown} is not allowed: the ramp from {runup[0]:g} "
                         f"to {runup[1]:g} rpm must hold at least {n} revolutions (duration >= "
                         f"{120.0 * n / (runup[0] + runup[1]):.3g} s)")
    if impact_duration_s < MIN_IMPACT_DURATION_S:
        raise ValueError(f"impact_duration_s = {impact_duration_s:g} is not allowed: at least "
                         f"{MIN_IMPACT_DURATION_S} s (a frequency resolution of 20 Hz, the "
                         "half-power bandwidth of a 500 Hz mode with 2 % damping)")
    if sample_rate_hz is not None and sample_rate_hz < MIN_SAMPLES_PER_REVOLUTION * hi:
        raise ValueError(f"sensors.daq.sample_rate_hz = {sample_rate_hz:g} is not allowed: "
                         f"at least {MIN_SAMPLES_PER_REVOLUTION} samples per revolution at the "
                         f"top speed ({60 * hi:g} rpm), i.e. >= "
                         f"{MIN_SAMPLES_PER_REVOLUTION * hi:.6g} Hz (the 1x and 2x orders "
                         "below the Nyquist frequency)")


def demodulate(record: Record, channels: tuple[str, ...] | None = None, *,
               orders: tuple[int, ...] = (1,), min_revolutions: int = 3) -> Phasors:
    """Synchronous demodulation of a constant-speed record over whole revolutions."""
    ang = shaft_angle(record, constant_speed=True)
    n_rev = ang.edges_s.size - 1
    if n_rev < min_revolutions:
        raise RecordError(f"record {record.id!r}", "duration",
                          f"{n_rev} revolutions: demodulation needs {min_revolutions}")
    if channels is None:
        channels = tuple(c.name for c in record.channels if c.quantity == "displacement")
    delays = np.array([record.channel(n).delay_s for n in channels])
    # whole revolutions of the channel with the largest delay; the same sample count for all
    tc = record.time_s[None, :] + delays[:, None]
    use = np.all((tc >= ang.edges_s[0]) & (tc < ang.edges_s[-1]), axis=0)
    Y = np.stack([record.values(n)[use] for n in channels])
    X, res = fit_orders(Y, ang.angle(tc[:, use]), orders)
    return Phasors(record.id, ang.speed_rpm, tuple(channels), tuple(orders), X, res, n_rev)


@dataclass(frozen=True)
class Tracking:
    """1x vs speed from a ramp: one phasor per block of ``revs_per_block`` revolutions."""

    record_id: str
    speed_rpm: np.ndarray          # (B,)
    channels: tuple[str, ...]
    X: np.ndarray                  # (n_channels, B)


def track_1x(record: Record, channels: tuple[str, ...] | None = None, *,
             revs_per_block: int = 4) -> Tracking:
    """Order tracking of a ramp: least-squares DC + 1x over blocks of whole revolutions."""
    ang = shaft_angle(record, constant_speed=False)
    e = ang.edges_s
    if channels is None:
        channels = tuple(c.name for c in record.channels if c.quantity == "displacement")
    starts = e[::revs_per_block]
    if starts.size < 2:
        raise RecordError(f"record {record.id!r}", "duration",
                          f"fewer than {revs_per_block} revolutions to track")
    B = starts.size - 1
    speed = 60.0 * revs_per_block / np.diff(starts)
    X = np.full((len(channels), B), np.nan + 0j)
    t = record.time_s
    for i, name in enumerate(channels):
        tc = t + record.channel(name).delay_s
        y = record.values(name)
        blk = np.searchsorted(starts, tc, side="right") - 1
        ok = (blk >= 0) & (blk < B)
        phi = ang.angle(tc[ok])
        X[i] = _blockwise_fit(y[ok], phi, blk[ok], B)
    return Tracking(record.id, speed, tuple(channels), X)


def _blockwise_fit(y, phi, blk, B):
    """Per block, least squares of ``a + b cos φ + c (−sin φ)`` via 3x3 normal equations."""
    c, s = np.cos(phi), -np.sin(phi)
    cols = [np.ones_like(y), c, s]
    N = np.empty((B, 3, 3))
    r = np.empty((B, 3))
    for i in range(3):
        r[:, i] = np.bincount(blk, cols[i] * y, B)
        for j in range(i, 3):
            N[:, i, j] = N[:, j, i] = np.bincount(blk, cols[i] * cols[j], B)
    sol = np.linalg.solve(N, r[..., None])[..., 0]
    return sol[:, 1] + 1j * sol[:, 2]


@dataclass(frozen=True)
class CriticalSpeed:
    """A 1x resonance seen in a ramp: speed of the amplitude peak, the peak, the phase change
    across it and the half-power amplification factor (API 684: ``N_c / (N₂ − N₁)``)."""

    speed_rpm: float
    amplitude: float
    phase_change_deg: float
    amplification_factor: float


def critical_speeds_from_ramp(tr: Tracking, channel: str, *, min_prominence: float = 0.3,
                              min_phase_change_deg: float = 45.0) -> tuple[CriticalSpeed, ...]:
    """Peaks of the 1x amplitude of ``channel`` with a phase change of at least
    ``min_phase_change_deg`` across the half-power band (a resonance, not a notch).

    The peak speed is refined by a parabola through the three highest blocks. After a fast
    sweep through a lightly damped resonance the free vibration beats with the 1x response;
    lower peaks within three half-power bandwidths (or 2 %) of a higher one are dropped.
    A run-up's peak lies above the critical speed and a run-down's below it, by an amount
    that grows with the sweep rate (``tests/rig/test_demod.py``).
    """
    A = np.abs(tr.X[tr.channels.index(channel)])
    ph = np.unwrap(np.angle(tr.X[tr.channels.index(channel)]))
    sp = tr.speed_rpm
    order = np.argsort(sp)
    A, ph, sp = A[order], ph[order], sp[order]
    peaks, _ = find_peaks(A, prominence=min_prominence * A.max())
    found = []
    for p in peaks[np.argsort(-A[peaks])]:        # highest first
        half = A[p] / np.sqrt(2)
        lo = p
        while lo > 0 and A[lo] > half:
            lo -= 1
        hi = p
        while hi < A.size - 1 and A[hi] > half:
            hi += 1
        dphi = np.degrees(abs(ph[hi] - ph[lo]))
        if dphi < min_phase_change_deg or lo == 0 or hi == A.size - 1:
            continue
        x0 = sp[p]
        if 0 < p < A.size - 1:
            a, b, _ = np.polyfit(sp[p - 1:p + 2] - sp[p], A[p - 1:p + 2], 2)
            if a < 0:
                x0 = sp[p] - b / (2 * a)
        n1 = np.interp(half, A[lo:p + 1], sp[lo:p + 1])
        n2 = np.interp(half, A[p:hi + 1][::-1], sp[p:hi + 1][::-1])
        # a lower peak within a few bandwidths of a higher one is the sweep's beating
        if any(abs(x0 - c.speed_rpm) < max(3 * (n2 - n1), 0.02 * x0) for c in found):
            continue
        found.append(CriticalSpeed(float(x0), float(A[p]), float(dphi),
                                   float(x0 / (n2 - n1)) if n2 > n1 else np.inf))
    out = sorted(found, key=lambda c: c.speed_rpm)
    return tuple(out)
