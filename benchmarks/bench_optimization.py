"""Paper-scale RBRDO loop with a cheap stand-in for the fast surrogate predictor.

Three RBRDO runs (P_target = 10 %, 5 %, 1 %), each NSGA-II with pop 100 × 200 generations and a
fixed sample of 1000 θ: 3 × 100 × 200 × 1000 = 60 M response evaluations, as in the paper
(~20 M surrogate calls per run). The stand-in response has the shape of
``ProductKernelPredictor.predict_grid``: a design block ``Kx`` (P × n, n = 200 "training points")
times a θ block ``Kt`` (N × n) precomputed once for the fixed θ sample, i.e. one
(P × n) @ (n × N) matmul per generation. BLAS is pinned to one thread (threadpoolctl).

Run::

    python benchmarks/bench_optimization.py            # paper scale
    python benchmarks/bench_optimization.py --quick    # 20 generations
    python benchmarks/bench_optimization.py --profile  # cProfile of one run, top 25

Prints wall time per run and in total (sequential, then ``run_many`` with 2 processes), surrogate
and model calls, and the time inside the stand-in response/FE callables versus the rest (pymoo's
per-generation bookkeeping, MC estimates, archive). Needs the package importable
(``pip install -e .`` or ``PYTHONPATH=.``).
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import time
from functools import partial

import numpy as np
from threadpoolctl import threadpool_limits

from surrogate_rbrdo.core import LimitState
from surrogate_rbrdo.formulations import DeterministicOptions, FormulationOptions, make_formulation
from surrogate_rbrdo.optimization import NSGA2Options, run_many, run_nsga2
from surrogate_rbrdo.uncertainty import MultivariateNormal

LOWER = np.array([1000.0, 0.300, 0.050])   # preload N, span m, diameter m
UPPER = np.array([3000.0, 0.750, 0.080])


class StandIn:
    """Separable stand-in ``y = c + (Kx ⊙ α) Kt^T`` in metres, Kt cached per θ array."""

    def __init__(self, n_train: int = 200, *, rng: np.random.Generator) -> None:
        self.Xc = rng.random((n_train, 3))
        self.Tc = rng.standard_normal((n_train, 2))
        self.alpha = rng.normal(0.0, 1.0, n_train) / n_train
        self._key: np.ndarray | None = None
        self._Kt: np.ndarray | None = None

    def _theta_block(self, theta: np.ndarray) -> np.ndarray:
        if self._key is not theta:
            tn = (theta - np.array([3.0e8, 2.7e8])) / np.array([1.9e7, 1.7e7])
            d2 = ((tn[:, None, :] - self.Tc[None, :, :]) ** 2).sum(axis=2)
            self._Kt, self._key = np.exp(-0.5 * d2), theta
        return self._Kt

    def __call__(self, x: np.ndarray, theta: np.ndarray) -> np.ndarray:
        xn = (x - LOWER) / (UPPER - LOWER)
        d2 = ((xn[:, None, :] - self.Xc[None, :, :]) ** 2).sum(axis=2)
        Kx = np.exp(-2.0 * d2) * self.alpha
        # a smooth trend so the problem has a real μ–σ trade-off, plus the kernel part
        trend = 16e-6 + 3e-6 * (xn[:, :1] - 0.6) ** 2 - 2e-6 * xn[:, 2:3]
        tn1 = (theta[:, 0] - 3.0e8) / 1.9e7
        sens = 1e-6 * (3.0 - 2.0 * xn[:, 1:2])          # span changes the θ sensitivity
        return trend + sens * tn1[None, :] + 1e-5 * (Kx @ self._theta_block(theta).T)


def deterministic(x: np.ndarray) -> dict[str, np.ndarray]:
    xn = (x - LOWER) / (UPPER - LOWER)
    return {"von_mises_pa": 900e6 * (0.3 + 0.2 * xn[:, 0] + 0.7 * (1 - xn[:, 2])),
            "omega_n1": 2 * np.pi * (900.0 - 500.0 * xn[:, 1] + 300.0 * xn[:, 2])}


def one_run(p_target: float, n_gen: int, seed: int):
    rng = np.random.default_rng(seed)
    r_sur, r_form, r_opt = rng.spawn(3)
    stand_in = StandIn(rng=r_sur)
    inputs = MultivariateNormal(np.array([3.0e8, 2.7e8]), std=np.array([1.9e7, 1.7e7]),
                                corr=np.array([[1.0, 0.5], [0.5, 1.0]]))
    timed = {"t": 0.0}

    def response(x, theta):
        t0 = time.perf_counter()
        y = stand_in(x, theta)
        timed["t"] += time.perf_counter() - t0
        return y

    def timed_deterministic(x):
        t0 = time.perf_counter()
        q = deterministic(x)
        timed["t"] += time.perf_counter() - t0
        return q

    form = make_formulation(
        "rbrdo", response=response, inputs=inputs, limit=LimitState(19.5e-6),
        options=FormulationOptions(p_target=p_target, n_theta=1000,
                                   deterministic=DeterministicOptions(
                                       resonance="paper", omega_max=2 * np.pi * 400.0)),
        deterministic=timed_deterministic, rng=r_form)
    cpu = time.process_time()
    res = run_nsga2(form, LOWER, UPPER, rng=r_opt,
                    options=NSGA2Options(pop_size=100, n_gen=n_gen))
    timed["cpu"] = time.process_time() - cpu
    return res, timed


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="20 generations instead of 200")
    ap.add_argument("--profile", action="store_true", help="cProfile one run")
    ap.add_argument("--jobs", type=int, default=2,
                    help="worker processes for the parallel pass (default 2)")
    args = ap.parse_args()
    n_gen = 20 if args.quick else 200
    with threadpool_limits(limits=1, user_api="blas"):
        one_run(0.1, 2, 0)  # warm-up: imports, pymoo compilation checks
        if args.profile:
            prof = cProfile.Profile()
            prof.enable()
            one_run(0.05, n_gen, 1)
            prof.disable()
            pstats.Stats(prof).sort_stats("cumulative").print_stats(25)
            return
        tasks = [partial(one_run, pt, n_gen, 100 + i)
                 for i, pt in enumerate((0.10, 0.05, 0.01))]
        archives = []
        for label, n_jobs in (("sequential", 1), (f"parallel, {args.jobs} processes", args.jobs)):
            total = time.perf_counter()
            outs = run_many(tasks, n_jobs=n_jobs, blas_threads=1)
            total = time.perf_counter() - total
            archives.append([res.archive.X for res, _ in outs])
            calls = sum(res.n_surrogate_calls for res, _ in outs)
            cpu = sum(t["cpu"] for _, t in outs)
            print(f"-- {label}")
            for (res, tm), pt in zip(outs, (0.10, 0.05, 0.01), strict=True):
                fc, t_resp = res.formulation, tm["t"]
                print(f"P_target {pt:4.0%}: run {res.wall_time_s:5.2f} s wall, "
                      f"{tm['cpu']:5.2f} s CPU (stand-in response+FE "
                      f"{t_resp:4.2f} s, rest {res.wall_time_s - t_resp:4.2f} s)  "
                      f"surrogate calls {res.n_surrogate_calls:,}  model calls "
                      f"{res.n_model_calls:,}  archive {len(res.archive):,}  "
                      f"front {int(res.pareto_mask.sum())}  [{fc['formulation']}]")
            print(f"total wall: {total:.2f} s for 3 runs (CPU {cpu:.2f} s), {calls:,} surrogate "
                  f"calls ({calls / total / 1e6:.1f} M/s); target <= 10 s")
        # identical results whichever way they were run (seeds travel with the tasks)
        same = all(np.array_equal(a, b) for a, b in zip(*archives, strict=True))
        print(f"parallel archives == sequential archives (bit for bit): {same}")


if __name__ == "__main__":
    main()
