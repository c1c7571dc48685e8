"""The ``[rig]`` table of an experiment config → a truth and campaign options.

Everything has a documented default (``docs/rig.md``); the truth's hidden effects are given
as ``effects = [{ name = "<registry name>", <parameters> }, ...]``, the same form as
``[spindle] effects``. Unknown keys raise a ``ValueError`` naming the table.

>>> cfg = rig_config_from_dict({"effects": [{"name": "cross_coupling", "kappa": 0.05}],
...                             "campaign": {"repeats": 2}})
>>> [e.name for e in cfg.truth.hidden], cfg.options.repeats, len(cfg.options.speeds_rpm)
(['cross_coupling'], 2, 50)
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from surrogate_rbrdo.core.validate import check_keys
from surrogate_rbrdo.rig.campaign import CampaignOptions
from surrogate_rbrdo.rig.sensors import (
    DAQModel,
    HammerModel,
    KeyphasorModel,
    ProbeModel,
    SensorSet,
)
from surrogate_rbrdo.rig.truth import Truth, Variability, reference_truth

SENSOR_PARTS = {"probe": ProbeModel, "daq": DAQModel, "keyphasor": KeyphasorModel,
                "hammer": HammerModel}


@dataclass(frozen=True)
class RigConfig:
    """A parsed ``[rig]`` table: the truth, the campaign options and whether to draw figures."""

    truth: Truth
    options: CampaignOptions
    figures: bool = True


def _build(cls: type, data: Mapping[str, Any], where: str) -> Any:
    check_keys(where, data, {f.name for f in dataclasses.fields(cls)})
    kw = {k: tuple(v) if isinstance(v, list) else v for k, v in data.items()}
    return cls(**kw)


def rig_config_from_dict(data: Mapping[str, Any]) -> RigConfig:
    """Parse ``{"effects": [...], "design": [F, L, D], "variability": {...},
    "sensors": {"probe": {...}, "daq": {...}, "keyphasor": {...}, "hammer": {...},
    "targets": [...], "noise": true}, "campaign": {...}, "figures": true}``."""
    check_keys("rig", data, {"effects", "design", "variability", "sensors", "campaign",
                             "figures"})
    var = _build(Variability, data.get("variability", {}), "rig.variability")
    sdata = dict(data.get("sensors", {}))
    check_keys("rig.sensors", sdata, set(SENSOR_PARTS) | {"targets", "noise"})
    parts = {k: _build(cls, sdata.get(k, {}), f"rig.sensors.{k}")
             for k, cls in SENSOR_PARTS.items()}
    sensors = SensorSet(**parts, targets=tuple(sdata.get("targets", ("front", "rear", "tool"))),
                        noise=bool(sdata.get("noise", True)))
    camp = dict(data.get("campaign", {}))
    check_keys("rig.campaign", camp, {f.name for f in dataclasses.fields(CampaignOptions)}
               - {"sensors"})
    if "speeds_rpm" in camp and isinstance(camp["speeds_rpm"], Mapping):
        sp = camp["speeds_rpm"]
        check_keys("rig.campaign.speeds_rpm", sp, {"start", "stop", "num"})
        camp["speeds_rpm"] = tuple(np.linspace(sp["start"], sp["stop"], sp["num"]).tolist())
    options = _build(CampaignOptions, {**camp}, "rig.campaign")
    options = dataclasses.replace(options, sensors=sensors)
    design = data.get("design")
    truth = reference_truth(hidden=[dict(e) for e in data.get("effects", [])],
                            variability=var,
                            x=None if design is None else np.asarray(design, float))
    return RigConfig(truth, options, bool(data.get("figures", True)))
