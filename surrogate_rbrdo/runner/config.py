"""Experiment configs (TOML): reading, validation, and the spindle they describe.

A config has an ``[experiment]`` table (``name``, ``kind``, optional ``seed`` and
``results_dir``) and one table per part the kind needs. Unknown keys raise, naming the table.
"""

from __future__ import annotations

import tomllib
from collections.abc import Mapping
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from surrogate_rbrdo.core.validate import check_int, check_keys, check_positive
from surrogate_rbrdo.spindle.effects import effect_from_dict
from surrogate_rbrdo.spindle.geometry import DesignMap, SpindleGeometry
from surrogate_rbrdo.spindle.reference import ReferenceSpindle, reference_spindle

EXPERIMENT_KEYS = {"name", "kind", "seed", "results_dir", "description"}


def load_config(path: str | Path) -> dict[str, Any]:
    """Read a TOML experiment config; the file's folder is stored as ``_base_dir``."""
    path = Path(path)
    if not path.is_file():
        raise ValueError(f"config file {str(path)!r} does not exist")
    try:
        cfg = tomllib.loads(path.read_text())
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"config file {str(path)!r} is not valid TOML: {exc}") from None
    exp = cfg.get("experiment")
    if not isinstance(exp, Mapping):
        raise ValueError(f"config {str(path)!r}: missing [experiment] table with name and kind")
    check_keys("[experiment]", exp, EXPERIMENT_KEYS)
    for key in ("name", "kind"):
        if not isinstance(exp.get(key), str) or not exp[key]:
            raise ValueError(f"experiment.{key} = {exp.get(key)!r} is not allowed: "
                             "must be a non-empty string")
    if "seed" in exp:
        check_int("experiment.seed", exp["seed"], minimum=0)
    cfg["_base_dir"] = str(path.parent.resolve())
    return cfg


SPINDLE_KEYS = {"geometry", "balance_grade_mm_s", "effects", "design_map", "baseline",
                "theta_bearings"}


def spindle_from_config(section: Mapping[str, Any], base_dir: str | Path = ".") -> ReferenceSpindle:
    """The spindle of a ``[spindle]`` table.

    ``geometry = "reference"`` (default) is the reference spindle; otherwise a path (relative
    to the config) to a TOML/JSON geometry. ``effects`` (a list of ``{name = ..., params}``)
    replaces the default effects; ``design_map`` and ``baseline`` override those parts.
    """
    check_keys("[spindle]", section, SPINDLE_KEYS)
    geo = section.get("geometry", "reference")
    if geo == "reference":
        grade = check_positive("spindle.balance_grade_mm_s",
                               section.get("balance_grade_mm_s", 2.5))
        sp = reference_spindle(balance_grade_mm_s=grade)
    else:
        if "balance_grade_mm_s" in section:
            raise ValueError("spindle.balance_grade_mm_s applies only to geometry = 'reference'; "
                             "give the unbalances in the geometry file")
        p = Path(geo)
        p = p if p.is_absolute() else Path(base_dir) / p
        geometry = SpindleGeometry.load(p)
        sp = ReferenceSpindle(geometry, (), DesignMap(), np.array(DesignMap().lower))
        sp = replace(sp, baseline=np.mean(sp.design_map.bounds, axis=1))
    if "effects" in section:
        sp = replace(sp, effects=tuple(effect_from_dict(e) for e in section["effects"]))
    if "design_map" in section:
        dm = dict(section["design_map"])
        check_keys("[spindle.design_map]", dm, {"preload_bearing", "span_tag", "lower", "upper"})
        for k in ("lower", "upper"):
            if k in dm:
                dm[k] = tuple(float(v) for v in dm[k])
        sp = replace(sp, design_map=DesignMap(**dm))
    if "baseline" in section:
        sp = replace(sp, baseline=sp.design_map.check(np.asarray(section["baseline"], float)))
    if "theta_bearings" in section:
        sp = replace(sp, theta_bearings=tuple(section["theta_bearings"]))
    # the design box: every check of DesignMap.apply (preload > 0, diameter > bore) is monotone
    # in its variable, so the two corners stand for the whole box
    dmap = sp.design_map
    for name, corner in (("lower", dmap.lower), ("upper", dmap.upper)):
        try:
            sp.geometry_for(np.asarray(corner, dtype=float))
        except ValueError as exc:
            raise ValueError(f"[spindle.design_map] {name} = {list(corner)}: {exc}") from exc
    sp.model(np.asarray(dmap.lower, dtype=float))     # effects and theta_bearings, checked
    return sp


UNCERTAINTY_KEYS = {"mean", "std", "corr"}
#: Table 4 pooled CoVs of k_yy (front, rear): the default scatter of the stiffness factors
TABLE4_STD = (0.0605, 0.0641)


def uncertainty_from_config(table: Mapping[str, Any], theta_bearings: tuple[str, ...]):
    """θ ~ MVN(mean, std, corr) from an ``[uncertainty]`` table, one entry per bearing of θ.

    Defaults: mean 1 and the Table 4 CoVs (docs/reference-spindle.md). Shapes, positivity and
    unknown keys are checked with messages naming the field.
    """
    from surrogate_rbrdo.uncertainty import MultivariateNormal

    table = dict(table)
    check_keys("[uncertainty]", table, UNCERTAINTY_KEYS)
    m = len(theta_bearings)
    mean = np.asarray(table.get("mean", [1.0] * m), dtype=float)
    std = np.asarray(table.get("std", TABLE4_STD[:m]), dtype=float)
    if mean.shape != (m,) or std.shape != (m,):
        raise ValueError(f"uncertainty.mean/std have shapes {mean.shape}/{std.shape}: need "
                         f"({m},) for bearings {list(theta_bearings)}")
    for i, s in enumerate(std):
        check_positive(f"uncertainty.std[{i}]", float(s))
    corr = table.get("corr")
    return MultivariateNormal(mean, std=std, corr=None if corr is None else np.asarray(corr))


LIMIT_KEYS = {"delta_lim_um"}


def limit_from_config(table: Mapping[str, Any]):
    """The limit state ``y > δ_lim`` from a ``[limit]`` table (``delta_lim_um``, default 19.5,
    paper-notes §3.3).

    >>> round(limit_from_config({"delta_lim_um": 20.0}).threshold * 1e6, 9)
    20.0
    """
    from surrogate_rbrdo.core.protocols import LimitState

    table = dict(table)
    check_keys("[limit]", table, LIMIT_KEYS)
    return LimitState(check_positive("limit.delta_lim_um", table.get("delta_lim_um", 19.5))
                      * 1e-6)


RESPONSE_KEYS = {"kind", "speed_rpm"}


def response_from_config(table: Mapping[str, Any]):
    """What ``y`` is, from a ``[response]`` table: ``kind = "peak"`` (default, the peak
    tool-tip amplitude over the speed range) or ``"at_speed"`` with ``speed_rpm``.

    >>> response_from_config({"kind": "at_speed", "speed_rpm": 24000}).label
    'amplitude at 24000 rpm'
    >>> response_from_config({}).kind
    'peak'
    """
    from surrogate_rbrdo.spindle.evaluate import ResponseSpec

    table = dict(table)
    check_keys("[response]", table, RESPONSE_KEYS)
    return ResponseSpec(**table)
