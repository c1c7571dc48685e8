"""The discrepancy workflow: find where a spindle model and measured data disagree, name the
missing effect (or say that nothing is missing, or that no library effect explains it), add it
and show the gap shrink on held-out speeds.

Typical use::

    from surrogate_rbrdo.discrepancy import DiscrepancyOptions, find_discrepancy
    result = find_discrepancy(data, geometry, effects, options=DiscrepancyOptions(), rng=rng)
    result.verdict, findings(result)

See ``docs/discrepancy.md`` for the method and its blind-test rates.
"""

from surrogate_rbrdo.discrepancy.candidates import DEFAULT_LIBRARY, Candidate, candidate, library
from surrogate_rbrdo.discrepancy.forward import ForwardModel
from surrogate_rbrdo.discrepancy.nuisance import NuisanceOptions
from surrogate_rbrdo.discrepancy.observables import ComplexBlock, MeasuredData, RealBlock
from surrogate_rbrdo.discrepancy.sweeps import Channel, Sweep
from surrogate_rbrdo.discrepancy.truth_effects import TRUTH_MODIFIERS
from surrogate_rbrdo.discrepancy.workflow import (
    VERDICTS,
    DiscrepancyOptions,
    DiscrepancyResult,
    find_discrepancy,
)

__all__ = [
    "DEFAULT_LIBRARY",
    "TRUTH_MODIFIERS",
    "VERDICTS",
    "Candidate",
    "Channel",
    "ComplexBlock",
    "DiscrepancyOptions",
    "DiscrepancyResult",
    "ForwardModel",
    "MeasuredData",
    "NuisanceOptions",
    "RealBlock",
    "Sweep",
    "candidate",
    "find_discrepancy",
    "library",
]
