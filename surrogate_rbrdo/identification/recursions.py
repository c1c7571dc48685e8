"""SG, MISG, RLS and batch least squares: the recursions behind :func:`identify`.

Each method is a frozen options dataclass registered in :data:`RECURSIONS` with a ``run``
kernel. Kernels work on a *scaled* regression (``identify`` divides the parameters by a scale
and the output by its RMS, so every parameter is O(1)) and on a whole batch of independent
records at once: the loop is over time, every step is one array operation over the batch.

Update rules (``e`` innovations, ``φ`` regressors, estimate ``ϑ``, projection ``Π`` onto the box):

* **MISG** (Ding F., Chen T., "Performance analysis of multi-innovation gradient type
  identification methods", *Automatica* 43(1):1–14, 2007; the paper's Eq. 8), innovation
  length ``p``:
  ``Φ = [φ(t) … φ(t−p+1)]``, ``E = Y − Φᵀϑ``, ``ϑ ← Π(ϑ + μ Φ E / d(t))`` with

  - ``step="accumulated"`` (default): ``d = λ r(t−1) + ‖Φ‖²``, ``r(t) = λ r(t−1) + ‖φ(t)‖²``,
    ``r(0) = r0``. For ``p = 1``, ``λ = 1`` this is Ding's SG (``φ e / r(t)``); for ``p > 1``
    it is *our reading* of the paper's Eq. 8 ``μ Φ I / (r(k) + ‖Φ_p‖²)`` with ``r(k)`` the
    accumulated energy of the samples before the window's newest (Ding & Chen's MISG divides
    by ``r(t)`` itself: the same for ``p = 1``, smaller steps for ``p > 1``, since
    ``d = r(t) + Σ_{j<p} ‖φ(t−j)‖²``). The gain decays like ``1/t``, so the estimate averages
    the noise out and converges in mean square under persistent excitation (Ding & Chen 2007,
    Thm. 1). With a forgetting factor ``λ < 1`` the gain settles at about ``(1 − λ)μ``, which
    tracks a slow drift at the price of a noise floor. This is the default because it is the
    only form that converges to the true parameters in noise.
  - ``step="normalised"``: ``d = δ + ‖Φ‖²`` — the normalised-gradient (NLMS for ``p = 1``,
    affine-projection-like for ``p > 1``) form with a constant step ``μ ∈ (0, 2)``: fast at the
    start, but the estimate keeps fluctuating with a misadjustment ∝ ``μ σ²`` (no averaging).

* **SG** = MISG with ``p = 1``; "SG with a tuned gain" is SG with ``μ > 1``.
* **RLS** with forgetting ``λ``: ``K = Pφ / (λ + φᵀPφ)``, ``ϑ ← ϑ + K e``,
  ``P ← (P − K φᵀ P) / λ`` re-symmetrised every step, ``P(0) = p0 I``; the *reported* estimate
  is ``Π(ϑ)``. It equals exponentially weighted least squares with weights ``λ^{T−1−t}`` (and a
  prior ``λ^T / p0`` on ``ϑ − ϑ0``); a final ``P`` that is not positive definite is flagged.
  The state is not projected: with ``λ = 1`` and a large ``p0`` RLS is the growing-window
  least-squares solution, and clipping its state would break that (after a clipped first
  step the collapsed ``P`` keeps the clipping error for hundreds of samples).
* **Batch LS** on the first ``t`` samples (its "trajectory" is the growing-window estimate);
  the final estimate is the least-squares solution of the whole record, projected.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from surrogate_rbrdo.core.registry import Registry
from surrogate_rbrdo.core.validate import check_choice, check_int, check_positive, check_range

RECURSIONS = Registry("recursion")

STEP_FORMS = ("accumulated", "normalised")


@dataclass(frozen=True)
class KernelOutput:
    """What a kernel returns, in scaled units.

    ``last_violation`` is, per record and parameter, the last sample index whose estimate was
    farther than the tolerance from the reference (−1: only the initial estimate ``θ0`` was,
    −2: never); ``peak`` the largest ``|ϑ|``
    before projection; ``innov_early``/``innov_late`` the RMS a-priori innovation over the
    first and last quarter of the record (NaN where the kernel has none).
    """

    theta: np.ndarray
    trajectory: np.ndarray | None
    samples: np.ndarray | None
    last_violation: np.ndarray | None
    peak: np.ndarray
    innov_early: np.ndarray
    innov_late: np.ndarray
    indefinite: np.ndarray | None = None


class _Tracker:
    """Trajectory storage, tolerance tracking and divergence statistics of a time loop."""

    def __init__(self, B: int, n: int, T: int, *, truth, tol: float, stride: int | None,
                 theta0: np.ndarray | None = None):
        self.T = T
        self.truth = truth
        self.tol_abs = None if truth is None else tol * np.abs(truth)
        self.last = None if truth is None else np.full((B, n), -2, dtype=np.int64)
        if self.last is not None and theta0 is not None:
            self.last[np.abs(theta0 - truth) > self.tol_abs] = -1
        self.stride = stride
        self.samples = None if stride is None else np.unique(
            np.r_[np.arange(stride - 1, T, stride), T - 1])
        self.traj = None if stride is None else np.empty((B, self.samples.size, n))
        self._k = 0
        self.peak = np.zeros(B)
        q = max(T // 4, 1)
        self.q = q
        self.e2 = np.zeros((2, B))

    def innovation(self, t: int, e: np.ndarray) -> None:
        if t < self.q:
            self.e2[0] += e * e
        elif t >= self.T - self.q:
            self.e2[1] += e * e

    def record(self, t: int, theta: np.ndarray, raw: np.ndarray | None = None) -> None:
        if raw is not None:
            np.maximum(self.peak, np.max(np.abs(raw), axis=-1), out=self.peak)
        if self.last is not None:
            viol = np.abs(theta - self.truth) > self.tol_abs
            self.last[viol] = t
        if self.traj is not None and self._k < self.samples.size and self.samples[self._k] == t:
            self.traj[:, self._k] = theta
            self._k += 1

    def output(self, theta: np.ndarray, innovations: bool = True,
               indefinite: np.ndarray | None = None) -> KernelOutput:
        rms = np.sqrt(self.e2 / self.q) if innovations else np.full_like(self.e2, np.nan)
        return KernelOutput(theta, self.traj, self.samples, self.last, self.peak, rms[0], rms[1],
                            indefinite)


def _check_forgetting(value: float) -> None:
    check_range("forgetting", value, 0.5, 1.0)
    if value <= 0.5:
        raise ValueError(f"forgetting = {value!r} is not allowed: must lie in (0.5, 1.0]")


@RECURSIONS.register("misg")
@dataclass(frozen=True)
class MISG:
    """Multi-innovation stochastic gradient with innovation length ``p`` (module docstring).

    Parameters
    ----------
    p : int >= 1
        Innovation length (``p = 1`` is SG).
    mu : float > 0
        Step factor (the paper's ``μ_k``, constant here). With ``step="normalised"`` it must be
        below 2 for stability.
    forgetting : float in (0.5, 1]
        ``λ`` of the accumulated gain ``r(t) = λ r(t−1) + ‖φ(t)‖²``.
    step : {"accumulated", "normalised"}
    r0 : float > 0
        ``r(0)`` (scaled units: one sample's energy is about ``n``).
    delta : float > 0
        Regulariser of the normalised form.

    >>> MISG(p=0)
    Traceback (most recent call last):
    ...
    ValueError: p = 0 is not allowed: must be an integer >= 1
    """

    p: int = 3
    mu: float = 1.0
    forgetting: float = 1.0
    step: str = "accumulated"
    r0: float = 1.0
    delta: float = 1e-8
    label: ClassVar[str] = "MISG"

    def __post_init__(self) -> None:
        check_int("p", self.p, minimum=1)
        check_positive("mu", self.mu)
        _check_forgetting(self.forgetting)
        check_choice("step", self.step, STEP_FORMS)
        check_positive("r0", self.r0)
        check_positive("delta", self.delta)
        if self.step == "normalised" and self.mu >= 2.0:
            raise ValueError(f"mu = {self.mu!r} is not allowed with step='normalised': the "
                             "normalised gradient is stable only for 0 < mu < 2")

    @property
    def min_samples(self) -> int:
        return int(self.p)

    @property
    def covariance_form(self) -> str | None:
        """SG/MISG are not least-squares estimators: no covariance formula (``None``)."""
        return None

    @property
    def name(self) -> str:
        return f"{self.label}(p={self.p})" if self.label == "MISG" else self.label

    def run(self, phi: np.ndarray, y: np.ndarray, theta0: np.ndarray, lo: np.ndarray,
            hi: np.ndarray, *, truth=None, tol: float = 0.05, stride=None) -> KernelOutput:
        """Run the recursion over a scaled batch ``phi (B, T, n)``, ``y (B, T)``."""
        B, T, n = phi.shape
        p = int(self.p)
        tr = _Tracker(B, n, T, truth=truth, tol=tol, stride=stride, theta0=theta0)
        nrm = np.einsum("btn,btn->bt", phi, phi)
        cs = np.concatenate([np.zeros((B, 1)), np.cumsum(nrm, axis=1)], axis=1)
        th = np.array(theta0, dtype=float, copy=True)
        r = np.full(B, float(self.r0))
        lam, mu = float(self.forgetting), float(self.mu)
        for t in range(T):
            a = max(0, t - p + 1)
            Phi, Y = phi[:, a:t + 1], y[:, a:t + 1]
            E = Y - np.einsum("bwn,bn->bw", Phi, th)
            tr.innovation(t, E[:, -1])
            window = cs[:, t + 1] - cs[:, a]
            if self.step == "accumulated":
                d = lam * r + window
            else:
                d = self.delta + window
            r = lam * r + nrm[:, t]
            raw = th + (mu / d)[:, None] * np.einsum("bwn,bw->bn", Phi, E)
            th = np.clip(raw, lo, hi)
            tr.record(t, th, raw)
        return tr.output(th)


@RECURSIONS.register("sg")
@dataclass(frozen=True)
class SG(MISG):
    """Stochastic gradient: MISG with ``p = 1`` (``mu > 1`` is "SG with a tuned gain").

    >>> SG().p, SG(mu=3.0).name
    (1, 'SG')
    """

    p: int = 1
    label: ClassVar[str] = "SG"

    def __post_init__(self) -> None:
        if self.p != 1:
            raise ValueError(f"p = {self.p!r} is not allowed for SG: SG has p = 1 (use MISG)")
        super().__post_init__()


@RECURSIONS.register("rls")
@dataclass(frozen=True)
class RLS:
    """Recursive least squares with forgetting factor ``λ`` and ``P(0) = p0 I``."""

    forgetting: float = 1.0
    p0: float = 1e6
    min_samples: ClassVar[int] = 1
    name: ClassVar[str] = "RLS"

    def __post_init__(self) -> None:
        _check_forgetting(self.forgetting)
        check_positive("p0", self.p0)

    @property
    def covariance_form(self) -> str:
        """``"least_squares"`` (λ = 1) or ``"ewls"`` (exponentially weighted, λ < 1)."""
        return "least_squares" if self.forgetting == 1.0 else "ewls"

    def run(self, phi: np.ndarray, y: np.ndarray, theta0: np.ndarray, lo: np.ndarray,
            hi: np.ndarray, *, truth=None, tol: float = 0.05, stride=None) -> KernelOutput:
        """Run RLS over a scaled batch ``phi (B, T, n)``, ``y (B, T)``."""
        B, T, n = phi.shape
        tr = _Tracker(B, n, T, truth=truth, tol=tol, stride=stride, theta0=theta0)
        th = np.array(theta0, dtype=float, copy=True)
        P = np.broadcast_to(float(self.p0) * np.eye(n), (B, n, n)).copy()
        lam = float(self.forgetting)
        for t in range(T):
            ph = phi[:, t]
            Pp = np.einsum("bnm,bm->bn", P, ph)
            den = lam + np.einsum("bn,bn->b", ph, Pp)
            K = Pp / den[:, None]
            e = y[:, t] - np.einsum("bn,bn->b", ph, th)
            tr.innovation(t, e)
            th = th + K * e[:, None]
            P = (P - K[:, :, None] * Pp[:, None, :]) / lam
            # re-symmetrise: with λ < 1 the round-off of the update grows like λ^−t and an
            # unsymmetric P turns indefinite (review item 1: min eigenvalue −6.9 at λ = 0.99)
            P = 0.5 * (P + np.swapaxes(P, 1, 2))
            tr.record(t, np.clip(th, lo, hi), th)
        lam_min = np.linalg.eigvalsh(P)[:, 0]
        return tr.output(np.clip(th, lo, hi), indefinite=~(lam_min > 0))


@RECURSIONS.register("batch_ls")
@dataclass(frozen=True)
class BatchLS:
    """Least squares on the whole record (trajectory: on the first ``t`` samples), projected.

    ``ridge`` (relative to the trace of ``ΦᵀΦ``) only keeps the first few growing-window
    solves defined; the final estimate of a well-posed record is the plain LS solution.
    """

    chunk: int = 256
    ridge: float = 1e-12
    min_samples: ClassVar[int] = 1
    name: ClassVar[str] = "batch LS"
    covariance_form: ClassVar[str] = "least_squares"

    def __post_init__(self) -> None:
        check_int("chunk", self.chunk, minimum=1)
        check_positive("ridge", self.ridge)

    def run(self, phi: np.ndarray, y: np.ndarray, theta0: np.ndarray, lo: np.ndarray,
            hi: np.ndarray, *, truth=None, tol: float = 0.05, stride=None) -> KernelOutput:
        """Growing-window LS over a scaled batch ``phi (B, T, n)``, ``y (B, T)``."""
        B, T, n = phi.shape
        tr = _Tracker(B, n, T, truth=truth, tol=tol, stride=stride, theta0=theta0)
        A = np.zeros((B, n, n))
        b = np.zeros((B, n))
        eye = np.eye(n)
        th = np.array(theta0, dtype=float, copy=True)
        for s in range(0, T, self.chunk):
            e = min(s + self.chunk, T)
            Ac = A[:, None] + np.cumsum(np.einsum("btn,btm->btnm", phi[:, s:e], phi[:, s:e]),
                                        axis=1)
            bc = b[:, None] + np.cumsum(phi[:, s:e] * y[:, s:e, None], axis=1)
            tr_ = np.trace(Ac, axis1=-2, axis2=-1)
            reg = Ac + (self.ridge * np.maximum(tr_, 1e-300))[..., None, None] * eye
            # the ridge pulls an under-determined early window towards theta0, not towards 0
            sol = theta0[:, None] + np.linalg.solve(
                reg, (bc - np.einsum("btnm,bm->btn", Ac, theta0))[..., None])[..., 0]
            raw = sol
            proj = np.clip(sol, lo[:, None], hi[:, None])
            for j, t in enumerate(range(s, e)):
                tr.record(t, proj[:, j], raw[:, j])
            A, b, th = Ac[:, -1], bc[:, -1], proj[:, -1]
        return tr.output(th, innovations=False)


__all__ = ["RECURSIONS", "BatchLS", "KernelOutput", "MISG", "RLS", "SG"]
