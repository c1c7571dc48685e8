"""Forward critical speeds against the damped Campbell diagram; API separation margins."""

from dataclasses import replace

import numpy as np
import pytest
import scipy.linalg as sla
from scipy.optimize import brentq

from surrogate_rbrdo.spindle.assembly import RPM
from surrogate_rbrdo.spindle.effects import Anisotropy, HousingFlexibility
from surrogate_rbrdo.spindle.modal import critical_speeds, first_natural_frequency, modal_analysis
from surrogate_rbrdo.spindle.reference import reference_spindle
from surrogate_rbrdo.spindle.separation import (
    ResonanceGuard,
    api_separation_margins,
    bounding_critical_speeds,
    forward_critical_speeds,
)

SP = reference_spindle()


@pytest.mark.known_answer
@pytest.mark.parametrize("x", [[2000.0, 500.0, 65.0], [1000.0, 750.0, 50.0],
                               [3000.0, 350.0, 80.0]])
def test_critical_speeds_equal_the_damped_campbell_crossings(x):
    """Independent: 1x crossings of the damped forward modes (state-space eigenproblem)."""
    m = SP.model(np.array(x))
    crit = forward_critical_speeds(m, 40000.0)
    ref = critical_speeds(m, np.linspace(500.0, 40000.0, 40))
    np.testing.assert_allclose(crit.speeds_rpm, ref, rtol=1e-4)
    for s, z in zip(crit.speeds_rpm, crit.damping_ratio, strict=True):
        md = modal_analysis(m, s)
        k = np.argmin(np.where(md.whirl == "forward", np.abs(md.frequency_hz * 60 - s), np.inf))
        assert z == pytest.approx(md.damping_ratio[k], rel=0.05)   # Rayleigh quotient


@pytest.mark.known_answer
def test_api_margins():
    below, above = api_separation_margins(np.array([2.4, 3.0, 10.0, 1000.0]))
    core = 0.17 * (1 - 1 / (np.array([3.0, 10.0]) - 1.5))
    np.testing.assert_allclose(below, [0.0, *np.minimum(0.16, core), 0.16])
    np.testing.assert_allclose(above, [0.0, *np.minimum(0.26, 0.10 + core), 0.26])


def test_guards_on_designs_with_and_without_a_critical_in_range():
    g = ResonanceGuard(SP)
    X = np.array([[2000.0, 500.0, 65.0], [3000.0, 300.0, 80.0]])
    sep = g(X)[:, 0]
    assert sep[0] > 0 > sep[1]                 # 21 780 rpm in range; 39 300 rpm > 1.26 n_max
    m = SP.model(X[1])
    crit = forward_critical_speeds(m, 1.5 * 24000.0)
    assert crit.speeds_rpm.size == 0 and sep[1] == pytest.approx(1 - 1.5)
    paper = ResonanceGuard(SP, "paper")(X)[:, 0]
    np.testing.assert_allclose(paper, [1 - first_natural_frequency(SP.model(x)) / 480.0
                                       for x in X])


def test_anisotropic_bearings_are_refused():
    m = SP.model(SP.baseline, effects=SP.effects + (Anisotropy(s=0.1),))
    with pytest.raises(ValueError, match="isotropic"):
        forward_critical_speeds(m, 30000.0)
    with pytest.raises(ValueError, match="kind"):
        ResonanceGuard(SP, "api")


@pytest.mark.known_answer
@pytest.mark.parametrize("housing", [HousingFlexibility(k_N_per_m=6e8, m_kg=20.0),
                                     HousingFlexibility(k_N_per_m=2e8, m_kg=5.0,
                                                        c_Ns_per_m=2000.0)])
@pytest.mark.parametrize("x", [[2000.0, 500.0, 65.0], [1000.0, 750.0, 50.0]])
def test_a_housing_stage_gives_the_damped_campbell_crossings(x, housing):
    """Independent: the 1x crossings of the damped forward modes of the whole model (housing
    DOFs included); the housing mode adds a critical below 1.7 n_max."""
    m = SP.model(np.array(x), effects=SP.effects + (housing,))
    crit = forward_critical_speeds(m, 40000.0)
    ref = critical_speeds(m, np.linspace(500.0, 40000.0, 40))
    assert crit.speeds_rpm.size == ref.size == 2
    np.testing.assert_allclose(crit.speeds_rpm, ref, rtol=1e-4)


def _all_synchronous_crossings(m, up_to_rpm):
    """Independent: every undamped 1x crossing of the whole model, from the Hermitian pencil
    ``K(Ω) u = Ω² (M − i G) u`` built from ``system_matrices``."""
    def freq(n, k):
        M, _, K = m.system_matrices(n * RPM)
        A = M.astype(complex)
        A[:m.n_dof, :m.n_dof] -= 1j * m.gyro_scale * m.G
        mu = sla.eigh(A, K, eigvals_only=True)[::-1]
        return 1.0 / np.sqrt(mu[k]) / RPM if mu[k] > 0 else np.inf
    out = []
    for k in range(20):
        if freq(up_to_rpm, k) >= up_to_rpm:
            break
        out.append(brentq(lambda n, k=k: freq(n, k) - n, 1e-3 * up_to_rpm, up_to_rpm))
    return np.array(out)


@pytest.mark.known_answer
@pytest.mark.parametrize("s", [0.05, 0.2, -0.2])
@pytest.mark.parametrize("x", [[2000.0, 500.0, 65.0], [3000.0, 350.0, 80.0]])
def test_anisotropic_critical_speeds_lie_in_the_bounding_bands(x, s):
    """The k-th exact 1x crossing lies in the k-th band (the isotropic rotors at k_yy and
    k_xx), and so does every damped forward crossing of ``modal.critical_speeds``."""
    m = SP.model(np.array(x), effects=SP.effects + (Anisotropy(s=s),))
    up = 50000.0
    bands = bounding_critical_speeds(m, up)
    exact = _all_synchronous_crossings(m, up)
    assert exact.size <= bands.lower_rpm.size
    lo, hi = bands.lower_rpm[:exact.size], bands.upper_rpm[:exact.size]
    assert np.all((lo <= exact * (1 + 1e-6)) & (exact <= hi * (1 + 1e-6)))
    assert np.all(hi - lo > 0)                                # the split is real
    for n in critical_speeds(m, np.linspace(500.0, up, 60)):
        assert np.any((bands.lower_rpm <= n * (1 + 1e-4)) & (n <= bands.upper_rpm * (1 + 1e-4)))


@pytest.mark.known_answer
def test_isotropic_bands_are_the_forward_critical_speeds_and_the_guard_is_conservative():
    m = SP.model(np.array([2000.0, 500.0, 65.0]))
    b = bounding_critical_speeds(m, 40000.0)
    np.testing.assert_array_equal(b.lower_rpm, forward_critical_speeds(m, 40000.0).speeds_rpm)
    np.testing.assert_array_equal(b.lower_rpm, b.upper_rpm)
    # a design whose critical sits inside the range stays infeasible with anisotropy; the
    # anisotropic guard is never below what the exact crossings alone would give
    X = np.array([[2000.0, 500.0, 65.0], [3000.0, 300.0, 80.0]])
    aniso = replace(SP, effects=SP.effects + (Anisotropy(s=0.05),))
    g = ResonanceGuard(aniso)(X)[:, 0]
    assert g[0] > 0
    geo = SP.geometry
    for gi, x in zip(g, X, strict=True):
        ex = _all_synchronous_crossings(aniso.model(x), 1.5 * geo.speed_max_rpm)
        if ex.size:                                   # AF is saturated (> 18.5): 26 %, 16 %
            exact = np.max(np.minimum(1.26 - ex / geo.speed_max_rpm,
                                      ex / geo.speed_min_rpm - 0.84))
            assert gi >= exact - 1e-9
