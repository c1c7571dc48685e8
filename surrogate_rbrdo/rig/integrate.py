"""Time integration of the spindle model: exact at constant speed, exponential midpoint on ramps.

The model ``M q'' + (C(Ω) + Ω G) q' + K(Ω) q = f(t)`` (bearings, gyroscopics and housing stages
as :meth:`SpindleModel.system_matrices` gives them) is written in first-order form
``z' = A z + B f`` and diagonalised, ``A = V Λ V⁻¹``. In modal coordinates ``η = V⁻¹ z`` each
mode obeys ``η' = λ η + p(t)``, whose step over ``[t, t + h]`` is *exact* for an input of the
form ``e^{ντ} (c₀ + c₁ τ/h)``:

    η(t + h) = e^{λh} η(t) + h e^{λh} [φ₁(μh) c₀ + (φ₁(μh) − φ₂(μh)) c₁],   μ = ν − λ,

with ``φ₁(x) = (eˣ − 1)/x`` and ``φ₂(x) = (eˣ − 1 − x)/x²``. The rotating unbalance force
``Re(P (φ'² − iφ'') e^{iφ(t)})`` is such an input with ``ν = ±iΩ`` and a slowly varying
envelope taken linear over the step; a sampled force (hammer) is ``ν = 0`` with linear
interpolation between samples (first-order hold).

* **Constant speed** (one segment, full basis): exact for the linear model — the response
  converges to the FE harmonic solution (``spindle.harmonic``) to round-off, tested ≤ 1e-6.
* **Speed ramps**: ``A(Ω)`` is frozen at the mid-segment speed over segments of
  ``segment_s`` (exponential midpoint rule, second order in ``segment_s``), the modal state is
  carried across segments by ``η ← V_{s+1}⁻¹ V_s η``. The rotor is projected on a Ritz basis
  (undamped modes below ``f_cut_hz`` plus the static shapes of the loads, which keep the
  quasi-static part of the truncated modes); ``f_cut_hz=None`` keeps every DOF.
  Convergence in ``segment_s`` and ``f_cut_hz`` is tested.

Massless DOFs (a housing stage without mass) have no first-order form here: give them a mass.

>>> import numpy as np
>>> from surrogate_rbrdo.rig.integrate import SpeedProfile
>>> p = SpeedProfile.ramp(1000.0, 2000.0, 1.0)
>>> round(float(p.angle(np.array([1.0]))[0] / (2 * np.pi)), 6)   # revolutions in the ramp
25.0
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from surrogate_rbrdo.core.errors import ModelError
from surrogate_rbrdo.core.validate import check_int, check_positive
from surrogate_rbrdo.spindle.assembly import RPM, SpindleModel


@dataclass(frozen=True)
class SpeedProfile:
    """Spin speed linear between breakpoints ``(times_s, speeds_rpm)``; constant outside.

    The shaft angle ``φ(t) = phase0_rad + ∫Ω`` is integrated exactly (quadratic per piece).
    """

    times_s: tuple[float, ...]
    speeds_rpm: tuple[float, ...]
    phase0_rad: float = 0.0

    def __post_init__(self) -> None:
        t = np.asarray(self.times_s, float)
        s = np.asarray(self.speeds_rpm, float)
        if t.ndim != 1 or t.size < 1 or t.shape != s.shape or np.any(np.diff(t) <= 0):
            raise ValueError(f"SpeedProfile: times_s = {self.times_s} and speeds_rpm = "
                             f"{self.speeds_rpm} must be equal-length, times increasing")
        if not (np.all(np.isfinite(s)) and np.all(s >= 0)):
            raise ValueError(f"SpeedProfile.speeds_rpm = {self.speeds_rpm}: must be >= 0")
        object.__setattr__(self, "times_s", tuple(map(float, t)))
        object.__setattr__(self, "speeds_rpm", tuple(map(float, s)))

    @classmethod
    def constant(cls, speed_rpm: float, phase0_rad: float = 0.0) -> SpeedProfile:
        return cls((0.0,), (speed_rpm,), phase0_rad)

    @classmethod
    def ramp(cls, start_rpm: float, end_rpm: float, duration_s: float,
             phase0_rad: float = 0.0) -> SpeedProfile:
        check_positive("duration_s", duration_s)
        return cls((0.0, duration_s), (start_rpm, end_rpm), phase0_rad)

    @property
    def is_constant(self) -> bool:
        return len(set(self.speeds_rpm)) == 1

    def omega(self, t: np.ndarray) -> np.ndarray:
        """Spin speed (rad/s) at times ``t``."""
        return np.interp(t, self.times_s, self.speeds_rpm) * RPM

    def alpha(self, t: np.ndarray) -> np.ndarray:
        """Angular acceleration (rad/s²) at times ``t`` (piecewise constant)."""
        tb, sb = np.asarray(self.times_s), np.asarray(self.speeds_rpm) * RPM
        if tb.size == 1:
            return np.zeros_like(np.asarray(t, float))
        slope = np.diff(sb) / np.diff(tb)
        i = np.clip(np.searchsorted(tb, t, side="right") - 1, 0, slope.size - 1)
        inside = (t >= tb[0]) & (t < tb[-1])
        return np.where(inside, slope[i], 0.0)

    def angle(self, t: np.ndarray) -> np.ndarray:
        """Shaft angle (rad) at times ``t``: exact integral of the piecewise-linear speed."""
        t = np.asarray(t, float)
        tb, wb = np.asarray(self.times_s), np.asarray(self.speeds_rpm) * RPM
        cum = np.concatenate([[0.0], np.cumsum(0.5 * (wb[1:] + wb[:-1]) * np.diff(tb))])
        i = np.clip(np.searchsorted(tb, t, side="right") - 1, 0, tb.size - 1)
        dt = t - tb[i]
        w0 = wb[i]
        acc = np.where((i < tb.size - 1) & (t >= tb[0]), self.alpha(t), 0.0)
        before = t < tb[0]
        val = cum[i] + w0 * dt + 0.5 * acc * dt**2
        val = np.where(before, wb[0] * (t - tb[0]), val)
        return self.phase0_rad + val


@dataclass(frozen=True)
class IntegratorOptions:
    """``segment_s``: length over which the speed-dependent matrices are frozen (ramps);
    ``f_cut_hz``: modes kept in the Ritz basis (``None``: all DOFs, exact);
    ``oversample``: integrator steps per output sample."""

    segment_s: float = 0.005
    f_cut_hz: float | None = 20_000.0
    oversample: int = 1

    def __post_init__(self) -> None:
        check_positive("segment_s", self.segment_s)
        if self.f_cut_hz is not None:
            check_positive("f_cut_hz", self.f_cut_hz)
        check_int("oversample", self.oversample, minimum=1)


@dataclass(frozen=True)
class Simulation:
    """Displacements ``q`` (T, n_out) at the requested DOFs, sample times and shaft angle."""

    t_s: np.ndarray
    q: np.ndarray
    angle_rad: np.ndarray
    speed_rpm: np.ndarray


def unbalance_pattern(model: SpindleModel, n: int) -> np.ndarray:
    """Complex load pattern ``P`` (n,) with the unbalance force ``Re(P (φ'² − iφ'') e^{iφ})``."""
    P = np.zeros(n, dtype=complex)
    for node, U in zip(model.unbalance_nodes, model.unbalance, strict=True):
        P[4 * node] += U
        P[4 * node + 1] += -1j * U
    return P


def _phi12(lam_h: np.ndarray, nu_h: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``e^{λh} φ₁(x)`` and ``e^{λh} (φ₁ − φ₂)(x)`` with ``x = (ν − λ)h``, where
    ``φ₁(x) = (eˣ − 1)/x`` and ``φ₂(x) = (eˣ − 1 − x)/x²``: Taylor series near ``x = 0``, else
    ``(e^{νh} − e^{λh})/x`` and ``(x e^{νh} − e^{νh} + e^{λh})/x²`` (no overflow for stiff
    modes, ``Re λ ≪ 0``)."""
    x = nu_h - lam_h
    el, en = np.exp(lam_h), np.exp(nu_h)
    small = np.abs(x) < 1e-2
    xs = np.where(small, 1.0, x)
    p1 = np.where(small, el * (1 + x / 2 + x**2 / 6 + x**3 / 24 + x**4 / 120),
                  (en - el) / xs)
    p12 = np.where(small, el * (0.5 + x / 3 + x**2 / 8 + x**3 / 30 + x**4 / 144),
                   (xs * en - en + el) / xs**2)
    return p1, p12


def ritz_basis(model: SpindleModel, theta: np.ndarray | None, omega: float,
               loads: np.ndarray, f_cut_hz: float | None) -> np.ndarray:
    """Real basis ``Φ`` (n, r): undamped modes below ``f_cut_hz`` at speed ``omega`` plus the
    static shapes ``K⁻¹ loads`` (mass-orthonormalised); identity when ``f_cut_hz`` is None."""
    M, _, K = model.system_matrices(omega, theta)
    n = M.shape[0]
    if f_cut_hz is None:
        return np.eye(n)
    Ks = 0.5 * (K + K.T)
    try:
        w2, modes = sla.eigh(Ks, M, subset_by_value=(-np.inf, (2 * np.pi * f_cut_hz) ** 2))
        static = np.linalg.solve(Ks, np.column_stack([loads.real, loads.imag]))
    except np.linalg.LinAlgError as exc:
        raise ModelError("ritz_basis: singular mass or stiffness (massless DOFs?)") from exc
    Phi = np.column_stack([modes, static])
    # mass-orthonormalise and drop dependent vectors
    m_r = Phi.T @ M @ Phi
    lam, U = np.linalg.eigh(0.5 * (m_r + m_r.T))
    keep = lam > 1e-12 * lam.max()
    return Phi @ (U[:, keep] / np.sqrt(lam[keep]))


def _modal(model, theta, omega, Phi):
    """Eigenvalues, ``V`` and ``V⁻¹`` of the projected first-order system at speed ``omega``."""
    M, C, K = model.system_matrices(omega, theta)
    Mr, Cr, Kr = (Phi.T @ X @ Phi for X in (M, C, K))
    r = Mr.shape[0]
    try:
        Minv = np.linalg.inv(Mr)
    except np.linalg.LinAlgError as exc:
        raise ModelError("integrate: singular mass matrix (massless DOFs need a mass)") from exc
    A = np.block([[np.zeros((r, r)), np.eye(r)], [-Minv @ Kr, -Minv @ Cr]])
    lam, V = np.linalg.eig(A)
    try:
        W = np.linalg.inv(V)
    except np.linalg.LinAlgError as exc:
        raise ModelError(f"integrate: defective system at {omega / RPM:.6g} rpm") from exc
    if np.any(lam.real >= 0):
        raise ModelError(f"integrate: unstable or undamped mode at {omega / RPM:.6g} rpm "
                         f"(max Re λ = {lam.real.max():.3g})")
    Bin = np.vstack([np.zeros((r, r)), Minv]) @ Phi.T  # (2r, n): physical force -> state
    return lam, V, W @ Bin


def simulate(model: SpindleModel, profile: SpeedProfile, t_s: np.ndarray, out_dofs: np.ndarray,
             *, theta: np.ndarray | None = None, unbalance: bool = True,
             force_dofs: np.ndarray | None = None, force: np.ndarray | None = None,
             t0_s: float | None = None, options: IntegratorOptions = IntegratorOptions()
             ) -> Simulation:
    """Integrate from rest at ``t0_s`` (default ``t_s[0]``) and return ``q`` at ``t_s``.

    Parameters
    ----------
    model, profile : the rotor and its speed (constant or ramps).
    t_s : ndarray (T,)
        Uniformly spaced output times.
    out_dofs : ndarray of int
        DOF indices (of ``system_matrices``) to return.
    unbalance : bool
        Apply the model's rotating unbalance force.
    force_dofs, force : int array (k,), ndarray (T, k)
        A sampled external force (N) at ``force_dofs``, linear between output samples.
    t0_s : float
        Start from rest this early (≤ ``t_s[0]``); the interval before ``t_s[0]`` is stepped
        exactly in one jump when the speed is constant there.
    """
    t_s = np.asarray(t_s, float)
    dt = float(t_s[1] - t_s[0])
    if t_s.size < 2 or not np.allclose(np.diff(t_s), dt, rtol=1e-9, atol=0):
        raise ValueError("t_s must hold at least two uniformly spaced times")
    h = dt / options.oversample
    n = model.system_matrices(0.0, theta)[0].shape[0]
    P = unbalance_pattern(model, n) if unbalance else np.zeros(n, complex)
    loads = P[:, None]
    if force_dofs is not None:
        Fd = np.zeros((n, len(force_dofs)))
        Fd[np.asarray(force_dofs), np.arange(len(force_dofs))] = 1.0
        loads = np.column_stack([loads, Fd])
        force = np.asarray(force, float)
        if force.shape != (t_s.size, len(force_dofs)):
            raise ValueError(f"force has shape {force.shape}: must be ({t_s.size}, "
                             f"{len(force_dofs)})")
    t0 = t_s[0] if t0_s is None else float(t0_s)
    if t0 > t_s[0]:
        raise ValueError(f"t0_s = {t0} is after the first output time {t_s[0]}")
    omega_mean = float(np.mean(profile.omega(t_s)))
    Phi = ritz_basis(model, theta, omega_mean, loads, options.f_cut_hz)
    tf = np.arange(t_s.size * options.oversample) * h + t_s[0]   # fine grid
    segs = _segments(profile, t0, tf, options.segment_s)
    eta = None
    V_prev = None
    out = np.empty((tf.size, len(out_dofs)))
    fine_force = None if force is None else np.column_stack(
        [np.interp(tf, t_s, f) for f in force.T])
    for a, b in segs:
        w_mid = float(profile.omega(np.array([0.5 * (tf[max(a - 1, 0)] + tf[b - 1])]))[0])
        lam, V, Wb = _modal(model, theta, w_mid, Phi)
        if eta is None:  # from rest at t0, exactly to the first sample (constant speed there)
            eta = _advance(np.zeros(lam.size, complex), lam, Wb, P, profile, t0, tf[0])
            lo = 0
        else:            # carry the state across the change of modal basis
            eta = np.linalg.solve(V, V_prev @ eta)
            lo = a - 1
        grid = tf[lo:b]
        fseg = None if fine_force is None else fine_force[lo:b]
        Cv = Phi[np.asarray(out_dofs)] @ V[: Phi.shape[1]]
        y, eta = _run(eta, lam, Wb, P, profile, grid, fseg, force_dofs, Cv)
        out[a:b] = y[a - lo:]
        V_prev = V
    q = out[:: options.oversample]
    return Simulation(t_s, q, profile.angle(t_s), profile.omega(t_s) / RPM)


def _segments(profile: SpeedProfile, t0: float, tf: np.ndarray, seg: float
              ) -> list[tuple[int, int]]:
    """Index ranges ``[a, b)`` of the fine grid over which the matrices are frozen; one range
    when the speed is constant over ``[t0, tf[-1]]``. Raises if the speed is not constant
    between ``t0`` and the first sample (the start is jumped over in one exact step)."""
    w = profile.omega(np.array([t0, tf[0]]))
    if w[0] != w[1] or any(t0 < t < tf[0] for t in profile.times_s):
        raise ValueError(f"t0_s = {t0}: the speed must be constant between t0_s and the "
                         f"first output time {tf[0]}")
    tb = profile.times_s
    if profile.is_constant or t0 >= tb[-1] or tf[-1] <= tb[0]:
        return [(0, tf.size)]
    n = max(1, int(round(seg / (tf[1] - tf[0]))))
    idx = list(range(0, tf.size, n)) + [tf.size]
    return [(a, b) for a, b in zip(idx[:-1], idx[1:], strict=True)]


def _envelope(profile: SpeedProfile, t: np.ndarray) -> np.ndarray:
    """``φ'² − iφ''`` at ``t``."""
    return profile.omega(t) ** 2 - 1j * profile.alpha(t)


def _advance(eta, lam, Wb, P, profile, ta, tb):
    """Exact jump over a constant-speed interval ``[ta, tb]`` (unbalance only)."""
    w = float(profile.omega(np.array([ta]))[0])
    hh = tb - ta
    ph = float(profile.angle(np.array([ta]))[0])
    bP = Wb @ P
    bPc = Wb @ P.conj()
    c = w**2 * np.exp(1j * ph)
    acc = np.zeros_like(eta)
    for nu, coef in ((1j * w, 0.5 * c * bP), (-1j * w, 0.5 * np.conj(c) * bPc)):
        p1, _ = _phi12(lam * hh, nu * hh)
        acc += hh * p1 * coef
    return np.exp(lam * hh) * eta + acc


def _run(eta0, lam, Wb, P, profile, grid, fseg, force_dofs, Cv, chunk=4096):
    """Outputs ``Re(Cv η)`` at every time of ``grid`` (constant matrices) and the final modal
    state; worked in chunks of ``chunk`` steps so memory stays bounded.

    The unbalance input over a step is ``e^{iφ_k} e^{iΩ_s τ} g(τ)`` with ``Ω_s`` the segment's
    mid speed and ``g`` (the envelope ``φ'² − iφ''`` times the residual phase) linear over the
    step: exact at constant speed, ``O(h²)`` in the envelope's curvature on a ramp."""
    T = grid.size
    out = np.empty((T, Cv.shape[0]))
    out[0] = (Cv @ eta0).real
    if T == 1:
        return out, eta0
    h = float(grid[1] - grid[0])
    a = np.exp(lam * h)
    ws = float(profile.omega(np.array([0.5 * (grid[0] + grid[-1])]))[0])
    coef = []
    if np.any(P != 0):
        for sgn, b in ((1.0, Wb @ P), (-1.0, Wb @ P.conj())):
            p1, p12 = _phi12(lam * h, np.full_like(lam, sgn * 1j * ws * h))
            coef.append((sgn, 0.5 * h * p1 * b, 0.5 * h * p12 * b))
    if fseg is not None:
        p1, p12 = _phi12(lam * h, np.zeros_like(lam))
        bF = Wb[:, np.asarray(force_dofs)]                   # (2r, k)
    eta = eta0
    for c0 in range(0, T - 1, chunk):
        c1 = min(c0 + chunk, T - 1)
        if not coef and (fseg is None or not np.any(fseg[c0:c1 + 1])):
            # free response: η_k = e^{λ h k} η_0 in closed form (no loop)
            etas = eta[None, :] * np.exp(np.outer(np.arange(1, c1 - c0 + 1) * h, lam))
            out[c0 + 1:c1 + 1] = (etas @ Cv.T).real
            eta = etas[-1]
            continue
        t = grid[c0:c1 + 1]
        ph = profile.angle(t)
        env = _envelope(profile, t)
        g0 = env[:-1] * np.exp(1j * ph[:-1])
        g1 = env[1:] * np.exp(1j * (ph[1:] - ws * h))
        r = np.zeros((c1 - c0, lam.size), complex)
        for sgn, B0, B1 in coef:
            G0, G1 = (g0, g1) if sgn > 0 else (g0.conj(), g1.conj())
            r += G0[:, None] * B0 + (G1 - G0)[:, None] * B1
        if fseg is not None:
            F0, F1 = fseg[c0:c1] @ bF.T, fseg[c0 + 1:c1 + 1] @ bF.T     # (n, 2r)
            r += h * (p1 * F0 + p12 * (F1 - F0))
        etas = np.empty((c1 - c0, lam.size), complex)
        for k in range(c1 - c0):  # the diagonal recurrence: a loop over steps, vector over modes
            eta = a * eta + r[k]
            etas[k] = eta
        out[c0 + 1:c1 + 1] = (etas @ Cv.T).real
    return out, eta
