"""The exact stepper's closed form for stretches without input (``rig.stepping``)."""

import numpy as np
import pytest
from scipy.signal import lsim

from surrogate_rbrdo.rig.integrate import IntegratorOptions, SpeedProfile, simulate
from surrogate_rbrdo.rig.simulate import ProbeLayout, hammer_pulse
from surrogate_rbrdo.rig.stepping import Segment, free_outputs, run_segment
from surrogate_rbrdo.spindle import reference_spindle


def _oscillator(m=1.0, f_hz=50.0, zeta=0.02):
    """``m x'' + c x' + k x = f`` in first-order form and its modal segment."""
    k, w = m * (2 * np.pi * f_hz) ** 2, 2 * np.pi * f_hz
    A = np.array([[0.0, 1.0], [-k / m, -2 * zeta * w]])
    B, C = np.array([[0.0], [1.0 / m]]), np.array([[1.0, 0.0]])
    lam, V = np.linalg.eig(A)
    W = np.linalg.inv(V)
    return (A, B, C), Segment(lam, W @ B, C @ V, np.zeros(1, complex))


@pytest.mark.known_answer
def test_oscillator_hit_matches_the_matrix_exponential_solution():
    """A half-sine hit on one mode, first-order hold of the force samples: the closed form
    after the pulse (and the recurrence during it) against scipy's ``lsim`` (the exact
    discretisation of the linearly interpolated input by one matrix exponential)."""
    (A, B, C), seg = _oscillator()
    t = np.arange(3001) * 1e-4
    f = hammer_pulse(t, 0.01, 200.0, 2e-3)
    ref = lsim((A, B, C, np.zeros((1, 1))), f, t, interp=True)[1]
    y, eta, _ = run_segment(np.zeros(2, complex), seg, SpeedProfile.constant(0.0), t,
                            f[:, None], [0])
    assert np.max(np.abs(y[:, 0] - ref)) <= 1e-9 * np.sqrt(np.mean(ref**2))
    assert np.all(y[: int(0.01 / 1e-4) + 1] == 0.0)          # at rest until the hit


@pytest.mark.known_answer
def test_free_outputs_is_the_damped_sine_for_any_block_length():
    """``Re(CV a^j η)`` in closed form: x(t) = e^{−σt} cos(ω_d t) from x = 1, x' = −σ."""
    sigma, wd, h = 3.0, 2 * np.pi * 40.0, 1e-3
    lam = np.array([-sigma + 1j * wd, -sigma - 1j * wd])
    t = np.arange(1, 1001) * h
    for L in (0, 1, 7, 1000, 1500):
        y, eta = free_outputs(np.exp(lam * h), np.array([0.5, 0.5], complex),
                              np.ones((1, 2)), t.size, L)
        assert np.max(np.abs(y[:, 0] - np.exp(-sigma * t) * np.cos(wd * t))) < 1e-13
        assert np.allclose(eta, 0.5 * np.exp(lam * t[-1]), rtol=1e-12, atol=0)


@pytest.mark.parametrize("speed_rpm", [0.0, 20_000.0])
def test_hit_on_the_spindle_equals_the_recurrence(speed_rpm):
    """A hammer hit at the tool of the reference spindle (168 modes, 40 000 fine steps): the
    closed-form free decay against the step-by-step recurrence: ≤ 1e-9 of the record's RMS."""
    sp = reference_spindle()
    m = sp.model(sp.baseline)
    lay = ProbeLayout.of(m)
    dofs = np.array([4 * n + d for n in lay.nodes.values() for d in (0, 1)])
    tf = np.arange(40_000) / 40_000.0
    f = hammer_pulse(tf, 0.05, 300.0, 0.4e-3)[:, None]
    tool = 4 * m.tool_node

    def run(closed_form):
        return simulate(m, SpeedProfile.constant(speed_rpm), tf, dofs, unbalance=False,
                        force_dofs=np.array([tool]), force=f, acc_dofs=np.array([tool]),
                        options=IntegratorOptions(closed_form=closed_form))

    new, old = run(True), run(False)
    for a, b in ((new.q, old.q), (new.acc, old.acc)):
        assert np.max(np.abs(a - b)) <= 1e-9 * np.sqrt(np.mean(b**2))


def test_closed_form_option_is_checked():
    with pytest.raises(ValueError, match="closed_form = 1 is not allowed"):
        IntegratorOptions(closed_form=1)
