"""1× responses to a *known* excitation, from corrected measured phasors.

* :func:`trial_pairs` — trial-weight runs: a record labelled ``trial = 1`` and its partner with
  the same labels and speed but no trial mass give the response to the trial mass alone,
  ``Δq = q_trial − q``; the unknown residual unbalance drops out (the rotor–bearing system is
  linear) and the trial mass (``provenance["test_setup"]["trial_unbalance"]``, or given) is the
  known excitation. This is the influence-coefficient practice of field balancing
  (ISO 21940-13; Foiles et al. 1998, *Shock Vib. Dig.* 30:211). Its noise is the two records'
  together.
* :func:`known_unbalance` — the records as they are, with an unbalance the caller states (a
  rotor balanced to a measured residual, or a simulation).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from surrogate_rbrdo.identification.measured import MeasuredPhasors
from surrogate_rbrdo.rig.records import RecordError


@dataclass(frozen=True, eq=False)
class Responses:
    """1× responses to a *known* unbalance, ready for identification (one row per vector).

    ``excitation`` is ``"trial"`` (trial-mass differences, :func:`trial_pairs`) or ``"known"``
    (records taken as they are, with an unbalance the caller states); ``unbalance`` lists the
    known planes ``(position_mm, magnitude_kgm, phase_deg)``; ``repeat`` the ``repeat`` label of
    each row (else its index); ``groups`` the cluster label of
    each row (records of one run share it: their physical state is the same);
    ``perturbations (N, r, p)`` the change of the phasors for one standard deviation of each of
    ``r`` independent real errors besides the channels' noise (each record's keyphasor phase:
    ``−i q σ_Δ``), or ``None``.
    """

    record_ids: tuple[str, ...]
    speed_rpm: np.ndarray
    repeat: np.ndarray
    groups: np.ndarray
    channels: tuple[str, ...]
    positions_mm: np.ndarray
    phasors: np.ndarray
    phasor_sd: np.ndarray
    unbalance: tuple[tuple[float, float, float], ...]
    excitation: str
    perturbations: np.ndarray | None = None

    @property
    def n(self) -> int:
        return len(self.record_ids)


def _group(labels: Mapping, key: str | None) -> str:
    """The run a record belongs to: its label ``key``, else all its labels but the speed index
    and the trial flag (on the rig: build, tool, run)."""
    if key is not None:
        if key not in labels:
            raise ValueError(f"group_label = {key!r}: a record has no such label "
                             f"({sorted(labels)})")
        return str(labels[key])
    return "|".join(f"{k}={labels[k]}" for k in sorted(labels)
                    if k not in ("speed_index", "trial"))


def _repeats(labels, rows) -> np.ndarray:
    return np.array([labels[i].get("repeat", i) for i in rows])


def _phase_terms(m: MeasuredPhasors, rows: np.ndarray) -> np.ndarray:
    """``−i q σ_Δ``: the phasors' change for one standard deviation of the record's keyphasor
    phase ``(len(rows), p)``."""
    return -1j * m.phasors[rows] * m.phase_sd[rows, None]


def _trial_of(setup: Mapping, rid: str) -> tuple[float, float, float]:
    t = setup.get("trial_unbalance")
    if not isinstance(t, Mapping) or not {"position_mm", "magnitude_kgm", "phase_deg"} <= set(t):
        raise RecordError(f"record {rid!r}", "provenance.test_setup.trial_unbalance",
                          "missing or incomplete: need position_mm, magnitude_kgm, phase_deg "
                          "(or give trial_unbalance=)")
    return float(t["position_mm"]), float(t["magnitude_kgm"]), float(t["phase_deg"])


def trial_pairs(m: MeasuredPhasors, *, trial_unbalance: tuple[float, float, float] | None = None,
                group_label: str | None = None) -> Responses:
    """Pair every trial record (label ``trial = 1``) with the record of the same labels and
    speed without it: ``Δq = q_trial − q``, noise ``√(s_trial² + s²)``.

    ``trial_unbalance`` (``(position_mm, magnitude_kgm, phase_deg)``) overrides the records'
    ``test_setup``; ``group_label`` names the label that says which run a record belongs to
    (default: all labels but the speed index and the trial flag).
    Raises ``ValueError`` if a trial record has no partner or the trial masses differ.
    """
    key = [tuple(sorted((k, v) for k, v in lab.items() if k != "trial")) + (sp,)
           for lab, sp in zip(m.labels, m.speed_rpm.tolist(), strict=True)]
    is_trial = np.array([bool(lab.get("trial", 0)) for lab in m.labels])
    if not is_trial.any():
        raise ValueError(f"{m.source}: no record is labelled trial = 1: trial-weight "
                         "identification needs runs with a trial mass")
    base = {k: i for i, k in enumerate(key) if not is_trial[i]}
    pairs = []
    for i in np.flatnonzero(is_trial):
        if key[i] not in base:
            raise ValueError(f"{m.source}: trial record {m.record_ids[i]!r} has no partner "
                             f"without the trial mass (same labels and speed)")
        pairs.append((base[key[i]], i))
    b, t = np.array(pairs).T
    trials = {_trial_of(m.test_setup[i], m.record_ids[i]) for i in t} if trial_unbalance is None \
        else {tuple(float(v) for v in trial_unbalance)}
    if len(trials) != 1:
        raise ValueError(f"{m.source}: the records use {len(trials)} different trial masses "
                         f"{sorted(trials)[:3]}: identify them separately")
    return Responses(
        tuple(f"{m.record_ids[j]}|{m.record_ids[i]}" for j, i in zip(b, t, strict=True)),
        m.speed_rpm[t], _repeats(m.labels, t),
        np.array([_group(m.labels[i], group_label) for i in t]), m.channels,
        m.positions_mm, m.phasors[t] - m.phasors[b], np.hypot(m.phasor_sd[t], m.phasor_sd[b]),
        (trials.pop(),), "trial",
        np.stack([_phase_terms(m, t), -_phase_terms(m, b)], axis=1))


def known_unbalance(m: MeasuredPhasors, unbalance: Sequence[tuple[float, float, float]], *,
                    group_label: str | None = None) -> Responses:
    """The records as they are, excited by a stated unbalance ``[(position_mm, magnitude_kgm,
    phase_deg), ...]`` (records with a trial mass are left out)."""
    keep = np.array([not lab.get("trial", 0) for lab in m.labels])
    planes = tuple(tuple(float(v) for v in u) for u in unbalance)
    if not planes or any(len(u) != 3 or u[1] < 0 for u in planes):
        raise ValueError(f"unbalance = {unbalance!r} is not allowed: need one or more "
                         "(position_mm, magnitude_kgm >= 0, phase_deg)")
    s = m.select(keep)
    return Responses(s.record_ids, s.speed_rpm, _repeats(s.labels, range(s.n_records)),
                     np.array([_group(lab, group_label) for lab in s.labels]), s.channels,
                     s.positions_mm, s.phasors, s.phasor_sd, planes, "known",
                     _phase_terms(s, np.arange(s.n_records))[:, None, :])


__all__ = ["Responses", "known_unbalance", "trial_pairs"]
