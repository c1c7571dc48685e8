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

With repeats the law is fitted to the speed means by weighted least squares, each mean weighted
by ``n_g / v_g``: identification error grows at low speed, where the unbalance force ∝ Ω² is
small, by orders of magnitude. ``v_g`` is the speed's sample variance when it has at least
``MIN_REPEATS_WEIGHTED`` repeats, else a smooth model of the variance in ``log n`` fitted to the
speeds that have repeats (quadratic in ``log n``: identification variance ∝ Ω⁻⁴ where the
unbalance force is small, constant where physical scatter dominates). The residual of the means
against their own scatter is the lack-of-fit test (Draper & Smith, *Applied Regression
Analysis*, §2.1, in its weighted form); because sample-variance weights are themselves random,
each term ``n_g r_g² / v̂_g`` is ``(1 − h_g) F(1, ν_g)`` rather than ``χ²₁`` under the law, and
the sum is referred to a Satterthwaite ``a χ²_f`` matched to its mean and variance (a plain
``F(m − P, N − m)`` over-rejects: 16 % at a nominal 5 % with 20 repeats).
``law="auto"`` takes the simplest law that passes it. Without repeats: ordinary least squares on
the records. ``"power"`` is fitted by ``scipy.optimize.least_squares`` started from the quadratic
fit.

Parameter covariance: ``(JᵀWJ)⁻¹``, inflated by the lack-of-fit ratio when the law does not fit;
or, with ``clusters`` (records that share a physical state, e.g. the runs of a campaign: one
thermal state per repeat of the speed sweep), the law's shape is fitted and tested on the
values with each run's common factor divided out (weights = the identification variance
alone), and its covariance is the cluster-robust sandwich on the original values (Liang &
Zeger 1986; Cameron & Miller 2015, *J. Human Resources* 50:317) with the small-sample factor
``G/(G−1)`` and ``t_{G−1}`` intervals. Records of one run share their physical deviation at
every speed, so the speed means are *not* independent: the model-based covariance then
understates the level's uncertainty by about ``√(number of speeds)``.

>>> import numpy as np
>>> n = np.repeat(np.linspace(1000, 24000, 10), 5)
>>> k = 3.2e8 * (1 - 0.15 * (n / 24000) ** 2)
>>> fit = fit_trend(n, k, law="quadratic")
>>> print(f"{fit.params[0] / 3.2e8:.6f} {-fit.params[1] / fit.params[0]:.6f}")
1.000000 0.150000
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from scipy import optimize, special, stats

from surrogate_rbrdo.core.errors import ModelError
from surrogate_rbrdo.core.validate import check_choice, check_positive
from surrogate_rbrdo.identification.jsonio import arrayed, listed

TREND_LAWS = ("constant", "quadratic", "power", "cubic")
_N_PARAMS = {"constant": 1, "quadratic": 2, "power": 3, "cubic": 4}
#: significance level of the lack-of-fit test used by ``law="auto"``
LOF_ALPHA = 0.05
_POWER_BOUNDS = ([0.0, -5.0, 0.5], [np.inf, 0.99, 4.0])


@dataclass(frozen=True)
class LackOfFit:
    """Lack-of-fit test of the weighted speed means: ``F = Σ w r² / df_lof`` and its p-value
    (Satterthwaite reference, module docstring); ``df_pe`` is the pure-error degrees of freedom
    (repeats) behind the weights."""

    F: float
    p_value: float
    df_lof: int
    df_pe: int


@dataclass(frozen=True, eq=False)
class TrendFit:
    """A fitted speed law with its parameter covariance and diagnostics.

    ``covariance`` is ``"model"`` (``(JᵀWJ)⁻¹``, inflated on lack of fit), ``"cluster"``
    (cluster-robust sandwich, ``dof = G − 1``) or ``"ols"`` (no repeats). ``group_speeds_rpm``
    and ``group_var`` are the speeds and the variance ``v_g`` of one record there used as
    weights (``None`` without repeats); ``variance_model`` says where ``v_g`` came from
    (``"sample"``, ``"smoothed"`` for speeds with too few repeats, or ``"none"``).
    """

    law: str
    params: np.ndarray
    param_cov: np.ndarray
    speed_ref_rpm: float
    residual_std: float
    n: int
    lack_of_fit: LackOfFit | None
    covariance: str = "model"
    dof: float = np.inf
    group_speeds_rpm: np.ndarray | None = None
    group_var: np.ndarray | None = None
    variance_model: str = "none"

    def predict(self, speed_rpm) -> np.ndarray:
        """``k̄`` at the speeds (rpm)."""
        return _evaluate(self.law, self.params, np.asarray(speed_rpm, float) / self.speed_ref_rpm)

    def jacobian(self, speed_rpm) -> np.ndarray:
        """``∂k̄/∂params`` at the speeds, ``(S, P)``."""
        s = np.atleast_1d(np.asarray(speed_rpm, dtype=float)) / self.speed_ref_rpm
        return _jacobian(self.law, self.params, s)

    def predict_std(self, speed_rpm) -> np.ndarray:
        """Standard error of ``k̄`` at the speeds (delta method on the parameter covariance)."""
        J = self.jacobian(speed_rpm)
        var = np.einsum("ni,ij,nj->n", J, self.param_cov, J)
        return np.sqrt(np.maximum(var, 0.0)).reshape(np.shape(speed_rpm))

    def interval(self, speed_rpm, level: float = 0.95) -> tuple[np.ndarray, np.ndarray]:
        """Two-sided confidence interval of ``k̄`` (``t_dof`` quantile; normal if ``dof`` = ∞)."""
        q = stats.t.ppf(0.5 + level / 2, self.dof) if np.isfinite(self.dof) \
            else stats.norm.ppf(0.5 + level / 2)
        m, sd = self.predict(speed_rpm), self.predict_std(speed_rpm)
        return m - q * sd, m + q * sd

    def to_dict(self) -> dict:
        lof = None if self.lack_of_fit is None else vars(self.lack_of_fit).copy()
        return {"law": self.law, "params": self.params.tolist(),
                "param_cov": self.param_cov.tolist(), "speed_ref_rpm": self.speed_ref_rpm,
                "residual_std": self.residual_std, "n": self.n, "lack_of_fit": lof,
                "covariance": self.covariance,
                "dof": None if not np.isfinite(self.dof) else self.dof,
                "group_speeds_rpm": listed(self.group_speeds_rpm),
                "group_var": listed(self.group_var), "variance_model": self.variance_model}

    @classmethod
    def from_dict(cls, d: dict) -> TrendFit:
        check_choice("trend.law", d["law"], TREND_LAWS)
        lof = d.get("lack_of_fit")
        return cls(d["law"], np.asarray(d["params"], float), np.asarray(d["param_cov"], float),
                   float(d["speed_ref_rpm"]), float(d["residual_std"]), int(d["n"]),
                   None if lof is None else LackOfFit(**lof), d.get("covariance", "model"),
                   np.inf if d.get("dof") is None else float(d["dof"]),
                   arrayed(d.get("group_speeds_rpm")), arrayed(d.get("group_var")),
                   d.get("variance_model", "none"))


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


#: repeats at a speed from which its sample variance weights its mean (ν = n − 1 ≥ 5: the
#: variance of F(1, ν) behind the lack-of-fit reference is finite); fewer: smoothed variance
MIN_REPEATS_WEIGHTED = 6


@dataclass(frozen=True, eq=False)
class _Groups:
    """Records grouped by speed with the variance model of one record at each speed."""

    sp: np.ndarray
    y: np.ndarray
    ref: float
    u: np.ndarray
    inv: np.ndarray
    cnt: np.ndarray
    mean: np.ndarray
    v: np.ndarray | None
    nu: np.ndarray | None
    kind: str
    raw: np.ndarray | None = None

    @classmethod
    def of(cls, sp: np.ndarray, y: np.ndarray, ref: float) -> _Groups:
        u, inv, cnt = np.unique(sp, return_inverse=True, return_counts=True)
        mean = np.bincount(inv, y) / cnt
        ss = np.bincount(inv, (y - mean[inv]) ** 2)
        with np.errstate(invalid="ignore", divide="ignore"):
            var = np.where(cnt > 1, ss / np.maximum(cnt - 1, 1), np.nan)
        has = (cnt > 1) & (var > 0)
        if not has.any():
            return cls(sp, y, ref, u, inv, cnt, mean, None, None, "none")
        good = has & (cnt >= MIN_REPEATS_WEIGHTED)
        if good.all():
            return cls(sp, y, ref, u, inv, cnt, mean, var, cnt - 1.0, "sample")
        smooth, nu_s = _smoothed_variance(u[has], var[has], cnt[has] - 1.0, u)
        return cls(sp, y, ref, u, inv, cnt, mean, np.where(good, var, smooth),
                   np.where(good, cnt - 1.0, nu_s), "smoothed")


def _run_factors(sp: np.ndarray, y: np.ndarray, cl: np.ndarray) -> np.ndarray:
    """Each record's run factor ``a_r`` (mean over the run's records of ``y / ȳ(speed)``,
    normalised to mean 1): records of one run share a physical deviation at every speed.
    Dividing it out leaves, within each speed, the identification error only — the variance
    the speed *means* carry once the common level is a parameter of the law — so the
    lack-of-fit test can see a wrong shape (with the run scatter in the weights it could not:
    a quadratic passed for the rear's p = 1.52 law in 30 of 30 campaigns)."""
    u, inv = np.unique(sp, return_inverse=True)
    ratio = y / (np.bincount(inv, y) / np.bincount(inv))[inv]
    G = int(cl.max()) + 1
    a = np.bincount(cl, ratio, G) / np.bincount(cl, minlength=G)
    return (a / a.mean())[cl]


def _smoothed_variance(u, var, nu, at) -> tuple[np.ndarray, np.ndarray]:
    """``exp`` of a weighted polynomial (degree ≤ 3) in ``log n`` fitted to ``log v̂`` (bias of
    ``log χ²_ν/ν`` removed, weights ``1/ψ'(ν/2)``, its variance), and the equivalent degrees of
    freedom ``2 / var(log v_smooth)`` of the smoothed value at each speed ``at``."""
    z = np.log(var) - (special.digamma(nu / 2) - np.log(nu / 2))
    w = 1.0 / special.polygamma(1, nu / 2)
    deg = int(min(3, u.size - 1))
    L0 = np.log(u).mean()
    X = np.vander(np.log(u) - L0, deg + 1, increasing=True)
    A = np.linalg.inv(X.T @ (w[:, None] * X))
    c = A @ (X.T @ (w * z))
    Xa = np.vander(np.log(at) - L0, deg + 1, increasing=True)
    var_log = np.einsum("gi,ij,gj->g", Xa, A, Xa)
    return np.exp(Xa @ c), np.maximum(2.0 / var_log, 4.5)


def _lack_of_fit(J, w, r, nu, P: int, df_pe: int) -> tuple[LackOfFit, float]:
    """Satterthwaite lack-of-fit test of weighted means (module docstring) and the ratio of
    the statistic to its null mean (the covariance inflation on lack of fit)."""
    S = float(np.sum(w * r**2))
    h = w * np.einsum("gi,ij,gj->g", J, _inv_normal(J, w), J)
    with np.errstate(divide="ignore", invalid="ignore"):
        c = np.where(np.isfinite(nu), nu / (nu - 2), 1.0)
        var = np.where(np.isfinite(nu), 2 * nu**2 * (nu - 1) / ((nu - 2) ** 2 * (nu - 4)), 2.0)
    m0 = float(np.sum((1 - h) * c))
    v0 = float(np.sum((1 - h) ** 2 * var))
    a, f = v0 / (2 * m0), 2 * m0**2 / v0
    df_lof = int(r.size - P)
    return LackOfFit(S / df_lof, float(stats.chi2.sf(S / a, f)), df_lof, int(df_pe)), S / m0


def _fit_one(law: str, g: _Groups, cl: np.ndarray | None) -> TrendFit:
    """One law: weighted fit to the speed means (ordinary least squares on the records without
    repeats), its lack of fit and its parameter covariance (model-based or cluster-robust)."""
    P = _N_PARAMS[law]
    if g.v is None:
        s = g.sp / g.ref
        b = _solve(law, s, g.y, np.ones_like(g.y))
        resid = g.y - _evaluate(law, b, s)
        sigma2 = float(resid @ resid) / max(g.y.size - P, 1)
        fit = TrendFit(law, b, sigma2 * _inv_normal(_jacobian(law, b, s), np.ones_like(g.y)),
                       g.ref, float(np.sqrt(sigma2)), int(g.y.size), None, "ols")
    else:
        s = g.u / g.ref
        w = g.cnt / g.v
        b = _solve(law, s, g.mean, w)
        J = _jacobian(law, b, s)
        lof, ratio = (None, 1.0) if g.u.size <= P else _lack_of_fit(
            J, w, g.mean - _evaluate(law, b, s), g.nu, P, int(np.sum(g.cnt - 1)))
        resid = g.y - _evaluate(law, b, g.sp / g.ref)
        # E[1/v̂] = ν/(ν−2) /v: the sample-variance weights overstate the means' precision
        w_unbiased = w * np.where(np.isfinite(g.nu), (g.nu - 2) / g.nu, 1.0)
        fit = TrendFit(law, b, _inv_normal(J, w_unbiased) * max(1.0, ratio), g.ref,
                       float(np.sqrt(np.mean(resid**2))), int(g.y.size), lof, "model",
                       group_speeds_rpm=g.u, group_var=g.v, variance_model=g.kind)
    if cl is None:
        return fit
    bread, scores = trend_scores(fit, g.sp, g.raw)
    G = int(cl.max()) + 1
    U = np.zeros((G, P))
    np.add.at(U, cl, scores)
    cov = bread @ (U.T @ U) @ bread * G / (G - 1)
    return replace(fit, param_cov=0.5 * (cov + cov.T), covariance="cluster", dof=float(G - 1))


def trend_scores(fit: TrendFit, speeds_rpm, values) -> tuple[np.ndarray, np.ndarray]:
    """The "bread" ``(Σ_i J_i J_iᵀ / v_i)⁻¹`` and the per-record scores ``J_i (y_i − k̄_i) / v_i``
    of a fit on these records: cluster sums of the scores give the cluster-robust covariance,
    also jointly for several coefficients fitted on the same records."""
    sp = np.asarray(speeds_rpm, dtype=float).ravel()
    y = np.asarray(values, dtype=float).ravel()
    J = fit.jacobian(sp)
    if fit.group_var is None:
        v = np.ones_like(sp)
    else:
        idx = np.searchsorted(fit.group_speeds_rpm, sp)
        idx = np.clip(idx, 0, fit.group_speeds_rpm.size - 1)
        if np.any(fit.group_speeds_rpm[idx] != sp):
            raise ValueError("speeds_rpm has speeds the trend was not fitted at")
        v = fit.group_var[idx]
    return _inv_normal(J, 1.0 / v), J * ((y - fit.predict(sp)) / v)[:, None]


def fit_trend(speeds_rpm, values, *, law: str = "auto", speed_ref_rpm: float = 24000.0,
              clusters=None) -> TrendFit:
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
    clusters : array (N,), optional
        Label of the physical state each record belongs to (its run): the parameter covariance
        is then cluster-robust (module docstring). Needs at least 3 clusters.
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
    cl = None if clusters is None else np.unique(np.asarray(clusters).ravel(),
                                                 return_inverse=True)[1]
    if cl is not None and (cl.shape != sp.shape or cl.max() < 2):
        raise ValueError(f"clusters has {np.size(clusters)} labels in {cl.max() + 1} groups: "
                         f"need one label per record ({sp.size}) and at least 3 groups")
    need = {"auto": 3, **{k: v + 1 for k, v in _N_PARAMS.items()}}[law]
    if np.unique(sp).size < need - 1 or sp.size < need:
        raise ValueError(f"{sp.size} records at {np.unique(sp).size} speeds cannot fit law "
                         f"{law!r}: need at least {need - 1} speeds and {need} records")
    data = _Groups.of(sp, y if cl is None else y / _run_factors(sp, y, cl), speed_ref_rpm)
    data = replace(data, raw=y)
    if law != "auto":
        return _fit_one(law, data, cl)
    fits = []
    for cand in ("quadratic", "power", "cubic"):
        if data.u.size < _N_PARAMS[cand] + 1 and fits:
            break
        fits.append(_fit_one(cand, data, cl))
        lof = fits[-1].lack_of_fit
        if lof is None or lof.p_value >= LOF_ALPHA:
            return fits[-1]
    best = min(fits, key=lambda f: f.residual_std)
    if not np.all(np.isfinite(best.params)):
        raise ModelError(f"fit_trend: non-finite parameters for law {best.law!r}")
    return best


__all__ = ["LOF_ALPHA", "MIN_REPEATS_WEIGHTED", "TREND_LAWS", "LackOfFit", "TrendFit",
           "fit_trend", "trend_scores"]
