"""Replicated builds of several designs on the rig's truth, paired replication by replication.

The rig's truth (:class:`~surrogate_rbrdo.rig.truth.Truth`) is one spindle; a
:class:`TruthFamily` is the truth for *any* design ``x``: the same hidden effects and
variability model on the geometry that the spindle's design map makes of ``x`` — the
spindle a workshop would build from the drawing, not the model the optimiser used.

**A replication** is a fresh assembly and run, drawn as the rig's variability model says
(``docs/rig.md``): new bearing draws, a new balancing (residual unbalance magnitudes and
phases), a new tool clamping and a new thermal state. ``replicate`` names the levels that are
drawn anew per replication (default all three: build, tool change, run).

**What makes a pair.** Replication ``i`` of the baseline and replication ``i`` of another
design are built and run side by side; ``shared`` names the draws they have in common:

========================  ======  ============================================  ==========
group                     level   draws                                         default
========================  ======  ============================================  ==========
``bearings``              build   bearing stiffness and damping factors         shared
``unbalance_magnitude``   build   residual unbalance per plane (fraction)       own
``unbalance_phase``       build   unbalance phase per plane                     own
``tool``                  tool    tool/holder mass factor                       shared
``interface``             tool    tool-interface stiffness factors              own
``thermal``               run     thermal preload state                         shared
========================  ======  ============================================  ==========

Default, physically: both spindles of a pair get bearing sets from the same matched lot
(the lot's deviation from the catalogue is the bearings', not the shaft's), the same tool and
holder, and are run on the same day from the same warm-up (same thermal state: the paper pairs
"to eliminate any potential experimental ambient bias"). Each rotor is balanced on its own,
so its residual unbalance (magnitude and phase) is its own, and each clamping of the holder
makes its own interface contact. A shared draw is the same random number fed through each
design's truth (a shared unbalance *fraction* of each rotor's own ISO permissible value).

>>> import numpy as np
>>> fam = reference_family()
>>> xs = {"a": [2000.0, 500.0, 65.0], "b": [3000.0, 400.0, 70.0]}
>>> st = replica_states(fam, xs, 2, seed=np.random.SeedSequence(3))
>>> [len(v) for v in st.values()]
[2, 2]
>>> a, b = st["a"][0].draws["build"], st["b"][0].draws["build"]
>>> a["k_factor"] == b["k_factor"], a["unbalance_phase_deg"] == b["unbalance_phase_deg"]
(True, False)
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from surrogate_rbrdo.core.validate import check_choice, check_int
from surrogate_rbrdo.rig.truth import Truth, TruthState, Variability, reference_truth
from surrogate_rbrdo.spindle.effects import Effect
from surrogate_rbrdo.spindle.reference import reference_spindle

LEVELS = ("build", "tool", "run")

#: share group -> (level, keys of that level's draw dict)
SHARE_GROUPS: dict[str, tuple[str, tuple[str, ...]]] = {
    "bearings": ("build", ("k_factor", "damping_factor")),
    "unbalance_magnitude": ("build", ("unbalance_kgm",)),
    "unbalance_phase": ("build", ("unbalance_phase_deg",)),
    "tool": ("tool", ("mass_factor",)),
    "interface": ("tool", ("interface_factor",)),
    "thermal": ("run", ("preload_factor",)),
}

DEFAULT_SHARED = ("bearings", "tool", "thermal")


@dataclass(frozen=True)
class TruthFamily:
    """The rig's truth for any design: a truth (its hidden effects and variability) and the
    design map that turns ``x`` into its geometry (``design_map.check`` / ``.apply``)."""

    template: Truth
    design_map: Any

    def at(self, x: Sequence[float]) -> Truth:
        """The truth of design ``x`` (checked against the design map's bounds)."""
        x = self.design_map.check(np.asarray(x, dtype=float))
        return replace(self.template, geometry=self.design_map.apply(self.template.geometry, x))


def reference_family(hidden: Sequence[Effect | dict[str, Any]] = (),
                     variability: Variability | None = None) -> TruthFamily:
    """The reference spindle's truth family (``rig.truth.reference_truth`` for every x)."""
    v = Variability() if variability is None else variability
    return TruthFamily(reference_truth(hidden, v), reference_spindle().design_map)


def check_groups(name: str, groups: Sequence[str], allowed: Sequence[str]) -> tuple[str, ...]:
    """Validate a tuple of names against ``allowed`` (no repeats)."""
    groups = tuple(groups)
    for g in groups:
        check_choice(f"{name}[]", g, allowed)
    if len(set(groups)) != len(groups):
        raise ValueError(f"{name} = {list(groups)} is not allowed: a name appears twice")
    return groups


def child_seed(ss: np.random.SeedSequence, *key: int) -> np.random.SeedSequence:
    """A child seed sequence addressed by ``key`` (random access: any replica alone)."""
    return np.random.SeedSequence(ss.entropy, spawn_key=tuple(ss.spawn_key) + tuple(key))


def _level_keys(r: int, replicate: tuple[str, ...]) -> dict[str, tuple[int, ...]]:
    """Nested keys (build,), (build, tool), (build, tool, run) of replication ``r``."""
    b, t, u = (r if lvl in replicate else 0 for lvl in LEVELS)
    return {"build": (b,), "tool": (b, t), "run": (b, t, u)}


def _draw(truth: Truth, level: str, ss: np.random.SeedSequence) -> dict[str, Any]:
    return {"build": truth.draw_build, "tool": truth.draw_tool, "run": truth.draw_run}[level](ss)


def replica_draws(truth: Truth, design_index: int, r: int, *, seed: np.random.SeedSequence,
                  shared: tuple[str, ...], replicate: tuple[str, ...]
                  ) -> dict[str, dict[str, Any]]:
    """The build/tool/run draws of replication ``r`` of design ``design_index``: shared groups
    from the replication's common stream, the rest from the design's own stream."""
    keys = _level_keys(r, replicate)
    shared_keys = {k for g in shared for k in SHARE_GROUPS[g][1]}
    out = {}
    for j, level in enumerate(LEVELS):
        common = _draw(truth, level, child_seed(seed, 0, j, *keys[level]))
        own = _draw(truth, level, child_seed(seed, 1, design_index, j, *keys[level]))
        out[level] = {k: (common[k] if k in shared_keys else own[k]) for k in own}
    return out


def replica_states(family: TruthFamily, designs: Mapping[str, Sequence[float]], n: int, *,
                   seed: np.random.SeedSequence, shared: Sequence[str] = DEFAULT_SHARED,
                   replicate: Sequence[str] = LEVELS) -> dict[str, list[TruthState]]:
    """``n`` paired replications (truth states) of every design, by design name.

    Draws are addressed by ``(stream, design index, level, replication keys)`` under
    ``seed``, so the same seed gives the same spindles whatever else is measured.
    """
    n = check_int("n_replications", n, minimum=1)
    shared = check_groups("shared", shared, tuple(SHARE_GROUPS))
    replicate = check_groups("replicate", replicate, LEVELS)
    out = {}
    for i, (name, x) in enumerate(designs.items()):
        truth = family.at(x)
        states = []
        for r in range(n):
            d = replica_draws(truth, i, r, seed=seed, shared=shared, replicate=replicate)
            states.append(truth.apply(d["build"], d["tool"], d["run"]))
        out[name] = states
    return out
