"""Surrogate study vs FE-in-the-loop study: both fronts judged by the FE model on fresh θ.

Run:  OMP_NUM_THREADS=1 python benchmarks/fe_front_compare.py SURROGATE_RUN FE_RUN
      [--n-theta 1000] [--max-points 1000] [--seed 5]

Takes two ``study`` run folders of the same problem (configs equal apart from ``[experiment]``
and ``[surrogate]``, checked; e.g. ``results/paper/<id>`` and ``results/rated_speed/<id>``).
For every front of both (``pareto_fronts.csv``; its distinct designs, thinned to every k-th in
μ order when there are more than ``--max-points``) it evaluates the designs with the FE model
on ONE fresh θ sample (``--n-theta``, not the optimiser's CRN sample, so neither study is
flattered by the sample it optimised on), keeps those with FE ``P_f <= P_target`` (RBRDO
fronts) and their FE non-dominated set, and prints per front:

* the designs, how many stay feasible, the FE μ and σ ranges;
* the multiplicative ε-indicator both ways, ``ε(A, B) = max_b min_a max_i a_i / b_i``: the
  factor by which front A must be scaled to weakly dominate every point of B (1 = A covers B;
  no reference point needed);
* the hypervolume ratio surrogate / FE loop (pymoo's ``HV``, minimisation of (μ, σ) in µm) at
  two reference points, 1.1× and 1.5× the worst μ and σ of the two fronts: on fronts whose σ
  spans only a few hundredths of a µm the ratio depends strongly on the reference point.

The FE model at one speed is solved by exact condensation (``method="condensed"``, ~3.5 ms per
design for 1 000 θ); the peak response uses the direct solver (slow: use a small
``--max-points``). A relative geometry path in the config resolves from the working directory.
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
    """``{front label: (P_target, designs (n, 3))}``: distinct designs, every k-th in μ order."""
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


def eps_mult(A: np.ndarray, B: np.ndarray) -> float:
    """Multiplicative ε-indicator ``max_b min_a max_i a_i / b_i`` (positive objectives)."""
    return float(np.max(np.min(np.max(A[:, None, :] / B[None, :, :], axis=2), axis=0)))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("surrogate_run", type=Path)
    ap.add_argument("fe_run", type=Path)
    ap.add_argument("--n-theta", type=int, default=1000)
    ap.add_argument("--max-points", type=int, default=1000)
    ap.add_argument("--seed", type=int, default=5)
    a = ap.parse_args()
    cfg = json.loads((a.fe_run / "config.json").read_text())
    cfg_s = json.loads((a.surrogate_run / "config.json").read_text())
    differ = sorted(k for k in set(cfg) | set(cfg_s)
                    if k not in ("experiment", "surrogate") and cfg.get(k) != cfg_s.get(k))
    if differ:
        raise SystemExit(f"the two runs' configs differ in {differ}: not the same problem")
    sp = spindle_from_config(cfg.get("spindle", {}))
    inputs = uncertainty_from_config(cfg.get("uncertainty", {}), sp.theta_bearings)
    limit = limit_from_config(cfg.get("limit", {}))
    resp = response_from_config(cfg.get("response", {}))
    fe = (resp.fe_response(sp, "condensed") if resp.kind == "at_speed"
          else resp.fe_response(sp))
    theta = inputs.sample(a.n_theta, rng=np.random.default_rng(a.seed))
    print(f"y = {resp.label}, delta_lim = {limit.threshold * 1e6:g} µm; FE on {a.n_theta} "
          f"fresh θ (seed {a.seed}); surrogate run {a.surrogate_run}, FE-in-the-loop run "
          f"{a.fe_run}")
    fs, ff = fronts(a.surrogate_run, a.max_points), fronts(a.fe_run, a.max_points)
    for lab in [k for k in ff if k in fs]:
        p_t = ff[lab][0]
        res = {}
        for who, (_, X) in (("surrogate", fs[lab]), ("FE loop", ff[lab])):
            y = fe(X, theta)
            mu, sd = y.mean(axis=1) * 1e6, y.std(axis=1, ddof=1) * 1e6
            pf = np.mean(limit.failed(y), axis=1)
            ok = pf <= p_t if lab.startswith("rbrdo") else np.ones(len(X), bool)
            F = np.column_stack([mu, sd])[ok]
            res[who] = (len(X), F[nondominated(F)] if len(F) else F)
        print(f"\n{lab} (P_target {p_t:.0%})")
        for w, (n, F) in res.items():
            rng_txt = (f"μ {F[:, 0].min():.4f}–{F[:, 0].max():.4f}, "
                       f"σ {F[:, 1].min():.4f}–{F[:, 1].max():.4f} µm") if len(F) else "-"
            print(f"  {w:9s}: {n:4d} designs, {len(F):4d} FE-feasible non-dominated, {rng_txt}")
        Fs, Ff = res["surrogate"][1], res["FE loop"][1]
        if not (len(Fs) and len(Ff)):
            print("  a front has no FE-feasible design: no indicator")
            continue
        print(f"  ε(surrogate covers FE loop) = {eps_mult(Fs, Ff):.4f}, "
              f"ε(FE loop covers surrogate) = {eps_mult(Ff, Fs):.4f}")
        worst = np.vstack([Fs, Ff]).max(axis=0)
        ratios = []
        for k in (1.1, 1.5):
            hv = HV(ref_point=k * worst)
            ratios.append(f"{hv(Fs) / hv(Ff):.4f} (ref {k}x worst)")
        print("  HV surrogate / FE loop = " + ", ".join(ratios))


if __name__ == "__main__":
    main()
