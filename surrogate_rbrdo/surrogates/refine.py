"""Refinement of the surrogate where the optimiser went (infill at the chosen designs).

Why: a surrogate validated at fixed designs can still be wrong exactly where an optimiser
goes, because the optimiser *seeks* the designs the surrogate under-predicts (measured on the
reference study: with the ``resonance4_lim`` options the chosen RBRDO design had μ 0.29 µm
predicted vs 0.46 µm by the FE, docs/paper-study.md). The remedy is the usual infill loop of
surrogate-based optimisation: evaluate the FE model at the designs the optimiser chose (each on
a few θ samples), measure the surrogate's error there, add the points to the training set,
refit and optimise again, until the error at the chosen designs is below a tolerance.

:func:`select_designs` picks the designs (compromises first, then the extremes and a spread of
each front); :func:`refine_surrogate` evaluates them with the FE model, reports the error
*before* the refit and returns the refitted surrogate.

>>> import numpy as np
>>> fronts = {"a": np.array([[1.0, 300.0, 50.0], [2.0, 400.0, 60.0], [3.0, 500.0, 70.0]])}
>>> bounds = np.array([[0.0, 4.0], [300.0, 700.0], [50.0, 80.0]])
>>> select_designs([np.array([1.0, 300.0, 50.0])], fronts, bounds, 2).tolist()
[[1.0, 300.0, 50.0], [3.0, 500.0, 70.0]]
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from surrogate_rbrdo.core.validate import check_choice, check_int, check_positive
from surrogate_rbrdo.doe.infill import maximin_select
from surrogate_rbrdo.sampling.fe import sample_positive
from surrogate_rbrdo.surrogates.structured.base import STRUCTURES, TrainedSurrogate
from surrogate_rbrdo.surrogates.structured.resonance import fit_resonance_surrogate
from surrogate_rbrdo.surrogates.structured.resonance_train import sample_resonance
from surrogate_rbrdo.surrogates.transformed import fit_transformed


@dataclass(frozen=True)
class RefineOptions:
    """``[refine]`` of a study: the infill loop at the optimiser's designs.

    Parameters
    ----------
    rounds : int
        Maximum refinement rounds (0: off). Each round: FE at the chosen designs, refit,
        optimise again.
    designs : int
        Designs per round (compromises first, then front extremes and spread).
    theta : int
        θ samples per design (a fresh sample per round, shared by the round's designs).
    tol : float
        Stop (without refitting) once ``max |μ̂ − μ_FE| / μ_FE`` over the round's designs,
        on its θ sample, is at most ``tol``.
    hyper : {"warm", "keep", "refit"}
        ``"warm"``: one local likelihood optimisation started from the previous length scales;
        ``"keep"``: condition on the new points with them; ``"refit"``: fresh multistart.
    """

    rounds: int = 0
    designs: int = 8
    theta: int = 8
    tol: float = 0.05
    hyper: str = "warm"

    def __post_init__(self) -> None:
        check_int("refine.rounds", self.rounds, minimum=0)
        check_int("refine.designs", self.designs, minimum=1)
        check_int("refine.theta", self.theta, minimum=2)
        check_positive("refine.tol", self.tol)
        check_choice("refine.hyper", self.hyper, ("warm", "keep", "refit"))

    def memory_bytes(self) -> dict[str, float]:
        """Peak bytes (``core.memory``): every round adds ``designs × theta`` (x, θ) points to
        the surrogate, whose Kriging holds ~10 matrices of (points added)² (the DOE's own
        points are the structure's share); blamed on the larger of ``designs`` and ``theta``.

        >>> RefineOptions(rounds=1, theta=10 ** 11).memory_bytes()["theta"] > 1e20
        True
        """
        n = float(self.rounds) * self.designs * self.theta
        key = "theta" if self.theta >= self.designs else "designs"
        return {key: 8.0 * (10.0 * n * n + 16.0 * n)}


def select_designs(priority: Sequence[np.ndarray], fronts: Mapping[str, np.ndarray],
                   bounds: np.ndarray, n: int, *, min_dist: float = 0.02) -> np.ndarray:
    """Up to ``n`` distinct designs: ``priority`` (e.g. compromises) first, then each front's
    two ends, then its points farthest (greedy maximin in the unit box) from those chosen.

    Designs closer than ``min_dist`` (unit-box Euclidean) to a chosen one are skipped.
    """
    bounds = np.asarray(bounds, dtype=float)
    lo, span = bounds[:, 0], bounds[:, 1] - bounds[:, 0]
    chosen: list[np.ndarray] = []

    def unit(x: np.ndarray) -> np.ndarray:
        return (np.asarray(x, dtype=float) - lo) / span

    def far(x: np.ndarray) -> float:
        if not chosen:
            return np.inf
        return float(np.min(np.linalg.norm(unit(np.array(chosen)) - unit(x), axis=1)))

    def add(x: np.ndarray) -> None:
        if len(chosen) < n and far(x) >= min_dist:
            chosen.append(np.asarray(x, dtype=float))

    for x in priority:
        add(x)
    F = [np.asarray(f, dtype=float) for f in fronts.values() if np.size(f)]
    for f in F:  # a front's rows are sorted by the first objective: its two ends
        add(f[0])
        add(f[-1])
    X = np.array(chosen).reshape(-1, bounds.shape[0])
    if F and len(chosen) < n:  # the spread: greedy maximin over the fronts' designs
        X = np.vstack([X, maximin_select(np.vstack(F), X, bounds, n - len(chosen),
                                         min_dist=min_dist)])
    return X


def _errors(model: Any, Zn: np.ndarray, yn: np.ndarray, X: np.ndarray, M: int
            ) -> dict[str, Any]:
    """The surrogate's error at the refinement points (before a refit)."""
    P = X.shape[0]
    y_hat = model.response_points(Zn)
    rel = np.abs(y_hat - yn) / yn
    des = np.argmin(np.abs(Zn[:, None, :X.shape[1]] - X[None]).sum(axis=-1), axis=1)
    cnt = np.bincount(des, minlength=P)
    with np.errstate(invalid="ignore", divide="ignore"):
        mu_fe = np.bincount(des, yn, minlength=P) / cnt
        mu_sur = np.bincount(des, y_hat, minlength=P) / cnt
    return {
        "n_designs": int(P), "n_theta": int(M), "fe_points": int(Zn.shape[0]),
        "max_rel_err_y": float(rel.max()), "median_rel_err_y": float(np.median(rel)),
        "max_rel_err_mean": float(np.nanmax(np.abs(mu_sur - mu_fe) / mu_fe)),
        "mean_um_fe": (mu_fe * 1e6).tolist(), "mean_um_surrogate": (mu_sur * 1e6).tolist(),
    }


def refine_surrogate(trained: TrainedSurrogate, spindle: Any, X: np.ndarray,
                     theta: np.ndarray, limit: Any, *, rng: np.random.Generator,
                     cache: Any = None, counter: Any = None, progress: bool = False,
                     tol: float | None = None, hyper: str = "warm"
                     ) -> tuple[TrainedSurrogate, dict[str, Any]]:
    """FE at designs ``X`` (P, d) × ``theta`` (M, m), the error there, and a refit.

    Returns ``(new_trained, stats)``. ``stats`` has the error of the surrogate given *before*
    the refit: ``max_rel_err_y`` (pointwise), ``max_rel_err_mean`` (per design, over its θ
    sample) and the per-design means. If ``tol`` is given and ``max_rel_err_mean <= tol``,
    no refit is done and ``trained`` is returned (``stats["refit"] = False``).
    ``hyper``: how the refit treats the Kriging length scales of the model (smt Kriging):
    ``"warm"`` one local likelihood optimisation started from them, ``"keep"`` kept
    (conditioning only), ``"refit"`` a fresh multistart optimisation. Only structures
    registered as ``refinable`` (``global``, ``resonance``) can be refined.
    """
    check_choice("hyper", hyper, ("warm", "keep", "refit"))
    if not STRUCTURES[trained.structure].refinable:
        raise ValueError(f"surrogate structure {trained.structure!r} is not allowed in "
                         "refine_surrogate: it adds (x, θ) FE points to a Kriging of y")
    o, model = trained.options, trained.model
    like_mode = "keep" if hyper == "keep" else "warm"
    X = np.atleast_2d(np.asarray(X, dtype=float))
    theta = np.atleast_2d(np.asarray(theta, dtype=float))
    P, M = X.shape[0], theta.shape[0]
    Z = np.hstack([np.repeat(X, M, axis=0), np.tile(theta, (P, 1))])
    start = counter.calls if counter is not None else 0
    structured = trained.structure == "resonance"
    if structured:
        Zn, Qn = sample_resonance(spindle, Z, o, cache=cache, counter=counter,
                                  progress=progress, label="refinement")
        yn = Qn[:, 3]
    else:
        Zn, yn = sample_positive(trained.response.pointwise(spindle), Z, n_jobs=o.n_jobs,
                                 backend=o.backend, cache=cache, counter=counter,
                                 progress=progress, desc="FE: refinement points")
    if Zn.shape[0] == 0:
        raise ValueError("refine: the FE model gave no finite value at any refinement point")
    stats = _errors(model, Zn, yn, X, M)
    if tol is not None and stats["max_rel_err_mean"] <= tol:
        stats["refit"] = False
        return trained, stats
    d = spindle.design_map.bounds.shape[0]
    like = None if hyper == "refit" else model
    if structured:
        # band rows are n_lhs .. n_lhs + n_band (refinement rows of earlier rounds follow)
        n_lhs = int(model.info.get("n_lhs", model.n_train))
        n_band = int(model.info.get("n_band", 0))
        i = np.arange(model.Z_train.shape[0] + Zn.shape[0])
        is_band = (i >= n_lhs) & (i < n_lhs + n_band)
        new = fit_resonance_surrogate(
            np.vstack([model.Z_train, Zn]), np.vstack([model.Q_train, Qn]), o,
            rng=rng, n_max_rpm=model.n_max_rpm, n_design=d, is_band=is_band,
            threshold_m=limit.threshold, like=like, like_mode=like_mode)
    else:
        Zt, yt = model.training_data()
        new = fit_transformed(np.vstack([Zt, Zn]), np.concatenate([yt, yn]), rng=rng,
                              surrogate=o.surrogate, transform=o.transform,
                              n_start=o.n_start, n_design=d, like=like, like_mode=like_mode)
    new.info = {**model.info, **new.info}  # keeps n_lhs (the fit's n_band is the same)
    new.info["n_refine_points"] = int(model.info.get("n_refine_points", 0) + Zn.shape[0])
    stats["refit"] = True
    calls = (counter.calls - start) if counter is not None else 0
    return replace(trained, model=new, fe_calls=trained.fe_calls + calls,
                   info={**trained.info, "n_refine_points": new.info["n_refine_points"]}), stats


__all__ = ["RefineOptions", "refine_surrogate", "select_designs"]
