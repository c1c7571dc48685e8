"""A measurement campaign on the virtual rig: options → dataset + 1x table + summary.

The paper's campaign by default: 50 speeds uniformly in 1 000–24 000 rpm × 20 repeats of 1 s
steady-state records, a run-up and a run-down, and impact tests at the tool tip (x and y).
Each repeat is one *run* (its own thermal state); builds and tool changes are nested around
runs. With ``soak`` (a :class:`~.thermal.SoakPlan`) each tool ends with a thermal soak: runs of
steady records at a speed held (by default two either side of the resonance, run by run) as
the spindle warms from a cold start (``rig.soak``). Records
stream to disk one run at a time (bounded memory); a campaign interrupted and started again
with the same options and seed skips every record already written.

>>> import numpy as np, tempfile
>>> from surrogate_rbrdo.rig.truth import reference_truth
>>> opts = CampaignOptions(speeds_rpm=(6000.0, 12000.0), repeats=2, duration_s=0.2,
...                        runup=None, impacts_per_direction=0)
>>> with tempfile.TemporaryDirectory() as d:
...     res = run_campaign(reference_truth(), opts, d, rng=np.random.default_rng(1))
...     res.n_records, sorted(res.phasors.columns)[:3]
(4, ['amplitude_m', 'build', 'channel'])
"""

from __future__ import annotations

import csv
import dataclasses
import json
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from joblib import Parallel, delayed

from surrogate_rbrdo.core.errors import ModelError
from surrogate_rbrdo.core.rng import require_rng
from surrogate_rbrdo.core.validate import check_int, check_positive
from surrogate_rbrdo.rig.demod import check_record_lengths, demodulate
from surrogate_rbrdo.rig.integrate import SpeedProfile, unbalance_pattern
from surrogate_rbrdo.rig.records import Record
from surrogate_rbrdo.rig.sensors import SensorSet
from surrogate_rbrdo.rig.simulate import (
    ImpactResponse,
    check_stable,
    impact_record,
    impact_response,
    runup_record,
    steady_records,
)
from surrogate_rbrdo.rig.soak import (
    soak_id,
    soak_jobs,
    soak_labels,
    soak_plan,
    soak_run,
    sweep_probe_rise,
)
from surrogate_rbrdo.rig.statespace import (
    Reduction,
    first_order,
    reduction,
    require_stable,
)
from surrogate_rbrdo.rig.store import DatasetWriter, read_record
from surrogate_rbrdo.rig.thermal import SoakPlan
from surrogate_rbrdo.rig.truth import Truth, _child
from surrogate_rbrdo.spindle.assembly import RPM
from surrogate_rbrdo.spindle.geometry import Unbalance

Progress = Callable[[int, int, str], None]


def _default_speeds() -> tuple[float, ...]:
    return tuple(np.linspace(1000.0, 24000.0, 50).tolist())


@dataclass(frozen=True)
class SpeedGrid:
    """``num`` speeds uniformly from ``start`` to ``stop`` rpm (``numpy.linspace``): the
    config form ``speeds_rpm = { start = 1000.0, stop = 24000.0, num = 50 }``.

    >>> SpeedGrid(1000.0, 3000.0, 3).speeds()
    (1000.0, 2000.0, 3000.0)
    """

    start: float
    stop: float
    num: int

    def __post_init__(self) -> None:
        check_positive("start", self.start)
        check_int("num", self.num, minimum=1)
        if not (self.stop > self.start or (self.num == 1 and self.stop == self.start)):
            raise ValueError(f"stop = {self.stop} is not allowed: must be > start = "
                             f"{self.start}")

    def speeds(self) -> tuple[float, ...]:
        return tuple(np.linspace(self.start, self.stop, self.num).tolist())


@dataclass(frozen=True)
class CampaignOptions:
    """What to measure (defaults: the paper's campaign; see ``docs/rig.md``).

    ``speeds_rpm``: the steady-state speeds, a list or a :class:`SpeedGrid`; ``runup``:
    ``(start_rpm, end_rpm, duration_s)`` of the run-up (and the reverse run-down if
    ``rundown``), ``None`` or ``()`` (``runup = []`` in a config) for none; impacts: hits per
    direction (x, y) at the tool tip, at each of ``impact_speeds_rpm`` (default standstill
    only; a speed > 0 is an impact test on the running spindle, ``rig.impacts``), all in the
    tool's first run.
    ``trial_unbalance``: ``(position_mm, magnitude_kgm, phase_deg)`` of a known trial mass;
    every run then measures each speed twice, without and with it (record ids ``..._trial``,
    label ``trial = 1``, the mass in the record's ``provenance["test_setup"]``): the
    difference isolates a known excitation (influence-coefficient practice, ISO 21940-13).
    ``soak``: a thermal soak after each tool's other records (:class:`~.thermal.SoakPlan`,
    ``rig.soak``; its speeds not given: by its rule from that tool's sweep), or None for
    none.
    """

    speeds_rpm: tuple[float, ...] | SpeedGrid = field(default_factory=_default_speeds)
    repeats: int = 20
    duration_s: float = 1.0
    builds: int = 1
    tools_per_build: int = 1
    runup: tuple[float, float, float] | tuple[()] | None = (1000.0, 24000.0, 10.0)
    rundown: bool = True
    impacts_per_direction: int = 5
    impact_duration_s: float = 1.0
    impact_speeds_rpm: tuple[float, ...] = (0.0,)
    sensors: SensorSet = SensorSet()
    trial_unbalance: tuple[float, float, float] | None = None
    soak: SoakPlan | None = None

    def __post_init__(self) -> None:
        if isinstance(self.speeds_rpm, SpeedGrid):
            object.__setattr__(self, "speeds_rpm", self.speeds_rpm.speeds())
        sp = np.asarray(self.speeds_rpm, float)
        if sp.ndim != 1 or sp.size == 0 or np.any(sp <= 0) or np.any(np.diff(sp) <= 0):
            raise ValueError(f"speeds_rpm = {self.speeds_rpm} is not allowed: a strictly "
                             "increasing list of speeds > 0")
        object.__setattr__(self, "speeds_rpm", tuple(sp.tolist()))
        for n in ("repeats", "builds", "tools_per_build"):
            check_int(n, getattr(self, n), minimum=1)
        check_int("impacts_per_direction", self.impacts_per_direction, minimum=0)
        isp = tuple(float(s) for s in self.impact_speeds_rpm)
        if not isp or len(set(isp)) != len(isp) or min(isp) < 0:
            raise ValueError(f"impact_speeds_rpm = {list(self.impact_speeds_rpm)} is not "
                             "allowed: distinct speeds >= 0 rpm (0: standstill), at least one")
        object.__setattr__(self, "impact_speeds_rpm", isp)
        check_positive("duration_s", self.duration_s)
        check_positive("impact_duration_s", self.impact_duration_s)
        if self.runup == ():
            object.__setattr__(self, "runup", None)
        if self.runup is not None:
            a, b, d = self.runup
            if not (0 < a < b <= 1e6 and 0 < d <= 1e5):
                raise ValueError(f"runup = {self.runup} is not allowed: need 0 < start_rpm < "
                                 "end_rpm <= 1e6 and 0 < duration_s <= 1e5")
            object.__setattr__(self, "runup", (float(a), float(b), float(d)))
        # the sample rate is checked with the final sensors (run_campaign, [rig] RigTable)
        check_record_lengths(self.duration_s, self.speeds_rpm + soak_speed(self), None,
                             self.runup, self.impact_duration_s)
        if self.trial_unbalance is not None:
            pos, U, ph = (float(v) for v in self.trial_unbalance)
            # a trial mass is a few grams at the rotor's radius: 1e-2 kg m is 100 g at 100 mm
            if not (abs(pos) <= 1e4 and abs(ph) <= 360.0 and 0 < U <= 1e-2):
                raise ValueError(f"trial_unbalance = {list(self.trial_unbalance)} is not "
                                 "allowed: need (position_mm in [-1e4, 1e4], magnitude_kgm in "
                                 "(0, 1e-2], phase_deg in [-360, 360])")
            object.__setattr__(self, "trial_unbalance", (pos, U, ph))

    def to_dict(self) -> dict[str, Any]:
        return dataclasses.asdict(self)


@dataclass(frozen=True)
class PhasorTable:
    """The demodulated 1x phasors of every steady record (one row per record and channel)."""

    columns: tuple[str, ...]
    rows: tuple[tuple[Any, ...], ...]

    def array(self, name: str) -> np.ndarray:
        i = self.columns.index(name)
        return np.array([r[i] for r in self.rows])


@dataclass(frozen=True)
class CampaignResult:
    """Where the dataset is, the 1x table, counts and timings."""

    root: Path
    dataset: Path
    phasors: PhasorTable
    n_records: int
    n_written: int
    seconds: float
    ramps: tuple[str, ...]
    impacts: tuple[str, ...]
    soaks: tuple[str, ...] = ()


PHASOR_COLUMNS = ("record", "build", "tool", "run", "speed_rpm", "measured_speed_rpm",
                  "channel", "amplitude_m", "phase_deg", "re_m", "im_m")


def run_campaign(truth: Truth, options: CampaignOptions, out_dir: str | Path, *,
                 rng: np.random.Generator, progress: Progress | None = None,
                 n_jobs: int = 1) -> CampaignResult:
    """Simulate the campaign into ``out_dir/dataset`` (resumable) and write ``phasors.csv`` and
    ``summary.json`` into ``out_dir``. ``n_jobs`` worker processes (joblib) simulate the
    steady records (a run at a time, with its stability check and 1x phasors, while this
    process writes the runs made) and the ramps; every record draws from its own seeded
    stream, so the files do not depend on it. The impact records are made here: the hits of
    one speed and direction share one simulation (:class:`~.simulate.ImpactResponse`, the
    model is linear in the hit's peak force). With ``options.soak``, each tool's soak records
    are made here too, a soak run at a time (``rig.soak``: a few records, ~10 ms each)."""
    require_rng(rng)
    check_int("n_jobs", n_jobs, minimum=1)
    check_record_lengths(options.duration_s, options.speeds_rpm + soak_speed(options),
                         options.sensors.daq.sample_rate_hz, options.runup)
    t_start = time.perf_counter()
    out = Path(out_dir)
    root_ss = _root_seed(rng)
    sens = options.sensors
    inst = sens.install(np.random.default_rng(_child(root_ss, 9)))
    writer = DatasetWriter(out / "dataset", {
        "title": "virtual rig campaign", "truth": truth.describe(),
        "campaign": options.to_dict(), "installation": inst.to_dict(),
        "seed": {"entropy": str(root_ss.entropy), "spawn_key": list(root_ss.spawn_key)}})
    done = writer.done()
    n_steady = options.builds * options.tools_per_build * options.repeats * len(
        options.speeds_rpm) * (1 if options.trial_unbalance is None else 2)
    total = n_steady + _n_extra(options)
    rows: list[tuple[Any, ...]] = []
    count = written = 0
    ramps, impacts, soaks = [], [], []
    for b in range(options.builds):
        for tl in range(options.tools_per_build):
            st0 = truth.state(root_ss, build=b, tool=tl, run=0)
            red = _precheck(st0, options)
            plans = [_run_plan(options, done, b, tl, r) for r in range(options.repeats)]
            # on workers the runs start now, while this process checks the truth's stability
            # (nothing is written before it passes; one process makes them after it)
            runs = _steady_runs((truth, options, inst, root_ss, red, b, tl), plans, n_jobs)
            check_stable(st0.model(), st0.theta, stability_speeds(options))
            sweep = np.zeros((options.repeats, len(options.speeds_rpm)))  # largest |1x|
            for r, made_run in enumerate(runs):
                for trial, ids, new in made_run:
                    for i, rid in enumerate(ids):
                        if rid in new:
                            rec, rec_rows = new[rid]
                            labels = {"build": b, "tool": tl, "run": r, "repeat": r,
                                      "speed_index": i}
                            writer.write(rec, labels={**labels, "trial": 1} if trial
                                         else labels)
                            written += 1
                        else:
                            rec_rows = _phasor_rows(
                                read_record(writer.root / f"records/{rid}.npz"), b, tl, r)
                        rows += rec_rows
                        if not trial:
                            sweep[r, i] = max(row[7] for row in rec_rows)   # amplitude_m
                        count += 1
                        if progress:
                            progress(count, total, rid)
            extras = _extras(truth, st0, options, inst, root_ss, b, tl)
            made = _made([make for rec_id, make in extras
                          if rec_id not in done and "_hit" not in rec_id], n_jobs)
            for rec_id, make in extras:
                kind = "impact" if "_hit" in rec_id else "ramp"
                (impacts if kind == "impact" else ramps).append(rec_id)
                if rec_id not in done:
                    rec = make() if kind == "impact" else next(made)
                    writer.write(rec, labels={"build": b, "tool": tl, "run": 0})
                    written += 1
                count += 1
                if progress:
                    progress(count, total, rec_id)
            if options.soak is not None:
                plan = soak_plan(options.soak, options.speeds_rpm, sweep)
                common = (truth, options, inst, root_ss, red, b, tl, plan,
                          lambda st, r, b=b, tl=tl: _provenance(truth, st, inst, root_ss, b,
                                                                tl, r))
                jobs = dict(soak_jobs(plan, done, b, tl))
                for j in range(plan.runs):        # a run's records made, then written
                    new = soak_run(common, j, jobs[j]) if j in jobs else {}
                    for k in range(len(plan.times_s)):
                        rid = soak_id(b, tl, j, k)
                        if rid in new:
                            writer.write(new.pop(rid), labels=soak_labels(
                                plan, b, tl, options.repeats, j, k))
                            written += 1
                        soaks.append(rid)
                        count += 1
                        if progress:
                            progress(count, total, rid)
    table = PhasorTable(PHASOR_COLUMNS, tuple(rows))
    _write_csv(out / "phasors.csv", table)
    secs = time.perf_counter() - t_start
    summary = {"n_records": count, "n_written_this_call": written, "seconds": secs,
               "n_steady": n_steady, "ramps": ramps, "impacts": impacts, "soak": soaks}
    writer.finish(summary)
    (out / "summary.json").write_text(json.dumps(summary, indent=2))
    return CampaignResult(out, writer.root, table, count, written, secs, tuple(ramps),
                          tuple(impacts), tuple(soaks))


def _root_seed(rng: np.random.Generator) -> np.random.SeedSequence:
    """The campaign's root seed: a child spawned from ``rng`` (so the generator's state
    matters: the same generator passed twice gives two campaigns; a fresh
    ``default_rng(seed)`` gives the same one again, which is how a campaign resumes)."""
    try:
        return rng.spawn(1)[0].bit_generator.seed_seq
    except (TypeError, AttributeError) as exc:
        raise ValueError(f"rng = {rng!r} is not allowed: its bit generator has no seed "
                         "sequence to spawn from; pass numpy.random.default_rng(seed)") from exc


def _precheck(st, o: CampaignOptions) -> Reduction:
    """Before any record: the truth's time-domain model builds (massless DOFs, joints) and is
    stable where the ramps go; returns the Ritz basis the per-run checks use."""
    model = st.model()
    n = model.system_matrices(0.0, st.theta)[0].shape[0]
    loads = unbalance_pattern(model, n)[:, None]
    sp = np.asarray(stability_speeds(o))
    red = reduction(model, st.theta, np.array([sp.min(), sp.max()]) * RPM, loads, 5_000.0)
    first_order(model, st.theta, 0.0, red)              # standstill (impacts) builds too
    return red


def _check_run(st, o: CampaignOptions, red: Reduction, b: int, tl: int, r: int) -> None:
    """Each run's own truth (its thermal draw) must be stable at the campaign's speeds."""
    require_stable(st.model(), st.theta, o.speeds_rpm, red,
                   f"the truth of build {b}, tool {tl}, run {r}",
                   "its thermal preload draw; cross-coupling too strong?")


def soak_speed(o: CampaignOptions) -> tuple[float, ...]:
    """The soak's speeds when given (else they are among ``speeds_rpm``)."""
    return () if o.soak is None else o.soak.speeds


def stability_speeds(o: CampaignOptions) -> np.ndarray:
    """Speeds at which the truth must be stable: the campaign's speeds (with the impacts' and
    a soak's) and the ramp's range."""
    sp = list(o.speeds_rpm) + [s for s in o.impact_speeds_rpm if s > 0] + list(soak_speed(o))
    if o.runup is not None:
        sp += np.linspace(o.runup[0], o.runup[1], 12).tolist()
    return np.unique(sp)


@dataclass(frozen=True)
class Footprint:
    """What a campaign writes and holds (an estimate, made before any work).

    Disk: every record's samples (``daq.bits`` ≤ 16: 2 bytes, else 4) plus ~24 kB of
    metadata (its provenance), and ``phasors.csv``. Memory above the interpreter's: the
    largest of one run's steady records (all its speeds are held until written, ~128 bytes
    per channel and sample of temporaries besides; a soak run's records likewise, with their
    temperature channel), one ramp (~96 bytes per channel and
    sample: integration, driver filter in the frequency domain) and one impact (integrated at
    4x the sample rate), plus 128 MB for what the report loads. Those per-sample costs were
    measured with ``resource.getrusage`` (``benchmarks/bench_rig.py`` prints the estimate
    beside the measured peak).
    """

    n_records: int
    disk_bytes: float
    memory_bytes: float
    memory_by: str      # the option sizing the memory: duration_s, runup, impact_duration_s


def footprint(options: CampaignOptions) -> Footprint:
    """The :class:`Footprint` of a campaign.

    >>> f = footprint(CampaignOptions())     # the paper's campaign
    >>> f.n_records, round(f.disk_bytes / 1e6), round(f.memory_bytes / 1e6), f.memory_by
    (1012, 169, 195, 'runup')
    """
    o, daq = options, options.sensors.daq
    n_ch = len(o.sensors.probe_channels) + 1
    item = np.dtype(daq.dtype).itemsize
    n_s = round(o.duration_s * daq.sample_rate_hz)
    n_r = 0 if o.runup is None else round(o.runup[2] * daq.sample_rate_hz)
    n_i = round(o.impact_duration_s * daq.sample_rate_hz)
    per_tool = o.builds * o.tools_per_build
    steady = per_tool * o.repeats * len(o.speeds_rpm) * (1 + (o.trial_unbalance is not None))
    ramps = per_tool * (0 if o.runup is None else 1 + o.rundown)
    hits = per_tool * 2 * o.impacts_per_direction * len(o.impact_speeds_rpm)
    n_k = 0 if o.soak is None else len(o.soak.times_s)
    soaks = per_tool * (0 if o.soak is None else o.soak.runs * n_k)
    meta = 24e3
    disk = (steady * (n_ch * n_s * item + meta + 160.0 * (n_ch - 1))
            + ramps * (n_ch * n_r * item + meta) + hits * (n_ch * n_i * item + meta)
            + soaks * ((n_ch + 1) * n_s * item + meta))
    held = max(len(o.speeds_rpm) * n_ch, n_k * (n_ch + 1))      # channels x records at once
    memory = {"duration_s": n_s * (held * item + 128.0 * n_ch),
              "runup": n_ch * n_r * 96.0, "impact_duration_s": n_ch * 4 * n_i * 48.0 * (hits > 0)}
    by = max(memory, key=memory.get)
    return Footprint(steady + ramps + hits + soaks, float(disk), memory[by] + 128e6, by)


def _n_extra(o: CampaignOptions) -> int:
    per_tool = (0 if o.runup is None else 1 + o.rundown) + (
        2 * o.impacts_per_direction * len(o.impact_speeds_rpm)) + (
        0 if o.soak is None else o.soak.runs * len(o.soak.times_s))
    return o.builds * o.tools_per_build * per_tool


def _provenance(truth, st, inst, root_ss, b, tl, r) -> dict[str, Any]:
    """What every record carries: the truth's effects (model and hidden) with parameters, the
    draws of its build/tool/run, θ, the sensors' hidden installation errors and the seed."""
    d = truth.describe()
    return {"source": "surrogate_rbrdo virtual rig", "build": b, "tool": tl, "run": r,
            "truth_effects": d["effects"], "hidden_effects": d["hidden"],
            "truth_draws": st.draws, "theta": st.theta[0].tolist(),
            "sensor_installation": inst.to_dict(), "seed_entropy": str(root_ss.entropy),
            "seed_spawn_key": list(root_ss.spawn_key)}


def _run_plan(options: CampaignOptions, done: set[str], b: int, tl: int, r: int
              ) -> tuple[int, tuple[tuple[bool, tuple[str, ...], tuple[int, ...]], ...]]:
    """Run ``r`` of build ``b``, tool ``tl``: ``(r, ((trial, ids, todo), ...))``, the ids of
    its steady records without and (with a trial mass) with the trial mass, and the indices
    of those not written yet."""
    out = []
    for trial in (False, True) if options.trial_unbalance else (False,):
        ids = tuple(f"b{b}_t{tl}_r{r:02d}_s{i:02d}" + ("_trial" if trial else "")
                    for i in range(len(options.speeds_rpm)))
        out.append((trial, ids, tuple(i for i, rid in enumerate(ids) if rid not in done)))
    return r, tuple(out)


def _steady_run(common: tuple, plan: tuple) -> list[tuple[bool, tuple[str, ...], dict]]:
    """One run's steady records not written yet, each with its 1x phasor rows: the run's
    truth state, its stability check (:func:`_check_run`) and the records of every speed
    (``common``: truth, options, installation, root seed, reduction, build, tool)."""
    truth, options, inst, root_ss, red, b, tl = common
    r, parts = plan
    st = truth.state(root_ss, build=b, tool=tl, run=r)
    _check_run(st, options, red, b, tl, r)
    out = []
    for trial, ids, todo in parts:
        new = _steady(truth, st, options, inst, root_ss, list(ids), list(todo), b, tl, r,
                      trial) if todo else {}
        out.append((trial, ids, {rid: (rec, _phasor_rows(rec, b, tl, r))
                                 for rid, rec in new.items()}))
    return out


def _steady_runs(common: tuple, plans: list[tuple], n_jobs: int):
    """:func:`_steady_run` of every run, in order: here, one run at a time, or on ``n_jobs``
    joblib worker processes (loky) a few runs at a time (``pre_dispatch``: bounded memory)
    while this process writes the runs already made. Every record draws from its own seeded
    stream (:func:`_steady`), so the records are the same either way."""
    if n_jobs == 1 or len(plans) < 2:
        return (_steady_run(common, p) for p in plans)
    return _raising(Parallel(n_jobs=min(n_jobs, len(plans)), return_as="generator",
                             pre_dispatch="2 * n_jobs")(
        delayed(_run_or_error)(common, p) for p in plans))


def _run_or_error(common: tuple, plan: tuple):
    """:func:`_steady_run` on a worker, its ``ModelError`` (an unstable run) returned rather
    than raised: a raise would abort the runs before it that are made but not yet written."""
    try:
        return _steady_run(common, plan)
    except ModelError as exc:
        return exc


def _raising(results: Iterable):
    """The runs' results in order, the first failed one raised where it comes — after every
    run before it has been handed on (written), and naming that run, as one process would.

    >>> list(_raising([1, 2]))
    [1, 2]
    """
    for res in results:
        if isinstance(res, ModelError):
            raise res
        yield res


def _steady(truth, st, options, inst, root_ss, ids, todo, b, tl, r, trial=False
            ) -> dict[str, Record]:
    sp = np.asarray(options.speeds_rpm)[todo]
    key = 6 if trial else 3                      # trial records draw from their own streams
    rngs = [np.random.default_rng(_child(root_ss, key, b, tl, r, i)) for i in todo]
    base = _provenance(truth, st, inst, root_ss, b, tl, r)
    if trial:
        pos, U, ph = options.trial_unbalance
        base["test_setup"] = {"trial_unbalance": {"position_mm": pos, "magnitude_kgm": U,
                                                  "phase_deg": ph}}
        g = st.geometry
        st = dataclasses.replace(st, geometry=dataclasses.replace(
            g, unbalances=g.unbalances + (Unbalance(pos, U, ph),)))
    prov = [{**base, "seed_key": [key, b, tl, r, i]} for i in todo]
    rise = sweep_probe_rise(truth, options.sensors.probe, sp)
    recs = steady_records(st.model(), st.theta, sp, options.sensors, inst, rngs,
                          duration_s=options.duration_s, ids=[ids[i] for i in todo],
                          provenance=prov, probe_rise_K=rise)
    return {rec.id: rec for rec in recs}


def _extras(truth, st, options, inst, root_ss, b, tl):
    """(id, thunk) of the run-up/run-down and impact records of one tool (on its run 0); the
    impact thunks of one speed and direction share one simulation (made by the first)."""
    model = st.model()
    base = _provenance(truth, st, inst, root_ss, b, tl, 0)
    out = []
    if options.runup is not None:
        a, e, d = options.runup
        ramps = [("runup", a, e)] + ([("rundown", e, a)] if options.rundown else [])
        for k, (name, s0, s1) in enumerate(ramps):
            rid = f"b{b}_t{tl}_{name}"
            out.append((rid, lambda s0=s0, s1=s1, rid=rid, k=k: runup_record(
                model, st.theta, SpeedProfile.ramp(s0, s1, d), options.sensors, inst,
                np.random.default_rng(_child(root_ss, 4, b, tl, k)), rid=rid,
                provenance={**base, "seed_key": [4, b, tl, k]})))
    shared: dict[tuple[float, str], ImpactResponse] = {}

    def response(speed: float, direction: str) -> ImpactResponse:
        if (speed, direction) not in shared:       # simulated once, at the first hit made
            shared[speed, direction] = impact_response(
                model, st.theta, options.sensors, inst, direction=direction,
                duration_s=options.impact_duration_s, speed_rpm=speed)
        return shared[speed, direction]

    for k, speed in enumerate(options.impact_speeds_rpm):
        # standstill hits keep their ids and seeds; hits at speed are named by it
        tag, key = ("", ()) if speed == 0 else (f"_{speed:.0f}rpm", (k,))
        for di, direction in enumerate(("x", "y")):
            for h in range(options.impacts_per_direction):
                rid = f"b{b}_t{tl}_hit_{direction}{h}{tag}"
                sk = (5, b, tl, di, h) + key
                out.append((rid, lambda rid=rid, sk=sk, direction=direction, speed=speed:
                            impact_record(model, st.theta, options.sensors, inst,
                                          np.random.default_rng(_child(root_ss, *sk)), rid=rid,
                                          provenance={**base, "seed_key": list(sk)},
                                          direction=direction,
                                          duration_s=options.impact_duration_s,
                                          speed_rpm=speed,
                                          response=response(speed, direction))))
    return out


def _made(thunks: list[Callable[[], Record]], n_jobs: int):
    """The records the ``thunks`` make, in order: here, or on ``n_jobs`` joblib worker
    processes (loky) a few at a time (bounded memory). Each thunk draws from its own
    seeded generator, so the records are the same either way."""
    if n_jobs == 1 or len(thunks) < 2:
        return (make() for make in thunks)
    return iter(Parallel(n_jobs=min(n_jobs, len(thunks)), return_as="generator")(
        delayed(make)() for make in thunks))


def _phasor_rows(rec: Record, b: int, tl: int, r: int) -> list[tuple[Any, ...]]:
    p = demodulate(rec)
    rows = []
    for j, ch in enumerate(p.channels):
        X = p.X[j, 0]
        rows.append((rec.id, b, tl, r, rec.speed_rpm, p.speed_rpm, ch, abs(X),
                     float(np.degrees(np.angle(X))), X.real, X.imag))
    return rows


def read_phasors(path: str | Path) -> PhasorTable:
    """Read a campaign's ``phasors.csv`` back (numbers as floats/ints, names as str)."""
    with open(path, newline="") as fh:
        rows = list(csv.reader(fh))
    cols = tuple(rows[0])
    if cols != PHASOR_COLUMNS:
        raise ValueError(f"{path}: header {list(cols)} is not a phasor table "
                         f"{list(PHASOR_COLUMNS)}")
    ints = {"build", "tool", "run"}
    conv = [str if c in ("record", "channel") else int if c in ints else float for c in cols]
    return PhasorTable(cols, tuple(tuple(f(v) for f, v in zip(conv, r, strict=True))
                                   for r in rows[1:]))


def _write_csv(path: Path, table: PhasorTable) -> None:
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(table.columns)
        w.writerows(table.rows)
