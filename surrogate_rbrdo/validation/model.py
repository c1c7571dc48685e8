"""The model's side of the validation: μ, σ, P_f predicted by the FE model with the study's
uncertainty model, its ±2σ response band and its Campbell diagram.

A :class:`ModelSpec` is what the study optimised with: one response ``y(x, θ)`` per measured
quantity (``"peak"`` over the range, ``"rated"`` at the rated speed; metres; the core
``Response`` protocol) and the random vector θ. :func:`predict_model` estimates μ, σ, P_f of
every design by crude Monte Carlo (``estimators.mc``: Clopper–Pearson interval of P_f,
distribution-free standard error of σ) on one common θ sample for all designs and quantities.

>>> import numpy as np
>>> from surrogate_rbrdo.uncertainty import Independent, Uniform
>>> spec = ModelSpec({"peak": lambda x, t: x[:, :1] * t[:, 0][None, :]},
...                  Independent([Uniform(0.25, 1.0)]), n_samples=4000)
>>> p = predict_model(spec, {"a": [40e-6]}, delta_lim_m=30e-6, confidence=0.95,
...                   rng=np.random.default_rng(0))
>>> m = p.moments["a"]["peak"]
>>> bool(abs(m.mean - 25e-6) < 3 * m.mean_se)       # 40 µm x E[U(0.25, 1)] = 25 µm
True
>>> bool(m.pf_ci[0] < 1 / 3 < m.pf_ci[1])           # P(U > 0.75) = 0.25 / 0.75
True
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np
from scipy import stats

from surrogate_rbrdo.core.protocols import Estimate, LimitState
from surrogate_rbrdo.core.rng import require_rng
from surrogate_rbrdo.core.validate import check_int
from surrogate_rbrdo.estimators.mc import MonteCarlo, mc_from_values
from surrogate_rbrdo.spindle.evaluate import AtSpeedAmplitudeResponse, PeakAmplitudeResponse
from surrogate_rbrdo.spindle.harmonic import tool_amplitude
from surrogate_rbrdo.spindle.modal import Campbell, campbell

#: quantities a validation measures (and a model may predict)
QUANTITIES = ("peak", "rated")


@dataclass(frozen=True)
class Moments:
    """μ, σ, P_f of ``y`` for one design from ``n`` values (measured replications or model
    samples), with standard errors and intervals at ``confidence``.

    ``mean_ci``: t interval; ``std_ci``: ``σ̂ exp(±t u/σ̂)`` from the distribution-free
    delta-method standard error (positive, skewed like the sampling distribution of an SD);
    ``pf_ci``: Clopper–Pearson.
    """

    n: int
    mean: float
    mean_se: float
    mean_ci: tuple[float, float]
    std: float
    std_se: float
    std_ci: tuple[float, float]
    pf: float
    pf_ci: tuple[float, float]
    n_fail: int

    @classmethod
    def from_estimate(cls, est: Estimate, j: int, n: int, confidence: float) -> Moments:
        tq = float(stats.t.ppf(0.5 + 0.5 * confidence, max(n - 1, 1)))
        mu, se, sd, sd_se = (float(getattr(est, k)[j]) for k in
                             ("mean", "mean_se", "std", "std_se"))
        f = float(np.exp(tq * sd_se / sd)) if sd > 0 else 1.0
        pf = float(est.pf[j])
        return cls(n, mu, se, (mu - tq * se, mu + tq * se), sd, sd_se, (sd / f, sd * f), pf,
                   (float(est.pf_ci[j][0]), float(est.pf_ci[j][1])), int(round(pf * n)))

    @classmethod
    def from_summary(cls, n: int, mean: float, std: float, pf: float,
                     pf_ci: tuple[float, float], confidence: float) -> Moments:
        """Moments known only as ``n``, μ, σ, P_f and P_f's interval (a study's verification
        table). The standard errors are σ/√n and, for σ, the normal-theory σ/√(2(n − 1)):
        the distribution-free delta-method error needs the fourth moment, which such a table
        does not hold (for a heavy-tailed y it is smaller than the true one).

        >>> m = Moments.from_summary(1000, 20e-6, 5e-6, 0.3, (0.27, 0.33), 0.95)
        >>> round(m.mean_se * 1e6, 4), round(m.std_se * 1e6, 4), m.n_fail
        (0.1581, 0.1119, 300)
        """
        n = check_int("n", n, minimum=2)
        tq = float(stats.t.ppf(0.5 + 0.5 * confidence, n - 1))
        se, sd_se = std / np.sqrt(n), std / np.sqrt(2.0 * (n - 1))
        f = float(np.exp(tq * sd_se / std)) if std > 0 else 1.0
        return cls(n, float(mean), float(se), (mean - tq * se, mean + tq * se), float(std),
                   float(sd_se), (std / f, std * f), float(pf),
                   (float(pf_ci[0]), float(pf_ci[1])), int(round(pf * n)))

    @classmethod
    def of_values(cls, y: np.ndarray, delta_lim_m: float, confidence: float) -> Moments:
        """Moments of measured values ``y`` (n,)."""
        y = np.asarray(y, float)
        est = mc_from_values(y[None, :], LimitState(delta_lim_m), ci_level=confidence)
        return cls.from_estimate(est, 0, y.size, confidence)

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


#: ``curves(x, θ, speeds_rpm) -> (N, S)`` tool-tip amplitudes (m)
Curves = Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray]


@dataclass(frozen=True)
class SpindleCurves:
    """Model response curves of a spindle whose θ are bearing stiffness factors, solved
    ``chunk`` θ rows at a time (the batched solve holds ~20 kB per row and speed)."""

    spindle: Any
    chunk: int = 16

    def __call__(self, x: np.ndarray, theta: np.ndarray, speeds_rpm: np.ndarray) -> np.ndarray:
        model = self.spindle.model(np.asarray(x, float))
        th = np.atleast_2d(theta)
        return np.concatenate([tool_amplitude(model, speeds_rpm, th[i:i + self.chunk])
                               for i in range(0, th.shape[0], self.chunk)])


@dataclass(frozen=True)
class ModelSpec:
    """The model the study used: responses per quantity, the random vector θ, and optionally
    its response curves (Fig. 8 band) and nominal FE model per design (Fig. 7 Campbell).

    ``known`` holds moments the study already has (design name → quantity → :class:`Moments`,
    e.g. from its FE verification, built with :meth:`Moments.from_estimate`); they are used
    as given and not estimated again.
    """

    responses: Mapping[str, Callable[[np.ndarray, np.ndarray], np.ndarray]]
    inputs: Any
    n_samples: int = 1000
    curves: Curves | None = None
    spindle_model: Callable[[np.ndarray], Any] | None = None
    name: str = "model"
    known: Mapping[str, Mapping[str, Moments]] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if not self.responses:
            raise ValueError("responses = {} is not allowed: give at least one of "
                             f"{list(QUANTITIES)}")
        for q in self.responses:
            if q not in QUANTITIES:
                raise ValueError(f"responses[{q!r}] is not allowed: quantities are "
                                 f"{list(QUANTITIES)}")
        check_int("n_samples", self.n_samples, minimum=10)


def spindle_model_spec(spindle: Any, inputs: Any, *, n_samples: int = 1000,
                       rated_speed_rpm: float = 24000.0,
                       known: Mapping[str, Mapping[str, Moments]] | None = None) -> ModelSpec:
    """The FE model of a spindle (``spindle.model(x)``, θ = bearing stiffness factors) with
    the random vector ``inputs``: peak over the range, amplitude at the rated speed."""
    return ModelSpec({"peak": PeakAmplitudeResponse(spindle),
                      "rated": AtSpeedAmplitudeResponse(spindle, rated_speed_rpm)},
                     inputs, n_samples, SpindleCurves(spindle), spindle.model,
                     known=dict(known or {}))


@dataclass(frozen=True)
class ModelPrediction:
    """The model's μ, σ, P_f per design and quantity, its band and Campbell diagrams."""

    moments: Mapping[str, Mapping[str, Moments]]
    band_mean: Mapping[str, np.ndarray] = field(default_factory=dict)
    band_std: Mapping[str, np.ndarray] = field(default_factory=dict)
    campbell: Mapping[str, Campbell] = field(default_factory=dict)
    n_calls: int = 0
    timings: Mapping[str, float] = field(default_factory=dict)


def predict_model(spec: ModelSpec, designs: Mapping[str, Sequence[float]], *,
                  delta_lim_m: float, confidence: float, rng: np.random.Generator,
                  speeds_rpm: Sequence[float] | None = None, band_samples: int = 100,
                  campbell_speeds_rpm: Sequence[float] | None = None) -> ModelPrediction:
    """Monte Carlo μ, σ, P_f of every design (common θ sample), and — where the spec has them
    and speeds are given — the ±2σ band of its curves and the nominal Campbell diagram."""
    rng = require_rng(rng)
    t0 = time.perf_counter()
    names = list(designs)
    X = np.array([np.asarray(designs[k], float) for k in names])
    u = spec.inputs.standard_sample(spec.n_samples, rng=rng)
    mc = MonteCarlo(spec.n_samples, ci_level=confidence)
    limit = LimitState(delta_lim_m)
    moments: dict[str, dict[str, Moments]] = {k: {} for k in names}
    calls = 0
    for q, resp in spec.responses.items():
        todo = [j for j, k in enumerate(names) if q not in spec.known.get(k, {})]
        est = mc.estimate(resp, spec.inputs, limit, X[todo], rng=rng, u=u) if todo else None
        calls += 0 if est is None else est.n_calls
        for j, k in enumerate(names):
            moments[k][q] = spec.known[k][q] if j not in todo else Moments.from_estimate(
                est, todo.index(j), spec.n_samples, confidence)
    t1 = time.perf_counter()
    bm, bs = {}, {}
    if spec.curves is not None and speeds_rpm is not None:
        th = spec.inputs.from_standard(u[:band_samples])
        sp = np.asarray(speeds_rpm, float)
        for j, k in enumerate(names):
            A = spec.curves(X[j], th, sp)
            bm[k], bs[k] = A.mean(axis=0), A.std(axis=0, ddof=1)
            calls += A.size
    t2 = time.perf_counter()
    camp = {}
    if spec.spindle_model is not None and campbell_speeds_rpm is not None:
        camp = {k: campbell(spec.spindle_model(X[j]), np.asarray(campbell_speeds_rpm, float))
                for j, k in enumerate(names)}
    t3 = time.perf_counter()
    return ModelPrediction(moments, bm, bs, camp, calls,
                           {"moments_s": t1 - t0, "band_s": t2 - t1, "campbell_s": t3 - t2})
