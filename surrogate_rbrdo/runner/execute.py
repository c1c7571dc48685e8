"""Run one experiment config: validate everything, then run the kind's stages in a run folder.

Order: read the TOML → ``[experiment]`` → the kind's schema (every table and key) → the kind's
``build`` (files, spindle, memory) — any ``ValueError`` so far leaves no folder — → open the
run folder (new, ``resume`` or ``overwrite``) → the stages (a finished stage's pickled result
is loaded instead of recomputed) → the report → ``status = "complete"``. An exception marks
the run ``failed``; Ctrl-C or SIGTERM mark it ``interrupted``.
"""

from __future__ import annotations

import json
import time
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Any

from surrogate_rbrdo.core.validate import check_int
from surrogate_rbrdo.runner.kinds import Kind, StageContext, discover
from surrogate_rbrdo.runner.runfolder import RunFolder, json_default
from surrogate_rbrdo.runner.schema import load_toml, parse
from surrogate_rbrdo.runner.tables import ExperimentTable, require_disk


class Terminated(BaseException):  # noqa: N818 - a signal, like KeyboardInterrupt
    """Raised in the main thread when the process receives SIGTERM."""


@dataclass(frozen=True)
class Prepared:
    """A validated config: the ``[experiment]`` table, its kind, the typed tables, the plan."""

    path: Path
    experiment: ExperimentTable
    kind: Kind
    config: Any
    plan: Any

    def resolved(self) -> dict[str, Any]:
        """The config with every default filled in (``config.json``)."""
        return {"experiment": asdict(self.experiment), **asdict(self.config)}


def prepare(config_path: str | Path, *, seed: int | None = None) -> Prepared:
    """Read and validate ``config_path`` (no work, no folder); ``seed`` replaces
    ``[experiment] seed``."""
    path = Path(config_path)
    raw = load_toml(path)
    if not isinstance(raw.get("experiment"), dict):
        raise ValueError(f"config {str(path)!r}: missing [experiment] table with name and kind")
    tables = dict(raw)
    exp = parse(ExperimentTable, tables.pop("experiment"), "experiment")
    if seed is not None:
        exp = replace(exp, seed=check_int("--seed", seed, minimum=0))
    kinds = discover()
    if exp.kind not in set(kinds):   # Registry.__contains__ raises for unknown names
        raise ValueError(f"experiment.kind = {exp.kind!r} is not allowed: unknown experiment "
                         f"kind; known: {', '.join(sorted(kinds))}")
    kind = kinds[exp.kind]
    config = parse(kind.schema, tables, "")
    plan = kind.build(config, path.parent.resolve())
    return Prepared(path, exp, kind, config, plan)


def _first_difference(a: Any, b: Any, where: str = "") -> str:
    if isinstance(a, dict) and isinstance(b, dict):
        for k in sorted(set(a) | set(b)):
            if a.get(k) != b.get(k):
                return _first_difference(a.get(k), b.get(k), f"{where}.{k}" if where else k)
    return f"{where}: {a!r} then, {b!r} now"


def _open(prep: Prepared, results_dir: str | Path | None, run_id: str | None, *,
          resume: bool, overwrite: bool) -> RunFolder:
    root = Path(results_dir) if results_dir is not None else Path(prep.experiment.results_dir)
    run = RunFolder.open(root, prep.experiment.name, run_id, resume=resume, overwrite=overwrite)
    resolved = json.loads(json.dumps(prep.resolved(), default=json_default))
    if resume:
        try:
            old = json.loads(run.file("config.json").read_text())
        except (OSError, ValueError):
            old = None
        if old != resolved:
            diff = "no config.json" if old is None else _first_difference(old, resolved)
            raise ValueError(f"--resume: the config differs from the one {str(run.path)!r} "
                             f"started with ({diff}): run it under another --run-id")
    else:
        run.write_json("config.json", resolved)
        run.write_bytes("config.toml", prep.path.read_bytes())
    return run


def _stages(prep: Prepared, run: RunFolder, ctx: StageContext) -> dict[str, Any]:
    done: dict[str, Any] = {}
    for i, stage in enumerate(prep.kind.stages):
        if run.has_stage(i, stage.name):
            done[stage.name] = run.load_stage(i, stage.name)
            continue
        t0 = time.perf_counter()
        result = stage.func(prep.plan, dict(done), ctx)
        run.save_stage(i, stage.name, result, time.perf_counter() - t0)
        done[stage.name] = result
    return done


def run_experiment(config_path: str | Path, *, results_dir: str | Path | None = None,
                   run_id: str | None = None, progress: bool = True, seed: int | None = None,
                   resume: bool = False, overwrite: bool = False) -> RunFolder:
    """Run one experiment config into ``<results>/<experiment>/<run-id>/``; returns the run
    folder.

    ``seed`` replaces ``[experiment] seed`` (recorded in ``config.json`` and ``meta.json``;
    ``config.toml`` is the file as given). ``resume`` continues an unfinished run of the same
    config (finished stages are loaded, cached FE points are not recomputed); ``overwrite``
    replaces an existing run. Raises ``ValueError`` (bad config or folder, nothing written)
    or :class:`~surrogate_rbrdo.runner.runfolder.AlreadyComplete`.
    """
    prep = prepare(config_path, seed=seed)
    need = getattr(prep.plan, "disk_need", None)     # (field, value, bytes, what)
    if need is not None and not resume:
        require_disk(*need, Path(results_dir or prep.experiment.results_dir))
    run = _open(prep, results_dir, run_id, resume=resume, overwrite=overwrite)
    run.start(kind=prep.kind.name, seeds={"seed": prep.experiment.seed})
    ctx = StageContext(seed=prep.experiment.seed, progress=progress,
                       label=f"{prep.experiment.name}/{run.run_id}",
                       cache_dir=run.path.parent / "_fe_cache", run_dir=run.path)
    try:
        done = _stages(prep, run, ctx)
        t0 = time.perf_counter()
        summary = dict(prep.kind.report(prep.plan, dict(done), run, ctx))
        run.timings["report"] = time.perf_counter() - t0
        run.write_json("summary.json", summary)
        run.stop("complete", **dict(summary.get("meta", {})))
    except (KeyboardInterrupt, Terminated) as exc:
        run.stop("interrupted", signal="SIGINT" if isinstance(exc, KeyboardInterrupt)
                 else "SIGTERM")
        exc.run = run   # the CLI names the folder to resume
        raise
    except BaseException as exc:
        run.stop("failed", error=f"{type(exc).__name__}: {exc}")
        raise
    return run


__all__ = ["Prepared", "Terminated", "prepare", "run_experiment"]
