"""The peak tool-tip amplitude over speed for random multi-plane unbalance, by exact coupling.

The FE model's peak (``harmonic.peak_tool_amplitude``) searches the speed range anew for every
θ sample: ~170 solves of the whole rotor per sample. This module gets the same number from a
few exact solves per *design*, using three exact structures of the linear model:

1. **Linear in the unbalance.** The tool response is ``q(Ω) = Σ_j U_j h_j(Ω, θ)`` for the
   complex residual unbalances ``U_j`` (kg m, magnitude and phase) of the planes ``j``: each
   plane's transfer ``h_j`` is solved once and every unbalance sample is a weighted sum.
2. **Polynomial in θ.** With the rotor condensed exactly onto its retained nodes
   (``substructure.condensed_rotor_chain``) and the bearings added, ``K_c(Ω, θ) = S(Ω) +
   P Z(Ω, θ) Pᵀ``; each θ bearing's two rows are affine in its factor, so by Cramer's rule
   ``D = det K_c`` and ``N_j = D h_j`` are polynomials of degree ≤ 2 in each ``θ_j``
   (``coupling.theta_grid``): solved at the ``3^m`` nodes, interpolated exactly to any θ.
3. **Smooth in speed.** ``D`` and ``N_j`` have no resonance: the resonances of the spindle are
   the (complex) zeros of ``D``, and the only singularities of ``D`` and ``N_j`` are the
   clamped-segment poles of ``S`` (> 1.6 kHz for the reference spindle, against ≤ 400 Hz in
   the range). On a geometric speed grid (uniform in ``ln Ω``) they are interpolated by
   local Lagrange polynomials of degree ``stencil − 1`` to ~1e-9 of their scale; the
   amplitude ``(|Σ U_j N^a_j| + |Σ U_j N^b_j|) / (2 |D|)`` (semi-major axis of the orbit, with
   ``N^a``, ``N^b`` the forward and backward circular components ``X ± iY``) is then searched
   for its peak per sample: candidates on a sub-grid, refined on the local interpolants
   (:class:`CoupledPeakOptions`).

Only step 3 approximates, and its error is measured against the FE peak search
(``tests/spindle/test_peak_coupling.py``, ``benchmarks/bench_peak_coupling.py``).

>>> import numpy as np
>>> from surrogate_rbrdo.spindle.reference import reference_spindle
>>> m = reference_spindle().model(np.array([2000.0, 500.0, 65.0]))
>>> rng = np.random.default_rng(0)
>>> th = rng.normal(1.0, 0.03, size=(40, 2))
>>> U = 1e-5 * np.exp(2j * np.pi * rng.random((40, 2)))      # two planes, random phase
>>> fast = peak_tool_amplitude_coupled(m, th, U)
>>> fe = peak_tool_amplitude_unbalance(m, th[:3], U[:3])
>>> bool(np.allclose(fast.amplitude[:3], fe.amplitude, rtol=1e-3))
True
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

import numpy as np

from surrogate_rbrdo.core.errors import ModelError
from surrogate_rbrdo.spindle.assembly import RPM, SpindleModel, theta_affine
from surrogate_rbrdo.spindle.coupling import theta_grid
from surrogate_rbrdo.spindle.harmonic import (
    PeakOptions,
    PeakResult,
    orbit_amplitude,
    peak_search,
    unbalance_response,
)
from surrogate_rbrdo.spindle.peak_interp import (
    CoupledPeakOptions,
    CoupledTables,
    peak_from_tables,
)
from surrogate_rbrdo.spindle.substructure import (
    RetainedLayout,
    condense_chain,
    retained_layout,
)


def _coupled_matrix(layout: RetainedLayout, S: np.ndarray, Z: np.ndarray) -> np.ndarray:
    """``S + P Z Pᵀ``: bearing impedances ``Z (..., nb, 2, 2)`` on the bearing nodes' x, y."""
    Kc = np.array(np.broadcast_to(S, Z.shape[:-3] + S.shape[-2:]), dtype=complex)
    for j, k in enumerate(layout.bearings):
        Kc[..., 4 * k:4 * k + 2, 4 * k:4 * k + 2] += Z[..., j, :, :]
    return Kc


def _unit_forces(layout: RetainedLayout, omega: np.ndarray) -> np.ndarray:
    """Force of a unit unbalance (1 kg m, phase 0) in each plane: ``(S, r, P)``,
    ``Ω² [1, −i]`` on the plane node's x, y (``harmonic.unbalance_load``)."""
    P = len(layout.unbalance)
    F = np.zeros((omega.size, layout.n_dof, P), dtype=complex)
    for j, k in enumerate(layout.unbalance):
        F[:, 4 * k, j] += omega**2
        F[:, 4 * k + 1, j] += -1j * omega**2
    return F


def forward_basis(layout: RetainedLayout) -> np.ndarray:
    """Orthonormal basis ``(r, r/2)`` of forward-whirl motions of the retained nodes.

    Per node ``(1, −i, 0, 0)/√2`` (translation ``x = Re Q e^{iΩt}``, ``y = Im Q e^{iΩt}``) and
    ``(0, 0, 1, −i)/√2`` (slopes). A rotor–bearing system invariant under rotation about its
    axis (isotropic bearings, skew cross-coupling, gyroscopics) maps this subspace onto
    itself, and the forward unbalance force ``Ω² U [1, −i]`` lies in it: the forward
    response solves ``Vᴴ K_c V`` alone, whose determinant has no backward-whirl zeros.
    """
    r = layout.n_dof
    V = np.zeros((r, r // 2), dtype=complex)
    for k in range(r // 4):
        V[4 * k, 2 * k] = V[4 * k + 2, 2 * k + 1] = 1.0 / np.sqrt(2.0)
        V[4 * k + 1, 2 * k] = V[4 * k + 3, 2 * k + 1] = -1j / np.sqrt(2.0)
    return V


def invariant_part(S: np.ndarray, V: np.ndarray) -> np.ndarray:
    """The part of ``S (..., r, r)`` invariant under rotation about the axis:
    ``V (VᴴSV) Vᴴ + V̄ (VᵀSV̄) Vᵀ`` with ``V`` the forward-whirl basis
    (:func:`forward_basis`) and ``V̄`` the backward one (the cross blocks dropped), e.g. to
    restore the symmetry of an approximated ``S`` (a Kriging of its entries).

    >>> V = forward_basis(RetainedLayout((0,), 0, (), ()))
    >>> S = np.diag([2.0, 2.0, 3.0, 3.0]) + 0j         # isotropic: invariant already
    >>> bool(np.allclose(invariant_part(S, V), S))
    True
    >>> bool(np.allclose(invariant_part(np.diag([1.0, 3.0, 0, 0]) + 0j, V)[:2, :2], 2 * np.eye(2)))
    True
    """
    Vh, W = V.conj().T, V.conj()
    return V @ (Vh @ S @ V) @ Vh + W @ (W.conj().T @ S @ W) @ W.conj().T


def rotation_residual(S: np.ndarray, V: np.ndarray) -> float:
    """Largest ``‖SV − V(VᴴSV)‖ / ‖SV‖`` over the matrices ``S (..., r, r)``: 0 for a rotor
    invariant under rotation about its axis (:func:`tables_from_condensed` checks it)."""
    SV = S @ V
    R = SV - V @ (V.conj().T @ SV)
    return float(np.max(np.linalg.norm(R, axis=(-2, -1)) / np.linalg.norm(SV, axis=(-2, -1))))


def coupled_tables(model: SpindleModel, speeds_rpm: np.ndarray, theta_nodes: np.ndarray,
                   layout: RetainedLayout | None = None) -> CoupledTables:
    """:class:`CoupledTables` of ``model`` at geometric ``speeds_rpm`` and θ rows
    ``theta_nodes`` (K, m): one chain condensation per speed and one solve and determinant
    per (θ row, speed). Exact (no interpolation yet).

    When the coupled system is invariant under rotation about the axis
    (:func:`forward_basis`; checked to 1e-10), the forward-whirl block alone is solved:
    ``D = det Vᴴ K_c V`` then holds only the forward resonances, so the backward-whirl zero
    a few per cent away cannot spoil the interpolation in speed, and ``Nb`` is None.
    Otherwise (anisotropic bearings) the whole ``K_c`` is solved.
    """
    layout = retained_layout(model) if layout is None else layout
    sp = check_geometric(speeds_rpm)
    th = model.check_theta(theta_nodes)
    chain = condense_chain(model, sp, layout)
    Z = model.bearing_impedance(np.broadcast_to(sp * RPM, (th.shape[0], sp.size)), th)
    return tables_from_condensed(layout, sp, th, chain.S, Z,
                                 (chain.interior_sign, chain.interior_logabs))


def check_geometric(speeds_rpm: np.ndarray) -> np.ndarray:
    """``speeds_rpm`` as a float array if it is a geometric grid of at least two speeds."""
    sp = np.asarray(speeds_rpm, dtype=float)
    ls = np.log(sp) if np.all(sp > 0) else np.full(sp.shape, np.nan)
    if sp.ndim != 1 or sp.size < 2 or not np.allclose(np.diff(ls), ls[1] - ls[0], rtol=1e-9):
        raise ValueError("speeds_rpm must be a geometric grid of at least two speeds "
                         "(np.geomspace)")
    return sp


def tables_from_condensed(layout: RetainedLayout, speeds_rpm: np.ndarray, theta_nodes: np.ndarray,
                          S: np.ndarray, Z: np.ndarray,
                          interior: tuple[np.ndarray, np.ndarray] | None = None
                          ) -> CoupledTables:
    """:class:`CoupledTables` from the condensed rotor ``S (G, r, r)`` at geometric
    ``speeds_rpm`` and the bearing impedances ``Z (K, G, nb, 2, 2)`` at the θ rows
    ``theta_nodes (K, m)``: one solve and determinant per (θ row, speed).

    ``interior``: ``(sign, logabs)`` of ``det A_II`` per speed (``substructure.
    condense_chain``), which makes ``D`` the whole system's determinant, free of the poles
    of ``S``; ``None`` (e.g. ``S`` from a surrogate) leaves ``D = det K_c``, smooth in speed
    only where ``S`` is (no clamped-interior resonance near the range).
    """
    sp = check_geometric(speeds_rpm)
    ls = np.log(sp)
    F = _unit_forces(layout, sp * RPM)                                  # (G, r, P)
    V = forward_basis(layout)
    SV = S @ V
    Sf = V.conj().T @ SV
    zxx, zxy, zyx, zyy = Z[..., 0, 0], Z[..., 0, 1], Z[..., 1, 0], Z[..., 1, 1]
    scale = np.abs(Z).max()
    forward = (np.linalg.norm(SV - V @ Sf) <= 1e-10 * np.linalg.norm(SV)
               and np.abs(zxx - zyy).max() <= 1e-12 * scale
               and np.abs(zxy + zyx).max() <= 1e-12 * scale)
    if forward:
        # each bearing adds vᴴ Z v = Z_xx − i Z_xy to its node's forward translation
        A = np.array(np.broadcast_to(Sf, Z.shape[:2] + Sf.shape[1:]))  # (K, G, r/2, r/2)
        for j, k in enumerate(layout.bearings):
            A[..., 2 * k, 2 * k] += zxx[..., j] - 1j * zxy[..., j]
        rhs = V.conj().T @ F
    else:
        A, rhs = _coupled_matrix(layout, S[None], Z), F                 # (K, G, r, r)
    try:
        q = np.linalg.solve(A, np.broadcast_to(rhs, A.shape[:2] + rhs.shape[1:]))
    except np.linalg.LinAlgError as exc:
        raise ModelError("coupled_tables: singular coupled dynamic stiffness") from exc
    if forward:
        q = V @ q
    sign, logdet = np.linalg.slogdet(A)
    if interior is not None:
        # det A_II · det(S + P Z Pᵀ) is the whole system's determinant: S's poles (clamped-
        # interior resonances, e.g. behind a soft tool interface) cancel, D stays smooth in Ω
        sign = sign * interior[0]
        logdet = logdet + interior[1]
    D = sign * np.exp(logdet - logdet.max())                            # one common scale
    t = 4 * layout.tool
    Na = D[..., None] * (q[..., t, :] + 1j * q[..., t + 1, :])
    Nb = None if forward else D[..., None] * (q[..., t, :] - 1j * q[..., t + 1, :])
    if not (np.all(np.isfinite(Na)) and np.all(np.isfinite(D))
            and (Nb is None or np.all(np.isfinite(Nb)))):
        raise ModelError("coupled_tables: non-finite coupled response")
    return CoupledTables(ls, np.asarray(theta_nodes, dtype=float), D, Na, Nb)


def check_unbalance(unbalance: np.ndarray, n_rows: int, n_planes: int) -> np.ndarray:
    """Unbalance phasors as a finite complex ``(N, P)`` array, else a ``ValueError``."""
    U = np.asarray(unbalance, dtype=complex)
    if U.ndim == 1:
        U = np.broadcast_to(U, (n_rows, U.size))
    if U.shape != (n_rows, n_planes) or not np.all(np.isfinite(U)):
        raise ValueError(f"unbalance has shape {np.shape(unbalance)}: must be finite complex "
                         f"({n_rows}, {n_planes}) phasors in kg m (one per θ row and plane)")
    return U


def peak_tool_amplitude_coupled(
    model: SpindleModel, theta: np.ndarray | None, unbalance: np.ndarray, *,
    speed_range_rpm: tuple[float, float] | None = None,
    options: CoupledPeakOptions | None = None, rtol: float = 1e-9,
    grid: tuple[np.ndarray, np.ndarray] | None = None,
) -> PeakResult:
    """Peak tool-tip amplitude over the speed range for θ rows and unbalance phasors.

    The same quantity as :func:`peak_tool_amplitude_unbalance` (the FE model's peak search),
    from ``n_grid · 3^m`` exact coupled solves per design instead of ~170 per row (module
    docstring). Rows whose θ-interpolation round-off bound exceeds ``rtol``, and every row
    when a θ bearing has a housing stage (``assembly.theta_affine``), are solved row by row
    at the grid speeds instead.

    Parameters
    ----------
    model : SpindleModel
    theta : array (N, m) or None
        Bearing stiffness factors (None: nominal).
    unbalance : array (N, P) or (P,) complex
        Residual unbalance phasors per plane (kg m), in the order of the geometry's planes.
    options : CoupledPeakOptions, optional
        The search (default ``CoupledPeakOptions()``).
    grid : (nodes, basis), optional
        ``coupling.theta_grid(theta)``, when the caller already has it (a θ sample shared by
        many designs).
    """
    options = CoupledPeakOptions() if options is None else options
    g = model.geometry
    lo, hi = speed_range_rpm or (g.speed_min_rpm, g.speed_max_rpm)
    if not (0 < lo < hi and np.isfinite(hi)):
        raise ValueError(f"speed_range_rpm = ({lo}, {hi}) is not allowed: need 0 < lo < hi")
    U0 = np.asarray(unbalance, dtype=complex)
    n_rows = 1 if theta is None and U0.ndim == 1 else (
        U0.shape[0] if theta is None else np.atleast_2d(theta).shape[0])
    th = model.check_theta(theta, n_rows)
    U = check_unbalance(unbalance, th.shape[0], model.unbalance_nodes.size)
    layout = retained_layout(model)
    speeds = np.geomspace(lo, hi, options.n_grid)
    affine = theta_affine(model.geometry, model.effects, model.theta_bearings)
    return peak_by_tables(lambda rows: coupled_tables(model, speeds, rows, layout), th, U,
                          options, affine=affine, grid=grid, rtol=rtol)


def peak_by_tables(tables: Callable[[np.ndarray], CoupledTables], theta: np.ndarray,
                   unbalance: np.ndarray, options: CoupledPeakOptions, *, affine: bool,
                   grid: tuple[np.ndarray, np.ndarray] | None = None, rtol: float = 1e-9
                   ) -> PeakResult:
    """The peak of every θ row (N, m) with its phasors ``unbalance`` (N, P) from the
    tables ``tables(theta_rows)`` of one rotor: at the ``3^m`` nodes of ``grid`` (default
    ``coupling.theta_grid(theta)``) when ``affine`` (every θ bearing's impedance affine in
    its factor), and row by row for the rows whose θ-interpolation round-off bound exceeds
    ``rtol`` (every row when not ``affine``)."""
    out_a, out_s = np.empty(theta.shape[0]), np.empty(theta.shape[0])
    redo = np.arange(theta.shape[0])
    if affine:
        nodes, basis = theta_grid(theta) if grid is None else grid
        res, bound = peak_from_tables(tables(nodes), basis, unbalance, options)
        out_a[:], out_s[:] = res.amplitude, res.speed_rpm
        redo = np.flatnonzero(~(bound <= rtol))
    if redo.size:
        res, _ = peak_from_tables(tables(theta[redo]), None, unbalance[redo], options)
        out_a[redo], out_s[redo] = res.amplitude, res.speed_rpm
    return PeakResult(out_a, out_s)


def tool_response_per_plane(model: SpindleModel, speeds_rpm: np.ndarray,
                            theta: np.ndarray | None = None) -> np.ndarray:
    """Tool-tip ``(X, Y)`` per unit unbalance (1 kg m, phase 0) in each plane, by the FE
    model's direct solve: ``(P, B, S, 2)`` complex (``harmonic.unbalance_response``)."""
    out = []
    for j in range(model.unbalance.size):
        unit = np.zeros(model.unbalance.size, dtype=complex)
        unit[j] = 1.0
        q = unbalance_response(_with_unbalance(model, unit), speeds_rpm, theta)
        out.append(q[..., model.tool_node, :2])
    return np.stack(out)


def _with_unbalance(model: SpindleModel, U: np.ndarray) -> SpindleModel:
    return replace(model, unbalance=np.asarray(U, dtype=complex))


def peak_tool_amplitude_unbalance(
    model: SpindleModel, theta: np.ndarray | None, unbalance: np.ndarray, *,
    speed_range_rpm: tuple[float, float] | None = None,
    options: PeakOptions | None = None, chunk: int = 16,
) -> PeakResult:
    """The FE model's peak tool amplitude for θ rows, each with its own unbalance phasors.

    ``harmonic.peak_search`` (the search of ``harmonic.peak_tool_amplitude``) on the direct
    block-tridiagonal solve, the response of each row being ``Σ_j U_j h_j`` with ``h_j`` the
    FE response to a unit unbalance in plane ``j`` (:func:`tool_response_per_plane`): the
    reference the fast path is measured against (``options`` default: ``PeakOptions()``).
    """
    options = PeakOptions() if options is None else options
    g = model.geometry
    lo, hi = speed_range_rpm or (g.speed_min_rpm, g.speed_max_rpm)
    if not (0 < lo < hi and np.isfinite(hi)):
        raise ValueError(f"speed_range_rpm = ({lo}, {hi}) is not allowed: need 0 < lo < hi")
    U0 = np.asarray(unbalance, dtype=complex)
    n_rows = U0.shape[0] if theta is None and U0.ndim == 2 else (
        1 if theta is None else np.atleast_2d(theta).shape[0])
    th = model.check_theta(theta, n_rows)
    U = check_unbalance(unbalance, th.shape[0], model.unbalance.size)
    m = th.shape[1]
    rows = np.column_stack([th, np.arange(th.shape[0])])            # row index rides along

    def amplitude(speeds, r):
        h = tool_response_per_plane(model, speeds, r[:, :m])           # (P, B, S, 2)
        q = np.einsum("pbsc,bp->bsc", h, U[r[:, m].astype(int)])
        return orbit_amplitude(q[..., 0], q[..., 1])

    amps, sps = [], []
    for s in range(0, th.shape[0], chunk):
        a, v = peak_search(amplitude, rows[s:s + chunk], lo, hi, options)
        amps.append(a)
        sps.append(v)
    return PeakResult(np.concatenate(amps), np.concatenate(sps))


__all__ = [
    "CoupledPeakOptions",
    "CoupledTables",
    "check_unbalance",
    "coupled_tables",
    "check_geometric",
    "forward_basis",
    "invariant_part",
    "peak_by_tables",
    "peak_from_tables",
    "peak_tool_amplitude_coupled",
    "peak_tool_amplitude_unbalance",
    "rotation_residual",
    "tables_from_condensed",
    "tool_response_per_plane",
]
