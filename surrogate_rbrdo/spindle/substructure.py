"""The rotor as a substructure: its dynamic stiffness condensed exactly onto a few nodes.

Receptance / impedance coupling is how machine-tool spindles are assembled from their parts
(Schmitz & Smith, *Machining Dynamics*, ch. 6, "receptance coupling substructure analysis").
Here the rotor without bearings, ``A(Ω) = (1 + iΩβ)K − Ω²M + iΩαM + iΩ²G``, is condensed onto
the *retained* nodes (tool tip, bearings, unbalance planes) by the exact dynamic Schur complement

    S(Ω) = A_RR − A_RI A_II⁻¹ A_IR,

and the bearings (stiffness × θ, damping, housing stage) are added on the retained bearing
DOFs by :mod:`surrogate_rbrdo.spindle.coupling`. The retained system reproduces the full
model's response at the retained nodes to round-off: nothing is approximated. What makes it
useful is that ``S`` depends on the design only through the rotor (span, diameter), is free of
θ, and is *smooth* in the design: its poles are the natural frequencies of the rotor segments
clamped at the retained nodes (> 1.6 kHz for the reference spindle, far above 400 Hz =
24 000 rpm), while the resonances and the tool-tip cancellation notch of the assembled spindle
come from the coupling algebra. A surrogate of ``S``
over the design (``runner.substructure_surrogate``) therefore keeps the notch and the resonance
that a Kriging of the amplitude itself smooths away.

>>> import numpy as np
>>> from surrogate_rbrdo.spindle.reference import reference_spindle
>>> from surrogate_rbrdo.spindle.harmonic import tool_amplitude
>>> from surrogate_rbrdo.spindle.coupling import coupled_tool_amplitude
>>> sp = reference_spindle()
>>> x, th = np.array([3000.0, 442.5, 65.7]), np.array([[1.0, 1.0], [0.9, 1.1]])
>>> m = sp.model(x)
>>> lay = retained_layout(m)
>>> S = condensed_rotor(m, np.array([24000.0]))            # (1, 16, 16)
>>> Z = m.bearing_impedance(np.full((2, 1), 24000.0 * np.pi / 30), th)[:, 0]
>>> y = coupled_tool_amplitude(lay, S[0], Z, unbalance_force(m, 24000.0, lay))
>>> bool(np.allclose(y, tool_amplitude(m, np.array([24000.0]), th)[:, 0], rtol=1e-9))
True
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from surrogate_rbrdo.core.errors import ModelError
from surrogate_rbrdo.spindle.assembly import RPM, SpindleModel
from surrogate_rbrdo.spindle.harmonic import dynamic_coefficients, unbalance_load


@dataclass(frozen=True)
class RetainedLayout:
    """Which FE nodes are kept, and where the tool, bearings and unbalances sit among them.

    Attributes
    ----------
    nodes : tuple of int
        Retained FE nodes, ascending; all 4 DOFs ``[x, y, a, b]`` of each are kept.
    tool : int
        Index (into ``nodes``) of the tool-tip node.
    bearings : tuple of int
        Index of each bearing's node, in the geometry's bearing order.
    unbalance : tuple of int
        Index of each unbalance plane's node.
    """

    nodes: tuple[int, ...]
    tool: int
    bearings: tuple[int, ...]
    unbalance: tuple[int, ...]

    @property
    def n_dof(self) -> int:
        return 4 * len(self.nodes)

    @property
    def dofs(self) -> np.ndarray:
        """Global DOF indices of the retained DOFs (in retained order)."""
        return (4 * np.asarray(self.nodes)[:, None] + np.arange(4)).ravel()


def retained_layout(model: SpindleModel) -> RetainedLayout:
    """The retained nodes of ``model``: tool tip, bearing and unbalance nodes."""
    nodes = sorted({int(model.tool_node), *map(int, model.bearing_nodes),
                    *map(int, model.unbalance_nodes)})
    return RetainedLayout(
        nodes=tuple(nodes), tool=nodes.index(int(model.tool_node)),
        bearings=tuple(nodes.index(int(n)) for n in model.bearing_nodes),
        unbalance=tuple(nodes.index(int(n)) for n in model.unbalance_nodes))


def rotor_dynamic_stiffness(model: SpindleModel, omega: np.ndarray) -> np.ndarray:
    """Dense dynamic stiffness of the rotor alone (no bearings) at speeds ``omega`` (rad/s).

    Returns ``(S, n, n)`` complex, the operator of ``harmonic.unbalance_response`` without the
    bearing blocks (:func:`~surrogate_rbrdo.spindle.harmonic.dynamic_coefficients`).
    """
    aK, aM, aG = (a[:, None, None] for a in dynamic_coefficients(
        model, np.asarray(omega, dtype=float).reshape(-1)))
    return aK * model.K + aM * model.M + aG * model.G


def condensed_rotor(model: SpindleModel, speeds_rpm: np.ndarray,
                    layout: RetainedLayout | None = None) -> np.ndarray:
    """Exact dynamic condensation of the rotor onto the retained nodes, ``(S, r, r)`` complex.

    ``S(Ω) = A_RR − A_RI A_II⁻¹ A_IR`` with ``A`` from :func:`rotor_dynamic_stiffness`.

    Raises
    ------
    ModelError
        If the interior is singular at a speed (a clamped-segment resonance without damping)
        or the result is not finite.
    """
    layout = retained_layout(model) if layout is None else layout
    sp = np.asarray(speeds_rpm, dtype=float).reshape(-1)
    if sp.size == 0 or not np.all(np.isfinite(sp)) or np.any(sp <= 0):
        raise ValueError(f"speeds_rpm = {sp.tolist()} is not allowed: give finite speeds > 0")
    A = rotor_dynamic_stiffness(model, sp * RPM)
    R = layout.dofs
    Ii = np.setdiff1d(np.arange(A.shape[-1]), R)
    try:
        X = np.linalg.solve(A[:, Ii[:, None], Ii], A[:, Ii[:, None], R])
    except np.linalg.LinAlgError as exc:
        raise ModelError("condensed_rotor: the rotor interior is singular at one of the "
                         f"speeds {sp.tolist()} rpm") from exc
    S = A[:, R[:, None], R] - A[:, R[:, None], Ii] @ X
    if not np.all(np.isfinite(S)):
        raise ModelError(f"condensed_rotor: non-finite condensed stiffness at {sp.tolist()} rpm")
    return S


@dataclass(frozen=True)
class ChainCondensation:
    """The condensed rotor ``S (S, r, r)`` and the determinant of the eliminated interior,
    ``det A_II = sign · exp(logabs)`` per speed (``det A = det A_II · det S``)."""

    S: np.ndarray
    interior_sign: np.ndarray
    interior_logabs: np.ndarray


def condense_chain(model: SpindleModel, speeds_rpm: np.ndarray,
                   layout: RetainedLayout | None = None) -> ChainCondensation:
    """:func:`condensed_rotor` by block elimination along the shaft, with ``det A_II``.

    The rotor couples only neighbouring nodes (4x4 blocks), so the interior nodes between two
    retained nodes (and the free ends beyond the first and last) are eliminated one node at a
    time, each step a 4x4 solve batched over the speeds: the cost grows with the number of
    nodes, not with its cube. The result is the same Schur complement (equal to round-off,
    ``tests/spindle/test_substructure.py``), 5–14x faster for the reference spindle's 20
    nodes at 48–64 speeds (measured under load; ``benchmarks/bench_peak_coupling.py`` prints
    it). The product of the elimination's pivot determinants is ``det A_II``: ``S`` has
    poles where it vanishes (clamped-interior resonances), ``det A_II · det(S + …)`` none.
    """
    layout = retained_layout(model) if layout is None else layout
    sp = np.asarray(speeds_rpm, dtype=float).reshape(-1)
    if sp.size == 0 or not np.all(np.isfinite(sp)) or np.any(sp <= 0):
        raise ValueError(f"speeds_rpm = {sp.tolist()} is not allowed: give finite speeds > 0")
    return chain_condensation(model, dynamic_coefficients(model, sp * RPM), layout.nodes,
                              f"at one of the speeds {sp.tolist()} rpm")


def chain_condensation(model: SpindleModel,
                       coefficients: tuple[np.ndarray, np.ndarray, np.ndarray],
                       nodes: tuple[int, ...], where: str = "", *, with_det: bool = True
                       ) -> ChainCondensation:
    """The block elimination of :func:`condense_chain` for any operating points: the rotor
    ``a_K K + a_M M + a_G G`` with coefficient arrays ``(a_K, a_M, a_G)`` of shape ``(S,)``
    (:func:`~surrogate_rbrdo.spindle.harmonic.dynamic_coefficients` for ``ω = Ω``; a response
    frequency apart from the spin, ``1 + iωβ``, ``−ω² + iωα``, ``iωΩ g``, for impact tests),
    condensed onto all four DOFs of each of the ascending ``nodes``. ``where`` completes the
    error message; ``with_det=False`` skips the interior determinant (returned as 1)."""
    idx = np.asarray(nodes)
    if (idx.ndim != 1 or idx.size == 0 or not np.issubdtype(idx.dtype, np.integer)
            or idx[0] < 0 or idx[-1] >= model.n_nodes or np.any(np.diff(idx) <= 0)):
        raise ValueError(f"nodes = {tuple(nodes)!r} is not allowed: must be strictly "
                         f"ascending node indices in [0, {model.n_nodes - 1}]")
    aK, aM, aG = (np.asarray(a)[:, None, None, None] for a in coefficients)
    (Kd, Ku, Kl), (Md, Mu, Ml), (Gd, Gu, Gl) = (model.blocks[k] for k in ("K", "M", "G"))
    D = aK * Kd + aM * Md + aG * Gd                  # (S, nn, 4, 4)
    U = aK * Ku + aM * Mu + aG * Gu                  # (S, nn-1, 4, 4): block (i, i+1)
    L = aK * Kl + aM * Ml + aG * Gl                  # block (i+1, i)
    R = list(nodes)
    nn = model.n_nodes
    Dr = {a: D[:, a].copy() for a in R}              # retained diagonal blocks
    off = {}
    pivots = []                                      # each eliminated node's pivot block
    pivot = pivots.append

    try:
        # free end before the first retained node: eliminate 0 .. R[0]-1 towards R[0]
        Dc = D[:, 0]
        for i in range(R[0]):
            pivot(Dc)
            Dc = D[:, i + 1] - L[:, i] @ np.linalg.solve(Dc, U[:, i])
        if R[0] > 0:
            Dr[R[0]] = Dc.copy()
        # free end after the last retained node: eliminate nn-1 .. R[-1]+1 towards R[-1]
        Dc = D[:, nn - 1]
        for i in range(nn - 2, R[-1] - 1, -1):
            pivot(Dc)
            Dc = D[:, i] - U[:, i] @ np.linalg.solve(Dc, L[:, i])
        if R[-1] < nn - 1:
            Dr[R[-1]] = Dr[R[-1]] + Dc - D[:, R[-1]]
        # segments between consecutive retained nodes a < b
        for a, b in zip(R[:-1], R[1:], strict=True):
            C, Ct, Dc = U[:, a], L[:, a], D[:, a + 1]
            for i in range(a + 1, b):
                pivot(Dc)
                X = np.linalg.solve(Dc, np.concatenate([Ct, U[:, i]], axis=-1))
                Dr[a] = Dr[a] - C @ X[..., :4]
                C, Ct, Dc = (-C @ X[..., 4:], -L[:, i] @ X[..., :4],
                             D[:, i + 1] - L[:, i] @ X[..., 4:])
            Dr[b] = Dr[b] + Dc - D[:, b]
            off[a, b] = (C, Ct)
    except np.linalg.LinAlgError as exc:
        raise ModelError(f"condensed_rotor_chain: an interior block is singular {where}"
                         ) from exc
    n_pts = D.shape[0]
    r = 4 * len(R)
    S = np.zeros((n_pts, r, r), dtype=complex)
    pos = {a: 4 * k for k, a in enumerate(R)}
    for a in R:
        S[:, pos[a]:pos[a] + 4, pos[a]:pos[a] + 4] = Dr[a]
    for (a, b), (C, Ct) in off.items():
        S[:, pos[a]:pos[a] + 4, pos[b]:pos[b] + 4] = C
        S[:, pos[b]:pos[b] + 4, pos[a]:pos[a] + 4] = Ct
    if not np.all(np.isfinite(S)):
        raise ModelError(f"condensed_rotor_chain: non-finite stiffness {where}")
    if pivots and with_det:
        sg, la = np.linalg.slogdet(np.stack(pivots))                # (n_interior, S)
        sign, logabs = np.prod(sg, axis=0), la.sum(axis=0)
    else:
        sign, logabs = np.ones(n_pts, dtype=complex), np.zeros(n_pts)
    return ChainCondensation(S, sign, logabs)


def condensed_rotor_chain(model: SpindleModel, speeds_rpm: np.ndarray,
                          layout: RetainedLayout | None = None) -> np.ndarray:
    """:func:`condensed_rotor` by block elimination along the shaft (:func:`condense_chain`),
    ``(S, r, r)`` complex.

    >>> import numpy as np
    >>> from surrogate_rbrdo.spindle.reference import reference_spindle
    >>> m = reference_spindle().model(np.array([2000.0, 500.0, 65.0]))
    >>> sp = np.array([6000.0, 24000.0])
    >>> S1, S2 = condensed_rotor(m, sp), condensed_rotor_chain(m, sp)
    >>> bool(np.allclose(S1, S2, rtol=1e-10, atol=1e-6 * np.abs(S1).max()))
    True
    """
    return condense_chain(model, speeds_rpm, layout).S


def unbalance_force(model: SpindleModel, speed_rpm: float | np.ndarray,
                    layout: RetainedLayout | None = None) -> np.ndarray:
    """Unbalance force on the retained DOFs, ``U Ω² [1, −i]`` per plane: ``(..., r)``
    (:func:`~surrogate_rbrdo.spindle.harmonic.unbalance_load` at the retained nodes)."""
    layout = retained_layout(model) if layout is None else layout
    w = np.asarray(speed_rpm, dtype=float) * RPM
    f = unbalance_load(model, w)[..., list(layout.nodes), :]
    return f.reshape(*w.shape, layout.n_dof)


def condensed_vector(S: np.ndarray) -> np.ndarray:
    """Real vector ``[Re S, Im S]`` (flattened) of condensed stiffnesses ``(..., r, r)``."""
    return np.concatenate([S.real.reshape(*S.shape[:-2], -1),
                           S.imag.reshape(*S.shape[:-2], -1)], axis=-1)


def condensed_from_vector(v: np.ndarray, r: int) -> np.ndarray:
    """Inverse of :func:`condensed_vector`: ``(..., 2 r²)`` real → ``(..., r, r)`` complex."""
    v = np.asarray(v, dtype=float)
    n = r * r
    return (v[..., :n] + 1j * v[..., n:]).reshape(*v.shape[:-1], r, r)


@dataclass(frozen=True)
class PointwiseCondensed:
    """FE call for sampling: design ``x`` → ``condensed_vector`` of ``S`` at ``speeds_rpm``.

    One call condenses the rotor of one design at every speed (``2 S r²`` outputs, speeds
    outermost). It pickles cheaply (the spindle description and the speeds). With ``nodes``
    (``unbalance``) it refuses a design whose retained nodes (unbalance) differ from them, with
    a ``ModelError``: the surrogate takes both from the baseline design.
    """

    spindle: object
    speeds_rpm: tuple[float, ...]
    nodes: tuple[int, ...] | None = None
    unbalance: tuple[complex, ...] | None = None

    def n_outputs(self, r: int) -> int:
        return 2 * len(self.speeds_rpm) * r * r

    def __call__(self, x: np.ndarray) -> np.ndarray:
        m = self.spindle.model(np.asarray(x, dtype=float))
        lay = retained_layout(m)
        if self.nodes is not None and lay.nodes != tuple(self.nodes):
            raise ModelError(f"design {np.asarray(x).tolist()}: retained nodes {lay.nodes} differ "
                             f"from {tuple(self.nodes)} (the mesh changes with the design); the "
                             "substructure surrogate needs one layout over the design box")
        if self.unbalance is not None and not np.allclose(m.unbalance, self.unbalance,
                                                          rtol=1e-12, atol=0.0):
            raise ModelError(f"design {np.asarray(x).tolist()}: unbalance {m.unbalance.tolist()} "
                             f"differs from {list(self.unbalance)}; the substructure surrogate "
                             "needs an unbalance that does not change with the design")
        return condensed_vector(condensed_rotor(m, np.asarray(self.speeds_rpm), lay)).ravel()


__all__ = [
    "ChainCondensation",
    "PointwiseCondensed",
    "RetainedLayout",
    "condensed_from_vector",
    "condensed_rotor",
    "condense_chain",
    "condensed_rotor_chain",
    "condensed_vector",
    "retained_layout",
    "rotor_dynamic_stiffness",
    "unbalance_force",
]
