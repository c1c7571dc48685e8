"""The ``[rig]`` table of an experiment config: its schema, and the truth and campaign options
it describes.

The tables are frozen dataclasses; the runner checks a config's ``[rig]`` against them
(pydantic, strict: every key, type and range, errors naming the dotted path), and a Python
user constructs them directly. Everything has a documented default (``docs/rig.md``); the
truth's hidden effects are ``effects = [{ name = "<registry name>", <parameters> }, ...]``,
the same form as ``[spindle] effects``.

* :class:`RigTruthTable` — the truth and how it is measured: ``effects``, ``variability``
  (:class:`~surrogate_rbrdo.rig.truth.Variability`), ``sensors``
  (:class:`~surrogate_rbrdo.rig.sensors.SensorSet`); the ``[rig]`` of a validation.
* :class:`RigTable` — adds the campaign: ``design`` (``[F N, L mm, D mm]`` of the truth,
  default the reference baseline), ``campaign``
  (:class:`~surrogate_rbrdo.rig.campaign.CampaignOptions` without ``sensors``) and
  ``figures``; the ``[rig]`` of a rig campaign.

>>> t = RigTable(effects=({"name": "cross_coupling", "kappa": 0.05},),
...              campaign=CampaignOptions(repeats=2))
>>> cfg = t.config()
>>> [e.name for e in cfg.truth.hidden], cfg.options.repeats, len(cfg.options.speeds_rpm)
(['cross_coupling'], 2, 50)
>>> RigTable(design=(2000.0, 900.0, 65.0))
Traceback (most recent call last):
...
ValueError: design span_mm = 900.0 is not allowed: must lie in [300.0, 750.0]
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from surrogate_rbrdo.core.errors import ModelError
from surrogate_rbrdo.core.memory import require_memory
from surrogate_rbrdo.core.validate import check_int
from surrogate_rbrdo.rig.campaign import (
    CampaignOptions,
    footprint,
    soak_speed,
    stability_speeds,
)
from surrogate_rbrdo.rig.demod import check_record_lengths
from surrogate_rbrdo.rig.sensors import SensorSet
from surrogate_rbrdo.rig.simulate import check_nominal_stable
from surrogate_rbrdo.rig.truth import Truth, Variability, reference_truth
from surrogate_rbrdo.spindle.effects import Effect, effect_from_dict
from surrogate_rbrdo.spindle.reference import reference_spindle


@dataclass(frozen=True)
class RigConfig:
    """A ``[rig]`` table made into objects: the truth, the campaign options (with the
    sensors) and whether to draw figures."""

    truth: Truth
    options: CampaignOptions
    figures: bool = True
    n_jobs: int = 1


@dataclass(frozen=True)
class RigTruthTable:
    """The rig's truth and its sensors: hidden ``effects`` (added to the reference spindle's
    own), ``variability``, ``sensors``."""

    effects: tuple[dict[str, Any], ...] = ()
    variability: Variability = field(default_factory=Variability)
    sensors: SensorSet = field(default_factory=SensorSet)

    def __post_init__(self) -> None:
        self.hidden()

    def hidden(self) -> tuple[Effect, ...]:
        """The hidden effects (each checked: registry name, parameters)."""
        out = []
        for i, e in enumerate(self.effects):
            try:
                out.append(effect_from_dict(dict(e)))
            except (TypeError, ValueError) as exc:
                raise ValueError(f"effects[{i}]: {exc}") from None
        return tuple(out)

    def truth(self, x: np.ndarray | None = None) -> Truth:
        """The reference spindle (design ``x``, default the baseline) as the rig's truth."""
        return reference_truth(self.hidden(), self.variability, x)


@dataclass(frozen=True)
class RigTable(RigTruthTable):
    """A rig campaign's ``[rig]``: the truth, its ``design``, the ``campaign`` (its sensors
    are ``[rig.sensors]``), ``figures`` and ``n_jobs``: worker processes for the steady runs
    and the ramps (``rig.campaign.run_campaign``; the records are the same for any value; the
    impact records share one simulation per speed and direction, made in the main process)."""

    design: tuple[float, float, float] | None = None
    campaign: CampaignOptions = field(default_factory=CampaignOptions)
    figures: bool = True
    n_jobs: int = 1

    def __post_init__(self) -> None:
        super().__post_init__()
        check_int("n_jobs", self.n_jobs, minimum=1)
        if self.campaign.sensors != SensorSet():
            raise ValueError("campaign.sensors is not allowed: the sensors are [rig.sensors]")
        if self.design is not None:     # "design span_mm = 900.0 is not allowed: ..."
            reference_spindle().design_map.check(np.asarray(self.design, float))

    def config(self) -> RigConfig:
        """The truth (at ``design``) and the campaign options with ``sensors``."""
        x = None if self.design is None else np.asarray(self.design, float)
        return RigConfig(self.truth(x), replace(self.campaign, sensors=self.sensors),
                         self.figures, self.n_jobs)


@dataclass(frozen=True, eq=False)
class RigPlan:
    """A checked campaign: the truth and options (``rig``) and the disk it needs
    (``disk_need = (field, value, bytes, what)``, checked against the results root)."""

    rig: RigConfig
    disk_need: tuple[str, Any, float, str]


#: the fastest a rig campaign may run a spindle, as a multiple of its ``speed_max_rpm``: an
#: overspeed test runs at 1.15 x the maximum continuous speed (API 617 section 4.3.3 and
#: API RP 684), Campbell sweeps a little beyond; 1.5 x leaves room for both, faster is
#: outside any rig test (and outside the bearing laws' fitted range)
RIG_SPEED_FACTOR = 1.5


def check_rig_speeds(options: CampaignOptions, speed_max_rpm: float) -> None:
    """Refuse campaign speeds (steady, impact, soak and ramp) above :data:`RIG_SPEED_FACTOR` x
    the spindle's ``speed_max_rpm`` (``ValueError`` naming ``campaign.speeds_rpm[i]``,
    ``campaign.impact_speeds_rpm[i]``, ``campaign.soak.speed_rpm``,
    ``campaign.soak.speeds_rpm[i]`` or ``campaign.runup``)."""
    top = RIG_SPEED_FACTOR * speed_max_rpm
    why = (f"must be at most {top:g} rpm, {RIG_SPEED_FACTOR:g} x the spindle's speed_max_rpm "
           f"= {speed_max_rpm:g} (an overspeed test runs at 1.15 x)")
    for i, v in enumerate(options.speeds_rpm):
        if v > top:
            raise ValueError(f"campaign.speeds_rpm[{i}] = {v:g} is not allowed: {why}")
    for i, v in enumerate(options.impact_speeds_rpm):
        if v > top:
            raise ValueError(f"campaign.impact_speeds_rpm[{i}] = {v:g} is not allowed: {why}")
    soak = options.soak
    if soak is not None and soak.speed_rpm is not None and soak.speed_rpm > top:
        raise ValueError(f"campaign.soak.speed_rpm = {soak.speed_rpm:g} is not allowed: {why}")
    for i, s in enumerate(() if soak is None else soak.speeds_rpm):
        if s > top:
            raise ValueError(f"campaign.soak.speeds_rpm[{i}] = {s:g} is not allowed: {why}")
    if options.runup is not None and options.runup[1] > top:
        raise ValueError(f"campaign.runup = {list(options.runup)} is not allowed: end_rpm {why}")


def rig_plan(cfg: RigConfig, effects: Any = ()) -> RigPlan:
    """The checks before work (the nominal truth stable at the campaign's speeds, memory) and
    the disk the campaign needs, for a truth and campaign made into objects (``[rig]``'s
    ``effects`` named in the error)."""
    o = cfg.options
    try:        # the sample rate against the top speed (the record lengths: CampaignOptions)
        check_rig_speeds(o, cfg.truth.geometry.speed_max_rpm)
        check_record_lengths(o.duration_s, o.speeds_rpm + soak_speed(o),
                             o.sensors.daq.sample_rate_hz, o.runup)
    except ValueError as exc:
        raise ValueError(f"rig.{exc}") from None
    sp = stability_speeds(o)       # the campaign checks them all for each tool
    try:
        check_nominal_stable(cfg.truth, np.linspace(sp[0], sp[-1], 12))
    except ModelError as exc:
        raise ValueError(f"rig.effects = {list(effects)} is not allowed: {exc}") from None
    fp = footprint(o)
    require_memory(f"rig.campaign.{fp.memory_by}", getattr(o, fp.memory_by), fp.memory_bytes,
                   "its records (a run's steady records, a ramp or an impact held at once)")
    return RigPlan(cfg, ("rig.campaign.repeats", o.repeats, fp.disk_bytes,
                         f"{fp.n_records} records ({len(o.speeds_rpm)} speeds x repeats x "
                         f"{o.duration_s:g} s, ramps, impacts)"))


__all__ = ["RIG_SPEED_FACTOR", "RigConfig", "RigPlan", "RigTable", "RigTruthTable",
           "check_rig_speeds", "rig_plan"]
