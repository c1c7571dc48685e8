"""Training of structure ``"substructure"``: its options, the speed nodes, the DOE over the
designs and the FE condensations (the surrogate itself: ``structured.substructure``).

>>> SubstructureOptions().n_doe
200
"""
from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from surrogate_rbrdo.core.protocols import LimitState
from surrogate_rbrdo.core.rng import require_rng
from surrogate_rbrdo.core.validate import check_int
from surrogate_rbrdo.doe import lhs
from surrogate_rbrdo.sampling.evaluate import evaluate_points
from surrogate_rbrdo.spindle.evaluate import ResponseSpec
from surrogate_rbrdo.spindle.substructure import PointwiseCondensed, retained_layout
from surrogate_rbrdo.surrogates.structured.base import (
    SamplingOptions,
    TrainedSurrogate,
    kriging_bytes,
    register_structure,
)
from surrogate_rbrdo.surrogates.structured.substructure import (
    chebyshev_nodes,
    fit_substructure_surrogate,
)


def speed_nodes(spindle: Any, kind: str, speed_rpm: float | None, n_speeds: int) -> np.ndarray:
    """Speeds (rpm) at which ``S`` is trained: the one speed, or Chebyshev nodes in the range."""
    if kind == "at_speed":
        return np.array([float(speed_rpm)])
    g = spindle.geometry            # "peak" and "peak_unbalance": the whole speed range
    return chebyshev_nodes(g.speed_min_rpm, g.speed_max_rpm, n_speeds)


@dataclass(frozen=True)
class SubstructureOptions(SamplingOptions):
    """Options of the substructure surrogate (``structure = "substructure"``; static DOE over
    the designs only, θ is exact).

    Attributes
    ----------
    n_doe : int
        Training designs (maximin LHS over the design box; one FE condensation each), >= 7.
    n_start : int
        Multistarts of the multi-output Kriging's likelihood optimisation.
    sub_n_speeds : int
        The peak response: Chebyshev speed nodes at which ``S`` is trained and between which
        it is interpolated (the at-speed response uses its one speed).
    """

    structure: ClassVar[str] = "substructure"
    n_doe: int = 200
    n_start: int = 5
    sub_n_speeds: int = 12

    def __post_init__(self) -> None:
        super().__post_init__()
        check_int("n_doe", self.n_doe, minimum=7)
        check_int("n_start", self.n_start, minimum=1)
        check_int("sub_n_speeds", self.sub_n_speeds, minimum=2)

    def memory_bytes(self) -> dict[str, float]:
        """Peak bytes (``core.memory``): the multi-output Kriging on ``n_doe`` designs and
        its outputs, ``2 · sub_n_speeds · r²`` per design for ``r`` retained DOFs (at least
        12: the tool tip and two bearings, 4 DOFs each; a lower bound, the geometry is not
        known here), and one design's rotor dynamic stiffness, ``sub_n_speeds`` complex
        ``r × r`` matrices or more.

        >>> SubstructureOptions(sub_n_speeds=10 ** 8).memory_bytes()["sub_n_speeds"] > 1e11
        True
        """
        r2 = 12.0 ** 2
        return {"n_doe": kriging_bytes(self.n_doe),
                "sub_n_speeds": 8.0 * 2 * self.sub_n_speeds * r2 * (self.n_doe + 2)}

@register_structure("substructure", SubstructureOptions, "Kriging of the rotor's condensed "
                    "dynamic stiffness over the designs, bearings and θ coupled exactly")
def train_substructure(spindle: Any, inputs: Any, limit: LimitState, response: ResponseSpec,
                       options: SubstructureOptions, *, rng: np.random.Generator,
                       cache: Any = None, counter: Any, progress: bool = False,
                       label: str = "") -> TrainedSurrogate:
    """LHS over the designs → FE condensations → fit (``inputs`` and ``limit`` are not
    needed: θ is coupled exactly)."""
    o = options
    r_doe, r_fit = require_rng(rng).spawn(2)
    start, start_cached = counter.calls, counter.cached
    t0 = time.perf_counter()
    xb = np.asarray(spindle.design_map.bounds, dtype=float)
    nodes = speed_nodes(spindle, response.kind, response.speed_rpm, o.sub_n_speeds)
    m0 = spindle.model(spindle.baseline)
    lay = retained_layout(m0)
    # the random-unbalance peak takes its phasors from θ: the geometry's unbalance is unused
    fixed = None if response.kind == "peak_unbalance" else tuple(complex(u)
                                                                 for u in m0.unbalance)
    func = PointwiseCondensed(spindle, tuple(float(s) for s in nodes), lay.nodes, fixed)
    X = lhs(o.n_doe, xb, rng=r_doe)
    res = evaluate_points(
        func, X, n_jobs=o.n_jobs, backend=o.backend, cache=cache, counter=counter,
        on_nonfinite="raise", progress=progress, n_outputs=func.n_outputs(lay.n_dof),
        client="local" if o.backend == "dask" else None,
        desc=f"{label} FE: condensed rotor".strip())
    sample_s = time.perf_counter() - t0
    unb = (response.fe_response(spindle, "condensed") if response.kind == "peak_unbalance"
           else None)
    model = fit_substructure_surrogate(spindle, X, res.y, kind=response.kind,
                                       speed_rpm=response.speed_rpm, nodes_rpm=nodes,
                                       rng=r_fit, n_start=o.n_start, unbalance_response=unb)
    info = {**model.info, "sampling_time_s": sample_s, "bounds": xb.tolist(),
            "active_learning": False, "response": response.label}
    model.info = dict(info)
    return TrainedSurrogate("substructure", model, o, response, fe_calls=counter.calls - start,
                            fe_cache_hits=counter.cached - start_cached, info=info)


__all__ = ["SubstructureOptions", "speed_nodes", "train_substructure"]
