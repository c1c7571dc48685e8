"""Digits of the discrepancy workflow's numerical core on one fixed problem, to check that a
change to the hot path leaves every number the same (bit for bit) or to measure by how much it
moves them.

    PYTHONPATH=<tree> python3 benchmarks/discrepancy_fingerprint.py save OUT.npz
    python3 benchmarks/discrepancy_fingerprint.py compare A.npz B.npz

``save`` builds the rig's data of a hidden housing stage (6e8 N/m at 20 kg, default noise,
seed 3, the impact plan), recalibrates the nuisance on the training speeds (the workflow's
``_recalibrate``, run-averaging included), linearises every library candidate at that fit
(``calibration.linearise``: nuisance, generic and every variant's columns) and makes a short fit
(8 evaluations) of every candidate at every scope; it saves the recalibration's parameters,
χ² and Jacobian, the linearisation's columns and each short fit's parameters, χ² and Jacobian.
``compare`` prints the arrays that differ with their largest relative difference, or
``identical``. Run ``save`` once per code tree (``git archive`` of each commit) and compare.

Not covered: the identified-stiffness block (the rig's data have none), the rival tests, the
bootstrap null draws and the held-out checks — a bit-for-bit claim for those rests on the blind
samples' ``--compare`` (every statistic of every scenario).
"""

from __future__ import annotations

import sys

import numpy as np

from surrogate_rbrdo.discrepancy import workflow
from surrogate_rbrdo.discrepancy.blind import HIDDEN, rig_context
from surrogate_rbrdo.discrepancy.calibration import linearise
from surrogate_rbrdo.discrepancy.candidates import library
from surrogate_rbrdo.discrepancy.fit import fit
from surrogate_rbrdo.discrepancy.forward import ForwardModel
from surrogate_rbrdo.discrepancy.holdout import split_speeds
from surrogate_rbrdo.discrepancy.nuisance import Slot


def save(out: str) -> None:
    """Compute the fixed problem's digits and save them to ``out`` (npz)."""
    ctx = rig_context(impacts=True, n_draws=400)
    data = ctx.source.measure(*ctx.truth(((HIDDEN["housing"], 6e8),)), "default", 3)
    opt = ctx.options
    one_x = [b for b in data.blocks if b.sweep.kind == "unbalance_1x"]
    split = split_speeds(one_x[0].mean.shape[0], opt.holdout_every, opt.extrapolate_fraction)
    fm = ForwardModel(ctx.geometry, ctx.effects, data.channels,
                      tuple(u.position_mm for u in ctx.geometry.unbalances), None,
                      opt.nuisance.mass_disks)
    train, _, _, base, _ = workflow._recalibrate(fm, data, split, opt)
    cands = library(opt.library, fm.bearing_names)
    res = {"base_x": base.x, "base_jac": base.jac, "base_chi2": np.array(base.chi2)}
    lin = linearise(train, base, cands)
    res["lin_nuisance"], res["lin_generic"] = lin.nuisance, lin.generic
    for c, vs in lin.candidates:
        res[f"lin_{c.name}"] = np.hstack([v.columns for v in vs])
    for c in cands:
        for scope in c.scopes:
            par = base.par.with_slots((Slot(c, scope),))
            x0 = par.x0()
            x0[:base.x.size] = base.x
            f = fit(train, par, x0, max_nfev=8)
            res[f"fit_{c.name}_{'-'.join(scope) or 'all'}"] = np.concatenate(
                [f.x, [f.chi2], f.jac.ravel()])
    np.savez(out, **res)
    print(f"saved {len(res)} arrays to {out}")


def compare(a_path: str, b_path: str) -> None:
    """Print the arrays of two saves that differ, with their largest relative difference."""
    a, b = np.load(a_path), np.load(b_path)
    worst = 0.0
    for k in sorted(set(a.files) | set(b.files)):
        if k not in a.files or k not in b.files or a[k].shape != b[k].shape:
            print(f"{k}: only in one file or shapes differ")
            worst = np.inf
            continue
        if np.array_equal(a[k], b[k]):
            continue
        d = float(np.max(np.abs(a[k] - b[k])) / max(np.max(np.abs(a[k])), 1e-300))
        worst = max(worst, d)
        print(f"{k}: largest difference {d:.3g} of the largest entry")
    print("identical" if worst == 0 else f"largest relative difference {worst:.3g}")


if __name__ == "__main__":
    if len(sys.argv) == 3 and sys.argv[1] == "save":
        save(sys.argv[2])
    elif len(sys.argv) == 4 and sys.argv[1] == "compare":
        compare(sys.argv[2], sys.argv[3])
    else:
        sys.exit(__doc__)
