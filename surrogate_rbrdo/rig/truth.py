"""The rig's hidden truth: the model's machinery plus hidden effects plus variability.

A :class:`Truth` is a geometry, the effects the *model* also has, the *hidden* effects (from the
effects registry, with parameters) and a :class:`Variability` model. Variability is drawn at
three levels, each from its own random stream so any record can be regenerated alone:

* **build** (assembly): bearing stiffness factor and damping (η) factor per bearing,
  unbalance magnitude per plane (a fraction of the ISO 21940-11 permissible residual
  unbalance) with a uniformly random phase per plane;
* **tool change**: tool/holder mass and inertia factor; the stiffness of a
  ``tool_interface`` effect if the truth has one;
* **run** (thermal state): a preload factor per preloaded bearing (stiffness ∝ F^{1/3}).

Every number and its source is in ``docs/rig.md``.

>>> import numpy as np
>>> truth = reference_truth()
>>> st = truth.state(np.random.SeedSequence(1), build=0, tool=0, run=0)
>>> st.model().theta_bearings, st.theta.shape
(('front', 'rear'), (1, 2))
>>> sorted(st.draws)
['build', 'run', 'tool']
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from surrogate_rbrdo.core.validate import check_choice, check_positive, check_range
from surrogate_rbrdo.rig.thermal import ThermalModel
from surrogate_rbrdo.spindle.assembly import SpindleModel, build_model
from surrogate_rbrdo.spindle.effects import Effect, effect_from_dict, with_effects
from surrogate_rbrdo.spindle.geometry import PreloadLaw, SpindleGeometry, Unbalance
from surrogate_rbrdo.spindle.reference import (
    BALANCE_SPEED_RPM,
    iso_unbalance_kgm,
    reference_spindle,
)
from surrogate_rbrdo.spindle.unbalance import (
    PlaneTolerance,
    UnbalanceTolerances,
    permissible_unbalance,
)


@dataclass(frozen=True)
class Variability:
    """The truth's variability model (sources in ``docs/rig.md``).

    Attributes
    ----------
    bearing_k_cov : float
        Coefficient of variation of each bearing's stiffness per build (lognormal).
    bearing_damping_cov : float
        CoV of each bearing's damping (η) per build (lognormal).
    balance_grade_mm_s : float
        ISO 21940-11 balance quality grade the rotor is balanced to.
    unbalance_fraction : (lo, hi)
        Residual unbalance per plane as a fraction of the plane's share of the permissible
        unbalance, uniform in ``[lo, hi]`` (``unbalance_magnitude = "uniform"``); phase uniform
        in [0, 360°) per plane.
    thermal_preload_cov : float
        CoV of the preload per run (thermal state at the start of a run), lognormal;
        the stiffness follows as ``F^{exponent}``.
    tool_mass_cov : float
        CoV of the tool/holder mass and inertia per tool change (lognormal).
    interface_k_cov : float
        CoV of a ``tool_interface`` effect's stiffnesses per tool change (lognormal).
    tool_disk : str
        Name of the geometry's disk that is the tool/holder.
    unbalance_allocation : {"equal", "iso"}
        How the rotor's permissible residual unbalance ``U = m G / Ω`` is shared by the planes:
        ``"equal"`` — equal shares (the rig's first model); ``"iso"`` — each plane keeps the
        permissible residual of the parts balanced in it (ISO 21940-11 §7 allocation, as
        ``spindle.unbalance``): the tool disk's mass in the plane at the tool disk, the rest of
        the rotor in the other plane (two planes). This is the credible problem's model.
    unbalance_magnitude : {"uniform", "disk"}
        ``"uniform"`` — the fraction of the share is uniform in ``unbalance_fraction``;
        ``"disk"`` — the residual is uniform over its tolerance disk (radius fraction ``√V``,
        ``V ~ U(0, 1)``: maximum entropy inside the accepted disk, the credible problem's model).
    """

    bearing_k_cov: float = 0.05
    bearing_damping_cov: float = 0.20
    balance_grade_mm_s: float = 2.5
    unbalance_fraction: tuple[float, float] = (0.25, 1.0)
    thermal_preload_cov: float = 0.08
    tool_mass_cov: float = 0.03
    interface_k_cov: float = 0.15
    tool_disk: str = "tool_holder"
    unbalance_allocation: str = "equal"
    unbalance_magnitude: str = "uniform"

    def __post_init__(self) -> None:
        check_choice("variability.unbalance_allocation", self.unbalance_allocation,
                     ("equal", "iso"))
        check_choice("variability.unbalance_magnitude", self.unbalance_magnitude,
                     ("uniform", "disk"))
        for name in ("bearing_k_cov", "bearing_damping_cov", "thermal_preload_cov",
                     "tool_mass_cov", "interface_k_cov"):
            check_range(f"variability.{name}", getattr(self, name), 0.0, 1.0)
        check_positive("variability.balance_grade_mm_s", self.balance_grade_mm_s, allow_zero=True)
        lo, hi = self.unbalance_fraction
        if not (0.0 <= lo <= hi <= 10.0):    # 10 x the ISO limit: not a balanced rotor
            raise ValueError(f"variability.unbalance_fraction = {self.unbalance_fraction}"
                             " is not allowed: need 0 <= lo <= hi <= 10 (fractions of the ISO "
                             "21940-11 permissible unbalance)")
        object.__setattr__(self, "unbalance_fraction", (float(lo), float(hi)))

    @classmethod
    def none(cls) -> Variability:
        """No scatter at all: every build, tool and run is the nominal truth, and the unbalance
        is the full permissible value at phase 0 in every plane."""
        return cls(0.0, 0.0, 2.5, (1.0, 1.0), 0.0, 0.0, 0.0)


def _lognormal(rng: np.random.Generator, cov: float, size: int | None = None) -> np.ndarray:
    """Mean-one lognormal factors with coefficient of variation ``cov``."""
    s2 = np.log1p(cov**2)
    return np.exp(rng.normal(-0.5 * s2, np.sqrt(s2), size=size))


@dataclass(frozen=True)
class TruthState:
    """One realisation of the truth (a build, a tool, a run): geometry, effects, θ, draws."""

    geometry: SpindleGeometry
    effects: tuple[Effect, ...]
    theta_bearings: tuple[str, ...]
    theta: np.ndarray
    draws: dict[str, Any]

    def model(self) -> SpindleModel:
        return build_model(self.geometry, self.effects, theta_bearings=self.theta_bearings)

    def warming(self, fraction: float) -> TruthState:
        """This state at thermal fraction ``fraction`` of the steady state after a cold start
        (:meth:`~surrogate_rbrdo.spindle.effects.Effect.warming` of every effect; the run's own
        draws unchanged): what a soak record at ``rig.thermal.ThermalModel.fraction(t)``
        sees."""
        return dataclasses.replace(self, effects=tuple(e.warming(fraction)
                                                       for e in self.effects))


@dataclass(frozen=True)
class Truth:
    """A truth spindle: what the rig measures (never what the model knows).

    ``effects`` are those the model has too; ``hidden`` are added on top (the discrepancy the
    workflow should find); ``random_phase``: unbalance phases drawn per build (else as given).
    A hidden effect of a kind the model carries only in its off (identity) state (the
    reference model's ``Gyroscopics(g=0)``: the coupling as the geometry gives it) replaces
    that state instead of adding a second one: hiding ``{"name": "gyroscopics", "g": 0.5}``
    gives the truth 1.5 times the geometric gyroscopic coupling.

    >>> from surrogate_rbrdo.spindle.effects import Gyroscopics
    >>> t = reference_truth(hidden=[{"name": "gyroscopics", "g": 0.5}])
    >>> [e.g for e in t.all_effects if isinstance(e, Gyroscopics)]
    [0.5]
    """

    geometry: SpindleGeometry
    effects: tuple[Effect, ...] = ()
    hidden: tuple[Effect, ...] = ()
    variability: Variability = Variability()
    theta_bearings: tuple[str, ...] | None = None
    random_phase: bool = True
    #: the warm-up after a cold start (a thermal soak, :mod:`.thermal`)
    thermal: ThermalModel = ThermalModel()
    _u_perm: float = dataclasses.field(init=False, repr=False, compare=False, default=0.0)
    _u_planes: np.ndarray = dataclasses.field(init=False, repr=False, compare=False,
                                              default=None)

    def __post_init__(self) -> None:
        object.__setattr__(self, "effects", tuple(self.effects))
        object.__setattr__(self, "hidden", tuple(self.hidden))
        names = tuple(b.name for b in self.geometry.bearings)
        tb = names if self.theta_bearings is None else tuple(self.theta_bearings)
        object.__setattr__(self, "theta_bearings", tb)
        if not self.geometry.unbalances:
            raise ValueError("truth.geometry has no unbalance planes: the rig needs at least one")
        model = build_model(self.geometry, ())
        object.__setattr__(self, "_u_perm", iso_unbalance_kgm(
            model.rotor_mass_kg, self.variability.balance_grade_mm_s, BALANCE_SPEED_RPM))
        object.__setattr__(self, "_u_planes", self._plane_shares(model))

    @property
    def all_effects(self) -> tuple[Effect, ...]:
        """The model's effects and the hidden (:func:`~surrogate_rbrdo.spindle.effects.
        with_effects`: an off effect of a hidden kind is replaced)."""
        return with_effects(self.effects, self.hidden)

    def _plane_shares(self, model: SpindleModel) -> np.ndarray:
        """Permissible residual per plane (kg m) under ``variability.unbalance_allocation``."""
        v, g = self.variability, self.geometry
        n_pl = len(g.unbalances)
        if v.unbalance_allocation == "equal":
            return np.full(n_pl, self._u_perm / n_pl)
        disks = {d.name: d for d in g.disks}
        tool = disks.get(v.tool_disk)
        if n_pl != 2 or tool is None:
            raise ValueError(f"variability.unbalance_allocation = 'iso' is not allowed here: it "
                             f"needs two unbalance planes (the geometry has {n_pl}) and the "
                             f"tool disk {v.tool_disk!r} (disks: {sorted(disks)})")
        at_tool = [abs(u.position_mm - tool.position_mm) for u in g.unbalances]
        j = int(np.argmin(at_tool))
        planes = [PlaneTolerance(v.balance_grade_mm_s, None)] * 2
        planes[j] = PlaneTolerance(v.balance_grade_mm_s, (v.tool_disk,))
        tol = UnbalanceTolerances(tuple(planes), BALANCE_SPEED_RPM)
        return permissible_unbalance(model, tol)

    def permissible_unbalance_kgm(self) -> float:
        """ISO 21940-11 permissible residual unbalance ``U = m G / Ω`` of the nominal rotor at
        the balancing speed (24 000 rpm)."""
        return self._u_perm

    def describe(self) -> dict[str, Any]:
        """JSON-able description for provenance (effects with their parameters)."""
        return {"effects": [_effect_dict(e) for e in self.effects],
                "hidden": [_effect_dict(e) for e in self.hidden],
                "variability": dataclasses.asdict(self.variability),
                "theta_bearings": list(self.theta_bearings),
                "thermal": dataclasses.asdict(self.thermal),
                "geometry": self.geometry.to_dict()}

    # ------------------------------------------------------------------ draws
    def draw_build(self, ss: np.random.SeedSequence) -> dict[str, Any]:
        v, rng = self.variability, np.random.default_rng(ss)
        nb = len(self.geometry.bearings)
        k = _lognormal(rng, v.bearing_k_cov, nb)
        c = _lognormal(rng, v.bearing_damping_cov, nb)
        n_pl = len(self.geometry.unbalances)
        disk = v.unbalance_magnitude == "disk"
        frac = rng.uniform(*((0.0, 1.0) if disk else v.unbalance_fraction), size=n_pl)
        frac = np.sqrt(frac) if disk else frac      # uniform over the tolerance disk
        phase = rng.uniform(0.0, 360.0, size=n_pl)
        U = self._u_planes * frac
        return {"k_factor": k.tolist(), "damping_factor": c.tolist(),
                "unbalance_kgm": U.tolist(),
                "unbalance_phase_deg": phase.tolist() if self.random_phase
                else [u.phase_deg for u in self.geometry.unbalances]}

    def draw_tool(self, ss: np.random.SeedSequence) -> dict[str, Any]:
        v, rng = self.variability, np.random.default_rng(ss)
        return {"mass_factor": float(_lognormal(rng, v.tool_mass_cov)),
                "interface_factor": _lognormal(rng, v.interface_k_cov, 2).tolist()}

    def draw_run(self, ss: np.random.SeedSequence) -> dict[str, Any]:
        v, rng = self.variability, np.random.default_rng(ss)
        return {"preload_factor": _lognormal(rng, v.thermal_preload_cov,
                                             len(self.geometry.bearings)).tolist()}

    def state(self, ss: np.random.SeedSequence, *, build: int, tool: int, run: int
              ) -> TruthState:
        """The truth of build ``build``, tool change ``tool`` and run ``run``; the draws come
        from ``ss`` spawned by key ``(build,)``, ``(build, tool)``, ``(build, tool, run)``."""
        b = self.draw_build(_child(ss, 0, build))
        t = self.draw_tool(_child(ss, 1, build, tool))
        r = self.draw_run(_child(ss, 2, build, tool, run))
        return self.apply(b, t, r)

    def apply(self, b: dict[str, Any], t: dict[str, Any], r: dict[str, Any]) -> TruthState:
        """The truth state for given draws (as :meth:`draw_build` etc. return them)."""
        g = self.geometry
        bearings, theta = [], []
        for j, br in enumerate(g.bearings):
            law = br.law
            law = replace(law, damping_eta_s=law.damping_eta_s * b["damping_factor"][j])
            # thermal preload state: k ∝ F^exponent for a preload law, F^{1/3} otherwise
            expo = law.exponent if isinstance(law, PreloadLaw) else 1.0 / 3.0
            kf = b["k_factor"][j] * r["preload_factor"][j] ** expo
            bearings.append(replace(br, law=law))
            if br.name in self.theta_bearings:
                theta.append(kf)
            elif kf != 1.0:
                raise ValueError(f"truth: bearing {br.name!r} varies but is not a θ bearing")
        unb = tuple(Unbalance(u.position_mm, U, ph) for u, U, ph in
                    zip(g.unbalances, b["unbalance_kgm"], b["unbalance_phase_deg"], strict=True))
        disks = tuple(
            replace(d, mass_kg=d.mass_kg * t["mass_factor"],
                    polar_inertia_kgm2=d.polar_inertia_kgm2 * t["mass_factor"],
                    diametral_inertia_kgm2=d.diametral_inertia_kgm2 * t["mass_factor"])
            if d.name == self.variability.tool_disk else d for d in g.disks)
        geom = replace(g, bearings=tuple(bearings), unbalances=unb, disks=disks)
        effects = tuple(_scale_interface(e, t["interface_factor"]) for e in self.all_effects)
        return TruthState(geom, effects, self.theta_bearings, np.array([theta]),
                          {"build": b, "tool": t, "run": r})


def _child(ss: np.random.SeedSequence, *key: int) -> np.random.SeedSequence:
    """A child seed sequence addressed by ``key`` (random access, so runs can resume)."""
    return np.random.SeedSequence(ss.entropy, spawn_key=tuple(ss.spawn_key) + tuple(key))


def _scale_interface(e: Effect, factors: Sequence[float]) -> Effect:
    """A ``tool_interface`` effect with its two stiffnesses scaled (others unchanged)."""
    if e.name != "tool_interface" or e.is_off:
        return e
    return replace(e, k_t_N_per_m=e.k_t_N_per_m * factors[0],
                   k_r_Nm_per_rad=e.k_r_Nm_per_rad * factors[1])


def _effect_dict(e: Effect) -> dict[str, Any]:
    d = {"name": e.name}
    for k, v in e.params().items():
        d[k] = list(v) if isinstance(v, tuple) else (None if v == np.inf else v)
    return d


def spindle_truth(spindle: Any, hidden: Sequence[Effect | dict[str, Any]] = (),
                  variability: Variability = Variability(),
                  x: np.ndarray | None = None) -> Truth:
    """A parametric spindle (``reference_spindle()``, ``credible_spindle()``, …; design ``x``,
    default its baseline) as a truth: the model's effects, plus ``hidden`` effects (objects or
    ``{"name": ..., <params>}``)."""
    geom = spindle.geometry_for(spindle.baseline if x is None else np.asarray(x, float))
    hid = tuple(e if isinstance(e, Effect) else effect_from_dict(dict(e)) for e in hidden)
    return Truth(geom, spindle.effects, hid, variability, spindle.theta_bearings)


def reference_truth(hidden: Sequence[Effect | dict[str, Any]] = (),
                    variability: Variability = Variability(),
                    x: np.ndarray | None = None) -> Truth:
    """The reference spindle (design ``x``, default the baseline) as a truth
    (:func:`spindle_truth` of ``reference_spindle()``)."""
    return spindle_truth(reference_spindle(), hidden, variability, x)
