"""Cheap deterministic quantities for g_det: a small Kriging model over the design x only.

The formulations call ``deterministic(x (P, 3)) -> {"von_mises_pa", "omega_n1"}`` once per
generation (20 000 designs per run). One FE design evaluation (nominal peak search, stress at the
peak speed, first natural frequency) costs ~0.1–0.2 s, so the loop would spend an hour in the FE.
Both quantities are smooth functions of the three design variables at nominal θ, so a 3-D
ordinary-Kriging model (smt KRG, squared exponential) of ``log(σ_VM/σ_yield)`` and
``log f_n1`` fitted on ~30–60 maximin-LHS FE designs replaces them; it is validated on fresh random
designs, and its maximum errors are reported (``DesignModel.validation``).

``critical_speeds`` (separation guard) is not modelled: the number of critical speeds inside the
speed range changes across the box, which is not a smooth 3-D function. A study that selects
``resonance = "separation"`` gets a clear error from :func:`fit_design_model` (use ``"paper"`` or
``"none"``).

>>> opts = DesignModelOptions(n_train=30, n_validate=8)
>>> opts.n_train, opts.n_validate
(30, 8)
>>> DesignModelOptions(n_train=2)
Traceback (most recent call last):
...
ValueError: n_train = 2 is not allowed: must be an integer >= 8
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from surrogate_rbrdo.core.counting import CallCounter
from surrogate_rbrdo.core.validate import check_int
from surrogate_rbrdo.doe.lhs import lhs
from surrogate_rbrdo.sampling.evaluate import evaluate_points
from surrogate_rbrdo.spindle.harmonic import peak_tool_amplitude
from surrogate_rbrdo.spindle.modal import first_natural_frequency
from surrogate_rbrdo.spindle.stress import max_von_mises
from surrogate_rbrdo.surrogates.fast import ProductKernelPredictor
from surrogate_rbrdo.surrogates.kriging import KrgSE, KrigingOptions

QUANTITIES = ("stress_ratio", "first_natural_frequency_hz")


@dataclass(frozen=True)
class DesignModelOptions:
    """Budget of the g_det design model (TOML table ``[design_model]``).

    Parameters
    ----------
    n_train : int
        FE designs (maximin LHS over the design box) the Kriging models are fitted on, >= 8.
    n_validate : int
        Fresh FE designs (uniform, independent of the training LHS) for the reported
        validation errors, >= 0.
    n_jobs : int
        Worker processes for the FE evaluations (joblib/loky), >= 1.
    """

    n_train: int = 40
    n_validate: int = 10
    n_jobs: int = 1

    def __post_init__(self) -> None:
        check_int("n_train", self.n_train, minimum=8)
        check_int("n_validate", self.n_validate, minimum=0)
        check_int("n_jobs", self.n_jobs, minimum=1)

    def memory_bytes(self) -> dict[str, float]:
        """Peak bytes per size field (``core.memory``): the Kriging fits hold a few
        ``n_train × n_train`` matrices (~10, smt KRG), the designs and their FE quantities
        a few rows each.

        >>> DesignModelOptions(n_train=40).memory_bytes()["n_train"] < 1e6
        True
        """
        n, v = float(self.n_train), float(self.n_validate)
        return {"n_train": 8.0 * (10.0 * n * n + 16.0 * n), "n_validate": 8.0 * 16.0 * v}


def fe_design_quantities(spindle, x: np.ndarray) -> np.ndarray:
    """FE quantities of designs ``x`` (P, 3) at nominal θ: columns ``QUANTITIES``.

    The stress ratio is the maximum von Mises stress at the nominal peak-amplitude speed (as in
    :func:`~surrogate_rbrdo.spindle.evaluate.design_quantities`) over the lowest yield strength
    of the shaft sections; the frequency is the first non-rotating natural frequency (Hz).
    """
    x = np.atleast_2d(np.asarray(x, dtype=float))
    out = np.empty((x.shape[0], 2))
    for i, xi in enumerate(x):
        model = spindle.model(xi)
        yield_pa = model.geometry.min_yield_Pa
        peak = peak_tool_amplitude(model, None)
        stress = max_von_mises(model, float(peak.speed_rpm[0]))
        out[i, 0] = stress.max_von_mises_Pa / yield_pa
        out[i, 1] = first_natural_frequency(model, 0.0)
    return out


@dataclass(frozen=True)
class PointwiseDesignQuantities:
    """``f(x) -> [stress_ratio, f_n1_hz]`` of one design (for counted, parallel sampling)."""

    spindle: Any

    def __call__(self, x: np.ndarray) -> np.ndarray:
        return fe_design_quantities(self.spindle, x)[0]


def _fe_designs(spindle, X: np.ndarray, n_jobs: int, counter: CallCounter | None,
                progress: bool, desc: str) -> np.ndarray:
    """FE design quantities of the rows of ``X`` (one counted FE call per design)."""
    res = evaluate_points(PointwiseDesignQuantities(spindle), X, n_jobs=n_jobs,
                          counter=counter, n_outputs=len(QUANTITIES), progress=progress,
                          desc=desc)
    return res.y


@dataclass(frozen=True, eq=False)
class DesignModel:
    """``x (P, 3) -> {"von_mises_pa", "omega_n1"}`` (SI) from two fitted 3-D Kriging models.

    Attributes
    ----------
    lower, upper : ndarray (3,)
        Design box (inputs are scaled to the unit cube).
    yield_pa : float
        Yield strength used to turn the stress ratio back into a stress.
    models : tuple
        Fitted ``KrgSE`` of ``log stress_ratio`` and ``log f_n1``.
    validation : dict
        Max/mean relative errors on fresh designs, FE calls and fit time.
    """

    lower: np.ndarray
    upper: np.ndarray
    yield_pa: float
    models: tuple[Any, Any]
    validation: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        # separable predictor with an empty θ part: a plain numpy kernel product, ~10x less
        # overhead per call than smt's predict_values (called once per generation)
        fast = tuple(ProductKernelPredictor.from_model(m, n_design=self.lower.size)
                     for m in self.models)
        blocks = tuple(f.prepare_theta(np.empty((1, 0))) for f in fast)
        object.__setattr__(self, "_fast", tuple(zip(fast, blocks, strict=True)))

    def quantities(self, x: np.ndarray) -> np.ndarray:
        """Predicted ``[stress_ratio, f_n1_hz]`` of designs ``x`` (P, 3)."""
        u = (np.atleast_2d(np.asarray(x, dtype=float)) - self.lower) / (self.upper - self.lower)
        return np.column_stack([np.exp(f.predict_grid(u, b).mean[:, 0]) for f, b in self._fast])

    def __call__(self, x: np.ndarray) -> dict[str, np.ndarray]:
        q = self.quantities(x)
        return {"von_mises_pa": q[:, 0] * self.yield_pa, "omega_n1": 2.0 * np.pi * q[:, 1]}


def fit_design_model(spindle, options: DesignModelOptions, *, rng: np.random.Generator,
                     progress: bool = False, counter: CallCounter | None = None,
                     label: str = "") -> DesignModel:
    """Fit the g_det design model on FE designs and validate it on fresh ones.

    Parameters
    ----------
    spindle : ReferenceSpindle
    options : DesignModelOptions
    rng : numpy.random.Generator
        Children are spawned for the training LHS, the validation LHS and the Kriging fits.
    progress : bool
        Progress bars over the FE designs.
    counter : CallCounter, optional
        Receives every FE call (``validation["n_fe_calls"]`` is this fit's share).
    label : str
        Prefix of the progress bars.
    """
    counter = counter if counter is not None else CallCounter()
    start = counter.calls
    r_train, r_val, r_fit = rng.spawn(3)
    b = spindle.design_map.bounds
    lo, hi = b[:, 0].astype(float), b[:, 1].astype(float)
    t0 = time.perf_counter()
    X = lhs(options.n_train, b, rng=r_train)
    Y = _fe_designs(spindle, X, options.n_jobs, counter, progress,
                    f"{label} FE: design-model DOE".strip())
    U = (X - lo) / (hi - lo)
    kopts = KrigingOptions(theta0=1.0, theta_lower=1e-3, theta_upper=100.0, n_start=5)
    models = tuple(KrgSE(kopts, rng=r).fit(U, np.log(Y[:, j]))
                   for j, r in enumerate(r_fit.spawn(2)))
    yield_pa = spindle.geometry.min_yield_Pa
    dm = DesignModel(lower=lo, upper=hi, yield_pa=yield_pa, models=models)
    val: dict[str, Any] = {"n_train": options.n_train, "n_validate": options.n_validate,
                           "fit_time_s": time.perf_counter() - t0}
    if options.n_validate:
        Xv = lo + r_val.random((options.n_validate, lo.size)) * (hi - lo)  # fresh, uniform
        Yv = _fe_designs(spindle, Xv, options.n_jobs, counter, progress,
                         f"{label} FE: design-model validation".strip())
        Pv = dm.quantities(Xv)
        for j, name in enumerate(QUANTITIES):
            rel = np.abs(Pv[:, j] - Yv[:, j]) / np.abs(Yv[:, j])
            val[f"{name}_max_rel_err"] = float(rel.max())
            val[f"{name}_mean_rel_err"] = float(rel.mean())
        val["stress_ratio_max_abs_err"] = float(np.abs(Pv[:, 0] - Yv[:, 0]).max())
        val["stress_ratio_max_fe"] = float(Yv[:, 0].max())
        val["validation_designs"] = Xv.tolist()
    val["n_fe_calls"] = counter.calls - start
    val["time_s"] = time.perf_counter() - t0
    return DesignModel(lower=lo, upper=hi, yield_pa=yield_pa, models=models, validation=val)
