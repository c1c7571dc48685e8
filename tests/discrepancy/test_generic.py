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
    shaft_diameter_at,
)
from surrogate_rbrdo.discrepancy.problem import Problem
from surrogate_rbrdo.discrepancy.truth_effects import magnetic_pull
from surrogate_rbrdo.spindle.assembly import build_model
from surrogate_rbrdo.spindle.geometry import SpindleGeometry

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


def _beside(labels):
    """Node -> the bearings its grounded spring's label names (parsed from the label)."""
    out = {}
    for lb in (lb for lb, _, _ in labels if lb.startswith("grounded spring")):
        head, _, tail = lb.partition(" beside bearing")
        node = int(head.split()[-1])
        names = tail.removeprefix("s").strip().replace(" and ", ", ").split(", ")
        out[node] = tuple(n for n in names if n)
    return out


@pytest.mark.known_answer
def test_springs_within_a_shaft_diameter_of_a_bearing_are_labelled_with_it(spindle):
    """The reference spindle's bearings sit at 100 mm (nose 70 mm meets span 65 mm: reach
    70 mm) and 600 mm (span 65 mm meets rear 50 mm: reach 65 mm); computed here from the node
    positions: the springs within that axial distance carry the bearing's name, none other."""
    sp, g = spindle
    m = build_model(g)
    got = _beside(generic_labels(m))
    assert len(got) == m.n_nodes
    z_mm = m.z * 1e3
    for name, z_b, d in (("front", 100.0, 70.0), ("rear", 600.0, 65.0)):
        want = np.flatnonzero(np.abs(z_mm - z_b) <= d + 1e-6).tolist()
        assert [n for n, b in got.items() if b == (name,)] == want
    assert sum(bool(b) for b in got.values()) == 8          # 4 per bearing on this mesh


def test_beside_is_a_distance_not_a_node_count():
    """A shaft of 60 mm diameter: one 300 mm element, then ten of 10 mm; bearings a at 300 mm
    and b at 400 mm. The node one element before a is 300 mm away (node count would call it
    beside a: it is not); nodes three to six elements after a are within 60 mm (node count
    would not); those within 60 mm of both bearings (340-360 mm) name both."""
    law = {"type": "constant", "k_N_per_m": 1e8}
    g = SpindleGeometry.from_dict({
        "sections": [{"length_mm": 300, "outer_diameter_mm": 60, "elements": 1},
                     {"length_mm": 100, "outer_diameter_mm": 60, "elements": 10}],
        "bearings": [{"name": "a", "position_mm": 300, "law": law},
                     {"name": "b", "position_mm": 400, "law": law}],
        "tool_tip_mm": 0.0})
    m = build_model(g)
    z = np.round(m.z * 1e3, 6).tolist()
    got = {z[n]: b for n, b in _beside(generic_labels(m)).items()}
    assert got[0.0] == ()
    assert [k for k, b in got.items() if b == ("a",)] == [300.0, 310.0, 320.0, 330.0]
    assert [k for k, b in got.items() if b == ("a", "b")] == [340.0, 350.0, 360.0]
    assert [k for k, b in got.items() if b == ("b",)] == [370.0, 380.0, 390.0, 400.0]
    assert any(lb.endswith("beside bearings a and b") for lb, _, _ in generic_labels(m))


def test_an_unknown_position_has_no_shaft_diameter(spindle):
    _, g = spindle
    with pytest.raises(ValueError, match="position_mm = 2000"):
        shaft_diameter_at(g, 2000.0)
