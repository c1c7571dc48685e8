"""Structure ``"global"``: one Kriging of ``t(y)`` over the joint (x, θ) box.

The paper's method: a static maximin-LHS DOE of ``n_doe`` joint points, the FE response at
each (one counted, cached FE call per point), a Kriging of ``t(y)``
(:class:`~surrogate_rbrdo.surrogates.transformed.TransformedKriging`).

Transform: with ``transform = "log"`` (default) the Kriging model is fitted to ``log y`` and
the response returns ``exp(μ_log)``. Why log: the peak amplitude spans 0.4–55 µm with a 10–50×
jump where the first critical speed crosses the top of the speed range; in log space the jump
is a step of ~3–4 units on a smooth background of ~±1, and the subcritical plateau (the
designs that matter) is not swamped by the resonant region's variance (docs/surrogates.md).

Active learning (``active_learning = true``): start from ``al_n_initial`` LHS points, candidate
pool = ``al_pool_designs`` LHS designs × ``al_pool_theta`` θ samples of the θ distribution (a
:class:`~surrogate_rbrdo.surrogates.active.GridPool`, predicted by the separable predictor);
:func:`~surrogate_rbrdo.surrogates.active.ak_mcs` adds ``al_batch_size`` pool points per
iteration with the smallest ``U = |μ_t - t(δ_lim)| / σ_t`` (transformed space; at most one
per pool design), until the fraction of pool points with ``U < al_u_stop`` is at most
``al_uncertain_frac`` or ``al_max_added`` points were added; then the final fit with
``n_start`` multistarts.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from functools import partial
from typing import Any, ClassVar

import numpy as np

from surrogate_rbrdo.core.protocols import LimitState, Prediction
from surrogate_rbrdo.core.rng import require_rng
from surrogate_rbrdo.core.validate import check_choice, check_int, check_positive, check_range
from surrogate_rbrdo.doe import lhs
from surrogate_rbrdo.sampling.fe import sample_positive
from surrogate_rbrdo.surrogates.active import AKMCSOptions, GridPool, ak_mcs
from surrogate_rbrdo.surrogates.structured.base import (
    TrainedSurrogate,
    kriging_bytes,
    register_structure,
)
from surrogate_rbrdo.surrogates.structured.joint import JointDOEOptions
from surrogate_rbrdo.surrogates.transformed import TransformedKriging, fit_transformed
from surrogate_rbrdo.surrogates.transforms import TRANSFORMS, forward


@dataclass(frozen=True)
class GlobalOptions(JointDOEOptions):
    """Options of the global Kriging (the ``[surrogate]`` table with ``structure = "global"``,
    the default).

    Attributes
    ----------
    transform : {"log", "none"}
        Fit ``log y`` (default) or ``y``.
    active_learning : bool
        Replace the static DOE by AK-MCS enrichment (``al_*`` options).
    al_n_initial, al_max_added, al_batch_size : int
        Initial LHS size, budget of added points, points added per iteration.
    al_pool_designs, al_pool_theta : int
        Candidate pool: LHS designs × θ samples.
    al_u_stop : float
        U threshold of "uncertain" candidates (2: misclassification probability ≤ 2.3 %).
    al_uncertain_frac : float
        Stop when at most this fraction of the pool has ``U < al_u_stop``.
    al_n_start : int
        Multistarts during the AL refits (the final fit uses ``n_start``).
    """

    structure: ClassVar[str] = "global"
    transform: str = "log"
    active_learning: bool = False
    al_n_initial: int = 60
    al_max_added: int = 140
    al_batch_size: int = 10
    al_pool_designs: int = 400
    al_pool_theta: int = 100
    al_u_stop: float = 2.0
    al_uncertain_frac: float = 0.002
    al_n_start: int = 2

    def __post_init__(self) -> None:
        super().__post_init__()
        check_choice("transform", self.transform, TRANSFORMS)
        if not isinstance(self.active_learning, bool):
            raise ValueError(f"active_learning = {self.active_learning!r} is not allowed: "
                             "must be true or false")
        check_int("al_n_initial", self.al_n_initial, minimum=7)
        check_int("al_max_added", self.al_max_added, minimum=0)
        check_int("al_batch_size", self.al_batch_size, minimum=1)
        check_int("al_pool_designs", self.al_pool_designs, minimum=1)
        check_int("al_pool_theta", self.al_pool_theta, minimum=1)
        check_positive("al_u_stop", self.al_u_stop)
        check_range("al_uncertain_frac", self.al_uncertain_frac, 0.0, 1.0)
        check_int("al_n_start", self.al_n_start, minimum=1)

    def memory_bytes(self) -> dict[str, float]:
        """Peak bytes (``core.memory``): the static DOE's Kriging; with active learning the
        Kriging of up to ``al_n_initial + al_max_added`` points (blamed on the larger) and the
        pool's predictions (mean, std, U and work arrays: ~8 values per pool point, and the
        cross-covariances of the pool's designs and θ rows with the training points).

        >>> m = GlobalOptions(active_learning=True, al_n_initial=10 ** 10).memory_bytes()
        >>> m["al_n_initial"] > 1e20
        True
        """
        out = super().memory_bytes()
        if self.active_learning:
            n = self.al_n_initial + self.al_max_added
            key = "al_n_initial" if self.al_n_initial >= self.al_max_added else "al_max_added"
            out[key] = kriging_bytes(n)
            pd, pt = self.al_pool_designs, self.al_pool_theta
            out["al_pool_designs*al_pool_theta"] = 64.0 * pd * pt + 16.0 * n * (pd + pt)
        return out


class _TransformedSpace:
    """A :class:`TransformedKriging` seen in its fitted space (for AK-MCS on a grid pool)."""

    def __init__(self, model: TransformedKriging) -> None:
        self.model = model

    def predict_grid(self, x: np.ndarray, theta: np.ndarray) -> Prediction:
        return self.model.predict_transformed(x, theta)

    def predict(self, Z: np.ndarray) -> Prediction:
        return self.model.model.predict(Z)


@dataclass(frozen=True)
class _RefitFactory:
    """``factory(rng).fit(Z, y)`` for :func:`ak_mcs`: a transformed Kriging with the AL
    multistarts."""

    options: GlobalOptions
    n_design: int
    rng: np.random.Generator | None = None

    def __call__(self, rng: np.random.Generator) -> _RefitFactory:
        return _RefitFactory(self.options, self.n_design, rng)

    def fit(self, Z: np.ndarray, y: np.ndarray) -> _TransformedSpace:
        o = self.options
        return _TransformedSpace(fit_transformed(
            Z, y, rng=self.rng, surrogate=o.surrogate, transform=o.transform,
            n_start=o.al_n_start, n_design=self.n_design))


def active_learning(spindle: Any, inputs: Any, limit: LimitState, response: Any,
                    options: GlobalOptions, *, rng: np.random.Generator, cache: Any = None,
                    counter: Any = None, progress: bool = False, label: str = ""
                    ) -> tuple[np.ndarray, np.ndarray, list[dict[str, Any]], str]:
    """AK-MCS enrichment of the global Kriging (module docstring); ``Z, y, history, reason``."""
    o = options
    r_doe, r_pool_x, r_pool_t, r_fit = require_rng(rng).spawn(4)
    bounds = o.bounds(spindle, inputs)
    d = spindle.design_map.bounds.shape[0]
    sample = partial(sample_positive, response.pointwise(spindle), n_jobs=o.n_jobs,
                     backend=o.backend, cache=cache, counter=counter)
    Z, y = sample(lhs(o.al_n_initial, bounds, rng=r_doe), progress=progress,
                  desc=f"{label} FE: initial DOE".strip())
    pool = GridPool(lhs(o.al_pool_designs, bounds[:d], rng=r_pool_x, criterion="random"),
                    inputs.sample(o.al_pool_theta, rng=r_pool_t))
    res = ak_mcs(response.pointwise(spindle), pool, bounds,
                 LimitState(float(forward(limit.threshold, o.transform)), limit.failure_if),
                 _RefitFactory(o, d), rng=r_fit,
                 options=AKMCSOptions(max_added=o.al_max_added, batch_size=o.al_batch_size,
                                      u_stop=o.al_u_stop, uncertain_frac=o.al_uncertain_frac),
                 counter=counter, initial=(Z, y), evaluate=sample, progress=progress)
    return res.X, res.y, res.history, res.stop_reason


@register_structure("global", GlobalOptions, "one Kriging of t(y) over the joint (x, θ) box "
                    "(static maximin LHS or AK-MCS active learning)", refinable=True)
def train_global(spindle: Any, inputs: Any, limit: LimitState, response: Any,
                 options: GlobalOptions, *, rng: np.random.Generator, cache: Any = None,
                 counter: Any, progress: bool = False, label: str = "") -> TrainedSurrogate:
    """DOE (static or active) → FE sampling → fit (:func:`train_surrogate` calls it)."""
    o = options
    r_doe, r_fit = require_rng(rng).spawn(2)
    start, start_cached = counter.calls, counter.cached
    d = spindle.design_map.bounds.shape[0]
    bounds = o.bounds(spindle, inputs)
    t0 = time.perf_counter()
    history: list[dict[str, Any]] = []
    reason = ""
    if o.active_learning:
        Z, y, history, reason = active_learning(spindle, inputs, limit, response, o,
                                                rng=r_doe, cache=cache, counter=counter,
                                                progress=progress, label=label)
    else:
        Z, y = sample_positive(response.pointwise(spindle), lhs(o.n_doe, bounds, rng=r_doe),
                               n_jobs=o.n_jobs, backend=o.backend, cache=cache,
                               counter=counter, progress=progress,
                               desc=f"{label} FE: surrogate DOE".strip())
    sample_s = time.perf_counter() - t0
    model = fit_transformed(Z, y, rng=r_fit, surrogate=o.surrogate, transform=o.transform,
                            n_start=o.n_start, n_design=d)
    info = {**model.info, "structure": "global", "sampling_time_s": sample_s,
            "bounds": bounds.tolist(), "active_learning": o.active_learning,
            "response": response.label}
    if o.active_learning:
        info.update(al_history=history, al_stop_reason=reason)
    model.info = dict(info)
    return TrainedSurrogate("global", model, o, response, fe_calls=counter.calls - start,
                            fe_cache_hits=counter.cached - start_cached, info=info)


__all__ = ["GlobalOptions", "active_learning", "train_global"]
