"""The two-speed soak's test of β = 1 (``discrepancy.soak``) under a probe gain drift: its
size, β̂'s spread and the mean reported SE over synthetic soaks whose predicted drift lies
near the response (review s13, H1).

Three channels, 2 speeds × ``runs`` runs × 8 records, each probe's gain drifting by
(3, −2, 1)·10⁻⁴ per kelvin, the predicted drift ``Δ_s = κ_s a_s (1 + 0.1i)`` (opposite
signs of ``κ`` on opposite flanks, alike on one), noise 3e-9 on a 1e-6 response, true β = 1,
level 0.05::

    python3 benchmarks/soak_beta_size.py --n 2000
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from surrogate_rbrdo.discrepancy.soak import drift_test, warmup
from surrogate_rbrdo.discrepancy.soak_synthetic import gain_drift_soaks

CASES = {"opposite flanks": (0.02, -0.02), "one flank": (0.02, 0.015),
         "one flank, equal": (0.02, 0.02)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=2000, help="data sets per case")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--runs", type=int, default=2, help="runs per speed")
    args = ap.parse_args()
    for label, kappas in CASES.items():
        rng = np.random.default_rng(args.seed)
        t0 = time.perf_counter()
        rows = []
        for _ in range(args.n):
            blocks, drifts = gain_drift_soaks(rng, kappas, runs=args.runs)
            r = drift_test("x", blocks, tuple(warmup(b) for b in blocks),
                           (np.zeros(3),) * 2, drifts, 0.0, 0.05)
            rows.append((r.beta, r.se, r.p_predicted < 0.05, r.outcome))
        b = np.array([x[0] for x in rows])
        out = [x[3] for x in rows]
        print(f"{label} κ={kappas}: SD(β̂) {b.std():.4f}, mean SE "
              f"{np.nanmean([x[1] for x in rows]):.4f}, P(reject β=1) "
              f"{np.mean([x[2] for x in rows]):.4f}, drift {out.count('drift') / args.n:.4f},"
              f" no_drift {out.count('no_drift') / args.n:.4f}"
              f" ({time.perf_counter() - t0:.1f} s)", flush=True)


if __name__ == "__main__":
    main()
