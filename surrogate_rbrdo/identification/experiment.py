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
from dataclasses import asdict, dataclass, field, fields
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
from surrogate_rbrdo.identification.measured import SensorCorrections, measured_phasors
from surrogate_rbrdo.identification.model import save_uncertainty
from surrogate_rbrdo.identification.responses import Responses, known_unbalance, trial_pairs
from surrogate_rbrdo.identification.systematic import SystematicUncertainty
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
    gains: dict = field(default_factory=dict)
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
    convergence_speed_rpm: float = 10_000.0
    n_jobs: int = 1
    figures: bool = True

    def __post_init__(self) -> None:
        check_choice("excitation", self.excitation, EXCITATIONS)
        check_choice("fit_on", self.fit_on, FIT_ON)
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


def _responses(model: SpindleModel, source, o: IdentificationOptions) -> Responses:
    m = measured_phasors(source, targets=o.targets, corrections=o.corrections(),
                         n_jobs=o.n_jobs)
    if o.excitation == "trial":
        trial = o.unbalance[0] if o.unbalance else None
        return trial_pairs(m, trial_unbalance=trial, group_label=o.group_label)
    return known_unbalance(m, o.unbalance, group_label=o.group_label)


def identify_records(model: SpindleModel, source, options: IdentificationOptions = (
        IdentificationOptions()), *, rng: np.random.Generator,
        truth: np.ndarray | None = None) -> IdentificationRun:
    """Identify the steady records of a measured-data folder (module docstring).

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
    resp = _responses(model, source, options)
    t1 = time.perf_counter()
    probe_nodes = [node_at(model, float(p)) for p in resp.positions_mm[::2]]
    unb = [(node_at(model, pos), U * np.exp(1j * np.radians(ph)))
           for pos, U, ph in resp.unbalance]
    prov = {"source": str(source), "excitation": resp.excitation,
            "unbalance": [list(u) for u in resp.unbalance], "channels": list(resp.channels),
            "options": options.to_dict()}
    camp = identify_campaign(
        model, resp.speed_rpm, resp.repeat, resp.phasors, phasor_sd=resp.phasor_sd,
        groups=resp.groups, perturbations=resp.perturbations,
        probe_nodes=probe_nodes, unbalance=unb, fit_on=options.fit_on,
        max_rel_se=options.max_rel_se, law=options.law, study=options.study,
        scatter=options.scatter, truth=truth, rng=rng, n_boot=options.n_boot,
        systematic=options.systematic, probe_bandwidth_hz=options.probe_bandwidth_hz,
        summary_speed_rpm=options.summary_speed_rpm, provenance=prov)
    t2 = time.perf_counter()
    return IdentificationRun(resp, camp, {"demodulation_s": t1 - t0, "identification_s": t2 - t1,
                                          "total_s": t2 - t0}, prov)


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


def _write_table(path: Path, table: dict) -> Path:
    cols = list(table)
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(cols)
        for i in range(len(table[cols[0]])):
            w.writerow([_cell(table[c][i]) for c in cols])
    return path


def _cell(v):
    if isinstance(v, (bool, np.bool_)):
        return int(v)
    if isinstance(v, (float, np.floating)):
        return "" if not np.isfinite(v) else repr(float(v))
    return v


__all__ = ["EXCITATIONS", "IdentificationOptions", "IdentificationRun", "identification_config",
           "identify_records", "run_identification"]
