"""One entry point for every recursion: :func:`identify` → :class:`IdentificationResult`.

``identify`` scales the problem (so that a gradient step treats every parameter alike), checks
the data (a record too short for the method raises; a rank-deficient record, a diverging
recursion and an estimate stuck on a bound are *flagged* per record), runs the method's kernel
on the whole batch and maps the estimates back to SI units with their covariance.

Scaling (``scaling=``): the output is divided by its RMS per record and the parameters by a
scale ``s`` (``θ = s ϑ``):

* ``"columns"`` (default): ``s_i = RMS(y) / RMS(φ_i)``, so every scaled regressor has unit RMS
  — a diagonal (Jacobi) preconditioner. Least squares and RLS do not depend on it; SG and MISG
  do, a lot: with ``s = θ0`` the damping column ``c ẋ`` of a bearing is ~0.4 % of ``k x`` and
  its error decays ~10⁵ times slower than the stiffness's.
* ``"initial"``: ``s = θ0`` (parameters in units of their initial values, as the paper's
  bounds are).

Covariance (``covariance_kind``), for white output noise:

* batch LS and RLS with ``λ = 1``: ``σ̂² (ΦᵀΦ)⁻¹``, ``σ̂²`` the residual variance at the final
  estimate (``T − n`` degrees of freedom);
* RLS with ``λ < 1`` (exponentially weighted least squares, weights ``w_t = λ^{T−1−t}``): the
  sandwich ``σ̂² (ΦᵀWΦ)⁻¹ (ΦᵀW²Φ) (ΦᵀWΦ)⁻¹`` with the weighted residual variance — the
  effective window is ``~(1+λ)/(1−λ)`` samples, not the record;
* SG and MISG: none (NaN): they are not least-squares estimators and their error depends on
  the step history; a least-squares formula understated their scatter 4–17× (review item 2);
* ``covariance=`` given: that (e.g. the phasor covariance when the regression is built from
  phasors, whose residual is zero: the noise sits in the regressors);
* a record that the estimate fits exactly (residual ≤ 1e-10 of the output) gets NaN and the
  reason: a residual-based covariance would be zero.

>>> import numpy as np
>>> rng = np.random.default_rng(1)
>>> phi = rng.normal(size=(400, 2)) * [1e-6, 1e-3]           # x (m), xdot (m/s)
>>> y = phi @ [2.5e8, 1.0e3]                                  # k x + c xdot (N)
>>> res = identify(Regression(phi, y, ("k", "c")), "rls", theta0=[2.0e8, 800.0])
>>> np.allclose(res.estimate, [[2.5e8, 1.0e3]], rtol=1e-8), bool(res.ok.all())
(True, True)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from surrogate_rbrdo.core.errors import ModelError
from surrogate_rbrdo.core.validate import check_choice, check_int, check_positive
from surrogate_rbrdo.identification.recursions import RECURSIONS
from surrogate_rbrdo.identification.regression import Bounds, Regression

SCALINGS = ("columns", "initial")

#: a record whose scaled information matrix has eigenvalue ratio below this is rank deficient
RCOND = 1e-10
#: a recursion whose late innovations are this many times its early ones has diverged
DIVERGENCE_RATIO = 10.0


@dataclass(frozen=True, eq=False)
class IdentificationResult:
    """Estimates of a batch of records, their covariance, trajectory and quality flags.

    Attributes
    ----------
    method : str
    names : tuple of str
    estimate : ndarray (B, n)
        Final estimate per record (SI units).
    covariance : ndarray (B, n, n)
        Per ``covariance_kind`` (module docstring); NaN where there is none.
    trajectory : ndarray (B, K, n) or None
        Estimates after the samples ``trajectory_samples`` (0-based), if stored.
    iterations_to_tol : ndarray (B, n) or None
        Number of samples after which each parameter stays within ``tol`` (relative) of the
        reference (the truth if given, else the final estimate: then only on the stored
        trajectory's grid); ``inf`` if never, 0 if it never left.
    reference : {"truth", "final", None}
    at_bound, diverged, rank_deficient : bool arrays (B, n), (B,), (B,)
        Flags; ``ok`` is true where none is raised.
    condition : ndarray (B,)
        Eigenvalue ratio ``λ_min / λ_max`` of the scaled information matrix.
    residual_rms : ndarray (B,)
        RMS of ``y − φᵀθ̂`` per record (SI units of ``y``).
    """

    method: str
    names: tuple[str, ...]
    estimate: np.ndarray
    covariance: np.ndarray
    trajectory: np.ndarray | None
    trajectory_samples: np.ndarray | None
    iterations_to_tol: np.ndarray | None
    tol: float
    reference: str | None
    at_bound: np.ndarray
    diverged: np.ndarray
    rank_deficient: np.ndarray
    condition: np.ndarray
    residual_rms: np.ndarray
    n_samples: int
    covariance_kind: str = "least_squares"
    indefinite: np.ndarray | None = None

    @property
    def ok(self) -> np.ndarray:
        """Records with no flag raised, ``(B,)``."""
        return ~(self.at_bound.any(axis=1) | self.diverged | self.rank_deficient)

    @property
    def std(self) -> np.ndarray:
        """Standard errors ``√diag(covariance)``, ``(B, n)``."""
        return np.sqrt(np.diagonal(self.covariance, axis1=1, axis2=2))

    def flags(self, i: int) -> list[str]:
        """Plain-language flags of record ``i`` (empty if it is fine)."""
        out = []
        if self.rank_deficient[i]:
            out.append(f"rank-deficient regression (eigenvalue ratio {self.condition[i]:.1e} "
                       f"< {RCOND:g}): a parameter is not excited (with forgetting: within "
                       "the window the estimate rests on)")
        if self.diverged[i]:
            out.append("the recursion diverged (non-finite or growing innovations)")
        if self.indefinite is not None and self.indefinite[i]:
            out.append("RLS: the final P is not positive definite (numerically unstable)")
        for j in np.flatnonzero(self.at_bound[i]):
            out.append(f"{self.names[j]} = {self.estimate[i, j]:.6g} sits on its bound")
        return out

    def raise_if_flagged(self) -> IdentificationResult:
        """Return ``self`` if every record is fine, else raise ``ModelError`` naming them."""
        bad = np.flatnonzero(~self.ok)
        if bad.size:
            i = int(bad[0])
            raise ModelError(f"{self.method}: {bad.size} of {self.ok.size} records flagged; "
                             f"record {i}: {'; '.join(self.flags(i))}")
        return self

    def to_dict(self) -> dict:
        """Plain lists (no trajectory), for JSON."""
        return {"method": self.method, "names": list(self.names),
                "estimate": self.estimate.tolist(), "covariance": self.covariance.tolist(),
                "ok": self.ok.tolist(), "n_samples": self.n_samples, "tol": self.tol,
                "iterations_to_tol": None if self.iterations_to_tol is None
                else self.iterations_to_tol.tolist()}


def _method(method):
    if isinstance(method, str):
        return RECURSIONS.get(method)()
    if not hasattr(method, "run"):
        raise ValueError(f"method = {method!r} is not allowed: give a name of "
                         f"{sorted(RECURSIONS)} or an options object (SG(), MISG(p=3), ...)")
    return method


def _per_record(name: str, value, B: int, n: int) -> np.ndarray:
    a = np.asarray(value, dtype=float)
    if a.ndim == 1:
        a = a[None]
    if a.shape not in ((1, n), (B, n)) or not np.all(np.isfinite(a)):
        raise ValueError(f"{name} has shape {np.shape(value)}: need ({n},) or ({B}, {n}), "
                         "finite")
    return np.broadcast_to(a, (B, n)).copy()


def _scales(reg: Regression, theta0: np.ndarray, scaling: str) -> tuple[np.ndarray, np.ndarray]:
    """Output scale ``(B,)`` and parameter scales ``(B, n)``."""
    ys = np.sqrt(np.mean(reg.y**2, axis=1))
    ys = np.where(ys > 0, ys, 1.0)
    if scaling == "initial":
        if np.any(theta0 == 0):
            raise ValueError("theta0 has a zero entry: scaling='initial' divides by theta0")
        return ys, np.abs(theta0)
    col = np.sqrt(np.mean(reg.phi**2, axis=1))                    # (B, n)
    safe = np.where(theta0 != 0, np.abs(theta0), 1.0)
    s = np.where(col > 0, ys[:, None] / np.where(col > 0, col, 1.0), safe)
    return ys, s


def _condition(phi_s: np.ndarray, forgetting: float = 1.0) -> np.ndarray:
    """``λ_min / λ_max`` of the scaled information; with forgetting, ``λ_min`` of the
    exponentially weighted information (what the estimate rests on at the end) over
    ``Σw λ_max / T`` of the whole record's: a record whose excitation stopped is rank deficient
    *in its window*, and RLS's ``P`` winds up."""
    lam = np.linalg.eigvalsh(np.einsum("btn,btm->bnm", phi_s, phi_s))
    top = np.maximum(lam[:, -1], 1e-300)
    cond = np.where(lam[:, -1] > 0, lam[:, 0] / top, 0.0)
    if forgetting < 1.0:
        T = phi_s.shape[1]
        w = forgetting ** (T - 1 - np.arange(T))
        lw = np.linalg.eigvalsh(np.einsum("t,btn,btm->bnm", w, phi_s, phi_s))[:, 0]
        cond = np.minimum(cond, lw / (w.sum() * top / T))
    return cond


def identify(regression: Regression, method="misg", *, theta0, bounds: Bounds | None = None,
             truth=None, tol: float = 0.05, scaling: str = "columns",
             stride: int | None = None, covariance=None) -> IdentificationResult:
    """Identify ``θ`` in ``y = φᵀθ + v`` for every record of ``regression``.

    Parameters
    ----------
    regression : Regression
    method : str or options object
        A name of :data:`~surrogate_rbrdo.identification.recursions.RECURSIONS` (``"sg"``,
        ``"misg"``, ``"rls"``, ``"batch_ls"``) with default options, or an options object
        (``MISG(p=10, forgetting=0.999)``).
    theta0 : array (n,) or (B, n)
        Initial estimate (SI), e.g. the catalogue stiffness and ``η k`` damping.
    bounds : Bounds, optional
        Box the estimates are projected onto (``Bounds.paper``); none if omitted.
    truth : array (n,) or (B, n), optional
        Known parameters: ``iterations_to_tol`` is then measured against them.
    tol : float
        Relative tolerance of ``iterations_to_tol`` (default 5 %).
    scaling : {"columns", "initial"}
        Parameter scaling (module docstring).
    stride : int, optional
        Store the trajectory every ``stride`` samples (and the last); ``None`` stores none.
    covariance : array (n, n) or (B, n, n), optional
        The estimates' covariance when it is known from elsewhere (module docstring).

    Raises
    ------
    ValueError
        A record shorter than the method needs (``p`` for MISG, more than ``n`` samples for
        the covariance), bad shapes or options.
    """
    if not isinstance(regression, Regression):
        raise ValueError(f"regression = {type(regression).__name__} is not allowed: give a "
                         "Regression")
    m = _method(method)
    check_choice("scaling", scaling, SCALINGS)
    check_positive("tol", tol)
    if stride is not None:
        check_int("stride", stride, minimum=1)
    B, T, n = regression.phi.shape
    need = max(int(m.min_samples), n + 1)
    if T < need:
        raise ValueError(f"record has {T} samples: {m.name} with {n} parameters needs at least "
                         f"{need} (innovation length and one degree of freedom)")
    th0 = _per_record("theta0", theta0, B, n)
    ys, s = _scales(regression, th0, scaling)
    phi_s = regression.phi * (s / ys[:, None])[:, None, :]
    y_s = regression.y / ys[:, None]
    lo, hi = (np.full((B, n), -np.inf), np.full((B, n), np.inf)) if bounds is None \
        else bounds.for_records(B, n)
    lo_s, hi_s = lo / s, hi / s
    tr_s = None if truth is None else _per_record("truth", truth, B, n) / s
    # a diverging recursion may overflow: it is detected and flagged below, not warned about
    with np.errstate(over="ignore", invalid="ignore"):
        out = m.run(phi_s, y_s, np.clip(th0 / s, lo_s, hi_s), lo_s, hi_s, truth=tr_s,
                    tol=tol, stride=stride)
    est = out.theta * s
    cond = _condition(phi_s, float(getattr(m, "forgetting", 1.0)))
    rank_def = cond < RCOND
    finite = np.all(np.isfinite(out.theta), axis=1) & np.isfinite(out.peak)
    with np.errstate(invalid="ignore", divide="ignore"):
        growing = out.innov_late > DIVERGENCE_RATIO * out.innov_early
    diverged = ~finite | (growing & np.isfinite(out.innov_late))
    if out.indefinite is not None:                 # RLS: P overflowed or lost definiteness
        diverged = diverged | out.indefinite
    resid = regression.y - np.einsum("btn,bn->bt", regression.phi, est)
    rms = np.sqrt(np.mean(resid**2, axis=1))
    cov, kind = _covariance(regression, resid, rank_def | ~finite, m, covariance)
    width = hi - lo
    tiny = np.where(np.isfinite(width), 1e-9 * width, 0.0)
    at_bound = (np.isfinite(lo) & (est <= lo + tiny)) | (np.isfinite(hi) & (est >= hi - tiny))
    traj = None if out.trajectory is None else out.trajectory * s[:, None, :]
    iters, ref = _iterations(out, traj, est, tol, T)
    return IdentificationResult(
        method=m.name, names=regression.names, estimate=est, covariance=cov, trajectory=traj,
        trajectory_samples=out.samples, iterations_to_tol=iters, tol=float(tol), reference=ref,
        at_bound=at_bound, diverged=diverged, rank_deficient=rank_def, condition=cond,
        residual_rms=rms, n_samples=T, covariance_kind=kind, indefinite=out.indefinite)


def _covariance(reg: Regression, resid: np.ndarray, bad: np.ndarray, method, given
                ) -> tuple[np.ndarray, str]:
    """The estimates' covariance and its kind (module docstring)."""
    B, T, n = reg.phi.shape
    if given is not None:
        C = np.asarray(given, dtype=float)
        if C.shape not in ((n, n), (B, n, n)) or not np.all(np.isfinite(C)):
            raise ValueError(f"covariance has shape {C.shape}: need ({n}, {n}) or ({B}, {n}, "
                             f"{n}), finite")
        return np.broadcast_to(C, (B, n, n)).copy(), "given"
    form = getattr(method, "covariance_form", None)
    cov = np.full((B, n, n), np.nan)
    if form is None:
        return cov, "none"
    exact = np.sqrt(np.mean(resid**2, axis=1)) <= 1e-10 * np.sqrt(np.mean(reg.y**2, axis=1))
    good = ~(bad | exact)
    if not good.any():
        return cov, "exact_fit" if exact.any() else form
    w = np.ones(T) if form == "least_squares" else \
        float(method.forgetting) ** (T - 1 - np.arange(T))
    phi = reg.phi[good]
    A = np.einsum("t,btn,btm->bnm", w, phi, phi)
    # weighted residual variance; degrees of freedom Σw − n Σw²/Σw (T − n when w = 1)
    sigma2 = np.einsum("t,bt->b", w, resid[good] ** 2) / (w.sum() - n * np.sum(w**2) / w.sum())
    Ainv = _scaled_inv(A)
    if form == "least_squares":
        cov[good] = sigma2[:, None, None] * Ainv
    else:
        Bm = np.einsum("t,btn,btm->bnm", w**2, phi, phi)
        cov[good] = sigma2[:, None, None] * Ainv @ Bm @ Ainv
    return cov, form


def _scaled_inv(A: np.ndarray) -> np.ndarray:
    """Inverse of information matrices whose columns differ by ~1e9 (k and c in SI): scale to
    unit diagonal first."""
    d = np.sqrt(np.diagonal(A, axis1=1, axis2=2))
    d = np.where(d > 0, d, 1.0)
    return np.linalg.inv(A / (d[:, :, None] * d[:, None, :])) / (d[:, :, None] * d[:, None, :])


def _iterations(out, traj, est, tol, T):
    if out.last_violation is not None:
        # the estimate after sample t has used t + 1 samples, so the first good one after a
        # violation at t needs t + 2; θ0 (t = −1) outside the tolerance needs 1; −2: never out
        lv = out.last_violation
        it = np.where(lv == -2, 0.0, lv + 2.0)
        it[lv >= T - 1] = np.inf
        return it, "truth"
    if traj is None:
        return None, None
    viol = np.abs(traj - est[:, None, :]) > tol * np.abs(est[:, None, :])
    K = traj.shape[1]
    last = np.where(viol.any(axis=1), K - 1 - np.argmax(viol[:, ::-1], axis=1), -1)
    it = np.where(last < 0, 0.0, out.samples[np.minimum(last + 1, K - 1)] + 1.0)
    it[last >= K - 1] = np.inf
    return it, "final"


__all__ = ["IdentificationResult", "identify"]
