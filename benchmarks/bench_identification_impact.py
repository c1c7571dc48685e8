"""Bearing damping from impact tests against the rig's truth, over seeds, at the rig's default
noise (``identification.impact``), beside the damping from the 1× unbalance response.

    PYTHONPATH=$PWD python3 benchmarks/bench_identification_impact.py --seeds 20

Each seed is a new rig (random build: bearing stiffness and damping factors; tool mass; thermal
state), default sensors (noise, gains, skews, quantisation), 5 hits per direction at the tool
and steady records with and without a 50 g mm trial mass at 4 speeds × 2 runs. The damping
``ĉ = η̂ k̂`` of every steady record (``η̂`` from the impacts, ``k̂`` that record's stiffness from
the unbalance response) is compared with the record's true ``c``; also ``η̂`` with the build's
``η``, and the reported standard error with the error. Timings under the machine's load.
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import numpy as np
from scipy import stats

from surrogate_rbrdo.identification import IdentificationOptions, identify_records
from surrogate_rbrdo.identification.impact import impact_damping
from surrogate_rbrdo.identification.rigtruth import truth_coefficients
from surrogate_rbrdo.rig import CampaignOptions, open_dataset, reference_truth, run_campaign
from surrogate_rbrdo.spindle import reference_spindle

TRIAL = (0.0, 5e-5, 0.0)
SPEEDS = (6000.0, 12000.0, 18000.0, 24000.0)
K_COLS, C_COLS = [0, 1, 4, 5], [2, 3, 6, 7]


def one_seed(out: Path, seed: int, model) -> dict:
    truth = reference_truth()
    path = out / f"campaign_{seed}"
    if not (path / "summary.json").is_file():
        run_campaign(truth, CampaignOptions(speeds_rpm=SPEEDS, repeats=2, runup=None,
                                            impacts_per_direction=5, trial_unbalance=TRIAL),
                     path, rng=np.random.default_rng(seed))
    ds = open_dataset(path / "dataset")
    impacts = [ds.load(r) for r in ds.index if r["kind"] == "impact"]
    t = time.perf_counter()
    imp = impact_damping(model, impacts)
    t_fit = time.perf_counter() - t
    eta_true = 4e-6 * np.array(impacts[0].provenance["truth_draws"]["build"]["damping_factor"])
    run = identify_records(model, path, IdentificationOptions(max_rel_se=1e9, n_boot=50,
                                                              figures=False),
                           rng=np.random.default_rng(0))
    prov = {r["id"]: ds.load(r).provenance for r in ds.index}
    ids = [i.split("|")[1] for i in run.responses.record_ids]
    true = truth_coefficients(truth, [prov[i] for i in ids], run.responses.speed_rpm)
    est = run.campaign.identification.estimate
    k_hat = est[:, K_COLS]
    c_imp = k_hat * np.repeat(imp.eta_s, 2)[None, :]          # front yy, zz; rear yy, zz
    return {"eta_err": imp.eta_s / eta_true - 1, "eta_se": imp.eta_rel_se,
            "c_imp_err": c_imp / true[:, C_COLS] - 1, "c_resp_err": est[:, C_COLS]
            / true[:, C_COLS] - 1, "tool": imp.factor("tool_mass") / float(
                impacts[0].provenance["truth_draws"]["tool"]["mass_factor"]) - 1,
            "fit_s": t_fit, "chi2": imp.chi2_dof, "lof": imp.lack_of_fit.chi2_dof,
            "flagged": imp.lack_of_fit.flagged, "n_rep": imp.n_replicates,
            "threshold": imp.lack_of_fit.threshold,
            "eta_se_model": np.sqrt(np.diag(imp.model_covariance))[
                [imp.names.index(f"{b}_damping") for b in imp.bearings]]}


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--seeds", type=int, default=20)
    p.add_argument("--out", type=Path, default=Path("/tmp/bench_identification_impact"))
    a = p.parse_args()
    a.out.mkdir(parents=True, exist_ok=True)
    sp = reference_spindle()
    model = sp.model(sp.baseline)
    rows = []
    for seed in range(a.seeds):
        r = one_seed(a.out, 1000 + seed, model)
        rows.append(r)
        print(f"seed {1000 + seed}: η error front {r['eta_err'][0]:+.2%} (SE {r['eta_se'][0]:.2%})"
              f", rear {r['eta_err'][1]:+.2%} (SE {r['eta_se'][1]:.2%}); tool mass "
              f"{r['tool']:+.2%}; fit {r['fit_s']:.1f} s, χ²/ν {r['chi2']:.2f}, lack of fit "
              f"{r['lof']:.2f}{' FLAGGED' if r['flagged'] else ''}", flush=True)
    eta = np.array([r["eta_err"] for r in rows])
    se = np.array([r["eta_se"] for r in rows])
    ci = np.concatenate([r["c_imp_err"] for r in rows])
    cr = np.concatenate([r["c_resp_err"] for r in rows])
    tool = np.array([r["tool"] for r in rows])

    def rms(x, axis=0):
        return np.sqrt(np.nanmean(np.square(x), axis=axis))

    print(f"\n{a.seeds} seeds, default noise; load average {os.getloadavg()[0]:.1f}; fit "
          f"{np.mean([r['fit_s'] for r in rows]):.1f} s per installation")
    print("| quantity | front | rear |\n|---|---|---|")
    print(f"| η̂ error: RMS | {rms(eta)[0]:.2%} | {rms(eta)[1]:.2%} |")
    print(f"| η̂ error: mean (bias) | {eta.mean(0)[0]:+.2%} | {eta.mean(0)[1]:+.2%} |")
    print(f"| η̂ error: max | {np.abs(eta).max(0)[0]:.2%} | {np.abs(eta).max(0)[1]:.2%} |")
    sem = np.array([r["eta_se_model"] for r in rows])
    z, zm = np.log1p(eta) / se, np.log1p(eta) / sem
    q = stats.t.ppf(0.975, rows[0]["n_rep"] - 1)
    print(f"| reported SE (jackknife over hits): RMS | {rms(se)[0]:.2%} | {rms(se)[1]:.2%} |")
    cov_jk, cov_m = np.mean(np.abs(z) <= q, 0), np.mean(np.abs(zm) <= 1.96, 0)
    print(f"| 95 % t({rows[0]['n_rep'] - 1}) interval covers η | {cov_jk[0]:.2f} | "
          f"{cov_jk[1]:.2f} |")
    print(f"| RMS of error / SE: jackknife; model-based (H1 coherence) | {rms(z)[0]:.2f}; "
          f"{rms(zm)[0]:.2f} | {rms(z)[1]:.2f}; {rms(zm)[1]:.2f} |")
    print(f"| model-based SE: 95 % normal interval covers η | {cov_m[0]:.2f} | {cov_m[1]:.2f} |")
    print(f"| c = η̂ k̂ per record: RMS error | {rms(ci[:, :2].ravel()):.2%} | "
          f"{rms(ci[:, 2:].ravel()):.2%} |")
    print(f"| c from 1× response per record: RMS error | {rms(cr[:, :2].ravel()):.0%} | "
          f"{rms(cr[:, 2:].ravel()):.0%} |")
    print(f"tool mass factor error: RMS {rms(tool):.2%}, max {np.abs(tool).max():.2%}")
    lof = np.array([r["lof"] for r in rows])
    print(f"lack of fit χ²/ν (jackknife variance): {lof.min():.2f}–{lof.max():.2f}, flagged in "
          f"{sum(r['flagged'] for r in rows)} of {len(rows)} (threshold {rows[0]['threshold']:g};"
          " the model is right)")


if __name__ == "__main__":
    main()
