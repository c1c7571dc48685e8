"""Fit the identified uncertainty model: trend, scatter, normality, variance split.

>>> import numpy as np
>>> rng = np.random.default_rng(0)
>>> n = np.repeat(np.linspace(1000, 24000, 50), 20)
>>> trend = 3.2e8 * (1 - 0.15 * (n / 24000) ** 2)
>>> e = 1 + 0.015 * rng.standard_normal((1000, 2))
>>> k = trend[:, None] * e
>>> u = fit_uncertainty(k, n, ("front_k_yy", "front_k_zz"))
>>> u.names, [round(float(s), 3) for s in np.sqrt(np.diag(u.scatter_cov))]
(('front',), [0.015, 0.015])
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from surrogate_rbrdo.core.validate import check_choice
from surrogate_rbrdo.identification.model import (
    SCATTERS,
    IdentifiedUncertainty,
    study_weights,
)
from surrogate_rbrdo.identification.normality import normality_report
from surrogate_rbrdo.identification.trend import fit_trend


def _psd(C: np.ndarray) -> tuple[np.ndarray, bool]:
    """Nearest positive semi-definite matrix (eigenvalues clipped at 0) and whether it clipped."""
    C = 0.5 * (C + C.T)
    lam, V = np.linalg.eigh(C)
    if lam.min() >= 0:
        return C, False
    return (V * np.maximum(lam, 0.0)) @ V.T, True


def variance_split(factors: np.ndarray, *, per_record_cov: np.ndarray | None = None,
                   truth_factors: np.ndarray | None = None) -> dict:
    """How much of the identified scatter of each factor is identification error.

    Parameters
    ----------
    factors : array (N, d)
        Identified detrended factors ``e``.
    per_record_cov : array (N, d, d), optional
        Each record's identification covariance of ``e`` (relative units): *estimated* split,
        ``identification = mean(per_record_cov)``, ``physical = total − identification``.
    truth_factors : array (N, d), optional
        The true factors of each record (known on the virtual rig): *measured* split,
        ``identification = cov(e − e_true)``, ``physical = cov(e_true)``.

    Returns
    -------
    dict
        ``total_var``, and per available route ``estimated``/``measured`` with
        ``identification_var``, ``physical_var``, ``identification_fraction`` (per factor) and
        the matrices under ``*_cov``.
    """
    e = np.asarray(factors, dtype=float)
    total = np.atleast_2d(np.cov(e, rowvar=False))
    out: dict = {"total_var": np.diag(total).tolist()}
    if per_record_cov is not None:
        C = np.asarray(per_record_cov, dtype=float)
        if C.shape != (e.shape[0], e.shape[1], e.shape[1]):
            raise ValueError(f"per_record_cov has shape {C.shape}: need "
                             f"{(e.shape[0],) + 2 * e.shape[1:]}")
        ident = C.mean(axis=0)
        phys, clipped = _psd(total - ident)
        out["estimated"] = _split(total, ident, phys) | {"physical_clipped": clipped}
    if truth_factors is not None:
        t = np.asarray(truth_factors, dtype=float)
        if t.shape != e.shape:
            raise ValueError(f"truth_factors has shape {t.shape}: need {e.shape}")
        ident = np.atleast_2d(np.cov(e - t, rowvar=False))
        phys = np.atleast_2d(np.cov(t, rowvar=False))
        out["measured"] = _split(total, ident, phys)
    return out


def _split(total, ident, phys) -> dict:
    tv = np.diag(total)
    return {"identification_var": np.diag(ident).tolist(), "physical_var": np.diag(phys).tolist(),
            "identification_fraction": (np.diag(ident) / np.where(tv > 0, tv, 1.0)).tolist(),
            "identification_cov": ident.tolist(), "physical_cov": phys.tolist()}


def output_variance_share(gradient, identification_cov, total_cov) -> float:
    """First-order share of an output's variance due to identification error:
    ``gᵀ Σ_id g / gᵀ Σ_total g`` (the paper's "< 3 % of the output variance", Sect. 2.1.2).

    >>> output_variance_share([1.0, 0.0], np.diag([0.01, 1.0]), np.diag([1.0, 1.0]))
    0.01
    """
    g = np.asarray(gradient, dtype=float)
    return float(g @ np.asarray(identification_cov) @ g / (g @ np.asarray(total_cov) @ g))


def fit_uncertainty(values, speeds_rpm, coefficients: Sequence[str], *, law: str = "auto",
                    study: str = "isotropic", scatter: str = "total",
                    per_record_cov=None, truth=None, speed_ref_rpm: float = 24000.0,
                    provenance: dict | None = None) -> IdentifiedUncertainty:
    """Build the uncertainty model from identified coefficients (see :mod:`.model`).

    Parameters
    ----------
    values : array (N, d)
        Identified coefficients (SI) of good records (drop flagged ones first).
    speeds_rpm : array (N,)
    coefficients : sequence of str
        Names ``<bearing>_<k|c>_<yy|zz>`` of the columns.
    law : str
        Trend law for every coefficient (:func:`fit_trend`; default "auto").
    study : {"isotropic", "stiffness"}
        What θ the study uses (:func:`study_weights`).
    scatter : {"total", "physical"}
        Which factor covariance the study gets: all the identified scatter (default,
        conservative: identification error included) or the physical part (needs
        ``per_record_cov`` or ``truth``; the measured split is preferred when both are given).
    per_record_cov : array (N, d, d), optional
        Identification covariance of each record (SI), e.g. ``PhasorIdentification.covariance``.
    truth : array (N, d), optional
        The true coefficients of each record (virtual rig).
    """
    check_choice("scatter", scatter, SCATTERS)
    X = np.asarray(values, dtype=float)
    sp = np.asarray(speeds_rpm, dtype=float).ravel()
    coefficients = tuple(coefficients)
    if X.ndim != 2 or X.shape != (sp.size, len(coefficients)):
        raise ValueError(f"values has shape {X.shape}: need ({sp.size}, {len(coefficients)}) for "
                         f"{sp.size} speeds and coefficients {list(coefficients)}")
    if not np.all(np.isfinite(X)):
        raise ValueError("values contains a non-finite value: drop flagged records first")
    trends = tuple(fit_trend(sp, X[:, j], law=law, speed_ref_rpm=speed_ref_rpm)
                   for j in range(X.shape[1]))
    tr = np.stack([t.predict(sp) for t in trends], axis=1)
    e = X / tr
    rel_cov = None if per_record_cov is None else \
        np.asarray(per_record_cov, float) / (tr[:, :, None] * tr[:, None, :])
    t_fac = None if truth is None else np.asarray(truth, float) / tr
    split = variance_split(e, per_record_cov=rel_cov, truth_factors=t_fac)
    route = "measured" if "measured" in split else "estimated" if "estimated" in split else None
    phys = ident = None
    if route is not None:
        phys = np.asarray(split[route]["physical_cov"])
        ident = np.asarray(split[route]["identification_cov"])
    if scatter == "physical" and phys is None:
        raise ValueError("scatter = 'physical' is not allowed without per_record_cov or truth")
    names, W = study_weights(coefficients, study)
    report = normality_report(e, coefficients)
    pooled = normality_report(X, coefficients)
    tests = {"detrended": report.to_dict(),
             "study": normality_report(e @ W.T, names).to_dict(),
             "pooled": {"shapiro": pooled.to_dict()["shapiro"], "qq_r2": pooled.to_dict()["qq_r2"],
                        "henze_zirkler": pooled.to_dict()["henze_zirkler"]},
             "trend_law": {c: t.law for c, t in zip(coefficients, trends, strict=True)},
             "split_route": route}
    return IdentifiedUncertainty(
        coefficients=coefficients, trends=trends, scatter_mean=e.mean(axis=0),
        scatter_cov=np.atleast_2d(np.cov(e, rowvar=False)), names=names, weights=W,
        scatter=scatter, physical_cov=phys, identification_cov=ident,
        pooled_mean=X.mean(axis=0), pooled_cov=np.atleast_2d(np.cov(X, rowvar=False)),
        tests=tests, variance_split=split, n_records=int(sp.size), speeds_rpm=np.unique(sp),
        provenance=dict(provenance or {}))


__all__ = ["fit_uncertainty", "output_variance_share", "variance_split"]
