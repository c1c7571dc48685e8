"""The thermal soak: the separating test of an effect that drifts as the spindle warms.

A preload growth and a passive spring beside its bearing (or a centrifugal softening, or a
housing stage) can explain a speed sweep alike — the sweep's steady records are each at their
speed's thermal equilibrium, and the run-to-run thermal scatter of the preload hides the rest.
A soak holds a speed from a cold start (``rig.thermal.SoakPlan``; by default two runs at
each of the two sweep speeds either side of the resonance, a block per speed): an effect whose
parameters follow temperature (:attr:`~surrogate_rbrdo.spindle.effects.Effect.thermal_params`)
changes the 1x response during the hold, in proportion to the normalised temperature rise
``θ`` (one time constant, ``rig.thermal``); a spring, a softening or a housing does not.
Within a run the run's own thermal scatter is common to all its records, so the drift is
measured against the probes' noise alone, not against the scatter between runs.

The test (:func:`soak_test`), for a candidate fitted on the sweep:

1. **Warm-up.** ``θ`` of every record from the measured temperatures: one rise and time
   constant for the soak, a starting temperature per run (:func:`warmup`, least squares).
2. **Prediction.** The model's hot − cold 1x response at the soak's speed and channels, at the
   candidate's fit (its nuisance, probe chain, unbalance) with and without the candidate:
   ``Δ₁`` and ``Δ₀`` (:func:`drift_prediction`; ``Δ₀ = 0`` unless the model itself has an
   effect that drifts).
3. **A drift beyond the rival's and beyond the probes' gains?** Each run's slope of the
   phasors on ``θ`` (its own intercept: the run's cold response), pooled over the runs, minus
   ``Δ₀``, against the noise of the runs' residuals about their own lines (``ν = R (K − 2)``
   degrees of freedom; the channels' correlation within a record, the keyphasor's phase
   error, carried). **A probe's gain drift** (an eddy-current probe's sensitivity tempco; the
   probes sit beside the warming bearings) adds to channel ``c`` a real multiple
   ``α_c ΔT a_c`` of its cold response, one ``α_c`` at every speed; near the resonance a
   preload's drift lies almost along the response, so it is the test's nuisance: per speed,
   Hotelling's ``T²`` on the slope's ``C`` quadratures to the cold responses (``F(C, ν − C +
   1)``; no verdict when ``ν < C + 2``), and between two speeds Hotelling's ``T²`` on the
   difference of the in-phase parts per kelvin (relative to the cold responses; ``α`` at both
   under a gain drift, of opposite signs either side of the resonance under a stiffening;
   covariances summed, the smaller ``ν``); Bonferroni over the tests. ``gain=False``: the test
   on all ``2C`` real components (``F(2C, ν − 2C + 1)``), as before the nuisance.
4. **The candidate's drift?** Each run's ``β_r = Re⟨Δ, s_r − Δ₀⟩_W / ⟨Δ, Δ⟩_W`` with
   ``Δ = Δ₁ − Δ₀`` (1: as predicted; ``W`` each channel's inverse residual variance) — at one
   speed with the gain nuisance on the quadratures alone, at two or more on the slopes less
   their gain part (``α`` fitted with a common ``β``) — averaged over the runs: Student's
   ``t`` on ``R − 1`` degrees of freedom (the runs' sensitivities differ with their thermal
   states; the runs are independent whatever the noise within one), the SE from the runs'
   spread at one speed, at two or more from the leave-one-run-out jackknife of the whole
   fit (``α`` and ``β`` refitted without each run: the fitted ``α``, shared by the runs, is
   uncertain too, most when the drift lies near the response), the prediction's own
   relative uncertainty from the fit's covariance added (Welch–Satterthwaite degrees of
   freedom).
5. **Verdict** at ``level``: ``"drift"`` when (3) rejects no drift, ``β̂ > 0`` and (4) does
   not reject ``β = 1``; ``"no_drift"`` when (3) does not reject and (4) rejects ``β = 1``
   one-sided (``β < 1``); else ``"inconclusive"`` (a drift unlike the prediction, or a soak
   too short or too quiet to tell).

>>> import numpy as np
>>> from surrogate_rbrdo.discrepancy.sweeps import Channel
>>> rng = np.random.default_rng(0)
>>> t = np.tile([0.0, 600.0, 1200.0, 2400.0, 3600.0], (4, 1))
>>> th = -np.expm1(-t / 900.0)
>>> T = 293.0 + rng.normal(0, 0.3, (4, 1)) + 12.0 * th + rng.normal(0, 0.05, t.shape)
>>> d = np.array([2e-8 + 1e-8j, -1e-8j])
>>> Y = 1e-6 * (1 + rng.normal(0, 0.02, (4, 1, 2))) + th[..., None] * d
>>> Y = Y + 1e-10 * (rng.normal(size=Y.shape) + 1j * rng.normal(size=Y.shape))
>>> blk = SoakBlock("soak", 24000.0, (Channel("a", 0.0, "x"), Channel("b", 0.0, "y")), t, T, Y)
>>> w = warmup(blk)
>>> round(w.time_constant_s / 900.0, 1), round(w.rise_K, 1)
(1.0, 12.0)
>>> res = drift_test("thermal_preload", (blk,), (w,), (np.zeros(2),), (d,), 0.05, 0.01)
>>> res.outcome, round(res.beta, 1)
('drift', 1.0)
>>> drift_test("thermal_preload", (blk,), (w,), (np.zeros(2),), (3 * d,), 0.05, 0.01).outcome
'inconclusive'
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.optimize import least_squares
from scipy.stats import f as fdist
from scipy.stats import t as student

from surrogate_rbrdo.discrepancy.fit import Fit, _fd_rows
from surrogate_rbrdo.discrepancy.nuisance import Rows
from surrogate_rbrdo.discrepancy.observables import ComplexBlock, MeasuredData
from surrogate_rbrdo.discrepancy.problem import Problem
from surrogate_rbrdo.discrepancy.sweeps import Channel, Sweep

#: a warm-up whose rise is not this many standard errors above zero is no warm-up
MIN_RISE_Z = 10.0


@dataclass(frozen=True)
class SoakBlock:
    """A thermal soak's 1x phasors: ``R`` runs (cold starts) × ``K`` records at one speed
    (``R`` ≥ 2: a soak at two speeds splits its runs).

    Attributes
    ----------
    name : str
    speed_rpm : float
        The speed held.
    channels : tuple of Channel
        Displacement channels (those of the 1x sweep: the model's outputs).
    times_s : ndarray (R, K)
        Each record's time after the run reached speed.
    temperature_K : ndarray (R, K)
        A bearing temperature during each record (the front outer ring on the rig).
    phasors : ndarray (R, K, C) complex
        The 1x phasors (m) against the keyphasor, the format's convention.
    """

    name: str
    speed_rpm: float
    channels: tuple[Channel, ...]
    times_s: np.ndarray
    temperature_K: np.ndarray
    phasors: np.ndarray
    meta: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        where = f"soak {self.name!r}"
        object.__setattr__(self, "channels", tuple(self.channels))
        t = np.asarray(self.times_s, dtype=float)
        T = np.asarray(self.temperature_K, dtype=float)
        Y = np.asarray(self.phasors, dtype=complex)
        if not (self.speed_rpm > 0 and np.isfinite(self.speed_rpm)):
            raise ValueError(f"{where}: speed_rpm = {self.speed_rpm!r} is not allowed: > 0")
        if t.ndim != 2 or t.shape[0] < 2 or t.shape[1] < 3:
            raise ValueError(f"{where}: times_s has shape {t.shape}: need (runs >= 2, "
                             "records >= 3)")
        if T.shape != t.shape or Y.shape != (*t.shape, len(self.channels)):
            raise ValueError(f"{where}: temperature_K {T.shape} and phasors {Y.shape} must be "
                             f"{t.shape} and {(*t.shape, len(self.channels))} (runs x records"
                             " [x channels])")
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(T)) and np.all(np.isfinite(Y))):
            raise ValueError(f"{where}: non-finite times, temperatures or phasors")
        if np.any(t < 0) or np.any(np.diff(t, axis=1) <= 0):
            raise ValueError(f"{where}: times_s must be >= 0 and increase within each run")
        for n, v in (("times_s", t), ("temperature_K", T), ("phasors", Y)):
            v.setflags(write=False)
            object.__setattr__(self, n, v)

    @property
    def runs(self) -> int:
        return self.times_s.shape[0]


@dataclass(frozen=True)
class Warmup:
    """The soak's warm-up ``T = T₀ᵣ + ΔT (1 − e^{−t/τ})`` fitted to its temperatures."""

    fraction: np.ndarray
    time_constant_s: float
    rise_K: float
    rise_se_K: float
    noise_K: float

    @property
    def measured(self) -> bool:
        """Whether the rise stands out of the readings' noise (:data:`MIN_RISE_Z`)."""
        return bool(self.rise_K > MIN_RISE_Z * self.rise_se_K)


def warmup(block: SoakBlock) -> Warmup:
    """Fit one rise and time constant and a starting temperature per run to the soak's
    temperatures (least squares; ``τ`` between a tenth of the shortest step and 100 times the
    longest hold); ``fraction`` is every record's ``θ = 1 − e^{−t/τ̂}``."""
    t, T = block.times_s, block.temperature_K
    R = t.shape[0]
    span = float(t.max())
    step = float(np.diff(t, axis=1).min())

    def res(p: np.ndarray) -> np.ndarray:
        return (p[:R, None] + p[R] * -np.expm1(-t / np.exp(p[R + 1])) - T).ravel()

    lo = np.r_[np.full(R, -np.inf), -np.inf, np.log(step / 10)]
    hi = np.r_[np.full(R, np.inf), np.inf, np.log(100 * span)]
    x0 = np.r_[T[:, 0], np.mean(T[:, -1] - T[:, 0]),
               np.clip(np.log(span / 3), lo[-1], hi[-1])]
    sol = least_squares(res, x0, bounds=(lo, hi), x_scale="jac")
    dof = max(t.size - R - 2, 1)
    s2 = float(sol.fun @ sol.fun) / dof
    J = sol.jac
    cov = np.linalg.pinv(J.T @ J) * s2
    tau = float(np.exp(sol.x[R + 1]))
    return Warmup(-np.expm1(-t / tau), tau, float(sol.x[R]), float(np.sqrt(cov[R, R])),
                  float(np.sqrt(s2)))


@dataclass(frozen=True)
class SoakTest:
    """The soak's verdict on one candidate (see module doc)."""

    candidate: str
    outcome: str
    #: the drift beyond the rival's: Hotelling's F on the pooled slope, its dofs, p-value
    drift_F: float
    drift_dof: tuple[int, int]
    p_drift: float
    #: the drift in units of the candidate's prediction: mean over runs, its SE, dof
    beta: float
    se: float
    dof: int
    p_predicted: float
    p_below: float
    prediction_sd: float
    level: float
    runs: int
    time_constant_s: float = float("nan")
    rise_K: float = float("nan")

    def to_dict(self) -> dict[str, Any]:
        return dataclasses.asdict(self)


def drift_test(candidate: str, blocks: tuple[SoakBlock, ...], warm: tuple[Warmup, ...],
               rival: tuple[np.ndarray, ...], predicted: tuple[np.ndarray, ...],
               prediction_sd: float, level: float, *, gain: bool = True) -> SoakTest:
    """The drift test (module doc, steps 3–4) given each block's warm-up, the rival's
    predicted hot − cold drift ``Δ₀`` and the candidate's ``Δ₁`` (``(C,)`` each), and the
    relative standard deviation of the candidate's prediction. ``gain``: a drift of each
    probe's gain with temperature is a nuisance (module doc, "A probe's gain drift"); False:
    the test without it (any drift along the response counts). With several tests (blocks,
    speed contrasts) the drift's p-value is the smallest times their number (Bonferroni)."""
    parts = []
    for blk, w, d0, d1 in zip(blocks, warm, rival, predicted, strict=True):
        if not w.measured:
            continue
        parts.append(_block_drift(blk, w, np.asarray(d0), np.asarray(d1), gain))
    tests = [(p.F, p.dof, p.p) for p in parts]
    if gain:
        tests += [_contrast(parts[0], q) for q in parts[1:]]
    usable = [p for p in parts if p.betas]
    if gain and len(usable) > 1:
        beta, se, n = _gain_free_beta(usable)
    else:
        b = np.asarray([b for p in usable for b in p.betas])
        n = b.size
        beta = float(b.mean()) if n else float("nan")
        se = float(b.std(ddof=1) / np.sqrt(n)) if n > 1 else float("nan")
    F_hot, dofs, p_min = min(tests, key=lambda x: x[2], default=(0.0, (0, 0), 1.0))
    p_drift = min(1.0, p_min * max(len(tests), 1))
    if n < 3 or not np.isfinite(se):
        return SoakTest(candidate, "inconclusive", float(F_hot), dofs, p_drift,
                        float("nan"), float("nan"), max(n - 1, 0), 1.0, 1.0,
                        float(prediction_sd), level, n, *_warm_figures(warm))
    nu = n - 1
    se = max(se, 1e-300)
    sd = float(np.hypot(se, prediction_sd))
    nu_eff = nu * (sd / se) ** 4                  # Welch–Satterthwaite, the fit's dof ∞
    z = (beta - 1.0) / sd
    p_pred = float(2 * student.sf(abs(z), nu_eff))
    p_below = float(student.cdf(z, nu_eff))
    if p_drift < level and beta > 0 and p_pred >= level:
        outcome = "drift"
    elif p_drift >= level and p_below < level:
        outcome = "no_drift"
    else:
        outcome = "inconclusive"
    return SoakTest(candidate, outcome, float(F_hot), dofs, p_drift, beta, se, nu, p_pred,
                    p_below, float(prediction_sd), level, n, *_warm_figures(warm))


@dataclass(frozen=True)
class _Part:
    """One block's drift test and what a contrast between speeds needs: its in-phase drift
    per kelvin ``x`` (``(C,)``, relative to the cold response) and its covariance, ``ν``; and
    for :func:`_gain_free_betas` the runs' slopes beyond ``Δ₀`` and cold responses ``(R, C)``,
    the channels' weights, the drift predicted beyond ``Δ₀`` and the rise."""

    F: float
    dof: tuple[int, int]
    p: float
    betas: list
    x: np.ndarray
    cov_x: np.ndarray
    nu: int
    slopes: np.ndarray
    cold: np.ndarray
    wgt: np.ndarray
    D: np.ndarray
    rise: float


def _block_drift(blk: SoakBlock, w: Warmup, d0: np.ndarray, d1: np.ndarray, gain: bool
                 ) -> _Part:
    """One block's drift test: Hotelling's F of the pooled slope on ``θ`` beyond ``Δ₀``
    against the runs' residual noise (each run's own slope and intercept removed: ``ν =
    R (K − 2)`` degrees of freedom; p = 1 and no ``β_r`` when ``ν`` is too small for the
    test's dimensions), its dofs and p-value, and every run's ``β_r``. With ``gain``, of the
    slope's quadrature to each channel's cold response only (``C`` dimensions: a real gain
    drift has none), ``β_r`` likewise, and the in-phase part per kelvin for :func:`_contrast`;
    else of all ``2C`` real components."""
    th = w.fraction - w.fraction.mean(axis=1, keepdims=True)                 # (R, K)
    Y = blk.phasors - blk.phasors.mean(axis=1, keepdims=True)               # (R, K, C)
    den = np.sum(th ** 2, axis=1)                                           # (R,)
    slope = np.einsum("rk,rkc->rc", th, Y) / den[:, None]
    e = Y - th[..., None] * slope[:, None]
    R, K, C = Y.shape
    nu = R * (K - 2)
    E = np.concatenate([e.real, e.imag], axis=-1).reshape(-1, 2 * C)
    S = E.T @ E / nu                                                        # (2C, 2C)
    v = np.einsum("rk,rkc->c", th, Y) / den.sum() - d0
    # each run's cold response (intercept at θ = 0), weighted as the pooled slope
    cold = blk.phasors.mean(axis=1) - slope * w.fraction.mean(axis=1)[:, None]
    a = np.einsum("r,rc->c", den, cold) / den.sum()
    u = a / np.where(np.abs(a) > 0, np.abs(a), 1.0)
    if gain:
        # quadrature Im(ū v) = Re u Im v − Im u Re v, in-phase Re(ū v)/|a|/rise per kelvin
        M = np.hstack([-np.diag(u.imag), np.diag(u.real)])                  # (C, 2C)
        Mx = np.hstack([np.diag(u.real), np.diag(u.imag)]) / (
            np.abs(a)[:, None] * max(w.rise_K, 1e-300))
    else:
        M = np.eye(2 * C)
        Mx = np.zeros((0, 2 * C))
    vr = np.concatenate([v.real, v.imag])
    MSM = M @ S @ M.T
    q, cov = M @ vr, MSM / den.sum()
    x, cov_x = Mx @ vr, Mx @ S @ Mx.T / den.sum()
    p_dim = M.shape[0]
    var_c = np.diag(S)[:C] + np.diag(S)[C:]
    D = d1 - d0
    rest = (slope - d0, cold, 1.0 / np.where(var_c > 0, var_c, np.inf), D, w.rise_K)
    if nu - p_dim + 1 < 3:
        # too few residual dofs to estimate the channels' covariance: a diagonal one would not
        # give F under correlated channels (the keyphasor's common phase error), so no verdict
        return _Part(float("nan"), (p_dim, nu), 1.0, [], x, cov_x, nu, *rest)
    F, dof, p = _hotelling(q, cov, nu)
    var = np.diag(MSM)
    wgt = 1.0 / np.where(var > 0, var, np.inf)
    qD = M @ np.concatenate([D.real, D.imag])
    qs = (M @ np.hstack([(slope - d0).real, (slope - d0).imag]).T).T       # (R, p_dim)
    norm = float(np.sum(wgt * qD ** 2))
    betas = (qs @ (wgt * qD) / norm).tolist() if norm > 0 else []
    return _Part(F, dof, p, betas, x, cov_x, nu, *rest)


def _gain_free_betas(parts: list[_Part], drop: tuple[int, int] | None = None) -> list[float]:
    """Every run's ``β_r`` at two or more speeds (without run ``drop = (part, run)``): the
    probes' drift per kelvin ``α`` (``(C,)``, one at every speed) and a common ``β`` fitted to
    the runs' slopes by weighted least squares (``s_r ≈ β Δ + α ΔT a_r``, each channel
    weighted by its inverse residual variance), then each run's slope less its gain part
    ``α̂ ΔT a_r`` along the whole prediction (both components: the in-phase parts, which the
    two speeds separate from a gain, carry most of a preload's drift beside the resonance).
    ``α̂`` is common to the runs, so their spread leaves out its noise: the SE is
    :func:`_gain_free_beta`'s jackknife."""
    C = parts[0].D.size
    keep = [np.array([drop != (i, r) for r in range(p.slopes.shape[0])])
            for i, p in enumerate(parts)]
    rows, rhs = [], []
    for p, k in zip(parts, keep, strict=True):
        sw = np.sqrt(p.wgt)
        for s, a in zip(p.slopes[k], p.cold[k], strict=True):
            X = np.hstack([p.D[:, None], np.diag(p.rise * a)]) * sw[:, None]   # (C, 1 + C)
            rows += [X.real, X.imag]
            rhs += [(s * sw).real, (s * sw).imag]
    coef = np.linalg.lstsq(np.vstack(rows), np.concatenate(rhs), rcond=None)[0]
    alpha = coef[1:1 + C]
    out = []
    for p, k in zip(parts, keep, strict=True):
        norm = float(np.sum(p.wgt * np.abs(p.D) ** 2))
        if not norm > 0:
            continue
        r = p.slopes[k] - alpha[None] * p.rise * p.cold[k]
        out += (np.sum(p.wgt * np.conj(p.D) * r, axis=1).real / norm).tolist()
    return out


def _gain_free_beta(parts: list[_Part]) -> tuple[float, float, int]:
    """``β̂`` at two or more speeds (the mean of :func:`_gain_free_betas`), its standard error
    and the number of runs ``R``. The SE is the leave-one-run-out jackknife of the whole fit
    (``α`` and ``β`` refitted without each run in turn): ``√((R − 1)/R Σ (β̂₍ᵢ₎ − β̄)²)``, for
    Student's ``t`` on ``R − 1`` dofs. The runs' spread about one ``α̂`` misses ``α̂``'s own
    error, which every run shares; it is large when the predicted drift lies near the gain
    direction (both speeds on one flank; review s13, H1: the spread's SE 1.5–7× too small).
    NaN when a run left out leaves a single speed (``α`` and ``β`` not separable)."""
    full = _gain_free_betas(parts)
    R = sum(p.slopes.shape[0] for p in parts)
    beta = float(np.mean(full)) if full else float("nan")
    if len(full) < 3:
        return beta, float("nan"), len(full)
    jack = []
    for i, p in enumerate(parts):
        for r in range(p.slopes.shape[0]):
            speeds = sum(q.slopes.shape[0] - (j == i) > 0 for j, q in enumerate(parts))
            b = _gain_free_betas(parts, (i, r)) if speeds > 1 else []
            if not b:
                return beta, float("nan"), len(full)
            jack.append(np.mean(b))
    jk = np.asarray(jack)
    return beta, float(np.sqrt((R - 1) / R * np.sum((jk - jk.mean()) ** 2))), len(full)


def _hotelling(z: np.ndarray, cov: np.ndarray, nu: int) -> tuple[float, tuple[int, int], float]:
    """Hotelling's ``T²`` of ``z`` (``p`` dims) with ``cov`` estimated on ``ν`` dofs, as
    ``F(p, ν − p + 1)``: F, dofs, p-value."""
    p_dim = z.size
    T2 = float(z @ np.linalg.solve(cov, z))
    F, dof = T2 * (nu - p_dim + 1) / (p_dim * nu), (p_dim, nu - p_dim + 1)
    return F, dof, float(fdist.sf(F, *dof))


def _contrast(a: _Part, b: _Part) -> tuple[float, tuple[int, int], float]:
    """Two speeds' in-phase drifts per kelvin, relative to their cold responses, alike? A gain
    drift gives each channel the same at both (``α`` per kelvin of the probes' rise, which is
    the bearing's times a constant); a bearing that stiffens gives them opposite signs either
    side of the resonance. Hotelling on the difference with the two blocks' covariances
    summed, ``ν`` the smaller block's (conservative: a sum of Wisharts has at least it)."""
    nu = min(a.nu, b.nu)
    p_dim = a.x.size
    if nu - p_dim + 1 < 3:
        return float("nan"), (p_dim, nu), 1.0
    return _hotelling(b.x - a.x, a.cov_x + b.cov_x, nu)


def _warm_figures(warm: tuple[Warmup, ...]) -> tuple[float, float]:
    return ((warm[0].time_constant_s, warm[0].rise_K) if warm
            else (float("nan"), float("nan")))


def drift_prediction(problem: Problem, fit: Fit, block: SoakBlock, *, jacobian: bool = False
                     ) -> tuple[np.ndarray, float]:
    """The model's hot − cold 1x response ``(C,)`` at the soak's speed and channels at
    ``fit`` (its rows on ``problem``'s forward model, the unbalance of its first 1x block), and
    with ``jacobian`` the prediction's relative standard deviation along itself, from the
    fit's bounded covariance (first order; the unbalance held at its fit), else 0."""
    soak_problem = _soak_problem(problem, block)
    fm = problem.forward
    u = fit.evaluation.unbalance[0][0]
    X = fit.x[None]
    h = None
    if jacobian:
        lo, hi = fit.par.bounds()
        rows_fd, h = _fd_rows(fit.x, fit.par, lo, hi)
        X = np.vstack([X, rows_fd])
    n = X.shape[0]
    if any(e.thermal_params for e in fm.effects):
        # the model's own drifting effects cold too: a forward model of its own
        cold_fm = dataclasses.replace(fm, effects=tuple(e.warming(0.0) for e in fm.effects))
        hot = soak_problem.responses(fit.par.rows(X))[0][:, 0] @ u            # (B, C)
        cold_rows = _cold(fit.par.rows(X))
        cold = _soak_problem(Problem(cold_fm, problem.data, None, problem.nuisance),
                             block).responses(cold_rows)[0][:, 0] @ u
    else:
        # hot and cold rows in one call: the second half with the extras cold
        rows = fit.par.rows(np.vstack([X, X]))
        rows = dataclasses.replace(rows, extras=rows.extras[:n] + _cold(rows).extras[n:])
        both = soak_problem.responses(rows)[0][:, 0] @ u
        hot, cold = both[:n], both[n:]
    D = hot - cold
    if not jacobian:
        return D[0], 0.0
    d = D[0]
    nrm = float(np.vdot(d, d).real)
    if not nrm > 0:
        return d, 0.0
    g = (np.conj(d)[None] * (D[1:] - d[None])).sum(axis=1).real / nrm / h
    cov = fit.covariance(bounded=True)
    return d, float(np.sqrt(max(g @ cov @ g, 0.0)))


def _cold(rows: Rows) -> Rows:
    """``rows`` with every extra effect at its cold state (:meth:`~surrogate_rbrdo.spindle.
    effects.Effect.warming` 0)."""
    return dataclasses.replace(rows, extras=[tuple(e.warming(0.0) for e in ex)
                                             for ex in rows.extras])


def _soak_problem(problem: Problem, block: SoakBlock) -> Problem:
    """A problem whose one 1x block is the soak's speed at its channels (its data unused:
    only :meth:`~.problem.Problem.responses` is called)."""
    C = len(block.channels)
    cov = np.broadcast_to(np.eye(2), (1, C, 2, 2)).copy()
    blk = ComplexBlock(f"{block.name}_model", Sweep.unbalance([block.speed_rpm]),
                       block.channels, np.ones((1, C), dtype=complex), cov, 10**9)
    return Problem(problem.forward, MeasuredData((blk,)), None, problem.nuisance)


def soak_test(problem: Problem, rival: Fit, fit: Fit, name: str,
              soaks: tuple[SoakBlock, ...], level: float, *, gain: bool = True) -> SoakTest:
    """The soak's verdict on candidate ``name`` fitted as ``fit`` against ``rival`` (the fit
    of the model without it, whose drift is the no-drift hypothesis): module doc; ``gain``
    as in :func:`drift_test`."""
    warm = tuple(warmup(b) for b in soaks)
    d0 = tuple(drift_prediction(problem, rival, b)[0] for b in soaks)
    pred = [drift_prediction(problem, fit, b, jacobian=True) for b in soaks]
    sd = max((p[1] for p in pred), default=0.0)
    return drift_test(name, soaks, warm, d0, tuple(p[0] for p in pred), sd, level, gain=gain)
