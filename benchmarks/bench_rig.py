"""Benchmark of the virtual rig: the paper's default campaign, timed, with its peak memory.

Run:  PYTHONPATH=$PWD python3 benchmarks/bench_rig.py [--repeats 20] [--out /tmp/bench_rig]

Prints the wall time of each part (1 000 steady-state records of 1 s at 10 kHz with 6 probe
channels + keyphasor; the run-up and run-down; 10 impact records), the dataset's size on disk,
the peak resident memory (``resource.getrusage``), and the fast path's time for the same 1 000
steady-state 1x phasors.
"""

from __future__ import annotations

import argparse
import os
import resource
import shutil
import time
from pathlib import Path

import numpy as np

from surrogate_rbrdo.rig.campaign import CampaignOptions, footprint, run_campaign
from surrogate_rbrdo.rig.phasors import sample_phasors
from surrogate_rbrdo.rig.truth import reference_truth


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeats", type=int, default=20)
    ap.add_argument("--out", default="/tmp/bench_rig")
    args = ap.parse_args()
    out = Path(args.out)
    shutil.rmtree(out, ignore_errors=True)
    truth = reference_truth()
    print(f"load average: {os.getloadavg()}")
    rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    est = footprint(CampaignOptions(repeats=args.repeats))
    print(f"footprint estimate of the whole campaign (rig.campaign.footprint): "
          f"{est.n_records} records, {est.disk_bytes / 1e6:.0f} MB on disk, "
          f"{est.memory_bytes / 1e6:.0f} MB above the interpreter's {rss0:.0f} MB "
          f"(sized by {est.memory_by})")
    t0 = time.perf_counter()
    steady = run_campaign(truth, CampaignOptions(repeats=args.repeats, runup=None,
                                                 impacts_per_direction=0),
                          out / "steady", rng=np.random.default_rng(0))
    t1 = time.perf_counter()
    extra = run_campaign(truth, CampaignOptions(speeds_rpm=(1000.0,), repeats=1),
                         out / "extra", rng=np.random.default_rng(0))
    t2 = time.perf_counter()
    size = sum(f.stat().st_size for f in (out / "steady").rglob("*.npz"))
    print(f"steady state: {steady.n_records} records in {t1 - t0:.1f} s "
          f"({size / 1e6:.0f} MB on disk, int16 counts)")
    print(f"run-up + run-down (1000-24000 rpm, 10 s each) and 10 impacts: "
          f"{t2 - t1:.1f} s ({extra.n_records - 1} records)")
    print(f"campaign total: {t2 - t0:.1f} s")
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"peak RSS: {peak:.0f} MB ({peak - rss0:.0f} MB above the start)")
    st = truth.state(np.random.default_rng(0).bit_generator.seed_seq, build=0, tool=0, run=0)
    sens = CampaignOptions().sensors
    inst = sens.install(np.random.default_rng(1))
    t3 = time.perf_counter()
    ph = sample_phasors(st.model(), st.theta, np.linspace(1000, 24000, 50), sens, inst,
                        np.random.default_rng(2), n_repeats=args.repeats)
    t4 = time.perf_counter()
    sample_phasors(st.model(), st.theta, np.linspace(1000, 24000, 50), sens, inst,
                   np.random.default_rng(2), n_repeats=args.repeats, keyphasor_error=False)
    t5 = time.perf_counter()
    print(f"fast path: {ph.size // 6} records' 1x phasors in {t4 - t3:.2f} s with the "
          f"keyphasor's phase error simulated, {t5 - t4:.3f} s without "
          f"(time domain / fast path: {(t1 - t0) / (t4 - t3):.0f}x and "
          f"{(t1 - t0) / (t5 - t4):.0f}x)")


if __name__ == "__main__":
    main()
