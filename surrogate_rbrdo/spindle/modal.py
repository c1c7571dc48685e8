"""Damped modal analysis, Campbell diagram, critical speeds and the first natural frequency.

Modes come from the state-space form of ``M q'' + (C + Ω G) q' + K q = 0``. An eigenvalue
``λ = −ζ ω_n + i ω_d`` with ``ω_d > 0`` is kept; its whirl is *forward* when the orbit of the
mode shape turns with the spin: ``Σ |X + iY|² > Σ |X − iY|²`` over the rotor nodes.
Roots whose mode shape is over-damped without gyroscopics (modal ζ ≥ 1, the FE mesh's high modes
under Rayleigh damping) are no vibration modes and are left out at every speed.
Critical speeds are the 1x crossings ``ω_d(Ω) = Ω`` of forward modes, located on the Campbell
grid and refined by Brent's method.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
from scipy.optimize import brentq

from surrogate_rbrdo.core.errors import ModelError, SingularSystemError
from surrogate_rbrdo.core.validate import check_int
from surrogate_rbrdo.spindle.assembly import RPM, SpindleModel


@dataclass(frozen=True)
class ModalResult:
    """Modes at one speed, sorted by damped natural frequency."""

    speed_rpm: float
    frequency_hz: np.ndarray  # damped natural frequency ω_d / 2π
    damping_ratio: np.ndarray
    whirl: np.ndarray  # "forward" / "backward"
    eigenvalues: np.ndarray

    def forward(self) -> np.ndarray:
        """Damped frequencies (Hz) of the forward-whirl modes."""
        return self.frequency_hz[self.whirl == "forward"]


def modal_analysis(
    model: SpindleModel, speed_rpm: float, theta: np.ndarray | None = None,
    *, n_modes: int | None = None,
) -> ModalResult:
    """Damped complex modes at one spin speed.

    Parameters
    ----------
    model : SpindleModel
    speed_rpm : float
        Spin speed (rpm), >= 0.
    theta : array (m,), optional
        Bearing stiffness factors.
    n_modes : int, optional
        Keep only the lowest ``n_modes`` (by damped frequency).
    """
    if not (np.isfinite(speed_rpm) and speed_rpm >= 0):
        raise ValueError(f"speed_rpm = {speed_rpm} is not allowed: must be finite and >= 0")
    omega = speed_rpm * RPM
    M, C, K = model.system_matrices(omega, theta)
    n = M.shape[0]
    massless = ~np.any(M != 0, axis=1)
    if massless.any():
        # massless DOFs (e.g. a housing stage without mass): the pencil form
        # [[I, 0], [0, M]] z' = [[0, I], [-K, -C]] z has infinite eigenvalues there; drop them
        A = np.block([[np.zeros((n, n)), np.eye(n)], [-K, -C]])
        Bm = np.block([[np.eye(n), np.zeros((n, n))], [np.zeros((n, n)), M]])
        lam, vec = sla.eig(A, Bm)
        ok = np.isfinite(lam)
        lam, vec = lam[ok], vec[:, ok]
    else:
        try:
            Minv_K = np.linalg.solve(M, K)
            Minv_C = np.linalg.solve(M, C)
        except np.linalg.LinAlgError as exc:
            raise SingularSystemError("singular mass matrix") from exc
        A = np.block([[np.zeros((n, n)), np.eye(n)], [-Minv_K, -Minv_C]])
        lam, vec = sla.eig(A)
    if lam.size == 0 or not np.all(np.isfinite(lam)):
        raise ModelError(f"no finite eigenvalues at {speed_rpm} rpm")
    scale = max(np.max(np.abs(lam)), 1.0)
    keep = lam.imag > 1e-9 * scale
    lam, vec = lam[keep], vec[:n, keep]
    # over-damped roots (ζ >= 1 without gyroscopics) are no vibration modes, see _modal_damping
    C0 = C.copy()
    C0[:model.n_dof, :model.n_dof] -= omega * model.gyro_scale * model.G
    osc = _modal_damping(vec, M, C0, K) < 1.0
    lam, vec = lam[osc], vec[:, osc]
    order = np.argsort(lam.imag)
    lam, vec = lam[order], vec[:, order]
    if n_modes is not None:
        lam, vec = lam[:n_modes], vec[:, :n_modes]
    r = model.n_dof
    vec = _circular_basis(lam, vec, r)
    X = vec[0:r:4]
    Y = vec[1:r:4]
    fw = np.sum(np.abs(X + 1j * Y) ** 2, axis=0)
    bw = np.sum(np.abs(X - 1j * Y) ** 2, axis=0)
    whirl = np.where(fw >= bw, "forward", "backward")
    wn = np.abs(lam)
    return ModalResult(
        speed_rpm=float(speed_rpm),
        frequency_hz=lam.imag / (2 * np.pi),
        damping_ratio=-lam.real / wn,
        whirl=whirl,
        eigenvalues=lam,
    )


def _modal_damping(vec: np.ndarray, M: np.ndarray, C0: np.ndarray, K: np.ndarray) -> np.ndarray:
    """Damping ratio of each mode shape from its Rayleigh quotients, gyroscopics left out:
    ``ζ = φᴴC₀φ / (2 √(φᴴKφ · φᴴMφ))``.

    Why: Rayleigh damping ``βK`` over-damps the FE mesh's high modes (``ζ = α/2ω + βω/2 > 1``
    above ``ω ≈ 2/β``, 150 kHz for the paper's β = 2.1e-6 s). Their roots are real at rest, but
    at speed the gyroscopic coupling gives each over-damped pair an imaginary part ∝ Ω (a slow
    precession of a non-oscillating motion: λ ≈ −5e5 ± 6e3i s⁻¹ at 24 000 rpm), which a test on
    ``Im λ > 0`` takes for a mode of a few tens of Hz, sorted before the physical ones. For a
    classical normal mode the quotient is its exact modal damping ratio; the gyroscopic term
    only perturbs the shape (second order in the quotient), so ``ζ < 1`` keeps exactly the modes
    that are under-damped at rest, at any speed.
    """
    def quad(A: np.ndarray) -> np.ndarray:
        return np.real(np.einsum("ik,ij,jk->k", vec.conj(), A, vec))

    m, k = quad(M), quad(0.5 * (K + K.T))
    with np.errstate(divide="ignore", invalid="ignore"):
        zeta = quad(0.5 * (C0 + C0.T)) / (2.0 * np.sqrt(np.maximum(k * m, 0.0)))
    return np.where(np.isfinite(zeta), zeta, np.inf)


def _circular_basis(lam: np.ndarray, vec: np.ndarray, r: int, rtol: float = 1e-6) -> np.ndarray:
    """Split each cluster of (numerically) repeated eigenvalues into pure forward/backward modes.

    Any combination of a repeated pair is an eigenvector (an isotropic mode untouched by
    gyroscopics), so the solver returns an arbitrary one and the whirl label would be random.
    The eigenvectors of the Hermitian form ``Σ|X + iY|² − Σ|X − iY|²`` on the cluster's span
    give one forward and one backward circular mode.
    """
    vec = vec.copy()
    i = 0
    while i < lam.size:
        j = i + 1
        while j < lam.size and abs(lam[j] - lam[i]) <= rtol * abs(lam[i]):
            j += 1
        if j - i > 1:
            V = vec[:, i:j]
            Zf = V[0:r:4] + 1j * V[1:r:4]
            Zb = V[0:r:4] - 1j * V[1:r:4]
            _, c = np.linalg.eigh(Zf.conj().T @ Zf - Zb.conj().T @ Zb)
            vec[:, i:j] = V @ c
        i = j
    return vec


@dataclass(frozen=True)
class Campbell:
    """Damped natural frequencies over a speed grid (NaN-padded to ``n_modes``)."""

    speeds_rpm: np.ndarray
    frequency_hz: np.ndarray  # (S, n_modes)
    damping_ratio: np.ndarray
    whirl: np.ndarray  # (S, n_modes) of "forward"/"backward"/""
    critical_speeds_rpm: np.ndarray


def check_modes(model: SpindleModel, n_modes: int, name: str = "n_modes") -> int:
    """``n_modes`` if the model has that many modes (one per degree of freedom)."""
    return check_modes_of(model.n_dof, n_modes, name)


def check_modes_of(n_dof: int, n_modes: int, name: str = "n_modes") -> int:
    """``n_modes`` if a model with ``n_dof`` degrees of freedom has that many modes."""
    check_int(name, n_modes, minimum=1)
    if n_modes > n_dof:
        raise ValueError(f"{name} = {n_modes} is not allowed: the model has {n_dof} modes "
                         "(one per degree of freedom)")
    return n_modes


def campbell(
    model: SpindleModel, speeds_rpm: np.ndarray, theta: np.ndarray | None = None,
    *, n_modes: int = 8, refine: bool = True,
) -> Campbell:
    """Campbell diagram over ``speeds_rpm`` and the 1x critical speeds inside that range."""
    sp = np.asarray(speeds_rpm, dtype=float)
    if sp.ndim != 1 or sp.size < 2 or np.any(np.diff(sp) <= 0) or sp[0] < 0:
        raise ValueError(
            "speeds_rpm is not allowed: need at least two strictly increasing speeds >= 0"
        )
    check_modes(model, n_modes)
    S = sp.size
    f = np.full((S, n_modes), np.nan)
    z = np.full((S, n_modes), np.nan)
    wh = np.full((S, n_modes), "", dtype=object)
    for i, s in enumerate(sp):
        m = modal_analysis(model, s, theta, n_modes=n_modes)
        k = m.frequency_hz.size
        f[i, :k], z[i, :k], wh[i, :k] = m.frequency_hz, m.damping_ratio, m.whirl
    crit = critical_speeds(model, sp, theta, refine=refine, _campbell=(f, wh))
    return Campbell(sp, f, z, wh.astype(str), crit)


def _forward_k(model, speed_rpm, theta, k) -> float:
    fw = modal_analysis(model, speed_rpm, theta).forward()
    return fw[k] if k < fw.size else np.inf


def critical_speeds(
    model: SpindleModel, speeds_rpm: np.ndarray, theta: np.ndarray | None = None,
    *, refine: bool = True, _campbell=None,
) -> np.ndarray:
    """Forward 1x critical speeds (rpm) inside ``[speeds_rpm[0], speeds_rpm[-1]]``.

    The k-th forward mode crosses the 1x line where ``f_k(n) − n/60`` changes sign; the
    crossing is refined with Brent's method to 1e-6 relative.
    """
    sp = np.asarray(speeds_rpm, dtype=float)
    if _campbell is None:
        fw_list = [modal_analysis(model, s, theta).forward() for s in sp]
    else:
        f, wh = _campbell
        fw_list = [f[i][wh[i] == "forward"] for i in range(sp.size)]
    n_fw = min(len(v) for v in fw_list)
    out = []
    for k in range(n_fw):
        g = np.array([v[k] for v in fw_list]) - sp / 60.0
        for i in np.nonzero(np.sign(g[:-1]) != np.sign(g[1:]))[0]:
            if refine:
                # the bracket ends are known from the scan (when it was this same solve)
                known = {} if _campbell is not None else {sp[i]: g[i], sp[i + 1]: g[i + 1]}

                def h(s, k=k, known=known):
                    return known[s] if s in known else _forward_k(model, s, theta, k) - s / 60.0

                root = brentq(h, sp[i], sp[i + 1], rtol=1e-6)
            else:
                root = sp[i] - g[i] * (sp[i + 1] - sp[i]) / (g[i + 1] - g[i])
            out.append(root)
    return np.sort(np.asarray(out))


def first_natural_frequency(
    model: SpindleModel, speed_rpm: float = 0.0, theta: np.ndarray | None = None
) -> float:
    """Lowest undamped, non-rotating natural frequency (Hz), bearings at ``speed_rpm``.

    Solves ``(K + K_b,sym) φ = ω² M φ`` (symmetric part of the bearing stiffness, no
    gyroscopics, no damping): the quantity of the paper's resonance constraint. Massless
    DOFs (a housing stage without mass) are condensed out statically, which is exact.
    """
    M, _, K = model.system_matrices(speed_rpm * RPM, theta)
    Ks = 0.5 * (K + K.T)
    massless = ~np.any(M != 0, axis=1)
    if massless.any():  # static (Guyan) condensation of massless DOFs is exact here
        m, z = ~massless, massless
        try:
            Ks = Ks[np.ix_(m, m)] - Ks[np.ix_(m, z)] @ np.linalg.solve(Ks[np.ix_(z, z)],
                                                                     Ks[np.ix_(z, m)])
        except np.linalg.LinAlgError as exc:
            raise SingularSystemError("massless DOFs without stiffness") from exc
        M = M[np.ix_(m, m)]
    try:
        w2 = sla.eigh(Ks, M, eigvals_only=True, subset_by_index=[0, 0])[0]
    except np.linalg.LinAlgError as exc:
        raise SingularSystemError("mass matrix not positive definite") from exc
    return float(np.sqrt(max(w2, 0.0)) / (2 * np.pi))
