"""The ``rbrdo`` command line.

``rbrdo run EXPERIMENT.toml`` runs an experiment into ``results/<experiment>/<run-id>/``;
``rbrdo kinds`` describes the experiment kinds; ``rbrdo --version``. A bad config (or folder)
gives one line and exit code 2 and leaves nothing behind; an error during the work one line and
exit code 1 (the run is marked ``failed``, the traceback is in its ``meta.json``); Ctrl-C one
line and 130; SIGTERM one line and 143 (the run is marked ``interrupted`` and worker processes
are stopped). Progress bars are drawn only on a terminal.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import secrets
import sys
import time
from collections.abc import Sequence
from typing import Any, NoReturn

# one BLAS thread: the hot paths are many small solves, where threads only add overhead
for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

from surrogate_rbrdo import __version__  # noqa: E402 - after the BLAS pinning
from surrogate_rbrdo.core.schema import table_defaults  # noqa: E402
from surrogate_rbrdo.runner.execute import RunFailed, Terminated, run_experiment  # noqa: E402
from surrogate_rbrdo.runner.kinds import discover  # noqa: E402
from surrogate_rbrdo.runner.runfolder import AlreadyComplete  # noqa: E402
from surrogate_rbrdo.runner.signals import handled_signals  # noqa: E402

MAX_ROWS = 12


#: the tables that say which problem is solved (their defaults are printed by ``rbrdo kinds``)
PROBLEM_TABLES = ("spindle", "uncertainty", "response", "limit", "deterministic")


def describe_kinds() -> str:
    """One paragraph per kind: name, what it does, its tables and stages, and the problem a
    left-out problem table means."""
    out = []
    for name, kind in sorted(discover().items()):
        tables = ", ".join(f"[{t}]" for t in kind.schema.__dataclass_fields__)
        stages = " → ".join(s.name for s in kind.stages) or "(report only)"
        text = (f"{name}\n  {kind.summary}\n  tables: [experiment], {tables}\n"
                f"  stages: {stages} → report")
        defaults = table_defaults(kind.schema, PROBLEM_TABLES)
        if defaults:
            text += f"\n  a left-out table means: {defaults}"
        if kind.defaults:
            text += f"\n  {kind.defaults}"
        out.append(text)
    return "\n\n".join(out)


class _Parser(argparse.ArgumentParser):
    """Command-line errors in one line (``rbrdo: error: ...``), exit code 2, like a bad
    config (argparse would print the usage first)."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"rbrdo: error: {message} (see {self.prog} --help)\n")


def _parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="rbrdo",
        description="Reliability-based robust design optimisation of spindle-bearing systems.")
    parser.add_argument("--version", action="version", version=f"rbrdo {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    p_run = sub.add_parser("run", help="run an experiment config (experiments/*.toml)")
    p_run.add_argument("config", help="path to the experiment TOML file")
    p_run.add_argument("--results", default=None,
                       help="results root (default: [experiment] results_dir, or results/)")
    p_run.add_argument("--run-id", default=None, help="run folder name (default: timestamp)")
    p_run.add_argument("--no-progress", action="store_true", help="hide progress bars")
    p_run.add_argument("--seed", type=int, nargs="+", default=None,
                       help="replace [experiment] seed (recorded in config.json and meta.json); "
                            "several seeds run one after another into <run-id>-seed<N>")
    how = p_run.add_mutually_exclusive_group()
    how.add_argument("--resume", action="store_true",
                     help="continue an unfinished run (needs --run-id): finished stages and "
                          "cached FE points are not recomputed")
    how.add_argument("--overwrite", action="store_true",
                     help="replace the run folder of --run-id if it exists (the old run is "
                          "deleted when the new one completes)")
    p_run.add_argument("--accept-changes", action="store_true",
                       help="with --resume: continue although an input file, the code or a "
                            "package version changed since the run started")
    sub.add_parser("kinds", help="describe the experiment kinds")
    return parser


def _run(args: argparse.Namespace) -> int:
    seeds = [None] if args.seed is None else list(args.seed)
    if len(set(seeds)) != len(seeds):
        raise ValueError(f"--seed {' '.join(map(str, seeds))} is not allowed: a seed "
                         "appears twice")
    if args.resume and args.run_id is None:
        raise ValueError("--resume is not allowed without --run-id: name the run to continue")
    base = args.run_id or (time.strftime("%Y%m%dT%H%M%SZ", time.gmtime())
                           + f"-{secrets.token_hex(3)}")
    progress = not args.no_progress and sys.stderr.isatty()
    for s in seeds:
        rid = args.run_id if len(seeds) == 1 else f"{base}-seed{s}"
        try:
            run = run_experiment(args.config, results_dir=args.results, run_id=rid,
                                 progress=progress, seed=s, resume=args.resume,
                                 overwrite=args.overwrite,
                                 accept_changes=args.accept_changes)
        except AlreadyComplete as exc:
            print(f"rbrdo: {exc}")
            continue
        _report(run.path)
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    try:
        if args.command == "kinds":
            print(describe_kinds())
            return 0
        with handled_signals():
            return _run(args)
    except ValueError as exc:
        print(f"rbrdo: error: {exc}", file=sys.stderr)
        return 2
    except RunFailed as exc:
        print(f"rbrdo: run failed in {exc.stage!r}: {_one_line(str(exc))}; {exc.run.path} is "
              "marked 'failed' (traceback in its meta.json)", file=sys.stderr)
        return 1
    except (KeyboardInterrupt, Terminated) as exc:
        what = "interrupted (Ctrl-C)" if isinstance(exc, KeyboardInterrupt) else \
            "terminated (SIGTERM)"
        run = getattr(exc, "run", None)
        where = "" if run is None else (
            f"; {run.path} is marked 'interrupted': continue it with "
            f"rbrdo run {args.config} --resume --run-id {run.run_id}"
            + (f" --results {args.results}" if args.results else ""))
        print(f"rbrdo: {what}{where}", file=sys.stderr)
        return 130 if isinstance(exc, KeyboardInterrupt) else 143


def _one_line(text: str, limit: int = 300) -> str:
    line = " ".join(text.split())
    return line if len(line) <= limit else line[:limit - 3] + "..."


def _report(path: Any) -> None:
    summary = json.loads((path / "summary.json").read_text())
    print(f"results written to {path}")
    rows = summary.get("summary", [])
    for row in rows[:MAX_ROWS]:    # a NaN column (no such value in this run) is not shown
        print("  " + ", ".join(f"{k}={v}" for k, v in row.items()
                               if not (isinstance(v, float) and math.isnan(v))))
    if len(rows) > MAX_ROWS:
        print(f"  ... first {MAX_ROWS} of {len(rows)} rows shown; all in {path / 'summary.json'}")


if __name__ == "__main__":
    raise SystemExit(main())
