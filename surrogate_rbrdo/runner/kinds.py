"""Experiment kinds: a config schema, stage functions with frozen results, and a report.

A kind is a :class:`Kind` registered in :data:`KINDS` (``register_kind``), usually from a
module in ``surrogate_rbrdo/runner/experiments/`` (every module there is imported by
:func:`discover`, so adding a kind is adding a file). ``docs/runner.md`` has a worked example.

* ``schema``: a frozen dataclass with one field per config table (each a frozen dataclass
  whose annotations and ``__post_init__`` are the table's schema); the runner validates the
  whole config against it before any work (:func:`~surrogate_rbrdo.core.schema.parse`).
* ``build(config, base_dir) -> plan``: turns the validated tables into the objects the stages
  use (a spindle, a problem, options); raises ``ValueError`` naming the dotted path; runs
  before the run folder exists, so a rejected config leaves nothing behind. Default: the
  config itself. A plan that writes much may say so in ``disk_need = (field, value, bytes,
  what)``; a new run is refused if the results root has less free space.
* ``stages``: ``Stage(name, func)``, ``func(plan, done, ctx) -> result`` with ``done`` the
  results of the stages before (by name) and ``ctx`` a :class:`StageContext`. The result
  (a frozen dataclass) is pickled into the run folder when the stage ends, so ``--resume``
  skips finished stages.
* ``report(plan, done, run, ctx) -> summary``: writes tables and figures into the run folder
  (``run.write_rows``, ``run.write_csv``, ``run.save_figure``, ``run.write_json``) and returns
  a JSON-able summary; its ``"meta"`` entry (counted model calls, …) goes into ``meta.json``
  and its ``"summary"`` rows are printed.
"""

from __future__ import annotations

import importlib
import pkgutil
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from tqdm.auto import tqdm

from surrogate_rbrdo.core.registry import Registry
from surrogate_rbrdo.runner import experiments

KINDS = Registry("experiment kind")


@dataclass(frozen=True)
class StageContext:
    """What a stage gets besides the plan and the earlier results.

    ``stream(i)`` is the ``i``-th child generator of the experiment's seed (the same on every
    resume, whatever ran before); ``cache_dir`` holds FE results shared by the runs of one
    experiment; ``run_dir`` is the run folder, where a stage may stream output that it
    resumes itself (a dataset written record by record); ``label`` (``experiment/run-id``)
    prefixes progress bars; ``bar(what)`` is a progress callback for library loops.
    """

    seed: int
    progress: bool
    label: str
    cache_dir: Path
    run_dir: Path

    @contextmanager
    def bar(self, what: str, unit: str = "it") -> Iterator[Callable[[int, int, str], None]]:
        """A ``progress(done, total, label)`` callback drawing a bar ``<label> <what>`` that
        shows the item in progress (does nothing without ``progress``)."""
        if not self.progress:
            yield lambda done, total, item: None
            return
        bar = tqdm(desc=f"{self.label} {what}", unit=unit, leave=False)

        def update(done: int, total: int, item: str) -> None:
            bar.total = total
            bar.update(done - bar.n)
            bar.set_postfix_str(item)

        try:
            yield update
        finally:
            bar.close()

    def seed_sequence(self, i: int) -> np.random.SeedSequence:
        """Child ``i`` of the experiment seed (``default_rng(seed).spawn(n)[i]``'s seeds)."""
        return np.random.SeedSequence(self.seed, spawn_key=(i,))

    def stream(self, i: int) -> np.random.Generator:
        """A fresh generator on child ``i`` of the experiment seed."""
        return np.random.default_rng(self.seed_sequence(i))


@dataclass(frozen=True)
class Stage:
    """One step of a kind: ``func(plan, done, ctx) -> frozen result``."""

    name: str
    func: Callable[[Any, Mapping[str, Any], StageContext], Any]


def _identity(config: Any, base_dir: Path) -> Any:
    return config


@dataclass(frozen=True)
class Kind:
    """An experiment kind (see the module docstring)."""

    name: str
    summary: str
    schema: type
    stages: tuple[Stage, ...]
    report: Callable[[Any, Mapping[str, Any], Any, StageContext], Mapping[str, Any]]
    build: Callable[[Any, Path], Any] = _identity
    #: what the kind is when its problem tables are left out (``rbrdo kinds``)
    defaults: str = ""

    def __post_init__(self) -> None:
        names = [s.name for s in self.stages]
        if len(set(names)) != len(names):
            raise ValueError(f"stages {names} is not allowed: stage names must be unique")


def register_kind(kind: Kind) -> Kind:
    """Add ``kind`` to :data:`KINDS` (a duplicate name raises)."""
    KINDS.register(kind.name)(kind)
    return kind


def discover() -> Registry:
    """Import every module of ``surrogate_rbrdo.runner.experiments`` (each registers its
    kinds) and return :data:`KINDS`."""
    for mod in pkgutil.iter_modules(experiments.__path__):
        importlib.import_module(f"{experiments.__name__}.{mod.name}")
    return KINDS


__all__ = ["KINDS", "Kind", "Stage", "StageContext", "discover", "register_kind"]
