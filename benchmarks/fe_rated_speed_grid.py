"""Is there a μ–σ trade-off when y is the tool-tip amplitude at one operating speed? (full FE)

Run:  OMP_NUM_THREADS=1 python benchmarks/fe_rated_speed_grid.py [--n-theta 100] [--n-jobs 2]

The peak over 1000–24 000 rpm has none (``fe_design_lines.py``, ``fe_uncertainty_scenarios.py``):
μ_y and σ_y fall together. At a fixed speed the design can tune the tool-tip cancellation notch to
that speed. This script evaluates the FE amplitude at several candidate rated speeds on a grid
over the whole design box (5 preloads × 46 spans × 7 diameters = 1610 designs) with common
stiffness samples (Table 4 CoVs), and prints, per speed, the designs that are non-dominated in
(μ_y, σ_y) among the grid, and for ``--delta-lim-um`` values the size of the non-dominated set
among the designs that are feasible at P_target 10 / 5 / 1 %. ~45 s on 2 cores with 100 θ samples.
"""

from __future__ import annotations

import argparse
import os
import time

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import numpy as np  # noqa: E402
from joblib import Parallel, delayed  # noqa: E402

from surrogate_rbrdo.optimization.pareto import nondominated  # noqa: E402
from surrogate_rbrdo.spindle.harmonic import tool_amplitude  # noqa: E402
from surrogate_rbrdo.spindle.reference import reference_spindle  # noqa: E402
from surrogate_rbrdo.study import TABLE4_STD  # noqa: E402

STD = np.array(TABLE4_STD)   # the paper's Table 4 CoVs of the bearing stiffness


def amplitudes(sp, x, speeds, k):
    """Tool-tip amplitude (µm) of design ``x`` at ``speeds`` for stiffness samples ``k``."""
    return tool_amplitude(sp.model(np.asarray(x, float)), speeds, k) * 1e6


def front(mu, sd):
    """Indices of the (μ, σ)-non-dominated designs, sorted by μ."""
    idx = np.flatnonzero(nondominated(np.column_stack([mu, sd])))
    return idx[np.argsort(mu[idx], kind="stable")]


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--n-theta", type=int, default=100)
    ap.add_argument("--speeds", type=float, nargs="+",
                    default=[8000.0, 12000.0, 16000.0, 20000.0, 24000.0])
    ap.add_argument("--delta-lim-um", type=float, nargs="+", default=[1.3, 1.5, 1.6])
    ap.add_argument("--n-jobs", type=int, default=2)
    args = ap.parse_args()
    k = 1.0 + STD * np.random.default_rng(5).standard_normal((args.n_theta, 2))
    speeds = np.sort(np.asarray(args.speeds, float))
    X = np.array([[F, L, D] for F in (1000, 1500, 2000, 2500, 3000)
                  for L in np.arange(300.0, 751.0, 10.0) for D in np.arange(50.0, 80.1, 5.0)])
    t = time.time()
    sp = reference_spindle()
    Y = np.array(Parallel(n_jobs=args.n_jobs)(delayed(amplitudes)(sp, x, speeds, k) for x in X))
    print(f"{len(X)} designs x {args.n_theta} θ x {speeds.size} speeds: FE {time.time() - t:.0f} s")
    for s, spd in enumerate(speeds):
        y = Y[:, :, s]
        mu, sd = y.mean(1), y.std(1, ddof=1)
        nd = front(mu, sd)
        print(f"\n== {spd:.0f} rpm: {nd.size} non-dominated grid designs "
              f"(μ {mu.min():.3f} - {mu.max():.1f} µm over the grid)")
        print("   F_N   L_mm  D_mm    mu_um    sd_um  sd/mu")
        for i in nd:
            print(f"  {X[i, 0]:5.0f} {X[i, 1]:6.1f} {X[i, 2]:5.1f} {mu[i]:8.4f} {sd[i]:8.4f} "
                  f"{sd[i] / mu[i]:6.3f}")
        for lim in args.delta_lim_um:
            pf = (y > lim).mean(1)
            parts = []
            for pt in (0.10, 0.05, 0.01):
                ok = np.flatnonzero(pf <= pt)
                f = ok[front(mu[ok], sd[ok])]
                parts.append(f"P_t {pt:.0%}: {f.size} nd, σ_min {sd[f].min():.4f}")
            print(f"  δ_lim {lim} µm: " + "; ".join(parts))


if __name__ == "__main__":
    main()
