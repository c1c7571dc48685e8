"""Timoshenko beam element for a rotor: 4 DOF per node, consistent mass, gyroscopics.

Degrees of freedom per node are ``[x, y, a, b]``: the two lateral displacements and the two
slopes ``a = dx/dz`` and ``b = dy/dz`` (rotations expressed as slopes, so both bending planes use
the same planar element). With spin ``Ω`` about ``+z`` the rotor equation reads

    M q'' + (C + Ω G) q' + K q = f,

where ``G`` is skew-symmetric. For a rigid disk this gives ``I_d a'' + Ω I_p b' = M_a`` and
``I_d b'' − Ω I_p a' = M_b``: with ``r = x + i y`` the whirl ``r ∝ exp(iωt)`` is *forward* for
``ω > 0``, whose frequency rises with speed (gyroscopic stiffening).

The planar matrices are the exact-shape-function Timoshenko matrices of Friedman & Kosmatka
(1993, Comput. Struct. 47:473), with ``φ = 12 E I / (κ G A L²)``; they reduce to the
Euler–Bernoulli consistent matrices at ``φ = 0``.

>>> import numpy as np
>>> k = planar_stiffness(EI=1.0, L=1.0, phi=0.0)
>>> float(k[0, 0]), float(k[1, 1])            # 12 EI/L^3 and 4 EI/L
(12.0, 4.0)
>>> m = planar_mass(rhoA=420.0, rhoI=0.0, L=1.0, phi=0.0)
>>> np.round(m[0], 9).tolist()                # 156, 22L, 54, -13L (rho A L / 420)
[156.0, 22.0, 54.0, -13.0]
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from surrogate_rbrdo.core.validate import check_positive

#: planar DOF index -> index in the 8-DOF element vector [x1, y1, a1, b1, x2, y2, a2, b2]
XPLANE = np.array([0, 2, 4, 6])  # (x1, a1, x2, a2)
YPLANE = np.array([1, 3, 5, 7])  # (y1, b1, y2, b2)


def shear_coefficient_hollow(nu: float, ratio: float) -> float:
    """Cowper's (1966) shear coefficient of a hollow circular section.

    ``ratio`` is inner/outer diameter; ``ratio = 0`` gives the solid value
    ``6(1+ν)/(7+6ν)``.

    >>> round(shear_coefficient_hollow(0.3, 0.0), 4)
    0.8864
    """
    m2 = ratio**2
    return 6 * (1 + nu) * (1 + m2) ** 2 / ((7 + 6 * nu) * (1 + m2) ** 2 + (20 + 12 * nu) * m2)


def planar_stiffness(EI: float, L: float, phi: float) -> np.ndarray:
    """4x4 bending stiffness in one plane, DOFs ``(w1, ψ1, w2, ψ2)`` with ψ = dw/dz."""
    c = EI / ((1 + phi) * L**3)
    return c * np.array(
        [
            [12, 6 * L, -12, 6 * L],
            [6 * L, (4 + phi) * L**2, -6 * L, (2 - phi) * L**2],
            [-12, -6 * L, 12, -6 * L],
            [6 * L, (2 - phi) * L**2, -6 * L, (4 + phi) * L**2],
        ]
    )


def planar_rotary(rhoI: float, L: float, phi: float) -> np.ndarray:
    """4x4 rotary-inertia mass matrix in one plane (``ρ I ∫ Nψᵀ Nψ dz``)."""
    r1 = 6 / 5
    r2 = 1 / 10 - phi / 2
    r3 = 2 / 15 + phi / 6 + phi**2 / 3
    r4 = -1 / 30 - phi / 6 + phi**2 / 6
    c = rhoI / ((1 + phi) ** 2 * L)
    return c * np.array(
        [
            [r1, r2 * L, -r1, r2 * L],
            [r2 * L, r3 * L**2, -r2 * L, r4 * L**2],
            [-r1, -r2 * L, r1, -r2 * L],
            [r2 * L, r4 * L**2, -r2 * L, r3 * L**2],
        ]
    )


def planar_mass(rhoA: float, rhoI: float, L: float, phi: float) -> np.ndarray:
    """4x4 consistent mass in one plane: translational plus rotary inertia."""
    m1 = 13 / 35 + 7 * phi / 10 + phi**2 / 3
    m2 = 11 / 210 + 11 * phi / 120 + phi**2 / 24
    m3 = 9 / 70 + 3 * phi / 10 + phi**2 / 6
    m4 = 13 / 420 + 3 * phi / 40 + phi**2 / 24
    m5 = 1 / 105 + phi / 60 + phi**2 / 120
    m6 = 1 / 140 + phi / 60 + phi**2 / 120
    c = rhoA * L / (1 + phi) ** 2
    mt = c * np.array(
        [
            [m1, m2 * L, m3, -m4 * L],
            [m2 * L, m5 * L**2, m4 * L, -m6 * L**2],
            [m3, m4 * L, m1, -m2 * L],
            [-m4 * L, -m6 * L**2, -m2 * L, m5 * L**2],
        ]
    )
    return mt + planar_rotary(rhoI, L, phi)


@dataclass(frozen=True)
class BeamSection:
    """A hollow circular section of an isotropic material (SI units)."""

    outer_diameter: float
    inner_diameter: float
    E: float
    nu: float
    rho: float

    def __post_init__(self) -> None:
        check_positive("outer_diameter", self.outer_diameter)
        check_positive("inner_diameter", self.inner_diameter, allow_zero=True)
        if self.inner_diameter >= self.outer_diameter:
            raise ValueError(
                f"inner_diameter = {self.inner_diameter} is not allowed: must be smaller than "
                f"outer_diameter = {self.outer_diameter}"
            )
        check_positive("E", self.E)
        check_positive("rho", self.rho)
        if not -1.0 < self.nu < 0.5:
            raise ValueError(f"nu = {self.nu} is not allowed: must lie in (-1, 0.5)")

    @property
    def area(self) -> float:
        return np.pi / 4 * (self.outer_diameter**2 - self.inner_diameter**2)

    @property
    def inertia(self) -> float:
        """Diametral second moment of area I (m^4); the polar one is 2 I."""
        return np.pi / 64 * (self.outer_diameter**4 - self.inner_diameter**4)

    @property
    def shear_modulus(self) -> float:
        return self.E / (2 * (1 + self.nu))

    @property
    def kappa(self) -> float:
        return shear_coefficient_hollow(self.nu, self.inner_diameter / self.outer_diameter)


def element_matrices(
    section: BeamSection, L: float, *, shear: bool = True, rotary: bool = True
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """8x8 mass, stiffness and gyroscopic matrices of one spinning Timoshenko element.

    DOF order ``[x1, y1, a1, b1, x2, y2, a2, b2]``. ``shear=False`` and ``rotary=False`` give
    the Euler–Bernoulli/Rayleigh variants (used for verification).

    >>> s = BeamSection(0.05, 0.0, 2.1e11, 0.3, 7850.0)
    >>> M, K, G = element_matrices(s, 0.1)
    >>> bool(np.allclose(G, -G.T)), bool(np.allclose(M, M.T)), bool(np.allclose(K, K.T))
    (True, True, True)
    """
    check_positive("element length", L)
    EI = section.E * section.inertia
    phi = 12 * EI / (section.kappa * section.shear_modulus * section.area * L**2) if shear else 0.0
    rhoI = section.rho * section.inertia if rotary else 0.0
    kp = planar_stiffness(EI, L, phi)
    mp = planar_mass(section.rho * section.area, rhoI, L, phi)
    rp = 2.0 * planar_rotary(section.rho * section.inertia, L, phi)  # polar: J_p = 2 I
    M = np.zeros((8, 8))
    K = np.zeros((8, 8))
    G = np.zeros((8, 8))
    for plane in (XPLANE, YPLANE):
        M[np.ix_(plane, plane)] = mp
        K[np.ix_(plane, plane)] = kp
    # gyroscopic coupling between the slopes of the two planes: +R_p (x rows, y cols)
    G[np.ix_(XPLANE, YPLANE)] = rp
    G[np.ix_(YPLANE, XPLANE)] = -rp
    return M, K, G
