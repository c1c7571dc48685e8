"""FORM: design-point search by the improved HL-RF algorithm (iHL-RF) with an Armijo line search.

The limit state ``G(u) = limit.g(response(x, T(u)))`` is searched in standard-normal space from
``u = 0``. Gradients are finite differences (one batched model call of ``m`` or ``2m`` points per
iteration; every point is counted). ``β = sign(G(0)) ‖u*‖`` so a mean point in the failure domain
gives ``β < 0`` and ``P_f = Φ(−β) > 0.5``. Where iHL-RF (:mod:`._ihlrf`) does not converge, SLSQP
and a ray search take over (``fallback="sqp"``, :mod:`._constrained`). When the search still does
not converge the estimator raises
:class:`~surrogate_rbrdo.core.errors.ModelError` (``on_failure="raise"``) or returns NaN for that
design (``on_failure="nan"``), with ``diagnostics["converged"]`` False: never a silent wrong
answer.

Reference: Y. Zhang, A. Der Kiureghian (1995), Two improved algorithms for reliability analysis,
in *Reliability and Optimization of Structural Systems*, Springer.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from scipy import special

from surrogate_rbrdo.core.errors import ModelError
from surrogate_rbrdo.core.protocols import Estimate, LimitState
from surrogate_rbrdo.core.validate import check_choice, check_int, check_positive
from surrogate_rbrdo.estimators._common import LimitStateU, check_args, make_estimate
from surrogate_rbrdo.estimators._constrained import ray_roots, refine
from surrogate_rbrdo.estimators._ihlrf import (
    FLAT,
    IHLRF_ITER,
    SETTLED_BETA,
    STATUSES,
    DesignPoint,
    _settled,
    fd_gradient,
    ihlrf,
)
from surrogate_rbrdo.estimators._minimum import nearer_point
from surrogate_rbrdo.estimators._periodic import (
    conditional_search,
    dominant_theta,
    periodic_columns,
)
from surrogate_rbrdo.estimators._tail import EstimatorWarning
from surrogate_rbrdo.estimators.registry import ESTIMATORS

#: restarts of the search from a nearer poll point at most (:meth:`FORM._descend`)
MAX_RESTARTS = 3


@ESTIMATORS.register("form")
@dataclass(frozen=True)
class FORM:
    """First-order reliability method (iHL-RF), one design-point search per design.

    Gives ``pf = Φ(−β)``; ``mean``, ``std`` and all standard errors are NaN (use ``"fosm"`` or
    ``"mc"`` for moments). Diagnostics: ``beta``, ``u_star`` and ``theta_star`` ``(P, m)``,
    ``alpha`` (unit vector towards failure), ``importance_factors`` ``α²``, ``converged``,
    ``status`` (``"converged"``, ``"not_reached"``, ``"unconverged"``: the search ended on a
    point of the limit state not shown to be the nearest, ``|β|`` an upper bound of the distance,
    ``"failed"``), ``pf_bound``
    (``"upper"``/``"lower"`` where the limit state was not reached, else ``""``), ``n_iter``,
    ``calls``
    (model calls per design), ``message``.

    **Limit state not reached.** When the search meets the edge of the model's physical
    domain (the model raises ``OutsideDomainError``, e.g. a stiffness factor θ ≤ 0; points
    outside are not failures, :mod:`._common`) or passes ``‖u‖ = beta_max`` with ``G`` still of
    the sign of ``G(0)`` at the last point ``u_b``, the design never fails (never survives) as
    far as the search can see: ``status = "not_reached"``, ``pf = Φ(−|β_b|)`` with
    ``β_b = ‖u_b‖`` (``1 − Φ(−|β_b|)`` when the mean point fails) and
    ``pf_bound = "upper"`` (``"lower"``): ``pf`` is the first-order probability of
    ``{G ≤ G(u_b)}``, a superset of the failure domain. It is not a rigorous bound (FORM only
    explores along its path), so ``pf_ci`` stays NaN, as for every FORM result. Not an error,
    whatever ``on_failure`` says.

    Parameters
    ----------
    max_iter : int
    tol_g : float
        Convergence on ``|G(u)| / |G(0)|``.
    tol_u : float
        Convergence on the distance of ``u`` from the line through ``α``, relative to
        ``max(1, ‖u‖)`` (an angle for ``‖u‖ > 1``).
    fd_step : float
        Finite-difference step in standard space (raise it for noisy models, e.g. FE solves).
    fd_scheme : {"forward", "central"}
    on_failure : {"raise", "nan"}
        Non-convergence raises ``ModelError`` or returns NaN for that design.
    beta_max : float
        Distance beyond which an unreached limit state is reported as a bound
        (``Φ(−10) = 7.6e-24``).
    phase_nodes, phase_max_nodes : int
        Periodic inputs (phases, ``Uniform(..., periodic=True)``) are conditioned on, not
        searched: one search per node of a trapezoidal rule over each phase, ``phase_nodes``
        nodes doubled up to ``phase_max_nodes`` (:mod:`._periodic`).
    phase_rtol : float
        The nodes double until the rule on ``K`` and on ``K/2`` nodes agree within this
        relative tolerance; their difference is ``diagnostics["pf_quadrature_error"]``.
    fallback : {"sqp", "none"}
        Where iHL-RF does not converge (three line-search stalls in a row, or ``max_iter``):
        ``"sqp"`` continues from its last point with SLSQP on ``min ½‖u‖² s.t. G(u) = 0`` and,
        where that point is not settled (a kink of ``G``), a ray search for the shortest
        distance to the limit state (:mod:`._constrained`); ``"none"`` reports the failure.
    check_minimum : bool
        After convergence, poll ``2(m − 1)`` points just inside the sphere ``‖u‖ = β`` around
        ``u*`` (one batched call, :mod:`._minimum`): a stationary point that is not a local
        minimum of the distance (a saddle of a limit state concave towards the origin) is left
        for a nearer point and the search restarts there; where that does not converge,
        ``status = "unconverged"`` (``|β|`` an upper bound) with an ``EstimatorWarning``.

    **Periodic inputs.** With a phase the result is ``P_f = mean_j Φ(−β(φ_j))`` over the
    nodes: ``beta`` is the generalised index ``−Φ⁻¹(P_f)``, ``u_star``/``alpha`` those of the
    node contributing most (NaN in the phase columns; ``theta_star`` holds its phase),
    ``status`` ``"converged"`` if every node converged, ``"not_reached"`` if some never fail
    (they contribute their bound), ``phase_nodes`` the nodes per phase used.

    Examples
    --------
    >>> from surrogate_rbrdo.core import LimitState
    >>> from surrogate_rbrdo.uncertainty import MultivariateNormal
    >>> inputs = MultivariateNormal(np.zeros(2), cov=np.eye(2))
    >>> resp = lambda x, t: (t[:, 0] + t[:, 1])[None, :] / np.sqrt(2.0)   # y = α·u
    >>> est = FORM().estimate(resp, inputs, LimitState(3.0), np.zeros((1, 0)),
    ...                       rng=np.random.default_rng(0))
    >>> round(float(est.diagnostics["beta"][0]), 8), bool(est.diagnostics["converged"][0])
    (3.0, True)

    A response that never reaches the threshold (``y = tanh(u₁) < 2``):

    >>> est = FORM().estimate(lambda x, t: np.tanh(t[:, :1].T), inputs, LimitState(2.0),
    ...                       np.zeros((1, 0)), rng=np.random.default_rng(0))
    >>> d = est.diagnostics
    >>> str(d["status"][0]), str(d["pf_bound"][0]), float(d["beta"][0]), bool(est.pf[0] < 1e-20)
    ('not_reached', 'upper', 10.0, True)
    """

    max_iter: int = 100
    tol_g: float = 1e-8
    tol_u: float = 1e-6
    fd_step: float = 1e-6
    fd_scheme: str = "forward"
    on_failure: str = "raise"
    beta_max: float = 10.0
    phase_nodes: int = 8
    phase_max_nodes: int = 32
    phase_rtol: float = 0.05
    fallback: str = "sqp"
    check_minimum: bool = True

    def __post_init__(self) -> None:
        check_int("max_iter", self.max_iter, minimum=1)
        check_positive("tol_g", self.tol_g)
        check_positive("tol_u", self.tol_u)
        check_positive("fd_step", self.fd_step)
        check_choice("fd_scheme", self.fd_scheme, ("forward", "central"))
        check_choice("on_failure", self.on_failure, ("raise", "nan"))
        check_positive("beta_max", self.beta_max)
        check_int("phase_nodes", self.phase_nodes, minimum=2)
        if check_int("phase_max_nodes", self.phase_max_nodes, minimum=2) < self.phase_nodes:
            raise ValueError(f"phase_max_nodes = {self.phase_max_nodes} is not allowed: must "
                             f"be >= phase_nodes = {self.phase_nodes}")
        check_positive("phase_rtol", self.phase_rtol)
        check_choice("fallback", self.fallback, ("sqp", "none"))
        if not isinstance(self.check_minimum, bool):
            raise ValueError(f"check_minimum = {self.check_minimum!r} is not allowed: must be "
                             "True or False")

    def search(self, response: Any, inputs: Any, limit: LimitState,
               x_row: np.ndarray) -> DesignPoint:
        """Design-point search for one design ``x_row`` (shape ``(d,)``)."""
        G = LimitStateU(response, inputs, limit, np.asarray(x_row, dtype=float))
        return self.run(G, inputs.dim)

    def run(self, G: Any, m: int, *, start: tuple[np.ndarray, float] | None = None,
            max_iter: int | None = None, stop: Callable[[np.ndarray], bool] | None = None
            ) -> DesignPoint:
        """iHL-RF with these options on a limit-state function ``G(u (n, m)) -> (n,)`` that
        counts its calls in ``G.calls`` (``start``, ``stop``: see :func:`ihlrf`), then the
        ``fallback`` where it failed (not for searches with a ``stop`` rule)."""
        n_iter = self.max_iter if max_iter is None else max_iter
        dp = self._search_once(G, m, n_iter, start, stop)
        if self.check_minimum and stop is None and dp.status == "converged":
            dp = self._descend(G, m, dp, n_iter)
        return dp

    def _descend(self, G: Any, m: int, dp: DesignPoint, n_iter: int) -> DesignPoint:
        """The local-minimum check of a converged point (:mod:`._minimum`): where the poll finds
        a point of the far side nearer than ``β``, the search restarts there (at most
        ``MAX_RESTARTS`` times); a restart that does not converge to a nearer point leaves
        ``status = "unconverged"`` at the limit-state point on the ray through the poll point
        (``|β|`` an upper bound of the distance) and an :class:`EstimatorWarning`."""
        sign0 = 1.0 if dp.g_origin >= 0 else -1.0
        for k in range(MAX_RESTARTS + 1):
            p = nearer_point(G, dp.u_star, sign0)
            if p is None:
                note = f" (local minimum checked; {k} restart(s) from a saddle)" if k else ""
                return replace(dp, calls=G.calls, message=dp.message + note)
            if k == MAX_RESTARTS:
                break
            new = self._search_once(G, m, n_iter, start=(p, dp.g_origin))
            if new.status != "converged" or abs(new.beta) >= abs(dp.beta):
                break
            dp = new
        return self._not_minimum(G, m, dp, p, sign0)

    def _search_once(self, G: Any, m: int, n_iter: int,
                     start: tuple[np.ndarray, float] | None = None,
                     stop: Callable[[np.ndarray], bool] | None = None) -> DesignPoint:
        """One iHL-RF search, then the ``fallback`` where it failed (not with a ``stop``)."""
        fall = self.fallback == "sqp" and stop is None
        dp = ihlrf(G, m, max_iter=min(n_iter, IHLRF_ITER) if fall else n_iter,
                   tol_g=self.tol_g, tol_u=self.tol_u, fd_step=self.fd_step,
                   fd_scheme=self.fd_scheme, beta_max=self.beta_max, start=start, stop=stop,
                   max_stalls=3 if fall else None)
        if fall and dp.status == "failed" and np.all(np.isfinite(dp.u_star)):
            dp = self._fallback(G, m, dp)
        return dp

    def _not_minimum(self, G: Any, m: int, dp: DesignPoint, p: np.ndarray,
                     sign0: float) -> DesignPoint:
        """``"unconverged"`` at the limit state on the ray through ``p`` (nearer than ``β``)."""
        e = p / float(np.linalg.norm(p))
        rho = float(ray_roots(G, e[None, :], np.array([float(np.linalg.norm(p))]),
                              1e-3 * SETTLED_BETA * abs(dp.beta))[0])
        u = rho * e if np.isfinite(rho) and rho < np.linalg.norm(p) else p
        g = float(G(u[None, :])[0])
        grad = fd_gradient(G, u, g, self.fd_step, self.fd_scheme)
        ng = float(np.linalg.norm(grad))
        msg = (f"FORM: the design point at |beta| = {abs(dp.beta):.4g} is not a local minimum "
               "of the distance (a saddle of a limit state concave towards the origin): a "
               f"point of the limit state lies at |beta| <= {np.linalg.norm(u):.4g} and the "
               "search from it did not converge; beta is an upper bound of the distance "
               "(pf_bound), use 'is', 'ais' or 'subset'")
        warnings.warn(msg, EstimatorWarning, stacklevel=4)
        return DesignPoint(sign0 * float(np.linalg.norm(u)), u,
                           -grad / ng if ng > 0 else np.full(m, np.nan), grad, g, False,
                           dp.n_iter, G.calls, msg, "unconverged", dp.g_origin)

    def _fallback(self, G: Any, m: int, dp: DesignPoint) -> DesignPoint:
        """SLSQP and the ray search from the last point of a failed iHL-RF search."""
        scale = max(abs(dp.g_origin), float(getattr(G, "scale", 0.0)))
        nu = float(np.linalg.norm(dp.u_star))
        u, g, grad, ok, msg = refine(
            G, dp.u_star, dp.grad,
            gradient=lambda v, gv: fd_gradient(G, v, gv, self.fd_step, self.fd_scheme),
            settled=lambda v, gv, gr: _settled(v, gv, gr, scale, self.tol_g, self.tol_u),
            on_surface=lambda gv, gr: abs(gv) <= np.sqrt(self.tol_g) * max(
                scale, float(np.linalg.norm(gr))),
            tol_beta=SETTLED_BETA * max(1.0, nu), max_iter=self.max_iter)
        if not ok:
            if not (np.isfinite(g) and abs(g) <= np.sqrt(self.tol_g) * max(
                    scale, float(np.linalg.norm(grad)))):
                return replace(dp, calls=G.calls, message=f"{dp.message}; fallback: {msg}")
            # a point of the limit state, not shown to be the nearest: ‖u‖ bounds β*
            ng = float(np.linalg.norm(grad))
            return DesignPoint(
                (1.0 if dp.g_origin >= 0 else -1.0) * float(np.linalg.norm(u)), u,
                -grad / ng if ng > 0 else np.full(m, np.nan), grad, g, False, dp.n_iter, G.calls,
                f"design point not found to tolerance ({dp.message}; fallback: {msg}): the "
                f"point reached lies on the limit state at |beta| = {np.linalg.norm(u):.4g}, "
                "an upper bound of the distance to the design point (pf_bound)", "unconverged",
                dp.g_origin)
        ng = float(np.linalg.norm(grad))
        alpha = -grad / ng if np.isfinite(ng) and ng > 0 else np.full(m, np.nan)
        sign0 = 1.0 if dp.g_origin >= 0 else -1.0
        return DesignPoint(sign0 * float(np.linalg.norm(u)), u, alpha, grad, g, True,
                           dp.n_iter, G.calls, msg, "converged", dp.g_origin)

    def check(self, dp: DesignPoint, p: int) -> None:
        """Raise ``ModelError`` for a failed search when ``on_failure == "raise"``."""
        if dp.status == "failed" and self.on_failure == "raise":
            raise ModelError(
                f"FORM did not converge for design {p}: {dp.message} after {dp.n_iter} "
                f"iterations (beta={dp.beta:.6g}, G(u)={dp.g_star:.3g}); increase max_iter, "
                "loosen tol_g/tol_u, pass on_failure='nan', or use an estimator that needs no "
                "converged design point ('is' on periodic inputs, 'ais', 'subset', 'mc')"
            )

    def estimate(self, response: Any, inputs: Any, limit: LimitState, x: np.ndarray, *,
                 rng: np.random.Generator, u: np.ndarray | None = None) -> Estimate:
        """Design-point search for every design of ``x`` (``rng`` and ``u`` are unused)."""
        x, _ = check_args(inputs, limit, x, rng, u)
        p, m = x.shape[0], inputs.dim
        cols = periodic_columns(inputs)
        beta, nit, pf = np.full(p, np.nan), np.zeros(p, int), np.full(p, np.nan)
        ustar, alpha = np.full((p, m), np.nan), np.full((p, m), np.nan)
        calls, msgs, per, status = 0, [], np.zeros(p, int), []
        theta = np.full((p, m), np.nan)
        nodes, qerr = np.zeros(p, int), np.full(p, np.nan)
        for i in range(p):
            if cols:
                dp, q = conditional_search(self, response, inputs, limit, x[i], cols)
                nodes[i], qerr[i] = q.n_nodes, q.error
            else:
                dp = self.search(response, inputs, limit, x[i])
            self.check(dp, i)
            calls += dp.calls
            per[i], nit[i] = dp.calls, dp.n_iter
            msgs.append(dp.message)
            status.append(dp.status)
            if dp.status != "failed":
                beta[i], ustar[i], alpha[i] = dp.beta, dp.u_star, dp.alpha
                pf[i] = q.pf if cols else special.ndtr(-dp.beta)
                theta[i] = (dominant_theta(inputs, cols, q) if cols
                            else inputs.from_standard(dp.u_star[None, :])[0])
        status = np.array(status)
        return make_estimate(
            "form", calls, p, pf=pf,
            diagnostics={"beta": beta, "u_star": ustar, "theta_star": theta, "alpha": alpha,
                         "importance_factors": alpha**2, "converged": status == "converged",
                         "status": status, "pf_bound": bound_labels(beta, status),
                         "n_iter": nit, "calls": per, "phase_nodes": nodes,
                         "pf_quadrature_error": qerr, "message": msgs},
        )


def bound_labels(beta: np.ndarray, status: np.ndarray) -> np.ndarray:
    """``pf_bound`` of a design-point result: ``"upper"`` where the limit state was not reached
    from a safe mean (``pf`` is that of a superset of the failure domain), ``"lower"`` where it
    was not reached from a failing mean; where the search ended ``"unconverged"`` on a point
    ``u_b`` of the limit state, ``‖u_b‖ ≥ β*`` so FORM's ``pf`` is at least the one reported
    from a safe mean (``"lower"``) and at most from a failing mean (``"upper"``); ``""``
    elsewhere.

    >>> bound_labels(np.array([3.0, 10.0, -10.0, 3.0]), np.array(
    ...     ["converged", "not_reached", "not_reached", "unconverged"])).tolist()
    ['', 'upper', 'lower', 'lower']
    """
    status, safe = np.asarray(status), np.asarray(beta) >= 0
    out = np.where(status == "not_reached", np.where(safe, "upper", "lower"), "")
    return np.where(status == "unconverged", np.where(safe, "lower", "upper"), out)


__all__ = ["FLAT", "FORM", "SETTLED_BETA", "STATUSES", "DesignPoint", "bound_labels",
           "fd_gradient", "ihlrf"]
