"""The model side of the comparison: complex responses at the measured channels, batched.

A *sweep* is a list of operating points, each a spin speed ``Ω`` and a response frequency ``ω``:
the steady 1x unbalance response has ``ω = Ω`` at every measured speed, an impact test at
standstill has ``Ω = 0`` and ``ω`` on the FRF's frequency lines. At every point the rotor alone,

    A(Ω, ω) = (1 + iωβ) K + (−ω² + iωα) M + iωΩ g G,

is condensed exactly onto the retained nodes (unbalance planes, bearings, channels, excitation
points: the dynamic Schur complement of :mod:`surrogate_rbrdo.spindle.substructure`, here with
separate spin and frequency), and the bearings are coupled by a low-rank (Woodbury) update:
with ``H = S⁻¹`` and ``P`` picking the bearing DOFs,

    q_O = H_OF − H_OP (I + Z H_PP)⁻¹ Z H_PF,

``Z`` the bearing dynamic stiffness (housing stage condensed in). The condensed rotor depends
on the rotor only, so it is computed once per rotor (cached) and every batch row — a bearing
stiffness factor θ, a damping scale, a candidate effect's parameters — costs one ``2 nb``-square
solve per point. Nothing is approximated: the tests compare with the dense solve of
:meth:`~surrogate_rbrdo.spindle.assembly.SpindleModel.system_matrices`.

Loads are unit loads: a unit unbalance (1 kg m) in each plane for the 1x test (force
``Ω² [1, −i]``, :func:`~surrogate_rbrdo.spindle.harmonic.unbalance_load`), a unit force for an
impact test, so the response to any unbalance is ``G u`` (linear in the plane phasors ``u``).
"""

from __future__ import annotations

import hashlib
from collections import OrderedDict
from collections.abc import Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from surrogate_rbrdo.core.errors import ModelError
from surrogate_rbrdo.core.validate import check_choice, check_finite
from surrogate_rbrdo.spindle.assembly import (
    RPM,
    SpindleModel,
    bearing_coefficients,
    bearing_supports,
    build_model,
)
from surrogate_rbrdo.spindle.effects import Effect
from surrogate_rbrdo.spindle.geometry import SpindleGeometry, Unbalance

DIRECTIONS = ("x", "y")

#: effect hooks that leave the rotor's matrices alone (the loads here are unit loads, so the
#: unbalance hook does not enter either)
BEARING_HOOKS = frozenset({"preload", "bearing", "support", "unbalance"})
_NOT_HOOKS = frozenset({"applies_to", "off", "params", "is_off"})


def acts_on_rotor(effect: Effect) -> bool:
    """Whether ``effect`` overrides a hook other than the bearing-level ones (then the rotor
    must be reassembled with it; otherwise the base rotor is reused).

    >>> from surrogate_rbrdo.spindle.effects import Gyroscopics, SpeedSoftening
    >>> acts_on_rotor(SpeedSoftening(a=0.1)), acts_on_rotor(Gyroscopics(g=0.1))
    (False, True)
    """
    for name in dir(Effect):
        if name.startswith("_") or name in _NOT_HOOKS or name in BEARING_HOOKS:
            continue
        if callable(getattr(Effect, name)) and getattr(type(effect), name) is not getattr(
                Effect, name):
            return True
    return False


@dataclass(frozen=True)
class Channel:
    """A measured displacement: a probe at ``position_mm`` (from the tool tip) in ``x`` or ``y``.

    >>> Channel("tool_x", 0.0, "x").dof_offset
    0
    """

    name: str
    position_mm: float
    direction: str

    def __post_init__(self) -> None:
        check_finite(f"channels[{self.name}].position_mm", self.position_mm)
        check_choice(f"channels[{self.name}].direction", self.direction, DIRECTIONS)

    @property
    def dof_offset(self) -> int:
        return DIRECTIONS.index(self.direction)


@dataclass(frozen=True)
class Sweep:
    """Operating points of one kind of test and its unit loads.

    Attributes
    ----------
    kind : str
        ``"unbalance_1x"`` (``ω = Ω``; one unit unbalance per plane) or ``"impact"``
        (``Ω = 0``; one unit force per excitation channel).
    spin_rad_s, freq_rad_s : ndarray (X,)
        Spin speed and response frequency of every point.
    excitations : tuple of Channel
        Where a unit force acts (impact tests only).
    """

    kind: str
    spin_rad_s: np.ndarray
    freq_rad_s: np.ndarray
    excitations: tuple[Channel, ...] = ()

    def __post_init__(self) -> None:
        check_choice("sweep.kind", self.kind, ("unbalance_1x", "impact"))
        s = np.asarray(self.spin_rad_s, dtype=float)
        w = np.asarray(self.freq_rad_s, dtype=float)
        if s.ndim != 1 or s.shape != w.shape or s.size == 0:
            raise ValueError(f"sweep.spin_rad_s / freq_rad_s have shapes {s.shape}, {w.shape}: "
                             "must be equal, one-dimensional and not empty")
        if not (np.all(np.isfinite(s)) and np.all(np.isfinite(w)) and np.all(w > 0)
                and np.all(s >= 0)):
            raise ValueError("sweep.freq_rad_s must be finite and > 0, spin_rad_s finite >= 0")
        if self.kind == "impact" and not self.excitations:
            raise ValueError("sweep.excitations = () is not allowed for an impact test: give "
                             "at least one excitation channel")
        object.__setattr__(self, "spin_rad_s", s)
        object.__setattr__(self, "freq_rad_s", w)

    @classmethod
    def unbalance(cls, speeds_rpm: Sequence[float]) -> Sweep:
        """Steady-state 1x unbalance response at ``speeds_rpm``.

        >>> Sweep.unbalance([6000.0]).freq_rad_s.round(3).tolist()
        [628.319]
        """
        w = np.asarray(speeds_rpm, dtype=float) * RPM
        return cls("unbalance_1x", w, w)

    @classmethod
    def impact(cls, freqs_hz: Sequence[float], excitations: Sequence[Channel]) -> Sweep:
        """Impact test at standstill, FRF lines ``freqs_hz``, forces at ``excitations``."""
        w = 2 * np.pi * np.asarray(freqs_hz, dtype=float)
        return cls("impact", np.zeros_like(w), w, tuple(excitations))


def with_nodes_at(geometry: SpindleGeometry, positions_mm: Sequence[float]) -> SpindleGeometry:
    """The geometry with a mesh node at every position: zero-magnitude unbalances are added
    (the mesher puts a node at every unbalance position; a zero unbalance loads nothing)."""
    extra = tuple(Unbalance(float(p), 0.0) for p in positions_mm)
    return replace(geometry, unbalances=geometry.unbalances + extra)


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


@dataclass(frozen=True)
class _Condensed:
    """Per point: the rotor's receptances restricted to outputs O, bearing DOFs P, loads F."""

    H_OF: np.ndarray  # (X, nO, nL)
    H_OP: np.ndarray  # (X, nO, 2nb)
    H_PP: np.ndarray  # (X, 2nb, 2nb)
    H_PF: np.ndarray  # (X, 2nb, nL)


@dataclass
class ForwardModel:
    """Complex responses of a spindle at measured channels, for batches of parameters.

    Parameters
    ----------
    geometry : SpindleGeometry
        The model's geometry (nodes are added at channel, plane and excitation positions).
    effects : tuple of Effect
        The model's own effects; a row's extra effects are appended to them.
    channels : tuple of Channel
        The measured outputs.
    planes_mm : tuple of float
        Unbalance planes (positions, mm) whose phasors are unknown.
    theta_bearings : tuple of str
        Bearings carrying a stiffness factor θ (default all).

    The instance memoises assembled models (keyed by the effect tuple) and condensed rotors
    (keyed by the rotor matrices and the test), at most ``cache_size`` each; nothing else
    changes between calls.

    Examples
    --------
    >>> from surrogate_rbrdo.spindle import reference_spindle
    >>> sp = reference_spindle()
    >>> g = sp.geometry_for(sp.baseline)
    >>> fm = ForwardModel(g, sp.effects, (Channel("tool_x", 0.0, "x"),), (0.0, 350.0))
    >>> G = fm.response(Sweep.unbalance([12000.0]), np.ones((1, 2)), np.ones((1, 2)))
    >>> G.shape                                  # (B, X, channels, planes)
    (1, 1, 1, 2)
    """

    geometry: SpindleGeometry
    effects: tuple[Effect, ...]
    channels: tuple[Channel, ...]
    planes_mm: tuple[float, ...]
    theta_bearings: tuple[str, ...] | None = None
    cache_size: int = 64
    _models: OrderedDict = field(default_factory=OrderedDict, init=False, repr=False)
    _condensed: OrderedDict = field(default_factory=OrderedDict, init=False, repr=False)

    def __post_init__(self) -> None:
        # an off effect leaves the model unchanged; dropping it lets a candidate of the same
        # kind (at most one gyroscopics effect) be added
        self.effects = tuple(e for e in self.effects if not e.is_off)
        self.channels = tuple(self.channels)
        self.planes_mm = tuple(float(p) for p in self.planes_mm)
        names = [b.name for b in self.geometry.bearings]
        self.theta_bearings = tuple(names if self.theta_bearings is None
                                    else self.theta_bearings)
        if not self.channels:
            raise ValueError("channels = () is not allowed: give at least one channel")
        if not self.planes_mm:
            raise ValueError("planes_mm = () is not allowed: give at least one unbalance plane")
        self._positions = sorted({c.position_mm for c in self.channels} | set(self.planes_mm))
        self.geometry = with_nodes_at(self.geometry, self._positions)

    @property
    def n_bearings(self) -> int:
        return len(self.geometry.bearings)

    @property
    def bearing_names(self) -> tuple[str, ...]:
        return tuple(b.name for b in self.geometry.bearings)

    def model(self, extra: tuple[Effect, ...] = ()) -> SpindleModel:
        """The assembled model with the extra effects (memoised)."""
        key = tuple(extra)
        if key not in self._models:
            self._models[key] = build_model(self.geometry, self.effects + key,
                                            theta_bearings=self.theta_bearings)
            if len(self._models) > self.cache_size:
                self._models.popitem(last=False)
        return self._models[key]

    def _node(self, model: SpindleModel, position_mm: float) -> int:
        return int(np.argmin(np.abs(model.z - position_mm * 1e-3)))

    def _layout(self, model: SpindleModel, sweep: Sweep):
        nodes = sorted({self._node(model, p) for p in self._positions}
                       | {self._node(model, c.position_mm) for c in sweep.excitations}
                       | set(map(int, model.bearing_nodes)))
        dofs = (4 * np.asarray(nodes)[:, None] + np.arange(4)).ravel()
        at = {n: 4 * i for i, n in enumerate(nodes)}
        out = np.array([at[self._node(model, c.position_mm)] + c.dof_offset
                        for c in self.channels])
        brg = np.concatenate([[at[int(n)], at[int(n)] + 1] for n in model.bearing_nodes])
        r = dofs.size
        if sweep.kind == "unbalance_1x":
            F = np.zeros((sweep.freq_rad_s.size, r, len(self.planes_mm)), dtype=complex)
            w2 = sweep.freq_rad_s**2
            for j, p in enumerate(self.planes_mm):
                k = at[self._node(model, p)]
                F[:, k, j] = w2
                F[:, k + 1, j] = -1j * w2
        else:
            F = np.zeros((sweep.freq_rad_s.size, r, len(sweep.excitations)), dtype=complex)
            for j, c in enumerate(sweep.excitations):
                F[:, at[self._node(model, c.position_mm)] + c.dof_offset, j] = 1.0
        return dofs, out, brg, F

    def _rotor(self, model: SpindleModel, sweep: Sweep) -> _Condensed:
        h = hashlib.sha1()
        spinning = bool(np.any(sweep.spin_rad_s != 0))  # at standstill G does not enter
        for a in (model.M, model.K, model.G * model.gyro_scale * spinning, sweep.spin_rad_s,
                  sweep.freq_rad_s):
            h.update(np.ascontiguousarray(a).tobytes())
        h.update(repr((model.alpha, model.beta, sweep.kind, sweep.excitations)).encode())
        key = h.hexdigest()
        if key not in self._condensed:
            dofs, out, brg, F = self._layout(model, sweep)
            S = condensed_dynamic_stiffness(model, sweep.spin_rad_s, sweep.freq_rad_s, dofs)
            try:
                HF = np.linalg.solve(S, F)
                HP = np.linalg.solve(S, np.broadcast_to(np.eye(dofs.size)[:, brg],
                                                        S.shape[:1] + (dofs.size, brg.size)))
            except np.linalg.LinAlgError as exc:
                raise ModelError("ForwardModel: singular condensed rotor") from exc
            self._condensed[key] = _Condensed(HF[:, out], HP[:, out], HP[:, brg], HF[:, brg])
            if len(self._condensed) > self.cache_size:
                self._condensed.popitem(last=False)
        return self._condensed[key]

    def response(self, sweep: Sweep, theta: np.ndarray, damping_scale: np.ndarray,
                 extras: Sequence[tuple[Effect, ...]] | None = None) -> np.ndarray:
        """Channel responses to the test's unit loads, ``(B, X, n_channels, n_loads)``.

        Parameters
        ----------
        sweep : Sweep
        theta : ndarray (B, m)
            Stiffness factors of ``theta_bearings``.
        damping_scale : ndarray (B, nb)
            Factors on each bearing's damping.
        extras : sequence of tuple of Effect, optional
            Per row, effects added to the model's own (default none).
        """
        theta = np.atleast_2d(np.asarray(theta, dtype=float))
        ds = np.atleast_2d(np.asarray(damping_scale, dtype=float))
        B = theta.shape[0]
        extras = [()] * B if extras is None else [tuple(e) for e in extras]
        if ds.shape != (B, self.n_bearings) or len(extras) != B:
            raise ValueError(f"damping_scale has shape {ds.shape} and extras {len(extras)} "
                             f"rows: must be ({B}, {self.n_bearings}) and {B} rows")
        groups: dict[tuple[Effect, ...], list[int]] = {}
        for i, e in enumerate(extras):
            groups.setdefault(e, []).append(i)
        out = None
        for extra, rows in groups.items():
            rotor = tuple(e for e in extra if acts_on_rotor(e))
            model = self.model(rotor)
            cond = self._rotor(model, sweep)
            Z = bearing_dynamic_stiffness(self.geometry, self.effects + extra,
                                          self.theta_bearings, sweep.spin_rad_s,
                                          sweep.freq_rad_s, theta[rows], ds[rows])
            q = _couple(cond, Z)
            if out is None:
                out = np.empty((B,) + q.shape[1:], dtype=complex)
            out[rows] = q
        if not np.all(np.isfinite(out)):
            raise ModelError("ForwardModel.response: non-finite response")
        return out

    def bearing_impedance(self, sweep: Sweep, theta: np.ndarray, damping_scale: np.ndarray,
                          extras: Sequence[tuple[Effect, ...]] | None = None) -> np.ndarray:
        """Effective bearing impedance ``(B, X, nb, 2, 2)`` (what an identification of the
        bearing coefficients at the bearing nodes sees: housing stage condensed in)."""
        theta = np.atleast_2d(np.asarray(theta, dtype=float))
        ds = np.atleast_2d(np.asarray(damping_scale, dtype=float))
        extras = [()] * theta.shape[0] if extras is None else [tuple(e) for e in extras]
        rows = []
        for i, extra in enumerate(extras):
            rows.append(bearing_dynamic_stiffness(
                self.geometry, self.effects + extra, self.theta_bearings, sweep.spin_rad_s,
                sweep.freq_rad_s, theta[i:i + 1], ds[i:i + 1])[0])
        return np.stack(rows)


def _couple(c: _Condensed, Z: np.ndarray) -> np.ndarray:
    """Woodbury coupling of the condensed rotor with bearing impedances ``Z`` (B, X, nb, 2, 2)."""
    B, X, nb = Z.shape[:3]
    Zf = np.zeros((B, X, 2 * nb, 2 * nb), dtype=complex)
    for j in range(nb):
        Zf[:, :, 2 * j:2 * j + 2, 2 * j:2 * j + 2] = Z[:, :, j]
    lhs = np.eye(2 * nb) + Zf @ c.H_PP[None]
    try:
        U = np.linalg.solve(lhs, Zf @ c.H_PF[None])
    except np.linalg.LinAlgError as exc:
        raise ModelError("ForwardModel: singular coupled system") from exc
    return c.H_OF[None] - c.H_OP[None] @ U
