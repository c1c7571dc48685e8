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

``kind = "peak_unbalance"`` (the credible problem: random magnitude and phase per plane): the
response is linear in the unbalance phasors, so the interpolated ``S`` enters the exact
coupled tables of the FE fast path (``spindle.peak_coupling.tables_from_condensed``: the
determinant and each plane's numerator on a geometric speed grid, at the 3^m θ nodes), each
design's permissible unbalance (ISO 21940-11, from its geometry) times θ's unit phasors
combines the planes, and the peak is searched on the tables (``peak_by_tables``), as the
fast path does with the FE condensation. Without the interior determinant (it would need the
FE model at the prediction design) ``D = det K_c`` is smooth in speed only where ``S`` is:
the same condition the Chebyshev interpolation of ``S`` already needs.

The Kriging of ``S`` is :class:`~surrogate_rbrdo.surrogates.multioutput.MultiOutputKriging`
(one correlation shared by all entries, its likelihood from the ``n × n`` matrix ``Y Yᵀ``).
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np

from surrogate_rbrdo.core.errors import ModelError
from surrogate_rbrdo.core.protocols import Prediction
from surrogate_rbrdo.core.rng import require_rng
from surrogate_rbrdo.spindle.assembly import RPM, bearing_impedance, check_theta, theta_affine
from surrogate_rbrdo.spindle.coupling import (
    coupled_tool_amplitude,
    coupled_tool_amplitude_sample,
    theta_grid,
)
from surrogate_rbrdo.spindle.harmonic import PeakOptions, peak_search
from surrogate_rbrdo.spindle.peak_coupling import (
    forward_basis,
    invariant_part,
    peak_by_tables,
    rotation_residual,
    tables_from_condensed,
)
from surrogate_rbrdo.spindle.peak_response import PeakUnbalanceResponse
from surrogate_rbrdo.spindle.substructure import (
    RetainedLayout,
    condensed_from_vector,
    condensed_vector,
    retained_layout,
    unbalance_force,
)
from surrogate_rbrdo.spindle.unbalance import (
    geometry_permissible_unbalance,
    geometry_rotor_mass_kg,
)
from surrogate_rbrdo.surrogates.multioutput import MultiOutputKriging
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
    unbalance_response: PeakUnbalanceResponse | None = None
    rotor_invariant: bool = False

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
        """Designs inside the box and θ of the right width, finite and > 0, else ValueError
        (``kind = "peak_unbalance"``: θ's columns are checked where they are split)."""
        x = np.atleast_2d(np.asarray(x, dtype=float))
        d = self.X_train.shape[1]
        if x.ndim != 2 or x.shape[1] != d:
            raise ValueError(f"x has shape {np.shape(x)}: must be (P, {d}) = designs "
                             f"{list(self.spindle.design_map.names)}")
        x = self.spindle.design_map.check_batch(x)
        if self.unbalance_response is not None:
            return x, np.atleast_2d(np.asarray(theta, dtype=float))
        return x, check_theta(self.spindle.theta_bearings, theta)

    def response(self, x: np.ndarray, theta: np.ndarray) -> np.ndarray:
        """Predicted ``y`` (m), designs ``(P, d)`` × θ ``(N, m)`` → ``(P, N)``."""
        x, theta = self._check(x, theta)
        return self._y_from_nodes(x, self.condensed(x), theta)

    __call__ = response

    def _y_from_nodes(self, X: np.ndarray, Sn: np.ndarray, theta: np.ndarray) -> np.ndarray:
        """``y`` of designs ``X`` with node stiffnesses ``Sn`` (P, ns, r, r) at θ (N, m)."""
        if self.kind == "peak_unbalance":
            return self._peak_unbalance(X, Sn, theta)
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

    def _peak_unbalance(self, X: np.ndarray, Sn: np.ndarray, theta: np.ndarray) -> np.ndarray:
        """The random-unbalance peak: ``S`` interpolated from the Chebyshev nodes to the
        geometric speed grid of ``spindle.peak_coupling``, the bearings and θ coupled
        exactly at the θ nodes, each design's permissible unbalance times θ's unit phasors,
        and the peak searched on the tables (``peak_coupling.peak_by_tables``). When the
        training condensations are invariant under rotation about the axis (an axisymmetric
        rotor), so is the predicted ``S`` (:func:`invariant_part`; the Kriging of its
        entries breaks it at ~1e-9), and the forward-whirl block alone is solved."""
        resp, opt = self.unbalance_response, self.unbalance_response.options
        k, unit = resp.split(theta)
        g = self.spindle.geometry
        lo, hi = resp.speed_range_rpm or (g.speed_min_rpm, g.speed_max_rpm)
        speeds = np.geomspace(lo, hi, opt.n_grid)
        W = barycentric_weights(self.nodes_rpm, speeds)                  # (G, ns)
        w = speeds * RPM
        grid = theta_grid(k)
        out = np.empty((X.shape[0], k.shape[0]))
        if self.rotor_invariant:
            Sn = invariant_part(Sn, forward_basis(self.layout))
        for i, x in enumerate(X):
            S = np.einsum("gn,nab->gab", W, Sn[i])
            U = geometry_permissible_unbalance(self.spindle.geometry_for(x),
                                               resp.tolerances) * unit

            def tables(rows, x=x, S=S):
                Z = self._impedance(x[None], w, rows)[0]                  # (K, G, nb, 2, 2)
                return tables_from_condensed(self.layout, speeds, rows, S, Z)

            out[i] = peak_by_tables(tables, k, U, opt, affine=self.theta_affine,
                                    grid=grid).amplitude
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
        """``y`` at the training designs (θ of :meth:`_nominal_theta`): exact (their FE
        condensation, coupled) and leave-one-out (closed-form LOO of the Kriging of ``S``,
        coupled the same way)."""
        r, ns = self.layout.n_dof, self.nodes_rpm.size
        n = self.X_train.shape[0]
        th = self._nominal_theta()
        S_true = condensed_from_vector(self.V_fit.reshape(n, ns, -1), r)
        S_loo = condensed_from_vector(self.kriging.loo().reshape(n, ns, -1), r)
        return (self._y_from_nodes(self.X_train, S_true, th).max(axis=1),
                self._y_from_nodes(self.X_train, S_loo, th).max(axis=1))

    def _nominal_theta(self) -> np.ndarray:
        """θ of the LOO check: nominal stiffness; with a random unbalance the deterministic
        design basis (every plane at its permissible value, in phase and in couple: ``y``
        is the worse of the two rows, ``ThetaSpec.unbalance_cases``)."""
        if self.unbalance_response is None:
            return np.ones((1, len(self.spindle.theta_bearings)))
        spec = self.unbalance_response.theta_spec
        t0 = np.array([0.0 if n == "thermal_preload" or n.startswith("phase") else 1.0
                       for n in spec.names])
        return spec.unbalance_cases(t0)

    def response_points(self, Z: np.ndarray) -> np.ndarray:
        """``y`` (m) at joint points ``Z = [x, θ]`` (n, d + m)."""
        Z = np.atleast_2d(np.asarray(Z, dtype=float))
        d = self.X_train.shape[1]
        X, T = self._check(Z[:, :d], Z[:, d:])
        Sn = self.condensed(X)                     # one Kriging prediction for all points
        return np.array([self._y_from_nodes(X[i:i + 1], Sn[i:i + 1], T[i:i + 1])[0, 0]
                         for i in range(X.shape[0])])


def fit_substructure_surrogate(spindle: Any, X: np.ndarray, V: np.ndarray, *, kind: str,
                               speed_rpm: float | None, nodes_rpm: np.ndarray,
                               rng: np.random.Generator, n_start: int = 3,
                               unbalance_response: PeakUnbalanceResponse | None = None
                               ) -> SubstructureSurrogate:
    """Fit the Kriging of ``S`` to FE condensations ``V`` (one row per design of ``X``).

    ``kind = "peak_unbalance"`` needs ``unbalance_response`` (θ's columns, the unbalance
    tolerances and the peak search; ``PeakUnbalanceSpec.fe_response(spindle, "condensed")``).

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
    _check_unbalance_response(spindle, m0, layout, nodes_rpm, kind, unbalance_response)
    r, ns = layout.n_dof, nodes_rpm.size
    S = condensed_from_vector(V.reshape(V.shape[0], ns, -1), r)        # (n, ns, r, r)
    dg = np.abs(np.einsum("knii->kni", S))
    ratio = np.abs(S) / np.sqrt(dg[..., :, None] * dg[..., None, :])
    zero = np.all(ratio < STRUCTURAL_ZERO, axis=0)                       # (ns, r, r)
    S = np.where(zero, 0.0, S)
    Vc = condensed_vector(S).reshape(V.shape[0], -1)
    invariant = rotation_residual(S, forward_basis(layout)) <= 1e-10
    t0 = time.perf_counter()
    krg = MultiOutputKriging(bounds=np.asarray(spindle.design_map.bounds, dtype=float),
                             n_start=n_start).fit(X, Vc, rng=rng)
    fit_s = time.perf_counter() - t0
    force = unbalance_force(m0, 1.0 / RPM, layout)       # at Ω = 1 rad/s: scale by Ω² at use
    info = {"structure": "substructure", "transform": "none (S standardised per entry)",
            "n_train": int(X.shape[0]), "fit_time_s": fit_s,
            "speed_nodes_rpm": nodes_rpm.tolist(), "retained_nodes": list(layout.nodes),
            "n_outputs": int(krg.vary_.sum()), "n_structural_zeros": int(zero.sum()),
            "length_scales_unit_box": krg.length_scales, "nugget": krg.nugget_used_,
            "rotor_invariant": bool(invariant)}
    return SubstructureSurrogate(spindle=spindle, layout=layout, kind=kind,
                                 speed_rpm=speed_rpm, nodes_rpm=np.asarray(nodes_rpm, float),
                                 kriging=krg, force_per_w2=force, X_train=X, V_fit=Vc,
                                 info=info, unbalance_response=unbalance_response,
                                 rotor_invariant=invariant)


def _check_unbalance_response(spindle: Any, m0: Any, layout: RetainedLayout,
                              nodes_rpm: np.ndarray, kind: str,
                              resp: PeakUnbalanceResponse | None) -> None:
    """``resp`` given exactly for ``kind = "peak_unbalance"``, with this spindle's θ bearings
    and unbalance planes and a speed range inside the speed nodes (no extrapolation of
    ``S``), and the geometry's rotor mass (the permissible unbalance at prediction designs)
    the FE model's."""
    if (kind == "peak_unbalance") != (resp is not None):
        raise ValueError(f"unbalance_response is not allowed to be "
                         f"{'None' if resp is None else 'given'} with kind = {kind!r}: "
                         "give it exactly for 'peak_unbalance'")
    if resp is None:
        return
    spec = resp.theta_spec
    if tuple(spec.bearings) != tuple(spindle.theta_bearings):
        raise ValueError(f"unbalance_response.theta_spec.bearings = {list(spec.bearings)} is "
                         f"not allowed: must be the spindle's {list(spindle.theta_bearings)}")
    if spec.n_planes != len(layout.unbalance):
        raise ValueError(f"unbalance_response.theta_spec.n_planes = {spec.n_planes} is not "
                         f"allowed: the geometry has {len(layout.unbalance)} unbalance planes")
    lo, hi = resp.speed_range_rpm or (spindle.geometry.speed_min_rpm,
                                      spindle.geometry.speed_max_rpm)
    if lo < nodes_rpm.min() or hi > nodes_rpm.max():
        raise ValueError(f"unbalance_response.speed_range_rpm = ({lo}, {hi}) is not allowed: "
                         f"must lie inside the speed nodes [{nodes_rpm.min()}, "
                         f"{nodes_rpm.max()}] rpm (S is not extrapolated)")
    mg = geometry_rotor_mass_kg(spindle.geometry_for(spindle.baseline))
    if not np.isclose(mg, m0.rotor_mass_kg, rtol=1e-9):
        raise ModelError(f"rotor mass from the geometry {mg:.6g} kg differs from the FE "
                         f"model's {m0.rotor_mass_kg:.6g} kg: the surrogate's permissible "
                         "unbalance would be wrong (an effect adds mass?)")


__all__ = ["STRUCTURAL_ZERO", "SubstructureSurrogate", "barycentric_weights", "chebyshev_nodes",
           "fit_substructure_surrogate"]
