"""The discrepancy workflow on effects of a physically typical size (not calibrated by z).

The blind grid (``discrepancy_blind.py``) hides effects at a signal-to-noise level; on the rig's
data those are physically tiny (a 0.3 % softening). A user's spindle has effects of the size
the literature reports. Each library effect is hidden alone at such a size on the virtual rig
(with the impact plan unless ``--impacts none``), and the workflow's verdict, names, fitted
parameters and final goodness of fit are printed next to the truth:

    PYTHONPATH=$PWD python3 benchmarks/discrepancy_physical.py --seeds 1 --noise default

Sizes (``SIZES``; the knob of :data:`~surrogate_rbrdo.discrepancy.blind.HIDDEN`, its other
parameters as there):

* speed softening ``a = 0.2``, exponent 2, both bearings: a 20 % loss of bearing stiffness at
  24 000 rpm — the order of the centrifugal/gyroscopic stiffness loss of angular-contact
  spindle bearings at high DmN (Jorgensen & Shin 1998, *J. Tribol.* 120:280; Cao & Altintas
  2004, *J. Manuf. Sci. Eng.* 126:443);
* thermal preload ``b = 0.5``, ``q = 2``: a 50 % preload growth at top speed under
  fixed-position preload (tens of percent to a doubling: Li & Shin 2004, *J. Manuf. Sci. Eng.*
  126:148);
* housing stage ``k = 6e8 N/m``, ``m = 20 kg``: the shipped ``experiments/discrepancy.toml``;
* tool interface ``k_t = 3e8 N/m``, ``k_r = 5e6 N m/rad``: the example of ``docs/rig.md``;
* anisotropy ``s = 0.1`` (a 10 % x/y support asymmetry) and cross-coupling ``κ = 0.05``:
  assumed sizes, no source;
* gyroscopics ``g = 0.5`` and ``g = 1`` (the end of its range: the gyroscopic coupling doubled).

Prints one line per scenario and the count of correct names; CPU per scenario (measured under
whatever load the machine has: the load average is printed).
"""

from __future__ import annotations

import argparse
import csv
import os

import numpy as np

from surrogate_rbrdo.discrepancy.blind import HIDDEN, Scenario, rig_context, run_scenario
from surrogate_rbrdo.discrepancy.rig_source import FACTORS

#: (effect, knob value) pairs: module doc
SIZES = (("speed_softening", 0.2), ("thermal_preload", 0.5), ("housing", 6e8),
         ("tool_interface", 3e8), ("anisotropy", 0.1), ("cross_coupling", 0.05),
         ("gyroscopics", 0.5), ("gyroscopics", 1.0))


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seeds", type=int, default=1)
    ap.add_argument("--noise", nargs="+", default=["default"], choices=list(FACTORS))
    ap.add_argument("--impacts", choices=("plan", "none"), default="plan")
    ap.add_argument("--effects", nargs="+", default=[], help="only these effects")
    ap.add_argument("--base-seed", type=int, default=0)
    ap.add_argument("--draws", type=int, default=400)
    ap.add_argument("--out", default="")
    args = ap.parse_args()
    ctx = rig_context(impacts=args.impacts == "plan", n_draws=args.draws)
    ss = np.random.SeedSequence(args.base_seed)
    sizes = [(n, v) for n, v in SIZES if not args.effects or n in args.effects]
    rows = []
    for nz in args.noise:
        for n, v in sizes:
            for _ in range(args.seeds):
                seed = int(ss.spawn(1)[0].generate_state(1)[0])
                row = run_scenario(ctx, Scenario(f"single: {n}", "physical",
                                                 ((HIDDEN[n], v),), nz, seed))
                rows.append(row)
                print(f"{n:16s} {v:<8.3g} {nz:8s} {seed:>10d}  {row['verdict']:17s} "
                      f"{row['names'] or '-':28s} {row['outcome']:18s} gof p "
                      f"{float(row['gof_p']):.3f}  CPU {row['cpu_seconds']:.1f} s  "
                      f"{row['parameters']}", flush=True)
    good = sum(r["outcome"] in ("correct_name", "correct_confounded") for r in rows)
    wrong = sum(r["outcome"] == "wrong_name" for r in rows)
    print(f"\nname or correct set: {good}/{len(rows)}; wrong names {wrong}/{len(rows)}; "
          f"load average {os.getloadavg()}")
    if args.out:
        with open(args.out, "w", newline="") as fh:
            w = csv.DictWriter(fh, fieldnames=list(rows[0]))
            w.writeheader()
            w.writerows(rows)


if __name__ == "__main__":
    main()
