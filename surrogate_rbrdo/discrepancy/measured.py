"""Measured data in the toolkit's format (``docs/measured-data.md``) → observables.

* :func:`phasor_block` turns a table of demodulated 1x phasors — the rig campaign's
  ``phasors.csv`` (one row per steady record and displacement channel: ``run`` (or
  ``repeat``), ``speed_rpm``, ``channel``, ``re_m``, ``im_m``; ``build``/``tool`` when there are
  several), or a user's table in the same columns — into a 1x block: one repeat per
  ``(build, tool, run)``, every repeat at every speed and channel. The convention is the
  format's: ``x(t) = Re(X e^{iφ})`` against the keyphasor, the FE model's own.
* :func:`channel_positions` reads the channels' axial positions and directions from one native
  record (``records/<id>.npz``: its ``meta`` JSON), so a campaign folder needs nothing else.
* :func:`dataset_phasor_rows` demodulates the steady records of a dataset folder (a user's
  measurements put into the format, or the rig's) into such rows, with the channels' positions.
* :func:`frf_block` turns averaged H1 FRFs with their coherence into an impact block; the
  variance of each line is Bendat & Piersol's (*Random Data*, 4th ed., eq. 9.90):
  ``var(Re H) = var(Im H) = |H|² (1 − γ²) / (2 n γ²)`` per component for ``n`` averages.
* :func:`impact_blocks` makes impact blocks from the impact records of a dataset folder: per
  spin speed and hit direction, each hit's FRF (``rig.frf.h1_frf`` of the one record: its
  response over its force) at the FRF lines of the test plan, the mean and covariance from
  the hits (as the 1x phasors from the repeats; no coherence threshold is needed, so the
  bearing probes' noisier FRFs are kept with their own variance). An FRF taken on the running
  spindle is a different observable from one at standstill, so each record must carry its
  ``speed_rpm`` (the format's field; 0 at standstill), and the synchronous response must have
  been removed from records at speed (subtract the 1x phasor demodulated against the
  keyphasor; lines near the running frequency are dropped anyway).
* :func:`soak_blocks` makes thermal soak blocks (:class:`~.soak.SoakBlock`) from the soak
  records of a dataset folder (kind ``soak``: a speed held from a cold start, labels
  ``time_s`` and the run's ``build``/``tool``/``run``): per speed held, per run the records
  in the order of their ``time_s``, each demodulated as a steady record, with the mean of its
  temperature channel.
"""

from __future__ import annotations

import csv
import json
import math
import warnings
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from surrogate_rbrdo.discrepancy.observables import ComplexBlock
from surrogate_rbrdo.discrepancy.soak import SoakBlock
from surrogate_rbrdo.discrepancy.sweeps import Channel, Sweep
from surrogate_rbrdo.rig.demod import demodulate
from surrogate_rbrdo.rig.frf import h1_frf
from surrogate_rbrdo.rig.impacts import ImpactPlan
from surrogate_rbrdo.rig.store import open_dataset

#: the phasor table's required columns
PHASOR_COLUMNS = ("speed_rpm", "channel", "re_m", "im_m")


def read_phasor_table(path: str | Path) -> list[dict[str, Any]]:
    """Rows of a phasor CSV (header row of column names); a missing column raises."""
    path = Path(path)
    if not path.is_file():
        raise ValueError(f"phasor table {str(path)!r} does not exist")
    with path.open(newline="") as fh:
        rows = list(csv.DictReader(fh))
    if not rows:
        raise ValueError(f"{path}: the phasor table has no rows")
    missing = [c for c in PHASOR_COLUMNS if c not in rows[0]]
    if missing or not ({"run", "repeat"} & set(rows[0])):
        raise ValueError(f"{path}: columns {sorted(rows[0])} lack {missing or ['run']}; "
                         f"need {list(PHASOR_COLUMNS)} and 'run' (or 'repeat')")
    return rows


def channel_positions(record_npz: str | Path) -> dict[str, tuple[float, str]]:
    """Channel name → (axial position in mm, direction) of the displacement channels of one
    native record file."""
    path = Path(record_npz)
    try:
        with np.load(path, allow_pickle=False) as z:
            meta = json.loads(str(z["meta"]))
    except (OSError, KeyError, ValueError) as exc:
        raise ValueError(f"{path}: not a native record ({exc})") from None
    out = {}
    for ch in meta.get("channels", []):
        loc = ch.get("location", {})
        if ch.get("quantity") == "displacement":
            if loc.get("position_mm") is None or loc.get("direction") not in ("x", "y"):
                raise ValueError(f"{path}: channel {ch.get('name')!r}: location needs "
                                 "position_mm and direction x or y")
            out[ch["name"]] = (float(loc["position_mm"]), loc["direction"])
    if not out:
        raise ValueError(f"{path}: no displacement channel")
    return out


def dataset_phasor_rows(root: str | Path
                        ) -> tuple[list[dict[str, Any]], dict[str, tuple[float, str]]]:
    """The 1x phasor rows of every steady record of the dataset folder ``root`` (each
    record checked and demodulated against its keyphasor, :func:`~surrogate_rbrdo.rig.demod.
    demodulate`) and the displacement channels' positions. A record's repeat is its index
    labels ``build``, ``tool`` and ``run`` (or ``repeat``); without them, the records at one
    speed are the repeats in the index's order."""
    ds = open_dataset(root)
    rows: list[dict[str, Any]] = []
    pos: dict[str, tuple[float, str]] = {}
    count: dict[float, int] = {}
    for row in ds.select(kind="steady"):
        rec = ds.load(row)
        lab = row.get("labels", {})
        speed = float(rec.speed_rpm)
        run = lab.get("run", lab.get("repeat", count.get(speed, 0)))
        count[speed] = count.get(speed, 0) + 1
        p = demodulate(rec)
        pos.update(_positions(root, rec, p.channels))
        for j, ch in enumerate(p.channels):
            rows.append({"build": lab.get("build", 0), "tool": lab.get("tool", 0), "run": run,
                         "speed_rpm": speed, "channel": ch, "re_m": p.X[j, 0].real,
                         "im_m": p.X[j, 0].imag})
    if not rows:
        raise ValueError(f"dataset {str(root)!r}: no steady records (kind = 'steady') to take "
                         "the 1x phasors from")
    return rows, pos


def phasor_block(rows: Iterable[Mapping[str, Any]],
                 positions: Mapping[str, tuple[float, str]],
                 name: str = "unbalance_1x") -> ComplexBlock:
    """A 1x block from phasor rows (see module doc) and channel positions."""
    table: dict[tuple, dict[tuple[float, str], complex]] = {}
    for r in rows:
        rep = (r.get("build", 0), r.get("tool", 0), r.get("run", r.get("repeat")))
        ch = r["channel"]
        if ch not in positions:
            raise ValueError(f"phasor table: channel {ch!r} has no position; known: "
                             f"{sorted(positions)}")
        table.setdefault(rep, {})[(float(r["speed_rpm"]), ch)] = complex(
            float(r["re_m"]), float(r["im_m"]))
    speeds = sorted({s for t in table.values() for s, _ in t})
    chans = sorted({c for t in table.values() for _, c in t})
    rec = np.empty((len(table), len(speeds), len(chans)), dtype=complex)
    for i, (rep, t) in enumerate(sorted(table.items(), key=lambda kv: str(kv[0]))):
        for j, s in enumerate(speeds):
            for k, c in enumerate(chans):
                if (s, c) not in t:
                    raise ValueError(f"phasor table: repeat {rep} has no phasor for channel "
                                     f"{c!r} at {s} rpm (every repeat needs every speed)")
                rec[i, j, k] = t[(s, c)]
    channels = tuple(Channel(c, *positions[c]) for c in chans)
    return ComplexBlock.from_repeats(name, Sweep.unbalance(speeds), channels, rec,
                                     {"source": "phasor table", "repeats": len(table)})


def frf_block(name: str, freq_hz: Sequence[float], H: np.ndarray, coherence: np.ndarray,
              n_averages: int, outputs: Sequence[Channel], excitation: Channel,
              *, min_coherence: float = 0.9, speed_rpm: float = 0.0) -> ComplexBlock:
    """An impact block from averaged FRFs ``H`` (n_out, F) with coherence (n_out, F); lines
    where any output's coherence is below ``min_coherence`` are dropped (antiresonances,
    noise floor: the variance formula is a small-error approximation). ``speed_rpm``: the
    spin speed the hits were taken at (0: standstill) — an FRF at speed is a different
    observable (gyroscopics, speed-dependent bearings), so it must be given."""
    H = np.asarray(H, dtype=complex)
    g2 = np.asarray(coherence, dtype=float)
    f = np.asarray(freq_hz, dtype=float)
    if H.shape != g2.shape or H.shape != (len(outputs), f.size):
        raise ValueError(f"frf {name!r}: H {H.shape} and coherence {g2.shape} must be "
                         f"({len(outputs)}, {f.size})")
    keep = np.all(g2 >= min_coherence, axis=0) & (f > 0)
    if keep.sum() < 3:
        raise ValueError(f"frf {name!r}: fewer than 3 lines with coherence >= {min_coherence}")
    var = np.abs(H[:, keep]) ** 2 * (1 - g2[:, keep]) / (2 * n_averages * g2[:, keep])
    var = np.maximum(var, 1e-12 * np.abs(H[:, keep]) ** 2 + 1e-300)
    cov = var.T[..., None, None] * np.eye(2)
    return ComplexBlock(name, Sweep.impact(f[keep], (excitation,), speed_rpm), tuple(outputs),
                        H[:, keep].T, cov, max(2 * n_averages - 2, 4),
                        {"source": "H1 FRF", "n_averages": n_averages,
                         "speed_rpm": float(speed_rpm)})


#: the fewest hits per speed and direction from which an FRF block's noise is estimated (the
#: workflow itself uses blocks from ``DiscrepancyOptions.min_impact_dof + 1`` hits)
MIN_HITS = 5


def impact_blocks(root: str | Path, plan: ImpactPlan | None = None
                  ) -> tuple[ComplexBlock, ...]:
    """FRF blocks of every impact record of the dataset folder ``root``: per ``speed_rpm``
    and hit direction (the force channel's location), the hits' FRFs of every displacement
    channel (no exponential window) at ``plan``'s lines for that speed (default
    :class:`~surrogate_rbrdo.rig.impacts.ImpactPlan`), averaged with their covariance from the
    hits. A speed and direction with fewer than :data:`MIN_HITS` hits is left out with a
    warning (a campaign planned for identification may hit twice). Empty if there are no
    impact records."""
    return impact_data(root, plan)[0]


def impact_data(root: str | Path, plan: ImpactPlan | None = None
                ) -> tuple[tuple[ComplexBlock, ...], tuple[tuple[str, int], ...]]:
    """:func:`impact_blocks` and ``(name, dof)`` of the blocks it leaves out for fewer than
    :data:`MIN_HITS` hits (``dof``: hits − 1), for a workflow's findings to list beside the
    blocks it leaves out itself."""
    plan = ImpactPlan() if plan is None else plan
    out, thin = [], []
    for (speed, d), recs in sorted(_impact_groups(root).items()):
        if len(recs) < MIN_HITS:
            warnings.warn(f"{root}: {len(recs)} impact records at {speed:g} rpm in {d} left "
                          f"out: the FRF noise is estimated from the hits, which needs at "
                          f"least {MIN_HITS}", stacklevel=3)
            thin.append((_impact_name(speed, d), len(recs) - 1))
            continue
        force = next(c for c in recs[0].channels if c.quantity == "force")
        probes = [c for c in recs[0].channels if c.quantity == "displacement"]
        f = plan.lines(speed)
        hits = []
        for rec in recs:
            with np.errstate(divide="ignore", invalid="ignore"):  # pyFRF's H2 of one hit
                est = h1_frf([rec], [c.name for c in probes], force.name, exp_window_end=None)
            idx = np.clip(np.searchsorted(est.freq_hz, f), 0, est.freq_hz.size - 1)
            hits.append(est.H[:, idx].T)
        outputs = tuple(Channel(c.name, float(c.location.position_mm), c.location.direction)
                        for c in probes)
        exc = Channel(f"{force.location.target}_{d}", float(force.location.position_mm), d)
        out.append(ComplexBlock.from_repeats(
            _impact_name(speed, d), Sweep.impact(est.freq_hz[idx], (exc,), speed),
            outputs, np.array(hits), {"source": "impact records", "n_hits": len(recs),
                                      "speed_rpm": speed}, runs=False))
    return tuple(out), tuple(thin)


def _impact_name(speed_rpm: float, direction: str) -> str:
    return f"impact_{direction}_{speed_rpm:.0f}rpm"


def _impact_groups(root: str | Path) -> dict[tuple[float, str], list]:
    """The impact records of the dataset folder ``root`` by (spin speed in rpm, 0 at
    standstill; hit direction)."""
    ds = open_dataset(root)
    groups: dict[tuple[float, str], list] = {}
    for row in ds.select(kind="impact"):
        rec = ds.load(row)
        speed = 0.0 if not math.isfinite(rec.speed_rpm) else float(rec.speed_rpm)
        force = next((c for c in rec.channels if c.quantity == "force"), None)
        if force is None or force.location.direction not in ("x", "y"):
            raise ValueError(f"{root}: impact record {rec.id!r} needs a force channel with a "
                             "location direction x or y")
        groups.setdefault((speed, force.location.direction), []).append(rec)
    return groups


def soak_blocks(root: str | Path) -> tuple[SoakBlock, ...]:
    """The thermal soaks of the dataset folder ``root``, one :class:`~.soak.SoakBlock` per
    speed held (in increasing speed; empty without soak records). A run is a record's labels
    ``(build, tool, run)`` (``build``/``tool`` default 0; ``run``, else ``soak``, is
    required), its records ordered by their label ``time_s`` (s after reaching speed,
    required); every run of a speed must have as many records. Each record is demodulated
    (:func:`~surrogate_rbrdo.rig.demod.demodulate`: its displacement channels, in name
    order, as the 1x block of :func:`phasor_block` has them) and its temperature is the mean
    of its temperature channel (quantity ``temperature``, K; the first if several)."""
    ds = open_dataset(root)
    groups: dict[float, dict[tuple, list]] = {}
    for row in ds.select(kind="soak"):
        lab = row.get("labels", {})
        run = lab.get("run", lab.get("soak"))
        if run is None or lab.get("time_s") is None:
            raise ValueError(f"{root}: soak record {row['id']!r}: labels {lab} need 'time_s' "
                             "(s after reaching speed) and 'run' (or 'soak')")
        rec = ds.load(row)
        if not (math.isfinite(rec.speed_rpm) and rec.speed_rpm > 0):
            raise ValueError(f"{root}: soak record {rec.id!r}: speed_rpm = {rec.speed_rpm} is "
                             "not allowed: the speed held, > 0")
        key = (lab.get("build", 0), lab.get("tool", 0), run)
        groups.setdefault(float(rec.speed_rpm), {}).setdefault(key, []).append(
            (float(lab["time_s"]), _soak_point(root, rec)))
    return tuple(_soak_block(root, s, runs) for s, runs in sorted(groups.items()))


def _positions(root, rec, channels) -> dict[str, tuple[float, str]]:
    """Each named displacement channel's (axial position in mm, direction) from ``rec``;
    a channel without both raises, naming the record."""
    pos = {}
    for ch in channels:
        c = rec.channel(ch).location
        if not math.isfinite(c.position_mm) or c.direction not in ("x", "y"):
            raise ValueError(f"{root}: record {rec.id!r}: channel {ch!r}: location needs "
                             "position_mm and direction x or y")
        pos[ch] = (float(c.position_mm), c.direction)
    return pos


def _soak_point(root, rec) -> tuple[dict[str, complex], dict[str, tuple[float, str]], float]:
    """One soak record's 1x phasor per displacement channel, their positions, temperature."""
    temp = rec.find("temperature")
    if not temp:
        raise ValueError(f"{root}: soak record {rec.id!r} has no temperature channel "
                         "(quantity 'temperature', K)")
    p = demodulate(rec)
    return dict(zip(p.channels, p.X[:, 0], strict=True)), _positions(root, rec, p.channels), float(
        np.mean(rec.values(temp[0].name)))


def _soak_block(root, speed: float, runs: dict[tuple, list]) -> SoakBlock:
    """The soak block of one speed from its runs' ``(time_s, point)`` lists."""
    sizes = {k: len(v) for k, v in runs.items()}
    if len(set(sizes.values())) != 1:
        raise ValueError(f"{root}: the soak at {speed:g} rpm has runs (build, tool, run) with "
                         f"different numbers of records {sizes}: every run needs the same "
                         "times")
    first = next(iter(runs.values()))[0][1]
    chans = sorted(first[0])
    keys = sorted(runs)
    t, T, Y = [], [], []
    for k in keys:
        pts = sorted(runs[k], key=lambda p: p[0])
        t.append([p[0] for p in pts])
        T.append([p[1][2] for p in pts])
        for _, (X, _pos, _) in pts:
            if sorted(X) != chans:
                raise ValueError(f"{root}: the soak at {speed:g} rpm: run {k} has channels "
                                 f"{sorted(X)}, the first record {chans}")
        Y.append([[X[c] for c in chans] for _, (X, _pos, _) in pts])
    channels = tuple(Channel(c, *first[1][c]) for c in chans)
    return SoakBlock(f"soak_{speed:.0f}rpm", speed, channels, np.array(t), np.array(T),
                     np.array(Y), {"source": "soak records", "runs": [list(k) for k in keys]})
