"""An identification config's tables and the checked plan they describe
(:func:`build_identification`).

Tables: ``[identification]`` (:class:`IdentificationTable`: ``source`` and the fields of
:class:`~surrogate_rbrdo.identification.experiment.IdentificationOptions`) and ``[spindle]``
(the experimenter's model of the tested rotor, at ``spindle.baseline``; only the rotor and the
node layout are used, the bearings are what is identified). ``source`` is a rig campaign run
folder (``<results>/<rig experiment>/<run-id>``, its dataset in ``campaign/dataset``), a
campaign or dataset folder, or ``<results>/<rig experiment>/latest``: the newest complete run
of that experiment (no ``latest`` link is made). A relative ``source`` is taken from the
working directory, where ``results/`` is.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

import numpy as np

from surrogate_rbrdo.core.files import read_input, read_meta
from surrogate_rbrdo.identification.experiment import IdentificationOptions, check_source
from surrogate_rbrdo.spindle.assembly import SpindleModel
from surrogate_rbrdo.spindle.config import SpindleTable, build_spindle
from surrogate_rbrdo.spindle.reference import reference_spindle


@dataclass(frozen=True)
class IdentificationTable(IdentificationOptions):
    """``[identification]``: ``source`` (required: the campaign to identify from, module
    docstring) and the options of
    :class:`~surrogate_rbrdo.identification.experiment.IdentificationOptions`."""

    source: str = field(default="", kw_only=True)

    def __post_init__(self) -> None:
        if not self.source.strip():
            raise ValueError(f"source = {self.source!r} is not allowed: give the rig campaign "
                             "run folder or measured-data folder to identify from")
        super().__post_init__()

    def options(self) -> IdentificationOptions:
        return IdentificationOptions(**{f.name: getattr(self, f.name)
                                        for f in fields(IdentificationOptions)})


@dataclass(frozen=True)
class IdentificationConfig:
    """The tables of an ``identification`` config."""

    identification: IdentificationTable
    spindle: SpindleTable = field(default_factory=SpindleTable)


@dataclass(frozen=True, eq=False)
class IdentificationPlan:
    """The model of the tested rotor, the source and dataset folders, the options and the
    rig run's provenance (empty: not a rig run)."""

    model: SpindleModel
    source: Path
    dataset: Path
    options: IdentificationOptions
    rig_run: dict[str, Any]


def _latest(path: Path) -> Path:
    """``<folder>/latest``: the newest complete run in ``<folder>`` (by finishing time)."""
    runs = [(m.get("finished_utc", ""), p) for p in sorted(path.parent.glob("*"))
            if p.is_dir() and not p.name.startswith(".")
            and (m := read_meta(p) or {}).get("status") == "complete"]
    if not runs:
        raise ValueError(f"identification.source = {str(path)!r} is not allowed: "
                         f"{str(path.parent)!r} holds no complete run to take as the latest; "
                         "run that experiment first (for experiments/identification.toml: rbrdo "
                         "run experiments/rig_campaign_trial.toml)")
    return max(runs)[1]


def _source(given: str) -> tuple[Path, dict[str, Any]]:
    """The folder ``source`` names, and the rig run's meta and config if it is one."""
    p = Path(given).expanduser()
    if p.name == "latest" and not p.exists():
        p = _latest(p)
    meta = read_meta(p) if p.is_dir() else None
    if meta is None:
        return p, {}
    if meta.get("status") != "complete":
        raise ValueError(f"identification.source = {given!r} is not allowed: the run "
                         f"{str(p)!r} is {meta.get('status')!r}, not complete")
    try:
        cfg = json.loads((p / "config.json").read_text())
    except (OSError, ValueError):
        cfg = {}
    info = {"path": str(p.resolve()), **{k: meta.get(k) for k in (
        "experiment", "run_id", "kind", "finished_utc", "git_sha", "source_sha256")}}
    return (p / "campaign" if (p / "campaign").is_dir() else p), {**info, "config": cfg}


def _check_design(model_design: np.ndarray, rig: Mapping[str, Any], where: str) -> None:
    """A rig campaign's truth is built at ``[rig] design`` (default the reference spindle's
    baseline): the model must be that design."""
    if rig.get("kind") != "rig":
        return
    design = (rig.get("config") or {}).get("rig", {}).get("design")
    design = reference_spindle().baseline.tolist() if design is None else design
    if not np.allclose(design, model_design, rtol=1e-9):
        raise ValueError(f"spindle.baseline = {np.round(model_design, 6).tolist()} is not "
                         f"allowed: the rig campaign {where!r} was built at design {design} "
                         "(set [spindle] baseline to it)")


def build_identification(c: IdentificationConfig, base_dir: str | Path = "."
                         ) -> IdentificationPlan:
    """The checked plan of an ``identification`` config (errors name the dotted path)."""
    spindle = build_spindle(c.spindle, base_dir)
    model = spindle.model(spindle.baseline)
    o = c.identification.options()
    disks = [d.name for d in model.geometry.disks]
    if o.systematic.tool_mass_sd > 0 and o.systematic.tool_disk not in disks:
        raise ValueError(f"identification.systematic.tool_disk = {o.systematic.tool_disk!r} "
                         f"is not allowed: not a disk of the [spindle] model; its disks: {disks}")
    src = c.identification.source
    folder, rig = _source(src)
    _check_design(spindle.baseline, rig, src)
    try:
        dataset = check_source(folder, o)
    except ValueError as exc:
        raise ValueError(f"identification.{exc}") from None
    for name in ("dataset.json", "index.jsonl"):   # tracked: --resume sees a changed dataset
        read_input(dataset / name, "identification.source")
    return IdentificationPlan(model, folder, dataset, o,
                              {k: v for k, v in rig.items() if k != "config"})


__all__ = ["IdentificationConfig", "IdentificationPlan", "IdentificationTable",
           "build_identification"]
