r"""The single-degree-of-freedom shape of a resonance, used by the resonance structure.

``ρ(r, ζ) = r² / sqrt((1 - r²)² + (2ζr)²) · 2ζ sqrt(1 - ζ²)`` is the single-mode unbalance
response (forcing ∝ Ω²) normalised by its maximum, which lies at ``r_pk = 1 / sqrt(1 - 2ζ²)``;
``ρ_env(r) = max_{r' ≤ r} ρ(r')`` is ``ρ`` below ``r_pk`` and 1 above (the peak over a range
ending at ``r`` is the resonance itself once it is inside). The rest selects between global and
local sub-models and between the resonance branch and the background
(:mod:`~surrogate_rbrdo.surrogates.structured.resonance`).

>>> import numpy as np
>>> round(float(rho(np.array(1.0 / np.sqrt(1 - 2 * 0.01**2)), 0.01)), 12)
1.0
>>> float(rho_env(np.array(1.2), 0.01)), round(float(zeta_from_ratio(rho(0.9, 0.003), 0.9)), 6)
(1.0, 0.003)
"""

from __future__ import annotations

import numpy as np

ZETA_BRACKET = (1e-5, 0.2)


def rho(r: np.ndarray, zeta: np.ndarray) -> np.ndarray:
    """Single-mode unbalance response at frequency ratio ``r``, normalised by its maximum.

    ``ρ(r, ζ) = r² / sqrt((1 - r²)² + (2ζr)²) · 2ζ sqrt(1 - ζ²)``; 1 at ``r = 1/sqrt(1-2ζ²)``.

    >>> round(float(rho(0.5, 0.05)), 6)   # 0.25 / sqrt(0.5625 + 0.0025) * 0.0998749
    0.033218
    """
    r = np.asarray(r, dtype=float)
    z = np.asarray(zeta, dtype=float)
    return r**2 / np.sqrt((1.0 - r**2) ** 2 + (2.0 * z * r) ** 2) * (2.0 * z * np.sqrt(1 - z**2))


def rho_env(r: np.ndarray, zeta: np.ndarray) -> np.ndarray:
    """``max_{r' ≤ r} ρ(r', ζ)``: ``ρ`` below the peak ratio ``1/sqrt(1-2ζ²)``, 1 above."""
    r = np.asarray(r, dtype=float)
    z = np.asarray(zeta, dtype=float)
    r_pk = 1.0 / np.sqrt(1.0 - 2.0 * z**2)
    return np.where(r >= r_pk, 1.0, np.minimum(rho(np.minimum(r, r_pk), z), 1.0))


def zeta_from_ratio(ratio: np.ndarray, r: np.ndarray, *, n_iter: int = 80) -> np.ndarray:
    """Solve ``ρ(r, ζ) = ratio`` for ``ζ`` in ``ZETA_BRACKET`` (bisection in ``log ζ``).

    ``ρ`` increases with ``ζ`` on the bracket for ``r`` off resonance; values outside the
    attainable range are clipped to the bracket ends.

    >>> round(float(zeta_from_ratio(rho(0.95, 0.004), 0.95)), 8)
    0.004
    """
    ratio = np.asarray(ratio, dtype=float)
    r = np.asarray(r, dtype=float)
    lo = np.full(np.broadcast(ratio, r).shape, np.log(ZETA_BRACKET[0]))
    hi = np.full_like(lo, np.log(ZETA_BRACKET[1]))
    for _ in range(n_iter):
        mid = 0.5 * (lo + hi)
        up = rho(r, np.exp(mid)) < ratio
        lo = np.where(up, mid, lo)
        hi = np.where(up, hi, mid)
    return np.exp(0.5 * (lo + hi))


def combine(nc: np.ndarray, ares: np.ndarray, zeta: np.ndarray, bg: np.ndarray | None,
            n_max: float) -> np.ndarray:
    """The combination rule ``ŷ = max(A_res · ρ_env(n_max / n_c, ζ), bg)`` (broadcasting).

    >>> float(combine(np.array(20e3), np.array(30e-6), 0.003, np.array(1e-6), 24e3)) * 1e6
    30.0
    """
    flank = np.asarray(ares) * rho_env(n_max / np.asarray(nc), zeta)
    return flank if bg is None else np.maximum(flank, bg)


def nc_band(nc: np.ndarray, n_max: float, band: float) -> np.ndarray:
    """Where the local n_c model applies: ``|n_max / nc - 1| <= band``."""
    return np.abs(n_max / np.asarray(nc, dtype=float) - 1.0) <= band


def local_band(ln_glob: np.ndarray, center: float, band: float) -> np.ndarray:
    """Where a local model of ``log glob`` applies: ``|log glob - center| <= band``."""
    return np.abs(np.asarray(ln_glob, dtype=float) - center) <= band


def bg_only(nc: np.ndarray, n_max: float, bg_only_r: float) -> np.ndarray:
    """Where the background alone is used: ``n_max / nc <= bg_only_r``."""
    return n_max / np.asarray(nc, dtype=float) <= bg_only_r


def select_nc(nc: np.ndarray, nc_local: np.ndarray | None, n_max: float,
              band: float) -> np.ndarray:
    """``nc_local`` where ``|n_max / nc - 1| <= band`` (the global model's band), else ``nc``.

    >>> select_nc(np.array([20e3, 24.5e3]), np.array([1.0, 2.0]), 24e3, 0.05).tolist()
    [20000.0, 2.0]
    """
    nc = np.asarray(nc, dtype=float)
    if nc_local is None or band <= 0:
        return nc
    return np.where(nc_band(nc, n_max, band), nc_local, nc)


def select_local(glob: np.ndarray, local: np.ndarray | None, center: float,
                 band: float) -> np.ndarray:
    """``local`` where ``|log glob - center| <= band``, else ``glob``.

    >>> select_local(np.array([1.0, 2.0]), np.array([5.0, 6.0]), np.log(2.0), 0.1).tolist()
    [1.0, 6.0]
    """
    glob = np.asarray(glob, dtype=float)
    if local is None or band <= 0:
        return glob
    return np.where(local_band(np.log(glob), center, band), local, glob)


def combine_bg_only(y: np.ndarray, nc: np.ndarray, bg: np.ndarray | None, n_max: float,
                    bg_only_r: float) -> np.ndarray:
    """``bg`` where ``n_max / nc <= bg_only_r`` (background alone), else ``y``.

    >>> combine_bg_only(np.array([5.0, 5.0]), np.array([30e3, 24e3]), np.array([1.0, 1.0]),
    ...                 24e3, 0.95).tolist()
    [1.0, 5.0]
    """
    if bg is None or bg_only_r <= 0:
        return y
    return np.where(bg_only(nc, n_max, bg_only_r), bg, y)


__all__ = ["ZETA_BRACKET", "bg_only", "combine", "combine_bg_only", "local_band", "nc_band",
           "rho", "rho_env", "select_local", "select_nc", "zeta_from_ratio"]
