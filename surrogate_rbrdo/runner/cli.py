"""The ``rbrdo`` command line.

``rbrdo run EXPERIMENT.toml`` runs an experiment into ``results/<experiment>/<run-id>/``;
``rbrdo kinds`` lists the experiment kinds. Bad input gives a one-line error and exit code 2.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from collections.abc import Sequence
from pathlib import Path

# one BLAS thread: the hot paths are many small solves, where threads only add overhead
for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")


def _kinds():
    from surrogate_rbrdo.runner import spindle_report  # noqa: F401  (registers its kind)
    from surrogate_rbrdo.runner.experiments import EXPERIMENTS

    for mod in ("surrogate_rbrdo.runner.surrogate_validation", "surrogate_rbrdo.runner.study"):
        try:
            __import__(mod)
        except ModuleNotFoundError as exc:
            if exc.name != mod:
                raise
    return EXPERIMENTS


def run_experiment(config_path: str | Path, *, results_dir: str | Path | None = None,
                   run_id: str | None = None, progress: bool = True, seed: int | None = None):
    """Run one experiment config; returns the run folder.

    ``seed`` replaces ``[experiment] seed`` (a seed sweep without copies of the config); the
    run folder's ``config.json`` and ``meta.json`` record the seed used, ``config.toml`` is the
    file as given.
    """
    from surrogate_rbrdo.core.validate import check_int
    from surrogate_rbrdo.runner.config import load_config
    from surrogate_rbrdo.runner.runfolder import RunFolder

    cfg = load_config(config_path)
    exp = cfg["experiment"]
    if seed is not None:
        exp["seed"] = check_int("--seed", seed, minimum=0)
    kind = _kinds().get(exp["kind"])  # unknown kind -> ValueError listing the known ones
    root = results_dir or exp.get("results_dir", "results")
    run = RunFolder.create(root, exp["name"], run_id)
    resolved = {k: v for k, v in cfg.items() if not k.startswith("_")}
    run.write_json("config.json", resolved)
    try:
        import shutil

        shutil.copyfile(config_path, run.file("config.toml"))
    except OSError:
        pass
    summary = kind(cfg, run, progress=progress)
    run.write_json("summary.json", summary)
    extra = summary.get("meta") if isinstance(summary, dict) else None
    run.write_meta(seeds={"seed": exp.get("seed")}, extra=extra)  # kinds may add to meta.json
    return run


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="rbrdo",
        description="Reliability-based robust design optimisation of spindle-bearing systems.",
    )
    sub = parser.add_subparsers(dest="command", required=True)
    p_run = sub.add_parser("run", help="run an experiment config (experiments/*.toml)")
    p_run.add_argument("config", help="path to the experiment TOML file")
    p_run.add_argument("--results", default=None, help="results root (default: results/)")
    p_run.add_argument("--run-id", default=None, help="run folder name (default: timestamp)")
    p_run.add_argument("--no-progress", action="store_true", help="hide progress bars")
    p_run.add_argument("--seed", type=int, nargs="+", default=None,
                       help="replace [experiment] seed (recorded in config.json and meta.json); "
                            "several seeds run one after another into <run-id>-seed<N>")
    sub.add_parser("kinds", help="list the experiment kinds")
    args = parser.parse_args(argv)
    try:
        if args.command == "kinds":
            for name in sorted(_kinds()):
                print(name)
            return 0
        seeds = [None] if args.seed is None else list(args.seed)
        if len(set(seeds)) != len(seeds):
            raise ValueError(f"--seed {' '.join(map(str, seeds))} is not allowed: a seed "
                             "appears twice")
        base = args.run_id or time.strftime("%Y%m%dT%H%M%SZ", time.gmtime())
        for s in seeds:
            rid = args.run_id if len(seeds) == 1 else f"{base}-seed{s}"
            run = run_experiment(args.config, results_dir=args.results, run_id=rid,
                                 progress=not args.no_progress, seed=s)
            _report(run)
    except ValueError as exc:
        print(f"rbrdo: error: {exc}", file=sys.stderr)
        return 2
    return 0


def _report(run) -> None:
    summary = json.loads((run.path / "summary.json").read_text())
    print(f"results written to {run.path}")
    if "summary" in summary:
        for row in summary["summary"][:12]:
            print("  " + ", ".join(f"{k}={v}" for k, v in row.items()))


if __name__ == "__main__":
    raise SystemExit(main())
