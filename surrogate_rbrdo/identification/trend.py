"""The deterministic speed trend ``k̄(Ω)`` of an identified coefficient, with its uncertainty.

Laws (``s = n / n_ref``, ``n`` in rpm, ``n_ref`` = 24 000 rpm by default):

* ``"constant"``: ``k̄ = β0``;
* ``"quadratic"``: ``k̄ = β0 + β1 s²`` — centrifugal softening of an angular-contact bearing
  grows with the ball's centrifugal force ∝ Ω² (Harris & Kotzalas, *Rolling Bearing Analysis*,
  ch. 3; Jones's high-speed model); the paper's Table 3 is close to it (1.5 % worst residual);
* ``"power"``: ``k̄ = k0 (1 − a s^p)`` — the form the reference spindle's softening effect uses
  (Table 3 fits best with p ≈ 1.25 front, 1.52 rear); it nests the quadratic law at ``p = 2``;
* ``"cubic"``: ``k̄ = β0 + β1 s + β2 s² + β3 s³`` — no physics, the fallback for competing
  effects (softening and thermal preload growth together make a non-monotone trend).

With repeats at every speed (≥ 10) the law is fitted to the speed means by weighted least
squares, each mean weighted by ``n_g / s_g²`` (its repeats' scatter: identification error grows
at low speed, where the unbalance force ∝ Ω² is small), and the residual of the means against
their own scatter is the lack-of-fit F test (Draper & Smith, *Applied Regression Analysis*,
§2.1, in its weighted form); ``law="auto"`` takes the simplest law that passes it. Without
(or fewer) repeats: ordinary least squares on the records, with the classical unweighted
lack-of-fit test when some speeds repeat. ``"power"`` is fitted by
``scipy.optimize.least_squares`` started from the quadratic fit; the parameter covariance is
``(JᵀWJ)⁻¹``, inflated by the reduced χ² when the law does not fit.

>>> import numpy as np
>>> n = np.repeat(np.linspace(1000, 24000, 10), 5)
>>> k = 3.2e8 * (1 - 0.15 * (n / 24000) ** 2)
>>> fit = fit_trend(n, k, law="quadratic")
>>> print(f"{fit.params[0] / 3.2e8:.6f} {-fit.params[1] / fit.params[0]:.6f}")
1.000000 0.150000
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import optimize, stats

from surrogate_rbrdo.core.errors import ModelError
from surrogate_rbrdo.core.validate import check_choice, check_positive

TREND_LAWS = ("constant", "quadratic", "power", "cubic")
_N_PARAMS = {"constant": 1, "quadratic": 2, "power": 3, "cubic": 4}
#: significance level of the lack-of-fit test used by ``law="auto"``
LOF_ALPHA = 0.05
_POWER_BOUNDS = ([0.0, -5.0, 0.5], [np.inf, 0.99, 4.0])


@dataclass(frozen=True)
class LackOfFit:
    """Lack-of-fit F test: ``F = (SS_LOF/df_LOF) / (SS_PE/df_PE)``, p-value ``P(F_df > F)``."""

    F: float
    p_value: float
    df_lof: int
    df_pe: int


@dataclass(frozen=True, eq=False)
class TrendFit:
    """A fitted speed law with its parameter covariance and diagnostics."""

    law: str
    params: np.ndarray
    param_cov: np.ndarray
    speed_ref_rpm: float
    residual_std: float
    n: int
    lack_of_fit: LackOfFit | None

    def predict(self, speed_rpm) -> np.ndarray:
        """``k̄`` at the speeds (rpm)."""
        return _evaluate(self.law, self.params, np.asarray(speed_rpm, float) / self.speed_ref_rpm)

    def predict_std(self, speed_rpm) -> np.ndarray:
        """Standard error of ``k̄`` at the speeds (delta method on the parameter covariance)."""
        s = np.asarray(speed_rpm, dtype=float) / self.speed_ref_rpm
        J = _jacobian(self.law, self.params, np.atleast_1d(s))
        var = np.einsum("ni,ij,nj->n", J, self.param_cov, J)
        return np.sqrt(np.maximum(var, 0.0)).reshape(np.shape(s))

    def to_dict(self) -> dict:
        lof = None if self.lack_of_fit is None else vars(self.lack_of_fit).copy()
        return {"law": self.law, "params": self.params.tolist(),
                "param_cov": self.param_cov.tolist(), "speed_ref_rpm": self.speed_ref_rpm,
                "residual_std": self.residual_std, "n": self.n, "lack_of_fit": lof}

    @classmethod
    def from_dict(cls, d: dict) -> TrendFit:
        check_choice("trend.law", d["law"], TREND_LAWS)
        lof = d.get("lack_of_fit")
        return cls(d["law"], np.asarray(d["params"], float), np.asarray(d["param_cov"], float),
                   float(d["speed_ref_rpm"]), float(d["residual_std"]), int(d["n"]),
                   None if lof is None else LackOfFit(**lof))


def _evaluate(law: str, b: np.ndarray, s: np.ndarray) -> np.ndarray:
    if law == "constant":
        return np.full_like(s, b[0], dtype=float)
    if law == "quadratic":
        return b[0] + b[1] * s**2
    if law == "cubic":
        return b[0] + s * (b[1] + s * (b[2] + s * b[3]))
    return b[0] * (1.0 - b[1] * s ** b[2])


def _jacobian(law: str, b: np.ndarray, s: np.ndarray) -> np.ndarray:
    if law == "constant":
        return np.ones((s.size, 1))
    if law == "quadratic":
        return np.column_stack([np.ones_like(s), s**2])
    if law == "cubic":
        return np.column_stack([np.ones_like(s), s, s**2, s**3])
    sp = s ** b[2]
    with np.errstate(divide="ignore", invalid="ignore"):
        dlog = np.where(s > 0, sp * np.log(np.where(s > 0, s, 1.0)), 0.0)
    return np.column_stack([1.0 - b[1] * sp, -b[0] * sp, -b[0] * b[1] * dlog])


#: repeats per speed needed to weight the speed means by their own scatter
MIN_REPEATS_WEIGHTED = 10


def _groups(speeds: np.ndarray, y: np.ndarray):
    """Speed groups: unique speeds, counts, means and (unbiased) variances, or ``None`` when a
    speed has fewer than ``MIN_REPEATS_WEIGHTED`` repeats (its variance would be too rough a
    weight) or no scatter; records are then fitted one by one."""
    u, inv, cnt = np.unique(speeds, return_inverse=True, return_counts=True)
    if cnt.min() < MIN_REPEATS_WEIGHTED:
        return None
    mean = np.bincount(inv, y) / cnt
    var = np.bincount(inv, (y - mean[inv]) ** 2) / (cnt - 1)
    if np.any(var <= 0):
        return None
    return u, cnt, mean, var


def _solve(law: str, s: np.ndarray, y: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Weighted least squares ``min Σ w (y − f(s))²`` of one law."""
    sw = np.sqrt(w)
    if law in ("constant", "quadratic", "cubic"):
        J = _jacobian(law, np.zeros(4), s)
        return np.linalg.lstsq(J * sw[:, None], y * sw, rcond=None)[0]
    q = _solve("quadratic", s, y, w)
    b0 = np.array([q[0], np.clip(-q[1] / q[0], -4.9, 0.98), 2.0])
    sol = optimize.least_squares(lambda b: sw * (_evaluate(law, b, s) - y), b0,
                                 jac=lambda b: sw[:, None] * _jacobian(law, b, s),
                                 bounds=_POWER_BOUNDS, x_scale=np.abs(b0) + [0.0, 1e-3, 0.0],
                                 method="trf")
    return sol.x


def _inv_normal(J: np.ndarray, w: np.ndarray) -> np.ndarray:
    """``(Jᵀ W J)⁻¹`` with the columns scaled to unit norm first: the columns of a trend law
    differ by ~10⁸ (N/m per unit of ``a`` vs per N/m of ``k0``), and an unscaled ``pinv``
    would cut the weakest direction as if it were round-off."""
    d = np.sqrt(np.einsum("n,ni,ni->i", w, J, J))
    d = np.where(d > 0, d, 1.0)
    Js = J / d
    return np.linalg.pinv(Js.T @ (w[:, None] * Js)) / np.outer(d, d)


def _classical_lof(speeds: np.ndarray, resid: np.ndarray, n_params: int) -> LackOfFit | None:
    """Unweighted lack-of-fit F test from the pure error among repeats (if any)."""
    u, inv = np.unique(speeds, return_inverse=True)
    df_pe, df_lof = speeds.size - u.size, u.size - n_params
    if df_pe < 1 or df_lof < 1:
        return None
    means = np.bincount(inv, resid) / np.bincount(inv)
    ss_pe = float(np.sum((resid - means[inv]) ** 2))
    if ss_pe <= 0:
        return LackOfFit(np.inf, 0.0, df_lof, df_pe)
    F = max(float(resid @ resid) - ss_pe, 0.0) / df_lof / (ss_pe / df_pe)
    return LackOfFit(float(F), float(stats.f.sf(F, df_lof, df_pe)), df_lof, df_pe)


def _fit_one(law: str, speeds: np.ndarray, y: np.ndarray, speed_ref: float) -> TrendFit:
    """With repeats: weighted fit to the speed means (weights ``n_g / s_g²``, so speeds where
    identification is noisy count less), lack-of-fit ``F = χ²/(m − P)`` on ``(m − P, N − m)``
    degrees of freedom and the parameter covariance ``(JᵀWJ)⁻¹ max(1, χ²/(m − P))``. Without:
    ordinary least squares on the records, ``σ̂² (JᵀJ)⁻¹``."""
    P = _N_PARAMS[law]
    g = _groups(speeds, y)
    if g is None:
        s = speeds / speed_ref
        b = _solve(law, s, y, np.ones_like(y))
        resid = y - _evaluate(law, b, s)
        sigma2 = float(resid @ resid) / max(y.size - P, 1)
        J = _jacobian(law, b, s)
        return TrendFit(law, b, sigma2 * _inv_normal(J, np.ones_like(y)), speed_ref,
                        float(np.sqrt(sigma2)), int(y.size), _classical_lof(speeds, resid, P))
    u, cnt, mean, var = g
    s = u / speed_ref
    w = cnt / var
    b = _solve(law, s, mean, w)
    r = mean - _evaluate(law, b, s)
    df_lof, df_pe = u.size - P, int(y.size - u.size)
    J = _jacobian(law, b, s)
    cov = _inv_normal(J, w)
    lof = None
    if df_lof >= 1:
        F = float(np.sum(w * r**2)) / df_lof
        lof = LackOfFit(F, float(stats.f.sf(F, df_lof, df_pe)), df_lof, df_pe)
        cov = cov * max(1.0, F)
    resid = y - _evaluate(law, b, speeds / speed_ref)
    return TrendFit(law, b, cov, speed_ref, float(np.sqrt(np.mean(resid**2))), int(y.size), lof)


def fit_trend(speeds_rpm, values, *, law: str = "auto",
              speed_ref_rpm: float = 24000.0) -> TrendFit:
    """Fit a speed law to identified values of one coefficient.

    Parameters
    ----------
    speeds_rpm, values : array (N,)
        Speed of each record (rpm) and its identified value (SI).
    law : {"auto", "constant", "quadratic", "power", "cubic"}
        ``"auto"``: the first of quadratic, power, cubic that passes the lack-of-fit test at
        5 % (needs repeats), else the one with the smallest residual (its failed test is kept
        in ``lack_of_fit`` for the report).
    speed_ref_rpm : float
        Reference speed of ``s = n / n_ref``.
    """
    check_choice("law", law, ("auto",) + TREND_LAWS)
    check_positive("speed_ref_rpm", speed_ref_rpm)
    sp = np.asarray(speeds_rpm, dtype=float).ravel()
    y = np.asarray(values, dtype=float).ravel()
    if sp.shape != y.shape:
        raise ValueError(f"speeds_rpm {sp.shape} and values {y.shape}: need equal lengths")
    if not (np.all(np.isfinite(sp)) and np.all(np.isfinite(y))):
        raise ValueError("speeds_rpm or values has a non-finite entry: drop flagged records "
                         "first")
    need = {"auto": 3, **{k: v + 1 for k, v in _N_PARAMS.items()}}[law]
    if np.unique(sp).size < need - 1 or sp.size < need:
        raise ValueError(f"{sp.size} records at {np.unique(sp).size} speeds cannot fit law "
                         f"{law!r}: need at least {need - 1} speeds and {need} records")
    if law != "auto":
        return _fit_one(law, sp, y, speed_ref_rpm)
    fits = []
    for cand in ("quadratic", "power", "cubic"):
        if np.unique(sp).size < _N_PARAMS[cand] + 1 and fits:
            break
        fits.append(_fit_one(cand, sp, y, speed_ref_rpm))
        lof = fits[-1].lack_of_fit
        if lof is None or lof.p_value >= LOF_ALPHA:
            return fits[-1]
    best = min(fits, key=lambda f: f.residual_std)
    if not np.all(np.isfinite(best.params)):
        raise ModelError(f"fit_trend: non-finite parameters for law {best.law!r}")
    return best


__all__ = ["LOF_ALPHA", "TREND_LAWS", "LackOfFit", "TrendFit", "fit_trend"]
