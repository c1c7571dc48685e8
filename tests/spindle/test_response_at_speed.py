"""The amplitude at one operating speed (``ResponseSpec(kind="at_speed")``)."""

from __future__ import annotations

import numpy as np
import pytest

from surrogate_rbrdo.spindle.evaluate import (
    AtSpeedAmplitudeResponse,
    PeakAmplitudeResponse,
    PointwiseAtSpeed,
    PointwisePeak,
    ResponseSpec,
)
from surrogate_rbrdo.spindle.reference import reference_spindle

from .conftest import dense_response


def _dense_tool_amplitude(model, speed_rpm, theta):
    """Independent path: the dense solve of ``conftest.dense_response`` (not the
    block-tridiagonal solver), orbit semi-major axis at the tool node."""
    X, Y = dense_response(model, [speed_rpm], theta)[0, model.tool_node, :2]
    return 0.5 * (abs(X + 1j * Y) + abs(X - 1j * Y))


@pytest.mark.known_answer
@pytest.mark.parametrize("x,speed", [([2000.0, 465.8, 65.0], 24000.0),
                                     ([3000.0, 490.0, 75.0], 24000.0),
                                     ([1000.0, 700.0, 55.0], 9000.0)])
def test_at_speed_amplitude_equals_a_dense_solve(x, speed):
    sp = reference_spindle()
    theta = np.array([[1.0, 1.0], [0.9, 1.12]])
    y = AtSpeedAmplitudeResponse(sp, speed)(np.array([x]), theta)[0]
    model = sp.model(np.array(x))
    ref = [_dense_tool_amplitude(model, speed, t) for t in theta]
    np.testing.assert_allclose(y, ref, rtol=1e-8)
    z = np.concatenate([x, theta[1]])
    assert PointwiseAtSpeed(sp, speed)(z) == pytest.approx(ref[1], rel=1e-8)


def test_at_speed_amplitude_never_exceeds_the_peak_over_the_range():
    sp = reference_spindle()
    X = np.array([[2000.0, 465.8, 65.0], [3000.0, 600.0, 80.0], [1000.0, 350.0, 50.0]])
    theta = np.array([[1.0, 1.0], [1.1, 0.9]])
    peak = PeakAmplitudeResponse(sp)(X, theta)
    for s in (1000.0, 12000.0, 24000.0):
        assert np.all(AtSpeedAmplitudeResponse(sp, s)(X, theta) <= peak * (1 + 1e-9))


def test_response_spec_builds_the_matching_fe_functions():
    sp = reference_spindle()
    assert isinstance(ResponseSpec().fe_response(sp), PeakAmplitudeResponse)
    assert isinstance(ResponseSpec().pointwise(sp), PointwisePeak)
    r = ResponseSpec("at_speed", 18000).fe_response(sp)
    assert isinstance(r, AtSpeedAmplitudeResponse) and r.speed_rpm == 18000.0
    assert ResponseSpec("at_speed", 18000).pointwise(sp).speed_rpm == 18000.0


@pytest.mark.parametrize("kw,match", [
    ({"kind": "rms"}, r"response.kind = 'rms' is not allowed: must be one of \['peak', "),
    ({"kind": "at_speed"}, r"response.speed_rpm = None is not allowed.*required with kind"),
    ({"kind": "at_speed", "speed_rpm": -5.0}, r"response.speed_rpm = -5.0 is not allowed"),
    ({"kind": "at_speed", "speed_rpm": float("nan")}, r"response.speed_rpm = nan"),
    ({"kind": "peak", "speed_rpm": 24000.0}, r"speed_rpm = 24000.0 is not allowed with kind"),
])
def test_bad_response_spec_names_the_field(kw, match):
    with pytest.raises(ValueError, match=match):
        ResponseSpec(**kw)


def test_at_speed_response_rejects_a_bad_speed():
    with pytest.raises(ValueError, match=r"speed_rpm = 0.0 is not allowed"):
        AtSpeedAmplitudeResponse(reference_spindle(), 0.0)


@pytest.mark.known_answer
@pytest.mark.parametrize("effects", ["default", "housing_on_front"])
def test_condensed_method_equals_the_direct_solve(effects):
    """Known answer: the direct solve (one whole-system solve per θ). 60 θ go through the
    θ-polynomial coupling (9 node solves); 3 θ, and a housing stage on a θ bearing, through the
    row-by-row coupling of the condensed rotor."""
    from dataclasses import replace

    from surrogate_rbrdo.spindle.effects import HousingFlexibility

    sp = reference_spindle()
    if effects == "housing_on_front":
        sp = replace(sp, effects=(*sp.effects, HousingFlexibility(
            bearings=("front",), k_N_per_m=3e8, m_kg=12.0, c_Ns_per_m=3000.0)))
    X = np.array([[3000.0, 442.5, 65.7], [2000.0, 465.8, 65.0], [1000.0, 750.0, 50.0]])
    theta = np.random.default_rng(4).normal(1.0, [0.0605, 0.0641], size=(60, 2))
    for s in (9000.0, 24000.0):
        direct = AtSpeedAmplitudeResponse(sp, s)(X, theta)
        cond = AtSpeedAmplitudeResponse(sp, s, method="condensed")
        np.testing.assert_allclose(cond(X, theta), direct, rtol=1e-9)
        np.testing.assert_allclose(cond(X, theta[:3]), direct[:, :3], rtol=1e-9)


def test_fe_methods_are_checked():
    sp = reference_spindle()
    with pytest.raises(ValueError, match=r"method = 'fast' is not allowed: must be one of"):
        AtSpeedAmplitudeResponse(sp, 24000.0, method="fast")
    with pytest.raises(ValueError, match=r"method = 'condensed' is not allowed with the peak"):
        ResponseSpec().fe_response(sp, "condensed")
    r = ResponseSpec("at_speed", 24000.0).fe_response(sp, "condensed")
    assert r.method == "condensed"
