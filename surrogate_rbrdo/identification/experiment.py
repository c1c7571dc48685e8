"""The ``identification`` experiment: a measured-data folder → identified coefficients and the
uncertainty model, with its files (what the runner's kind calls).

:func:`identify_records` does the work and returns a frozen :class:`IdentificationRun`;
:func:`run_identification` also writes the run folder's files:

* ``identified.csv`` — one row per identified vector: ``speed_rpm``, ``repeat``, one column per
  coefficient ``<bearing>_<k|c>_<yy|zz>`` (SI), its standard error ``<name>_se`` and flags
  ``<name>_flag``, ``used`` and the plain-language ``flags``;
* ``uncertainty.json`` — :func:`~surrogate_rbrdo.identification.model.save_uncertainty`
  (``names``, ``mean``, ``cov`` of the study's θ at ``speed_rpm``, ``by_speed``, the trend laws
  and parameters, the scatter, the test statistics, provenance);
* ``summary.json`` — flag counts, timings, options and the source;
* figures like the paper's Fig. 1 (convergence of SG, MISG(p = 3) and RLS on one speed's
  records), Fig. 3 (trend ±2σ) and Fig. 4 (Q–Q plots), written by
  :func:`surrogate_rbrdo.reporting.plots_identification.write_identification_figures` (reporting
  sits above identification).

The chain: :func:`~surrogate_rbrdo.identification.measured.measured_phasors` (demodulation and
the known corrections) → :func:`~surrogate_rbrdo.identification.measured.trial_pairs` (or a
stated unbalance) → :func:`~surrogate_rbrdo.identification.campaign.identify_campaign`.
"""

from __future__ import annotations

import csv
import json
import time
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field, fields, replace
from pathlib import Path
from typing import Any

import numpy as np

from surrogate_rbrdo.core.rng import require_rng
from surrogate_rbrdo.core.validate import check_choice, check_int, check_keys, check_positive
from surrogate_rbrdo.identification.campaign import (
    DEFAULT_MAX_REL_SE,
    FIT_ON,
    CampaignResult,
    identify_campaign,
)
from surrogate_rbrdo.identification.condensation import node_at
from surrogate_rbrdo.identification.damping import (
    DAMPING_SOURCES,
    impact_dampings,
    record_installations,
    with_impact_damping,
)
from surrogate_rbrdo.identification.impact import ImpactOptions
from surrogate_rbrdo.identification.measured import (
    SensorCorrections,
    dataset_root,
    measured_phasors,
    probe_channels,
)
from surrogate_rbrdo.identification.model import SCATTERS, STUDY_FORMS, save_uncertainty
from surrogate_rbrdo.identification.responses import Responses, known_unbalance, trial_pairs
from surrogate_rbrdo.identification.systematic import SystematicUncertainty
from surrogate_rbrdo.identification.trend import TREND_LAWS
from surrogate_rbrdo.identification.updating import with_tool_mass
from surrogate_rbrdo.rig.store import open_dataset
from surrogate_rbrdo.spindle.assembly import SpindleModel

EXCITATIONS = ("trial", "known")


@dataclass(frozen=True)
class IdentificationOptions:
    """Options of an identification run (the ``[identification]`` table).

    Parameters
    ----------
    excitation : {"trial", "known"}
        ``"trial"``: trial-weight differences (the trial mass from the records' test set-up,
        or ``unbalance`` if given); ``"known"``: the records as they are, excited by
        ``unbalance`` (``(position_mm, magnitude_kgm, phase_deg)`` per plane).
    targets : tuple of str
        Probe targets whose ``x, y`` are used (default the bearing planes).
    probe_bandwidth_hz, gains, keyphasor_angle_deg
        What the experimenter knows of the sensors
        (:class:`~surrogate_rbrdo.identification.measured.SensorCorrections`).
    fit_on, max_rel_se, law, study, scatter, n_boot, summary_speed_rpm
        As :func:`~surrogate_rbrdo.identification.campaign.identify_campaign`.
    systematic : SystematicUncertainty
        Tolerances of the sensors, the trial mass and the rotor model (what the experimenter
        knows of what is not corrected): their effect on the trends.
    damping : {"response", "impact"}
        Where the bearings' damping comes from: ``"response"`` (default) — the 1× unbalance
        response, like the stiffness (not identifiable at a realistic noise); ``"impact"`` —
        each installation's impact tests at standstill (``c = η̂ k̂``,
        :mod:`~surrogate_rbrdo.identification.damping`); the source must have impact records.
    tool_mass : {"model", "impact"}
        The tool/holder mass of the rotor model the reactions are condensed with:
        ``"model"`` (default) — as the model has it; ``"impact"`` — scaled by the factor the
        impact tests weigh (the disk ``systematic.tool_disk``; one installation only), and
        the systematic budget's ``tool_mass_sd`` becomes that factor's standard error.
    group_label : str or None
        Index label naming the run of a record; ``None``: all labels but the speed index.
    convergence_speed_rpm : float
        The campaign speed nearest to it is used for the Fig. 1 convergence plot.
    n_jobs : int
        Processes for the demodulation.
    figures : bool
    """

    excitation: str = "trial"
    unbalance: tuple[tuple[float, float, float], ...] | None = None
    targets: tuple[str, ...] = ("front", "rear")
    probe_bandwidth_hz: float | None = 10_000.0
    gains: dict[str, float] = field(default_factory=dict)
    keyphasor_angle_deg: float = 0.0
    fit_on: str = "stiffness"
    max_rel_se: float = DEFAULT_MAX_REL_SE
    law: str = "auto"
    study: str = "isotropic"
    scatter: str = "auto"
    n_boot: int = 200
    summary_speed_rpm: float | None = None
    group_label: str | None = None
    systematic: SystematicUncertainty = SystematicUncertainty()
    damping: str = "response"
    tool_mass: str = "model"
    convergence_speed_rpm: float = 10_000.0
    n_jobs: int = 1
    figures: bool = True

    def __post_init__(self) -> None:
        check_choice("excitation", self.excitation, EXCITATIONS)
        check_choice("damping", self.damping, DAMPING_SOURCES)
        check_choice("tool_mass", self.tool_mass, ("model", "impact"))
        check_choice("fit_on", self.fit_on, FIT_ON)
        check_choice("law", self.law, ("auto",) + TREND_LAWS)
        check_choice("study", self.study, STUDY_FORMS)
        check_choice("scatter", self.scatter, ("auto",) + SCATTERS)
        if self.summary_speed_rpm is not None:
            check_positive("summary_speed_rpm", self.summary_speed_rpm)
        check_positive("max_rel_se", self.max_rel_se)
        check_int("n_boot", self.n_boot, minimum=20)
        check_int("n_jobs", self.n_jobs, minimum=1)
        check_positive("convergence_speed_rpm", self.convergence_speed_rpm)
        if self.excitation == "known" and not self.unbalance:
            raise ValueError("unbalance = None is not allowed with excitation = 'known': give "
                             "[(position_mm, magnitude_kgm, phase_deg), ...]")
        if self.unbalance is not None:
            object.__setattr__(self, "unbalance", tuple(tuple(float(v) for v in u)
                                                        for u in self.unbalance))
        object.__setattr__(self, "targets", tuple(self.targets))
        if isinstance(self.systematic, dict):
            object.__setattr__(self, "systematic", SystematicUncertainty(**self.systematic))
        self.corrections()                       # validates bandwidth, gains, angle

    def corrections(self) -> SensorCorrections:
        return SensorCorrections(self.probe_bandwidth_hz, dict(self.gains),
                                 self.keyphasor_angle_deg)

    def to_dict(self) -> dict:
        return asdict(self)

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> IdentificationOptions:
        """From an ``[identification]`` table (without its ``source``); unknown keys raise a
        ``ValueError`` naming the table; lists become tuples."""
        check_keys("identification", d, {f.name for f in fields(cls)})
        kw = {k: tuple(tuple(x) if isinstance(x, list) else x for x in v)
              if isinstance(v, list) else v for k, v in d.items()}
        if "systematic" in kw:
            sysd = dict(kw["systematic"])
            check_keys("identification.systematic", sysd,
                       {f.name for f in fields(SystematicUncertainty)})
            kw["systematic"] = SystematicUncertainty(**sysd)
        return cls(**kw)


def identification_config(table: Mapping[str, Any]) -> tuple[Path, IdentificationOptions]:
    """The ``[identification]`` table of an experiment config: the ``source`` folder (a rig
    campaign run or a measured-data folder) and the options.

    >>> src, o = identification_config({"source": "results/rig/r1", "n_boot": 100,
    ...                                 "systematic": {"gain_sd": 0.01}})
    >>> str(src), o.n_boot, o.systematic.gain_sd
    ('results/rig/r1', 100, 0.01)
    """
    d = dict(table)
    if not isinstance(d.get("source"), str) or not d["source"]:
        raise ValueError(f"identification.source = {d.get('source')!r} is not allowed: give "
                         "the rig campaign or measured-data folder to identify from")
    return Path(d.pop("source")), IdentificationOptions.from_dict(d)


@dataclass(frozen=True, eq=False)
class IdentificationRun:
    """What an identification run produced: the responses used, the campaign result (table,
    flags, uncertainty model), timings (s) and, once written, the files."""

    responses: Responses
    campaign: CampaignResult
    timings: dict
    provenance: dict
    files: dict = field(default_factory=dict)

    @property
    def uncertainty(self):
        return self.campaign.uncertainty


def check_source(source, options: IdentificationOptions = IdentificationOptions()) -> Path:
    """The dataset folder of ``source`` (a dataset folder, a rig campaign folder with
    ``dataset/``), checked against ``options`` before any work: it has steady records, the
    probes of ``options.targets``, trial-weight runs for ``excitation = "trial"``, the
    ``group_label``, and ``summary_speed_rpm`` inside its speeds. Reads the index and one
    record; raises ``ValueError`` naming the field, its value and what is allowed.
    """
    src = Path(source)
    if not src.is_dir():
        raise ValueError(f"source = {str(source)!r} is not allowed: no such folder; give a rig "
                         "campaign run folder or a measured-data folder (with dataset.json)")
    root = dataset_root(src)
    if not (root / "dataset.json").is_file():
        raise ValueError(f"source = {str(source)!r} is not allowed: not a campaign (no "
                         "dataset.json in it or in its dataset/); give a rig campaign run "
                         "folder or a measured-data folder")
    ds = open_dataset(root)
    rows = [r for r in ds.index if r.get("kind") == "steady"]
    if not rows:
        raise ValueError(f"source = {str(source)!r} is not allowed: the dataset has no steady "
                         "records to identify from")
    labels = [r.get("labels", {}) for r in rows]
    if options.excitation == "trial" and not any(lab.get("trial", 0) for lab in labels):
        raise ValueError(f"excitation = 'trial' is not allowed with source = {str(source)!r}: "
                         "it has no trial-weight runs (no record labelled trial = 1); measure "
                         "with [rig.campaign] trial_unbalance = [position_mm, magnitude_kgm, "
                         "phase_deg], or use excitation = 'known' with unbalance")
    if options.group_label is not None and any(options.group_label not in lab
                                               for lab in labels):
        raise ValueError(f"group_label = {options.group_label!r} is not allowed: not a label "
                         f"of every record (labels: {sorted(labels[0])})")
    speeds = [float(r["speed_rpm"]) for r in rows]
    s = options.summary_speed_rpm
    if s is not None and not min(speeds) <= s <= max(speeds):
        raise ValueError(f"summary_speed_rpm = {s!r} is not allowed: must lie in the "
                         f"campaign's speeds [{min(speeds):g}, {max(speeds):g}] rpm")
    for name in ("damping", "tool_mass"):
        if getattr(options, name) == "impact" and not any(r.get("kind") == "impact"
                                                          for r in ds.index):
            raise ValueError(f"{name} = 'impact' is not allowed with source = "
                             f"{str(source)!r}: it has no impact records (measure with "
                             "[rig.campaign] impacts_per_direction > 0)")
    try:
        probe_channels(ds.load(rows[0]), options.targets)
    except ValueError as exc:
        raise ValueError(f"targets = {list(options.targets)} is not allowed: {exc}") from None
    return root


def read_responses(source, options: IdentificationOptions = IdentificationOptions()
                   ) -> Responses:
    """Demodulate and correct the steady records of ``source`` and form the responses to a
    known unbalance (trial-weight differences or the stated ``unbalance``)."""
    o = options
    m = measured_phasors(source, targets=o.targets, corrections=o.corrections(),
                         n_jobs=o.n_jobs)
    if o.excitation == "trial":
        trial = o.unbalance[0] if o.unbalance else None
        return trial_pairs(m, trial_unbalance=trial, group_label=o.group_label)
    return known_unbalance(m, o.unbalance, group_label=o.group_label)


def identify_responses(model: SpindleModel, resp: Responses, options: IdentificationOptions = (
        IdentificationOptions()), *, rng: np.random.Generator, source="",
        truth: np.ndarray | None = None, demodulation_s: float = 0.0) -> IdentificationRun:
    """Identify every response vector and fit the uncertainty model (the second half of
    :func:`identify_records`; ``source`` and ``demodulation_s`` are recorded)."""
    require_rng(rng)
    t1 = time.perf_counter()
    probe_nodes = [node_at(model, float(p)) for p in resp.positions_mm[::2]]
    unb = [(node_at(model, pos), U * np.exp(1j * np.radians(ph)))
           for pos, U, ph in resp.unbalance]
    prov = {"source": str(source), "excitation": resp.excitation,
            "unbalance": [list(u) for u in resp.unbalance], "channels": list(resp.channels),
            "options": options.to_dict()}
    impacts = _impacts(model, source, options)
    rotor, systematic = model, options.systematic
    if options.tool_mass == "impact":
        rotor, systematic, prov["tool_mass_factor"] = _weighed_tool(model, impacts, options)
    camp = identify_campaign(
        rotor, resp.speed_rpm, resp.repeat, resp.phasors, phasor_sd=resp.phasor_sd,
        groups=resp.groups, perturbations=resp.perturbations,
        probe_nodes=probe_nodes, unbalance=unb, fit_on=options.fit_on,
        max_rel_se=options.max_rel_se, law=options.law, study=options.study,
        scatter=options.scatter, truth=truth, rng=rng, n_boot=options.n_boot,
        systematic=systematic, probe_bandwidth_hz=options.probe_bandwidth_hz,
        summary_speed_rpm=options.summary_speed_rpm, provenance=prov)
    if options.damping == "impact":
        camp = with_impact_damping(rotor, camp, record_installations(source, resp.record_ids),
                                   impacts, max_rel_se=options.max_rel_se)
    dt = time.perf_counter() - t1
    timings = {"demodulation_s": demodulation_s, "identification_s": dt,
               "total_s": demodulation_s + dt}
    return IdentificationRun(resp, camp, timings, prov)


def _impacts(model: SpindleModel, source, options: IdentificationOptions) -> dict | None:
    """The impact tests' updated factors per installation, when an option asks for them."""
    if "impact" not in (options.damping, options.tool_mass):
        return None
    if not str(source):
        raise ValueError("source = '' is not allowed with damping or tool_mass = 'impact': "
                         "give the dataset whose impact records are used")
    return impact_dampings(model, source, ImpactOptions(tool_disk=options.systematic.tool_disk))


def _weighed_tool(model: SpindleModel, impacts: dict, options: IdentificationOptions):
    """The model with the tool mass the impacts weigh, the systematic budget with its SE."""
    if len(impacts) != 1:
        raise ValueError(f"tool_mass = 'impact' is not allowed with {len(impacts)} "
                         f"installations {sorted(impacts)}: one rotor model per run; use "
                         "tool_mass = 'model'")
    imp = next(iter(impacts.values()))
    j = imp.names.index("tool_mass")
    m, se = float(imp.parameters[j]), float(np.sqrt(imp.covariance[j, j]))
    rotor = with_tool_mass(model, options.systematic.tool_disk, m)
    return rotor, replace(options.systematic, tool_mass_sd=se), {"factor": m, "rel_se": se}


def identify_records(model: SpindleModel, source, options: IdentificationOptions = (
        IdentificationOptions()), *, rng: np.random.Generator,
        truth: np.ndarray | None = None) -> IdentificationRun:
    """Identify the steady records of a measured-data folder (module docstring):
    :func:`read_responses` then :func:`identify_responses`.

    Parameters
    ----------
    model : SpindleModel
        The experimenter's model of the rotor (only the rotor and the node layout are used;
        its bearings give the catalogue box and the nominal stiffness θ refers to).
    source : path
        A measured-data folder or a rig campaign folder (with ``dataset/``).
    options : IdentificationOptions
    rng : numpy.random.Generator
        For the bootstrap of the physical scatter.
    truth : array (N, 8), optional
        True coefficients of each identified vector, when known (virtual rig).
    """
    require_rng(rng)
    t0 = time.perf_counter()
    resp = read_responses(source, options)
    return identify_responses(model, resp, options, rng=rng, source=source, truth=truth,
                              demodulation_s=time.perf_counter() - t0)


def run_identification(model: SpindleModel, source, out_dir, options: IdentificationOptions = (
        IdentificationOptions()), *, rng: np.random.Generator,
        truth: np.ndarray | None = None) -> IdentificationRun:
    """:func:`identify_records`, then write ``identified.csv``, ``uncertainty.json`` and
    ``summary.json`` into ``out_dir`` (the figures: ``reporting.plots_identification.
    write_identification_figures(model, run, out_dir)``, when ``options.figures``)."""
    run = identify_records(model, source, options, rng=rng, truth=truth)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    files = {"identified": _write_table(out / "identified.csv", run.campaign.table),
             "uncertainty": save_uncertainty(run.uncertainty, out / "uncertainty.json")}
    summary = {"flag_counts": run.campaign.flag_counts, "timings": run.timings,
               "provenance": run.provenance, "files": {k: str(v) for k, v in files.items()}}
    files["summary"] = out / "summary.json"
    files["summary"].write_text(json.dumps(summary, indent=1, default=float))
    return IdentificationRun(run.responses, run.campaign, run.timings, run.provenance, files)


def table_rows(table: Mapping[str, Any]) -> tuple[list[str], list[list[Any]]]:
    """``identified.csv``'s header and rows from a campaign table (columns of equal length):
    booleans as 0/1, non-finite numbers as empty cells.

    >>> table_rows({"speed_rpm": [1000.0], "front_k_yy": [float("nan")], "used": [True]})
    (['speed_rpm', 'front_k_yy', 'used'], [[1000.0, '', 1]])
    """
    cols = list(table)
    return cols, [[_cell(table[c][i]) for c in cols] for i in range(len(table[cols[0]]))]


def _write_table(path: Path, table: dict) -> Path:
    cols, rows = table_rows(table)
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(cols)
        w.writerows(rows)
    return path


def _cell(v):
    if isinstance(v, (bool, np.bool_)):
        return int(v)
    if isinstance(v, (float, np.floating)):
        return "" if not np.isfinite(v) else float(v)
    return v


__all__ = ["EXCITATIONS", "IdentificationOptions", "IdentificationRun", "check_source",
           "identification_config", "identify_records", "identify_responses", "read_responses",
           "run_identification", "table_rows"]
