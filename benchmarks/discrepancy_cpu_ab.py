"""CPU of the discrepancy workflow on fixed blind scenarios, two code trees back to back.

    PYTHONPATH=$PWD python3 benchmarks/discrepancy_cpu_ab.py OLD_TREE NEW_TREE [--repeats 2]

Each scenario (the rig's data of a hidden effect at a physical size, default noise, the impact
plan: what ``discrepancy_one_effect.py`` runs) is run by ``find_discrepancy`` in a fresh
interpreter on each tree (``PYTHONPATH=<tree>``), the trees alternating, so both see the same
machine load; per run the workflow's CPU (``time.process_time`` around ``find_discrepancy``,
the data's simulation excluded), the verdict and the names are printed, then per tree the
total and the ratio, with the load average before and after. Example: ``OLD_TREE`` a
``git archive`` of main, ``NEW_TREE`` the working tree.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys

#: (hidden effect or "none", knob, seed): strong and weak effects and nothing hidden
SCENARIOS = (("thermal_preload", 0.05, 12), ("anisotropy", 0.02, 12), ("none", 0.0, 12),
             ("housing", 6e8, 3))

CHILD = """
import sys, time
import numpy as np
from surrogate_rbrdo.discrepancy.blind import HIDDEN, rig_context
from surrogate_rbrdo.discrepancy.workflow import find_discrepancy
name, knob, seed = sys.argv[1], float(sys.argv[2]), int(sys.argv[3])
ctx = rig_context(impacts=True, n_draws=400)
eff = () if name == "none" else ((HIDDEN[name], knob),)
data = ctx.source.measure(*ctx.truth(eff), "default", seed)
c0 = time.process_time()
res = find_discrepancy(data, ctx.geometry, ctx.effects, options=ctx.options,
                       rng=np.random.default_rng([seed, 7]))
print(time.process_time() - c0, res.verdict, ",".join(a.name for a in res.effects),
      res.test.get("statistic") if isinstance(res.test, dict) else "")
"""


def run(tree: str, name: str, knob: float, seed: int) -> tuple[float, str]:
    """One scenario on one tree: (workflow CPU in s, verdict and names)."""
    env = dict(os.environ, PYTHONPATH=tree, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1",
               MKL_NUM_THREADS="1")
    out = subprocess.run([sys.executable, "-c", CHILD, name, str(knob), str(seed)], env=env,
                         capture_output=True, text=True, check=True).stdout.split()
    return float(out[0]), " ".join(out[1:])


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("old")
    ap.add_argument("new")
    ap.add_argument("--repeats", type=int, default=2)
    args = ap.parse_args()
    if args.repeats < 1:
        ap.error(f"--repeats = {args.repeats} is not allowed: must be at least 1")
    print("load average before", os.getloadavg())
    total = {"old": 0.0, "new": 0.0}
    for name, knob, seed in SCENARIOS:
        for k in range(args.repeats):
            for lab, tree in (("old", args.old), ("new", args.new)):
                cpu, ans = run(tree, name, knob, seed)
                total[lab] += cpu
                print(f"{name:16s} {knob:<8g} seed {seed:3d} rep {k}  {lab}  {cpu:6.2f} s  {ans}",
                      flush=True)
    n = len(SCENARIOS) * args.repeats
    print(f"mean workflow CPU per run: old {total['old'] / n:.2f} s, new {total['new'] / n:.2f} s,"
          f" new/old {total['new'] / total['old']:.3f}")
    print("load average after", os.getloadavg())


if __name__ == "__main__":
    main()
