"""FRFs from impact tests (H1 with coherence) and modal identification from FRFs.

* H1 and the coherence are estimated by **sdypy-FRF** (``pyFRF``; averaged cross and auto
  spectra over the hits) — a maintained implementation of the textbook estimators (Bendat &
  Piersol, *Random Data*, 4th ed. 2010, ch. 9): ``H1 = G_fx / G_ff``,
  ``γ² = |G_fx|² / (G_ff G_xx)``. The known sampling delay of each channel is removed from the
  phase (``H ← H e^{−iω(τ_x − τ_f)}``).
* **Windows** (Brandt, *Noise and Vibration Analysis*, 2011, §13.6; Ewins, *Modal Testing*,
  2000, §3.9): a force window (rectangular, to twice the pulse's end) on the hammer channel, and
  an **exponential window** ``e^{−σ_w t}`` on response *and* force so that the tail, where only
  noise is left of a lightly damped response, is suppressed. The windowed signals are the
  response of the same system with every pole moved left by ``σ_w``: ``H_w(iω) = H(iω + σ_w)``,
  so the modal fit subtracts ``σ_w`` from each identified pole (the damping correction).
* Natural frequencies and damping ratios come from **sdypy-EMA** (poly-reference least-squares
  complex frequency, pLSCF, with a stabilisation over model orders, then least-squares
  frequency-domain residues): the maintained open implementation of the method commercial
  modal software uses. The poles nearest to the FRF's peaks (or to given frequencies) are kept.

Accelerometer channels give accelerance (``form="accelerance"``), probes receptance;
:meth:`FRFEstimate.receptance` converts.
"""

from __future__ import annotations

import contextlib
import io
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.signal import find_peaks
from sdypy.FRF import FRF

from surrogate_rbrdo.core.errors import ModelError
from surrogate_rbrdo.rig.records import Record, RecordError

FORMS = {"displacement": "receptance", "velocity": "mobility", "acceleration": "accelerance"}


@dataclass(frozen=True)
class FRFEstimate:
    """``H[j]`` from the force to response channel ``responses[j]`` (SI: m/N, m/s/N or
    m/s²/N by ``form``), with coherence; ``exp_decay_per_s``: ``σ_w`` of the exponential window
    the spectra were taken with (0: none) — ``H`` is the FRF at ``iω + σ_w``."""

    freq_hz: np.ndarray
    H: np.ndarray              # (n_resp, F)
    coherence: np.ndarray      # (n_resp, F)
    responses: tuple[str, ...]
    force: str
    n_averages: int
    form: str = "receptance"
    exp_decay_per_s: float = 0.0

    def receptance(self) -> np.ndarray:
        """``H`` as receptance (m/N): accelerance / (iω)², mobility / iω (the window's shift
        included, ``s = iω + σ_w``)."""
        s = 2j * np.pi * self.freq_hz + self.exp_decay_per_s
        with np.errstate(divide="ignore", invalid="ignore"):
            p = {"receptance": 0, "mobility": 1, "accelerance": 2}[self.form]
            return self.H / s**p if p else self.H


def _impact_channels(rec: Record, responses: Sequence[str] | None) -> tuple[str, ...]:
    if responses is not None:
        return tuple(responses)
    acc = tuple(c.name for c in rec.channels if c.quantity == "acceleration")
    return acc or tuple(c.name for c in rec.channels if c.quantity == "displacement")


def h1_frf(records: Sequence[Record], responses: Sequence[str] | None = None,
           force: str = "hammer", *, force_window: float | None = None,
           exp_window_end: float | None = 0.01) -> FRFEstimate:
    """H1 FRFs and coherence averaged over impact ``records`` (one hit each).

    ``responses``: default the accelerometers, else the displacement probes (one quantity per
    estimate). ``force_window``: fraction of the record kept on the force channel; default up to
    twice the pulse's end (the last sample above 5 % of the peak) over all hits.
    ``exp_window_end``: the exponential window's value at the record's end (``σ_w = −ln(p)/T``;
    ``None``: no exponential window). Offsets are removed with the mean of the samples before
    the hit (the pre-trigger part).
    """
    recs = list(records)
    if not recs:
        raise ValueError("records = [] is not allowed: give at least one impact record")
    first = recs[0]
    responses = _impact_channels(first, responses)
    qty = {first.channel(n).quantity for n in responses}
    if len(qty) != 1 or next(iter(qty)) not in FORMS:
        raise ValueError(f"responses = {list(responses)} is not allowed: channels of one "
                         f"quantity (displacement, velocity or acceleration), got {sorted(qty)}")
    fs = first.sample_rate_hz
    for r in recs:
        if r.sample_rate_hz != fs or r.n_samples != first.n_samples:
            raise RecordError(f"record {r.id!r}", "sample_rate_hz/n_samples",
                              "all impact records of one FRF need the same rate and length")
    T = first.n_samples / fs
    sigma = 0.0 if exp_window_end is None else -np.log(exp_window_end) / T
    w = np.exp(-sigma * np.arange(first.n_samples) / fs)
    raw = np.stack([r.values(force) for r in recs])
    # offsets (a probe's gap, a bias) from the samples before the hit: a whole-record mean
    # would leave a windowed step in the response
    start = np.argmax(np.abs(raw) > 0.05 * np.abs(raw).max(axis=1, keepdims=True), axis=1)
    pre = np.maximum(start - 5, 0)
    exc = (raw - _pretrigger_mean(raw, pre)) * w                         # (n, T)
    if force_window is None:
        above = np.abs(exc) > 0.05 * np.abs(exc).max(axis=1, keepdims=True)
        end = int(np.max(exc.shape[1] - 1 - np.argmax(above[:, ::-1], axis=1)))
        force_window = min(1.0, 2.0 * (end + 1) / exc.shape[1])
    out_H, out_c = [], []
    for name in responses:
        resp = np.stack([r.values(name) for r in recs])
        resp = (resp - _pretrigger_mean(resp, pre)) * w
        est = FRF(int(round(fs)), exc=exc, resp=resp, exc_type="f", resp_type="d",
                  window=(f"force:{force_window}", "none"))
        f = est.get_f_axis()
        dt = first.channel(name).delay_s - first.channel(force).delay_s
        out_H.append(np.reshape(est.get_H1(), -1) * np.exp(-2j * np.pi * f * dt))
        out_c.append(np.reshape(est.get_coherence(), -1))
    return FRFEstimate(f, np.array(out_H), np.array(out_c), tuple(responses), force, len(recs),
                       FORMS[next(iter(qty))], float(sigma))


def _pretrigger_mean(x: np.ndarray, pre: np.ndarray) -> np.ndarray:
    """Mean of each row over its first ``pre`` samples (0 where fewer than 8)."""
    n = np.arange(x.shape[1])[None, :] < pre[:, None]
    cnt = n.sum(axis=1, keepdims=True)
    return np.where(cnt >= 8, (x * n).sum(axis=1, keepdims=True) / np.maximum(cnt, 1), 0.0)


@dataclass(frozen=True)
class ModalFit:
    """Identified natural frequencies (Hz, *undamped*: ``|λ|/2π``) and damping ratios, after
    removing the exponential window's added damping."""

    frequency_hz: np.ndarray
    damping_ratio: np.ndarray

    @property
    def damped_frequency_hz(self) -> np.ndarray:
        """``f √(1 − ζ²)``: where the FRF peaks for light damping."""
        return self.frequency_hz * np.sqrt(1.0 - self.damping_ratio**2)


def pick_peaks(est: FRFEstimate, f_range: tuple[float, float], *, max_modes: int = 6,
               prominence_decades: float = 0.3, min_coherence: float = 0.9) -> np.ndarray:
    """Frequencies of the peaks of the summed receptance magnitude inside ``f_range`` that
    stand out by ``prominence_decades`` (log10) where the coherence of at least one response is
    ``min_coherence`` or more."""
    f = est.freq_hz
    s = np.log10(np.sum(np.abs(est.receptance()), axis=0) + 1e-300)
    band = (f >= f_range[0]) & (f <= f_range[1])
    idx = np.nonzero(band)[0]
    pk, prop = find_peaks(s[idx], prominence=prominence_decades)
    good = np.max(est.coherence[:, idx[pk]], axis=0) >= min_coherence
    pk, prom = pk[good], prop["prominences"][good]
    best = pk[np.argsort(-prom)][:max_modes]
    return np.sort(f[idx][best])


def modal_fit(est: FRFEstimate, f_range: tuple[float, float],
              approx_hz: Sequence[float] | None = None, *, model_order: int = 40,
              tolerance: float = 0.03) -> ModalFit:
    """Natural frequencies and damping ratios by pLSCF (sdypy-EMA) in ``f_range``.

    ``approx_hz``: the modes to keep (nearest stable poles); default the FRF's peaks. A pole
    farther than ``tolerance`` (relative) from its peak is dropped (no physical mode there).
    Numerical failure inside sdypy-EMA raises :class:`ModelError` naming the band and order.
    """
    from sdypy import EMA  # heavy import (~1 s): only modal fits need it

    approx = pick_peaks(est, f_range) if approx_hz is None else np.asarray(approx_hz, float)
    if approx.size == 0:
        raise ValueError(f"modal_fit: no FRF peak with coherence ≥ 0.9 inside f_range = "
                         f"{f_range}; give approx_hz or a wider range")
    try:
        # only the band goes in: the H1 of an accelerance is 0/0 at DC (NaN), outside the band
        band = (est.freq_hz >= f_range[0]) & (est.freq_hz <= f_range[1])
        m = EMA.Model(frf=est.H[:, band], freq=est.freq_hz[band], lower=f_range[0],
                      upper=f_range[1],
                      pol_order_high=model_order, frf_form=est.form)
        with contextlib.redirect_stderr(io.StringIO()):  # its progress bar ignores the flag
            m.get_poles(show_progress=False)
            m.select_closest_poles(list(approx))
    except (np.linalg.LinAlgError, ValueError, IndexError) as exc:
        raise ModelError(f"modal_fit: pLSCF (sdypy-EMA) failed in {f_range} Hz at model "
                         f"order {model_order} ({type(exc).__name__}: {exc}); try a narrower "
                         "band around the peaks, a lower model_order or more averages") from exc
    fn = np.asarray(m.nat_freq, float)
    zeta = np.asarray(m.nat_xi, float)
    # the window's added damping: the measured pole is the true one moved left by σ_w
    sig = zeta * 2 * np.pi * fn - est.exp_decay_per_s
    wd = 2 * np.pi * fn * np.sqrt(np.clip(1 - zeta**2, 0.0, None))
    wn = np.hypot(sig, wd)
    f, z = wn / (2 * np.pi), np.divide(sig, wn, out=np.zeros_like(wn), where=wn > 0)
    # keep a pole only if it lies near the frequency it was picked for, once
    near = (np.abs(f - approx) <= tolerance * approx) & (fn > 0)
    _, first = np.unique(np.round(f, 6), return_index=True)
    keep = near & np.isin(np.arange(f.size), first)
    return ModalFit(f[keep], z[keep])
