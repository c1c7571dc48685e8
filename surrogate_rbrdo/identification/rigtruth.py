"""What the virtual rig knows and an experimenter does not: the truth behind each record.

Every rig record carries the draws of its build, tool change and run (``provenance``:
``truth_draws``), so the truth state it was measured on can be rebuilt
(:meth:`~surrogate_rbrdo.rig.truth.Truth.apply`). :func:`truth_coefficients` gives the eight
coefficients the diagonal identification measures on that state (the effective impedance
``Re Z``, ``Im Z / Ω`` each bearing, with its housing stage if any, puts on the journal:
:func:`~surrogate_rbrdo.identification.phasor.effective_coefficients`).

:func:`population_truth` is the target of the uncertainty model: over the thermal states of runs
(the campaign's random level, drawn ``n_runs`` times from the truth's own variability model) with
the build and tool of the records fixed, the mean of each coefficient at each speed (the truth's
*trend*) and the covariance of the factors ``k / mean`` (the truth's *physical scatter*).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from surrogate_rbrdo.core.validate import check_int
from surrogate_rbrdo.identification.phasor import effective_coefficients
from surrogate_rbrdo.rig.truth import Truth, TruthState


def record_state(truth: Truth, provenance: Mapping) -> TruthState:
    """The truth state a rig record was measured on (its ``provenance["truth_draws"]``)."""
    d = provenance.get("truth_draws")
    if not isinstance(d, Mapping) or not {"build", "tool", "run"} <= set(d):
        raise ValueError("provenance has no truth_draws {build, tool, run}: not a rig record")
    return truth.apply(d["build"], d["tool"], d["run"])


def truth_coefficients(truth: Truth, provenances: Sequence[Mapping], speeds_rpm) -> np.ndarray:
    """The true effective coefficients ``(N, 8)`` of each record at its speed (records of one
    run share a state: one FE model per run)."""
    sp = np.asarray(speeds_rpm, dtype=float).ravel()
    if len(provenances) != sp.size:
        raise ValueError(f"provenances has {len(provenances)} entries for {sp.size} speeds")
    out = np.empty((sp.size, 8))
    keys = [tuple(p.get(k) for k in ("build", "tool", "run")) for p in provenances]
    for key in dict.fromkeys(keys):
        rows = [i for i, k in enumerate(keys) if k == key]
        st = record_state(truth, provenances[rows[0]])
        c = effective_coefficients(st.model(), sp[rows], st.theta)[0]      # (n, 8)
        out[rows] = c
    return out


@dataclass(frozen=True, eq=False)
class PopulationTruth:
    """Mean coefficients (the truth's trend) and factor covariance (its physical scatter) over
    runs, at ``speeds_rpm``: ``mean (S, 8)``, ``factor_cov (S, 8, 8)``."""

    speeds_rpm: np.ndarray
    mean: np.ndarray
    factor_cov: np.ndarray
    n_runs: int

    def study_cov(self, weights: np.ndarray, columns: Sequence[int]) -> np.ndarray:
        """Covariance ``(S, m, m)`` of the study's θ = ``W e`` over the given columns."""
        C = self.factor_cov[:, columns][:, :, columns]
        return np.einsum("ij,sjk,lk->sil", weights, C, weights)


def population_truth(truth: Truth, provenance: Mapping, speeds_rpm, *, n_runs: int = 2000,
                     seed: int = 0) -> PopulationTruth:
    """Trend and physical scatter of the truth over ``n_runs`` thermal states, build and tool
    fixed at those of a record (``provenance``)."""
    n_runs = check_int("n_runs", n_runs, minimum=10)
    d = provenance.get("truth_draws")
    if not isinstance(d, Mapping):
        raise ValueError("provenance has no truth_draws: not a rig record")
    sp = np.asarray(speeds_rpm, dtype=float).ravel()
    base = np.random.SeedSequence(seed)
    thetas = np.concatenate([truth.apply(d["build"], d["tool"], truth.draw_run(c)).theta
                             for c in base.spawn(n_runs)])
    model = truth.apply(d["build"], d["tool"], d["run"]).model()
    c = effective_coefficients(model, sp, thetas)                         # (R, S, 8)
    mean = c.mean(axis=0)
    e = c / mean
    cov = np.einsum("rsi,rsj->sij", e - 1.0, e - 1.0) / (n_runs - 1)
    return PopulationTruth(sp, mean, cov, n_runs)


__all__ = ["PopulationTruth", "population_truth", "record_state", "truth_coefficients"]
