"""The paper's convergence comparison (Sect. 3.1, Fig. 1), done fairly.

Every method sees the same records (common random numbers: one noise realisation per seed, the
four bearing/direction regressions of each), the same initial estimate, the same bounds and the
same scaling. Reported per method: samples to stay within ``tol`` of the true ``k`` and ``c``
(median over records, and the fraction of records that get there), the final NRMSE of ``k`` and
``c`` over the records, and the wall time per sample per record of the vectorised kernel.

>>> import numpy as np
>>> from surrogate_rbrdo.identification.recursions import RLS, MISG
>>> rows = compare_methods({"RLS": RLS(), "MISG(p=3)": MISG(p=3)},
...                        SyntheticSetting(n_samples=300, noise_rel=0.0), n_seeds=2,
...                        rng=np.random.default_rng(0))
>>> [r.method for r in rows], all(r.nrmse_k < 1e-3 for r in rows)
(['RLS', 'MISG(p=3)'], True)
"""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass

import numpy as np

from surrogate_rbrdo.core.rng import require_rng
from surrogate_rbrdo.core.validate import check_int
from surrogate_rbrdo.identification.identify import identify
from surrogate_rbrdo.identification.recursions import SG
from surrogate_rbrdo.identification.regression import Bounds, Regression
from surrogate_rbrdo.identification.synthetic import (
    RigidRotor,
    SyntheticSetting,
    bearing_regression,
    measure,
    simulate,
)

#: initial estimate as factors on the truth (k, c): inside the paper's box around it
THETA0_FACTORS = (0.8, 0.7)


@dataclass(frozen=True)
class ComparisonRow:
    """One method under one setting (see the module docstring for the metrics)."""

    method: str
    excitation: str
    noise_rel: float
    scaling: str
    iters_k: float
    reached_k: float
    iters_c: float
    reached_c: float
    nrmse_k: float
    nrmse_c: float
    us_per_sample: float
    n_records: int

    def to_dict(self) -> dict:
        return asdict(self)


def synthetic_problem(setting: SyntheticSetting, n_seeds: int, *, rng: np.random.Generator,
                      rotor: RigidRotor | None = None,
                      theta0_factors: Sequence[float] = THETA0_FACTORS):
    """Records of ``n_seeds`` noise (and random-force) realisations: the regression (``4 n``
    records), the truth, the initial estimate and the paper's box around it."""
    require_rng(rng)
    rotor = RigidRotor() if rotor is None else rotor
    n_runs = n_seeds if setting.excitation == "random" else 1
    rec = simulate(rotor, setting, n_runs, rng=rng)
    reg = bearing_regression(rec, *measure(rec, n_seeds, rng=rng))
    truth = np.tile(rotor.truth, (n_seeds, 1))
    theta0 = truth * np.asarray(theta0_factors, dtype=float)
    bounds = Bounds.paper(("k", "c"), theta0[:, 0], theta0[:, 1])
    return reg, truth, theta0, bounds


def _run(method, reg: Regression, truth, theta0, bounds, scaling, tol):
    """Samples to ``tol`` (B, 2), relative errors (B, 2) and wall time of one method."""
    t0 = time.perf_counter()
    res = identify(reg, method, theta0=theta0, bounds=bounds, truth=truth, tol=tol,
                   scaling=scaling)
    return res.iterations_to_tol, (res.estimate - truth) / truth, time.perf_counter() - t0


def _row(label, it, err, dt, setting, scaling, n_samples) -> ComparisonRow:
    nrmse = np.sqrt(np.mean(err**2, axis=0))
    med = [float(np.median(it[:, j])) for j in range(2)]
    return ComparisonRow(
        method=label, excitation=setting.excitation, noise_rel=setting.noise_rel,
        scaling=scaling, iters_k=med[0], reached_k=float(np.isfinite(it[:, 0]).mean()),
        iters_c=med[1], reached_c=float(np.isfinite(it[:, 1]).mean()),
        nrmse_k=float(nrmse[0]), nrmse_c=float(nrmse[1]),
        us_per_sample=1e6 * dt / (it.shape[0] * n_samples), n_records=int(it.shape[0]))


def compare_methods(methods: Mapping[str, object], setting: SyntheticSetting, n_seeds: int, *,
                    rng: np.random.Generator, scaling: str | Mapping[str, str] = "columns",
                    tol: float = 0.05, rotor: RigidRotor | None = None,
                    chunk: int = 250) -> list[ComparisonRow]:
    """Run every method on the same ``n_seeds`` records of ``setting``.

    ``scaling`` is one scaling for all methods or a mapping label → scaling. Seeds are
    simulated and identified ``chunk`` at a time (memory: ~100 MB per 250 seeds of 3 000
    samples), so any number of Monte Carlo trials fits.
    """
    n_seeds = check_int("n_seeds", n_seeds, minimum=1)
    chunk = check_int("chunk", chunk, minimum=1)
    acc: dict[str, list] = {label: [] for label in methods}
    for s in range(0, n_seeds, chunk):
        reg, truth, theta0, bounds = synthetic_problem(setting, min(chunk, n_seeds - s),
                                                       rng=rng, rotor=rotor)
        for label, m in methods.items():
            sc = scaling if isinstance(scaling, str) else scaling.get(label, "columns")
            acc[label].append(_run(m, reg, truth, theta0, bounds, sc, tol))
    rows = []
    for label, parts in acc.items():
        sc = scaling if isinstance(scaling, str) else scaling.get(label, "columns")
        it = np.concatenate([p[0] for p in parts])
        err = np.concatenate([p[1] for p in parts])
        rows.append(_row(label, it, err, sum(p[2] for p in parts), setting, sc,
                         setting.n_samples))
    return rows


def tune_sg_gain(setting: SyntheticSetting, n_seeds: int, *, rng: np.random.Generator,
                 gains: Sequence[float] = (1.0, 2.0, 3.0, 5.0, 10.0, 20.0, 50.0),
                 scaling: str = "columns", tol: float = 0.05, target: str = "k") -> float:
    """The SG step factor ``μ`` with the fewest median samples to ``tol`` in ``target``
    (``"k"`` or ``"c"``; ties and misses broken by the final NRMSE), on records of their own
    (tuning seeds are not the comparison's seeds)."""
    reg, truth, theta0, bounds = synthetic_problem(setting, n_seeds, rng=rng)
    j = {"k": 0, "c": 1}[target]
    best, best_key = gains[0], None
    for g in gains:
        r = _row("SG", *_run(SG(mu=float(g)), reg, truth, theta0, bounds, scaling, tol),
                 setting, scaling, setting.n_samples)
        key = ((r.iters_k, r.nrmse_k) if j == 0 else (r.iters_c, r.nrmse_c))
        if best_key is None or key < best_key:
            best, best_key = float(g), key
    return best


__all__ = ["THETA0_FACTORS", "ComparisonRow", "compare_methods", "synthetic_problem",
           "tune_sg_gain"]
