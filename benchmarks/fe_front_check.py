"""Check a study's Pareto front with the full FE model. Prints surrogate vs FE μ_y, σ_y, P_f.

Run:  OMP_NUM_THREADS=1 python benchmarks/fe_front_check.py RUN_FOLDER [--front "rbrdo 5%"]
      [--points 7] [--n-theta 400]

Reads ``pareto_fronts.csv`` of a ``study`` run folder, picks ``--points`` designs spread along
the chosen front (sorted by the surrogate's μ) and evaluates them with the FE model
(``PeakAmplitudeResponse``) on one fresh θ sample of the reference uncertainty model.
"""

from __future__ import annotations

import argparse
import csv
import os
from pathlib import Path

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import numpy as np  # noqa: E402
from joblib import Parallel, delayed  # noqa: E402

from surrogate_rbrdo.spindle.evaluate import PeakAmplitudeResponse  # noqa: E402
from surrogate_rbrdo.spindle.reference import reference_spindle  # noqa: E402


def fe_stats(x, theta, delta_lim_um):
    y = PeakAmplitudeResponse(reference_spindle())(np.array([x]), theta)[0] * 1e6
    return y.mean(), y.std(ddof=1), float(np.mean(y > delta_lim_um))


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("run_folder", type=Path)
    ap.add_argument("--front", default="rbrdo 5%")
    ap.add_argument("--points", type=int, default=7)
    ap.add_argument("--n-theta", type=int, default=400)
    ap.add_argument("--delta-lim-um", type=float, default=19.5)
    ap.add_argument("--seed", type=int, default=11)
    args = ap.parse_args()
    rows = [r for r in csv.DictReader((args.run_folder / "pareto_fronts.csv").open())
            if r["run"] == args.front]
    if not rows:
        raise SystemExit(f"no front named {args.front!r} in {args.run_folder}")
    rows.sort(key=lambda r: float(r["mean_um"]))
    pick = [rows[i] for i in np.linspace(0, len(rows) - 1, args.points).astype(int)]
    rng = np.random.default_rng(args.seed)
    theta = 1.0 + np.array([0.0605, 0.0641]) * rng.standard_normal((args.n_theta, 2))
    X = [[float(r[k]) for k in ("preload_N", "span_mm", "diameter_mm")] for r in pick]
    res = Parallel(n_jobs=2)(delayed(fe_stats)(x, theta, args.delta_lim_um) for x in X)
    print(f"front {args.front!r} of {args.run_folder} ({len(rows)} points), N_theta = "
          f"{args.n_theta}")
    print("  F_N    L_mm   D_mm | surrogate mu_um sd_um | FE mu_um  sd_um   P_f")
    for r, x, (m, s, p) in zip(pick, X, res, strict=True):
        print(f"{x[0]:6.0f} {x[1]:7.1f} {x[2]:6.2f} | {float(r['mean_um']):9.4f} "
              f"{float(r['std_um']):7.4f} | {m:7.4f} {s:7.4f} {p:6.3f}")


if __name__ == "__main__":
    main()
