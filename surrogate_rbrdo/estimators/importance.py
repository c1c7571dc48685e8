"""Importance sampling centred at the FORM design point, with the FORM hyperplane as a control
variate.

After an iHL-RF search for ``u*`` (counted), ``N`` points ``v = u + u*`` are drawn with
``u ~ N(0, I)`` (or the fixed ``u``: common random numbers), weighted by
``w = φ(v)/φ(v − u*) = exp(−u*·v + ‖u*‖²/2)``. Two weighted indicators are formed:
``Y = w·1[v fails]`` (plain IS: ``E[Y] = P_f``) and ``C = w·1[u*·v ≥ ‖u*‖²]``, the half-space
beyond the FORM hyperplane, whose mean is known exactly, ``E[C] = Φ(−β)``. The estimate is the
control-variate one (Rubinstein & Kroese 2017, *Simulation and the Monte Carlo Method*, §5.3):

    P_f = mean(Y) − c (mean(C) − Φ(−β)),   c = cov(Y, C) / var(C),

unbiased (up to the O(1/N) of the estimated ``c``) for any failure domain, with the variance of
``Y − cC``: zero for a limit state that is linear in ``u`` and small when the hyperplane is a good
approximation. ``pf_se`` is the sample standard error of ``Y − cC``; when no sample fell where
the failure domain and the half-space disagree, the unseen disagreement is accounted for by the
floor ``exp(−β²/2)·√(p̃(1 − p̃)/N)`` with ``p̃ = 1/(N + 2)`` (Laplace's rule for an event not
observed in ``N`` trials, weighted by ``w`` on the hyperplane), never by a zero error.

When the mean point lies in the failure domain (FORM's β < 0, P_f > 1/2) the density at ``u*``
covers the *safe* tail, and weighting the failures has a variance of order ``exp(β²)`` (at
β = −3 a plain IS run of 2000 points returned 0.46 ± 0.06 for P_f = 0.9987): there the
complement is estimated, ``P_f = 1 − P(safe)``, with the same half-space as control.

**Other failure regions.** A unit normal at ``u*`` almost never samples a second design point
(a series system, a limit state with two branches): the estimate would miss it with a small
reported error. A fraction ``defensive`` of the sample is therefore drawn from the standard
normal *outside the ball* of radius ``R = shell·|β|`` (a radial "shell": ``φ`` truncated to
``‖v‖ ≥ R``, the region where every design point lies), so that the mixture
``q = (1 − a) φ(v − u*) + a φ(v) 1[‖v‖ ≥ R] / P(χ²_m ≥ R²)`` reaches the other branches and the
weights there are bounded by ``P(χ²_m ≥ R²)/a``. In a few dimensions this turns the misses
into honest (wider) errors; in many dimensions the shell is most of ``φ`` and finds little
(use ``"subset"`` there).
Two diagnostics raise an :class:`~._tail.EstimatorWarning`: more than 20 % of P_f from failures
on the origin's side of the FORM hyperplane (other failure regions, found by the shell: the
error is then that of a handful of hits), and a heavy tail of the main component's failure
weights (Pareto ``k̂ > 0.7``, :mod:`._tail`). When FORM finds the limit state not reached
(``status = "not_reached"``) no sample is drawn and FORM's bound is reported.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy import special, stats

from surrogate_rbrdo.core.protocols import Estimate, LimitState
from surrogate_rbrdo.core.validate import check_int, check_range
from surrogate_rbrdo.estimators._common import (
    LimitStateU,
    check_args,
    make_estimate,
    nan_p,
    normal_ci,
)
from surrogate_rbrdo.estimators._gmm import _ess
from surrogate_rbrdo.estimators._tail import EstimatorWarning, pareto_khat
from surrogate_rbrdo.estimators.form import FORM, bound_interval
from surrogate_rbrdo.estimators.registry import ESTIMATORS

#: Pareto k̂ above which the weights' tail makes the standard error unreliable (Vehtari et al.)
KHAT_LIMIT = 0.7
#: share of P_f from the origin's side of the FORM hyperplane above which IS reports other
#: failure regions
OTHER_SHARE_LIMIT = 0.2


def is_weights_estimate(fail: np.ndarray, logw: np.ndarray) -> tuple[float, float, float]:
    """``(pf, se, ess)`` from failure indicators and log-weights of a plain IS sample."""
    n = fail.size
    w = np.where(fail, np.exp(np.where(fail, logw, 0.0)), 0.0)
    pf = float(w.mean())
    se = float(w.std(ddof=1) / np.sqrt(n)) if n > 1 else np.nan
    return pf, se, _ess(w)


@dataclass(frozen=True)
class ControlVariateResult:
    """Control-variate IS estimate of a tail probability and its diagnostics."""

    p: float
    se: float
    coef: float
    ess: float
    khat: float
    n_disagree: int


def cv_estimate(tail: np.ndarray, half: np.ndarray, logw: np.ndarray, beta: float
                ) -> ControlVariateResult:
    """P(tail) by IS with the half-space indicator ``half`` (known mean ``Φ(−|β|)``) as control.

    >>> rng = np.random.default_rng(0)
    >>> ustar = np.array([3.0, 0.0])
    >>> v = rng.standard_normal((500, 2)) + ustar
    >>> logw = -v @ ustar + 0.5 * ustar @ ustar
    >>> half = v @ ustar >= ustar @ ustar
    >>> r = cv_estimate(half.copy(), half, logw, 3.0)      # a linear limit state: exact
    >>> bool(np.isclose(r.p, special.ndtr(-3.0))), r.n_disagree, bool(0 < r.se / r.p < 0.02)
    (True, 0, True)
    """
    n = tail.size
    w = np.exp(logw)
    y = np.where(tail, w, 0.0)
    c = np.where(half, w, 0.0)
    p_half = float(special.ndtr(-abs(beta)))
    vc = float(c.var(ddof=1)) if n > 1 else 0.0
    coef = float(np.cov(y, c, ddof=1)[0, 1] / vc) if vc > 0 else 0.0
    r = y - coef * (c - p_half)
    p = float(r.mean())
    se = float(r.std(ddof=1) / np.sqrt(n)) if n > 1 else np.nan
    p_tilde = 1.0 / (n + 2.0)
    floor = float(np.exp(-0.5 * beta * beta) * np.sqrt(p_tilde * (1.0 - p_tilde) / n))
    return ControlVariateResult(min(max(p, 0.0), 1.0), max(se, floor), coef, _ess(y),
                                pareto_khat(y), int(np.count_nonzero(tail != half)))


def check_form(value: Any) -> None:
    """Raise unless ``value`` is a :class:`FORM` options object."""
    if not isinstance(value, FORM):
        raise ValueError(f"form = {value!r} is not allowed: must be a FORM(...) options object")


@dataclass(frozen=True)
class ShellDraws:
    """The defensive shell component's share of a standard-normal sample ``u`` (no new draws:
    the estimate stays a function of ``u``, common random numbers across designs).

    The first ``round(a·N)`` rows are the shell's (a deterministic mixture: exactly that many
    from the shell and the rest from ``N(u*, I)``, all weighted by the full mixture density;
    unbiased, Owen & Zhou 2000). Each shell row keeps its direction ``u/‖u‖`` and its radius
    quantile ``q = P(χ²_m ≥ ‖u‖²)``, uniform and independent of the direction.
    """

    pick: np.ndarray
    direction: np.ndarray
    q: np.ndarray

    @classmethod
    def from_sample(cls, u: np.ndarray, a: float) -> ShellDraws:
        n, m = u.shape
        r2 = np.einsum("ij,ij->i", u, u)
        norm = np.sqrt(r2)[:, None]
        pick = np.arange(n) < int(round(a * n))
        return cls(pick, u / np.where(norm > 0, norm, 1.0), stats.chi2.sf(r2, m))

    def points(self, u: np.ndarray, ustar: np.ndarray, radius: float, a: float
               ) -> tuple[np.ndarray, np.ndarray]:
        """The mixture sample ``v`` and its log-weights ``log φ(v) − log q(v)``."""
        m = u.shape[1]
        s_r = float(stats.chi2.sf(radius**2, m))
        r = np.sqrt(stats.chi2.isf(self.q * s_r, m))
        v = np.where(self.pick[:, None], r[:, None] * self.direction, u + ustar)
        lphi = -0.5 * np.einsum("ij,ij->i", v, v)
        lmain = -0.5 * np.einsum("ij,ij->i", v - ustar, v - ustar)
        if a <= 0:
            return v, lphi - lmain
        with np.errstate(divide="ignore"):
            lshell = np.where(np.linalg.norm(v, axis=1) >= radius, lphi - np.log(s_r), -np.inf)
        return v, lphi - np.logaddexp(np.log1p(-a) + lmain, np.log(a) + lshell)


@ESTIMATORS.register("is")
@dataclass(frozen=True)
class ImportanceSampling:
    """Importance sampling at the FORM design point with the FORM hyperplane as control variate.

    ``mean`` and ``std`` of ``y`` are NaN (the sample targets the tail). Diagnostics:
    ``beta_form``, ``u_star``, ``ess`` (effective sample size of the failure weights),
    ``n_failures``, ``n_disagree`` (samples where the failure domain and the FORM half-space
    disagree), ``cv_coef``, ``pareto_k`` (tail of the failure weights of the main component),
    ``other_share`` (share of P_f from the origin's side of the FORM hyperplane) and
    ``n_other_failures``, ``form_calls``,
    ``status`` and ``pf_bound`` (as FORM), ``n_outside_domain``. ``u`` given: its rows are
    shifted to ``u*``.

    Parameters
    ----------
    n_samples : int
        IS sample size per design (ignored when ``u`` is given).
    ci_level : float
        Level of the normal-approximation interval ``pf ± z·pf_se``.
    form : FORM
        Options of the design-point search.
    defensive : float
        Share ``a`` of the sample drawn from the shell ``‖v‖ ≥ shell·|β|``, in [0, 0.9]
        (0: plain IS at ``u*``).
    shell : float
        Inner radius of the shell as a fraction of ``|β|``, in (0, 1].

    Examples
    --------
    >>> from surrogate_rbrdo.estimators.problems import paraboloid
    >>> prob = paraboloid(beta=3.0, kappa=0.3, dim=5)      # curved: the control helps little
    >>> est = ImportanceSampling(1000).estimate(prob.response, prob.inputs, prob.limit,
    ...                                         prob.x, rng=np.random.default_rng(0))
    >>> bool(abs(est.pf[0] - prob.pf_exact[0]) < 3 * est.pf_se[0]), bool(est.pf_cov[0] < 0.15)
    (True, True)
    """

    n_samples: int = 1000
    ci_level: float = 0.95
    form: FORM = field(default_factory=FORM)
    defensive: float = 0.3
    shell: float = 0.9

    def __post_init__(self) -> None:
        check_int("n_samples", self.n_samples, minimum=2)
        check_range("ci_level", self.ci_level, 0.0, 1.0, inclusive=False)
        check_form(self.form)
        check_range("defensive", self.defensive, 0.0, 0.9)
        if check_range("shell", self.shell, 0.0, 1.0) == 0.0:
            raise ValueError("shell = 0.0 is not allowed: must lie in (0.0, 1.0]")

    def estimate(self, response: Any, inputs: Any, limit: LimitState, x: np.ndarray, *,
                 rng: np.random.Generator, u: np.ndarray | None = None) -> Estimate:
        """Design-point search then control-variate IS, for every design of ``x``."""
        x, u = check_args(inputs, limit, x, rng, u)
        p, m = x.shape[0], inputs.dim
        if u is None:
            u = inputs.standard_sample(self.n_samples, rng=rng)
        shell = ShellDraws.from_sample(u, self.defensive)
        pf, se, beta = nan_p(p), nan_p(p), nan_p(p)
        diag = {k: nan_p(p) for k in ("ess", "cv_coef", "pareto_k", "other_share")}
        nfail, ndis, nout = np.zeros(p, int), np.zeros(p, int), np.zeros(p, int)
        nother = np.zeros(p, int)
        ustar, status = np.full((p, m), np.nan), np.full(p, "failed", dtype=object)
        calls = form_calls = 0
        for i in range(p):
            dp = self.form.search(response, inputs, limit, x[i])
            self.form.check(dp, i)
            form_calls += dp.calls
            calls += dp.calls
            status[i] = dp.status
            if dp.status == "failed":
                continue
            beta[i], ustar[i] = dp.beta, dp.u_star
            if dp.status == "not_reached":
                pf[i] = special.ndtr(-dp.beta)
                continue
            G = LimitStateU(response, inputs, limit, x[i])
            v, logw = shell.points(u, dp.u_star, self.shell * abs(dp.beta), self.defensive)
            fail = G(v) < 0
            calls += G.calls
            nout[i] = G.n_outside
            half = v @ dp.u_star >= dp.u_star @ dp.u_star
            # the tail beyond u*: failures when the mean is safe, survivals when it fails
            tail = fail if dp.beta >= 0 else ~fail
            r = cv_estimate(tail, half, logw, dp.beta)
            pf[i] = r.p if dp.beta >= 0 else 1.0 - r.p
            se[i], nfail[i], ndis[i] = r.se, int(fail.sum()), r.n_disagree
            diag["ess"][i], diag["cv_coef"][i] = r.ess, r.coef
            wt = np.where(tail, np.exp(np.where(tail, logw, 0.0)), 0.0)
            diag["pareto_k"][i] = pareto_khat(wt[~shell.pick])
            # tail samples on the origin's side of the FORM hyperplane: other failure regions
            diag["other_share"][i] = wt[~half].sum() / wt.sum() if wt.sum() > 0 else 0.0
            nother[i] = int(np.count_nonzero(tail & ~half))
        status = status.astype(str)
        self._warn(diag["pareto_k"], diag["other_share"], nother)
        bound, ci_b = bound_interval(pf, beta, status)
        ci = np.where((status == "not_reached")[:, None], ci_b, normal_ci(pf, se, self.ci_level))
        return make_estimate(
            "is", calls, p, pf=pf, pf_se=se, pf_ci=ci,
            diagnostics={"ci_level": self.ci_level, "ci_method": "normal", "beta_form": beta,
                         "u_star": ustar, "n_failures": nfail, "n_disagree": ndis,
                         "form_calls": form_calls, "n_samples": u.shape[0], "status": status,
                         "pf_bound": bound, "n_outside_domain": nout,
                         "n_other_failures": nother, **diag},
        )

    @staticmethod
    def _warn(khat: np.ndarray, share: np.ndarray, nother: np.ndarray) -> None:
        heavy = np.flatnonzero(np.nan_to_num(khat, nan=-np.inf) > KHAT_LIMIT)
        other = np.flatnonzero(np.nan_to_num(share) > OTHER_SHARE_LIMIT)
        if heavy.size:
            warnings.warn(
                f"importance sampling: heavy-tailed weights for design(s) {heavy[:10].tolist()} "
                f"(Pareto k = {np.round(khat[heavy[:10]], 2).tolist()} > {KHAT_LIMIT}): the "
                "failure domain reaches far from the FORM design point, pf_se is unreliable; "
                "use 'ais' or 'subset'", EstimatorWarning, stacklevel=3)
        if other.size:
            warnings.warn(
                f"importance sampling: for design(s) {other[:10].tolist()} "
                f"{np.round(100 * share[other[:10]]).astype(int).tolist()} % of P_f comes from "
                f"{nother[other[:10]].tolist()} failures on the origin's side of the FORM "
                "hyperplane: the failure domain has other regions (several design points) or "
                "bends back towards the mean, pf_se is approximate; use 'ais' or 'subset'",
                EstimatorWarning, stacklevel=3)
