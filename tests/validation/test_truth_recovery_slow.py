"""With the rig's full variability model, the validation's measured μ, σ, P_f cover the truth's
own values, computed independently: many truth states through the FE peak search, no sensors."""

import numpy as np
import pytest
from scipy import stats

from surrogate_rbrdo.spindle.harmonic import peak_tool_amplitude
from surrogate_rbrdo.validation import ValidationOptions, reference_family, validate_designs
from surrogate_rbrdo.validation.replicas import replica_states

DESIGNS = {"baseline": [2000.0, 465.8, 65.0], "rbrdo5": [3000.0, 477.4, 71.8]}


@pytest.mark.slow
@pytest.mark.known_answer
def test_measured_moments_cover_the_truths():
    fam = reference_family()
    states = replica_states(fam, DESIGNS, 400, seed=np.random.SeedSequence(99))
    truth = {k: np.array([peak_tool_amplitude(s.model(), s.theta).amplitude[0] for s in v])
             for k, v in states.items()}
    o = ValidationOptions(ramps=0, n_boot=2000, calibration_u=None)
    res = validate_designs(fam, DESIGNS, options=o, rng=np.random.default_rng(5))
    for d in res.designs:
        y, m = truth[d.name], d.moments["peak"]
        # compare with the uncertainty of both sides (the truth's MC with 400 states),
        # plus the installation's gain error (2 % SD per probe)
        u = np.sqrt(m.mean_se**2 + (y.std(ddof=1) / np.sqrt(y.size))**2 + (0.02 * m.mean)**2)
        assert abs(m.mean - y.mean()) < 3 * u
        u_sd = np.sqrt(m.std_se**2 + (0.02 * m.std)**2)
        assert abs(m.std - y.std(ddof=1)) < 3 * u_sd + 3 * y.std(ddof=1) / np.sqrt(2 * y.size)
        pf_true = np.mean(y > o.delta_lim_m)
        k = round(m.pf * m.n)
        assert stats.binomtest(k, m.n, np.clip(pf_true, 1e-3, 1 - 1e-3)).pvalue > 0.001
