"""The native on-disk form of measured data: one ``.npz`` file per record in a dataset folder.

A record file holds ``data`` (the samples, ``(n_channels, n_samples)``, int16/int32 counts or
float64), ``meta`` (the record's metadata as a JSON string: channels, calibration, sample rate,
speed, provenance, the names of its event channels; see ``docs/measured-data.md``) and one
float64 array ``event:<name>`` per event channel (e.g. the keyphasor's counter timestamps).
A dataset is a folder::

    dataset.json        what the dataset is (written last: its presence marks it complete)
    index.jsonl         one line per record written so far (id, kind, speed, file, labels)
    records/<id>.npz    the records

Records are written atomically (temporary file, then rename) and the index is appended after the
file exists, so an interrupted campaign resumes at record granularity (:meth:`DatasetWriter.done`).

>>> import numpy as np, tempfile
>>> from surrogate_rbrdo.rig.records import ChannelSpec, Record, SensorLocation
>>> ch = ChannelSpec("f", "force", "N", SensorLocation("tool", "x"))
>>> rec = Record("hit0", "impact", 10_000.0, (ch,), np.zeros((1, 8)), speed_rpm=0.0)
>>> with tempfile.TemporaryDirectory() as d:
...     w = DatasetWriter(d, {"title": "demo"})
...     w.write(rec, labels={"hit": 0})
...     _ = w.finish()
...     ds = open_dataset(d)
...     [r.id for r in ds], ds.index[0]["labels"]
(['hit0'], {'hit': 0})
"""

from __future__ import annotations

import json
import os
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from surrogate_rbrdo.rig.records import (
    FORMAT_NAME,
    FORMAT_VERSION,
    Record,
    RecordError,
    record_from_metadata,
)

DATASET_FORMAT = "surrogate_rbrdo.rig.dataset"


def write_record(record: Record, path: str | Path) -> Path:
    """Write one record to ``path`` (``.npz``) atomically; returns the path."""
    path = Path(path)
    tmp = path.with_name(path.name + ".tmp")
    meta = record.metadata()
    meta["events"] = sorted(record.events)       # names; the times are binary arrays
    arrays = {f"event:{k}": v for k, v in record.events.items()}
    with open(tmp, "wb") as fh:
        np.savez(fh, data=record.data, meta=np.array(json.dumps(meta)), **arrays)
    os.replace(tmp, path)
    return path


def read_record(path: str | Path) -> Record:
    """Read a record written by :func:`write_record`; bad content raises :class:`RecordError`."""
    path = Path(path)
    src = str(path)
    if not path.is_file():
        raise RecordError(src, "file", "does not exist")
    try:
        with np.load(path, allow_pickle=False) as z:
            if "data" not in z or "meta" not in z:
                raise RecordError(src, "arrays", f"need 'data' and 'meta', found {list(z)}")
            data = z["data"]
            meta = json.loads(str(z["meta"]))
            names = meta.get("events") or []
            if isinstance(names, list):
                missing = [n for n in names if f"event:{n}" not in z]
                if missing:
                    raise RecordError(src, "events", f"{missing} listed but not stored")
                meta["events"] = {n: z[f"event:{n}"] for n in names}
    except (OSError, ValueError) as exc:
        if isinstance(exc, RecordError):
            raise
        raise RecordError(src, "file", f"not a readable record ({exc})") from None
    if meta.get("format") != FORMAT_NAME:
        raise RecordError(src, "format", f"= {meta.get('format')!r}, expected {FORMAT_NAME!r}")
    if meta.get("version", 0) > FORMAT_VERSION:
        raise RecordError(src, "version", f"= {meta['version']} is newer than this reader "
                                          f"({FORMAT_VERSION})")
    if meta.get("n_samples", data.shape[-1]) != data.shape[-1]:
        raise RecordError(src, "n_samples", f"= {meta['n_samples']} but the data hold "
                                            f"{data.shape[-1]} samples")
    return record_from_metadata(meta, data, src)


class DatasetWriter:
    """Streams records into a dataset folder; resumable (records already written are kept).

    Parameters
    ----------
    root : path
        The dataset folder (created if missing).
    info : mapping
        JSON-able description written into ``dataset.json`` by :meth:`finish` (title, truth,
        campaign options ...).
    """

    def __init__(self, root: str | Path, info: Mapping[str, Any]) -> None:
        self.root = Path(root)
        self.info = dict(info)
        self.records_dir = self.root / "records"
        self.index_path = self.root / "index.jsonl"

    def done(self) -> set[str]:
        """Ids of the records already written completely (index line and file present)."""
        if not self.index_path.is_file():
            return set()
        ids = set()
        for line in self.index_path.read_text().splitlines():
            try:
                row = json.loads(line)
            except json.JSONDecodeError:  # a line cut by an interruption
                continue
            if (self.root / row["file"]).is_file():
                ids.add(row["id"])
        return ids

    def write(self, record: Record, labels: Mapping[str, Any] | None = None) -> None:
        """Write ``record`` and append its index line (``labels``: campaign coordinates)."""
        self.records_dir.mkdir(parents=True, exist_ok=True)
        rel = f"records/{record.id}.npz"
        write_record(record, self.root / rel)
        row = {"id": record.id, "kind": record.kind, "file": rel,
               "speed_rpm": None if np.isnan(record.speed_rpm) else record.speed_rpm,
               "n_samples": record.n_samples, "sample_rate_hz": record.sample_rate_hz,
               "labels": dict(labels or {})}
        with open(self.index_path, "a") as fh:
            fh.write(json.dumps(row) + "\n")

    def finish(self, summary: Mapping[str, Any] | None = None) -> Path:
        """Write ``dataset.json`` (marks the dataset complete)."""
        self.root.mkdir(parents=True, exist_ok=True)
        out = {"format": DATASET_FORMAT, "version": FORMAT_VERSION, **self.info,
               "n_records": len(self.done()), "summary": dict(summary or {})}
        path = self.root / "dataset.json"
        tmp = path.with_name("dataset.json.tmp")
        tmp.write_text(json.dumps(out, indent=2))
        os.replace(tmp, path)
        return path


@dataclass(frozen=True)
class Dataset:
    """A dataset folder opened for reading: ``index`` rows and lazily loaded records."""

    root: Path
    info: Mapping[str, Any]
    index: tuple[Mapping[str, Any], ...]

    def __len__(self) -> int:
        return len(self.index)

    def __iter__(self) -> Iterator[Record]:
        for row in self.index:
            yield read_record(self.root / row["file"])

    def select(self, **labels: Any) -> tuple[Mapping[str, Any], ...]:
        """Index rows whose ``kind``/labels match, e.g. ``select(kind="steady", repeat=3)``."""
        out = []
        for row in self.index:
            merged = {"kind": row["kind"], **row["labels"]}
            if all(merged.get(k) == v for k, v in labels.items()):
                out.append(row)
        return tuple(out)

    def load(self, row_or_id: Mapping[str, Any] | str) -> Record:
        """The record of an index row (or of an id)."""
        if isinstance(row_or_id, str):
            rows = [r for r in self.index if r["id"] == row_or_id]
            if not rows:
                raise RecordError(str(self.root), "id", f"{row_or_id!r} not in the dataset")
            row_or_id = rows[0]
        return read_record(self.root / row_or_id["file"])


def open_dataset(root: str | Path, *, require_complete: bool = True) -> Dataset:
    """Open a dataset folder (``require_complete``: ``dataset.json`` must exist)."""
    root = Path(root)
    info_path = root / "dataset.json"
    if require_complete and not info_path.is_file():
        raise RecordError(str(root), "dataset.json", "missing: the dataset is incomplete "
                                                     "(interrupted campaign?)")
    info = json.loads(info_path.read_text()) if info_path.is_file() else {}
    rows = []
    index_path = root / "index.jsonl"
    if index_path.is_file():
        seen = set()
        for line in index_path.read_text().splitlines():
            try:
                row = json.loads(line)
            except json.JSONDecodeError:
                continue
            if row["id"] not in seen and (root / row["file"]).is_file():
                seen.add(row["id"])
                rows.append(row)
    return Dataset(root, info, tuple(rows))
