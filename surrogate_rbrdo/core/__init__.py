"""Shared protocols, result types, registries, validation helpers and errors."""

from surrogate_rbrdo.core.counting import CallCounter, CountingResponse
from surrogate_rbrdo.core.errors import ModelError, OutsideDomainError, SingularSystemError
from surrogate_rbrdo.core.protocols import (
    Estimate,
    Estimator,
    LimitState,
    Prediction,
    Response,
    Surrogate,
)
from surrogate_rbrdo.core.registry import Registry

__all__ = [
    "CallCounter",
    "CountingResponse",
    "Estimate",
    "Estimator",
    "LimitState",
    "ModelError",
    "OutsideDomainError",
    "Prediction",
    "Registry",
    "Response",
    "SingularSystemError",
    "Surrogate",
]
