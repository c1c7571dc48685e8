"""Files in and out: the one atomic writer, CSV text, and input files read with their hash.

* :func:`atomic_write_bytes` / :func:`atomic_write_text`: the file is written to a temporary
  name in its folder, made mode 0644 (readable by everyone, whatever the umask) and moved into
  place with ``os.replace``, so a crash never leaves a half-written file. Every writer of the
  toolkit (run folders, figures, ``optimization.write_csv``) goes through it.
* :func:`read_input`: read a file a model or a config refers to (a geometry file, …), with
  one-line errors naming it; while :func:`tracked_inputs` is active, every file read this way
  is recorded with its SHA-256, so a run can tell later whether its inputs changed.
* :func:`source_digest`: a hash of the package's source code (the FE cache and ``--resume``
  are keyed to it, so a fix of the model never reuses stale results).

>>> import tempfile, pathlib
>>> with tempfile.TemporaryDirectory() as d:
...     p = atomic_write_text(pathlib.Path(d) / "a.csv", csv_text(["x", "y"], [[1, 2]]))
...     with tracked_inputs() as seen:
...         data = read_input(p, "table")
...     data, oct(p.stat().st_mode & 0o777), list(seen.values()) == [sha256(data)]
(b'x,y\\n1,2\\n', '0o644', True)
"""

from __future__ import annotations

import contextvars
import csv
import hashlib
import io
import json
import os
import secrets
import shutil
from collections.abc import Iterable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np

FILE_MODE = 0o644
DIR_MODE = 0o755

_TRACKER: contextvars.ContextVar[dict[str, str] | None] = contextvars.ContextVar(
    "input_files", default=None)


def make_dirs(path: str | Path) -> Path:
    """Create ``path`` and its missing parents with mode 0755 (whatever the umask)."""
    path = Path(path)
    missing = []
    p = path
    while not p.exists():
        missing.append(p)
        if p.parent == p:
            break
        p = p.parent
    for p in reversed(missing):
        try:
            p.mkdir()
        except FileExistsError:
            pass
        else:
            os.chmod(p, DIR_MODE)
    return path


def atomic_write_bytes(path: str | Path, data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically (temporary file + ``os.replace``), mode 0644."""
    path = Path(path)
    make_dirs(path.parent)
    tmp = path.with_name(f".{path.name}.{secrets.token_hex(4)}.tmp")
    try:
        tmp.write_bytes(data)
        os.chmod(tmp, FILE_MODE)
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()
    return path


def atomic_write_text(path: str | Path, text: str) -> Path:
    """Write ``text`` (UTF-8) to ``path`` atomically, mode 0644."""
    return atomic_write_bytes(path, text.encode("utf-8"))


def csv_text(header: Sequence[str], rows: Iterable[Sequence[Any]]) -> str:
    """CSV with ``\\n`` line ends."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(header)
    w.writerows(rows)
    return buf.getvalue()


def rows_text(rows: Sequence[Mapping[str, Any]], columns: Sequence[str] | None = None) -> str:
    """CSV of dict rows (columns: ``columns`` or the union of keys in first-seen order; the
    csv module's default ``\\r\\n`` line ends, as the study's tables always had)."""
    if columns is None:
        columns = list(dict.fromkeys(k for r in rows for k in r))
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=list(columns), extrasaction="raise")
    w.writeheader()
    w.writerows(rows)
    return buf.getvalue()


def json_default(o: Any) -> Any:
    """``json.dumps`` ``default`` for numpy arrays and scalars, paths, mappings, tuples and
    objects with ``to_dict``."""
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, (np.floating, np.integer, np.bool_)):
        return o.item()
    if isinstance(o, Path):
        return str(o)
    if isinstance(o, Mapping):
        return dict(o)
    if isinstance(o, (tuple, set, frozenset)):
        return list(o)
    if hasattr(o, "to_dict"):
        return o.to_dict()
    raise TypeError(f"cannot serialise {type(o).__name__}")


def json_text(data: Any) -> str:
    """``data`` as indented JSON text (numpy values as plain numbers), ending in a newline."""
    return json.dumps(data, indent=2, default=json_default) + "\n"


def sha256(data: bytes) -> str:
    """Hex SHA-256 of ``data``."""
    return hashlib.sha256(data).hexdigest()


def read_input(path: str | Path, what: str = "file") -> bytes:
    """The bytes of an input file; a missing, unreadable or directory path raises
    ``ValueError`` naming ``what`` and the path. Recorded by :func:`tracked_inputs`."""
    path = Path(path)
    where = f"{what} {str(path)!r}"
    if path.is_dir():
        raise ValueError(f"{where} is a directory: must be a file")
    if not path.is_file():
        raise ValueError(f"{where} does not exist")
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise ValueError(f"{where} cannot be read: {exc.strerror or exc}") from None
    seen = _TRACKER.get()
    if seen is not None:
        seen[str(path.resolve())] = sha256(data)
    return data


@contextmanager
def tracked_inputs() -> Iterator[dict[str, str]]:
    """Inside: every :func:`read_input` adds ``{absolute path: sha256}`` to the yielded
    dict."""
    seen: dict[str, str] = {}
    token = _TRACKER.set(seen)
    try:
        yield seen
    finally:
        _TRACKER.reset(token)


def input_changes(recorded: Mapping[str, str]) -> list[str]:
    """The files of ``recorded`` (path → sha256) whose content differs now (or that are
    gone), as ``"<path> (changed)"`` / ``"<path> (missing)"``."""
    out = []
    for path, digest in sorted(recorded.items()):
        try:
            now = sha256(Path(path).read_bytes())
        except OSError:
            out.append(f"{path} (missing)")
            continue
        if now != digest:
            out.append(f"{path} (changed)")
    return out


def share_tree(root: str | Path) -> None:
    """Make every folder under ``root`` 0755 and every file 0644 (caches that other libraries
    write with the process's umask)."""
    root = Path(root)
    if not root.is_dir():
        return
    for dirpath, dirnames, filenames in os.walk(root):
        for name, mode in [(d, DIR_MODE) for d in dirnames] + [(f, FILE_MODE)
                                                               for f in filenames]:
            p = os.path.join(dirpath, name)
            try:
                if os.stat(p, follow_symlinks=False).st_mode & 0o777 != mode:
                    os.chmod(p, mode)
            except OSError:
                pass
    os.chmod(root, DIR_MODE)


@cache
def source_digest() -> str:
    """SHA-256 (first 16 hex digits) of every ``.py`` file of the package, path and content:
    changes with any change of the code, whatever git says."""
    root = Path(__file__).resolve().parent.parent
    h = hashlib.sha256()
    for p in sorted(root.rglob("*.py")):
        h.update(str(p.relative_to(root)).encode())
        h.update(p.read_bytes())
    return h.hexdigest()[:16]


def read_meta(path: str | Path) -> dict[str, Any] | None:
    """``meta.json`` of a run folder (``None``: none or unreadable)."""
    try:
        return json.loads((Path(path) / "meta.json").read_text())
    except (OSError, ValueError):
        return None


def require_disk(field: str, value: Any, nbytes: float, detail: str, root: str | Path) -> None:
    """Refuse ``field = value`` if what it writes (``nbytes``, described by ``detail``)
    exceeds the free space of the file system holding ``root`` (or its nearest existing
    parent).

    >>> require_disk("n", 1, 1.0, "a byte", ".")
    """
    p = Path(root).absolute()
    while not p.exists():
        p = p.parent
    free = shutil.disk_usage(p).free
    if nbytes > free:
        raise ValueError(f"{field} = {value!r} is not allowed: {detail} need ~{nbytes / 1e9:.3g} "
                         f"GB of disk, more than the {free / 1e9:.3g} GB free under {str(p)!r}")


__all__ = ["FILE_MODE", "atomic_write_bytes", "atomic_write_text", "csv_text", "input_changes",
           "json_default", "json_text", "make_dirs", "read_input", "read_meta", "require_disk",
           "rows_text",
           "sha256", "share_tree", "source_digest", "tracked_inputs"]
