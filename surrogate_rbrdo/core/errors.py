"""Error types.

Bad *input* (a field out of range, an unknown key or name) raises the built-in
:class:`ValueError` with a message naming the field, its value and what is allowed.
Numerical trouble inside a model (a singular system, NaN from a solver) raises
:class:`ModelError` or a subclass, never returns NaN silently.

>>> err = OutsideDomainError("theta = [-0.1, 1.0] is not allowed", rows=[3])
>>> isinstance(err, ModelError), isinstance(err, ValueError), err.rows
(True, True, (3,))
"""

from __future__ import annotations

from collections.abc import Iterable


class ModelError(RuntimeError):
    """A model evaluation failed numerically (NaN/inf, no convergence, ...)."""


class SingularSystemError(ModelError):
    """A linear system is singular or too ill-conditioned to trust its solution."""


class OutsideDomainError(ModelError, ValueError):
    """A model input lies outside the model's physical domain (e.g. a bearing stiffness factor
    θ ≤ 0).

    A :class:`ModelError` (so ``on_failure="nan"`` and the estimators handle it: a point outside
    the domain is not a failure, see ``docs/estimators.md``) and, for callers that validate
    their own input, a :class:`ValueError`. ``rows`` holds the indices of the offending rows of
    the batch the model was given, when the model knows them (``None`` otherwise).
    """

    def __init__(self, message: str, rows: Iterable[int] | None = None) -> None:
        super().__init__(message)
        self.rows = None if rows is None else tuple(int(r) for r in rows)
