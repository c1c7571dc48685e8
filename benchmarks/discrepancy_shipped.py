"""What the shipped discrepancy run costs, phase by phase: the runner's own stages of
``rbrdo run experiments/discrepancy.toml`` (campaign, analysis, tables, figures) called one
after the other in this process, each timed in CPU (this process's ``time.process_time`` plus
the joblib workers', read from ``resource.getrusage(RUSAGE_CHILDREN)`` after they are shut
down) and wall seconds; then the total CPU, wall and peak RSS (this process's and the
workers'), and the machine's load average (other jobs inflate the wall times, not the CPU).

    PYTHONPATH=$PWD python3 benchmarks/discrepancy_shipped.py --out /tmp/<you>/shipped \
        [--config experiments/discrepancy.toml] [--n-jobs N]

``--n-jobs`` replaces ``[discrepancy] n_jobs`` (the config's by default): the worker processes
of the candidate fits and the figures (``[rig] n_jobs``, the steady runs', stays the config's).
The run folder under
``--out`` holds what the runner writes (campaign/, findings.json, tables, figures/), so
``diff`` against a ``rbrdo run`` folder checks the answers. No timed asserts: it prints.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import resource
import time
from pathlib import Path

from joblib.externals.loky import get_reusable_executor

from surrogate_rbrdo.discrepancy.report import write_run
from surrogate_rbrdo.reporting.plots_discrepancy import plot_all, verdict_line
from surrogate_rbrdo.runner.execute import prepare
from surrogate_rbrdo.runner.experiments import discrepancy as kind
from surrogate_rbrdo.runner.kinds import StageContext


def _children_cpu() -> float:
    """CPU seconds of the finished (waited-for) child processes: the joblib workers once
    their executor is shut down."""
    get_reusable_executor().shutdown(wait=True)
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--config", default="experiments/discrepancy.toml")
    ap.add_argument("--out", required=True)
    ap.add_argument("--n-jobs", type=int, default=None)
    args = ap.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    print(f"load average at start {os.getloadavg()}")
    prep = prepare(args.config)
    p = prep.plan
    if args.n_jobs is not None:
        p = dataclasses.replace(p, options=dataclasses.replace(p.options, n_jobs=args.n_jobs))
    ctx = StageContext(seed=prep.experiment.seed, progress=False, label="bench",
                       cache_dir=out / "_fe_cache", run_dir=out)
    done: dict = {}
    rows = []

    def phase(name, func):
        c0, k0, w0 = time.process_time(), _children_cpu(), time.perf_counter()
        value = func()
        cpu = time.process_time() - c0 + _children_cpu() - k0
        rows.append((name, cpu, time.perf_counter() - w0))
        return value

    w_all = time.perf_counter()
    done["campaign"] = phase("campaign", lambda: kind._campaign(p, done, ctx))
    res = done["analyse"] = phase("analysis", lambda: kind.analyse(p, done, ctx))
    phase("tables", lambda: write_run(res, out, spindle_section=p.spindle_section,
                                      model_effects=p.spindle.effects))
    figs = phase("figures", lambda: plot_all(res, _mkdir(out / "figures"),
                                             n_jobs=p.options.n_jobs))
    wall = time.perf_counter() - w_all
    print(verdict_line(res))
    print(f"{len(figs)} figures; discrepancy n_jobs = {p.options.n_jobs} (the figures' too), "
          f"rig n_jobs = {p.rig.rig.n_jobs if p.rig is not None else '-'}")
    print(f"{'phase':<10} {'CPU s':>8} {'wall s':>8}")
    for name, cpu, w in rows:
        print(f"{name:<10} {cpu:8.2f} {w:8.2f}")
    me = resource.getrusage(resource.RUSAGE_SELF)
    kids = resource.getrusage(resource.RUSAGE_CHILDREN)
    print(f"{'total':<10} {sum(r[1] for r in rows):8.2f} {wall:8.2f}   (CPU of this process "
          f"{me.ru_utime + me.ru_stime:.2f} s with imports and set-up, workers "
          f"{kids.ru_utime + kids.ru_stime:.2f} s)")
    print(f"peak RSS {me.ru_maxrss / 1024:.0f} MB (workers {kids.ru_maxrss / 1024:.0f} MB); "
          f"load average at end {os.getloadavg()}")


def _mkdir(path: Path) -> Path:
    path.mkdir(exist_ok=True)
    return path


if __name__ == "__main__":
    main()
