"""Structure ``"resonance"``: its options, the boundary infill and the training.

Training: a static maximin LHS of ``n_doe`` joint points → the FE resonance quantities at each
(:class:`~surrogate_rbrdo.spindle.evaluate.PointwiseResonance`: critical speed, resonance
height, amplitude at the top speed, peak; one counted, cached FE call per point) → optionally
``res_n_band`` points near the critical-speed boundary ``n_c = n_max`` and ``res_n_band_lim``
points near the second boundary ``A_res = δ_lim`` (:func:`band_points`) → the sub-models of
:class:`~surrogate_rbrdo.surrogates.structured.resonance.ResonanceSurrogate`.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from functools import partial
from typing import Any, ClassVar

import numpy as np

from surrogate_rbrdo.core.protocols import LimitState
from surrogate_rbrdo.core.rng import require_rng
from surrogate_rbrdo.core.validate import check_int, check_range
from surrogate_rbrdo.doe import lhs
from surrogate_rbrdo.doe.infill import maximin_select
from surrogate_rbrdo.sampling.fe import sample_positive
from surrogate_rbrdo.spindle.evaluate import PointwiseResonance, ResponseSpec
from surrogate_rbrdo.surrogates.structured.base import (
    TrainedSurrogate,
    kriging_bytes,
    register_structure,
)
from surrogate_rbrdo.surrogates.structured.joint import JointDOEOptions
from surrogate_rbrdo.surrogates.structured.resonance import fit_resonance_surrogate
from surrogate_rbrdo.surrogates.transformed import fit_transformed


@dataclass(frozen=True)
class ResonanceOptions(JointDOEOptions):
    """Options of the physics-structured resonance surrogate (``structure = "resonance"``;
    every sub-model is a log-Kriging; static DOE only; the peak response only).

    Attributes
    ----------
    res_ares_r_min : float
        Resonance height sub-model trained on points with ``n_max / n_c >=`` this.
    res_bg_r_max : float
        Background sub-model trained on points with ``n_max / n_c <=`` this (< 1).
    res_zeta_r_min : float
        Effective damping ratio from flank points with ``res_zeta_r_min <= n_max/n_c < 1``.
    res_zeta_min_points : int
        Kriging of ``log ζ`` from at least this many flank points, else a constant ζ.
    res_n_band : int
        Points "where they matter" added after the ``n_doe`` LHS: a Kriging of ``log n_c``
        on the LHS predicts ``r = n_max / n_c`` on a random pool of ``res_band_pool`` joint
        points; ``res_n_band`` pool points with ``|r̂ - 1| <= res_band`` are chosen by greedy
        maximin (normalised box, distance to all points so far) and evaluated. Total FE
        calls: ``n_doe + res_n_band``.
    res_band : float
        Half-width of the band in ``r``.
    res_band_pool : int
        Size of the random candidate pool.
    res_n_band_lim : int
        Further points near the second boundary ``A_res = δ_lim`` with the resonance in the
        range (``|log Â_res - log δ_lim| <= res_band_lim``), after the ``n_c`` band.
    res_band_lim : float
        Half-width of that band in ``log A_res``.
    res_band_n_start : int
        Multistarts of the screening Kriging models of the band infill.
    res_nc_local : float
        ``0`` (default): off. Otherwise a second, *local* Kriging of ``log n_c`` fitted only
        on the training points with ``|n_max / n_c - 1| <= res_nc_local``, used instead of the
        global one wherever the global ``r̂`` lies within ``res_band`` of 1.
    res_bg_only_r : float
        ``0`` (default): off. Otherwise ``ŷ = b̂`` wherever ``r̂ <= res_bg_only_r``; must not
        exceed ``res_bg_r_max``.
    res_ares_local : float
        ``0`` (default): off. Otherwise a second, *local* Kriging of ``log A_res`` on the
        training points with the resonance in the range and ``|log A_res - log δ_lim| <=
        res_ares_local``, used wherever ``|log Â_res - log δ_lim| <= res_band_lim``.
    """

    structure: ClassVar[str] = "resonance"
    res_ares_r_min: float = 0.85
    res_bg_r_max: float = 0.95
    res_zeta_r_min: float = 0.95
    res_zeta_min_points: int = 20
    res_n_band: int = 0
    res_band: float = 0.05
    res_band_pool: int = 20000
    res_n_band_lim: int = 0
    res_band_lim: float = 0.05
    res_band_n_start: int = 2
    res_nc_local: float = 0.0
    res_bg_only_r: float = 0.0
    res_ares_local: float = 0.0

    def __post_init__(self) -> None:
        super().__post_init__()
        check_range("res_ares_r_min", self.res_ares_r_min, 0.0, 1.0)
        check_range("res_bg_r_max", self.res_bg_r_max, 0.0, 1.0)
        check_range("res_zeta_r_min", self.res_zeta_r_min, 0.0, 1.0)
        check_int("res_zeta_min_points", self.res_zeta_min_points, minimum=1)
        check_int("res_n_band", self.res_n_band, minimum=0)
        check_range("res_band", self.res_band, 0.0, 1.0, inclusive=False)
        check_int("res_band_pool", self.res_band_pool, minimum=1)
        check_int("res_n_band_lim", self.res_n_band_lim, minimum=0)
        check_range("res_band_lim", self.res_band_lim, 0.0, 1.0, inclusive=False)
        check_int("res_band_n_start", self.res_band_n_start, minimum=1)
        check_range("res_nc_local", self.res_nc_local, 0.0, 1.0)
        check_range("res_bg_only_r", self.res_bg_only_r, 0.0, 1.0)
        check_range("res_ares_local", self.res_ares_local, 0.0, 10.0)
        if self.res_bg_only_r > self.res_bg_r_max:
            raise ValueError(f"res_bg_only_r = {self.res_bg_only_r} is not allowed: must be "
                             f"<= res_bg_r_max = {self.res_bg_r_max} (the background model "
                             "is fitted only up to there)")

    def memory_bytes(self) -> dict[str, float]:
        """Peak bytes (``core.memory``): the sub-models' Kriging on up to ``n_doe + res_n_band
        + res_n_band_lim`` points (blamed on the largest) and the band screening's
        predictions on ``res_band_pool`` points (their covariances with the training points).

        >>> ResonanceOptions(res_band_pool=10 ** 12).memory_bytes()["res_band_pool"] > 1e14
        True
        """
        n = self.n_doe + self.res_n_band + self.res_n_band_lim
        key = max(("n_doe", "res_n_band", "res_n_band_lim"), key=lambda k: getattr(self, k))
        return {key: kriging_bytes(n), "res_band_pool": 8.0 * self.res_band_pool * (n + 16)}

    def check_response(self, response: ResponseSpec) -> None:
        if response.kind != "peak":
            why = ("its sub-models are of the peak of the geometry's fixed unbalance (θ = the "
                   "stiffness factors), not of random unbalance phasors" if
                   response.kind == "peak_unbalance" else
                   "the resonance structure models the peak over the speed range")
            raise ValueError(f"structure = 'resonance' is not allowed with response.kind = "
                             f"{response.kind!r}: {why}; use 'substructure', 'global' or 'fe'")


def band_points(Z: np.ndarray, nc_rpm: np.ndarray, bounds: np.ndarray, n_max_rpm: float,
                options: ResonanceOptions, *, rng: np.random.Generator, n_design: int = 3,
                amp_res_m: np.ndarray | None = None, threshold_m: float | None = None
                ) -> np.ndarray:
    """New joint points where the structured surrogate's boundaries lie.

    Without ``amp_res_m``: ``res_n_band`` points with predicted ``|n_max / n_c - 1| <=
    res_band`` (the critical-speed boundary). With ``amp_res_m`` and ``threshold_m``:
    ``res_n_band_lim`` points with the resonance in the range (``r̂ >= 1``) and
    ``|log Â_res - log threshold| <= res_band_lim`` (the second boundary: ``y ≈ A_res =
    δ_lim``). Kriging models of ``log n_c`` (and ``log A_res`` on the rows with ``r >= 1``)
    screen a random pool of ``res_band_pool`` points of ``bounds``; the candidates are
    thinned by greedy maximin. Fewer points are returned if the pool has fewer candidates.
    """
    o = options
    r_fit, r_pool, r_fit2 = require_rng(rng).spawn(3)
    fit = {"surrogate": o.surrogate, "transform": "log", "n_start": o.res_band_n_start,
           "n_design": n_design}
    sub = fit_transformed(Z, nc_rpm, rng=r_fit, **fit)
    pool = lhs(o.res_band_pool, bounds, rng=r_pool, criterion="random")
    r_hat = n_max_rpm / np.exp(sub.model.predict(pool, return_std=False).mean)
    if amp_res_m is None:
        return maximin_select(pool[np.abs(r_hat - 1.0) <= o.res_band], Z, bounds, o.res_n_band)
    if threshold_m is None or not threshold_m > 0:
        raise ValueError(f"threshold_m = {threshold_m!r} is not allowed: must be > 0")
    rows = n_max_rpm / nc_rpm >= 1.0
    ares = fit_transformed(Z[rows], amp_res_m[rows], rng=r_fit2, **fit)
    la = ares.model.predict(pool, return_std=False).mean
    near = (r_hat >= 1.0) & (np.abs(la - np.log(threshold_m)) <= o.res_band_lim)
    return maximin_select(pool[near], Z, bounds, o.res_n_band_lim)


def sample_resonance(spindle: Any, Z: np.ndarray, options: Any, *, cache: Any = None,
                     counter: Any = None, progress: bool = False, label: str = ""
                     ) -> tuple[np.ndarray, np.ndarray]:
    """FE resonance quantities at joint points (one counted, cached FE call per point): the
    points whose four outputs are finite and positive, and those outputs ``(n, 4)``."""
    return sample_positive(PointwiseResonance(spindle), Z, n_outputs=4, n_jobs=options.n_jobs,
                           backend=options.backend, cache=cache, counter=counter,
                           progress=progress, desc=f"{label} FE: resonance quantities".strip())


@register_structure("resonance", ResonanceOptions, "physics-structured Kriging of the peak: "
                    "critical speed, resonance height, flank and background sub-models",
                    refinable=True)
def train_resonance(spindle: Any, inputs: Any, limit: LimitState, response: ResponseSpec,
                    options: ResonanceOptions, *, rng: np.random.Generator, cache: Any = None,
                    counter: Any, progress: bool = False, label: str = "") -> TrainedSurrogate:
    """LHS → FE resonance quantities → band infill → sub-model fits (module docstring)."""
    o = options
    r_doe, r_fit = require_rng(rng).spawn(2)
    start, start_cached = counter.calls, counter.cached
    d = spindle.design_map.bounds.shape[0]
    bounds = o.bounds(spindle, inputs)
    n_max = float(spindle.geometry.speed_max_rpm)
    t0 = time.perf_counter()
    sample = partial(sample_resonance, spindle, options=o, cache=cache, counter=counter,
                     progress=progress, label=label)
    Z, Q = sample(lhs(o.n_doe, bounds, rng=r_doe))
    n_lhs = Z.shape[0]
    if o.res_n_band > 0:
        Zb, Qb = sample(band_points(Z, Q[:, 0], bounds, n_max, o, rng=r_doe.spawn(1)[0],
                                    n_design=d))
        Z, Q = np.vstack([Z, Zb]), np.vstack([Q, Qb])
    if o.res_n_band_lim > 0:
        Zb, Qb = sample(band_points(Z, Q[:, 0], bounds, n_max, o, rng=r_doe.spawn(1)[0],
                                    n_design=d, amp_res_m=Q[:, 1],
                                    threshold_m=limit.threshold))
        Z, Q = np.vstack([Z, Zb]), np.vstack([Q, Qb])
    sample_s = time.perf_counter() - t0
    model = fit_resonance_surrogate(Z, Q, o, rng=r_fit, n_max_rpm=n_max, n_design=d,
                                    is_band=np.arange(Z.shape[0]) >= n_lhs,
                                    threshold_m=limit.threshold)
    info = {**model.info, "n_lhs": n_lhs, "n_band": int(Z.shape[0] - n_lhs),
            "sampling_time_s": sample_s, "bounds": bounds.tolist(), "active_learning": False,
            "response": response.label}
    model.info = dict(info)
    return TrainedSurrogate("resonance", model, o, response, fe_calls=counter.calls - start,
                            fe_cache_hits=counter.cached - start_cached, info=info)


__all__ = ["ResonanceOptions", "band_points", "sample_resonance", "train_resonance"]
