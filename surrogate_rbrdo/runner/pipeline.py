"""The reusable surrogate pipeline: DOE → FE sampling (counted, cached, parallel) → Kriging fit
(optionally with AK-MCS-style enrichment near ``y = δ_lim``) → a fast ``Response``.

``train_peak_surrogate(spindle, inputs, limit, cfg, *, rng, ...)`` returns a fitted
:class:`PeakSurrogate` (the core ``Response``: ``(P, 3), (N, 2) -> (P, N)`` metres) and an info
dict (DOE size, FE calls, fit time, hyperparameters, AL history).

Response definition and transform
---------------------------------
``y`` is the peak tool-tip amplitude (m) over the speed range (``PeakAmplitudeResponse``) by
default, or the amplitude at one speed (``response=ResponseSpec("at_speed", n)``).
With ``transform = "log"`` (default) the Kriging model is fitted to ``log y`` and the response
returns ``exp(μ_log)`` (the median of the lognormal predictive distribution; a monotone map, so
``P[y > δ_lim]`` from the surrogate equals ``P[μ_log > log δ_lim]``). ``predict(Z)`` returns the
lognormal moments ``mean = exp(μ + s²/2)``, ``std = mean·sqrt(exp(s²) - 1)``. Why log: ``y``
spans 0.4–55 µm with a 10–50× jump where the first critical speed crosses the top of the speed
range; in log space the jump is a step of ~3–4 units on a smooth background of ~±1, and the
subcritical plateau (the designs that matter) is not swamped by the resonant region's variance
(numbers in ``docs/surrogates.md``).

θ box: ``"sigma"`` = ``mean ± theta_sigmas·std`` of ``inputs`` (default ±4σ: the MC samples
live there, P(outside) ≈ 6e-5 per component) or ``"bounds"`` = ``theta_bounds`` per component.

Active learning (``active_learning = true``): start from ``al_n_initial`` LHS points, candidate
pool = ``al_pool_designs`` LHS designs × ``al_pool_theta`` θ samples of ``inputs`` (a grid, so
the prediction with variance uses the separable predictor); each iteration adds ``al_batch_size``
pool points with the smallest ``U = |μ_t - t(δ_lim)| / σ_t`` (transformed space; at most one per
pool design, for diversity), evaluated by the FE model; stops when the fraction of pool points
with ``U < al_u_stop`` is ≤ ``al_uncertain_frac`` or after ``al_max_added`` points.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from surrogate_rbrdo.core.counting import CallCounter
from surrogate_rbrdo.core.protocols import LimitState, Prediction
from surrogate_rbrdo.core.rng import require_rng
from surrogate_rbrdo.core.validate import (
    check_choice,
    check_finite_array,
    check_int,
    check_positive,
    check_range,
)
from surrogate_rbrdo.doe import lhs
from surrogate_rbrdo.sampling import evaluate_points
from surrogate_rbrdo.sampling.evaluate import BACKENDS
from surrogate_rbrdo.spindle.evaluate import FE_METHODS, PointwiseResonance, ResponseSpec
from surrogate_rbrdo.surrogates import SURROGATES, GPROptions, KrigingOptions
from surrogate_rbrdo.surrogates.fast import ProductKernelPredictor

TRANSFORMS = ("log", "none")
THETA_BOXES = ("sigma", "bounds")
STRUCTURES = ("global", "resonance", "fe", "substructure")
#: structures without active learning, and why
_NO_ACTIVE_LEARNING = {
    "fe": "there is no surrogate to enrich",
    "substructure": "its DOE is over the designs only (θ is exact)",
    "resonance": "the structured surrogate uses a static DOE",
}


@dataclass(frozen=True)
class SurrogateConfig:
    """Options of the surrogate pipeline (also the TOML ``[surrogate]`` table).

    Attributes
    ----------
    n_doe : int
        Size of the static space-filling DOE (maximin LHS in the joint (x, θ) box).
    surrogate : str
        Name in ``SURROGATES`` (``krg_se``, ``krg_matern52``, ``gpr``).
    transform : {"log", "none"}
        Fit ``log y`` (default) or ``y``; see the module docstring.
    theta_box : {"sigma", "bounds"}
        θ part of the DOE box: ``mean ± theta_sigmas·std`` or ``theta_bounds``.
    theta_sigmas : float
    theta_bounds : (float, float)
    n_jobs : int
        Worker processes of the FE sampling.
    backend : str
        ``evaluate_points`` backend (``loky``, ``threading``, ``sequential``, ``dask``: a
        temporary local cluster with ``n_jobs`` workers).
    active_learning : bool
        Replace the static DOE by AK-MCS-style enrichment (``al_*`` options).
    n_start : int
        Multistarts of the hyperparameter optimisation (smt ``n_start`` / sklearn restarts + 1).
    al_n_initial, al_max_added, al_batch_size : int
        Initial LHS size, budget of added points, points added per iteration.
    al_pool_designs, al_pool_theta : int
        Candidate pool: LHS designs × θ samples of ``inputs``.
    al_u_stop : float
        U threshold of "uncertain" candidates (2: misclassification probability ≤ 2.3 %).
    al_uncertain_frac : float
        Stop when at most this fraction of the pool has ``U < al_u_stop``.
    al_n_start : int
        Multistarts during the AL refits (the final fit uses ``n_start``).
    structure : {"global", "resonance", "fe", "substructure"}
        ``"global"`` (default): one Kriging of ``t(y)`` (:class:`PeakSurrogate`).
        ``"fe"``: no surrogate: the full FE model in the loop (:class:`FullModel`), the
        ground truth a surrogate study is compared with (cheap for ``at_speed`` responses
        with ``fe_method`` "auto"/"condensed", ~3.5–7 ms per design for 1 000 θ; no DOE, no
        training).
        ``"substructure"``: a Kriging of the rotor's condensed dynamic stiffness over the
        design box (``n_doe`` designs, one FE call each; θ needs no DOE) coupled exactly with
        the bearing laws
        (:class:`~surrogate_rbrdo.runner.substructure_surrogate.SubstructureSurrogate`;
        ``transform`` and ``surrogate`` are ignored; static DOE only).
        ``"resonance"``: the physics-structured
        :class:`~surrogate_rbrdo.runner.resonance_surrogate.ResonanceSurrogate` (critical
        speed, resonance height, flank, background; ``transform`` is ignored, every sub-model
        is a log-Kriging; static DOE only).
    res_ares_r_min : float
        Resonance height sub-model trained on points with ``n_max / n_c >=`` this.
    res_bg_r_max : float
        Background sub-model trained on points with ``n_max / n_c <=`` this (< 1).
    res_zeta_r_min : float
        Effective damping ratio from flank points with ``res_zeta_r_min <= n_max/n_c < 1``.
    res_zeta_min_points : int
        Kriging of ``log ζ`` from at least this many flank points, else a constant ζ.
    res_n_band : int
        Points "where they matter" added after the ``n_doe`` LHS (structure ``"resonance"``):
        a Kriging of ``log n_c`` on the LHS predicts ``r = n_max / n_c`` on a random pool of
        ``res_band_pool`` joint points; ``res_n_band`` pool points with
        ``|r̂ - 1| <= res_band`` are chosen by greedy maximin (normalised box, distance to
        all points so far) and evaluated. Total FE calls: ``n_doe + res_n_band``.
    res_band : float
        Half-width of the band in ``r``.
    res_band_pool : int
        Size of the random candidate pool.
    res_n_band_lim : int
        Further points near the second boundary ``A_res = δ_lim`` with the resonance in the
        range (``|log Â_res - log δ_lim| <= res_band_lim``), after the ``n_c`` band.
    res_band_lim : float
        Half-width of that band in ``log A_res``.
    res_nc_local : float
        ``0`` (default): off. Otherwise a second, *local* Kriging of ``log n_c`` fitted only
        on the training points with ``|n_max / n_c - 1| <= res_nc_local`` (FE ``n_c``), used
        instead of the global one wherever the global ``r̂`` lies within ``res_band`` of 1
        (where the boundary is placed; docs/surrogates.md, run ``struct3``).
    res_bg_only_r : float
        ``0`` (default): off (``ŷ = max(flank, b̂)`` everywhere). Otherwise ``ŷ = b̂`` (the
        background Kriging alone, which is fitted to ``y`` itself there) wherever
        ``r̂ <= res_bg_only_r``; must not exceed ``res_bg_r_max``. Removes the SDOF flank's
        overshoot where resonance tail and background interfere (``subcritical_edge``).
    sub_n_speeds : int
        Structure ``"substructure"`` with the peak response: Chebyshev speed nodes at which
        the condensed stiffness is trained and between which it is interpolated.
    fe_method : str
        Structure ``"fe"``: how the FE model in the loop is solved (both exact;
        ``AtSpeedAmplitudeResponse``). ``"auto"`` (default): ``"condensed"`` for the at-speed
        response (rotor condensed once per design, the θ sample through 3^m node solves),
        ``"direct"`` for the peak (the only method there).
    res_ares_local : float
        ``0`` (default): off. Otherwise a second, *local* Kriging of ``log A_res`` fitted only
        on the training points with the resonance in the range (``r >= 1``) and
        ``|log A_res - log δ_lim| <= res_ares_local`` (typically the ``res_n_band_lim``
        points), used instead of the global one wherever ``|log Â_res - log δ_lim| <=
        res_band_lim`` (the second boundary; docs/surrogates.md, run ``struct4``).
    """

    n_doe: int = 200
    surrogate: str = "krg_se"
    transform: str = "log"
    theta_box: str = "sigma"
    theta_sigmas: float = 4.0
    theta_bounds: tuple[float, float] = (0.5, 1.5)
    n_jobs: int = 2
    backend: str = "loky"
    active_learning: bool = False
    n_start: int = 5
    al_n_initial: int = 60
    al_max_added: int = 140
    al_batch_size: int = 10
    al_pool_designs: int = 400
    al_pool_theta: int = 100
    al_u_stop: float = 2.0
    al_uncertain_frac: float = 0.002
    al_n_start: int = 2
    structure: str = "global"
    res_ares_r_min: float = 0.85
    res_bg_r_max: float = 0.95
    res_zeta_r_min: float = 0.95
    res_zeta_min_points: int = 20
    res_n_band: int = 0
    res_band: float = 0.05
    res_band_pool: int = 20000
    res_n_band_lim: int = 0
    res_band_lim: float = 0.05
    res_nc_local: float = 0.0
    res_bg_only_r: float = 0.0
    res_ares_local: float = 0.0
    sub_n_speeds: int = 12
    fe_method: str = "auto"

    def __post_init__(self) -> None:
        check_int("n_doe", self.n_doe, minimum=7)
        check_choice("surrogate", self.surrogate, sorted(SURROGATES))
        check_choice("transform", self.transform, TRANSFORMS)
        check_choice("theta_box", self.theta_box, THETA_BOXES)
        check_positive("theta_sigmas", self.theta_sigmas)
        tb = tuple(self.theta_bounds) if isinstance(self.theta_bounds, (list, tuple)) else None
        if tb is None or len(tb) != 2 or not all(
                isinstance(v, (int, float)) and not isinstance(v, bool) for v in tb) \
                or not 0 < tb[0] < tb[1] or not np.isfinite(tb[1]):
            raise ValueError(f"theta_bounds = {self.theta_bounds!r} is not allowed: must be "
                             "(lower, upper) with 0 < lower < upper")
        object.__setattr__(self, "theta_bounds", (float(tb[0]), float(tb[1])))
        check_int("n_jobs", self.n_jobs, minimum=1)
        check_choice("backend", self.backend, BACKENDS)
        if not isinstance(self.active_learning, bool):
            raise ValueError(f"active_learning = {self.active_learning!r} is not allowed: "
                             "must be true or false")
        check_int("n_start", self.n_start, minimum=1)
        check_int("al_n_initial", self.al_n_initial, minimum=7)
        check_int("al_max_added", self.al_max_added, minimum=0)
        check_int("al_batch_size", self.al_batch_size, minimum=1)
        check_int("al_pool_designs", self.al_pool_designs, minimum=1)
        check_int("al_pool_theta", self.al_pool_theta, minimum=1)
        check_positive("al_u_stop", self.al_u_stop)
        check_range("al_uncertain_frac", self.al_uncertain_frac, 0.0, 1.0)
        check_int("al_n_start", self.al_n_start, minimum=1)
        check_choice("structure", self.structure, STRUCTURES)
        check_range("res_ares_r_min", self.res_ares_r_min, 0.0, 1.0)
        check_range("res_bg_r_max", self.res_bg_r_max, 0.0, 1.0)
        check_range("res_zeta_r_min", self.res_zeta_r_min, 0.0, 1.0)
        check_int("res_zeta_min_points", self.res_zeta_min_points, minimum=1)
        check_int("res_n_band", self.res_n_band, minimum=0)
        check_range("res_band", self.res_band, 0.0, 1.0, inclusive=False)
        check_int("res_band_pool", self.res_band_pool, minimum=1)
        check_int("res_n_band_lim", self.res_n_band_lim, minimum=0)
        check_range("res_band_lim", self.res_band_lim, 0.0, 1.0, inclusive=False)
        check_range("res_nc_local", self.res_nc_local, 0.0, 1.0)
        check_range("res_bg_only_r", self.res_bg_only_r, 0.0, 1.0)
        check_range("res_ares_local", self.res_ares_local, 0.0, 10.0)
        if self.res_bg_only_r > self.res_bg_r_max:
            raise ValueError(f"res_bg_only_r = {self.res_bg_only_r} is not allowed: must be "
                             f"<= res_bg_r_max = {self.res_bg_r_max} (the background model "
                             "is fitted only up to there)")
        if self.active_learning and self.structure in _NO_ACTIVE_LEARNING:
            raise ValueError(f"active_learning = True is not allowed with structure = "
                             f"{self.structure!r}: {_NO_ACTIVE_LEARNING[self.structure]}")
        check_int("sub_n_speeds", self.sub_n_speeds, minimum=2)
        check_choice("fe_method", self.fe_method, ("auto", *FE_METHODS))
        if self.fe_method != "auto" and self.structure != "fe":
            raise ValueError(f"fe_method = {self.fe_method!r} is not allowed with structure = "
                             f"{self.structure!r}: it sets how the FE model in the loop is "
                             "solved (structure = 'fe')")

    @classmethod
    def from_dict(cls, table: dict[str, Any]) -> SurrogateConfig:
        """From a TOML ``[surrogate]`` table; unknown keys raise, listing the allowed ones."""
        from dataclasses import fields

        from surrogate_rbrdo.core.validate import check_keys

        check_keys("[surrogate]", table, [f.name for f in fields(cls)])
        kw = dict(table)
        if "theta_bounds" in kw and isinstance(kw["theta_bounds"], list):
            kw["theta_bounds"] = tuple(kw["theta_bounds"])
        return cls(**kw)

    def to_dict(self) -> dict[str, Any]:
        from dataclasses import asdict

        return asdict(self)


# ---------------------------------------------------------------------- transforms
def forward(y: np.ndarray, transform: str) -> np.ndarray:
    """``t(y)``: ``log y`` or ``y``."""
    y = np.asarray(y, dtype=float)
    return np.log(y) if transform == "log" else y


def inverse(t: np.ndarray, transform: str) -> np.ndarray:
    """``y = t⁻¹(t)``: ``exp t`` or ``t``."""
    return np.exp(t) if transform == "log" else np.asarray(t, dtype=float)


# ---------------------------------------------------------------------- the fitted surrogate
@dataclass(eq=False)
class PeakSurrogate:
    """Fitted surrogate of the peak amplitude; ``y`` in metres at the interface.

    Calling it (or :meth:`response`) is the core ``Response``. The θ block of the separable
    predictor is cached keyed on the identity of the θ array (``id`` and shape; the array is
    kept referenced so the id cannot be reused): pass the same CRN sample object each time and
    every call costs one design block and one matrix product. Do not modify a θ array in place
    between calls (copy it instead).

    Attributes
    ----------
    model : Surrogate
        The fitted wrapper (``KrgSE``, ...), trained on ``(Z, t(y))``.
    fast : ProductKernelPredictor
    transform : {"log", "none"}
    n_design : int
    info : dict
    theta_block_builds : int
        How many θ blocks were computed (cache misses).
    """

    model: Any
    fast: ProductKernelPredictor
    transform: str
    n_design: int = 3
    info: dict[str, Any] = field(default_factory=dict)
    theta_block_builds: int = 0
    _blocks: dict[tuple[int, tuple[int, ...]], tuple[np.ndarray, Any]] = field(
        default_factory=dict, repr=False)
    max_cached_blocks: int = 4

    @property
    def n_train(self) -> int:
        return int(self.model.y_train_.size)

    def theta_block(self, theta: np.ndarray) -> Any:
        """The (cached) θ block of ``theta``."""
        key = (id(theta), np.shape(theta))
        hit = self._blocks.get(key)
        if hit is not None and hit[0] is theta:
            return hit[1]
        block = self.fast.prepare_theta(theta)
        self.theta_block_builds += 1
        if len(self._blocks) >= self.max_cached_blocks:
            self._blocks.pop(next(iter(self._blocks)))
        self._blocks[key] = (theta, block)
        return block

    def response(self, x: np.ndarray, theta: np.ndarray) -> np.ndarray:
        """Predicted ``y`` (m) for designs ``x`` (P, 3) × θ ``(N, 2)`` → ``(P, N)``.

        With the log transform this is ``exp(μ_log)`` (the predictive median).
        """
        t = self.fast.predict_grid(x, self.theta_block(theta)).mean
        return inverse(t, self.transform)

    __call__ = response

    def predict_transformed(self, x: np.ndarray, theta: np.ndarray, *,
                            return_std: bool = True) -> Prediction:
        """Mean and std of ``t(y)`` on the grid (no inverse transform)."""
        return self.fast.predict_grid(x, self.theta_block(theta), return_std=return_std)

    def response_points(self, Z: np.ndarray) -> np.ndarray:
        """``y`` (m) at joint points ``Z = [x, θ]``: the quantity of :meth:`response`."""
        Z = np.atleast_2d(np.asarray(Z, dtype=float))
        return inverse(self.model.predict(Z, return_std=False).mean, self.transform)

    def predict(self, Z: np.ndarray) -> Prediction:
        """Mean and std (m) at joint points ``Z = [x, θ]`` (n, 5).

        ``transform = "log"``: lognormal moments of ``exp(N(μ, s²))``; ``"none"``: the Kriging
        mean and std themselves.
        """
        p = self.model.predict(np.atleast_2d(np.asarray(Z, dtype=float)))
        if self.transform == "none":
            return p
        mean = np.exp(p.mean + 0.5 * p.std**2)
        return Prediction(mean=mean, std=mean * np.sqrt(np.expm1(p.std**2)))


@dataclass(eq=False)
class FullModel:
    """The full FE model behind the surrogate interface (``structure = "fe"``).

    ``response(x, θ)`` runs the FE model for every design and θ sample: the reference a
    surrogate-based study is judged against. Its calls are FE calls.

    >>> import numpy as np
    >>> from surrogate_rbrdo.spindle.evaluate import ResponseSpec
    >>> from surrogate_rbrdo.spindle.reference import reference_spindle
    >>> fm = FullModel(ResponseSpec("at_speed", 24000.0).fe_response(reference_spindle()))
    >>> fm.response(np.array([[3000.0, 600.0, 80.0]]), np.ones((2, 2))).shape
    (1, 2)
    """

    fe: Any
    info: dict[str, Any] = field(default_factory=dict)
    n_train: int = 0

    def response(self, x: np.ndarray, theta: np.ndarray) -> np.ndarray:
        """FE ``y`` (m) for designs ``x`` (P, 3) × θ (N, m) → (P, N)."""
        return self.fe(x, theta)

    __call__ = response

    def response_points(self, Z: np.ndarray) -> np.ndarray:
        """FE ``y`` (m) at joint points ``Z = [x, θ]``."""
        return np.array([self.fe.point(z) for z in np.atleast_2d(np.asarray(Z, dtype=float))])


def check_structure_response(cfg: SurrogateConfig, response: ResponseSpec) -> None:
    """Refuse a surrogate structure (or FE method) that cannot model ``response``."""
    if cfg.structure == "resonance" and response.kind != "peak":
        raise ValueError(f"surrogate.structure = 'resonance' is not allowed with response.kind "
                         f"= {response.kind!r}: the resonance structure models the peak over "
                         "the speed range; use 'global', 'substructure' or 'fe'")
    if cfg.fe_method == "condensed" and response.kind == "peak":
        raise ValueError("surrogate.fe_method = 'condensed' is not allowed with response.kind = "
                         "'peak': only 'direct' or 'auto' (the peak is searched per θ)")


# ---------------------------------------------------------------------- building blocks
def joint_bounds(spindle: Any, inputs: Any, cfg: SurrogateConfig) -> np.ndarray:
    """The (3 + m, 2) joint DOE box: the design box and the θ box of ``cfg``."""
    xb = np.asarray(spindle.design_map.bounds, dtype=float)
    mean = np.asarray(inputs.mean, dtype=float)
    if cfg.theta_box == "sigma":
        std = np.sqrt(np.diag(np.asarray(inputs.cov, dtype=float)))
        tb = np.column_stack([mean - cfg.theta_sigmas * std, mean + cfg.theta_sigmas * std])
    else:
        tb = np.tile(np.asarray(cfg.theta_bounds, dtype=float), (mean.size, 1))
    return np.vstack([xb, tb])


def build_doe(n: int, bounds: np.ndarray, *, rng: np.random.Generator) -> np.ndarray:
    """Maximin LHS of ``n`` points in ``bounds``."""
    return lhs(n, bounds, rng=require_rng(rng))


def fe_cache(cache_dir: str | Path | None) -> Any:
    """A ``joblib.Memory`` under ``cache_dir/fe_points`` (``None``: no cache)."""
    if cache_dir is None:
        return None
    import joblib

    return joblib.Memory(location=str(Path(cache_dir) / "fe_points"), verbose=0)


def sample_fe(spindle: Any, Z: np.ndarray, cfg: SurrogateConfig, *, cache: Any = None,
              counter: CallCounter | None = None, progress: bool = False,
              response: ResponseSpec | None = None) -> tuple[np.ndarray, np.ndarray]:
    """FE response ``y`` (m; default the peak amplitude, else ``response``) at joint points
    ``Z`` via ``evaluate_points`` (counted, cached).

    Returns the points with a finite positive value and their values.
    """
    Z = check_finite_array("Z", Z, ndim=2)
    response = ResponseSpec() if response is None else response
    res = evaluate_points(
        response.pointwise(spindle), Z, n_jobs=cfg.n_jobs, backend=cfg.backend, cache=cache,
        counter=counter, on_nonfinite="exclude", progress=progress,
        client="local" if cfg.backend == "dask" else None)
    ok = res.y > 0
    ok &= res.ok_mask
    return Z[ok], res.y[ok]


def sample_resonance(spindle: Any, Z: np.ndarray, cfg: SurrogateConfig, *, cache: Any = None,
                     counter: CallCounter | None = None, progress: bool = False
                     ) -> tuple[np.ndarray, np.ndarray]:
    """FE resonance quantities at joint points (one counted, cached FE call per point).

    Returns the points whose four outputs (``critical_rpm, amp_res_m, amp_top_m, peak_m``) are
    finite and positive, and those outputs ``(n, 4)``. Cached apart from :func:`sample_fe`
    (a different function and a vector-output cache entry).
    """
    Z = check_finite_array("Z", Z, ndim=2)
    res = evaluate_points(
        PointwiseResonance(spindle), Z, n_jobs=cfg.n_jobs, backend=cfg.backend, cache=cache,
        counter=counter, on_nonfinite="exclude", progress=progress, n_outputs=4,
        client="local" if cfg.backend == "dask" else None)
    ok = res.ok_mask & np.all(np.where(np.isfinite(res.y), res.y, 0.0) > 0, axis=1)
    return Z[ok], res.y[ok]


def _maximin_select(cand: np.ndarray, Z: np.ndarray, bounds: np.ndarray, n: int, *,
                    min_dist: float = 0.0) -> np.ndarray:
    """Greedy maximin: ``n`` rows of ``cand``, each the farthest (unit-scaled box) from all
    points so far (``Z`` included); stops early when the farthest is nearer than
    ``min_dist``."""
    lo, span = bounds[:, 0], bounds[:, 1] - bounds[:, 0]
    cu, zu = (cand - lo) / span, (Z - lo) / span
    dmin = np.full(cand.shape[0], np.inf)
    for a in range(0, zu.shape[0], 256):
        d = np.sqrt(((cu[:, None, :] - zu[None, a:a + 256, :]) ** 2).sum(-1))
        dmin = np.minimum(dmin, d.min(axis=1))
    chosen: list[int] = []
    for _ in range(min(n, cand.shape[0])):
        i = int(np.argmax(dmin))
        if dmin[i] < min_dist:
            break
        chosen.append(i)
        dmin = np.minimum(dmin, np.sqrt(((cu - cu[i]) ** 2).sum(-1)))
        dmin[i] = -np.inf
    return cand[chosen]


def band_points(Z: np.ndarray, nc_rpm: np.ndarray, bounds: np.ndarray, n_max_rpm: float,
                cfg: SurrogateConfig, *, rng: np.random.Generator, n_design: int = 3,
                amp_res_m: np.ndarray | None = None, threshold_m: float | None = None
                ) -> np.ndarray:
    """New joint points where the structured surrogate's boundaries lie.

    Without ``amp_res_m``: ``cfg.res_n_band`` points with predicted
    ``|n_max / n_c - 1| <= res_band`` (the critical-speed boundary). With ``amp_res_m`` and
    ``threshold_m``: ``cfg.res_n_band_lim`` points with the resonance in the range
    (``r̂ >= 1``) and ``|log Â_res - log threshold| <= res_band_lim`` (the second boundary:
    ``y ≈ A_res = δ_lim``). Kriging models of ``log n_c`` (and ``log A_res`` on the rows with
    ``r >= 1``) screen a random pool of ``res_band_pool`` points of ``bounds``; the
    candidates are thinned by greedy maximin. Fewer points are returned if the pool has fewer
    candidates.
    """
    r_fit, r_pool, r_fit2 = require_rng(rng).spawn(3)
    sub_cfg = replace(cfg, transform="log", structure="global")
    sub = fit_surrogate(Z, nc_rpm, sub_cfg, rng=r_fit, n_start=cfg.al_n_start,
                        n_design=n_design)
    pool = lhs(cfg.res_band_pool, bounds, rng=r_pool, criterion="random")
    r_hat = n_max_rpm / np.exp(sub.model.predict(pool, return_std=False).mean)
    if amp_res_m is None:
        return _maximin_select(pool[np.abs(r_hat - 1.0) <= cfg.res_band], Z, bounds,
                               cfg.res_n_band)
    if threshold_m is None or not threshold_m > 0:
        raise ValueError(f"threshold_m = {threshold_m!r} is not allowed: must be > 0")
    rows = n_max_rpm / nc_rpm >= 1.0
    ares = fit_surrogate(Z[rows], amp_res_m[rows], sub_cfg, rng=r_fit2,
                         n_start=cfg.al_n_start, n_design=n_design)
    la = ares.model.predict(pool, return_std=False).mean
    near = (r_hat >= 1.0) & (np.abs(la - np.log(threshold_m)) <= cfg.res_band_lim)
    return _maximin_select(pool[near], Z, bounds, cfg.res_n_band_lim)


def fit_surrogate(Z: np.ndarray, y: np.ndarray, cfg: SurrogateConfig, *,
                  rng: np.random.Generator, n_start: int | None = None,
                  n_design: int = 3, like: PeakSurrogate | None = None,
                  like_mode: str = "warm") -> PeakSurrogate:
    """Fit ``cfg.surrogate`` to ``(Z, t(y))`` and wrap it (``y`` in metres, > 0).

    ``like``: a fitted smt-Kriging ``PeakSurrogate`` whose *physical* length scales start
    (``like_mode = "warm"``: one local likelihood optimisation from them) or are kept
    (``"keep"``: no optimisation, the old model conditioned on the new data). smt normalises
    inputs by their sample std ``s``; the kernel weights are rescaled so that ``w / s²``
    (squared exponential) or ``w / s`` (Matérn 5/2) is unchanged. Used by the refinement loop:
    a fresh multistart optimisation on clustered infill points changed the fit far from them,
    and kept length scales made near-duplicate points (θ-weights ~1e-3) ill-conditioned
    (docs/paper-study.md).
    """
    n_start = cfg.n_start if n_start is None else n_start
    cls = SURROGATES[cfg.surrogate]
    if like is not None and cfg.surrogate != "gpr":
        f = like.fast
        p = 2.0 if f.kernel == "se" else 1.0
        s_new = np.asarray(Z, dtype=float).std(axis=0, ddof=1)
        w = np.asarray(f.weights) * (s_new / np.asarray(f.scale)) ** p
        check_choice("like_mode", like_mode, ("warm", "keep"))
        d = KrigingOptions()
        opts = KrigingOptions(theta0=tuple(np.clip(w, d.theta_lower, d.theta_upper)), n_start=1,
                              hyper_opt="NoOp" if like_mode == "keep" else "TNC")
    else:
        opts = (GPROptions(n_restarts=n_start - 1) if cfg.surrogate == "gpr"
                else KrigingOptions(n_start=n_start))
    t0 = time.perf_counter()
    model = cls(opts, rng=require_rng(rng)).fit(Z, forward(y, cfg.transform))
    fit_s = time.perf_counter() - t0
    fast = ProductKernelPredictor.from_model(model, n_design=n_design)
    info = {"n_train": int(y.size), "fit_time_s": fit_s,
            "hyperparameters": np.asarray(fast.weights).tolist(),
            "surrogate": cfg.surrogate, "transform": cfg.transform}
    return PeakSurrogate(model=model, fast=fast, transform=cfg.transform,
                         n_design=n_design, info=info)


# ---------------------------------------------------------------------- active learning
def active_learning(spindle: Any, inputs: Any, limit: LimitState, cfg: SurrogateConfig, *,
                    rng: np.random.Generator, cache: Any = None,
                    counter: CallCounter | None = None, progress: bool = False,
                    response: ResponseSpec | None = None
                    ) -> tuple[np.ndarray, np.ndarray, list[dict[str, Any]], str]:
    """AK-MCS-style enrichment (see the module docstring). Returns ``Z, y, history, reason``."""
    rng = require_rng(rng)
    r_doe, r_pool_x, r_pool_t, r_fit = rng.spawn(4)
    bounds = joint_bounds(spindle, inputs, cfg)
    d = spindle.design_map.bounds.shape[0]
    Z, y = sample_fe(spindle, build_doe(cfg.al_n_initial, bounds, rng=r_doe), cfg,
                     cache=cache, counter=counter, progress=progress, response=response)
    pool_x = lhs(cfg.al_pool_designs, bounds[:d], rng=r_pool_x, criterion="random")
    pool_t = inputs.sample(cfg.al_pool_theta, rng=r_pool_t)
    used = np.zeros((pool_x.shape[0], pool_t.shape[0]), dtype=bool)
    thr = float(forward(limit.threshold, cfg.transform))
    history: list[dict[str, Any]] = []
    n_added, reason = 0, "al_max_added reached"
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=cfg.al_max_added, desc="active learning", unit="pt")
    try:
        while True:
            sur = fit_surrogate(Z, y, cfg, rng=r_fit.spawn(1)[0], n_start=cfg.al_n_start,
                                n_design=d)
            p = sur.predict_transformed(pool_x, pool_t)
            with np.errstate(divide="ignore", invalid="ignore"):
                U = np.where(p.std > 0, np.abs(p.mean - thr) / p.std, np.inf)
            U[used] = np.inf
            frac = float(np.mean(U < cfg.al_u_stop))
            pf = float(np.mean(limit.failed(inverse(p.mean, cfg.transform))))
            history.append({"n_points": int(y.size), "pf_pool": pf, "min_u": float(U.min()),
                            "uncertain_frac": frac})
            if frac <= cfg.al_uncertain_frac:
                reason = f"uncertain fraction {frac:.4f} <= {cfg.al_uncertain_frac}"
                break
            if n_added >= cfg.al_max_added:
                break
            k = min(cfg.al_batch_size, cfg.al_max_added - n_added)
            best_t = np.argmin(U, axis=1)                  # best θ per pool design
            best_u = U[np.arange(U.shape[0]), best_t]
            rows = np.argsort(best_u, kind="stable")[:k]
            rows = rows[np.isfinite(best_u[rows])]
            if rows.size == 0:
                reason = "pool exhausted"
                break
            used[rows, best_t[rows]] = True
            new = np.column_stack([pool_x[rows], pool_t[best_t[rows]]])
            Zn, yn = sample_fe(spindle, new, cfg, cache=cache, counter=counter,
                               response=response)
            Z, y = np.vstack([Z, Zn]), np.concatenate([y, yn])
            n_added += rows.size
            if bar is not None:
                bar.update(rows.size)
    finally:
        if bar is not None:
            bar.close()
    return Z, y, history, reason


def _train_substructure(spindle: Any, cfg: SurrogateConfig, response: ResponseSpec, *,
                        rng: tuple[np.random.Generator, np.random.Generator], cache: Any,
                        counter: CallCounter, progress: bool, t0: float, start: int
                        ) -> tuple[Any, dict[str, Any]]:
    """Structure ``"substructure"``: LHS over the designs → FE condensations → fit."""
    from surrogate_rbrdo.runner.substructure_surrogate import (
        fit_substructure_surrogate,
        speed_nodes,
    )
    from surrogate_rbrdo.spindle.substructure import PointwiseCondensed, retained_layout

    r_doe, r_fit = rng
    xb = np.asarray(spindle.design_map.bounds, dtype=float)
    nodes = speed_nodes(spindle, response.kind, response.speed_rpm, cfg.sub_n_speeds)
    m0 = spindle.model(spindle.baseline)
    lay = retained_layout(m0)
    func = PointwiseCondensed(spindle, tuple(float(s) for s in nodes), lay.nodes,
                              tuple(complex(u) for u in m0.unbalance))
    X = build_doe(cfg.n_doe, xb, rng=r_doe)
    res = evaluate_points(
        func, X, n_jobs=cfg.n_jobs, backend=cfg.backend, cache=cache, counter=counter,
        on_nonfinite="raise", progress=progress, n_outputs=func.n_outputs(lay.n_dof),
        client="local" if cfg.backend == "dask" else None)
    sample_s = time.perf_counter() - t0
    sur = fit_substructure_surrogate(spindle, X, res.y, kind=response.kind,
                                     speed_rpm=response.speed_rpm, nodes_rpm=nodes, rng=r_fit,
                                     n_start=cfg.n_start)
    info = {**sur.info, "fe_calls": counter.calls - start, "sampling_time_s": sample_s,
            "bounds": xb.tolist(), "active_learning": False, "config": cfg.to_dict(),
            "response": response.label}
    sur.info = info
    return sur, info


# ---------------------------------------------------------------------- entry point
def train_peak_surrogate(spindle: Any, inputs: Any, limit: LimitState, cfg: SurrogateConfig,
                         *, rng: np.random.Generator, cache_dir: str | Path | None = None,
                         progress: bool = False, counter: CallCounter | None = None,
                         response: ResponseSpec | None = None
                         ) -> tuple[PeakSurrogate, dict[str, Any]]:
    """DOE (static or active) → FE sampling → fit; returns the surrogate and an info dict.

    ``response`` says what ``y`` is (default: the peak amplitude). With ``cfg.structure =
    "fe"`` no surrogate is built: the returned :class:`FullModel` runs the FE model, and its
    calls are *not* seen by ``counter`` (the caller counts them, as the study does with the
    optimiser's call counts).

    With ``cfg.structure = "substructure"`` the returned surrogate is a
    :class:`~surrogate_rbrdo.runner.substructure_surrogate.SubstructureSurrogate` trained on
    ``n_doe`` designs (one FE condensation each; θ is coupled exactly, so the DOE has none).

    With ``cfg.structure = "resonance"`` the returned surrogate is a
    :class:`~surrogate_rbrdo.runner.resonance_surrogate.ResonanceSurrogate` (same interface:
    ``response``, ``__call__``, ``predict``, ``n_train``, ``info``), trained on the FE
    resonance quantities of the same static DOE.

    Parameters
    ----------
    spindle : ReferenceSpindle
    inputs : RandomVector
        θ distribution (``mean``, ``cov``, ``sample``): sets the θ box and the AL pool.
    limit : LimitState
        ``δ_lim`` (used by active learning).
    cfg : SurrogateConfig
    rng : numpy.random.Generator
    cache_dir : path, optional
        FE results are cached (resumable) under ``cache_dir/fe_points``.
    progress : bool
    counter : CallCounter, optional
        Receives every FE call (a new one is made if omitted; its total is in the info).
    response : ResponseSpec, optional
    """
    if not isinstance(cfg, SurrogateConfig):
        raise ValueError(f"cfg = {cfg!r} is not allowed: must be a SurrogateConfig")
    response = ResponseSpec() if response is None else response
    if not isinstance(response, ResponseSpec):
        raise ValueError(f"response = {response!r} is not allowed: must be a ResponseSpec")
    check_structure_response(cfg, response)
    if cfg.structure == "fe":
        method = cfg.fe_method if cfg.fe_method != "auto" else (
            "condensed" if response.kind == "at_speed" else "direct")
        info = {"structure": "fe", "response": response.label, "fe_calls": 0,
                "n_train": 0, "config": {"structure": "fe", "fe_method": method}}
        return FullModel(response.fe_response(spindle, method), info=info), info
    rng = require_rng(rng)
    r_doe, r_fit = rng.spawn(2)
    counter = counter if counter is not None else CallCounter()
    start = counter.calls
    cache = fe_cache(cache_dir)
    d = spindle.design_map.bounds.shape[0]
    t0 = time.perf_counter()
    if cfg.structure == "substructure":
        return _train_substructure(spindle, cfg, response, rng=(r_doe, r_fit), cache=cache,
                                   counter=counter, progress=progress, t0=t0, start=start)
    history: list[dict[str, Any]] = []
    reason = ""
    if cfg.structure == "resonance":
        from surrogate_rbrdo.runner.resonance_surrogate import fit_resonance_surrogate

        bounds = joint_bounds(spindle, inputs, cfg)
        n_max = float(spindle.geometry.speed_max_rpm)
        Z = build_doe(cfg.n_doe, bounds, rng=r_doe)
        Z, Q = sample_resonance(spindle, Z, cfg, cache=cache, counter=counter,
                                progress=progress)
        n_lhs = Z.shape[0]
        if cfg.res_n_band > 0:
            Zb = band_points(Z, Q[:, 0], bounds, n_max, cfg, rng=r_doe.spawn(1)[0],
                             n_design=d)
            Zb, Qb = sample_resonance(spindle, Zb, cfg, cache=cache, counter=counter,
                                      progress=progress)
            Z, Q = np.vstack([Z, Zb]), np.vstack([Q, Qb])
        if cfg.res_n_band_lim > 0:
            Zb = band_points(Z, Q[:, 0], bounds, n_max, cfg, rng=r_doe.spawn(1)[0],
                             n_design=d, amp_res_m=Q[:, 1], threshold_m=limit.threshold)
            Zb, Qb = sample_resonance(spindle, Zb, cfg, cache=cache, counter=counter,
                                      progress=progress)
            Z, Q = np.vstack([Z, Zb]), np.vstack([Q, Qb])
        sample_s = time.perf_counter() - t0
        rsur = fit_resonance_surrogate(Z, Q, cfg, rng=r_fit, n_max_rpm=n_max, n_design=d,
                                       is_band=np.arange(Z.shape[0]) >= n_lhs,
                                       threshold_m=limit.threshold)
        rsur.info["n_lhs"], rsur.info["n_band"] = n_lhs, int(Z.shape[0] - n_lhs)
        info = {**rsur.info, "fe_calls": counter.calls - start, "sampling_time_s": sample_s,
                "bounds": joint_bounds(spindle, inputs, cfg).tolist(),
                "active_learning": False, "config": cfg.to_dict()}
        rsur.info = info
        return rsur, info
    if cfg.active_learning:
        Z, y, history, reason = active_learning(spindle, inputs, limit, cfg, rng=r_doe,
                                                cache=cache, counter=counter,
                                                progress=progress, response=response)
    else:
        Z = build_doe(cfg.n_doe, joint_bounds(spindle, inputs, cfg), rng=r_doe)
        Z, y = sample_fe(spindle, Z, cfg, cache=cache, counter=counter, progress=progress,
                         response=response)
    sample_s = time.perf_counter() - t0
    sur = fit_surrogate(Z, y, cfg, rng=r_fit, n_design=d)
    info = {**sur.info, "fe_calls": counter.calls - start, "sampling_time_s": sample_s,
            "bounds": joint_bounds(spindle, inputs, cfg).tolist(),
            "active_learning": cfg.active_learning, "config": cfg.to_dict(),
            "response": response.label}
    if cfg.active_learning:
        info.update(al_history=history, al_stop_reason=reason)
    sur.info = info
    return sur, info
