"""Below 3 347 rpm: do longer records or a heavier trial mass make the stiffness identifiable?

    PYTHONPATH=$PWD python3 benchmarks/bench_identification_lowspeed.py

At the rig's default sensors (noise 50 nm, 16 bit, gains, skews; counter keyphasor) the
trial-mass response at the rear journal is below 5 × its phasor noise under ~3 000 rpm with
1 s records and 50 g mm (``docs/identification.md`` §5). The phasor noise falls as
``1/√N`` with the record's samples and the response grows with the trial mass, so each
option is tried alone and together: 6 speeds in 1 000–3 500 rpm × 4 runs; printed per
speed: the vectors used (no SNR/precision flag on k) and the RMS error of k against each
record's truth (front, rear). Timings under the machine's load.
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import numpy as np

from surrogate_rbrdo.identification import (
    IdentificationOptions,
    catalog_coefficients,
    condense_reactions,
    identify_phasors,
)
from surrogate_rbrdo.identification.condensation import node_at
from surrogate_rbrdo.identification.experiment import read_responses
from surrogate_rbrdo.identification.rigtruth import truth_coefficients
from surrogate_rbrdo.rig import CampaignOptions, open_dataset, reference_truth, run_campaign
from surrogate_rbrdo.spindle import reference_spindle

SPEEDS = (1000.0, 1500.0, 2000.0, 2500.0, 3000.0, 3500.0)
CASES = {"1 s, 50 g mm": (1.0, 5e-5), "16 s, 50 g mm": (16.0, 5e-5),
         "1 s, 500 g mm": (1.0, 5e-4), "16 s, 500 g mm": (16.0, 5e-4)}


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", type=Path, default=Path("/tmp/bench_identification_lowspeed"))
    p.add_argument("--seed", type=int, default=7)
    a = p.parse_args()
    sp = reference_spindle()
    model = sp.model(sp.baseline)
    truth = reference_truth()
    print(f"load average {os.getloadavg()[0]:.1f}")
    print("| case | speed (rpm) | used / runs | k RMS error front | rear |\n|---|---|---|---|---|")
    for label, (dur, U) in CASES.items():
        path = a.out / label.replace(" ", "").replace(",", "_")
        t = time.perf_counter()
        if not (path / "summary.json").is_file():
            run_campaign(truth, CampaignOptions(speeds_rpm=SPEEDS, repeats=4, duration_s=dur,
                                                runup=None, impacts_per_direction=0,
                                                trial_unbalance=(0.0, U, 0.0)),
                         path, rng=np.random.default_rng(a.seed))
        resp = read_responses(path, IdentificationOptions())
        s = resp.speed_rpm
        unb = [(node_at(model, pos), U * np.exp(1j * np.radians(ph)))
               for pos, U, ph in resp.unbalance]
        cr = condense_reactions(model, np.unique(s), unbalance=unb, probe_nodes=[
            node_at(model, float(x)) for x in resp.positions_mm[::2]])
        res = identify_phasors(cr, resp.phasors, s, phasor_sd=resp.phasor_sd,
                               catalog=catalog_coefficients(model, s), max_rel_se=0.2,
                               perturbations=resp.perturbations)
        ok = res.usable([0, 1, 4, 5])
        ds = open_dataset(path / "dataset")
        prov = {r["id"]: ds.load(r).provenance for r in ds.index}
        ids = [i.split("|")[1] for i in resp.record_ids]
        err = res.estimate / truth_coefficients(truth, [prov[i] for i in ids], s) - 1
        for v in SPEEDS:
            g = s == v
            used = ok[g]
            e = err[g & ok] if used.any() else np.full((1, 8), np.nan)
            rms = np.sqrt(np.mean(e**2, axis=0))
            print(f"| {label} | {v:.0f} | {int(used.sum())} / {int(g.sum())} | "
                  f"{max(rms[0], rms[1]):.2%} | {max(rms[4], rms[5]):.2%} |")
        print(f"  ({label}: simulated and identified in {time.perf_counter() - t:.1f} s)")


if __name__ == "__main__":
    main()
