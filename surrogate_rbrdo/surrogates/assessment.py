"""A trained surrogate structure against the full FE model (the ``surrogate_validation`` kind).

:func:`fe_truth` computes the FE side once (fresh LHS test points of the joint box, a θ
sample and the full-FE Monte Carlo at designs, the FE resonance quantities if asked);
:func:`assess` compares one trained structure with it: point predictions at the test points,
its leave-one-out, and μ_y, σ_y, P_f on the same θ sample (common random numbers). Every FE
and surrogate call is counted. ``y`` is the response (``spindle.evaluate.ResponseSpec``;
default the peak tool-tip amplitude of the geometry's unbalance).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from surrogate_rbrdo.core.counting import CallCounter, CountingResponse
from surrogate_rbrdo.core.protocols import LimitState, Prediction
from surrogate_rbrdo.doe import lhs
from surrogate_rbrdo.sampling.fe import sample_designs, sample_positive
from surrogate_rbrdo.spindle.evaluate import ResponseSpec
from surrogate_rbrdo.surrogates.structured.base import TrainedSurrogate, train_surrogate
from surrogate_rbrdo.surrogates.structured.joint import JointDOEOptions
from surrogate_rbrdo.surrogates.structured.resonance_train import sample_resonance
from surrogate_rbrdo.surrogates.validation import LOOSummary, MCComparison, compare_mc


@dataclass(frozen=True, eq=False)
class FETruth:
    """The FE side: test points ``Z`` and ``y``, the θ sample, designs ``X`` and their FE
    values ``y_fe`` (X × θ), optional resonance quantities ``(Z_t, Q_t, Z_d, Q_d)`` (test
    points; designs × the first θ rows), counted FE calls (``test``, ``mc``) and the points
    loaded from the FE cache instead (``cache_hits``, same keys)."""

    Z: np.ndarray
    y: np.ndarray
    theta: np.ndarray
    X: np.ndarray
    y_fe: np.ndarray
    resonance: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None = None
    calls: dict[str, int] = field(default_factory=dict)
    cache_hits: dict[str, int] = field(default_factory=dict)


def fe_truth(spindle: Any, inputs: Any, X: np.ndarray, box: JointDOEOptions, *, n_test: int,
             n_theta: int, rng_test: np.random.Generator, rng_theta: np.random.Generator,
             n_theta_nc: int | None = None, cache: Any = None, mc_cache: Any = None,
             progress: bool = False, label: str = "", response: ResponseSpec | None = None
             ) -> FETruth:
    """FE at ``n_test`` maximin-LHS points of ``box``'s joint box, and full-FE MC of the
    designs ``X`` on ``n_theta`` θ (the FE model's own solve of ``response``, default
    ``ResponseSpec()``: its ``"direct"`` method); with ``n_theta_nc`` also the resonance
    quantities (test points, and designs × the first ``n_theta_nc`` θ)."""
    response = ResponseSpec() if response is None else response
    c_test, c_mc = CallCounter(), CallCounter()
    Z, y = sample_positive(response.pointwise(spindle),
                           lhs(n_test, box.bounds(spindle, inputs), rng=rng_test),
                           n_jobs=box.n_jobs, backend=box.backend, cache=cache, counter=c_test,
                           progress=progress, desc=f"{label} FE test points".strip())
    theta = inputs.sample(n_theta, rng=rng_theta)
    X = np.atleast_2d(np.asarray(X, dtype=float))
    y_fe = sample_designs(response.fe_response(spindle, "direct"), X, theta, n_jobs=box.n_jobs,
                          cache=mc_cache, counter=c_mc, progress=progress,
                          desc=f"{label} full-FE MC".strip())
    res = None
    if n_theta_nc is not None:
        n = min(n_theta_nc, n_theta)
        Z_t, Q_t = sample_resonance(spindle, Z, box, cache=cache, counter=c_test,
                                    progress=progress, label=label)
        Z_d = np.column_stack([np.repeat(X, n, axis=0), np.tile(theta[:n], (len(X), 1))])
        Z_d, Q_d = sample_resonance(spindle, Z_d, box, cache=cache, counter=c_test,
                                    progress=progress, label=label)
        if Z_d.shape[0] != X.shape[0] * n:
            raise ValueError("FE resonance quantities failed at a validation design")
        res = (Z_t, Q_t, Z_d, Q_d)
    return FETruth(Z, y, theta, X, y_fe, res, {"test": c_test.calls, "mc": c_mc.calls},
                   {"test": c_test.cached, "mc": c_mc.cached})


def truth_memory_bytes(*, n_test: int, n_theta: int, n_inputs: int, n_designs: int,
                       n_variants: int) -> dict[str, float]:
    """Peak bytes of :func:`fe_truth` and the assessments of ``n_variants`` structures, per
    size field (``core.memory``): the joint test points (3 design + ``n_inputs`` θ columns)
    with ~4 values per variant, and the θ sample with ~4 values per design for the FE and
    every variant.

    >>> truth_memory_bytes(n_test=10, n_theta=10 ** 11, n_inputs=2, n_designs=1,
    ...                    n_variants=1)["n_theta"] > 1e13
    True
    """
    m = 3 + n_inputs
    return {"n_theta": 8.0 * n_theta * (m + 4 * n_designs * (1 + n_variants)),
            "n_test": 8.0 * n_test * (m + 4 * n_variants)}


@dataclass(frozen=True, eq=False)
class Assessment:
    """One trained structure against :class:`FETruth`: ``y_pred`` at the test points, its
    ``loo``, the Monte Carlo comparison ``mc``, the counted surrogate calls and the FE
    evaluations its training used, counted at the sampler (``fe_calls`` computed,
    ``fe_cache_hits`` loaded from the FE cache; ``None`` if not counted)."""

    name: str
    trained: TrainedSurrogate
    y_pred: np.ndarray
    loo: LOOSummary
    mc: MCComparison
    surrogate_calls: int
    fe_calls: int | None = None
    fe_cache_hits: int | None = None


class _Grid:
    """``compare_mc`` sees the model's response (the median for a log transform)."""

    def __init__(self, model: Any) -> None:
        self.model = model

    def predict_grid(self, x: np.ndarray, theta: np.ndarray) -> Prediction:
        y = self.model(x, theta)
        return Prediction(mean=y, std=np.full_like(y, np.nan))


def assess(name: str, trained: TrainedSurrogate, truth: FETruth, limit: LimitState, *,
           rel_tol: float = 0.05, counter: CallCounter | None = None) -> Assessment:
    """Compare ``trained`` with the FE side (μ, σ within ``rel_tol``; P_f within
    max(1 point, 3 SE)); ``counter``: the one its training counted FE calls with."""
    model = CountingResponse(trained.model.response)
    yp = trained.model.response_points(truth.Z)
    cmp = compare_mc(_Grid(model), truth.X, truth.theta, limit, y_true=truth.y_fe,
                     rel_tol=rel_tol)
    return Assessment(name, trained, yp, trained.model.loo_summary(), cmp,
                      int(yp.size + model.counter.calls),
                      None if counter is None else counter.calls,
                      None if counter is None else counter.cached)


def train_and_assess(name: str, spindle: Any, inputs: Any, limit: LimitState, options: Any,
                     truth: FETruth, *, rng: np.random.Generator, cache: Any = None,
                     rel_tol: float = 0.05, progress: bool = False, label: str = "",
                     response: ResponseSpec | None = None) -> Assessment:
    """Train the structure of ``options`` for ``response`` (``train_surrogate``, its FE
    calls counted) and :func:`assess` it against ``truth``."""
    counter = CallCounter()
    trained = train_surrogate(spindle, inputs, limit, options, rng=rng, counter=counter,
                              response=response,
                              cache=cache, progress=progress, label=f"{label} {name}".strip())
    return assess(name, trained, truth, limit, rel_tol=rel_tol, counter=counter)


__all__ = ["Assessment", "FETruth", "assess", "fe_truth", "train_and_assess",
           "truth_memory_bytes"]
