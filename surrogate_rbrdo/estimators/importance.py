"""Importance sampling at the design points, in two stages, with their FORM hyperplanes as
control variates.

After an iHL-RF search for ``u₁`` and a search for further design points (Der Kiureghian &
Dakessian 1998, :mod:`._design_points`; all counted):

1. **Stage 1** (a share ``pilot`` of the sample): the mixture ``Σ_k π_k φ(v − u_k)``
   (``π_k ∝ Φ(−β_k)``, the weights of multi-point FORM) plus, where it can find something, a
   defensive shell (:mod:`._is_density`). Its tail samples outside every known half-space
   start further design-point searches.
2. **Stage 2** (the rest): at each design point a Gaussian fitted to the stage-1 tail samples in
   the FORM geometry (a mean along ``α_k``, one spread along and one across:
   :class:`~._is_density.ScaledGaussians`, after Bucher 1988), with 20 % of it from the
   stage-1 mixture (defensive). Its estimate and SE are the result: given stage 1 it is a plain
   IS run from a fixed density.

In both stages ``w = φ(v)/q(v)`` and, besides ``Y = w·1[v fails]``, the half-spaces beyond each
design point's hyperplane give controls ``C_k = w·1[u_k·v ≥ ‖u_k‖²]`` with exactly known means
``Φ(−β_k)`` (Rubinstein & Kroese 2017, *Simulation and the Monte Carlo Method*, §5.3):
``P_f = mean(Y − c·(C − Φ(−β)))`` with cross-fitted least-squares ``c``, unbiased for any
failure domain, exact for a union of half-spaces (a series system of limit states linear in
``u``). Under common random numbers the rows of the fixed ``u`` are transformed, never redrawn.

When the mean point lies in the failure domain (FORM's β < 0, P_f > 1/2) the density at ``u*``
covers the *safe* tail and the complement is estimated, ``P_f = 1 − P(safe)`` (weighting the
failures there has a variance of order ``exp(β²)``: at β = −3 a plain IS run of 2000 points
returned 0.46 ± 0.06 for P_f = 0.9987).

**What it cannot see, and says.** Two diagnostics raise an :class:`~._tail.EstimatorWarning`:
more than 20 % of P_f from failures outside every design point's half-space (a failure domain
that bends back towards the mean — concave — or regions the searches missed), and a heavy tail
of the weights (Pareto ``k̂ > 0.7``, :mod:`._tail`). A limit state that FORM finds not reached
(``status = "not_reached"``) is sampled at the last point ``u_b`` of the search for the superset
``{G ≤ G(u_b)}``: ``pf`` then estimates an upper bound of P_f with its own error
(``pf_bound = "upper"``, ``pf_ci = [0, upper end]``). Points outside the model's physical domain
are not failures (:mod:`._common`).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy import special

from surrogate_rbrdo.core.protocols import Estimate, LimitState
from surrogate_rbrdo.core.validate import check_int, check_range
from surrogate_rbrdo.estimators._common import (
    LimitStateU,
    check_args,
    make_estimate,
    nan_p,
    normal_ci,
)
from surrogate_rbrdo.estimators._design_points import design_point_from, design_points
from surrogate_rbrdo.estimators._is_density import (
    MixtureDraws,
    ScaledGaussians,
    cv_estimate,
    shell_share,
)
from surrogate_rbrdo.estimators._tail import EstimatorWarning, pareto_khat
from surrogate_rbrdo.estimators.form import FORM, bound_labels
from surrogate_rbrdo.estimators.registry import ESTIMATORS

#: Pareto k̂ above which the weights' tail makes the standard error unreliable (Vehtari et al.)
KHAT_LIMIT = 0.7
#: share of P_f from failures outside every design point's half-space above which IS reports
#: other failure regions
OTHER_SHARE_LIMIT = 0.2
#: share of the second stage drawn from the first stage's mixture (defensive, Hesterberg 1995)
STAGE2_DEFENSIVE = 0.2
#: searches for further design points started from first-stage samples
DISCOVERY_TRIES = 2


def check_form(value: Any) -> None:
    """Raise unless ``value`` is a :class:`FORM` options object."""
    if not isinstance(value, FORM):
        raise ValueError(f"form = {value!r} is not allowed: must be a FORM(...) options object")


@ESTIMATORS.register("is")
@dataclass(frozen=True)
class ImportanceSampling:
    """Importance sampling at the design points, in two stages, with their FORM hyperplanes as
    control variates.

    ``mean`` and ``std`` of ``y`` are NaN (the sample targets the tail). Diagnostics:
    ``beta_form``, ``u_star`` (the first design point), ``n_design_points``, ``betas`` (all,
    ``(P, n_design_points)``, NaN-padded), ``ess``, ``n_failures``, ``n_disagree`` (samples where
    the failure domain and the union of half-spaces disagree), ``pareto_k``, ``other_share``
    (share of P_f from failures outside every half-space) and ``n_other_failures``,
    ``shell_share``, ``pf_stages`` ``(P, 2)``, ``form_calls`` (searches included), ``status``,
    ``pf_bound`` (as FORM: for ``"upper"``, ``pf`` estimates ``P(G ≤ G(u_b))``, a superset of
    the failure domain, and ``pf_ci = [0, upper end]``), ``n_outside_domain``. ``u`` given:
    its rows are transformed (common random numbers).

    Parameters
    ----------
    n_samples : int
        IS sample size per design (ignored when ``u`` is given).
    ci_level : float
        Level of the normal-approximation interval ``pf ± z·pf_se``.
    form : FORM
        Options of the design-point searches.
    n_design_points : int
        Most design points searched (Der Kiureghian & Dakessian 1998, :mod:`._design_points`);
        1: FORM's only.
    pilot : float
        Share of the sample in the first stage, in [0.1, 1]; 1: one stage at ``N(u_k, I)``
        (plain post-FORM IS with the control variates).
    defensive : float
        Share ``a`` of the first-stage mixture drawn from the shell ``‖v‖ ≥ shell·|β|``, in
        [0, 0.9], where it can find other regions (:func:`~._is_density.shell_share`); 0: never.
    shell : float
        Inner radius of the shell as a fraction of ``|β|``, in (0, 1].

    Examples
    --------
    >>> from surrogate_rbrdo.estimators.problems import paraboloid
    >>> prob = paraboloid(beta=3.0, kappa=0.3, dim=5)
    >>> est = ImportanceSampling(1000).estimate(prob.response, prob.inputs, prob.limit,
    ...                                         prob.x, rng=np.random.default_rng(0))
    >>> bool(abs(est.pf[0] - prob.pf_exact[0]) < 3 * est.pf_se[0]), bool(est.pf_cov[0] < 0.1)
    (True, True)
    """

    n_samples: int = 1000
    ci_level: float = 0.95
    form: FORM = field(default_factory=FORM)
    n_design_points: int = 4
    pilot: float = 0.25
    defensive: float = 0.3
    shell: float = 0.9

    def __post_init__(self) -> None:
        check_int("n_samples", self.n_samples, minimum=4)
        check_range("ci_level", self.ci_level, 0.0, 1.0, inclusive=False)
        check_form(self.form)
        check_int("n_design_points", self.n_design_points, minimum=1)
        check_range("pilot", self.pilot, 0.1, 1.0)
        check_range("defensive", self.defensive, 0.0, 0.9)
        if check_range("shell", self.shell, 0.0, 1.0) == 0.0:
            raise ValueError("shell = 0.0 is not allowed: must lie in (0.0, 1.0]")

    def estimate(self, response: Any, inputs: Any, limit: LimitState, x: np.ndarray, *,
                 rng: np.random.Generator, u: np.ndarray | None = None) -> Estimate:
        """Design-point searches then two-stage control-variate IS, for every design of ``x``."""
        x, u = check_args(inputs, limit, x, rng, u)
        p, m = x.shape[0], inputs.dim
        if u is None:
            u = inputs.standard_sample(self.n_samples, rng=rng)
        out = _Collect(p, m, self.n_design_points)
        for i in range(p):
            G = LimitStateU(response, inputs, limit, x[i])
            dp = self.form.run(G, m)
            self.form.check(dp, i)
            out.status[i] = dp.status
            if dp.status != "failed":
                pts = [dp]
                if dp.status == "converged" and dp.beta >= 0:
                    pts = design_points(G, m, dp, self.form, max_points=self.n_design_points)
                out.form_calls += G.calls
                _Stages(self, G, pts, u).run(out, i)
            else:
                out.form_calls += G.calls
            out.calls += G.calls
        status = out.status.astype(str)
        self._warn(out.diag["pareto_k"], out.diag["other_share"], out.n_other)
        bound = bound_labels(out.beta, status)
        ci = normal_ci(out.pf, out.se, self.ci_level)
        up, lo = bound == "upper", bound == "lower"
        ci[up, 0], ci[lo, 1] = 0.0, 1.0
        return make_estimate(
            "is", out.calls, p, pf=out.pf, pf_se=out.se, pf_ci=ci,
            diagnostics={"ci_level": self.ci_level, "ci_method": "normal",
                         "beta_form": out.beta, "u_star": out.ustar, "betas": out.betas,
                         "n_design_points": out.n_dp, "n_failures": out.nfail,
                         "n_disagree": out.ndis, "form_calls": out.form_calls,
                         "n_samples": u.shape[0], "status": status, "pf_bound": bound,
                         "n_outside_domain": out.nout, "n_other_failures": out.n_other,
                         "pf_stages": out.stages, **out.diag})

    @staticmethod
    def _warn(khat: np.ndarray, share: np.ndarray, nother: np.ndarray) -> None:
        heavy = np.flatnonzero(np.nan_to_num(khat, nan=-np.inf) > KHAT_LIMIT)
        other = np.flatnonzero(np.nan_to_num(share) > OTHER_SHARE_LIMIT)
        if heavy.size:
            warnings.warn(
                f"importance sampling: heavy-tailed weights for design(s) {heavy[:10].tolist()} "
                f"(Pareto k = {np.round(khat[heavy[:10]], 2).tolist()} > {KHAT_LIMIT}): the "
                "failure domain reaches far from the design points, pf_se is unreliable; "
                "use 'ais' or 'subset'", EstimatorWarning, stacklevel=3)
        if other.size:
            warnings.warn(
                f"importance sampling: for design(s) {other[:10].tolist()} "
                f"{np.round(100 * share[other[:10]]).astype(int).tolist()} % of P_f comes from "
                f"{nother[other[:10]].tolist()} failures outside every design point's "
                "half-space: the failure domain has other regions or bends back towards the "
                "mean, pf_se is approximate; use 'ais' or 'subset'",
                EstimatorWarning, stacklevel=3)


class _Stages:
    """The two IS stages for one design (see the module docstring)."""

    def __init__(self, est: ImportanceSampling, G: LimitStateU, pts: list, u: np.ndarray
                 ) -> None:
        self.est, self.G, self.u, self.pts, self.dp = est, G, u, list(pts), pts[0]
        m, n = u.shape[1], u.shape[0]
        beta, centres, shares = _geometry(self.pts)
        a = (0.0 if self.dp.status == "not_reached"      # one region by construction
             else shell_share(est.defensive, est.shell, self.dp.beta, m, n))
        n_shell = int(round(a * n))
        self.two = est.pilot < 1.0 and self.dp.status == "converged"
        self.n1 = n_shell + max(2, int(round(est.pilot * (n - n_shell)))) if self.two else n
        self.two = self.two and n - self.n1 >= 2
        self.q1 = MixtureDraws(centres, shares, est.shell * abs(self.dp.beta),
                               n_shell / self.n1 if self.two else a)
        # the tail beyond the design points: failures when the mean is safe, survivals when it
        # fails; for a limit state not reached, the superset {G <= G(u_b)} ({G >= G(u_b)})
        self.level = self.dp.g_star if self.dp.status == "not_reached" else 0.0

    def _tail(self, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        g = self.G(v)
        if self.dp.status == "not_reached":
            fail = g <= self.level if self.dp.beta >= 0 else g < self.level
        else:
            fail = g < 0
        return (fail if self.dp.beta >= 0 else ~fail), fail

    def _stage(self, v: np.ndarray, logq: Any, pts: list) -> dict:
        beta, c, _ = _geometry(pts)
        tail, fail = self._tail(v)
        logw = -0.5 * np.einsum("ij,ij->i", v, v) - logq(v)
        w_floor = float(np.exp(np.max(-0.5 * np.sum(c * c, axis=1) - logq(c))))
        half = v @ c.T >= np.sum(c * c, axis=1)
        r = cv_estimate(tail, half, logw, beta, w_floor)
        wt = np.where(tail, np.exp(np.where(tail, logw, 0.0)), 0.0)
        outside = ~half.any(axis=1)
        return {"r": r, "v": v, "wt": wt, "fail": fail, "outside": tail & outside,
                "n_other": int(np.sum(tail & outside)),
                "other": wt[outside].sum() / wt.sum() if wt.sum() > 0 else 0.0}

    def _discover(self, s1: dict) -> list:
        """Further design points from the first stage's tail samples outside every known
        half-space (found there by the shell): a search on the deflected function from the
        heaviest of them, then from the mirror image of what it found, while any remain (at
        most ``DISCOVERY_TRIES`` searches from samples: on a failure domain that bends back
        every search ends in a bulge)."""
        pts = list(self.pts)
        if self.dp.status != "converged" or self.dp.beta < 0:
            return pts
        v, wt = s1["v"], s1["wt"]
        tried = np.zeros(v.shape[0], dtype=bool)
        for _ in range(DISCOVERY_TRIES):
            if len(pts) >= self.est.n_design_points:
                break
            c = _geometry(pts)[1]
            left = (wt > 0) & ~(v @ c.T >= np.sum(c * c, axis=1)).any(axis=1) & ~tried
            if not left.any():
                break
            j = np.flatnonzero(left)[np.argmax(wt[left])]
            tried[j] = True
            dp = design_point_from(self.G, v.shape[1], pts, self.est.form, v[j])
            if dp is None:
                continue
            pts.append(dp)
            mirror = design_point_from(self.G, v.shape[1], pts, self.est.form, -dp.u_star)
            if mirror is not None and len(pts) < self.est.n_design_points:
                pts.append(mirror)
        return pts

    def run(self, out: _Collect, i: int) -> None:
        """Fill row ``i`` of ``out``."""
        n_out0 = self.G.n_outside
        v1, comp = self.q1.points(self.u[: self.n1])
        s1 = self._stage(v1, self.q1.logpdf, self.pts)
        stages, pts = [s1], self.pts
        khat = pareto_khat(s1["wt"][comp >= 0])
        if self.two:
            pts = self._discover(s1)
            _, centres, shares = _geometry(pts)
            comp_all = comp if len(pts) == len(self.pts) else np.where(comp >= 0, comp, -1)
            sg = ScaledGaussians.fit(v1, s1["wt"], comp_all, centres, shares)
            u2 = self.u[self.n1:]
            nd = int(round(STAGE2_DEFENSIVE * u2.shape[0]))
            v2 = np.vstack([self.q1.points(u2[:nd])[0], sg.points(u2[nd:])])

            def logq2(v: np.ndarray) -> np.ndarray:
                return np.logaddexp(np.log(STAGE2_DEFENSIVE) + self.q1.logpdf(v),
                                    np.log1p(-STAGE2_DEFENSIVE) + sg.logpdf(v))

            stages.append(self._stage(v2, logq2, pts))
            khat = pareto_khat(stages[1]["wt"])
        # the estimate is the last stage's: given the first stage, the second is a plain IS
        # run from a fixed density (an inverse-variance combination would favour the runs
        # that land low, whose reported errors are small too)
        last = stages[-1]
        out.pf[i] = last["r"].p if self.dp.beta >= 0 else 1.0 - last["r"].p
        out.se[i] = last["r"].se
        out.stages[i, : len(stages)] = [st["r"].p for st in stages]
        out.nfail[i] = sum(int(st["fail"].sum()) for st in stages)
        out.ndis[i] = sum(st["r"].n_disagree for st in stages)
        out.n_other[i] = last["n_other"]
        out.nout[i] = self.G.n_outside - n_out0
        beta = _geometry(pts)[0]
        out.beta[i], out.ustar[i], out.n_dp[i] = self.dp.beta, self.dp.u_star, beta.size
        out.betas[i, : beta.size] = beta
        out.diag["ess"][i] = last["r"].ess
        out.diag["shell_share"][i] = self.q1.a
        out.diag["pareto_k"][i] = khat
        out.diag["other_share"][i] = last["other"]


def _geometry(pts: list) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``β_k = ±‖u_k‖``, centres ``u_k`` and shares ``π_k ∝ Φ(−|β_k|)`` of a list of design
    points (the distance itself, not FORM's β clipped at ``beta_max`` when not reached: the
    half-space at ``u_k`` has probability ``Φ(−‖u_k‖)``)."""
    beta = np.array([np.copysign(np.linalg.norm(q.u_star), q.beta) for q in pts])
    shares = special.ndtr(-np.abs(beta))
    shares = shares / shares.sum() if shares.sum() > 0 else np.full(len(pts), 1 / len(pts))
    return beta, np.array([q.u_star for q in pts]), shares


class _Collect:
    """Per-design results of :class:`ImportanceSampling` (arrays of length P)."""

    def __init__(self, p: int, m: int, k: int) -> None:
        self.pf, self.se, self.beta = nan_p(p), nan_p(p), nan_p(p)
        self.diag = {key: nan_p(p) for key in ("ess", "pareto_k", "other_share",
                                               "shell_share")}
        self.nfail, self.ndis, self.nout = (np.zeros(p, int) for _ in range(3))
        self.n_other, self.n_dp = np.zeros(p, int), np.zeros(p, int)
        self.ustar, self.betas = np.full((p, m), np.nan), np.full((p, k), np.nan)
        self.stages = np.full((p, 2), np.nan)
        self.status = np.full(p, "failed", dtype=object)
        self.calls = self.form_calls = 0
