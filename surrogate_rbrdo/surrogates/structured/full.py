"""Structure ``"fe"``: no surrogate, the full FE model behind the surrogate interface.

The ground truth a surrogate study is compared with: every ``response(x, θ)`` query runs the FE
model (cheap for the at-speed response with ``fe_method`` ``"auto"``/``"condensed"``, ~3.5–7 ms
per design for 1 000 θ; no DOE, no training). Its calls are FE calls: wrap it in a
:class:`~surrogate_rbrdo.core.CountingResponse` to count them.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from surrogate_rbrdo.core.protocols import LimitState, Prediction
from surrogate_rbrdo.core.validate import check_choice
from surrogate_rbrdo.spindle.evaluate import FE_METHODS, ResponseSpec
from surrogate_rbrdo.surrogates.structured.base import TrainedSurrogate, register_structure


@dataclass(eq=False)
class FullModel:
    """The full FE model behind the surrogate interface (``structure = "fe"``).

    ``response(x, θ)`` runs the FE model for every design and θ sample: the reference a
    surrogate-based study is judged against. Its calls are FE calls.

    >>> import numpy as np
    >>> from surrogate_rbrdo.spindle.evaluate import ResponseSpec
    >>> from surrogate_rbrdo.spindle.reference import reference_spindle
    >>> fm = FullModel(ResponseSpec("at_speed", 24000.0).fe_response(reference_spindle()))
    >>> fm.response(np.array([[3000.0, 600.0, 80.0]]), np.ones((2, 2))).shape
    (1, 2)
    """

    fe: Any
    info: dict[str, Any] = field(default_factory=dict)
    n_train: int = 0

    def response(self, x: np.ndarray, theta: np.ndarray) -> np.ndarray:
        """FE ``y`` (m) for designs ``x`` (P, 3) × θ (N, m) → (P, N)."""
        return self.fe(x, theta)

    __call__ = response

    def response_points(self, Z: np.ndarray) -> np.ndarray:
        """FE ``y`` (m) at joint points ``Z = [x, θ]``."""
        return np.array([self.fe.point(z) for z in np.atleast_2d(np.asarray(Z, dtype=float))])

    def predict(self, Z: np.ndarray) -> Prediction:
        """The FE values; std 0 (the model is exact)."""
        y = self.response_points(Z)
        return Prediction(mean=y, std=np.zeros_like(y))


@dataclass(frozen=True)
class FEOptions:
    """Options of structure ``"fe"``.

    Attributes
    ----------
    fe_method : {"auto", "direct", "condensed"}
        How the FE model in the loop is solved (both exact; ``AtSpeedAmplitudeResponse``).
        ``"auto"``: ``"condensed"`` for the at-speed response (rotor condensed once per
        design, the θ sample through 3^m node solves) and for the random-unbalance peak (the
        exact coupling of ``spindle.peak_coupling``, ~1e5 predictions/s, ≤ 3e-5 from the FE
        peak search), ``"direct"`` for the peak (the only method there).
    """

    structure: ClassVar[str] = "fe"
    fe_method: str = "auto"

    def __post_init__(self) -> None:
        check_choice("fe_method", self.fe_method, ("auto", *FE_METHODS))

    def check_response(self, response: ResponseSpec) -> None:
        if self.fe_method == "condensed" and response.kind == "peak":
            raise ValueError("fe_method = 'condensed' is not allowed with response.kind = "
                             "'peak': only 'direct' or 'auto' (the peak is searched per θ)")

    def method(self, response: ResponseSpec) -> str:
        """The FE method ``"auto"`` resolves to for ``response``."""
        if self.fe_method != "auto":
            return self.fe_method
        return "direct" if response.kind == "peak" else "condensed"


@register_structure("fe", FEOptions, "no surrogate: the full FE model answers every (x, θ) "
                    "query (the ground truth)")
def train_fe(spindle: Any, inputs: Any, limit: LimitState, response: ResponseSpec,
             options: FEOptions, *, rng: np.random.Generator, cache: Any = None,
             counter: Any = None, progress: bool = False, label: str = "") -> TrainedSurrogate:
    """No training: the FE response itself (no FE calls until it is queried)."""
    method = options.method(response)
    info = {"structure": "fe", "response": response.label, "n_train": 0, "fe_method": method}
    model = FullModel(response.fe_response(spindle, method), info=dict(info))
    return TrainedSurrogate("fe", model, options, response, fe_calls=0, info=info)


__all__ = ["FEOptions", "FullModel", "train_fe"]
