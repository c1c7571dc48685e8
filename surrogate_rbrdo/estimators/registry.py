"""The estimator registry and the ``get_estimator`` convenience.

>>> est = get_estimator("mc", n_samples=100)
>>> est.n_samples
100
>>> get_estimator("nope")
Traceback (most recent call last):
...
ValueError: unknown estimator 'nope'; known: ais, form, fosm, is, mc, sorm, subset
"""

from __future__ import annotations

import dataclasses
from typing import Any

from surrogate_rbrdo.core.registry import Registry

ESTIMATORS = Registry("estimator")


def get_estimator(name: str, **options: Any) -> Any:
    """Construct the estimator registered as ``name`` with the given options.

    An unknown name raises ``ValueError`` listing the known ones; an unknown option raises
    ``ValueError`` listing the allowed ones.
    """
    cls = ESTIMATORS.get(name)
    allowed = [f.name for f in dataclasses.fields(cls) if f.init]
    unknown = sorted(set(options) - set(allowed))
    if unknown:
        raise ValueError(f"unknown option(s) {unknown} for estimator {name!r}; allowed: {allowed}")
    return cls(**options)
