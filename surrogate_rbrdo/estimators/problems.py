"""Analytic reliability problems with exact or many-digit reference values.

Used by the known-answer tests and by ``benchmarks/bench_estimators.py``. Each
:class:`Problem` has a vectorised response ``y(x, θ) -> (P, N)``, its random inputs, the limit
state (failure ``y > threshold``), a design batch ``x`` and the reference ``P_f`` per design.

>>> prob = linear_standard(beta=3.0, dim=2)
>>> round(float(prob.pf_exact[0]), 8)
0.0013499
"""

from __future__ import annotations

import itertools
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy import integrate, special, stats

from surrogate_rbrdo.core.protocols import LimitState
from surrogate_rbrdo.uncertainty import Independent, LogNormal, MultivariateNormal, Nataf, Uniform


@dataclass(frozen=True)
class Problem:
    """An analytic reliability problem with its reference answer."""

    name: str
    response: Callable[[np.ndarray, np.ndarray], np.ndarray]
    inputs: object
    limit: LimitState
    x: np.ndarray
    pf_exact: np.ndarray
    mean_exact: np.ndarray | None = None
    std_exact: np.ndarray | None = None
    source: str = ""


def _shift(x: np.ndarray) -> np.ndarray:
    """Design shift ``x[:, 0]`` as a column (zero when there are no design variables)."""
    return x[:, :1] if x.shape[1] else np.zeros((x.shape[0], 1))


def linear_standard(beta: float = 3.0, dim: int = 3, shifts: tuple[float, ...] = (0.0,)
                    ) -> Problem:
    """``y = x₀ + α·u`` with ``u ~ N(0, I)``, ``‖α‖ = 1``; failure ``y > β``.

    Exact: ``P_f(x) = Φ(−(β − x₀))``; ``μ_y = x₀``, ``σ_y = 1``. FORM is exact.
    """
    alpha = np.arange(1.0, dim + 1.0)
    alpha /= np.linalg.norm(alpha)
    x = np.asarray(shifts, dtype=float)[:, None]
    return Problem(
        f"linear_{dim}d_beta{beta:g}",
        lambda x, t: _shift(x) + (t @ alpha)[None, :],
        MultivariateNormal(np.zeros(dim), cov=np.eye(dim)),
        LimitState(beta), x, special.ndtr(-(beta - x[:, 0])),
        mean_exact=x[:, 0].copy(), std_exact=np.ones(x.shape[0]),
        source="closed form Φ(−β)",
    )


def correlated_normal() -> Problem:
    """``y = x₀ + a·θ`` with correlated normal ``θ``; failure ``y > 10``.

    Exact: ``y ~ N(x₀ + a·μ, aᵀΣa)``.
    """
    mean = np.array([1.0, 2.0, 3.0])
    corr = np.array([[1.0, 0.5, -0.3], [0.5, 1.0, 0.2], [-0.3, 0.2, 1.0]])
    inputs = MultivariateNormal(mean, std=[0.5, 1.0, 0.8], corr=corr)
    a = np.array([1.0, 1.5, -0.5])
    x = np.array([[2.0], [4.0], [5.0]])
    mu = x[:, 0] + a @ mean
    sd = float(np.sqrt(a @ inputs.cov @ a))
    return Problem("correlated_normal", lambda x, t: _shift(x) + (t @ a)[None, :], inputs,
                   LimitState(10.0), x, special.ndtr(-(10.0 - mu) / sd),
                   mean_exact=mu, std_exact=np.full(3, sd), source="closed form (normal y)")


def lognormal_nataf(rho: float = 0.5) -> Problem:
    """``y = ln θ₁ + ln θ₂`` with Nataf-correlated lognormals; failure ``y > 1.5``.

    ``ln θ`` is bivariate normal with correlation
    ``ρ₀ = ln(1 + ρ √((e^{s₁²}−1)(e^{s₂²}−1))) / (s₁ s₂)`` (closed form, Liu & Der Kiureghian
    1986), so ``y`` is normal and ``P_f`` exact; the limit state is linear in ``u``.
    """
    m1, s1, m2, s2 = 0.1, 0.3, -0.2, 0.5
    inputs = Nataf([LogNormal(m1, s1), LogNormal(m2, s2)], [[1.0, rho], [rho, 1.0]])
    rho0 = np.log1p(rho * np.sqrt(np.expm1(s1**2) * np.expm1(s2**2))) / (s1 * s2)
    sd = float(np.sqrt(s1**2 + s2**2 + 2 * rho0 * s1 * s2))
    return Problem("lognormal_nataf",
                   lambda x, t: np.log(t[:, 0] * t[:, 1])[None, :] + 0 * _shift(x), inputs,
                   LimitState(1.5), np.zeros((1, 0)),
                   np.array([special.ndtr(-(1.5 - m1 - m2) / sd)]),
                   mean_exact=np.array([m1 + m2]), std_exact=np.array([sd]),
                   source="closed form (Nataf for lognormals is exact)")


def paraboloid(beta: float = 3.0, kappa: float = 0.3, dim: int = 5) -> Problem:
    """Parabolic limit state ``g(u) = β − u_m + (κ/2) Σ_{i<m} u_i²`` (Breitung 1984; Der Kiureghian
    & De Stefano 1991): failure ``y = u_m − (κ/2) Σ u_i² > β``.

    Exact: ``P_f = E[Φ(−β − κ χ²_{m−1} / 2)]`` by 1-D quadrature (≈ 1e-13 absolute). FORM gives
    ``Φ(−β)``, Breitung ``Φ(−β)(1 + βκ)^{−(m−1)/2}``.
    """
    def resp(x: np.ndarray, t: np.ndarray) -> np.ndarray:
        y = t[:, -1] - 0.5 * kappa * np.sum(t[:, :-1] ** 2, axis=1)
        return y[None, :] + 0 * _shift(x)

    chi = stats.chi2(dim - 1)
    pf, _ = integrate.quad(lambda s: special.ndtr(-beta - 0.5 * kappa * s) * chi.pdf(s),
                           0, np.inf, epsabs=1e-15, epsrel=1e-12, limit=200)
    return Problem(f"paraboloid_{dim}d_k{kappa:g}", resp,
                   MultivariateNormal(np.zeros(dim), cov=np.eye(dim)), LimitState(beta),
                   np.zeros((1, 0)), np.array([pf]),
                   source="Breitung (1984) parabolic limit state; exact by quadrature")


def series_four_branch(k: float = 6.0) -> Problem:
    """Four-branch series system (Waarts 2000; Schueremans & Van Gemert 2005; Au & Beck 1999)::

        g = min(3 + 0.1(u₁−u₂)² − (u₁+u₂)/√2, 3 + 0.1(u₁−u₂)² + (u₁+u₂)/√2,
                (u₁−u₂) + k/√2, (u₂−u₁) + k/√2)

    failure ``y = −g > 0``. In rotated coordinates ``s = (u₁+u₂)/√2``, ``t = (u₁−u₂)/√2``
    failure is ``|t| > k/2`` or ``|s| > 3 + 0.2t²``, so
    ``P_f = 2Φ(−k/2) + ∫_{|t|<k/2} φ(t) 2Φ(−3 − 0.2t²) dt`` (1-D quadrature). For k = 6 this
    gives 4.4573e-3 (Echard et al. 2011 report 4.416e-3 by MC with 1e6 samples), for k = 7
    2.2228e-3 (Echard: 2.233e-3). Four design points: FORM finds only one.
    """
    r2 = np.sqrt(2.0)

    def resp(x: np.ndarray, t: np.ndarray) -> np.ndarray:
        u1, u2 = t[:, 0], t[:, 1]
        c = 3 + 0.1 * (u1 - u2) ** 2
        g = np.minimum(np.minimum(c - (u1 + u2) / r2, c + (u1 + u2) / r2),
                       np.minimum((u1 - u2) + k / r2, (u2 - u1) + k / r2))
        return -g[None, :] + 0 * _shift(x)

    inner, _ = integrate.quad(lambda t: stats.norm.pdf(t) * 2 * special.ndtr(-3 - 0.2 * t * t),
                              -k / 2, k / 2, epsabs=1e-15, epsrel=1e-12)
    pf = 2 * special.ndtr(-k / 2) + inner
    return Problem(f"series4_k{k:g}", resp, MultivariateNormal(np.zeros(2), cov=np.eye(2)),
                   LimitState(0.0), np.zeros((1, 0)), np.array([pf]),
                   source="4-branch series system (Waarts 2000); exact by 1-D quadrature")


def uniform_sum(threshold: float = 1.8) -> Problem:
    """``y = θ₁ + θ₂`` with independent ``U(0, 1)`` inputs; failure ``y > t`` (``1 ≤ t ≤ 2``).

    Exact: ``P_f = (2 − t)² / 2`` (a corner triangle of the unit square), 0.02 for t = 1.8. The
    limit state is non-linear in ``u`` (through ``Φ``), so FORM is only approximate.
    """
    return Problem(f"uniform_sum_t{threshold:g}",
                   lambda x, t: (t[:, 0] + t[:, 1])[None, :] + 0 * _shift(x),
                   Independent([Uniform(0.0, 1.0), Uniform(0.0, 1.0)]), LimitState(threshold),
                   np.zeros((1, 0)), np.array([(2.0 - threshold) ** 2 / 2.0]),
                   mean_exact=np.array([1.0]), std_exact=np.array([np.sqrt(1 / 6)]),
                   source="closed form (triangle area)")


def two_design_points(b: float = 5.0, kappa: float = 0.5, e: float = 0.1) -> Problem:
    """Parabolic limit state with two design points (Der Kiureghian & Dakessian 1998, *Struct.
    Safety* 20, 37–49): ``g = b − u₂ − κ(u₁ − e)²``, failure ``y = −g > 0``.

    Exact: ``P_f = ∫ φ(u₁) Φ(−b + κ(u₁ − e)²) du₁`` by 1-D quadrature: 3.0163e-3 for the paper's
    ``b = 5, κ = 0.5, e = 0.1`` (its two design points at ``β ≈ 2.74`` and ``2.86``).
    The failure domain wraps around the origin side of each FORM hyperplane.
    """
    def resp(x: np.ndarray, t: np.ndarray) -> np.ndarray:
        g = b - t[:, 1] - kappa * (t[:, 0] - e) ** 2
        return -g[None, :] + 0 * _shift(x)

    pf, _ = integrate.quad(lambda s: stats.norm.pdf(s) * special.ndtr(-b + kappa * (s - e) ** 2),
                           -np.inf, np.inf, epsabs=1e-15, epsrel=1e-12, limit=200)
    return Problem("two_design_points", resp, MultivariateNormal(np.zeros(2), cov=np.eye(2)),
                   LimitState(0.0), np.zeros((1, 0)), np.array([pf]),
                   source="Der Kiureghian & Dakessian (1998); exact by 1-D quadrature")


#: crude Monte Carlo reference of the oscillator's P_f: 5 717 336 failures in 2·10⁸ samples,
#: standard error 1.18e-5 (0.04 %); ``python benchmarks/reference_oscillator.py`` reruns it
OSCILLATOR_PF = 2.858668e-2
OSCILLATOR_PF_SE = 1.18e-5


def nonlinear_oscillator() -> Problem:
    """Non-linear undamped single-degree-of-freedom oscillator under a rectangular pulse
    (Rajashekhar & Ellingwood 1993; Gayton, Bourinet & Lemaire 2003; Echard et al. 2011):
    ``g = 3r − |2F₁/(mω₀²) sin(ω₀t₁/2)|``, ``ω₀ = √((c₁ + c₂)/m)``, six independent normals
    ``m ~ N(1, 0.05)``, ``c₁ ~ N(1, 0.1)``, ``c₂ ~ N(0.1, 0.01)``, ``r ~ N(0.5, 0.05)``,
    ``F₁ ~ N(1, 0.2)``, ``t₁ ~ N(1, 0.2)``; failure ``y = −g > 0``.

    No closed form: the reference is our crude Monte Carlo with 2·10⁸ samples (see
    :data:`OSCILLATOR_PF`); Echard et al. (2011) report 2.834e-2 from 7·10⁴ samples.
    """
    mean = np.array([1.0, 1.0, 0.1, 0.5, 1.0, 1.0])
    std = np.array([0.05, 0.1, 0.01, 0.05, 0.2, 0.2])

    def resp(x: np.ndarray, t: np.ndarray) -> np.ndarray:
        m, c1, c2, r, f1, t1 = t.T
        w0 = np.sqrt((c1 + c2) / m)
        g = 3 * r - np.abs(2 * f1 / (m * w0**2) * np.sin(w0 * t1 / 2))
        return -g[None, :] + 0 * _shift(x)

    return Problem("nonlinear_oscillator", resp, MultivariateNormal(mean, std=std),
                   LimitState(0.0), np.zeros((1, 0)), np.array([OSCILLATOR_PF]),
                   source="Echard et al. (2011); reference by crude MC, 2e8 samples")


def two_sided_linear(dim: int = 10, beta: float = 5.0) -> Problem:
    """Two linear components on opposite sides of the mean: failure ``|a·u| > β`` (``‖a‖ = 1``),
    a series system with two design points ``±β a`` at the same distance.

    Exact: ``P_f = 2Φ(−β)``. A search from the mean finds one design point; IS at it sees half
    of P_f (the case Der Kiureghian & Dakessian 1998 motivate their search with).
    """
    a = np.ones(dim) / np.sqrt(dim)
    return Problem(f"two_sided_linear_{dim}d_b{beta:g}",
                   lambda x, t: np.abs(t @ a)[None, :] + 0 * _shift(x),
                   MultivariateNormal(np.zeros(dim), cov=np.eye(dim)), LimitState(beta),
                   np.zeros((1, 0)), np.array([2.0 * special.ndtr(-beta)]),
                   source="two symmetric linear components; closed form 2Φ(−β)")


def series_linear(dim: int = 10, beta: tuple[float, float] = (3.0, 3.5)) -> Problem:
    """A four-branch series system of limit states linear in ``u``, in ``dim`` dimensions:
    failure ``u₁ > β₁`` or ``u₂ > β₁`` or ``−u₁ > β₂`` or ``−u₂ > β₂`` (two pairs of opposite
    half-spaces on two orthogonal axes; four design points, two of them less probable).

    Exact: ``P_f = 1 − (1 − Φ(−β₁) − Φ(−β₂))²`` (the two coordinates are independent). The
    straight-branch analogue of the four-branch system in many dimensions, where a
    cross-entropy fit loses the weaker branches (review of issue 13, est6).
    """
    b1, b2 = beta
    q = 1.0 - special.ndtr(-b1) - special.ndtr(-b2)
    return Problem(f"series_linear_{dim}d",
                   lambda x, t: np.max(np.stack([t[:, 0] - b1, t[:, 1] - b1, -t[:, 0] - b2,
                                                 -t[:, 1] - b2]), axis=0)[None, :]
                   + 0 * _shift(x),
                   MultivariateNormal(np.zeros(dim), cov=np.eye(dim)), LimitState(0.0),
                   np.zeros((1, 0)), np.array([1.0 - q * q]),
                   source="four linear components on two axes; closed form")


#: unit normals of the oblique three-branch system (first six coordinates; review s5 of issue 13)
OBLIQUE_NORMALS = np.array([[1.0, 0, 0, 0, 0, 0], [0.5, 1.0, 0, 0, 0, 0], [-1.0, 0, 1, 1, 1, 0]])
OBLIQUE_NORMALS /= np.linalg.norm(OBLIQUE_NORMALS, axis=1, keepdims=True)


def union_of_half_spaces(normals: np.ndarray, offsets: np.ndarray) -> float:
    """``P(∪_i {a_i·u > b_i})`` for ``u ~ N(0, I)`` and unit normals ``a_i``: inclusion–exclusion
    over the upper orthant probabilities of ``z = A u ~ N(0, A Aᵀ)`` (one-dimensional terms by
    ``Φ``, bivariate ones by scipy's Genz–Drezner algorithm, higher ones by Genz's quasi-Monte
    Carlo with a fixed seed and ``abseps = 1e-14``).

    >>> a = np.eye(2)                                   # two independent branches
    >>> p = union_of_half_spaces(a, np.array([3.0, 3.0]))
    >>> bool(np.isclose(p, 1 - (1 - special.ndtr(-3.0)) ** 2, rtol=1e-9))
    True
    """
    normals = np.atleast_2d(np.asarray(normals, dtype=float))
    offsets = np.atleast_1d(np.asarray(offsets, dtype=float))
    n = offsets.size
    if normals.shape[0] != n:
        raise ValueError(f"normals has {normals.shape[0]} rows and offsets {n} entries: "
                         "need one unit normal per offset")
    norms = np.linalg.norm(normals, axis=1)
    if not np.allclose(norms, 1.0, atol=1e-9):
        raise ValueError(f"normals have lengths {np.round(norms, 6).tolist()}: unit normals "
                         "are required (divide each row by its norm)")
    gram = normals @ normals.T
    if n > 1 and np.max(np.abs(gram[np.triu_indices(n, 1)])) > 1.0 - 1e-9:
        raise ValueError("normals contains parallel or opposite rows: their orthant "
                         "probabilities are degenerate; merge or split them by hand")
    total = 0.0
    for k in range(1, n + 1):
        for sub in itertools.combinations(range(n), k):
            idx = list(sub)
            if k == 1:
                term = float(special.ndtr(-offsets[idx[0]]))
            else:
                cov = normals[idx] @ normals[idx].T
                term = float(stats.multivariate_normal.cdf(
                    -offsets[idx], np.zeros(k), cov, abseps=1e-14, releps=1e-10,
                    rng=np.random.default_rng(0)))
            total += (-1) ** (k + 1) * term
    return total


def series_oblique(dim: int = 6, beta: tuple[float, float, float] = (3.0, 3.4, 3.8)) -> Problem:
    """A three-branch series system of linear limit states whose branches are neither
    axis-aligned nor opposite: failure ``max_i (a_i·u − β_i) > 0`` with ``a₁ = e₁``,
    ``a₂ = (0.5, 1)/√1.25`` (``ρ₁₂ = 0.45``: half of branch 2 lies in branch 1's half-space) and
    ``a₃ = (−1, 0, 1, 1, 1)/2`` (``ρ₁₃ = −0.5``), ``dim ≥ 6``.

    Exact by inclusion–exclusion (:func:`union_of_half_spaces`; 1.7373e-3 at the defaults,
    cross-checked by 10⁷ Monte Carlo draws: 1.7361e-3 ± 1.3e-5). In review s5 of issue 13 IS
    reported the two-branch value (branches 1 and 3) 7–23 SE low in 5 of 8 runs, and ais lost
    branch 2 in 2 of 19 runs in 15-D, without a warning.
    """
    if int(dim) != dim or dim < 6:
        raise ValueError(f"dim = {dim!r} is not allowed: must be an integer >= 6")
    a = np.zeros((3, dim))
    a[:, :6] = OBLIQUE_NORMALS
    b = np.asarray(beta, dtype=float)
    if b.shape != (3,) or not np.all(np.isfinite(b)):
        raise ValueError(f"beta = {beta!r} is not allowed: must be three finite numbers")
    return Problem(f"series_oblique_{dim}d",
                   lambda x, t: np.max(t @ a.T - b, axis=1)[None, :] + 0 * _shift(x),
                   MultivariateNormal(np.zeros(dim), cov=np.eye(dim)), LimitState(0.0),
                   np.zeros((1, 0)), np.array([union_of_half_spaces(a, b)]),
                   source="three oblique linear components; inclusion-exclusion (scipy MVN)")


def two_sided_safe(dim: int = 2, beta: float = 4.5) -> Problem:
    """A failing mean point whose safe set is two slivers: failure ``|a·u| < β`` (``‖a‖ = 1``),
    ``y = β − |a·u| > 0``; the complement of :func:`two_sided_linear`.

    Exact: ``1 − P_f = 2Φ(−β)`` (6.8e-6 at β = 4.5; ``P_f`` reported as ``1 − 2Φ(−β)``). A search
    from the (failing) mean finds one sliver's design point; IS of the complement at it sees
    half of ``1 − P_f`` — the analytic analogue of a credible-problem design where almost every
    sample fails (review of issue 13: IS reported ``1 − P_f`` = 1.0e-6 ± 5e-7 where MC gave
    2.0e-5 ± 4.5e-6).
    """
    a = np.ones(dim) / np.sqrt(dim)
    return Problem(f"two_sided_safe_{dim}d_b{beta:g}",
                   lambda x, t: (beta - np.abs(t @ a))[None, :] + 0 * _shift(x),
                   MultivariateNormal(np.zeros(dim), cov=np.eye(dim)), LimitState(0.0),
                   np.zeros((1, 0)), np.array([1.0 - 2.0 * special.ndtr(-beta)]),
                   source="complement of two symmetric linear components; closed form")


def exponential_sum(dim: int = 10, pf: float = 3e-7) -> Problem:
    """``y = Σ X_i`` of ``dim`` independent ``Exp(1)`` variables, failure ``y > c`` with ``c``
    the ``(1 − pf)``-quantile of ``Gamma(dim, 1)``.

    Exact: ``P_f = Gamma(dim).sf(c)``. In standard space ``X_i = −ln Φ(−u_i)``, so the limit
    state is strongly non-linear and bends back towards the mean (about ``u_i²/2`` per
    coordinate): the sum of exponentials of the rare-event literature (Rubinstein & Kroese
    2017, *Simulation and the Monte Carlo Method*, 3rd ed.).
    """
    c = float(stats.gamma(dim).isf(pf))
    return Problem(f"exponential_sum_{dim}d",
                   lambda x, t: np.sum(-special.log_ndtr(-t), axis=1)[None, :] + 0 * _shift(x),
                   MultivariateNormal(np.zeros(dim), cov=np.eye(dim)), LimitState(c),
                   np.zeros((1, 0)), np.array([float(stats.gamma(dim).sf(c))]),
                   source="sum of exponentials; closed form (Gamma tail)")


def convex_waarts() -> Problem:
    """Convex limit state ``g = 0.1(u₁ − u₂)² − (u₁ + u₂)/√2 + 2.5`` (Borri & Speranzini 1997;
    Waarts 2000), failure ``g < 0``.

    Exact by 1-D quadrature in ``s = (u₁+u₂)/√2``, ``t = (u₁−u₂)/√2``:
    ``P_f = ∫ φ(t) Φ(−2.5 − 0.2 t²) dt`` = 4.2073e-3.
    """
    def resp(x: np.ndarray, t: np.ndarray) -> np.ndarray:
        u1, u2 = t[:, 0], t[:, 1]
        return -(0.1 * (u1 - u2) ** 2 - (u1 + u2) / np.sqrt(2.0) + 2.5)[None, :] + 0 * _shift(x)

    pf, _ = integrate.quad(lambda t: stats.norm.pdf(t) * special.ndtr(-2.5 - 0.2 * t * t),
                           -np.inf, np.inf, epsabs=1e-16, epsrel=1e-12)
    return Problem("convex_waarts", resp, MultivariateNormal(np.zeros(2), cov=np.eye(2)),
                   LimitState(0.0), np.zeros((1, 0)), np.array([pf]),
                   source="Borri & Speranzini (1997); Waarts (2000); exact by 1-D quadrature")


def benchmark_problems() -> list[Problem]:
    """The published reliability problems of ``benchmarks/bench_coverage.py`` (first design of
    each): linear in 2-D, 10-D (P_f = 2.9e-7) and 100-D, correlated normal, Nataf lognormals, the
    sum of two uniforms, Breitung's paraboloid (5-D; 10-D convex at 1e-7 and concave at 3e-4),
    the four-branch series system (k = 6, 7), the two-design-point parabola, the convex
    limit state of Borri & Speranzini, two-sided linear limit states (two design points, 5-D and
    10-D), a four-branch linear series system in 10-D, the sum of ten exponentials at 3e-7, the
    non-linear oscillator, a failing mean point (β = −1) and the oblique three-branch linear
    series system in 6-D and 15-D.

    >>> [p.name for p in benchmark_problems()][:3]
    ['linear_2d_beta3', 'linear_10d_beta5', 'linear_100d_beta3.5']
    """
    cn = correlated_normal()
    cn = Problem(**{**cn.__dict__, "x": cn.x[:1], "pf_exact": cn.pf_exact[:1],
                    "name": "correlated_normal_3d"})
    return [
        linear_standard(beta=3.0, dim=2), linear_standard(beta=5.0, dim=10),
        linear_standard(beta=3.5, dim=100), cn, lognormal_nataf(), uniform_sum(),
        paraboloid(beta=3.0, kappa=0.3, dim=5), paraboloid(beta=5.0, kappa=0.05, dim=10),
        paraboloid(beta=4.0, kappa=-0.1, dim=10), series_four_branch(6.0),
        series_four_branch(7.0), two_design_points(), convex_waarts(),
        two_sided_linear(dim=5, beta=3.5), two_sided_linear(dim=10, beta=5.0),
        series_linear(dim=10), exponential_sum(dim=10, pf=3e-7), nonlinear_oscillator(),
        linear_standard(beta=-1.0, dim=2), series_oblique(dim=6), series_oblique(dim=15),
    ]
