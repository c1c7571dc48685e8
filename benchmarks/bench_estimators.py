"""Benchmark every registered estimator on the analytic problems with known P_f.

Run from the repository root::

    OMP_NUM_THREADS=1 python benchmarks/bench_estimators.py --reps 20

For each problem × estimator the sampling methods are repeated ``--reps`` times with independent
generators (seeds 0..reps-1). Columns: mean P_f over the runs, relative error of that mean,
empirical CoV (std of the runs / exact P_f), mean reported CoV (``pf_se / pf``), the fraction of
runs whose exact value lies within 4 reported standard errors, model calls per run and wall time
per run. Deterministic methods (form, sorm, fosm) run once; their CoV columns are "-".
It also times ``mc_from_values`` on a (100, 1000) array (the optimisation hot path).
``--estimators`` selects registry names (e.g. ``--estimators subset form``).
"""

from __future__ import annotations

import argparse
import time
import warnings

import numpy as np
from threadpoolctl import threadpool_limits

from surrogate_rbrdo.core import LimitState
from surrogate_rbrdo.estimators import EstimatorWarning, get_estimator, mc_from_values
from surrogate_rbrdo.estimators.problems import benchmark_problems, linear_standard

DETERMINISTIC = {"form", "sorm", "fosm"}
CONFIGS = [
    ("mc", {"n_samples": 100_000}),
    ("is", {}),
    ("ais", {}),
    ("subset", {}),
    ("form", {}),
    ("sorm", {}),
    ("fosm", {}),
]


def problems():
    """The coverage problems (``problems.benchmark_problems``) plus P_f = 1e-6 in 5-D."""
    return [*benchmark_problems(), linear_standard(beta=4.753424, dim=5)]


def run_pair(prob, name, opts, reps):
    est = get_estimator(name, **opts)
    n = 1 if name in DETERMINISTIC else reps
    pf, cov, cover, calls, secs = [], [], [], [], []
    for seed in range(n):
        t0 = time.perf_counter()
        try:
            r = est.estimate(prob.response, prob.inputs, prob.limit, prob.x,
                             rng=np.random.default_rng(seed))
        except Exception as exc:  # noqa: BLE001 - report, do not stop the table
            return f"failed: {type(exc).__name__}: {str(exc)[:60]}"
        secs.append(time.perf_counter() - t0)
        pf.append(r.pf[0])
        calls.append(r.n_calls)
        cov.append(r.pf_cov[0])
        se = r.pf_se[0]
        cover.append(bool(np.isfinite(se) and abs(r.pf[0] - prob.pf_exact[0]) <= 4 * se))
    pf = np.array(pf)
    exact = prob.pf_exact[0]
    row = {
        "pf": pf.mean(), "relerr": abs(pf.mean() - exact) / exact,
        "emp_cov": pf.std(ddof=1) / exact if n > 1 else np.nan,
        "rep_cov": np.nanmean(cov) if n > 1 and np.isfinite(cov).any() else np.nan,
        "cover": np.mean(cover) if n > 1 else np.nan,
        "calls": np.mean(calls), "ms": 1e3 * np.mean(secs),
    }
    return row


def fmt(v, f):
    return "-" if not np.isfinite(v) else format(v, f)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--reps", type=int, default=20)
    ap.add_argument("--estimators", nargs="*", default=None, help="registry names to run")
    args = ap.parse_args()
    # the methods' own warnings (heavy tails, several design points) are counted by
    # benchmarks/bench_coverage.py; here they would only clutter the table
    warnings.simplefilter("ignore", EstimatorWarning)
    with threadpool_limits(1):
        print("| problem | exact P_f | estimator | mean P_f | rel. error | CoV (empirical) "
              "| CoV (reported) | within 4 SE | model calls | wall time [ms] |")
        print("|---|---|---|---|---|---|---|---|---|---|")
        for prob in problems():
            for name, opts in CONFIGS:
                if args.estimators and name not in args.estimators:
                    continue
                row = run_pair(prob, name, opts, args.reps)
                label = name + ("" if not opts else " " + ",".join(
                    f"{k}={v}" for k, v in opts.items()))
                if isinstance(row, str):
                    print(f"| {prob.name} | {prob.pf_exact[0]:.4e} | {label} | {row} "
                          "| | | | | | |")
                    continue
                print(f"| {prob.name} | {prob.pf_exact[0]:.4e} | {label} | {row['pf']:.4e} "
                      f"| {fmt(row['relerr'], '.3f')} | {fmt(row['emp_cov'], '.3f')} "
                      f"| {fmt(row['rep_cov'], '.3f')} | {fmt(row['cover'], '.2f')} "
                      f"| {row['calls']:.0f} | {row['ms']:.1f} |")
        y = np.random.default_rng(0).normal(size=(100, 1000))
        lim = LimitState(2.0)
        mc_from_values(y, lim)
        t0 = time.perf_counter()
        k = 200
        for _ in range(k):
            mc_from_values(y, lim)
        dt = (time.perf_counter() - t0) / k
        print(f"\nmc_from_values on a (100, 1000) array: {1e3 * dt:.3f} ms per call")


if __name__ == "__main__":
    main()
