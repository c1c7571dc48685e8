"""What the experiment kind ``discrepancy`` composes: the ``[discrepancy]`` table → options, a
measured-data folder → observables, and the analysis → a frozen result and its files.

The runner (``rbrdo run experiments/discrepancy.toml``) is expected to do, in order:

1. the model: ``spindle_from_config(cfg["spindle"])`` → its geometry at the baseline design and
   its effects;
2. the data: with ``[rig] effects = [...]``, the virtual rig's campaign into ``<run>/rig``
   (``rig.config.RigTable(...).config()`` then ``rig.campaign.run_campaign``); with ``[data] path``
   a folder of the user's measurements; either way :func:`data_from_folder`;
3. :func:`analyse` with :func:`options_from_dict` of ``[discrepancy]`` and the experiment's seed;
4. the figures: ``reporting.plots_discrepancy.plot_all(result, <run>)``.

>>> o = options_from_dict({"alpha": 0.01, "nuisance": {"preset": "probe_chain"}})
>>> o.nuisance.gain_sd, o.alpha
(0.02, 0.01)
"""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from surrogate_rbrdo.core.rng import require_rng
from surrogate_rbrdo.core.validate import check_choice, check_keys
from surrogate_rbrdo.discrepancy.measured import channel_positions, phasor_block, read_phasor_table
from surrogate_rbrdo.discrepancy.nuisance import NuisanceOptions
from surrogate_rbrdo.discrepancy.observables import MeasuredData
from surrogate_rbrdo.discrepancy.report import write_run
from surrogate_rbrdo.discrepancy.workflow import (
    DiscrepancyOptions,
    DiscrepancyResult,
    find_discrepancy,
)
from surrogate_rbrdo.spindle.effects import Effect
from surrogate_rbrdo.spindle.geometry import SpindleGeometry

#: nuisance presets: the probe chain of docs/rig.md, or an ideal chain
PRESETS = {"probe_chain": NuisanceOptions.probe_chain, "ideal": NuisanceOptions}


def options_from_dict(table: Mapping[str, Any]) -> DiscrepancyOptions:
    """``[discrepancy]`` → :class:`~.workflow.DiscrepancyOptions`; ``nuisance`` may hold a
    ``preset`` (``probe_chain`` or ``ideal``) and any field of
    :class:`~.nuisance.NuisanceOptions`. Unknown keys raise, naming the table."""
    fields = {f.name for f in dataclasses.fields(DiscrepancyOptions)}
    check_keys("[discrepancy]", table, fields)
    kw = {k: (tuple(v) if isinstance(v, list) else v) for k, v in table.items()}
    if "nuisance" in kw:
        nu = dict(kw["nuisance"])
        nfields = {f.name for f in dataclasses.fields(NuisanceOptions)}
        check_keys("[discrepancy.nuisance]", nu, nfields | {"preset"})
        preset = check_choice("discrepancy.nuisance.preset", nu.pop("preset", "ideal"), PRESETS)
        nu = {k: (tuple(v) if isinstance(v, list) else v) for k, v in nu.items()}
        kw["nuisance"] = PRESETS[preset](**nu)
    return DiscrepancyOptions(**kw)


def data_from_folder(path: str | Path) -> MeasuredData:
    """Observables from a measured-data folder: ``phasors.csv`` (the rig campaign's 1x table,
    or a user's in the same columns) and the channels' positions from ``channels.json``
    (``{name: [position_mm, direction]}``) or else from the first native record of
    ``dataset/records``."""
    root = Path(path)
    table = root / "phasors.csv"
    if not table.is_file():
        raise ValueError(f"data folder {str(root)!r}: no phasors.csv (the 1x phasor table)")
    sidecar = root / "channels.json"
    if sidecar.is_file():
        pos = {k: (float(v[0]), str(v[1])) for k, v in json.loads(sidecar.read_text()).items()}
    else:
        recs = sorted((root / "dataset" / "records").glob("*.npz"))
        if not recs:
            raise ValueError(f"data folder {str(root)!r}: neither channels.json nor "
                             "dataset/records/*.npz to read the channels' positions from")
        pos = channel_positions(recs[0])
    return MeasuredData((phasor_block(read_phasor_table(table), pos),),
                        provenance={"source": str(root)})


def analyse(data: MeasuredData, geometry: SpindleGeometry, effects: tuple[Effect, ...], *,
            spindle_section: Mapping[str, Any], options: DiscrepancyOptions,
            rng: np.random.Generator, out_dir: str | Path
            ) -> tuple[DiscrepancyResult, dict[str, Path]]:
    """Run the workflow and write its files (``findings.json``, ``spindle_updated.toml``,
    ``candidates.csv``, ``curves.csv``) into ``out_dir``."""
    rng = require_rng(rng)
    result = find_discrepancy(data, geometry, effects, options=options, rng=rng)
    paths = write_run(result, out_dir, spindle_section=spindle_section, model_effects=effects)
    return result, paths
