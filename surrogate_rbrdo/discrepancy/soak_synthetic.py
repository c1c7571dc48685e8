"""Synthetic two-speed thermal soaks with the probes' gains drifting: the size check of the
soak's β test near the gain direction (:mod:`.soak`; review s13 H1), shared by
``tests/discrepancy/test_soak.py`` and ``benchmarks/soak_beta_size.py``.

Each speed's predicted drift is ``Δ_s = κ_s a_s (1 + 0.1i)``: close to the cold response
``a_s``, as a preload growth's is beside the resonance (``κ`` of opposite signs on opposite
flanks, alike on one). Each probe's gain drifts by ``α_c ΔT`` over the warm-up, the runs' cold
responses are 2 % apart and the records carry circular complex noise.

>>> blocks, drifts = gain_drift_soaks(np.random.default_rng(0), (0.02, -0.02))
>>> [b.speed_rpm for b in blocks], blocks[0].phasors.shape
([20000.0, 22000.0], (2, 8, 3))
"""

from __future__ import annotations

import numpy as np

from surrogate_rbrdo.discrepancy.soak import SoakBlock
from surrogate_rbrdo.discrepancy.sweeps import Channel

#: record times of a soak run (s after reaching speed)
TIMES = np.array([0.0, 300.0, 600.0, 900.0, 1200.0, 1800.0, 2700.0, 3600.0])
#: three probe channels
CHANNELS = tuple(Channel(f"p{i}", 10.0 * i, "xy"[i % 2]) for i in range(3))
#: each probe's gain drift per kelvin
ALPHA = np.array([3e-4, -2e-4, 1e-4])
#: the cold responses at the two speeds (m)
COLD = (1e-6 * np.exp(1j * np.array([0.3, 1.9, -2.2])) * np.array([1.0, 0.7, 1.3]),
        1e-6 * np.exp(1j * np.array([-1.0, 0.4, 2.8])) * np.array([1.2, 0.9, 0.8]))


def gain_drift_soaks(rng: np.random.Generator, kappas, *, beta: float = 1.0,
                     noise: float = 3e-9, runs: int = 2, rises=(10.0, 14.0)
                     ) -> tuple[tuple[SoakBlock, ...], tuple[np.ndarray, ...]]:
    """One data set (module doc): per speed ``runs`` runs with a warm-up of ``rises`` K
    (τ 900 s), the drift ``β Δ_s`` and the gain drift; the soak blocks and the ``Δ_s``."""
    out, drifts = [], []
    for s, (k, rise, a0) in enumerate(zip(kappas, rises, COLD, strict=True)):
        d = k * a0 * (1 + 0.1j)
        t = np.tile(TIMES, (runs, 1))
        th = -np.expm1(-t / 900.0)
        T = 293.0 + rng.normal(0, 0.5, (runs, 1)) + rise * th
        a = a0 * (1 + 0.02 * rng.normal(size=(runs, 1, 3)))
        y = a * (1 + ALPHA * rise * th[..., None]) + beta * th[..., None] * d
        y = y + noise * (rng.normal(size=y.shape) + 1j * rng.normal(size=y.shape))
        out.append(SoakBlock(f"soak{s}", 20000.0 + 2000.0 * s, CHANNELS, t, T, y))
        drifts.append(d)
    return tuple(out), tuple(drifts)
