"""Bearing reactions of the flexible FE rotor from measured 1× phasors, by exact condensation.

The rotor *without* its bearings is known: ``A(Ω) = (1 + iΩβ)K − Ω²M + iΩαM + iΩ²G``
(:func:`~surrogate_rbrdo.spindle.substructure.rotor_dynamic_stiffness`). It is condensed
exactly (dynamic Schur complement) onto the retained set ``R`` = the lateral DOFs ``x, y`` of
the bearing nodes and of the probe nodes; rotations and every other DOF are condensed out,
which is exact because the bearings carry no moment stiffness (true for this model):

    S(Ω) = A_RR − A_RI A_II⁻¹ A_IR,     f̃ = f_R − A_RI A_II⁻¹ f_I,
    S q_R = f̃ + P_b f_b,

with ``f`` the *known* unbalance load and ``f_b`` the bearing forces on the rotor. The unknown
journal displacements (bearing DOFs without a probe) and ``f_b`` solve this system in the least
squares sense (exactly when there are as many probe DOFs as bearing DOFs); the reaction on each
bearing is ``r = −f_b``. Everything is linear in the measured phasors ``q_m``:
``x_b = L_x q_m + c_x``, ``r_b = L_r q_m + c_r`` (:class:`CondensedReactions`).

Only the lateral DOFs are retained and the load is condensed with the stiffness, which is why
this does not call :func:`~surrogate_rbrdo.spindle.substructure.condensed_rotor` (it keeps all
four DOFs of each retained node and no load); both use the same ``rotor_dynamic_stiffness``.

Per bearing and direction (``x`` → ``yy``, ``y`` → ``zz``) the model is
``r = (k + iΩc) x`` — at one speed ``k + iΩc = r / x`` (:func:`identify_phasors`), or as a time
regression ``r(t) = k x(t) + c ẋ(t)`` for SG/MISG (:func:`phasor_time_regression`).

Assumptions and where they break (``docs/identification.md`` has the figures):

* the unbalance load is known — the rotor's own (simulation), or a trial mass whose response is
  the difference of runs with and without it (linearity; ``trial_weight_difference``). A
  residual unbalance that is not known cannot be separated from the bearings at one speed;
* bearings are diagonal: cross-coupled stiffness ``k_yz`` is not identifiable from synchronous
  unbalance response of a near-isotropic rotor (the orbits are circular, ``y = −i x``, so both
  directions see the same excitation) and shows up as a damping error ``Δc = −k_yz / Ω``;
* probes far from the bearings: the expansion ``q_m → x_b`` amplifies noise
  (``expansion_condition``, ``noise_gain``);
* a speed near a pole of ``S`` (a natural frequency of the rotor with the retained DOFs
  clamped): ``A_II`` is singular (``interior_condition``);
* damping: ``Ωc`` is ~0.4 % of ``k`` for η = 4e-6 s at 10 000 rpm (1 % at 24 000 rpm), so a
  phasor noise that costs ``k`` 0.3 % costs ``c`` tens of percent.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from surrogate_rbrdo.core.errors import ModelError
from surrogate_rbrdo.identification.regression import Regression
from surrogate_rbrdo.spindle.assembly import RPM, SpindleModel
from surrogate_rbrdo.spindle.harmonic import unbalance_load
from surrogate_rbrdo.spindle.substructure import rotor_dynamic_stiffness

#: the model's lateral directions and the paper's names for them
DIRECTIONS = {"x": "yy", "y": "zz"}


def coefficient_names(bearings: Sequence[str]) -> tuple[str, ...]:
    """``<bearing>_<k|c>_<yy|zz>`` per bearing: k_yy, k_zz, c_yy, c_zz.

    >>> coefficient_names(("front",))
    ('front_k_yy', 'front_k_zz', 'front_c_yy', 'front_c_zz')
    """
    return tuple(f"{b}_{q}_{d}" for b in bearings for q in ("k", "c")
                 for d in DIRECTIONS.values())


def node_at(model: SpindleModel, position_mm: float, *, tol_mm: float = 1.0) -> int:
    """The FE node at an axial position (mm), or a ``ValueError`` if none is within ``tol_mm``."""
    d = np.abs(model.z * 1e3 - position_mm)
    i = int(np.argmin(d))
    if d[i] > tol_mm:
        raise ValueError(f"position_mm = {position_mm} is not allowed: no FE node within "
                         f"{tol_mm} mm (nearest {model.z[i] * 1e3:.3f} mm); add a node there")
    return i


@dataclass(frozen=True, eq=False)
class CondensedReactions:
    """Linear maps from measured phasors to journal displacements and bearing reactions.

    Attributes
    ----------
    speeds_rpm : ndarray (S,)
    bearings : tuple of str
    probe_nodes : tuple of int
        Measured nodes; measured phasors are ordered ``[x, y]`` per probe node.
    Lx, Lr : ndarray (S, 2 nb, 2 np) complex
    cx, cr : ndarray (S, 2 nb) complex
        ``x_b = Lx q_m + cx`` and ``r_b = Lr q_m + cr`` per speed (bearing-major, x then y).
    expansion_condition : ndarray (S,)
        Condition number of the (column-equilibrated) solve for the unmeasured journals and
        the bearing forces: 1 when the probes sit on the bearings, large when they are far.
    interior_condition : ndarray (S,)
        Condition number of the (equilibrated) ``A_II``: large near a pole of ``S(Ω)``.
    pole_ratio : ndarray (S,)
        ``interior_condition`` relative to its static value (``A_II`` at rest): ~1–10 away
        from a pole, ~100 within a few hundred rpm of one (reference spindle, 22 621 rpm).
    """

    speeds_rpm: np.ndarray
    bearings: tuple[str, ...]
    probe_nodes: tuple[int, ...]
    Lx: np.ndarray
    cx: np.ndarray
    Lr: np.ndarray
    cr: np.ndarray
    expansion_condition: np.ndarray
    interior_condition: np.ndarray
    pole_ratio: np.ndarray

    @property
    def names(self) -> tuple[str, ...]:
        return coefficient_names(self.bearings)

    def speed_index(self, speeds_rpm: np.ndarray) -> np.ndarray:
        """Index of each speed among ``speeds_rpm`` of the condensation (exact to 1e-9 rpm)."""
        sp = np.atleast_1d(np.asarray(speeds_rpm, dtype=float))
        idx = np.abs(sp[:, None] - self.speeds_rpm[None, :]).argmin(axis=1)
        bad = np.abs(self.speeds_rpm[idx] - sp) > 1e-9 * np.maximum(sp, 1.0)
        if bad.any():
            raise ValueError(f"speeds_rpm {sp[bad][:3].tolist()} were not condensed; condensed "
                             f"speeds: {self.speeds_rpm[:5].tolist()}...")
        return idx

    def reactions(self, phasors: np.ndarray, speeds_rpm: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray]:
        """Journal displacements and bearing reactions ``(N, 2 nb)`` of records ``(N, 2 np)``."""
        q = _check_phasors(phasors, 2 * len(self.probe_nodes))
        si = self.speed_index(speeds_rpm)
        if si.size != q.shape[0]:
            raise ValueError(f"speeds_rpm has {si.size} entries for {q.shape[0]} records")
        x = np.einsum("nij,nj->ni", self.Lx[si], q) + self.cx[si]
        r = np.einsum("nij,nj->ni", self.Lr[si], q) + self.cr[si]
        return x, r


def _check_phasors(phasors, n: int) -> np.ndarray:
    q = np.asarray(phasors, dtype=complex)
    if q.ndim == 1:
        q = q[None]
    if q.ndim != 2 or q.shape[1] != n or not np.all(np.isfinite(q)):
        raise ValueError(f"phasors has shape {np.shape(phasors)}: need (N, {n}) finite complex "
                         "amplitudes ([x, y] per probe node, m)")
    return q


def trial_weight_difference(with_trial: np.ndarray, without: np.ndarray) -> np.ndarray:
    """Phasors of the trial mass alone: ``q(U0 + U_t) − q(U0)`` (the system is linear).

    Use them with ``condense_reactions(..., unbalance=[(node, U_t)])``; the residual unbalance
    ``U0`` drops out. Their noise is √2 times a single run's.
    """
    a, b = np.asarray(with_trial, dtype=complex), np.asarray(without, dtype=complex)
    if a.shape != b.shape:
        raise ValueError(f"with_trial has shape {a.shape} and without {b.shape}: they must match")
    return a - b


def _lateral_dofs(nodes) -> np.ndarray:
    """Global indices of the ``x, y`` DOFs of ``nodes``."""
    return np.array([4 * n + d for n in nodes for d in (0, 1)], dtype=int)


def _load(model: SpindleModel, omega: np.ndarray, unbalance) -> np.ndarray:
    if unbalance is not None:
        nodes = np.array([int(n) for n, _ in unbalance], dtype=int)
        U = np.array([complex(u) for _, u in unbalance], dtype=complex)
        if nodes.size == 0 or np.any((nodes < 0) | (nodes >= model.n_nodes)):
            raise ValueError(f"unbalance nodes {nodes.tolist()} are not allowed: need nodes in "
                             f"[0, {model.n_nodes - 1}]")
        model = replace(model, unbalance_nodes=nodes, unbalance=U)
    return unbalance_load(model, omega).reshape(omega.size, -1)


def condense_reactions(model: SpindleModel, speeds_rpm: np.ndarray, *,
                       probe_nodes: Sequence[int] | None = None,
                       unbalance: Sequence[tuple[int, complex]] | None = None
                       ) -> CondensedReactions:
    """Condense the known rotor of ``model`` onto its bearings and probes at ``speeds_rpm``.

    Parameters
    ----------
    model : SpindleModel
        Only the rotor (M, K, G, Rayleigh damping, gyroscopic scale) and the node layout are
        used; the bearings are what is identified.
    speeds_rpm : array (S,)
    probe_nodes : sequence of int, optional
        Nodes whose ``x, y`` are measured; default the bearing nodes.
    unbalance : sequence of (node, U kg m), optional
        The known excitation; default the model's own unbalance. Give the trial mass when the
        phasors are trial-weight differences.

    Raises
    ------
    ValueError
        Fewer probe DOFs than bearing DOFs without a probe (the reactions are not determined).
    ModelError
        ``A_II`` singular (a speed on a pole of ``S(Ω)``).
    """
    sp = np.atleast_1d(np.asarray(speeds_rpm, dtype=float))
    if sp.ndim != 1 or sp.size == 0 or not np.all(np.isfinite(sp) & (sp > 0)):
        raise ValueError(f"speeds_rpm = {sp.tolist()} is not allowed: need finite speeds > 0")
    bnodes = [int(n) for n in model.bearing_nodes]
    pnodes = list(bnodes if probe_nodes is None else [int(n) for n in probe_nodes])
    if len(set(pnodes)) != len(pnodes) or any(not 0 <= n < model.n_nodes for n in pnodes):
        raise ValueError(f"probe_nodes = {pnodes} is not allowed: distinct nodes in "
                         f"[0, {model.n_nodes - 1}]")
    lat = _lateral_dofs
    R = np.unique(np.concatenate([lat(bnodes), lat(pnodes)]))
    pos = {int(d): i for i, d in enumerate(R)}
    m_idx = np.array([pos[d] for d in lat(pnodes)])
    b_idx = np.array([pos[d] for d in lat(bnodes)])
    u_idx = np.array([pos[d] for d in lat(bnodes) if d not in set(lat(pnodes).tolist())], int)
    if u_idx.size + b_idx.size > R.size:
        raise ValueError(f"probe_nodes = {pnodes}: {m_idx.size} probe DOFs cannot determine "
                         f"{u_idx.size} unmeasured journal DOFs and {b_idx.size} bearing forces; "
                         "put at least one probe pair per bearing")
    omega = sp * RPM
    A = rotor_dynamic_stiffness(model, omega)
    f = _load(model, omega, unbalance)
    Ii = np.setdiff1d(np.arange(A.shape[-1]), R)
    AII = A[:, Ii[:, None], Ii]
    try:
        X = np.linalg.solve(AII, np.concatenate([A[:, Ii[:, None], R], f[:, Ii, None]], -1))
    except np.linalg.LinAlgError as exc:
        raise ModelError(f"condense_reactions: A_II singular at one of {sp.tolist()} rpm (a "
                         "pole of the condensed rotor)") from exc
    Sc = A[:, R[:, None], R] - A[:, R[:, None], Ii] @ X[..., :-1]
    ft = f[:, R] - (A[:, R[:, None], Ii] @ X[..., -1:])[..., 0]
    Lx, cx, Lr, cr, Gm = _journals_and_forces(Sc, ft, m_idx, b_idx, u_idx)
    if not (np.all(np.isfinite(Lr)) and np.all(np.isfinite(cr))):
        raise ModelError(f"condense_reactions: non-finite reactions at {sp.tolist()} rpm")
    inner = _equilibrated_cond(AII)
    static = _equilibrated_cond(rotor_dynamic_stiffness(model, np.array([1e-6]))[
        :, Ii[:, None], Ii])
    return CondensedReactions(
        speeds_rpm=sp, bearings=tuple(b.name for b in model.geometry.bearings),
        probe_nodes=tuple(pnodes), Lx=Lx, cx=cx, Lr=Lr, cr=cr,
        expansion_condition=_equilibrated_cond(Gm), interior_condition=inner,
        pole_ratio=inner / static)


def _journals_and_forces(Sc, ft, m_idx, b_idx, u_idx):
    """Solve ``S q_R = f̃ + P_b f_b`` for the unmeasured journals and the bearing forces in
    terms of the measured DOFs: ``x_b = Lx q_m + cx``, ``r_b = −f_b = Lr q_m + cr``; also the
    (unknowns') system matrix ``Gm`` for its condition number."""
    S = Sc.shape[0]
    Pb = np.zeros((Sc.shape[1], b_idx.size))
    Pb[b_idx, np.arange(b_idx.size)] = 1.0
    Gm = np.concatenate([Sc[:, :, u_idx], np.broadcast_to(-Pb, (S,) + Pb.shape)], -1)
    Gp = np.linalg.pinv(Gm)                                    # (S, nu + nb2, r)
    W = -Gp @ Sc[:, :, m_idx]                                  # w = W q_m + w0
    w0 = (Gp @ ft[..., None])[..., 0]
    Lx = np.zeros((S, b_idx.size, m_idx.size), complex)
    cx = np.zeros((S, b_idx.size), complex)
    u_pos = {int(j): i for i, j in enumerate(u_idx)}
    m_pos = {int(j): i for i, j in enumerate(m_idx)}
    for i, j in enumerate(b_idx):
        if int(j) in m_pos:
            Lx[:, i, m_pos[int(j)]] = 1.0
        else:
            Lx[:, i], cx[:, i] = W[:, u_pos[int(j)]], w0[:, u_pos[int(j)]]
    nu = u_idx.size
    return Lx, cx, -W[:, nu:], -w0[:, nu:], Gm


def _equilibrated_cond(A: np.ndarray) -> np.ndarray:
    """Condition number after scaling every column to unit norm (unit-free)."""
    n = np.linalg.norm(A, axis=-2, keepdims=True)
    return np.linalg.cond(A / np.where(n > 0, n, 1.0))


def phasor_time_regression(x: np.ndarray, r: np.ndarray, speeds_rpm: np.ndarray, *,
                           n_samples: int, dt_s: float = 1e-4) -> Regression:
    """Time samples of the 1× signals as the regression ``r(t) = k x(t) + c ẋ(t)``.

    ``x``, ``r`` are journal displacement and reaction phasors ``(N, 2 nb)``; each record and
    bearing direction becomes one regression record (record-major), sampled at ``t_j = j Δt``:
    ``y = Re(r e^{iΩt})``, ``φ = [Re(x e^{iΩt}), Re(iΩ x e^{iΩt})]``. A 1× signal carries two
    real numbers per channel, so least squares on these samples equals the phasor solution;
    SG and MISG see the pure-1× (nearly collinear) regressors of the paper's setting.
    """
    x, r = np.asarray(x, dtype=complex), np.asarray(r, dtype=complex)
    w = np.atleast_1d(np.asarray(speeds_rpm, dtype=float)) * RPM
    if x.shape != r.shape or x.ndim != 2 or w.shape != (x.shape[0],):
        raise ValueError(f"x {x.shape}, r {r.shape}, speeds_rpm {w.shape}: need (N, m), (N, m) "
                         "and (N,)")
    e = np.exp(1j * w[:, None] * np.arange(int(n_samples))[None, :] * dt_s)   # (N, T)
    xt = (x[:, :, None] * e[:, None, :])                                      # (N, m, T)
    phi = np.stack([xt.real, (1j * w[:, None, None] * xt).real], axis=-1)
    y = (r[:, :, None] * e[:, None, :]).real
    N, m = x.shape
    return Regression(phi.reshape(N * m, -1, 2), y.reshape(N * m, -1), ("k", "c"))


__all__ = ["DIRECTIONS", "CondensedReactions", "coefficient_names", "condense_reactions",
           "node_at", "phasor_time_regression", "trial_weight_difference"]
