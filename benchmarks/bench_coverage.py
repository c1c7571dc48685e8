"""Coverage of every sampling estimator's error bars on published reliability benchmarks.

    OMP_NUM_THREADS=1 PYTHONPATH=. python benchmarks/bench_coverage.py --seeds 40

For each problem × estimator (the same options on every problem, ``CONFIGS``) the estimator
runs with generators ``default_rng(0..seeds-1)``; the row gives (see
``surrogate_rbrdo.estimators.coverage``):

* **covered**: share of the runs *that did not warn* whose interval at the 3σ level (99.73 %:
  ``P̂ ± 3·SE`` for IS/ais, log-normal for subset, Clopper–Pearson for MC) covers the
  reference (a Monte Carlo reference's own SE added in quadrature) — must be ≥ 0.95;
* **warned**: share of runs that warned, raised or gave a bound, with the false alarms
  (warned yet covered) in brackets;
* **silent**: share of runs neither covered nor warned;
* **95 % CI**: share of all runs whose nominal 95 % interval covers (≈ 0.95 when the errors
  are honest, not just wide); **3 SE sym.**: share within the symmetric ``P̂ ± 3·SE``;
* mean model calls, the empirical CoV (run-to-run std / reference) and the mean reported CoV.

``--problems`` and ``--estimators`` select subsets by name.
"""

from __future__ import annotations

import argparse
import time

from threadpoolctl import threadpool_limits

from surrogate_rbrdo.estimators.coverage import coverage
from surrogate_rbrdo.estimators.problems import OSCILLATOR_PF_SE, benchmark_problems

#: (registry name, options): the same options on every problem (no per-problem tuning)
CONFIGS = [
    ("mc", {"n_samples": 100_000}),
    ("is", {}),
    ("ais", {}),
    ("subset", {}),
]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=40)
    ap.add_argument("--problems", nargs="*", default=None)
    ap.add_argument("--estimators", nargs="*", default=None)
    args = ap.parse_args()
    print("| problem | reference P_f | estimator | covered | warned (false alarms) | silent "
          "| 95 % CI | 3 SE sym. | model calls | CoV empirical | CoV reported | s/run |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    with threadpool_limits(1):
        for prob in benchmark_problems():
            if args.problems and prob.name not in args.problems:
                continue
            ref_se = OSCILLATOR_PF_SE if prob.name == "nonlinear_oscillator" else 0.0
            for name, opts in CONFIGS:
                if args.estimators and name not in args.estimators:
                    continue
                t0 = time.perf_counter()
                row = coverage(prob, name, opts, n_seeds=args.seeds, ref_se=ref_se)
                dt = (time.perf_counter() - t0) / args.seeds
                label = name + "".join(f" {k}={v}" for k, v in opts.items())
                n = row.n_runs
                print(f"| {prob.name} | {row.exact:.4e} | {label} | {row.share_covered:.3f} "
                      f"| {row.warned / n:.3f} ({row.false_alarms / n:.3f}) "
                      f"| {row.silent_misses / n:.3f} | {row.covered_95 / n:.3f} "
                      f"| {row.covered_3se / n:.3f} | {row.mean_calls:.0f} "
                      f"| {row.cov_empirical:.3f} | {row.cov_reported:.3f} | {dt:.2f} |",
                      flush=True)
                for m in row.messages[:1]:
                    print(f"|  | | ↳ {m[:110]} | | | | | | | | | |", flush=True)


if __name__ == "__main__":
    main()
