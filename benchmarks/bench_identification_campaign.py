"""Phasor-level campaigns (no time domain): coverage over many seeds, and the per-speed check
of the first-order identification variance.

``identification.virtual.phasor_campaign`` draws what demodulation would return — the FE 1×
response of the reference spindle with one θ per run (physical scatter 1.5 % front, 3.3 % rear,
the paper's residual scatter) plus circular phasor noise — for 50 speeds × 20 runs, in well
under a second. It has no sensor errors, no keyphasor and no trial weights (the rig's records:
``bench_identification_rig.py``); it isolates the statistics.

    PYTHONPATH=$PWD python3 benchmarks/bench_identification_campaign.py [--seeds 50]
        [--noise-nm 0.028]

Prints (1) per speed, the mean first-order identification variance of ``rear_k_yy`` against
the variance of its actual error (review item 10), (2) over the seeds, how often the trend
intervals cover the truth's law and the physical-scatter intervals cover the scatter of the θ
actually drawn, (3) the timings (load average printed).
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np

from surrogate_rbrdo.identification import catalog_coefficients, identify_campaign
from surrogate_rbrdo.identification.virtual import phasor_campaign
from surrogate_rbrdo.spindle import reference_spindle

SPEEDS = np.linspace(1000.0, 24000.0, 50)
K = [0, 1, 4, 5]
STD = (0.015, 0.033)


def one(m, seed: int, noise_m: float):
    camp = phasor_campaign(m, SPEEDS, 20, theta_std=STD, noise_m=noise_m,
                           rng=np.random.default_rng(seed))
    out = identify_campaign(m, camp.speeds_rpm, camp.repeats, camp.phasors, phasor_sd=noise_m,
                            truth=camp.truth, rng=np.random.default_rng(seed + 1))
    return camp, out


def split_table(camp, out) -> None:
    """Estimated (first-order) vs measured identification variance of rear_k_yy per speed."""
    res, used = out.identification, out.used
    sp = res.speed_rpm
    print("| speed (rpm) | used | estimated id. var | measured id. var | ratio | RMS error |")
    print("|---|---|---|---|---|---|")
    for s in SPEEDS[[0, 1, 2, 3, 5, 10, 20, 30, 40, 45, 49]]:
        g = used & (sp == s)
        if g.sum() < 3:
            print(f"| {s:.0f} | {g.sum()} | — | — | — | — |")
            continue
        err = res.estimate[g, 4] / camp.truth[g, 4] - 1
        est = np.mean(res.covariance[g, 4, 4] / camp.truth[g, 4] ** 2)
        print(f"| {s:.0f} | {g.sum()} | {est:.2e} | {np.var(err):.2e} | "
              f"{est / np.var(err):.2f} | {np.sqrt(np.mean(err**2)):.3f} |")


def coverage(m, seeds: int, noise_m: float) -> None:
    trend, scat, ratio = [], [], []
    for seed in range(seeds):
        camp, out = one(m, 1000 + seed, noise_m)
        u = out.uncertainty
        hit = []
        for s in u.speeds_rpm:
            lo, hi = u.trend_interval(s)
            t = catalog_coefficients(m, [s])[0, K]         # the truth's law (θ mean 1)
            hit.append((lo <= t) & (t <= hi))
        trend.append(np.mean(hit, axis=0))
        real = np.repeat(STD, 2)                          # the population scatter
        lo, hi = u.scatter_fit.ci_sd.T
        scat.append((lo <= real) & (real <= hi))
        ratio.append(np.sqrt(np.diag(u.scatter_fit.physical)) / real)
    trend, scat, ratio = np.array(trend), np.array(scat), np.array(ratio)
    print(f"\n{seeds} seeds, noise {noise_m * 1e9:.3f} nm: trend intervals cover the truth at "
          f"{trend.mean(axis=0).round(3).tolist()} of (seed, speed); physical-scatter intervals "
          f"cover the population SD in {scat.mean(axis=0).round(3).tolist()} of the seeds; "
          f"identified / population SD {ratio.mean(axis=0).round(3).tolist()} ± "
          f"{ratio.std(axis=0, ddof=1).round(3).tolist()}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=50)
    ap.add_argument("--noise-nm", type=float, default=0.028,
                    help="phasor noise per part (0.028 nm: 2 nm probe noise, 1 s at 10 kHz)")
    a = ap.parse_args()
    sp = reference_spindle()
    m = sp.model(sp.baseline)
    t0 = time.perf_counter()
    camp, out = one(m, 2026, a.noise_nm * 1e-9)
    dt = time.perf_counter() - t0
    print(f"one phasor-level campaign (simulate + identify + uncertainty with bootstrap): "
          f"{dt:.2f} s, load average {os.getloadavg()[0]:.1f}\n")
    split_table(camp, out)
    coverage(m, a.seeds, a.noise_nm * 1e-9)


if __name__ == "__main__":
    main()
