"""FORM: design-point search by the improved HL-RF algorithm (iHL-RF) with an Armijo line search.

The limit state ``G(u) = limit.g(response(x, T(u)))`` is searched in standard-normal space from
``u = 0``. Gradients are finite differences (one batched model call of ``m`` or ``2m`` points per
iteration; every point is counted). ``β = sign(G(0)) ‖u*‖`` so a mean point in the failure domain
gives ``β < 0`` and ``P_f = Φ(−β) > 0.5``. When the search does not converge the estimator raises
:class:`~surrogate_rbrdo.core.errors.ModelError` (``on_failure="raise"``) or returns NaN for that
design (``on_failure="nan"``), with ``diagnostics["converged"]`` False: never a silent wrong
answer.

Reference: Y. Zhang, A. Der Kiureghian (1995), Two improved algorithms for reliability analysis,
in *Reliability and Optimization of Structural Systems*, Springer.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from scipy import special

from surrogate_rbrdo.core.errors import ModelError
from surrogate_rbrdo.core.protocols import Estimate, LimitState
from surrogate_rbrdo.core.validate import check_choice, check_int, check_positive
from surrogate_rbrdo.estimators._common import LimitStateU, check_args, make_estimate
from surrogate_rbrdo.estimators._constrained import refine
from surrogate_rbrdo.estimators._periodic import (
    conditional_search,
    dominant_theta,
    periodic_columns,
)
from surrogate_rbrdo.estimators.registry import ESTIMATORS

#: outcome of a design-point search
STATUSES = ("converged", "not_reached", "failed")
#: relative change of G over a finite-difference step below which G is flat (round-off level)
FLAT = 1e-10
#: relative error of β accepted where the iteration can make no further progress
SETTLED_BETA = 1e-3
#: iHL-RF iterations before the fallback takes over (iHL-RF converges in fewer where it
#: converges at all; beyond, it creeps: review 3 of issue 13)
IHLRF_ITER = 20


@dataclass(frozen=True)
class DesignPoint:
    """Result of one design-point search (standard space).

    ``status`` is ``"converged"``, ``"not_reached"`` (the limit state ``G = 0`` was not met
    before the model's physical domain ended or before ``‖u‖ = beta_max``: ``beta`` is the
    distance reached, a first-order bound) or ``"failed"`` (no convergence, see ``message``).
    """

    beta: float
    u_star: np.ndarray
    alpha: np.ndarray
    grad: np.ndarray
    g_star: float
    converged: bool
    n_iter: int
    calls: int
    message: str
    status: str = "converged"
    g_origin: float = float("nan")


def fd_gradient(G: LimitStateU, u: np.ndarray, g_u: float, step: float,
                scheme: str) -> np.ndarray:
    """Finite-difference gradient of ``G`` at ``u`` (one batched model call).

    A difference point outside the model's domain (``G = −inf``) is replaced by the one-sided
    difference on the other side (one more call); both sides outside gives a non-finite entry.
    """
    m = u.size
    eye = np.eye(m) * step
    if scheme == "forward":
        gp = G(u[None, :] + eye)
        grad = (gp - g_u) / step
        out = ~np.isfinite(gp)
        if out.any():
            grad[out] = (g_u - G(u[None, :] - eye[out])) / step
        return grad
    gv = G(np.vstack([u[None, :] + eye, u[None, :] - eye]))
    gp, gm = gv[:m], gv[m:]
    with np.errstate(invalid="ignore"):
        grad = (gp - gm) / (2.0 * step)
        grad = np.where(np.isfinite(gp), grad, (g_u - gm) / step)
        return np.where(np.isfinite(gm) | ~np.isfinite(gp), grad, (gp - g_u) / step)


def _alignment(u: np.ndarray, alpha: np.ndarray) -> float:
    """Angle-like distance of ``u`` from the line through ``α`` (relative to ``max(1, ‖u‖)``)."""
    return float(np.linalg.norm(u - (alpha @ u) * alpha)) / max(1.0, float(np.linalg.norm(u)))


def _settled(u: np.ndarray, g: float, grad: np.ndarray, scale: float, tol_g: float,
             tol_u: float) -> bool:
    """Converged as far as the iteration can tell where it makes no further progress (a stalled
    line search, ``max_iter``): ``|G|`` within ``√tol_g`` of its scale and an estimated error
    of ``β`` — ``|G|/‖∇G‖`` (distance to the limit state) plus ``‖u‖ ε²/2`` (``ε`` the angle
    between ``u`` and ``−∇G``: the distance minus the linearised index) — below
    ``SETTLED_BETA · max(1, ‖u‖)``; or the alignment itself below ``√tol_u``."""
    ng = float(np.linalg.norm(grad))
    if not (np.isfinite(ng) and ng > 0 and abs(g) <= np.sqrt(tol_g) * max(scale, ng)):
        return False
    eps, nu = _alignment(u, -grad / ng), float(np.linalg.norm(u))
    return bool(eps <= np.sqrt(tol_u)
                or abs(g) / ng + 0.5 * nu * eps**2 <= SETTLED_BETA * max(1.0, nu))


def _boundary(G: LimitStateU, u: np.ndarray, g: float, d: np.ndarray, lam_in: float,
              lam_out: float, n_bisect: int = 8) -> tuple[np.ndarray, float, bool]:
    """Bisect ``[lam_in, lam_out]`` along ``u + λd`` for the edge of the physical domain
    (``G`` finite at ``lam_in``, ``−inf`` at ``lam_out``). Returns the last point inside, its
    ``G`` and whether ``G`` changed sign on the way (the limit state lies inside after all)."""
    g_in = float(G((u + lam_in * d)[None, :])[0]) if lam_in > 0 else g
    crossed = np.sign(g_in) != np.sign(g)
    for _ in range(n_bisect):
        if crossed:
            break
        lam = 0.5 * (lam_in + lam_out)
        gl = float(G((u + lam * d)[None, :])[0])
        if np.isfinite(gl):
            lam_in, g_in = lam, gl
            crossed = np.sign(gl) != np.sign(g)
        else:
            lam_out = lam
    return u + lam_in * d, g_in, bool(crossed)


def _line_search(G: LimitStateU, u: np.ndarray, g: float, grad: np.ndarray, d: np.ndarray,
                 c: float) -> tuple[np.ndarray, float, bool, float, float]:
    """Armijo backtracking on the merit ``½‖u‖² + c|G|`` (12 halvings at most).

    Returns the last trial inside the domain (``u`` itself if none), its ``G``, whether Armijo
    accepted it, and the largest ``λ`` tried inside / smallest outside the domain (``nan`` /
    ``inf`` when there was none)."""
    merit = 0.5 * u @ u + c * abs(g)
    slope = (u + c * np.sign(g) * grad) @ d
    lam, lam_in, lam_out = 1.0, np.nan, np.inf
    best = (u, g)
    for _ in range(12):
        un = u + lam * d
        gn = float(G(un[None, :])[0])
        if not np.isfinite(gn):      # outside the physical domain: shorten the step
            lam_out = lam
        else:
            lam_in = lam if np.isnan(lam_in) else lam_in
            best = (un, gn)
            if 0.5 * un @ un + c * abs(gn) <= merit + 1e-4 * lam * min(slope, 0.0):
                return un, gn, True, lam_in, lam_out
        lam *= 0.5
    return best[0], best[1], False, lam_in, lam_out


def _start(G: Any, m: int, start: tuple[np.ndarray, float] | None
           ) -> tuple[np.ndarray, float, float]:
    """Start point, its ``G`` and ``G(0)``; the mean point outside the domain is an error."""
    if start is None:
        u = np.zeros(m)
        g = float(G(u[None, :])[0])
        if not np.isfinite(g):
            raise ModelError("FORM: the mean point (u = 0) lies outside the model's physical "
                             "domain")
        return u, g, g
    u = np.array(start[0], dtype=float)
    return u, float(G(u[None, :])[0]), float(start[1])


def ihlrf(G: LimitStateU, m: int, *, max_iter: int, tol_g: float, tol_u: float,
          fd_step: float, fd_scheme: str, beta_max: float = np.inf,
          start: tuple[np.ndarray, float] | None = None,
          stop: Callable[[np.ndarray], bool] | None = None,
          max_stalls: int | None = None) -> DesignPoint:
    """Run iHL-RF on ``G`` from the origin; never raises on non-convergence (see ``status``).

    Convergence: ``|G(u)| <= tol_g · max(|G(0)|, |threshold|, ‖∇G(u)‖)`` — relative to
    ``G(0)`` or the threshold (``G.scale``), or, where
    ``G(0)`` is itself tiny (a design next to its limit state, whose ``G`` is then limited by
    round-off), a distance ``|G|/‖∇G‖ <= tol_g`` from the limit state in standard space — and
    the relative distance of ``u`` from the line through ``α``,
    ``‖u − (α·u)α‖ / max(1, ‖u‖) <= tol_u``. When the line search cannot improve, or at
    ``max_iter``, at a point with ``|G|`` within ``√tol_g`` and that distance below ``√tol_u``
    (the accuracy a finite-difference gradient allows; the error of ``β`` is first order in the
    former, second order in the latter), the search has converged too (review of issue 13:
    β = −3.47 with ``G = −8e-13`` m for a 1 µm limit was reported as a stall).
    The limit state is *not reached* when an iterate still on the side of ``G(0)`` lies beyond
    ``beta_max``, when ``G`` is flat there (its change over a finite-difference step below
    ``FLAT`` of its scale: inputs of bounded support, such as a uniform-disk radius, at the end
    of their support, where ``y`` saturates below the threshold; the point is then carried out
    radially to ``beta_max`` and kept there if ``G`` still has the sign of ``G(0)``), or when
    the step towards the linearised design point leaves the physical domain twice in a row and
    ``G`` keeps its sign up to the domain's edge.

    ``start = (u0, G(0))`` starts the search at ``u0`` instead of the origin (the sign and scale
    of ``G(0)``, known from an earlier search, are then not recomputed); ``stop(u)`` ends the
    search (``status = "failed"``) when it returns True for an iterate; ``max_stalls`` ends it
    (``"failed"``) after that many line-search stalls in a row (for a fallback to take over).
    """
    u, g, g_origin = _start(G, m, start)
    if not np.isfinite(g):
        return DesignPoint(np.nan, u, np.full(m, np.nan), np.full(m, np.nan), g, False, 0,
                           G.calls, "start point outside the physical domain", "failed",
                           g_origin)
    # |G| is judged against |G(0)| and the threshold's own scale (G = threshold - y: a G of
    # 1e-12 m is converged for a 1 µm limit whatever G(0) is)
    scale = max(abs(g_origin), float(getattr(G, "scale", 0.0)))
    sign0 = 1.0 if g_origin >= 0 else -1.0
    grad = fd_gradient(G, u, g, fd_step, fd_scheme)
    msg, status, it, blocked = "maximum number of iterations reached", "failed", 0, 0
    stalls = 0
    while it < max_iter:
        it += 1
        if sign0 * g > 0 and float(np.linalg.norm(u)) >= beta_max:
            status = "not_reached"
            msg = (f"limit state not reached within beta_max = {beta_max:g} "
                   f"(|beta| >= {np.linalg.norm(u):.4g})")
            break
        if stop is not None and stop(u):
            msg = "stopped by the caller"
            break
        ng = float(np.linalg.norm(grad))
        if it > 1 and sign0 * g > 0 and ng * fd_step <= FLAT * max(scale, abs(g)):
            status = "not_reached"   # e.g. bounded inputs at the end of their support
            if np.isfinite(beta_max) and np.linalg.norm(u) > 0:
                ub = u * (beta_max / float(np.linalg.norm(u)))   # checked out to beta_max
                gb = float(G(ub[None, :])[0])
                if np.isfinite(gb) and sign0 * gb > 0:
                    u, g = ub, gb
            msg = ("limit state not reached: G is flat (its change over a finite-difference "
                   f"step is below {FLAT:g} of its scale) at |beta| = {np.linalg.norm(u):.4g} "
                   "with the sign of G(0)")
            break
        if not np.isfinite(ng) or ng == 0.0:
            msg = f"zero or non-finite gradient of the limit state at u={u.tolist()}"
            break
        alpha = -grad / ng
        if abs(g) <= tol_g * max(scale, ng) and _alignment(u, alpha) <= tol_u:
            status, msg = "converged", "converged"
            break
        d = ((grad @ u - g) / ng**2) * grad - u
        c = 2.0 * float(np.linalg.norm(u)) / ng + 10.0
        un, gn, accepted, lam_in, lam_out = _line_search(G, u, g, grad, d, c)
        blocked = blocked + 1 if np.isfinite(lam_out) else 0
        if blocked >= 2 and sign0 * gn > 0:
            ub, gb, crossed = _boundary(G, u, g, d, 0.0 if np.isnan(lam_in) else lam_in,
                                        lam_out)
            if not crossed:
                u, g, status = ub, gb, "not_reached"
                msg = ("limit state not reached inside the model's physical domain "
                       f"(|beta| >= {np.linalg.norm(ub):.4g} along the search direction)")
                break
            blocked, un, gn = 0, ub, gb
        u, g = un, gn  # the last trial inside is taken even if Armijo failed (as FERUM does)
        grad = fd_gradient(G, u, g, fd_step, fd_scheme)
        stalls = 0 if accepted else stalls + 1
        if not accepted:  # after 12 halvings (λ = 2⁻¹²)
            msg = "line search stalled"
            if _settled(u, g, grad, scale, tol_g, tol_u):
                status = "converged"
                msg = ("converged (the line search cannot improve further: the accuracy is "
                       "limited by the finite-difference gradient)")
                break
            if max_stalls is not None and stalls >= max_stalls:
                msg = f"line search stalled {stalls} times in a row"
                break
    else:
        if _settled(u, g, grad, scale, tol_g, tol_u):
            status = "converged"
            msg = ("converged (at max_iter, within the accuracy a finite-difference gradient "
                   "allows)")
    ng = float(np.linalg.norm(grad))
    alpha = -grad / ng if np.isfinite(ng) and ng > 0 else np.full(m, np.nan)
    beta = sign0 * min(float(np.linalg.norm(u)),
                       beta_max if status == "not_reached" else np.inf)
    return DesignPoint(beta, u, alpha, grad, g, status == "converged", it, G.calls, msg, status,
                       g_origin)


@ESTIMATORS.register("form")
@dataclass(frozen=True)
class FORM:
    """First-order reliability method (iHL-RF), one design-point search per design.

    Gives ``pf = Φ(−β)``; ``mean``, ``std`` and all standard errors are NaN (use ``"fosm"`` or
    ``"mc"`` for moments). Diagnostics: ``beta``, ``u_star`` and ``theta_star`` ``(P, m)``,
    ``alpha`` (unit vector towards failure), ``importance_factors`` ``α²``, ``converged``,
    ``status`` (``"converged"``, ``"not_reached"``, ``"failed"``), ``pf_bound``
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
        fall = self.fallback == "sqp" and stop is None
        n_iter = self.max_iter if max_iter is None else max_iter
        dp = ihlrf(G, m, max_iter=min(n_iter, IHLRF_ITER) if fall else n_iter,
                   tol_g=self.tol_g, tol_u=self.tol_u, fd_step=self.fd_step,
                   fd_scheme=self.fd_scheme, beta_max=self.beta_max, start=start, stop=stop,
                   max_stalls=3 if fall else None)
        if not fall or dp.status != "failed" or not np.all(np.isfinite(dp.u_star)):
            return dp
        return self._fallback(G, m, dp)

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
            return replace(dp, calls=G.calls, message=f"{dp.message}; fallback: {msg}")
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
    was not reached from a failing mean, ``""`` elsewhere.

    >>> bound_labels(np.array([3.0, 10.0, -10.0]), np.array(["converged", "not_reached",
    ...                                                       "not_reached"])).tolist()
    ['', 'upper', 'lower']
    """
    nr = np.asarray(status) == "not_reached"
    return np.where(nr, np.where(np.asarray(beta) >= 0, "upper", "lower"), "")
