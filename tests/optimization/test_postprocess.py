"""Post-processing: fronts, ASF compromise, MBR, tables, CSV."""

import csv

import numpy as np
import pytest

from surrogate_rbrdo.formulations import DeterministicOptions, FormulationOptions, make_formulation
from surrogate_rbrdo.optimization import (
    NSGA2Options,
    archive_front,
    asf_compromise,
    feasible_pareto,
    front_table,
    mbr_table,
    nondominated,
    run_nsga2,
    select_compromise,
    strategy_table,
    write_csv,
)
from surrogate_rbrdo.optimization.toys import LinearMixToy


def brute_nondominated(F):
    n = len(F)
    out = np.ones(n, bool)
    for i in range(n):
        for j in range(n):
            if np.all(F[j] <= F[i]) and np.any(F[j] < F[i]):
                out[i] = False
    return out


@pytest.mark.parametrize("n_obj", [2, 3])
def test_nondominated_matches_brute_force(n_obj):
    F = np.random.default_rng(n_obj).integers(0, 6, size=(80, n_obj)).astype(float)
    got = nondominated(F)
    ref = brute_nondominated(F)
    # duplicates keep one copy: compare the sets of non-dominated vectors
    assert {tuple(r) for r in F[got]} == {tuple(r) for r in F[ref]}
    assert got.sum() == len({tuple(r) for r in F[ref]})


def test_feasible_pareto_ignores_infeasible_dominators():
    F = np.array([[0.0, 0.0], [1.0, 2.0], [2.0, 1.0]])
    G = np.array([[0.1], [0.0], [-1.0]])
    assert feasible_pareto(F, G).tolist() == [False, True, True]


def test_asf_on_a_symmetric_front_and_weights():
    t = np.linspace(0, 1, 101)
    F = np.column_stack([t, (1 - t) * 10.0])      # normalisation makes the scale irrelevant
    assert asf_compromise(F) == 50
    assert asf_compromise(F, (0.25, 0.75)) == 25   # w1 f1 = ... : f̃1/0.25 = f̃2/0.75
    with pytest.raises(ValueError, match="weights"):
        asf_compromise(F, (0.5, -0.5))


def test_mbr_paper_table6():
    # paper Table 5 compromises → Table 6 MBR 0.55 and 0.39 μm per percentage point (§3.9)
    rows = mbr_table([(0.01, 17.25e-6, 8.15e-6), (0.10, 15.02e-6, 12.42e-6),
                      (0.05, 16.44e-6, 9.69e-6)])
    assert [r["from_pct"] for r in rows] == [10.0, 5.0]
    assert rows[0]["mbr_um_per_pp"] == pytest.approx(0.55, abs=0.005)
    assert rows[1]["mbr_um_per_pp"] == pytest.approx(0.39, abs=0.006)
    assert rows[0]["delta_mean_um"] == pytest.approx(1.42)
    with pytest.raises(ValueError, match="two"):
        mbr_table([(0.1, 1.0, 1.0)])


def test_compromise_tables_and_csv(tmp_path):
    toy = LinearMixToy()
    form = make_formulation(
        "rbrdo", response=toy.response, inputs=toy.inputs(), limit=toy.limit,
        options=FormulationOptions(p_target=0.12, n_theta=2000,
                                   deterministic=DeterministicOptions(stress=False,
                                                                      resonance="none")),
        rng=np.random.default_rng(0))
    res = run_nsga2(form, [0.0], [1.0], rng=np.random.default_rng(1),
                    options=NSGA2Options(pop_size=20, n_gen=10))
    idx = archive_front(res)
    c = select_compromise(res)
    assert c.index in idx and np.all(c.G <= 0)
    assert c.mean == res.archive.F[c.index, 0] and c.std == res.archive.F[c.index, 1]
    est = form.assess(c.x[None, :])
    assert est.pf[0] == c.pf
    rows = strategy_table({"rbrdo 12 %": {"x": c.x, "mean": c.mean, "std": c.std, "pf": c.pf,
                                          "p_target": 0.12, "G": c.G,
                                          "constraint_names": form.constraint_names}},
                          design_names=["x"])
    assert rows[0]["pf_pct"] == pytest.approx(100 * c.pf) and "g_pf" in rows[0]
    ft = front_table(res, design_names=["x"])
    assert len(ft) == idx.size
    path = write_csv(tmp_path / "front.csv", ft)
    with open(path, newline="") as fh:
        back = list(csv.DictReader(fh))
    assert len(back) == idx.size and float(back[0]["mean_um"]) == pytest.approx(ft[0]["mean_um"])
    assert [p.name for p in tmp_path.iterdir()] == ["front.csv"]   # no temp file left
    with pytest.raises(ValueError):
        write_csv(tmp_path / "bad.csv", [{"a": 1}], columns=["b"])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["front.csv"]
