"""Crude Monte Carlo reference of the non-linear oscillator's P_f (problems.nonlinear_oscillator).

    PYTHONPATH=. python benchmarks/reference_oscillator.py [--chunks 20]

20 chunks of 1e7 samples from ``default_rng(20240613)``; prints the running estimate and its
standard error (the stored value: 5 717 336 failures in 2e8 samples, 2.858668e-2 ± 1.18e-5).
"""

from __future__ import annotations

import argparse

import numpy as np

from surrogate_rbrdo.estimators.problems import nonlinear_oscillator


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--chunks", type=int, default=20)
    ap.add_argument("--chunk-size", type=int, default=10_000_000)
    args = ap.parse_args()
    prob = nonlinear_oscillator()
    rng = np.random.default_rng(20240613)
    fails = total = 0
    for i in range(args.chunks):
        theta = prob.inputs.from_standard(rng.standard_normal((args.chunk_size, 6)))
        fails += int(np.count_nonzero(prob.limit.failed(prob.response(prob.x, theta))))
        total += args.chunk_size
        p = fails / total
        se = np.sqrt(p * (1 - p) / total)
        print(f"{i:2d} N={total:.1e} failures={fails} pf={p:.6e} se={se:.2e}")


if __name__ == "__main__":
    main()
