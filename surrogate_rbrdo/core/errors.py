"""Error types.

Bad *input* (a field out of range, an unknown key or name) raises the built-in
:class:`ValueError` with a message naming the field, its value and what is allowed.
Numerical trouble inside a model (a singular system, NaN from a solver) raises
:class:`ModelError` or a subclass, never returns NaN silently.
"""


class ModelError(RuntimeError):
    """A model evaluation failed numerically (NaN/inf, no convergence, ...)."""


class SingularSystemError(ModelError):
    """A linear system is singular or too ill-conditioned to trust its solution."""
