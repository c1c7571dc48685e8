"""Fallback design-point search where iHL-RF does not converge: SQP, then a ray search.

iHL-RF linearises ``G`` at every step; it creeps (or its line search stalls) where ``G`` is
strongly curved relative to its gradient — e.g. a bounded input driven into its tail, a
uniform-disk radius ``r = √Φ(u)`` at ``u ≈ −3`` — and it cannot converge at a **kink**, where
the peak of a response over speed switches from one mode to another and the gradient jumps
(review 3 of issue 13: 2 of 16 random designs of the credible problem). The design point is
the solution of ``min ½‖u‖² s.t. G(u) = 0`` whatever the algorithm (Hasofer & Lind 1974), so
two further searches are tried from the last iHL-RF point:

1. **SLSQP** (Kraft 1988, ``scipy.optimize``) on that problem with ``G`` scaled by its gradient
   norm at the start (the constraint is then a distance in standard space) and the same
   finite-difference gradients: its quasi-Newton Hessian of the Lagrangian carries the
   curvature that iHL-RF ignores (Liu & Der Kiureghian 1991, *Structural Safety* 9, 161–177,
   found SQP the most robust of the design-point algorithms they compared).
2. A **ray search** on the unit sphere (a pattern search, Kolda, Lewis & Torczon 2003, *SIAM
   Review* 45, 385–482): ``β = min_e ρ(e)``, ``ρ(e)`` the distance along the ray ``e`` from
   the origin to the limit state (a root of ``G(ρe) = 0``, found by a safeguarded secant).
   ``ρ`` is continuous across a kink of ``G`` and needs no gradient there. The poll tilts the
   ray by an angle ``h`` towards ``±`` each of ``m − 1`` orthonormal directions and ``±`` the
   projected gradient; a shorter ray is taken, else ``h`` halves, down to ``H_MIN``.

The point is accepted when it lies on the limit state and either the usual test of iHL-RF
holds (``form._settled``: the gradient points along ``u``) or no ray within the final angle is
shorter than ``ρ(e)·(1 − SETTLED_BETA)`` (a kink, where the gradient need not point along
``u``: a local minimum of the distance all the same).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy import optimize

#: first and last tilt of the ray search (radians)
H_START, H_MIN = 0.05, 2e-3
#: polls of the ray search at most
MAX_POLLS = 40
#: SLSQP iterations at most (it converges in 8–30 where it converges: at a kink it does not)
SQP_ITER = 30


class _Outside(Exception):
    """A trial point left the model's physical domain (``G`` not finite)."""


def orthonormal_complement(e: np.ndarray, extra: np.ndarray | None = None) -> np.ndarray:
    """Rows: an orthonormal basis of the space orthogonal to the unit vector ``e``, plus the
    normalised projection of ``extra`` (when it is not parallel to ``e``) at the end.

    >>> q = orthonormal_complement(np.array([0.0, 0.0, 1.0]))
    >>> q.shape, bool(np.allclose(q @ [0.0, 0.0, 1.0], 0.0))
    ((2, 3), True)
    """
    m = e.size
    q, _ = np.linalg.qr(np.column_stack([e, np.eye(m)]))
    basis = q[:, 1:m].T
    if extra is not None:
        v = extra - (extra @ e) * e
        nv = float(np.linalg.norm(v))
        if np.isfinite(nv) and nv > 1e-12:
            basis = np.vstack([basis, v / nv])
    return basis


def ray_roots(G: Any, D: np.ndarray, rho0: np.ndarray, tol: float, n_iter: int = 12
              ) -> np.ndarray:
    """Distances ``ρ_k`` along the unit rows ``D`` of the limit state ``G(ρ D_k) = 0`` near
    ``rho0`` (one batched call per iteration): a secant that keeps a sign-change bracket once
    it has one (regula falsi, Illinois variant) and stops when the step is below ``tol``.
    ``inf`` where the ray leaves the physical domain or no root is found (not shorter).

    >>> class Lin:                         # G = 2 − u₁
    ...     def __call__(self, u): return 2.0 - u[:, 0]
    >>> D = np.array([[1.0, 0.0], [np.sqrt(0.5), np.sqrt(0.5)]])
    >>> np.round(ray_roots(Lin(), D, np.array([2.5, 2.5]), 1e-10), 8).tolist()
    [2.0, 2.82842712]
    """
    k = D.shape[0]
    rho = np.array(rho0, dtype=float)
    g = G(rho[:, None] * D)
    prev_r, prev_g = rho * 1.05, G((rho * 1.05)[:, None] * D)
    out = np.full(k, np.inf)
    lo = np.full(k, np.nan)
    glo = np.full(k, np.nan)
    live = np.isfinite(g) & np.isfinite(prev_g)
    for _ in range(n_iter):
        idx = np.flatnonzero(live)
        if idx.size == 0:
            break
        with np.errstate(divide="ignore", invalid="ignore"):
            step = g[idx] * (rho[idx] - prev_r[idx]) / (g[idx] - prev_g[idx])
        new = rho[idx] - step
        br = np.isfinite(lo[idx])      # bracketed: stay inside [lo, rho]
        inside = (new - lo[idx]) * (new - rho[idx]) <= 0
        fix = br & ~inside | ~np.isfinite(new)
        new[fix] = np.where(br[fix], 0.5 * (lo[idx][fix] + rho[idx][fix]), rho[idx][fix] * 1.1)
        new = np.maximum(new, 1e-3 * rho[idx])
        done = np.abs(new - rho[idx]) <= tol       # the step is below tol: converged
        out[idx[done]] = new[done]
        live[idx[done]] = False
        idx, new = idx[~done], new[~done]
        if idx.size == 0:
            break
        gn = G(new[:, None] * D[idx])
        ok = np.isfinite(gn)
        live[idx[~ok]] = False
        flip = ok & (np.sign(gn) != np.sign(g[idx]))
        lo[idx[flip]], glo[idx[flip]] = rho[idx[flip]], g[idx[flip]]
        prev_r[idx], prev_g[idx] = rho[idx], g[idx]
        rho[idx], g[idx] = new, gn
        hit = ok & (gn == 0.0)                      # on the limit state exactly
        out[idx[hit]] = new[hit]
        live[idx[hit]] = False
    return out


def ray_search(G: Any, u: np.ndarray, grad: np.ndarray, tol_beta: float
               ) -> tuple[np.ndarray, bool, str]:
    """Pattern search of ``min_e ρ(e)`` from the ray through ``u`` (see the module docstring).

    Returns the best point found on the limit state, whether the final poll at ``H_MIN``
    found no shorter ray (a local minimum of the distance) and a message.
    """
    e = u / float(np.linalg.norm(u))
    rho = ray_roots(G, e[None, :], np.array([float(np.linalg.norm(u))]), 0.01 * tol_beta)[0]
    if not np.isfinite(rho):
        return u, False, "ray search: no root of G along the ray through the start point"
    h, polls = H_START, 0
    while polls < MAX_POLLS:
        polls += 1
        basis = orthonormal_complement(e, -grad)
        tilts = np.vstack([basis, -basis])
        D = e[None, :] + h * tilts
        D /= np.linalg.norm(D, axis=1, keepdims=True)
        r = ray_roots(G, D, np.full(D.shape[0], rho), 0.01 * tol_beta)
        j = int(np.argmin(r))
        if r[j] < rho - 0.1 * tol_beta:
            e, rho = D[j], float(r[j])
            continue
        if not np.all(np.isfinite(r)):   # a ray without a root is no evidence of a minimum
            return rho * e, False, (f"ray search: no root of G along {np.sum(~np.isfinite(r))}"
                                    f" of the {r.size} rays tilted by {h:.2g} rad")
        if h <= H_MIN:
            return rho * e, True, (f"ray search: no shorter ray within {h:.2g} rad after "
                                   f"{polls} polls")
        h *= 0.5
    return rho * e, False, f"ray search: still improving after {MAX_POLLS} polls"


def slsqp_search(G: Any, u0: np.ndarray, grad0: np.ndarray, gradient: Any,
                 max_iter: int) -> np.ndarray | None:
    """``min ½‖u‖² s.t. G(u)/‖∇G(u0)‖ = 0`` by SLSQP from ``u0``; ``gradient(u, g)`` is the
    finite-difference gradient. None when it leaves the physical domain or fails."""
    s = float(np.linalg.norm(grad0))
    if not (np.isfinite(s) and s > 0):
        return None
    memo: dict[bytes, float] = {}

    def g_of(u: np.ndarray) -> float:
        key = u.tobytes()
        if key not in memo:
            memo[key] = float(G(u[None, :])[0])
        if not np.isfinite(memo[key]):
            raise _Outside
        return memo[key]

    try:
        res = optimize.minimize(
            lambda u: 0.5 * float(u @ u), u0, jac=lambda u: u, method="SLSQP",
            constraints=[{"type": "eq", "fun": lambda u: g_of(u) / s,
                          "jac": lambda u: gradient(u, g_of(u)) / s}],
            options={"maxiter": max_iter, "ftol": 1e-9})
    except _Outside:
        return None
    return np.asarray(res.x, dtype=float) if np.all(np.isfinite(res.x)) else None


def refine(G: Any, u0: np.ndarray, grad0: np.ndarray, *, gradient: Any, settled: Any,
           on_surface: Any, tol_beta: float, max_iter: int
           ) -> tuple[np.ndarray, float, np.ndarray, bool, str]:
    """SLSQP, then the ray search where SLSQP's point is not settled (module docstring).

    ``gradient(u, g)`` is the finite-difference gradient, ``settled(u, g, grad)`` the test of
    iHL-RF, ``on_surface(g, grad)`` whether ``|G|`` is small enough. Returns the point, its
    ``G`` and gradient, whether it is accepted as the design point and a message.
    """
    best = slsqp_search(G, u0, grad0, gradient, min(max_iter, SQP_ITER))
    how = "SLSQP"
    if best is not None:
        g = float(G(best[None, :])[0])
        grad = gradient(best, g)
        if np.isfinite(g) and on_surface(g, grad) and settled(best, g, grad):
            return best, g, grad, True, "converged (SLSQP after iHL-RF did not converge)"
    else:
        best, how = u0, "SLSQP left the domain or failed"
    nb = float(np.linalg.norm(best))
    if not (np.isfinite(nb) and nb > 0):
        return best, np.nan, grad0, False, f"{how} no ray to search from"
    u, ok, msg = ray_search(G, best, grad0, tol_beta)
    g = float(G(u[None, :])[0])
    grad = gradient(u, g) if np.isfinite(g) else np.full(u.size, np.nan)
    ok = ok and np.isfinite(g)
    return u, g, grad, ok, (f"converged ({how}, then {msg}: a local minimum of the distance "
                            "to the limit state, e.g. at a kink)" if ok else f"{how}, then {msg}")


__all__ = ["H_MIN", "H_START", "orthonormal_complement", "ray_roots", "ray_search", "refine",
           "slsqp_search"]
