"""Benchmark of the substructure surrogate on the credible problem (issue 17 item 2).

Run:  OMP_NUM_THREADS=1 python benchmarks/bench_substructure_credible.py [--n-points 300]

The credible reference response (``PeakUnbalanceSpec``: peak tool-tip amplitude over
1 000–24 000 rpm, θ = stiffness factors 1.5 % / 3.3 % + ISO 21940-11 unbalance magnitude per
plane uniform over its tolerance disk + relative phase) on ``credible_spindle()``. Prints
(asserts nothing), for substructure surrogates trained on 30, 60 and 200 designs (one FE
condensation each, counted):

* the relative error of the peak at ``--n-points`` random joint points (designs uniform over
  the box, θ from the credible θ model) against the FE model's own peak search
  (``PeakUnbalanceResponse(method="direct")``) and against the FE fast path
  (``method="coupled"``): max, 99 %, median;
* predictions/s on a grid of 40 random designs × 1 000 θ (the study's shape: the Kriging of
  ``S`` and the coupled peak), side by side with the FE fast path and the FE peak search on
  the same work, in one run (best of ``--repeat``);
* the training time and the peak memory (ru_maxrss); the load average (``os.getloadavg``).
"""

from __future__ import annotations

import argparse
import os
import resource
import time

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import numpy as np  # noqa: E402

from surrogate_rbrdo.core.counting import CallCounter  # noqa: E402
from surrogate_rbrdo.spindle.peak_response import PeakUnbalanceSpec  # noqa: E402
from surrogate_rbrdo.spindle.reference import credible_spindle  # noqa: E402
from surrogate_rbrdo.surrogates.structured import (  # noqa: E402
    SubstructureOptions,
    train_surrogate,
)
from surrogate_rbrdo.uncertainty.spindle_theta import theta_random_vector  # noqa: E402


def _rel(a: np.ndarray, b: np.ndarray) -> str:
    r = np.abs(a / b - 1).ravel()
    return f"max {r.max():.2e}, 99 % {np.quantile(r, 0.99):.2e}, median {np.median(r):.2e}"


def _best(f, repeat: int) -> tuple[float, np.ndarray]:
    best, out = np.inf, None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = f()
        best = min(best, time.perf_counter() - t0)
    return best, out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--n-points", type=int, default=300)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--sizes", type=int, nargs="+", default=[30, 60, 200])
    a = ap.parse_args()
    print(f"load average at start: {os.getloadavg()}")
    sp, spec = credible_spindle(), PeakUnbalanceSpec()
    fe, fast = spec.fe_response(sp, "direct"), spec.fe_response(sp, "condensed")
    rng = np.random.default_rng(20261124)
    lo, hi = np.asarray(sp.design_map.bounds, dtype=float).T
    theta_v = theta_random_vector(spec.theta_spec)
    Xp = lo + (hi - lo) * rng.random((a.n_points, 3))
    Tp = theta_v.sample(a.n_points, rng=rng)
    t0 = time.perf_counter()
    y_fe = np.array([fe(Xp[i:i + 1], Tp[i:i + 1])[0, 0] for i in range(a.n_points)])
    t_fe = time.perf_counter() - t0
    y_fast = np.array([fast(Xp[i:i + 1], Tp[i:i + 1])[0, 0] for i in range(a.n_points)])
    print(f"{a.n_points} joint points; FE peak search {t_fe:.1f} s "
          f"({a.n_points / t_fe:.0f} predictions/s); y from {y_fe.min() * 1e6:.3f} to "
          f"{y_fe.max() * 1e6:.1f} µm")
    print(f"FE fast path vs FE peak search: {_rel(y_fast, y_fe)}")
    Xg = lo + (hi - lo) * rng.random((40, 3))
    Tg = theta_v.sample(1000, rng=rng)
    t_fast, yg_fast = _best(lambda: fast(Xg, Tg), a.repeat)
    print(f"grid 40 designs x 1000 θ: FE fast path {t_fast:.3f} s "
          f"({Tg.shape[0] * 40 / t_fast:.3g} predictions/s)")
    for n in a.sizes:
        counter = CallCounter()
        t0 = time.perf_counter()
        tr = train_surrogate(sp, None, None, SubstructureOptions(
            n_doe=n, n_jobs=1, backend="sequential", n_start=3), rng=np.random.default_rng(0),
            response=spec, counter=counter)
        t_train = time.perf_counter() - t0
        y_sur = tr.model.response_points(np.column_stack([Xp, Tp]))
        t_sur, yg_sur = _best(lambda tr=tr: tr.model(Xg, Tg), a.repeat)
        print(f"substructure, {n} designs: {counter.calls} FE calls, training {t_train:.1f} s")
        print(f"  joint points vs FE peak search: {_rel(y_sur, y_fe)}")
        print(f"  joint points vs FE fast path:   {_rel(y_sur, y_fast)}")
        print(f"  grid vs FE fast path: {_rel(yg_sur, yg_fast)}; μ per design max "
              f"{np.abs(yg_sur.mean(1) / yg_fast.mean(1) - 1).max():.2e}, σ max "
              f"{np.abs(yg_sur.std(1) / yg_fast.std(1) - 1).max():.2e}")
        print(f"  grid {t_sur:.3f} s ({Tg.shape[0] * 40 / t_sur:.3g} predictions/s): "
              f"{t_fast / t_sur:.2f}x the FE fast path, {t_fe / a.n_points * 40000 / t_sur:.0f}x "
              "the FE peak search")
    print(f"peak memory {resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024:.0f} MB; "
          f"load average at end: {os.getloadavg()}")


if __name__ == "__main__":
    main()
