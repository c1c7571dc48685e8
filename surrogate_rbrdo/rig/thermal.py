"""The rig's thermal transient and the thermal soak: a cold start, a speed held, records as the
spindle warms.

A spindle's bearings warm after a start with a time constant of tens of minutes; a rigidly
(position-) preloaded arrangement then gains preload as the inner ring and shaft grow more than
the outer ring and housing (Holkup, Cao, Kolář, Altintas & Zelený, *CIRP Annals* 59, 2010;
Li & Shin, *J. Manuf. Sci. Eng.* 126, 2004), a spring (constant-force) preload does not. The
rig models this with one time constant (Bossmanns & Tu, *J. Manuf. Sci. Eng.* 121, 1999, a
lumped thermal network's dominant mode): after a cold start at speed ``Ω`` every temperature
rise, and every parameter of an effect that follows temperature
(:attr:`~surrogate_rbrdo.spindle.effects.Effect.thermal_params`, the preload growth ``b`` of
``thermal_preload``), is the fraction

    θ(t) = 1 − exp(−t / τ)

of its steady-state value at that speed. The steady effect (``F(Ω) = F₀(1 + b (Ω/Ω_ref)^q)``)
is what the campaign's steady records see: each is taken at its speed's thermal equilibrium.

A **thermal soak** (:class:`SoakPlan`) holds a speed from a cold start (by default, run by
run in turn, the two sweep speeds either side of the resonance) and takes a steady record at
each of its times, in runs of their own (each with its run's thermal scatter, as any
run), with the front bearing's outer-ring temperature (:meth:`ThermalModel.temperature_K`).
An effect that drifts with temperature changes the 1x response during the hold; one that does
not (a centrifugal softening, a seal, a housing) leaves it constant — the separating test of a
preload growth (``discrepancy.soak``).

>>> tm = ThermalModel()
>>> round(tm.fraction(tm.time_constant_s), 4)
0.6321
>>> round(tm.rise_K(24000.0), 1), round(tm.rise_K(12000.0), 2)
(15.0, 4.72)
>>> SoakPlan(speed_rpm=24000.0).times_s[-1]
3600.0
>>> SoakPlan(speeds_rpm=(21000.0, 22500.0)).speed_of(1)
22500.0
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field, replace

import numpy as np

from surrogate_rbrdo.core.validate import check_choice, check_int, check_positive, check_range


def _default_times() -> tuple[float, ...]:
    return (0.0, 300.0, 600.0, 900.0, 1200.0, 1800.0, 2700.0, 3600.0)


@dataclass(frozen=True)
class ThermalModel:
    """One-time-constant warm-up of the spindle (see module doc).

    Attributes
    ----------
    time_constant_s : float
        τ of the dominant thermal mode (15 min; tens of minutes in the sources above).
    rise_ref_K : float
        Steady outer-ring temperature rise of the front bearing at ``speed_ref_rpm`` (15 K:
        measured rises of high-speed spindles' bearings are 10–25 K at their top speed).
    speed_ref_rpm : float
    speed_exponent : float
        Rise ∝ speed^exponent: the bearing's friction power, Palmgren's viscous moment
        ``M ∝ (ν n)^{2/3}`` times ``n`` (Harris & Kotzalas, *Rolling Bearing Analysis*, 2006).
    ambient_K : float
        Mean starting temperature; each run starts at ``ambient_K + N(0, ambient_sd_K²)``.
    ambient_sd_K : float
    sensor_noise_K : float
        SD of one temperature reading (a PT100 on the outer ring, averaged over a record).
    """

    time_constant_s: float = 900.0
    rise_ref_K: float = 15.0
    speed_ref_rpm: float = 24000.0
    speed_exponent: float = 5.0 / 3.0
    ambient_K: float = 293.15
    ambient_sd_K: float = 0.5
    sensor_noise_K: float = 0.05

    def __post_init__(self) -> None:
        for n in ("time_constant_s", "rise_ref_K", "speed_ref_rpm", "ambient_K"):
            check_positive(n, getattr(self, n))
        check_range("speed_exponent", self.speed_exponent, 0.0, 4.0)
        for n in ("ambient_sd_K", "sensor_noise_K"):
            check_positive(n, getattr(self, n), allow_zero=True)

    def fraction(self, t_s: float | np.ndarray) -> np.ndarray | float:
        """θ(t): the fraction of the steady thermal state reached ``t_s`` after a cold start."""
        t = np.asarray(t_s, dtype=float)
        if np.any(t < 0) or not np.all(np.isfinite(t)):
            raise ValueError(f"t_s = {t_s!r} is not allowed: times >= 0 s after the start")
        out = -np.expm1(-t / self.time_constant_s)
        return float(out) if out.ndim == 0 else out

    def rise_K(self, speed_rpm: float) -> float:
        """Steady temperature rise at ``speed_rpm``."""
        check_positive("speed_rpm", speed_rpm, allow_zero=True)
        return self.rise_ref_K * (speed_rpm / self.speed_ref_rpm) ** self.speed_exponent

    def temperature_K(self, speed_rpm: float, t_s: np.ndarray, rng: np.random.Generator
                      ) -> np.ndarray:
        """Readings of one run's outer-ring temperature at ``t_s`` after a cold start at
        ``speed_rpm``: its own starting temperature, the rise, the sensor's noise."""
        t = np.asarray(t_s, dtype=float)
        start = self.ambient_K + self.ambient_sd_K * rng.normal()
        return (start + self.rise_K(speed_rpm) * self.fraction(t)
                + self.sensor_noise_K * rng.normal(size=t.shape))


#: how a soak's speeds are chosen from the sweep measured before it (:meth:`SoakPlan.at`)
SOAK_RULES = ("flanks", "resonance")


@dataclass(frozen=True)
class SoakPlan:
    """A thermal soak: ``runs`` cold starts, each holding one speed and taking a steady record
    at each of ``times_s`` (s after reaching speed; default every 5–15 min for an hour, about
    4 τ of :class:`ThermalModel`).

    The speeds: ``speeds_rpm`` (any number, the runs taken at them in turn: run ``j`` at
    ``speeds_rpm[j % n]``), else ``speed_rpm`` (one), else chosen from the speed sweep measured
    before it (:meth:`at`) by ``rule``:

    * ``"flanks"`` (default; ``runs >= 4``): the two sweep speeds either side of its largest
      mean 1x amplitude (the resonance), ``runs`` split between them (the one-speed
      ``"resonance"`` soak, with a warning, when the largest is at an end of the sweep). A
      bearing that stiffens moves the resonance up: the amplitude below it falls and above it
      rises, while a drift of the probes' gain with temperature (:class:`~.sensors.ProbeModel`
      ``tempco_sd_per_K``) scales both speeds' responses alike — the soak test
      (``discrepancy.soak``) tells them apart.
    * ``"resonance"``: the one speed of the largest amplitude, where the response is most
      sensitive to a bearing's stiffness (the soak before the two-speed rule; its drift lies
      almost along the response itself, so at one speed a gain drift removes most of it;
      ``runs >= 3``).

    >>> SoakPlan().at([1000.0, 2000.0, 3000.0, 4000.0], [1e-7, 3e-6, 1e-6, 5e-7]).speeds
    (1000.0, 3000.0)
    >>> SoakPlan(rule="resonance").at([1000.0, 2000.0, 3000.0], [1e-7, 3e-6, 1e-6]).speeds
    (2000.0,)
    """

    speed_rpm: float | None = None
    times_s: tuple[float, ...] = field(default_factory=_default_times)
    runs: int = 4
    rule: str = "flanks"
    speeds_rpm: tuple[float, ...] = ()

    def __post_init__(self) -> None:
        if self.speed_rpm is not None:
            check_positive("soak.speed_rpm", self.speed_rpm)
            object.__setattr__(self, "speed_rpm", float(self.speed_rpm))
        t = np.asarray(self.times_s, dtype=float)
        if t.ndim != 1 or t.size < 3 or np.any(t < 0) or np.any(np.diff(t) <= 0):
            raise ValueError(f"soak.times_s = {list(self.times_s)} is not allowed: at least 3 "
                             "increasing times >= 0 s after reaching speed")
        object.__setattr__(self, "times_s", tuple(t.tolist()))
        check_choice("soak.rule", self.rule, SOAK_RULES)
        sp = tuple(float(s) for s in np.atleast_1d(np.asarray(self.speeds_rpm, dtype=float)))
        for s in sp:
            check_positive("soak.speeds_rpm[]", s)
        if len(set(sp)) != len(sp):
            raise ValueError(f"soak.speeds_rpm = {list(sp)} is not allowed: distinct speeds")
        if sp and self.speed_rpm is not None:
            raise ValueError(f"soak.speed_rpm = {self.speed_rpm:g} and soak.speeds_rpm = "
                             f"{list(sp)}: give one of them")
        object.__setattr__(self, "speeds_rpm", sp)
        n = len(sp) or (1 if self.speed_rpm is not None or self.rule == "resonance" else 2)
        check_int("soak.runs", self.runs, minimum=3)
        if n > 1 and self.runs < 2 * n:
            # before the two-speed rule (tenth session) 3 runs at the resonance were allowed
            how = (f"{n} soak.speeds_rpm" if sp else
                   "soak.rule = 'flanks' (the default since the tenth session: 2 speeds)")
            raise ValueError(f"soak.runs = {self.runs} is not allowed with {how}: at least 2 "
                             f"runs at each speed, runs >= {2 * n}; or rule = 'resonance' (or "
                             "one speed_rpm) for the one-speed soak, runs >= 3")

    @property
    def speeds(self) -> tuple[float, ...]:
        """The speeds held (``()`` until resolved by :meth:`at`)."""
        return self.speeds_rpm or (() if self.speed_rpm is None else (self.speed_rpm,))

    def speed_of(self, j: int) -> float:
        """The speed of run ``j`` (the speeds in turn)."""
        sp = self.speeds
        if not sp:
            raise ValueError("the soak's speed is not resolved: SoakPlan.at(sweep) first")
        return sp[j % len(sp)]

    def at(self, speeds_rpm, amplitude=None) -> SoakPlan:
        """The plan with its speeds resolved: when none is given, by ``rule`` from the sweep's
        ``speeds_rpm`` and ``amplitude`` (its mean 1x amplitude there, any channel): the
        largest amplitude's speed (``"resonance"``), or its two neighbours (``"flanks"``).
        Without amplitudes the top speed. When ``"flanks"`` cannot put a speed either side
        (the largest amplitude at the sweep's first or last speed, or no amplitudes), a
        ``UserWarning`` naming the speeds and the one-speed plan (``rule = "resonance"``).

        >>> SoakPlan(rule="resonance").at([1000.0, 2000.0, 3000.0], [1e-7, 3e-6, 1e-6]).speed_rpm
        2000.0
        >>> import warnings
        >>> with warnings.catch_warnings():
        ...     warnings.simplefilter("ignore")
        ...     end = SoakPlan().at([1000.0, 2000.0, 3000.0], [1e-7, 1e-6, 3e-6])
        >>> end.rule, end.speeds
        ('resonance', (3000.0,))
        """
        if self.speeds:
            return self
        sp = np.asarray(speeds_rpm, dtype=float)
        a = sp if amplitude is None else np.asarray(amplitude, dtype=float)
        if a.shape != sp.shape:
            raise ValueError(f"amplitude has shape {a.shape}: one per speed, {sp.shape}")
        i = int(np.argmax(a))
        if self.rule == "resonance":
            return replace(self, speed_rpm=float(sp[i]))
        order = np.argsort(sp)
        k = int(np.flatnonzero(order == i)[0])
        if amplitude is None or not 0 < k < sp.size - 1:
            # both speeds on one flank: their relative in-phase drifts nearly alike, so the
            # contrast that tells a stiffening from a gain drift has almost no power (review
            # s13, M3); the one-speed soak's quadratures are an honest, if weaker, test
            why = ("no sweep amplitudes given" if amplitude is None else
                   f"the largest 1x amplitude is at the sweep's "
                   f"{'first' if k == 0 else 'last'} speed")
            warnings.warn(f"soak.rule = 'flanks': {why} ({float(sp[i]):g} rpm of "
                          f"{float(sp.min()):g}–{float(sp.max()):g} rpm), so no two speeds lie "
                          "either side of a resonance; the one-speed soak at "
                          f"{float(sp[i]):g} rpm instead (rule = 'resonance', all "
                          f"{self.runs} runs)", UserWarning, stacklevel=2)
            return replace(self, rule="resonance", speed_rpm=float(sp[i]))
        return replace(self, speeds_rpm=(float(sp[order[k - 1]]), float(sp[order[k + 1]])))
