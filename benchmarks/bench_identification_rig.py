"""Identification on the virtual rig's records, against the rig's known truth.

    PYTHONPATH=$PWD python3 benchmarks/bench_identification_rig.py            # one campaign
    PYTHONPATH=$PWD python3 benchmarks/bench_identification_rig.py --seeds 12 # coverage
    PYTHONPATH=$PWD python3 benchmarks/bench_identification_rig.py --sources  # error sources
    PYTHONPATH=$PWD python3 benchmarks/bench_identification_rig.py --noise-free

One campaign (the paper's: 50 speeds in 1 000–24 000 rpm × 20 runs, 1 s records, each speed
with and without a 50 g mm trial mass at the nose: 2 000 records → 1 000 identified vectors)
is simulated by ``rig.run_campaign``, then identified from its records
(``identification.run_identification``: demodulation, corrections, trial pairs, condensation,
trend, scatter, systematic budget) and compared with the truth: the population trend and
physical scatter over thermal states (``rigtruth.population_truth``) and each record's own
coefficients (``rigtruth.truth_coefficients``). Timings are measured under the machine's load
(printed); the campaigns are cached in ``--out``.
"""

from __future__ import annotations

import argparse
import os
import resource
import time
from pathlib import Path

import numpy as np

from surrogate_rbrdo.identification import (
    IdentificationOptions,
    identify_records,
    run_identification,
)
from surrogate_rbrdo.identification.rigtruth import population_truth, truth_coefficients
from surrogate_rbrdo.reporting.plots_identification import write_identification_figures
from surrogate_rbrdo.rig import CampaignOptions, open_dataset, reference_truth, run_campaign
from surrogate_rbrdo.rig.sensors import DAQModel, KeyphasorModel, ProbeModel, SensorSet
from surrogate_rbrdo.rig.truth import Variability
from surrogate_rbrdo.spindle import reference_spindle

TRIAL = (0.0, 5e-5, 0.0)
#: the rig's "ideal" keyphasor (tests/rig/conftest.py): slow edges, no phase error to speak of
SLOW_KP = KeyphasorModel(notch_deg=120.0, edge_deg=60.0)
K_COLS = [0, 1, 4, 5]
PAPER_T3 = {"front": (3.183, 3.125, 2.985, 2.856, 2.712), "rear": (2.764, 2.716, 2.638, 2.514,
                                                                     2.382)}
T3_SPEEDS = (1000.0, 5000.0, 10000.0, 15000.0, 20000.0)


def campaign(out: Path, seed: int, *, truth=None, sensors=None, repeats=20,
             speeds=None, impacts=0) -> tuple[Path, object]:
    truth = reference_truth() if truth is None else truth
    sensors = SensorSet() if sensors is None else sensors
    opts = CampaignOptions(runup=None, impacts_per_direction=impacts, trial_unbalance=TRIAL,
                           sensors=sensors, repeats=repeats,
                           **({} if speeds is None else {"speeds_rpm": tuple(speeds)}))
    path = out / f"campaign_{seed}"
    if not (path / "summary.json").is_file():
        t = time.perf_counter()
        run_campaign(truth, opts, path, rng=np.random.default_rng(seed))
        print(f"  campaign {seed} simulated in {time.perf_counter() - t:.1f} s")
    return path, truth


def _model():
    sp = reference_spindle()
    return sp.model(sp.baseline)


def _truths(path, truth, run):
    ds = open_dataset(path / "dataset")
    prov = {r["id"]: ds.load(r).provenance for r in ds.index}
    ids = [i.split("|")[1] for i in run.responses.record_ids]
    per_record = truth_coefficients(truth, [prov[i] for i in ids], run.responses.speed_rpm)
    pop = population_truth(truth, prov[ids[0]], run.uncertainty.speeds_rpm, n_runs=2000)
    return per_record, pop


def coverage_of(run, pop) -> dict:
    """Trend intervals (at every identified speed) and physical-scatter intervals against the
    population truth."""
    u = run.uncertainty
    cover = []
    for i, s in enumerate(pop.speeds_rpm):
        lo, hi = u.trend_interval(s)
        t = pop.mean[i, K_COLS]
        cover.append((lo <= t) & (t <= hi))
    true_sd = np.sqrt(np.mean(np.diagonal(pop.factor_cov, axis1=1, axis2=2), axis=0))[K_COLS]
    lo, hi = u.scatter_fit.ci_sd.T
    return {"trend": np.array(cover), "scatter": (lo <= true_sd) & (true_sd <= hi),
            "sd": np.sqrt(np.diag(u.scatter_fit.physical)), "true_sd": true_sd}


def report_one(out: Path, seed: int, n_jobs: int) -> None:
    path, truth = campaign(out, seed)
    model = _model()
    t = time.perf_counter()
    run = run_identification(model, path, out / f"run_{seed}", IdentificationOptions(
        n_jobs=n_jobs), rng=np.random.default_rng(0))
    wall = time.perf_counter() - t
    t = time.perf_counter()
    write_identification_figures(model, run, out / f"run_{seed}")
    figs = time.perf_counter() - t
    print(f"identification of {run.responses.n} vectors from {2 * run.responses.n} records: "
          f"{wall:.1f} s (demodulation {run.timings['demodulation_s']:.1f} s, identification + "
          f"uncertainty {run.timings['identification_s']:.1f} s), figures {figs:.1f} s, "
          f"n_jobs {n_jobs}; load average {os.getloadavg()[0]:.1f}; peak RSS "
          f"{resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024:.0f} MB")
    fc = run.campaign.flag_counts
    print(f"flags: used {fc['used']} / {fc['records']}; unexcited {fc['unexcited']}, imprecise "
          f"{fc['imprecise']}, near a pole {fc['near_pole']}; first used speed "
          f"{run.uncertainty.speed_range_rpm[0]:.0f} rpm")
    per_record, pop = _truths(path, truth, run)
    _trend_table(run, pop)
    _scatter_table(run, pop, per_record)
    _damping_table(run, per_record)


def _trend_table(run, pop) -> None:
    u = run.uncertainty
    print("\n| speed (rpm) | paper Table 3 k_f, k_r (1e8 N/m) | truth k_f, k_r | identified "
          "k_f, k_r (95 % interval) | covered |\n|---|---|---|---|---|")
    lo_s = u.speed_range_rpm[0]
    for j, s in enumerate(T3_SPEEDS + (24000.0,)):
        paper = f"{PAPER_T3['front'][j]:.3f}, {PAPER_T3['rear'][j]:.3f}" if j < 5 else "—"
        if s < lo_s:
            print(f"| {s:.0f} | {paper} | — | not identified (below {lo_s:.0f} rpm) | — |")
            continue
        i = int(np.argmin(np.abs(pop.speeds_rpm - s)))
        sp = pop.speeds_rpm[i]
        lo, hi = u.trend_interval(sp)
        t, m = pop.mean[i, K_COLS] / 1e8, u.trend(sp) / 1e8
        cov = (lo / 1e8 <= t) & (t <= hi / 1e8)
        print(f"| {sp:.0f} | {paper} | {t[0]:.3f}, {t[2]:.3f} | {m[0]:.3f} ({lo[0] / 1e8:.3f}–"
              f"{hi[0] / 1e8:.3f}), {m[2]:.3f} ({lo[2] / 1e8:.3f}–{hi[2] / 1e8:.3f}) | "
              f"{int(cov[0])}{int(cov[2])} |")
    print("laws:", u.tests["trend_law"])


def _scatter_table(run, pop, per_record) -> None:
    u = run.uncertainty
    res = run.campaign.identification
    used = run.campaign.used
    X = res.estimate[used][:, K_COLS]
    sd_true = np.sqrt(np.mean(np.diagonal(pop.factor_cov, axis1=1, axis2=2), axis=0))[K_COLS]
    t = u.tests
    print("\n| coefficient | pooled mean ± SD (MN/m) | pooled CoV | SW p pooled | physical SD "
          "(95 % CI) | truth SD | SW p (20 runs) | Q-Q R² (runs) |\n|---|---|---|---|---|---|"
          "---|---|")
    for j, c in enumerate(u.coefficients):
        pre = t["runs"]
        print(f"| {c} | {X[:, j].mean() / 1e6:.2f} ± {X[:, j].std(ddof=1) / 1e6:.2f} | "
              f"{X[:, j].std(ddof=1) / X[:, j].mean():.2%} | "
              f"{t['pooled']['shapiro'][c]['p_value']:.2g} | "
              f"{np.sqrt(u.scatter_fit.physical[j, j]):.2%} ({u.scatter_fit.ci_sd[j, 0]:.2%}–"
              f"{u.scatter_fit.ci_sd[j, 1]:.2%}) | {sd_true[j]:.2%} | "
              f"{pre['shapiro'][c]['p_value']:.2g} | {pre['qq_r2'][c]:.4f} |")
    hz, hz_all = t["study_runs"]["henze_zirkler"], t["study"]["henze_zirkler"]
    print(f"study θ Henze–Zirkler p = {hz['p_value']:.3g} over the runs, "
          f"{hz_all['p_value']:.3g} over all used records; speed homogeneity p: "
          f"{ {k: round(v, 3) for k, v in t['speed_homogeneity_p'].items()} }")
    e = X / u.trend(res.speed_rpm[used])
    e_true = per_record[used][:, K_COLS] / u.trend(res.speed_rpm[used])
    ident = np.var(e - e_true, axis=0) / np.var(e, axis=0)
    print("identification share of the detrended variance (measured with the truth):",
          np.round(ident, 3).tolist())


def _damping_table(run, per_record) -> None:
    res = run.campaign.identification
    sp = res.speed_rpm
    print("\n| speeds (rpm) | c_f: RMS error | median reported SE | c_r: RMS error | median SE |"
          "\n|---|---|---|---|---|")
    for a, b in ((3000, 8000), (8000, 16000), (16000, 24001)):
        g = (sp >= a) & (sp < b) & ~res.unexcited.any(axis=1)
        err = res.estimate[g][:, [2, 6]] / per_record[g][:, [2, 6]] - 1
        se = res.std[g][:, [2, 6]] / per_record[g][:, [2, 6]]
        print(f"| {a}–{min(b, 24000)} | {np.sqrt(np.mean(err[:, 0] ** 2)):.0%} | "
              f"{np.median(se[:, 0]):.0%} | {np.sqrt(np.mean(err[:, 1] ** 2)):.0%} | "
              f"{np.median(se[:, 1]):.0%} |")


def report_coverage(out: Path, seeds: int) -> None:
    model = _model()
    trend, scat, sds = [], [], []
    for seed in range(100, 100 + seeds):
        path, truth = campaign(out, seed)
        run = run_identification(model, path, out / f"run_{seed}",
                                 rng=np.random.default_rng(seed))
        _, pop = _truths(path, truth, run)
        c = coverage_of(run, pop)
        trend.append(c["trend"].mean(axis=0))
        scat.append(c["scatter"])
        sds.append(c["sd"] / c["true_sd"])
        print(f"seed {seed}: trend covered at {c['trend'].mean(axis=0).round(2).tolist()} of "
              f"the speeds; scatter CI covers truth {c['scatter'].astype(int).tolist()}; SD / "
              f"truth {np.round(c['sd'] / c['true_sd'], 2).tolist()}")
    trend, scat, sds = np.array(trend), np.array(scat), np.array(sds)
    print(f"\n{seeds} seeds: trend intervals cover the truth at {trend.mean(axis=0).round(3)} "
          f"of (seed, speed) pairs (k_yy,f k_zz,f k_yy,r k_zz,r); physical-scatter intervals "
          f"cover in {scat.mean(axis=0).round(3)} of the seeds; identified / true SD "
          f"{sds.mean(axis=0).round(3)} ± {sds.std(axis=0, ddof=1).round(3)}")


def report_sources(out: Path) -> None:
    """Each hidden error alone (everything else ideal), 6 speeds × 6 runs: RMS relative error of
    k and c against each record's truth."""
    ideal = dict(noise=False)              # the rig's own switch: no noise, errors, rounding
    cases = {
        "none (ideal)": (SensorSet(**ideal), Variability(tool_mass_cov=0.0)),
        "probe noise 50 nm + 16 bit": (SensorSet(probe=ProbeModel(gain_error_sd=0.0,
                                                                  bandwidth_sd=0.0),
                                                 daq=DAQModel(skew_sd_s=0.0)),
                                       Variability(tool_mass_cov=0.0)),
        "sampled keyphasor (10° edges), refined": (SensorSet(noise=False, keyphasor=(
            KeyphasorModel(timing="sampled"))), Variability(tool_mass_cov=0.0)),
        "tool mass 3 % (model error)": (SensorSet(**ideal), Variability()),
    }
    model = _model()
    speeds = np.linspace(5000.0, 24000.0, 6)
    print("\n| hidden error | k RMS error (front, rear) | c RMS error (front, rear) |\n"
          "|---|---|---|")
    for i, (label, (sens, var)) in enumerate(cases.items()):
        path, truth = campaign(out / f"src{i}", 7, truth=reference_truth(variability=var),
                               sensors=sens, repeats=6, speeds=speeds)
        run = run_identification(model, path, out / f"src{i}" / "run",
                                 IdentificationOptions(max_rel_se=1e9, n_boot=50),
                                 rng=np.random.default_rng(0))
        per_record, _ = _truths(path, truth, run)
        err = run.campaign.identification.estimate / per_record - 1
        rms = np.sqrt(np.nanmean(err**2, axis=0))
        print(f"| {label} | {rms[0]:.1e}, {rms[4]:.1e} | {rms[2]:.1e}, {rms[6]:.1e} |")
    _gain_alone(out, model, speeds)


def _gain_alone(out, model, speeds) -> None:
    """Gain, bandwidth and skew errors are drawn once per installation: their effect is a bias
    common to every record, compared with the systematic budget's prediction."""
    for label, probe, daq in (("gain 2 %", ProbeModel(noise_rms_m=0.0, bandwidth_sd=0.0,
                                                       gap_sd_m=0.0), DAQModel(bits=31,
                                                                               skew_sd_s=0.0)),
                              ("skew 0.2 µs", ProbeModel(noise_rms_m=0.0, gain_error_sd=0.0,
                                                         bandwidth_sd=0.0, gap_sd_m=0.0),
                               DAQModel(bits=31))):
        errs, pred = [], []
        for seed in range(5):
            sens = SensorSet(probe=probe, daq=daq, keyphasor=SLOW_KP)
            path, truth = campaign(out / f"gain_{label[:4]}", seed, sensors=sens, repeats=2,
                                   speeds=speeds,
                                   truth=reference_truth(variability=Variability(
                                       tool_mass_cov=0.0)))
            run = run_identification(model, path, out / f"gain_{label[:4]}" / f"run{seed}",
                                     IdentificationOptions(max_rel_se=1e9, n_boot=50),
                                     rng=np.random.default_rng(0))
            per_record, _ = _truths(path, truth, run)
            errs.append(run.campaign.identification.estimate[:, K_COLS] / per_record[:, K_COLS]
                        - 1)
            u = run.uncertainty
            pred.append([np.sqrt(np.diag(u.trend_cov_at(s)) - np.diag(
                u.trend_cov_at(s, systematic=False))) / u.trend(s) for s in speeds])
        print(f"| {label} (5 installations) | k bias RMS {np.sqrt(np.mean(np.square(errs))):.1e}"
              f" | budget predicts {np.sqrt(np.mean(np.square(pred))):.1e} (incl. tool mass) |")


def report_noise_free(out: Path, seeds: int = 3) -> None:
    """The rig with its noise switched off as a user does it (``SensorSet(noise=False)``:
    no noise, sensor errors or quantisation; the default counter-timed keyphasor), the tool
    mass fixed (the rotor model exact), the truth random (``seeds`` campaigns), all 50 speeds
    × 2 runs; then the same with a *sampled* keyphasor; then with the rig's hidden 3 % tool-mass
    scatter on (the rotor model not exact), the tool weighed by two impact hits per direction
    or left nominal. Per speed band: the largest relative
    error and the conditioning of c, ``|k + iΩc| / (Ωc)`` (a relative phasor error ε moves c by
    up to that many ε)."""
    exact = reference_truth(variability=Variability(tool_mass_cov=0.0))
    sampled = SensorSet(noise=False, keyphasor=KeyphasorModel(timing="sampled"))
    cases = {"counter keyphasor (default)": ("noise_free", SensorSet(noise=False), exact, {}),
             "sampled keyphasor": ("noise_free_sampled", sampled, exact, {}),
             "tool mass scatter on, weighed by impacts (tool_mass = 'impact')": (
                 "noise_free_scatter", SensorSet(noise=False), reference_truth(),
                 {"tool_mass": "impact"}),
             "tool mass scatter on, nominal model (tool_mass = 'model')": (
                 "noise_free_scatter", SensorSet(noise=False), reference_truth(), {})}
    for label, (tag, sens, truth, extra) in cases.items():
        errs, conds, sps, flag = [], [], [], []
        for seed in range(3, 3 + seeds):
            path, _ = campaign(out / tag, seed, sensors=sens, repeats=2, truth=truth,
                               impacts=2 if tag == "noise_free_scatter" else 0)
            run = identify_records(_model(), path, IdentificationOptions(
                max_rel_se=1e9, n_boot=50, figures=False, **extra),
                rng=np.random.default_rng(0))
            per_record, _ = _truths(path, truth, run)
            res = run.campaign.identification
            errs.append(np.abs(res.estimate / per_record - 1))
            flag.append(np.any(res.std[:, [2, 3, 6, 7]] > 0.2 * np.abs(
                res.estimate[:, [2, 3, 6, 7]]), axis=1))
            w = run.responses.speed_rpm[:, None] * np.pi / 30
            k, c = per_record[:, [0, 1, 4, 5]], per_record[:, [2, 3, 6, 7]]
            conds.append(np.abs(k + 1j * w * c) / (w * c))
            sps.append(run.responses.speed_rpm)
        err, cond, sp = np.concatenate(errs), np.concatenate(conds), np.concatenate(sps)
        flagged = np.concatenate(flag)
        print(f"\nnoise-free, {label}: {seeds} random truths × 50 speeds × 2 runs; load "
              f"average {os.getloadavg()[0]:.1f}")
        print("| speeds (rpm) | max |k error| | max |c error| | |Z|/(Ωc) | c SE > 20 % (flagged "
              "imprecise by default): records, their max |c error| |\n|---|---|---|---|---|")
        for a, b in ((1000, 1001), (1001, 5000), (5000, 20000), (20000, 22000),
                     (22000, 23300), (23300, 23999), (23999, 24001)):
            g = (sp >= a) & (sp < b)
            ok = g & ~flagged
            print(f"| {a}–{min(b, 24000)} | {err[g][:, K_COLS].max():.1e} | "
                  f"{err[g][:, [2, 3, 6, 7]].max():.1e} | {cond[g].min():.0f}–"
                  f"{cond[g].max():.0f} | {int((g & flagged).sum())} of {int(g.sum())}"
                  + (f"; the others' max |c error| {err[ok][:, [2, 3, 6, 7]].max():.1e}"
                     if (g & flagged).any() and ok.any() else "") + " |")


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--seeds", type=int, default=0, help="coverage over this many campaigns")
    p.add_argument("--sources", action="store_true", help="each hidden error alone")
    p.add_argument("--noise-free", action="store_true")
    p.add_argument("--n-jobs", type=int, default=1)
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--out", type=Path, default=Path("/tmp/bench_identification_rig"))
    a = p.parse_args()
    a.out.mkdir(parents=True, exist_ok=True)
    if a.seeds:
        report_coverage(a.out, a.seeds)
    elif a.sources:
        report_sources(a.out)
    elif a.noise_free:
        report_noise_free(a.out)
    else:
        report_one(a.out, a.seed, a.n_jobs)


if __name__ == "__main__":
    main()
