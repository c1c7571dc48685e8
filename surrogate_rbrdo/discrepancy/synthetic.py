"""Phasor-level virtual measurements from a truth spindle: a stand-in for the virtual rig's fast
path, used for the blind grid and the tests until the rig provides one.

The truth is the model's machinery with other effects (hidden effects from the registry, and
truth-only geometry changes from :mod:`~surrogate_rbrdo.discrepancy.truth_effects`) and a drawn
assembly: bearing stiffness factors θ ~ N(1, σ_θ) (Table 4's CoVs), a lognormal bearing damping
factor, and per unbalance plane a magnitude uniform in [0.25, 1] of the ISO 21940-11 G2.5
permissible value with a uniform random phase (notes §3.15). Every record (one repeat at one
speed) is the exact steady response plus noise: a per-record complex gain error
``1 + g + i φ`` (gain ``g`` and phase ``φ`` jitter of the probe chain and the keyphasor) and an
additive circular complex noise (probe noise after synchronous demodulation: a probe with RMS
noise ``σ_n`` demodulated over ``N`` samples gives ``σ_n √(2/N)`` per component). Impact tests
give FRF lines with the same two kinds of noise; an identification run gives the effective
bearing stiffness at each speed with a relative error per record.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from surrogate_rbrdo.core.rng import require_rng
from surrogate_rbrdo.core.validate import check_int, check_positive
from surrogate_rbrdo.discrepancy.forward import ForwardModel
from surrogate_rbrdo.discrepancy.observables import ComplexBlock, MeasuredData, RealBlock
from surrogate_rbrdo.discrepancy.sweeps import Channel, Sweep
from surrogate_rbrdo.spindle.effects import Effect
from surrogate_rbrdo.spindle.geometry import SpindleGeometry


def default_channels(geometry: SpindleGeometry) -> tuple[Channel, ...]:
    """x/y probes at the tool tip and at every bearing (the rig's probe set)."""
    out = [Channel(f"tool_{d}", geometry.tool_tip_mm, d) for d in ("x", "y")]
    for b in geometry.bearings:
        out += [Channel(f"{b.name}_{d}", b.position_mm, d) for d in ("x", "y")]
    return tuple(out)


@dataclass(frozen=True)
class NoiseLevel:
    """Measurement noise per record.

    Attributes
    ----------
    additive_m : float
        SD of each component of the 1x phasor's additive noise (m).
    gain : float
        SD of the relative gain error per record.
    phase_rad : float
        SD of the phase error per record (rad).
    frf_additive : float
        SD of each component of an FRF line's additive noise (m/N).
    k_relative : float
        Relative SD of an identified bearing stiffness per record.
    """

    additive_m: float = 5e-9
    gain: float = 0.005
    phase_rad: float = 0.005
    frf_additive: float = 2e-10
    k_relative: float = 0.004

    def __post_init__(self) -> None:
        for f in ("additive_m", "gain", "phase_rad", "frf_additive", "k_relative"):
            check_positive(f"noise.{f}", getattr(self, f))


@dataclass(frozen=True)
class Campaign:
    """What is measured: speeds × repeats of the 1x response, impact tests, identification."""

    speeds_rpm: tuple[float, ...] = tuple(np.linspace(1000.0, 24000.0, 50).tolist())
    repeats: int = 20
    impact_freqs_hz: tuple[float, ...] = tuple(np.arange(20.0, 1500.0, 10.0).tolist())
    impact_repeats: int = 10
    identification: bool = True

    def __post_init__(self) -> None:
        check_int("campaign.repeats", self.repeats, minimum=5)
        check_int("campaign.impact_repeats", self.impact_repeats, minimum=5)
        if len(self.speeds_rpm) < 8:
            raise ValueError(f"campaign.speeds_rpm has {len(self.speeds_rpm)} speeds: need >= 8")


@dataclass(frozen=True)
class Assembly:
    """One built spindle: stiffness factors, damping factor, unbalance phasors (kg m)."""

    theta: np.ndarray
    damping: np.ndarray
    unbalance: np.ndarray

    @classmethod
    def draw(cls, permissible_kgm: float, n_planes: int, n_bearings: int, *,
             rng: np.random.Generator, theta_sd: tuple[float, ...] = (0.0605, 0.0641),
             damping_sd: float = 0.2) -> Assembly:
        """θ ~ N(1, σ) (clipped to [0.8, 1.2]), lognormal damping, random unbalance."""
        rng = require_rng(rng)
        th = np.clip(1.0 + rng.normal(size=len(theta_sd)) * np.asarray(theta_sd), 0.8, 1.2)
        d = np.exp(rng.normal() * damping_sd) * np.ones(n_bearings)
        mag = permissible_kgm * rng.uniform(0.25, 1.0, n_planes)
        return cls(th, d, mag * np.exp(2j * np.pi * rng.uniform(size=n_planes)))


@dataclass(frozen=True)
class Truth:
    """A truth spindle: geometry (possibly changed by truth-only effects) and effects."""

    geometry: SpindleGeometry
    effects: tuple[Effect, ...]
    theta_bearings: tuple[str, ...] = ("front", "rear")
    planes_mm: tuple[float, ...] = ()
    provenance: dict[str, Any] = field(default_factory=dict)

    def forward(self, channels: tuple[Channel, ...]) -> ForwardModel:
        planes = self.planes_mm or tuple(u.position_mm for u in self.geometry.unbalances)
        return ForwardModel(self.geometry, self.effects, channels, planes, self.theta_bearings)

    def rows(self, assembly: Assembly) -> tuple[np.ndarray, np.ndarray]:
        """θ and damping factors of ``assembly`` as one model row (a bearing the truth adds,
        beyond the assembly's, keeps its own damping)."""
        nb = len(self.geometry.bearings)
        d = np.ones(nb)
        d[:min(nb, assembly.damping.size)] = assembly.damping[:nb]
        return assembly.theta[None], d[None]


def measure(truth: Truth, assembly: Assembly, campaign: Campaign, noise: NoiseLevel,
            *, rng: np.random.Generator, channels: tuple[Channel, ...] | None = None
            ) -> MeasuredData:
    """Virtual measurements of ``truth`` built as ``assembly``: 1x records at every speed and
    repeat, impact FRFs at the tool tip (x and y), and identified bearing stiffness."""
    rng = require_rng(rng)
    channels = channels or default_channels(truth.geometry)
    fm = truth.forward(channels)
    th, ds = truth.rows(assembly)
    t1 = Sweep.unbalance(campaign.speeds_rpm)
    y = np.einsum("xcl,l->xc", fm.response(t1, th, ds)[0], assembly.unbalance)
    blocks = [ComplexBlock.from_repeats("unbalance_1x", t1, channels,
                                        _noisy(y, campaign.repeats, noise.additive_m, noise, rng),
                                        {"source": "synthetic"})]
    for d in ("x", "y"):
        tool = next(c for c in channels if c.position_mm == truth.geometry.tool_tip_mm
                    and c.direction == d)
        outs = tuple(c for c in channels if c.direction == d)
        ti = Sweep.impact(campaign.impact_freqs_hz, (tool,))
        idx = [channels.index(c) for c in outs]
        H = fm.response(ti, th, ds)[0][:, idx, 0]
        blocks.append(ComplexBlock.from_repeats(
            f"impact_tool_{d}", ti, outs,
            _noisy(H, campaign.impact_repeats, noise.frf_additive, noise, rng)))
    ident = None
    if campaign.identification:
        Z = fm.bearing_impedance(t1, th, ds)[0]
        names = [b.name for b in truth.geometry.bearings if b.name in truth.theta_bearings]
        j = [fm.bearing_names.index(n) for n in names]
        k = np.stack([Z[:, j, 0, 0].real, Z[:, j, 1, 1].real], axis=-1)
        R = campaign.repeats
        rec = k[None] * (1 + noise.k_relative * rng.normal(size=(R,) + k.shape))
        ident = RealBlock("identified_k", np.asarray(campaign.speeds_rpm), tuple(names),
                          rec.mean(axis=0), rec.std(axis=0, ddof=1) / np.sqrt(R), R - 1)
    return MeasuredData(tuple(blocks), ident, dict(truth.provenance))


def expected(truth: Truth, assembly: Assembly, campaign: Campaign, noise: NoiseLevel,
             channels: tuple[Channel, ...] | None = None) -> MeasuredData:
    """The noise-free means of :func:`measure` with the noise covariance of the means (known,
    not estimated: ``dof`` is set so large that the whitening is the exact precision). Used to
    measure how strong an effect is: the whitened distance the recalibration cannot close."""
    channels = channels or default_channels(truth.geometry)
    fm = truth.forward(channels)
    th, ds = truth.rows(assembly)
    t1 = Sweep.unbalance(campaign.speeds_rpm)
    y = np.einsum("xcl,l->xc", fm.response(t1, th, ds)[0], assembly.unbalance)
    blocks = [ComplexBlock("unbalance_1x", t1, channels, y,
                           _record_cov(y, noise.additive_m, noise) / campaign.repeats, BIG_DOF)]
    for d in ("x", "y"):
        tool = next(c for c in channels if c.position_mm == truth.geometry.tool_tip_mm
                    and c.direction == d)
        outs = tuple(c for c in channels if c.direction == d)
        ti = Sweep.impact(campaign.impact_freqs_hz, (tool,))
        H = fm.response(ti, th, ds)[0][:, [channels.index(c) for c in outs], 0]
        blocks.append(ComplexBlock(f"impact_tool_{d}", ti, outs, H,
                                   _record_cov(H, noise.frf_additive, noise)
                                   / campaign.impact_repeats, BIG_DOF))
    return MeasuredData(tuple(blocks), None, dict(truth.provenance))


#: degrees of freedom standing for a known covariance
BIG_DOF = 10**9


def _record_cov(y: np.ndarray, additive: float, noise: NoiseLevel) -> np.ndarray:
    """Covariance of ``[Re, Im]`` of one record of :func:`_noisy` (first order in the gain and
    phase errors): ``a² I + |y|² R_ψ diag(σ_g², σ_φ²) R_ψᵀ``, ``ψ = arg y``."""
    c, s = np.cos(np.angle(y)), np.sin(np.angle(y))
    R = np.stack([np.stack([c, -s], -1), np.stack([s, c], -1)], -2)
    D = np.diag([noise.gain**2, noise.phase_rad**2])
    return additive**2 * np.eye(2) + np.abs(y)[..., None, None] ** 2 * (R @ D @ np.swapaxes(
        R, -1, -2))


def _noisy(y: np.ndarray, R: int, additive: float, noise: NoiseLevel,
           rng: np.random.Generator) -> np.ndarray:
    """``R`` records of the exact responses ``y`` (X, C) with gain/phase and additive noise."""
    g = noise.gain * rng.normal(size=(R,) + y.shape)
    p = noise.phase_rad * rng.normal(size=(R,) + y.shape)
    e = additive * (rng.normal(size=(R,) + y.shape) + 1j * rng.normal(size=(R,) + y.shape))
    return y[None] * (1 + g) * np.exp(1j * p) + e
