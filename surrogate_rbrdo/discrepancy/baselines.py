"""Two baselines the workflow is compared with on the same scenarios.

* **GP discrepancy** (Kennedy & O'Hagan 2001): recalibrate the model, then test whether a GP
  discrepancy term is needed (the structure test of :mod:`.calibration` at level ``alpha``). It
  detects; it cannot name, so its verdicts are ``"unnamed_residual"`` or ``"nothing_missing"``.
* **Sparse regression on identified stiffness** (SINDy's sequentially thresholded least
  squares, Brunton, Proctor & Kutz, *PNAS* 113, 2016, one term dropped per pass; with the
  threshold on standardised coefficients, as FROLS selects terms by significance, Billings
  2013): the identified bearing
  stiffness relative to the model's, ``k_id(Ω)/k_model(Ω) − 1``, per bearing and direction,
  regressed on ``[1, x, x², x³, x⁴]``, ``x = Ω/Ω_max``. The selected terms are read as effects:
  a speed trend falling → ``speed_softening``, rising → ``thermal_preload``; different constant
  terms in x and y → ``anisotropy``; only equal constants → nothing (a stiffness scale). Effects
  that leave ``k(Ω)`` alone (cross-coupling, gyroscopics, unbalance) are invisible to it, and
  a housing stage shows as a speed trend — the sceptic's point about sparse regression on a
  collinear, physics-blind library. The regression is a few lines of NumPy; pysindy's STLSQ
  does the same on a static library and is not needed for it.
"""

from __future__ import annotations

import numpy as np

from surrogate_rbrdo.discrepancy.forward import ForwardModel
from surrogate_rbrdo.discrepancy.observables import MeasuredData
from surrogate_rbrdo.discrepancy.sweeps import Sweep
from surrogate_rbrdo.discrepancy.workflow import DiscrepancyResult

#: |coefficient| / standard error below which a term is dropped (STLSQ threshold)
T_THRESHOLD = 4.0
#: polynomial degree of the library in x = Ω / Ω_max
DEGREE = 4


def gp_baseline(result: DiscrepancyResult, alpha: float = 0.01) -> str:
    """The Kennedy–O'Hagan verdict on the recalibrated baseline (first stage)."""
    return "unnamed_residual" if result.stages[0].structure_p <= alpha else "nothing_missing"


def stlsq(Theta: np.ndarray, y: np.ndarray, w: np.ndarray, t_threshold: float = T_THRESHOLD,
          max_iter: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Weighted sequentially thresholded least squares: coefficients and standard errors.

    One term is dropped per pass — the least significant, if its ``|ξ|/se`` is below
    ``t_threshold`` — and the rest refitted. Thresholding every term at once (SINDy's STLSQ
    as written) fails on a polynomial library: its columns are so collinear that every
    coefficient's standard error is inflated in the full fit, so a strong trend is dropped
    with everything else in the first pass (this baseline detected nothing, even a 5 %
    softening, until this was changed). Dropping one term per pass is backward elimination,
    the classical remedy (Miller, *Subset Selection in Regression*, 2002, §3.4).

    >>> x = np.linspace(0, 1, 30)
    >>> Th = np.vander(x, 4, increasing=True)
    >>> xi, se = stlsq(Th, 0.1 - 0.05 * x**2, np.full(30, 1e5))
    >>> np.round(xi, 6).tolist()
    [0.1, 0.0, -0.05, 0.0]
    """
    active = np.ones(Theta.shape[1], dtype=bool)
    xi = np.zeros(Theta.shape[1])
    se = np.full(Theta.shape[1], np.inf)
    A, b = Theta * w[:, None], y * w
    for _ in range(Theta.shape[1] if max_iter is None else max_iter):
        xi[:] = 0.0
        se[:] = np.inf
        if not active.any():
            break
        Aa = A[:, active]
        coef, *_ = np.linalg.lstsq(Aa, b, rcond=None)
        cov = np.linalg.pinv(Aa.T @ Aa)
        xi[active] = coef
        se[active] = np.sqrt(np.clip(np.diag(cov), 1e-300, None))
        t = np.where(active, np.abs(xi) / se, np.inf)
        weakest = int(np.argmin(t))
        if t[weakest] >= t_threshold:
            break
        active[weakest] = False
    else:
        xi[~active] = 0.0
    return xi, se


def sparse_baseline(data: MeasuredData, forward: ForwardModel) -> tuple[str, tuple[str, ...]]:
    """The sparse-regression verdict and names from identified stiffness (needs
    ``data.identified``)."""
    ib = data.identified
    if ib is None:
        raise ValueError("sparse_baseline: the data carry no identified stiffness "
                         "(data.identified is None)")
    B = len(forward.bearing_names)
    Z = forward.bearing_impedance(Sweep.unbalance(ib.speeds_rpm), np.ones((1, len(
        forward.theta_bearings))), np.ones((1, B)))[0]
    j = [forward.bearing_names.index(n) for n in ib.bearings]
    k_model = np.stack([Z[:, j, 0, 0].real, Z[:, j, 1, 1].real], axis=-1)
    x = ib.speeds_rpm / ib.speeds_rpm.max()
    Theta = np.vander(x, DEGREE + 1, increasing=True)
    names: set[str] = set()
    for b in range(len(ib.bearings)):
        consts = []
        for d in range(2):
            y = ib.values[:, b, d] / k_model[:, b, d] - 1.0
            w = k_model[:, b, d] / ib.sd[:, b, d]
            xi, se = stlsq(Theta, y, w)
            consts.append((xi[0], se[0]))
            if np.any(xi[1:] != 0):
                trend = float(Theta[-1, 1:] @ xi[1:] - Theta[0, 1:] @ xi[1:])
                names.add("speed_softening" if trend < 0 else "thermal_preload")
        (a, sa), (c, sc) = consts
        if abs(a - c) > T_THRESHOLD * np.hypot(min(sa, 1e6), min(sc, 1e6)):
            names.add("anisotropy")
    return ("named", tuple(sorted(names))) if names else ("nothing_missing", ())
