"""Every FORM-type estimator on the credible reference problem, design by design (review 3 of
issue 13). Designs: the baseline, the review's never-failing design, two intermediate ones, then
the 16 random designs of the review's form_credible.py. Usage:

    PYTHONPATH=$PWD python3 benchmarks/bench_credible_estimators.py form,sorm,is 0 20
    PYTHONPATH=$PWD python3 benchmarks/bench_credible_estimators.py --reference

``--reference`` prints crude MC (1e5 samples, seed 123) at every design (about 2 minutes). FORM
and SORM run with ``on_failure="nan"`` so that a design whose search fails is reported, not
raised. ``q`` is ``1 − pf`` (the safe probability, where ``pf`` is near 1).
"""
import sys
import time
import warnings

import numpy as np

from surrogate_rbrdo.estimators import ESTIMATORS
from surrogate_rbrdo.study import credible_problem

p = credible_problem()
R = p.response.fe_response(p.spindle, "condensed")
b = p.spindle.design_map.bounds
z = np.random.default_rng(0).random((16, 3))
X = np.vstack([p.baseline, [1004.5, 315.1, 71.9], [774.6, 472.7, 79.9], [1035.8, 402.2, 68.7],
               b[:, 0] + z * (b[:, 1] - b[:, 0])])
if sys.argv[1] == "--reference":
    th = p.inputs.sample(100_000, rng=np.random.default_rng(123))
    y = np.hstack([R(X, th[i:i + 5000]) for i in range(0, th.shape[0], 5000)])
    pf = (y > p.limit.threshold).mean(1)
    for i in range(X.shape[0]):
        print(i, np.round(X[i], 1), f"pf={pf[i]:.5g} q={1 - pf[i]:.3g} "
              f"se={np.sqrt(pf[i] * (1 - pf[i]) / y.shape[1]):.2g} "
              f"max y um={y[i].max() * 1e6:.3g}", flush=True)
    sys.exit(0)
lo, hi = int(sys.argv[2]), int(sys.argv[3])
OPTS = {"form": {"on_failure": "nan"}, "sorm": {"form": ESTIMATORS["form"](on_failure="nan")}}
for name in sys.argv[1].split(","):
    for i in range(lo, hi):
        t = time.time()
        with warnings.catch_warnings(record=True) as w:
            warnings.simplefilter("always")
            e = ESTIMATORS[name](**OPTS.get(name, {})).estimate(
                R, p.inputs, p.limit, X[i:i + 1], rng=np.random.default_rng(0))
        d = e.diagnostics
        qe = d.get("pf_quadrature_error", [np.nan])[0]
        print(name, i, np.round(X[i], 1), f"pf={e.pf[0]:.4g} q={1 - e.pf[0]:.3g} "
              f"se={e.pf_se[0]:.2g} "
              f"status={d['status'][0]} bound={d['pf_bound'][0]} qerr={qe:.2g} "
              f"calls={e.n_calls} {time.time() - t:.0f}s", [str(x.message)[:100] for x in w],
              flush=True)
        if d["status"][0] == "failed":
            print("    ", d.get("message", [""])[0][:200], flush=True)
