"""A validation run on two designs whose truth is known in closed form.

The truth: the reference spindle with no hidden effect, one unbalance plane (the tool holder)
and only one source of scatter — the residual unbalance, a fraction f ~ U(0.25, 1) of the
rotor's ISO permissible value. The response is linear in the unbalance, so with ``c`` the FE
peak amplitude of a design at f = 1, its ``y = c f`` exactly:

    μ = c (0.25 + 1)/2,  σ = c (1 − 0.25)/√12,  P_f = P(f > δ/c) = (1 − δ/c)/0.75,

and for a pair of designs with independent balancing, d = y_b − y_a has
``d_z = (μ_b − μ_a)/√(σ_a² + σ_b²)``; with the same balancing fraction (shared), d = (c_b − c_a) f
and ``d_z = −0.625/0.2165 = −2.887`` while ``σ_b/σ_a = c_b/c_a`` exactly.
``c`` comes from the FE model's own peak search — no sensor, no replication, no statistics.
"""

from dataclasses import replace

import numpy as np
import pytest

from surrogate_rbrdo.rig.sensors import ProbeModel, SensorSet
from surrogate_rbrdo.rig.truth import Truth, Variability
from surrogate_rbrdo.spindle.harmonic import PeakOptions, peak_tool_amplitude
from surrogate_rbrdo.spindle.reference import reference_spindle
from surrogate_rbrdo.uncertainty import Independent, Uniform
from surrogate_rbrdo.validation.campaign import validate_designs
from surrogate_rbrdo.validation.model import ModelSpec
from surrogate_rbrdo.validation.options import ValidationOptions
from surrogate_rbrdo.validation.replicas import TruthFamily

LO, HI = 0.25, 1.0
DESIGNS = {"baseline": [2000.0, 500.0, 65.0], "short": [3000.0, 350.0, 75.0]}
PEAK = PeakOptions(n_grid=24, n_candidates=2, n_refine=11, n_zoom=3)


def _family() -> TruthFamily:
    sp = reference_spindle()
    g = sp.geometry
    geom = replace(g, unbalances=(g.unbalances[0],))        # the tool-holder plane only
    var = Variability(0.0, 0.0, 2.5, (LO, HI), 0.0, 0.0, 0.0)
    return TruthFamily(Truth(geom, sp.effects, (), var, sp.theta_bearings), sp.design_map)


def _c(fam: TruthFamily, x) -> float:
    """FE peak tool amplitude of design x at the full permissible unbalance (f = 1)."""
    t = fam.at(x)
    st = t.apply({"k_factor": [1.0, 1.0], "damping_factor": [1.0, 1.0],
                  "unbalance_kgm": [t.permissible_unbalance_kgm()], "unbalance_phase_deg": [0.0]},
                 {"mass_factor": 1.0, "interface_factor": [1.0, 1.0]},
                 {"preload_factor": [1.0, 1.0]})
    return float(peak_tool_amplitude(st.model(), st.theta, options=PEAK).amplitude[0])


class LinearModel:
    """The exact model of this truth: y(x, f) = c(x) f (times ``bias``)."""

    def __init__(self, c: dict, bias: float = 1.0) -> None:
        self.c, self.bias = c, bias

    def __call__(self, x, theta):
        cx = np.array([self.c[tuple(v)] for v in np.asarray(x).tolist()])
        return self.bias * cx[:, None] * theta[:, 0][None, :]


@pytest.fixture(scope="module")
def setup():
    fam = _family()
    c = {k: _c(fam, x) for k, x in DESIGNS.items()}
    delta_um = 0.6 * c["baseline"] * 1e6                  # P_f,baseline = 0.4 / 0.75
    sensors = SensorSet(probe=ProbeModel(gain_error_sd=0.0))
    opts = ValidationOptions(n_replications=20, delta_lim_um=delta_um, ramps=0, n_boot=2000,
                             speeds_rpm={"start": 1000, "stop": 24000, "step": 1000},
                             peak=PEAK, sensors=sensors, calibration_u=0.0, band_samples=20)
    return fam, c, delta_um, opts


def _truth(c, delta_um):
    mu = {k: v * (LO + HI) / 2 for k, v in c.items()}
    sd = {k: v * (HI - LO) / np.sqrt(12) for k, v in c.items()}
    pf = {k: float(np.clip((HI - delta_um * 1e-6 / v) / (HI - LO), 0, 1)) for k, v in c.items()}
    return mu, sd, pf


def _model(c, bias=1.0):
    by_x = {tuple(DESIGNS[k]): v for k, v in c.items()}
    return ModelSpec({"peak": LinearModel(by_x, bias)}, Independent([Uniform(LO, HI)]),
                     n_samples=4000)


@pytest.mark.known_answer
def test_independent_balancing_recovers_moments_ordering_and_effect_size(setup):
    fam, c, delta_um, opts = setup
    res = validate_designs(fam, DESIGNS, options=opts, rng=np.random.default_rng(21),
                           model=_model(c))
    mu, sd, pf = _truth(c, delta_um)
    assert 0.5 < pf["baseline"] < 0.55 and pf["short"] == 0.0
    for d in res.designs:
        m = d.moments["peak"]
        assert m.mean_ci[0] < mu[d.name] < m.mean_ci[1]
        assert m.std_ci[0] < sd[d.name] < m.std_ci[1]
        assert m.pf_ci[0] <= pf[d.name] <= m.pf_ci[1]
    comp = next(k for k in res.comparisons if k.quantity == "peak")
    assert comp.mean.bootstrap_diff_ci[1] < 0 and comp.mean.diff_ci[1] < 0   # right ordering
    dz = (mu["short"] - mu["baseline"]) / np.hypot(sd["short"], sd["baseline"])
    assert comp.mean.d_z_ci[0] < dz < comp.mean.d_z_ci[1]
    lo, hi = comp.std.ratio_ci
    assert lo < sd["short"] / sd["baseline"] < hi
    assert comp.pf.diff_ci[0] < pf["short"] - pf["baseline"] < comp.pf.diff_ci[1]
    # the exact model agrees with the rig on every quantity
    assert res.verdicts and all(v.agree for v in res.verdicts)


@pytest.mark.known_answer
def test_shared_balancing_gives_the_closed_form_pairing(setup):
    fam, c, delta_um, opts = setup
    o = replace(opts, shared=("bearings", "tool", "thermal", "unbalance_magnitude"))
    res = validate_designs(fam, DESIGNS, options=o, rng=np.random.default_rng(22))
    comp = next(k for k in res.comparisons if k.quantity == "peak")
    dz = -((LO + HI) / 2) / ((HI - LO) / np.sqrt(12))
    assert dz == pytest.approx(-2.8868, abs=1e-4)
    assert comp.mean.d_z_ci[0] < dz < comp.mean.d_z_ci[1]
    # y_short = (c_short / c_base) y_base replication by replication (noise ~1e-4)
    assert comp.std.correlation > 0.999
    assert comp.std.ratio == pytest.approx(c["short"] / c["baseline"], rel=0.02)


@pytest.mark.known_answer
def test_a_biased_model_is_flagged(setup):
    # μ's standard error at n = 20 is 7.8 % of μ here (σ/μ = 0.35); a 50 % bias is 6 SE
    fam, c, delta_um, opts = setup
    res = validate_designs(fam, DESIGNS, options=opts, rng=np.random.default_rng(21),
                           model=_model(c, bias=1.5))
    bad = {(v.design, v.metric) for v in res.disagreements}
    assert ("baseline", "mean") in bad and ("short", "mean") in bad
    assert all(v.quantity == "peak" for v in res.verdicts)
