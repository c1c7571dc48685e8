"""The memory a study's sizes need, checked before any work (``core.memory``).

Each options dataclass states the bytes of the arrays its size fields make
(``memory_bytes``); :func:`check_study_memory` adds what only the problem knows (the designs
the verification checks, the model's degrees of freedom, θ's dimension) and refuses, naming
the field (or product of fields) that needs most, any size whose arrays would not fit in the
memory available now.

>>> from surrogate_rbrdo.study import OptimizationOptions, VerificationOptions, \\
...     reference_problem
>>> from surrogate_rbrdo.surrogates.structured import GlobalOptions
>>> p = reference_problem()
>>> check_study_memory(p, GlobalOptions(), OptimizationOptions(), VerificationOptions())
>>> check_study_memory(p, GlobalOptions(), OptimizationOptions(pop_size=10 ** 8,
...                    n_gen=10 ** 8), VerificationOptions())   # doctest: +ELLIPSIS
Traceback (most recent call last):
...
ValueError: optimization.pop_size × n_gen = 100000000 × 100000000 is not allowed: ...
"""

from __future__ import annotations

from typing import Any

from surrogate_rbrdo.core.memory import check_memory, memory_needs
from surrogate_rbrdo.study.options import OptimizationOptions, VerificationOptions
from surrogate_rbrdo.study.problem import Problem


def check_study_memory(problem: Problem, surrogate: Any, optimization: OptimizationOptions,
                       verification: VerificationOptions, *others: tuple[str, Any]) -> None:
    """Refuse sizes of the surrogate's options, ``optimization`` and ``verification`` (and
    of ``others``: ``(table name, options)`` pairs, e.g. ``("refine", RefineOptions(...))``)
    whose arrays would not fit; messages name ``<table>.<field>``, its value and the need."""
    runs = optimization.runs
    n_dof = problem.spindle.model(problem.baseline).n_dof
    fronts = sum(1 for name, _ in runs if name in ("rbrdo", "rdo"))
    check_memory(memory_needs(surrogate, "surrogate"))
    check_memory(memory_needs(optimization, "optimization"))
    check_memory(memory_needs(verification, "verification", n_designs=1 + len(runs),
                              n_dof=n_dof, n_inputs=len(problem.theta_names),
                              n_fronts=max(fronts, 1)))
    for where, options in others:
        check_memory(memory_needs(options, where))


__all__ = ["check_study_memory"]
