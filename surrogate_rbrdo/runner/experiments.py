"""Experiment kinds, in a registry: each turns a validated config into a run folder.

Kinds register themselves with ``@EXPERIMENTS.register("name")``; a kind is a function
``run(config: dict, run: RunFolder, *, progress: bool) -> dict`` returning a summary.
"""

from __future__ import annotations

from surrogate_rbrdo.core.registry import Registry

EXPERIMENTS = Registry("experiment kind")
