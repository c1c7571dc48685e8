"""Periodic inputs (phase angles) in the design-point estimators: conditioning and quadrature.

A phase ``φ ~ U(lo, hi)`` on which the response depends periodically (``lo ≡ hi``, marked
``Uniform(..., periodic=True)``) has no place in a design-point search: the transform
``φ = lo + (hi − lo) Φ(u)`` puts ``lo ≡ hi`` at ``u = ±∞``, so when the worst phase is there
(two unbalances in phase) the search runs away along ``u_φ`` and never converges (review of
issue 13: FORM stalled on 12 of 16 designs of the credible problem). Instead the estimators
**condition on the phase**: by total probability

    P_f = (1 / (hi − lo)) ∫ P_f(φ) dφ,

``P_f(φ)`` from a design-point method over the other inputs with ``φ`` fixed (independent of
them, so the conditional distribution of the others is unchanged): FORM/SORM conditional on
some variables and integrated over them numerically, the "outer integration" of Wen & Chen
(1987, On fast integration for time variant structural reliability, *Probabilistic
Engineering Mechanics* 2, 156–162) for variables that FORM cannot linearise. The integrand
is smooth and periodic, so the trapezoidal rule on ``K`` equispaced nodes
``φ_j = lo + (j/K + δ)(hi − lo)`` converges geometrically (Trefethen & Weideman 2014, *SIAM Review*
56, 385–458); ``K`` doubles (the nodes nest) until the rule on ``K`` and on the ``K/2`` nodes
inside it agree within ``rtol``, and their difference is reported as the quadrature error.
Several periodic inputs take the tensor grid (``K`` per phase).

Importance sampling **stratifies** instead (:class:`Stratum`): the phase range is cut into
``K`` equal cells, each sampled by IS at the conditional design point of its centre with the
phase drawn uniformly inside the cell, ``P_f = (1/K) Σ_k P_f,k`` and
``SE² = (1/K²) Σ_k SE_k²`` (stratified sampling with proportional allocation: Rubinstein &
Kroese 2017, *Simulation and the Monte Carlo Method*, ch. 5) — unbiased whatever the design
points.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from fractions import Fraction
from itertools import product
from typing import Any

import numpy as np
from scipy import special

from surrogate_rbrdo.estimators._common import LimitStateU


def periodic_columns(inputs: Any) -> tuple[tuple[int, float, float], ...]:
    """``(column, lo, hi)`` of every periodic uniform marginal of ``inputs`` (an independent
    marginal, an ``Independent`` vector or a ``BlockIndependent`` of them); a periodic marginal
    correlated with others (Nataf) cannot be conditioned on alone: ``ValueError``.

    >>> from surrogate_rbrdo.uncertainty import Independent, Normal, Uniform
    >>> periodic_columns(Independent([Normal(0, 1), Uniform(0.0, 360.0, periodic=True)]))
    ((1, 0.0, 360.0),)
    """
    out, off = [], 0
    for block in getattr(inputs, "blocks", (inputs,)):
        marginals = getattr(block, "marginals", (block,) if int(block.dim) == 1 else ())
        correlated = hasattr(block, "chol0")
        for i, mg in enumerate(marginals):
            if getattr(mg, "periodic", False):
                if correlated:
                    raise ValueError(f"inputs column {off + i} is a periodic marginal inside a "
                                     "correlated (Nataf) block: it must be independent of the "
                                     "others to be conditioned on")
                out.append((off + i, float(mg.lo), float(mg.hi)))
        off += int(block.dim)
    return tuple(out)


class _Fixed:
    """Shared parts of the conditioned vectors: the columns kept and the fixed ones."""

    def __init__(self, inputs: Any, cols: tuple) -> None:
        self.inputs, self.full = inputs, int(inputs.dim)
        self.cols = np.array([c[0] for c in cols], dtype=int)
        self.lo = np.array([c[1] for c in cols])
        self.span = np.array([c[2] - c[1] for c in cols])
        self.keep = np.setdiff1d(np.arange(self.full), self.cols)

    def standard_sample(self, n: int, *, rng: np.random.Generator) -> np.ndarray:
        return rng.standard_normal((n, self.dim))

    def sample(self, n: int, *, rng: np.random.Generator) -> np.ndarray:
        return self.from_standard(self.standard_sample(n, rng=rng))

    @property
    def dim(self) -> int:
        raise NotImplementedError

    def from_standard(self, u: np.ndarray) -> np.ndarray:
        raise NotImplementedError


class Conditioned(_Fixed):
    """``inputs`` with the periodic columns fixed at ``theta`` (the others' distribution is
    unchanged: they are independent): a random vector of dimension ``m − p`` whose
    ``from_standard`` returns the full ``θ``.

    >>> from surrogate_rbrdo.uncertainty import Independent, Normal, Uniform
    >>> v = Independent([Normal(1.0, 0.1), Uniform(0.0, 360.0, periodic=True)])
    >>> c = Conditioned(v, periodic_columns(v), np.array([90.0]))
    >>> c.dim, c.from_standard(np.array([[1.0]])).tolist()
    (1, [[1.1, 90.0]])
    """

    def __init__(self, inputs: Any, cols: tuple, theta: np.ndarray) -> None:
        super().__init__(inputs, cols)
        self.theta = np.asarray(theta, dtype=float)

    @property
    def dim(self) -> int:
        return int(self.keep.size)

    def from_standard(self, u: np.ndarray) -> np.ndarray:
        u = np.atleast_2d(np.asarray(u, dtype=float))
        full = np.zeros((u.shape[0], self.full))
        full[:, self.keep] = u
        theta = self.inputs.from_standard(full)
        theta[:, self.cols] = self.theta
        return theta


class Stratum(_Fixed):
    """``inputs`` with each periodic column restricted to a cell ``[a, b)`` (fractions of its
    range), still in ``m`` standard dimensions: ``u_φ ~ N(0, 1)`` maps to a uniform phase in
    the cell, ``φ = lo + (a + (b − a) Φ(u_φ)) (hi − lo)``.

    >>> from surrogate_rbrdo.uncertainty import Independent, Uniform
    >>> v = Independent([Uniform(0.0, 360.0, periodic=True)])
    >>> Stratum(v, periodic_columns(v), np.array([0.25]), np.array([0.5])).from_standard(
    ...     np.array([[0.0]])).tolist()
    [[135.0]]
    """

    def __init__(self, inputs: Any, cols: tuple, a: np.ndarray, b: np.ndarray) -> None:
        super().__init__(inputs, cols)
        self.a, self.b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)

    @property
    def dim(self) -> int:
        return self.full

    def from_standard(self, u: np.ndarray) -> np.ndarray:
        u = np.atleast_2d(np.asarray(u, dtype=float))
        theta = self.inputs.from_standard(np.where(np.isin(np.arange(self.full), self.cols),
                                                   0.0, u))
        frac = self.a + (self.b - self.a) * special.ndtr(u[:, self.cols])
        theta[:, self.cols] = self.lo + self.span * frac
        return theta


def lift(v: np.ndarray, keep: np.ndarray, full: int, fill: float = 0.0) -> np.ndarray:
    """Vectors ``v`` of the kept columns put back in ``full`` dimensions (``fill`` elsewhere).

    >>> lift(np.array([1.0, 2.0]), np.array([0, 2]), 3).tolist()
    [1.0, 0.0, 2.0]
    """
    out = np.full(v.shape[:-1] + (full,), fill)
    out[..., keep] = v
    return out


@dataclass(frozen=True)
class Quadrature:
    """Result of :func:`integrate`: the integral ``pf``, its ``error`` (rule on ``K`` minus rule
    on ``K/2`` nodes), ``n_nodes`` (``K`` per periodic column), the node phases ``(n, p)`` of
    the final rule and their ``records`` (whatever the node function returned besides P_f)."""

    pf: float
    error: float
    n_nodes: int
    phases: np.ndarray
    pfs: np.ndarray
    records: list


def integrate(node: Callable[[np.ndarray], tuple[float, Any]], cols: tuple, *, n_nodes: int,
              max_nodes: int, rtol: float) -> Quadrature:
    """Trapezoidal rule over the periodic columns ``cols`` of ``node(phases) -> (pf, record)``,
    doubling ``K`` from ``n_nodes`` up to ``max_nodes`` until ``|P_K − P_{K/2}| <= rtol·P_K``.
    A NaN ``pf`` at a node stops the integration (the result is NaN). The nodes are
    ``lo + (j/K + 1/(2·max_nodes)) (hi − lo)``: shifted by half the finest spacing (the rule
    stays nested and exact for trigonometric polynomials of degree < K) so that no node lies
    at a symmetric phase such as 0° or 180°, where the magnitude of a sum of phasors
    ``|r₁ + r₂ e^{iφ}|`` can vanish and has a kink that a design-point search cannot cross.

    >>> q = integrate(lambda t: (1.0 + np.cos(np.radians(t[0])), None), ((0, 0.0, 360.0),),
    ...               n_nodes=4, max_nodes=16, rtol=1e-9)
    >>> round(q.pf, 12), q.n_nodes, q.error < 1e-12
    (1.0, 4, True)
    """
    lo = np.array([c[1] for c in cols])
    span = np.array([c[2] - c[1] for c in cols])
    lo = lo + span * 0.5 / max_nodes     # off the symmetric phases (see the docstring)
    cache: dict[tuple, tuple[float, Any]] = {}
    k = n_nodes
    while True:
        keys = list(product([Fraction(j, k) for j in range(k)], repeat=len(cols)))
        for key in keys:
            if key not in cache:
                phase = lo + span * np.array([float(f) for f in key])
                cache[key] = node(phase)
                if not np.isfinite(cache[key][0]):
                    return Quadrature(np.nan, np.nan, k, phase[None, :], np.array([np.nan]),
                                      [cache[key][1]])
        pfs = np.array([cache[key][0] for key in keys])
        pf = float(pfs.mean())
        coarse = [cache[key][0] for key in keys if all((f * k).numerator % 2 == 0
                                                       for f in key)]
        err = abs(pf - float(np.mean(coarse))) if k % 2 == 0 else np.nan
        if not err > rtol * pf or 2 * k > max_nodes:
            phases = lo + span * np.array([[float(f) for f in key] for key in keys])
            return Quadrature(pf, err, k, phases, pfs, [cache[key][1] for key in keys])
        k *= 2


def cells(cols: tuple, k: int) -> list[tuple[np.ndarray, np.ndarray]]:
    """The ``k`` equal cells per periodic column as ``(a, b)`` fraction arrays (tensor grid).

    >>> [(a.tolist(), b.tolist()) for a, b in cells(((0, 0.0, 1.0),), 2)]
    [([0.0], [0.5]), ([0.5], [1.0])]
    """
    edges = [(j / k, (j + 1) / k) for j in range(k)]
    return [(np.array([e[0] for e in c]), np.array([e[1] for e in c]))
            for c in product(edges, repeat=len(cols))]


def conditional_search(form: Any, response: Any, inputs: Any, limit: Any, x_row: np.ndarray,
                       cols: tuple, correct: Callable | None = None) -> tuple[Any, Quadrature]:
    """Design-point searches of ``form`` (a :class:`~surrogate_rbrdo.estimators.form.FORM`)
    conditional on the periodic columns, integrated over them (:func:`integrate` with the
    FORM options ``phase_nodes``, ``phase_max_nodes``, ``phase_rtol``).

    ``correct(G, dp) -> pf`` replaces ``Φ(−β)`` at the converged nodes (SORM). Returns the
    design point of the node contributing most, in full dimension (NaN in the periodic
    columns, which are conditioned on), with ``beta = −Φ⁻¹(P_f)`` the generalised reliability
    index of the integral, ``status`` ``"failed"`` if a node failed, ``"converged"`` if every
    node converged, ``"unconverged"`` where some node's search ended on a point of the limit
    state not shown to be nearest (:func:`_bounded_status`), ``"not_reached"`` otherwise (nodes
    never failing contribute FORM's bound
    ``Φ(−β_max)``), and ``calls`` of every node; and the :class:`Quadrature`.
    """
    calls, prev = [0], []
    span = np.array([c[2] - c[1] for c in cols])

    def node(phases: np.ndarray) -> tuple[float, Any]:
        cond = Conditioned(inputs, cols, phases)
        G = LimitStateU(response, cond, limit, x_row)
        g0 = float(G(np.zeros((1, cond.dim)))[0])
        # warm start at the design point of the nearest node in phase (periodic distance;
        # neighbouring phases have nearby design points) where G(0) has the same sign; else
        # from the origin
        near = [(float(np.sum(np.minimum(np.abs(ph - phases), span - np.abs(ph - phases)))), d)
                for ph, d in prev if d.status == "converged" and (d.g_origin >= 0) == (g0 >= 0)]
        start = min(near, key=lambda t: t[0])[1].u_star if near else None
        dp = form.run(G, cond.dim, start=None if start is None else (start, g0))
        if dp.status == "failed" and near:
            dp = form.run(G, cond.dim)
        prev.append((phases, dp))
        pf = np.nan
        if dp.status in ("not_reached", "unconverged") or (dp.status == "converged"
                                                           and correct is None):
            pf = float(special.ndtr(-dp.beta))
        elif dp.status == "converged":
            pf = float(correct(G, dp))
            if not np.isfinite(pf):
                dp = replace(dp, status="failed", message=(
                    f"the correction is not applicable at the phase node {phases.tolist()} "
                    f"(e.g. SORM: a curvature factor 1 + psi*kappa <= 0, beta={dp.beta:.4g})"))
        calls[0] += G.calls
        return pf, dp

    q = integrate(node, cols, n_nodes=form.phase_nodes, max_nodes=form.phase_max_nodes,
                  rtol=form.phase_rtol)
    dps = q.records
    statuses = {d.status for d in dps}
    if not np.isfinite(q.pf):
        status = "failed"
    elif "unconverged" in statuses:
        status = _bounded_status(dps, q.pf)
    else:
        status = "converged" if statuses == {"converged"} else "not_reached"
    d = dps[int(np.argmax(q.pfs))] if q.pfs.size else dps[0]
    keep, m = Conditioned(inputs, cols, np.zeros(len(cols))).keep, int(inputs.dim)
    beta = float(-special.ndtri(q.pf)) if np.isfinite(q.pf) else d.beta
    bad = [j for j, x in enumerate(dps) if x.status == "failed"]
    msg = (f"{dps[bad[0]].message} (search conditional on the phase(s) "
           f"{np.round(q.phases[bad[0]], 2).tolist()})"
           if status == "failed" and bad else d.message if status == "failed" else (
        f"{status} (conditional on {len(cols)} periodic input(s), {q.n_nodes} nodes each, "
        f"quadrature error {q.error:.2g}; at the dominant node: {d.message})"))
    dp = replace(d, beta=beta, u_star=lift(d.u_star, keep, m, np.nan),
                 alpha=lift(d.alpha, keep, m, np.nan), grad=lift(d.grad, keep, m, np.nan),
                 converged=status == "converged", calls=calls[0], message=msg, status=status,
                 n_iter=int(sum(x.n_iter for x in dps)))
    return dp, q


def _bounded_status(dps: list, pf: float) -> str:
    """Status of an integral over nodes of which some ended ``"unconverged"`` (a lower bound of
    their P_f from a safe mean, an upper one from a failing mean) and some perhaps
    ``"not_reached"`` (the reverse): ``"unconverged"`` when every bounded node bounds from the
    side the integral's own label will say (lower for ``pf < 1/2``, upper above), else
    ``"failed"`` (bounds from both sides bound nothing)."""
    sides = {("lower" if (d.beta >= 0) == (d.status == "unconverged") else "upper")
             for d in dps if d.status in ("not_reached", "unconverged")}
    return "unconverged" if sides == {"lower" if pf < 0.5 else "upper"} else "failed"


def dominant_theta(inputs: Any, cols: tuple, q: Quadrature) -> np.ndarray:
    """``θ*`` (full dimension, its phase included) of the node contributing most to ``q``."""
    j = int(np.argmax(q.pfs))
    return Conditioned(inputs, cols, q.phases[j]).from_standard(q.records[j].u_star[None, :])[0]
