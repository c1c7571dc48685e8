"""Substructure surrogate (``[surrogate] structure = "substructure"``): Kriging of the rotor's
condensed dynamic stiffness over the design, exact bearing coupling for θ.

What is modelled
----------------
``y(x, θ)`` (the amplitude at one speed, or the peak over the speed range) is assembled from

* ``S(x, Ω)``: the rotor's dynamic stiffness condensed onto the tool, bearing and unbalance
  nodes (``spindle.substructure``). It holds no bearing and no θ, and it is smooth in ``x``
  (its poles are clamped-segment frequencies far above the speed range). One FE call per
  training *design* gives it at every speed node; a multi-output Kriging over the design box
  (shared anisotropic squared-exponential kernel, constant trend, every real entry
  standardised) predicts it at new designs.
* the bearings, ``Z(x, Ω, θ)``: the bearing laws themselves (preload, speed softening, θ,
  damping, housing stage). They cost microseconds and are not approximated.
* the coupling of the two (a low-rank solve per θ): exact. For a θ sample at one speed it is
  solved at the 3^m nodes of a θ grid only and interpolated exactly, because the tool
  displacement is a ratio of polynomials of degree ≤ 2 in each θ_j
  (``spindle.coupling.coupled_tool_amplitude_theta``): all designs × 1 000 θ in
  milliseconds.

So the only approximation is ``S`` over ``x``; the resonance and the tool-tip anti-resonance
of the assembled spindle, and the whole θ dependence, come out of the coupling algebra. A
Kriging of ``y`` itself over ``(x, θ)`` has to learn them from 200 points and smooths them away
(docs/surrogates.md, "Substructure surrogate").

The DOE is over the design box only (``n_doe`` maximin-LHS designs): θ needs no training
points. For ``kind = "peak"`` ``S`` is trained at ``sub_n_speeds`` Chebyshev nodes in ``Ω``
over the speed range and interpolated between them (barycentric formula; ``S`` is a
degree-2 polynomial in ``Ω`` plus a rational part with poles far outside the range, so the
interpolation converges geometrically), and the peak is searched exactly as the FE model's
(``harmonic.peak_search``).

Multi-output Kriging (:class:`MultiOutputKriging`, written here): one correlation shared by
all entries of ``S``, its likelihood from the ``n × n`` matrix ``Y Yᵀ``. smt's ``KRG`` warns
that multi-output training is unsupported and may become an error; one smt model per entry
(hundreds to thousands) would cost minutes of fitting and of prediction; scikit-learn's
multi-output GP works but its likelihood gradient builds an ``n × n × k`` array (800 MB and
minutes for 200 designs × 2 500 outputs).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np

from surrogate_rbrdo.core.errors import ModelError
from surrogate_rbrdo.core.rng import require_rng
from surrogate_rbrdo.spindle.assembly import RPM, bearing_impedance, check_theta, theta_affine
from surrogate_rbrdo.spindle.coupling import (
    coupled_tool_amplitude,
    coupled_tool_amplitude_sample,
)
from surrogate_rbrdo.spindle.harmonic import PeakOptions, peak_search
from surrogate_rbrdo.spindle.substructure import (
    RetainedLayout,
    condensed_from_vector,
    condensed_vector,
    retained_layout,
    unbalance_force,
)
from surrogate_rbrdo.surrogates._common import blas_threads

#: entries of S smaller than this fraction of ``sqrt(|S_ii| |S_jj|)`` at every training design
#: are round-off of exact zeros (e.g. x–y coupling without gyroscopics) and are set to zero
STRUCTURAL_ZERO = 1e-8


def chebyshev_nodes(lo: float, hi: float, n: int) -> np.ndarray:
    """``n`` Chebyshev points of the second kind on ``[lo, hi]`` (ascending; ends included).

    >>> chebyshev_nodes(0.0, 2.0, 3).tolist()
    [0.0, 1.0, 2.0]
    """
    if n < 2:
        raise ValueError(f"n = {n} is not allowed: Chebyshev nodes need n >= 2")
    k = np.arange(n)[::-1]
    return 0.5 * (lo + hi) + 0.5 * (hi - lo) * np.cos(np.pi * k / (n - 1))


def barycentric_weights(nodes: np.ndarray, at: np.ndarray) -> np.ndarray:
    """Interpolation weights ``(len(at), n)`` of Chebyshev nodes of the second kind
    (:func:`chebyshev_nodes`; the weights are wrong for other nodes).

    Barycentric formula (Berrut & Trefethen 2004, Eq. 5.1): ``w_j = (-1)^j``, halved at the ends.

    >>> nodes = chebyshev_nodes(-1.0, 1.0, 5)
    >>> W = barycentric_weights(nodes, np.array([0.3]))
    >>> round(float((W @ nodes**3)[0]), 12)      # a cubic is reproduced exactly
    0.027
    """
    n = nodes.size
    at = np.asarray(at, dtype=float).reshape(-1)
    w = (-1.0) ** np.arange(n)
    w[0] *= 0.5
    w[-1] *= 0.5
    d = at[:, None] - nodes[None, :]
    hit = d == 0
    with np.errstate(divide="ignore", invalid="ignore"):
        c = w / d
    c = np.where(hit.any(axis=1, keepdims=True), hit.astype(float), c)
    return c / c.sum(axis=1, keepdims=True)


def _corr(U: np.ndarray, V: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """Anisotropic squared-exponential correlation ``exp(-Σ_j θ_j (u_j - v_j)²)``."""
    d2 = (U[:, None, :] - V[None, :, :]) ** 2
    return np.exp(-(d2 @ theta))


@dataclass(eq=False)
class MultiOutputKriging:
    """Kriging of many outputs with one anisotropic squared-exponential correlation.

    Inputs are scaled to the unit box ``bounds``; every output column is centred and scaled
    (columns that do not vary are kept as constants). Model: each standardised column
    ``(y_c − μ_c) / s_c`` is a zero-mean Gaussian process with covariance ``σ² R_θ``, one
    ``σ²`` and one correlation ``θ`` for all columns, chosen to maximise the concentrated
    likelihood summed over the ``k`` columns,

        ℓ(θ) = −(n k / 2) log σ̂² − (k / 2) log |R_θ|,   σ̂² = tr(R_θ⁻¹ Y Yᵀ) / (n k),

    which needs only the ``n × n`` matrix ``Y Yᵀ``: the cost does not grow with ``k`` (the
    condensed stiffness at 12 speeds has ~2 500 outputs). This is smt's reduced likelihood
    (Jones et al. 1998) with the trend replaced by the column mean, for several outputs.
    ``θ`` is optimised in ``log10`` by L-BFGS-B from ``n_start`` starts (the first at
    ``θ = 1``, the others log-uniform in ``[0.01, 100]``), bounds ``[1e-8, 1e4]`` (an input
    ``S`` does not depend on, the preload, goes to the lower bound).
    """

    bounds: np.ndarray
    n_start: int = 3
    nugget: float = 1e-12
    theta_: np.ndarray | None = None
    mean_: np.ndarray | None = None
    std_: np.ndarray | None = None
    vary_: np.ndarray | None = None
    U_: np.ndarray | None = field(default=None, repr=False)
    W_: np.ndarray | None = field(default=None, repr=False)
    Rinv_diag_: np.ndarray | None = field(default=None, repr=False)
    Yn_: np.ndarray | None = field(default=None, repr=False)
    nugget_used_: float | None = None

    def _nll(self, log_theta: np.ndarray, D2: np.ndarray, YY: np.ndarray, k: int
             ) -> tuple[float, np.ndarray]:
        """``−ℓ / k`` and its gradient in ``log10 θ`` (``D2``: squared distances, (n, n, d)).

        ``∂/∂θ_j = −tr(R⁻¹ R_j R⁻¹ YYᵀ) / (2 k σ̂²) + tr(R⁻¹ R_j) / 2`` with
        ``R_j = −D2_j ∘ R``.
        """
        n = D2.shape[0]
        th = 10.0 ** log_theta
        R = np.exp(-(D2 @ th)) + self.nugget * np.eye(n)
        try:
            L = np.linalg.cholesky(R)
        except np.linalg.LinAlgError:
            return np.inf, np.zeros_like(log_theta)
        from scipy.linalg import cho_solve

        Ri = cho_solve((L, True), np.eye(n))
        RiYY = cho_solve((L, True), YY)
        s2 = np.trace(RiYY) / (n * k)
        if not s2 > 0:
            return np.inf, np.zeros_like(log_theta)
        f = 0.5 * n * np.log(s2) + np.sum(np.log(np.diag(L)))
        A = RiYY @ Ri                                        # R⁻¹ YYᵀ R⁻¹ (symmetric)
        dR = -D2 * R[..., None]                              # (n, n, d)
        g = (-np.einsum("ij,ijk->k", A, dR) / (2.0 * k * s2)
             + 0.5 * np.einsum("ij,ijk->k", Ri, dR))
        return float(f), g * th * np.log(10.0)

    def fit(self, X: np.ndarray, Y: np.ndarray, *, rng: np.random.Generator
            ) -> MultiOutputKriging:
        from scipy.optimize import minimize

        X = np.asarray(X, dtype=float)
        Y = np.asarray(Y, dtype=float)
        d = X.shape[1]
        if X.shape[0] < d + 1:
            raise ValueError(f"n_doe = {X.shape[0]} is not allowed: the Kriging of the "
                             f"condensed rotor needs at least d + 1 = {d + 1} designs")
        self.mean_ = Y.mean(axis=0)
        sd = Y.std(axis=0)
        scale = np.abs(Y).max(axis=0)
        self.vary_ = sd > 1e-13 * np.where(scale > 0, scale, 1.0)
        self.std_ = np.where(self.vary_, sd, 1.0)
        if not self.vary_.any():
            raise ModelError("MultiOutputKriging: no output varies over the training designs "
                             "(the condensed rotor does not depend on the design variables)")
        Yn = (Y[:, self.vary_] - self.mean_[self.vary_]) / self.std_[self.vary_]
        U = self._u(X)
        D2 = (U[:, None, :] - U[None, :, :]) ** 2
        YY = Yn @ Yn.T
        k = Yn.shape[1]
        starts = [np.zeros(d)] + [rng.uniform(-2.0, 2.0, d) for _ in range(self.n_start - 1)]
        best = None
        with blas_threads(1):
            for x0 in starts:
                r = minimize(self._nll, x0, args=(D2, YY, k), method="L-BFGS-B",
                             jac=True, bounds=[(-8.0, 4.0)] * d)
                if best is None or r.fun < best.fun:
                    best = r
        if best is None or not np.isfinite(best.fun):
            raise ModelError("MultiOutputKriging: no correlation parameters with a finite "
                             "likelihood (duplicate designs?)")
        self.theta_ = 10.0 ** best.x
        self.U_, self.Yn_ = U, Yn
        self._condition()
        return self

    def _condition(self) -> None:
        """Weights ``R⁻¹ Y`` by Cholesky solves (an explicit inverse loses digits: ``R`` of
        smooth data has a condition number near ``1 / nugget``)."""
        from scipy.linalg import cho_factor, cho_solve

        n = self.U_.shape[0]
        R = _corr(self.U_, self.U_, self.theta_)
        for nug in self.nugget * 10.0 ** np.arange(5):
            try:
                c = cho_factor(R + nug * np.eye(n), lower=True)
                break
            except np.linalg.LinAlgError:
                continue
        else:
            raise ModelError("MultiOutputKriging: the correlation matrix is singular "
                             "(duplicate designs?)")
        self.nugget_used_ = float(nug)
        self.W_ = cho_solve(c, self.Yn_)
        self.Rinv_diag_ = np.diag(cho_solve(c, np.eye(n))).copy()

    def _u(self, X: np.ndarray) -> np.ndarray:
        lo, hi = self.bounds[:, 0], self.bounds[:, 1]
        return (np.atleast_2d(np.asarray(X, dtype=float)) - lo) / (hi - lo)

    def predict(self, X: np.ndarray) -> np.ndarray:
        """Predicted outputs ``(P, n_out)`` (the Kriging mean)."""
        U = self._u(X)
        out = np.tile(self.mean_, (U.shape[0], 1))   # the constant columns: their mean
        out[:, self.vary_] = (_corr(U, self.U_, self.theta_) @ self.W_) * self.std_[self.vary_] \
            + self.mean_[self.vary_]
        return out

    def loo(self) -> np.ndarray:
        """Closed-form leave-one-out predictions of the training outputs, ``(n, n_out)``.

        Simple-Kriging identity ``e_i = (R⁻¹ y)_i / (R⁻¹)_ii`` (Dubrule 1983), with the
        correlation, the column means and the scaling all fixed at the full-data fit (Dubrule's
        ordinary-Kriging form re-estimates the mean; measured: it changes S by ≤ 1.4e-6 and
        the LOO y by ≤ 3e-6 relative at n = 30).
        """
        e = self.W_ / self.Rinv_diag_[:, None]
        out = np.tile(self.mean_, (self.U_.shape[0], 1))
        out[:, self.vary_] = (self.Yn_ - e) * self.std_[self.vary_] + self.mean_[self.vary_]
        return out

    @property
    def length_scales(self) -> list[float]:
        """``1 / sqrt(2 θ)`` per input (unit box), comparable to an RBF length scale."""
        return (1.0 / np.sqrt(2.0 * self.theta_)).tolist()


@dataclass(eq=False)
class SubstructureSurrogate:
    """``y(x, θ)`` from a Kriging of the condensed rotor and the exact bearing coupling.

    Calling it (or :meth:`response`) is the core ``Response``: designs ``(P, d)`` × θ
    ``(N, m)`` → ``(P, N)`` metres. Build it with :func:`fit_substructure_surrogate`.
    """

    spindle: Any
    layout: RetainedLayout
    kind: str
    speed_rpm: float | None
    nodes_rpm: np.ndarray
    kriging: MultiOutputKriging
    force_per_w2: np.ndarray
    X_train: np.ndarray
    V_fit: np.ndarray
    peak_options: PeakOptions = field(default_factory=PeakOptions)
    info: dict[str, Any] = field(default_factory=dict)

    @property
    def n_train(self) -> int:
        """FE calls of the training (one per design)."""
        return int(self.X_train.shape[0])

    def condensed(self, x: np.ndarray) -> np.ndarray:
        """Predicted ``S`` at the speed nodes, ``(P, n_nodes, r, r)`` complex."""
        v = self.kriging.predict(x)
        r = self.layout.n_dof
        return condensed_from_vector(v.reshape(v.shape[0], self.nodes_rpm.size, -1), r)

    @cached_property
    def theta_affine(self) -> bool:
        """Whether the θ sample can go through the θ-polynomial coupling (every
        θ bearing's impedance affine in its factor: no housing stage in series with it)."""
        sp = self.spindle
        return theta_affine(sp.geometry, sp.effects, sp.theta_bearings)

    def _impedance(self, X: np.ndarray, omega: np.ndarray, theta: np.ndarray) -> np.ndarray:
        """Bearing impedances of designs ``X`` (P, d) at speeds ``omega`` (broadcast to
        (P, B, S)) and θ rows ``theta`` (B, m): ``(P, B, S, nb, 2, 2)``, all in one call of
        the bearing laws (a design enters them only through ``DesignMap.bearing_preloads``)."""
        sp = self.spindle
        P, B = X.shape[0], theta.shape[0]
        om = np.broadcast_to(omega, (P, B, np.shape(omega)[-1])).reshape(P * B, -1)
        pre = {k: np.repeat(v, B)[:, None] for k, v in sp.design_map.bearing_preloads(X).items()}
        Z = bearing_impedance(sp.geometry, sp.effects, sp.theta_bearings, om,
                              np.tile(theta, (P, 1)), preloads=pre)
        return Z.reshape(P, B, *Z.shape[1:])

    def _amplitude(self, x: np.ndarray, Snodes: np.ndarray, speeds: np.ndarray,
                   theta: np.ndarray) -> np.ndarray:
        """Amplitude of one design at speeds ``(S,)`` (shared by all θ rows: the rotor part
        is solved once per speed) or ``(B, S)`` (a row per θ) for θ ``(B, m)`` → ``(B, S)``;
        ``S`` interpolated between the speed nodes (the peak response)."""
        rows = np.atleast_2d(np.asarray(speeds, dtype=float))           # (1 or B, S)
        W = barycentric_weights(self.nodes_rpm, rows.ravel())
        S = (W @ Snodes.reshape(Snodes.shape[0], -1)).reshape(*rows.shape, *Snodes.shape[1:])
        w = rows * RPM
        Z = self._impedance(x[None], w, theta)[0]
        f = self.force_per_w2 * w[..., None] ** 2
        return coupled_tool_amplitude(self.layout, S, Z, f)

    def _check(self, x: np.ndarray, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Designs inside the box and θ of the right width, finite and > 0, else ValueError."""
        x = np.atleast_2d(np.asarray(x, dtype=float))
        d = self.X_train.shape[1]
        if x.ndim != 2 or x.shape[1] != d:
            raise ValueError(f"x has shape {np.shape(x)}: must be (P, {d}) = designs "
                             f"{list(self.spindle.design_map.names)}")
        return self.spindle.design_map.check_batch(x), check_theta(self.spindle.theta_bearings,
                                                                    theta)

    def response(self, x: np.ndarray, theta: np.ndarray) -> np.ndarray:
        """Predicted ``y`` (m), designs ``(P, d)`` × θ ``(N, m)`` → ``(P, N)``."""
        x, theta = self._check(x, theta)
        return self._y_from_nodes(x, self.condensed(x), theta)

    __call__ = response

    def _y_from_nodes(self, X: np.ndarray, Sn: np.ndarray, theta: np.ndarray) -> np.ndarray:
        """``y`` of designs ``X`` with node stiffnesses ``Sn`` (P, ns, r, r) at θ (N, m)."""
        if self.kind == "at_speed":
            # all designs at once: 3^m exact solves per design and an (N, 3^m) product
            w = np.array([self.speed_rpm * RPM])
            return coupled_tool_amplitude_sample(
                self.layout, Sn[:, 0], self.force_per_w2 * w[0] ** 2, theta,
                lambda rows, which: self._impedance(X[which], w, rows)[:, :, 0],
                affine=self.theta_affine)
        out = np.empty((X.shape[0], theta.shape[0]))
        g = self.spindle.geometry
        for i, xi in enumerate(X):
            for s in range(0, theta.shape[0], 64):
                out[i, s:s + 64] = peak_search(
                    lambda spd, th, xi=xi, Si=Sn[i]: self._amplitude(xi, Si, spd, th),
                    theta[s:s + 64], g.speed_min_rpm, g.speed_max_rpm, self.peak_options)[0]
        if not np.all(np.isfinite(out)):
            raise ModelError("substructure surrogate: non-finite amplitude")
        return out

    def loo_points(self) -> tuple[np.ndarray, np.ndarray]:
        """``y`` at the training designs (nominal θ): exact (their FE condensation, coupled)
        and leave-one-out (closed-form LOO of the Kriging of ``S``, coupled the same way)."""
        r, ns = self.layout.n_dof, self.nodes_rpm.size
        n = self.X_train.shape[0]
        th = np.ones((1, len(self.spindle.theta_bearings)))
        S_true = condensed_from_vector(self.V_fit.reshape(n, ns, -1), r)
        S_loo = condensed_from_vector(self.kriging.loo().reshape(n, ns, -1), r)
        return (self._y_from_nodes(self.X_train, S_true, th)[:, 0],
                self._y_from_nodes(self.X_train, S_loo, th)[:, 0])

    def response_points(self, Z: np.ndarray) -> np.ndarray:
        """``y`` (m) at joint points ``Z = [x, θ]`` (n, d + m)."""
        Z = np.atleast_2d(np.asarray(Z, dtype=float))
        d = self.X_train.shape[1]
        X, T = self._check(Z[:, :d], Z[:, d:])
        Sn = self.condensed(X)                     # one Kriging prediction for all points
        return np.array([self._y_from_nodes(X[i:i + 1], Sn[i:i + 1], T[i:i + 1])[0, 0]
                         for i in range(X.shape[0])])


def speed_nodes(spindle: Any, kind: str, speed_rpm: float | None, n_speeds: int) -> np.ndarray:
    """Speeds (rpm) at which ``S`` is trained: the one speed, or Chebyshev nodes in the range."""
    if kind == "at_speed":
        return np.array([float(speed_rpm)])
    g = spindle.geometry
    return chebyshev_nodes(g.speed_min_rpm, g.speed_max_rpm, n_speeds)


def fit_substructure_surrogate(spindle: Any, X: np.ndarray, V: np.ndarray, *, kind: str,
                               speed_rpm: float | None, nodes_rpm: np.ndarray,
                               rng: np.random.Generator, n_start: int = 3
                               ) -> SubstructureSurrogate:
    """Fit the Kriging of ``S`` to FE condensations ``V`` (one row per design of ``X``).

    ``V`` rows are ``spindle.substructure.PointwiseCondensed`` outputs at ``nodes_rpm``
    (kept, with the structural zeros applied, as ``V_fit``).
    Entries that are zero in exact arithmetic (below :data:`STRUCTURAL_ZERO` of their diagonal
    scale at every design) are set to zero instead of being fitted to round-off.
    """
    rng = require_rng(rng)
    X = np.atleast_2d(np.asarray(X, dtype=float))
    V = np.atleast_2d(np.asarray(V, dtype=float))
    m0 = spindle.model(spindle.baseline)
    layout = retained_layout(m0)
    r, ns = layout.n_dof, nodes_rpm.size
    S = condensed_from_vector(V.reshape(V.shape[0], ns, -1), r)        # (n, ns, r, r)
    dg = np.abs(np.einsum("knii->kni", S))
    ratio = np.abs(S) / np.sqrt(dg[..., :, None] * dg[..., None, :])
    zero = np.all(ratio < STRUCTURAL_ZERO, axis=0)                       # (ns, r, r)
    S = np.where(zero, 0.0, S)
    Vc = condensed_vector(S).reshape(V.shape[0], -1)
    t0 = time.perf_counter()
    krg = MultiOutputKriging(bounds=np.asarray(spindle.design_map.bounds, dtype=float),
                             n_start=n_start).fit(X, Vc, rng=rng)
    fit_s = time.perf_counter() - t0
    force = unbalance_force(m0, 1.0 / RPM, layout)       # at Ω = 1 rad/s: scale by Ω² at use
    info = {"structure": "substructure", "transform": "none (S standardised per entry)",
            "n_train": int(X.shape[0]), "fit_time_s": fit_s,
            "speed_nodes_rpm": nodes_rpm.tolist(), "retained_nodes": list(layout.nodes),
            "n_outputs": int(krg.vary_.sum()), "n_structural_zeros": int(zero.sum()),
            "length_scales_unit_box": krg.length_scales, "nugget": krg.nugget_used_}
    return SubstructureSurrogate(spindle=spindle, layout=layout, kind=kind,
                                 speed_rpm=speed_rpm, nodes_rpm=np.asarray(nodes_rpm, float),
                                 kriging=krg, force_per_w2=force, X_train=X, V_fit=Vc,
                                 info=info)


__all__ = ["MultiOutputKriging", "SubstructureSurrogate", "barycentric_weights",
           "chebyshev_nodes", "fit_substructure_surrogate", "speed_nodes"]
