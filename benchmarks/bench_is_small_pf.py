"""Importance sampling at P_f ≈ 1e-7–3e-7 in 10-D: ours against OpenTURNS' post-FORM importance
sampling at the same budget, over 20 seeds.

    OMP_NUM_THREADS=1 PYTHONPATH=. python benchmarks/bench_is_small_pf.py [--seeds 20]

Problems: the 10-D linear limit state with β = 5 (P_f = 2.8665e-7, the issue's anchor: the
half-space control variate makes any IS at the design point exact there) and 10-D paraboloids
with β = 5, convex (κ = 0.05, P_f = 9.97e-8) and concave (κ = −0.05), P_f by 1-D quadrature —
the cases that judge the target (CoV 5 % with ≤ 1 500 model calls, FORM included). Ours:
``ImportanceSampling`` with ``N = 1370`` (1 500 calls with FORM and the search for further design
points, 130 calls here: 112 for the searches, 18 for FORM's local-minimum poll), defaults
otherwise; and as plain post-FORM IS with the control variate
(``pilot=1, n_design_points=1``, N = 1460). OpenTURNS (optional: ``pip install openturns``, not a
package dependency): ``FORM(AbdoRackwitz)`` then ``ProbabilitySimulationAlgorithm`` with
``ImportanceSamplingExperiment(Normal(u*, I))``, block size 1, with ``1500 − (its FORM calls)``
samples (the same budget) and stopped at a CoV of 5 % (its default way of use). Columns: mean
P_f / exact, empirical CoV (std of the runs / exact), mean reported CoV, share of runs within
3 reported SE, mean and largest number of model calls (FORM included, counted by a wrapper
around the model in both libraries).
"""

from __future__ import annotations

import argparse
import time
import warnings

import numpy as np
from threadpoolctl import threadpool_limits

from surrogate_rbrdo.core import CountingResponse
from surrogate_rbrdo.estimators import EstimatorWarning, ImportanceSampling
from surrogate_rbrdo.estimators.problems import linear_standard, paraboloid


def ours(prob, seeds, n, **opts):
    """Rows (pf, se, calls) and the number of runs that raised an EstimatorWarning."""
    rows, warned = [], 0
    for s in range(seeds):
        resp = CountingResponse(prob.response)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", EstimatorWarning)
            r = ImportanceSampling(n_samples=n, **opts).estimate(
                resp, prob.inputs, prob.limit, prob.x, rng=np.random.default_rng(s))
        warned += any(issubclass(w.category, EstimatorWarning) for w in caught)
        rows.append((r.pf[0], r.pf_se[0], resp.counter.calls))
    return np.array(rows), warned


def openturns_runs(prob, seeds, budget=None):
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
        if budget is None:
            algo.setMaximumCoefficientOfVariation(0.05)
            algo.setMaximumOuterSampling(100_000)
        else:                                   # the same total budget as ours
            algo.setMaximumCoefficientOfVariation(0.0)
            algo.setMaximumOuterSampling(budget - calls[0])
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
    probs = [linear_standard(beta=5.0, dim=10), paraboloid(beta=5.0, kappa=0.05, dim=10),
             paraboloid(beta=5.0, kappa=-0.05, dim=10)]
    with threadpool_limits(1):
        for prob in probs:
            exact = float(prob.pf_exact[0])
            print(f"\n{prob.name}: exact P_f = {exact:.4e}, {args.seeds} seeds\n")
            print("| method | mean P_f / exact | CoV empirical | CoV reported | within 3 SE "
                  "| model calls (mean) | model calls (max) |")
            print("|---|---|---|---|---|---|---|")
            for label, n, opts in [("ours, defaults, N = 1370", 1370, {}),
                                   ("ours, one stage at u* (pilot=1, n_design_points=1), "
                                    "N = 1460", 1460, {"pilot": 1.0, "n_design_points": 1})]:
                t0 = time.perf_counter()
                rows, warned = ours(prob, args.seeds, n, **opts)
                line(label, rows, exact)
                print(f"|  (wall {1e3 * (time.perf_counter() - t0) / args.seeds:.1f} ms/run; "
                      f"warned in {warned} of {args.seeds} runs) | | | | | | |")
            for budget in (1500, None):
                rows = openturns_runs(prob, args.seeds, budget)
                if rows is None:
                    print("| OpenTURNS: not installed (pip install openturns) | | | | | | |")
                    break
                label = ("OpenTURNS post-FORM IS, stop at CoV 5 %" if budget is None
                         else f"OpenTURNS post-FORM IS, {budget} calls in all")
                line(label, rows, exact)


if __name__ == "__main__":
    main()
