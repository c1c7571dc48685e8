"""Impact tests at speed, the fast path: per-hit FRFs ``H(ω; Ω)`` without the time domain.

Under 1x unbalance excitation the response frequency is the spin speed, ``ω = Ω``, and there
a bearing stiffness that varies as ``Ω²`` is indistinguishable from a mass at the bearing, a
polar-inertia change from a diametral one, a cross-coupled stiffness ``k_xy`` from a damping
``−k_xy/Ω``. Off the synchronous line they part: a hit at the tool while the spindle runs
excites every mode at its own frequency ``ω ≠ Ω`` — the whirl modes split into forward and
backward by the gyroscopic coupling ``iωΩ G``, the bearings at their speed ``K(Ω)`` (not a
mass: ``−ω² Δm`` at standstill too), the cross-coupled stiffness as a forward/backward damping
asymmetry. Tool-point FRFs measured on the running spindle are the practice of operational
spindle testing (Zaghbani & Songmene 2009, *Int. J. Mach. Tools Manuf.* 49:947; Özşahin et
al. 2015, *Mech. Syst. Signal Process.* 50:533; Rantatalo et al. 2007, *Int. J. Mach. Tools
Manuf.* 47:1034 with non-contact excitation); the hit goes on a smooth cylindrical test arbor
in the holder.

:class:`ImpactPlan` states the test plan (speeds, lines, hits). Each hit is one record of
``duration_s`` without exponential window (the slowest mode of the reference spindle decays as
``e^{−7.7 t}``: 5e-4 of its amplitude is left after 1 s, so the rectangular window leaks
nothing measurable). All hits are taken in one run — one thermal state of the bearings (the
rig draws the preload per run: 8 % CoV, a few percent of stiffness) — speed after speed, so
the FRFs of the different speeds differ by what depends on speed and not by the run-to-run
scatter, whose common level the workflow recalibrates (``impact_theta_sd``); the synchronous
response is subtracted with the keyphasor's 1x phasor, and lines within
``exclude_hz`` of the running frequency are dropped (what is left there is the phasor's
estimation error and, on a real machine, runout). What :func:`rig.frf.h1_frf` gives for one
hit of the linear truth is

    H_hit(ω) = [g_p L_p(ω) e^{iω s_p} H(ω; Ω) F(ω) + N_x] / [g_f e^{iω s_f} F(ω) + N_f],

with ``H`` the FE receptance at spin ``Ω`` (:func:`frf_exact`: the dense dynamic stiffness
``K(Ω) + iω C(Ω) − ω² M`` of :meth:`~surrogate_rbrdo.spindle.assembly.SpindleModel.system_matrices`,
gyroscopics in ``C(Ω)``), ``F`` the half-sine pulse's spectrum (its peak scattered per hit),
the probe's gain, driver low-pass and skew, the force channel's gain and skew, and ``N_x``,
``N_f`` the DFTs of the probe noise (white, with the ADC's quantisation) over the record and of
the hammer's noise over the force window (twice the pulse). :func:`sample_frfs` draws exactly
this.

>>> f = hammer_spectrum(np.array([0.0, 1000.0]), 300.0, 0.4e-3)
>>> np.round(np.abs(f), 5).tolist()        # 2 P τ / π at DC (N s)
[0.07639, 0.06558]
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from surrogate_rbrdo.core.validate import check_int, check_positive
from surrogate_rbrdo.rig.sensors import Installation, SensorSet
from surrogate_rbrdo.rig.simulate import ProbeLayout
from surrogate_rbrdo.spindle.assembly import RPM, SpindleModel

DIRECTIONS = ("x", "y")


def _default_lines() -> tuple[float, ...]:
    return tuple(np.arange(40.0, 1481.0, 40.0).tolist())


@dataclass(frozen=True)
class ImpactPlan:
    """Impact tests at speed: where, at which speeds, which FRF lines, how many hits.

    Attributes
    ----------
    speeds_rpm : tuple of float
        Spin speeds of the tests (0: standstill). Default standstill, 10 000 and 20 000 rpm:
        inside the 1x campaign's training speeds (the top 10 % are held out).
    freqs_hz : tuple of float
        FRF lines kept (default 40–1 480 Hz every 40 Hz: both bending modes of the reference
        spindle, ~360 and ~790 Hz, with their gyroscopic split).
    directions : tuple of str
        Hit directions at the tool (every probe records every hit: the cross FRFs carry the
        gyroscopic and cross-coupled coupling).
    hits : int
        Hits per speed and direction (20: the per-line noise is estimated from them, and the
        H1 average over 20 hits is the usual practice; all in the impact run).
    duration_s : float
        Record length of one hit.
    exclude_hz : float
        Lines within this distance of the running frequency are dropped.
    """

    speeds_rpm: tuple[float, ...] = (0.0, 10_000.0, 20_000.0)
    freqs_hz: tuple[float, ...] = _default_lines()
    directions: tuple[str, ...] = DIRECTIONS
    hits: int = 20
    duration_s: float = 1.0
    exclude_hz: float = 10.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "speeds_rpm", tuple(float(s) for s in self.speeds_rpm))
        object.__setattr__(self, "freqs_hz", tuple(float(f) for f in self.freqs_hz))
        object.__setattr__(self, "directions", tuple(self.directions))
        for s in self.speeds_rpm:
            check_positive("impacts.speeds_rpm[]", s, allow_zero=True)
        if len(self.freqs_hz) < 3 or min(self.freqs_hz) <= 0:
            raise ValueError(f"impacts.freqs_hz = {self.freqs_hz[:4]}... is not allowed: need "
                             "at least 3 lines, all > 0 Hz")
        for d in self.directions:
            if d not in DIRECTIONS:
                raise ValueError(f"impacts.directions[] = {d!r} is not allowed: 'x' or 'y'")
        check_int("impacts.hits", self.hits, minimum=5)
        check_positive("impacts.duration_s", self.duration_s)
        check_positive("impacts.exclude_hz", self.exclude_hz, allow_zero=True)

    def lines(self, speed_rpm: float) -> np.ndarray:
        """The FRF lines kept at ``speed_rpm`` (away from the running frequency).

        >>> ImpactPlan(freqs_hz=(150.0, 160.0, 170.0, 180.0)).lines(10_000.0).tolist()
        [150.0, 180.0]
        """
        f = np.asarray(self.freqs_hz)
        return f[np.abs(f - speed_rpm / 60.0) > self.exclude_hz]


def hammer_spectrum(freq_hz: np.ndarray, peak_N: float, pulse_s: float) -> np.ndarray:
    """Fourier transform (N s) of the half-sine pulse ``P sin(π t/τ)``, ``0 ≤ t ≤ τ``:
    ``P τ π (1 + e^{−iωτ}) / (π² − (ωτ)²)`` (its limit ``−i P τ/2`` at ``ωτ = π``)."""
    x = 2 * np.pi * np.asarray(freq_hz, dtype=float) * pulse_s
    den = np.pi**2 - x**2
    near = np.abs(den) < 1e-9
    val = peak_N * pulse_s * np.pi * (1 + np.exp(-1j * x)) / np.where(near, 1.0, den)
    return np.where(near, -0.5j * peak_N * pulse_s, val)


def frf_exact(model: SpindleModel, theta: np.ndarray, speed_rpm: float, freq_hz: np.ndarray,
              force_dof: int, out_dofs: np.ndarray) -> np.ndarray:
    """Receptances ``(F, n_out)`` (m/N) at ``out_dofs`` to a unit force at ``force_dof``, at
    spin ``speed_rpm`` and the frequencies ``freq_hz``: the dense solve of
    ``(K(Ω) + iω C(Ω) − ω² M) q = e`` (housing stages included)."""
    M, C, K = model.system_matrices(speed_rpm * RPM, theta)
    w = 2 * np.pi * np.asarray(freq_hz, dtype=float)[:, None, None]
    A = K[None] + 1j * w * C[None] - w**2 * M[None]
    e = np.zeros((w.shape[0], K.shape[0], 1), dtype=complex)
    e[:, force_dof, 0] = 1.0
    return np.linalg.solve(A, e)[:, np.asarray(out_dofs), 0]


def _chain(sensors: SensorSet, inst: Installation, freq_hz: np.ndarray) -> np.ndarray:
    """``(F, n_probe)``: each probe's gain, driver and skew over the force channel's gain and
    skew (the known delays are corrected by the FRF estimate)."""
    w = 2 * np.pi * freq_hz
    probe = np.stack([inst.gain[c] * sensors.lowpass(c, inst, freq_hz)
                      * np.exp(1j * w * inst.skew_s[c]) for c in sensors.probe_channels], -1)
    return probe / (inst.gain["hammer"] * np.exp(1j * w * inst.skew_s["hammer"]))[:, None]


def expected_frfs(model: SpindleModel, theta: np.ndarray, speed_rpm: float,
                  freq_hz: np.ndarray, sensors: SensorSet, inst: Installation,
                  direction: str) -> np.ndarray:
    """Noise-free measured FRFs ``(F, n_probe)`` (m/N) of a hit at the tool in ``direction``,
    in ``sensors.probe_channels`` order."""
    layout = ProbeLayout.of(model)
    fdof = 4 * layout.nodes["tool"] + DIRECTIONS.index(direction)
    H = frf_exact(model, theta, speed_rpm, freq_hz, fdof, layout.dofs(sensors))
    return H * _chain(sensors, inst, np.asarray(freq_hz, dtype=float))


def sample_frfs(model: SpindleModel, theta: np.ndarray, speed_rpm: float, freq_hz: np.ndarray,
                sensors: SensorSet, inst: Installation, rng: np.random.Generator, *,
                direction: str, n_hits: int = 1, duration_s: float = 1.0) -> np.ndarray:
    """FRFs of ``n_hits`` hits at the tool in ``direction`` (one truth state), drawn as the
    module doc states: ``(n_hits, F, n_probe)`` complex (m/N)."""
    f = np.asarray(freq_hz, dtype=float)
    H = expected_frfs(model, theta, speed_rpm, f, sensors, inst, direction)
    if not sensors.noise:
        return np.broadcast_to(H, (n_hits,) + H.shape).copy()
    hm, daq = sensors.hammer, sensors.daq
    dt = 1.0 / daq.sample_rate_hz
    peak = hm.peak_N * (1 + hm.peak_sd * rng.normal(size=n_hits))
    F = hammer_spectrum(f[None, :], 1.0, hm.pulse_ms * 1e-3) * peak[:, None]     # (n, F)
    q = daq.lsb_V if sensors.quantised else 0.0
    var_x = (sensors.probe.noise_rms_m**2 + (q / sensors.probe.sensitivity_V_per_m)**2 / 12)
    sd_x = np.sqrt(var_x * dt * duration_s / 2)                 # per component of the DFT
    var_f = hm.noise_N**2 + (q / hm.sensitivity_V_per_N)**2 / 12
    sd_f = np.sqrt(var_f * dt * 2 * hm.pulse_ms * 1e-3 / 2)      # over the force window
    w = 2 * np.pi * f
    g_f = inst.gain["hammer"] * np.exp(1j * w * inst.skew_s["hammer"])
    shape = (n_hits, f.size, H.shape[1])
    n_x = sd_x * (rng.normal(size=shape) + 1j * rng.normal(size=shape))
    n_f = sd_f * (rng.normal(size=(n_hits, f.size)) + 1j * rng.normal(size=(n_hits, f.size)))
    # H already carries the chain over g_f: the response is H g_f F + N_x
    x = H[None] * (g_f[None] * F)[..., None] + n_x
    return x / (g_f[None] * F + n_f)[..., None]
