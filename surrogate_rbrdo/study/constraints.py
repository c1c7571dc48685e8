"""Deterministic design constraints of a spindle study, as :class:`DesignConstraint` columns.

* :func:`spindle_constraints`: the checks a spindle designer imposes
  (:class:`~surrogate_rbrdo.spindle.practice.PracticeConstraints`: bearing speed capability,
  ISO 281 life, ISO 76 static safety, motor length against the span, run-up time) and the
  API 617 / API RP 684 separation guard (:class:`~surrogate_rbrdo.spindle.separation.
  ResonanceGuard`, exact forward critical speeds of each design). Each block is evaluated once
  per distinct design and kept (:func:`~surrogate_rbrdo.formulations.constraints.
  block_constraints`), so the guard's eigenproblems (~3–15 ms per design) are never repeated.
* :func:`expression_constraints`: ``name``/``expression``/``scale`` entries (the TOML
  ``[[constraints]]`` tables) over the spindle's design variables.

>>> import numpy as np
>>> from surrogate_rbrdo.spindle.practice import PracticeSpec
>>> from surrogate_rbrdo.spindle.reference import credible_spindle
>>> cons = spindle_constraints(credible_spindle(), practice=PracticeSpec(),
...                            resonance="separation")
>>> [c.name for c in cons][-3:]
['span', 'run_up', 'resonance_separation']
>>> g = np.column_stack([c(np.array([[237.5, 390.0, 74.0]])) for c in cons])
>>> bool(np.all(g <= 0))                        # phase 1's optimum meets every check
True
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Any

import numpy as np

from surrogate_rbrdo.core.validate import check_choice, check_positive
from surrogate_rbrdo.formulations.constraints import DesignConstraint, block_constraints
from surrogate_rbrdo.spindle.practice import PracticeConstraints, PracticeSpec
from surrogate_rbrdo.spindle.reference import ReferenceSpindle
from surrogate_rbrdo.spindle.separation import ResonanceGuard

#: resonance guards computed exactly per design (the paper's guard goes through the g_det
#: design model, ``DeterministicOptions(resonance="paper")``)
EXACT_GUARDS = ("separation", "none")


def spindle_constraints(spindle: ReferenceSpindle, *, practice: PracticeSpec | None = None,
                        resonance: str = "none", search_factor: float = 1.5
                        ) -> tuple[DesignConstraint, ...]:
    """The practice checks (if ``practice`` is given) and the exact API separation guard
    (``resonance = "separation"``: every critical speed up to ``search_factor · n_max`` with
    AF ≥ 2.5 outside the operating range by the API margins). The practice data are checked
    against the spindle (bearing names) on its baseline design."""
    check_choice("resonance", resonance, EXACT_GUARDS)
    check_positive("search_factor", search_factor)
    out: tuple[DesignConstraint, ...] = ()
    if practice is not None:
        con = PracticeConstraints(spindle, practice)
        try:
            con(np.asarray(spindle.baseline, dtype=float)[None, :])
        except (KeyError, ValueError) as exc:
            raise ValueError(f"practice: {exc}") from None
        out += block_constraints(con.names, con)
    if resonance == "separation":
        guard = ResonanceGuard(spindle, "separation", search_factor=search_factor)
        out += block_constraints(guard.names, guard)
    return out


def expression_constraints(entries: Iterable[Mapping[str, Any]], variables: tuple[str, ...]
                           ) -> tuple[DesignConstraint, ...]:
    """:meth:`DesignConstraint.from_expression` of each ``{name, expression, scale}``."""
    return tuple(DesignConstraint.from_expression(e["name"], e["expression"], variables,
                                                  e.get("scale", 1.0)) for e in entries)


__all__ = ["EXACT_GUARDS", "expression_constraints", "spindle_constraints"]
