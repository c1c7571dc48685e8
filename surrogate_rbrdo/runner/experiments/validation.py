"""Experiment kind ``validation``: designs built and measured on the virtual rig, compared
with each other (Table 7) and with the model (``docs/validation.md``).

The tables are :class:`~surrogate_rbrdo.validation.plan.ValidationConfig`'s (``[rig]``,
``[validation]``, ``[designs]`` — given, or ``from`` a study run folder —, ``[model]``,
``[spindle]``, ``[uncertainty]``), checked by
:func:`~surrogate_rbrdo.validation.plan.build_validation`. Stages: ``measure``
(``validation.measure_designs``) → ``model`` (``validation.add_model``); both draw from
stream 0 of the seed, addressed by key.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from surrogate_rbrdo.reporting.plots_validation import (
    validation_summary,
    write_validation_report,
)
from surrogate_rbrdo.runner.kinds import Kind, Stage, StageContext, register_kind
from surrogate_rbrdo.validation import add_model, measure_designs
from surrogate_rbrdo.validation.plan import ValidationConfig, ValidationPlan, build_validation


def measure(p: ValidationPlan, done: Mapping[str, Any], ctx: StageContext) -> Any:
    with ctx.bar("validation: measuring on the rig", "replication") as progress:
        return measure_designs(p.family, p.designs, options=p.options, rng=ctx.stream(0),
                               progress=progress)


def model(p: ValidationPlan, done: Mapping[str, Any], ctx: StageContext) -> Any:
    res = done["measure"]
    if p.model is None:
        return res
    with ctx.bar("validation: the model's moments, band and Campbell", "part") as progress:
        progress(0, 1, f"{len(p.designs)} designs, {p.model.n_samples} θ samples")
        return add_model(res, p.model, rng=ctx.stream(0))


def _report(p: ValidationPlan, done: Mapping[str, Any], run: Any, ctx: StageContext
            ) -> dict[str, Any]:
    write_validation_report(done["model"], run.path)
    run.write_json("designs_source.json", p.source)
    return validation_summary(done["model"])


register_kind(Kind(
    name="validation",
    summary="designs built on the virtual rig's truth and measured over paired replications: "
            "Table 7 (paired t, d_z, Wilcoxon, McNemar, bootstrap), model vs measurement, "
            "Fig. 7/8 analogues",
    schema=ValidationConfig,
    stages=(Stage("measure", measure), Stage("model", model)),
    report=_report,
    build=build_validation,
))
