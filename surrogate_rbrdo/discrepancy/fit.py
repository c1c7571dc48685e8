"""Nonlinear weighted least squares of the outer parameters (bounded trust region), with a
batched finite-difference Jacobian; the unbalance is projected out inside
(:mod:`~surrogate_rbrdo.discrepancy.problem`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares
from scipy.stats import norm

from surrogate_rbrdo.discrepancy.nuisance import Parametrisation
from surrogate_rbrdo.discrepancy.problem import Evaluation, Problem

#: relative finite-difference step (of a parameter's typical magnitude)
FD_STEP = 1e-5
#: the trust-region solver stops when a step lowers χ² by less than ``CHI2_TOL`` (χ² units,
#: as a fraction of the start's χ²; at most :data:`FTOL_MAX`, at least 1e-10): far below every
#: margin a decision takes from two χ² (``confound_delta`` 6.63, the likelihood ratio's
#: thresholds ≈ 10–20). The 1e-10 of the start's χ² used before spent about 40 % of a strong
#: scenario's CPU on the last digits of χ²; a relative 1e-5 alone left a base fit of a large χ²
#: (1e6–1e7: an effect outside the library) short by tens, which every candidate fitted on it
#: then collected as Δχ² (review s13 M1)
CHI2_TOL = 0.02
FTOL_MAX = 1e-5
#: a parameter this fraction of its range (or of its scale, beside an infinite bound) from a
#: bound its χ² slope points to is put on the bound after the solver stops (:func:`fit`)
SNAP = 1e-3


@dataclass(frozen=True)
class Fit:
    """A fitted parametrisation.

    Attributes
    ----------
    par : Parametrisation
    x : ndarray
        Outer parameters (fitting units).
    chi2 : float
        Sum of squared whitened residuals at ``x``.
    jac : ndarray (n_obs, n_x)
        Jacobian of the whitened (variable-projection) residuals at ``x``.
    evaluation : Evaluation
        Residuals, predictions and unbalance at ``x`` (batch of one).
    n_obs : int
    n_params : int
        Outer plus inner (unbalance) parameters.
    nfev : int
        Rows evaluated.
    """

    par: Parametrisation
    x: np.ndarray
    chi2: float
    jac: np.ndarray
    evaluation: Evaluation
    n_obs: int
    n_params: int
    nfev: int

    @property
    def names(self) -> tuple[str, ...]:
        return self.par.names

    @property
    def dof(self) -> int:
        return self.n_obs - self.n_params

    def covariance(self, fixed: np.ndarray | None = None, *, bounded: bool = False
                   ) -> np.ndarray:
        """Gauss–Newton covariance ``(JᵀJ)⁻¹`` of ``x`` (pseudo-inverse if singular; a
        parameter the residuals do not depend on gets an infinite variance); with
        ``fixed`` (boolean mask) those parameters are held at their values (zero rows).

        With ``bounded`` no direction of the parameters is less known than one parameter's physical
        range allows (a regulariser: Popoviciu would allow a mixed direction up to ``(Σ|v_i|)²`` in
        range units, up to ``n``). An estimate confined to ``[a, b]`` (the fit's bounds,
        :meth:`Parametrisation.bounds`) of a truth in the same range errs by at most ``b − a``, so
        its error variance is at most ``(b − a)²/4`` (Popoviciu's inequality on variances, 1935).
        In range units ``u = x / s`` with ``s = (b − a)/2`` the covariance's eigenvalues are capped
        at that bound, 1: ``Σ = S V diag(1/max(μ_k, 1)) Vᵀ S`` with ``μ_k, V`` the eigenpairs of
        ``S JᵀJ S``. A direction the data determine better keeps its Gauss–Newton variance exactly;
        a direction the data do not see (``μ = 0``) and one they barely see (``μ`` small) both get
        the bound — ``1/max(μ, 1)`` is continuous, so the covariance of a prediction
        (:func:`~.holdout.predictive_chi2`) has no jump between "unseen" and "barely seen" and no
        infinity. A parameter with an unbounded range is scaled by :meth:`Parametrisation.scales`.

        >>> from types import SimpleNamespace
        >>> par = SimpleNamespace(bounds=lambda: (np.zeros(2), np.array([1.0, 6.0])),
        ...                       scales=lambda: np.ones(2))
        >>> J = np.array([[20.0, 0.0], [0.0, 0.0]])
        >>> f = Fit(par, np.zeros(2), 0.0, J, None, 2, 2, 0)
        >>> f.covariance().diagonal().tolist()                  # seen: 1/400; unseen: inf
        [0.0025, inf]
        >>> f.covariance(bounded=True).diagonal().round(6).tolist()    # unseen: 6²/4
        [0.0025, 9.0]
        """
        keep = np.ones(self.x.size, dtype=bool) if fixed is None else ~np.asarray(fixed)
        cov = np.zeros((self.x.size, self.x.size))
        J = self.jac[:, keep]
        if bounded:
            lo, hi = self.par.bounds()
            s = np.where(np.isfinite(hi - lo), (hi - lo) / 2.0, self.par.scales())
            s = s[keep]
            mu, V = np.linalg.eigh((J * s).T @ (J * s))
            cov[np.ix_(keep, keep)] = (V / np.maximum(mu, 1.0)) @ V.T * np.outer(s, s)
            return cov
        d = np.linalg.norm(J, axis=0)
        blind = d == 0                         # the data do not see it: unbounded variance
        d = np.where(d > 0, d, 1.0)            # columns scaled: parameters differ by 1e20
        Js = J / d
        sub = np.linalg.pinv(Js.T @ Js) / np.outer(d, d)
        sub[blind, blind] = np.inf
        cov[np.ix_(keep, keep)] = sub
        return cov

    def wald_ci(self, level: float = 0.95, fixed: np.ndarray | None = None
                ) -> tuple[np.ndarray, np.ndarray]:
        """Symmetric Wald interval of every outer parameter (conditional on ``fixed``)."""
        se = np.sqrt(np.clip(np.diag(self.covariance(fixed)), 0.0, None))
        z = norm.ppf(0.5 + level / 2)
        return self.x - z * se, self.x + z * se


def _fd_rows(x: np.ndarray, par: Parametrisation, lo: np.ndarray, hi: np.ndarray
             ) -> tuple[np.ndarray, np.ndarray]:
    """Rows ``x + h_j e_j`` (step towards the interior at a bound) and the steps ``h``; for
    ``x`` of shape ``(B, n)`` (a batch of points) rows ``(B, n, n)`` and steps ``(B, n)``."""
    h = FD_STEP * np.maximum(np.abs(x), par.scales())
    h = np.where(x + h > hi, -h, h)
    return x[..., None, :] + h[..., :, None] * np.eye(x.shape[-1]), h


def jacobian(problem: Problem, par: Parametrisation, x: np.ndarray,
             r0: np.ndarray | None = None) -> tuple[np.ndarray, int]:
    """Forward-difference Jacobian of the whitened residuals, one batched evaluation."""
    lo, hi = par.bounds()
    rows, h = _fd_rows(x, par, lo, hi)
    if r0 is None:
        rows = np.vstack([x[None], rows])
    ev = problem.evaluate(par, rows)
    R = ev.residuals
    if r0 is None:
        r0, R = R[0], R[1:]
    return ((R - r0[None]) / h[:, None]).T, rows.shape[0]


def fit(problem: Problem, par: Parametrisation, x0: np.ndarray, *, max_nfev: int = 60,
        start: Fit | None = None) -> Fit:
    """Minimise the whitened χ² over the outer parameters within their bounds.

    Parameters
    ----------
    problem : Problem
    par : Parametrisation
    x0 : ndarray
        Start (clipped into the bounds).
    max_nfev : int
        Most residual evaluations of the trust-region solver.
    start : Fit, optional
        A fit of ``problem`` in ``par`` ending at ``x0`` (a short fit finished): its
        evaluation and Jacobian are used at ``x0`` instead of being computed again (the same
        numbers: the same rows, the same ``r0``).
    """
    lo, hi = par.bounds()
    x0 = np.clip(np.asarray(x0, dtype=float), lo, hi)
    # evaluations by point since the last accepted one, and that point's Jacobian: the solver
    # asks for the Jacobian of its last evaluation, and it ends at its last accepted point.
    # Jacobians are kept as :func:`jacobian` makes them (column-major) and the result's as
    # before (a row-major copy when the solver ended on its last evaluation): the solver's and
    # the covariances' BLAS sums then run in the same order, so the digits are the same.
    evs: dict[bytes, object] = {}
    jacs: dict[bytes, np.ndarray] = {}
    if start is not None and start.par is par and np.array_equal(start.x, x0):
        evs[x0.tobytes()] = start.evaluation
        jacs[x0.tobytes()] = np.asfortranarray(start.jac)
    count = [0]
    last = [b""]

    def evaluate(x: np.ndarray):
        key = x.tobytes()
        if key not in evs:
            evs[key] = problem.evaluate(par, x[None])
            count[0] += 1
        return evs[key]

    def fun(x: np.ndarray) -> np.ndarray:
        last[0] = x.tobytes()
        return evaluate(x).residuals[0]

    def jac(x: np.ndarray) -> np.ndarray:
        key = x.tobytes()
        if key not in jacs:
            J, n = jacobian(problem, par, x, evaluate(x).residuals[0])
            count[0] += n
            ev = evs[key]
            evs.clear()
            jacs.clear()
            evs[key], jacs[key] = ev, J
        return jacs[key].copy(order="F")

    if x0.size:
        ftol = float(np.clip(CHI2_TOL / max(float(evaluate(x0).chi2[0]), 1e-300), 1e-10,
                             FTOL_MAX))
        sol = least_squares(fun, x0, jac=jac, bounds=(lo, hi), method="trf", x_scale="jac",
                            max_nfev=max_nfev, xtol=1e-10, ftol=ftol, gtol=1e-10)
        x = sol.x
    else:
        x = x0
    key = x.tobytes()
    ev = evaluate(x)
    if key in jacs:
        J = jacs[key].copy() if key == last[0] else jacs[key]
    elif x.size:
        J, n = jacobian(problem, par, x, ev.residuals[0])
        count[0] += n
    else:
        J = np.zeros((ev.residuals.shape[1], 0))
    xs = to_bounds(x, J.T @ ev.residuals[0], lo, hi, par.scales()) if x.size else None
    if xs is not None:
        es = evaluate(xs)
        if es.chi2[0] <= ev.chi2[0]:
            Js, n = jacobian(problem, par, xs, es.residuals[0])
            count[0] += n
            # kept only if χ² still falls outwards at the bounds it was put on (KKT there)
            if not falls_inwards(xs, Js.T @ es.residuals[0], lo, hi, xs != x):
                x, ev, J = xs, es, Js
    return Fit(par, x, float(ev.chi2[0]), J, ev, problem.n_obs, x.size + problem.n_inner,
               count[0])


def to_bounds(x: np.ndarray, g: np.ndarray, lo: np.ndarray, hi: np.ndarray,
              scale: np.ndarray) -> np.ndarray | None:
    """``x`` with every parameter within :data:`SNAP` of its range (or of ``scale`` beside an
    infinite bound) from a bound that the χ² slope ``g = Jᵀr`` points to put on that bound;
    ``None`` when there is none.

    The trust-region solver keeps its iterates strictly inside the bounds (each step stops
    short of a bound, Branch, Coleman & Li 1999, *SIAM J. Sci. Comput.* 21:1), so a parameter
    the data push against a bound approaches it geometrically, and the solver stops, at
    :data:`CHI2_TOL`, a little inside it. What is decided from a fit on a bound — a strength on
    its physical end (:func:`~.search.bound_score`), a shape pinned (``search.on_bound``), a
    recalibration stretched (``search.stretched``) — asks for the bound itself; :func:`fit`
    takes the point on the bounds when its χ² is not larger and χ² does not fall inwards from
    any bound it was put on (:func:`falls_inwards`).

    >>> lo, hi, s = np.zeros(3), np.ones(3), np.ones(3)
    >>> to_bounds(np.array([0.9995, 0.0004, 0.5]), np.array([-1.0, 1.0, 1.0]), lo, hi, s)
    array([1. , 0. , 0.5])
    >>> to_bounds(np.array([0.9995, 0.5, 0.5]), np.array([1.0, 1.0, 1.0]), lo, hi, s) is None
    True
    """
    width = np.where(np.isfinite(hi - lo), hi - lo, scale)
    down = (x > lo) & (x - lo <= SNAP * width) & (g > 0)       # χ² falls towards lo
    up = (x < hi) & (hi - x <= SNAP * width) & (g < 0)
    if not (down.any() or up.any()):
        return None
    return np.where(down, lo, np.where(up, hi, x))


def falls_inwards(x: np.ndarray, g: np.ndarray, lo: np.ndarray, hi: np.ndarray,
                  moved: np.ndarray) -> bool:
    """Whether χ² falls inwards (slope ``g = Jᵀr``) from a bound that a ``moved`` component
    of ``x`` sits on: that component was not held there by the data.

    >>> lo, hi = np.zeros(3), np.ones(3)
    >>> on = np.array([True, False, False])           # put on its upper bound: χ² falls inwards
    >>> falls_inwards(np.array([1.0, 0.5, 0.5]), np.array([1.0, 0.0, 0.0]), lo, hi, on)
    True
    >>> falls_inwards(np.array([1.0, 0.5, 0.5]), np.array([-1.0, 0.0, 0.0]), lo, hi, on)
    False
    """
    return bool(np.any(moved & (((x <= lo) & (g < 0)) | ((x >= hi) & (g > 0)))))


def fit_batch(problem: Problem, par: Parametrisation, X: np.ndarray, *, n_iter: int = 6
              ) -> tuple[np.ndarray, np.ndarray]:
    """A few Levenberg–Marquardt steps from every row of ``X`` at once (one batched
    evaluation per step for all the rows' finite-difference Jacobians): the rows improved
    within the bounds and their χ². A multi-start re-solves the nuisance at every start this
    way before the starts are ranked (:mod:`.search`).

    Each step solves ``(JᵀJ + λ diag JᵀJ) δ = −Jᵀr`` per row (columns scaled, Marquardt
    1963, *SIAM J. Appl. Math.* 11:431), keeps it if χ² falls (λ / 3) and otherwise raises
    λ tenfold. A row whose step was refused stays where it was, and so does its Jacobian:
    only the rows that moved are differentiated again.
    """
    lo, hi = par.bounds()
    X = np.clip(np.array(X, dtype=float), lo, hi)
    B, n = X.shape
    r = problem.evaluate(par, X).residuals
    chi = np.sum(r**2, axis=1)
    lam = np.full(B, 1e-3)
    eye = np.eye(n)
    J = np.empty((B, n, r.shape[1]))
    moved = np.ones(B, dtype=bool)
    for _ in range(n_iter):
        if moved.any():
            rows, h = _fd_rows(X[moved], par, lo, hi)
            J[moved] = (problem.evaluate(par, rows.reshape(-1, n)).residuals.reshape(
                -1, n, r.shape[1]) - r[moved][:, None]) / h[..., None]
        A = np.einsum("bio,bjo->bij", J, J)
        g = np.einsum("bio,bo->bi", J, r)
        d = np.sqrt(np.maximum(np.einsum("bii->bi", A), 1e-300))
        M = A / (d[:, :, None] * d[:, None, :]) + lam[:, None, None] * eye[None]
        step = -np.linalg.solve(M + 1e-12 * eye[None], (g / d)[..., None])[..., 0] / d
        Xn = np.clip(X + step, lo, hi)
        rn = problem.evaluate(par, Xn).residuals
        cn = np.sum(rn**2, axis=1)
        moved = cn < chi
        X[moved], r[moved], chi[moved] = Xn[moved], rn[moved], cn[moved]
        lam = np.where(moved, lam / 3, lam * 10)
    return X, chi
