"""§7 benchmark: the three RBRDO runs of the study with the REAL surrogate predictor.

3 × (pop 100 × 200 generations × 1000 θ) = 60 M surrogate predictions, the g_det design model,
BLAS pinned to one thread. Two problems (``--problem``):

* ``rated`` (default; the reference study, ``experiments/paper.toml``): y = tool-tip amplitude
  at 24 000 rpm, δ_lim = 1.5 µm, the substructure surrogate on 60 FE designs (Kriging of the
  condensed rotor, bearings and θ coupled exactly; the θ sample goes through the θ-polynomial
  coupling, ``spindle.coupling.coupled_tool_amplitude_theta``).
* ``peak`` (``experiments/synthetic_peak_in_phase.toml``): y = peak amplitude over 1000–24 000 rpm,
  δ_lim = 19.5 µm, the pipeline's global ``PeakSurrogate`` (Kriging on a 200-point DOE over
  (x, θ), separable predictor with the θ block cached for the CRN sample).

Runs the same three tasks with ``engine="pymoo"`` (pymoo's ``minimize`` loop) and
``engine="lean"`` (array-based loop with pymoo's operators), sequentially and with 2 processes.

Run::

    python benchmarks/bench_study.py                    # reference problem, paper scale
    python benchmarks/bench_study.py --problem peak     # the paper's peak problem
    python benchmarks/bench_study.py --quick            # 20 generations

The FE DOE is cached under ``results/_bench_cache`` (first run: extra seconds, not part of the
timed loop). Prints wall time, surrogate calls and FE calls.
"""

from __future__ import annotations

import argparse
import resource
import time
from functools import partial

import numpy as np
from threadpoolctl import threadpool_limits

from surrogate_rbrdo.core import LimitState
from surrogate_rbrdo.formulations import DeterministicOptions, FormulationOptions, make_formulation
from surrogate_rbrdo.optimization import NSGA2Options, run_many, run_nsga2
from surrogate_rbrdo.sampling.fe import fe_cache
from surrogate_rbrdo.spindle import reference_spindle
from surrogate_rbrdo.spindle.evaluate import ResponseSpec
from surrogate_rbrdo.study import TABLE4_STD
from surrogate_rbrdo.surrogates.design_model import DesignModelOptions, fit_design_model
from surrogate_rbrdo.surrogates.structured import (
    GlobalOptions,
    SubstructureOptions,
    train_surrogate,
)
from surrogate_rbrdo.uncertainty import MultivariateNormal

PROBLEMS = {
    # name: (surrogate config, response, delta_lim in m)
    "rated": (SubstructureOptions(n_doe=60, n_start=3, n_jobs=2),
              ResponseSpec("at_speed", 24000.0), 1.5e-6),
    "peak": (GlobalOptions(n_doe=200, n_jobs=2), ResponseSpec(), 19.5e-6),
}


def build(problem: str, seed: int = 7):
    sp = reference_spindle()
    inputs = MultivariateNormal(np.array([1.0, 1.0]), std=np.array(TABLE4_STD))
    cfg, resp, dlim = PROBLEMS[problem]
    limit = LimitState(dlim)
    r_sur, r_dm, r_crn, r_opt = np.random.default_rng(seed).spawn(4)
    tr = train_surrogate(sp, inputs, limit, cfg, rng=r_sur,
                         cache=fe_cache("results/_bench_cache"), response=resp)
    sur, info = tr.model, {**tr.info, "fe_calls": tr.fe_calls}
    dm = fit_design_model(sp, DesignModelOptions(n_train=30, n_validate=0, n_jobs=2), rng=r_dm)
    lo, hi = sp.design_map.bounds[:, 0], sp.design_map.bounds[:, 1]
    det = DeterministicOptions(resonance="none")
    crn = r_crn.bit_generator.seed_seq
    forms = [make_formulation("rbrdo", response=sur.response, inputs=inputs, limit=limit,
                              deterministic=dm, rng=np.random.default_rng(crn),
                              options=FormulationOptions(p_target=pt, n_theta=1000,
                                                         deterministic=det))
             for pt in (0.10, 0.05, 0.01)]
    return forms, lo, hi, r_opt.bit_generator.seed_seq, info, dm, resp


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="20 generations instead of 200")
    ap.add_argument("--problem", choices=sorted(PROBLEMS), default="rated")
    args = ap.parse_args()
    n_gen = 20 if args.quick else 200
    forms, lo, hi, ss, info, dm, resp = build(args.problem)
    fe_calls = int(info["fe_calls"]) + int(dm.validation["n_fe_calls"])
    kind = info.get("structure", "global")
    print(f"problem {args.problem!r}: y = {resp.label}, surrogate {kind!r} "
          f"trained on {info['n_train']} FE designs; FE calls of this run (DOE not cached + "
          f"g_det model): {fe_calls}; none inside the optimisation loop")
    seeds = ss.spawn(3)  # spawn once: the same three seeds for every configuration
    with threadpool_limits(limits=1, user_api="blas"):
        archives = {}
        for engine in ("pymoo", "lean"):
            opts = NSGA2Options(pop_size=100, n_gen=n_gen, engine=engine)
            for n_jobs in (1, 2):
                tasks = [partial(run_nsga2, f, lo, hi, rng=np.random.default_rng(seeds[i]),
                                 options=opts) for i, f in enumerate(forms)]
                t0 = time.perf_counter()
                res = run_many(tasks, n_jobs=n_jobs)
                wall = time.perf_counter() - t0
                calls = sum(r.n_surrogate_calls for r in res)
                archives[(engine, n_jobs)] = [r.archive.X for r in res]
                per = ", ".join(f"{r.wall_time_s:.2f}" for r in res)
                print(f"engine={engine:5s} n_jobs={n_jobs}: total wall {wall:6.2f} s "
                      f"(runs {per} s)  surrogate calls {calls:,}  FE calls in loop 0  "
                      f"design-model calls {sum(r.n_model_calls for r in res):,}  "
                      f"fronts {[int(r.pareto_mask.sum()) for r in res]}")
        for engine in ("pymoo", "lean"):
            same = all(np.array_equal(a, b) for a, b in
                       zip(archives[(engine, 1)], archives[(engine, 2)], strict=True))
            print(f"{engine}: 2-process archives == sequential (bit for bit): {same}")
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"peak memory (ru_maxrss) of this process, which ran the sequential runs: "
          f"{rss:.0f} MB (the 2-process runs' workers are not included)")
    print("target: <= 10 s wall for the three runs")


if __name__ == "__main__":
    main()
