"""Importance sampling at P_f ≈ 3e-7 in 10-D: our control-variate IS against OpenTURNS' post-FORM
importance sampling, over 20 seeds.

    OMP_NUM_THREADS=1 PYTHONPATH=. python benchmarks/bench_is_small_pf.py [--seeds 20]

Problems: the 10-D linear limit state with β = 5 (P_f = 2.8665e-7, the issue's anchor) and a
mildly curved 10-D paraboloid (β = 5, κ = 0.05: P_f by 1-D quadrature), so that the control
variate is not judged on a limit state it makes exact. Ours: ``ImportanceSampling`` (defaults,
1000 samples, and 1478 samples: 1500 calls with the 22-call FORM search). OpenTURNS (optional:
``pip install openturns``, not a package dependency): ``FORM(AbdoRackwitz)`` then
``ProbabilitySimulationAlgorithm`` with ``ImportanceSamplingExperiment(Normal(u*, I))``, block
size 1, stopped at a CoV of 5 % (its default way of use) and, for a like-for-like budget, at a
fixed 1500 samples. Columns: mean P_f / exact, empirical CoV (std of the runs / exact), mean
reported CoV, share of runs within 3 reported SE, mean model calls (FORM included, counted by
a wrapper around the model in both libraries).
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from threadpoolctl import threadpool_limits

from surrogate_rbrdo.core import CountingResponse
from surrogate_rbrdo.estimators import ImportanceSampling
from surrogate_rbrdo.estimators.problems import linear_standard, paraboloid


def ours(prob, seeds, n):
    rows = []
    for s in range(seeds):
        resp = CountingResponse(prob.response)
        r = ImportanceSampling(n_samples=n).estimate(resp, prob.inputs, prob.limit, prob.x,
                                                     rng=np.random.default_rng(s))
        rows.append((r.pf[0], r.pf_se[0], resp.counter.calls))
    return np.array(rows)


def openturns_runs(prob, seeds, fixed_n=None):
    """Post-FORM IS in OpenTURNS; ``None`` if it is not installed."""
    try:
        import openturns as ot  # optional: only for this side-by-side comparison
    except ImportError:
        return None
    ot.Log.Show(ot.Log.NONE)
    m = prob.inputs.dim
    calls = [0]

    def g(x):
        x = np.asarray(x)
        calls[0] += len(x)
        return prob.response(prob.x, x).T       # standard normal inputs: θ = u

    model = ot.PythonFunction(m, 1, func_sample=g)
    dist = ot.Normal(m)
    event = ot.ThresholdEvent(ot.CompositeRandomVector(model, ot.RandomVector(dist)),
                              ot.Greater(), float(prob.limit.threshold))
    rows = []
    for s in range(seeds):
        calls[0] = 0
        ot.RandomGenerator.SetSeed(s)
        optim = ot.AbdoRackwitz()
        optim.setStartingPoint(dist.getMean())
        form = ot.FORM(optim, event)
        form.run()
        ustar = form.getResult().getStandardSpaceDesignPoint()
        algo = ot.ProbabilitySimulationAlgorithm(
            ot.StandardEvent(event),
            ot.ImportanceSamplingExperiment(ot.Normal(ustar, ot.CovarianceMatrix(m))))
        algo.setBlockSize(1)
        if fixed_n is None:
            algo.setMaximumCoefficientOfVariation(0.05)
            algo.setMaximumOuterSampling(100_000)
        else:
            algo.setMaximumCoefficientOfVariation(0.0)
            algo.setMaximumOuterSampling(fixed_n)
        algo.run()
        r = algo.getResult()
        rows.append((r.getProbabilityEstimate(), r.getStandardDeviation(), calls[0]))
    return np.array(rows)


def line(label, rows, exact):
    pf, se, calls = rows.T
    print(f"| {label} | {pf.mean() / exact:.3f} | {pf.std(ddof=1) / exact:.3f} "
          f"| {np.mean(se / pf):.3f} | {np.mean(np.abs(pf - exact) <= 3 * se):.2f} "
          f"| {calls.mean():.0f} | {calls.max():.0f} |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=20)
    args = ap.parse_args()
    probs = [linear_standard(beta=5.0, dim=10), paraboloid(beta=5.0, kappa=0.05, dim=10)]
    with threadpool_limits(1):
        for prob in probs:
            exact = float(prob.pf_exact[0])
            print(f"\n{prob.name}: exact P_f = {exact:.4e}, {args.seeds} seeds\n")
            print("| method | mean P_f / exact | CoV empirical | CoV reported | within 3 SE "
                  "| model calls (mean) | model calls (max) |")
            print("|---|---|---|---|---|---|---|")
            for n in (1000, 1478):
                t0 = time.perf_counter()
                line(f"ours: IS + FORM control variate, N = {n}", ours(prob, args.seeds, n),
                     exact)
                print(f"|  (wall {1e3 * (time.perf_counter() - t0) / args.seeds:.1f} ms/run) "
                      "| | | | | | |")
            for fixed in (None, 1478):
                rows = openturns_runs(prob, args.seeds, fixed)
                if rows is None:
                    print("| OpenTURNS: not installed (pip install openturns) | | | | | | |")
                    break
                label = ("OpenTURNS post-FORM IS, stop at CoV 5 %" if fixed is None
                         else f"OpenTURNS post-FORM IS, N = {fixed}")
                line(label, rows, exact)


if __name__ == "__main__":
    main()
