"""Resonance guards: exact forward critical speeds and API 684 separation margins.

**Critical speeds.** A synchronous forward whirl ``x = Re(u e^{iΩt})``, ``y = Im(u e^{iΩt})``
(slopes alike) of a rotor invariant under rotation about its axis (isotropic bearings, no
cross-coupling) turns ``M q'' + Ω G q' + K(Ω) q = 0`` into the real symmetric problem

    (K + K_b(Ω)) u = Ω² (M − G T) u

on the ``x``–slope plane alone (``T`` the 90° rotation; ``G T`` puts ``−J_p`` on the slope
DOFs: the diametral inertia of a forward whirl is ``J_d − J_p``). Its eigenvalues ``ω_k(Ω)²``
give the critical speeds as the fixed points ``ω_k(Ω) = Ω`` (the bearings soften with speed):
a few ``eigh`` calls of half the model's size per critical speed. Damping is left out (the
damped 1x crossings of ``modal.critical_speeds`` differ by ``O(ζ²)``); the modal damping ratio
of each critical, ``ζ = uᵀ C u / (2 Ω uᵀ (M − G T) u)``, gives its amplification factor
``AF = 1 / (2ζ)``. Rotors that are not rotationally invariant raise a ``ValueError``; use
``modal.critical_speeds`` for them.

**Separation margins** (API 617 7th ed. §2.6.2.10, reproduced in API RP 684 2nd ed. §1.3): a
critical speed with ``AF ≥ 2.5`` must lie below the minimum operating speed by
``SM_b = min(16, 17 (1 − 1/(AF − 1.5)))`` % or above the maximum by
``SM_a = min(26, 10 + 17 (1 − 1/(AF − 1.5)))`` %. The guard of a design is
``g = max_k min(1 + SM_a − n_k / n_max, n_k / n_min − (1 − SM_b))`` over its critical speeds
up to ``search_factor · n_max`` (≤ 0 where every one is separated; a critical inside the
operating range makes both terms positive). The paper's guard (its Eq. 11) is
``1 − f_n1 / (1.2 n_max / 60)`` with ``f_n1`` the first undamped natural frequency at rest.

>>> import numpy as np
>>> from surrogate_rbrdo.spindle.reference import reference_spindle
>>> sp = reference_spindle()
>>> crit = forward_critical_speeds(sp.model(np.array([2000.0, 500.0, 65.0])), 40000.0)
>>> crit.speeds_rpm.round(-1).tolist(), bool(crit.amplification[0] > 100)
([21780.0], True)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
from scipy.optimize import brentq

from surrogate_rbrdo.core.errors import ModelError
from surrogate_rbrdo.core.validate import check_choice, check_positive
from surrogate_rbrdo.spindle.assembly import RPM, SpindleModel
from surrogate_rbrdo.spindle.modal import first_natural_frequency
from surrogate_rbrdo.spindle.reference import ReferenceSpindle

GUARDS = ("separation", "paper")


@dataclass(frozen=True)
class CriticalSpeeds:
    """Forward critical speeds (rpm), their modal damping ratios and amplification factors."""

    speeds_rpm: np.ndarray
    damping_ratio: np.ndarray

    @property
    def amplification(self) -> np.ndarray:
        return 1.0 / (2.0 * self.damping_ratio)


class _Plane:
    """``K_t``, ``M − G T`` and ``C`` on the x–slope plane of one model and θ: the speed-free
    parts built once, the bearings added per speed."""

    def __init__(self, model: SpindleModel, theta) -> None:
        if any(s is not None for s in model.supports):
            raise ValueError("forward_critical_speeds: a housing stage is not handled here; "
                             "use modal.critical_speeds")
        self.model, self.theta = model, model.check_theta(theta)[:1]
        n = model.n_dof
        idx = np.sort(np.concatenate([np.arange(0, n, 4), np.arange(2, n, 4)]))   # x, a
        T = np.zeros((n, n))                              # 90° rotation: x → y, a → b
        T[np.arange(1, n, 4), np.arange(0, n, 4)] = T[np.arange(3, n, 4),
                                                      np.arange(2, n, 4)] = 1
        T[np.arange(0, n, 4), np.arange(1, n, 4)] = T[np.arange(2, n, 4),
                                                      np.arange(3, n, 4)] = -1
        ix = np.ix_(idx, idx)
        self.M = (model.M - model.gyro_scale * model.G @ T)[ix]
        self.K0 = model.K[ix]
        self.C0 = (model.alpha * model.M + model.beta * model.K)[ix]
        # the x DOF of node i is row 2i of the plane
        self.rows = np.array([2 * node for node in model.bearing_nodes])

    def at(self, omega: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``K_t``, ``M − G T``, ``C`` at speed ``omega`` (rad/s)."""
        Kb, Cb = self.model.bearing_coefficients(np.array([[omega]]), self.theta)
        Kb, Cb = Kb[0, 0], Cb[0, 0]                                     # (nb, 2, 2)
        iso = np.allclose(Kb[:, 0, 0], Kb[:, 1, 1], rtol=1e-12) and np.allclose(
            Kb[:, 0, 1], 0.0) and np.allclose(Kb[:, 1, 0], 0.0)
        if not iso:
            raise ValueError("forward_critical_speeds: bearings are not isotropic without "
                             "cross-coupling; use modal.critical_speeds")
        K, C = self.K0.copy(), self.C0.copy()
        np.add.at(K, (self.rows, self.rows), Kb[:, 0, 0])
        np.add.at(C, (self.rows, self.rows), Cb[:, 0, 0])
        return K, self.M, C

    def omega_k(self, n_rpm: float, k: int) -> tuple[float, np.ndarray]:
        """k-th synchronous forward frequency (rpm) at speed ``n_rpm`` and its mode.

        ``M − G T`` is indefinite (a shaft's polar inertia is twice its diametral one),
        ``K_t`` positive definite: solve ``(M − G T) u = μ K_t u``; each ``μ > 0`` is
        ``1/ω²``, largest first; ``μ ≤ 0`` never meets the synchronous line (``inf``).
        """
        K, M, _ = self.at(n_rpm * RPM)
        m = K.shape[0]
        mu, v = sla.eigh(M, K, subset_by_index=[m - 1 - k, m - 1 - k])
        if mu[0] <= 0:
            return np.inf, v[:, 0]
        return float(1.0 / np.sqrt(mu[0]) / RPM), v[:, 0]


def forward_critical_speeds(model: SpindleModel, up_to_rpm: float, theta=None,
                            *, rtol: float = 1e-9) -> CriticalSpeeds:
    """Undamped forward critical speeds (rpm) up to ``up_to_rpm``, with damping ratios."""
    check_positive("up_to_rpm", up_to_rpm)
    plane = _Plane(model, theta)
    speeds, zetas = [], []
    for k in range(model.n_dof // 2):
        seen: dict[float, float] = {}       # brentq asks for the bracket ends again

        def h(n: float, k: int = k, seen: dict[float, float] = seen) -> float:
            if n not in seen:
                seen[n] = plane.omega_k(n, k)[0] - n
            return seen[n]
        lo, hi = 1e-3 * up_to_rpm, up_to_rpm
        if not h(hi) < 0:                                   # crosses beyond up_to_rpm
            break
        if not h(lo) > 0:                                   # below the search range
            continue
        nc = brentq(h, lo, hi, xtol=1e-6, rtol=rtol)
        _, u = plane.omega_k(nc, k)
        _, M, C = plane.at(nc * RPM)
        zetas.append(float(u @ C @ u / (2.0 * nc * RPM * (u @ M @ u))))
        speeds.append(nc)
    if not all(np.isfinite(speeds)):
        raise ModelError("forward_critical_speeds: non-finite critical speed")
    return CriticalSpeeds(np.array(speeds), np.array(zetas))


def api_separation_margins(amplification: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Required separation margins below and above the operating range (fractions), API 617
    §2.6.2.10: none where ``AF < 2.5``.

    >>> api_separation_margins(np.array([2.0, 5.0, 100.0]))[1].round(4).tolist()
    [0.0, 0.2214, 0.26]
    """
    AF = np.asarray(amplification, float)
    with np.errstate(divide="ignore", invalid="ignore"):
        core = 0.17 * (1.0 - 1.0 / (AF - 1.5))
    below = np.where(AF >= 2.5, np.minimum(0.16, core), 0.0)
    above = np.where(AF >= 2.5, np.minimum(0.26, 0.10 + core), 0.0)
    return below, above


@dataclass(frozen=True)
class ResonanceGuard:
    """``g(X) -> (P, 1)``, feasible ``≤ 0``: the API separation guard or the paper's (module
    docstring), at nominal θ, over the spindle geometry's operating range."""

    spindle: ReferenceSpindle
    kind: str = "separation"
    search_factor: float = 1.5
    paper_factor: float = 1.2

    def __post_init__(self) -> None:
        check_choice("kind", self.kind, GUARDS)
        check_positive("search_factor", self.search_factor)
        check_positive("paper_factor", self.paper_factor)

    @property
    def names(self) -> tuple[str, ...]:
        return (f"resonance_{self.kind}",)

    def margin(self, x: np.ndarray) -> float:
        model = self.spindle.model(np.asarray(x, dtype=float))
        g = model.geometry
        if self.kind == "paper":
            return 1.0 - first_natural_frequency(model) / (self.paper_factor
                                                           * g.speed_max_rpm / 60.0)
        crit = forward_critical_speeds(model, self.search_factor * g.speed_max_rpm)
        if crit.speeds_rpm.size == 0:
            return 1.0 - self.search_factor                 # none up to the search limit
        below, above = api_separation_margins(crit.amplification)
        g_above = 1.0 + above - crit.speeds_rpm / g.speed_max_rpm
        g_below = crit.speeds_rpm / g.speed_min_rpm - (1.0 - below)
        return float(np.max(np.minimum(g_above, g_below)))

    def __call__(self, X: np.ndarray) -> np.ndarray:
        X = self.spindle.design_map.check_batch(X)
        return np.array([[self.margin(x)] for x in X])


__all__ = ["GUARDS", "CriticalSpeeds", "ResonanceGuard", "api_separation_margins",
           "forward_critical_speeds"]
