"""A stage's candidate fits: the same on worker processes as in this one."""

from __future__ import annotations

import numpy as np
import pytest

from surrogate_rbrdo.discrepancy.candidates import candidate
from surrogate_rbrdo.discrepancy.forward import ForwardModel
from surrogate_rbrdo.discrepancy.naming import fit_all
from surrogate_rbrdo.discrepancy.problem import Problem
from surrogate_rbrdo.discrepancy.search import fit_nuisance, warm_base
from surrogate_rbrdo.discrepancy.workflow import DiscrepancyOptions
from surrogate_rbrdo.spindle.effects import EFFECTS

from .conftest import campaign_data


def test_candidate_fits_on_two_workers_are_those_of_one_process(spindle):
    """The fits draw no random numbers and share nothing but their inputs, so on two loky
    workers every candidate's parameters and χ² are bit for bit those of the serial loop,
    in the candidates' order."""
    sp, g = spindle
    data, _ = campaign_data(spindle, (EFFECTS["gyroscopics"](g=0.3),), seed=3)
    prob = Problem(ForwardModel(g, sp.effects, data.channels, (0.0, 350.0)), data)
    base = fit_nuisance(prob)
    cands = [candidate(n, prob.forward.bearing_names)
             for n in ("gyroscopics", "unbalance_error", "anisotropy")]
    warm = warm_base(prob, base, max_nfev=60)
    kw = {"max_nfev": 60, "confound_delta": 6.63}
    serial = fit_all(prob, base, cands, warm, n_jobs=1, **kw)
    parallel = fit_all(prob, base, cands, warm, n_jobs=2, **kw)
    assert [f.name for f in parallel] == [c.name for c in cands]
    for a, b in zip(serial, parallel, strict=True):
        assert np.array_equal(a.fit.x, b.fit.x) and a.fit.chi2 == b.fit.chi2
    assert serial[0].delta_chi2 > serial[1].delta_chi2      # the hidden one fits best


def test_n_jobs_is_checked():
    with pytest.raises(ValueError, match="n_jobs = 0"):
        DiscrepancyOptions(n_jobs=0)
