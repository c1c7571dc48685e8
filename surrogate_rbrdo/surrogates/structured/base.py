"""What every surrogate structure shares: the protocol, the one return type, the registry.

A *structure* turns FE evaluations of a spindle into a model of ``y(x, θ)`` (the tool-tip
amplitude of a :class:`~surrogate_rbrdo.spindle.evaluate.ResponseSpec`). Each registers in
:data:`STRUCTURES` with one frozen options dataclass (its TOML ``[surrogate]`` table, selected
by ``structure = "<name>"``) and a ``train`` function; :func:`train_surrogate` dispatches on
the options' type and returns a :class:`TrainedSurrogate` whatever the structure.

>>> sorted(STRUCTURES)
['fe', 'global', 'resonance', 'substructure']
>>> STRUCTURES["substructure"].options.structure
'substructure'
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import asdict, dataclass, field
from typing import Any, ClassVar, Protocol, runtime_checkable

import numpy as np

from surrogate_rbrdo.core.counting import CallCounter
from surrogate_rbrdo.core.protocols import LimitState, Prediction
from surrogate_rbrdo.core.registry import Registry
from surrogate_rbrdo.core.schema import parse
from surrogate_rbrdo.core.validate import check_choice, check_int
from surrogate_rbrdo.sampling.evaluate import BACKENDS
from surrogate_rbrdo.spindle.evaluate import ResponseSpec

STRUCTURES = Registry("surrogate structure")


@runtime_checkable
class SurrogateModel(Protocol):
    """A fitted model of ``y(x, θ)`` (SI units at the interface).

    ``response(x (P, d), theta (N, m)) -> (P, N)`` on a CRN sample (also ``__call__``: the core
    ``Response``), ``response_points(Z) -> (n,)`` point predictions at joint rows
    ``z = [x, θ]``, ``predict(Z) -> Prediction`` (``std`` NaN where the structure has no
    predictive distribution, 0 for the FE model), ``n_train`` (FE evaluations it was trained
    on) and ``info``.
    """

    info: dict[str, Any]

    @property
    def n_train(self) -> int: ...

    def response(self, x: np.ndarray, theta: np.ndarray) -> np.ndarray: ...

    def __call__(self, x: np.ndarray, theta: np.ndarray) -> np.ndarray: ...

    def response_points(self, Z: np.ndarray) -> np.ndarray: ...

    def predict(self, Z: np.ndarray) -> Prediction: ...


@dataclass(frozen=True, eq=False)
class TrainedSurrogate:
    """What :func:`train_surrogate` returns for every structure.

    Attributes
    ----------
    structure : str
        Registry name (``"global"``, ``"resonance"``, ``"substructure"``, ``"fe"``).
    model : SurrogateModel
    options : dataclass
        The structure's options it was trained with.
    response : ResponseSpec
        What ``y`` is.
    fe_calls : int
        FE evaluations counted during the training (computed, not loaded from the cache).
    fe_cache_hits : int
        Training points loaded from the FE cache instead.
    info : mapping
        Training details (sizes, fit time, hyperparameters, active-learning history, ...).
    """

    structure: str
    model: Any
    options: Any
    response: ResponseSpec
    fe_calls: int
    fe_cache_hits: int = 0
    info: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        object.__setattr__(self, "info", dict(self.info))

    @property
    def in_loop(self) -> str:
        """``"fe"`` when the model *is* the FE model (its calls are FE calls), else
        ``"surrogate"``."""
        return "fe" if self.structure == "fe" else "surrogate"

    def to_dict(self) -> dict[str, Any]:
        return {"structure": self.structure, "response": self.response.label,
                "options": asdict(self.options), "fe_calls": self.fe_calls,
                "fe_cache_hits": self.fe_cache_hits, **dict(self.info)}


def kriging_bytes(n: int) -> float:
    """Peak bytes of a Kriging fit on ``n`` points: ~10 ``n × n`` matrices of 8 B (smt KRG's
    correlation matrix, its Cholesky factor and the likelihood's work arrays) and ~16 values
    per point (``core.memory``).

    >>> kriging_bytes(1000) / 1e6
    80.128
    """
    return 8.0 * (10.0 * float(n) ** 2 + 16.0 * float(n))


@dataclass(frozen=True)
class SamplingOptions:
    """How a structure's FE training points are computed.

    Attributes
    ----------
    n_jobs : int
        Worker processes of the FE sampling.
    backend : str
        ``evaluate_points`` backend (``loky``, ``threading``, ``sequential``, ``dask``: a
        temporary local cluster with ``n_jobs`` workers).
    """

    structure: ClassVar[str] = ""
    n_jobs: int = 2
    backend: str = "loky"

    def __post_init__(self) -> None:
        check_int("n_jobs", self.n_jobs, minimum=1)
        check_choice("backend", self.backend, BACKENDS)

    def check_response(self, response: ResponseSpec) -> None:
        """Raise ``ValueError`` if the structure cannot model ``response``."""

    def to_dict(self) -> dict[str, Any]:
        return {"structure": self.structure, **asdict(self)}


@dataclass(frozen=True)
class Structure:
    """A registry entry: the options class, the training function and a one-line summary.

    ``refinable``: :func:`~surrogate_rbrdo.surrogates.refine.refine_surrogate` can add
    (x, θ) FE points to it and refit.
    """

    name: str
    options: type
    train: Callable[..., TrainedSurrogate]
    summary: str
    refinable: bool = False


def register_structure(name: str, options: type, summary: str, *, refinable: bool = False
                       ) -> Callable[[Callable[..., TrainedSurrogate]],
                                     Callable[..., TrainedSurrogate]]:
    """Decorator registering a ``train`` function with its options class."""
    if getattr(options, "structure", None) != name:
        raise ValueError(f"options class {options.__name__} has structure = "
                         f"{getattr(options, 'structure', None)!r}: must be {name!r}")

    def deco(train: Callable[..., TrainedSurrogate]) -> Callable[..., TrainedSurrogate]:
        STRUCTURES.register(name)(Structure(name, options, train, summary, refinable))
        return train

    return deco


def structure_of(options: Any) -> Structure:
    """The registry entry whose options class ``options`` is an instance of."""
    for entry in STRUCTURES.values():
        if type(options) is entry.options:
            return entry
    raise ValueError(f"options = {options!r} is not allowed: must be the options of a "
                     f"registered structure ({', '.join(sorted(STRUCTURES))})")


def train_surrogate(spindle: Any, inputs: Any, limit: LimitState, options: Any, *,
                    rng: np.random.Generator, response: ResponseSpec | None = None,
                    cache: Any = None, counter: CallCounter | None = None,
                    progress: bool = False, label: str = "") -> TrainedSurrogate:
    """Train the structure of ``options`` on FE evaluations of ``spindle``.

    Parameters
    ----------
    spindle : ReferenceSpindle
    inputs : RandomVector
        θ distribution (``mean``, ``cov``, ``sample``): sets the θ box and any θ pool.
    limit : LimitState
        ``δ_lim`` (used by active learning and boundary infill).
    options : GlobalOptions, ResonanceOptions, SubstructureOptions or FEOptions
        (or any registered structure's options).
    rng : numpy.random.Generator
    response : ResponseSpec, optional
        What ``y`` is (default: the peak amplitude).
    cache : joblib.Memory, optional
        FE results are cached there (a rerun loads them).
    counter : CallCounter, optional
        Receives every FE call (``TrainedSurrogate.fe_calls`` has this training's share).
    progress : bool
    label : str
        Prefix of the progress bars (e.g. the run: ``"quick/r1"``).
    """
    entry = structure_of(options)
    response = ResponseSpec() if response is None else response
    if not isinstance(response, ResponseSpec):
        raise ValueError(f"response = {response!r} is not allowed: must be a ResponseSpec")
    options.check_response(response)
    counter = counter if counter is not None else CallCounter()
    return entry.train(spindle, inputs, limit, response, options, rng=rng, cache=cache,
                       counter=counter, progress=progress, label=label)


def surrogate_options(table: Mapping[str, Any], response: ResponseSpec, where: str) -> Any:
    """The options of the structure a ``[surrogate]`` table selects (``structure``, default
    ``"global"``), checked against ``response``; errors name ``<where>.<field>``.

    >>> surrogate_options({"structure": "fe"}, ResponseSpec(), "surrogate").structure
    'fe'
    """
    table = dict(table)
    name = table.pop("structure", "global")
    if not isinstance(name, str) or name not in set(STRUCTURES):
        raise ValueError(f"{where}.structure = {name!r} is not allowed: must be one of "
                         f"{sorted(STRUCTURES)}")
    options = parse(STRUCTURES[name].options, table, where)
    try:
        options.check_response(response)
    except ValueError as exc:
        raise ValueError(f"{where}.{exc}") from None
    return options


__all__ = ["STRUCTURES", "SamplingOptions", "Structure", "SurrogateModel", "TrainedSurrogate",
           "kriging_bytes", "register_structure", "structure_of", "surrogate_options",
           "train_surrogate"]
