"""The decisions and plans between the loop's parts (``docs/validation.md``, "The loop end to
end"), as functions of the :class:`~surrogate_rbrdo.loop.plan.LoopPlan` and the results of
the steps before (by step name, as the ``end_to_end`` kind stores them).

The campaign's records are in ``<run_dir>/campaign``; the identification of them
(:func:`identification_plan`) gives the study's θ (:func:`identified_theta`); the study's
chosen designs (:func:`validated_designs`) are measured on the rig against the model
(:func:`validation_plan_for`); the discrepancy workflow runs on the campaign when
:func:`discrepancy_reason` says so (:func:`discrepancy_plan`), and the model it updates is
optimised again when :func:`reoptimisation` finds that possible (:func:`study_plan` with
``updated``). The second round's results are stored as ``<name>_updated``
(:func:`round_results`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from surrogate_rbrdo.core.errors import ModelError
from surrogate_rbrdo.core.schema import parse
from surrogate_rbrdo.discrepancy.plan import DiscrepancyPlan
from surrogate_rbrdo.discrepancy.report import updated_spindle
from surrogate_rbrdo.identification.experiment import check_source
from surrogate_rbrdo.identification.plan import IdentificationPlan
from surrogate_rbrdo.loop.plan import UPDATED, LoopPlan
from surrogate_rbrdo.rig.truth import spindle_truth
from surrogate_rbrdo.spindle.config import SpindleTable
from surrogate_rbrdo.study.config import build_theta, identified_inputs, response_speeds
from surrogate_rbrdo.study.plan import StudyPlan, build_study, final_models
from surrogate_rbrdo.validation.campaign import file_label
from surrogate_rbrdo.validation.model import ModelSpec, Moments
from surrogate_rbrdo.validation.plan import ValidationPlan, validation_plan


def model_at_baseline(p: LoopPlan) -> Any:
    """The experimenter's model of the campaign's rotor: ``[spindle]`` at its baseline."""
    return p.study.problem.spindle.model(p.study.problem.baseline)


def identification_plan(p: LoopPlan, run_dir: Path) -> IdentificationPlan:
    """The identification of the campaign in ``run_dir/campaign`` (its checks included)."""
    campaign = run_dir / "campaign"
    try:
        dataset = check_source(campaign, p.identification)
    except ValueError as exc:
        raise ValueError(f"identification.{exc}") from None
    return IdentificationPlan(model_at_baseline(p), campaign, dataset, p.identification,
                              {"path": str(campaign), "kind": "end_to_end campaign stage"})


@dataclass(frozen=True, eq=False)
class IdentifiedTheta:
    """The study's θ: the identified stiffness block (``stiffness``), the full random vector
    (``inputs``, with the ``[uncertainty]`` unbalance block for ``peak_unbalance``), the
    response carrying θ's columns, and the provenance (file, SHA-256, speeds)."""

    stiffness: Any
    inputs: Any
    response: Any
    provenance: Mapping[str, Any]


def identified_theta(p: LoopPlan, identification_dir: Path) -> IdentifiedTheta:
    """``[uncertainty] from = <identification_dir>``: the study's θ as the ``study`` kind
    makes it (:func:`~surrogate_rbrdo.study.config.build_theta`)."""
    pr = p.study.problem
    t = replace(p.config.uncertainty, from_=str(identification_dir))
    inputs, response, prov = build_theta(t, pr.spindle, pr.response)
    block, _ = identified_inputs(t, pr.spindle.theta_bearings,
                                 response_speeds(pr.response, pr.spindle))
    return IdentifiedTheta(block, inputs, response, dict(prov))


def round_results(done: Mapping[str, Any], updated: bool) -> Mapping[str, Any]:
    """The results of one round under the names the study and validation steps read
    (``surrogate``, …, ``model``): the second round's are stored as ``<name>_updated``.

    >>> round_results({"verify": 1, "verify_updated": 2}, True)["verify"]
    2
    """
    if not updated:
        return done
    out = dict(done)
    out.update({k[:-len(UPDATED)]: v for k, v in done.items() if k.endswith(UPDATED)})
    return out


def spindle_section(p: LoopPlan) -> dict[str, Any]:
    """``[spindle]`` as given, with the baseline (what the discrepancy workflow updates)."""
    section = {k: v for k, v in dataclasses.asdict(p.config.spindle).items() if v is not None}
    section["baseline"] = [float(v) for v in p.study.problem.baseline]
    return section


def updated_study(p: LoopPlan, done: Mapping[str, Any]) -> StudyPlan:
    """The study's plan on the spindle the discrepancy workflow updated."""
    table = parse(SpindleTable, updated_spindle(spindle_section(p), p.study.problem.spindle
                                                .effects, done["discrepancy"].result), "spindle")
    return build_study(replace(p.config, spindle=table), p.base_dir)


def study_plan(p: LoopPlan, done: Mapping[str, Any], updated: bool = False
               ) -> StudyPlan | None:
    """The study's plan with the identified θ of step ``uncertainty``; with ``updated`` on
    the spindle the discrepancy workflow updated (``None`` unless step ``reoptimise`` found
    it can be optimised)."""
    base = p.study
    if updated:
        r = done.get("reoptimise")
        if r is None or not r.done:
            return None
        base = updated_study(p, done)
    th = done["uncertainty"]
    return replace(base, problem=replace(base.problem, inputs=th.inputs, response=th.response))


@dataclass(frozen=True)
class Reoptimisation:
    """Whether the updated model is optimised again (``done``) and why (``reason``)."""

    done: bool
    reason: str


def reoptimisation(p: LoopPlan, done: Mapping[str, Any]) -> Reoptimisation:
    """Whether the model the discrepancy workflow updated can be optimised again: it ran,
    named effects, and every design constraint of the study exists for the new spindle."""
    d = done["discrepancy"]
    if not p.config.loop.reoptimise:
        return Reoptimisation(False, "loop.reoptimise = false")
    if not d.ran:
        return Reoptimisation(False, f"the discrepancy workflow did not run ({d.reason})")
    named = [e.name for e in d.result.named_effects]
    if not named:
        return Reoptimisation(False, f"the discrepancy workflow named no effect (verdict "
                                     f"{d.result.verdict!r}): the model is unchanged")
    pr = updated_study(p, done).problem
    for k in pr.constraints:        # every design constraint must exist for the new spindle
        try:
            k.func(pr.baseline[None, :])
        except (ValueError, ModelError) as exc:
            return Reoptimisation(False, f"the study's design constraint {k.name!r} cannot be "
                                         f"evaluated on the updated spindle (with {named}): "
                                         f"{exc}")
    return Reoptimisation(True, f"the updated spindle adds {named}")


def validated_designs(p: LoopPlan, done: Mapping[str, Any]) -> dict[str, int]:
    """The study's chosen designs that are validated: name → row of the verification."""
    names = done["verify"].names
    want = p.config.loop.designs or ("baseline",) + tuple(
        n for n in names if n.startswith("rbrdo"))
    for n in want:
        if n not in names:
            raise ValueError(f"loop.designs: {n!r} is not a chosen design of the study; its "
                             f"designs: {list(names)}")
    if want[0] != "baseline":
        want = ("baseline",) + tuple(n for n in want if n != "baseline")
    return {n: names.index(n) for n in want}


def validation_plan_for(p: LoopPlan, done: Mapping[str, Any], updated: bool = False
                        ) -> ValidationPlan | None:
    """The validation of one round's designs on the rig (``None``: no such round). The
    truth is always the rig's (the model's spindle with the hidden effects); the model is
    the round's: its spindle, its FE verification."""
    d = round_results(done, updated)
    if updated and done.get("verify" + UPDATED) is None:
        return None
    ver, o, c = d["verify"], p.validation, p.config
    rows = validated_designs(p, d)
    labels = {n: file_label(n) for n in rows}
    designs = {labels[n]: tuple(float(v) for v in ver.X[i]) for n, i in rows.items()}
    model = None
    if c.model.compare:
        known = {labels[n]: {"peak": Moments.from_estimate(ver.fe, i, ver.n_theta,
                                                           o.confidence)}
                 for n, i in rows.items()}
        sur, _ = final_models(d)
        model = ModelSpec({"peak": sur.model.response}, done["uncertainty"].inputs,
                          c.model.n_samples, spindle_model=study_plan(p, done, updated)
                          .problem.spindle.model, known=known,
                          name="updated model" if updated else "model")
    spindle = p.study.problem.spindle
    template = spindle_truth(spindle, c.rig.hidden(), c.rig.variability)
    where = "study_updated" if updated else "study"
    source = {"designs": f"stage verify{UPDATED if updated else ''} ({where}/verification.csv)",
              "study_labels": labels,
              "known_from_study": f"peak: the FE verification of {where} (n_theta fresh θ)"}
    o = replace(o, baseline=labels["baseline"])
    return validation_plan(template, spindle, designs, o, model, source)


@dataclass(frozen=True, eq=False)
class DiscrepancyStage:
    """Whether the discrepancy workflow ran, why, and its result."""

    ran: bool
    reason: str
    result: Any = None


def discrepancy_reason(p: LoopPlan, done: Mapping[str, Any]) -> tuple[bool, str]:
    """Whether the discrepancy workflow runs (``[loop] discrepancy`` and the validation's
    disagreements, step ``model``) and why."""
    bad = done["model"].disagreements
    when = p.config.loop.discrepancy
    if when == "never" or (when == "on_disagreement" and not bad):
        return False, ("loop.discrepancy = 'never'" if when == "never" else
                       "the validation found no disagreement beyond uncertainty")
    return True, ("loop.discrepancy = 'always'" if when == "always" else
                  f"{len(bad)} model-vs-rig disagreement(s): "
                  + "; ".join(f"{v.design} {v.quantity} {v.metric}" for v in bad))


def discrepancy_plan(p: LoopPlan, run_dir: Path) -> DiscrepancyPlan:
    """The discrepancy workflow on the campaign in ``run_dir/campaign``: the model is
    ``[spindle]`` at the campaign's design (the study's baseline)."""
    pr = p.study.problem
    return DiscrepancyPlan(replace(pr.spindle, baseline=pr.baseline), spindle_section(p),
                           p.discrepancy, None, run_dir / "campaign", None)


__all__ = ["DiscrepancyStage", "IdentifiedTheta", "Reoptimisation", "discrepancy_plan",
           "discrepancy_reason", "identification_plan", "identified_theta", "model_at_baseline",
           "reoptimisation", "round_results", "spindle_section", "study_plan", "updated_study",
           "validated_designs", "validation_plan_for"]
