"""The data-driven loop's tables (:class:`EndToEndConfig`: the study's plus ``[rig]``,
``[identification]``, ``[validation]``, ``[model]``, ``[discrepancy]``, ``[loop]``) and the
checked plan of every part (:class:`LoopPlan`, :func:`build_loop`).

Tables: the study's (``[spindle]`` … ``[refine]``, :class:`~surrogate_rbrdo.study.plan.
StudyConfig`), ``[rig]`` (``RigTable`` without ``design``: the campaign's rotor is
``[spindle]``'s baseline), ``[identification]`` (``IdentificationOptions``; the source is the
loop's campaign), ``[validation]``, ``[model]`` and ``[loop]`` (:class:`LoopTable`).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from surrogate_rbrdo.core.validate import check_choice
from surrogate_rbrdo.discrepancy.experiment import DiscrepancyTable
from surrogate_rbrdo.identification.experiment import IdentificationOptions
from surrogate_rbrdo.rig.config import RigPlan, RigTable, rig_plan
from surrogate_rbrdo.rig.truth import spindle_truth
from surrogate_rbrdo.study.plan import StudyConfig, StudyPlan, build_study
from surrogate_rbrdo.validation.options import ValidationOptions
from surrogate_rbrdo.validation.plan import ModelTable, validation_options

#: the parts of the loop, in order: each draws from its own child of the experiment's seed
PARTS = ("rig", "identification", "study", "validation", "discrepancy")
DISCREPANCY_WHEN = ("on_disagreement", "always", "never")
#: repeats per speed the discrepancy workflow needs (``discrepancy.observables``)
MIN_REPEATS_DISCREPANCY = 5
#: speeds it needs (``discrepancy.holdout``: some are held out)
MIN_SPEEDS_DISCREPANCY = 8
#: suffix of the second round's stages (the model the discrepancy workflow updated)
UPDATED = "_updated"


@dataclass(frozen=True)
class LoopTable:
    """``[loop]``: which of the study's chosen designs are validated (default: the baseline
    and every RBRDO compromise) and when the discrepancy workflow runs
    (``"on_disagreement"``: when the validation finds model and rig disagreeing beyond
    uncertainty; ``"always"``; ``"never"``) and whether a model it updates (named effects) is
    optimised again and its designs validated on the rig (``reoptimise``)."""

    designs: tuple[str, ...] = ()
    discrepancy: str = "on_disagreement"
    reoptimise: bool = True

    def __post_init__(self) -> None:
        check_choice("discrepancy", self.discrepancy, DISCREPANCY_WHEN)
        if len(set(self.designs)) != len(self.designs):
            raise ValueError(f"designs = {list(self.designs)} is not allowed: a name appears "
                             "twice")


@dataclass(frozen=True)
class EndToEndConfig(StudyConfig):
    """The study's tables plus the rig, identification, validation and the loop's."""

    rig: RigTable = field(default_factory=RigTable)
    identification: IdentificationOptions = field(default_factory=IdentificationOptions)
    validation: ValidationOptions = field(default_factory=ValidationOptions)
    model: ModelTable = field(default_factory=ModelTable)
    discrepancy: DiscrepancyTable = field(default_factory=DiscrepancyTable)
    loop: LoopTable = field(default_factory=LoopTable)


@dataclass(frozen=True, eq=False)
class LoopPlan:
    """The validated objects of every part (the study's with the configured θ, replaced by
    the identified one in step ``uncertainty``)."""

    config: EndToEndConfig
    rig: RigPlan
    study: StudyPlan
    identification: IdentificationOptions
    validation: Any
    discrepancy: Any
    disk_need: tuple[str, Any, float, str]
    base_dir: Path


def _check_agreement(c: EndToEndConfig, o: Any, spindle: Any) -> None:
    """The validation measures what the study optimised: its δ_lim and speed range."""
    g = spindle.geometry
    if o.delta_lim_um != c.limit.delta_lim_um:
        raise ValueError(f"validation.delta_lim_um = {o.delta_lim_um} is not allowed: the study "
                         f"has limit.delta_lim_um = {c.limit.delta_lim_um}")
    if tuple(o.speed_range_rpm) != (g.speed_min_rpm, g.speed_max_rpm):
        raise ValueError(f"validation.speed_range_rpm = {list(o.speed_range_rpm)} is not allowed:"
                         f" the study's y is the peak over [{g.speed_min_rpm}, "
                         f"{g.speed_max_rpm}] rpm")
    if c.response.kind == "at_speed":
        raise ValueError("response.kind = 'at_speed' is not allowed: the loop validates the "
                         "peak over the range (use 'peak_unbalance' or 'peak')")


def _check_discrepancy_data(loop: LoopTable, o: Any) -> None:
    """The campaign holds what the discrepancy workflow needs (unless it never runs)."""
    if loop.discrepancy == "never":
        return
    why = (f"with loop.discrepancy = {loop.discrepancy!r}: the discrepancy workflow needs >= "
           "{} {} (or set loop.discrepancy = 'never')")
    if o.repeats < MIN_REPEATS_DISCREPANCY:
        raise ValueError(f"rig.campaign.repeats = {o.repeats} is not allowed "
                         + why.format(MIN_REPEATS_DISCREPANCY, "repeats (the noise)"))
    if len(o.speeds_rpm) < MIN_SPEEDS_DISCREPANCY:
        raise ValueError(f"rig.campaign.speeds_rpm has {len(o.speeds_rpm)} speeds: not allowed "
                         + why.format(MIN_SPEEDS_DISCREPANCY, "speeds (some are held out)"))


def build_loop(c: EndToEndConfig, base_dir: str | Path = ".") -> LoopPlan:
    """The checked plan of every part of the loop (errors name the dotted path): the
    study's (:func:`~surrogate_rbrdo.study.plan.build_study`; its θ's stiffness block is
    the identification's), the rig's campaign at the study's baseline with trial weights,
    the identification, the validation (measuring what the study optimised) and the
    discrepancy workflow (the data it needs, unless it never runs)."""
    given = [k for k in ("from_", "mean", "std", "corr") if getattr(c.uncertainty, k) is not None]
    if given:
        v = getattr(c.uncertainty, given[0])
        v = [list(r) if isinstance(r, tuple) else r for r in v] if isinstance(v, tuple) else v
        raise ValueError(f"uncertainty.{given[0].rstrip('_')} = {v!r} is not allowed: the loop's "
                         "stiffness block is this run's identification (uncertainty.from is "
                         "set by stage 'uncertainty'); keep distribution, thermal_max, unbalance")
    study = build_study(c, base_dir)
    spindle = study.problem.spindle
    if c.rig.design is not None:
        raise ValueError(f"rig.design = {list(c.rig.design)} is not allowed: the campaign's "
                         "rotor is [spindle]'s baseline (report.baseline)")
    cfg = c.rig.config()
    truth = spindle_truth(spindle, c.rig.hidden(), c.rig.variability, study.problem.baseline)
    rig = rig_plan(replace(cfg, truth=truth), c.rig.effects)
    if cfg.options.trial_unbalance is None and c.identification.excitation == "trial":
        raise ValueError("rig.campaign.trial_unbalance = None is not allowed: the "
                         "identification uses trial-weight differences; give the trial mass "
                         "[position mm, kg m, phase deg], e.g. [0.0, 5e-5, 0.0]")
    _check_discrepancy_data(c.loop, cfg.options)
    ident = c.identification
    n_coef = 4 if ident.fit_on == "stiffness" else 8      # per bearing pair: k (and c) yy, zz
    if cfg.options.repeats < n_coef + 2:
        raise ValueError(f"rig.campaign.repeats = {cfg.options.repeats} is not allowed: the "
                         f"identification's scatter fit over runs needs >= {n_coef + 2} repeats"
                         f" for identification.fit_on = {ident.fit_on!r} ({n_coef} "
                         "coefficients + 2)")
    o = validation_options(c.rig, c.validation)
    _check_agreement(c, o, spindle)
    disc = c.discrepancy.options()
    return LoopPlan(c, rig, study, ident, o, disc, rig.disk_need, Path(base_dir))


__all__ = ["DISCREPANCY_WHEN", "UPDATED", "EndToEndConfig", "LoopPlan", "LoopTable",
           "MIN_REPEATS_DISCREPANCY", "MIN_SPEEDS_DISCREPANCY", "PARTS", "build_loop"]
