"""The paper's synthetic identification setting (Sect. 3.1), reproduced and made richer.

A rigid rotor on two bearings (front, rear), 4 DOF ``q = [y, z, ψ_y, ψ_z]`` (centre-of-mass
translations and slopes), integrated by classical RK4 at ``Δt = 0.1 ms`` (10 kHz, the paper's
sampling), with diagonal bearings ``k``, ``c = η k`` (paper: ``k0 = 2.5e8 N/m``, η = 4e-6 s):

    M q̈ + (C + Ω G) q̇ + K q = Lᵀ f(t),   K = Tᵀ K_b T,   C = Tᵀ C_b T,

``T`` maps ``q`` to the bearing displacements ``[front_y, front_z, rear_y, rear_z]`` and ``L``
to the displacements at the excitation plane. Excitations (``excitation=``):

* ``"unbalance"``: the paper's pure 1× unbalance at constant speed (10 000 rpm);
* ``"run_up"``: the unbalance during a linear run-up from ``run_up_from_rpm`` to the speed;
* ``"random"``: the unbalance plus a known random force (white, zero-order hold, e.g. a shaker
  with a force cell) at the excitation plane, RMS ``random_force_rel`` × the unbalance force.

Measured channels: displacement, velocity and acceleration of each bearing journal, each with
independent Gaussian white noise of standard deviation ``noise_rel`` × the channel's RMS (the
paper adds white noise to the displacements; a noise level relative to the signal keeps the
benchmark meaningful at 22 nm amplitudes, where an absolute probe floor would swamp it).

Bearing reactions from the rotor's equations of motion (rigid-body balance, known mass
properties and known excitation): ``r = T⁻ᵀ (Lᵀ f − M q̈ − Ω G q̇)`` with ``q = T⁻¹ x_b``; per
bearing and direction ``r = k x + c ẋ`` — the regression ``y = φᵀθ``, ``φ = [x, ẋ]``. Noise in
``x, ẋ`` makes it an errors-in-variables problem: least squares is biased by ``≈ −noise_rel²``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from surrogate_rbrdo.core.rng import require_rng
from surrogate_rbrdo.core.validate import check_choice, check_int, check_positive
from surrogate_rbrdo.identification.regression import Regression
from surrogate_rbrdo.spindle.assembly import RPM

EXCITATIONS = ("unbalance", "run_up", "random")
#: (bearing, direction) of each regression, in channel order
CHANNELS = (("front", "y"), ("front", "z"), ("rear", "y"), ("rear", "z"))


@dataclass(frozen=True)
class RigidRotor:
    """A rigid rotor on two diagonal bearings (SI; axial positions from the centre of mass).

    Defaults: the paper's 4.25 kg rotor (Table 1), a Ø50 × 300 mm cylinder's inertias,
    ``k0 = 2.5e8 N/m`` (Sect. 3.1) at both bearings in both directions, ``c = η k0`` with
    η = 4e-6 s, and an ISO 21940 G2.5 unbalance at 10 000 rpm on the nose plane.
    """

    mass_kg: float = 4.25
    diametral_inertia_kgm2: float = 0.0325
    polar_inertia_kgm2: float = 0.0013
    front_m: float = -0.12
    rear_m: float = 0.10
    excitation_m: float = -0.15
    k_N_per_m: tuple[float, float, float, float] = (2.5e8, 2.5e8, 2.5e8, 2.5e8)
    c_Ns_per_m: tuple[float, float, float, float] = (1000.0, 1000.0, 1000.0, 1000.0)
    unbalance_kgm: float = 4.25 * 2.5e-3 / (10000 * np.pi / 30)

    def __post_init__(self) -> None:
        for f in ("mass_kg", "diametral_inertia_kgm2", "unbalance_kgm"):
            check_positive(f, getattr(self, f))
        check_positive("polar_inertia_kgm2", self.polar_inertia_kgm2, allow_zero=True)
        if not self.front_m < self.rear_m:
            raise ValueError(f"front_m = {self.front_m} is not allowed: must be < rear_m = "
                             f"{self.rear_m}")
        for f in ("k_N_per_m", "c_Ns_per_m"):
            v = np.asarray(getattr(self, f), dtype=float)
            if v.shape != (4,) or np.any(~np.isfinite(v) | (v <= 0)):
                raise ValueError(f"{f} = {getattr(self, f)!r} is not allowed: need 4 finite "
                                 "values > 0 (front_y, front_z, rear_y, rear_z)")

    @property
    def truth(self) -> np.ndarray:
        """``[k, c]`` per channel, ``(4, 2)``."""
        return np.column_stack([self.k_N_per_m, self.c_Ns_per_m]).astype(float)

    def transforms(self) -> tuple[np.ndarray, np.ndarray]:
        """``T`` (bearing displacements from ``q``) and ``L`` (excitation plane), 4x4 and 2x4."""
        a, b, s = self.front_m, self.rear_m, self.excitation_m
        T = np.array([[1, 0, a, 0], [0, 1, 0, a], [1, 0, b, 0], [0, 1, 0, b]], dtype=float)
        L = np.array([[1, 0, s, 0], [0, 1, 0, s]], dtype=float)
        return T, L

    def matrices(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``M``, ``K``, ``C`` and the gyroscopic ``G`` (per unit spin) in ``q``."""
        T, _ = self.transforms()
        M = np.diag([self.mass_kg, self.mass_kg, self.diametral_inertia_kgm2,
                     self.diametral_inertia_kgm2])
        K = T.T @ np.diag(self.k_N_per_m) @ T
        C = T.T @ np.diag(self.c_Ns_per_m) @ T
        G = np.zeros((4, 4))
        G[2, 3], G[3, 2] = self.polar_inertia_kgm2, -self.polar_inertia_kgm2
        return M, K, C, G


@dataclass(frozen=True)
class SyntheticSetting:
    """Record settings: speed, sampling, length, excitation and noise (module docstring)."""

    speed_rpm: float = 10000.0
    dt_s: float = 1e-4
    n_samples: int = 3000
    warmup_s: float = 0.05
    excitation: str = "unbalance"
    noise_rel: float = 0.01
    run_up_from_rpm: float = 5000.0
    random_force_rel: float = 1.0

    def __post_init__(self) -> None:
        check_positive("speed_rpm", self.speed_rpm)
        check_positive("dt_s", self.dt_s)
        check_int("n_samples", self.n_samples, minimum=2)
        check_positive("warmup_s", self.warmup_s, allow_zero=True)
        check_choice("excitation", self.excitation, EXCITATIONS)
        check_positive("noise_rel", self.noise_rel, allow_zero=True)
        check_positive("run_up_from_rpm", self.run_up_from_rpm)
        check_positive("random_force_rel", self.random_force_rel, allow_zero=True)


@dataclass(frozen=True, eq=False)
class SyntheticRecords:
    """Noise-free journal signals of ``B`` runs: ``x, v, a`` of shape ``(B, T, 4)`` (channels
    ``CHANNELS``), the spin speed ``(T,)`` (rad/s) and the known force ``(B, T, 2)`` (N)."""

    rotor: RigidRotor
    setting: SyntheticSetting
    x: np.ndarray
    v: np.ndarray
    a: np.ndarray
    omega: np.ndarray
    force: np.ndarray


def _speed_and_phase(st: SyntheticSetting, n_total: int, n_warm: int):
    t = np.arange(n_total + 1) * st.dt_s * 0.5                     # half-step grid
    w_end = st.speed_rpm * RPM
    if st.excitation == "run_up":
        w0 = st.run_up_from_rpm * RPM
        ramp = np.clip((t - n_warm * st.dt_s) / (st.n_samples * st.dt_s), 0.0, 1.0)
        w = w0 + (w_end - w0) * ramp
        wdot = np.where((ramp > 0) & (ramp < 1), (w_end - w0) / (st.n_samples * st.dt_s), 0.0)
    else:
        w, wdot = np.full_like(t, w_end), np.zeros_like(t)
    phase = np.concatenate([[0.0], np.cumsum(0.5 * (w[1:] + w[:-1]) * np.diff(t))])
    return w, wdot, phase


def simulate(rotor: RigidRotor, setting: SyntheticSetting, n_runs: int = 1, *,
             rng: np.random.Generator) -> SyntheticRecords:
    """Integrate the rotor by RK4 and return the noise-free journal signals of ``n_runs`` runs.

    Runs differ only by the random force (``excitation="random"``); the other excitations are
    deterministic, so one run serves any number of noise trials (:func:`measure`).

    >>> rec = simulate(RigidRotor(), SyntheticSetting(n_samples=200), rng=np.random.default_rng(0))
    >>> rec.x.shape, bool(abs(rec.x).max() < 1e-6)
    ((1, 200, 4), True)
    """
    require_rng(rng)
    n_runs = check_int("n_runs", n_runs, minimum=1)
    st = setting
    M, K, C, G = rotor.matrices()
    T, L = rotor.transforms()
    Minv = np.linalg.inv(M)
    n_warm = int(round(st.warmup_s / st.dt_s))
    n_total = n_warm + st.n_samples
    w, wdot, ph = _speed_and_phase(st, 2 * n_total, n_warm)        # index 2k: t_k
    U = rotor.unbalance_kgm
    fu = U * (w[:, None] ** 2 * np.column_stack([np.cos(ph), np.sin(ph)])
              - wdot[:, None] * np.column_stack([-np.sin(ph), np.cos(ph)]))   # (2N+1, 2)
    fr = np.zeros((n_runs, n_total, 2))
    if st.excitation == "random" and st.random_force_rel > 0:
        fr = rng.standard_normal((n_runs, n_total, 2)) * (
            st.random_force_rel * U * (st.speed_rpm * RPM) ** 2)

    def accel(q, qd, i2, k):
        f = fu[i2][None] + fr[:, min(k, n_total - 1)]
        return (f @ L - qd @ (C + w[i2] * G).T - q @ K.T) @ Minv.T

    q = np.zeros((n_runs, 4))
    qd = np.zeros((n_runs, 4))
    X = np.empty((n_runs, st.n_samples, 4))
    V, A = np.empty_like(X), np.empty_like(X)
    F = np.empty((n_runs, st.n_samples, 2))
    h = st.dt_s
    for k in range(n_total):
        if k >= n_warm:
            j = k - n_warm
            X[:, j], V[:, j] = q @ T.T, qd @ T.T
            A[:, j] = accel(q, qd, 2 * k, k) @ T.T
            F[:, j] = fu[2 * k][None] + fr[:, k]
        k1v, k1a = qd, accel(q, qd, 2 * k, k)
        k2v, k2a = qd + 0.5 * h * k1a, accel(q + 0.5 * h * k1v, qd + 0.5 * h * k1a, 2 * k + 1, k)
        k3v, k3a = qd + 0.5 * h * k2a, accel(q + 0.5 * h * k2v, qd + 0.5 * h * k2a, 2 * k + 1, k)
        k4v, k4a = qd + h * k3a, accel(q + h * k3v, qd + h * k3a, 2 * k + 2, k)
        q = q + h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v)
        qd = qd + h / 6 * (k1a + 2 * k2a + 2 * k3a + k4a)
    omega = w[2 * n_warm:2 * n_total:2]
    return SyntheticRecords(rotor, st, X, V, A, omega, F)


def measure(records: SyntheticRecords, n_trials: int, *, rng: np.random.Generator,
            noise_rel: float | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Noisy ``x, v, a`` of ``n_trials`` trials, ``(n_trials, T, 4)`` each.

    Trial ``i`` uses run ``i mod B``. Noise: independent Gaussian, standard deviation
    ``noise_rel`` (default the setting's) × each channel's RMS over the record.
    """
    require_rng(rng)
    n_trials = check_int("n_trials", n_trials, minimum=1)
    rel = records.setting.noise_rel if noise_rel is None else check_positive(
        "noise_rel", noise_rel, allow_zero=True)
    idx = np.arange(n_trials) % records.x.shape[0]
    out = []
    for sig in (records.x, records.v, records.a):
        s = sig[idx]
        rms = np.sqrt(np.mean(sig**2, axis=1))[idx]                  # (n, 4)
        out.append(s + rel * rms[:, None, :] * rng.standard_normal(s.shape))
    return out[0], out[1], out[2]


def bearing_regression(records: SyntheticRecords, x: np.ndarray, v: np.ndarray,
                       a: np.ndarray) -> Regression:
    """Per trial and channel, ``y = r`` (reaction from the equations of motion) and
    ``φ = [x, ẋ]``: a batch of ``4 n_trials`` regressions (trial-major, channels ``CHANNELS``).

    >>> rec = simulate(RigidRotor(), SyntheticSetting(n_samples=100), rng=np.random.default_rng(0))
    >>> reg = bearing_regression(rec, rec.x, rec.v, rec.a)
    >>> k, c = reg.least_squares()[0]
    >>> print(f"{k / 2.5e8:.9f} {c / 1000.0:.6f}")
    1.000000000 1.000000
    """
    M, _, _, G = records.rotor.matrices()
    T, L = records.rotor.transforms()
    Tinv = np.linalg.inv(T)
    n = x.shape[0]
    idx = np.arange(n) % records.force.shape[0]
    qdd = a @ Tinv.T
    qd = v @ Tinv.T
    gyro = records.omega[None, :, None] * (qd @ G.T)
    gen = records.force[idx] @ L - qdd @ M.T - gyro                 # generalised reaction
    r = gen @ Tinv                                                   # T^-T gen, (n, T, 4)
    phi = np.stack([x, v], axis=-1)                                   # (n, T, 4, 2)
    phi = np.moveaxis(phi, 2, 1).reshape(n * 4, x.shape[1], 2)
    y = np.moveaxis(r, 2, 1).reshape(n * 4, x.shape[1])
    return Regression(phi, y, ("k", "c"))


__all__ = ["CHANNELS", "EXCITATIONS", "RigidRotor", "SyntheticRecords", "SyntheticSetting",
           "bearing_regression", "measure", "simulate"]
