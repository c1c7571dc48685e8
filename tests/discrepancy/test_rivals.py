"""The encompassing test of a library candidate against generic rivals (known answers on a
linear problem with identity whitening, where every χ² is a projection)."""

from types import SimpleNamespace

import numpy as np
import pytest

from surrogate_rbrdo.discrepancy import rivals
from surrogate_rbrdo.discrepancy.calibration import Linearisation
from surrogate_rbrdo.discrepancy.rivals import RivalTest, damping_law_columns, rival_test
from surrogate_rbrdo.discrepancy.sweeps import Channel, Sweep
from surrogate_rbrdo.discrepancy.workflow import _rival_separation

N_CELLS = 30                      # complex cells: 60 real observations, no priors


def _problem():
    whiten = [np.broadcast_to(np.eye(2), (N_CELLS, 1, 2, 2))]
    return SimpleNamespace(whiten=whiten, noise_cells=lambda: (None, None, np.ones(0), None))


def _setup(rng):
    n = 2 * N_CELLS
    nuis = rng.standard_normal((n, 2))
    gen = rng.standard_normal((n, 3))
    lin = Linearisation(nuis, (), (), gen, 0, ("g0", "g1", "g2"))
    return lin, nuis, gen


def _ls_residual(A, y):
    return y - A @ np.linalg.lstsq(A, y, rcond=None)[0]


@pytest.mark.known_answer
def test_a_candidate_that_is_a_generic_direction_adds_nothing_to_it():
    """Truth along generic column g1, the candidate's direction equal to it: both explain the
    same, so the candidate adds 0 to its rival g1 and is not separable."""
    rng = np.random.default_rng(1)
    lin, nuis, gen = _setup(rng)
    y = 3.0 * gen[:, 1] + 0.1 * rng.standard_normal(nuis.shape[0])
    r0 = _ls_residual(nuis, y)
    A = np.hstack([nuis, gen[:, 1:2]])
    r1 = _ls_residual(A, y)
    t = rival_test(_problem(), lin, float(r0 @ r0), r0, float(r1 @ r1), r1, A, 1, 6.63)
    assert t.rival == "g1"
    assert t.statistic == pytest.approx(0.0, abs=1e-8)
    assert not t.passed


@pytest.mark.known_answer
def test_what_the_rival_adds_to_the_candidate_is_an_independent_least_squares_gain():
    """The reverse direction of the encompassing test: the closest rival's gain on top of the
    fitted candidate, ``|r_cand|² − |r_cand+rival|²``, against a least-squares fit of
    nuisance + candidate + rival (free range). Truth ``3 g1``; the candidate mimics g1 (``d =
    g1 + 0.05 e``): it adds nothing to g1 and g1 adds nothing to it — *mutual*. A candidate
    that explains only part of it (``d = g1 + 2 e``) still adds nothing to g1, but g1 adds a
    lot to it: not mutual (the rival explains the data, the candidate does not)."""
    rng = np.random.default_rng(3)
    lin, nuis, gen = _setup(rng)
    n = nuis.shape[0]
    e = _ls_residual(np.hstack([nuis, gen]), rng.standard_normal(n))
    e /= np.linalg.norm(e)
    y = 3.0 * gen[:, 1] + 0.1 * rng.standard_normal(n)
    r0 = _ls_residual(nuis, y)
    for eps, mutual in ((0.05, True), (2.0, False)):
        d = gen[:, 1] + eps * e * np.linalg.norm(gen[:, 1])
        A = np.hstack([nuis, d[:, None]])
        r1 = _ls_residual(A, y)
        both = _ls_residual(np.hstack([A, gen[:, 1:2]]), y)
        # the candidate's model as the workflow hands it over: its outer Jacobian (here the
        # first nuisance column and d) and the unbalance design (the second) apart
        for jac, design in ((A, None), (A[:, [0, 2]], nuis[:, 1:])):
            t = rival_test(_problem(), lin, float(r0 @ r0), r0, float(r1 @ r1), r1, jac, 1,
                           6.63, fit_design=design)
            assert t.rival == "g1" and not t.passed
            assert t.rival_adds == pytest.approx(float(r1 @ r1 - both @ both), rel=1e-8,
                                                 abs=1e-9)
            assert t.mutual is mutual


@pytest.mark.known_answer
def test_a_candidate_no_rival_can_mimic_adds_its_whole_fit():
    """Truth along a direction orthogonal to the nuisance and every generic column: the
    closest rival explains nothing and the candidate adds its whole Δχ² = |r0|² − |r1|²."""
    rng = np.random.default_rng(2)
    lin, nuis, gen = _setup(rng)
    d = _ls_residual(np.hstack([nuis, gen]), rng.standard_normal(nuis.shape[0]))
    y = 5.0 * d / np.linalg.norm(d)
    r0 = _ls_residual(nuis, y)
    A = np.hstack([nuis, d[:, None]])
    r1 = _ls_residual(A, y)
    t = rival_test(_problem(), lin, float(r0 @ r0), r0, float(r1 @ r1), r1, A, 1, 6.63)
    assert t.statistic == pytest.approx(25.0, rel=1e-9)
    assert t.rival_delta_chi2 == pytest.approx(0.0, abs=1e-9)
    assert t.passed and t.threshold == pytest.approx(6.63)


@pytest.mark.known_answer
def test_a_rival_needing_an_implausible_size_is_held_to_its_range():
    """The same mimic as above, but the rival may change by at most 1 (column units) while the
    data need 3: the rival's χ² is that of its bounded best, ``|r0 − u|²`` (u its
    nuisance-orthogonal part), and the candidate, which fits all of it, adds that minus its
    own χ²."""
    rng = np.random.default_rng(1)
    lin, nuis, gen = _setup(rng)
    lin = Linearisation(nuis, (), (), gen, 0, ("g0", "g1", "g2"), np.tile([-1.0, 1.0], (3, 1)))
    y = 3.0 * gen[:, 1] + 0.1 * rng.standard_normal(nuis.shape[0])
    r0 = _ls_residual(nuis, y)
    A = np.hstack([nuis, gen[:, 1:2]])
    r1 = _ls_residual(A, y)
    u = _ls_residual(nuis, gen[:, 1])
    c = float(u @ r0) / float(u @ u)
    assert c > 1.0
    t = rival_test(_problem(), lin, float(r0 @ r0), r0, float(r1 @ r1), r1, A, 1, 6.63)
    expected = float((r0 - u) @ (r0 - u)) - float(r1 @ r1)
    assert t.rival == "g1" and t.statistic == pytest.approx(expected, rel=1e-9)
    assert t.passed


@pytest.mark.known_answer
@pytest.mark.parametrize("limit", [np.inf, 1.0])
def test_the_residual_after_the_best_rival_is_that_of_its_bounded_least_squares_fit(limit):
    """Truth along generic column g1 plus noise: the rival left is g1, and the residual after it
    equals the nuisance + g1 least-squares residual (free range) or, with g1 held to at most 1
    where the data need 3, the nuisance refitted with g1 fixed at 1 — an independent fit."""
    rng = np.random.default_rng(5)
    lin, nuis, gen = _setup(rng)
    lin = Linearisation(nuis, (), (), gen, 0, ("g0", "g1", "g2"),
                        np.tile([-limit, limit], (3, 1)))
    y = 3.0 * gen[:, 1] + 0.1 * rng.standard_normal(nuis.shape[0])
    r0 = _ls_residual(nuis, y)
    gain, label, left = rivals.rival_refit(_problem(), lin, r0)
    want = (_ls_residual(np.hstack([nuis, gen[:, 1:2]]), y) if np.isinf(limit)
            else _ls_residual(nuis, y - limit * gen[:, 1]))
    assert label == "g1"
    np.testing.assert_allclose(left, want, atol=1e-9)
    assert gain == pytest.approx(float(r0 @ r0 - want @ want), rel=1e-9)


@pytest.mark.known_answer
def test_damping_speed_law_refers_every_test_to_one_speed():
    """``c ∝ (Ω/Ω_ref)^p``: ∂/∂p at p = 0 is ``ln(Ω/Ω_ref)`` times the damping factor's column,
    with Ω_ref the 1x speeds' geometric mean for every test — an impact block at speed sees the
    damping at its own speed, at standstill the law does not act."""
    ch = (Channel("t", 0.0, "x"),)
    one_x = Sweep.unbalance([1000.0, 4000.0])                 # geometric mean 2000 rpm
    blocks = [SimpleNamespace(mean=np.zeros((2, 1)), sweep=one_x),
              SimpleNamespace(mean=np.zeros((3, 1)), sweep=Sweep.impact([50, 60, 70], ch, 8000)),
              SimpleNamespace(mean=np.zeros((1, 1)), sweep=Sweep.impact([50], ch))]
    prob = SimpleNamespace(blocks=blocks, n_obs=2 * 6 + 1)
    lin = SimpleNamespace(nuisance=np.ones((13, 2)))
    cols, labels, ranges = damping_law_columns(prob, lin, ("log_theta_front", "log_damping_f"))
    expect = np.r_[np.repeat(np.log([0.5, 2.0]), 2), np.full(6, np.log(4.0)), 0, 0, 0]
    assert np.allclose(cols[:, 0], expect)
    assert labels == ("speed law of damping (f)",) and ranges.tolist() == [[-1.0, 1.0]]


def _span_case(rng, sign: float):
    """A 'bearing' column ``k`` (the stiffness factor θ's, in the nuisance) and a constant
    'spring' ``s`` at the same node (a generic rival): the candidate's direction is inside their
    span, ``d = k − s`` scaled by ``sign`` — a speed law ``a + b k(Ω)`` of that bearing."""
    n = 2 * N_CELLS
    k = rng.standard_normal(n)
    other = rng.standard_normal((n, 1))
    nuis = np.column_stack([k, other])
    s = rng.standard_normal(n)
    d = sign * (k - s)
    y = 4.0 * d + 0.05 * rng.standard_normal(n)
    r0 = _ls_residual(nuis, y)
    A = np.hstack([nuis, d[:, None]])
    r1 = _ls_residual(A, y)
    return nuis, s, r0, r1, A


@pytest.mark.known_answer
@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_a_signature_inside_the_span_of_theta_and_a_spring_is_not_separable(sign):
    """The hypothesis in miniature: with θ free, a constant spring at the bearing's node spans
    the bearing's speed law, so a candidate inside that span adds nothing to the spring (either
    sign, when the spring may take either)."""
    rng = np.random.default_rng(5)
    nuis, s, r0, r1, A = _span_case(rng, sign)
    lin = Linearisation(nuis, (), (), s[:, None], 0, ("spring",), np.array([[-np.inf, np.inf]]))
    t = rival_test(_problem(), lin, float(r0 @ r0), r0, float(r1 @ r1), r1, A, 1, 6.63)
    assert t.rival == "spring" and t.statistic == pytest.approx(0.0, abs=1e-8)
    assert not t.passed


@pytest.mark.known_answer
def test_a_one_sided_spring_cannot_mimic_what_needs_it_negative():
    """The same span, but the spring is passive (range ``[0, ∞)``). When the data need it
    negative (``y ∝ k − s`` asks for ``−4 s``) its bounded best is 0: it explains nothing and
    the candidate adds its whole ``Δχ² = |r0|² − |r1|²``; when they need it positive
    (``y ∝ s − k``) it mimics the candidate as before."""
    rng = np.random.default_rng(5)
    for sign, separable in ((1.0, True), (-1.0, False)):
        nuis, s, r0, r1, A = _span_case(rng, sign)
        lin = Linearisation(nuis, (), (), s[:, None], 0, ("spring",), np.array([[0.0, np.inf]]))
        t = rival_test(_problem(), lin, float(r0 @ r0), r0, float(r1 @ r1), r1, A, 1, 6.63)
        if separable:
            assert t.rival_delta_chi2 == pytest.approx(0.0, abs=1e-12)
            assert t.statistic == pytest.approx(float(r0 @ r0 - r1 @ r1), rel=1e-9)
        else:
            assert t.statistic == pytest.approx(0.0, abs=1e-8)
        assert t.passed is separable


def test_a_name_withheld_for_a_spring_asks_for_a_thermal_soak():
    """The experiment a withheld name carries: off-synchronous excitation without impact tests
    at speed; with them, a thermal soak when the best-separated member drifts with temperature
    (a preload growth) and its closest rival is a grounded spring beside a bearing it acts on
    (the spring spans that bearing's speed law, no excitation separates them); else a larger
    effect or more speeds — also for a member that does not drift (a soak cannot separate a
    housing from a spring), one at the other bearing, or when the data hold a soak already."""
    ch = (Channel("t", 0.0, "x"),)
    one_x = SimpleNamespace(sweep=Sweep.unbalance([1000.0, 4000.0]))
    at_speed = SimpleNamespace(blocks=(one_x, SimpleNamespace(sweep=Sweep.impact([50], ch, 8e3))),
                               soaks=())
    standstill = SimpleNamespace(blocks=(one_x, SimpleNamespace(sweep=Sweep.impact([50], ch))),
                                 soaks=())
    soaked = SimpleNamespace(blocks=at_speed.blocks, soaks=("a soak",))

    def held(name, scope, *labels):
        fit = SimpleNamespace(slot=SimpleNamespace(scope=scope))
        return tuple(SimpleNamespace(name=name, fit=fit, rival=RivalTest(float(i), 9.2, lb, 1.0))
                     for i, lb in enumerate(labels))

    spring = ("stiffness of shaft element 3", "grounded spring at node 4 beside bearing a")
    assert _rival_separation(standstill, held("thermal_preload", (), *spring)) \
        == rivals.RIVAL_SEPARATION
    soak, more = rivals.RIVAL_SEPARATION_SPRING, rivals.RIVAL_SEPARATION_AT_SPEED
    assert _rival_separation(at_speed, held("thermal_preload", (), *spring)) == soak
    # a soak was run already (its verdicts are in the findings): more speeds or a larger effect
    assert _rival_separation(soaked, held("thermal_preload", (), *spring)) == more
    assert _rival_separation(at_speed, held("thermal_preload", ("a",), *spring)) == soak
    assert _rival_separation(at_speed, held("thermal_preload", ("b",), *spring)) == more
    assert _rival_separation(at_speed, held("housing", (), *spring)) == more
    both = ("mass of disk x", "grounded spring at node 7 beside bearings a and b")
    assert _rival_separation(at_speed, held("thermal_preload", ("b",), *both)) == soak
    far = ("stiffness of shaft element 3", "grounded spring at node 9")
    assert _rival_separation(at_speed, held("thermal_preload", (), *far)) == more
    assert _rival_separation(at_speed, held("thermal_preload", (), "grounded spring at node 4",
                                            "mass of disk x")) == more


@pytest.mark.known_answer
def test_the_projection_does_not_depend_on_the_columns_units():
    """A span does not change when its columns are rescaled: parameters in their own units
    differ by many decades (a compliance's column is 1e9 times a factor's), and the rank test
    must not read a small column as a dependent one; an exactly repeated column adds nothing
    (its projection is that of the span without it)."""
    rng = np.random.default_rng(0)
    B = rng.standard_normal((50, 3))
    Y = rng.standard_normal((50, 2))
    want = _ls_residual(B, Y)
    for s in (1e-12, 1e-6, 1.0, 1e6, 1e12):
        np.testing.assert_allclose(rivals._orth(B * np.array([1.0, s, 1.0 / s]), Y), want,
                                   atol=1e-9)
    np.testing.assert_allclose(rivals._orth(np.hstack([B, 3.0 * B[:, 1:2]]), Y), want,
                               atol=1e-9)


@pytest.mark.known_answer
def test_a_one_sided_rival_is_mutual_only_below_its_mixture_quantile():
    """Under the null a rival bounded at 0 (a passive spring) gains ``½χ²₀ + ½χ²₁``
    (Self & Liang 1987): its quantile at level 0.01 is χ²₁'s at 0.02 (5.41), below the
    two-sided 6.63. A rival adding 6.0 is mutual with a two-sided range, not with a sign."""
    level = 0.01
    # P(½χ²₀ + ½χ²₁ > q) = ½ P(Z² > q) = P(Z > √q) = 0.01: q = z_0.99², z_0.99 = 2.32634787...
    q = 2.3263478740408408 ** 2
    for one_sided, mutual in ((False, True), (True, False)):
        t = RivalTest(0.5, 6.63, "spring", 10.0, level, 1, 6.0, one_sided)
        assert t.mutual is mutual
    assert RivalTest(0.5, 6.63, "spring", 10.0, level, 1, q - 1e-9, True).mutual
    assert not RivalTest(0.5, 6.63, "spring", 10.0, level, 1, q + 1e-9, True).mutual


@pytest.mark.known_answer
def test_the_forward_statistic_is_the_nested_least_squares_gain_when_base_and_fit_differ():
    """The base's nuisance columns differ from those of the candidate's fit (a nonlinear model
    linearised at two points): what the candidate adds to each rival is ``χ²(base + rival) −
    χ²(fit + rival)``, each model's least squares on its own columns — never negative — and not
    the joint model with the base's columns projected out as well (review s11 H2)."""
    rng = np.random.default_rng(7)
    lin, nuis, gen = _setup(rng)
    n = nuis.shape[0]
    moved = nuis + 0.5 * rng.standard_normal(nuis.shape)       # the nuisance at the fit
    d = rng.standard_normal(n)
    y = 2.0 * d + 1.5 * gen[:, 0] + 0.1 * rng.standard_normal(n)
    r0 = _ls_residual(nuis, y)
    A = np.hstack([moved, d[:, None]])
    r1 = _ls_residual(A, y)
    t = rival_test(_problem(), lin, float(r0 @ r0), r0, float(r1 @ r1), r1, A, 1, 6.63)
    expected = []
    for j in range(gen.shape[1]):
        alone = _ls_residual(np.hstack([nuis, gen[:, j:j + 1]]), y)
        both = _ls_residual(np.hstack([A, gen[:, j:j + 1]]), y)
        expected.append(float(alone @ alone - both @ both))
    j = int(np.argmin(expected))
    assert t.rival == f"g{j}"
    assert t.statistic == pytest.approx(expected[j], rel=1e-8)
    assert min(expected) > 0
    both = _ls_residual(np.hstack([A, gen[:, j:j + 1]]), y)
    assert t.rival_adds == pytest.approx(float(r1 @ r1 - both @ both), rel=1e-8)
