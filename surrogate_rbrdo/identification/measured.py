"""1× phasors of a measured-data folder, with what the experimenter knows corrected.

:func:`measured_phasors` opens a dataset (the virtual rig's campaign or a user's own folder in
the measured-data format, ``docs/measured-data.md``), demodulates every steady record
(:func:`surrogate_rbrdo.rig.demod.demodulate`: keyphasor → shaft angle, least-squares DC + 1×
over whole revolutions, each channel at its own known sampling delay) and corrects what a real
experimenter knows (:class:`SensorCorrections`):

* the probe driver's **low-pass** from its datasheet (first order, ``probe_bandwidth_hz``):
  ``X ← X (1 + i f/f_c)``. Its unit-to-unit scatter (the rig draws ±10 %) is not known;
* the probes' **calibration sheets** (``gains``: measured/true sensitivity per channel); the
  rig's residual gain error (2 %, *after* calibration on the shaft material) is not known;
* the **keyphasor's angular position** relative to the angle reference of the trial mass
  (``keyphasor_angle_deg``; 0 on the rig by construction): ``X ← X e^{−i angle}``;
* the keyphasor's **edge-interpolation error** of a *sampled* keyphasor (a whole number of
  samples per revolution): the phase is refined on the pulse's own shape (:mod:`.keyphasor`),
  with its standard error. A record whose keyphasor edges are counter timestamps
  (``events["keyphasor"]``, the rig's default) is not refined: its edges are already exact to
  the timebase and the trigger jitter, and refitting them on the sampled pulse would replace
  exact edges by the template's interpolation error (noise-free at 24 000 rpm it moved c by
  71 %; ``docs/identification.md`` §3).

What stays hidden: the channels' timing skew, the residual gain and bandwidth errors and the
keyphasor's edge-interpolation phase error (``docs/rig.md``); what they do to the identified
coefficients is measured by ``benchmarks/bench_identification_rig.py``.

Noise: each phasor's noise standard deviation (real and imaginary part) is estimated from the
record itself, ``s = RMS(residual) √(2/N)`` with ``N`` the samples in the whole revolutions
(white noise; the convention of ``rig.phasors.phasor_noise_sd``).

Which excitation the phasors answer (trial-weight differences or a stated unbalance) is
:mod:`.responses`' job.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from joblib import Parallel, delayed

from surrogate_rbrdo.core.validate import check_finite, check_int, check_positive
from surrogate_rbrdo.identification.keyphasor import (
    MAX_GAP,
    SEARCH_GAP,
    SEARCH_RAD,
    TWO_PI,
    pulse_template,
    refine_phase,
    sample_phase_gap,
    template_crossing,
)
from surrogate_rbrdo.rig.demod import keyphasor_edges
from surrogate_rbrdo.rig.keyphasor import polarity_of
from surrogate_rbrdo.rig.records import Record, RecordError
from surrogate_rbrdo.rig.store import Dataset, open_dataset, read_record


@dataclass(frozen=True)
class SensorCorrections:
    """What the experimenter knows about the measurement chain (module docstring).

    Parameters
    ----------
    probe_bandwidth_hz : float or None
        −3 dB frequency of the probe drivers' first-order low-pass (datasheet); ``None``: no
        correction.
    gains : mapping channel → float
        Calibration-sheet ratio of each channel's true to nominal sensitivity (1 if absent).
    keyphasor_angle_deg : float
        Angle of the keyphasor mark from the angle reference of the unbalance phases.
    """

    probe_bandwidth_hz: float | None = 10_000.0
    gains: Mapping[str, float] = field(default_factory=dict)
    keyphasor_angle_deg: float = 0.0

    def __post_init__(self) -> None:
        if self.probe_bandwidth_hz is not None:
            check_positive("probe_bandwidth_hz", self.probe_bandwidth_hz)
        for k, v in dict(self.gains).items():
            check_positive(f"gains[{k!r}]", v)
        check_finite("keyphasor_angle_deg", self.keyphasor_angle_deg)
        object.__setattr__(self, "gains", dict(self.gains))

    def factor(self, channel: str, speed_rpm: np.ndarray) -> np.ndarray:
        """The complex factor that turns a demodulated phasor into the corrected one."""
        f = np.asarray(speed_rpm, float) / 60.0
        out = np.exp(-1j * np.radians(self.keyphasor_angle_deg)) / self.gains.get(channel, 1.0)
        if self.probe_bandwidth_hz is not None:
            out = out * (1.0 + 1j * f / self.probe_bandwidth_hz)
        return out * np.ones_like(f)

    def to_dict(self) -> dict:
        return {"probe_bandwidth_hz": self.probe_bandwidth_hz, "gains": dict(self.gains),
                "keyphasor_angle_deg": self.keyphasor_angle_deg}


@dataclass(frozen=True, eq=False)
class MeasuredPhasors:
    """Corrected 1× phasors of the steady records of a dataset (one row per record).

    ``labels`` are the dataset index labels of each record (``repeat``, ``run``, ``trial``…),
    ``positions_mm`` the axial position of each probe channel, ``test_setup`` each record's
    known test set-up (``provenance["test_setup"]``, e.g. its trial mass), or ``{}``;
    ``phase_sd`` the standard error (rad) of each record's keyphasor phase (0 if not refined)
    and ``phase_shift`` the refinement applied.
    """

    record_ids: tuple[str, ...]
    speed_rpm: np.ndarray
    measured_speed_rpm: np.ndarray
    labels: tuple[Mapping, ...]
    channels: tuple[str, ...]
    positions_mm: np.ndarray
    phasors: np.ndarray
    phasor_sd: np.ndarray
    test_setup: tuple[Mapping, ...]
    corrections: SensorCorrections
    phase_sd: np.ndarray
    phase_shift: np.ndarray
    source: str = ""

    @property
    def n_records(self) -> int:
        return len(self.record_ids)

    def select(self, rows: np.ndarray) -> MeasuredPhasors:
        """The records ``rows`` (indices or a boolean mask)."""
        idx = np.arange(self.n_records)[rows]
        return MeasuredPhasors(
            tuple(self.record_ids[i] for i in idx), self.speed_rpm[idx],
            self.measured_speed_rpm[idx], tuple(self.labels[i] for i in idx), self.channels,
            self.positions_mm, self.phasors[idx], self.phasor_sd[idx],
            tuple(self.test_setup[i] for i in idx), self.corrections, self.phase_sd[idx],
            self.phase_shift[idx], self.source)


def probe_channels(rec: Record, targets: Sequence[str] | None) -> tuple[str, ...]:
    chans = [c for c in rec.channels if c.quantity == "displacement"
             and c.location.direction in ("x", "y")
             and (targets is None or c.location.target in targets)]
    if targets is not None:
        missing = [t for t in targets if not any(c.location.target == t for c in chans)]
        if missing:
            raise RecordError(f"record {rec.id!r}", "channels",
                              f"no x/y displacement probe at target(s) {missing}")
    # x before y at each target, targets in the order given (else in record order)
    order = list(targets) if targets is not None else list(
        dict.fromkeys(c.location.target for c in chans))
    chans.sort(key=lambda c: (order.index(c.location.target), c.location.direction))
    return tuple(c.name for c in chans)


@dataclass(frozen=True)
class _Demodulated:
    """One record: speed, 1× phasors and their noise, test set-up, and its keyphasor samples
    with the shaft angle line ``φ = 2π (t − t0) / T`` (kept for the phase refinement)."""

    speed_rpm: float
    X: np.ndarray
    sd: np.ndarray
    setup: dict
    kp: np.ndarray
    kp_times: np.ndarray
    t0: float
    period: float
    gap: float
    counter: bool = False
    polarity: str = "positive"

    def angles(self) -> np.ndarray:
        return TWO_PI * (self.kp_times - self.t0) / self.period


def _demodulate_one(rec: Record, channels: tuple[str, ...]) -> _Demodulated:
    """:func:`rig.demod.demodulate`'s steps (keyphasor edges → least-squares angle line → DC +
    1× over whole revolutions at each channel's own sample times, :func:`fit_1x`), keeping the
    angle line and the sample count for the noise estimate and the keyphasor refinement."""
    edges = keyphasor_edges(rec)
    if edges.size < 4:
        raise RecordError(f"record {rec.id!r}", "keyphasor",
                          f"{edges.size} pulses: demodulation needs at least 3 revolutions")
    period, t0 = np.polyfit(np.arange(edges.size), edges, 1)
    delays = np.array([rec.channel(n).delay_s for n in channels])
    tc = rec.time_s[None, :] + delays[:, None]
    use = np.all((tc >= edges[0]) & (tc < edges[-1]), axis=0)
    Y = np.stack([rec.values(n)[use] for n in channels])
    base = TWO_PI * (rec.time_s[use] - t0) / period               # one angle, shifted per channel
    c0, s0 = np.cos(base), np.sin(base)
    dc, ds = np.cos(TWO_PI * delays / period), np.sin(TWO_PI * delays / period)
    X, res = _fit_1x_cs(Y, c0 * dc[:, None] - s0 * ds[:, None], c0 * ds[:, None] + s0 * dc[:, None])
    kp = rec.channel("keyphasor")
    counter = "keyphasor" in rec.events
    return _Demodulated(60.0 / period, X, res * np.sqrt(2.0 / use.sum()),
                        dict(rec.provenance.get("test_setup", {})),
                        rec.values("keyphasor").astype(np.float32), rec.time_s + kp.delay_s,
                        float(t0), float(period),
                        sample_phase_gap(60.0 / period, rec.sample_rate_hz, edges.size - 1),
                        counter, "positive" if counter else polarity_of(
                            rec.values("keyphasor"), kp.info.get("polarity")))


def measured_phasors(source: str | Path | Dataset, *, targets: Sequence[str] | None = (
        "front", "rear"), corrections: SensorCorrections = SensorCorrections(),
        refine_keyphasor: bool = True, n_jobs: int = 1) -> MeasuredPhasors:
    """Demodulate and correct every steady record of a dataset.

    Parameters
    ----------
    source : path or Dataset
        A dataset folder (``dataset.json``, ``index.jsonl``, ``records/``) or a rig campaign
        folder holding one in ``dataset/``.
    targets : sequence of str or None
        Probe targets to use (their ``x`` and ``y`` channels), default the bearing planes
        ``front`` and ``rear``; ``None``: every displacement probe.
    corrections : SensorCorrections
    refine_keyphasor : bool
        Refine the phase of each record with a *sampled* keyphasor on the pulse's shape
        (:mod:`.keyphasor`); records with counter timestamps are never refined.
    n_jobs : int
        Processes for the demodulation (joblib); 1 runs in this process.

    Raises
    ------
    RecordError
        A record that is unreadable, lacks a probe or its keyphasor, or has too few
        revolutions (names the file and the field).
    """
    ds = source if isinstance(source, Dataset) else open_dataset(dataset_root(source))
    rows = [r for r in ds.index if r["kind"] == "steady"]
    if not rows:
        raise RecordError(str(ds.root), "index", "no steady records to identify from")
    first = ds.load(rows[0])
    channels = probe_channels(first, targets)
    positions = np.array([first.channel(c).location.position_mm for c in channels])
    if np.any(~np.isfinite(positions)):
        raise RecordError(f"record {first.id!r}", "channels[].location.position_mm",
                          "unknown probe position: identification needs each probe's axial "
                          "position")
    out = _run(ds, rows, channels, n_jobs)
    shift, phase_sd, note = _refine(out, [r["file"] for r in rows]) if refine_keyphasor else (
        np.zeros(len(out)), np.zeros(len(out)), "keyphasor phase not refined")
    speed = np.array([float(r["speed_rpm"]) for r in rows])
    X = np.stack([o.X for o in out]) * np.exp(-1j * shift)[:, None]
    for j, c in enumerate(channels):
        X[:, j] = X[:, j] * corrections.factor(c, speed)
    sd = np.stack([o.sd for o in out]) * np.array(
        [1.0 / corrections.gains.get(c, 1.0) for c in channels])
    return MeasuredPhasors(
        tuple(r["id"] for r in rows), speed, np.array([o.speed_rpm for o in out]),
        tuple(dict(r.get("labels", {})) for r in rows), channels, positions, X, sd,
        tuple(o.setup for o in out), corrections, phase_sd, shift, f"{ds.root} ({note})")


def dataset_root(source: str | Path) -> Path:
    p = Path(source)
    return p / "dataset" if (p / "dataset" / "dataset.json").is_file() else p


def fit_1x(y: np.ndarray, angle: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Least squares ``y ≈ a₀ + Re(X e^{iφ})`` per row (``(C, N)``): ``X (C,)`` and the residual
    RMS — :func:`rig.demod.fit_orders` with ``orders=(1,)`` by its 3×3 normal equations built
    from sums (3× faster; equal to it to round-off, ``tests/identification``).

    >>> t = np.linspace(0, 1, 1000, endpoint=False)
    >>> ang = 2 * np.pi * 13.3 * t
    >>> X, res = fit_1x(np.real((2 - 1j) * np.exp(1j * ang))[None] + 0.5, ang[None])
    >>> np.round(X, 12), bool(res[0] < 1e-12)
    (array([2.-1.j]), True)
    """
    return _fit_1x_cs(y, np.cos(angle), np.sin(angle))


def _fit_1x_cs(y: np.ndarray, c: np.ndarray, s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`fit_1x` from ``cos φ`` and ``sin φ`` (``(C, N)`` each). ``y`` is centred first:
    the probe gap's DC is ~10⁴ times the signal, and the residual from sums would lose it."""
    s = -s
    y = y - y.mean(axis=-1, keepdims=True)
    n = np.full(y.shape[0], float(y.shape[1]))
    sc, ss = c.sum(-1), s.sum(-1)
    A = np.stack([np.stack([n, sc, ss], -1),
                  np.stack([sc, np.einsum("cn,cn->c", c, c), np.einsum("cn,cn->c", c, s)], -1),
                  np.stack([ss, np.einsum("cn,cn->c", c, s), np.einsum("cn,cn->c", s, s)], -1)],
                 -2)
    b = np.stack([y.sum(-1), np.einsum("cn,cn->c", c, y), np.einsum("cn,cn->c", s, y)], -1)
    coef = np.linalg.solve(A, b[..., None])[..., 0]
    ss_res = np.einsum("cn,cn->c", y, y) - np.einsum("ci,ci->c", coef, b)
    return coef[:, 1] + 1j * coef[:, 2], np.sqrt(np.maximum(ss_res, 0.0) / y.shape[1])


def _work(root: Path, files: list[str], channels: tuple[str, ...]) -> list[_Demodulated]:
    return [_demodulate_one(read_record(root / f), channels) for f in files]


#: the pulse template and its records' phases are refolded until the phases move less than this
SWEEP_TOL = 1e-9
MAX_SWEEPS = 30


def _refine(out: list[_Demodulated], files: Sequence[str], max_template_records: int = 100,
            max_sweeps: int = MAX_SWEEPS) -> tuple[np.ndarray, np.ndarray, str]:
    """Keyphasor phase refinement (:mod:`.keyphasor`) of every record whose edges come from
    the sampled keyphasor channel (counter-timed records keep their edges): shifts, standard
    errors and a note for the provenance.

    The template is folded on the records' angles, those records refitted on it, and the
    template folded again on the refitted angles until their phases change by less than
    ``SWEEP_TOL`` (alternating least squares of the pulse shape and the records' phases; the
    error falls ~3.5× per sweep): one fold on the edge angles alone kept their interpolation
    errors, up to ~5e-4 rad at 23 000 rpm, which blurred the template and put 3–7e-5 rad into
    records whose edges were exact to 1e-7 (c off by 1–5.5 % noise-free). The angle reference
    is the converged template's mid-swing crossing on its leading edge — the keyphasor's own
    definition of angle 0 — not the mean of the edges that built it. Then every record is
    refitted on the converged template."""
    check_int("max_sweeps", max_sweeps, minimum=1)
    shift, sd = np.zeros(len(out)), np.zeros(len(out))
    sampled = [i for i, o in enumerate(out) if not o.counter]
    if not sampled:
        return shift, sd, "keyphasor edges from counter timestamps (phase not refined)"
    good = [i for i in sampled if out[i].gap <= MAX_GAP]
    if len(good) < 3:
        return shift, sd, (
            "keyphasor phase not refined: fewer than 3 records whose samples drift through "
            "the revolution to learn the pulse shape from")
    pick = good[:: max(1, len(good) // max_template_records)]
    fit = np.zeros((len(pick), 2))
    for sweep in range(1, max_sweeps + 1):
        tpl = pulse_template([out[i].kp.astype(float) for i in pick],
                             [out[i].angles() + d + r * np.linspace(-1.0, 1.0, out[i].kp.size)
                              for i, (d, r) in zip(pick, fit, strict=True)])
        new = np.array([refine_phase(out[i].kp.astype(float), out[i].angles(), tpl)[::2]
                        for i in pick])                          # (offset, rate)
        step = float(np.max(np.abs(new[:, 0] - fit[:, 0]))) if sweep > 1 else np.inf
        fit = new
        if step < SWEEP_TOL:
            break
    else:
        warnings.warn(f"keyphasor phase refinement: not converged after max_sweeps = "
                      f"{max_sweeps} sweeps (last change {step:.1e} rad, tolerance "
                      f"{SWEEP_TOL:g})", UserWarning, stacklevel=3)
    zero = template_crossing(tpl, out[pick[0]].polarity,
                             f"{len(pick)} records ({files[pick[0]]}, …)")
    res = np.array([refine_phase(out[i].kp.astype(float), out[i].angles(), tpl,
                                 search_rad=SEARCH_RAD if out[i].gap > SEARCH_GAP else 0.0)[:2]
                    for i in sampled])
    shift[sampled], sd[sampled] = res[:, 0] - zero, res[:, 1]
    n_counter = len(out) - len(sampled)
    return shift, sd, f"keyphasor phase of {len(sampled)} sampled-keyphasor records refined " \
        f"on a pulse template from {len(pick)} records ({sweep} sweeps, last change " \
        f"{step:.1e} rad; angle 0 at its mid-swing crossing, {zero:.2e} rad)" \
        + (f"; {n_counter} counter-timed records not refined" if n_counter else "")


def _run(ds: Dataset, rows, channels, n_jobs: int) -> list[_Demodulated]:
    files = [r["file"] for r in rows]
    if check_int("n_jobs", n_jobs, minimum=1) == 1:
        return _work(ds.root, files, channels)
    chunks = [files[i::n_jobs] for i in range(n_jobs)]
    parts = Parallel(n_jobs=n_jobs)(delayed(_work)(ds.root, c, channels) for c in chunks)
    out: list = [None] * len(files)
    for i, part in enumerate(parts):
        out[i::n_jobs] = part
    return out


__all__ = ["MeasuredPhasors", "SensorCorrections", "measured_phasors"]
