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
   weighed by the FRF) and one calibration gain per direction (hammer × accelerometer). The
   weights are H1's random error, ``ε = √(1 − γ²) / (|γ| √(2 n_d))`` of ``|H|`` (Bendat &
   Piersol, *Random Data*, 4th ed. 2010, eq. 9.90), floored at ``rel_floor``; the
   covariance of the parameters is ``(JᵀJ)⁻¹`` scaled by ``χ²/ν`` when that exceeds 1.

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
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from surrogate_rbrdo.core.errors import ModelError
from surrogate_rbrdo.core.validate import check_positive, check_range
from surrogate_rbrdo.identification.updating import StandstillModel
from surrogate_rbrdo.rig.frf import FRFEstimate, h1_frf
from surrogate_rbrdo.rig.records import Record, RecordError
from surrogate_rbrdo.spindle.assembly import SpindleModel


@dataclass(frozen=True)
class ImpactOptions:
    """Options of :func:`impact_damping`.

    Parameters
    ----------
    band_hz : (lo, hi) or None
        Frequency band of the modes used; ``None`` (default): from 100 Hz to where the
        measured force autospectrum has fallen ``force_drop_db`` below its level at low
        frequency (the band the hammer tip excites; Ewins, *Modal Testing*, 2nd ed. 2000,
        §3.9.4; the rig's hard tip: ~2 kHz at 6 dB).
    force_drop_db : float
        The force spectrum's drop that ends the default band.
    search : float
        Relative half-width around a model mode in which its measured peak is looked for.
    half_width : float
        Relative half-width around each (updated) mode of the FRF points fitted.
    min_coherence : float
        FRF points with a lower coherence are not fitted.
    rel_floor : float
        Floor of the relative random error of H1 (the model's own accuracy).
    fit_tool_mass : bool
        Fit the tool/holder mass factor (the disk ``tool_disk`` of the model's geometry).
    tool_disk : str
    exp_window_end : float or None
        Exponential window of :func:`~surrogate_rbrdo.rig.frf.h1_frf`.
    """

    band_hz: tuple[float, float] | None = None
    force_drop_db: float = 6.0
    search: float = 0.08
    half_width: float = 0.03
    min_coherence: float = 0.8
    rel_floor: float = 1e-4
    fit_tool_mass: bool = True
    tool_disk: str = "tool_holder"
    exp_window_end: float | None = 0.01

    def __post_init__(self) -> None:
        if self.band_hz is not None:
            lo, hi = (float(v) for v in self.band_hz)
            if not 0.0 < lo < hi:
                raise ValueError(f"band_hz = {self.band_hz} is not allowed: need 0 < lo < hi")
            object.__setattr__(self, "band_hz", (lo, hi))
        check_range("force_drop_db", self.force_drop_db, 0.5, 40.0)
        check_range("search", self.search, 1e-3, 0.5)
        check_range("half_width", self.half_width, 1e-3, 0.5)
        check_range("min_coherence", self.min_coherence, 0.0, 1.0)
        check_positive("rel_floor", self.rel_floor)
        if self.exp_window_end is not None:
            check_range("exp_window_end", self.exp_window_end, 1e-6, 1.0)


@dataclass(frozen=True, eq=False)
class ImpactDamping:
    """Bearing damping (and stiffness at standstill, tool mass) updated on impact FRFs.

    ``names`` label ``parameters`` (the fitted factors, not their logs) and ``covariance``
    (of their logs: relative); ``eta_s`` is each bearing's identified ``η`` (s).
    """

    bearings: tuple[str, ...]
    names: tuple[str, ...]
    parameters: np.ndarray
    covariance: np.ndarray
    eta_s: np.ndarray
    n_points: int
    chi2_dof: float
    modes_hz: np.ndarray

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
                "chi2_dof": self.chi2_dof, "modes_hz": self.modes_hz.tolist()}


def _frfs(records: Sequence[Record], opts: ImpactOptions) -> dict[str, FRFEstimate]:
    """H1 per hit direction, response at the tool in that direction (accelerometer, else a
    displacement probe)."""
    by_dir: dict[str, list[Record]] = {}
    for r in records:
        if r.kind != "impact" or "hammer" not in r.channel_names:
            raise RecordError(f"record {r.id!r}", "kind/channels",
                              "an impact record with a 'hammer' channel is needed")
        by_dir.setdefault(r.channel("hammer").location.direction, []).append(r)
    out = {}
    for d, recs in sorted(by_dir.items()):
        chans = [c for c in recs[0].channels if c.location.target == "tool"
                 and c.location.direction == d and c.quantity in ("acceleration",
                                                                   "displacement")]
        chans.sort(key=lambda c: c.quantity != "acceleration")
        if not chans:
            raise RecordError(f"record {recs[0].id!r}", "channels",
                              f"no response channel at the tool in direction {d!r}")
        if len(recs) < 2:
            # one hit: H1's coherence is 1 by construction, so neither its random error
            # (the fit's weights) nor the coherence filter can see the noise
            warnings.warn(f"impact damping: one hit in direction {d!r} (record {recs[0].id!r}):"
                          " with a single average the coherence is 1 by construction, so the"
                          " fit is unweighted and its standard errors assume noise-free FRFs;"
                          " average at least 2 hits (rig: impacts_per_direction >= 2)",
                          UserWarning, stacklevel=3)
        out[d] = h1_frf(recs, [chans[0].name], exp_window_end=opts.exp_window_end)
    return out


def impact_damping(model: SpindleModel, records: Sequence[Record],
                   options: ImpactOptions = ImpactOptions()) -> ImpactDamping:
    """Update the bearings' damping (and stiffness at standstill, tool mass, gains) of
    ``model`` on the impact ``records`` of one installation (module docstring).

    Raises
    ------
    ValueError
        No mode of the model in the band; a bearing with a housing stage or without an η law.
    ModelError
        No measured peak near the model's modes, or the fit does not converge.
    """
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
    frfs = _frfs(records, options)
    up = StandstillModel(model, disk)
    _check_planes(up, model)
    lo, hi = options.band_hz or (100.0, force_band_top(records, options.force_drop_db))
    f0 = np.unique(np.round(up.natural_hz(np.ones(nb), 1.0), 3))
    f0 = f0[(f0 >= lo) & (f0 <= hi)]
    if f0.size == 0:
        raise ValueError(f"band_hz = {options.band_hz} is not allowed: the model has no mode "
                         "there")
    theta, m = _align(up, frfs, f0, options, nb)
    return _update(up, frfs, theta, m, (lo, hi), options, model)


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


def force_band_top(records: Sequence[Record], drop_db: float = 6.0) -> float:
    """Frequency (Hz) where the hits' mean force autospectrum has fallen ``drop_db`` below
    its median over 5–50 Hz.

    >>> from surrogate_rbrdo.rig.records import Calibration, ChannelSpec, SensorLocation
    >>> fs, T = 200_000.0, 0.4e-3                  # finely sampled: the continuous pulse
    >>> t = np.arange(200_000) / fs
    >>> f = np.where((t >= 0.05) & (t < 0.05 + T), np.sin(np.pi * (t - 0.05) / T), 0.0)
    >>> ch = ChannelSpec("hammer", "force", "N", SensorLocation("tool", "x", 0.0),
    ...                  Calibration(1.0, 0.0, -1e9, 1e9), 0.0, {})
    >>> rec = Record("h", "impact", fs, (ch,), f[None, :], speed_rpm=0.0)
    >>> round(force_band_top([rec], 6.0), -1)      # a 0.4 ms half-sine: −6 dB at 2.05 kHz
    2050.0
    """
    g = np.mean([np.abs(np.fft.rfft(r.values("hammer") - np.median(r.values("hammer")))) ** 2
                 for r in records], axis=0)
    f = np.fft.rfftfreq(records[0].n_samples, 1.0 / records[0].sample_rate_hz)
    ref = np.median(g[(f >= 5.0) & (f <= 50.0)])
    below = np.nonzero((f > 50.0) & (g < ref * 10 ** (-drop_db / 10)))[0]
    return float(f[below[0]]) if below.size else float(f[-1])


def _peaks(est: FRFEstimate, f0, opts) -> np.ndarray:
    """The measured peak (Hz) of one direction's FRF nearest each model mode (NaN where none
    is coherent)."""
    out = np.full(f0.size, np.nan)
    for i, f in enumerate(f0):
        g = ((est.freq_hz >= f * (1 - opts.search)) & (est.freq_hz <= f * (1 + opts.search))
             & (est.coherence[0] >= opts.min_coherence))
        if g.sum() < 3:
            continue
        a = np.abs(est.receptance()[0][g])
        j = int(np.argmax(a))
        if 0 < j < a.size - 1:                   # an interior maximum: a peak
            out[i] = est.freq_hz[g][j]
    return out


def _align(up: StandstillModel, frfs, f0, opts, nb):
    """Stiffness factors per direction (and one tool mass factor) putting the model's natural
    frequencies on each direction's measured peaks: least squares on log frequency."""
    dirs = sorted(frfs)
    peaks = [_peaks(frfs[d], f0, opts) for d in dirs]
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


def _fit_data(up: StandstillModel, frfs, theta, m, band, opts, model):
    """The FRF points fitted: within ``half_width`` of each direction's (aligned) modes where
    the coherence is high enough, with H1's random error as SD; and the modes (Hz)."""
    lo, hi = band
    data, all_modes = [], []
    for di, d in enumerate(sorted(frfs)):
        modes = up.natural_hz(theta[di], m)
        modes = np.unique(np.round(modes[(modes >= lo) & (modes <= hi)], 3))
        all_modes.append(modes)
        est = frfs[d]
        f = est.freq_hz
        near = np.any(np.abs(f[:, None] / modes[None, :] - 1) <= opts.half_width, axis=1)
        g = near & (est.coherence[0] >= opts.min_coherence) & (f > 0)
        gam = np.sqrt(np.clip(est.coherence[0][g], 1e-12, 1.0))
        eps = np.maximum(np.sqrt(1 - gam**2) / (gam * np.sqrt(2 * est.n_averages)),
                         opts.rel_floor)
        H = est.H[0][g] if est.form == "accelerance" else est.receptance()[0][g] * (
            2j * np.pi * f[g] + est.exp_decay_per_s) ** 2
        dof = 4 * model.tool_node + (1 if d == "y" else 0)
        data.append((2j * np.pi * f[g] + est.exp_decay_per_s, H, eps * np.abs(H),
                     np.full(g.sum(), dof), np.full(g.sum(), di)))
    s, H, sd, dof, gi = (np.concatenate([x[k] for x in data]) for k in range(5))
    return s, H, sd, dof, gi, np.unique(np.concatenate(all_modes))


def _update(up: StandstillModel, frfs, theta, m, band, opts, model) -> ImpactDamping:
    nd, nb = theta.shape
    dirs = sorted(frfs)
    s, H, sd, dof, gi, modes = _fit_data(up, frfs, theta, m, band, opts, model)
    if s.size < (nd + 1) * nb + 2:
        raise ModelError(f"impact_damping: {s.size} coherent FRF points near the modes "
                         f"{np.round(modes, 1).tolist()} Hz; too few to fit")
    n_m = 1 if up.tool_disk is not None else 0
    names = ([f"{b}_stiffness_{d}" for d in dirs for b in model.theta_bearings]
             + [f"{b}_damping" for b in model.theta_bearings]
             + (["tool_mass"] if n_m else []) + [f"gain_{d}" for d in dirs])
    k0 = nd * nb                                 # first damping factor

    def unpack(p):
        return (np.exp(p[:k0]).reshape(nd, nb), np.exp(p[k0:k0 + nb]),
                float(np.exp(p[k0 + nb])) if n_m else 1.0, np.exp(p[k0 + nb + n_m:]))

    def model_frf(p):
        # at standstill the experimenter's model has no coupling between the two planes:
        # each direction's FRF sees that direction's bearing stiffness only
        th, dd, mm, gain = unpack(p)
        h = np.zeros(s.size, complex)
        jac = np.zeros((s.size, p.size), complex)
        for di in range(nd):
            g = gi == di
            hd, dh = up.accelerance(th[di], dd, mm, s[g], dof[g])
            h[g] = gain[di] * hd
            rows = np.nonzero(g)[0][:, None]
            jac[rows, np.arange(di * nb, (di + 1) * nb)] = gain[di] * dh[:, :nb]
            jac[rows, np.arange(k0, k0 + nb + n_m)] = gain[di] * dh[:, nb:]
            jac[g, k0 + nb + n_m + di] = h[g]
        return h, jac

    def res(p):
        r = (H - model_frf(p)[0]) / sd
        return np.concatenate([r.real, r.imag])

    def jac(p):
        j = -model_frf(p)[1] / sd[:, None]
        return np.concatenate([j.real, j.imag])

    p0 = np.concatenate([np.log(theta).ravel(), np.zeros(nb), [np.log(m)] * n_m,
                         np.zeros(nd)])
    sol = least_squares(res, p0, jac=jac, x_scale=0.05, max_nfev=400)
    if not sol.success:
        raise ModelError(f"impact_damping: the FRF fit did not converge ({sol.message})")
    dof_res = max(2 * s.size - p0.size, 1)
    chi2 = float(2 * sol.cost / dof_res)
    try:
        cov = np.linalg.inv(sol.jac.T @ sol.jac) * max(chi2, 1.0)
    except np.linalg.LinAlgError as exc:
        raise ModelError("impact_damping: the FRF fit's information matrix is singular "
                         "(a parameter the modes in the band do not see)") from exc
    eta0 = np.array([b.law.damping_eta_s for b in model.geometry.bearings])
    par = np.exp(sol.x)
    return ImpactDamping(tuple(model.theta_bearings), tuple(names), par, cov,
                         eta0 * par[k0:k0 + nb], int(s.size), chi2, modes)


__all__ = ["ImpactDamping", "ImpactOptions", "force_band_top", "impact_damping"]
