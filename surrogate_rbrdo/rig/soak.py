"""A thermal soak in a rig campaign: steady records at a speed held as the spindle warms.

After a tool's steady runs (and its ramps and impacts), :func:`~.campaign.run_campaign`
with ``CampaignOptions.soak`` (a :class:`~.thermal.SoakPlan`) holds a speed — by default the
two speeds either side of the resonance of the sweep just measured (:func:`soak_plan`), soak
run ``j`` at ``plan.speed_of(j)`` — for ``plan.runs`` cold starts.
Soak run ``j`` is run ``repeats + 1 + j`` of its tool (its own thermal draw; run
``repeats`` stays free for an impact run), and at each of ``plan.times_s`` it takes a steady
record (``simulate.steady_records``) of the run's state warmed to the thermal model's
fraction (``TruthState.warming(truth.thermal.fraction(t))``), plus the front bearing's
outer-ring temperature (:meth:`~.thermal.ThermalModel.temperature_K` of the run, one
reading per record, held over the record), the probes' gains through their tempcos at that
ring's true rise (:func:`probe_rise`): a record of kind ``"soak"`` with labels
``build, tool, run, soak, time_s, speed_rpm``. Record ``k`` of soak run ``j`` draws its noise
from stream ``(7, build, tool, j, k)``; the run's temperature readings from ``(8, build, tool,
j)``: any record can be made alone (resuming, worker processes).

>>> from surrogate_rbrdo.rig.thermal import SoakPlan
>>> amp = np.array([[1e-7, 3e-6, 1e-6], [2e-7, 2e-6, 1e-6]])     # (runs, speeds)
>>> soak_plan(SoakPlan(rule="resonance"), (1000.0, 2000.0, 3000.0), amp).speed_rpm
2000.0
>>> lab = soak_labels(SoakPlan(speeds_rpm=(21000.0, 22500.0)), 0, 1, 20, 2, 3)
>>> soak_id(0, 1, 2, 3), lab["run"], lab["speed_rpm"]
('b0_t1_soak2_k03', 23, 21000.0)
"""

from __future__ import annotations

from typing import Any

import numpy as np

from surrogate_rbrdo.rig.records import Calibration, ChannelSpec, Record, SensorLocation
from surrogate_rbrdo.rig.sensors import SensorSet
from surrogate_rbrdo.rig.simulate import ProbeLayout, steady_records
from surrogate_rbrdo.rig.statespace import require_stable
from surrogate_rbrdo.rig.thermal import SoakPlan
from surrogate_rbrdo.rig.truth import _child

#: the streams of a soak record's noise ``(7, b, tl, j, k)`` and of a soak run's
#: temperature readings ``(8, b, tl, j)`` (the campaign's others: 0–6, 9)
RECORD_KEY, TEMPERATURE_KEY = 7, 8
#: the temperature channel: the front bearing's outer ring (a PT100 and its transmitter)
TEMPERATURE_CHANNEL = "T_front"
#: its calibration: 0.01 K per count from 273.15 K (0 °C); 16-bit counts span 273 ± 327 K
TEMPERATURE_SCALE_K, TEMPERATURE_OFFSET_K = 0.01, 273.15


def soak_plan(plan: SoakPlan, speeds_rpm, amplitude: np.ndarray) -> SoakPlan:
    """``plan`` with its speeds resolved (:meth:`~.thermal.SoakPlan.at`) from the sweep just
    measured: ``amplitude`` (runs, speeds), each run's largest channel 1x amplitude per speed,
    averaged over the runs."""
    return plan.at(speeds_rpm, np.asarray(amplitude, float).mean(axis=0))


def soak_id(b: int, tl: int, j: int, k: int) -> str:
    """Record id of soak run ``j``'s record ``k`` (build ``b``, tool ``tl``)."""
    return f"b{b}_t{tl}_soak{j}_k{k:02d}"


def soak_labels(plan: SoakPlan, b: int, tl: int, repeats: int, j: int, k: int
                ) -> dict[str, Any]:
    """Index labels of a soak record: ``build, tool, run`` (``repeats + 1 + j``), ``soak``
    (``j``), ``time_s`` (after reaching speed) and ``speed_rpm`` (the speed held)."""
    return {"build": b, "tool": tl, "run": soak_run_index(repeats, j), "soak": j,
            "time_s": plan.times_s[k], "speed_rpm": plan.speed_of(j)}


def probe_rise(truth, speed_rpm: float, fraction: float) -> float:
    """The probes' temperature rise during a soak record: the front bearing's outer ring's
    (``truth.thermal``: the steady rise at the speed held times the warm-up's fraction; the
    probes sit in the housing beside the bearings). Their gains follow it through their
    tempcos (:meth:`~.sensors.Installation.warmed`)."""
    return float(truth.thermal.rise_K(speed_rpm) * fraction)


def sweep_probe_rise(truth, probe, speeds_rpm) -> np.ndarray | None:
    """The probes' temperature rise at each steady speed's thermal equilibrium
    (:func:`probe_rise` at a warm-up's end) when their tempcos apply to the sweep
    (``probe``, a :class:`~.sensors.ProbeModel`: ``tempco_sweep`` and ``tempco_sd_per_K`` >
    0), else None."""
    if not (probe.tempco_sweep and probe.tempco_sd_per_K > 0):
        return None
    return np.array([probe_rise(truth, float(s), 1.0) for s in np.atleast_1d(speeds_rpm)])


def soak_run_index(repeats: int, j: int) -> int:
    """The run index of soak run ``j`` after ``repeats`` steady runs (run ``repeats`` is left
    for an impact run): every soak run is a cold start with its own thermal draw."""
    return repeats + 1 + j


def soak_run(common: tuple, j: int, todo: tuple[int, ...]) -> dict[str, Record]:
    """Soak run ``j``'s records ``todo`` (indices into ``plan.times_s``), by id.

    ``common``: truth, options (``sensors``, ``duration_s``, ``repeats``), installation, root
    seed, Ritz basis (:func:`~.statespace.reduction`, for the stability check), build, tool,
    the resolved plan and ``provenance(state, run)`` (what every record of a run carries). A
    warmed state equal to one seen before (a truth without an effect that drifts) reuses its
    model and stability check."""
    truth, options, inst, root_ss, red, b, tl, plan, provenance = common
    run = soak_run_index(options.repeats, j)
    st = truth.state(root_ss, build=b, tool=tl, run=run)
    t = np.asarray(plan.times_s)
    speed = plan.speed_of(j)
    temps = truth.thermal.temperature_K(
        speed, t, np.random.default_rng(_child(root_ss, TEMPERATURE_KEY, b, tl, j)))
    base = provenance(st, run)
    models: dict[tuple, Any] = {}
    out = {}
    for k in todo:
        f = float(truth.thermal.fraction(t[k]))
        w = st.warming(f)
        if w.effects not in models:
            models[w.effects] = w.model()
            require_stable(models[w.effects], w.theta, [speed], red,
                           f"the truth of build {b}, tool {tl}, soak run {j} (run {run}) "
                           f"after {t[k]:g} s")
        model = models[w.effects]
        rid = soak_id(b, tl, j, k)
        key = [RECORD_KEY, b, tl, j, k]
        prov = {**base, "seed_key": key, "soak": {
            "run": j, "time_s": float(t[k]), "thermal_fraction": f,
            "speed_rpm": speed, "effects_warmed": [e.name for e in w.effects
                                                   if e.thermal_params]}}
        rec = steady_records(model, w.theta, np.array([speed]), options.sensors, inst,
                             [np.random.default_rng(_child(root_ss, *key))],
                             duration_s=options.duration_s, ids=[rid], provenance=[prov],
                             probe_rise_K=np.array([probe_rise(truth, speed, f)]))[0]
        front = ProbeLayout.of(model).positions_mm["front"]
        out[rid] = with_temperature(rec, float(temps[k]), options.sensors, front)
    return out


def temperature_channel(sensors: SensorSet, position_mm: float) -> ChannelSpec:
    """The soak records' temperature channel (at the front bearing, in K)."""
    lo, hi = sensors.daq.counts_limits
    return ChannelSpec(TEMPERATURE_CHANNEL, "temperature", "K",
                       SensorLocation("front", "", position_mm),
                       Calibration(TEMPERATURE_SCALE_K, TEMPERATURE_OFFSET_K, lo, hi), 0.0,
                       {"sensor": "PT100 on the front bearing's outer ring",
                        "note": "one reading per record, held over the record"})


def with_temperature(rec: Record, temperature_K: float, sensors: SensorSet,
                     position_mm: float) -> Record:
    """The steady record ``rec`` as a ``soak`` record: a temperature channel holding
    ``temperature_K`` over the record (counts as the converter's other channels: rounded when
    ``sensors.quantised``, clipped at its limits).

    >>> import numpy as np
    >>> from surrogate_rbrdo.rig.records import Record
    >>> rec = Record("r", "steady", 1e3, (), np.zeros((0, 4), np.int16), speed_rpm=6e3)
    >>> soak = with_temperature(rec, 300.0, SensorSet(), 0.0)
    >>> soak.kind, soak.values("T_front").tolist()
    ('soak', [300.0, 300.0, 300.0, 300.0])
    """
    spec = temperature_channel(sensors, position_mm)
    lo, hi = sensors.daq.counts_limits
    c = (temperature_K - TEMPERATURE_OFFSET_K) / TEMPERATURE_SCALE_K
    c = float(np.clip(np.rint(c) if sensors.quantised else c, lo, hi))
    row = np.full((1, rec.n_samples), c, dtype=rec.data.dtype)
    return Record(rec.id, "soak", rec.sample_rate_hz, rec.channels + (spec,),
                  np.vstack([rec.data, row]), speed_rpm=rec.speed_rpm,
                  provenance=rec.provenance, events=rec.events)


def soak_jobs(plan: SoakPlan, done: set[str], b: int, tl: int
              ) -> list[tuple[int, tuple[int, ...]]]:
    """``(j, todo)`` of every soak run of build ``b``, tool ``tl`` with records not written
    yet (``done``: ids written)."""
    out = []
    for j in range(plan.runs):
        todo = tuple(k for k in range(len(plan.times_s)) if soak_id(b, tl, j, k) not in done)
        if todo:
            out.append((j, todo))
    return out
