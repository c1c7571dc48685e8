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
from dataclasses import dataclass
from functools import cache

import numpy as np

from surrogate_rbrdo.core.errors import ModelError
from surrogate_rbrdo.spindle.assembly import (
    SpindleModel,
    bearing_supports,
    scale_bearing_coefficients,
    unscaled_bearing_stiffness,
)
from surrogate_rbrdo.spindle.effects import Effect, Support
from surrogate_rbrdo.spindle.geometry import SpindleGeometry
from surrogate_rbrdo.spindle.substructure import chain_condensation

#: effect hooks that leave the rotor's matrices alone (the loads here are unit loads, so the
#: unbalance hook does not enter either)
BEARING_HOOKS = frozenset({"preload", "bearing", "support", "unbalance"})
#: ... of which those a bearing's impedance goes through
IMPEDANCE_HOOKS = BEARING_HOOKS - {"unbalance"}
_NOT_HOOKS = frozenset({"applies_to", "off", "params", "is_off", "warming"})


def acts_on_rotor(effect: Effect | type[Effect]) -> bool:
    """Whether ``effect`` (an effect or its class) overrides a hook other than the
    bearing-level ones (then the rotor must be reassembled with it; otherwise the base rotor
    is reused). A property of the effect's class, so it is looked up once per class.

    >>> from surrogate_rbrdo.spindle.effects import Gyroscopics, SpeedSoftening
    >>> acts_on_rotor(SpeedSoftening(a=0.1)), acts_on_rotor(Gyroscopics(g=0.1))
    (False, True)
    >>> acts_on_rotor(Gyroscopics)
    True
    """
    return bool(rotor_hooks(effect))


def acts_on_bearings(effect: Effect | type[Effect]) -> bool:
    """Whether ``effect`` (an effect or its class) overrides a hook a bearing's impedance goes
    through (preload, bearing stiffness, housing stage); the others leave
    :func:`bearing_parts` as they are (their hooks are the identity there).

    >>> from surrogate_rbrdo.spindle.effects import HousingFlexibility, ToolInterface
    >>> acts_on_bearings(HousingFlexibility(k_N_per_m=1e9)), acts_on_bearings(ToolInterface)
    (True, False)
    """
    return _class_acts_on_bearings(effect if isinstance(effect, type) else type(effect))


@cache
def _class_acts_on_bearings(cls: type) -> bool:
    return any(getattr(cls, n) is not getattr(Effect, n) for n in IMPEDANCE_HOOKS)


def rotor_hooks(effect: Effect | type[Effect]) -> frozenset[str]:
    """The hooks other than the bearing-level ones that ``effect`` (an effect or its class)
    overrides (looked up once per class).

    >>> from surrogate_rbrdo.spindle.effects import ToolInterface
    >>> sorted(rotor_hooks(ToolInterface))
    ['joint']
    """
    return _class_rotor_hooks(effect if isinstance(effect, type) else type(effect))


@cache
def _class_rotor_hooks(cls: type) -> frozenset[str]:
    return frozenset(
        name for name in dir(Effect)
        if not (name.startswith("_") or name in _NOT_HOOKS or name in BEARING_HOOKS)
        and callable(getattr(Effect, name)) and getattr(cls, name) is not getattr(Effect, name))


def condensed_dynamic_stiffness(model: SpindleModel, spin: np.ndarray, freq: np.ndarray,
                                dofs: np.ndarray) -> np.ndarray:
    """Rotor dynamic stiffness ``A(Ω, ω)`` condensed exactly onto ``dofs``: ``(X, r, r)``.

    With ``ω = Ω`` it equals :func:`~surrogate_rbrdo.spindle.substructure.condensed_rotor`.
    When ``dofs`` are whole nodes (all four DOFs of each, ascending — what the forward model
    retains) the interior is eliminated node by node along the shaft
    (:func:`~surrogate_rbrdo.spindle.substructure.chain_condensation`: the rotor couples only
    neighbouring nodes, so the cost grows with the number of nodes, not its cube); otherwise by
    the dense solve of :func:`condensed_dynamic_stiffness_dense`. Both are the exact Schur
    complement, equal to round-off (``tests/discrepancy/test_forward.py``).

    >>> from surrogate_rbrdo.spindle.reference import reference_spindle
    >>> from surrogate_rbrdo.spindle.assembly import build_model
    >>> sp = reference_spindle()
    >>> m = build_model(sp.geometry_for(sp.baseline), sp.effects)
    >>> dofs, spin, freq = np.r_[0:4, 40:48], np.array([0.0, 2000.0]), np.array([900.0, 3e3])
    >>> a = condensed_dynamic_stiffness(m, spin, freq, dofs)
    >>> b = condensed_dynamic_stiffness_dense(m, spin, freq, dofs)
    >>> bool(np.allclose(a, b, rtol=0, atol=1e-9 * np.abs(b).max()))
    True
    """
    dofs = np.asarray(dofs)
    nodes = dofs[::4] // 4
    if dofs.size % 4 or not np.array_equal(dofs, (4 * nodes[:, None] + np.arange(4)).ravel()) \
            or np.any(np.diff(nodes) <= 0):
        return condensed_dynamic_stiffness_dense(model, spin, freq, dofs)
    try:
        return chain_condensation(model, _coefficients(model, spin, freq),
                                  tuple(int(n) for n in nodes),
                                  "(condensed_dynamic_stiffness)", with_det=False).S
    except ModelError as exc:
        raise ModelError("condensed_dynamic_stiffness: singular rotor interior") from exc


def _coefficients(model: SpindleModel, spin: np.ndarray, freq: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(a_K, a_M, a_G)`` of ``A(Ω, ω) = a_K K + a_M M + a_G G`` per point: ``1 + iωβ``,
    ``−ω² + iωα``, ``iωΩ g``."""
    w = np.asarray(freq, dtype=float)
    return (1 + 1j * w * model.beta, -(w**2) + 1j * w * model.alpha,
            1j * w * np.asarray(spin, dtype=float) * model.gyro_scale)


def condensed_dynamic_stiffness_dense(model: SpindleModel, spin: np.ndarray, freq: np.ndarray,
                                      dofs: np.ndarray) -> np.ndarray:
    """:func:`condensed_dynamic_stiffness` by the dense solve ``A_dd − A_di A_ii⁻¹ A_id``
    (any DOFs; the reference the node-by-node elimination is tested against)."""
    aK, aM, aG = (a[:, None, None] for a in _coefficients(model, spin, freq))
    A = aK * model.K + aM * model.M + aG * model.G
    inner = np.setdiff1d(np.arange(A.shape[-1]), dofs)
    try:
        X = np.linalg.solve(A[:, inner[:, None], inner], A[:, inner[:, None], dofs])
    except np.linalg.LinAlgError as exc:
        raise ModelError("condensed_dynamic_stiffness: singular rotor interior") from exc
    return A[:, dofs[:, None], dofs] - A[:, dofs[:, None], inner] @ X


def bearing_dynamic_stiffness(geometry: SpindleGeometry, effects: Sequence[Effect],
                              theta_bearings: Sequence[str], spin: np.ndarray,
                              freq: np.ndarray, theta: np.ndarray,
                              damping_scale: np.ndarray,
                              parts: BearingParts | None = None) -> np.ndarray:
    """Bearing impedance ``Z = K(Ω) + iω s C(Ω)`` with its housing stage condensed in.

    As :func:`~surrogate_rbrdo.spindle.assembly.bearing_impedance` but with the response
    frequency ``ω`` apart from the spin ``Ω`` (an impact test at standstill) and a damping
    scale ``s`` per bearing. ``spin``, ``freq``: ``(X,)``; ``theta``: ``(B, m)``;
    ``damping_scale``: ``(B, nb)``. Returns ``(B, X, nb, 2, 2)``. ``parts``: what does not
    depend on θ and the damping scale (:func:`bearing_parts` of the same effects and ``spin``),
    if the caller keeps it.
    """
    B = theta.shape[0]
    if parts is None:
        parts = bearing_parts(geometry, effects, spin)
    Kb, Cb = scale_bearing_coefficients(geometry, theta_bearings, parts.stiffness, theta,
                                        (B, spin.size))
    w = freq[None, :, None, None, None]
    Z = Kb + 1j * w * Cb * damping_scale[:, None, :, None, None]
    if any(sup is not None for sup in parts.supports):
        with_supports(Z, freq, [parts.supports] * B)
    return Z


def with_supports(Z: np.ndarray, freq: np.ndarray,
                  supports: Sequence[Sequence[Support | None]]) -> np.ndarray:
    """Condense each row's housing stages into bearing impedances ``Z`` (B, X, nb, 2, 2), in
    place: bearing ``j`` of row ``b`` in series with ``supports[b][j]`` (None: rigidly held),
    ``Z − Z (Z + z_h I)⁻¹ Z`` with ``z_h = k + iωc − ω²m``. All the rows' stages of a bearing
    in one batched solve (each row's arithmetic is the same as on its own).

    Parameters
    ----------
    Z : ndarray, complex, shape (B, X, nb, 2, 2)
        Bearing impedances per row, frequency and bearing (N/m); overwritten.
    freq : ndarray, shape (X,)
        Excitation frequencies (rad/s).
    supports : sequence of sequences of Support or None
        Per row, per bearing: the housing stage it sits on, or None.

    Returns
    -------
    ndarray
        ``Z`` itself, the stages condensed in.

    >>> from surrogate_rbrdo.spindle.effects import Support
    >>> Z = np.full((2, 1, 1, 2, 2), 0.0, dtype=complex); Z[..., 0, 0] = Z[..., 1, 1] = 3.0
    >>> out = with_supports(Z, np.zeros(1), [(Support(6.0),), (None,)])
    >>> out[:, 0, 0, 0, 0].real.tolist()           # 3 and 6 in series: 2; row 2 unchanged
    [2.0, 3.0]
    """
    if len(supports) != Z.shape[0] or any(len(s) != Z.shape[2] for s in supports):
        raise ValueError(f"supports: {[len(s) for s in supports]} for impedances of shape "
                         f"{Z.shape}: must be {Z.shape[0]} rows of {Z.shape[2]} (one per "
                         "bearing)")
    for j in range(Z.shape[2]):
        rows = [b for b, s in enumerate(supports) if s[j] is not None]
        if not rows:
            continue
        k, c, m = (np.array([[getattr(supports[b][j], f)] for b in rows])
                   for f in ("k_N_per_m", "c_Ns_per_m", "m_kg"))
        zh = k + 1j * freq[None] * c - freq[None]**2 * m
        Zj = Z[rows, :, j]
        Z[rows, :, j] = Zj - Zj @ np.linalg.solve(Zj + zh[..., None, None] * np.eye(2), Zj)
    return Z


@dataclass(frozen=True)
class BearingParts:
    """What a bearing impedance needs besides θ and the damping scale, at given speeds:
    each bearing's stiffness with the effects applied and before θ, ``(1, X, 2, 2)``
    (:func:`~surrogate_rbrdo.spindle.assembly.unscaled_bearing_stiffness`), and its housing
    stage."""

    stiffness: tuple[np.ndarray, ...]
    supports: tuple[Support | None, ...]


def bearing_parts(geometry: SpindleGeometry, effects: Sequence[Effect], spin: np.ndarray
                  ) -> BearingParts:
    """:class:`BearingParts` of ``effects`` at spin speeds ``spin`` ``(X,)``."""
    spin = np.asarray(spin, dtype=float)[None]
    return BearingParts(tuple(unscaled_bearing_stiffness(geometry, effects, spin)),
                        bearing_supports(geometry, effects))
