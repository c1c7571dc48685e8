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

When the mean point lies in the failure domain (FORM's β < 0, P_f > 1/2) the *safe* set is the
tail: everything above runs on ``−G`` (:class:`~._is_stages.Negated`; its failure domain is the
safe set, with all its design points and the discovery searches) and ``P_f = 1 − P(safe)``
(weighting the failures instead has a variance of order ``exp(β²)``: at β = −3 a plain IS run of
2000 points returned 0.46 ± 0.06 for P_f = 0.9987; with the first safe design point only, a safe
set of two slivers ``|a·u| > 4.5`` gave half of ``1 − P_f`` with a 0.7 % error).

**What it cannot see, and says.** A failure branch that no search finds and that the first
stage never samples below the known tangent planes (:func:`~._is_stages.unexplained`) is not
sampled. One search after sampling, from the second-stage sample nearest failure among those
below every tangent plane, looks for it; a relevant design point found then raises an
:class:`~._tail.EstimatorWarning` (``late_beta``; the estimate is not corrected: on the oblique
three-branch system, ``problems.series_oblique``, with a hidden branch of 3 % of P_f, 8 of 40
runs warned, none was silently low). Two more diagnostics raise one:
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
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
from scipy import special

from surrogate_rbrdo.core.protocols import Estimate, LimitState
from surrogate_rbrdo.core.validate import check_int, check_range
from surrogate_rbrdo.estimators._common import (
    LimitStateU,
    check_args,
    make_estimate,
    normal_ci,
)
from surrogate_rbrdo.estimators._design_points import design_points
from surrogate_rbrdo.estimators._is_density import is_weights_estimate
from surrogate_rbrdo.estimators._is_stages import Collect, Negated, Stages, complement, negated
from surrogate_rbrdo.estimators._periodic import Conditioned, Stratum, cells, lift, periodic_columns
from surrogate_rbrdo.estimators._tail import EstimatorWarning
from surrogate_rbrdo.estimators.form import FORM, bound_labels
from surrogate_rbrdo.estimators.registry import ESTIMATORS

#: Pareto k̂ above which the weights' tail makes the standard error unreliable (Vehtari et al.)
KHAT_LIMIT = 0.7
#: share of P_f from failures outside every design point's half-space above which IS reports
#: other failure regions
OTHER_SHARE_LIMIT = 0.2


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
    ``late_beta`` (β of a relevant design point a search from a second-stage sample below every
    tangent plane found after sampling — the density left out its branch, and IS warns; NaN if
    none),
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
    phase_strata : int
        With periodic inputs (phases, ``Uniform(..., periodic=True)``): cells per phase of the
        stratified estimate (:mod:`._periodic`): in each, the two stages at the design points
        of a search conditional on the cell's centre phase, the phase uniform in the cell;
        ``pf`` is the mean over the cells and ``pf_se`` their combined error.

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
    phase_strata: int = 8

    def __post_init__(self) -> None:
        check_int("n_samples", self.n_samples, minimum=4)
        check_range("ci_level", self.ci_level, 0.0, 1.0, inclusive=False)
        check_form(self.form)
        check_int("n_design_points", self.n_design_points, minimum=1)
        check_range("pilot", self.pilot, 0.1, 1.0)
        check_range("defensive", self.defensive, 0.0, 0.9)
        if check_range("shell", self.shell, 0.0, 1.0) == 0.0:
            raise ValueError("shell = 0.0 is not allowed: must lie in (0.0, 1.0]")
        check_int("phase_strata", self.phase_strata, minimum=1)

    def estimate(self, response: Any, inputs: Any, limit: LimitState, x: np.ndarray, *,
                 rng: np.random.Generator, u: np.ndarray | None = None) -> Estimate:
        """Design-point searches then two-stage control-variate IS, for every design of ``x``."""
        x, u = check_args(inputs, limit, x, rng, u)
        p, m = x.shape[0], inputs.dim
        if u is None:
            u = inputs.standard_sample(self.n_samples, rng=rng)
        out = Collect(p, m, self.n_design_points)
        cols = periodic_columns(inputs)
        n_cells = self.phase_strata ** len(cols)
        if cols and u.shape[0] < 4 * n_cells:
            raise ValueError(f"n_samples = {u.shape[0]} is not allowed with {len(cols)} periodic "
                             f"input(s): need >= 4 per phase stratum ({4 * n_cells})")
        for i in range(p):
            if cols:
                self._stratified(response, inputs, limit, x[i], cols, u, out, i)
                continue
            G = LimitStateU(response, inputs, limit, x[i])
            dp = self.form.run(G, m)
            self.form.check(dp, i)
            # a design point not found to tolerance still centres the density: the IS estimate
            # does not depend on it being exact ("unconverged" bounds FORM's value, not IS's)
            out.status[i] = "converged" if dp.status == "unconverged" else dp.status
            if dp.status != "failed":
                Gt, pts = self._points(G, m, dp)
                out.form_calls += G.calls
                Stages(self, Gt, pts, u).run(out, i)
                if Gt is not G:
                    complement(out, i, u.shape[0])
            else:
                out.form_calls += G.calls
            out.calls += G.calls
        status = out.status.astype(str)
        self._warn(out.diag["pareto_k"], out.diag["other_share"], out.n_other)
        self._warn_late(out.diag["late_beta"])
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

    def _stratified(self, response: Any, inputs: Any, limit: LimitState, x_row: np.ndarray,
                    cols: tuple, u: np.ndarray, out: Collect, i: int) -> None:
        """Row ``i`` of ``out`` by stratified IS over the phase cells (:mod:`._periodic`): in
        each cell the two stages at the design points of a search conditional on the cell's
        centre phase, the phase drawn uniformly in the cell; the rows of ``u`` are split among
        the cells in order."""
        m, cs = inputs.dim, cells(cols, self.phase_strata)
        n_k = u.shape[0] // len(cs)
        sub = Collect(len(cs), m, self.n_design_points)
        n_mc = 0
        flipped = np.zeros(len(cs), dtype=bool)     # cells whose tail is the safe set
        lo = np.array([c[1] for c in cols])
        span = np.array([c[2] - c[1] for c in cols])
        for k, (a, b) in enumerate(cs):
            cond = Conditioned(inputs, cols, lo + span * 0.5 * (a + b))
            Gc = LimitStateU(response, cond, limit, x_row)
            dp = self.form.run(Gc, cond.dim)
            Gct, pts = self._points(Gc, cond.dim, dp)
            G = LimitStateU(response, Stratum(inputs, cols, a, b), limit, x_row)
            sub.status[k] = ("converged" if dp.status in ("failed", "unconverged")
                             else dp.status)
            if dp.status != "failed":
                pts = [replace(q, u_star=lift(q.u_star, cond.keep, m),
                               alpha=lift(q.alpha, cond.keep, m),
                               grad=lift(q.grad, cond.keep, m)) for q in pts]
                Gt = G if Gct is Gc else Negated(G)
                Stages(self, Gt, pts, u[k * n_k:(k + 1) * n_k]).run(sub, k)
                if Gt is not G:
                    complement(sub, k, n_k)
                    flipped[k] = True
            else:   # no design point: the cell's own distribution (crude MC in the cell)
                fail = G(u[k * n_k:(k + 1) * n_k]) < 0
                sub.pf[k], sub.se[k], sub.diag["ess"][k] = is_weights_estimate(
                    fail, np.zeros(fail.size))
                sub.nfail[k], n_mc = int(fail.sum()), n_mc + 1
            out.form_calls += Gc.calls
            out.calls += Gc.calls + G.calls
        st = set(sub.status.tolist())
        out.status[i] = ("failed" if "failed" in st else
                         "converged" if st == {"converged"} else "not_reached")
        out.pf[i] = float(np.mean(sub.pf))
        out.se[i] = float(np.sqrt(np.sum(sub.se**2))) / len(cs)
        with np.errstate(invalid="ignore", divide="ignore"):
            out.beta[i] = -special.ndtri(out.pf[i])
        j = int(np.nanargmax(sub.pf)) if np.isfinite(sub.pf).any() else 0
        out.ustar[i] = lift(sub.ustar[j][cond.keep], cond.keep, m, np.nan)
        out.betas[i], out.n_dp[i] = sub.betas[j], sub.n_dp[j]
        out.stages[i] = np.mean(sub.stages, axis=0)
        for name in ("nfail", "ndis", "nout", "n_other"):
            getattr(out, name)[i] = int(getattr(sub, name).sum())
        # diagnostics weighted by each cell's share of the sampled tail (1 - P_f where the mean
        # fails: weighting by P_f ~ 1 hid a cell carrying 65 % of 1 - P_f at a credible design)
        tail = np.where(flipped, 1.0 - sub.pf, sub.pf)
        w = tail / tail.sum() if tail.sum() > 0 else np.full(len(cs), 1 / len(cs))
        out.diag["ess"][i] = float(np.sum(sub.diag["ess"]))
        out.diag["pareto_k"][i] = float(np.nanmax(sub.diag["pareto_k"], initial=-np.inf))
        out.diag["other_share"][i] = float(np.nansum(w * sub.diag["other_share"]))
        late = sub.diag["late_beta"]
        out.diag["late_beta"][i] = float(np.nanmin(late)) if np.isfinite(late).any() else np.nan
        out.diag["shell_share"][i] = float(np.nanmean(sub.diag["shell_share"]))
        out.diag["n_mc_strata"][i] = n_mc

    def _points(self, G: Any, m: int, dp: Any) -> tuple[Any, list]:
        """The function whose tail IS samples and its design points: ``G`` and its points when
        the mean is safe; when it fails (converged, ``β < 0``) the safe set is the tail, so
        ``−G`` (:class:`Negated`) and the design points of the safe set, searched like those of
        a failure domain (a safe set of several slivers: one per point)."""
        if dp.status != "converged":
            return G, [dp]
        Gt, first = (G, dp) if dp.beta >= 0 else (Negated(G), negated(dp))
        return Gt, design_points(Gt, m, first, self.form, max_points=self.n_design_points)

    @staticmethod
    def _warn_late(late: np.ndarray) -> None:
        found = np.flatnonzero(np.isfinite(late))
        if found.size:
            warnings.warn(
                f"importance sampling: for design(s) {found[:10].tolist()} a design point "
                f"(beta = {np.round(np.abs(late[found[:10]]), 2).tolist()}) was found after "
                "sampling, below every sampled design point's tangent plane: the sampling "
                "density left out a failure branch and pf may be low by up to Phi(-beta); "
                "use 'ais' or 'subset'", EstimatorWarning, stacklevel=3)

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
                f"{np.round(100 * share[other[:10]]).astype(int).tolist()} % of P_f (of 1 - P_f "
                "where the mean fails) comes from "
                f"{nother[other[:10]].tolist()} failures outside every design point's "
                "half-space: the failure domain has other regions or bends back towards the "
                "mean, pf_se is approximate; use 'ais' or 'subset'",
                EstimatorWarning, stacklevel=3)


