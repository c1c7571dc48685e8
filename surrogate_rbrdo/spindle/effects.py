"""Named, switchable physical effects the spindle model is assembled from.

An effect is a frozen dataclass with a registry name, a few parameters with documented bounds,
and an *off* state (:meth:`Effect.off`). The assembly calls a fixed set of hooks on every effect
in the model's list; an effect overrides the hooks it needs, so adding an effect never means
editing the assembly:

* ``preload(bearing, omega, F)``: the operating preload (N) of a preload-law bearing;
* ``bearing(bearing, omega, K)``: the 2x2 stiffness (N/m) of a bearing, shape ``(..., 2, 2)``;
* ``support(bearing)``: a :class:`Support` in series between the bearing and ground (housing);
* ``gyroscopic_scale()``: a factor on the rotor's polar inertia (gyroscopic matrix);
* ``unbalance(U)``: the complex unbalance vector (kg m);
* ``joint()``: a :class:`Joint` (zero-length spring between two coincident rotor nodes).

``omega`` is the spin speed in rad/s, any shape; the hooks broadcast over it.

>>> import numpy as np
>>> eff = SpeedSoftening(a=0.2, exponent=2.0, omega_ref=100.0)
>>> K = np.broadcast_to(np.eye(2), (3, 2, 2)) * 1e8
>>> Kw = eff.bearing("front", np.array([0.0, 50.0, 100.0]), K)
>>> (Kw[:, 0, 0] / 1e8).round(3).tolist()
[1.0, 0.95, 0.8]
>>> SpeedSoftening.off().bearing("front", np.array([100.0]), K[:1])[0, 0, 0] == 1e8
np.True_
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Annotated, Any, ClassVar

import numpy as np
from pydantic import AllowInfNan

from surrogate_rbrdo.core.registry import Registry
from surrogate_rbrdo.core.schema import parse
from surrogate_rbrdo.core.validate import check_positive, check_range, check_text

EFFECTS = Registry("effect")

#: a parameter whose off state is ``inf`` (a rigid housing or joint): ``inf`` is allowed in data
InfOff = Annotated[float, AllowInfNan(True)]


@dataclass(frozen=True)
class Support:
    """Isotropic housing stage in series with a bearing: stiffness, damping and mass."""

    k_N_per_m: float
    c_Ns_per_m: float = 0.0
    m_kg: float = 0.0


@dataclass(frozen=True)
class Joint:
    """A zero-length elastic joint splitting the rotor at ``position_mm``: translational
    ``k_t`` (N/m) and rotational ``k_r`` (N m/rad) springs between the two coincident nodes.
    Items at the joint's position (disks, unbalances, tool tip) sit on its left node."""

    position_mm: float
    k_t_N_per_m: float
    k_r_Nm_per_rad: float


@dataclass(frozen=True)
class Effect:
    """Base class: every hook is the identity; ``bearings=()`` means all bearings."""

    name: ClassVar[str] = "effect"
    #: parameter name -> (lower, upper) physically plausible bounds
    bounds: ClassVar[dict[str, tuple[float, float]]] = {}
    #: parameter values of the off state
    off_params: ClassVar[dict[str, float]] = {}
    #: parameters that follow the spindle's temperature: at the thermal steady state of a
    #: speed they have their values, from a cold start they grow in proportion to the
    #: normalised temperature rise (:meth:`warming`); empty for an effect that does not drift
    thermal_params: ClassVar[tuple[str, ...]] = ()
    bearings: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        if isinstance(self.bearings, str) or not isinstance(self.bearings, Iterable):
            raise ValueError(f"bearings = {self.bearings!r} is not allowed: must be a sequence "
                             f"of bearing names, e.g. ['front'] ({self.name})")
        object.__setattr__(self, "bearings", tuple(self.bearings))
        for i, b in enumerate(self.bearings):
            check_text(f"bearings[{i}]", b)
        if len(set(self.bearings)) != len(self.bearings):
            raise ValueError(f"bearings = {list(self.bearings)} is not allowed: a name appears "
                             f"twice ({self.name})")
        for p, (lo, hi) in self.bounds.items():
            if p in self.off_params and getattr(self, p) == self.off_params[p]:
                continue  # the off state may sit on an open bound (e.g. k_h = inf)
            try:
                check_range(p, getattr(self, p), lo, hi)
            except ValueError as exc:
                raise ValueError(f"{exc} ({self.name})") from None

    def applies_to(self, bearing: str) -> bool:
        return not self.bearings or bearing in self.bearings

    @classmethod
    def off(cls, **kwargs: Any) -> Effect:
        """The effect switched off: it leaves the model exactly unchanged."""
        return cls(**{**cls.off_params, **kwargs})

    @property
    def is_off(self) -> bool:
        return all(getattr(self, k) == v for k, v in self.off_params.items())

    def params(self) -> dict[str, Any]:
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}

    def warming(self, fraction: float) -> Effect:
        """The effect at a thermal state between cold (``fraction = 0``: its thermal
        parameters at their off values) and the steady state of the running speed
        (``fraction = 1``: the effect as it is), the thermal parameters linear in between — a
        single-time-constant thermal model, where every temperature of the spindle rises as
        ``1 − e^{−t/τ}`` after a cold start (Bossmanns & Tu, *J. Manuf. Sci. Eng.* 121, 1999).
        An effect without :attr:`thermal_params` is returned as it is.

        >>> ThermalPreload(b=0.02).warming(0.25).b
        0.005
        >>> SpeedSoftening(a=0.2).warming(0.0).a
        0.2
        """
        check_range("fraction", fraction, 0.0, 1.0)
        if not self.thermal_params:
            return self
        return dataclasses.replace(self, **{
            p: self.off_params[p] + fraction * (getattr(self, p) - self.off_params[p])
            for p in self.thermal_params})

    # hooks -----------------------------------------------------------------
    def preload(self, bearing: str, omega: np.ndarray, F: np.ndarray) -> np.ndarray:
        return F

    def bearing(self, bearing: str, omega: np.ndarray, K: np.ndarray) -> np.ndarray:
        return K

    def support(self, bearing: str) -> Support | None:
        return None

    def gyroscopic_scale(self) -> float:
        return 1.0

    def unbalance(self, U: np.ndarray) -> np.ndarray:
        return U

    def joint(self) -> Joint | None:
        return None


def effect_from_dict(data: Mapping[str, Any], where: str = "") -> Effect:
    """Build an effect from ``{"name": ..., <params>}`` (TOML/JSON) through the strict
    schema (``core.schema``): a parameter of the wrong type (``a = "0.1"``, ``bearings =
    "front"``), an unknown key or a value out of bounds raises one line naming the path below
    ``where`` (default ``effects.<name>``).

    >>> effect_from_dict({"name": "speed_softening", "a": 0.1, "bearings": ["front"]}).a
    0.1
    >>> effect_from_dict({"name": "speed_softening", "bearings": "front"})  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    ValueError: effects.speed_softening.bearings = 'front' is not allowed: must be an array ...
    """
    if not isinstance(data, Mapping):
        raise ValueError(f"{where or 'effect'} = {data!r} is not allowed: must be a table "
                         "{name = ..., <parameters>}")
    d = dict(data)
    name = d.pop("name", None)
    if not isinstance(name, str) or name not in set(EFFECTS):
        raise ValueError(f"{where + '.' if where else ''}name = {name!r} is not allowed: "
                         f"unknown effect {name!r}; known: {', '.join(sorted(EFFECTS))}")
    return parse(EFFECTS[name], d, where or f"effects.{name}")


def effects_from_data(data: Sequence[Any], where: str = "effects") -> tuple[Effect, ...]:
    """Effects from a list of ``{"name": ..., <params>}`` tables (:func:`effect_from_dict`,
    errors name ``<where>[i]``); the same effect twice on one bearing is refused."""
    if isinstance(data, (str, Mapping)) or not isinstance(data, Sequence):
        raise ValueError(f"{where} = {data!r} is not allowed: must be an array of tables "
                         "[{name = ..., <parameters>}]")
    out = tuple(effect_from_dict(e, f"{where}[{i}]") for i, e in enumerate(data))
    check_effects(out, None, where)
    return out


def with_effects(effects: Sequence[Effect], added: Sequence[Effect]) -> tuple[Effect, ...]:
    """``effects`` with ``added`` appended; an effect of ``effects`` in its off (identity)
    state of a kind ``added`` has is dropped, so a model's neutral switch (the reference
    model's ``Gyroscopics(g=0)``) is replaced rather than doubled — it changes nothing, and
    some kinds allow one per model.

    >>> [e.g for e in with_effects((Gyroscopics(),), (Gyroscopics(g=0.5),))]
    [0.5]
    """
    kinds = {type(e) for e in added}
    return tuple(e for e in effects if not (type(e) in kinds and e.is_off)) + tuple(added)


def check_effects(effects: Sequence[Effect], bearings: Sequence[str] | None,
                  where: str = "effects") -> None:
    """Refuse effects on bearings that do not exist (``bearings``: the geometry's names,
    ``None``: not checked) and one effect applied twice to one bearing (they would
    compound).

    >>> check_effects([SpeedSoftening(a=0.1, bearings=("nose",))], ["front", "rear"])
    ... # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    ValueError: effects[0].bearings = ['nose'] is not allowed: 'nose' is not a bearing; ...
    """
    prev: list[tuple[str, set[str]]] = []
    for i, e in enumerate(effects):
        if bearings is not None:
            bad = [b for b in e.bearings if b not in bearings]
            if bad:
                raise ValueError(f"{where}[{i}].bearings = {list(e.bearings)} is not allowed: "
                                 f"{bad[0]!r} is not a bearing; bearings are {list(bearings)}")
        t = set(e.bearings) if e.bearings else set(bearings) if bearings is not None else {"*"}
        for j, (name, tj) in enumerate(prev):
            if name == e.name and (t & tj or "*" in t | tj):
                on = sorted(t & tj - {"*"}) or "all bearings"
                raise ValueError(f"{where}[{i}] = {e.name!r} is not allowed: {where}[{j}] "
                                 f"already applies {e.name} to {on} (they would compound)")
        prev.append((e.name, t))


@EFFECTS.register("speed_softening")
@dataclass(frozen=True)
class SpeedSoftening(Effect):
    """Centrifugal softening: ``k(Ω) = k₀ (1 − a (Ω/Ω_ref)^p)``.

    Signature: identified stiffness and critical speeds fall with speed.
    """

    name: ClassVar[str] = "speed_softening"
    bounds: ClassVar[dict[str, tuple[float, float]]] = {"a": (0.0, 0.9), "exponent": (0.5, 4.0)}
    off_params: ClassVar[dict[str, float]] = {"a": 0.0}
    a: float = 0.0
    exponent: float = 2.0
    omega_ref: float = 24000 * np.pi / 30

    def __post_init__(self) -> None:
        super().__post_init__()
        check_positive("omega_ref", self.omega_ref)

    def bearing(self, bearing: str, omega: np.ndarray, K: np.ndarray) -> np.ndarray:
        if not self.applies_to(bearing) or self.a == 0.0:
            return K
        f = 1.0 - self.a * (np.abs(omega) / self.omega_ref) ** self.exponent
        return K * f[..., None, None]


@EFFECTS.register("thermal_preload")
@dataclass(frozen=True)
class ThermalPreload(Effect):
    """Thermal preload growth ``F(Ω) = F₀ (1 + b (Ω/Ω_ref)^q)``; with ``k ∝ F^{1/3}``.

    Signature: the opposite trend to softening (stiffness rises with speed); the growth
    follows the bearings' temperature, so at a fixed speed it drifts as the spindle warms
    (a thermal soak, ``rig.thermal``, :meth:`Effect.warming`).
    """

    name: ClassVar[str] = "thermal_preload"
    bounds: ClassVar[dict[str, tuple[float, float]]] = {"b": (0.0, 3.0), "q": (0.5, 4.0)}
    off_params: ClassVar[dict[str, float]] = {"b": 0.0}
    #: the growth follows the rings' temperature difference: it drifts during a soak
    thermal_params: ClassVar[tuple[str, ...]] = ("b",)
    b: float = 0.0
    q: float = 2.0
    omega_ref: float = 24000 * np.pi / 30

    def __post_init__(self) -> None:
        super().__post_init__()
        check_positive("omega_ref", self.omega_ref)

    def preload(self, bearing: str, omega: np.ndarray, F: np.ndarray) -> np.ndarray:
        if not self.applies_to(bearing) or self.b == 0.0:
            return F
        return F * (1.0 + self.b * (np.abs(omega) / self.omega_ref) ** self.q)


@EFFECTS.register("cross_coupling")
@dataclass(frozen=True)
class CrossCoupling(Effect):
    """Skew-symmetric bearing cross-coupling ``k_xy = −k_yx = κ k``.

    Signature: a phase shift; acts like lost (κ > 0, forward) damping.
    """

    name: ClassVar[str] = "cross_coupling"
    bounds: ClassVar[dict[str, tuple[float, float]]] = {"kappa": (-0.5, 0.5)}
    off_params: ClassVar[dict[str, float]] = {"kappa": 0.0}
    kappa: float = 0.0

    def bearing(self, bearing: str, omega: np.ndarray, K: np.ndarray) -> np.ndarray:
        if not self.applies_to(bearing) or self.kappa == 0.0:
            return K
        k = 0.5 * (K[..., 0, 0] + K[..., 1, 1])
        out = np.array(K, dtype=float, copy=True)
        out[..., 0, 1] += self.kappa * k
        out[..., 1, 0] -= self.kappa * k
        return out


@EFFECTS.register("anisotropy")
@dataclass(frozen=True)
class Anisotropy(Effect):
    """Bearing anisotropy ``k_x = k (1 + s)``, ``k_y = k (1 − s)``.

    Signature: elliptical orbits; forward/backward split already at Ω = 0.
    """

    name: ClassVar[str] = "anisotropy"
    bounds: ClassVar[dict[str, tuple[float, float]]] = {"s": (-0.5, 0.5)}
    off_params: ClassVar[dict[str, float]] = {"s": 0.0}
    s: float = 0.0

    def bearing(self, bearing: str, omega: np.ndarray, K: np.ndarray) -> np.ndarray:
        if not self.applies_to(bearing) or self.s == 0.0:
            return K
        out = np.array(K, dtype=float, copy=True)
        out[..., 0, 0] *= 1.0 + self.s
        out[..., 1, 1] *= 1.0 - self.s
        return out


@EFFECTS.register("housing")
@dataclass(frozen=True)
class HousingFlexibility(Effect):
    """Housing/foundation stage in series with each bearing: spring ``k_h``, mass ``m_h``.

    ``k_h = inf`` is off. Signature: all bearing-dominated modes lower; an extra housing mode.

    The mass is the effective mass the housing adds at one bearing, at most
    250 kg: a stage at a bearing cannot move more than the housing it
    stands for. A motor spindle unit's housing is a steel shell around the bearings' outer
    rings and the stator with its cooling jacket (the principal set-up of Abele, Altintas &
    Brecher 2010, *CIRP Annals* 59:781, Fig. 3; the housing modelled as a beam carried by the
    spindle head through springs in Cao & Altintas 2007, *Int. J. Mach. Tools Manuf.*
    47:1342). For spindles of the reference's class (65 mm bearing bores, a 0.68 m rotor of
    21 kg) a generous shell, outer diameter 250 mm, bore 120 mm, length 0.7 m, weighs
    ``7850 π/4 (0.25² − 0.12²) 0.7 ≈ 207 kg``: an upper estimate of the whole housing, so of
    what one stage can carry. A fitted mass beyond it is not a housing (a 500 kg stage once
    stood in for a magnetic pull, docs/discrepancy.md). Heavier structures behind the housing
    (headstock, column) are a model of the machine, not of this stage.
    """

    name: ClassVar[str] = "housing"
    bounds: ClassVar[dict[str, tuple[float, float]]] = {
        "k_N_per_m": (1e6, np.inf), "m_kg": (0.0, 250.0), "c_Ns_per_m": (0.0, 1e6)}
    off_params: ClassVar[dict[str, float]] = {"k_N_per_m": np.inf}
    k_N_per_m: InfOff = np.inf
    m_kg: float = 0.0
    c_Ns_per_m: float = 0.0

    def support(self, bearing: str) -> Support | None:
        if not self.applies_to(bearing) or np.isinf(self.k_N_per_m):
            return None
        return Support(self.k_N_per_m, self.c_Ns_per_m, self.m_kg)


@EFFECTS.register("gyroscopics")
@dataclass(frozen=True)
class Gyroscopics(Effect):
    """Gyroscopic error: polar inertia scaled by ``1 + g`` in the gyroscopic matrix.

    The off state ``g = 0`` leaves the model unchanged (gyroscopics as the geometry gives
    them); :meth:`disabled` (``g = −1``) removes gyroscopic coupling altogether.
    Signature: forward/backward split ∝ Ω J_p / J_d.
    """

    name: ClassVar[str] = "gyroscopics"
    bounds: ClassVar[dict[str, tuple[float, float]]] = {"g": (-1.0, 1.0)}
    off_params: ClassVar[dict[str, float]] = {"g": 0.0}
    g: float = 0.0

    @classmethod
    def disabled(cls) -> Gyroscopics:
        """Gyroscopics switched off entirely (``g = −1``)."""
        return cls(g=-1.0)

    def gyroscopic_scale(self) -> float:
        return 1.0 + self.g


@EFFECTS.register("unbalance_error")
@dataclass(frozen=True)
class UnbalanceError(Effect):
    """Unbalance magnitude/phase error ``U → (1 + ε) U e^{iδ}`` (δ in degrees).

    Signature: a uniform complex ratio of the 1x response at every speed.
    """

    name: ClassVar[str] = "unbalance_error"
    bounds: ClassVar[dict[str, tuple[float, float]]] = {
        "epsilon": (-0.9, 5.0), "delta_deg": (-180.0, 180.0)}
    off_params: ClassVar[dict[str, float]] = {"epsilon": 0.0, "delta_deg": 0.0}
    epsilon: float = 0.0
    delta_deg: float = 0.0

    def unbalance(self, U: np.ndarray) -> np.ndarray:
        return U * (1.0 + self.epsilon) * np.exp(1j * np.deg2rad(self.delta_deg))


@EFFECTS.register("tool_interface")
@dataclass(frozen=True)
class ToolInterface(Effect):
    """Tool-holder/spindle interface compliance: a zero-length joint at ``position_mm``
    (the spindle nose face) with translational ``k_t`` and rotational ``k_r`` stiffness; the
    tool holder and tool tip (items at that position) sit on the tool side. Its damping is the
    rotor's stiffness-proportional Rayleigh term (``β k``).

    Plausible ranges (HSK/steep-taper interfaces identified by receptance coupling:
    Schmitz & Smith, *Machining Dynamics*, 2nd ed., 2019, ch. 6; Namazi et al. 2007,
    IJMTM 47:1333; Özşahin et al. 2009, IJMTM 49:25): k_t ~ 1e7–1e9 N/m, k_r ~ 1e5–1e7 N m/rad
    (see ``docs/rig.md``). Both ``inf`` is off (rigid). Signature: tool-tip response and
    tool-side modes only; bearing-plane responses barely move.
    """

    name: ClassVar[str] = "tool_interface"
    bounds: ClassVar[dict[str, tuple[float, float]]] = {
        "k_t_N_per_m": (1e6, np.inf), "k_r_Nm_per_rad": (1e4, np.inf)}
    off_params: ClassVar[dict[str, float]] = {"k_t_N_per_m": np.inf, "k_r_Nm_per_rad": np.inf}
    position_mm: float = 0.0
    k_t_N_per_m: InfOff = np.inf
    k_r_Nm_per_rad: InfOff = np.inf

    def __post_init__(self) -> None:
        super().__post_init__()
        if np.isinf(self.k_t_N_per_m) != np.isinf(self.k_r_Nm_per_rad):
            raise ValueError(
                f"k_r_Nm_per_rad = {self.k_r_Nm_per_rad} is not allowed with k_t_N_per_m = "
                f"{self.k_t_N_per_m}: both finite, or both inf (off) (tool_interface)")

    def joint(self) -> Joint | None:
        if self.is_off:
            return None
        return Joint(self.position_mm, self.k_t_N_per_m, self.k_r_Nm_per_rad)
