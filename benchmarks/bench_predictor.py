"""Benchmark: separable grid predictor vs smt ``predict_values`` on the same points, one run.

Setup as in the paper: a 200-point maximin LHS over the joint (x, θ) box of the spindle problem
(x = [preload_N, span_mm, diameter_mm], θ = bearing-stiffness factors in [0.5, 1.5]), an analytic
stand-in response, smt KRG fitted on it; then P designs × N θ samples (common random numbers).

    python benchmarks/bench_predictor.py [--P 100] [--N 1000] [--kernel krg_se] [--seed 0]

Prints predictions per second of both paths, their ratio, and the largest relative disagreement.
BLAS is pinned to one thread for everything.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from threadpoolctl import threadpool_limits

from surrogate_rbrdo.doe import lhs
from surrogate_rbrdo.surrogates import SURROGATES, ProductKernelPredictor

BOUNDS = np.array([[1000.0, 3000.0], [300.0, 750.0], [50.0, 80.0], [0.5, 1.5], [0.5, 1.5]])


def stand_in(Z: np.ndarray) -> np.ndarray:
    """Smooth analytic stand-in for the FE peak amplitude (μm-like scale)."""
    p, s, d, kf, kr = (Z[:, j] for j in range(5))
    return 10.0 * (s / 500.0) ** 2 * (65.0 / d) ** 3 / np.sqrt(p / 2000.0) / (0.6 * kf + 0.4 * kr)


def best_time(fn, repeat: int) -> float:
    best = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--P", type=int, default=100)
    ap.add_argument("--N", type=int, default=1000)
    ap.add_argument("--n-train", type=int, default=200)
    ap.add_argument("--kernel", default="krg_se", choices=["krg_se", "krg_matern52", "gpr"])
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--repeat", type=int, default=20)
    args = ap.parse_args()
    rng_doe, rng_fit, rng_eval = np.random.default_rng(args.seed).spawn(3)

    with threadpool_limits(limits=1, user_api="blas"):
        Z = lhs(args.n_train, BOUNDS, rng=rng_doe)
        t0 = time.perf_counter()
        model = SURROGATES[args.kernel](rng=rng_fit).fit(Z, stand_in(Z))
        t_fit = time.perf_counter() - t0
        fast = ProductKernelPredictor.from_model(model, n_design=3)

        x = BOUNDS[:3, 0] + rng_eval.random((args.P, 3)) * np.ptp(BOUNDS[:3], axis=1)
        theta = rng_eval.normal(1.0, 0.06, size=(args.N, 2))
        J = np.column_stack([np.repeat(x, args.N, axis=0), np.tile(theta, (args.P, 1))])
        n = args.P * args.N
        block = fast.prepare_theta(theta)

        if args.kernel == "gpr":
            Jn = (J - model.X_offset_) / model.X_scale_
            ref_fn = lambda: model.model_.predict(Jn)  # noqa: E731
            ref_var_fn = lambda: model.model_.predict(Jn, return_std=True)[1] ** 2  # noqa: E731
        else:
            ref_fn = lambda: model.model_.predict_values(J).ravel()  # noqa: E731
            ref_var_fn = lambda: model.model_.predict_variances(J).ravel()  # noqa: E731
        ref = ref_fn()
        ref_var = ref_var_fn()
        grid = fast.predict_grid(x, block, return_std=True)
        rel_mean = np.max(np.abs(grid.mean.ravel() - ref) / np.abs(ref))
        rel_var = np.max(np.abs(grid.std.ravel() ** 2 - ref_var) / ref_var)

        t_ref = best_time(ref_fn, max(1, args.repeat // 2))
        t_ref_var = best_time(ref_var_fn, 1)
        t_fast = best_time(lambda: fast.predict_grid(x, block), args.repeat)
        t_fast_cold = best_time(lambda: fast.predict_grid(x, theta), args.repeat)
        t_fast_var = best_time(lambda: fast.predict_grid(x, block, return_std=True), 1)

    print(f"model {args.kernel}: {args.n_train} training points, fit {t_fit:.1f} s (1 BLAS thread)")
    print(f"grid P x N = {args.P} x {args.N} = {n} predictions")
    print(f"reference predict (mean)         : {n / t_ref:12.3e} pred/s  ({t_ref * 1e3:8.1f} ms)")
    print(f"fast predict_grid, theta block   : {n / t_fast:12.3e} pred/s  ({t_fast * 1e3:8.2f} ms)"
          f"  speed-up {t_ref / t_fast:8.0f}x")
    print(f"fast predict_grid, incl. block   : {n / t_fast_cold:12.3e} pred/s  "
          f"({t_fast_cold * 1e3:8.2f} ms)  speed-up {t_ref / t_fast_cold:8.0f}x")
    print(f"reference mean+variance          : {n / t_ref_var:12.3e} pred/s  "
          f"({t_ref_var * 1e3:8.1f} ms)")
    print(f"fast mean+std                    : {n / t_fast_var:12.3e} pred/s  "
          f"({t_fast_var * 1e3:8.1f} ms)  speed-up {t_ref_var / t_fast_var:8.1f}x")
    print(f"max relative disagreement: mean {rel_mean:.2e}, variance {rel_var:.2e}")
    gen = 200 * 1e5
    print(f"=> one NSGA-II run (2e7 predictions): fast {gen / (n / t_fast):.1f} s, "
          f"reference {gen / (n / t_ref) / 60:.1f} min")


if __name__ == "__main__":
    main()
