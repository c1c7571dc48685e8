"""The ``study`` experiment end to end on a tiny config, and its config errors."""

import csv
import json
from pathlib import Path

import numpy as np
import pytest

from surrogate_rbrdo.runner.cli import run_experiment

TINY = """
[experiment]
name = "tiny"
kind = "study"
seed = 5

[surrogate]
n_doe = 24
n_jobs = 1
n_start = 1

[design_model]
n_train = 10
n_validate = 2

[deterministic]
resonance = "none"

[optimization]
p_targets = [0.10, 0.01]
strategies = ["rdo", "rbdo", "deterministic"]
n_theta = 40
pop_size = 8
n_gen = 4
n_jobs = 1

[verification]
n_theta = 6
n_jobs = 1

[report]
baseline = [2000.0, 465.8, 65.0]
n_speeds = 20
campbell_speeds = 4
n_modes = 2
"""


def _write(tmp_path: Path, text: str) -> Path:
    p = tmp_path / "study.toml"
    p.write_text(text)
    return p


def test_tiny_study_writes_the_expected_files(tmp_path):
    run = run_experiment(_write(tmp_path, TINY), results_dir=tmp_path / "res", run_id="r1",
                         progress=False)
    files = {p.name for p in run.path.iterdir()}
    for f in ("pareto_fronts.csv", "pareto_fronts.png", "compromises.csv", "mbr.csv",
              "verification.csv", "strategy_comparison.csv", "campbell.png",
              "unbalance_response.png", "meta.json", "config.json", "front_designs.png",
              "design_model_validation.json"):
        assert f in files, f
    meta = json.loads((run.path / "meta.json").read_text())
    assert meta["seeds"] == {"seed": 5}
    # FE calls: 24 DOE + 12 design-model + 6 designs x 6 θ verification (baseline, 2 RBRDO
    # compromises, RDO compromise, RBDO and deterministic optima)
    assert meta["fe_calls"]["design_model"] == 12
    assert meta["fe_calls"]["verification"] == 6 * 6
    assert meta["surrogate_calls"]["optimization"] == 5 * 8 * 4 * 40 - 8 * 4 * 39
    ver = (run.path / "verification.csv").read_text().splitlines()
    assert ver[0].startswith("design,preload_N,span_mm,diameter_mm")
    assert len(ver) == 1 + 6
    mbr = list(csv.DictReader((run.path / "mbr.csv").open()))
    # one step (10 % -> 1 %) from the surrogate's and the FE model's compromises, and from the
    # ends of the two fronts
    assert [r["source"] for r in mbr] == ["surrogate_crn", "fe_verification", "front_ends_crn"]
    fronts = list(csv.DictReader((run.path / "pareto_fronts.csv").open()))

    def end(run_label, col):
        return min(float(r[col]) for r in fronts if r["run"] == run_label)

    ends = mbr[2]
    for col, key in (("mean_um", "delta_mean_um"), ("std_um", "delta_std_um")):
        np.testing.assert_allclose(float(ends[key]),
                                   end("rbrdo 1%", col) - end("rbrdo 10%", col), atol=1e-9)
    np.testing.assert_allclose(float(ends["mbr_um_per_pp"]),
                               abs(float(ends["delta_std_um"])) / 9.0, rtol=1e-9)
    # every row says whether the reliability constraint acts at its two levels: front designs
    # with P_f > 0.9 P_target (pareto_fronts.csv holds each front)
    for lev, key in ((10.0, "active_from"), (1.0, "active_to")):
        n = sum(float(r["pf_pct"]) > 0.9 * lev for r in fronts if r["run"] == f"rbrdo {lev:g}%")
        assert all(int(r[key]) == n for r in mbr)
    assert {r["constraint"] for r in mbr} == {
        "active" if int(mbr[0]["active_from"]) + int(mbr[0]["active_to"]) else
        "inactive at both levels"}


def test_refine_round_evaluates_the_chosen_designs(tmp_path):
    text = TINY + "\n[refine]\nrounds = 1\ndesigns = 2\ntheta = 3\ntol = 1e-9\n"
    run = run_experiment(_write(tmp_path, text), results_dir=tmp_path / "res", run_id="r",
                         progress=False)
    meta = json.loads((run.path / "meta.json").read_text())
    assert meta["fe_calls"]["refine"] == 2 * 3          # fresh cache: every point is new
    rows = (run.path / "refine.csv").read_text().splitlines()
    assert rows[0].startswith("round,n_designs,n_theta,fe_points") and len(rows) == 2
    assert rows[1].startswith("1,2,3,6,")
    info = json.loads((run.path / "surrogate_info.json").read_text())
    assert info["n_refine_points"] == 6 and info["n_train"] == 24 + 6
    # two optimisation passes (before and after the refit), each 5 runs x 8 x 4 generations
    # x 40 θ minus the deterministic run's 8 x 4 x 39 (it evaluates nominal θ only)
    assert meta["surrogate_calls"]["optimization"] == 2 * (5 * 8 * 4 * 40 - 8 * 4 * 39)


TINY_FE = TINY.replace("""[surrogate]
n_doe = 24
n_jobs = 1
n_start = 1
""", """[surrogate]
structure = "fe"

[response]
kind = "at_speed"
speed_rpm = 24000.0

[limit]
delta_lim_um = 1.5
""").replace("n_theta = 6\n", "n_theta = 400\nchunk = 400\n")


def test_fe_in_the_loop_study_on_the_at_speed_response(tmp_path):
    """No surrogate: the fronts' μ_y are FE values (checked against an independent FE
    evaluation of the front designs on a fresh θ sample, within its MC error), every
    optimisation call is counted as an FE call, and the verification is FE on both sides."""
    from surrogate_rbrdo.spindle.evaluate import AtSpeedAmplitudeResponse
    from surrogate_rbrdo.spindle.reference import reference_spindle

    assert 'structure = "fe"' in TINY_FE and "chunk = 400" in TINY_FE
    run = run_experiment(_write(tmp_path, TINY_FE), results_dir=tmp_path / "res", run_id="fe",
                         progress=False)
    meta = json.loads((run.path / "meta.json").read_text())
    assert meta["model_in_loop"] == "fe" and meta["response"] == "amplitude at 24000 rpm"
    assert meta["fe_calls"]["doe"] == 0
    assert meta["fe_calls"]["optimization"] == 5 * 8 * 4 * 40 - 8 * 4 * 39
    assert meta["surrogate_calls"]["optimization"] == 0
    fr = np.genfromtxt(run.path / "pareto_fronts.csv", delimiter=",", names=True, dtype=None,
                       encoding="utf-8")
    X = np.column_stack([fr["preload_N"], fr["span_mm"], fr["diameter_mm"]])[:4]
    theta = np.random.default_rng(99).normal(1.0, [0.0605, 0.0641], size=(2000, 2))
    y = AtSpeedAmplitudeResponse(reference_spindle(), 24000.0)(X, theta) * 1e6
    se = y.std(axis=1) / np.sqrt(40) + y.std(axis=1) / np.sqrt(2000)
    assert np.all(np.abs(fr["mean_um"][:4] - y.mean(axis=1)) <= 5 * se)
    # the FE verification used the at-speed response: its μ (400 fresh θ) agrees with an
    # independent 2000-sample evaluation within MC error (the peak over the range would be
    # 1.3-20x larger); no surrogate columns in this mode
    ver = np.genfromtxt(run.path / "verification.csv", delimiter=",", names=True, dtype=None,
                        encoding="utf-8")
    Xv = np.column_stack([ver["preload_N"], ver["span_mm"], ver["diameter_mm"]])
    yv = AtSpeedAmplitudeResponse(reference_spindle(), 24000.0)(Xv, theta) * 1e6
    se_v = yv.std(axis=1) / np.sqrt(400) + yv.std(axis=1) / np.sqrt(2000)
    assert np.all(np.abs(ver["mean_um_fe"] - yv.mean(axis=1)) <= 5 * se_v)
    assert np.all(np.isnan(ver["mean_um_surrogate"]))
    # every FE call is counted: optimisation, verification (6 x 400) and the CRN assessment
    # there (μ/σ/P_f of the 6 chosen designs x 40 θ, once; their g_det come from the design
    # model)
    assert meta["fe_calls"]["verification"] == 6 * 400 + 6 * 40


TINY_SUB = TINY_FE.replace('structure = "fe"', 'structure = "substructure"\nn_doe = 40\n'
                           'n_jobs = 1\nn_start = 1')


def test_substructure_surrogate_study_on_the_at_speed_response(tmp_path):
    """The substructure surrogate in the loop: 40 FE calls of training (designs only), and at
    every chosen design its μ, σ and P_f on the verification θ sample agree with the FE
    model's on the same sample (the known answer) within 2 % and 1 point."""
    run = run_experiment(_write(tmp_path, TINY_SUB), results_dir=tmp_path / "res",
                         run_id="sub", progress=False)
    meta = json.loads((run.path / "meta.json").read_text())
    assert meta["fe_calls"]["doe"] == 40 and meta["response"] == "amplitude at 24000 rpm"
    ver = np.genfromtxt(run.path / "verification.csv", delimiter=",", names=True, dtype=None,
                        encoding="utf-8")
    np.testing.assert_allclose(ver["mean_um_surrogate"], ver["mean_um_fe"], rtol=0.02)
    np.testing.assert_allclose(ver["std_um_surrogate"], ver["std_um_fe"], rtol=0.02)
    assert np.all(np.abs(ver["pf_pct_surrogate"] - ver["pf_pct_fe"]) <= 1.0)
    info = json.loads((run.path / "surrogate_info.json").read_text())
    assert info["structure"] == "substructure" and info["n_train"] == 40


TINY_CREDIBLE = """
[experiment]
name = "tiny_credible"
kind = "study"
seed = 3

[spindle]
geometry = "credible"

[uncertainty]
std = [0.015, 0.033]

[response]
kind = "peak_unbalance"

[limit]
delta_lim_um = 1.0

[surrogate]
structure = "fe"

[deterministic]
stress = false
resonance = "separation"
practice = true

[[constraints]]
name = "slenderness"
expression = "span_mm / diameter_mm <= 9"

[optimization]
p_targets = [0.05]
strategies = ["rbdo"]
n_theta = 120
pop_size = 8
n_gen = 3
n_jobs = 1
reliability_measure = "quantile"
pf_bound = "upper"
single_objective_optimizer = "slsqp"
single_objective_options = { maxiter = 3, x0 = [237.5, 390.0, 74.0] }

[verification]
n_theta = 8
n_jobs = 1
campbell_speeds = 6
front_designs = 2
front_n_theta = 8

[report]
n_speeds = 20
campbell_speeds = 4
n_modes = 2
"""


def test_credible_problem_from_config(tmp_path):
    """The credible problem end to end: 5 θ columns (stiffness, unbalance fractions, relative
    phase), the practice checks, the exact API guard and an expression constraint in every
    formulation, SLSQP for RBDO, no design model (nothing in g_det needs it), and each chosen
    design checked by the FE peak search and its damped Campbell diagram."""
    from surrogate_rbrdo.spindle.practice import PracticeConstraints
    from surrogate_rbrdo.spindle.reference import credible_spindle
    from surrogate_rbrdo.spindle.separation import ResonanceGuard

    run = run_experiment(_write(tmp_path, TINY_CREDIBLE), results_dir=tmp_path / "res",
                         run_id="c", progress=False)
    meta = json.loads((run.path / "meta.json").read_text())
    assert meta["response"] == "peak amplitude, random unbalance"
    assert meta["fe_calls"]["design_model"] == 0
    assert not (run.path / "design_model_validation.json").exists()
    ver = list(csv.DictReader((run.path / "verification.csv").open()))
    assert [r["design"] for r in ver] == ["baseline", "rbrdo 5%", "rbdo 5%"]
    sp = credible_spindle()
    X = np.array([[float(r[k]) for k in ("preload_N", "span_mm", "diameter_mm")] for r in ver])
    # the verification's constraint columns are the library's checks at the same designs
    np.testing.assert_allclose([float(r["g_speed_front"]) for r in ver],
                               PracticeConstraints(sp)(X)[:, 0], rtol=1e-12)
    np.testing.assert_allclose([float(r["g_resonance_separation"]) for r in ver],
                               ResonanceGuard(sp)(X)[:, 0], rtol=1e-9)
    np.testing.assert_allclose([float(r["g_slenderness"]) for r in ver],
                               X[:, 1] / X[:, 2] - 9.0, rtol=1e-12)
    # the baseline runs through its first critical speed (~21 800 rpm, damped Campbell)
    assert ver[0]["criticals_in_range_fe"] == "1"
    assert abs(float(ver[0]["first_critical_rpm_fe"]) / 21780.0 - 1) < 2e-3
    comp = {r["run"]: r for r in csv.DictReader((run.path / "compromises.csv").open())}
    assert set(comp) == {"rbrdo 5%", "rbdo 5%"}
    cfg = json.loads((run.path / "config.json").read_text())
    assert cfg["optimization"]["single_objective_optimizer"] == "slsqp"
    # the RBRDO front checked by the FE model too: at most 2 of its designs, the FE moments
    # of a design equal to the chosen one's where the two coincide
    fv = list(csv.DictReader((run.path / "front_verification.csv").open()))
    assert 1 <= len(fv) <= 2 and {r["run"] for r in fv} == {"rbrdo 5%"}
    assert all(float(r["std_um_fe"]) > 0 for r in fv)
    assert any(r["fe_nondominated"] == "True" for r in fv)


@pytest.mark.slow
def test_same_seed_same_compromises(tmp_path):
    a = run_experiment(_write(tmp_path, TINY), results_dir=tmp_path / "res", run_id="a")
    b = run_experiment(_write(tmp_path, TINY), results_dir=tmp_path / "res", run_id="b")
    for f in sorted(a.path.glob("*.csv")):        # no timing column: byte-identical
        assert f.read_bytes() == (b.path / f.name).read_bytes(), f.name


@pytest.mark.parametrize("old,new,match", [
    ('strategies = ["rdo", "rbdo", "deterministic"]', 'strategies = ["rdo", "robust"]',
     r"optimization.strategies\[1\] = 'robust' is not allowed: must be one of \[.*'rbrdo'"),
    ("p_targets = [0.10, 0.01]", "p_targets = [0.10, 1.5]",
     r"optimization.p_targets\[1\] = 1.5 is not allowed: must lie in \(0.0, 1.0\)"),
    ("n_theta = 40", 'n_theta = 40\nestimator = "mcmc"',
     r"optimization.estimator = 'mcmc' is not allowed: must be one of .*'is'"),
    ("pop_size = 8", "pop_size = 8\nweights = [0.5, 0.0]",
     r"optimization.weights\[1\] = 0.0 is not allowed"),
    ("n_gen = 4", "n_gen = 0", r"optimization.n_gen = 0 is not allowed"),
    ("n_doe = 24", "n_doe = 0", r"surrogate.n_doe = 0 is not allowed"),
    ("n_theta = 6", "n_theta = 6\nn_thetas = 3",
     r"unknown key verification.n_thetas; allowed: \['campbell_speeds', 'chunk'"),
    ('resonance = "none"', 'resonance = "campbell"', r"resonance = 'campbell' is not allowed"),
    ("n_modes = 2", "n_modes = 2\n[refine]\nrounds = 1\ntheta = 1",
     r"refine.theta = 1 is not allowed"),
    ("n_modes = 2", "n_modes = 2\n[refine]\nround = 1", r"unknown key refine.round"),
    ("n_start = 1", 'n_start = 1\nstructure = "resonance"\n[response]\nkind = "at_speed"\n'
     "speed_rpm = 24000.0", r"surrogate.structure = 'resonance' is not allowed with "
     r"response.kind = 'at_speed'"),
    ("n_doe = 24\nn_jobs = 1\nn_start = 1", 'structure = "fe"\n[refine]\nrounds = 1',
     r"refine.rounds = 1 is not allowed with surrogate.structure = 'fe'"),
    ("n_start = 1", 'n_start = 1\nstructure = "fe"',
     r"unknown key surrogate.n_doe; allowed: \['fe_method'\]"),
    ("n_start = 1", 'n_start = 1\nstructure = "substructure"\n[refine]\nrounds = 1',
     r"refine.rounds = 1 is not allowed with surrogate.structure = 'substructure'"),
    ("n_start = 1", 'n_start = 1\n[response]\nkind = "at_speed"',
     r"response.speed_rpm = None is not allowed"),
    ("n_start = 1", 'n_start = 1\n[response]\nspeed = 3', r"unknown key response.speed"),
    ("n_start = 1", 'n_start = 1\n[response]\nkind = "at_speed"\nspeed_rpm = 30000',
     r"response.speed_rpm = 30000.0 is not allowed: must lie in the spindle's speed range"),
    ("n_start = 1", 'n_start = 1\nfe_method = "condensed"',
     r"unknown key surrogate.fe_method; allowed: \[.*'n_doe'"),
    ("n_doe = 24\nn_jobs = 1\nn_start = 1", 'structure = "fe"\nfe_method = "condensed"',
     r"fe_method = 'condensed' is not allowed with response.kind = 'peak'"),
])
def test_bad_config_fails_before_work(tmp_path, old, new, match):
    assert old in TINY
    cfg = _write(tmp_path, TINY.replace(old, new, 1))
    with pytest.raises(ValueError, match=match):
        run_experiment(cfg, results_dir=tmp_path / "res", run_id="bad")
    # nothing happened: no run folder, no FE cache
    assert not (tmp_path / "res").exists()


def test_optimizer_is_chosen_from_the_config(tmp_path):
    """optimization.optimizer selects from the OPTIMIZERS registry (optuna's NSGA-II here):
    the same stages, the runs recorded with the optimiser's name and seed."""
    text = TINY.replace("n_jobs = 1\n\n[verification]",
                        'n_jobs = 1\noptimizer = "optuna"\n\n[verification]')
    assert 'optimizer = "optuna"' in text
    run = run_experiment(_write(tmp_path, text), results_dir=tmp_path / "res", run_id="o",
                         progress=False)
    meta = json.loads((run.path / "meta.json").read_text())
    assert meta["status"] == "complete" and meta["optimizer"] == "optuna"
    assert set(meta["optimizer_seeds"]) == {"rbrdo 10%", "rbrdo 1%", "rdo 5%", "rbdo 5%",
                                            "deterministic 5%"}
    rows = list(csv.DictReader((run.path / "compromises.csv").open()))
    assert len(rows) == 5
