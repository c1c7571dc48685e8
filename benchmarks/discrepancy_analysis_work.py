"""What the shipped run's analysis (``discrepancy.workflow.find_discrepancy``) costs, in CPU
and in work that does not depend on the machine's load: residual rows evaluated
(``Problem.evaluate``) and distinct physical rows the forward model solved
(``ForwardModel.responses``), on the 1x-only problems of the continuation and on all the data.

    PYTHONPATH=$PWD python3 benchmarks/discrepancy_analysis_work.py --out /tmp/<you>/work \
        [--config experiments/discrepancy.toml]

The rig campaign is simulated once into ``--out`` (the runner resumes it there), then the
analysis runs in this process with both methods wrapped by counters. Run it on two commits
with the same ``--out`` to compare them: the counts are exact, the CPU is inflated by other
jobs on the machine (the load average is printed). No timed asserts: it prints.
"""

from __future__ import annotations

import argparse
import collections
import dataclasses
import functools
import os
import resource
import time
from pathlib import Path

import numpy as np

from surrogate_rbrdo.discrepancy.experiment import data_from_folder
from surrogate_rbrdo.discrepancy.forward import ForwardModel
from surrogate_rbrdo.discrepancy.problem import Problem
from surrogate_rbrdo.discrepancy.workflow import find_discrepancy
from surrogate_rbrdo.runner.execute import prepare
from surrogate_rbrdo.runner.experiments import discrepancy as kind
from surrogate_rbrdo.runner.kinds import StageContext

COUNTS: dict[str, collections.Counter] = {"evaluated": collections.Counter(),
                                          "solved": collections.Counter()}


def _counted(method, what: str, rows, part):
    """``method`` wrapped to add its rows to ``COUNTS[what][part(...)]``."""
    @functools.wraps(method)
    def wrapper(self, *args, **kwargs):
        COUNTS[what][part(self, *args)] += rows(*args)
        return method(self, *args, **kwargs)
    return wrapper


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--config", default="experiments/discrepancy.toml")
    ap.add_argument("--out", required=True)
    args = ap.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    prep = prepare(args.config)
    p = prep.plan
    ctx = StageContext(seed=prep.experiment.seed, progress=False, label="bench",
                       cache_dir=out / "_fe_cache", run_dir=out)
    src = kind._campaign(p, {}, ctx)                 # resumed: done once per --out
    folder = src if isinstance(src, Path) else src.root
    data = data_from_folder(folder, impacts=p.options.use_impacts)
    Problem.evaluate = _counted(Problem.evaluate, "evaluated",
                                lambda par, X: np.atleast_2d(X).shape[0],
                                lambda self, *a: "1x" if {b.sweep.kind for b in self.blocks}
                                == {"unbalance_1x"} else "all")
    ForwardModel.responses = _counted(ForwardModel.responses, "solved",
                                      lambda sweeps, theta, *a: np.atleast_2d(theta[0]).shape[0],
                                      lambda self, sweeps, *a: "1x" if {s.kind for s in sweeps}
                                      == {"unbalance_1x"} else "all")
    load0 = os.getloadavg()
    c0 = time.process_time()
    sp = p.spindle
    # one process: the counters and the CPU timer see no worker ([discrepancy] n_jobs = 1)
    res = find_discrepancy(data, sp.geometry_for(sp.baseline), sp.effects,
                           options=dataclasses.replace(p.options, n_jobs=1),
                           rng=ctx.stream(1))
    cpu = time.process_time() - c0
    print(f"{res.verdict} {[a.name for a in res.effects]}; "
          f"{[(n, e.parameters) for n, e in res.fitted_effects]}")
    print(f"analysis CPU {cpu:.1f} s (load average {load0} -> {os.getloadavg()})")
    for what, c in COUNTS.items():
        print(f"rows {what:9s}: 1x-only problems {c['1x']:7d}, all the data {c['all']:7d}")
    print(f"peak RSS {resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024:.0f} MB")


if __name__ == "__main__":
    main()
