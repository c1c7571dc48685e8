"""Experiment kind ``identification``: bearing coefficients and the study's uncertainty model
from a campaign's records (``docs/identification.md`` §8).

Tables: ``[identification]`` (:class:`IdentificationTable`: ``source`` and the fields of
:class:`~surrogate_rbrdo.identification.experiment.IdentificationOptions`) and ``[spindle]``
(the experimenter's model of the tested rotor, at ``spindle.baseline``; only the rotor and the
node layout are used, the bearings are what is identified). ``source`` is a rig campaign run
folder (``<results>/<rig experiment>/<run-id>``, its dataset in ``campaign/dataset``), a
campaign or dataset folder, or ``<results>/<rig experiment>/latest``: the newest complete run
of that experiment (the runner makes no ``latest`` link). A relative ``source`` is taken from
the working directory, where ``results/`` is (as ``designs.from`` of ``validation``).

Stages: ``demodulate`` (``identification.read_responses``: 1× phasors of every steady record,
trial-weight differences) → ``identify`` (``identification.identify_responses``: every
record, trend, scatter, tests; stream 0 of the seed drives the bootstrap); ``--resume`` loads
both. The report writes ``identified.csv``, ``uncertainty.json`` (what ``[uncertainty] from``
of a study reads), ``identification_summary.json`` and the figures (Fig. 1 convergence, Fig. 3
trend ±2σ, Fig. 4 Q–Q; ``reporting.plots_identification``).
"""

from __future__ import annotations

import json
import time
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

import numpy as np

from surrogate_rbrdo.core.files import read_input
from surrogate_rbrdo.identification.experiment import (
    IdentificationOptions,
    check_source,
    identify_responses,
    read_responses,
    table_rows,
)
from surrogate_rbrdo.reporting.plots_identification import write_identification_figures
from surrogate_rbrdo.runner.kinds import Kind, Stage, StageContext, register_kind
from surrogate_rbrdo.runner.runfolder import read_meta
from surrogate_rbrdo.runner.tables import SpindleTable, build_spindle
from surrogate_rbrdo.spindle.assembly import SpindleModel
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
    identification: IdentificationTable
    spindle: SpindleTable = field(default_factory=SpindleTable)


@dataclass(frozen=True, eq=False)
class Plan:
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


def build(c: IdentificationConfig, base_dir: Path) -> Plan:
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
    return Plan(model, folder, dataset, o, {k: v for k, v in rig.items() if k != "config"})


def _demodulate(p: Plan, done: Mapping[str, Any], ctx: StageContext) -> Any:
    t0 = time.perf_counter()
    resp = read_responses(p.dataset, p.options)
    return resp, time.perf_counter() - t0


def _identify(p: Plan, done: Mapping[str, Any], ctx: StageContext) -> Any:
    resp, seconds = done["demodulate"]
    return identify_responses(p.model, resp, p.options, rng=ctx.stream(0), source=p.dataset,
                              demodulation_s=seconds)


def _report(p: Plan, done: Mapping[str, Any], run: Any, ctx: StageContext) -> dict[str, Any]:
    res = done["identify"]
    camp, u = res.campaign, res.uncertainty
    run.write_csv("identified.csv", *table_rows(camp.table))
    run.write_json("uncertainty.json", u.to_dict())
    figures = (write_identification_figures(p.model, res, run.path,
                                            convergence_speed_rpm=p.options.convergence_speed_rpm)
               if p.options.figures else {})
    info = {"flag_counts": camp.flag_counts, "timings_s": res.timings,
            "provenance": res.provenance, "rig_run": p.rig_run,
            "figures": {k: Path(v).name for k, v in figures.items()}}
    run.write_json("identification_summary.json", info)
    d = u.to_dict()
    sd = np.sqrt(np.diag(np.asarray(d["cov"])))
    rows = [{"theta": n, "speed_rpm": d["speed_rpm"], "mean": round(float(m), 5),
             "std": round(float(s), 5)} for n, m, s in zip(d["names"], d["mean"], sd,
                                                            strict=True)]
    return {"meta": {"n_records": int(res.responses.n), "n_used": int(np.sum(camp.used)),
                     "source": str(p.source), "rig_run": p.rig_run,
                     "identification_s": res.timings, "flag_counts": camp.flag_counts},
            "summary": rows + [{"records": int(res.responses.n),
                                "used": int(np.sum(camp.used)),
                                "trend_laws": {c: t.law for c, t in zip(
                                    u.coefficients, u.trends, strict=True)}}]
            + _impact_rows(d.get("provenance", {}).get("damping"))}


def _impact_rows(damping: Mapping[str, Any] | None) -> list[dict[str, Any]]:
    """One summary line per installation's impact fit: η̂, the tool mass factor and the fit's
    χ²/ν — far above a few, the model cannot represent the FRFs (docs/identification.md §5b)."""
    if not damping or damping.get("source") != "impact":
        return []
    return [{"impacts": key, "eta_s": [float(f"{e:.4g}") for e in inst["eta_s"]],
             "tool_mass": round(float(inst["parameters"].get("tool_mass", 1.0)), 4),
             "chi2_dof": round(float(inst["chi2_dof"]), 2)}
            for key, inst in damping["installations"].items()]


register_kind(Kind(
    name="identification",
    summary="bearing coefficients identified from a campaign's records (trial-weight "
            "differences, FE condensation): identified.csv, uncertainty.json (speed trend, "
            "physical scatter, tests; a study's [uncertainty] from), Fig. 1/3/4 analogues",
    schema=IdentificationConfig,
    stages=(Stage("demodulate", _demodulate), Stage("identify", _identify)),
    report=_report,
    build=build,
))
