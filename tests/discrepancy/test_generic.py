"""Generic local sensitivities against finite differences of the truth-only geometry changes."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from surrogate_rbrdo.discrepancy.fit import fit
from surrogate_rbrdo.discrepancy.forward import ForwardModel
from surrogate_rbrdo.discrepancy.generic import (
    NODE_SPRING_SCALE,
    PLAUSIBLE,
    generic_columns,
    generic_labels,
    node_spring_ranges,
)
from surrogate_rbrdo.discrepancy.problem import Problem
from surrogate_rbrdo.discrepancy.truth_effects import magnetic_pull
from surrogate_rbrdo.spindle.assembly import build_model

from .conftest import baseline_1x


@pytest.mark.known_answer
def test_node_spring_column_is_the_derivative_of_a_grounded_spring(spindle):
    sp, g = spindle
    fm, data = baseline_1x(spindle, seed=0)
    ch = data.channels
    prob = Problem(fm, data)
    par = prob.parametrisation()
    f = fit(prob, par, par.x0())
    G = generic_columns(prob, f)
    u = tuple(v[0] for v in f.evaluation.unbalance)
    y0 = prob.model_vector(par, f.x[None], u)[0]
    eps = 1e3                                           # N/m, a small negative spring
    fm2 = ForwardModel(magnetic_pull(g, k_N_per_m=eps, position_mm=350.0), sp.effects, ch,
                       (0.0, 350.0), ("front", "rear"))
    prob2 = Problem(fm2, data)
    rows = par.rows(f.x[None])
    y1 = prob2.data_vector(type(rows)(rows.theta, np.hstack([rows.damping, np.ones((1, 1))]),
                                      rows.mass, rows.gain, rows.tau, rows.extras), u)[0]
    m = fm.model(())
    ne, nd = m.element_mats.shape[0], len(m.geometry.disks)
    col = G[:y1.size, 2 * ne + 2 * nd + fm.node(m, 350.0)]
    fd = (y1 - y0[:y1.size]) / (-eps) * NODE_SPRING_SCALE
    assert np.linalg.norm(fd - col) < 2e-3 * np.linalg.norm(col)


@pytest.mark.known_answer
def test_a_grounded_spring_may_be_negative_only_at_the_motor(spindle):
    """Passive connections are positive; a negative spring only where the motor's air gap is
    (the motor rotor's node, 350 mm, and its two neighbours); without a motor disk, anywhere."""
    sp, g = spindle
    m = build_model(g, sp.effects)
    rng_ = node_spring_ranges(m)
    motor = int(np.argmin(np.abs(m.z - 0.350)))
    negative = np.flatnonzero(rng_[:, 0] < 0)
    assert negative.tolist() == [motor - 1, motor, motor + 1]
    assert np.all(rng_[:, 1] == PLAUSIBLE["node_spring"][1])
    assert np.all(rng_[np.setdiff1d(np.arange(m.n_nodes), negative), 0] == 0.0)
    assert all(n not in negative for n in m.bearing_nodes)
    g2 = replace(g, disks=tuple(replace(d, name=d.name.replace("motor", "drive"))
                                for d in g.disks))
    assert np.all(node_spring_ranges(build_model(g2, sp.effects))[:, 0]
                  == PLAUSIBLE["node_spring"][0])


def test_springs_at_or_next_to_a_bearing_are_labelled_with_it(spindle):
    """The reference spindle's bearings sit at 100 and 600 mm: the springs at their nodes and
    one element either side carry the bearing's name, no other spring does."""
    sp, g = spindle
    m = build_model(g)
    springs = [lb for lb, _, _ in generic_labels(m) if lb.startswith("grounded spring")]
    assert len(springs) == m.n_nodes
    for name, z_mm in (("front", 100.0), ("rear", 600.0)):
        n = int(np.argmin(np.abs(m.z - z_mm * 1e-3)))
        assert [i for i, lb in enumerate(springs) if lb.endswith(f"beside bearing {name}")] \
            == [n - 1, n, n + 1]
    assert sum("beside bearing" in lb for lb in springs) == 6
