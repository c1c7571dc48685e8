"""The candidate search: a shape parameter on a bound is tried inside (``search.interior``)."""

from __future__ import annotations

import pytest

from surrogate_rbrdo.discrepancy.candidates import candidate
from surrogate_rbrdo.discrepancy.fit import fit
from surrogate_rbrdo.discrepancy.forward import ForwardModel
from surrogate_rbrdo.discrepancy.nuisance import Slot
from surrogate_rbrdo.discrepancy.problem import Problem
from surrogate_rbrdo.discrepancy.search import describe, fit_nuisance, interior
from surrogate_rbrdo.spindle.effects import EFFECTS

from .conftest import campaign_data


def _at_bound_fit(spindle, k_true, m_true, *, nfev):
    """Data with a hidden housing stage (k_true, m_true) and a housing fit started at the
    truth's stiffness with the mass on its upper bound (250 kg)."""
    sp, g = spindle
    data, _ = campaign_data(spindle, (EFFECTS["housing"](k_N_per_m=k_true, m_kg=m_true),),
                            seed=3)
    prob = Problem(ForwardModel(g, sp.effects, data.channels, (0.0, 350.0)), data)
    base = fit_nuisance(prob)
    c = candidate("housing", prob.forward.bearing_names)
    slot = Slot(c, ())
    par = base.par.with_slots((slot,))
    x0 = par.x0({"housing.k_N_per_m": 1.0 / k_true, "housing.m_kg": 250.0})
    x0[:base.x.size] = base.x
    f = fit(prob, par, x0, max_nfev=nfev)
    return prob, base, describe(c, slot, f, base.chi2)


@pytest.mark.known_answer
def test_a_mass_the_data_do_not_see_is_held_inside(spindle):
    """A stage of 3e10 N/m and 20 kg has its mode near 6 kHz, far above the FRFs' 1.5 kHz: it
    acts as a series spring whatever its mass. A fit parked on the mass bound is replaced by
    one with the mass held at an interior start, the stiffness near the truth's."""
    prob, base, cf = _at_bound_fit(spindle, 3e10, 20.0, nfev=1)
    assert cf.at_bound and cf.parameters["m_kg"] == pytest.approx(250.0)
    out = interior(prob, base, cf, 6.63)
    assert not out.at_bound
    assert dict(out.slot.fixed)["m_kg"] in (0.0, 10.0, 40.0)
    assert out.parameters["k_N_per_m"] == pytest.approx(3e10, rel=0.35)
    assert out.fit.chi2 <= cf.fit.chi2 + 6.63


@pytest.mark.known_answer
def test_a_mass_the_data_pin_on_its_bound_stays(spindle):
    """A stage of 2e9 N/m and 250 kg (the bound) rings at 450 Hz, inside the FRFs' band: the
    data pin the mass on its bound, every interior mass fits far worse, the fit is kept."""
    prob, base, cf = _at_bound_fit(spindle, 2e9, 250.0, nfev=1)       # started at the truth
    assert cf.at_bound
    assert interior(prob, base, cf, 6.63) is cf
