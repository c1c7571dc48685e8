"""Bearing damping from impact tests at standstill, by FRF-based model updating.

Why: the 1× unbalance response does not carry the bearings' damping at a realistic noise —
``Ωc`` is 0.04–1.5 % of the bearing's dynamic stiffness ``|k + iΩc|`` on the reference spindle
(1 000–24 000 rpm), so a phasor error ε moves ``c`` by up to ``|Z|/(Ωc)`` ε, 66–2 500 ε
(``docs/identification.md`` §3). An impact test at standstill measures the rotor's modes
directly, and on the reference spindle two of them are bearing modes: the bearings' damping
gives 70 % of the 792 Hz mode's modal damping (front) and 80 % of the 1 232 Hz mode's (rear).

Method — updating the experimenter's FE model on the measured FRFs (the response-function
approach of Friswell & Mottershead, *Finite Element Model Updating in Structural Dynamics*,
Kluwer 1995, ch. 6; Lin & Ewins, *Mech. Syst. Signal Process.* 8(4):437–458, 1994):

1. H1 accelerance at the tool from the hammer at the tool, per direction, with its coherence
   (:func:`surrogate_rbrdo.rig.frf.h1_frf`: sdypy-FRF, exponential window ``σ_w``, so the
   model is evaluated at ``s = iω + σ_w``);
2. the model's modes at standstill in ``band_hz`` and, per direction, the measured peak
   nearest each (within ``search``) → the bearings' stiffness factors of that direction (and
   one tool mass factor) that put the model's undamped natural frequencies on the peaks
   (least squares on log frequency);
3. weighted nonlinear least squares of the measured H1 within ``half_width`` of every mode
   whose coherence is at least ``min_coherence``, against
   ``H(s) = s² [K(θ) + s C(θ, d) + s² M(m)]⁻¹`` at the tool's DOF, over the log of: the
   bearings' stiffness factors ``θ`` at standstill *per direction* (``<bearing>_stiffness_x``,
   ``_y``: at standstill the model's two planes are uncoupled, each direction's FRF sees its
   own bearing stiffness; real bearings and the rig's ``anisotropy`` differ by direction,
   and one factor for both made the split peaks one broad peak — η 44 % / 100 % off on
   ``experiments/rig_campaign_trial.toml``), their damping factors ``d`` (``C_b ← d_b C_b``,
   i.e. ``η_b ← d_b η_b``), the tool/holder mass factor ``m`` (hidden on the rig:
   weighed by the FRF), one calibration gain per direction (hammer × accelerometer) and one
   delay per direction, ``e^{−iωτ_d}`` (the DAQ's unknown timing skew between the hammer and
   the accelerometer, 0.2 µs per channel on the rig: 2πfτ ≈ 2e-3 rad at 1.2 kHz, above H1's
   noise at low noise — without it the lack-of-fit test flagged right models and the rear
   η̂ was biased by several SEs; the discrepancy workflow's probe chains carry the same
   nuisance, :mod:`surrogate_rbrdo.discrepancy.nuisance`). The
   weights are H1's random error, ``ε = √(1 − γ²) / (|γ| √(2 n_d))`` of ``|H|`` (Bendat &
   Piersol, *Random Data*, 4th ed. 2010, eq. 9.90), its square averaged over ``smooth_bins``
   bins and floored at ``rel_floor``;
4. the covariance of the fitted coordinates (log factors; delays in µs) from a delete-one-hit
   jackknife (:func:`jackknife`; with fewer than 3 hits per direction ``(JᵀJ)⁻¹`` scaled by
   ``χ²/ν`` when that exceeds 1), and a lack-of-fit test of the fit against the jackknife
   variance of H1, flagged (with a warning) above the ``1 − lack_of_fit_level`` quantile of
   ``F(ν, 2(n − 1))`` (:func:`~surrogate_rbrdo.identification.impact_lof.lack_of_fit_threshold`):
   the model cannot represent the FRFs. The test has power only where the model error is
   large against H1's noise: at 10× the rig's noise with 3 hits a hidden tool interface
   passes it (docs/identification.md §5b), and the SEs never include model error.

The bearings' damping at any speed then follows from the damping law ``C_b = η_b K_b``
(:meth:`ImpactDamping.damping`): ``ĉ(Ω) = η̂ k̂(Ω)`` with ``k̂`` identified from the unbalance
response at that speed. Assumptions: the bearings' damping is stiffness-proportional with
an ``η`` that does not depend on speed (the model's law: the rig's truth uses it; a real
bearing's damping also changes with speed — Gargiulo, *Machine Design* 1980; Kraus et al.,
*ASME J. Tribol.* 1987, measured damping of ball bearings falling with speed — which this
route cannot see), the rotor model is right apart from the bearings and the tool mass, and the
test is linear. Bearings with a housing stage are refused (its damping is not separable).

>>> opts = ImpactOptions()
>>> opts.band_hz, opts.force_drop_db, opts.min_coherence
(None, 6.0, 0.8)
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np
from scipy.ndimage import uniform_filter1d
from scipy.optimize import least_squares

from surrogate_rbrdo.core.errors import ModelError
from surrogate_rbrdo.identification.impact_frf import (
    FitPoints,
    ImpactOptions,
    accelerance,
    fit_data,
    force_band_top,
    hit_frfs,
    hit_groups,
    measured_peaks,
)
from surrogate_rbrdo.identification.impact_lof import (
    ImpactLackOfFit,
    _at_least,
    delay_test,
    lack_of_fit_threshold,
)
from surrogate_rbrdo.identification.updating import StandstillModel
from surrogate_rbrdo.rig.records import Record
from surrogate_rbrdo.spindle.assembly import SpindleModel

#: the jackknife over hits needs at least this many hits per direction
MIN_HITS = 3
#: the fitted coordinate of a channel delay is the delay in this unit (1 µs: the DAQ's skew
#: scale, so its step is comparable to the log factors')
DELAY_UNIT_S = 1e-6


@dataclass(frozen=True, eq=False)
class ImpactDamping:
    """Bearing damping (and stiffness at standstill, tool mass) updated on impact FRFs.

    ``names`` label ``parameters`` (the fitted factors, not their logs; ``delay_<d>``: the
    delay of direction ``d``'s response behind its force, s) and ``covariance`` (of the fitted
    coordinates: the factors' logs, i.e. relative, and the delays in µs); ``eta_s`` is each
    bearing's identified ``η`` (s).
    """

    bearings: tuple[str, ...]
    names: tuple[str, ...]
    parameters: np.ndarray
    covariance: np.ndarray
    eta_s: np.ndarray
    n_points: int
    chi2_dof: float
    modes_hz: np.ndarray
    covariance_kind: str = "model"
    model_covariance: np.ndarray | None = None
    n_replicates: int = 0
    lack_of_fit: ImpactLackOfFit | None = None

    def factor(self, name: str) -> float:
        return float(self.parameters[self.names.index(name)])

    @property
    def eta_rel_se(self) -> np.ndarray:
        """Relative standard error of each bearing's ``η``."""
        idx = [self.names.index(f"{b}_damping") for b in self.bearings]
        return np.sqrt(np.diag(self.covariance)[idx])

    def damping(self, stiffness: np.ndarray) -> np.ndarray:
        """``c = η̂ k`` per bearing for stiffnesses ``(..., nb)`` (N/m) → N s/m."""
        return np.asarray(stiffness, float) * self.eta_s

    def to_dict(self) -> dict:
        return {"bearings": list(self.bearings), "eta_s": self.eta_s.tolist(),
                "eta_rel_se": self.eta_rel_se.tolist(),
                "parameters": dict(zip(self.names, self.parameters.tolist(), strict=True)),
                "log_covariance": self.covariance.tolist(), "n_points": self.n_points,
                "chi2_dof": self.chi2_dof, "modes_hz": self.modes_hz.tolist(),
                "covariance_kind": self.covariance_kind, "n_replicates": self.n_replicates,
                "lack_of_fit": None if self.lack_of_fit is None else self.lack_of_fit.to_dict()}


def impact_damping(model: SpindleModel, records: Sequence[Record],
                   options: ImpactOptions | None = None) -> ImpactDamping:
    """Update the bearings' damping (and stiffness at standstill, tool mass, gains) of
    ``model`` on the impact ``records`` of one installation (module docstring).

    Raises
    ------
    ValueError
        No mode of the model in the band; a bearing with a housing stage or without an η law.
    ModelError
        No measured peak near the model's modes, or the fit does not converge.
    """
    options = ImpactOptions() if options is None else options
    if any(s is not None for s in model.supports):
        raise ValueError("model.supports: bearings with a housing stage are not allowed "
                         "(the housing's damping is not separable from the bearing's)")
    if not all(hasattr(b.law, "damping_eta_s") for b in model.geometry.bearings):
        raise ValueError("model bearings: every bearing law needs damping_eta_s (C = η K)")
    nb = len(model.bearing_nodes)
    if tuple(model.theta_bearings) != tuple(b.name for b in model.geometry.bearings):
        raise ValueError(f"model.theta_bearings = {model.theta_bearings} is not allowed: "
                         "every bearing must be a θ bearing")
    disk = options.tool_disk if options.fit_tool_mass else None
    if disk is not None and disk not in {k.name for k in model.geometry.disks}:
        raise ValueError(f"tool_disk = {disk!r} is not allowed: the model's disks are "
                         f"{[k.name for k in model.geometry.disks]}")
    frfs = hit_frfs(records, options)
    up = StandstillModel(model, disk)
    _check_planes(up, model)
    lo, hi = options.band_hz or (100.0, force_band_top(records, options.force_drop_db))
    f0 = np.unique(np.round(up.natural_hz(np.ones(nb), 1.0), 3))
    f0 = f0[(f0 >= lo) & (f0 <= hi)]
    if f0.size == 0:
        raise ValueError(f"band_hz = {options.band_hz} is not allowed: the model has no mode "
                         "there")
    theta, m = _align(up, frfs, f0, options, nb)
    res, pts, x, h = _update(up, frfs, theta, m, (lo, hi), options, model)
    if options.covariance == "jackknife":
        res = jackknife(up, records, options, res, pts, x, h, theta, m, (lo, hi))
    lof = res.lack_of_fit
    if lof is not None and lof.flagged:
        warnings.warn(f"impact damping: the model does not fit the measured FRFs (lack of fit "
                      f"χ²/ν = {lof.chi2_dof:.3g} against the hit-to-hit variance, threshold "
                      f"{lof.threshold:.3g}; the fitted delays {np.round(lof.delays_s, 8)} s "
                      f"against the stated skew: χ² = {lof.delay_chi2:.3g}, threshold "
                      f"{lof.delay_threshold:.3g}): the model — rotor, bearings, tool mass, each "
                      "channel's gain and delay — misses something the tests see (e.g. a "
                      "tool-interface compliance) and η̂ and the tool mass absorb it",
                      UserWarning, stacklevel=2)
    return res


def _check_planes(up: StandstillModel, model: SpindleModel) -> None:
    """Each direction's stiffness factors are fitted on that direction's FRF: the model's two
    planes must be uncoupled at standstill (no cross-coupled bearing in the model)."""
    M, C, K = up.matrices(np.ones(len(model.bearing_nodes)), np.ones(len(model.bearing_nodes)),
                          1.0)
    s = 2j * np.pi * 500.0
    e = np.zeros(K.shape[0], complex)
    e[4 * model.tool_node + 1] = 1.0
    x = np.linalg.solve(K + s * C + s**2 * M, e)
    if abs(x[4 * model.tool_node]) > 1e-9 * abs(x[4 * model.tool_node + 1]):
        raise ValueError("model bearings: the two planes are coupled at standstill (a "
                         "cross-coupled bearing); per-direction impact updating needs them "
                         "uncoupled")


def _align(up: StandstillModel, frfs, f0, opts, nb):
    """Stiffness factors per direction (and one tool mass factor) putting the model's natural
    frequencies on each direction's measured peaks: least squares on log frequency."""
    dirs = sorted(frfs)
    peaks = [measured_peaks(frfs[d], f0, opts) for d in dirs]
    ok = [np.isfinite(pk) for pk in peaks]
    n_ok = int(sum(o.sum() for o in ok))
    if n_ok == 0:
        raise ModelError(f"impact_damping: no coherent FRF peak near the model's modes "
                         f"{np.round(f0, 1).tolist()} Hz")
    nd = len(dirs)
    n_m = 1 if up.tool_disk is not None and n_ok > nb * nd else 0

    def res(p):
        out = []
        for di in range(nd):
            if not ok[di].any():
                continue
            fn = up.natural_hz(np.exp(p[di * nb:(di + 1) * nb]),
                               float(np.exp(p[nd * nb])) if n_m else 1.0)
            pk = peaks[di][ok[di]]
            idx = np.searchsorted(fn, f0[ok[di]])       # the model mode that moved from f0
            cand = fn[np.clip(idx[:, None] + np.array([-1, 0]), 0, fn.size - 1)]
            near = cand[np.arange(cand.shape[0]),
                        np.argmin(np.abs(np.log(cand / pk[:, None])), axis=1)]
            out.append(np.log(near / pk))
        return np.concatenate(out)

    sol = least_squares(res, np.zeros(nd * nb + n_m), x_scale=0.05, diff_step=1e-4)
    return (np.exp(sol.x[:nd * nb]).reshape(nd, nb),
            float(np.exp(sol.x[nd * nb])) if n_m else 1.0)


def _names(model: SpindleModel, dirs, n_m: int) -> list[str]:
    return ([f"{b}_stiffness_{d}" for d in dirs for b in model.theta_bearings]
            + [f"{b}_damping" for b in model.theta_bearings]
            + (["tool_mass"] if n_m else []) + [f"gain_{d}" for d in dirs]
            + [f"delay_{d}" for d in dirs])


def _least_squares(up: StandstillModel, pts: FitPoints, nd: int, nb: int, p0: np.ndarray):
    """Weighted least squares of the accelerance on the log factors (module docstring):
    the solution, and the model's FRF at the points."""
    n_m = 1 if up.tool_disk is not None else 0
    k0 = nd * nb                                 # first damping factor
    kt = k0 + nb + n_m + nd                      # first delay (µs)
    s, dof, gi = pts.s, pts.dof, pts.gi
    w_us = (s.imag * DELAY_UNIT_S)               # ω in rad/µs

    last: list = [None, None]                   # the residual and Jacobian share one solve

    def model_frf(p):
        if last[0] is None or not np.array_equal(last[0], p):
            last[0], last[1] = p.copy(), _frf(p)
        return last[1]

    def _frf(p):
        # at standstill the experimenter's model has no coupling between the two planes:
        # each direction's FRF sees that direction's bearing stiffness only
        th, dd = np.exp(p[:k0]).reshape(nd, nb), np.exp(p[k0:k0 + nb])
        mm, gain = (float(np.exp(p[k0 + nb])) if n_m else 1.0), np.exp(p[k0 + nb + n_m:kt])
        h = np.zeros(s.size, complex)
        jac = np.zeros((s.size, p.size), complex)
        for di in range(nd):
            g = gi == di
            hd, dh = up.accelerance(th[di], dd, mm, s[g], dof[g])
            ph = gain[di] * np.exp(-1j * w_us[g] * p[kt + di])    # gain and timing skew
            h[g] = ph * hd
            rows = np.nonzero(g)[0][:, None]
            jac[rows, np.arange(di * nb, (di + 1) * nb)] = ph[:, None] * dh[:, :nb]
            jac[rows, np.arange(k0, k0 + nb + n_m)] = ph[:, None] * dh[:, nb:]
            jac[g, k0 + nb + n_m + di] = h[g]
            jac[g, kt + di] = -1j * w_us[g] * h[g]
        return h, jac

    def res(p):
        r = (pts.H - model_frf(p)[0]) / pts.sd
        return np.concatenate([r.real, r.imag])

    def jac(p):
        j = -model_frf(p)[1] / pts.sd[:, None]
        return np.concatenate([j.real, j.imag])

    sol = least_squares(res, p0, jac=jac, x_scale=0.05, max_nfev=400)
    if not sol.success:
        raise ModelError(f"impact_damping: the FRF fit did not converge ({sol.message})")
    return sol, model_frf(sol.x)[0]


def _update(up: StandstillModel, frfs, theta, m, band, opts, model):
    """The fit on every hit: the result (model-based covariance) and what the jackknife and
    the lack-of-fit test need (the points, the log solution, the model's FRF there)."""
    nd, nb = theta.shape
    pts = fit_data(up, frfs, theta, m, band, opts, model)
    n_m = 1 if up.tool_disk is not None else 0
    names = _names(model, sorted(frfs), n_m)
    if pts.s.size < (nd + 1) * nb + 2:
        raise ModelError(f"impact_damping: {pts.s.size} coherent FRF points near the modes "
                         f"{np.round(pts.modes, 1).tolist()} Hz; too few to fit")
    p0 = np.concatenate([np.log(theta).ravel(), np.zeros(nb), [np.log(m)] * n_m,
                         np.zeros(2 * nd)])
    sol, h = _least_squares(up, pts, nd, nb, p0)
    dof_res = max(2 * pts.s.size - p0.size, 1)
    chi2 = float(2 * sol.cost / dof_res)
    try:
        cov = np.linalg.inv(sol.jac.T @ sol.jac) * max(chi2, 1.0)
    except np.linalg.LinAlgError as exc:
        raise ModelError("impact_damping: the FRF fit's information matrix is singular "
                         "(a parameter the modes in the band do not see)") from exc
    k0 = nd * nb
    eta0 = np.array([b.law.damping_eta_s for b in model.geometry.bearings])
    par = np.concatenate([np.exp(sol.x[:-nd]), sol.x[-nd:] * DELAY_UNIT_S])
    res = ImpactDamping(tuple(model.theta_bearings), tuple(names), par, cov,
                        eta0 * par[k0:k0 + nb], int(pts.s.size), chi2, pts.modes)
    return res, pts, sol.x, h


def jackknife(up: StandstillModel, records: Sequence[Record], opts: ImpactOptions,
              res: ImpactDamping, pts: FitPoints, x: np.ndarray, h: np.ndarray, theta, m,
              band) -> ImpactDamping:
    """``res`` with the delete-a-group jackknife covariance of its fitted coordinates and the
    lack-of-fit test against the jackknife variance of H1 (module docstring).

    ``n`` is the fewest hits of a direction; replicate ``i`` leaves out hits ``i, i + n, …`` of
    every direction (every hit is left out once; with equal hit counts, delete-one-hit) and is
    refitted from the full fit's solution on the full fit's FRF bins (Efron & Tibshirani,
    *An Introduction to the Bootstrap*, 1993, §11.2 and §11.5: ``(n − 1)/n Σ (x_i − x̄)
    (x_i − x̄)ᵀ``; each variance at least the model-based one, :func:`_at_least`). The lack of
    fit is ``Σ 2|H − Ĥ|² / v / (2N − p)`` with ``v`` the jackknife variance of H1 at each
    point, averaged over ``smooth_bins`` bins and floored at ``(lack_of_fit_floor |H|)²``,
    tested against :func:`lack_of_fit_threshold`. Fewer than ``MIN_HITS`` hits in a direction:
    ``res`` unchanged (model-based covariance, no test).
    """
    by_dir, n = hit_groups(records)
    if n < MIN_HITS:
        return res
    dirs = sorted(by_dir)
    nd, nb = theta.shape
    bins = [pts.bins[pts.gi == di] for di in range(nd)]
    xs, acc = [], []
    for i in range(n):
        sub = [r for d in dirs for k, r in enumerate(by_dir[d]) if k % n != i]
        frfs = hit_frfs(sub, opts)
        try:
            sol, _ = _least_squares(up, fit_data(up, frfs, theta, m, band, opts, up.model,
                                                 bins=bins), nd, nb, x)
        except ModelError as exc:
            warnings.warn(f"impact damping: jackknife replicate {i} (hit {i} of each direction "
                          f"left out) did not fit ({exc}); the model-based covariance is kept "
                          "and the lack of fit is not tested", UserWarning, stacklevel=3)
            return res
        xs.append(sol.x)
        acc.append([accelerance(frfs[d]) for d in dirs])
    xs = np.array(xs)
    cov = _at_least(res.covariance,
                    (n - 1) / n * (xs - xs.mean(0)).T @ (xs - xs.mean(0)))
    A = np.array(acc)                                           # (n, nd, F)
    var = (n - 1) / n * np.sum(np.abs(A - A.mean(0)) ** 2, axis=0)
    var = uniform_filter1d(var, max(opts.smooth_bins, 1), axis=1, mode="nearest")
    # floor: a misfit below lack_of_fit_floor of |H| is not called a model error (noise-free
    # hits are identical: no scatter to refer to)
    v = np.maximum(var[pts.gi, pts.bins], (opts.lack_of_fit_floor * np.abs(pts.H)) ** 2)
    chi2 = float(np.sum(2 * np.abs(pts.H - h) ** 2 / v))
    dof = max(2 * pts.s.size - x.size, 1)
    fixed, level = opts.max_lack_of_fit, opts.lack_of_fit_level / 2   # two tests: Bonferroni
    thr = lack_of_fit_threshold(dof, n, level) if fixed is None else fixed
    d_stat, d_thr = delay_test(x[-nd:], cov[-nd:, -nd:], opts.skew_sd_s, level, n)
    lof = ImpactLackOfFit(chi2 / dof, dof, 2 * (n - 1), thr, None if fixed else level * 2,
                          tuple((x[-nd:] * DELAY_UNIT_S).tolist()), d_stat, d_thr,
                          bool(chi2 / dof > thr or d_stat > d_thr), n)
    return replace(res, covariance=cov, covariance_kind="jackknife",
                   model_covariance=res.covariance, n_replicates=n, lack_of_fit=lof)


__all__ = ["ImpactDamping", "ImpactOptions", "ImpactLackOfFit", "force_band_top", "impact_damping",
           "lack_of_fit_threshold"]
