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
``AF = 1 / (2ζ)``. An isotropic housing stage under a bearing (a non-rotating
mass–spring–damper, ``effects.Support``) keeps the rotor rotationally invariant: its x DOF joins
the plane with its mass and no gyroscopic term. Anisotropic bearings (``k_xx ≠ k_yy``) split
each critical speed; :func:`bounding_critical_speeds` brackets the split pair between the
isotropic rotors with every bearing at ``k_yy`` and at ``k_xx`` (exact bound, see there), and
the guard requires the whole interval to be separated. Cross-coupled bearings raise a
``ValueError``; use ``modal.critical_speeds`` for them.

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


#: the isotropic rotors that bound an anisotropic one: every bearing's stiffness and damping
#: taken from its x term, its y term, or their mean (:func:`bounding_critical_speeds`)
AXES = ("x", "y", "mean")


class _Plane:
    """``K_t``, ``M − G T`` and ``C`` on the x–slope plane of one model and θ (plus the x DOF
    of every housing stage): the speed-free parts built once, the bearings added per speed.
    ``axis`` (one of :data:`AXES`) takes each bearing's coefficients from that diagonal term;
    ``None`` requires isotropic bearings."""

    def __init__(self, model: SpindleModel, theta, axis: str | None = None,
                 backward: bool = False) -> None:
        if axis is not None:
            check_choice("axis", axis, AXES)
        sign = 1.0 if backward else -1.0                  # M ± G T: backward, forward
        self.model, self.theta, self.axis = model, model.check_theta(theta)[:1], axis
        n = model.n_dof
        idx = np.sort(np.concatenate([np.arange(0, n, 4), np.arange(2, n, 4)]))   # x, a
        T = np.zeros((n, n))                              # 90° rotation: x → y, a → b
        T[np.arange(1, n, 4), np.arange(0, n, 4)] = T[np.arange(3, n, 4),
                                                      np.arange(2, n, 4)] = 1
        T[np.arange(0, n, 4), np.arange(1, n, 4)] = T[np.arange(2, n, 4),
                                                      np.arange(3, n, 4)] = -1
        ix = np.ix_(idx, idx)
        # housing stages: one x DOF each after the rotor's, mass, spring and damper to ground
        # and no gyroscopic term (they do not spin); an isotropic stage keeps the rotor
        # rotationally invariant (effects.Support is isotropic)
        sup = [(j, s) for j, s in enumerate(model.supports) if s is not None]
        m, r = idx.size + len(sup), idx.size
        self.M, self.K0, self.C0 = np.zeros((m, m)), np.zeros((m, m)), np.zeros((m, m))
        self.M[:r, :r] = (model.M + sign * model.gyro_scale * model.G @ T)[ix]
        self.K0[:r, :r] = model.K[ix]
        self.C0[:r, :r] = (model.alpha * model.M + model.beta * model.K)[ix]
        # the x DOF of node i is row 2i of the plane; a bearing's outer side is its housing
        self.rows = np.array([2 * node for node in model.bearing_nodes])
        self.outer = self.rows.copy()
        for h, (j, s) in enumerate(sup):
            self.outer[j] = r + h
            self.M[r + h, r + h] = s.m_kg
            self.K0[r + h, r + h] = s.k_N_per_m
            self.C0[r + h, r + h] = s.c_Ns_per_m
        self.housed = self.outer != self.rows

    def _diagonal(self, A: np.ndarray, what: str) -> np.ndarray:
        """The bearings' x–x coefficient of ``A`` (nb, 2, 2) for this plane's ``axis``."""
        if self.axis is None:
            iso = np.allclose(A[:, 0, 0], A[:, 1, 1], rtol=1e-12)
            if not iso:
                raise ValueError(f"forward_critical_speeds: bearing {what} is not isotropic; "
                                 "use bounding_critical_speeds or modal.critical_speeds")
        if not (np.allclose(A[:, 0, 1], 0.0) and np.allclose(A[:, 1, 0], 0.0)):
            raise ValueError(f"forward_critical_speeds: bearing {what} has cross-coupling; "
                             "use modal.critical_speeds")
        if self.axis == "y":
            return A[:, 1, 1]
        if self.axis == "mean":
            return 0.5 * (A[:, 0, 0] + A[:, 1, 1])
        return A[:, 0, 0]

    def at(self, omega: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``K_t``, ``M − G T``, ``C`` at speed ``omega`` (rad/s)."""
        Kb, Cb = self.model.bearing_coefficients(np.array([[omega]]), self.theta)
        kb, cb = self._diagonal(Kb[0, 0], "stiffness"), self._diagonal(Cb[0, 0], "damping")
        K, C = self.K0.copy(), self.C0.copy()
        for A, b in ((K, kb), (C, cb)):
            np.add.at(A, (self.rows, self.rows), b)
            h, o, bh = self.rows[self.housed], self.outer[self.housed], b[self.housed]
            np.add.at(A, (o, o), bh)
            np.add.at(A, (h, o), -bh)
            np.add.at(A, (o, h), -bh)
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
                            *, rtol: float = 1e-9, axis: str | None = None,
                            backward: bool = False) -> CriticalSpeeds:
    """Undamped forward critical speeds (rpm) up to ``up_to_rpm``, with damping ratios.

    ``axis`` (``"x"``, ``"y"``, ``"mean"``): of the isotropic rotor whose bearings all take
    that diagonal term of their coefficients (:func:`bounding_critical_speeds`); ``None``
    requires isotropic bearings. ``backward``: the synchronous backward whirl instead
    (``M + G T``)."""
    check_positive("up_to_rpm", up_to_rpm)
    plane = _Plane(model, theta, axis, backward)
    speeds, zetas = [], []
    for k in range(plane.M.shape[0]):
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


@dataclass(frozen=True)
class CriticalBands:
    """Per critical speed, the interval (rpm) it lies in and the smallest modal damping ratio
    of its ends (:func:`bounding_critical_speeds`); a point for a rotationally invariant
    rotor."""

    lower_rpm: np.ndarray
    upper_rpm: np.ndarray
    damping_ratio: np.ndarray

    @property
    def amplification(self) -> np.ndarray:
        return 1.0 / (2.0 * self.damping_ratio)


def _isotropic(model: SpindleModel, up_to_rpm: float, theta) -> bool:
    """Bearings isotropic (x and y stiffness and damping equal) across the search range."""
    omega = np.linspace(0.0, up_to_rpm * RPM, 5)[None]
    Kb, Cb = model.bearing_coefficients(omega, model.check_theta(theta)[:1])
    return all(np.allclose(A[..., 0, 0], A[..., 1, 1], rtol=1e-12) for A in (Kb, Cb))


def bounding_critical_speeds(model: SpindleModel, up_to_rpm: float, theta=None
                             ) -> CriticalBands:
    """Critical speeds (rpm) up to ``up_to_rpm``: exact forward ones for isotropic bearings,
    intervals for bearings with ``k_xx ≠ k_yy`` (no cross-coupling).

    With anisotropic bearings every synchronous whirl is elliptical and unbalance excites both
    members of each split pair, so all 1x crossings count, forward and backward. They solve the
    Hermitian definite pencil ``K(Ω) u = Ω² (M − i G) u`` on the whole model (``K`` positive
    definite, ``M − i G`` Hermitian). The rotors whose bearings all take ``k_yy`` (softer) or
    ``k_xx`` bound its stiffness in the Loewner order (``K_y ⪯ K ⪯ K_x``), and by the
    Courant–Fischer theorem for definite pencils (Parlett, *The Symmetric Eigenvalue
    Problem*, 1998, §15.3; Horn & Johnson, *Matrix Analysis*, 2013, Cor. 4.3.12) the k-th
    synchronous frequency at every speed lies between theirs; an isotropic rotor's crossings
    are its forward and backward ones (the plane problems ``M ∓ G T``). So the k-th critical
    speed lies between the k-th of the two bounding rotors — for any anisotropy, as long as
    each frequency curve meets the 1x line once (bearings that soften with speed) — checked
    against the exact crossings and ``modal.critical_speeds`` at s = 0.05, 0.2, 0.35 in
    ``tests/spindle/test_separation.py``. It stops holding with cross-coupled bearings
    (``K`` not symmetric: refused). The damping ratio is the smaller of the two ends'
    (a larger amplification, a wider required margin).
    """
    if _isotropic(model, up_to_rpm, theta):
        c = forward_critical_speeds(model, up_to_rpm, theta)
        return CriticalBands(c.speeds_rpm, c.speeds_rpm, c.damping_ratio)
    ends = []
    for axis in ("y", "x"):
        cs = [forward_critical_speeds(model, up_to_rpm, theta, axis=axis, backward=b)
              for b in (False, True)]
        n = np.concatenate([c.speeds_rpm for c in cs])
        z = np.concatenate([c.damping_ratio for c in cs])
        order = np.argsort(n)
        ends.append((n[order], z[order]))
    size = max(e[0].size for e in ends)
    pad = [(np.pad(n, (0, size - n.size), constant_values=np.inf),
            np.pad(z, (0, size - z.size), constant_values=np.inf)) for n, z in ends]
    (ny, zy), (nx, zx) = pad
    return CriticalBands(np.minimum(ny, nx), np.maximum(ny, nx), np.minimum(zy, zx))


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
        crit = bounding_critical_speeds(model, self.search_factor * g.speed_max_rpm)
        if crit.lower_rpm.size == 0:
            return 1.0 - self.search_factor                 # none up to the search limit
        below, above = api_separation_margins(crit.amplification)
        # an interval is separated when it lies wholly below or wholly above the range
        g_above = 1.0 + above - crit.lower_rpm / g.speed_max_rpm
        g_below = crit.upper_rpm / g.speed_min_rpm - (1.0 - below)
        return float(np.max(np.minimum(g_above, g_below)))

    def __call__(self, X: np.ndarray) -> np.ndarray:
        X = self.spindle.design_map.check_batch(X)
        return np.array([[self.margin(x)] for x in X])


__all__ = ["AXES", "GUARDS", "CriticalBands", "CriticalSpeeds", "ResonanceGuard",
           "api_separation_margins", "bounding_critical_speeds", "forward_critical_speeds"]
