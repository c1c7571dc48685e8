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

from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy import special

from surrogate_rbrdo.core.errors import ModelError
from surrogate_rbrdo.core.protocols import Estimate, LimitState
from surrogate_rbrdo.core.validate import check_choice, check_int, check_positive
from surrogate_rbrdo.estimators._common import LimitStateU, check_args, make_estimate
from surrogate_rbrdo.estimators.registry import ESTIMATORS


@dataclass(frozen=True)
class DesignPoint:
    """Result of one design-point search (standard space)."""

    beta: float
    u_star: np.ndarray
    alpha: np.ndarray
    grad: np.ndarray
    g_star: float
    converged: bool
    n_iter: int
    calls: int
    message: str


def fd_gradient(G: LimitStateU, u: np.ndarray, g_u: float, step: float,
                scheme: str) -> np.ndarray:
    """Finite-difference gradient of ``G`` at ``u`` (one batched model call)."""
    m = u.size
    eye = np.eye(m) * step
    if scheme == "forward":
        gp = G(u[None, :] + eye)
        return (gp - g_u) / step
    gv = G(np.vstack([u[None, :] + eye, u[None, :] - eye]))
    return (gv[:m] - gv[m:]) / (2.0 * step)


def ihlrf(G: LimitStateU, m: int, *, max_iter: int, tol_g: float, tol_u: float,
          fd_step: float, fd_scheme: str) -> DesignPoint:
    """Run iHL-RF on ``G`` from the origin; never raises on non-convergence (see ``converged``)."""
    u = np.zeros(m)
    g = float(G(u[None, :])[0])
    g0 = g
    scale = abs(g0) if g0 != 0 else 1.0
    sign0 = 1.0 if g0 >= 0 else -1.0
    grad = fd_gradient(G, u, g, fd_step, fd_scheme)
    msg = "maximum number of iterations reached"
    converged = False
    it = 0
    while it < max_iter:
        it += 1
        ng = float(np.linalg.norm(grad))
        if not np.isfinite(ng) or ng == 0.0:
            msg = f"zero or non-finite gradient of the limit state at u={u.tolist()}"
            break
        alpha = -grad / ng
        e1 = abs(g) / scale
        e2 = float(np.linalg.norm(u - (alpha @ u) * alpha))
        if e1 <= tol_g and e2 <= tol_u:
            converged, msg = True, "converged"
            break
        d = ((grad @ u - g) / ng**2) * grad - u
        c = 2.0 * float(np.linalg.norm(u)) / ng + 10.0
        merit = 0.5 * u @ u + c * abs(g)
        slope = (u + c * np.sign(g) * grad) @ d
        lam, accepted = 1.0, False
        for _ in range(12):
            un = u + lam * d
            gn = float(G(un[None, :])[0])
            if 0.5 * un @ un + c * abs(gn) <= merit + 1e-4 * lam * min(slope, 0.0):
                accepted = True
                break
            lam *= 0.5
        u, g = un, gn  # the last trial is taken even if Armijo failed (as FERUM does)
        grad = fd_gradient(G, u, g, fd_step, fd_scheme)
        if not accepted:  # after 12 halvings (λ = 2⁻¹²)
            msg = "line search stalled"
    ng = float(np.linalg.norm(grad))
    alpha = -grad / ng if ng > 0 else np.full(m, np.nan)
    beta = sign0 * float(np.linalg.norm(u))
    return DesignPoint(beta, u, alpha, grad, g, converged, it, G.calls, msg)


@ESTIMATORS.register("form")
@dataclass(frozen=True)
class FORM:
    """First-order reliability method (iHL-RF), one design-point search per design.

    Gives ``pf = Φ(−β)``; ``mean``, ``std`` and all standard errors are NaN (use ``"fosm"`` or
    ``"mc"`` for moments). Diagnostics: ``beta``, ``u_star`` and ``theta_star`` ``(P, m)``,
    ``alpha`` (unit vector towards failure), ``importance_factors`` ``α²``, ``converged``,
    ``n_iter``, ``calls`` (model calls per design), ``message``.

    Parameters
    ----------
    max_iter : int
    tol_g : float
        Convergence on ``|G(u)| / |G(0)|``.
    tol_u : float
        Convergence on the distance of ``u`` from the line through ``α`` (alignment).
    fd_step : float
        Finite-difference step in standard space (raise it for noisy models, e.g. FE solves).
    fd_scheme : {"forward", "central"}
    on_failure : {"raise", "nan"}
        Non-convergence raises ``ModelError`` or returns NaN for that design.

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
    """

    max_iter: int = 100
    tol_g: float = 1e-8
    tol_u: float = 1e-6
    fd_step: float = 1e-6
    fd_scheme: str = "forward"
    on_failure: str = "raise"

    def __post_init__(self) -> None:
        check_int("max_iter", self.max_iter, minimum=1)
        check_positive("tol_g", self.tol_g)
        check_positive("tol_u", self.tol_u)
        check_positive("fd_step", self.fd_step)
        check_choice("fd_scheme", self.fd_scheme, ("forward", "central"))
        check_choice("on_failure", self.on_failure, ("raise", "nan"))

    def search(self, response: Any, inputs: Any, limit: LimitState,
               x_row: np.ndarray) -> DesignPoint:
        """Design-point search for one design ``x_row`` (shape ``(d,)``)."""
        G = LimitStateU(response, inputs, limit, np.asarray(x_row, dtype=float))
        return ihlrf(G, inputs.dim, max_iter=self.max_iter, tol_g=self.tol_g,
                     tol_u=self.tol_u, fd_step=self.fd_step, fd_scheme=self.fd_scheme)

    def check(self, dp: DesignPoint, p: int) -> None:
        """Raise ``ModelError`` for a non-converged search when ``on_failure == "raise"``."""
        if not dp.converged and self.on_failure == "raise":
            raise ModelError(
                f"FORM did not converge for design {p}: {dp.message} after {dp.n_iter} "
                f"iterations (beta={dp.beta:.6g}, G(u)={dp.g_star:.3g}); increase max_iter, "
                "loosen tol_g/tol_u, or pass on_failure='nan'"
            )

    def estimate(self, response: Any, inputs: Any, limit: LimitState, x: np.ndarray, *,
                 rng: np.random.Generator, u: np.ndarray | None = None) -> Estimate:
        """Design-point search for every design of ``x`` (``rng`` and ``u`` are unused)."""
        x, _ = check_args(inputs, limit, x, rng, u)
        p, m = x.shape[0], inputs.dim
        beta, conv, nit = np.full(p, np.nan), np.zeros(p, bool), np.zeros(p, int)
        ustar, alpha = np.full((p, m), np.nan), np.full((p, m), np.nan)
        calls, msgs, per = 0, [], np.zeros(p, int)
        for i in range(p):
            dp = self.search(response, inputs, limit, x[i])
            self.check(dp, i)
            calls += dp.calls
            per[i] = dp.calls
            conv[i], nit[i] = dp.converged, dp.n_iter
            msgs.append(dp.message)
            if dp.converged:
                beta[i], ustar[i], alpha[i] = dp.beta, dp.u_star, dp.alpha
        theta = np.full((p, m), np.nan)
        ok = conv
        if ok.any():
            theta[ok] = inputs.from_standard(ustar[ok])
        return make_estimate(
            "form", calls, p, pf=special.ndtr(-beta),
            diagnostics={"beta": beta, "u_star": ustar, "theta_star": theta, "alpha": alpha,
                         "importance_factors": alpha**2, "converged": conv, "n_iter": nit,
                         "calls": per, "message": msgs},
        )
