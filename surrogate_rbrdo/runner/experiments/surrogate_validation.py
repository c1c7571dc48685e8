"""Experiment kind ``surrogate_validation``: surrogate structures against the full FE model.

The tables and their checks are :mod:`surrogate_rbrdo.study.assessment`'s (``[surrogate]`` is
variant ``main``, ``[validation.variants]`` adds overrides of it). Every variant trains from
the same seed stream, so variants with the same DOE settings get the same DOE, and the FE
cache is shared. Stages: ``truth`` (FE at ``n_test`` fresh LHS points of the joint box,
full-FE MC at the ``designs`` on ``n_theta`` θ, FE resonance quantities if a resonance
variant needs them) → ``variants`` (train, test points, LOO, MC comparison). Tables
(``reporting.plots_surrogate.write_assessment_run``): ``metrics.csv``, ``loo.csv``,
``mc_comparison.csv``, ``cost.csv`` (the FE evaluations each training used, counted at the
sampler: computed now or loaded from the FE cache, so the table is the same on a rerun; and
the P_f accuracy; no timings), ``resonance_submodels.csv`` and ``nc_at_designs.csv``
(resonance variants), parity figures per variant. ``calls.json`` (and ``meta.json``) split
the counts into FE calls computed and cache hits, per stage and variant. ``y`` is the
``[response]`` (default the peak amplitude of the geometry's unbalance; ``kind =
"peak_unbalance"``: the credible problem's random-unbalance peak, θ with its unbalance columns
from ``[uncertainty]``, the FE side the FE model's own peak search).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from surrogate_rbrdo.reporting.plots_surrogate import write_assessment_run
from surrogate_rbrdo.runner.kinds import Kind, Stage, StageContext, register_kind
from surrogate_rbrdo.sampling.fe import fe_cache
from surrogate_rbrdo.study.assessment import (
    AssessmentPlan,
    SurrogateValidationConfig,
    build_assessment,
)
from surrogate_rbrdo.surrogates.assessment import Assessment, FETruth, fe_truth, train_and_assess


def _truth(p: AssessmentPlan, done: Mapping[str, Any], ctx: StageContext) -> FETruth:
    need_res = any(v.structure == "resonance" for v in p.variants.values())
    return fe_truth(p.spindle, p.inputs, np.vstack(list(p.designs.values())), p.test_box,
                    n_test=p.validation.n_test, n_theta=p.validation.n_theta,
                    rng_test=ctx.stream(1), rng_theta=ctx.stream(2),
                    n_theta_nc=p.validation.n_theta_nc if need_res else None,
                    cache=fe_cache(ctx.cache_dir), mc_cache=fe_cache(ctx.cache_dir, "fe_mc"),
                    progress=ctx.progress, label=ctx.label, response=p.response)


def _variants(p: AssessmentPlan, done: Mapping[str, Any], ctx: StageContext
              ) -> tuple[Assessment, ...]:
    """Every variant trained from the same seed stream (same DOE settings, same DOE)."""
    return tuple(train_and_assess(
        name, p.spindle, p.inputs, p.limit, options, done["truth"], rng=ctx.stream(0),
        cache=fe_cache(ctx.cache_dir), rel_tol=p.validation.rel_tol, progress=ctx.progress,
        label=ctx.label, response=p.response) for name, options in p.variants.items())


register_kind(Kind(
    name="surrogate_validation",
    summary="surrogate variants (structures, transforms, active learning) against the full "
            "FE model: test-point metrics, LOO, μ/σ/P_f at designs, cost",
    schema=SurrogateValidationConfig,
    stages=(Stage("truth", _truth), Stage("variants", _variants)),
    report=lambda p, done, run, ctx: write_assessment_run(run, p, done["truth"],
                                                          done["variants"]),
    build=build_assessment,
))
