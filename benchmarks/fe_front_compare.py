"""Surrogate study vs FE-in-the-loop study: both fronts judged by the FE model on fresh θ.

Run:  OMP_NUM_THREADS=1 python benchmarks/fe_front_compare.py SURROGATE_RUN FE_RUN
      [--n-theta 1000] [--max-points 300] [--seed 5]

Takes two ``study`` run folders of the same problem (the same config apart from
``[surrogate]``, e.g. ``results/paper/<id>`` and ``results/rated_speed/<id>``). For every front
of both (``pareto_fronts.csv``; at most ``--max-points`` distinct designs per front, evenly
spread along μ) it evaluates the designs with the FE model on ONE fresh θ sample
(``--n-theta``, not the optimiser's CRN sample, so neither study is flattered by the sample it
optimised on), keeps those with FE ``P_f <= P_target``, and prints per front: the designs, how
many stay feasible, the FE non-dominated count, the FE μ and σ ranges, and the hypervolume of
the FE-evaluated front (pymoo's ``HV``, minimisation of (μ, σ) in µm, one reference point per
front: 1.1 × the worst μ and σ of the two fronts), with the ratio surrogate / FE-in-the-loop.
The FE model at one speed is solved by exact condensation (``method="condensed"``, ~3.5 ms per
design for 1 000 θ); the peak response uses the direct solver (slow: use a small
``--max-points``).
"""

from __future__ import annotations

import argparse
import csv
import json
import os
from pathlib import Path

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import numpy as np  # noqa: E402
from pymoo.indicators.hv import HV  # noqa: E402

from surrogate_rbrdo.optimization.pareto import nondominated  # noqa: E402
from surrogate_rbrdo.runner.config import (  # noqa: E402
    limit_from_config,
    response_from_config,
    spindle_from_config,
    uncertainty_from_config,
)


def fronts(run: Path, max_points: int) -> dict[str, tuple[float, np.ndarray]]:
    """``{front label: (P_target, designs (n, 3))}``, distinct designs spread along μ."""
    rows: dict[str, list] = {}
    pt: dict[str, float] = {}
    with (run / "pareto_fronts.csv").open() as fh:
        for r in csv.DictReader(fh):
            rows.setdefault(r["run"], []).append(
                (float(r["mean_um"]), float(r["preload_N"]), float(r["span_mm"]),
                 float(r["diameter_mm"])))
            pt[r["run"]] = float(r["p_target_pct"]) / 100.0
    out = {}
    for lab, v in rows.items():
        a = np.unique(np.array(v), axis=0)               # distinct, sorted by μ
        idx = np.unique(np.linspace(0, len(a) - 1, min(max_points, len(a))).round().astype(int))
        out[lab] = (pt[lab], a[idx, 1:])
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("surrogate_run", type=Path)
    ap.add_argument("fe_run", type=Path)
    ap.add_argument("--n-theta", type=int, default=1000)
    ap.add_argument("--max-points", type=int, default=300)
    ap.add_argument("--seed", type=int, default=5)
    a = ap.parse_args()
    cfg = json.loads((a.fe_run / "config.json").read_text())
    sp = spindle_from_config(cfg.get("spindle", {}))
    inputs = uncertainty_from_config(cfg.get("uncertainty", {}), sp.theta_bearings)
    dlim = limit_from_config(cfg.get("limit", {})).threshold
    resp = response_from_config(cfg.get("response", {}))
    fe = (resp.fe_response(sp, "condensed") if resp.kind == "at_speed"
          else resp.fe_response(sp))
    theta = inputs.sample(a.n_theta, rng=np.random.default_rng(a.seed))
    print(f"y = {resp.label}, delta_lim = {dlim * 1e6:g} µm; FE on {a.n_theta} fresh θ "
          f"(seed {a.seed}); surrogate run {a.surrogate_run}, FE-in-the-loop run {a.fe_run}")
    fs, ff = fronts(a.surrogate_run, a.max_points), fronts(a.fe_run, a.max_points)
    for lab in [k for k in ff if k in fs]:
        p_t = ff[lab][0]
        res = {}
        for who, (_, X) in (("surrogate", fs[lab]), ("FE loop", ff[lab])):
            y = fe(X, theta) * 1e6
            mu, sd = y.mean(axis=1), y.std(axis=1, ddof=1)
            pf = np.mean(y > dlim * 1e6, axis=1)
            ok = pf <= p_t if lab.startswith("rbrdo") else np.ones(len(X), bool)
            F = np.column_stack([mu, sd])[ok]
            res[who] = (len(X), int(ok.sum()), F[nondominated(F)] if len(F) else F)
        both = np.vstack([r[2] for r in res.values() if len(r[2])])
        ref = 1.1 * both.max(axis=0)
        hv = {w: (HV(ref_point=ref)(r[2]) if len(r[2]) else 0.0) for w, r in res.items()}
        print(f"\n{lab} (P_target {p_t:.0%}; reference point μ {ref[0]:.4f}, σ {ref[1]:.4f} µm)")
        for w, (n, nok, F) in res.items():
            rng_txt = (f"μ {F[:, 0].min():.4f}–{F[:, 0].max():.4f}, "
                       f"σ {F[:, 1].min():.4f}–{F[:, 1].max():.4f} µm") if len(F) else "-"
            print(f"  {w:9s}: {n:4d} designs, {nok:4d} FE-feasible, {len(F):4d} FE "
                  f"non-dominated, {rng_txt}, HV {hv[w]:.6f}")
        print(f"  HV surrogate / FE loop = {hv['surrogate'] / hv['FE loop']:.4f}")


if __name__ == "__main__":
    main()
