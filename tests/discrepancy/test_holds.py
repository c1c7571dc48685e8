"""The candidate search: shape parameters on a bound are tried inside (``holds.interior``).

The fits on a bound are *converged* fits with the shapes pinned there (a fit of the rest with
the shapes held on their bounds, then described with them free), and the rule is checked
against an independent loop of held fits: the bound fit is replaced by the best physical held
fit iff that fit's χ² exceeds the bound fit's by at most the χ² margin for the number held.
"""

from __future__ import annotations

from dataclasses import replace
from types import SimpleNamespace

import numpy as np
import pytest
from scipy.optimize import lsq_linear
from scipy.special import log_ndtr
from scipy.stats import chi2

from surrogate_rbrdo.discrepancy import naming
from surrogate_rbrdo.discrepancy.calibration import Linearisation
from surrogate_rbrdo.discrepancy.candidates import candidate
from surrogate_rbrdo.discrepancy.fit import Fit, fit, jacobian
from surrogate_rbrdo.discrepancy.forward import ForwardModel
from surrogate_rbrdo.discrepancy.holds import held_options, hold_threshold, interior
from surrogate_rbrdo.discrepancy.nuisance import Slot
from surrogate_rbrdo.discrepancy.problem import Problem
from surrogate_rbrdo.discrepancy.rivals import RivalTest
from surrogate_rbrdo.discrepancy.search import (
    BOUND_SCORE,
    CandidateFit,
    bound_score,
    describe,
    fit_candidate,
    fit_nuisance,
    transfer,
)
from surrogate_rbrdo.spindle.effects import EFFECTS

from .conftest import campaign_data

M_MAX, C_MAX = 250.0, 1e6          # the housing's shape bounds (kg, N s/m)
DELTA = 6.635                      # the confounding margin: χ²₁ at 99 %


def _bound_fit(spindle, k_true, m_true, pins):
    """Data with a hidden housing stage (k_true, m_true) and a housing fit converged with its
    shapes held at ``pins``, then described with them free (a converged fit on the bound)."""
    sp, g = spindle
    data, _ = campaign_data(spindle, (EFFECTS["housing"](k_N_per_m=k_true, m_kg=m_true),),
                            seed=3)
    prob = Problem(ForwardModel(g, sp.effects, data.channels, (0.0, 350.0)), data)
    base = fit_nuisance(prob)
    c = candidate("housing", prob.forward.bearing_names)
    par = base.par.with_slots((Slot(c, (), tuple(pins.items())),))
    x0 = par.x0({"housing.k_N_per_m": 1.0 / k_true})
    x0[:base.x.size] = base.x
    pinned = fit(prob, par, x0)
    free = base.par.with_slots((Slot(c, ()),))
    x = transfer(par, pinned.x, free, free.x0({f"housing.{p}": v for p, v in pins.items()}))
    ev = prob.evaluate(free, x[None])
    J, n = jacobian(prob, free, x, ev.residuals[0])
    f = Fit(free, x, float(ev.chi2[0]), J, ev, prob.n_obs, x.size + prob.n_inner, n)
    return prob, base, describe(c, Slot(c, ()), f, base.chi2)


def _held_fits(prob, base, cf, holds):
    """Independently of ``interior``: per hold, the refit from the bound fit, its χ² and
    whether it is physical (no free shape on a bound that is not zero, the compliance not
    on its bound)."""
    c, out = cf.slot.candidate, []
    for hold in holds:
        par = base.par.with_slots((Slot(c, (), tuple(hold.items())),))
        f = fit(prob, par, transfer(cf.fit.par, cf.fit.x, par, par.x0()))
        v = f.par.slot_values(f.x)[-1]
        on_bound = (abs(v["m_kg"] - M_MAX) <= 1e-6 * M_MAX
                    or abs(v["c_Ns_per_m"] - C_MAX) <= 1e-6 * C_MAX
                    or abs(v["k_N_per_m"] - 1e-6) <= 1e-12)
        out.append((f.chi2, hold, not on_bound))
    return out


MASS_HOLDS = [{"m_kg": 0.0}, {"m_kg": 10.0}, {"m_kg": 40.0}]


def test_a_converged_fit_on_the_bound_is_replaced_iff_a_held_fit_is_within_delta(spindle):
    """A stage of 2e9 N/m and 250 kg rings at 450 Hz, inside the FRFs' band: the data pin the
    mass on its bound. Around the gap to the best held fit (independent loop), interior keeps
    the bound fit for a margin just below the gap and takes that held fit just above it."""
    prob, base, cf = _bound_fit(spindle, 2e9, 250.0, {"m_kg": M_MAX, "c_Ns_per_m": 0.0})
    assert cf.at_bound and cf.parameters["m_kg"] == M_MAX
    held = [h for h in _held_fits(prob, base, cf, MASS_HOLDS) if h[2]]
    best = min(held, key=lambda h: h[0])
    gap = best[0] - cf.fit.chi2
    assert gap > 100.0                      # the data do see the mass: interior mass far worse
    assert interior(prob, base, cf, gap - 0.5) is cf
    out = interior(prob, base, cf, gap + 0.5)
    assert out.fit.chi2 == pytest.approx(best[0], rel=1e-12)
    assert dict(out.slot.fixed) == best[1] and out.held == ("m_kg",)
    assert not out.at_bound
    assert cf.n_fitted == out.n_fitted == 3   # the held mass was chosen from the data


@pytest.mark.known_answer
def test_a_mass_the_data_do_not_see_is_held_inside(spindle):
    """A stage of 3e10 N/m and 20 kg has its mode near 6 kHz, far above the FRFs' 1.5 kHz: it
    acts as a series spring whatever its mass, so a converged fit with the mass on its bound
    (250 kg) is no better than one at an interior mass (independent loop: within the χ²₁
    margin), and interior replaces it by the best held fit, the stiffness near the truth's."""
    prob, base, cf = _bound_fit(spindle, 3e10, 20.0, {"m_kg": M_MAX, "c_Ns_per_m": 0.0})
    assert cf.at_bound
    held = [h for h in _held_fits(prob, base, cf, MASS_HOLDS) if h[2]]
    best = min(held, key=lambda h: h[0])
    assert best[0] - cf.fit.chi2 <= DELTA
    out = interior(prob, base, cf, DELTA)
    assert out.fit.chi2 == pytest.approx(best[0], rel=1e-12)
    assert dict(out.slot.fixed) == best[1] and not out.at_bound
    assert out.parameters["k_N_per_m"] == pytest.approx(3e10, rel=0.35)


def test_two_bound_shapes_are_held_alone_and_together(spindle):
    """Mass and damping both on their bounds (250 kg, 1e6 N s/m): each alone and both
    together are held (seven holds), a joint hold against the χ²₂ quantile at the margin's
    level; interior returns the best physical held fit within its threshold (independent
    loop), or the bound fit when there is none."""
    prob, base, cf = _bound_fit(spindle, 3e10, 20.0, {"m_kg": M_MAX, "c_Ns_per_m": C_MAX})
    c = cf.slot.candidate
    holds = [dict(h) for h in held_options(c, cf.slot, cf.fit.par.slot_values(cf.fit.x)[-1])]
    assert holds == MASS_HOLDS + [{"c_Ns_per_m": 0.0}] + [
        {**m, "c_Ns_per_m": 0.0} for m in MASS_HOLDS]
    level = chi2.sf(DELTA, 1)
    ok = [h for h in _held_fits(prob, base, cf, holds)
          if h[2] and h[0] - cf.fit.chi2 <= chi2.isf(level, len(h[1]))]
    out = interior(prob, base, cf, DELTA)
    if not ok:
        assert out is cf
        return
    best = min(ok, key=lambda h: h[0])
    assert out.fit.chi2 == pytest.approx(best[0], rel=1e-12)
    assert set(out.held) == set(best[1]) and out.n_fitted == 3


def test_a_shape_on_a_natural_zero_is_not_held():
    """A massless, undamped housing is physical: nothing to hold; a fixed shape is not held."""
    h = candidate("housing", ("front", "rear"))
    assert held_options(h, Slot(h, ()), {"m_kg": 0.0, "c_Ns_per_m": 0.0}) == []
    fixed = Slot(h, (), (("m_kg", M_MAX),))
    assert held_options(h, fixed, {"m_kg": M_MAX, "c_Ns_per_m": C_MAX}) == [
        (("c_Ns_per_m", 0.0),)]


@pytest.mark.known_answer
def test_the_hold_threshold_is_the_chi2_quantile_at_the_margins_level():
    """χ²₁ 99 % (6.635) → χ²₂ 99 % = −2 ln 0.01 = 9.210 (closed form for two degrees of
    freedom); a margin of 1e7, whose level underflows, still gives a finite threshold: for
    two degrees of freedom P(χ²₂ > t) = exp(−t/2), so t = −2 ln P(χ²₁ > 1e7)."""
    level = chi2.sf(DELTA, 1)
    assert hold_threshold(DELTA, 2) == pytest.approx(-2 * np.log(level), rel=1e-9)
    assert hold_threshold(DELTA, 3) == pytest.approx(chi2.isf(level, 3), rel=1e-9)
    log_level = np.log(2) + log_ndtr(-np.sqrt(1e7))          # P(χ²₁ > t) = 2Φ(−√t)
    assert hold_threshold(1e7, 2) == pytest.approx(-2 * log_level, rel=1e-9)
    assert hold_threshold(1e7, 1) == 1e7


def test_the_rival_test_counts_a_held_shape_as_fitted(monkeypatch):
    """Wiring of naming.run_stage: a candidate fit on a bound goes through interior, and the
    rival test of the held fit gets the free fit's parameter count (housing: k, m, c = 3, not
    the 2 left free), so its χ²ₖ threshold does not fall because a shape was chosen from the
    data. Everything but the wiring is stubbed."""
    c = candidate("housing", ("front", "rear"))
    ns = SimpleNamespace
    zero = ns(residuals=np.zeros((1, 3)))
    held = CandidateFit("housing", Slot(c, (), (("m_kg", 40.0),)),
                        ns(chi2=50.0, evaluation=zero, jac=None, par=None, x=None), 50.0, {},
                        {}, False, True,
                        held=("m_kg",))
    bound = replace(held, slot=Slot(c, ()), at_bound=True, held=())
    seen = {}

    def spy(*args, **kwargs):
        seen["n_free"] = args[7]
        return RivalTest(0.0, 1.0, "none", 0.0)

    tail = ns(isf=lambda p: 10.0, sf=lambda x: 1e-6)
    null = ns(p_value=lambda k, v: 0.5, tails=lambda: [tail], critical_p=lambda a: 0.01,
              adjusted=lambda p: p)
    for name, value in {
            "linearise": lambda *a: Linearisation(np.zeros((0, 0)), ((c, ()),), (),
                                                  np.zeros((0, 0))),
            "simulate_null": lambda *a, **k: null, "gp_statistic": lambda *a: 0.0,
            "generic_statistic": lambda *a: 0.0, "damping_law_columns": lambda *a: None,
            "linear_statistics": lambda *a: np.array([100.0]), "warm_base": lambda *a, **k: None,
            "fit_candidate": lambda *a, **k: bound, "rival_test": spy,
            "interior": lambda p, b, cf, d, **k: held if cf is bound else cf}.items():
        monkeypatch.setattr(naming, name, value)
    base = ns(chi2=100.0, evaluation=zero, par=ns(names=()))
    stage = naming.run_stage(ns(series=lambda: None, unbalance_design=lambda *a: None), base, (c,),
                             ns(chi2=lambda f, p: (0.0, 0.0)), alpha=0.05, n_draws=1,
                             holdout_tolerance=10.83, rng=np.random.default_rng(0),
                             max_nfev=1, confound_delta=DELTA)
    assert stage.assessments[0].fit is held
    assert len(held.slot.free) == 2 and seen["n_free"] == 3


@pytest.mark.known_answer
@pytest.mark.parametrize("true_beta, expect_binds", [(2.0, True), (1.0, False)])
def test_the_bound_score_is_the_exact_chi2_gain_of_relaxing_a_linear_bound(true_beta,
                                                                             expect_binds):
    """Linear least squares with β₁ ≤ 1: at the constrained optimum the score statistic
    ``g² V`` equals the χ² gained by dropping the bound (an independent unconstrained fit):
    large when the truth lies beyond the bound, within noise when it lies on it."""
    rng = np.random.default_rng(7)
    A = rng.standard_normal((80, 3))
    y = A @ np.array([0.5, true_beta, -1.0]) + 0.2 * rng.standard_normal(80)
    Aw, yw = A / 0.2, y / 0.2
    con = lsq_linear(Aw, yw, bounds=([-np.inf, -np.inf, -np.inf], [np.inf, 1.0, np.inf]))
    assert con.x[1] == pytest.approx(1.0) or not expect_binds
    r = Aw @ con.x - yw
    free = np.linalg.lstsq(Aw, yw, rcond=None)[0]
    gain = float(r @ r - np.sum((Aw @ free - yw) ** 2))
    f = SimpleNamespace(jac=Aw, evaluation=SimpleNamespace(residuals=r[None]),
                        covariance=lambda: np.linalg.inv(Aw.T @ Aw))
    score = bound_score(f, 1, +1.0)
    if con.x[1] >= 1.0 - 1e-9:
        assert score == pytest.approx(gain, rel=1e-6)
    assert (score > BOUND_SCORE) == expect_binds
    assert bound_score(f, 1, -1.0) == 0.0          # the data do not want it below


@pytest.mark.known_answer
@pytest.mark.parametrize("name, truth, narrowed_upper, flagged", [
    ("gyroscopics", dict(g=0.3), 0.1, True),                 # truth beyond a narrowed bound
    ("gyroscopics", dict(g=1.0), None, False),               # truth on the range's end
    ("housing", dict(k_N_per_m=1e6, m_kg=0.0), 2e-7, True),  # compliance: k >= 5e6 N/m allowed
])
def test_a_strength_on_its_bound_is_unphysical_iff_the_truth_lies_beyond(spindle, name, truth,
                                                                          narrowed_upper,
                                                                          flagged):
    """Through ``describe``: the fit ends on the strength's upper bound either way; it is
    flagged ``at_bound`` only when the truth lies beyond that bound (a narrowed range), not when
    the truth is the range's end itself. Covers the index, the outward direction and a
    reciprocal strength (the housing's compliance 1/k, whose upper bound is the softest k; with
    the outward direction inverted no fit on a bound would ever be flagged)."""
    sp, g = spindle
    data, _ = campaign_data(spindle, (EFFECTS[name](**truth),), seed=3)
    prob = Problem(ForwardModel(g, sp.effects, data.channels, (0.0, 350.0)), data)
    base = fit_nuisance(prob)
    c = candidate(name, prob.forward.bearing_names)
    if narrowed_upper is not None:
        c = replace(c, upper=(narrowed_upper,) + c.upper[1:])
    if name == "housing":                     # the mass and damping the truth has: held
        c = replace(c, shape=(), shape_bounds=(), shape_starts=())
    cf = fit_candidate(prob, base, c)
    k = cf.fit.par.names.index(f"{name}.{c.strength[0]}")
    assert cf.fit.x[k] == pytest.approx(c.upper[0], rel=1e-6)      # on the bound either way
    assert cf.at_bound == flagged
