"""The measured side of impact updating: H1 per hit direction, the hammer's band, the measured
peaks, and the FRF points a fit uses with their random error
(:func:`~surrogate_rbrdo.identification.impact.impact_damping` fits them).

>>> opts = ImpactOptions()
>>> opts.band_hz, opts.force_drop_db, opts.min_coherence, opts.smooth_bins
(None, 6.0, 0.8, 21)
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.ndimage import uniform_filter1d

from surrogate_rbrdo.core.validate import check_choice, check_int, check_positive, check_range
from surrogate_rbrdo.identification.updating import StandstillModel
from surrogate_rbrdo.rig.frf import FRFEstimate, h1_frf
from surrogate_rbrdo.rig.records import Record, RecordError


@dataclass(frozen=True)
class ImpactOptions:
    """Options of :func:`impact_damping`.

    Parameters
    ----------
    band_hz : (lo, hi) or None
        Frequency band of the modes used; ``None`` (default): from 100 Hz to where the
        measured force autospectrum has fallen ``force_drop_db`` below its level at low
        frequency (the band the hammer tip excites; Ewins, *Modal Testing*, 2nd ed. 2000,
        §3.9.4; the rig's hard tip: ~2 kHz at 6 dB).
    force_drop_db : float
        The force spectrum's drop that ends the default band.
    search : float
        Relative half-width around a model mode in which its measured peak is looked for.
    half_width : float
        Relative half-width around each (updated) mode of the FRF points fitted.
    min_coherence : float
        FRF points with a lower coherence are not fitted.
    rel_floor : float
        Floor of the relative random error of H1 (the model's own accuracy).
    fit_tool_mass : bool
        Fit the tool/holder mass factor (the disk ``tool_disk`` of the model's geometry).
    tool_disk : str
    exp_window_end : float or None
        Exponential window of :func:`~surrogate_rbrdo.rig.frf.h1_frf`.
    smooth_bins : int
        H1's noise variance (the fit's weights) and its jackknife variance (the lack-of-fit
        test) are averaged over this many neighbouring bins (the noise spectrum is smooth).
    covariance : {"jackknife", "model"}
        The factors' covariance: delete-one-hit jackknife (default; at least 3 hits per
        direction, else the model-based one) or ``(JᵀJ)⁻¹ max(χ²/ν, 1)`` from H1's coherence.
    lack_of_fit_level : float
        False-alarm probability of the model-error tests on a right model (half to each):
        the threshold of χ²/ν is the ``1 − level/2`` quantile of ``F(ν, 2(n − 1))`` (the
        fit's residual dof ``ν``
        over the dof of a complex variance estimated from ``n`` hits: Bartlett's reference for
        a χ² against an estimated variance, taken as one common estimate — the conservative
        case; :func:`~surrogate_rbrdo.identification.impact.lack_of_fit_threshold`).
    max_lack_of_fit : float or None
        A fixed threshold of χ²/ν instead (``None``, default: from ``lack_of_fit_level``).
    skew_sd_s : float or None
        SD of each channel's unknown timing skew as the acquisition states it (the rig's DAQ:
        0.2 µs, :class:`~surrogate_rbrdo.rig.sensors.DAQModel`; the default is that value: on
        measured data take it from the DAQ's datasheet or set ``None``): the fitted delays are
        tested against it (a delay far beyond it is model error the nuisance absorbed);
        ``None``: not tested. The lack-of-fit and the delay test share ``lack_of_fit_level``
        (half each).
    lack_of_fit_floor : float
        Relative FRF misfit never called a model error (an accelerometer's frequency
        response is known to ~0.1 %): floor of the lack-of-fit variance, ``(floor |H|)²``.
    """

    band_hz: tuple[float, float] | None = None
    force_drop_db: float = 6.0
    search: float = 0.08
    half_width: float = 0.03
    min_coherence: float = 0.8
    rel_floor: float = 1e-4
    fit_tool_mass: bool = True
    tool_disk: str = "tool_holder"
    exp_window_end: float | None = 0.01
    smooth_bins: int = 21
    covariance: str = "jackknife"
    lack_of_fit_level: float = 0.01
    max_lack_of_fit: float | None = None
    skew_sd_s: float | None = 0.2e-6
    lack_of_fit_floor: float = 1e-3

    def __post_init__(self) -> None:
        if self.band_hz is not None:
            lo, hi = (float(v) for v in self.band_hz)
            if not 0.0 < lo < hi:
                raise ValueError(f"band_hz = {self.band_hz} is not allowed: need 0 < lo < hi")
            object.__setattr__(self, "band_hz", (lo, hi))
        check_range("force_drop_db", self.force_drop_db, 0.5, 40.0)
        check_range("search", self.search, 1e-3, 0.5)
        check_range("half_width", self.half_width, 1e-3, 0.5)
        check_range("min_coherence", self.min_coherence, 0.0, 1.0)
        check_positive("rel_floor", self.rel_floor)
        check_int("smooth_bins", self.smooth_bins, minimum=1)
        check_choice("covariance", self.covariance, ("jackknife", "model"))
        check_range("lack_of_fit_level", self.lack_of_fit_level, 1e-9, 0.5)
        if self.max_lack_of_fit is not None:
            check_positive("max_lack_of_fit", self.max_lack_of_fit)
        check_positive("lack_of_fit_floor", self.lack_of_fit_floor)
        if self.skew_sd_s is not None:
            check_positive("skew_sd_s", self.skew_sd_s)
        if self.exp_window_end is not None:
            check_range("exp_window_end", self.exp_window_end, 1e-6, 1.0)


def hit_groups(records: Sequence[Record]) -> tuple[dict[str, list[Record]], int]:
    """The impact records by hit direction (the hammer channel's), and the fewest hits of a
    direction."""
    by_dir: dict[str, list[Record]] = {}
    for r in records:
        by_dir.setdefault(r.channel("hammer").location.direction, []).append(r)
    return by_dir, min(len(v) for v in by_dir.values())


def hit_frfs(records: Sequence[Record], opts: ImpactOptions) -> dict[str, FRFEstimate]:
    """H1 per hit direction, response at the tool in that direction (accelerometer, else a
    displacement probe)."""
    for r in records:
        if r.kind != "impact" or "hammer" not in r.channel_names:
            raise RecordError(f"record {r.id!r}", "kind/channels",
                              "an impact record with a 'hammer' channel is needed")
    by_dir, _ = hit_groups(records)
    out = {}
    for d, recs in sorted(by_dir.items()):
        chans = [c for c in recs[0].channels if c.location.target == "tool"
                 and c.location.direction == d and c.quantity in ("acceleration",
                                                                   "displacement")]
        chans.sort(key=lambda c: c.quantity != "acceleration")
        if not chans:
            raise RecordError(f"record {recs[0].id!r}", "channels",
                              f"no response channel at the tool in direction {d!r}")
        if len(recs) < 2:
            # one hit: H1's coherence is 1 by construction, so neither its random error
            # (the fit's weights) nor the coherence filter can see the noise
            warnings.warn(f"impact damping: one hit in direction {d!r} (record {recs[0].id!r}):"
                          " with a single average the coherence is 1 by construction, so the"
                          " fit is unweighted and its standard errors assume noise-free FRFs;"
                          " average at least 2 hits (rig: impacts_per_direction >= 2)",
                          UserWarning, stacklevel=3)
        out[d] = h1_frf(recs, [chans[0].name], exp_window_end=opts.exp_window_end)
    return out


def force_band_top(records: Sequence[Record], drop_db: float = 6.0) -> float:
    """Frequency (Hz) where the hits' mean force autospectrum has fallen ``drop_db`` below
    its median over 5–50 Hz.

    >>> from surrogate_rbrdo.rig.records import Calibration, ChannelSpec, SensorLocation
    >>> fs, T = 200_000.0, 0.4e-3                  # finely sampled: the continuous pulse
    >>> t = np.arange(200_000) / fs
    >>> f = np.where((t >= 0.05) & (t < 0.05 + T), np.sin(np.pi * (t - 0.05) / T), 0.0)
    >>> ch = ChannelSpec("hammer", "force", "N", SensorLocation("tool", "x", 0.0),
    ...                  Calibration(1.0, 0.0, -1e9, 1e9), 0.0, {})
    >>> rec = Record("h", "impact", fs, (ch,), f[None, :], speed_rpm=0.0)
    >>> round(force_band_top([rec], 6.0), -1)      # a 0.4 ms half-sine: −6 dB at 2.05 kHz
    2050.0
    """
    g = np.mean([np.abs(np.fft.rfft(r.values("hammer") - np.median(r.values("hammer")))) ** 2
                 for r in records], axis=0)
    f = np.fft.rfftfreq(records[0].n_samples, 1.0 / records[0].sample_rate_hz)
    ref = np.median(g[(f >= 5.0) & (f <= 50.0)])
    below = np.nonzero((f > 50.0) & (g < ref * 10 ** (-drop_db / 10)))[0]
    return float(f[below[0]]) if below.size else float(f[-1])


def measured_peaks(est: FRFEstimate, f0, opts) -> np.ndarray:
    """The measured peak (Hz) of one direction's FRF nearest each model mode (NaN where none
    is coherent)."""
    out = np.full(f0.size, np.nan)
    for i, f in enumerate(f0):
        g = ((est.freq_hz >= f * (1 - opts.search)) & (est.freq_hz <= f * (1 + opts.search))
             & (est.coherence[0] >= opts.min_coherence))
        if g.sum() < 3:
            continue
        a = np.abs(est.receptance()[0][g])
        j = int(np.argmax(a))
        if 0 < j < a.size - 1:                   # an interior maximum: a peak
            out[i] = est.freq_hz[g][j]
    return out


@dataclass(frozen=True, eq=False)
class FitPoints:
    """The FRF points of a fit: ``s`` (complex frequency), measured accelerance ``H``, its
    random error ``sd``, the response DOF, the direction index ``gi`` and the FRF bin ``bins``
    of each point; ``modes`` (Hz)."""

    s: np.ndarray
    H: np.ndarray
    sd: np.ndarray
    dof: np.ndarray
    gi: np.ndarray
    bins: np.ndarray
    modes: np.ndarray


def accelerance(est: FRFEstimate) -> np.ndarray:
    """The first response's FRF as accelerance at ``s = iω + σ_w``, every bin."""
    f = est.freq_hz
    return est.H[0] if est.form == "accelerance" else est.receptance()[0] * (
        2j * np.pi * f + est.exp_decay_per_s) ** 2


def fit_data(up: StandstillModel, frfs, theta, m, band, opts, model, bins=None) -> FitPoints:
    """The FRF points fitted: within ``half_width`` of each direction's (aligned) modes where
    the coherence is high enough (or the given ``bins``, one index array per direction: a
    jackknife replicate fits the full fit's points), with H1's random error as SD."""
    lo, hi = band
    data, all_modes = [], []
    for di, d in enumerate(sorted(frfs)):
        est = frfs[d]
        f = est.freq_hz
        if bins is None:            # a replicate's given bins need no modes (no eigensolve)
            modes = up.natural_hz(theta[di], m)
            modes = np.unique(np.round(modes[(modes >= lo) & (modes <= hi)], 3))
            all_modes.append(modes)
            near = np.any(np.abs(f[:, None] / modes[None, :] - 1) <= opts.half_width, axis=1)
            g = np.flatnonzero(near & (est.coherence[0] >= opts.min_coherence) & (f > 0))
        else:
            g = bins[di]
        H_all = accelerance(est)
        sd = frf_sd(H_all, est.coherence[0], est.n_averages, opts)
        dof = 4 * model.tool_node + (1 if d == "y" else 0)
        data.append((2j * np.pi * f[g] + est.exp_decay_per_s, H_all[g], sd[g],
                     np.full(g.size, dof), np.full(g.size, di), g))
    cat = [np.concatenate([x[k] for x in data]) for k in range(6)]
    return FitPoints(*cat, np.unique(np.concatenate(all_modes)) if all_modes else np.empty(0))


def frf_sd(H: np.ndarray, coh: np.ndarray, n_avg: int, opts: ImpactOptions) -> np.ndarray:
    """H1's random error per bin, ``ε |H|`` with ``ε = √(1 − γ²) / (|γ| √(2 n_d))`` (Bendat &
    Piersol 2010, eq. 9.90), floored at ``rel_floor`` of ``|H|``; its square is the noise
    spectrum over the force's, ``G_nn / (2 n_d G_ff)``, smooth in frequency, so it is averaged
    over ``smooth_bins`` neighbouring bins (each bin's coherence from a few hits is a χ² with
    2(n_d − 1) degrees of freedom: weighting by it gave the bins whose noise happened to look
    small far too much weight, and standard errors several times too small)."""
    gam2 = np.clip(np.nan_to_num(coh, nan=0.0), 1e-12, 1.0)
    var = (1 - gam2) / (gam2 * 2 * n_avg) * np.abs(np.nan_to_num(H)) ** 2
    if opts.smooth_bins > 1:
        var = uniform_filter1d(var, opts.smooth_bins, mode="nearest")
    return np.maximum(np.sqrt(var), opts.rel_floor * np.abs(H))


__all__ = ["FitPoints", "ImpactOptions", "accelerance", "fit_data", "force_band_top", "frf_sd",
           "hit_frfs", "measured_peaks"]
