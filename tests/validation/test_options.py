"""ValidationOptions: the speed-table form and the peak search's options are checked."""

import numpy as np
import pytest

from surrogate_rbrdo.spindle.harmonic import PeakOptions
from surrogate_rbrdo.validation import Moments, ValidationOptions


def test_speed_table_needs_all_three_keys():
    o = ValidationOptions(speeds_rpm={"start": 1000.0, "stop": 3000.0, "step": 1000.0})
    assert o.speeds_rpm == (1000.0, 2000.0, 3000.0)
    with pytest.raises(ValueError, match="a table needs start, stop and step"):
        ValidationOptions(speeds_rpm={"start": 1000.0, "stop": 3000.0})


@pytest.mark.parametrize(("peak", "field"), [({"n_zoom": 0}, "n_zoom"),
                                              ({"n_refine": 2}, "n_refine"),
                                              ({"n_grid": 1}, "n_grid"),
                                              ({"n_candidates": 0}, "n_candidates")])
def test_peak_search_options_are_checked(peak, field):
    with pytest.raises(ValueError, match=rf"peak.{field} = .* is not allowed"):
        ValidationOptions(peak=PeakOptions(**peak))


def test_moments_from_summary_match_the_samples_for_normal_data():
    """For normal y the normal-theory SE of σ equals the delta-method one (μ₄ = 3σ⁴)."""
    y = np.random.default_rng(3).normal(20e-6, 5e-6, 40_000)
    ref = Moments.of_values(y, 25e-6, 0.95)
    m = Moments.from_summary(ref.n, ref.mean, ref.std, ref.pf, ref.pf_ci, 0.95)
    assert m.mean_se == pytest.approx(ref.mean_se, rel=1e-12)
    assert m.mean_ci == pytest.approx(ref.mean_ci, rel=1e-12)
    assert m.std_se == pytest.approx(ref.std_se, rel=0.03)
    assert (m.pf, m.pf_ci, m.n_fail) == (ref.pf, ref.pf_ci, ref.n_fail)
