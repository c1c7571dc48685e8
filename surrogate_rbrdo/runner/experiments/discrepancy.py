"""Experiment kind ``discrepancy``: where the model and the measurement part, which effect is
missing, the model with it added and the gap before/after (``docs/discrepancy.md``).

Tables: ``[spindle]`` (the model, :class:`~surrogate_rbrdo.runner.tables.SpindleTable`: its
geometry at ``baseline``, its effects), ``[discrepancy]``
(:class:`~surrogate_rbrdo.discrepancy.experiment.DiscrepancyTable`) and the data, one of

* ``[rig]`` (:class:`~surrogate_rbrdo.rig.config.RigTable`): a campaign on the virtual rig with
  the truth's hidden ``effects``, streamed into ``<run>/campaign/`` by the stage ``campaign``
  (resumed record by record, as the ``rig`` kind);
* ``[data] path``: a finished ``rig`` run folder (or ``discrepancy`` run on the rig), a
  folder with ``phasors.csv`` (and ``channels.json``) or a dataset folder of
  ``docs/measured-data.md`` (relative to the config). The files the analysis reads
  (``discrepancy.experiment.data_files``) are hashed into ``meta.json`` ``inputs``, so
  ``--resume`` refuses data that changed since the run started.

Stages: ``campaign`` (the rig's, or the data folder resolved) → ``analyse``
(``discrepancy.find_discrepancy``, stream 1 of the seed); the report writes ``findings.json``,
``spindle_updated.toml``, ``candidates.csv``, ``curves.csv`` (``discrepancy.report.write_run``),
``figures/`` (``reporting.plots_discrepancy.plot_all``) and the verdict in ``summary.json``.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from surrogate_rbrdo.core.files import read_input
from surrogate_rbrdo.discrepancy.experiment import DiscrepancyTable, data_files, data_from_folder
from surrogate_rbrdo.discrepancy.report import write_run
from surrogate_rbrdo.discrepancy.workflow import DiscrepancyOptions, find_discrepancy
from surrogate_rbrdo.reporting.plots_discrepancy import plot_all
from surrogate_rbrdo.rig.campaign import CampaignResult, run_campaign
from surrogate_rbrdo.rig.config import RigTable
from surrogate_rbrdo.runner.experiments.rig import Plan as RigPlan
from surrogate_rbrdo.runner.experiments.rig import RigCampaignConfig
from surrogate_rbrdo.runner.experiments.rig import build as rig_build
from surrogate_rbrdo.runner.kinds import Kind, Stage, StageContext, register_kind
from surrogate_rbrdo.runner.runfolder import read_meta
from surrogate_rbrdo.runner.tables import SpindleTable, build_spindle
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
    spindle: SpindleTable = field(default_factory=SpindleTable)
    discrepancy: DiscrepancyTable = field(default_factory=DiscrepancyTable)
    rig: RigTable | None = None
    data: DataTable | None = None


@dataclass(frozen=True, eq=False)
class Plan:
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


def build(c: DiscrepancyConfig, base_dir: Path) -> Plan:
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
        rig = rig_build(RigCampaignConfig(c.rig), base_dir)
    else:
        folder = _data_folder(c, sp, base_dir)
    return Plan(sp, section, c.discrepancy.options(), rig, folder,
                None if rig is None else rig.disk_need)


def _campaign(p: Plan, done: Mapping[str, Any], ctx: StageContext) -> CampaignResult | Path:
    """The rig's campaign into ``<run>/campaign`` (resumable), or the data folder."""
    if p.rig is None:
        return p.folder
    with ctx.bar("rig campaign", "record") as progress:
        return run_campaign(p.rig.rig.truth, p.rig.rig.options, ctx.run_dir / "campaign",
                            rng=ctx.stream(0), progress=progress)


def _analyse(p: Plan, done: Mapping[str, Any], ctx: StageContext) -> Any:
    src = done["campaign"]
    data = data_from_folder(src if isinstance(src, Path) else src.root)
    sp = p.spindle
    with ctx.bar("discrepancy: recalibrate, fit the candidates, test", "step") as progress:
        progress(0, 1, f"{len(p.options.library)} candidates")
        return find_discrepancy(data, sp.geometry_for(sp.baseline), sp.effects,
                                options=p.options, rng=ctx.stream(1))


def verdict_line(res: Any) -> str:
    """One line: the verdict, what is named, the test and the held-out gap."""
    t, b, a = res.test, res.gap_before, res.gap_after
    what = {"named": ", ".join(e.name for e in res.effects),
            "confounded": " | ".join(res.confounded_with)}.get(res.verdict, "")
    return (f"{res.verdict}{': ' + what if what else ''} (statistic {t['statistic']:.4g}, "
            f"p {t['p_value']:.3g}, threshold {t['threshold']:g}); held-out RMSE "
            f"{b.rmse:.4g} -> {a.rmse:.4g} um, chi2/dof {b.chi2_dof:.3g} -> {a.chi2_dof:.3g}")


def _report(p: Plan, done: Mapping[str, Any], run: Any, ctx: StageContext) -> dict[str, Any]:
    res = done["analyse"]
    write_run(res, run.path, spindle_section=p.spindle_section, model_effects=p.spindle.effects)
    (run.path / "figures").mkdir(exist_ok=True)
    figs = plot_all(res, run.path / "figures")
    src = done["campaign"]
    named = [{"effect": e.name, **{k: float(f"{v:.6g}") for k, v in e.fit.parameters.items()
                                   if isinstance(v, float) and np.isfinite(v)}}
             for e in res.effects]
    return {"meta": {"verdict": res.verdict, "named": [e.name for e in res.effects],
                     "confounded_with": list(res.confounded_with),
                     "data": str(src if isinstance(src, Path) else src.root),
                     "analyse_s": res.seconds, "figures": sorted(f.name for f in figs.values())},
            "summary": [{"verdict": verdict_line(res)}, *named]}


register_kind(Kind(
    name="discrepancy",
    summary="where the model and measured data part, which library effect is missing (named, "
            "confounded, nothing missing or an unnamed residual), the updated [spindle] and "
            "the held-out gap before/after; data from the virtual rig ([rig]) or [data] path",
    schema=DiscrepancyConfig,
    stages=(Stage("campaign", _campaign), Stage("analyse", _analyse)),
    report=_report,
    build=build,
))
