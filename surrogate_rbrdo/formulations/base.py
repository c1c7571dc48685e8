"""The formulation machinery: a population ``x (P, d)`` → objectives ``F``, constraints ``G``.

A :class:`Formulation` owns one fixed standard-normal sample ``u`` (common random numbers):
drawn once by :func:`make_formulation` from the caller's Generator, mapped through the random
vector to ``theta = inputs.from_standard(u)`` and reused for every design and generation, so the
objectives are deterministic functions of ``x`` and formulations built from equal generators see
identical θ.

Constraint columns, all feasible where ``<= 0``, in this order:

1. reliability (``rbdo``, ``rbrdo``): ``P_f ≤ P_target`` for the primary limit state, then one
   column per extra :class:`ReliabilityConstraint` (same ``P_target``), written as
   ``options.reliability_measure`` says (:mod:`~.reliability`: ``P_f/P_target − 1`` by default);
2. deterministic: ``g_det`` from :class:`~.deterministic.DeterministicConstraints`;
3. generic design constraints ``g(x) <= 0`` (:class:`~.constraints.DesignConstraint`).

Points outside the model's physical domain (``OutsideDomainError``) are not failures, and μ_y,
σ_y are those of the points inside (:func:`~surrogate_rbrdo.estimators.mc_with_outside`, the
meaning every estimator uses); an :class:`~surrogate_rbrdo.estimators.EstimatorWarning` says
when the common sample has any.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace
from typing import Any, ClassVar

import numpy as np

from surrogate_rbrdo.core.errors import ModelError
from surrogate_rbrdo.core.protocols import Estimate, LimitState, Response
from surrogate_rbrdo.core.registry import Registry
from surrogate_rbrdo.core.rng import require_rng
from surrogate_rbrdo.estimators import evaluate_in_domain, get_estimator, mc_with_outside
from surrogate_rbrdo.estimators.mc import warn_outside
from surrogate_rbrdo.formulations.constraints import DesignConstraint, constraint_matrix
from surrogate_rbrdo.formulations.deterministic import DeterministicConstraints
from surrogate_rbrdo.formulations.options import FormulationOptions
from surrogate_rbrdo.formulations.reliability import reliability_column

FORMULATIONS = Registry("formulation")
_NO_FAILURE = LimitState(0.0)  # placeholder when no limit is given; its P_f is discarded


@dataclass(frozen=True, eq=False)
class ReliabilityConstraint:
    """An extra chance constraint ``P(limit fails on response) <= P_target``."""

    response: Response
    limit: LimitState
    name: str = "reliability"


@dataclass(frozen=True, eq=False)
class Evaluation:
    """Result of evaluating one population.

    Attributes
    ----------
    F : ndarray, shape (P, n_obj)
    G : ndarray, shape (P, n_con)
        Feasible where every entry is ``<= 0``.
    estimate : Estimate
        μ_y, σ_y, P_f of the primary response on the fixed sample (the deterministic
        formulation records the nominal value as ``mean`` and NaN elsewhere).
    n_surrogate_calls : int
        (x, θ) points evaluated by the response(s).
    n_model_calls : int
        Designs passed to the deterministic (FE) model.
    """

    F: np.ndarray
    G: np.ndarray
    estimate: Estimate
    n_surrogate_calls: int
    n_model_calls: int


@dataclass(frozen=True, eq=False)
class Formulation:
    """Base class; concrete strategies are registered in :data:`FORMULATIONS`.

    Build instances with :func:`make_formulation` (it draws the CRN sample); the constructor
    only stores arguments.
    """

    response: Response
    inputs: Any
    limit: LimitState | None
    u: np.ndarray
    options: FormulationOptions = field(default_factory=FormulationOptions)
    constraints_det: DeterministicConstraints | None = None
    extra_reliability: tuple[ReliabilityConstraint, ...] = ()
    estimator: Any = None
    estimator_seed: int = 0
    design_constraints: tuple[DesignConstraint, ...] = ()
    design_theta: np.ndarray | None = None
    _theta: np.ndarray = field(init=False, repr=False)
    _theta_nominal: np.ndarray = field(init=False, repr=False)

    name: ClassVar[str] = "base"
    objective_names: ClassVar[tuple[str, ...]] = ()
    reliability: ClassVar[bool] = False
    nominal_only: ClassVar[bool] = False

    def __post_init__(self) -> None:
        # map the CRN sample once; the same read-only array object is passed to the response on
        # every call, so a response may cache work keyed on it (e.g. a surrogate's θ block)
        theta = np.array(self.inputs.from_standard(self.u), dtype=float)
        theta.flags.writeable = False
        object.__setattr__(self, "_theta", theta)
        nominal = (self.inputs.from_standard(np.zeros((1, self.u.shape[1])))
                   if self.design_theta is None else self.design_theta)
        nominal = np.array(nominal, dtype=float)
        if nominal.ndim != 2 or nominal.shape[1] != theta.shape[1] or nominal.shape[0] < 1 \
                or not np.all(np.isfinite(nominal)):
            raise ValueError(f"design_theta has shape {nominal.shape}: must be finite (k >= 1, "
                             f"{theta.shape[1]}), one θ row per design case")
        nominal.flags.writeable = False
        object.__setattr__(self, "_theta_nominal", nominal)

    # ------------------------------------------------------------------ shape information
    @property
    def theta(self) -> np.ndarray:
        """The fixed θ sample, shape ``(N, m)``, read-only; the same object on every access."""
        return self._theta

    @property
    def theta_nominal(self) -> np.ndarray:
        """The design-basis θ rows ``(k, m)`` of the deterministic formulation: ``design_theta``
        if given (e.g. a problem's stated unbalance cases), else the image of ``u = 0`` (the
        mean for a Gaussian; ``k = 1``); read-only, the same object on every access (so a
        θ-block cache hits)."""
        return self._theta_nominal

    @property
    def constraint_names(self) -> tuple[str, ...]:
        names: tuple[str, ...] = ()
        if self.reliability:
            names += ("pf",) if self.limit is not None else ()
            names += tuple(f"pf_{c.name}" for c in self.extra_reliability)
        if self.constraints_det is not None:
            names += self.constraints_det.names
        return names + tuple(c.name for c in self.design_constraints)

    @property
    def n_obj(self) -> int:
        return len(self.objective_names)

    @property
    def n_con(self) -> int:
        return len(self.constraint_names)

    # ------------------------------------------------------------------ evaluation
    def estimate(self, x: np.ndarray, response: Response | None = None,
                 limit: LimitState | None = None) -> Estimate:
        """μ_y, σ_y, P_f of ``response`` (default: the primary one) on the fixed sample."""
        return self._estimate_values(x, response, limit)[0]

    def _estimate_values(self, x: np.ndarray, response: Response | None = None,
                         limit: LimitState | None = None) -> tuple[Estimate, np.ndarray | None]:
        """The estimate and, on the fast path, the responses ``(P, N)`` on the fixed sample."""
        response = self.response if response is None else response
        limit = self.limit if limit is None else limit
        no_limit = limit is None
        limit = _NO_FAILURE if no_limit else limit
        values = None
        if self.estimator is None or no_limit:  # values on the CRN sample (no P_f needed)
            values, _, _ = evaluate_in_domain(response, x, self.theta)
            est = mc_with_outside(values, limit, ci_level=self.options.ci_level)
            warn_outside(est.diagnostics["n_outside_domain"], values.shape[1],
                         f"formulation {self.name!r}")
        else:
            est = self.estimator.estimate(
                response, self.inputs, limit, x,
                rng=np.random.default_rng(self.estimator_seed), u=self.u,
            )
        if no_limit:  # no failure definition: P_f is not defined
            nan = np.full(np.shape(est.mean), np.nan)
            est = replace(est, pf=nan, pf_se=nan, pf_ci=np.full((nan.size, 2), np.nan))
        return est, values

    def _nominal(self, x: np.ndarray) -> Estimate:
        # the worst of the stated design cases (one case: the nominal response itself)
        values = np.asarray(self.response(x, self.theta_nominal), dtype=float)
        y = values.max(axis=1)
        nan = np.full_like(y, np.nan)
        return Estimate(mean=y, std=nan, pf=nan, mean_se=nan, std_se=nan, pf_se=nan,
                        pf_ci=np.full((y.size, 2), np.nan), n_calls=int(values.size),
                        method="nominal", diagnostics={})

    def assess(self, x: np.ndarray) -> Estimate:
        """Full-sample estimate of the primary response for any formulation (for tables)."""
        return self.estimate(_as_2d(x))

    def evaluate(self, x: np.ndarray) -> Evaluation:
        """Evaluate a population ``x`` of shape ``(P, d)``."""
        x = _as_2d(x)
        est, values = (self._nominal(x), None) if self.nominal_only else self._estimate_values(x)
        n_sur = int(est.n_calls)
        if not self.nominal_only and self.estimator is not None and (
                not np.all(np.isfinite(est.mean)) or not np.all(np.isfinite(est.std))):
            # reliability-only estimators (FORM, SORM, IS) give no moments: take μ_y, σ_y from
            # the CRN sample and keep the estimator's P_f
            y, _, _ = evaluate_in_domain(self.response, x, self.theta)
            mc = mc_with_outside(y, _NO_FAILURE, ci_level=self.options.ci_level)
            warn_outside(mc.diagnostics["n_outside_domain"], y.shape[1],
                         f"formulation {self.name!r}")
            n_sur += int(mc.n_calls)
            est = replace(est, mean=mc.mean, std=mc.std, mean_se=mc.mean_se, std_se=mc.std_se,
                          diagnostics={**est.diagnostics, "moments_from": "mc"})
        cols = []
        if self.reliability:
            if self.limit is not None:
                cols.append(self._reliability(est, values, self.limit))
            for c in self.extra_reliability:
                e, v = self._estimate_values(x, c.response, c.limit)
                n_sur += int(e.n_calls)
                cols.append(self._reliability(e, v, c.limit))
        n_model = 0
        if self.constraints_det is not None and self.constraints_det.names:
            gd = self.constraints_det(x)
            n_model = x.shape[0]
            cols.extend(gd.T)
        cols.extend(constraint_matrix(self.design_constraints, x).T)
        G = np.column_stack(cols) if cols else np.empty((x.shape[0], 0))
        F = self._objectives(est)
        bad = ~(np.all(np.isfinite(F), axis=1) & np.all(np.isfinite(G), axis=1))
        if bad.any():
            i = int(np.flatnonzero(bad)[0])
            raise ModelError(f"formulation {self.name!r} ({est.method}) gave non-finite "
                             f"F={F[i].tolist()}, G={G[i].tolist()} at x={x[i].tolist()}")
        return Evaluation(F=F, G=G, estimate=est, n_surrogate_calls=n_sur,
                          n_model_calls=n_model)

    def _reliability(self, est: Estimate, values: np.ndarray | None,
                     limit: LimitState) -> np.ndarray:
        o = self.options
        return reliability_column(o.reliability_measure, o.pf_bound, est, values, limit,
                                  o.p_target, o.ci_level)

    def _objectives(self, est: Estimate) -> np.ndarray:
        """The columns named by ``objective_names`` ("nominal"/"mean": μ_y, "std": σ_y)."""
        cols = {"nominal": est.mean, "mean": est.mean, "std": est.std}
        return np.column_stack([cols[n] for n in self.objective_names]).astype(float)

    def describe(self) -> dict[str, Any]:
        """Plain description for run metadata."""
        return {"formulation": self.name, "objectives": list(self.objective_names),
                "constraints": list(self.constraint_names),
                "p_target": self.options.p_target if self.reliability else None,
                "n_theta": int(self.u.shape[0]), "estimator": self.options.estimator,
                "reliability_measure": self.options.reliability_measure,
                "pf_bound": self.options.pf_bound,
                "design_constraints": {c.name: c.expression or "python callable"
                                       for c in self.design_constraints}}


def _as_2d(x: np.ndarray) -> np.ndarray:
    x = np.asarray(x, dtype=float)
    if x.ndim != 2:
        raise ValueError(f"x has shape {x.shape}: must be 2-dimensional (P, d)")
    return x


def make_formulation(
    name: str,
    *,
    response: Response,
    inputs: Any,
    limit: LimitState | None,
    rng: np.random.Generator,
    options: FormulationOptions | None = None,
    deterministic: Callable[[np.ndarray], Mapping[str, np.ndarray]] | None = None,
    extra_reliability: tuple[ReliabilityConstraint, ...] = (),
    constraints: tuple[DesignConstraint, ...] = (),
    design_theta: np.ndarray | None = None,
) -> Formulation:
    """Build a registered formulation and draw its common-random-number sample.

    All names and options are checked before ``rng`` is touched. Formulations built from
    generators in the same state see the same θ sample (common random numbers).

    Parameters
    ----------
    name : str
        ``"deterministic"``, ``"rdo"``, ``"rbdo"`` or ``"rbrdo"`` (see :data:`FORMULATIONS`).
    response : Response
        ``y(x (P, d), theta (N, m)) -> (P, N)`` (the surrogate, or any analytic model).
    inputs : random vector
        Has ``.dim``, ``.standard_sample(n, rng=)`` and ``.from_standard(u)``.
    limit : LimitState or None
        Failure definition of the primary response (its P_f is recorded by every formulation
        and constrained by ``rbdo``/``rbrdo``). ``None``: the primary response only supplies
        objectives (e.g. a cost), and the chance constraints come from ``extra_reliability``.
    rng : numpy.random.Generator
        Source of the fixed sample ``u`` (and of the estimator seed).
    options : FormulationOptions
    deterministic : callable, optional
        ``x -> {"von_mises_pa", "omega_n1", "critical_speeds"}``; required when
        ``options.deterministic`` imposes any constraint.
    extra_reliability : tuple of ReliabilityConstraint
        Further chance constraints (same ``P_target``).
    constraints : tuple of DesignConstraint
        Generic deterministic design constraints ``g(x) <= 0`` (Python callables or parsed
        expressions, :mod:`~.constraints`), appended after ``g_det``.
    design_theta : ndarray (k, m), optional
        The deterministic design basis: the ``deterministic`` formulation minimises the largest
        response over these θ rows (e.g. the stated unbalance cases of
        ``ThetaSpec.unbalance_cases``); ``None``: the image of ``u = 0``.
    """
    cls = FORMULATIONS.get(name)
    options = FormulationOptions() if options is None else options
    if not isinstance(options, FormulationOptions):
        raise ValueError(f"options = {options!r} is not allowed: must be FormulationOptions")
    if limit is not None and not isinstance(limit, LimitState):
        raise ValueError(f"limit = {limit!r} is not allowed: must be a LimitState or None")
    if cls.reliability and limit is None and not extra_reliability:
        raise ValueError(f"formulation {name!r} needs a failure definition: give limit or "
                         "extra_reliability")
    for c in extra_reliability:
        if not isinstance(c, ReliabilityConstraint):
            raise ValueError(f"extra_reliability entry {c!r} is not a ReliabilityConstraint")
    for c in constraints:
        if not isinstance(c, DesignConstraint):
            raise ValueError(f"constraints entry {c!r} is not a DesignConstraint")
    names = [c.name for c in constraints]
    if len(set(names)) != len(names):
        raise ValueError(f"constraints: names {names} are not allowed: each name once")
    if design_theta is not None:
        dt = np.asarray(design_theta, dtype=float)
        if dt.ndim != 2 or dt.shape[1] != int(inputs.dim) or not dt.shape[0] \
                or not np.all(np.isfinite(dt)):
            raise ValueError(f"design_theta has shape {dt.shape}: must be finite (k >= 1, "
                             f"{inputs.dim}), one θ row per design case")
    estimator = None
    if options.estimator != "mc":
        estimator = get_estimator(options.estimator, **options.estimator_options)
    det = DeterministicConstraints(options.deterministic, deterministic)
    rng = require_rng(rng)
    u = np.asarray(inputs.standard_sample(options.n_theta, rng=rng), dtype=float)
    if u.ndim == 1:
        u = u[:, None]
    seed = int(rng.integers(0, 2**63 - 1))
    return cls(response=response, inputs=inputs, limit=limit, u=u, options=options,
               constraints_det=det, extra_reliability=tuple(extra_reliability),
               estimator=estimator, estimator_seed=seed, design_constraints=tuple(constraints),
               design_theta=design_theta)
