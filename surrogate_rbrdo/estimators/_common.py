"""Helpers shared by the estimators: argument checks, checked model evaluation, intervals.

**Physical domain — one meaning for every estimator.** A model raises
:class:`~surrogate_rbrdo.core.errors.OutsideDomainError` for inputs outside its physical domain
(e.g. a bearing stiffness factor θ ≤ 0, which a normal θ reaches with a tiny probability and a
FORM search or a Markov chain can step into). Such a point is **not a failure**: the response
is not defined there, and the mass the input model puts outside the domain is a defect of the
input model, not of the design. Every estimator reports ``P_f = P(failure and inside the
domain)``, and the sampling estimators report the share of their sample that fell outside
(``diagnostics["n_outside_domain"]``; crude MC also ``p_outside``). :func:`evaluate_in_domain`
isolates the points outside (by the rows the error names, each claim checked, else by
bisection of the batch) and evaluates the others; :class:`LimitStateU` gives them
``G = +inf`` (safe), so a design-point search steps back from them and a Markov chain rejects
them. Moments of ``y`` are those of the points inside (the distribution of ``y`` conditional on
the domain). Where the domain matters, :func:`~surrogate_rbrdo.uncertainty.stiffness_factors`
offers inputs with positive support.
"""

from __future__ import annotations

from collections.abc import Callable
from types import MappingProxyType
from typing import Any

import numpy as np
from scipy import special

from surrogate_rbrdo.core.errors import ModelError, OutsideDomainError
from surrogate_rbrdo.core.protocols import Estimate, LimitState
from surrogate_rbrdo.core.rng import require_rng


def check_args(
    inputs: Any, limit: LimitState, x: Any, rng: Any, u: Any = None
) -> tuple[np.ndarray, np.ndarray | None]:
    """Validate the common ``estimate`` arguments; return ``x`` as ``(P, d)`` and ``u``."""
    require_rng(rng)
    if not isinstance(limit, LimitState):
        raise ValueError(f"limit = {limit!r} is not allowed: must be a core LimitState")
    for attr in ("dim", "from_standard"):
        if not hasattr(inputs, attr):
            raise ValueError(f"inputs = {inputs!r} is not allowed: must be a RandomVector")
    xa = np.asarray(x, dtype=float)
    if xa.ndim != 2 or xa.shape[0] < 1:
        raise ValueError(f"x has shape {xa.shape}: must be (P, d) with P >= 1 (use (1, 0) "
                         "for a problem without design variables)")
    if not np.all(np.isfinite(xa)):
        raise ValueError("x contains a non-finite value: designs must be finite")
    if u is None:
        return xa, None
    ua = np.asarray(u, dtype=float)
    if ua.ndim != 2 or ua.shape[1] != inputs.dim or ua.shape[0] < 1:
        raise ValueError(f"u has shape {ua.shape}: must be (N, {inputs.dim}) with N >= 1")
    if not np.all(np.isfinite(ua)):
        raise ValueError("u contains a non-finite value: must be a finite standard-normal sample")
    return xa, ua


def check_finite_y(y: np.ndarray, what: str = "response") -> None:
    """Raise :class:`ModelError` naming the first non-finite entry of a ``(P, N)`` array."""
    if not np.all(np.isfinite(y)):
        i, j = np.argwhere(~np.isfinite(y))[0]
        raise ModelError(f"{what} returned {y[i, j]} for design {i}, theta sample {j}: "
                         "responses must be finite")


def evaluate(response: Callable, x: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """Call ``response(x, theta)`` and check the ``(P, N)`` shape and finiteness."""
    y = np.asarray(response(x, theta), dtype=float)
    expected = (x.shape[0], theta.shape[0])
    if y.shape != expected:
        raise ModelError(f"response returned shape {y.shape}, expected {expected}")
    if not np.all(np.isfinite(y)):
        i, j = np.argwhere(~np.isfinite(y))[0]
        raise ModelError(f"response returned {y[i, j]} at design x={x[i].tolist()}, "
                         f"theta={theta[j].tolist()}: responses must be finite")
    return y


def evaluate_in_domain(response: Callable, x: np.ndarray, theta: np.ndarray
                       ) -> tuple[np.ndarray, np.ndarray, int]:
    """``response(x, theta)`` with the θ rows outside the model's domain left out.

    Returns ``y`` of shape ``(P, N)`` (NaN in the columns outside the domain), the boolean mask
    ``inside`` of shape ``(N,)`` and the number of model points evaluated (what
    :class:`~surrogate_rbrdo.core.CountingResponse` counts: only calls that returned). Rows
    named by :class:`OutsideDomainError` are set apart and both parts evaluated again (the named
    rows are outside only once a batch of exactly them raises: the claim is checked, at the cost
    of one call that raises); an error without rows splits the batch in halves. Any other error
    propagates.

    >>> from surrogate_rbrdo.core.errors import OutsideDomainError
    >>> def resp(x, t):
    ...     if np.any(t[:, 0] <= 0):
    ...         raise OutsideDomainError("theta <= 0", rows=np.flatnonzero(t[:, 0] <= 0))
    ...     return np.log(t[:, 0])[None, :]
    >>> y, inside, calls = evaluate_in_domain(resp, np.zeros((1, 0)), np.array([[1.0], [-1.0]]))
    >>> inside.tolist(), calls, np.isnan(y).tolist()
    ([True, False], 1, [[False, True]])
    """
    n = theta.shape[0]
    y = np.full((x.shape[0], n), np.nan)
    inside = np.ones(n, dtype=bool)
    todo, calls = [np.arange(n)], 0
    while todo:
        idx = todo.pop()
        try:
            y[:, idx] = evaluate(response, x, theta[idx])
            calls += x.shape[0] * idx.size
        except OutsideDomainError as exc:
            rows = np.unique(np.asarray(exc.rows if exc.rows is not None else (), dtype=int))
            named = rows.size > 0 and rows.min() >= 0 and rows.max() < idx.size
            if named and rows.size == idx.size or (not named and idx.size == 1):
                inside[idx] = False          # every point of this batch is outside
            elif named:
                # the claim is checked: the named rows are evaluated again on their own (a
                # model that reorders or deduplicates θ cannot drop the wrong points)
                bad = np.zeros(idx.size, dtype=bool)
                bad[rows] = True
                todo += [idx[bad], idx[~bad]]
            else:                       # the model did not say which rows: bisect the batch
                todo += [idx[: idx.size // 2], idx[idx.size // 2:]]
    return y, inside, calls


class LimitStateU:
    """``G(u) = limit.g(response(x_p, T(u)))`` for one design, counting model calls.

    A point outside the model's physical domain gets ``G = +inf`` (not a failure, see the module
    docstring); ``n_outside`` counts them and ``last_y`` is NaN there. ``scale`` is
    ``|threshold|``, the scale against which a design-point search judges ``|G| ≈ 0``.
    """

    def __init__(self, response: Callable, inputs: Any, limit: LimitState,
                 x_row: np.ndarray) -> None:
        self.response, self.inputs, self.limit = response, inputs, limit
        self.x_row = x_row.reshape(1, -1)
        self.scale = abs(float(limit.threshold))
        self.calls = 0
        self.n_outside = 0
        self.last_y = np.empty(0)

    def __call__(self, u: np.ndarray) -> np.ndarray:
        u = np.atleast_2d(u)
        y, inside, calls = evaluate_in_domain(self.response, self.x_row,
                                              self.inputs.from_standard(u))
        self.calls += calls
        self.n_outside += int(np.count_nonzero(~inside))
        self.last_y = y[0]
        return np.where(inside, self.limit.g(np.where(inside, y[0], 0.0)), np.inf)


def log_std_normal(v: np.ndarray) -> np.ndarray:
    """Log density of the standard normal ``N(0, I)`` at the rows of ``v``."""
    m = v.shape[1]
    return -0.5 * np.einsum("ij,ij->i", v, v) - 0.5 * m * np.log(2.0 * np.pi)


def z_of(level: float) -> float:
    """Two-sided normal quantile for a confidence ``level``."""
    return float(special.ndtri(0.5 + 0.5 * level))


def clopper_pearson(k: np.ndarray, n: int, level: float) -> np.ndarray:
    """Exact binomial (Clopper-Pearson) interval for ``k`` failures out of ``n``: ``(P, 2)``.

    Valid at ``k = 0`` (lower bound 0) and ``k = n`` (upper bound 1).

    >>> clopper_pearson(np.array([0]), 1000, 0.95).round(5).tolist()
    [[0.0, 0.00368]]
    """
    k_all = np.asarray(k, dtype=float)
    k, back = np.unique(k_all, return_inverse=True)   # designs often share failure counts
    a = 0.5 * (1.0 - level)
    lo = np.where(k > 0, special.betaincinv(np.maximum(k, 1e-300), n - k + 1, a), 0.0)
    hi = np.where(k < n, special.betaincinv(k + 1, np.maximum(n - k, 1e-300), 1 - a), 1.0)
    return np.column_stack([lo, hi])[back.reshape(-1)]


def normal_ci(pf: np.ndarray, se: np.ndarray, level: float) -> np.ndarray:
    """Normal-approximation interval ``pf ± z se`` clipped to ``[0, 1]``; ``[0, 1]`` where there
    is no hit and no error to go by (``pf = 0`` with a zero or NaN ``se``).

    >>> normal_ci(np.array([0.1, 0.0, 0.0]), np.array([0.01, 1e-5, 0.0]), 0.95).round(5).tolist()
    [[0.0804, 0.1196], [0.0, 2e-05], [0.0, 1.0]]
    """
    z = z_of(level)
    lo = np.clip(pf - z * se, 0.0, 1.0)
    hi = np.clip(pf + z * se, 0.0, 1.0)
    none = (pf <= 0) & ~(se > 0)
    return np.column_stack([np.where(none, 0.0, lo), np.where(none, 1.0, hi)])


def nan_p(p: int) -> np.ndarray:
    """A ``(P,)`` array of NaN."""
    return np.full(p, np.nan)


def make_estimate(method: str, n_calls: int, p: int, **kw: Any) -> Estimate:
    """Build an :class:`Estimate`, filling missing quantities with NaN."""
    fields = {k: np.asarray(kw.pop(k, nan_p(p)), dtype=float)
              for k in ("mean", "std", "pf", "mean_se", "std_se", "pf_se")}
    ci = np.asarray(kw.pop("pf_ci", np.full((p, 2), np.nan)), dtype=float)
    diagnostics = kw.pop("diagnostics", {})
    if kw:
        raise TypeError(f"unexpected fields {sorted(kw)}")
    for a in (*fields.values(), ci):
        a.setflags(write=False)
    for v in diagnostics.values():
        if isinstance(v, np.ndarray):
            v.setflags(write=False)
    return Estimate(pf_ci=ci, n_calls=int(n_calls), method=method,
                    diagnostics=MappingProxyType(dict(diagnostics)), **fields)
