"""The run folder of a discrepancy analysis: ``findings.json``, the updated spindle description,
tables and figures.

Files (:func:`write_run`); the figures are drawn by
:func:`surrogate_rbrdo.reporting.plots_discrepancy.plot_all`.

``findings.json`` (:func:`findings`) holds at least what the issue fixes — ``verdict``,
``effects`` (``name``, ``parameters``, ``ci``, ``identified``: those of the final joint
fit, exactly what ``spindle_updated.toml`` carries; ``ci`` is ``null`` for a parameter the data
cannot tell from off), ``updated_effects`` (every effect the spindle adds),
``confounded_with``, ``confounded_generic`` (a confounded set's generic local changes: a library
effect the data cannot tell from, e.g., a passive spring beside its bearing), ``test``
(``statistic``, ``p_value``, ``threshold``)
and ``gap`` (``before``/``after`` with ``rmse``, ``max_abs`` in µm and
``chi2_dof`` on held-out speeds) — plus the residual tests, the ranking of every candidate, the
recalibrated nuisance, the held-out split and the options. Infinite values (a rigid interface, an
open interval) are written as ``null``.

``spindle_updated.toml`` (:func:`updated_spindle`) is a ``[spindle]`` table a study loads: the
model's own effects plus the named ones with their fitted parameters (for *confounded*, the
best-fitting member, marked in a comment).
"""

from __future__ import annotations

import csv
import json
import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from surrogate_rbrdo.discrepancy.search import slot_estimate
from surrogate_rbrdo.discrepancy.workflow import DiscrepancyResult
from surrogate_rbrdo.spindle.effects import Effect


def _clean(v: Any) -> Any:
    """JSON-safe: numpy scalars to Python, non-finite floats to None, tuples to lists."""
    if isinstance(v, Mapping):
        return {str(k): _clean(x) for k, x in v.items()}
    if isinstance(v, (list, tuple, np.ndarray)):
        return [_clean(x) for x in v]
    if isinstance(v, (np.floating, float)):
        return float(v) if math.isfinite(float(v)) else None
    if isinstance(v, (np.integer,)):
        return int(v)
    if isinstance(v, (np.bool_, bool)):
        return bool(v)
    return v


def findings(result: DiscrepancyResult) -> dict[str, Any]:
    """The machine-readable answer (module doc)."""
    out = {
        "verdict": result.verdict,
        "effects": _effects(result),
        "updated_effects": [{"name": n, "parameters": e.parameters, "ci": e.ci,
                             "identified": e.identified} for n, e in result.fitted_effects],
        "confounded_with": list(result.confounded_with),
        "confounded_generic": list(result.confounded_generic),
        "separating_test": result.separating,
        "test": result.test,
        "residual_test": result.residual_test,
        "partial_library_fit": list(result.partial),
        "soak": [t.to_dict() for t in result.soak],
        "gap": {"before": result.gap_before.to_dict(), "after": result.gap_after.to_dict(),
                "units": {"rmse": "um", "max_abs": "um", "chi2_dof": "1",
                          "predictive_chi2_dof": "1"},
                "on": "held-out speeds (interleaved and extrapolated), parameters and "
                      "unbalance fitted on training speeds",
                "per_channel": {"before": result.gap_before.per_channel,
                                "after": result.gap_after.per_channel},
                "gp_correction": result.verdict == "unnamed_residual"},
        "candidates": [[a.to_dict() for a in st.assessments] for st in result.stages],
        "absorbed_by_recalibration": list(result.stages[0].absorbed),
        "recalibration": result.recalibration(result.base),
        "run_scatter_log_stiffness": list(result.run_scatter),
        "dropped_impact_blocks": [{"name": n, "dof": d} for n, d in result.dropped_blocks],
        "split_speeds_rpm": result.split.to_dict(result.speeds_rpm),
        "chi2_dof_by_observable": {c.name: {"before": c.chi2_table("before"),
                                            "after": c.chi2_table("after")}
                                   for c in result.curves},
        "options": {"library": list(result.options.library), "alpha": result.options.alpha,
                    "alpha_residual": result.options.alpha_residual,
                    "n_draws": result.options.n_draws,
                    "confound_delta": result.options.confound_delta,
                    "holdout_tolerance": result.options.holdout_tolerance,
                    "generic_confound": result.options.generic_confound},
        "seconds": result.seconds,
    }
    return _clean(out)


def _effects(result: DiscrepancyResult) -> list[dict[str, Any]]:
    """The named (or confounded) effects. A named effect's parameters are those of the final
    joint fit (what ``spindle_updated.toml`` carries; an effect named in an early stage is
    refitted with those named after it, ``parameters_when_named`` keeps its stage fit); a
    confounded member's are its own fit (the alternatives are separate models)."""
    fitted = dict(result.fitted_effects) if result.verdict == "named" else {}
    out = []
    for a in result.effects:
        e = fitted.get(a.name) or slot_estimate(a.fit.fit, len(a.fit.fit.par.slots) - 1)
        d = {"name": a.name, "parameters": e.parameters, "ci": e.ci,
             "identified": e.identified,
             "test": {"statistic": a.delta_chi2, "p_value": a.p_adjusted,
                      "threshold": result.options.alpha}}
        if a.name in fitted:
            d["parameters_when_named"] = a.fit.parameters
        out.append(d)
    return out


def effect_dict(e: Effect) -> dict[str, Any]:
    """``{"name": ..., <parameters>}`` of an effect (the ``[spindle] effects`` form)."""
    d: dict[str, Any] = {"name": e.name}
    for k, v in e.params().items():
        if isinstance(v, tuple):
            if v:
                d[k] = list(v)
        else:
            d[k] = v
    return d


def updated_spindle(section: Mapping[str, Any], model_effects: Sequence[Effect],
                    result: DiscrepancyResult) -> dict[str, Any]:
    """The ``[spindle]`` table with the named effects added to the model's own."""
    out = {k: v for k, v in section.items() if k != "effects"}
    out["effects"] = ([effect_dict(e) for e in model_effects if not e.is_off]
                      + [effect_dict(e) for e in result.named_effects])
    return out


def _toml_value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    if isinstance(v, (float, np.floating)):
        v = float(v)
        return repr(v) if math.isfinite(v) else ("inf" if v > 0 else "-inf")
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, Mapping):
        return "{ " + ", ".join(f"{k} = {_toml_value(x)}" for k, x in v.items()) + " }"
    return "[" + ", ".join(_toml_value(x) for x in v) + "]"


def toml_table(name: str, table: Mapping[str, Any], comment: str = "") -> str:
    """A flat TOML table (values: numbers, strings, lists, inline tables).

    >>> print(toml_table("spindle", {"geometry": "reference", "effects": [{"name": "x",
    ...                                                                   "a": 0.5}]}))
    [spindle]
    geometry = "reference"
    effects = [{ name = "x", a = 0.5 }]
    <BLANKLINE>
    """
    lines = [f"# {c}" for c in comment.splitlines()] + [f"[{name}]"]
    lines += [f"{k} = {_toml_value(v)}" for k, v in table.items()]
    return "\n".join(lines) + "\n"


def write_run(result: DiscrepancyResult, out_dir: str | Path, *,
              spindle_section: Mapping[str, Any], model_effects: Sequence[Effect]
              ) -> dict[str, Path]:
    """Write ``findings.json``, ``spindle_updated.toml``, ``candidates.csv`` and ``curves.csv``
    into ``out_dir``; returns the paths (figures:
    :func:`surrogate_rbrdo.reporting.plots_discrepancy.plot_all`)."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = {"findings": out / "findings.json", "spindle": out / "spindle_updated.toml",
             "candidates": out / "candidates.csv", "curves": out / "curves.csv"}
    paths["findings"].write_text(json.dumps(findings(result), indent=2))
    note = {"named": "named effects added with their fitted parameters",
            "confounded": f"confounded set {list(result.confounded_with)}"
                          + (f" with the generic local change(s) {list(result.confounded_generic)}"
                             if result.confounded_generic else "")
                          + ": the best-fitting member is added for prediction; the data "
                            "cannot tell which",
            "nothing_missing": "nothing missing: the model's own effects",
            "unnamed_residual": "unnamed residual: no library effect explains it; the model "
                                "is unchanged (the GP correction is for prediction only)"}
    paths["spindle"].write_text(toml_table(
        "spindle", updated_spindle(spindle_section, model_effects, result),
        "Updated by the discrepancy workflow: " + note[result.verdict]))
    _write_candidates(result, paths["candidates"])
    _write_curves(result, paths["curves"])
    return paths


def _write_candidates(result: DiscrepancyResult, path: Path) -> None:
    with path.open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["stage", "candidate", "delta_chi2", "p_raw", "p_adjusted", "passed",
                    "likelihood_ratio", "significant", "physical", "holdout",
                    "gain_interleaved", "gain_extrapolated", "parameters"])
        for i, st in enumerate(result.stages):
            for a in st.assessments:
                c = a.checks
                w.writerow([i, a.name, a.delta_chi2, a.p_raw, a.p_adjusted, a.passed,
                            c.get("likelihood_ratio"), c.get("significant"), c.get("physical"),
                            c.get("holdout"), a.holdout_gain.get("interleaved"),
                            a.holdout_gain.get("extrapolated"),
                            json.dumps(_clean(a.fit.parameters)) if a.fit else ""])


def _write_curves(result: DiscrepancyResult, path: Path) -> None:
    with path.open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["block", "coord", "channel", "held_out", "data_re_um", "data_im_um",
                    "se_um", "before_re_um", "before_im_um", "after_re_um", "after_im_um",
                    "white_before_re", "white_before_im", "white_after_re", "white_after_im"])
        for c in result.curves:
            for i, x in enumerate(c.coord):
                for j, ch in enumerate(c.channels):
                    d, b, a = c.data[i, j] * 1e6, c.before[i, j] * 1e6, c.after[i, j] * 1e6
                    w.writerow([c.name, x, ch, bool(c.held_out[i]), d.real, d.imag,
                                c.se[i, j] * 1e6, b.real, b.imag, a.real, a.imag,
                                *c.white_before[i, j], *c.white_after[i, j]])
