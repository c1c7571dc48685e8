"""Substructure surrogate: training cost, prediction speed and accuracy against the FE model.

Run:  OMP_NUM_THREADS=1 python benchmarks/bench_substructure.py [--n-doe 60] [--P 100] [--N 1000]

For each response (amplitude at 24 000 rpm; peak over 1000–24 000 rpm) it trains the
substructure surrogate on ``--n-doe`` designs (one FE call each), then times, in one run and on
the same designs × θ sample, the surrogate and the FE model (``AtSpeedAmplitudeResponse`` /
``PeakAmplitudeResponse``, both vectorised over θ), and prints the ratio and the relative
errors of y, μ_y and σ_y. The peak grid is smaller (``--P-peak``, ``--N-peak``): its FE
reference costs ~0.6–0.8 s per design for 100 θ.
"""

from __future__ import annotations

import argparse
import os
import time

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import numpy as np  # noqa: E402

from surrogate_rbrdo.doe import lhs  # noqa: E402
from surrogate_rbrdo.spindle.evaluate import ResponseSpec  # noqa: E402
from surrogate_rbrdo.spindle.reference import reference_spindle  # noqa: E402
from surrogate_rbrdo.study import TABLE4_STD  # noqa: E402
from surrogate_rbrdo.surrogates.structured import (  # noqa: E402
    SubstructureOptions,
    train_surrogate,
)

STD = np.array(TABLE4_STD)   # the paper's Table 4 CoVs of the bearing stiffness


def one(sp, resp, n_doe, P, N, seed):
    cfg = SubstructureOptions(n_doe=n_doe, n_jobs=1, backend="sequential", n_start=3)
    t0 = time.perf_counter()
    tr = train_surrogate(sp, None, None, cfg, rng=np.random.default_rng(seed), response=resp)
    sur, info = tr.model, {**tr.info, "fe_calls": tr.fe_calls}
    train = time.perf_counter() - t0
    X = lhs(P, sp.design_map.bounds, rng=np.random.default_rng(seed + 1))
    th = np.random.default_rng(seed + 2).normal(1.0, STD, size=(N, 2))
    sur(X[:2], th[:2])                        # warm-up (imports)
    t0 = time.perf_counter()
    ys = sur(X, th)
    ts = time.perf_counter() - t0
    t0 = time.perf_counter()
    yf = resp.fe_response(sp)(X, th)
    tf = time.perf_counter() - t0
    e = np.abs(ys / yf - 1)
    em = np.abs(ys.mean(1) / yf.mean(1) - 1)
    es = np.abs(ys.std(1) / yf.std(1) - 1)
    print(f"\n== {resp.label}: {n_doe} training designs ({info['fe_calls']} FE calls, "
          f"{info['n_outputs']} Kriged outputs), train {train:.1f} s "
          f"(fit {info['fit_time_s']:.2f} s)")
    print(f"grid P x N = {P} x {N} = {P * N} (y at every design x θ)")
    print(f"  surrogate : {ts:8.3f} s  ({P * N / ts:10.3e} pred/s)")
    print(f"  FE model  : {tf:8.3f} s  ({P * N / tf:10.3e} evals/s)   "
          f"FE / surrogate = {tf / ts:.1f}x")
    print(f"  |y_sur / y_FE - 1|      median {np.median(e):.1e}  "
          f"99 % {np.quantile(e, 0.99):.1e}  max {e.max():.1e}")
    print(f"  |mu_sur / mu_FE - 1|    median {np.median(em):.1e}  max {em.max():.1e}  "
          f"(over {P} designs)")
    print(f"  |sd_sur / sd_FE - 1|    median {np.median(es):.1e}  max {es.max():.1e}")
    i = int(np.argmin(yf.mean(1)))
    print(f"  lowest-mu design {np.round(X[i], 1).tolist()}: mu FE {yf[i].mean() * 1e6:.4f} µm, "
          f"surrogate {ys[i].mean() * 1e6:.4f} µm")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--n-doe", type=int, default=60)
    ap.add_argument("--P", type=int, default=100)
    ap.add_argument("--N", type=int, default=1000)
    ap.add_argument("--P-peak", type=int, default=20)
    ap.add_argument("--N-peak", type=int, default=100)
    ap.add_argument("--seed", type=int, default=11)
    a = ap.parse_args()
    sp = reference_spindle()
    one(sp, ResponseSpec("at_speed", 24000.0), a.n_doe, a.P, a.N, a.seed)
    one(sp, ResponseSpec(), a.n_doe, a.P_peak, a.N_peak, a.seed)


if __name__ == "__main__":
    main()
