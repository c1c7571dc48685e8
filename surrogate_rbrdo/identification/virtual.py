"""A phasor-level stand-in for a rig campaign, with a known truth (tests and benchmarks).

Each run (a repeat of the speed sweep, as on the rig) draws the bearing stiffness factors θ
from an MVN (physical scatter around the model's speed law) — or each record its own
(``theta_per="record"``) — computes the FE model's 1× response at the probe nodes
(:func:`~surrogate_rbrdo.spindle.harmonic.unbalance_response`) and adds circular complex
noise whose real and imaginary parts have a given standard deviation (what synchronous
demodulation of white probe noise leaves on a phasor). It is *not* the virtual rig (issue 14:
sensors, records, demodulation, hidden effects); it exercises the identification →
uncertainty chain where the answer is known. The truth is what the diagonal identification
measures: the effective impedance each bearing (with its housing, if any) puts on its journal
(:func:`~surrogate_rbrdo.identification.phasor.effective_coefficients`).

>>> import numpy as np
>>> from surrogate_rbrdo.spindle import reference_spindle
>>> sp = reference_spindle()
>>> c = phasor_campaign(sp.model(sp.baseline), [5000.0, 20000.0], 3, theta_std=[0.015, 0.03],
...                     noise_m=0.0, rng=np.random.default_rng(0))
>>> c.phasors.shape, c.truth.shape, c.speeds_rpm.tolist()
((6, 4), (6, 8), [5000.0, 5000.0, 5000.0, 20000.0, 20000.0, 20000.0])
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from surrogate_rbrdo.core.rng import require_rng
from surrogate_rbrdo.core.validate import check_choice, check_int, check_positive
from surrogate_rbrdo.identification.phasor import effective_coefficients
from surrogate_rbrdo.spindle.assembly import SpindleModel
from surrogate_rbrdo.spindle.harmonic import unbalance_response


@dataclass(frozen=True, eq=False)
class PhasorCampaign:
    """Records of a campaign: speed, repeat, measured phasors, their noise, the truth."""

    speeds_rpm: np.ndarray
    repeats: np.ndarray
    phasors: np.ndarray
    noise_m: float
    theta: np.ndarray
    truth: np.ndarray
    probe_nodes: tuple[int, ...]


def phasor_campaign(model: SpindleModel, speeds_rpm: Sequence[float], repeats: int, *,
                    theta_std: Sequence[float], noise_m: float, rng: np.random.Generator,
                    theta_corr=None, probe_nodes: Sequence[int] | None = None,
                    theta_per: str = "run") -> PhasorCampaign:
    """``len(speeds_rpm) × repeats`` records (speed-major) with physical scatter and noise.

    Parameters
    ----------
    model : SpindleModel
        The truth (its speed law is the truth's trend).
    speeds_rpm : sequence of float
    repeats : int
    theta_std : sequence of float
        Standard deviation of the stiffness factors of ``model.theta_bearings`` (relative).
    noise_m : float
        Standard deviation of the real (and of the imaginary) part of each phasor's noise (m).
    rng : numpy.random.Generator
    theta_corr : array (m, m), optional
        Correlation of the factors (default independent).
    probe_nodes : sequence of int, optional
        Measured nodes (default the bearing nodes).
    theta_per : {"run", "record"}
        One θ per repeat shared by all its speeds (a thermal state per run, as on the rig), or
        one per record.
    """
    require_rng(rng)
    repeats = check_int("repeats", repeats, minimum=1)
    check_positive("noise_m", noise_m, allow_zero=True)
    check_choice("theta_per", theta_per, ("run", "record"))
    sp = np.repeat(np.asarray(speeds_rpm, dtype=float), repeats)
    std = np.asarray(theta_std, dtype=float)
    m = len(model.theta_bearings)
    if std.shape != (m,) or np.any(std < 0):
        raise ValueError(f"theta_std = {theta_std!r} is not allowed: need {m} values >= 0")
    corr = np.eye(m) if theta_corr is None else np.asarray(theta_corr, dtype=float)
    L = np.linalg.cholesky(corr)
    rep = np.tile(np.arange(repeats), len(speeds_rpm))
    draws = 1.0 + (rng.standard_normal((repeats if theta_per == "run" else sp.size, m))
                   @ L.T) * std
    theta = draws[rep] if theta_per == "run" else draws
    nodes = list(model.bearing_nodes if probe_nodes is None else probe_nodes)
    q = unbalance_response(model, sp[:, None], theta)[:, 0]          # (N, nn, 4)
    ph = q[:, nodes, :2].reshape(sp.size, -1)
    if noise_m > 0:
        ph = ph + noise_m * (rng.standard_normal(ph.shape)
                             + 1j * rng.standard_normal(ph.shape))
    u, inv = np.unique(sp, return_inverse=True)
    eff = effective_coefficients(model, u, draws)                    # (runs | N, S, 8)
    truth = eff[rep if theta_per == "run" else np.arange(sp.size), inv]
    return PhasorCampaign(sp, rep, ph, float(noise_m), theta, truth,
                          tuple(int(n) for n in nodes))


__all__ = ["PhasorCampaign", "phasor_campaign"]
