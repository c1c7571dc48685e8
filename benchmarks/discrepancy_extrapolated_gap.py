"""Is the extrapolated held-out gap after a named effect a too-narrow prediction covariance or
a bias beyond it? The workflow's predictive χ² (``holdout.predictive_chi2``) propagates the
fit's Gauss–Newton covariance to first order; this script draws the parameters from that
covariance (bounded, 200 draws, the unbalance re-solved on the training points for each) and
evaluates the held-out extrapolated residuals at every draw, so the prediction's spread is
sampled, not linearised. Equal figures: the linearisation is adequate and a large predictive
χ² is a bias of the model against these data, not an uncertainty it understates.

    PYTHONPATH=$PWD python3 benchmarks/discrepancy_extrapolated_gap.py [--folder RUN/campaign]
        [--seed 23] [--k 6e8]

``--folder``: a run folder's campaign (the time-domain rig, e.g. of ``rbrdo run
experiments/discrepancy.toml``); else the rig's fast path with a hidden 20 kg housing stage of
stiffness ``--k`` at default noise. Prints; no asserts.
"""

from __future__ import annotations

import argparse

import numpy as np

from surrogate_rbrdo.discrepancy import holdout, workflow
from surrogate_rbrdo.discrepancy.blind import rig_context
from surrogate_rbrdo.discrepancy.experiment import data_from_folder
from surrogate_rbrdo.spindle.effects import EFFECTS, with_effects


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--folder", default="")
    ap.add_argument("--seed", type=int, default=23)
    ap.add_argument("--k", type=float, default=6e8)
    ap.add_argument("--draws", type=int, default=200)
    args = ap.parse_args()
    cap = {}
    conclude = workflow._conclude

    def spy(data, train, ho_pair, split, base, final, *a, **k):
        cap.update(train=train, ho=ho_pair[1], final=final)
        return conclude(data, train, ho_pair, split, base, final, *a, **k)

    workflow._conclude = spy
    ctx = rig_context()
    if args.folder:
        data = data_from_folder(args.folder)
    else:
        eff = with_effects(ctx.effects, (EFFECTS["housing"](k_N_per_m=args.k, m_kg=20.0),))
        data = ctx.source.measure(ctx.geometry, eff, "default", args.seed)
    res = workflow.find_discrepancy(data, ctx.geometry, ctx.effects, options=ctx.options,
                                    rng=np.random.default_rng([args.seed, 7]))
    print("verdict", res.verdict, [(a.name, a.fit.parameters) for a in res.effects])
    train, f = cap["train"], cap["final"]
    ex = cap["ho"].extrapolated.only("unbalance_1x")
    par = f.par

    def whitened(x):
        u = tuple(v[0] for v in train.evaluate(par, x[None]).unbalance)
        out, where = [], []
        for b, W, r in zip(ex.blocks, ex.whiten, holdout.residuals(ex, par, x, u),
                           strict=False):
            if b.sweep.kind != "unbalance_1x" or r.size == 0:
                continue
            out.append(holdout._whitened(r[None], W)[0].ravel())
            where += [(float(s), c.name) for s in b.coord for c in b.channels for _ in "ri"]
        return np.concatenate(out), where

    r0, where = whitened(f.x)
    n = r0.size
    lin = holdout.predictive_chi2(train, ex, f)
    S = f.covariance(bounded=True)
    w, V = np.linalg.eigh((S + S.T) / 2)
    L = V * np.sqrt(np.clip(w, 0, None))
    lo, hi = par.bounds()
    rng = np.random.default_rng(1)
    R = np.array([whitened(np.clip(f.x + L @ rng.standard_normal(f.x.size), lo, hi))[0]
                  for _ in range(args.draws)])
    C = np.cov(R.T)
    mc = float(r0 @ np.linalg.solve(np.eye(n) + C, r0))
    print(f"extrapolated 1x: {n} real observations; chi2/dof noise-only {r0 @ r0 / n:.3g}, "
          f"predictive linearised {lin / n:.4g}, predictive sampled ({args.draws} draws) "
          f"{mc / n:.4g}")
    for j in np.argsort(np.abs(r0))[::-1][:6]:
        print(f"  {where[j][0]:8.0f} rpm {where[j][1]:8s} whitened {r0[j]:+9.2f}, "
              f"prediction sd {np.sqrt(C[j, j]):.3g}")


if __name__ == "__main__":
    main()
