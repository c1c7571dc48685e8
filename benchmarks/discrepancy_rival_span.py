"""How much of a bearing speed law a constant spring at the bearing's node mimics.

    PYTHONPATH=$PWD python3 benchmarks/discrepancy_rival_span.py \
        speed_softening=0.003287 thermal_preload=0.009834

For each hidden effect (registry name = knob value; the blind grid's hidden form, e.g. a
quadratic softening on both bearings) on the virtual rig's noise-free data at default noise,
with the impact test plan and with the 1x data alone: the recalibrated baseline's χ², what a
grounded spring at each bearing's node explains of it (unbounded, with its size in N/m), and
for every scope of the candidates ``speed_softening`` and ``thermal_preload`` (first shape
start) the fraction of its nuisance-orthogonal signature left outside span(nuisance, spring at
a bearing node) — 0 means the spring, with the bearing's stiffness factor θ recalibrated,
mimics the candidate entirely (``docs/discrepancy.md``, "A grounded spring has a sign").
"""

from __future__ import annotations

import sys

import numpy as np

from surrogate_rbrdo.discrepancy.blind import HIDDEN, Context
from surrogate_rbrdo.discrepancy.calibration import _apply, _data_whitening, linearise
from surrogate_rbrdo.discrepancy.candidates import library
from surrogate_rbrdo.discrepancy.forward import ForwardModel
from surrogate_rbrdo.discrepancy.generic import BESIDE_BEARING, NODE_SPRING_SCALE
from surrogate_rbrdo.discrepancy.holdout import split_speeds
from surrogate_rbrdo.discrepancy.nuisance import NuisanceOptions
from surrogate_rbrdo.discrepancy.observables import MeasuredData
from surrogate_rbrdo.discrepancy.rig_source import FACTORS, RigSource
from surrogate_rbrdo.discrepancy.workflow import DiscrepancyOptions, _recalibrate
from surrogate_rbrdo.rig.impacts import ImpactPlan
from surrogate_rbrdo.spindle.reference import reference_spindle


def _orth(B: np.ndarray, Y: np.ndarray) -> np.ndarray:
    Q, _ = np.linalg.qr(B)
    return Y - Q @ (Q.T @ Y)


def report(ctx: Context, data: MeasuredData, label: str) -> None:
    o = ctx.options
    one_x = data.blocks[0].mean.shape[0]
    split = split_speeds(one_x, o.holdout_every, o.extrapolate_fraction)
    fm = ForwardModel(ctx.geometry, ctx.effects, data.channels, ctx.planes, None,
                      o.nuisance.mass_disks)
    train, _, _, base, _ = _recalibrate(fm, data, split, o)
    lin = linearise(train, base, library(("speed_softening", "thermal_preload"),
                                         fm.bearing_names))
    W = _data_whitening(train)
    N = _apply(W, lin.nuisance)
    G = _orth(N, _apply(W, lin.generic))
    r = _orth(N, base.evaluation.residuals[0][:, None])[:, 0]
    model = fm.model(())
    print(f"[{label}] recalibrated baseline: χ² {base.chi2:.1f}, of it outside the nuisance "
          f"{r @ r:.1f}")
    springs = {}
    for name, node in zip(fm.bearing_names, model.bearing_nodes, strict=True):
        j = lin.generic_labels.index(f"grounded spring at node {node} {BESIDE_BEARING} {name}")
        u = G[:, j]
        c = (u @ r) / (u @ u)
        # columns are scaled to unit nuisance-orthogonal norm: back to N/m
        norm = lin.generic_bounds[j, 1] / 0.5
        springs[name] = u
        print(f"  spring at {name} bearing's node {node}: explains {c * c * (u @ u):.1f}, "
              f"size {c / norm * NODE_SPRING_SCALE:+.3g} N/m")
    for c, variants in lin.candidates:
        for v in variants[::len(variants) // len(c.scopes) or 1]:
            s = _orth(N, _apply(W, v.columns))[:, 0]
            parts = []
            for name, u in springs.items():
                left = _orth(np.column_stack([N, u]), _apply(W, v.columns))[:, 0]
                cos = abs(s @ u) / np.linalg.norm(s) / np.linalg.norm(u)
                parts.append(f"{name}: |cos| {cos:.3f}, outside the span "
                             f"{(left @ left) / (s @ s):.4f}")
            print(f"  {c.name} {v.scope or 'all'} {dict(v.shape)}: " + "; ".join(parts))


def main() -> None:
    sp = reference_spindle()
    g = sp.geometry_for(sp.baseline)
    src = RigSource(tuple(np.linspace(1000.0, 24000.0, 50).tolist()), 20, FACTORS,
                    impacts=ImpactPlan())
    ctx = Context(g, sp.effects, src,
                  DiscrepancyOptions(nuisance=NuisanceOptions.probe_chain()))
    for arg in sys.argv[1:] or ["speed_softening=0.003287"]:
        name, knob = arg.split("=")
        data = src.expected(*ctx.truth(((HIDDEN[name], float(knob)),)), "default")
        print(f"\n== {name} = {knob} ==")
        report(ctx, data, "1x + impact plan")
        report(ctx, MeasuredData(data.blocks[:1]), "1x data alone")


if __name__ == "__main__":
    main()
