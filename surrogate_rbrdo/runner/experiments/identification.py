"""Experiment kind ``identification``: bearing coefficients and the study's uncertainty model
from a campaign's records (``docs/identification.md`` §8).

The tables (``[identification]`` with its ``source``, ``[spindle]``) and their checks are
:mod:`surrogate_rbrdo.identification.plan`'s. Stages: ``demodulate``
(``identification.read_responses``: 1× phasors of every steady record, trial-weight
differences) → ``identify`` (``identification.identify_responses``: every record, trend,
scatter, tests; stream 0 of the seed drives the bootstrap); ``--resume`` loads both. The
report (``reporting.plots_identification.write_identification_run``) writes
``identified.csv``, ``uncertainty.json`` (what ``[uncertainty] from`` of a study reads),
``identification_summary.json`` and the figures (Fig. 1 convergence, Fig. 3 trend ±2σ, Fig. 4
Q–Q).
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from typing import Any

from surrogate_rbrdo.identification.experiment import identify_responses, read_responses
from surrogate_rbrdo.identification.plan import (
    IdentificationConfig,
    IdentificationPlan,
    build_identification,
)
from surrogate_rbrdo.reporting.plots_identification import write_identification_run
from surrogate_rbrdo.runner.kinds import Kind, Stage, StageContext, register_kind


def demodulate(p: IdentificationPlan, done: Mapping[str, Any], ctx: StageContext) -> Any:
    t0 = time.perf_counter()
    resp = read_responses(p.dataset, p.options)
    return resp, time.perf_counter() - t0


def identify(p: IdentificationPlan, done: Mapping[str, Any], ctx: StageContext) -> Any:
    resp, seconds = done["demodulate"]
    return identify_responses(p.model, resp, p.options, rng=ctx.stream(0), source=p.dataset,
                              demodulation_s=seconds)


register_kind(Kind(
    name="identification",
    summary="bearing coefficients identified from a campaign's records (trial-weight "
            "differences, FE condensation): identified.csv, uncertainty.json (speed trend, "
            "physical scatter, tests; a study's [uncertainty] from), Fig. 1/3/4 analogues",
    schema=IdentificationConfig,
    stages=(Stage("demodulate", demodulate), Stage("identify", identify)),
    report=lambda p, done, run, ctx: write_identification_run(run, p, done["identify"]),
    build=build_identification,
))
