"""FORM, SORM and IS on a periodic phase with bounded inputs (review 3 of issue 13).

y = |r1 + r2 e^{i phi}|, r uniform-disk radii (<= 1), phi ~ U(0, 360) periodic; thresholds from
never reached (2.5) to failing at the mean (0.5); reference: crude MC of the closed form with
2e6 samples. Prints P_f, SE, status, bound label, phase nodes, quadrature error and calls.

    PYTHONPATH=$PWD python3 benchmarks/bench_periodic_phase.py
"""

import numpy as np

from surrogate_rbrdo.core import LimitState
from surrogate_rbrdo.estimators import ESTIMATORS
from surrogate_rbrdo.uncertainty import Independent, Uniform
from surrogate_rbrdo.uncertainty.disk import UniformDiskRadius

inp = Independent([UniformDiskRadius(), UniformDiskRadius(),
                   Uniform(0.0, 360.0, periodic=True)])
def resp(x, t):
    z = t[:, 0] + t[:, 1] * np.exp(1j * np.radians(t[:, 2]))
    return np.broadcast_to(np.abs(z), (x.shape[0], t.shape[0]))
rng = np.random.default_rng(0)
th = inp.sample(2_000_000, rng=rng)
y = resp(np.zeros((1,0)), th)[0]
for thr in (2.5, 1.9, 1.5, 1.0, 0.5):
    print(thr, "MC", (y > thr).mean())
    for name in ("form", "sorm", "is"):
        try:
            e = ESTIMATORS[name]().estimate(resp, inp, LimitState(thr), np.zeros((1, 0)),
                                            rng=np.random.default_rng(0))
            d = e.diagnostics
            print("   ", name, "pf", e.pf, e.pf_se, d["status"], d.get("pf_bound"),
                  d.get("phase_nodes"), d.get("pf_quadrature_error"), e.n_calls)
        except Exception as ex:
            print("   ", name, type(ex).__name__, str(ex)[:300])
