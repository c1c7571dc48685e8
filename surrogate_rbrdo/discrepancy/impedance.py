"""The spindle's parts as dynamic stiffnesses at separate spin speed ``Ω`` and frequency ``ω``.

At every operating point the rotor alone,

    A(Ω, ω) = (1 + iωβ) K + (−ω² + iωα) M + iωΩ g G,

is condensed exactly onto retained DOFs (the dynamic Schur complement of
:mod:`surrogate_rbrdo.spindle.substructure`, which has ``ω = Ω``), and a bearing's impedance is
``K(Ω) + iω s C(Ω)`` with its housing stage condensed in
(:func:`~surrogate_rbrdo.spindle.assembly.bearing_impedance`, also ``ω = Ω`` only). An impact test
at standstill needs them apart.
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import cache

import numpy as np

from surrogate_rbrdo.core.errors import ModelError
from surrogate_rbrdo.spindle.assembly import SpindleModel, bearing_coefficients, bearing_supports
from surrogate_rbrdo.spindle.effects import Effect
from surrogate_rbrdo.spindle.geometry import SpindleGeometry

#: effect hooks that leave the rotor's matrices alone (the loads here are unit loads, so the
#: unbalance hook does not enter either)
BEARING_HOOKS = frozenset({"preload", "bearing", "support", "unbalance"})
_NOT_HOOKS = frozenset({"applies_to", "off", "params", "is_off"})


def acts_on_rotor(effect: Effect) -> bool:
    """Whether ``effect`` overrides a hook other than the bearing-level ones (then the rotor
    must be reassembled with it; otherwise the base rotor is reused). A property of the
    effect's class, so it is looked up once per class.

    >>> from surrogate_rbrdo.spindle.effects import Gyroscopics, SpeedSoftening
    >>> acts_on_rotor(SpeedSoftening(a=0.1)), acts_on_rotor(Gyroscopics(g=0.1))
    (False, True)
    """
    return _class_acts_on_rotor(type(effect))


@cache
def _class_acts_on_rotor(cls: type) -> bool:
    for name in dir(Effect):
        if name.startswith("_") or name in _NOT_HOOKS or name in BEARING_HOOKS:
            continue
        if callable(getattr(Effect, name)) and getattr(cls, name) is not getattr(Effect, name):
            return True
    return False


def condensed_dynamic_stiffness(model: SpindleModel, spin: np.ndarray, freq: np.ndarray,
                                dofs: np.ndarray) -> np.ndarray:
    """Rotor dynamic stiffness ``A(Ω, ω)`` condensed exactly onto ``dofs``: ``(X, r, r)``.

    With ``ω = Ω`` it equals :func:`~surrogate_rbrdo.spindle.substructure.condensed_rotor`.
    """
    spin = np.asarray(spin, dtype=float)[:, None, None]
    w = np.asarray(freq, dtype=float)[:, None, None]
    A = ((1 + 1j * w * model.beta) * model.K + (-(w**2) + 1j * w * model.alpha) * model.M
         + 1j * w * spin * model.gyro_scale * model.G)
    inner = np.setdiff1d(np.arange(A.shape[-1]), dofs)
    try:
        X = np.linalg.solve(A[:, inner[:, None], inner], A[:, inner[:, None], dofs])
    except np.linalg.LinAlgError as exc:
        raise ModelError("condensed_dynamic_stiffness: singular rotor interior") from exc
    return A[:, dofs[:, None], dofs] - A[:, dofs[:, None], inner] @ X


def bearing_dynamic_stiffness(geometry: SpindleGeometry, effects: Sequence[Effect],
                              theta_bearings: Sequence[str], spin: np.ndarray,
                              freq: np.ndarray, theta: np.ndarray,
                              damping_scale: np.ndarray) -> np.ndarray:
    """Bearing impedance ``Z = K(Ω) + iω s C(Ω)`` with its housing stage condensed in.

    As :func:`~surrogate_rbrdo.spindle.assembly.bearing_impedance` but with the response
    frequency ``ω`` apart from the spin ``Ω`` (an impact test at standstill) and a damping
    scale ``s`` per bearing. ``spin``, ``freq``: ``(X,)``; ``theta``: ``(B, m)``;
    ``damping_scale``: ``(B, nb)``. Returns ``(B, X, nb, 2, 2)``.
    """
    B = theta.shape[0]
    sp = np.broadcast_to(spin, (B, spin.size))
    Kb, Cb = bearing_coefficients(geometry, effects, theta_bearings, sp, theta)
    w = freq[None, :, None, None, None]
    Z = Kb + 1j * w * Cb * damping_scale[:, None, :, None, None]
    sups = bearing_supports(geometry, effects)
    for j, sup in enumerate(sups):
        if sup is None:
            continue
        zh = sup.k_N_per_m + 1j * freq * sup.c_Ns_per_m - freq**2 * sup.m_kg
        Zj = Z[:, :, j]
        Z[:, :, j] = Zj - Zj @ np.linalg.solve(Zj + zh[None, :, None, None] * np.eye(2), Zj)
    return Z
