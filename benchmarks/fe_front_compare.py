"""Surrogate study vs FE-in-the-loop study: both fronts judged by the FE model on fresh θ.

Run:  OMP_NUM_THREADS=1 python benchmarks/fe_front_compare.py RUN RUN [RUN ...]
      [--n-theta 1000] [--max-points 1000] [--seed 5]

Takes two or more ``study`` run folders of the same problem (configs equal apart from
``[experiment]`` and ``[surrogate]``, checked): e.g. the surrogate study ``results/paper/<id>``
and the FE-in-the-loop study ``results/rated_speed/<id>``, and further seeds of each
(``rbrdo run ... --seed N``) to see the optimiser's run-to-run scatter. For every front of
each (``pareto_fronts.csv``; its distinct designs, thinned to every k-th in μ order when there
are more than ``--max-points``) it evaluates the designs with the FE model
on ONE fresh θ sample (``--n-theta``, not the optimiser's CRN sample, so neither study is
flattered by the sample it optimised on), keeps those with FE ``P_f <= P_target`` (RBRDO
fronts) and their FE non-dominated set, and prints per front:

* the designs, how many stay feasible, the FE μ and σ ranges;
* the multiplicative ε-indicator of every pair, ``ε(A, B) = max_b min_a max_i a_i / b_i``:
  the factor by which front A must be scaled to weakly dominate every point of B (1 = A covers
  B; no reference point needed);
* each front's hypervolume (pymoo's ``HV``, minimisation of (μ, σ) in µm) at two reference
  points, 1.1× and 1.5× the worst μ and σ of all fronts: on fronts whose σ spans only a few
  hundredths of a µm it depends strongly on the reference point.

The FE model at one speed is solved by exact condensation (``method="condensed"``, ~3.5–7 ms
per design for 1 000 θ); the peak response uses the direct solver (slow: use a small
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

from surrogate_rbrdo.core.schema import parse  # noqa: E402
from surrogate_rbrdo.optimization.pareto import nondominated  # noqa: E402
from surrogate_rbrdo.spindle.config import SpindleTable, build_spindle  # noqa: E402
from surrogate_rbrdo.spindle.evaluate import ResponseSpec  # noqa: E402
from surrogate_rbrdo.study.config import LimitTable, UncertaintyTable, build_inputs  # noqa: E402


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
    ap.add_argument("runs", type=Path, nargs="+",
                    help="two or more study run folders of the same problem")
    ap.add_argument("--n-theta", type=int, default=1000)
    ap.add_argument("--max-points", type=int, default=1000)
    ap.add_argument("--seed", type=int, default=5)
    a = ap.parse_args()
    if len(a.runs) < 2:
        raise SystemExit("give at least two run folders")
    cfgs = [json.loads((r / "config.json").read_text()) for r in a.runs]
    for r, c in zip(a.runs[1:], cfgs[1:], strict=True):
        differ = sorted(k for k in set(cfgs[0]) | set(c) if k not in ("experiment", "surrogate")
                        and cfgs[0].get(k) != c.get(k))
        if differ:
            raise SystemExit(f"{r}: its config differs from {a.runs[0]}'s in {differ}: not the "
                             "same problem")
    cfg = cfgs[0]
    sp = build_spindle(parse(SpindleTable, cfg.get("spindle", {}), "spindle"))
    inputs = build_inputs(parse(UncertaintyTable, cfg.get("uncertainty", {}), "uncertainty"),
                          sp.theta_bearings)
    limit = parse(LimitTable, cfg.get("limit", {}), "limit").limit()
    resp = parse(ResponseSpec, cfg.get("response", {}), "response")
    fe = (resp.fe_response(sp, "condensed") if resp.kind == "at_speed"
          else resp.fe_response(sp))
    theta = inputs.sample(a.n_theta, rng=np.random.default_rng(a.seed))
    names = []
    for r, c in zip(a.runs, cfgs, strict=True):
        structure = c.get("surrogate", {}).get("structure", "global")
        names.append(f"{c['experiment']['name']}/{r.name} ({structure}, "
                     f"seed {c['experiment'].get('seed')})")
    print(f"y = {resp.label}, delta_lim = {limit.threshold * 1e6:g} µm; FE on {a.n_theta} "
          f"fresh θ (seed {a.seed})")
    for i, n in enumerate(names):
        print(f"  [{i}] {n}")
    fr = [fronts(r, a.max_points) for r in a.runs]
    for lab in [k for k in fr[0] if all(k in f for f in fr)]:
        p_t = fr[0][lab][0]
        print(f"\n{lab} (P_target {p_t:.0%})")
        Fs = []
        for i, f in enumerate(fr):
            X = f[lab][1]
            y = fe(X, theta)
            mu, sd = y.mean(axis=1) * 1e6, y.std(axis=1, ddof=1) * 1e6
            pf = np.mean(limit.failed(y), axis=1)
            ok = pf <= p_t if lab.startswith("rbrdo") else np.ones(len(X), bool)
            F = np.column_stack([mu, sd])[ok]
            F = F[nondominated(F)] if len(F) else F
            Fs.append(F)
            rng_txt = (f"μ {F[:, 0].min():.4f}–{F[:, 0].max():.4f}, "
                       f"σ {F[:, 1].min():.4f}–{F[:, 1].max():.4f} µm") if len(F) else "-"
            print(f"  [{i}] {len(X):4d} designs, {len(F):4d} FE-feasible non-dominated, {rng_txt}")
        if not all(len(F) for F in Fs):
            print("  a front has no FE-feasible design: no indicator")
            continue
        print("  ε(row covers column):" + "".join(f"{f'[{j}]':>8s}" for j in range(len(Fs))))
        for i, A in enumerate(Fs):
            print(f"  {f'[{i}]':>21s}" + "".join(
                f"{'-' if i == j else f'{eps_mult(A, B):.4f}':>8s}" for j, B in enumerate(Fs)))
        worst = np.vstack(Fs).max(axis=0)
        for k in (1.1, 1.5):
            hv = HV(ref_point=k * worst)
            print(f"  HV (ref {k}x worst μ, σ):" + "".join(f"{hv(F):10.6f}" for F in Fs))


if __name__ == "__main__":
    main()
