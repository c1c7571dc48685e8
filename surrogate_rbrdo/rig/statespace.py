"""First-order (state-space) form of the spindle model at one speed, and its reduction basis.

``M q'' + C(Ω) q' + K(Ω) q = f`` (``C`` includes ``Ω G``; :meth:`SpindleModel.system_matrices`)
is written as ``z' = A z + B f``, ``q = C_q z``. Two things need care:

* **Massless DOFs** (a housing stage with ``m_kg = 0``: rows of ``M`` that are zero) have no
  acceleration. Those without damping are condensed statically
  (``q_u = −K_uu⁻¹ K_ur q_r``, exact for them); those with damping (the bearing's ``c = ηk`` in
  series with the stage) are first-order coordinates of their own,
  ``C_dd q_d' = f_d − K_ds q_s − C_ds q_s' − K_dd q_d`` (a spring–damper without mass is a
  first-order element; Géradin & Rixen, *Mechanical Vibrations*, 3rd ed. 2015, §2.6).
  The state is ``z = [q_s, q_s', q_d]`` with ``q_s`` the DOFs with mass.
* **Reduction** (ramps): ``q = T x`` with ``T`` a Ritz basis of the DOFs with mass — undamped
  modes of the statically condensed system below ``f_cut_hz`` plus the static shapes of the
  loads (they keep the quasi-static part of the truncated modes; Craig & Kurdila,
  *Fundamentals of Structural Dynamics*, 2006, §14.5) — and one unit column per massless DOF.
  ``f_cut_hz=None`` keeps every DOF (the exact form).

>>> from surrogate_rbrdo.spindle import reference_spindle
>>> sp = reference_spindle()
>>> m = sp.model(sp.baseline)
>>> red = reduction(m, None, [0.0], np.zeros((m.n_dof, 1)), None)
>>> fo = first_order(m, None, 1000.0, red)
>>> fo.A.shape == (2 * m.n_dof, 2 * m.n_dof), fo.B.shape[1] == m.n_dof
(True, True)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from surrogate_rbrdo.core.errors import ModelError
from surrogate_rbrdo.spindle.assembly import RPM, SpindleModel


def massless_dofs(M: np.ndarray) -> np.ndarray:
    """Indices of the DOFs without mass (all-zero rows of ``M``)."""
    return np.flatnonzero(~np.any(M != 0.0, axis=1))


@dataclass(frozen=True)
class Reduction:
    """``q = T x``: the first ``T.shape[1] − n_massless`` columns span the DOFs with mass (a
    Ritz basis or unit vectors), the last ``n_massless`` are the massless DOFs themselves."""

    T: np.ndarray
    n_massless: int


def _split(M: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    ml = massless_dofs(M)
    return np.setdiff1d(np.arange(M.shape[0]), ml), ml


def _condensed_stiffness(K: np.ndarray, s: np.ndarray, m: np.ndarray
                         ) -> tuple[np.ndarray, np.ndarray]:
    """``K_ss − K_sm K_mm⁻¹ K_ms`` and ``−K_mm⁻¹ K_ms`` (the static slave map)."""
    if m.size == 0:
        return K[np.ix_(s, s)], np.zeros((0, s.size))
    try:
        G = -np.linalg.solve(K[np.ix_(m, m)], K[np.ix_(m, s)])
    except np.linalg.LinAlgError:
        raise ModelError("integrate: massless DOFs without stiffness (a free massless "
                         "node?)") from None
    return K[np.ix_(s, s)] + K[np.ix_(s, m)] @ G, G


def reduction(model: SpindleModel, theta: np.ndarray | None, omegas: np.ndarray,
              loads: np.ndarray, f_cut_hz: float | None) -> Reduction:
    """The basis ``T`` for speeds ``omegas`` (rad/s; modes and static shapes at each, merged)
    and loads ``loads`` (n, k) complex."""
    M = model.system_matrices(0.0, theta)[0]
    n = M.shape[0]
    s, m = _split(M)
    T = np.zeros((n, 0))
    if f_cut_hz is None:
        T = np.eye(n)[:, s]
    else:
        Ms = M[np.ix_(s, s)]
        Phi = np.column_stack([_ritz_vectors(model, theta, float(w), Ms, s, m, loads, f_cut_hz)
                               for w in np.atleast_1d(omegas)])
        mass = np.einsum("ij,ik,kj->j", Phi, Ms, Phi)
        Phi = Phi[:, mass > 0] / np.sqrt(mass[mass > 0])                # unit modal mass
        lam, U = np.linalg.eigh(Phi.T @ Ms @ Phi)
        keep = lam > 1e-10 * lam.max()                                   # drop dependent ones
        T = np.zeros((n, int(keep.sum())))
        T[s] = Phi @ (U[:, keep] / np.sqrt(lam[keep]))
    E = np.zeros((n, m.size))
    E[m, np.arange(m.size)] = 1.0
    return Reduction(np.column_stack([T, E]), int(m.size))


def _ritz_vectors(model, theta, omega, Ms, s, m, loads, f_cut_hz) -> np.ndarray:
    """Ritz vectors at one speed: undamped modes of the condensed system below ``f_cut_hz``;
    static shapes ``K⁻¹ f`` of the loads and their mass correction ``K⁻¹ M K⁻¹ f`` (the
    truncated modes' quasi-static part to second order); and for the modes below
    ``f_cut_hz / 4`` the shapes ``K⁻¹ G φ`` and ``K⁻¹ C φ`` that the gyroscopic and damping
    forces of those modes induce (modal truncation augmentation; Dickens, Nakagawa & Wittbrodt,
    *Comput. Struct.* 62:985, 1997)."""
    _, C, K = model.system_matrices(omega, theta)
    G = np.zeros_like(K)
    G[:model.n_dof, :model.n_dof] = model.gyro_scale * model.G
    Kc, S = _condensed_stiffness(K, s, m)
    Kc = 0.5 * (Kc + Kc.T)
    ld = np.column_stack([loads.real, loads.imag])
    ld = ld[s] + S.T @ ld[m]
    try:
        w2, modes = sla.eigh(Kc, Ms, subset_by_value=(-np.inf, (2 * np.pi * f_cut_hz) ** 2))
        low = modes[:, w2 < (np.pi * f_cut_hz / 2) ** 2]
        rhs = np.column_stack([ld, G[np.ix_(s, s)] @ low, C[np.ix_(s, s)] @ low])
        static = np.linalg.solve(Kc, rhs)
        static2 = np.linalg.solve(Kc, Ms @ static[:, :ld.shape[1]])
    except np.linalg.LinAlgError as exc:
        raise ModelError("integrate: singular mass or stiffness of the DOFs with mass "
                         "(a free body?)") from exc
    return np.column_stack([modes, static, static2])


@dataclass(frozen=True)
class FirstOrder:
    """``z' = A z + B f`` (``f`` the physical force, n), ``q = Cq z`` (physical displacement),
    ``q'' = Ca z + Da f`` (physical acceleration of the DOFs with mass)."""

    A: np.ndarray
    B: np.ndarray
    Cq: np.ndarray
    Ca: np.ndarray
    Da: np.ndarray


def first_order(model: SpindleModel, theta: np.ndarray | None, omega: float,
                red: Reduction) -> FirstOrder:
    """The first-order form at speed ``omega`` (rad/s) in the coordinates of ``red``."""
    M, C, K = (red.T.T @ X @ red.T for X in model.system_matrices(omega, theta))
    p = M.shape[0]
    if red.n_massless == 0:                          # the usual case: z = [x, x']
        Mi = np.linalg.inv(M)
        A = np.block([[np.zeros((p, p)), np.eye(p)], [-Mi @ K, -Mi @ C]])
        B = np.vstack([np.zeros((p, red.T.shape[0])), Mi @ red.T.T])
        return FirstOrder(A, B, np.hstack([red.T, np.zeros_like(red.T)]), red.T @ A[p:],
                          red.T @ B[p:])
    ml = np.arange(p - red.n_massless, p)
    tol = 1e-12 * max(np.abs(C).max(), 1e-300)
    undamped = ml[~np.any(np.abs(C[ml]) > tol, axis=1) & ~np.any(np.abs(C[:, ml]) > tol,
                                                                   axis=0)]
    r = np.setdiff1d(np.arange(p), undamped)
    Kr, G = _condensed_stiffness(K, r, undamped)
    S = np.zeros((p, r.size))                      # x_full = S x_r
    S[r, np.arange(r.size)] = 1.0
    S[undamped] = G
    Mr, Cr = M[np.ix_(r, r)], C[np.ix_(r, r)]
    d = np.flatnonzero(np.isin(r, ml))             # damped massless, within r
    s = np.setdiff1d(np.arange(r.size), d)
    try:
        Mi = np.linalg.inv(Mr[np.ix_(s, s)])
        E = np.linalg.inv(Cr[np.ix_(d, d)]) if d.size else np.zeros((0, 0))
    except np.linalg.LinAlgError:
        raise ModelError("integrate: singular mass matrix, or massless DOFs whose damping "
                         "matrix is singular (give the housing stage a mass or a damper)"
                         ) from None
    ns, nd = s.size, d.size
    Kss, Ksd, Kds, Kdd = (Kr[np.ix_(a, b)] for a, b in ((s, s), (s, d), (d, s), (d, d)))
    Css, Csd, Cds = (Cr[np.ix_(a, b)] for a, b in ((s, s), (s, d), (d, s)))
    N = 2 * ns + nd
    A = np.zeros((N, N))
    A[:ns, ns:2 * ns] = np.eye(ns)
    EK, EC, EKd = E @ Kds, E @ Cds, E @ Kdd
    A[2 * ns:, :ns], A[2 * ns:, ns:2 * ns], A[2 * ns:, 2 * ns:] = -EK, -EC, -EKd
    A[ns:2 * ns, :ns] = -Mi @ (Kss - Csd @ EK)
    A[ns:2 * ns, ns:2 * ns] = -Mi @ (Css - Csd @ EC)
    A[ns:2 * ns, 2 * ns:] = -Mi @ (Ksd - Csd @ EKd)
    F = (red.T @ S).T                                # physical force -> x_r coordinates
    B = np.zeros((N, F.shape[1]))
    B[ns:2 * ns] = Mi @ (F[s] - Csd @ E @ F[d])
    B[2 * ns:] = E @ F[d]
    Q = red.T @ S                                    # x_r -> physical displacement
    Cq = np.zeros((Q.shape[0], N))
    Cq[:, :ns], Cq[:, 2 * ns:] = Q[:, s], Q[:, d]
    return FirstOrder(A, B, Cq, Q[:, s] @ A[ns:2 * ns], Q[:, s] @ B[ns:2 * ns])


@dataclass(frozen=True)
class Modes:
    """Eigen-decomposition ``A = V diag(λ) W`` (``W = V⁻¹``) of a first-order form."""

    lam: np.ndarray
    V: np.ndarray
    W: np.ndarray


def decompose(A: np.ndarray, omega: float) -> Modes:
    """Eigenvalues and vectors of ``A``; raises :class:`ModelError` for an unstable,
    undamped or defective system at speed ``omega`` (rad/s)."""
    lam, V = np.linalg.eig(A)
    try:
        W = np.linalg.inv(V)
    except np.linalg.LinAlgError as exc:
        raise ModelError(f"integrate: defective system at {omega / RPM:.6g} rpm") from exc
    if np.any(lam.real >= 0):
        raise ModelError(f"integrate: unstable or undamped mode at {omega / RPM:.6g} rpm "
                         f"(max Re λ = {lam.real.max():.3g})")
    return Modes(lam, V, W)


def require_stable(model: SpindleModel, theta: np.ndarray | None, speeds_rpm, red: Reduction,
                   what: str, hint: str = "") -> None:
    """Raise :class:`~surrogate_rbrdo.core.errors.ModelError` naming ``what`` (e.g. "the truth
    of build 0, tool 0, run 3"), the speed and ``hint`` (a likely cause, in brackets) if any
    :func:`growth_rates` is ``>= 0``: no steady state to measure there."""
    sp = np.asarray(speeds_rpm, float)
    g = growth_rates(model, theta, sp, red)
    if np.any(g >= 0):
        raise ModelError(f"{what} is unstable at {sp[int(np.argmax(g))]:.6g} rpm (growth rate "
                         f"{g.max():.3g} 1/s): no steady state to measure"
                         + (f" ({hint})" if hint else ""))


def growth_rates(model: SpindleModel, theta: np.ndarray | None, speeds_rpm: np.ndarray,
                 red: Reduction) -> np.ndarray:
    """Largest real part of the eigenvalues (1/s) at each speed, of the system projected on
    ``red`` (a Ritz basis is enough: the lowest modes, those that go unstable, are resolved to
    ~1e-6 of their frequency): > 0 means no steady state exists at that speed."""
    out = np.empty(len(speeds_rpm))
    for i, s in enumerate(np.asarray(speeds_rpm, float)):
        out[i] = np.linalg.eigvals(first_order(model, theta, s * RPM, red).A).real.max()
    return out
