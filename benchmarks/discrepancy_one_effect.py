"""One hidden effect at a physical size on the rig's data: the workflow's answer, every stage's
candidate fits and checks, and the CPU it took.

    PYTHONPATH=$PWD python3 benchmarks/discrepancy_one_effect.py <effect> <noise> <seed> \\
        <knob> <plan|none>

``effect`` is a key of ``discrepancy.blind.HIDDEN`` (its knob: softening ``a``, preload ``b``,
housing ``k_N_per_m`` at 20 kg, tool interface ``k_t_N_per_m`` …, on both bearings), ``plan``
adds the impact test plan (``rig.impacts.ImpactPlan``), ``none`` keeps the 1x data alone.
Example: ``speed_softening default 12 0.2 none`` (docs/discrepancy.md, "Physically typical
sizes").
"""

from __future__ import annotations

import resource
import sys

import numpy as np

from surrogate_rbrdo.discrepancy.blind import HIDDEN, rig_context
from surrogate_rbrdo.discrepancy.workflow import find_discrepancy


def main(name: str, noise: str, seed: int, knob: float, plan: str) -> None:
    ctx = rig_context(impacts=plan == "plan", n_draws=400)
    data = ctx.source.measure(*ctx.truth(((HIDDEN[name], knob),)), noise, seed)
    res = find_discrepancy(data, ctx.geometry, ctx.effects, options=ctx.options,
                           rng=np.random.default_rng([seed, 7]))
    print(res.verdict, [a.name for a in res.effects], res.test)
    print("residual", res.residual_test)
    for n, est in res.fitted_effects:
        print("fitted", n, est.parameters)
    for i, st in enumerate(res.stages):
        print("stage", i, "base chi2", round(st.base.chi2, 1), "gof_p", st.gof_p)
        for a in st.assessments:
            chi = a.fit.fit.chi2 if a.fit else float("nan")
            rival = (round(a.rival.statistic, 2), a.rival.rival) if a.rival else None
            print(f"  {a.name:16s} d={a.delta_chi2:10.2f} padj={a.p_adjusted:.3g} "
                  f"chi2={chi:.1f} checks={a.checks} rival={rival} "
                  f"params={a.fit.parameters if a.fit else None}")
    ru = resource.getrusage(resource.RUSAGE_SELF)
    print(f"CPU {ru.ru_utime + ru.ru_stime:.1f} s (data + workflow), peak RSS "
          f"{ru.ru_maxrss / 1024:.0f} MB")


if __name__ == "__main__":
    if len(sys.argv) != 6:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2], int(sys.argv[3]), float(sys.argv[4]), sys.argv[5])
