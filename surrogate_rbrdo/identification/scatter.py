"""Fit the identified uncertainty model: trend, scatter, normality, variance split.

>>> import numpy as np
>>> rng = np.random.default_rng(0)
>>> n = np.repeat(np.linspace(1000, 24000, 50), 20)
>>> trend = 3.2e8 * (1 - 0.15 * (n / 24000) ** 2)
>>> e = 1 + 0.015 * rng.standard_normal((1000, 2))
>>> u = fit_uncertainty(trend[:, None] * e, n, ("front_k_yy", "front_k_zz"))
>>> u.names, u.scatter, [round(float(s), 3) for s in np.sqrt(np.diag(u.factor_cov_at(1e4)))]
(('front',), 'total', [0.015, 0.015])
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from scipy.linalg import block_diag

from surrogate_rbrdo.core.validate import check_choice
from surrogate_rbrdo.identification.model import (
    SCATTERS,
    IdentifiedUncertainty,
    study_weights,
)
from surrogate_rbrdo.identification.normality import normality_report
from surrogate_rbrdo.identification.physical import physical_scatter
from surrogate_rbrdo.identification.trend import fit_trend, trend_scores


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


#: runs needed for cluster-robust trend intervals and a cluster bootstrap of the scatter
MIN_CLUSTERS = 5


def fits_trend(trends, speeds_rpm) -> np.ndarray:
    """Values ``(N, d)`` of every trend at the speeds."""
    return np.stack([t.predict(speeds_rpm) for t in trends], axis=1)


def _usable_groups(groups, sp) -> tuple[np.ndarray | None, int | None]:
    """The run labels if there are enough runs for cluster-robust intervals, and their count."""
    if groups is None:
        return None, None
    if np.shape(groups) != sp.shape:
        raise ValueError(f"groups has shape {np.shape(groups)}: need {sp.shape}, one per record")
    n = int(np.unique(np.asarray(groups)).size)
    return (np.asarray(groups) if n >= MIN_CLUSTERS else None), n


def _systematic_per_speed(systematic, sources, sp, trends) -> np.ndarray | None:
    """Per speed, the mean change of the records' coefficients for one SD of each systematic
    source, relative to the trend ``(S, n_ξ, d)``: the sources are common to every record, so
    the trend at a speed moves by their mean there."""
    if systematic is None:
        return None
    G = np.asarray(systematic, dtype=float)
    if G.ndim != 3 or G.shape[0] != sp.size or G.shape[2] != len(trends) \
            or len(sources) != G.shape[1]:
        raise ValueError(f"systematic has shape {G.shape}: need ({sp.size}, n, {len(trends)}) "
                         "with n = len(systematic_sources)")
    u, inv = np.unique(sp, return_inverse=True)
    Gm = np.zeros((u.size,) + G.shape[1:])
    np.add.at(Gm, inv, G)
    return Gm / np.bincount(inv)[:, None, None] / fits_trend(trends, u)[:, None, :]


def _joint_trend_cov(trends, sp, X, groups) -> np.ndarray | None:
    """Cluster-robust covariance of all trends' parameters together (their errors are
    correlated: the records of one run share its physical state in every coefficient)."""
    if groups is None:
        return None
    _, cl = np.unique(np.asarray(groups), return_inverse=True)
    parts = [trend_scores(t, sp, X[:, j]) for j, t in enumerate(trends)]
    bread = block_diag(*[b for b, _ in parts])
    scores = np.concatenate([s for _, s in parts], axis=1)
    G = int(cl.max()) + 1
    U = np.zeros((G, scores.shape[1]))
    np.add.at(U, cl, scores)
    cov = bread @ (U.T @ U) @ bread * G / (G - 1)
    return 0.5 * (cov + cov.T)


def run_factors(e: np.ndarray, groups, rel_cov=None) -> np.ndarray:
    """Each run's factors ``(G, d)``: the precision-weighted mean over its records (weights
    ``1/var_id``; equal without ``rel_cov``) — one physical state per run, measured many times."""
    _, g = np.unique(np.asarray(groups), return_inverse=True)
    w = np.ones_like(e) if rel_cov is None else 1.0 / np.maximum(
        np.diagonal(rel_cov, axis1=1, axis2=2), 1e-300)
    G = int(g.max()) + 1
    num, den = np.zeros((G, e.shape[1])), np.zeros((G, e.shape[1]))
    np.add.at(num, g, w * e)
    np.add.at(den, g, w)
    return num / den


def _tests(e, X, W, coefficients, names, rel_cov, phys, groups) -> dict:
    """Normality of the detrended factors (all records; the records whose identification
    variance is below the physical one; and, with runs, each run's precision-weighted factors:
    the records of one run share one physical state, so *they* are the independent sample of
    the physical distribution), of the study's θ, and of the pooled raw values (Table 4)."""
    out = {"detrended": normality_report(e, coefficients).to_dict()}
    if groups is not None:
        runs = run_factors(e, groups, rel_cov)
        out["runs"] = normality_report(runs, coefficients).to_dict()
        out["study_runs"] = normality_report(runs @ W.T, names).to_dict()
    if rel_cov is not None:
        precise = np.all(np.diagonal(rel_cov, axis1=1, axis2=2) < np.diag(phys), axis=1)
        out["precise_records"] = int(precise.sum())
        if precise.sum() >= max(3, e.shape[1] + 2):
            out["detrended_precise"] = normality_report(e[precise], coefficients).to_dict()
            out["study_precise"] = normality_report(e[precise] @ W.T, names).to_dict()
    out["study"] = normality_report(e @ W.T, names).to_dict()
    pooled = normality_report(X, coefficients).to_dict()
    out["pooled"] = {k: pooled[k] for k in ("shapiro", "qq_r2", "henze_zirkler")}
    return out


def fit_uncertainty(values, speeds_rpm, coefficients: Sequence[str], *, law: str = "auto",
                    study: str = "isotropic", scatter: str = "auto", per_record_cov=None,
                    truth=None, groups=None, rng: np.random.Generator | None = None,
                    n_boot: int = 200, speed_ref_rpm: float = 24000.0, reference=None,
                    systematic=None, systematic_sources=(),
                    summary_speed_rpm: float | None = None,
                    provenance: dict | None = None) -> IdentifiedUncertainty:
    """Build the uncertainty model from identified coefficients (see :mod:`.model`).

    Parameters
    ----------
    values : array (N, d)
        Identified coefficients (SI) of the records to use (drop flagged ones first).
    speeds_rpm : array (N,)
    coefficients : sequence of str
        Names ``<bearing>_<k|c>_<yy|zz>`` of the columns.
    law : str
        Trend law for every coefficient (:func:`fit_trend`; default "auto").
    study : {"isotropic", "stiffness"}
        What θ the study uses (:func:`study_weights`).
    scatter : {"auto", "physical", "total"}
        The factor covariance the study gets: physical only, or physical plus the
        identification error at the study's speed; ``"auto"``: physical when
        ``per_record_cov`` is given, else total.
    per_record_cov : array (N, d, d), optional
        Identification covariance of each record (SI), e.g. ``PhasorIdentification.covariance``.
    truth : array (N, d), optional
        The true coefficients of each record (virtual rig): the measured split.
    groups : array (N,), optional
        Run of each record (records sharing a physical state): cluster-robust trend
        covariance and cluster bootstrap of the scatter.
    rng : numpy.random.Generator, optional
        For the bootstrap interval of the physical scatter (none without it).
    reference : (speeds_rpm (S,), stiffness (S, m)), optional
        Nominal stiffness of the study's θ variables in the model the records were identified
        against (:func:`model_reference`), stored so that θ can be given as factors on it.
    systematic : array (N, n_ξ, d), optional
        Change of each record's coefficients for one standard deviation of each systematic
        source (:func:`~surrogate_rbrdo.identification.systematic.systematic_sensitivities`),
        named by ``systematic_sources``: averaged per speed, it is part of the trend's
        uncertainty.
    summary_speed_rpm : float, optional
        Speed of the JSON's top-level ``mean``/``cov`` (default the highest speed).
    """
    check_choice("scatter", scatter, ("auto",) + SCATTERS)
    X = np.asarray(values, dtype=float)
    sp = np.asarray(speeds_rpm, dtype=float).ravel()
    coefficients = tuple(coefficients)
    if X.ndim != 2 or X.shape != (sp.size, len(coefficients)):
        raise ValueError(f"values has shape {X.shape}: need ({sp.size}, {len(coefficients)}) for "
                         f"{sp.size} speeds and coefficients {list(coefficients)}")
    if not np.all(np.isfinite(X)):
        raise ValueError("values contains a non-finite value: drop flagged records first")
    groups, n_groups = _usable_groups(groups, sp)
    trends = tuple(fit_trend(sp, X[:, j], law=law, speed_ref_rpm=speed_ref_rpm, clusters=groups)
                   for j in range(X.shape[1]))
    tr = fits_trend(trends, sp)
    e = X / tr
    rel_cov = None if per_record_cov is None else \
        np.asarray(per_record_cov, float) / (tr[:, :, None] * tr[:, None, :])
    fit = physical_scatter(e, sp, ident_cov=rel_cov, groups=groups, rng=rng, n_boot=n_boot,
                           speed_ref_rpm=speed_ref_rpm)
    if scatter == "auto":
        scatter = "physical" if fit.separable else "total"
    t_fac = None if truth is None else np.asarray(truth, float) / tr
    names, W = study_weights(coefficients, study)
    sys_rel = _systematic_per_speed(systematic, systematic_sources, sp, trends)
    ref_sp, ref = (None, None) if reference is None else (
        np.asarray(reference[0], float), np.asarray(reference[1], float).reshape(-1, len(names)))
    return IdentifiedUncertainty(
        coefficients=coefficients, trends=trends, factor_mean=e.mean(axis=0), scatter_fit=fit,
        names=names, weights=W, scatter=scatter,
        trend_cov=_joint_trend_cov(trends, sp, X, groups),
        total_cov=np.atleast_2d(np.cov(e, rowvar=False)),
        pooled_mean=X.mean(axis=0), pooled_cov=np.atleast_2d(np.cov(X, rowvar=False)),
        reference_speeds_rpm=ref_sp, reference=ref,
        systematic_speeds_rpm=None if sys_rel is None else np.unique(sp), systematic=sys_rel,
        systematic_sources=tuple(systematic_sources), summary_speed_rpm=summary_speed_rpm,
        tests=_tests(e, X, W, coefficients, names, rel_cov, fit.physical, groups)
        | {"trend_law": {c: t.law for c, t in zip(coefficients, trends, strict=True)},
           "speed_homogeneity_p": dict(zip(coefficients, fit.homogeneity_p.tolist(),
                                           strict=True))},
        variance_split=variance_split(e, per_record_cov=rel_cov, truth_factors=t_fac),
        n_records=int(sp.size), speeds_rpm=np.unique(sp),
        provenance={**(provenance or {}), "runs": n_groups,
                    "trend_covariance": trends[0].covariance})


__all__ = ["MIN_CLUSTERS", "fit_uncertainty", "output_variance_share", "run_factors",
           "variance_split"]
