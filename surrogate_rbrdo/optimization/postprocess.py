"""Post-processing: archive fronts, ASF compromise, MBR table, strategy table, CSV output.

Responses are in SI (metres); tables convert with ``scale`` (default 1e6 → μm) and name the
unit in the column (``mean_um``). P_f and P_target are written in percent (``pf_pct``).

MBR (marginal benefit ratio) follows paper-notes §3.9: ``MBR = |Δσ_y| / |ΔP_target|`` in μm per
percentage point between consecutive P_target levels (the paper's text defines it on Δμ_y, but
its Table 6 numbers are Δσ_y); Δμ_y is reported alongside.

>>> rows = mbr_table([(0.10, 15.02e-6, 12.42e-6), (0.05, 16.44e-6, 9.69e-6),
...                   (0.01, 17.25e-6, 8.15e-6)])
>>> [(r["from_pct"], r["to_pct"], round(r["mbr_um_per_pp"], 3)) for r in rows]
[(10.0, 5.0, 0.546), (5.0, 1.0, 0.385)]
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from surrogate_rbrdo.core.files import atomic_write_text, rows_text
from surrogate_rbrdo.optimization.pareto import asf_compromise, feasible_pareto
from surrogate_rbrdo.optimization.result import OptimizationResult


def archive_front(result: OptimizationResult) -> np.ndarray:
    """Indices into ``result.archive`` of the feasible non-dominated designs of the whole run,
    sorted by the first objective."""
    arch = result.archive
    idx = np.flatnonzero(feasible_pareto(arch.F, arch.G))
    return idx[np.argsort(arch.F[idx, 0], kind="stable")]


@dataclass(frozen=True, eq=False)
class Compromise:
    """The ASF compromise design of one run (``index`` into the archive)."""

    index: int
    x: np.ndarray
    F: np.ndarray
    G: np.ndarray
    mean: float
    std: float
    pf: float

    def to_dict(self) -> dict[str, Any]:
        return {"index": self.index, "x": self.x.tolist(), "F": self.F.tolist(),
                "G": self.G.tolist(), "mean": self.mean, "std": self.std, "pf": self.pf}


def select_compromise(result: OptimizationResult, weights: Sequence[float] | None = None
                      ) -> Compromise:
    """ASF compromise on the archive's feasible front (weights default to equal, 0.5/0.5).

    A single-objective run returns its best feasible design. Raises ``ValueError`` when no
    evaluated design is feasible.
    """
    idx = archive_front(result)
    if idx.size == 0:
        raise ValueError("no feasible design in the archive: cannot pick a compromise")
    arch = result.archive
    n_obj = arch.F.shape[1]
    w = tuple(weights) if weights is not None else (1.0 / n_obj,) * n_obj
    k = int(idx[asf_compromise(arch.F[idx], w)])
    return Compromise(index=k, x=arch.X[k].copy(), F=arch.F[k].copy(), G=arch.G[k].copy(),
                      mean=float(arch.mean[k]), std=float(arch.std[k]), pf=float(arch.pf[k]))


def mbr_table(levels: Iterable[tuple[float, float, float]], *, scale: float = 1e6,
              unit: str = "um") -> list[dict[str, float]]:
    """Marginal benefit ratios between consecutive P_target levels.

    Parameters
    ----------
    levels : iterable of (p_target, mean, std)
        One compromise design per level (fractions and SI units); sorted here from the loosest
        to the tightest target.
    scale, unit : float, str
        Output scaling of μ and σ and its unit name.

    Returns
    -------
    list of dict
        ``from_pct, to_pct, delta_mean_<unit>`` (signed, tighter − looser),
        ``delta_std_<unit>`` (signed), ``mbr_<unit>_per_pp = |Δσ| / |ΔP_target|`` and
        ``mbr_mean_<unit>_per_pp = |Δμ| / |ΔP_target|``.
    """
    lv = sorted(((float(p), float(m), float(s)) for p, m, s in levels), reverse=True)
    if len(lv) < 2:
        raise ValueError(f"need at least two P_target levels for an MBR table, got {len(lv)}")
    if len({p for p, _, _ in lv}) != len(lv):
        raise ValueError(f"P_target levels {[p for p, _, _ in lv]} contain duplicates")
    out = []
    for (p0, m0, s0), (p1, m1, s1) in zip(lv[:-1], lv[1:], strict=True):
        dpp = abs(p0 - p1) * 100.0
        dm, ds = (m1 - m0) * scale, (s1 - s0) * scale
        out.append({"from_pct": p0 * 100.0, "to_pct": p1 * 100.0,
                    f"delta_mean_{unit}": dm, f"delta_std_{unit}": ds,
                    f"mbr_{unit}_per_pp": abs(ds) / dpp,
                    f"mbr_mean_{unit}_per_pp": abs(dm) / dpp})
    return out


def strategy_table(entries: Mapping[str, Mapping[str, Any]], *,
                   design_names: Sequence[str] | None = None, scale: float = 1e6,
                   unit: str = "um") -> list[dict[str, Any]]:
    """One row per strategy: design vector, μ, σ, P_f (and P_target when given).

    Parameters
    ----------
    entries : mapping label -> {"x", "mean", "std", "pf", optional "p_target", "G",
        "constraint_names"}
        Evaluate all strategies' designs on the same θ sample (``Formulation.assess`` of any
        formulation built from the same generator state) for a like-for-like comparison.

    >>> strategy_table({"rdo": {"x": [1.0, 2.0], "mean": 15e-6, "std": 8e-6, "pf": 0.2}},
    ...                design_names=["a", "b"])[0]
    {'strategy': 'rdo', 'a': 1.0, 'b': 2.0, 'mean_um': 15.0, 'std_um': 8.0, 'pf_pct': 20.0}
    """
    rows = []
    for label, e in entries.items():
        x = np.atleast_1d(np.asarray(e["x"], dtype=float))
        names = list(design_names) if design_names is not None else [
            f"x{i}" for i in range(x.size)]
        if len(names) != x.size:
            raise ValueError(f"design_names has {len(names)} names for {x.size} variables")
        row: dict[str, Any] = {"strategy": label}
        row.update({n: float(v) for n, v in zip(names, x, strict=True)})
        row[f"mean_{unit}"] = float(e["mean"]) * scale
        row[f"std_{unit}"] = float(e["std"]) * scale
        row["pf_pct"] = float(e["pf"]) * 100.0
        if e.get("p_target") is not None:
            row["p_target_pct"] = float(e["p_target"]) * 100.0
        if e.get("G") is not None:
            g = np.atleast_1d(np.asarray(e["G"], dtype=float))
            cn = e.get("constraint_names") or [f"g{i}" for i in range(g.size)]
            row.update({f"g_{n}": float(v) for n, v in zip(cn, g, strict=True)})
        rows.append(row)
    return rows


def front_table(result: OptimizationResult, *, design_names: Sequence[str] | None = None,
                scale: float = 1e6, unit: str = "um") -> list[dict[str, Any]]:
    """The archive's feasible front as rows (design, μ, σ, P_f, generation)."""
    arch = result.archive
    rows = strategy_table(
        {str(i): {"x": arch.X[i], "mean": arch.mean[i], "std": arch.std[i], "pf": arch.pf[i]}
         for i in archive_front(result)}, design_names=design_names, scale=scale, unit=unit)
    for r in rows:
        i = int(r.pop("strategy"))
        r["archive_index"] = i
        r["generation"] = int(arch.generation[i])
    return rows


def write_csv(path: str | os.PathLike, rows: Sequence[Mapping[str, Any]],
              columns: Sequence[str] | None = None) -> Path:
    """Write ``rows`` to ``path`` through the toolkit's one atomic writer
    (``core.files.atomic_write_text``: a temporary file in the same folder, mode 0644, then
    ``os.replace``). Columns default to the union of keys in first-seen order."""
    return atomic_write_text(path, rows_text(rows, columns))
