"""Run folders: ``results/<experiment>/<run-id>/`` with atomic writes and ``meta.json``.

A run never overwrites another: the run id is a UTC timestamp plus a short random suffix.
Every file is written to a temporary name in the same folder and moved into place with
``os.replace``, so a crash never leaves a half-written table.
"""

from __future__ import annotations

import csv
import io
import json
import os
import platform
import secrets
import subprocess
import time
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from datetime import UTC, datetime
from importlib import metadata
from pathlib import Path
from typing import Any

PACKAGES = ("surrogate_rbrdo", "numpy", "scipy", "scikit-learn", "smt", "pymoo", "optuna",
            "joblib", "matplotlib", "dask", "distributed")


def atomic_write_text(path: str | Path, text: str) -> Path:
    """Write ``text`` to ``path`` atomically (temporary file + ``os.replace``)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{secrets.token_hex(4)}.tmp")
    tmp.write_text(text)
    os.replace(tmp, path)
    return path


def atomic_write_csv(path: str | Path, header: Sequence[str], rows: Iterable[Sequence[Any]]
                     ) -> Path:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(header)
    for r in rows:
        w.writerow(r)
    return atomic_write_text(path, buf.getvalue())


def git_sha(cwd: str | Path | None = None) -> str | None:
    try:
        out = subprocess.run(["git", "rev-parse", "HEAD"], cwd=cwd, capture_output=True,
                             text=True, timeout=5, check=False)
    except (OSError, subprocess.SubprocessError):
        return None
    return out.stdout.strip() or None


def package_versions() -> dict[str, str | None]:
    out: dict[str, str | None] = {}
    for p in PACKAGES:
        try:
            out[p] = metadata.version(p)
        except metadata.PackageNotFoundError:
            out[p] = None
    return out


@dataclass
class RunFolder:
    """A results folder for one run of one experiment, with timings and a manifest."""

    path: Path
    experiment: str
    started: float = field(default_factory=time.time)
    timings: dict[str, float] = field(default_factory=dict)
    files: list[str] = field(default_factory=list)

    @classmethod
    def create(cls, root: str | Path, experiment: str, run_id: str | None = None) -> RunFolder:
        if run_id is None:
            stamp = datetime.now(UTC).strftime("%Y%m%dT%H%M%SZ")
            run_id = f"{stamp}-{secrets.token_hex(3)}"
        path = Path(root) / experiment / run_id
        path.mkdir(parents=True, exist_ok=True)
        return cls(path=path, experiment=experiment)

    def file(self, name: str) -> Path:
        self.files.append(name)
        return self.path / name

    def write_text(self, name: str, text: str) -> Path:
        return atomic_write_text(self.file(name), text)

    def write_json(self, name: str, data: Any) -> Path:
        return self.write_text(name, json.dumps(data, indent=2, default=_json_default) + "\n")

    def write_csv(self, name: str, header: Sequence[str], rows: Iterable[Sequence[Any]]) -> Path:
        return atomic_write_csv(self.file(name), header, rows)

    def timed(self, step: str) -> _Timer:
        return _Timer(self, step)

    def write_meta(self, *, seeds: Mapping[str, Any], extra: Mapping[str, Any] | None = None
                   ) -> Path:
        meta = {
            "experiment": self.experiment,
            "run_folder": str(self.path),
            "started_utc": datetime.fromtimestamp(self.started, UTC).isoformat(),
            "wall_time_s": time.time() - self.started,
            "timings_s": self.timings,
            "git_sha": git_sha(Path(__file__).parent),
            "python": platform.python_version(),
            "platform": platform.platform(),
            "packages": package_versions(),
            "seeds": dict(seeds),
            "files": sorted(set(self.files)),
            **(dict(extra) if extra else {}),
        }
        return self.write_json("meta.json", meta)


class _Timer:
    def __init__(self, run: RunFolder, step: str) -> None:
        self.run, self.step = run, step

    def __enter__(self) -> _Timer:
        self.t0 = time.perf_counter()
        return self

    def __exit__(self, *exc: object) -> None:
        self.run.timings[self.step] = self.run.timings.get(self.step, 0.0) + (
            time.perf_counter() - self.t0)


def _json_default(o: Any) -> Any:
    import numpy as np

    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, (np.floating, np.integer, np.bool_)):
        return o.item()
    if isinstance(o, Path):
        return str(o)
    if hasattr(o, "to_dict"):
        return o.to_dict()
    raise TypeError(f"cannot serialise {type(o).__name__}")
