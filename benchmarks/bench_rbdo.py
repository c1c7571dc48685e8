"""RBDO to published optima: the FORM-based and the exact-probability SLSQP solvers on the
published benchmarks, each design re-checked by an independent crude MC.

    OMP_NUM_THREADS=1 PYTHONPATH=. python benchmarks/bench_rbdo.py [--n-theta 1000000]

FORM solver: ``make_formulation("rbdo", estimator="form", reliability_measure="beta")`` (the
reliability-index approach) + ``run_slsqp``. Exact-probability solver: crude MC on a common
sample of ``--n-theta`` points, ``reliability_measure="quantile"``, ``pf_bound="upper"``
(Clopper-Pearson 95 %) + ``run_slsqp``. Independent references (``rbdo_references``, no
estimator of the toolkit): the FORM optimum by nested SciPy SLSQP (normal inputs), the
exact-probability optimum of Youn & Choi by 1-D quadratures and of the cantilever by its closed
form. MC re-check: 10⁶ fresh samples, P_f / P_target per chance constraint (the largest shown).
Prints model calls (θ points) and wall time per solve.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from surrogate_rbrdo.formulations import DeterministicOptions, FormulationOptions, make_formulation
from surrogate_rbrdo.optimization import SLSQPOptions, run_slsqp
from surrogate_rbrdo.optimization.rbdo_benchmarks import cantilever, short_column, youn_choi
from surrogate_rbrdo.optimization.rbdo_references import (
    exact_optimum,
    form_optimum_nested,
    mc_recheck,
)

NO_DET = DeterministicOptions(stress=False, resonance="none")


def solve(bench, **opts):
    form = make_formulation(
        "rbdo", response=bench.cost, inputs=bench.inputs, limit=None,
        extra_reliability=bench.constraints, rng=np.random.default_rng(0),
        options=FormulationOptions(p_target=bench.p_target, deterministic=NO_DET, **opts))
    t0 = time.perf_counter()
    res = run_slsqp(form, bench.lower, bench.upper, rng=np.random.default_rng(1),
                    options=SLSQPOptions(fd_step=1e-4))
    return res.X[0], res.n_surrogate_calls, time.perf_counter() - t0


def recheck(bench, x):
    return float(mc_recheck(bench, x).max())


def cost_of(bench, x):
    return float(x.sum() if bench.name.startswith("youn_choi") else np.prod(x))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n-theta", type=int, default=1_000_000)
    args = ap.parse_args()
    print("| benchmark | published (kind) | solver | design | cost | vs reference | "
          "MC re-check max P_f/P_t | θ points | s |")
    print("|---|---|---|---|---|---|---|---|---|")
    for bench in (youn_choi(0.3, 3.0), youn_choi(0.6, 2.0), short_column(),
                  short_column("normal", 3.0), cantilever()):
        pub = np.array(bench.published_x)
        ref = exact_optimum(bench)
        nested = form_optimum_nested(bench) if bench.name != "short_column" else None
        pub_s = (f"({', '.join(f'{v:g}' for v in pub)}), {bench.published_cost:g} "
                 f"({bench.published_kind})" if pub.size else bench.published_kind)
        runs = {
            "FORM (RIA) + SLSQP": solve(bench, n_theta=100, estimator="form",
                                        reliability_measure="beta", estimator_options={
                                            "fd_scheme": "central", "tol_g": 1e-10}),
            f"MC quantile, CP 95 %, N = {args.n_theta:.0e}": solve(
                bench, n_theta=args.n_theta, reliability_measure="quantile", pf_bound="upper"),
        }
        for label, (x, calls, dt) in runs.items():
            if label.startswith("FORM"):
                against, kind = (pub, "published") if pub.size else (nested, "nested FORM")
            else:
                against, kind = ref, "exact"
            vs = ("-" if against is None else
                  f"{100 * np.max(np.abs(x / against - 1)):.2f} % ({kind})")
            print(f"| {bench.name} | {pub_s} | {label} | ({', '.join(f'{v:.4f}' for v in x)}) "
                  f"| {cost_of(bench, x):.4f} | {vs} | {recheck(bench, x):.3f} | {calls} "
                  f"| {dt:.1f} |", flush=True)
        if nested is not None:
            print(f"| {bench.name} | | FORM reference (nested SLSQP) | "
                  f"({', '.join(f'{v:.4f}' for v in nested)}) | {cost_of(bench, nested):.4f} | | "
                  f"{recheck(bench, nested):.3f} | | |", flush=True)
        if ref is not None:
            print(f"| {bench.name} | | exact-probability reference | "
                  f"({', '.join(f'{v:.4f}' for v in ref)}) | {cost_of(bench, ref):.4f} | | "
                  f"{recheck(bench, ref):.3f} | | |", flush=True)


if __name__ == "__main__":
    main()
