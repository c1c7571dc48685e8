"""Assembly of the spindle FE model from a geometry and a list of effects.

The model keeps the rotor matrices in two forms: dense ``(n, n)`` (modal analysis) and as
node blocks of a block-tridiagonal matrix (``(nn, 4, 4)`` diagonal and ``(nn-1, 4, 4)``
off-diagonal blocks), which the harmonic solver uses to treat many speeds at once.

>>> from surrogate_rbrdo.spindle.geometry import SpindleGeometry
>>> g = SpindleGeometry.from_dict({
...     "sections": [{"length_mm": 500, "outer_diameter_mm": 50, "elements": 10}],
...     "bearings": [{"name": "a", "position_mm": 0, "law": {"type": "constant",
...                   "k_N_per_m": 1e8}},
...                  {"name": "b", "position_mm": 500, "law": {"type": "constant",
...                   "k_N_per_m": 1e8}}]})
>>> m = build_model(g)
>>> m.n_nodes, m.n_dof, round(m.rotor_mass_kg, 3)
(11, 44, 7.707)
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np

from surrogate_rbrdo.core.errors import OutsideDomainError
from surrogate_rbrdo.spindle.effects import Effect, Gyroscopics, Joint, Support
from surrogate_rbrdo.spindle.element import BeamSection, element_matrices
from surrogate_rbrdo.spindle.geometry import ConstantLaw, PreloadLaw, SpindleGeometry

MM = 1e-3
RPM = np.pi / 30.0  # rpm -> rad/s


def _mesh(geometry: SpindleGeometry, joints: Sequence[Joint] = ()
          ) -> tuple[np.ndarray, np.ndarray]:
    """Node positions (m) and, per element, the index of its shaft section. Each joint's
    position gets two coincident nodes (a zero-length element between them)."""
    edges = np.concatenate([[0.0], np.cumsum([s.length_mm for s in geometry.sections])])
    pts = []
    for i, s in enumerate(geometry.sections):
        n = s.elements
        if geometry.max_element_length_mm is not None:
            n = max(n, int(np.ceil(s.length_mm / geometry.max_element_length_mm - 1e-9)))
        pts.append(np.linspace(edges[i], edges[i + 1], n + 1))
    items = [b.position_mm for b in geometry.bearings] + [d.position_mm for d in geometry.disks]
    items += [u.position_mm for u in geometry.unbalances] + [geometry.tool_tip_mm]
    items += [j.position_mm for j in joints]
    z = np.unique(np.round(np.concatenate(pts + [np.asarray(items, float)]), 9))
    # merge nodes closer than 1 µm (an item sitting on a mesh node)
    keep = np.concatenate([[True], np.diff(z) > 1e-3])
    z = z[keep]
    for j in joints:
        z = np.insert(z, _node_of(z * MM, j.position_mm), z[_node_of(z * MM, j.position_mm)])
    mid = 0.5 * (z[:-1] + z[1:])
    sec = np.clip(np.searchsorted(edges, mid, side="right") - 1, 0, len(geometry.sections) - 1)
    return z * MM, sec


def _check_joints(geometry: SpindleGeometry, joints: Sequence[Joint]) -> None:
    """A joint splits the shaft with mass on both sides: ``0 ≤ z < L`` (the rotor's length),
    and at ``z = 0`` a disk on its node (the items at a joint sit on its left node)."""
    length = sum(s.length_mm for s in geometry.sections)
    for j in joints:
        on_disk = any(abs(d.position_mm - j.position_mm) < 1e-3 for d in geometry.disks)
        if not (-1e-3 < j.position_mm < length - 1e-3) or (j.position_mm < 1e-3
                                                           and not on_disk):
            raise ValueError(
                f"effects: a joint at position_mm = {j.position_mm} is not allowed: it must "
                f"lie on the shaft, 0 <= position_mm < {length:g}, with mass on both sides "
                "(at 0 a disk there)")


def _node_of(z: np.ndarray, position_mm: float) -> int:
    return int(np.argmin(np.abs(z - position_mm * MM)))


@dataclass(frozen=True, eq=False)
class SpindleModel:
    """An assembled rotor–bearing model (SI units). Build it with :func:`build_model`.

    Attributes
    ----------
    z : ndarray (nn,)
        Node positions along the axis (m).
    M, K, G : ndarray (n, n)
        Rotor mass, structural stiffness and gyroscopic (skew, per unit spin) matrices,
        ``n = 4 nn``, DOFs ``[x, y, a, b]`` per node; disks included, bearings excluded.
    blocks : dict
        Block-tridiagonal parts ``{"M": (diag, upper), "K": ..., "G": ...}``.
    bearing_nodes : ndarray (nb,)
        Node index of each bearing (in the geometry's bearing order).
    theta_bearings : tuple of str
        Bearings whose stiffness the columns of θ multiply (θ = 1 is nominal).
    """

    geometry: SpindleGeometry
    effects: tuple[Effect, ...]
    theta_bearings: tuple[str, ...]
    z: np.ndarray
    element_section: np.ndarray
    M: np.ndarray
    K: np.ndarray
    G: np.ndarray
    blocks: dict[str, tuple[np.ndarray, np.ndarray]]
    bearing_nodes: np.ndarray
    supports: tuple[Support | None, ...]
    unbalance_nodes: np.ndarray
    unbalance: np.ndarray
    tool_node: int
    rotor_mass_kg: float
    sections: tuple[BeamSection, ...] = field(repr=False, default=())
    #: per element: its 8x8 mass, stiffness and gyroscopic matrices, shape (ne, 3, 8, 8)
    element_mats: np.ndarray = field(repr=False, default_factory=lambda: np.zeros((0, 3, 8, 8)))

    @property
    def n_nodes(self) -> int:
        return self.z.size

    @property
    def n_dof(self) -> int:
        return 4 * self.z.size

    @property
    def speed_range_rad_s(self) -> tuple[float, float]:
        g = self.geometry
        return g.speed_min_rpm * RPM, g.speed_max_rpm * RPM

    @property
    def alpha(self) -> float:
        return self.geometry.rayleigh_alpha_per_s

    @property
    def beta(self) -> float:
        return self.geometry.rayleigh_beta_s

    @property
    def gyro_scale(self) -> float:
        s = 1.0
        for e in self.effects:
            s *= e.gyroscopic_scale()
        return s

    # ------------------------------------------------------------------ bearings
    def check_theta(self, theta: np.ndarray | None, batch: int | None = None) -> np.ndarray:
        """Return θ as an array of shape (N, m); ``None`` means nominal (all ones)."""
        return check_theta(self.theta_bearings, theta, batch)

    def bearing_coefficients(
        self, omega: np.ndarray, theta: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """Stiffness and damping of every bearing at spin speeds ``omega`` (rad/s).

        ``omega`` has shape ``(B, S)`` and ``theta`` ``(B, m)``; returns ``K`` and ``C`` of
        shape ``(B, S, nb, 2, 2)`` (:func:`bearing_coefficients`).
        """
        omega = np.asarray(omega, dtype=float)
        th = self.check_theta(theta, omega.shape[0])
        return bearing_coefficients(self.geometry, self.effects, self.theta_bearings, omega, th)

    def bearing_impedance(self, omega: np.ndarray, theta: np.ndarray | None = None) -> np.ndarray:
        """Dynamic stiffness ``(B, S, nb, 2, 2)`` each bearing puts on its rotor node
        (:func:`bearing_impedance`)."""
        omega = np.asarray(omega, dtype=float)
        th = self.check_theta(theta, omega.shape[0])
        return bearing_impedance(self.geometry, self.effects, self.theta_bearings, omega, th,
                                 self.supports)

    # ------------------------------------------------------------------ full matrices
    def system_matrices(
        self, omega: float, theta: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Dense ``M``, ``C + Ω G`` and ``K`` of the whole system at one speed.

        Housing stages add two DOFs each, appended after the rotor DOFs.
        """
        th = self.check_theta(theta)[:1]
        Kb, Cb = self.bearing_coefficients(np.array([[omega]]), th)
        Kb, Cb = Kb[0, 0], Cb[0, 0]
        n_extra = 2 * sum(s is not None for s in self.supports)
        n = self.n_dof + n_extra
        M = np.zeros((n, n))
        K = np.zeros((n, n))
        C = np.zeros((n, n))
        r = self.n_dof
        M[:r, :r] = self.M
        K[:r, :r] = self.K
        C[:r, :r] = self.alpha * self.M + self.beta * self.K + omega * self.gyro_scale * self.G
        h = r
        for j, node in enumerate(self.bearing_nodes):
            dofs = np.array([4 * node, 4 * node + 1])
            sup = self.supports[j]
            if sup is None:
                K[np.ix_(dofs, dofs)] += Kb[j]
                C[np.ix_(dofs, dofs)] += Cb[j]
                continue
            hd = np.array([h, h + 1])
            h += 2
            for A, B, extra in ((K, Kb[j], sup.k_N_per_m), (C, Cb[j], sup.c_Ns_per_m)):
                A[np.ix_(dofs, dofs)] += B
                A[np.ix_(dofs, hd)] -= B
                A[np.ix_(hd, dofs)] -= B
                A[np.ix_(hd, hd)] += B + extra * np.eye(2)
            M[np.ix_(hd, hd)] += sup.m_kg * np.eye(2)
        return M, C, K


def _joint_matrix(j: Joint) -> np.ndarray:
    """8x8 stiffness of a zero-length joint: ``[[D, −D], [−D, D]]``, ``D = diag(k_t, k_t, k_r,
    k_r)`` on the DOFs ``[x, y, a, b]`` of its two nodes."""
    D = np.diag([j.k_t_N_per_m, j.k_t_N_per_m, j.k_r_Nm_per_rad, j.k_r_Nm_per_rad])
    return np.block([[D, -D], [-D, D]])


def check_theta(theta_bearings: Sequence[str], theta: np.ndarray | None,
                batch: int | None = None) -> np.ndarray:
    """θ as ``(N, m)`` for the ``m`` bearings ``theta_bearings``: finite factors > 0, else
    :class:`~surrogate_rbrdo.core.errors.OutsideDomainError` (a ``ModelError`` and a
    ``ValueError``) naming the value and listing the rows; ``None`` means nominal (``batch``
    rows of ones). A wrong shape is a ``ValueError``.

    >>> check_theta(("front", "rear"), [1.0, 0.9]).tolist()
    [[1.0, 0.9]]
    """
    m = len(theta_bearings)
    if theta is None:
        return np.ones((batch or 1, m))
    th = np.asarray(theta, dtype=float)
    if th.ndim == 1:
        th = th[None, :]
    if th.ndim != 2 or th.shape[1] != m:
        raise ValueError(
            f"theta has shape {np.shape(theta)}: must be ({m},) or (N, {m}) — stiffness "
            f"factors of bearings {list(theta_bearings)}"
        )
    bad = ~np.all(np.isfinite(th) & (th > 0), axis=1)
    if bad.any():  # outside the physical domain: a ModelError (and a ValueError), with the rows
        raise OutsideDomainError(f"theta = {th[bad][0].tolist()} is not allowed: stiffness "
                                 "factors must be finite and > 0", rows=np.flatnonzero(bad))
    return th


def bearing_coefficients(
    geometry: SpindleGeometry, effects: Sequence[Effect], theta_bearings: Sequence[str],
    omega: np.ndarray, theta: np.ndarray,
    preloads: Mapping[str, np.ndarray] | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Stiffness and damping of every bearing of ``geometry`` at spin speeds ``omega`` (rad/s).

    Needs the geometry and the effects only, not an assembled rotor. ``omega`` has shape
    ``(B, S)`` and ``theta`` ``(B, m)`` (checked by the caller: factors on the stiffness of
    ``theta_bearings``); returns ``K`` and ``C`` of shape ``(B, S, nb, 2, 2)``. Damping is
    ``C = η K_sym`` (the paper's Eq. 2) unless the law gives a damping matrix; cross-coupled
    stiffness adds no damping. ``preloads`` (bearing name → preload in N, broadcast against
    ``omega``) replaces the ``preload_N`` of those bearings' preload laws, so a batch row can
    stand for another design (``DesignMap.bearing_preloads``).
    """
    Ks = unscaled_bearing_stiffness(geometry, effects, omega, preloads)
    return scale_bearing_coefficients(geometry, theta_bearings, Ks, theta, omega.shape)


def unscaled_bearing_stiffness(
    geometry: SpindleGeometry, effects: Sequence[Effect], omega: np.ndarray,
    preloads: Mapping[str, np.ndarray] | None = None,
) -> list[np.ndarray]:
    """Per bearing, its stiffness ``(…, 2, 2)`` at ``omega`` (broadcastable to
    ``omega.shape + (2, 2)``) with the effects applied, before the factors θ: the part of
    :func:`bearing_coefficients` that does not depend on θ (a caller evaluating many θ at the
    same speeds and effects computes it once, :func:`scale_bearing_coefficients` the rest)."""
    preloads = {} if preloads is None else preloads
    laws = {b.name: b.law for b in geometry.bearings}
    for name, F in preloads.items():
        if name not in laws:
            raise ValueError(f"preloads: {name!r} is not a bearing; bearings are {list(laws)}")
        if not isinstance(laws[name], PreloadLaw):
            raise ValueError(f"preloads: bearing {name!r} has a constant law; a preload needs "
                             "a 'preload' law")
        F = np.asarray(F, dtype=float)
        if not np.all(np.isfinite(F) & (F > 0)):
            raise ValueError(f"preloads[{name!r}] = {F[~(np.isfinite(F) & (F > 0))].flat[0]} "
                             "is not allowed: must be finite and > 0 (N)")
    Ks = []
    for b in geometry.bearings:
        law = b.law
        if isinstance(law, PreloadLaw):
            F = np.broadcast_to(np.asarray(preloads.get(b.name, law.preload_N), dtype=float),
                                omega.shape)
            for e in effects:
                F = e.preload(b.name, omega, F)
            K = law.stiffness(F)[..., None, None] * np.eye(2)
        else:
            K = np.broadcast_to(law.stiffness_matrix(), omega.shape + (2, 2))
        for e in effects:
            K = e.bearing(b.name, omega, K)
        Ks.append(K)
    return Ks


def scale_bearing_coefficients(
    geometry: SpindleGeometry, theta_bearings: Sequence[str], Ks: Sequence[np.ndarray],
    theta: np.ndarray, shape: tuple[int, ...],
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`bearing_coefficients` from :func:`unscaled_bearing_stiffness`'s ``Ks``: each θ
    bearing's stiffness times its factor, the damping, stacked to ``shape + (nb, 2, 2)``."""
    out_K, out_C = [], []
    for b, K in zip(geometry.bearings, Ks, strict=True):
        law = b.law
        if b.name in theta_bearings:
            j = list(theta_bearings).index(b.name)
            K = K * theta[:, j][:, None, None, None]
        if isinstance(law, ConstantLaw) and law.c_matrix_Ns_per_m is not None:
            C = np.broadcast_to(np.asarray(law.c_matrix_Ns_per_m, float), K.shape)
        else:
            C = law.damping_eta_s * 0.5 * (K + np.swapaxes(K, -1, -2))
        out_K.append(np.broadcast_to(K, shape + (2, 2)))
        out_C.append(np.broadcast_to(C, shape + (2, 2)))
    return np.stack(out_K, axis=-3), np.stack(out_C, axis=-3)


def bearing_supports(geometry: SpindleGeometry, effects: Sequence[Effect]
                     ) -> tuple[Support | None, ...]:
    """The housing stage (or ``None``) in series with each bearing; at most one per bearing."""
    supports = []
    for b in geometry.bearings:
        sup = [s for e in effects if (s := e.support(b.name)) is not None]
        if len(sup) > 1:
            raise ValueError(f"bearing {b.name!r}: more than one effect adds a support stage")
        supports.append(sup[0] if sup else None)
    return tuple(supports)


def bearing_impedance(
    geometry: SpindleGeometry, effects: Sequence[Effect], theta_bearings: Sequence[str],
    omega: np.ndarray, theta: np.ndarray,
    supports: Sequence[Support | None] | None = None,
    preloads: Mapping[str, np.ndarray] | None = None,
) -> np.ndarray:
    """Dynamic stiffness ``Z = K + iΩC`` each bearing puts on its rotor node, ``(B, S, nb, 2, 2)``.

    A housing stage ``z_h = k + iΩc − Ω²m`` in series with a bearing is condensed into it:
    ``Z ← Z − Z (Z + z_h I)⁻¹ Z``. Arguments as :func:`bearing_coefficients`; ``supports``
    defaults to :func:`bearing_supports`. Without a stage, a θ bearing's impedance is affine in
    its factor: ``Z_j(θ) = θ_j (K_j + iΩ η K_j,sym)`` with proportional damping, or
    ``θ_j K_j + iΩ C_j`` with a law's own damping matrix (:func:`theta_affine`).
    """
    Kb, Cb = bearing_coefficients(geometry, effects, theta_bearings, omega, theta, preloads)
    Zb = Kb + 1j * omega[..., None, None, None] * Cb
    supports = bearing_supports(geometry, effects) if supports is None else supports
    if all(s is None for s in supports):
        return Zb
    out = []
    for j, sup in enumerate(supports):
        Z = Zb[..., j, :, :]
        if sup is not None:
            zh = sup.k_N_per_m + 1j * omega * sup.c_Ns_per_m - omega**2 * sup.m_kg
            Zs = Z + zh[..., None, None] * np.eye(2)
            Z = Z - Z @ np.linalg.solve(Zs, Z)
        out.append(Z)
    return np.stack(out, axis=-3)


def theta_affine(geometry: SpindleGeometry, effects: Sequence[Effect],
                 theta_bearings: Sequence[str]) -> bool:
    """Whether every bearing impedance is affine in θ: no housing stage in series with a θ
    bearing (a stage makes the condensed impedance rational in θ_j).

    θ scales a bearing's stiffness after every effect and its damping is either proportional
    to that stiffness or a constant matrix, so without a stage ``Z_j = θ_j A_j + B_j``.

    >>> from surrogate_rbrdo.spindle.effects import HousingFlexibility
    >>> from surrogate_rbrdo.spindle.reference import reference_spindle
    >>> sp = reference_spindle()
    >>> theta_affine(sp.geometry, sp.effects, ("front", "rear"))
    True
    >>> theta_affine(sp.geometry, (HousingFlexibility(bearings=("rear",), k_N_per_m=1e8,
    ...                                               m_kg=10.0),), ("front", "rear"))
    False
    """
    supports = bearing_supports(geometry, effects)
    return all(s is None for b, s in zip(geometry.bearings, supports, strict=True)
               if b.name in theta_bearings)


def build_model(
    geometry: SpindleGeometry,
    effects: Sequence[Effect] = (),
    *,
    theta_bearings: Sequence[str] | None = None,
    shear: bool = True,
    rotary: bool = True,
) -> SpindleModel:
    """Assemble the FE model of ``geometry`` with the given physical ``effects``.

    Parameters
    ----------
    geometry : SpindleGeometry
    effects : sequence of Effect
        Switchable physical effects (see :mod:`surrogate_rbrdo.spindle.effects`). Gyroscopics
        are on unless a :class:`~surrogate_rbrdo.spindle.effects.Gyroscopics` effect says
        otherwise.
    theta_bearings : sequence of str, optional
        Bearings whose stiffness the uncertain factors θ multiply; default all bearings.
    shear, rotary : bool
        Timoshenko shear deformation and rotary inertia (switch off only for verification).
    """
    effects = _check_effects(effects)
    theta_bearings = _check_theta_bearings(geometry, theta_bearings)
    joints = [j for e in effects if (j := e.joint()) is not None]
    if len({j.position_mm for j in joints}) != len(joints):
        raise ValueError("effects: two joints at one position")
    _check_joints(geometry, joints)
    z, sec_idx = _mesh(geometry, joints)
    sections = _beam_sections(geometry)
    M, K, G, emats, shaft_mass = _assemble_shaft(z, sec_idx, sections, joints, shear=shear,
                                                 rotary=rotary)
    mass = _add_disks(M, G, geometry, z, shaft_mass)
    bearing_nodes = np.array([_node_of(z, b.position_mm) for b in geometry.bearings])
    if len(set(bearing_nodes.tolist())) != len(bearing_nodes):
        raise ValueError("bearings: two bearings share one node; place them apart")
    return SpindleModel(
        geometry=geometry,
        effects=effects,
        theta_bearings=theta_bearings,
        z=z,
        element_section=sec_idx,
        M=M,
        K=K,
        G=G,
        blocks={"M": _split_blocks(M), "K": _split_blocks(K), "G": _split_blocks(G)},
        bearing_nodes=bearing_nodes,
        supports=bearing_supports(geometry, effects),
        unbalance_nodes=np.array([_node_of(z, u.position_mm) for u in geometry.unbalances],
                                 dtype=int),
        unbalance=_unbalance_phasors(geometry, effects),
        tool_node=_node_of(z, geometry.tool_tip_mm),
        rotor_mass_kg=float(mass),
        sections=sections,
        element_mats=emats,
    )


def _check_effects(effects: Sequence[Effect]) -> tuple[Effect, ...]:
    """The effects as a tuple: every one an :class:`Effect`, at most one gyroscopics switch."""
    effects = tuple(effects)
    for e in effects:
        if not isinstance(e, Effect):
            raise ValueError(f"effects: {e!r} is not an Effect")
    if sum(isinstance(e, Gyroscopics) for e in effects) > 1:
        raise ValueError("effects: at most one 'gyroscopics' effect is allowed")
    return effects


def _check_theta_bearings(geometry: SpindleGeometry,
                          theta_bearings: Sequence[str] | None) -> tuple[str, ...]:
    """The bearings θ multiplies (default all), each a bearing of ``geometry``, none twice."""
    names = [b.name for b in geometry.bearings]
    theta_bearings = tuple(names if theta_bearings is None else theta_bearings)
    for t in theta_bearings:
        if t not in names:
            raise ValueError(f"theta_bearings: {t!r} is not a bearing; bearings are {names}")
    if len(set(theta_bearings)) != len(theta_bearings):
        raise ValueError(f"theta_bearings = {list(theta_bearings)} is not allowed: each bearing "
                         "may carry one θ factor (a name appears twice)")
    return theta_bearings


def _beam_sections(geometry: SpindleGeometry) -> tuple[BeamSection, ...]:
    """The geometry's shaft sections in SI with their materials."""
    mats = geometry.materials
    return tuple(
        BeamSection(s.outer_diameter_mm * MM, s.inner_diameter_mm * MM,
                    mats[s.material].E_Pa, mats[s.material].nu, mats[s.material].rho_kg_m3)
        for s in geometry.sections
    )


def _assemble_shaft(z: np.ndarray, sec_idx: np.ndarray, sections: tuple[BeamSection, ...],
                    joints: Sequence[Joint], *, shear: bool, rotary: bool
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, float]:
    """Global M, K, G of the shaft's Timoshenko elements (a zero-length element is a joint:
    springs between two coincident nodes, no mass), the element matrices and the shaft mass."""
    nn = z.size
    n = 4 * nn
    M, K, G = np.zeros((n, n)), np.zeros((n, n)), np.zeros((n, n))
    mass = 0.0
    emats = np.zeros((nn - 1, 3, 8, 8))
    for e in range(nn - 1):
        L = z[e + 1] - z[e]
        sec = sections[sec_idx[e]]
        if L == 0.0:
            emats[e, 1] = _joint_matrix(next(j for j in joints
                                             if abs(j.position_mm * MM - z[e]) < 1e-9))
        else:
            emats[e] = _element_matrices(sec, float(L), shear, rotary)
        sl = slice(4 * e, 4 * e + 8)
        M[sl, sl] += emats[e, 0]
        K[sl, sl] += emats[e, 1]
        G[sl, sl] += emats[e, 2]
        mass += sec.rho * sec.area * L
    return M, K, G, emats, mass


@lru_cache(maxsize=4096)
def _element_matrices(sec: BeamSection, L: float, shear: bool, rotary: bool) -> np.ndarray:
    """:func:`~.element.element_matrices` as one read-only ``(3, 8, 8)`` array, memoised: a
    model rebuilt with another effect (a candidate's joint, a gyroscopic scale) has the same
    elements."""
    out = np.array(element_matrices(sec, L, shear=shear, rotary=rotary))
    out.flags.writeable = False
    return out


def _add_disks(M: np.ndarray, G: np.ndarray, geometry: SpindleGeometry, z: np.ndarray,
               mass: float) -> float:
    """Add the rigid disks' mass, diametral and polar inertia in place; ``mass`` plus theirs."""
    for d in geometry.disks:
        i = 4 * _node_of(z, d.position_mm)
        M[i, i] += d.mass_kg
        M[i + 1, i + 1] += d.mass_kg
        M[i + 2, i + 2] += d.diametral_inertia_kgm2
        M[i + 3, i + 3] += d.diametral_inertia_kgm2
        G[i + 2, i + 3] += d.polar_inertia_kgm2
        G[i + 3, i + 2] -= d.polar_inertia_kgm2
        mass += d.mass_kg
    return mass


def _split_blocks(A: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The 4 × 4 diagonal, upper and lower node blocks of a block-tridiagonal matrix."""
    nn = A.shape[0] // 4
    idx = np.arange(nn)
    diag = np.stack([A[4 * i:4 * i + 4, 4 * i:4 * i + 4] for i in idx])
    up = np.stack([A[4 * i:4 * i + 4, 4 * i + 4:4 * i + 8] for i in idx[:-1]])
    low = np.stack([A[4 * i + 4:4 * i + 8, 4 * i:4 * i + 4] for i in idx[:-1]])
    return diag, up, low


def _unbalance_phasors(geometry: SpindleGeometry, effects: tuple[Effect, ...]) -> np.ndarray:
    """``U e^{iφ}`` of each unbalance plane, after the effects that change the unbalance."""
    U = np.array([u.magnitude_kgm * np.exp(1j * np.deg2rad(u.phase_deg))
                  for u in geometry.unbalances], dtype=complex)
    for e in effects:
        U = e.unbalance(U)
    return U
