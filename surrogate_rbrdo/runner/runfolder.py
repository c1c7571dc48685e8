"""Run folders ``results/<experiment>/<run-id>/``: status, stage results, atomic 0644 files.

Rules (tested in ``tests/runner/test_runfolder.py``):

* a run id and an experiment name are one folder name each (letters, digits, ``._-``), and
  every file name a kind writes is one path component (:meth:`RunFolder.file`), so nothing is
  written outside the run folder;
* a folder that holds a run is never reused silently: a finished run is replaced only with
  ``overwrite`` (renamed aside, deleted when the new run completes), an unfinished one is
  continued with ``resume`` (or replaced); a symbolic link is never a run folder;
* ``meta.json`` says ``status``: ``running`` (with the pid), ``complete`` (written last),
  ``failed`` (with the error) or ``interrupted`` (with the signal); only ``complete`` is
  finished;
* every stage's frozen result is pickled to ``stages/<n>-<name>.pkl`` when the stage ends, so
  a resumed run loads it instead of recomputing;
* every file is written to a temporary name in the same folder, made 0644 and moved into
  place with ``os.replace`` (``core.files``), so a crash never leaves a half-written table;
  folders are 0755, whatever the umask;
* every session (start or resume) records the code it ran (git SHA, source hash, package
  versions).
"""

from __future__ import annotations

import io
import os
import pickle
import platform
import re
import secrets
import shutil
import socket
import time
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from surrogate_rbrdo.core.files import (
    atomic_write_bytes,
    atomic_write_text,
    csv_text,
    json_text,
    make_dirs,
    read_meta,
    rows_text,
)
from surrogate_rbrdo.core.provenance import environment

NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9._-]{0,127}")
#: a file name inside a run folder: one path component, no control characters
FILE_NAME = re.compile(r"[^/\\\x00-\x1f\x7f]{1,200}")


def check_name(where: str, value: Any) -> str:
    """A run id or experiment name: one folder name (no path separators, no ``..``)."""
    if not isinstance(value, str) or not NAME.fullmatch(value) or ".." in value:
        raise ValueError(f"{where} = {value!r} is not allowed: must be 1-128 letters, digits, "
                         "'.', '_' or '-', starting with a letter or digit (it names a folder "
                         "under the results root)")
    return value


def _alive(meta: Mapping[str, Any]) -> bool:
    """Whether the process that wrote a ``running`` meta.json still runs (same host)."""
    pid = meta.get("pid")
    if meta.get("status") != "running" or meta.get("host") != socket.gethostname() \
            or not isinstance(pid, int):
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


class AlreadyComplete(Exception):
    """``resume`` of a run that has finished: nothing to do."""


def check_root(value: Any, where: str = "--results") -> Path:
    """A results root: a folder (existing or to be created), not a file, not ``""``."""
    if not isinstance(value, (str, os.PathLike)) or not str(value).strip():
        raise ValueError(f"{where} = {value!r} is not allowed: give a folder (e.g. results)")
    root = Path(value)
    p = root
    while not p.exists() and p.parent != p:
        p = p.parent
    if p.exists() and not p.is_dir():
        raise ValueError(f"{where} = {str(value)!r} is not allowed: {str(p)!r} is a file, "
                         "not a folder")
    return root


@dataclass
class RunFolder:
    """One run's folder: files, stage results and ``meta.json``.

    ``replaced``: where an overwritten run waits (renamed aside) until this one completes.
    """

    path: Path
    experiment: str
    run_id: str
    meta: dict[str, Any] = field(default_factory=dict)
    started: float = field(default_factory=time.time)
    timings: dict[str, float] = field(default_factory=dict)
    replaced: Path | None = None

    @classmethod
    def open(cls, root: str | Path, experiment: str, run_id: str | None = None, *,
             resume: bool = False, overwrite: bool = False) -> RunFolder:
        """Create (or, with ``resume``, reopen) ``root/experiment/run_id``.

        Raises ``ValueError`` naming ``--overwrite``/``--resume``/a new id when the folder
        holds a run that may not be reused, :class:`AlreadyComplete` when ``resume`` finds a
        finished run. With ``overwrite`` the old run is renamed aside and deleted when the
        new one completes (:meth:`stop`).
        """
        root = check_root(root)
        check_name("experiment.name", experiment)
        if run_id is None:
            run_id = f"{datetime.now(UTC).strftime('%Y%m%dT%H%M%SZ')}-{secrets.token_hex(3)}"
        check_name("--run-id", run_id)
        path = root / experiment / run_id
        if path.is_symlink():
            raise ValueError(f"{str(path)!r} is a symbolic link, not a run folder: choose "
                             "another --run-id")
        meta = read_meta(path) if path.exists() else None
        if path.exists():
            cls._check_reuse(path, meta, resume=resume, overwrite=overwrite)
        elif resume:
            raise ValueError(f"--resume: there is no run folder {str(path)!r} to continue: "
                             "it does not exist (start without --resume)")
        aside = None
        if overwrite and path.exists():
            aside = path.with_name(f".{run_id}.replaced-{secrets.token_hex(3)}")
            os.replace(path, aside)
        if meta is None or overwrite:
            make_dirs(path.parent)
            path.mkdir()
            os.chmod(path, 0o755)
            meta = {"replaced_run": str(aside)} if aside else {}
        return cls(path=path, experiment=experiment, run_id=run_id, meta=dict(meta),
                   replaced=aside)

    @staticmethod
    def _check_reuse(path: Path, meta: Mapping[str, Any] | None, *, resume: bool,
                     overwrite: bool) -> None:
        where = repr(str(path))
        if meta is None:
            raise ValueError(f"{where} exists and is not a run folder (no readable meta.json): "
                             "choose another --run-id")
        status = meta.get("status", "unknown")
        if _alive(meta):
            raise ValueError(f"{where} is being written by process {meta.get('pid')} (status "
                             "'running'): wait for it or choose another --run-id")
        if overwrite:
            return
        if status == "complete":
            if resume:
                raise AlreadyComplete(f"{where} is already complete: nothing to resume")
            raise ValueError(f"{where} holds a finished run: pass --overwrite to replace it or "
                             "choose another --run-id")
        if not resume:
            raise ValueError(f"{where} holds an unfinished run (status {status!r}): pass "
                             "--resume to continue it, --overwrite to start over, or choose "
                             "another --run-id")

    # ------------------------------------------------------------------ files
    def file(self, name: str) -> Path:
        """``name`` inside the run folder: one path component (no separator, no control
        character, not ``.``/``..``), so nothing is written outside the folder."""
        if not isinstance(name, str) or not FILE_NAME.fullmatch(name) or name in (".", "..") \
                or name != name.strip():
            raise ValueError(f"file name {name!r} is not allowed: must be one file name inside "
                             f"the run folder {str(self.path)!r} (no '/', no control characters)")
        return self.path / name

    def write_bytes(self, name: str, data: bytes) -> Path:
        return atomic_write_bytes(self.file(name), data)

    def write_text(self, name: str, text: str) -> Path:
        return atomic_write_text(self.file(name), text)

    def write_json(self, name: str, data: Any) -> Path:
        return self.write_text(name, json_text(data))

    def write_csv(self, name: str, header: Sequence[str], rows: Iterable[Sequence[Any]]) -> Path:
        return self.write_text(name, csv_text(header, rows))

    def write_rows(self, name: str, rows: Sequence[Mapping[str, Any]]) -> Path:
        return self.write_text(name, rows_text(rows))

    def save_figure(self, name: str, fig: Any) -> Path:
        """Save a matplotlib figure (format from the suffix, 120 dpi)."""
        buf = io.BytesIO()
        fig.savefig(buf, dpi=120, format=Path(name).suffix[1:])
        return self.write_bytes(name, buf.getvalue())

    # ------------------------------------------------------------------ stage results
    def _stage_file(self, index: int, name: str) -> Path:
        return self.path / "stages" / f"{index:02d}-{name}.pkl"

    def has_stage(self, index: int, name: str) -> bool:
        return self._stage_file(index, name).is_file()

    def save_stage(self, index: int, name: str, result: Any, seconds: float) -> None:
        atomic_write_bytes(self._stage_file(index, name),
                           pickle.dumps(result, protocol=pickle.HIGHEST_PROTOCOL))
        self.timings[name] = seconds
        self.meta.setdefault("stages", {})[name] = {"status": "done", "time_s": seconds}
        self.write_meta()

    def load_stage(self, index: int, name: str) -> Any:
        try:
            return pickle.loads(self._stage_file(index, name).read_bytes())
        except Exception as exc:  # noqa: BLE001 - any unpickling trouble means "cannot resume"
            raise ValueError(f"--resume: the saved result of stage {name!r} in "
                             f"{str(self.path)!r} cannot be loaded ({type(exc).__name__}: "
                             f"{exc}); start over with --overwrite") from None

    # ------------------------------------------------------------------ meta.json
    def write_meta(self, **update: Any) -> Path:
        self.meta.update(update)
        return self.write_json("meta.json", self.meta)

    def start(self, *, kind: str, seeds: Mapping[str, Any], **info: Any) -> None:
        """Mark the run ``running`` (this process) with the environment it runs in; every
        start or resume adds a session with its code version and package versions."""
        now = datetime.fromtimestamp(self.started, UTC).isoformat()
        env = environment()
        sessions = [s if isinstance(s, dict) else {"started_utc": s}
                    for s in self.meta.get("sessions", [])]
        sessions.append({"started_utc": now, "pid": os.getpid(), **env})
        self.write_meta(
            experiment=self.experiment, run_id=self.run_id, kind=kind, status="running",
            pid=os.getpid(), host=socket.gethostname(),
            started_utc=self.meta.get("started_utc", now), sessions=sessions,
            python=platform.python_version(), platform=platform.platform(), **env,
            seeds=dict(seeds), **info)

    def stop(self, status: str, **info: Any) -> None:
        """Mark the run ``complete``, ``failed`` or ``interrupted``; a complete run deletes
        the run(s) it replaced (a failed ``--overwrite`` keeps them aside)."""
        files = sorted(p.name for p in self.path.iterdir() if p.is_file()
                       and not p.name.startswith("."))
        if status == "complete" and self.replaced is not None:
            # this run's predecessor, and any run an earlier failed --overwrite set aside
            for aside in self.path.parent.glob(f".{self.run_id}.replaced-*"):
                shutil.rmtree(aside, ignore_errors=True)
            self.meta.pop("replaced_run", None)
            self.replaced = None
        self.write_meta(status=status, finished_utc=datetime.now(UTC).isoformat(),
                        wall_time_s=time.time() - self.started,
                        timings_s={**self.meta.get("timings_s", {}), **self.timings},
                        files=sorted(set(files) | {"meta.json"}), **info)


__all__ = ["AlreadyComplete", "RunFolder", "check_name", "check_root", "read_meta"]
