"""SORM: second-order correction of FORM from the principal curvatures at the design point.

After the FORM search, the Hessian of ``G`` in the tangent plane at ``u*`` is found by central
second differences along an orthonormal basis ``R`` of the plane orthogonal to ``α``
(``2m(m−1) + 1`` extra calls in one batch — four per pair ``i ≤ j`` of the ``m − 1`` basis
vectors, plus ``u*`` — counted), the curvatures are ``κ_i = eig(Rᵀ H R) / ‖∇G‖`` (``κ > 0``: the
limit state bends away from the origin) and

* Breitung (1984): ``P_f ≈ Φ(−β) Π (1 + β κ_i)^{−1/2}``;
* Hohenbichler & Rackwitz (1988): ``β`` in the product replaced by ``φ(β)/Φ(−β)``.

For ``β < 0`` the formula is applied to the safe set: ``P_f = 1 − Φ(β) Π (1 + β κ_i)^{−1/2}``
(``κ`` and ``β`` both change sign). A factor ``1 + ψκ ≤ 0`` (a very concave limit state) makes the
asymptotic formula meaningless: ``ModelError`` or NaN, as FORM's ``on_failure`` says. When FORM
finds the limit state not reached, its first-order value is reported (``status``,
``pf_bound`` as FORM).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy import special

from surrogate_rbrdo.core.errors import ModelError
from surrogate_rbrdo.core.protocols import Estimate, LimitState
from surrogate_rbrdo.core.validate import check_choice, check_positive
from surrogate_rbrdo.estimators._common import LimitStateU, check_args, make_estimate, nan_p
from surrogate_rbrdo.estimators._periodic import conditional_search, periodic_columns
from surrogate_rbrdo.estimators._tail import EstimatorWarning
from surrogate_rbrdo.estimators.form import FORM, bound_labels
from surrogate_rbrdo.estimators.importance import check_form
from surrogate_rbrdo.estimators.registry import ESTIMATORS


def tangent_basis(alpha: np.ndarray) -> np.ndarray:
    """Orthonormal ``(m, m−1)`` basis of the plane orthogonal to the unit vector ``alpha``."""
    m = alpha.size
    q, _ = np.linalg.qr(np.column_stack([alpha, np.eye(m)]))
    return q[:, 1:m]


def curvatures(G: LimitStateU, u_star: np.ndarray, alpha: np.ndarray, grad_norm: float,
               step: float) -> np.ndarray:
    """Principal curvatures of ``G = 0`` at ``u_star`` (second differences, one batched call)."""
    m = u_star.size
    if m == 1:
        return np.zeros(0)
    R = tangent_basis(alpha)
    k = m - 1
    pts, idx = [u_star], {}
    for i in range(k):
        for j in range(i, k):
            for si in (1, -1):
                for sj in (1, -1):
                    idx[(i, j, si, sj)] = len(pts)
                    pts.append(u_star + step * (si * R[:, i] + sj * R[:, j]))
    g = G(np.array(pts))
    A = np.empty((k, k))
    for i in range(k):
        for j in range(i, k):
            gpp, gpm = g[idx[(i, j, 1, 1)]], g[idx[(i, j, 1, -1)]]
            gmp, gmm = g[idx[(i, j, -1, 1)]], g[idx[(i, j, -1, -1)]]
            if i == j:   # points u* ± 2h r_i (and the ± combos equal u*)
                A[i, i] = (gpp - 2 * g[0] + gmm) / (4 * step**2)
            else:
                A[i, j] = A[j, i] = (gpp - gpm - gmp + gmm) / (4 * step**2)
    return np.linalg.eigvalsh(A) / grad_norm


def sorm_pf(beta: float, kappa: np.ndarray, formula: str) -> float:
    """Second-order P_f from ``β`` and curvatures (``NaN`` where a factor is not positive)."""
    b, kap = (beta, kappa) if beta >= 0 else (-beta, -kappa)
    if formula == "breitung":
        psi = b
    else:  # phi(b) / Phi(-b), in logs to stay finite for large b
        psi = float(np.exp(-0.5 * b * b - 0.5 * np.log(2 * np.pi) - special.log_ndtr(-b)))
    fac = 1.0 + psi * kap
    if np.any(fac <= 0):
        return np.nan
    p = float(special.ndtr(-b) * np.prod(fac ** -0.5))
    return p if beta >= 0 else 1.0 - p


@ESTIMATORS.register("sorm")
@dataclass(frozen=True)
class SORM:
    """Second-order reliability method from the FORM design point.

    Diagnostics: ``beta``, ``beta_sorm = −Φ⁻¹(P_f)``, ``curvatures`` ``(P, m − 1)``,
    ``pf_form``, ``converged``, ``pf_quadrature_error``. ``mean``/``std`` and errors are NaN.

    With periodic inputs (phases) the second-order P_f is computed conditional on the phase at
    the nodes of FORM's phase rule and integrated over it (:mod:`._periodic`); ``beta`` is then
    the generalised index ``−Φ⁻¹(P_f)``, ``curvatures`` and ``pf_form`` are NaN. A node where
    the second-order formula is not applicable (``1 + ψκ ≤ 0``) contributes its first-order
    value; ``n_first_order_nodes`` counts them and an :class:`~._tail.EstimatorWarning` says so.

    Parameters
    ----------
    formula : {"hohenbichler", "breitung"}
    hessian_step : float
        Step of the second differences in standard space.
    form : FORM

    Examples
    --------
    >>> from surrogate_rbrdo.estimators.problems import paraboloid
    >>> prob = paraboloid(beta=3.0, kappa=0.3, dim=3)
    >>> est = SORM(formula="breitung").estimate(prob.response, prob.inputs, prob.limit,
    ...                                         prob.x, rng=np.random.default_rng(0))
    >>> np.round(est.diagnostics["curvatures"][0], 5).tolist()
    [0.3, 0.3]
    """

    formula: str = "hohenbichler"
    hessian_step: float = 1e-3
    form: FORM = field(default_factory=FORM)

    def __post_init__(self) -> None:
        check_choice("formula", self.formula, ("hohenbichler", "breitung"))
        check_positive("hessian_step", self.hessian_step)
        check_form(self.form)

    def estimate(self, response: Any, inputs: Any, limit: LimitState, x: np.ndarray, *,
                 rng: np.random.Generator, u: np.ndarray | None = None) -> Estimate:
        """FORM search and curvature correction for every design (``rng``, ``u`` unused)."""
        x, _ = check_args(inputs, limit, x, rng, u)
        p = x.shape[0]
        pf, beta, pf_form = nan_p(p), nan_p(p), nan_p(p)
        conv, calls = np.zeros(p, bool), 0
        status = np.full(p, "failed", dtype=object)
        kappas = np.full((p, max(inputs.dim - 1, 0)), np.nan)
        cols = periodic_columns(inputs)
        qerr, n_first = nan_p(p), np.zeros(p, int)
        for i in range(p):
            if cols:   # conditional on the phases, integrated over them (:mod:`._periodic`)
                first = [0]
                dp, q = conditional_search(self.form, response, inputs, limit, x[i], cols,
                                           correct=lambda G, d, f=first: self._correct(G, d, f))
                self.form.check(dp, i)
                n_first[i] = first[0]
                calls += dp.calls
                status[i], beta[i], pf[i], qerr[i] = dp.status, dp.beta, q.pf, q.error
                conv[i] = dp.status != "failed"
                continue
            dp = self.form.search(response, inputs, limit, x[i])
            self.form.check(dp, i)
            calls += dp.calls
            status[i] = dp.status
            if dp.status in ("not_reached", "unconverged"):   # FORM's bound; nothing to correct
                beta[i] = dp.beta
                pf[i] = pf_form[i] = special.ndtr(-dp.beta)
                continue
            if not dp.converged:
                continue
            G = LimitStateU(response, inputs, limit, x[i])
            kap = curvatures(G, dp.u_star, dp.alpha, float(np.linalg.norm(dp.grad)),
                             self.hessian_step)
            calls += G.calls
            kappas[i] = kap
            beta[i], pf_form[i] = dp.beta, special.ndtr(-dp.beta)
            pf[i] = sorm_pf(dp.beta, kap, self.formula)
            conv[i] = np.isfinite(pf[i])
            if not conv[i]:
                status[i] = "failed"
                if self.form.on_failure == "raise":
                    raise ModelError(
                        f"SORM is not applicable for design {i}: a curvature factor 1 + psi*kappa"
                        f" <= 0 (beta={dp.beta:.4g}, curvatures={np.round(kap, 4).tolist()})")
        if n_first.any():
            bad = np.flatnonzero(n_first)
            warnings.warn(f"SORM: for design(s) {bad[:10].tolist()} the second-order formula is "
                          f"not applicable at {n_first[bad[:10]].tolist()} phase node(s) "
                          "(1 + psi*kappa <= 0): their first-order value is used",
                          EstimatorWarning, stacklevel=2)
        with np.errstate(divide="ignore"):
            beta_sorm = -special.ndtri(pf)
        status = status.astype(str)
        return make_estimate("sorm", calls, p, pf=pf, diagnostics={
            "beta": beta, "beta_sorm": beta_sorm, "curvatures": kappas, "pf_form": pf_form,
            "converged": conv, "status": status, "pf_bound": bound_labels(beta, status),
            "pf_quadrature_error": qerr, "n_first_order_nodes": n_first,
            "formula": self.formula})

    def _correct(self, G: LimitStateU, dp: Any, first: list) -> float:
        """SORM's P_f at a converged design point of ``G``; FORM's where the second-order
        formula is not applicable (counted in ``first[0]``)."""
        kap = curvatures(G, dp.u_star, dp.alpha, float(np.linalg.norm(dp.grad)),
                         self.hessian_step)
        pf = sorm_pf(dp.beta, kap, self.formula)
        if np.isfinite(pf):
            return pf
        first[0] += 1
        return float(special.ndtr(-dp.beta))
