"""The outer parameters: the model's own uncertain parameters and the candidate effects' ones.

The *nuisance* is what every spindle and every measurement chain has and the model does not know
exactly, recalibrated before any effect is tried:

* a stiffness factor θ per bearing (assembly; the paper's θ) and a damping factor per bearing
  (or one for all);
* optionally a mass factor of named disks (a tool/holder changed or re-clamped), with a
  Gaussian prior;
* optionally the measurement chain of each probe channel: a gain factor (calibration error, prior
  SD ``gain_sd``) and a first-order low-pass time constant ``τ = 1/(2π f_c)`` around the
  drivers' nominal bandwidth (prior SD ``delay_sd_s``, which also takes an unknown timing
  skew: ``e^{iωs}/(1 + iωτ) ≈ 1/(1 + iω(τ − s))``), so the model's channel reads
  ``g/(1 + iωτ) × response``;
* optionally the force channel of impact tests (an FRF is response over force): the hammer's
  (or force sensor's) gain factor, prior SD ``force_gain_sd`` (its calibration certificate),
  and its unknown timing skew ``s_f`` (prior SD ``force_delay_sd_s``), so an FRF reads
  ``g/(1 + iωτ) / (g_f e^{iω s_f}) × H`` — one pair for all impact tests (one hammer, one
  installation);
* optionally the thermal state of the run the impact tests were taken in: a stiffness factor
  per θ bearing on every impact test, relative to the 1x runs' mean state (prior SD
  ``impact_theta_sd``). A run's preload, hence its bearing stiffness, scatters from run to run
  (the rig's thermal state); hits taken in one run share it, so FRFs at several speeds of one
  run keep the speed dependence of the bearings while their common level is free.

Priors enter as pseudo-observations ``(p − μ)/σ`` appended to the residuals. The unbalance is
not here: it is solved exactly inside (:mod:`.problem`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from surrogate_rbrdo.core.validate import check_choice, check_positive, check_range
from surrogate_rbrdo.discrepancy.candidates import Candidate
from surrogate_rbrdo.spindle.effects import Effect


@dataclass(frozen=True)
class NuisanceOptions:
    """Which of the model's own parameters are recalibrated, and within which range.

    Attributes
    ----------
    theta_bounds : (float, float)
        Range of each bearing's stiffness factor θ (the paper's identification bounds
        ``[0.5, 1.5] k_catalog``).
    damping : {"per_bearing", "common", "fixed"}
        A factor on each bearing's damping, one for all, or none.
    damping_bounds : (float, float)
        Range of a damping factor (the paper's ``[0.5, 2.0] c_init``, widened to 0.25–4 since
        damping is the worst-known parameter).
    mass_disks : tuple of str
        Disks whose mass and inertias get a factor (prior lognormal, SD ``mass_sd``).
    mass_sd : float
    gain_sd : float
        Prior SD of each probe channel's gain factor (0: gains known, no parameter).
    bandwidth_hz : float or None
        Nominal first-order bandwidth of the probe drivers (None: an ideal chain).
    delay_sd_s : float
        Prior SD of each channel's time constant (0: known, no parameter).
    force_gain_sd : float
        Prior SD of the force channel's gain factor (impact tests; 0: known, no parameter).
    force_delay_sd_s : float
        Prior SD of the force channel's timing skew (s; 0: known, no parameter).
    impact_theta_sd : float
        Prior SD of the impact run's log stiffness factor per θ bearing (0: the impact tests
        share the 1x runs' θ, no parameter).
    """

    theta_bounds: tuple[float, float] = (0.5, 1.5)
    damping: str = "per_bearing"
    damping_bounds: tuple[float, float] = (0.25, 4.0)
    mass_disks: tuple[str, ...] = ()
    mass_sd: float = 0.03
    gain_sd: float = 0.0
    bandwidth_hz: float | None = None
    delay_sd_s: float = 0.0
    force_gain_sd: float = 0.0
    force_delay_sd_s: float = 0.0
    impact_theta_sd: float = 0.0

    def __post_init__(self) -> None:
        check_choice("nuisance.damping", self.damping, ("common", "per_bearing", "fixed"))
        for name in ("theta_bounds", "damping_bounds"):
            lo, hi = getattr(self, name)
            check_range(f"nuisance.{name}[0]", lo, 1e-3, 1.0)
            check_range(f"nuisance.{name}[1]", hi, 1.0, 1e3)
        object.__setattr__(self, "mass_disks", tuple(self.mass_disks))
        check_range("nuisance.mass_sd", self.mass_sd, 1e-6, 0.5)
        check_range("nuisance.gain_sd", self.gain_sd, 0.0, 0.5)
        check_positive("nuisance.delay_sd_s", self.delay_sd_s, allow_zero=True)
        check_range("nuisance.force_gain_sd", self.force_gain_sd, 0.0, 0.5)
        check_range("nuisance.force_delay_sd_s", self.force_delay_sd_s, 0.0, 1e-3)
        check_range("nuisance.impact_theta_sd", self.impact_theta_sd, 0.0, 0.5)
        if self.bandwidth_hz is not None:
            check_positive("nuisance.bandwidth_hz", self.bandwidth_hz)

    @classmethod
    def probe_chain(cls, **kw) -> NuisanceOptions:
        """Eddy-current probe systems as ``docs/rig.md`` states them (API 670 class): gain SD
        2 %, 10 kHz first-order drivers with ±10 % bandwidth and 0.2 µs skew; the tool/holder's
        mass re-clamped (3 %); for impact tests the hammer's calibration (1 %, its certificate),
        the force channel's skew (0.2 µs) and the impact run's thermal state (stiffness SD
        10 %: weakly informative, several times the rig's run-to-run scatter)."""
        tau = 1.0 / (2 * np.pi * 1e4)
        return cls(**{"gain_sd": 0.02, "bandwidth_hz": 1e4,
                      "delay_sd_s": math.hypot(0.1 * tau, 0.2e-6),
                      "force_gain_sd": 0.01, "force_delay_sd_s": 0.2e-6,
                      "impact_theta_sd": 0.1,
                      "mass_disks": ("tool_holder",), "mass_sd": 0.03, **kw})

    @property
    def tau0(self) -> float:
        return 0.0 if self.bandwidth_hz is None else 1.0 / (2 * np.pi * self.bandwidth_hz)


@dataclass(frozen=True)
class Slot:
    """A candidate effect in the model at one bearing scope; ``fixed`` shape values are not
    fitted."""

    candidate: Candidate
    scope: tuple[str, ...] = ()
    fixed: tuple[tuple[str, float], ...] = ()

    @property
    def free(self) -> tuple[str, ...]:
        fx = dict(self.fixed)
        return self.candidate.strength + tuple(p for p in self.candidate.shape if p not in fx)

    @property
    def label(self) -> str:
        s = f"{self.candidate.name}"
        return s + (f"[{','.join(self.scope)}]" if self.scope else "")


#: typical size of a reciprocal strength parameter (a compliance, m/N): 1/(1 GN/m)
RECIPROCAL_SCALE = 1e-9


@dataclass(frozen=True)
class Rows:
    """Model rows for a batch of outer parameter vectors."""

    theta: np.ndarray                     # (B, m)
    damping: np.ndarray                   # (B, nb)
    mass: np.ndarray                      # (B, n_mass)
    gain: np.ndarray                      # (B, C)
    tau: np.ndarray                       # (B, C)
    extras: list[tuple[Effect, ...]]
    force: np.ndarray | None = None       # (B, 2): force channel's gain and skew (s)
    theta_impact: np.ndarray | None = None  # (B, m): impact run's stiffness factors

    def theta_for(self, kind: str) -> np.ndarray:
        """The stiffness factors a test of ``kind`` sees (``(B, m)``)."""
        if kind == "impact" and self.theta_impact is not None:
            return self.theta * self.theta_impact
        return self.theta

    def force_chain(self, freq_rad_s: np.ndarray) -> np.ndarray:
        """``1 / (g_f e^{iω s_f})`` per row and frequency, ``(B, X)``: what an FRF is
        multiplied by (ones without force parameters)."""
        w = np.asarray(freq_rad_s, dtype=float)[None, :]
        if self.force is None:
            return np.ones((self.theta.shape[0], w.shape[1]), dtype=complex)
        return np.exp(-1j * w * self.force[:, 1:2]) / self.force[:, :1]

    def repeat(self, n: int) -> Rows:
        """Every row repeated ``n`` times (``np.repeat`` order)."""
        rp = [np.repeat(a, n, 0) for a in (self.theta, self.damping, self.mass, self.gain,
                                             self.tau)]
        ex = [e for e in self.extras for _ in range(n)]
        return Rows(*rp, ex, None if self.force is None else np.repeat(self.force, n, 0),
                    None if self.theta_impact is None else np.repeat(self.theta_impact, n, 0))

    def physical(self) -> tuple[np.ndarray, np.ndarray, list, np.ndarray]:
        return self.theta, self.damping, self.extras, self.mass


@dataclass(frozen=True)
class Parametrisation:
    """Outer vector ``x`` ↔ model rows: ``[log θ…, log s…, log m…, log g…, τ…, slots…]``."""

    theta_bearings: tuple[str, ...]
    bearings: tuple[str, ...]
    nuisance: NuisanceOptions
    n_channels: int = 0
    slots: tuple[Slot, ...] = ()
    impacts: bool = False

    def with_slots(self, slots: tuple[Slot, ...]) -> Parametrisation:
        return Parametrisation(self.theta_bearings, self.bearings, self.nuisance,
                               self.n_channels, slots, self.impacts)

    @cached_property
    def force_names(self) -> tuple[str, ...]:
        """The force channel's parameters (only with impact tests in the data)."""
        o = self.nuisance
        if not self.impacts:
            return ()
        return (("log_force_gain",) if o.force_gain_sd > 0 else ()) + (
            ("force_delay",) if o.force_delay_sd_s > 0 else ()) + (
            tuple(f"log_theta_impact_{b}" for b in self.theta_bearings)
            if o.impact_theta_sd > 0 else ())

    @cached_property
    def sizes(self) -> tuple[int, int, int, int, int]:
        """Numbers of θ, damping, mass, gain and τ parameters."""
        o = self.nuisance
        nd = {"common": 1, "per_bearing": len(self.bearings), "fixed": 0}[o.damping]
        return (len(self.theta_bearings), nd, len(o.mass_disks),
                self.n_channels if o.gain_sd > 0 else 0,
                self.n_channels if o.delay_sd_s > 0 and o.bandwidth_hz is not None else 0)

    @cached_property
    def n_nuisance(self) -> int:
        return sum(self.sizes) + len(self.force_names)

    @property
    def names(self) -> tuple[str, ...]:
        nt, nd, nm, ng, nk = self.sizes
        out = [f"log_theta_{b}" for b in self.theta_bearings]
        out += {"common": ["log_damping"], "fixed": [],
                "per_bearing": [f"log_damping_{b}" for b in self.bearings]}[
            self.nuisance.damping]
        out += [f"log_mass_{d}" for d in self.nuisance.mass_disks]
        out += [f"log_gain_{c}" for c in range(ng)] + [f"tau_{c}" for c in range(nk)]
        out += list(self.force_names)
        for s in self.slots:
            out += [f"{s.label}.{p}" for p in s.free]
        return tuple(out)

    def _prior(self) -> tuple[np.ndarray, np.ndarray]:
        """Means and SDs of the nuisance parameters (SD inf: no prior; read-only arrays)."""
        return self._prior_arrays

    # the derived quantities below depend on the frozen fields only: computed once per
    # instance (a fit asks for them at every residual evaluation)
    @cached_property
    def _prior_arrays(self) -> tuple[np.ndarray, np.ndarray]:
        nt, nd, nm, ng, nk = self.sizes
        o = self.nuisance
        fsd = {"log_force_gain": o.force_gain_sd, "force_delay": o.force_delay_sd_s,
               **{f"log_theta_impact_{b}": o.impact_theta_sd for b in self.theta_bearings}}
        mu = np.concatenate([np.zeros(nt + nd + nm + ng), np.full(nk, o.tau0),
                             np.zeros(len(self.force_names))])
        sd = np.concatenate([np.full(nt + nd, np.inf), np.full(nm, o.mass_sd),
                             np.full(ng, o.gain_sd), np.full(nk, o.delay_sd_s),
                             [fsd[n] for n in self.force_names]])
        mu.flags.writeable = sd.flags.writeable = False
        return mu, sd

    @cached_property
    def n_prior(self) -> int:
        return int(np.sum(np.isfinite(self._prior()[1])))

    def prior_residuals(self, X: np.ndarray) -> np.ndarray:
        """Pseudo-observations ``(μ − p)/σ`` of the priored nuisance parameters, (B, n_prior)."""
        mu, sd = self._prior()
        k = np.isfinite(sd)
        return (mu[k] - np.atleast_2d(X)[:, :mu.size][:, k]) / sd[k]

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper bounds of the outer parameters (fitting units; copies)."""
        lo, hi = self._bounds
        return lo.copy(), hi.copy()

    @cached_property
    def _bounds(self) -> tuple[np.ndarray, np.ndarray]:
        nt, nd, nm, ng, nk = self.sizes
        o = self.nuisance
        mu, sd = self._prior()
        lo = [np.log(o.theta_bounds[0])] * nt + [np.log(o.damping_bounds[0])] * nd
        hi = [np.log(o.theta_bounds[1])] * nt + [np.log(o.damping_bounds[1])] * nd
        lo += list(mu[nt + nd:] - 6 * sd[nt + nd:])
        hi += list(mu[nt + nd:] + 6 * sd[nt + nd:])
        for s in self.slots:
            c = s.candidate
            lo += list(c.lower)
            hi += list(c.upper)
            fx = dict(s.fixed)
            for p, (a, b) in zip(c.shape, c.shape_bounds, strict=True):
                if p not in fx:
                    lo.append(a)
                    hi.append(b)
        lo_a = np.array(lo, dtype=float)
        k0 = nt + nd + nm + ng
        lo_a[k0:k0 + nk] = np.maximum(lo_a[k0:k0 + nk], 0.0)
        return lo_a, np.array(hi, dtype=float)

    def scales(self) -> np.ndarray:
        """A typical magnitude per parameter (finite-difference steps are relative to it)."""
        return self._scales.copy()

    @cached_property
    def _scales(self) -> np.ndarray:
        nt, nd, nm, ng, nk = self.sizes
        o = self.nuisance
        out = [0.05] * nt + [0.3] * nd + [o.mass_sd] * nm + [o.gain_sd] * ng
        out += [max(o.delay_sd_s, 1e-9)] * nk
        fsd = {"log_force_gain": o.force_gain_sd, "force_delay": o.force_delay_sd_s}
        out += [fsd.get(n, 0.05) for n in self.force_names]
        for s in self.slots:
            c = s.candidate
            for rec, a, b in zip(c.reciprocal, c.lower, c.upper, strict=True):
                out.append(RECIPROCAL_SCALE if rec else (b - a) / 50 if np.isfinite(b - a)
                           else 0.01)
            fx = dict(s.fixed)
            for p, (a, b) in zip(c.shape, c.shape_bounds, strict=True):
                if p not in fx:
                    out.append(max((b - a) / 100, 1e-3) if np.isfinite(b - a) else 1.0)
        return np.array(out, dtype=float)

    def x0(self, starts: dict[str, float] | None = None) -> np.ndarray:
        """Prior means (nominal) for the nuisance, every slot off, shapes at their first start
        (or ``starts``)."""
        starts = starts or {}
        x = list(self._prior()[0])
        for s in self.slots:
            c = s.candidate
            x += [starts.get(f"{s.label}.{p}", o) for p, o in zip(c.strength, c.off,
                                                                   strict=True)]
            fx = dict(s.fixed)
            for p, st in zip(c.shape, c.shape_starts, strict=True):
                if p not in fx:
                    x.append(starts.get(f"{s.label}.{p}", st[0]))
        return np.array(x, dtype=float)

    def slot_values(self, x: np.ndarray) -> list[dict[str, float]]:
        """Per slot: its parameters (fitting units) including fixed shapes."""
        k = self.n_nuisance
        out = []
        for s in self.slots:
            vals = dict(s.fixed)
            for p in s.free:
                vals[p] = float(x[k])
                k += 1
            out.append(vals)
        return out

    def rows(self, X: np.ndarray) -> Rows:
        """Model rows for outer rows ``X`` (B, n)."""
        X = np.atleast_2d(X)
        B = X.shape[0]
        nt, nd, nm, ng, nk = self.sizes
        o = self.nuisance
        parts = np.split(X[:, :self.n_nuisance], np.cumsum([nt, nd, nm, ng])[:4], axis=1)
        theta = np.exp(parts[0])
        ds = np.ones((B, len(self.bearings))) * (np.exp(parts[1]) if nd else 1.0)
        gain = np.exp(parts[3]) if ng else np.ones((B, self.n_channels))
        tau = parts[4][:, :nk] if nk else np.full((B, self.n_channels), o.tau0)
        force = theta_impact = None
        if self.force_names:
            f = parts[4][:, nk:]
            fn = self.force_names
            force = np.column_stack([
                np.exp(f[:, fn.index("log_force_gain")]) if "log_force_gain" in fn
                else np.ones(B),
                f[:, fn.index("force_delay")] if "force_delay" in fn else np.zeros(B)])
            ti = [i for i, n in enumerate(fn) if n.startswith("log_theta_impact_")]
            theta_impact = np.exp(f[:, ti]) if ti else None
        extras = [tuple(s.candidate.effect(s.scope, v)
                        for s, v in zip(self.slots, self.slot_values(x), strict=True))
                  for x in X]
        return Rows(theta, ds, np.exp(parts[2]), gain, tau, extras, force, theta_impact)
