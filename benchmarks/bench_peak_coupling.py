"""Benchmark of the exact fast path for the peak response with random unbalance (issue 17 §4).

Run:  OMP_NUM_THREADS=1 python benchmarks/bench_peak_coupling.py [--quick]

Prints (asserts nothing):
* predictions/s of ``PeakUnbalanceResponse`` (the credible reference response: peak tool-tip
  amplitude over 1 000–24 000 rpm, θ = stiffness factors + ISO 21940-11 unbalance magnitude
  and relative phase) for designs × 1 000 θ, on one process, with the split between the
  per-design tables and the per-sample search; the extrapolated wall time of the paper-scale
  study (3 × 100 × 200 designs × 1 000 θ);
* its relative error against the FE model: (a) the FE peak search
  (``peak_tool_amplitude_unbalance``, ``harmonic.peak_search`` on the direct solve) with
  the library's default options and with a 4× finer grid; (b) a dense sweep of the FE
  response (20 001 speeds, then 4 001 speeds in ±1 % around the three highest maxima);
* with ``--wide``: 120 uniformly random designs × 30 samples (stiffness factors CoV 4 %,
  unbalance uniform over a 10.4 g mm disk per plane) against the fine FE peak search, for the
  default options and for 40, 56 and 64 grid speeds (~2 min);
* the chain condensation of the rotor against the dense Schur complement (48 speeds);
* peak memory (ru_maxrss).
"""

from __future__ import annotations

import argparse
import os
import resource
import time

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import numpy as np  # noqa: E402

from surrogate_rbrdo.doe.lhs import lhs  # noqa: E402
from surrogate_rbrdo.spindle.coupling import theta_grid  # noqa: E402
from surrogate_rbrdo.spindle.harmonic import PeakOptions, orbit_amplitude  # noqa: E402
from surrogate_rbrdo.spindle.peak_coupling import (  # noqa: E402
    CoupledPeakOptions,
    coupled_tables,
    peak_from_tables,
    peak_tool_amplitude_coupled,
    peak_tool_amplitude_unbalance,
    tool_response_per_plane,
)
from surrogate_rbrdo.spindle.peak_response import PeakUnbalanceResponse, ThetaSpec  # noqa: E402
from surrogate_rbrdo.spindle.reference import reference_spindle  # noqa: E402
from surrogate_rbrdo.spindle.substructure import (  # noqa: E402
    condensed_rotor,
    condensed_rotor_chain,
)
from surrogate_rbrdo.uncertainty.spindle_theta import theta_random_vector  # noqa: E402


def dense_peak(model, k, U):
    """Reference: FE orbit amplitude on 20 001 speeds, then 4 001 speeds in ±1 % around each
    of the three highest local maxima (final spacing 5e-6 of the speed)."""
    def amp(speeds):
        h = tool_response_per_plane(model, speeds, k[None])[:, 0]        # (P, S, 2)
        q = np.einsum("psc,p->sc", h, U)
        return orbit_amplitude(q[:, 0], q[:, 1])
    sp = np.linspace(1000.0, 24000.0, 20_001)
    a = np.concatenate([amp(sp[i:i + 5000]) for i in range(0, sp.size, 5000)])
    is_max = (a >= np.r_[-np.inf, a[:-1]]) & (a >= np.r_[a[1:], -np.inf])
    best = a.max()
    for j in np.flatnonzero(is_max)[np.argsort(-a[is_max])][:3]:
        s = sp[j]
        fine = np.linspace(max(1000.0, 0.99 * s), min(24000.0, 1.01 * s), 4001)
        best = max(best, amp(fine).max())
    return best


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--wide", action="store_true", help="3 600-sample validation (~2 min)")
    args = ap.parse_args()
    n_designs, n_err, n_dense = (8, 4, 2) if args.quick else (40, 12, 5)
    sp = reference_spindle()
    spec = ThetaSpec()
    resp = PeakUnbalanceResponse(sp, spec)
    rng = np.random.default_rng(2024)
    theta = theta_random_vector(spec).sample(1000, rng=rng)
    X = lhs(n_designs, sp.design_map.bounds, rng=rng)
    resp(X[:2], theta)                                                  # warm-up
    wall = cpu = np.inf
    for _ in range(3):                                     # best of three (shared machine)
        t, c = time.perf_counter(), time.process_time()
        y = resp(X, theta)
        wall, cpu = min(wall, time.perf_counter() - t), min(cpu, time.process_time() - c)
    rate = y.size / wall
    # split: tables (per design) vs the per-sample search
    m = sp.model(X[0])
    k, U = resp.unbalance(m, theta)
    nodes, basis = theta_grid(k)
    speeds = np.geomspace(1000.0, 24000.0, resp.options.n_grid)
    t_tab = t_row = np.inf
    for _ in range(10):
        t0 = time.perf_counter()
        T = coupled_tables(m, speeds, nodes)
        t1 = time.perf_counter()
        peak_from_tables(T, basis, U, resp.options)
        t_tab, t_row = min(t_tab, t1 - t0), min(t_row, time.perf_counter() - t1)
    t_dense = t_chain = np.inf
    for _ in range(10):
        t0 = time.perf_counter()
        S1 = condensed_rotor(m, speeds)
        t1 = time.perf_counter()
        S2 = condensed_rotor_chain(m, speeds)
        t_dense, t_chain = min(t_dense, t1 - t0), min(t_chain, time.perf_counter() - t1)
    cond_err = np.abs(S1 - S2).max() / np.abs(S1).max()
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"load average {os.getloadavg()[0]:.2f} (2 cores shared)")
    print(f"PeakUnbalanceResponse: {n_designs} designs x 1000 theta in {wall:.2f} s wall "
          f"({cpu:.2f} s CPU, best of 3): {rate:.3g} predictions/s on one process")
    print(f"  one design (best of 10): tables {t_tab * 1e3:.1f} ms (condensation + "
          f"{nodes.shape[0]} x {speeds.size} coupled solves), search {t_row * 1e3:.1f} ms for "
          "1000 samples; the rest is the model build and θ mapping")
    study = 3 * 100 * 200 * 1000
    print(f"  paper-scale study (3 x 100 x 200 designs x 1000 theta = {study:.1e}): "
          f"{study / rate / 60:.1f} min on one process, ~{study / rate / 120:.1f} min on two")
    print(f"  condensation at {speeds.size} speeds: chain {t_chain * 1e3:.2f} ms, dense Schur "
          f"complement {t_dense * 1e3:.2f} ms ({t_dense / t_chain:.1f}x), difference "
          f"{cond_err:.1e} of the largest entry")
    print(f"  peak memory {rss:.0f} MB")
    # accuracy against the FE peak search, default and finer options
    errs = {"FE search (default PeakOptions)": [], "FE search (n_grid 200, zoom 3x21)": []}
    opts = {"FE search (default PeakOptions)": PeakOptions(),
            "FE search (n_grid 200, zoom 3x21)": PeakOptions(n_grid=200, n_candidates=4,
                                                             n_refine=21, n_zoom=3)}
    dense = []
    t_fe = 0.0
    for i in range(n_err):
        m = sp.model(X[i])
        k, U = resp.unbalance(m, theta[:10])
        for key, o in opts.items():
            t0 = time.perf_counter()
            r = peak_tool_amplitude_unbalance(m, k, U, options=o)
            t_fe += time.perf_counter() - t0
            errs[key].append(y[i, :10] / r.amplitude - 1)
        if i < n_dense:
            ref = np.array([dense_peak(m, k[j], U[j]) for j in range(3)])
            dense.append(y[i, :3] / ref - 1)
    for key, e in errs.items():
        e = np.abs(np.concatenate(e))
        print(f"relative error vs {key}: max {e.max():.2e}, median {np.median(e):.2e} "
              f"({e.size} samples, {n_err} designs)")
    e = np.abs(np.concatenate(dense))
    print(f"relative error vs dense FE sweep (20 001 + 3 x 4 001 speeds): max {e.max():.2e}, "
          f"median {np.median(e):.2e} ({e.size} samples)")
    n_fe = n_err * 10 * len(opts)
    print(f"FE peak search: {t_fe / n_fe * 1e3:.1f} ms per sample ({n_fe} samples) -> "
          f"{1.0 / (t_fe / n_fe):.3g} predictions/s; fast path {rate * t_fe / n_fe:.0f}x")
    if args.wide:
        wide(sp)


def wide(sp) -> None:
    """3 600 random (design, θ, unbalance) samples against the fine FE peak search."""
    fine = PeakOptions(n_grid=300, n_candidates=5, n_refine=21, n_zoom=3)
    b = sp.design_map.bounds
    data = []
    for seed in (7, 11, 23, 31):
        rng = np.random.default_rng(seed)
        for x in b[:, 0] + (b[:, 1] - b[:, 0]) * rng.random((30, 3)):
            m = sp.model(x)
            th = rng.normal(1.0, 0.04, (30, 2))
            U = 1.04e-5 * np.sqrt(rng.random((30, 2))) * np.exp(2j * np.pi * rng.random((30, 2)))
            data.append((m, th, U, peak_tool_amplitude_unbalance(m, th, U, options=fine)))
    for opts in (CoupledPeakOptions(), CoupledPeakOptions(n_grid=40),
                 CoupledPeakOptions(n_grid=56), CoupledPeakOptions(n_grid=64)):
        e = np.abs(np.concatenate([peak_tool_amplitude_coupled(m, th, U, options=opts).amplitude
                                   / ref.amplitude - 1 for m, th, U, ref in data]))
        print(f"wide validation, {opts.n_grid} speeds: max rel. error {e.max():.2e}, 99.9 % "
              f"{np.quantile(e, 0.999):.2e} ({e.size} samples, 120 designs)")


if __name__ == "__main__":
    main()
