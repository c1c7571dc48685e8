"""Ground truth of the RBRDO landscape from the full FE model (no surrogate). Prints a table.

Run:  OMP_NUM_THREADS=1 python benchmarks/fe_design_lines.py [--beta 2.1e-6] [--n-theta 400]

For lines of designs (F, D fixed, span L swept across the resonance boundary) it prints μ_y,
σ_y and P_f(y > δ_lim) of the peak tool-tip amplitude from N θ samples of the reference
uncertainty model (θ ~ MVN([1, 1], std [0.0605, 0.0641])), one common sample for all designs.
``--beta`` overrides the Rayleigh β (2.1e-6 s: the paper's Eq. 4; 2.3e-5 s gives ζ ≈ 2.5 % at
the first bending mode, the paper's stated damping level). Used in docs/paper-study.md to decide
whether the reference problem has a μ–σ trade-off at all.
"""

from __future__ import annotations

import argparse
import os
import time
from dataclasses import replace

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import numpy as np  # noqa: E402
from joblib import Parallel, delayed  # noqa: E402

from surrogate_rbrdo.spindle.evaluate import PeakAmplitudeResponse  # noqa: E402
from surrogate_rbrdo.spindle.reference import reference_spindle  # noqa: E402


def line_point(F, D, L, theta, beta, delta_lim_um):
    sp = reference_spindle()
    sp = replace(sp, geometry=replace(sp.geometry, rayleigh_beta_s=beta))
    y = PeakAmplitudeResponse(sp)(np.array([[F, L, D]]), theta)[0] * 1e6
    return F, D, L, y.mean(), y.std(ddof=1), float(np.mean(y > delta_lim_um))


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--beta", type=float, default=2.1e-6)
    ap.add_argument("--n-theta", type=int, default=400)
    ap.add_argument("--delta-lim-um", type=float, default=19.5)
    ap.add_argument("--preloads", type=float, nargs="+", default=[3000.0, 2000.0])
    ap.add_argument("--diameters", type=float, nargs="+", default=[65.0, 72.0, 80.0])
    ap.add_argument("--spans", type=float, nargs=3, default=[340.0, 560.0, 10.0],
                    metavar=("START", "STOP", "STEP"))
    ap.add_argument("--n-jobs", type=int, default=2)
    args = ap.parse_args()
    rng = np.random.default_rng(7)
    theta = 1.0 + np.array([0.0605, 0.0641]) * rng.standard_normal((args.n_theta, 2))
    spans = np.arange(*args.spans)
    jobs = [(F, D, L) for F in args.preloads for D in args.diameters for L in spans]
    t = time.time()
    rows = Parallel(n_jobs=args.n_jobs)(
        delayed(line_point)(F, D, L, theta, args.beta, args.delta_lim_um) for F, D, L in jobs)
    print(f"beta = {args.beta:g} s, N_theta = {args.n_theta}, delta_lim = {args.delta_lim_um} um")
    print("F_N    D_mm  L_mm     mu_um    sd_um   sd/mu    P_f")
    for F, D, L, mu, sd, pf in rows:
        print(f"{F:5.0f} {D:5.1f} {L:5.1f} {mu:9.3f} {sd:8.3f} {sd / mu:7.3f} {pf:6.3f}")
    print(f"wall {time.time() - t:.0f} s")


if __name__ == "__main__":
    main()
