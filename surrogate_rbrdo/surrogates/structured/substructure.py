"""Structure ``"substructure"``: Kriging of the rotor's
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

So the only approximation is ``S`` over ``x``; the resonance and the tool-tip cancellation notch
of the assembled spindle, and the whole θ dependence, come out of the coupling algebra. A
Kriging of ``y`` itself over ``(x, θ)`` has to learn them from 200 points and smooths them away
(docs/surrogates.md, "Substructure surrogate").

The DOE is over the design box only (``n_doe`` maximin-LHS designs): θ needs no training
points. For ``kind = "peak"`` ``S`` is trained at ``sub_n_speeds`` Chebyshev nodes in ``Ω``
over the speed range and interpolated between them (barycentric formula; ``S`` is a
degree-2 polynomial in ``Ω`` plus a rational part with poles far outside the range, so the
interpolation converges geometrically), and the peak is searched exactly as the FE model's
(``harmonic.peak_search``).

The Kriging of ``S`` is :class:`~surrogate_rbrdo.surrogates.multioutput.MultiOutputKriging`
(one correlation shared by all entries, its likelihood from the ``n × n`` matrix ``Y Yᵀ``).
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any, ClassVar

import numpy as np

from surrogate_rbrdo.core.errors import ModelError
from surrogate_rbrdo.core.protocols import LimitState, Prediction
from surrogate_rbrdo.core.rng import require_rng
from surrogate_rbrdo.core.validate import check_int
from surrogate_rbrdo.doe import lhs
from surrogate_rbrdo.sampling.evaluate import evaluate_points
from surrogate_rbrdo.spindle.assembly import RPM, bearing_impedance, check_theta, theta_affine
from surrogate_rbrdo.spindle.coupling import (
    coupled_tool_amplitude,
    coupled_tool_amplitude_sample,
)
from surrogate_rbrdo.spindle.evaluate import ResponseSpec
from surrogate_rbrdo.spindle.harmonic import PeakOptions, peak_search
from surrogate_rbrdo.spindle.substructure import (
    PointwiseCondensed,
    RetainedLayout,
    condensed_from_vector,
    condensed_vector,
    retained_layout,
    unbalance_force,
)
from surrogate_rbrdo.surrogates.multioutput import MultiOutputKriging
from surrogate_rbrdo.surrogates.structured.base import (
    SamplingOptions,
    TrainedSurrogate,
    kriging_bytes,
    register_structure,
)
from surrogate_rbrdo.surrogates.validation import LOOSummary, validation_metrics

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

    def predict(self, Z: np.ndarray) -> Prediction:
        """Point predictions at joint points; no predictive std (NaN): the Kriging of ``S``
        has one per entry of ``S``, not one of ``y``."""
        y = self.response_points(Z)
        return Prediction(mean=y, std=np.full_like(y, np.nan))

    def loo_summary(self) -> LOOSummary:
        """LOO of the Kriging of ``S`` at the training designs, ``y`` at nominal θ (metrics of
        ``log y``)."""
        y_tr, y_lo = self.loo_points()
        lm = validation_metrics(np.log(y_tr), np.log(y_lo))
        return LOOSummary("closed_form_condensed", self.n_train, lm.r2, lm.rmse, y_tr, y_lo, {})

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


@dataclass(frozen=True)
class SubstructureOptions(SamplingOptions):
    """Options of the substructure surrogate (``structure = "substructure"``; static DOE over
    the designs only, θ is exact).

    Attributes
    ----------
    n_doe : int
        Training designs (maximin LHS over the design box; one FE condensation each), >= 7.
    n_start : int
        Multistarts of the multi-output Kriging's likelihood optimisation.
    sub_n_speeds : int
        The peak response: Chebyshev speed nodes at which ``S`` is trained and between which
        it is interpolated (the at-speed response uses its one speed).
    """

    structure: ClassVar[str] = "substructure"
    n_doe: int = 200
    n_start: int = 5
    sub_n_speeds: int = 12

    def __post_init__(self) -> None:
        super().__post_init__()
        check_int("n_doe", self.n_doe, minimum=7)
        check_int("n_start", self.n_start, minimum=1)
        check_int("sub_n_speeds", self.sub_n_speeds, minimum=2)

    def memory_bytes(self) -> dict[str, float]:
        """Peak bytes (``core.memory``): the multi-output Kriging on ``n_doe`` designs and
        its outputs, ``2 · sub_n_speeds · r²`` per design for ``r`` retained DOFs (at least
        12: the tool tip and two bearings, 4 DOFs each; a lower bound, the geometry is not
        known here), and one design's rotor dynamic stiffness, ``sub_n_speeds`` complex
        ``r × r`` matrices or more.

        >>> SubstructureOptions(sub_n_speeds=10 ** 8).memory_bytes()["sub_n_speeds"] > 1e11
        True
        """
        r2 = 12.0 ** 2
        return {"n_doe": kriging_bytes(self.n_doe),
                "sub_n_speeds": 8.0 * 2 * self.sub_n_speeds * r2 * (self.n_doe + 2)}

    def check_response(self, response: ResponseSpec) -> None:
        if response.kind == "peak_unbalance":
            raise ValueError("structure = 'substructure' is not allowed with response.kind = "
                             "'peak_unbalance': its coupling takes the geometry's fixed "
                             "unbalance; the exact coupling of the random-unbalance peak is "
                             "the FE model itself (structure = 'fe'), or use 'global'")


@register_structure("substructure", SubstructureOptions, "Kriging of the rotor's condensed "
                    "dynamic stiffness over the designs, bearings and θ coupled exactly")
def train_substructure(spindle: Any, inputs: Any, limit: LimitState, response: ResponseSpec,
                       options: SubstructureOptions, *, rng: np.random.Generator,
                       cache: Any = None, counter: Any, progress: bool = False,
                       label: str = "") -> TrainedSurrogate:
    """LHS over the designs → FE condensations → fit (``inputs`` and ``limit`` are not
    needed: θ is coupled exactly)."""
    o = options
    r_doe, r_fit = require_rng(rng).spawn(2)
    start, start_cached = counter.calls, counter.cached
    t0 = time.perf_counter()
    xb = np.asarray(spindle.design_map.bounds, dtype=float)
    nodes = speed_nodes(spindle, response.kind, response.speed_rpm, o.sub_n_speeds)
    m0 = spindle.model(spindle.baseline)
    lay = retained_layout(m0)
    func = PointwiseCondensed(spindle, tuple(float(s) for s in nodes), lay.nodes,
                              tuple(complex(u) for u in m0.unbalance))
    X = lhs(o.n_doe, xb, rng=r_doe)
    res = evaluate_points(
        func, X, n_jobs=o.n_jobs, backend=o.backend, cache=cache, counter=counter,
        on_nonfinite="raise", progress=progress, n_outputs=func.n_outputs(lay.n_dof),
        client="local" if o.backend == "dask" else None,
        desc=f"{label} FE: condensed rotor".strip())
    sample_s = time.perf_counter() - t0
    model = fit_substructure_surrogate(spindle, X, res.y, kind=response.kind,
                                       speed_rpm=response.speed_rpm, nodes_rpm=nodes,
                                       rng=r_fit, n_start=o.n_start)
    info = {**model.info, "sampling_time_s": sample_s, "bounds": xb.tolist(),
            "active_learning": False, "response": response.label}
    model.info = dict(info)
    return TrainedSurrogate("substructure", model, o, response, fe_calls=counter.calls - start,
                            fe_cache_hits=counter.cached - start_cached, info=info)


__all__ = ["SubstructureOptions", "SubstructureSurrogate", "barycentric_weights",
           "chebyshev_nodes", "fit_substructure_surrogate", "speed_nodes", "train_substructure"]
