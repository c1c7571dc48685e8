"""Experiment kind ``surrogate_validation`` end to end on a tiny config (known answers: the
full-FE side against a direct PeakAmplitudeResponse call, pass flags against the errors, FE
call accounting and the shared cache)."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest

from surrogate_rbrdo.runner.cli import run_experiment
from surrogate_rbrdo.runner.execute import prepare
from surrogate_rbrdo.spindle.evaluate import PeakAmplitudeResponse
from surrogate_rbrdo.spindle.peak_response import PeakUnbalanceResponse
from surrogate_rbrdo.spindle.reference import credible_spindle, reference_spindle
from surrogate_rbrdo.uncertainty import MultivariateNormal

TINY = """
[experiment]
name = "sv_tiny"
kind = "surrogate_validation"
seed = 7

[surrogate]
n_doe = 14
n_start = 1
n_jobs = 1
backend = "sequential"

[validation]
n_test = 10
n_theta = 20

[validation.variants.al]
active_learning = true
al_n_initial = 10
al_max_added = 4
al_batch_size = 2
al_pool_designs = 15
al_pool_theta = 8
al_n_start = 1

[validation.designs]
subcritical = [2000.0, 330.0, 75.0]
resonant = [2000.0, 650.0, 60.0]
{extra}
"""


def _read(path):
    with open(path) as fh:
        return list(csv.DictReader(fh))


@pytest.fixture(scope="module")
def tiny_run(tmp_path_factory):
    d = tmp_path_factory.mktemp("sv")
    cfg = d / "tiny.toml"
    cfg.write_text(TINY.format(extra=""))
    run = run_experiment(cfg, results_dir=d / "results", run_id="r1", progress=False)
    return d, cfg, run


def test_tiny_run_writes_tables_and_figures(tiny_run):
    _, _, run = tiny_run
    for name in ("metrics.csv", "loo.csv", "mc_comparison.csv", "cost.csv", "meta.json",
                 "summary.json", "parity_main.png", "parity_log_al.png", "calls.json"):
        assert (run.path / name).is_file(), name
    metrics = _read(run.path / "metrics.csv")
    assert [r["variant"] for r in metrics] == ["main", "al"]
    assert all(int(r["n_test"]) == 10 for r in metrics)
    cost = {r["variant"]: r for r in _read(run.path / "cost.csv")}
    assert int(cost["main"]["n_train"]) == 14
    assert 10 <= int(cost["al"]["n_train"]) <= 14       # initial 10 + at most 4 added
    meta = json.loads((run.path / "meta.json").read_text())
    assert meta["seeds"] == {"seed": 7}


def test_fe_side_equals_direct_fe_mc_and_flags_match_errors(tiny_run):
    _, _, run = tiny_run
    rows = [r for r in _read(run.path / "mc_comparison.csv") if r["variant"] == "main"]
    assert [r["design"] for r in rows] == ["subcritical", "resonant"]
    # the θ sample is the third child of the experiment seed (documented in the module)
    theta = MultivariateNormal([1.0, 1.0], std=[0.0605, 0.0641]).sample(
        20, rng=np.random.default_rng(np.random.SeedSequence(7).spawn(3)[2]))
    y = PeakAmplitudeResponse(reference_spindle())(np.array([[2000.0, 650.0, 60.0]]), theta)
    assert float(rows[1]["mean_fe_um"]) == pytest.approx(y.mean() * 1e6, abs=1e-4)
    assert float(rows[1]["std_fe_um"]) == pytest.approx(y.std(ddof=1) * 1e6, abs=1e-4)
    assert float(rows[1]["pf_fe"]) == pytest.approx(np.mean(y > 19.5e-6))
    for r in rows:
        assert (r["ok_mean"] == "True") == (float(r["mean_rel_err"]) <= 0.05)
        assert (r["ok_pf"] == "True") == (float(r["pf_abs_err"]) <= float(r["pf_tol"]))


def test_fe_calls_counted_and_rerun_hits_cache(tiny_run):
    d, cfg, run = tiny_run
    s1 = json.loads((run.path / "meta.json").read_text())
    assert s1["fe_calls"]["mc"] == 2 * 20 and s1["fe_calls"]["test"] == 10
    assert s1["fe_calls"]["train_main"] == 14
    # per variant: 10 test points and 2 designs x 20 θ, counted at the model
    assert s1["surrogate_calls"] == {"main": 50, "al": 50, "total": 100}
    run2 = run_experiment(cfg, results_dir=d / "results", run_id="r2", progress=False)
    s2 = json.loads((run2.path / "meta.json").read_text())
    assert s2["fe_calls"] == {k: 0 for k in s1["fe_calls"]}
    assert _read(run2.path / "mc_comparison.csv") == _read(run.path / "mc_comparison.csv")


@pytest.mark.parametrize("extra,match", [
    ("[limit]\ndelta_lim = 19.5", "delta_lim"),
    ("[uncertainty]\nstd = [0.06, -0.06]", "std"),
    ('[response]\nkind = "rms"', r"response.kind = 'rms' is not allowed"),
    ('[response]\nkind = "at_speed"\nspeed_rpm = 90000.0',
     r"response.speed_rpm = 90000.0 is not allowed: must lie in the spindle's speed range"),
    ('[response]\nkind = "peak_unbalance"\n[validation.variants]\nres = {structure = '
     '"resonance"}', r"validation.variants.res.structure = 'resonance' is not allowed with "
     r"response.kind = 'peak_unbalance'"),
    ('[uncertainty.unbalance]\nmagnitude = "limit"', r"uncertainty.unbalance is not allowed "
     r"with response.kind = 'peak'"),
])
def test_bad_config_names_key(tmp_path, extra, match):
    cfg = tmp_path / "bad.toml"
    cfg.write_text(TINY.format(extra=extra))
    with pytest.raises(ValueError, match=match):
        run_experiment(cfg, results_dir=tmp_path / "res", progress=False)


def test_structure_fe_is_refused_before_any_work(tmp_path):
    cfg = tmp_path / "bad.toml"
    cfg.write_text(TINY.format(extra="").replace("active_learning = true", 'structure = "fe"'))
    with pytest.raises(ValueError, match=r"variants\.al\.structure = 'fe' is not allowed"):
        run_experiment(cfg, results_dir=tmp_path / "res", progress=False)
    assert not (tmp_path / "res").exists()   # no run folder


def test_bad_variant_names_variant(tmp_path):
    cfg = tmp_path / "bad.toml"
    cfg.write_text(TINY.format(extra="").replace("al_n_start = 1", "al_n_start = 0"))
    with pytest.raises(ValueError, match=r"validation\.variants\.al\.al_n_start = 0 is not"):
        run_experiment(cfg, results_dir=tmp_path / "res", progress=False)


TINY_RES = """
[experiment]
name = "sv_tiny_res"
kind = "surrogate_validation"
seed = 7

[surrogate]
n_doe = 16
n_start = 1
al_n_start = 1
n_jobs = 1
backend = "sequential"

[validation]
n_test = 10
n_theta = 20
n_theta_nc = 6

[validation.variants.copy]
structure = "global"

[validation.variants.res]
structure = "resonance"
res_n_band = 4
res_band = 0.1
res_band_pool = 2000

[validation.designs]
subcritical = [2000.0, 330.0, 75.0]
boundary = [3000.0, 490.0, 70.0]
"""


def test_tiny_run_with_resonance_variant(tmp_path):
    cfg = tmp_path / "res.toml"
    cfg.write_text(TINY_RES)
    run = run_experiment(cfg, results_dir=tmp_path / "results", run_id="r1", progress=False)
    cost = {r["variant"]: r for r in _read(run.path / "cost.csv")}
    # a variant equal to main trains on the same DOE (fresh seed copy per variant)
    m = {r["variant"]: r for r in _read(run.path / "metrics.csv")}
    assert {k: v for k, v in m["copy"].items() if k != "variant"} == \
        {k: v for k, v in m["main"].items() if k != "variant"}
    assert int(cost["res"]["n_train"]) == 20 and cost["res"]["structure"] == "resonance"
    assert cost["res"]["transform"] == "log" and cost["copy"]["structure"] == "global"
    loo = [r for r in _read(run.path / "loo.csv") if r["variant"] == "res"]
    assert loo[0]["method"] == "closed_form_combined"
    assert {r["method"] for r in loo[1:]} >= {"closed_form:nc", "closed_form:ares"}
    sub = _read(run.path / "resonance_submodels.csv")
    assert sub[0]["quantity"] == "critical_rpm" and int(sub[0]["n"]) == 10
    nc = _read(run.path / "nc_at_designs.csv")
    assert [r["design"] for r in nc] == ["subcritical", "boundary"]
    # the FE n_c at the boundary design is near n_max (r within a few % of 1)
    assert 0.95 < float(nc[1]["r_min"]) <= float(nc[1]["r_max"]) < 1.05
    s = json.loads((run.path / "meta.json").read_text())
    # test points: 10 scalar + 10 resonance + 2 designs × 6 θ resonance
    assert s["fe_calls"]["test"] == 10 + 10 + 12
    assert s["fe_calls"]["train_res"] == 20


TINY_PU = """
[experiment]
name = "sv_tiny_pu"
kind = "surrogate_validation"
seed = 7

[spindle]
geometry = "credible"

[uncertainty]
std = [0.015, 0.033]

[uncertainty.unbalance]
magnitude = "disk"

[response]
kind = "peak_unbalance"

[limit]
delta_lim_um = 1.0

[surrogate]
n_doe = 14
n_start = 1
n_jobs = 1
backend = "sequential"

[validation]
n_test = 9
n_theta = 20

[validation.variants.sub]
structure = "substructure"
n_doe = 20
n_start = 1

[validation.designs]
optimum = [237.5, 390.0, 74.0]
"""


def test_tiny_run_on_the_credible_problem(tmp_path):
    """The random-unbalance peak: θ has the unbalance columns, the FE side is the FE model's
    own peak search (known answer: ``PeakUnbalanceResponse(method="direct")`` on the same θ
    sample, the third child of the seed), and the substructure variant takes the problem."""
    cfg = tmp_path / "pu.toml"
    cfg.write_text(TINY_PU)
    run = run_experiment(cfg, results_dir=tmp_path / "results", run_id="r1", progress=False)
    cost = {r["variant"]: r for r in _read(run.path / "cost.csv")}
    assert cost["sub"]["structure"] == "substructure" and int(cost["sub"]["n_train"]) == 20
    plan = prepare(cfg).plan
    assert plan.inputs.dim == 5
    theta = plan.inputs.sample(20, rng=np.random.default_rng(
        np.random.SeedSequence(7).spawn(3)[2]))
    y = PeakUnbalanceResponse(credible_spindle(), method="direct")(
        np.array([[237.5, 390.0, 74.0]]), theta)
    rows = {r["variant"]: r for r in _read(run.path / "mc_comparison.csv")}
    assert float(rows["sub"]["mean_fe_um"]) == pytest.approx(y.mean() * 1e6, abs=1e-4)
    assert float(rows["sub"]["mean_rel_err"]) < 0.05
