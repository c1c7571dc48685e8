"""iHL-RF: the design-point search of FORM (improved HL-RF with an Armijo line search), its
convergence tests and the :class:`DesignPoint` it returns.

Reference: Y. Zhang, A. Der Kiureghian (1995), Two improved algorithms for reliability analysis,
in *Reliability and Optimization of Structural Systems*, Springer. Split from :mod:`.form`,
which adds the fallback (:mod:`._constrained`) and the estimator.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from surrogate_rbrdo.core.errors import ModelError
from surrogate_rbrdo.estimators._common import LimitStateU

#: outcome of a design-point search
STATUSES = ("converged", "not_reached", "unconverged", "failed")
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
    distance reached, a first-order bound), ``"unconverged"`` (the fallback ended on a point of
    the limit state not shown to be the nearest: ``|beta|`` bounds the distance from above) or
    ``"failed"`` (no convergence, see ``message``).
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


class _Run:
    """The named steps of one :func:`ihlrf` search (its options and the scale and sign of
    ``G(0)``)."""

    def __init__(self, G: LimitStateU, scale: float, sign0: float, tol_g: float,
                 tol_u: float, fd_step: float, fd_scheme: str, beta_max: float) -> None:
        self.G, self.scale, self.sign0 = G, scale, sign0
        self.tol_g, self.tol_u, self.fd_step, self.fd_scheme = tol_g, tol_u, fd_step, fd_scheme
        self.beta_max = beta_max

    def end_before_step(self, u: np.ndarray, g: float, grad: np.ndarray, it: int,
                        stop: Callable[[np.ndarray], bool] | None
                        ) -> tuple[str, str, np.ndarray, float] | None:
        """``(status, message, u, g)`` where the search ends at this iterate (beyond
        ``beta_max``, stopped by the caller, ``G`` flat, no gradient, converged), else None."""
        if self.sign0 * g > 0 and float(np.linalg.norm(u)) >= self.beta_max:
            return ("not_reached", f"limit state not reached within beta_max = "
                    f"{self.beta_max:g} (|beta| >= {np.linalg.norm(u):.4g})", u, g)
        if stop is not None and stop(u):
            return "failed", "stopped by the caller", u, g
        ng = float(np.linalg.norm(grad))
        if it > 1 and self.sign0 * g > 0 and ng * self.fd_step <= FLAT * max(self.scale,
                                                                             abs(g)):
            return self.flat_end(u, g)   # e.g. bounded inputs at the end of their support
        if not np.isfinite(ng) or ng == 0.0:
            return ("failed", f"zero or non-finite gradient of the limit state at "
                    f"u={u.tolist()}", u, g)
        if abs(g) <= self.tol_g * max(self.scale, ng) and _alignment(
                u, -grad / ng) <= self.tol_u:
            return "converged", "converged", u, g
        return None

    def flat_end(self, u: np.ndarray, g: float) -> tuple[str, str, np.ndarray, float]:
        """``G`` flat with the sign of ``G(0)``: not reached; the point is carried out radially
        to ``beta_max`` and kept there if ``G`` still has that sign."""
        if np.isfinite(self.beta_max) and np.linalg.norm(u) > 0:
            ub = u * (self.beta_max / float(np.linalg.norm(u)))   # checked out to beta_max
            gb = float(self.G(ub[None, :])[0])
            if np.isfinite(gb) and self.sign0 * gb > 0:
                u, g = ub, gb
        return ("not_reached", "limit state not reached: G is flat (its change over a "
                f"finite-difference step is below {FLAT:g} of its scale) at |beta| = "
                f"{np.linalg.norm(u):.4g} with the sign of G(0)", u, g)

    def step(self, u: np.ndarray, g: float, grad: np.ndarray, blocked: int
             ) -> tuple[np.ndarray, float, np.ndarray, bool, int, tuple[str, str] | None]:
        """One iHL-RF step with its line search: the new point, ``G``, gradient, whether Armijo
        accepted it, the count of steps in a row blocked by the domain's edge, and
        ``(status, message)`` where the edge ends the search (the limit state not reached
        inside the physical domain)."""
        ng = float(np.linalg.norm(grad))
        d = ((grad @ u - g) / ng**2) * grad - u
        c = 2.0 * float(np.linalg.norm(u)) / ng + 10.0
        un, gn, accepted, lam_in, lam_out = _line_search(self.G, u, g, grad, d, c)
        blocked = blocked + 1 if np.isfinite(lam_out) else 0
        if blocked >= 2 and self.sign0 * gn > 0:
            ub, gb, crossed = _boundary(self.G, u, g, d, 0.0 if np.isnan(lam_in) else lam_in,
                                        lam_out)
            if not crossed:
                return ub, gb, grad, accepted, blocked, (
                    "not_reached", "limit state not reached inside the model's physical "
                    f"domain (|beta| >= {np.linalg.norm(ub):.4g} along the search direction)")
            blocked, un, gn = 0, ub, gb
        # the last trial inside is taken even if Armijo failed (as FERUM does)
        grad = fd_gradient(self.G, un, gn, self.fd_step, self.fd_scheme)
        return un, gn, grad, accepted, blocked, None

    def result(self, u: np.ndarray, g: float, grad: np.ndarray, status: str, msg: str,
               it: int, g_origin: float) -> DesignPoint:
        """The :class:`DesignPoint` of the search's end (``β`` capped at ``beta_max`` where
        the limit state was not reached)."""
        ng = float(np.linalg.norm(grad))
        alpha = -grad / ng if np.isfinite(ng) and ng > 0 else np.full(u.size, np.nan)
        beta = self.sign0 * min(float(np.linalg.norm(u)),
                                self.beta_max if status == "not_reached" else np.inf)
        return DesignPoint(beta, u, alpha, grad, g, status == "converged", it, self.G.calls,
                           msg, status, g_origin)


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
    run = _Run(G, max(abs(g_origin), float(getattr(G, "scale", 0.0))),
               1.0 if g_origin >= 0 else -1.0, tol_g, tol_u, fd_step, fd_scheme, beta_max)
    grad = fd_gradient(G, u, g, fd_step, fd_scheme)
    msg, status, it, blocked, stalls = "maximum number of iterations reached", "failed", 0, 0, 0
    while it < max_iter:
        it += 1
        end = run.end_before_step(u, g, grad, it, stop)
        if end is not None:
            status, msg, u, g = end
            break
        u, g, grad, accepted, blocked, end = run.step(u, g, grad, blocked)
        if end is not None:
            status, msg = end
            break
        stalls = 0 if accepted else stalls + 1
        if not accepted:  # after 12 halvings (λ = 2⁻¹²)
            msg = "line search stalled"
            if _settled(u, g, grad, run.scale, tol_g, tol_u):
                status = "converged"
                msg = ("converged (the line search cannot improve further: the accuracy is "
                       "limited by the finite-difference gradient)")
                break
            if max_stalls is not None and stalls >= max_stalls:
                msg = f"line search stalled {stalls} times in a row"
                break
    else:
        if _settled(u, g, grad, run.scale, tol_g, tol_u):
            status = "converged"
            msg = ("converged (at max_iter, within the accuracy a finite-difference gradient "
                   "allows)")
    return run.result(u, g, grad, status, msg, it, g_origin)
