"""Time integration of the spindle model: exact at constant speed, error-controlled on ramps.

The model ``M q'' + (C(Ω) + Ω G) q' + K(Ω) q = f(t)`` (bearings, gyroscopics, housing stages —
massless ones too — as :meth:`SpindleModel.system_matrices` gives them) is put in first-order
form (:mod:`~.statespace`) and stepped exactly per mode (:mod:`~.stepping`).

* **Constant speed**: one segment, every DOF kept (whatever ``f_cut_hz``): exact for the linear
  model; the response from rest converges to the FE harmonic solution (``spindle.harmonic``)
  to round-off (tested ≤ 1e-6, measured ≤ 2e-10).
* **Speed ramps**: segments with the matrices of the segment's middle, plus the correction
  ``W δA(τ) V η`` for their variation inside the segment (quadratic in time); the state is
  carried across segments in physical coordinates. Segment lengths come from an **error
  estimate**: the part of ``A(t)`` the quadratic misses, measured a quarter into the segment
  (``e = H ‖W (A(t_q) − Q(t_q)) V‖_F``, ∝ H⁴), is kept below ``tol``; breakpoints of the speed
  profile are segment ends. The rotor is projected on a Ritz basis (modes below ``f_cut_hz``
  plus the static shapes of the loads; ``None``: all DOFs). Checked against an independent
  solution with time-varying matrices (``solve_ivp``) in ``tests/rig/test_integrate.py``.

>>> import numpy as np
>>> from surrogate_rbrdo.spindle import reference_spindle, unbalance_response
>>> m = reference_spindle().model(reference_spindle().baseline)
>>> t = 5.0 + np.arange(50) / 10_000.0        # 5 s after rest: the transient is gone
>>> s = simulate(m, SpeedProfile.constant(12000.0), t, np.array([4 * m.tool_node]), t0_s=0.0)
>>> X = unbalance_response(m, np.array([12000.0]))[0, 0, m.tool_node, 0]
>>> bool(np.max(np.abs(s.q[:, 0] - (X * np.exp(1j * s.angle_rad)).real)) < 1e-9 * abs(X))
True
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from surrogate_rbrdo.core.errors import ModelError
from surrogate_rbrdo.core.validate import check_int, check_positive
from surrogate_rbrdo.rig.profile import SpeedProfile
from surrogate_rbrdo.rig.statespace import Modes, decompose, first_order, reduction
from surrogate_rbrdo.rig.stepping import Segment, advance_constant, run_segment
from surrogate_rbrdo.spindle.assembly import RPM, SpindleModel

__all__ = ["IntegratorOptions", "Simulation", "SpeedProfile", "simulate", "unbalance_pattern"]


@dataclass(frozen=True)
class IntegratorOptions:
    """Options of :func:`simulate` on ramps (constant speed is always exact).

    ``segment_s``: a fixed segment length; ``None`` (default) chooses each segment by the error
    estimate, up to ``max_segment_s``, keeping it below ``tol``; ``f_cut_hz``: modes kept in
    the Ritz basis (``None``: all DOFs); ``oversample``: integrator steps per output sample;
    ``closed_form``: stretches without input at constant speed in closed form
    (:func:`~.stepping.free_outputs`; False: stepped by the recurrence — the same values to
    round-off, the reference the closed form is tested and benchmarked against).
    """

    segment_s: float | None = None
    f_cut_hz: float | None = 10_000.0
    oversample: int = 1
    tol: float = 1e-5
    max_segment_s: float = 0.1
    basis_speeds: int = 3
    correct_below_hz: float | None = None
    closed_form: bool = True

    def __post_init__(self) -> None:
        if not isinstance(self.closed_form, bool):
            raise ValueError(f"closed_form = {self.closed_form!r} is not allowed: true or false")
        if self.segment_s is not None:
            check_positive("segment_s", self.segment_s)
        if self.f_cut_hz is not None:
            check_positive("f_cut_hz", self.f_cut_hz)
        check_int("oversample", self.oversample, minimum=1)
        check_positive("tol", self.tol)
        check_positive("max_segment_s", self.max_segment_s)
        check_int("basis_speeds", self.basis_speeds, minimum=1)
        if self.correct_below_hz is not None:
            check_positive("correct_below_hz", self.correct_below_hz)


@dataclass(frozen=True)
class Simulation:
    """Displacements ``q`` (T, n_out) at the requested DOFs, sample times and shaft angle;
    ``segments``: how many frozen-matrix segments the ramp took; ``acc`` (T, n_acc): the
    accelerations at ``acc_dofs`` if asked for."""

    t_s: np.ndarray
    q: np.ndarray
    angle_rad: np.ndarray
    speed_rpm: np.ndarray
    segments: int = 1
    acc: np.ndarray | None = None


def unbalance_pattern(model: SpindleModel, n: int) -> np.ndarray:
    """Complex load pattern ``P`` (n,) with the unbalance force ``Re(P (φ'² − iφ'') e^{iφ})``."""
    P = np.zeros(n, dtype=complex)
    for node, U in zip(model.unbalance_nodes, model.unbalance, strict=True):
        P[4 * node] += U
        P[4 * node + 1] += -1j * U
    return P


class _System:
    """First-order forms and modes of one model on one reduction basis, cached by speed."""

    def __init__(self, model, theta, profile, red, out_dofs, acc_dofs, P, correct_below_hz):
        self.model, self.theta, self.profile, self.red = model, theta, profile, red
        self.out, self.acc, self.P = np.asarray(out_dofs), np.asarray(acc_dofs, int), P
        self.w_corr = 2 * np.pi * correct_below_hz
        self._fo: dict[float, object] = {}
        self._modes: tuple[float, Modes] | None = None

    def form(self, t: float):
        w = float(self.profile.omega(np.array([t]))[0])
        if w not in self._fo:
            if len(self._fo) > 64:
                self._fo.clear()
            self._fo[w] = first_order(self.model, self.theta, w, self.red)
        return self._fo[w]

    def segment(self, t_mid: float, modes: Modes, correction=None) -> Segment:
        fo = self.form(t_mid)
        D = None
        if correction is not None:
            A1, A2 = correction
            D = np.vstack([modes.W @ A1 @ modes.V, modes.W @ A2 @ modes.V])
        C = np.vstack([fo.Cq[self.out], fo.Ca[self.acc]])
        return Segment(modes.lam, modes.W @ fo.B, C @ modes.V, self.P, D, self.w_corr, t_mid)

    def modes(self, t: float) -> Modes:
        """The modes at ``t``'s speed; the last speed's are kept (at constant speed the start
        and the one segment share them: one eigen-decomposition instead of two)."""
        w = float(self.profile.omega(np.array([t]))[0])
        if self._modes is None or self._modes[0] != w:
            self._modes = (w, decompose(self.form(t).A, w))
        return self._modes[1]


def simulate(model: SpindleModel, profile: SpeedProfile, t_s: np.ndarray, out_dofs: np.ndarray,
             *, theta: np.ndarray | None = None, unbalance: bool = True,
             force_dofs: np.ndarray | None = None, force: np.ndarray | None = None,
             t0_s: float | None = None, options: IntegratorOptions = IntegratorOptions(),
             acc_dofs: np.ndarray | None = None) -> Simulation:
    """Integrate from rest at ``t0_s`` (default ``t_s[0]``) and return ``q`` at ``t_s``.

    Parameters
    ----------
    model, profile : the rotor and its speed (constant or ramps).
    t_s : ndarray (T,)
        Uniformly spaced output times (at least two).
    out_dofs : ndarray of int
        DOF indices (of ``system_matrices``) to return.
    unbalance : bool
        Apply the model's rotating unbalance force.
    force_dofs, force : int array (k,), ndarray (T, k)
        A sampled external force (N) at ``force_dofs``, linear between output samples.
    t0_s : float
        Start from rest this early (≤ ``t_s[0]``, constant speed until ``t_s[0]``); that
        interval is one exact jump.
    acc_dofs : ndarray of int, optional
        DOFs whose acceleration to return too (``Simulation.acc``), e.g. for accelerometers.
    """
    acc_dofs = np.zeros(0, int) if acc_dofs is None else np.asarray(acc_dofs, int)
    t_s = np.asarray(t_s, float)
    if t_s.ndim != 1 or t_s.size < 2:
        raise ValueError(f"t_s has shape {t_s.shape}: must hold at least two times")
    dt = float(t_s[1] - t_s[0])
    if not (dt > 0 and np.allclose(np.diff(t_s), dt, rtol=1e-9, atol=0)):
        raise ValueError("t_s must be uniformly spaced and increasing")
    h = dt / options.oversample
    P, loads, force = _loads(model, theta, t_s.size, unbalance, force_dofs, force)
    fine_force = None
    t0 = t_s[0] if t0_s is None else float(t0_s)
    if t0 > t_s[0]:
        raise ValueError(f"t0_s = {t0} is after the first output time {t_s[0]}")
    if not profile.constant_between(t0, t_s[0]):
        raise ValueError(f"t0_s = {t0}: the speed must be constant between t0_s and the "
                         f"first output time {t_s[0]}")
    tf = np.arange(t_s.size * options.oversample) * h + t_s[0]          # fine grid
    if force is not None:
        fine_force = np.column_stack([np.interp(tf, t_s, f) for f in force.T])
    constant = profile.constant_between(t0, tf[-1])
    red = reduction(model, theta, _basis_speeds(profile, tf, options.basis_speeds), loads,
                    None if constant else options.f_cut_hz)
    sys = _System(model, theta, profile, red, out_dofs, acc_dofs, P,
                  options.correct_below_hz or 0.25 / h)
    modes = sys.modes(tf[0])
    eta = advance_constant(np.zeros(modes.lam.size, complex), sys.segment(tf[0], modes),
                           profile, t0, tf[0])
    z = modes.V @ eta
    out = np.empty((tf.size, len(out_dofs) + acc_dofs.size))
    ctl = _Segmenter(sys, tf, options, constant)
    a = n_seg = 0
    while a < tf.size - 1:
        b = ctl.propose(a, modes)
        grid = tf[a:b + 1]
        t_mid = 0.5 * (grid[0] + grid[-1])
        modes = sys.modes(t_mid)
        corr = None if profile.constant_between(grid[0], grid[-1]) else _quadratic(
            sys, grid[0], t_mid, grid[-1])
        y, eta, sweeps = run_segment(modes.W @ z, sys.segment(t_mid, modes, corr), profile,
                                     grid, None if fine_force is None else fine_force[a:b + 1],
                                     force_dofs, tol=options.tol,
                                     closed_form=options.closed_form)
        if sweeps < 0:
            ctl.reject(a, b, grid)
            continue
        ctl.accept(a, b, sweeps)
        out[a:b + 1] = y
        z = modes.V @ eta
        a, n_seg = b, n_seg + 1
    q = out[:: options.oversample]
    acc = None
    if acc_dofs.size:                       # feedthrough of the force and the unbalance
        acc = q[:, len(out_dofs):] + _acc_feedthrough(sys, profile, t_s, force_dofs, force)
        q = q[:, :len(out_dofs)]
    return Simulation(t_s, q, profile.angle(t_s), profile.omega(t_s) / RPM, n_seg, acc)


def _loads(model, theta, n_t: int, unbalance: bool, force_dofs, force):
    """The unbalance pattern, the load vectors the Ritz basis must span, the checked force."""
    n = model.system_matrices(0.0, theta)[0].shape[0]
    P = unbalance_pattern(model, n) if unbalance else np.zeros(n, complex)
    loads = P[:, None]
    if force_dofs is not None:
        force = np.asarray(force, float)
        if force.shape != (n_t, len(force_dofs)):
            raise ValueError(f"force has shape {force.shape}: must be ({n_t}, "
                             f"{len(force_dofs)})")
        Fd = np.zeros((n, len(force_dofs)))
        Fd[np.asarray(force_dofs), np.arange(len(force_dofs))] = 1.0
        loads = np.column_stack([loads, Fd])
    return P, loads, force


def _acc_feedthrough(sys: _System, profile: SpeedProfile, t: np.ndarray, force_dofs,
                     force) -> np.ndarray:
    """``Da f(t)`` at the acceleration outputs (matrices of the first sample's speed: the
    feedthrough is the mass matrix's, speed-independent without massless DOFs)."""
    Da = sys.form(t[0]).Da[sys.acc]
    f = np.zeros((t.size, Da.shape[1]))
    if force_dofs is not None:
        f[:, np.asarray(force_dofs)] += force
    if np.any(sys.P != 0):
        env = profile.omega(t) ** 2 - 1j * profile.alpha(t)
        f += (sys.P[None, :] * (env * np.exp(1j * profile.angle(t)))[:, None]).real
    return f @ Da.T


def _basis_speeds(profile: SpeedProfile, tf: np.ndarray, k: int) -> np.ndarray:
    """``k`` speeds (rad/s) spread over the range the grid passes through."""
    w = profile.omega(np.concatenate([tf[[0, -1]], profile.breakpoints_between(tf[0], tf[-1])]))
    return np.linspace(w.min(), w.max(), k) if k > 1 else np.array([w.mean()])


def _quadratic(sys: _System, ta: float, tm: float, tb: float
               ) -> tuple[np.ndarray, np.ndarray]:
    """``A₁, A₂`` of ``A(t) ≈ A(t_m) + τ A₁ + τ² A₂`` through the segment's ends and middle."""
    Aa, Am, Ab = (sys.form(t).A for t in (ta, tm, tb))
    H = tb - ta
    return (Ab - Aa) / H, 2.0 * (Aa + Ab - 2.0 * Am) / H**2


class _Segmenter:
    """Segment lengths on the fine grid: one segment at constant speed; a fixed ``segment_s``;
    or (default) the longest segment, up to ``max_segment_s``, whose error estimates are below
    ``tol``: the cubic remainder of ``A(t)`` a quarter into the segment (the quadratic model's
    error, ``H ‖W ΔA V‖_F``, ∝ H⁴) before stepping, and the Picard iteration settling the
    outputs to ``tol`` while stepping (else the segment is halved and stepped again)."""

    def __init__(self, sys: _System, tf: np.ndarray, o: IntegratorOptions, constant: bool):
        self.sys, self.tf, self.o, self.constant = sys, tf, o, constant
        self.h = float(tf[1] - tf[0])
        bp = sys.profile.breakpoints_between(tf[0], tf[-1])
        self.stops = sorted({int(round((t - tf[0]) / self.h)) for t in bp} - {0}
                            | {tf.size - 1})
        self.n_max = max(1, int(round((o.segment_s or o.max_segment_s) / self.h)))
        self.n = self.n_max if o.segment_s is not None else max(1, self.n_max // 8)

    def propose(self, a: int, modes: Modes) -> int:
        stop = next(s for s in self.stops if s > a)
        if self.constant:
            return self.tf.size - 1
        self.n = min(self.n, stop - a)
        if self.o.segment_s is None:
            while self.n > 1:
                e = self._estimate(a, self.n, modes)
                if e <= self.o.tol:
                    break
                self.n = max(1, int(self.n * max(0.2, 0.9 * (self.o.tol / e) ** 0.25)))
        return a + self.n

    def _estimate(self, a: int, n: int, modes: Modes) -> float:
        ta, tb = self.tf[a], self.tf[a + n]
        H, tm = tb - ta, 0.5 * (ta + tb)
        A1, A2 = _quadratic(self.sys, ta, tm, tb)
        Aq = self.sys.form(tm).A - H / 4 * A1 + H**2 / 16 * A2
        return float(H * np.linalg.norm(modes.W @ (self.sys.form(ta + H / 4).A - Aq)
                                        @ modes.V))

    def reject(self, a: int, b: int, grid: np.ndarray) -> None:
        if b - a == 1:
            raise ModelError(f"integrate: the ramp correction does not converge at t = "
                             f"{grid[0]:.6g} s even over one step")
        self.n = (b - a) // 2

    def accept(self, a: int, b: int, sweeps: int) -> None:
        if self.o.segment_s is None:
            grow = 1.5 if sweeps <= 4 else 1.0 if sweeps <= 7 else 0.7
            self.n = int(min(self.n_max, max(1, (b - a) * grow)))
        else:
            self.n = self.n_max
