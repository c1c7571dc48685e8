"""What a study config with its problem tables left out solves (review item 19): the paper's
published problem, as ``rbrdo kinds`` says, and not the credible reference problem."""

from __future__ import annotations

import numpy as np
import pytest

from surrogate_rbrdo.runner.cli import describe_kinds
from surrogate_rbrdo.runner.execute import prepare
from surrogate_rbrdo.spindle.reference import reference_spindle
from surrogate_rbrdo.study import TABLE4_STD, credible_problem

BARE = """[experiment]
name = "bare"
kind = "study"
[surrogate]
n_doe = 20
[optimization]
n_theta = 40
pop_size = 8
n_gen = 2
[verification]
n_theta = 10
"""


@pytest.mark.known_answer
def test_left_out_problem_tables_are_the_papers_problem(tmp_path):
    cfg = tmp_path / "bare.toml"
    cfg.write_text(BARE)
    p = prepare(cfg).plan.problem
    # the paper's numbers (paper-notes §2, §13): δ_lim 19.5 µm, the peak over the speed
    # range, θ = the Table 4 pooled CoVs, f_n1 >= 1.2 × 24 000 rpm / 60, σ_yield 930 MPa
    assert p.limit.threshold == pytest.approx(19.5e-6)
    assert p.response.kind == "peak"
    assert p.spindle.geometry == reference_spindle().geometry
    assert np.allclose(np.sqrt(np.diag(p.inputs.cov)), TABLE4_STD)
    d = p.deterministic
    assert (d.stress, d.resonance, d.factor, d.yield_strength_pa) == (True, "paper", 1.2, 930e6)
    assert d.omega_max == pytest.approx(24000.0 * 2 * np.pi / 60)
    # ... which is not the credible reference problem, and rbrdo kinds says both
    assert credible_problem().limit.threshold != p.limit.threshold
    study = describe_kinds().split("\n\nstudy\n", 1)[1].split("\n\n", 1)[0]
    for shown in ("[limit] delta_lim_um=19.5", "[response] kind='peak'",
                  "[spindle] geometry='reference'", "resonance='paper'", "practice=False",
                  "NOT the credible reference problem"):
        assert shown in study, shown
