"""``validate_designs``: build designs on the rig's truth, measure them over paired
replications, compare them (Table 7), and compare the model with the measurement.

>>> import numpy as np
>>> from surrogate_rbrdo.validation.replicas import reference_family
>>> opts = ValidationOptions(n_replications=6, ramps=0, n_boot=500,
...                          speeds_rpm={"start": 1000, "stop": 24000, "step": 1000})
>>> res = validate_designs(reference_family(), {"baseline": [2000.0, 500.0, 65.0],
...                        "short": [3000.0, 350.0, 75.0]}, options=opts,
...                        rng=np.random.default_rng(1))
>>> res.baseline, [c.after for c in res.comparisons]
('baseline', ['short', 'short'])
>>> bool(res.design("short").peak.max() < res.design("baseline").peak.min())
True
"""

from __future__ import annotations

import re
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from surrogate_rbrdo.core.errors import ModelError
from surrogate_rbrdo.core.rng import require_rng
from surrogate_rbrdo.rig.simulate import check_nominal_stable, check_stable
from surrogate_rbrdo.spindle.modal import Campbell
from surrogate_rbrdo.validation.agreement import Verdict, compare_moments, holm
from surrogate_rbrdo.validation.measure import (
    CriticalSpeedMeasurement,
    measure_criticals,
    measure_replica,
    probe_positions,
)
from surrogate_rbrdo.validation.model import ModelPrediction, ModelSpec, Moments, predict_model
from surrogate_rbrdo.validation.options import ValidationOptions
from surrogate_rbrdo.validation.replicas import TruthFamily, child_seed, replica_states
from surrogate_rbrdo.validation.table7 import Comparison, compare_designs

Progress = Callable[[int, int, str], None]

#: the model's Campbell diagram reaches 15 % beyond the range, so a critical speed just above
#: it shows (the paper extrapolates its optimum's third critical speed to 25 800 rpm)
CAMPBELL_OVERSPEED = 1.15

#: the paper's campaign (every default of :class:`ValidationOptions`)
DEFAULT_OPTIONS = ValidationOptions()


@dataclass(frozen=True)
class DesignResult:
    """Everything measured on one design (amplitudes in m; arrays over replications)."""

    name: str
    x: tuple[float, ...]
    peak: np.ndarray               # (n,) the study's y: peak over the range
    peak_speed_rpm: np.ndarray     # (n,)
    rated: np.ndarray              # (n,) amplitude at the rated speed
    curve: np.ndarray              # (n, S) tool-tip amplitude at options.speeds_rpm
    phasors: np.ndarray            # (n, S, n_probe) complex 1x phasors of every probe
    criticals: tuple[CriticalSpeedMeasurement, ...]
    moments: Mapping[str, Moments]  # "peak", "rated"
    positions_mm: Mapping[str, float]
    draws: tuple[dict[str, Any], ...]   # provenance: the truth's draws per replication
    n_records: int

    def values(self, quantity: str) -> np.ndarray:
        """The per-replication values of ``"peak"`` or ``"rated"``."""
        return {"peak": self.peak, "rated": self.rated}[quantity]


@dataclass(frozen=True)
class ValidationResult:
    """A validation campaign: measurements, Table 7 comparisons, model verdicts."""

    options: ValidationOptions
    baseline: str
    designs: tuple[DesignResult, ...]
    comparisons: tuple[Comparison, ...]
    model: ModelPrediction | None
    verdicts: tuple[Verdict, ...]
    channels: tuple[str, ...]
    installation: Mapping[str, Any]
    seed: Mapping[str, Any]
    timings: Mapping[str, float]

    def design(self, name: str) -> DesignResult:
        for d in self.designs:
            if d.name == name:
                return d
        raise ValueError(f"design {name!r} is not in this result: {[d.name for d in self.designs]}")

    @property
    def disagreements(self) -> tuple[Verdict, ...]:
        """Model-vs-measurement verdicts that disagree beyond uncertainty (Holm, α)."""
        return tuple(v for v in self.verdicts if not v.agree)

    @property
    def model_campbell(self) -> Mapping[str, Campbell]:
        return {} if self.model is None else self.model.campbell


def check_designs(designs: Mapping[str, Sequence[float]], baseline: str | None) -> str:
    """The baseline's name; raises ``ValueError`` for fewer than two designs, a name that
    cannot name a file, or an unknown ``baseline``."""
    if len(designs) < 2:
        raise ValueError(f"designs has {len(designs)} entries: need a baseline and at least "
                         "one other design")
    for k in designs:
        if not isinstance(k, str) or not k or any(c in k for c in "/\\ ,"):
            raise ValueError(f"design name {k!r} is not allowed: a non-empty name without "
                             "spaces, commas or slashes (it names files)")
    base = next(iter(designs)) if baseline is None else baseline
    if base not in designs:
        raise ValueError(f"baseline = {baseline!r} is not allowed: one of {list(designs)}")
    return base


def file_label(name: str) -> str:
    """A design label that can name files.

    >>> file_label("rbrdo 5%"), file_label("rdo/x, y")
    ('rbrdo_5pct', 'rdo_x_y')
    """
    return re.sub(r"[^A-Za-z0-9._-]+", "_", name.replace("%", "pct"))


def check_nominal_designs(truth: TruthFamily, designs: Mapping[str, Sequence[float]],
                          options: ValidationOptions) -> None:
    """Every design in the truth's design map and, without the truth's variability, stable at
    the speeds it will run (``measure_designs`` checks each drawn truth again); the error
    names the design."""
    o = options
    speeds = np.unique(np.r_[np.linspace(*o.speed_range_rpm, 12), o.rated_speed_rpm, o.ramp_rpm])
    for name, x in designs.items():
        try:
            check_nominal_stable(truth.at(x), speeds)
        except ValueError as exc:
            raise ValueError(f"designs.{name}: {exc}") from None
        except ModelError as exc:
            raise ModelError(f"design {name!r}: {exc}") from None


def _measure_design(i: int, name: str, x, states, o: ValidationOptions, inst, ss,
                    progress: Progress | None, count: list[int], total: int) -> DesignResult:
    lo, hi = o.speed_range_rpm
    check_stable(states[0].model(), states[0].theta,
                 np.unique(np.r_[np.linspace(lo, hi, 12), o.rated_speed_rpm, o.ramp_rpm]))
    reps, crit = [], []
    for r, st in enumerate(states):
        rng = np.random.default_rng(child_seed(ss, 2, i, r))
        reps.append(measure_replica(st, o, inst, rng))
        if r < o.ramps:
            rng = np.random.default_rng(child_seed(ss, 3, i, r))
            crit += measure_criticals(st, r, o, inst, rng)
        count[0] += 1
        if progress:
            progress(count[0], total, f"{name} replication {r + 1}/{len(states)}")
    peak = np.array([m.peak for m in reps])
    rated = np.array([m.rated for m in reps])
    moments = {q: Moments.of_values(v, o.delta_lim_m, o.confidence)
               for q, v in (("peak", peak), ("rated", rated))}
    return DesignResult(
        name, tuple(float(v) for v in x), peak, np.array([m.peak_speed_rpm for m in reps]),
        rated, np.array([m.curve for m in reps]), np.array([m.phasors for m in reps]),
        tuple(crit), moments, probe_positions(states[0], o),
        tuple(st.draws for st in states), sum(m.n_records for m in reps))


def measure_designs(truth: TruthFamily, designs: Mapping[str, Sequence[float]], *,
                    options: ValidationOptions = DEFAULT_OPTIONS, rng: np.random.Generator,
                    progress: Progress | None = None) -> ValidationResult:
    """The rig's side of :func:`validate_designs`: measurements and Table 7's comparisons,
    without a model (``model`` None, no verdicts; :func:`add_model` adds them)."""
    require_rng(rng)
    o = options
    base = check_designs(designs, o.baseline)
    names = [base] + [k for k in designs if k != base]
    ordered = {k: designs[k] for k in names}
    t0 = time.perf_counter()
    ss = rng.bit_generator.seed_seq
    inst = o.sensors.install(np.random.default_rng(child_seed(ss, 9)))
    states = replica_states(truth, ordered, o.n_replications, seed=child_seed(ss, 1),
                            shared=o.shared, replicate=o.replicate)
    count, total = [0], len(names) * o.n_replications
    results = tuple(_measure_design(i, k, ordered[k], states[k], o, inst, ss, progress, count,
                                    total) for i, k in enumerate(names))
    t1 = time.perf_counter()
    stat_rng = np.random.default_rng(child_seed(ss, 5))
    comps = tuple(
        compare_designs(results[0].values(q), d.values(q), quantity=q, names=(base, d.name),
                        delta_lim_m=o.delta_lim_m, rng=stat_rng, confidence=o.confidence,
                        alpha=o.alpha, power=o.power, n_boot=o.n_boot)
        for d in results[1:] for q in ("peak", "rated"))
    t2 = time.perf_counter()
    return ValidationResult(
        o, base, results, comps, None, (), o.sensors.probe_channels, inst.to_dict(),
        {"entropy": str(ss.entropy), "spawn_key": list(ss.spawn_key)},
        {"measure_s": t1 - t0, "statistics_s": t2 - t1, "model_s": 0.0, "total_s": t2 - t0})


def add_model(result: ValidationResult, model: ModelSpec, *, rng: np.random.Generator
              ) -> ValidationResult:
    """``result`` with the model's μ, σ, P_f, band and Campbell diagram of every design and
    the verdicts model vs measurement; ``rng`` is the generator the measurement had (its
    stream for the model is addressed by key, as in :func:`validate_designs`)."""
    require_rng(rng)
    o, t0 = result.options, time.perf_counter()
    ss = rng.bit_generator.seed_seq
    ordered = {d.name: d.x for d in result.designs}
    pred = predict_model(model, ordered, delta_lim_m=o.delta_lim_m, confidence=o.confidence,
                         rng=np.random.default_rng(child_seed(ss, 6)), speeds_rpm=o.speeds_rpm,
                         band_samples=o.band_samples,
                         campbell_speeds_rpm=np.linspace(
                             0.0, CAMPBELL_OVERSPEED * o.speed_range_rpm[1], o.campbell_speeds))
    raw = [v for d in result.designs for q, m in pred.moments[d.name].items()
           for v in compare_moments(d.name, q, d.moments[q], m, u_cal=o.u_calibration)]
    dt = time.perf_counter() - t0
    timings = {**result.timings, "model_s": dt, "total_s": result.timings["total_s"] + dt}
    return replace(result, model=pred, verdicts=tuple(holm(raw, o.alpha)), timings=timings)


def validate_designs(truth: TruthFamily, designs: Mapping[str, Sequence[float]], *,
                     options: ValidationOptions = DEFAULT_OPTIONS,
                     rng: np.random.Generator, model: ModelSpec | None = None,
                     progress: Progress | None = None) -> ValidationResult:
    """Build every design on the rig's truth, measure ``options.n_replications`` paired
    replications of each, compare each design with the baseline (Table 7's analogue) and,
    with a ``model``, its μ, σ, P_f, band and Campbell diagram with the measurement
    (:func:`measure_designs`, then :func:`add_model`).

    Parameters
    ----------
    truth : TruthFamily
        The rig's truth for any design (hidden effects, variability, design map).
    designs : mapping name -> x
        Designs in the truth's design map (the baseline first unless ``options.baseline``).
    rng : numpy.random.Generator
        Root of every draw (truth, sensors, noise, bootstrap, model samples), addressed by
        key so the same seed gives the same spindles whatever else is measured.
    model : ModelSpec, optional
        The model the study used (responses and random vector).
    progress : callable(done, total, label), optional
    """
    res = measure_designs(truth, designs, options=options, rng=rng, progress=progress)
    return res if model is None else add_model(res, model, rng=rng)
