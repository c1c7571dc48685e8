"""Benchmark of the FE spindle model (issue 2 §5). Prints its figures; asserts nothing.

Run:  OMP_NUM_THREADS=1 python benchmarks/bench_spindle.py [--quick]

Measures, on the reference spindle at the baseline design:
* one peak tool-tip amplitude over 1000–24 000 rpm (median wall and CPU time) and its error
  against a very fine sweep (20 001 speeds, then 20 001 speeds in ±1 % around each of its three
  highest maxima) at 9 designs (corners + centre) x 3 θ values;
* modal analysis at one speed; a Campbell diagram over 50 speeds;
* 200 peak evaluations in one batch (200 θ samples of one design, and 200 designs);
* the amplitude at 24 000 rpm for 20 designs × 1 000 θ by the direct solve and by exact
  condensation (``AtSpeedAmplitudeResponse(method=...)``), side by side;
* peak memory (ru_maxrss) of the workloads, read before the accuracy check.
"""

from __future__ import annotations

import argparse
import itertools
import os
import resource
import time

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import numpy as np  # noqa: E402

from surrogate_rbrdo.spindle import (  # noqa: E402
    campbell,
    modal_analysis,
    peak_tool_amplitude,
    reference_spindle,
    tool_amplitude,
    unbalance_response,
)
from surrogate_rbrdo.spindle.evaluate import AtSpeedAmplitudeResponse  # noqa: E402


def timeit(fn, repeat):
    wall, cpu = [], []
    for _ in range(repeat):
        t, c = time.perf_counter(), time.process_time()
        fn()
        wall.append(time.perf_counter() - t)
        cpu.append(time.process_time() - c)
    return float(np.median(wall)), float(np.median(cpu))


def fine_peak(model, theta):
    """Reference peak: 20 001 uniform speeds, then 20 001 speeds in ±1 % around each of the
    three highest local maxima of that sweep (final spacing ~1e-6 of the speed)."""
    sp = np.linspace(1000.0, 24000.0, 20_001)
    amps = np.concatenate([tool_amplitude(model, sp[i:i + 4000], theta)[0]
                           for i in range(0, sp.size, 4000)])
    left = np.r_[-np.inf, amps[:-1]]
    right = np.r_[amps[1:], -np.inf]
    maxima = np.nonzero((amps >= left) & (amps >= right))[0]
    best = amps.max()
    for k in maxima[np.argsort(-amps[maxima])][:3]:
        loc = np.linspace(max(sp[k] * 0.99, 1000.0), min(sp[k] * 1.01, 24000.0), 20_001)
        a2 = np.concatenate([tool_amplitude(model, loc[i:i + 4000], theta)[0]
                             for i in range(0, loc.size, 4000)])
        best = max(best, a2.max())
    return best


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="fewer repeats and accuracy points")
    args = ap.parse_args()
    rep = 5 if args.quick else 30
    sp = reference_spindle()
    model = sp.model(sp.baseline)
    print(f"reference spindle, baseline x = {sp.baseline.tolist()}, {model.n_nodes} nodes, "
          f"{model.n_dof} DOF")

    w, c = timeit(lambda: peak_tool_amplitude(model), rep)
    print(f"one peak amplitude (1000-24000 rpm): median wall {w * 1e3:.1f} ms, "
          f"CPU {c * 1e3:.1f} ms   [target <= 20 ms]")

    for n_sp in (47, 500):
        grid = np.linspace(1000.0, 24000.0, n_sp)
        w, c = timeit(lambda grid=grid: unbalance_response(model, grid), rep)
        print(f"unbalance response, all nodes, {n_sp} speeds: median wall {w * 1e3:.1f} ms, "
              f"CPU {c * 1e3:.1f} ms   [ROSS 2.3: ~0.31 s (47), ~3.3 s (500), 30 elements]")

    w, c = timeit(lambda: modal_analysis(model, 24000.0), rep)
    print(f"modal analysis at one speed: median wall {w * 1e3:.1f} ms, CPU {c * 1e3:.1f} ms")
    w, c = timeit(lambda: campbell(model, np.linspace(0, 24000, 50)), 3 if args.quick else 5)
    print(f"Campbell diagram over 50 speeds (with refined critical speeds): wall {w:.2f} s, "
          f"CPU {c:.2f} s")
    w, c = timeit(lambda: campbell(model, np.linspace(0, 24000, 50), refine=False), 3)
    print(f"Campbell diagram over 50 speeds (crossings interpolated): wall {w:.2f} s")

    rng = np.random.default_rng(0)
    th200 = 1.0 + 0.06 * rng.standard_normal((200, 2))
    w, c = timeit(lambda: peak_tool_amplitude(model, th200), 1 if args.quick else 3)
    print(f"200 peak evaluations, one design x 200 θ: wall {w:.2f} s, CPU {c:.2f} s "
          f"({w / 200 * 1e3:.1f} ms each)   [target <= 4 s]")
    lhs = sp.design_map.bounds[:, 0] + rng.random((200, 3)) * np.diff(sp.design_map.bounds).T

    def many_designs():
        for x in lhs:
            peak_tool_amplitude(sp.model(x))

    w, c = timeit(many_designs, 1)
    print(f"200 peak evaluations, 200 designs (model built each time): wall {w:.2f} s, "
          f"CPU {c:.2f} s   [target <= 4 s]")
    # amplitude at 24 000 rpm, 20 designs x 1000 θ: the two exact FE methods side by side
    th1000 = 1.0 + 0.06 * rng.standard_normal((1000, 2))
    out = {}
    for method in ("direct", "condensed"):
        resp = AtSpeedAmplitudeResponse(sp, 24000.0, method=method)
        resp(lhs[:1], th1000[:40])                                   # warm-up
        t0 = time.perf_counter()
        out[method] = resp(lhs[:20], th1000)
        out[method + "_s"] = time.perf_counter() - t0
    d, cd = out["direct_s"], out["condensed_s"]
    err = np.abs(out["condensed"] / out["direct"] - 1).max()
    print(f"amplitude at 24000 rpm, 20 designs x 1000 θ (model built each time): direct "
          f"{d:.2f} s ({d / 20 * 1e3:.1f} ms/design), condensed {cd:.2f} s "
          f"({cd / 20 * 1e3:.1f} ms/design), ratio {d / cd:.1f}x, max rel. difference "
          f"{err:.1e}")
    peak_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"peak memory of the workloads above (max RSS so far): {peak_mb:.0f} MB   "
          "[target < 300 MB]")

    # accuracy last: its very fine reference sweeps need far more memory than the workload
    designs = [np.array(v, float) for v in itertools.product([1000, 3000], [300, 750], [50, 80])]
    designs.append(sp.design_map.bounds.mean(axis=1))
    thetas = np.array([[1.0, 1.0], [0.85, 1.1], [1.15, 0.9]])
    if args.quick:
        designs, thetas = designs[::4], thetas[:2]
    errs = []
    for x in designs:
        m = sp.model(x)
        p = peak_tool_amplitude(m, thetas)
        for i, th in enumerate(thetas):
            ref = fine_peak(m, th[None])
            errs.append(abs(p.amplitude[i] / ref - 1.0))
    errs = np.array(errs)
    print(f"peak vs very fine sweep over {errs.size} (design, θ) pairs: max rel. error "
          f"{errs.max():.2e}, median {np.median(errs):.2e}   [target <= 0.5 %]")



if __name__ == "__main__":
    main()
