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
* the coupling of the two (a low-rank solve per θ sample): exact.

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

Multi-output Kriging: scikit-learn's ``GaussianProcessRegressor`` supports several outputs with
one kernel (its likelihood sums over them). smt's ``KRG`` warns that multi-output training is
not supported and may become an error, and one smt model per entry (hundreds) would cost
minutes of fitting and of prediction.
"""

from __future__ import annotations

import time
import warnings
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from surrogate_rbrdo.core.errors import ModelError
from surrogate_rbrdo.core.rng import require_rng
from surrogate_rbrdo.spindle.assembly import RPM, bearing_impedance
from surrogate_rbrdo.spindle.harmonic import PeakOptions, peak_search
from surrogate_rbrdo.spindle.substructure import (
    RetainedLayout,
    condensed_from_vector,
    condensed_vector,
    coupled_tool_amplitude,
    retained_layout,
    unbalance_force,
)
from surrogate_rbrdo.surrogates._common import blas_threads, seed_from

#: entries of S smaller than this fraction of ``sqrt(|S_ii| |S_jj|)`` at every training design
#: are round-off of exact zeros (e.g. x–y coupling without gyroscopics) and are set to zero
STRUCTURAL_ZERO = 1e-8


def chebyshev_nodes(lo: float, hi: float, n: int) -> np.ndarray:
    """``n`` Chebyshev points of the second kind on ``[lo, hi]`` (ascending; ends included).

    >>> chebyshev_nodes(0.0, 2.0, 3).tolist()
    [0.0, 1.0, 2.0]
    """
    if n == 1:
        return np.array([0.5 * (lo + hi)])
    k = np.arange(n)[::-1]
    return 0.5 * (lo + hi) + 0.5 * (hi - lo) * np.cos(np.pi * k / (n - 1))


def barycentric_weights(nodes: np.ndarray, at: np.ndarray) -> np.ndarray:
    """Interpolation weights ``(len(at), n)`` of Chebyshev nodes of the second kind.

    Barycentric formula (Berrut & Trefethen 2004, Eq. 5.1): ``w_j = (-1)^j``, halved at the ends.

    >>> nodes = chebyshev_nodes(-1.0, 1.0, 5)
    >>> W = barycentric_weights(nodes, np.array([0.3]))
    >>> round(float(W @ nodes**3), 12)      # a cubic is reproduced exactly
    0.027
    """
    n = nodes.size
    at = np.asarray(at, dtype=float).reshape(-1)
    if n == 1:
        return np.ones((at.size, 1))
    w = (-1.0) ** np.arange(n)
    w[0] *= 0.5
    w[-1] *= 0.5
    d = at[:, None] - nodes[None, :]
    hit = d == 0
    with np.errstate(divide="ignore", invalid="ignore"):
        c = w / d
    c = np.where(hit.any(axis=1, keepdims=True), hit.astype(float), c)
    return c / c.sum(axis=1, keepdims=True)


@dataclass(eq=False)
class MultiOutputKriging:
    """Ordinary Kriging of many outputs with one anisotropic SE kernel (scikit-learn GPR).

    Inputs are scaled to the unit box ``bounds``; every output column is standardised. Columns
    that do not vary are kept as constants.
    """

    bounds: np.ndarray
    n_start: int = 3
    alpha: float = 1e-10
    blas: int | None = 1
    gp: Any = None
    mean_: np.ndarray | None = None
    std_: np.ndarray | None = None
    vary_: np.ndarray | None = None
    const_: np.ndarray | None = None

    def fit(self, X: np.ndarray, Y: np.ndarray, *, rng: np.random.Generator
            ) -> MultiOutputKriging:
        from sklearn.gaussian_process import GaussianProcessRegressor
        from sklearn.gaussian_process.kernels import RBF
        from sklearn.gaussian_process.kernels import ConstantKernel as C

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
        self.const_ = self.mean_.copy()
        Yn = (Y[:, self.vary_] - self.mean_[self.vary_]) / self.std_[self.vary_]
        kernel = C(1.0, (1e-3, 1e4)) * RBF(np.full(d, 0.5), (1e-3, 1e5))
        self.gp = GaussianProcessRegressor(
            kernel, alpha=self.alpha, normalize_y=False, n_restarts_optimizer=self.n_start - 1,
            random_state=seed_from(rng))
        with blas_threads(self.blas), warnings.catch_warnings():
            # a length scale at its upper bound is the answer for an input S does not depend
            # on (the preload): sklearn's ConvergenceWarning says only that
            from sklearn.exceptions import ConvergenceWarning

            warnings.filterwarnings("ignore", category=ConvergenceWarning)
            self.gp.fit(self._u(X), Yn)
        return self

    def _u(self, X: np.ndarray) -> np.ndarray:
        lo, hi = self.bounds[:, 0], self.bounds[:, 1]
        return (np.atleast_2d(np.asarray(X, dtype=float)) - lo) / (hi - lo)

    def predict(self, X: np.ndarray) -> np.ndarray:
        """Predicted outputs ``(P, n_out)``."""
        out = np.tile(self.const_, (np.atleast_2d(X).shape[0], 1))
        with blas_threads(self.blas):
            p = self.gp.predict(self._u(X))
        out[:, self.vary_] = p.reshape(out.shape[0], -1) * self.std_[self.vary_] \
            + self.mean_[self.vary_]
        return out

    def loo(self) -> np.ndarray:
        """Closed-form leave-one-out predictions of the training outputs, ``(n, n_out)``.

        With the kernel fixed at the full-data fit (Dubrule 1983; here simple Kriging of the
        standardised columns, sklearn's zero-mean GP): ``e_i = (K⁻¹ y)_i / (K⁻¹)_ii``.
        """
        from scipy.linalg import cho_solve

        L = self.gp.L_
        Kinv = cho_solve((L, True), np.eye(L.shape[0]))
        e = np.atleast_2d(self.gp.alpha_.T).T / np.diag(Kinv)[:, None]
        Yn = np.atleast_2d(self.gp.y_train_.T).T
        out = np.tile(self.const_, (L.shape[0], 1))
        out[:, self.vary_] = (Yn - e) * self.std_[self.vary_] + self.mean_[self.vary_]
        return out

    @property
    def length_scales(self) -> list[float]:
        return np.atleast_1d(self.gp.kernel_.k2.length_scale).tolist()


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

    def _impedance(self, x: np.ndarray, omega: np.ndarray, theta: np.ndarray) -> np.ndarray:
        sp = self.spindle
        return bearing_impedance(sp.geometry_for(x), sp.effects, sp.theta_bearings, omega,
                                 theta)

    def _amplitude(self, x: np.ndarray, Snodes: np.ndarray, speeds: np.ndarray,
                   theta: np.ndarray) -> np.ndarray:
        """Amplitude of one design at speeds ``(S,)`` (shared by all θ rows: the rotor part
        is solved once per speed) or ``(B, S)`` (a row per θ) for θ ``(B, m)`` → ``(B, S)``."""
        B = theta.shape[0]
        rows = np.atleast_2d(np.asarray(speeds, dtype=float))           # (1 or B, S)
        if self.nodes_rpm.size == 1:
            S = Snodes[0]
        else:
            W = barycentric_weights(self.nodes_rpm, rows.ravel())
            S = np.einsum("kn,nij->kij", W, Snodes).reshape(*rows.shape, *Snodes.shape[1:])
        w = rows * RPM
        Z = self._impedance(x, np.broadcast_to(w, (B, rows.shape[1])), theta)
        f = self.force_per_w2 * w[..., None] ** 2
        return coupled_tool_amplitude(self.layout, S, Z, f)

    def response(self, x: np.ndarray, theta: np.ndarray) -> np.ndarray:
        """Predicted ``y`` (m), designs ``(P, d)`` × θ ``(N, m)`` → ``(P, N)``."""
        x = np.atleast_2d(np.asarray(x, dtype=float))
        theta = np.atleast_2d(np.asarray(theta, dtype=float))
        return self._y_from_nodes(x, self.condensed(x), theta)

    __call__ = response

    def _y_from_nodes(self, X: np.ndarray, Sn: np.ndarray, theta: np.ndarray) -> np.ndarray:
        """``y`` of designs ``X`` with node stiffnesses ``Sn`` (P, ns, r, r) at θ (N, m)."""
        out = np.empty((X.shape[0], theta.shape[0]))
        g = self.spindle.geometry
        for i, xi in enumerate(X):
            if self.kind == "at_speed":
                out[i] = self._amplitude(xi, Sn[i], np.array([self.speed_rpm]), theta)[:, 0]
                continue
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
        return np.array([self.response(z[None, :d], z[None, d:])[0, 0] for z in Z])


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
    layout = retained_layout(spindle.model(spindle.baseline))
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
    m0 = spindle.model(spindle.baseline)
    force = unbalance_force(m0, 1.0 / RPM, layout)       # U·1²: scale by Ω² at use
    info = {"structure": "substructure", "n_train": int(X.shape[0]), "fit_time_s": fit_s,
            "speed_nodes_rpm": nodes_rpm.tolist(), "retained_nodes": list(layout.nodes),
            "n_outputs": int(krg.vary_.sum()), "n_structural_zeros": int(zero.sum()),
            "length_scales_unit_box": krg.length_scales}
    return SubstructureSurrogate(spindle=spindle, layout=layout, kind=kind,
                                 speed_rpm=speed_rpm, nodes_rpm=np.asarray(nodes_rpm, float),
                                 kriging=krg, force_per_w2=force, X_train=X, V_fit=Vc,
                                 info=info)


__all__ = ["MultiOutputKriging", "SubstructureSurrogate", "barycentric_weights",
           "chebyshev_nodes", "fit_substructure_surrogate", "speed_nodes"]
