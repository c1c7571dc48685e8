"""Observables of measured data: means over repeats, their noise covariance and its degrees of
freedom, and the whitening that turns residuals into standard-normal units.

A :class:`ComplexBlock` holds one test's complex responses (1x phasors vs speed, or FRF lines
of an impact test) at the measured channels. Every cell (point × channel) has a 2x2 real
covariance of the *mean* of ``[Re, Im]`` over the ``R`` repeats, estimated from the repeats
(``Σ̂ = S / R`` with ``S`` the sample covariance, ``ν = R − 1`` degrees of freedom). Phase
jitter makes the noise non-circular, so the full 2x2 is kept. The precision used to whiten is
the unbiased one, ``(ν − 3)/ν Σ̂⁻¹`` (``E[S⁻¹] = ν/(ν − p − 1) Σ⁻¹`` for a Wishart matrix with
``p = 2``; Anderson, *An Introduction to Multivariate Statistical Analysis*, 3rd ed., §7.2),
so a whitened squared residual has expectation 1 per real component; the tests' thresholds
come from simulating this very estimator (:mod:`surrogate_rbrdo.discrepancy.calibration`),
so the finite ``ν`` is accounted for, not only its mean.

A :class:`RealBlock` holds real observables with a standard error each (identified bearing
stiffness per speed, from an identification run).

>>> import numpy as np
>>> from surrogate_rbrdo.discrepancy.sweeps import Channel, Sweep
>>> rng = np.random.default_rng(0)
>>> rec = 1.0 + 0.1 * (rng.normal(size=(20, 3, 1)) + 1j * rng.normal(size=(20, 3, 1)))
>>> b = ComplexBlock.from_repeats("unbalance_1x", Sweep.unbalance([1e3, 2e3, 3e3]),
...                               (Channel("p", 0.0, "x"),), rec)
>>> b.mean.shape, b.cov.shape, b.dof
((3, 1), (3, 1, 2, 2), 19)
>>> w = b.whitening()                     # (X, C, 2, 2): r_w = w @ [Re r, Im r]
>>> bool(np.allclose(w[0, 0].T @ w[0, 0], (16 / 19) * np.linalg.inv(b.cov[0, 0])))
True
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from surrogate_rbrdo.core.validate import check_int
from surrogate_rbrdo.discrepancy.sweeps import Channel, Sweep
from surrogate_rbrdo.spindle.assembly import RPM


def _check_cov(name: str, cov: np.ndarray) -> None:
    ok = np.isfinite(cov).all(axis=(-1, -2))
    det = cov[..., 0, 0] * cov[..., 1, 1] - cov[..., 0, 1] * cov[..., 1, 0]
    ok &= (cov[..., 0, 0] > 0) & (det > 0)
    if not ok.all():
        i = tuple(np.argwhere(~ok)[0])
        raise ValueError(f"{name}: the noise covariance of cell {i} is {cov[i].tolist()}: it "
                         "must be finite and positive definite (repeats that differ; a "
                         "noise-free record cannot be whitened)")


@dataclass(frozen=True)
class ComplexBlock:
    """One test's complex responses at the measured channels (mean over repeats).

    Attributes
    ----------
    name : str
        Block name (``"unbalance_1x"``, ``"impact_tool_x"``, ...).
    sweep : Sweep
        Operating points and loads (:class:`~surrogate_rbrdo.discrepancy.forward.Sweep`).
    channels : tuple of Channel
    mean : ndarray (X, C) complex
        Mean over repeats (m per unit load: m for the 1x response, m/N for an FRF).
    cov : ndarray (X, C, 2, 2)
        Covariance of the mean's ``[Re, Im]`` per cell.
    dof : int
        Degrees of freedom of ``cov`` (``R − 1`` for ``R`` repeats); at least 4.
    runs : ndarray (R, X, C) complex, optional
        The repeats themselves when each is a *run* over all points (a speed sweep with its own
        thermal state): the null distributions then simulate the run-to-run structure.
    """

    name: str
    sweep: Sweep
    channels: tuple[Channel, ...]
    mean: np.ndarray
    cov: np.ndarray
    dof: int
    meta: dict[str, Any] = field(default_factory=dict)
    runs: np.ndarray | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "channels", tuple(self.channels))
        m = np.asarray(self.mean, dtype=complex)
        c = np.asarray(self.cov, dtype=float)
        X, C = self.sweep.freq_rad_s.size, len(self.channels)
        if m.shape != (X, C) or c.shape != (X, C, 2, 2):
            raise ValueError(f"block {self.name!r}: mean {m.shape} and cov {c.shape} must be "
                             f"({X}, {C}) and ({X}, {C}, 2, 2) (points x channels)")
        if not np.all(np.isfinite(m)):
            raise ValueError(f"block {self.name!r}: mean has non-finite values")
        _check_cov(f"block {self.name!r}", c)
        check_int(f"block {self.name!r}.dof", self.dof, minimum=4)
        object.__setattr__(self, "mean", m)
        object.__setattr__(self, "cov", c)
        if self.runs is not None:
            runs = np.asarray(self.runs, dtype=complex)
            if runs.shape[1:] != (X, C) or runs.shape[0] != self.dof + 1:
                raise ValueError(f"block {self.name!r}: runs {runs.shape} must be "
                                 f"({self.dof + 1}, {X}, {C})")
            object.__setattr__(self, "runs", runs)

    @classmethod
    def from_repeats(cls, name: str, sweep: Sweep, channels: tuple[Channel, ...],
                     records: np.ndarray, meta: dict[str, Any] | None = None, *,
                     runs: bool = True) -> ComplexBlock:
        """Mean and covariance of the mean from ``records`` (R, X, C) complex, R ≥ 5;
        ``runs``: each record is a run over all points (kept for the null distributions)."""
        rec = np.asarray(records, dtype=complex)
        if rec.ndim != 3 or rec.shape[0] < 5:
            raise ValueError(f"block {name!r}: records have shape {rec.shape}: need (R, X, C) "
                             "with R >= 5 repeats (the noise is estimated from them)")
        R = rec.shape[0]
        mean = rec.mean(axis=0)
        d = np.stack([rec.real - mean.real, rec.imag - mean.imag], axis=-1)  # (R, X, C, 2)
        S = np.einsum("rxci,rxcj->xcij", d, d) / (R - 1)
        return cls(name, sweep, channels, mean, S / R, R - 1, dict(meta or {}),
                   rec if runs else None)

    @property
    def coord(self) -> np.ndarray:
        """Speeds (rpm) of a 1x block, frequencies (Hz) of an impact block."""
        if self.sweep.kind == "unbalance_1x":
            return self.sweep.spin_rad_s / RPM
        return self.sweep.freq_rad_s / (2 * np.pi)

    @property
    def coord_label(self) -> str:
        return "speed (rpm)" if self.sweep.kind == "unbalance_1x" else "frequency (Hz)"

    def whitening(self) -> np.ndarray:
        """Per cell ``W`` with ``W.T @ W = (ν − 3)/ν Σ̂⁻¹`` (unbiased precision), (X, C, 2, 2)."""
        P = np.linalg.inv(self.cov) * (self.dof - 3) / self.dof
        return np.swapaxes(np.linalg.cholesky(P), -1, -2)

    def subset(self, mask: np.ndarray) -> ComplexBlock:
        """The block restricted to the points ``mask`` (X,) bool."""
        mask = np.asarray(mask, dtype=bool)
        t = self.sweep
        sweep = Sweep(t.kind, t.spin_rad_s[mask], t.freq_rad_s[mask], t.excitations)
        return ComplexBlock(self.name, sweep, self.channels, self.mean[mask], self.cov[mask],
                            self.dof, self.meta,
                            None if self.runs is None else self.runs[:, mask])


@dataclass(frozen=True)
class RealBlock:
    """Identified bearing stiffness per speed: ``values`` (X, nb, 2) for the ``xx``/``yy``
    directions, standard errors ``sd`` of the same shape, at ``speeds_rpm`` (X,)."""

    name: str
    speeds_rpm: np.ndarray
    bearings: tuple[str, ...]
    values: np.ndarray
    sd: np.ndarray
    dof: int = 19

    def __post_init__(self) -> None:
        v = np.asarray(self.values, dtype=float)
        s = np.asarray(self.sd, dtype=float)
        sp = np.asarray(self.speeds_rpm, dtype=float)
        shape = (sp.size, len(self.bearings), 2)
        if v.shape != shape or s.shape != shape:
            raise ValueError(f"block {self.name!r}: values {v.shape} and sd {s.shape} must be "
                             f"{shape} (speeds x bearings x [xx, yy])")
        if not (np.all(np.isfinite(v)) and np.all(np.isfinite(s)) and np.all(s > 0)):
            raise ValueError(f"block {self.name!r}: values must be finite and sd > 0")
        check_int(f"block {self.name!r}.dof", self.dof, minimum=3)
        object.__setattr__(self, "speeds_rpm", sp)
        object.__setattr__(self, "values", v)
        object.__setattr__(self, "sd", s)

    @property
    def sweep(self) -> Sweep:
        return Sweep.unbalance(self.speeds_rpm)


#: the provenance key of impact blocks a reader left out (:class:`MeasuredData`)
THIN_IMPACTS = "impact_blocks_left_out"


@dataclass(frozen=True)
class MeasuredData:
    """Everything the workflow compares with the model.

    Attributes
    ----------
    blocks : tuple of ComplexBlock
        At least one; each ``unbalance_1x`` block has its own unknown unbalance.
    identified : RealBlock or None
        Identified bearing stiffness vs speed (from an identification run), optional.
    provenance : dict
        Where the data came from (truth effects and seeds for rig data); under
        :data:`THIN_IMPACTS` the reader's ``(name, dof)`` of impact blocks it could not form
        (too few hits: :func:`~.measured.impact_data`), which the workflow's findings list.
    soaks : tuple of SoakBlock
        Thermal soaks (:class:`~.soak.SoakBlock`): not fitted, the separating test of an
        effect that drifts with temperature (:mod:`.soak`).
    """

    blocks: tuple[ComplexBlock, ...]
    identified: RealBlock | None = None
    provenance: dict[str, Any] = field(default_factory=dict)
    soaks: tuple = ()

    def __post_init__(self) -> None:
        object.__setattr__(self, "blocks", tuple(self.blocks))
        object.__setattr__(self, "soaks", tuple(self.soaks))
        if not self.blocks:
            raise ValueError("data.blocks = () is not allowed: give at least one test")
        names = [b.name for b in self.blocks]
        if len(set(names)) != len(names):
            raise ValueError(f"data.blocks names {names} must be unique")

    def block(self, name: str) -> ComplexBlock:
        for b in self.blocks:
            if b.name == name:
                return b
        raise ValueError(f"no block {name!r}; blocks: {[b.name for b in self.blocks]}")

    @property
    def channels(self) -> tuple[Channel, ...]:
        seen: dict[tuple[float, str], Channel] = {}
        for b in self.blocks:
            for c in b.channels:
                seen.setdefault((c.position_mm, c.direction), c)
        return tuple(seen.values())
