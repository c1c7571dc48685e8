"""The model side of the comparison: complex responses at the measured channels, batched.

At every operating point of a sweep (:mod:`.sweeps`) the rotor is condensed exactly onto the
retained nodes (unbalance planes, bearings, channels, excitation points, disks whose mass is
recalibrated; :mod:`.impedance`), and everything a batch row changes is coupled by a low-rank
(Woodbury) update: with ``H = S⁻¹`` and ``P`` picking the coupled DOFs,

    q_O = H_OF − H_OP (I + Z H_PP)⁻¹ Z H_PF,

where ``Z`` is block diagonal: each bearing's dynamic stiffness (housing stage condensed in) on
its node's x, y DOFs, each recalibrated disk's change of mass and inertia on its node's four
DOFs, and for a row with a joint (a tool interface: a zero-length joint splitting the rotor)
the joint's change of stiffness on the relative displacement of its two nodes (four DOFs). The
condensed rotor depends on the rotor only, so it is computed once per rotor (cached) and every
batch row — a bearing stiffness factor θ, a damping factor, a disk mass factor, a candidate
effect's parameters — costs one small solve per point.

Rows with a joint share the rotor with the joint at a fixed reference stiffness
(:data:`JOINT_REFERENCE`, the middle of a tool interface's plausible range), both of its nodes
retained. The joint element ``[[D, −D], [−D, D]] = V D Vᵀ`` (``V = [I; −I]``) changes by
``V ΔD Vᵀ``, so ``P`` here is ``Vᵀ`` (the relative displacement) and ``Z = (1 + iωβ) ΔD``: the
joint's stiffness enters only on that diagonal. Unlike a condensation at the row's own
stiffness — where a near-rigid joint (the candidates keep an "off" partner stiffness at 1e18)
is subtracted from itself and loses ``k / k_structure`` of the digits — the responses then
agree with an exact solve to round-off at any ``k`` (as ``Z → ∞`` the update tends to the rigid
constraint). Other rotor-acting effects (gyroscopics: a change of the whole rotor) and rows
with two joints are condensed per distinct rotor. Nothing is approximated: the tests compare
with the dense solve of :meth:`~surrogate_rbrdo.spindle.assembly.SpindleModel.system_matrices`.

Loads are unit loads: a unit unbalance (1 kg m) in each plane for the 1x sweep (force
``Ω² [1, −i]``, :func:`~surrogate_rbrdo.spindle.harmonic.unbalance_load`), a unit force for an
impact test, so the response to any unbalance is ``G u`` (linear in the plane phasors ``u``).
"""

from __future__ import annotations

import hashlib
from collections import OrderedDict
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from surrogate_rbrdo.core.errors import ModelError
from surrogate_rbrdo.discrepancy.impedance import (
    BearingParts,
    acts_on_bearings,
    acts_on_rotor,
    bearing_dynamic_stiffness,
    bearing_parts,
    condensed_dynamic_stiffness,
    rotor_hooks,
    with_supports,
)
from surrogate_rbrdo.discrepancy.sweeps import Channel, Sweep, with_nodes_at
from surrogate_rbrdo.spindle.assembly import SpindleModel, build_model
from surrogate_rbrdo.spindle.effects import Effect, Joint
from surrogate_rbrdo.spindle.geometry import SpindleGeometry


@dataclass(frozen=True)
class _Condensed:
    """Per point: the rotor's receptances restricted to outputs O, coupled DOFs P, loads F."""

    H_OF: np.ndarray  # (X, nO, nL)
    H_OP: np.ndarray  # (X, nO, nP)
    H_PP: np.ndarray  # (X, nP, nP)
    H_PF: np.ndarray  # (X, nP, nL)
    #: the coupled system's identity (rotor, points, retained and coupled DOFs, outputs):
    #: sweeps that share it differ in their loads only
    system: str = ""


@dataclass
class ForwardModel:
    """Complex responses of a spindle at measured channels, for batches of parameters.

    Parameters
    ----------
    geometry : SpindleGeometry
        The model's geometry (nodes are added at channel and plane positions).
    effects : tuple of Effect
        The model's own effects; a row's extra effects are appended to them.
    channels : tuple of Channel
        The measured outputs.
    planes_mm : tuple of float
        Unbalance planes (positions, mm) whose phasors are unknown.
    theta_bearings : tuple of str
        Bearings carrying a stiffness factor θ (default all).
    mass_disks : tuple of str
        Disks (by name) whose mass and inertias a row may scale.

    The instance memoises assembled models (keyed by the effect tuple) and condensed rotors
    (keyed by the rotor matrices and the sweep), at most ``cache_size`` each, and the coupling
    plan of the last :data:`PLAN_CACHE` rotors over a sweep list; nothing else changes between
    calls.

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
    mass_disks: tuple[str, ...] = ()
    cache_size: int = 256
    _models: OrderedDict = field(default_factory=OrderedDict, init=False, repr=False)
    _condensed: OrderedDict = field(default_factory=OrderedDict, init=False, repr=False)
    _schurs: OrderedDict = field(default_factory=OrderedDict, init=False, repr=False)
    _prints: dict = field(default_factory=dict, init=False, repr=False)
    _parts: OrderedDict = field(default_factory=OrderedDict, init=False, repr=False)
    _plans: OrderedDict = field(default_factory=OrderedDict, init=False, repr=False)

    def __post_init__(self) -> None:
        # an off effect leaves the model unchanged; dropping it lets a candidate of the same
        # kind (at most one gyroscopics effect) be added
        self.effects = tuple(e for e in self.effects if not e.is_off)
        self.channels = tuple(self.channels)
        self.planes_mm = tuple(float(p) for p in self.planes_mm)
        self.mass_disks = tuple(self.mass_disks)
        names = [b.name for b in self.geometry.bearings]
        self.theta_bearings = tuple(names if self.theta_bearings is None
                                    else self.theta_bearings)
        if not self.channels:
            raise ValueError("channels = () is not allowed: give at least one channel")
        if not self.planes_mm:
            raise ValueError("planes_mm = () is not allowed: give at least one unbalance plane")
        disks = {d.name: d for d in self.geometry.disks}
        for d in self.mass_disks:
            if d not in disks:
                raise ValueError(f"mass_disks: {d!r} is not a disk; disks are {sorted(disks)}")
        self._disks = tuple(disks[d] for d in self.mass_disks)
        self._positions = sorted({c.position_mm for c in self.channels} | set(self.planes_mm)
                                 | {d.position_mm for d in self._disks})
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
        return _lru(self._models, key, lambda: build_model(
            self.geometry, self.effects + key, theta_bearings=self.theta_bearings),
            self.cache_size)

    def node(self, model: SpindleModel, position_mm: float) -> int:
        """The mesh node at ``position_mm``."""
        return int(np.argmin(np.abs(model.z - position_mm * 1e-3)))

    def layout(self, model: SpindleModel, sweep: Sweep, joint_mm: float | None = None
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Retained DOFs (global), the channels' and coupled DOFs' positions among them (bearing
        x, y, then four per recalibrated disk), and the sweep's unit loads ``(X, r, L)``; with
        ``joint_mm`` the two nodes of the model's joint there are retained too."""
        joint = [] if joint_mm is None else _joint_nodes(model, self.node(model, joint_mm))
        nodes = sorted({self.node(model, p) for p in self._positions}
                       | {self.node(model, c.position_mm) for c in sweep.excitations}
                       | set(map(int, model.bearing_nodes)) | set(joint))
        dofs = (4 * np.asarray(nodes)[:, None] + np.arange(4)).ravel()
        at = {n: 4 * i for i, n in enumerate(nodes)}
        out = np.array([at[self.node(model, c.position_mm)] + c.dof_offset
                        for c in self.channels])
        cpl = [[at[int(n)], at[int(n)] + 1] for n in model.bearing_nodes]
        cpl += [list(range(at[self.node(model, d.position_mm)],
                           at[self.node(model, d.position_mm)] + 4)) for d in self._disks]
        r = dofs.size
        if sweep.kind == "unbalance_1x":
            F = np.zeros((sweep.freq_rad_s.size, r, len(self.planes_mm)), dtype=complex)
            w2 = sweep.freq_rad_s**2
            for j, p in enumerate(self.planes_mm):
                k = at[self.node(model, p)]
                F[:, k, j] = w2
                F[:, k + 1, j] = -1j * w2
        else:
            F = np.zeros((sweep.freq_rad_s.size, r, len(sweep.excitations)), dtype=complex)
            for j, c in enumerate(sweep.excitations):
                F[:, at[self.node(model, c.position_mm)] + c.dof_offset, j] = 1.0
        return dofs, out, np.concatenate(cpl), F

    def _fingerprint(self, model: SpindleModel) -> tuple[str, str]:
        """Digests of the rotor's matrices without and with its gyroscopic matrix (computed
        once per model object: models with equal matrices share condensed rotors)."""
        hit = self._prints.get(id(model))
        if hit is None or hit[0] is not model:
            h = hashlib.sha1()
            for a in (model.M, model.K):
                h.update(np.ascontiguousarray(a).tobytes())
            h.update(repr((model.alpha, model.beta)).encode())
            still = h.hexdigest()
            h.update(np.ascontiguousarray(model.G * model.gyro_scale).tobytes())
            hit = (model, (still, h.hexdigest()))
            self._prints[id(model)] = hit
            if len(self._prints) > self.cache_size:
                self._prints.pop(next(iter(self._prints)))
        return hit[1]

    def _key(self, model: SpindleModel, sweep: Sweep, *extra: object) -> str:
        """Cache key of a rotor at a sweep's points (at standstill G does not enter)."""
        h = hashlib.sha1()
        h.update(self._fingerprint(model)[int(bool(np.any(sweep.spin_rad_s != 0)))].encode())
        for a in (sweep.spin_rad_s, sweep.freq_rad_s):
            h.update(np.ascontiguousarray(a).tobytes())
        h.update(repr(extra).encode())
        return h.hexdigest()

    def _schur(self, model: SpindleModel, sweep: Sweep, dofs: np.ndarray) -> np.ndarray:
        """The rotor condensed onto ``dofs`` at the sweep's points (memoised: tests that share
        their points — hits in x and in y at one speed — share it)."""
        return _lru(self._schurs, self._key(model, sweep, dofs.tobytes()),
                    lambda: condensed_dynamic_stiffness(model, sweep.spin_rad_s,
                                                        sweep.freq_rad_s, dofs),
                    self.cache_size)

    def _rotor(self, model: SpindleModel, sweep: Sweep, joint_mm: float | None = None
               ) -> _Condensed:
        """The condensed rotor at the sweep's points (memoised per rotor, sweep and coupled
        joint: ``joint_mm`` couples the model's joint there, :meth:`layout`)."""
        joint = () if joint_mm is None else (joint_mm,)

        def make() -> _Condensed:
            dofs, out, cpl, F = self.layout(model, sweep, joint_mm)
            S = self._schur(model, sweep, dofs)
            E, pick = _coupling(dofs.size, cpl, None if joint_mm is None else np.searchsorted(
                dofs, 4 * self.node(model, joint_mm) + np.arange(8)))
            rhs = np.concatenate([F, np.broadcast_to(E, S.shape[:1] + E.shape)], -1)
            try:
                H = np.linalg.solve(S, rhs)              # one factorisation for both
            except np.linalg.LinAlgError as exc:
                raise ModelError("ForwardModel: singular condensed rotor") from exc
            HF, HP = H[..., :F.shape[-1]], H[..., F.shape[-1]:]
            return _Condensed(*(np.ascontiguousarray(a) for a in (
                HF[:, out], HP[:, out], pick(HP), pick(HF))), system=self._key(
                model, sweep, dofs.tobytes(), out.tobytes(), cpl.tobytes(), *joint))
        return _lru(self._condensed, self._key(model, sweep, sweep.kind, sweep.excitations,
                                               *joint), make, self.cache_size)

    @property
    def disks(self) -> tuple:
        """The disks whose mass a row may scale (geometry objects, ``mass_disks`` order)."""
        return self._disks

    def disk_impedance(self, sweep: Sweep, mass: np.ndarray, model: SpindleModel
                       ) -> np.ndarray:
        """Dynamic stiffness of each recalibrated disk's change ``(B, X, nd, 4, 4)``: mass and
        inertias scaled by ``mass`` (B, nd) factors (mass-proportional damping and gyroscopics
        included)."""
        return self._disk_impedance(sweep.spin_rad_s, sweep.freq_rad_s, mass, model)

    def _disk_impedance(self, spin: np.ndarray, freq: np.ndarray, mass: np.ndarray,
                        model: SpindleModel) -> np.ndarray:
        w = freq[None, :, None]
        s = spin[None, :, None]
        dm = (mass - 1.0)[:, None, :]                                  # (B, 1, nd)
        a_m = -(w**2) + 1j * w * model.alpha
        Z = np.zeros(mass.shape[:1] + (freq.size, len(self._disks), 4, 4), dtype=complex)
        for k, d in enumerate(self._disks):
            m, jd = d.mass_kg * dm[..., k], d.diametral_inertia_kgm2 * dm[..., k]
            jp = d.polar_inertia_kgm2 * dm[..., k] * model.gyro_scale
            Z[..., k, 0, 0] = Z[..., k, 1, 1] = a_m[..., 0] * m
            Z[..., k, 2, 2] = Z[..., k, 3, 3] = a_m[..., 0] * jd
            Z[..., k, 2, 3] = 1j * w[..., 0] * s[..., 0] * jp
            Z[..., k, 3, 2] = -1j * w[..., 0] * s[..., 0] * jp
        return Z

    def response(self, sweep: Sweep, theta: np.ndarray, damping_scale: np.ndarray,
                 extras: Sequence[tuple[Effect, ...]] | None = None,
                 mass: np.ndarray | None = None) -> np.ndarray:
        """Channel responses to the sweep's unit loads, ``(B, X, n_channels, n_loads)``.

        Parameters
        ----------
        sweep : Sweep
        theta : ndarray (B, m)
            Stiffness factors of ``theta_bearings``.
        damping_scale : ndarray (B, nb)
            Factors on each bearing's damping.
        extras : sequence of tuple of Effect, optional
            Per row, effects added to the model's own (default none).
        mass : ndarray (B, n_mass), optional
            Factors on the mass and inertias of ``mass_disks`` (default 1).
        """
        return self.responses((sweep,), (theta,), damping_scale, extras, mass)[0]

    def responses(self, sweeps: Sequence[Sweep], theta: Sequence[np.ndarray],
                  damping_scale: np.ndarray,
                  extras: Sequence[tuple[Effect, ...]] | None = None,
                  mass: np.ndarray | None = None) -> list[np.ndarray]:
        """:meth:`response` of several sweeps at once, each with its own stiffness factors
        ``theta[k]`` (B, m) (an impact run's thermal state) and the rows' other parameters in
        common: per sweep ``(B, X_k, n_channels, n_loads_k)``.

        The same numbers as one :meth:`response` per sweep (to round-off), computed in one
        pass: rows that share a rotor are coupled in one batched solve over every sweep's
        points (sweeps with the same coupled system — hits in x and in y at one speed — with
        their loads side by side, one factorisation), and each distinct row effect's bearing
        impedance is evaluated once per set of stiffness factors over those points, from its
        θ-free part kept per effect and speeds (the cost per row is Python's, not arithmetic).
        """
        theta = [np.atleast_2d(np.asarray(t, dtype=float)) for t in theta]
        ds = np.atleast_2d(np.asarray(damping_scale, dtype=float))
        B = theta[0].shape[0]
        extras = [()] * B if extras is None else [tuple(e) for e in extras]
        mass = np.ones((B, len(self._disks))) if mass is None else np.atleast_2d(mass)
        if len(theta) != len(sweeps) or not sweeps:
            raise ValueError(f"{len(theta)} theta arrays for {len(sweeps)} sweeps: give one "
                             "per sweep (at least one sweep)")
        if any(t.shape[0] != B for t in theta) or ds.shape != (B, self.n_bearings) or len(
                extras) != B or mass.shape != (B, len(self._disks)):
            raise ValueError(f"theta {[t.shape for t in theta]}, damping_scale {ds.shape}, "
                             f"extras {len(extras)} rows and mass {mass.shape}: must have "
                             f"{B} rows, ({B}, {self.n_bearings}), {B} rows and "
                             f"({B}, {len(self._disks)})")
        # sweeps sharing one theta array share its bearing-impedance evaluation
        kinds: dict[int, list[int]] = {}
        for k, t in enumerate(theta):
            kinds.setdefault(id(t), []).append(k)
        sizes = [s.freq_rad_s.size for s in sweeps]
        starts = np.concatenate([[0], np.cumsum(sizes)])
        spin = np.concatenate([s.spin_rad_s for s in sweeps])
        freq = np.concatenate([s.freq_rad_s for s in sweeps])
        n_load = [len(self.planes_mm) if s.kind == "unbalance_1x" else len(s.excitations)
                  for s in sweeps]
        out = [np.zeros((B, n, len(self.channels), nl), dtype=complex)
               for n, nl in zip(sizes, n_load, strict=True)]
        # rows sharing a rotor (a joint at its reference stiffness standing for theirs)
        rotors: dict[tuple[tuple[Effect, ...], float | None], list[int]] = {}
        joints: list[Joint | None] = []
        for i, e in enumerate(extras):
            rotor, joint = _rotor_and_joint(e)
            joints.append(joint)
            rotors.setdefault((rotor, None if joint is None else joint.position_mm),
                              []).append(i)
        for (rotor, joint_mm), rows in rotors.items():
            model = self.model(rotor)
            plan = self._plan(model, sweeps, n_load, joint_mm)
            Z = np.zeros((len(rows), spin.size, self.n_bearings, 2, 2), dtype=complex)
            # rows whose effects on the bearings agree share their bearing parts (a tool
            # interface, gyroscopics or an unbalance error leave them as they are)
            groups: dict[tuple[Effect, ...], list[int]] = {}
            for j, i in enumerate(rows):
                groups.setdefault(tuple(x for x in extras[i] if acts_on_bearings(x)),
                                  []).append(j)
            for ks in kinds.values():
                pts = np.concatenate([np.arange(starts[k], starts[k + 1]) for k in ks])
                self._bearings_into(Z, pts, groups, np.asarray(rows), spin[pts], freq[pts],
                                    theta[ks[0]], ds)
            Zd = self._disk_impedance(spin, freq, mass[rows], model) if self._disks else None
            Zj = None if joint_mm is None else _joint_impedance(
                freq, model.beta, [joints[i] for i in rows],
                next(x for x in rotor if isinstance(x, _ReferenceJoint)).joint())
            for sel, pts, cond, at in plan:
                q = _couple(cond, Z[:, pts], None if Zd is None else Zd[:, pts],
                            None if Zj is None else Zj[:, pts])
                for j, ks in enumerate(sel):
                    c0 = 0
                    for k in ks:
                        out[k][rows] = q[:, at[j]:at[j + 1], :, c0:c0 + n_load[k]]
                        c0 += n_load[k]
        if not all(np.all(np.isfinite(o)) for o in out):
            raise ModelError("ForwardModel.response: non-finite response")
        return out

    def _plan(self, model: SpindleModel, sweeps: Sequence[Sweep], n_load: list[int],
              joint_mm: float | None = None) -> list:
        """How the sweeps' points are coupled for one rotor (memoised per model, sweep objects
        and coupled joint): per number of loads, the sweeps solved together, their points,
        their condensed rotors stacked and the points' offsets.

        Sweeps with the same coupled system (hits in x and in y at one speed) share its
        factorisation: their loads are solved together; then one coupled solve per number of
        loads (padding loads with zero columns would change the BLAS kernels, hence the last
        digits)."""
        key = (id(model), tuple(id(s) for s in sweeps), joint_mm)
        hit = self._plans.get(key)
        if hit is not None and hit[0] is model and all(
                a is b for a, b in zip(hit[1], sweeps, strict=True)):
            self._plans.move_to_end(key)
            return hit[2]
        conds = [self._rotor(model, s, joint_mm) for s in sweeps]
        sizes = [s.freq_rad_s.size for s in sweeps]
        starts = np.concatenate([[0], np.cumsum(sizes)])
        systems: dict[str, list[int]] = {}
        for k, c in enumerate(conds):
            systems.setdefault(c.system, []).append(k)
        merged = list(systems.values())
        n_merged = [sum(n_load[k] for k in ks) for ks in merged]
        plan = []
        for nl in sorted(set(n_merged)):
            sel = [ks for ks, m in zip(merged, n_merged, strict=True) if m == nl]
            pts = np.concatenate([np.arange(starts[ks[0]], starts[ks[0] + 1]) for ks in sel])
            cond = _stack([_loads_together([conds[k] for k in ks]) for ks in sel])
            at = np.concatenate([[0], np.cumsum([sizes[ks[0]] for ks in sel])])
            plan.append((sel, pts, cond, at))
        self._plans[key] = (model, tuple(sweeps), plan)
        if len(self._plans) > PLAN_CACHE:
            self._plans.popitem(last=False)
        return plan

    def _bearings_into(self, Z: np.ndarray, pts: np.ndarray, groups: dict, rows: np.ndarray,
                       spin: np.ndarray, freq: np.ndarray, theta: np.ndarray, ds: np.ndarray
                       ) -> None:
        """Each group's bearing impedance into ``Z[sub, pts]`` (``groups``: the extra effects
        acting on bearings → positions ``sub`` among ``rows``), all groups in one call: their
        θ-free stiffness stacked row by row, then each row's housing stages condensed in
        (:func:`~.impedance.with_supports`) — the same elementwise arithmetic and 2 × 2 solves
        as one call per group (a linearisation has thousands of one-row groups)."""
        items = [(sub, self.bearing_parts(extra, spin)) for extra, sub in groups.items()]
        sub = np.concatenate([s for s, _ in items])
        stiffness = tuple(np.concatenate([np.broadcast_to(p.stiffness[j], (len(s),)
                                                          + p.stiffness[j].shape[1:])
                                          for s, p in items])
                          for j in range(self.n_bearings))
        at = rows[sub]
        Zs = bearing_dynamic_stiffness(
            self.geometry, self.effects, self.theta_bearings, spin, freq, theta[at], ds[at],
            BearingParts(stiffness, (None,) * self.n_bearings))
        supports = [p.supports for s, p in items for _ in s]
        if any(sup is not None for sups in supports for sup in sups):
            with_supports(Zs, freq, supports)
        Z[np.ix_(sub, pts)] = Zs

    def bearing_parts(self, extra: tuple[Effect, ...], spin: np.ndarray) -> BearingParts:
        """The bearings' θ-free parts with the extra effects at spin speeds ``spin`` (memoised:
        a fit's rows share them with its finite-difference rows)."""
        return _lru(self._parts, (extra, np.ascontiguousarray(spin, dtype=float).tobytes()),
                    lambda: bearing_parts(self.geometry, self.effects + extra, spin),
                    4 * self.cache_size)

    def bearing_impedance(self, sweep: Sweep, theta: np.ndarray, damping_scale: np.ndarray,
                          extras: Sequence[tuple[Effect, ...]] | None = None) -> np.ndarray:
        """Effective bearing impedance ``(B, X, nb, 2, 2)`` (what an identification of the
        bearing coefficients at the bearing nodes sees: housing stage condensed in)."""
        theta = np.atleast_2d(np.asarray(theta, dtype=float))
        ds = np.atleast_2d(np.asarray(damping_scale, dtype=float))
        extras = [()] * theta.shape[0] if extras is None else [tuple(e) for e in extras]
        if not len(extras) == theta.shape[0] == ds.shape[0]:
            raise ValueError(f"extras: {len(extras)} rows for theta {theta.shape} and "
                             f"damping_scale {ds.shape}: must be one per row of both")
        groups: dict[tuple[Effect, ...], list[int]] = {}
        for i, extra in enumerate(extras):
            groups.setdefault(extra, []).append(i)
        # rows with the same extra effects in one call: the same elementwise arithmetic (and
        # 2 × 2 solves) per row as one call per row
        Z = np.empty((theta.shape[0], sweep.freq_rad_s.size, self.n_bearings, 2, 2),
                     dtype=complex)
        for extra, rows in groups.items():
            Z[rows] = bearing_dynamic_stiffness(
                self.geometry, self.effects + extra, self.theta_bearings, sweep.spin_rad_s,
                sweep.freq_rad_s, theta[rows], ds[rows],
                self.bearing_parts(extra, sweep.spin_rad_s))
        return Z


#: rotors whose coupling plan (:meth:`ForwardModel._plan`) is kept
PLAN_CACHE = 32


def _lru(cache: OrderedDict, key, make, size: int):
    """``cache[key]``, made by ``make()`` on a miss; the least recently used entry beyond
    ``size`` is dropped."""
    if key in cache:
        cache.move_to_end(key)
        return cache[key]
    value = cache[key] = make()
    if len(cache) > size:
        cache.popitem(last=False)
    return value


def _stack(conds: list[_Condensed]) -> _Condensed:
    """Condensed rotors of several sweeps (with equal numbers of loads) as one, along the
    points."""
    if len(conds) == 1:
        return conds[0]
    return _Condensed(*(np.concatenate([getattr(c, f) for c in conds])
                        for f in ("H_OF", "H_OP", "H_PP", "H_PF")))


def _loads_together(conds: list[_Condensed]) -> _Condensed:
    """Condensed rotors of sweeps sharing one coupled system as one, along the loads."""
    if len(conds) == 1:
        return conds[0]
    c = conds[0]
    return _Condensed(np.concatenate([d.H_OF for d in conds], -1), c.H_OP, c.H_PP,
                      np.concatenate([d.H_PF for d in conds], -1), c.system)


#: bytes of the coupled system's work arrays per block of rows in :func:`_couple` (a
#: linearisation couples thousands of rows at once: a few hundred MB in one block)
COUPLE_BLOCK_BYTES = 2**25


def _couple(c: _Condensed, Z: np.ndarray, Zd: np.ndarray | None,
            Zj: np.ndarray | None = None) -> np.ndarray:
    """Woodbury coupling of the condensed rotor with bearing impedances ``Z`` (B, X, nb, 2, 2),
    disk changes ``Zd`` (B, X, nd, 4, 4) and a joint's change ``Zj`` (B, X, 4, 4), in blocks of
    rows of at most :data:`COUPLE_BLOCK_BYTES` of work arrays (each row's arithmetic is the
    same whatever the block)."""
    B, X, nb = Z.shape[:3]
    n = 2 * nb + (0 if Zd is None else 4 * Zd.shape[2]) + (0 if Zj is None else 4)
    per_row = 16 * X * n * (3 * n + 2 * c.H_PF.shape[-1])
    step = max(1, COUPLE_BLOCK_BYTES // max(per_row, 1))
    if B <= step:
        return _couple_block(c, Z, Zd, Zj)
    out = np.empty((B, X) + c.H_OF.shape[1:], dtype=complex)
    for i in range(0, B, step):
        out[i:i + step] = _couple_block(c, Z[i:i + step],
                                        None if Zd is None else Zd[i:i + step],
                                        None if Zj is None else Zj[i:i + step])
    return out


def _couple_block(c: _Condensed, Z: np.ndarray, Zd: np.ndarray | None,
                  Zj: np.ndarray | None = None) -> np.ndarray:
    """:func:`_couple` of one block of rows."""
    B, X, nb = Z.shape[:3]
    blocks = [Z[:, :, j] for j in range(nb)]
    if Zd is not None:
        blocks += [Zd[:, :, k] for k in range(Zd.shape[2])]
    if Zj is not None:
        blocks.append(Zj)
    n = sum(b.shape[-1] for b in blocks)
    Zf = np.zeros((B, X, n, n), dtype=complex)
    k = 0
    for b in blocks:
        m = b.shape[-1]
        Zf[:, :, k:k + m, k:k + m] = b
        k += m
    lhs = np.eye(n) + Zf @ c.H_PP[None]
    try:
        U = np.linalg.solve(lhs, Zf @ c.H_PF[None])
    except np.linalg.LinAlgError as exc:
        raise ModelError("ForwardModel: singular coupled system") from exc
    return c.H_OF[None] - c.H_OP[None] @ U


#: the reference joint's ``(k_t, k_r)`` (N/m, N m/rad) a coupled joint's change is measured
#: from: the middle of a tool interface's plausible range (``spindle.effects.ToolInterface``),
#: near the shaft's own stiffness across the joint, so neither the reference rotor nor the
#: relative displacement's receptance is dominated by the joint (responses at any row
#: stiffness, 1e6 to 1e18, agree with an exact solve to ~1e-12 of their scale)
JOINT_REFERENCE = (1e8, 1e6)


@dataclass(frozen=True)
class _ReferenceJoint(Effect):
    """The joint of the rotor a coupled joint's rows share: at ``position_mm`` with the
    reference stiffnesses (built by :func:`_rotor_and_joint` only)."""

    name: ClassVar[str] = "reference_joint"
    off_params: ClassVar[dict[str, float]] = {"k_t_N_per_m": np.inf,
                                              "k_r_Nm_per_rad": np.inf}
    position_mm: float = 0.0
    k_t_N_per_m: float = np.inf
    k_r_Nm_per_rad: float = np.inf

    def joint(self) -> Joint:
        return Joint(self.position_mm, self.k_t_N_per_m, self.k_r_Nm_per_rad)


def _rotor_and_joint(extra: tuple[Effect, ...]) -> tuple[tuple[Effect, ...], Joint | None]:
    """A row's rotor-acting effects, and its joint if it is coupled low-rank.

    It is when exactly one of those effects has a joint, finite and positive, and acts on the
    rotor through it alone (a tool interface): that effect is replaced by a
    :class:`_ReferenceJoint` at its position with the stiffnesses :data:`JOINT_REFERENCE`, so
    all such rows share one condensed rotor, and the row's own joint is returned. Otherwise
    the effects as they are and None.
    """
    rotor = tuple(x for x in extra if acts_on_rotor(x))
    found = [(k, j) for k, x in enumerate(rotor) if (j := x.joint()) is not None]
    if len(found) != 1:
        return rotor, None
    k, j = found[0]
    ks = (j.k_t_N_per_m, j.k_r_Nm_per_rad)
    if rotor_hooks(rotor[k]) != {"joint"} or not all(0 < v < np.inf for v in ks):
        return rotor, None
    ref = _ReferenceJoint(position_mm=j.position_mm, k_t_N_per_m=JOINT_REFERENCE[0],
                          k_r_Nm_per_rad=JOINT_REFERENCE[1])
    return rotor[:k] + (ref,) + rotor[k + 1:], j


def _joint_impedance(freq: np.ndarray, beta: float, joints: Sequence[Joint], ref: Joint
                     ) -> np.ndarray:
    """Each row's joint minus the reference as a dynamic stiffness ``(B, X, 4, 4)`` on the
    joint's relative displacement ``u_left − u_right`` (``[x, y, a, b]``):
    ``(1 + iωβ) ΔD``, ``ΔD = diag(Δk_t, Δk_t, Δk_r, Δk_r)``. The assembled joint element
    (``spindle.assembly``) is ``[[D, −D], [−D, D]] = V D Vᵀ`` with ``V = [I; −I]``, so its
    change is rank four; it carries the rotor's stiffness-proportional damping ``β``."""
    dk = np.array([[j.k_t_N_per_m - ref.k_t_N_per_m] * 2
                   + [j.k_r_Nm_per_rad - ref.k_r_Nm_per_rad] * 2 for j in joints])
    return (1 + 1j * freq * beta)[None, :, None, None] * (dk[:, :, None] * np.eye(4))[:, None]


def _coupling(r: int, cpl: np.ndarray, joint: np.ndarray | None
              ) -> tuple[np.ndarray, Callable[[np.ndarray], np.ndarray]]:
    """How the coupled DOFs ``P`` sit among ``r`` retained ones: ``E`` (r, nP), the unit loads
    on them (``H E`` is ``H_·P``), and ``pick``, their displacements from retained ones
    (``Eᵀ X`` along axis 1). Unit vectors at ``cpl``, then with ``joint`` (its two nodes'
    eight positions, left node first) the relative displacement ``u_left − u_right``."""
    E = np.eye(r)[:, cpl]
    if joint is None:
        return E, lambda X: X[:, cpl]
    jl, jr = joint[:4], joint[4:]
    E = np.concatenate([E, np.eye(r)[:, jl] - np.eye(r)[:, jr]], 1)
    return E, lambda X: np.concatenate([X[:, cpl], X[:, jl] - X[:, jr]], 1)


def _joint_nodes(model: SpindleModel, left: int) -> list[int]:
    """The two coincident nodes of the model's joint whose left node is ``left``."""
    if left + 1 >= model.z.size or model.z[left + 1] != model.z[left]:
        raise ModelError(f"ForwardModel: no joint at node {left} (z = {model.z[left]} m)")
    return [left, left + 1]
