"""Run one experiment config: validate everything, then run the kind's stages in a run folder.

Order: read the TOML → ``[experiment]`` → the kind's schema (every table and key) → the kind's
``build`` (files, spindle) → the memory of every table with ``memory_bytes`` — any
``ValueError`` so far is a *config error* and leaves no folder — → open the run folder (new,
``resume`` or ``overwrite``) → the stages (a finished stage's pickled result is loaded instead
of recomputed) → the report → ``status = "complete"``. An exception during the work marks the
run ``failed`` and is raised as :class:`RunFailed`; Ctrl-C or SIGTERM mark it ``interrupted``.

Files the config refers to (a geometry file, …) are read through
:func:`~surrogate_rbrdo.core.files.read_input` while the config is prepared, so their SHA-256
is recorded (``meta.json`` ``inputs``); ``--resume`` refuses when one of them, the code or a
package version changed since the run started (``accept_changes`` resumes anyway).
"""

from __future__ import annotations

import json
import time
import traceback
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Any

from surrogate_rbrdo.core.files import json_default, require_disk, share_tree, tracked_inputs
from surrogate_rbrdo.core.memory import check_memory, table_needs
from surrogate_rbrdo.core.provenance import changes_since, first_difference
from surrogate_rbrdo.core.schema import load_toml, parse
from surrogate_rbrdo.core.validate import check_int
from surrogate_rbrdo.runner.kinds import Kind, StageContext, discover
from surrogate_rbrdo.runner.runfolder import RunFolder, check_name, check_root


class Terminated(BaseException):  # noqa: N818 - a signal, like KeyboardInterrupt
    """Raised in the main thread when the process receives SIGTERM."""


class RunFailed(Exception):
    """An error during the work of an accepted config; the run folder is marked ``failed``
    (``meta.json``: ``error``, ``failed_in``, ``traceback``). The cause is ``__cause__``."""

    def __init__(self, run: RunFolder, stage: str, error: BaseException) -> None:
        self.run, self.stage, self.error = run, stage, error
        super().__init__(f"{type(error).__name__}: {error}")


@dataclass(frozen=True)
class ExperimentTable:
    """``[experiment]``: ``name`` (the results sub-folder), ``kind``, ``seed``,
    ``results_dir`` (the results root, relative to the config file; default ``results`` in
    the working directory), ``description``."""

    name: str
    kind: str
    seed: int = 0
    results_dir: str | None = None
    description: str = ""

    def __post_init__(self) -> None:
        check_name("name", self.name)
        check_int("seed", self.seed, minimum=0)
        if self.results_dir is not None and not self.results_dir.strip():
            raise ValueError(f"results_dir = {self.results_dir!r} is not allowed: give a folder")


@dataclass(frozen=True)
class Prepared:
    """A validated config: the ``[experiment]`` table, its kind, the typed tables, the plan,
    the input files it read (absolute path → SHA-256)."""

    path: Path
    experiment: ExperimentTable
    kind: Kind
    config: Any
    plan: Any
    inputs: dict[str, str]

    def resolved(self) -> dict[str, Any]:
        """The config with every default filled in (``config.json``)."""
        return {"experiment": asdict(self.experiment), **asdict(self.config)}

    def results_root(self, results_dir: str | Path | None) -> Path:
        """``results_dir`` (relative to the working directory), else ``[experiment]
        results_dir`` (relative to the config file, like every path in it), else
        ``results``."""
        if results_dir is not None:
            return check_root(results_dir)
        given = self.experiment.results_dir
        if given is None:
            return check_root("results")
        return check_root(self.path.parent / given, "experiment.results_dir")


def prepare(config_path: str | Path, *, seed: int | None = None) -> Prepared:
    """Read and validate ``config_path`` (no work, no folder); ``seed`` replaces
    ``[experiment] seed``."""
    path = Path(config_path)
    with tracked_inputs() as seen:
        raw = load_toml(path)
        seen.clear()                      # the config itself is compared as config.json
        if not isinstance(raw.get("experiment"), dict):
            raise ValueError(f"config {str(path)!r}: missing [experiment] table with name and "
                             "kind")
        tables = dict(raw)
        exp = parse(ExperimentTable, tables.pop("experiment"), "experiment")
        if seed is not None:
            exp = replace(exp, seed=check_int("--seed", seed, minimum=0))
        kinds = discover()
        if exp.kind not in set(kinds):   # Registry.__contains__ raises for unknown names
            raise ValueError(f"experiment.kind = {exp.kind!r} is not allowed: unknown "
                             f"experiment kind; known: {', '.join(sorted(kinds))}")
        kind = kinds[exp.kind]
        config = parse(kind.schema, tables, "")
        plan = kind.build(config, path.parent.resolve())
        for need in table_needs(config):
            check_memory(need)
    return Prepared(path, exp, kind, config, plan, dict(seen))


def _open(prep: Prepared, results_dir: str | Path | None, run_id: str | None, *,
          resume: bool, overwrite: bool, accept_changes: bool) -> RunFolder:
    root = prep.results_root(results_dir)
    run = RunFolder.open(root, prep.experiment.name, run_id, resume=resume, overwrite=overwrite)
    resolved = json.loads(json.dumps(prep.resolved(), default=json_default))
    if not resume:
        run.write_json("config.json", resolved)
        run.write_bytes("config.toml", prep.path.read_bytes())
        return run
    try:
        old = json.loads(run.file("config.json").read_text())
    except (OSError, ValueError):
        old = None
    if old != resolved:
        diff = "no config.json" if old is None else first_difference(old, resolved)
        raise ValueError(f"--resume: the config differs from the one {str(run.path)!r} "
                         f"started with ({diff}): run it under another --run-id")
    changed = changes_since(run.meta, prep.inputs)
    if changed and not accept_changes:
        raise ValueError(f"--resume: {'; '.join(changed)} changed since {str(run.path)!r} "
                         "started, so its finished stages rest on other inputs: run it under "
                         "another --run-id, or pass --accept-changes to resume anyway")
    if changed:
        run.meta["accepted_changes"] = [*run.meta.get("accepted_changes", []), *changed]
    return run


def _stages(prep: Prepared, run: RunFolder, ctx: StageContext, where: list[str]
            ) -> dict[str, Any]:
    done: dict[str, Any] = {}
    for i, stage in enumerate(prep.kind.stages):
        if run.has_stage(i, stage.name):
            done[stage.name] = run.load_stage(i, stage.name)
            continue
        where[0] = stage.name
        t0 = time.perf_counter()
        result = stage.func(prep.plan, dict(done), ctx)
        run.save_stage(i, stage.name, result, time.perf_counter() - t0)
        done[stage.name] = result
    return done


def run_experiment(config_path: str | Path, *, results_dir: str | Path | None = None,
                   run_id: str | None = None, progress: bool = True, seed: int | None = None,
                   resume: bool = False, overwrite: bool = False,
                   accept_changes: bool = False) -> RunFolder:
    """Run one experiment config into ``<results>/<experiment>/<run-id>/``; returns the run
    folder.

    ``seed`` replaces ``[experiment] seed`` (recorded in ``config.json`` and ``meta.json``;
    ``config.toml`` is the file as given). ``resume`` continues an unfinished run of the same
    config (finished stages are loaded, cached FE points are not recomputed; refused if an
    input file, the code or a package changed, unless ``accept_changes``); ``overwrite``
    replaces an existing run. Raises ``ValueError`` (bad config or folder: nothing written),
    :class:`~surrogate_rbrdo.runner.runfolder.AlreadyComplete` or :class:`RunFailed` (an
    error during the work: the folder is marked ``failed``).
    """
    if accept_changes and not resume:
        raise ValueError("--accept-changes is not allowed: it needs --resume")
    prep = prepare(config_path, seed=seed)
    need = getattr(prep.plan, "disk_need", None)     # (field, value, bytes, what)
    if need is not None and not resume:
        require_disk(*need, prep.results_root(results_dir))
    run = _open(prep, results_dir, run_id, resume=resume, overwrite=overwrite,
                accept_changes=accept_changes)
    run.start(kind=prep.kind.name, seeds={"seed": prep.experiment.seed}, inputs=prep.inputs)
    ctx = StageContext(seed=prep.experiment.seed, progress=progress,
                       label=f"{prep.experiment.name}/{run.run_id}",
                       cache_dir=run.path.parent / "_fe_cache", run_dir=run.path)
    where = ["setup"]
    try:
        done = _stages(prep, run, ctx, where)
        where[0] = "report"
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
    except Exception as exc:
        run.stop("failed", error=f"{type(exc).__name__}: {exc}", failed_in=where[0],
                 traceback=traceback.format_exc())
        raise RunFailed(run, where[0], exc) from exc
    except BaseException as exc:
        run.stop("failed", error=f"{type(exc).__name__}: {exc}", failed_in=where[0])
        raise
    finally:
        share_tree(ctx.cache_dir)     # the FE cache is written with the process's umask
    return run


__all__ = ["ExperimentTable", "Prepared", "RunFailed", "Terminated", "prepare", "run_experiment"]
