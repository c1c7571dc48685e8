"""A discrepancy config's tables and the checked plan they describe
(:func:`build_discrepancy`).

Tables: ``[spindle]`` (the model, :class:`~surrogate_rbrdo.spindle.config.SpindleTable`: its
geometry at ``baseline``, its effects), ``[discrepancy]``
(:class:`~surrogate_rbrdo.discrepancy.experiment.DiscrepancyTable`) and the data, one of

* ``[rig]`` (:class:`~surrogate_rbrdo.rig.config.RigTable`): a campaign on the virtual rig with
  the truth's hidden ``effects``;
* ``[data] path``: a finished ``rig`` run folder (or ``discrepancy`` run on the rig), a
  folder with ``phasors.csv`` (and ``channels.json``) or a dataset folder of
  ``docs/measured-data.md`` (relative to the config).
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from surrogate_rbrdo.core.files import read_input, read_meta
from surrogate_rbrdo.discrepancy.experiment import DiscrepancyTable, data_files
from surrogate_rbrdo.discrepancy.workflow import DiscrepancyOptions
from surrogate_rbrdo.rig.config import RigPlan, RigTable, rig_plan
from surrogate_rbrdo.spindle.config import SpindleTable, build_spindle
from surrogate_rbrdo.spindle.reference import ReferenceSpindle


@dataclass(frozen=True)
class DataTable:
    """``[data]``: ``path`` of the measurements (see the module doc)."""

    path: str

    def __post_init__(self) -> None:
        if not self.path.strip():
            raise ValueError(f"path = {self.path!r} is not allowed: give a finished rig run "
                             "folder, a folder with phasors.csv or a dataset folder")


@dataclass(frozen=True)
class DiscrepancyConfig:
    """The tables of a ``discrepancy`` config (the module docstring)."""

    spindle: SpindleTable = field(default_factory=SpindleTable)
    discrepancy: DiscrepancyTable = field(default_factory=DiscrepancyTable)
    rig: RigTable | None = None
    data: DataTable | None = None


@dataclass(frozen=True, eq=False)
class DiscrepancyPlan:
    """The model (``spindle`` and its ``[spindle]`` table, what the report updates), the
    options, and the data: a rig campaign to run (``rig``) or a folder (``folder``)."""

    spindle: ReferenceSpindle
    spindle_section: dict[str, Any]
    options: DiscrepancyOptions
    rig: RigPlan | None
    folder: Path | None
    disk_need: tuple[str, Any, float, str] | None


def _same_design(where: str, design: Any, sp: ReferenceSpindle | None, geometry: str) -> None:
    """The rig's truth is the reference spindle at ``design``: the model must be it."""
    if geometry != "reference":
        raise ValueError(f"spindle.geometry = {geometry!r} is not allowed: the data come from "
                         "the virtual rig, whose truth is the reference spindle")
    x = sp.baseline if design is None else np.asarray(design, float)
    if not np.allclose(x, sp.baseline, rtol=1e-9):
        raise ValueError(f"{where} = {[float(v) for v in x]} is not allowed: the model is "
                         f"spindle.baseline = {[float(v) for v in sp.baseline]}; give the same "
                         "design (the model must be the spindle that was measured)")


def _rig_run(folder: Path, sp: ReferenceSpindle, geometry: str) -> Path:
    """The campaign folder of a finished ``rig`` run, or of a ``discrepancy`` run on the rig
    (its design checked against the model)."""
    meta = read_meta(folder) or {}
    if meta.get("kind") not in ("rig", "discrepancy") or meta.get("status") != "complete" \
            or not (folder / "campaign" / "phasors.csv").is_file():
        raise ValueError(f"data.path = {str(folder)!r} is not allowed: a run folder that is not "
                         f"a finished rig campaign (meta.json: kind {meta.get('kind')!r}, status "
                         f"{meta.get('status')!r}; needs campaign/phasors.csv)")
    try:
        rig = json.loads(read_input(folder / "config.json", "data.path's config.json")
                         ).get("rig", {})
    except ValueError as exc:
        raise ValueError(f"data.path = {str(folder)!r}: its config.json: {exc}") from None
    _same_design(f"data.path = {str(folder)!r}: its rig.design", rig.get("design"), sp,
                 geometry)
    return folder / "campaign"


def _data_folder(c: DiscrepancyConfig, sp: ReferenceSpindle, base_dir: Path) -> Path:
    p = Path(c.data.path)
    p = p if p.is_absolute() else Path(base_dir) / p
    if (p / "meta.json").is_file():
        p = _rig_run(p, sp, c.spindle.geometry)
    if not ((p / "phasors.csv").is_file() or (p / "index.jsonl").is_file()):
        raise ValueError(f"data.path = {c.data.path!r} is not allowed: {str(p)!r} holds no "
                         "phasors.csv, no dataset (index.jsonl) and is no rig run folder")
    for f in data_files(p):                  # hashed into meta.json inputs: --resume checks
        read_input(f, "data file")
    return p


def build_discrepancy(c: DiscrepancyConfig, base_dir: str | Path = ".") -> DiscrepancyPlan:
    """The checked plan of a ``discrepancy`` config (errors name the dotted path)."""
    give = ("give [rig] (a campaign on the virtual rig) or [data] path (measurements), "
            "one of them")
    if c.rig is not None and c.data is not None:
        raise ValueError(f"[rig] and [data] are not allowed together: {give}")
    if c.rig is None and c.data is None:
        raise ValueError(f"[rig] or [data] is missing: {give}")
    if c.rig is not None and c.spindle.geometry != "reference":
        _same_design("rig.design", None, None, c.spindle.geometry)   # names the geometry
    sp = build_spindle(c.spindle, base_dir)
    section = {k: v for k, v in asdict(c.spindle).items() if v is not None}
    rig, folder = None, None
    if c.rig is not None:
        _same_design("rig.design", c.rig.design, sp, c.spindle.geometry)
        rig = rig_plan(c.rig.config(), c.rig.effects)
    else:
        folder = _data_folder(c, sp, base_dir)
    return DiscrepancyPlan(sp, section, c.discrepancy.options(), rig, folder,
                None if rig is None else rig.disk_need)


__all__ = ["DataTable", "DiscrepancyConfig", "DiscrepancyPlan", "build_discrepancy"]
