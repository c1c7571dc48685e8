"""FRFs from impact tests (H1 with coherence) and modal identification from FRFs.

* H1 and the coherence are estimated by **sdypy-FRF** (``pyFRF``; averaged cross and auto
  spectra over the hits, force window on the hammer channel) — a maintained implementation of
  the textbook estimators (Bendat & Piersol, *Random Data*, ch. 9): ``H1 = G_fx / G_ff``,
  ``γ² = |G_fx|² / (G_ff G_xx)``. The known sampling delay of each channel is removed from the
  phase (``H ← H e^{−iω(τ_x − τ_f)}``).
* Natural frequencies and damping ratios come from **sdypy-EMA** (poly-reference least-squares
  complex frequency, pLSCF, with a stabilisation over model orders, then least-squares
  frequency-domain residues): the maintained open implementation of the method commercial
  modal software uses. The poles nearest to the FRF's peaks (or to given frequencies) are kept.

Both are optional heavy dependencies imported where used.
"""

from __future__ import annotations

import contextlib
import io
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.signal import find_peaks

from surrogate_rbrdo.rig.records import Record, RecordError


@dataclass(frozen=True)
class FRFEstimate:
    """``H[j]`` (m/N) from the force to response channel ``responses[j]``, with coherence."""

    freq_hz: np.ndarray
    H: np.ndarray              # (n_resp, F)
    coherence: np.ndarray      # (n_resp, F)
    responses: tuple[str, ...]
    force: str
    n_averages: int


def h1_frf(records: Sequence[Record], responses: Sequence[str] | None = None,
           force: str = "hammer", *, force_window: float | None = None) -> FRFEstimate:
    """H1 FRFs and coherence averaged over impact ``records`` (one hit each).

    ``force_window``: fraction of the record kept on the force channel (a rectangular force
    window from the start, removing the noise after the pulse); default: up to twice the
    pulse's end (the last sample above 5 % of the peak) over all hits.
    """
    from sdypy.FRF import FRF  # optional heavy dependency (pyFRF + SEP-005 readers)

    recs = list(records)
    if not recs:
        raise ValueError("records = [] is not allowed: give at least one impact record")
    first = recs[0]
    if responses is None:
        responses = tuple(c.name for c in first.channels if c.quantity == "displacement")
    fs = first.sample_rate_hz
    for r in recs:
        if r.sample_rate_hz != fs or r.n_samples != first.n_samples:
            raise RecordError(f"record {r.id!r}", "sample_rate_hz/n_samples",
                              "all impact records of one FRF need the same rate and length")
    exc = np.stack([r.values(force) for r in recs])                   # (n, T)
    if force_window is None:
        above = np.abs(exc) > 0.05 * np.abs(exc).max(axis=1, keepdims=True)
        end = int(np.max(exc.shape[1] - 1 - np.argmax(above[:, ::-1], axis=1)))
        force_window = min(1.0, 2.0 * (end + 1) / exc.shape[1])
    out_H, out_c = [], []
    for name in responses:
        resp = np.stack([r.values(name) - np.mean(r.values(name)) for r in recs])
        est = FRF(int(round(fs)), exc=exc, resp=resp, exc_type="f", resp_type="d",
                  window=(f"force:{force_window}", "none"))
        f = est.get_f_axis()
        dt = first.channel(name).delay_s - first.channel(force).delay_s
        out_H.append(est.get_H1() * np.exp(-2j * np.pi * f * dt))
        out_c.append(est.get_coherence())
    H = np.squeeze(np.array(out_H), axis=tuple(range(1, np.ndim(out_H) - 1)))
    C = np.squeeze(np.array(out_c), axis=tuple(range(1, np.ndim(out_c) - 1)))
    return FRFEstimate(f, H.reshape(len(responses), -1), C.reshape(len(responses), -1),
                       tuple(responses), force, len(recs))


@dataclass(frozen=True)
class ModalFit:
    """Identified natural frequencies (Hz, damped) and damping ratios."""

    frequency_hz: np.ndarray
    damping_ratio: np.ndarray


def pick_peaks(est: FRFEstimate, f_range: tuple[float, float], *, max_modes: int = 6,
               prominence_decades: float = 0.3, min_coherence: float = 0.9) -> np.ndarray:
    """Frequencies of the peaks of the summed FRF magnitude inside ``f_range`` that stand out
    by ``prominence_decades`` (log10) where the mean coherence is at least ``min_coherence``."""
    f = est.freq_hz
    s = np.log10(np.sum(np.abs(est.H), axis=0) + 1e-300)
    band = (f >= f_range[0]) & (f <= f_range[1])
    idx = np.nonzero(band)[0]
    pk, prop = find_peaks(s[idx], prominence=prominence_decades)
    good = np.mean(est.coherence[:, idx[pk]], axis=0) >= min_coherence
    pk, prop = pk[good], {"prominences": prop["prominences"][good]}
    best = pk[np.argsort(-prop["prominences"])][:max_modes]
    return np.sort(f[idx][best])


def modal_fit(est: FRFEstimate, f_range: tuple[float, float],
              approx_hz: Sequence[float] | None = None, *, model_order: int = 40,
              tolerance: float = 0.03) -> ModalFit:
    """Natural frequencies and damping ratios by pLSCF (sdypy-EMA) in ``f_range``.

    ``approx_hz``: the modes to keep (nearest stable poles); default the FRF's peaks. A pole
    farther than ``tolerance`` (relative) from its peak is dropped (no physical mode there).
    """
    from sdypy import EMA  # optional heavy dependency (pLSCF / LSFD)

    approx = pick_peaks(est, f_range) if approx_hz is None else np.asarray(approx_hz, float)
    if approx.size == 0:
        raise ValueError(f"modal_fit: no FRF peak inside f_range = {f_range}")
    m = EMA.Model(frf=est.H, freq=est.freq_hz, lower=f_range[0], upper=f_range[1],
                  pol_order_high=model_order, frf_form="receptance")
    with contextlib.redirect_stderr(io.StringIO()):  # its progress bar ignores the flag
        m.get_poles(show_progress=False)
        m.select_closest_poles(list(approx))
    f = np.asarray(m.nat_freq, float)
    z = np.asarray(m.nat_xi, float)
    # keep a pole only if it lies near the frequency it was picked for, once
    near = np.abs(f - approx) <= tolerance * approx
    _, first = np.unique(np.round(f, 6), return_index=True)
    keep = near & np.isin(np.arange(f.size), first)
    return ModalFit(f[keep], z[keep])
