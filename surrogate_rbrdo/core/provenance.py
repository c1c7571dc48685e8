"""What produced a result: the code (git SHA, a hash of the package's source), the package
versions and the input files, and what changed since.

A run records :func:`environment` per session and the SHA-256 of the files it read
(``core.files.tracked_inputs``); :func:`changes_since` lists what differs now, so a resumed
run can refuse to mix results of two versions of the code or of an input file.

>>> env = environment()
>>> sorted(env)
['git_sha', 'packages', 'source_sha256']
>>> changes_since({**env, "inputs": {}})
[]
>>> first_difference({"a": {"b": 1}}, {"a": {"b": 2}})
'a.b: 1 then, 2 now'
"""

from __future__ import annotations

import subprocess
from collections.abc import Mapping
from importlib import metadata
from pathlib import Path
from typing import Any

from surrogate_rbrdo.core.files import input_changes, source_digest

PACKAGES = ("surrogate_rbrdo", "numpy", "scipy", "scikit-learn", "smt", "pymoo", "optuna",
            "joblib", "matplotlib", "pydantic", "dask", "distributed")


def git_sha(cwd: str | Path | None = None) -> str | None:
    """``git rev-parse HEAD`` in ``cwd`` (``None`` outside a repository)."""
    try:
        out = subprocess.run(["git", "rev-parse", "HEAD"], cwd=cwd, capture_output=True,
                             text=True, timeout=5, check=False)
    except (OSError, subprocess.SubprocessError):
        return None
    return out.stdout.strip() or None


def package_versions() -> dict[str, str | None]:
    """Installed versions of :data:`PACKAGES` (``None``: not installed)."""
    out: dict[str, str | None] = {}
    for p in PACKAGES:
        try:
            out[p] = metadata.version(p)
        except metadata.PackageNotFoundError:
            out[p] = None
    return out


def environment() -> dict[str, Any]:
    """The code in use: ``git_sha``, ``source_sha256`` (the package's source,
    :func:`~surrogate_rbrdo.core.files.source_digest`) and ``packages`` (versions)."""
    return {"git_sha": git_sha(Path(__file__).parent), "source_sha256": source_digest(),
            "packages": package_versions()}


def first_difference(a: Any, b: Any, where: str = "") -> str:
    """The first path where two nested dicts differ, ``"<path>: <a> then, <b> now"``."""
    if isinstance(a, dict) and isinstance(b, dict):
        for k in sorted(set(a) | set(b)):
            if a.get(k) != b.get(k):
                return first_difference(a.get(k), b.get(k), f"{where}.{k}" if where else k)
    return f"{where}: {a!r} then, {b!r} now"


def changes_since(recorded: Mapping[str, Any], inputs: Mapping[str, str] | None = None
                  ) -> list[str]:
    """What differs from ``recorded`` (``environment()`` plus ``inputs``, path → SHA-256):
    input files changed or gone, files read now that were not then (``inputs``), the source
    hash, package versions."""
    then = recorded.get("inputs", {})
    out = input_changes(then)
    out += [f"input file {p} (new)" for p in sorted(set(inputs or ()) - set(then))]
    now = environment()
    if recorded.get("source_sha256") not in (None, now["source_sha256"]):
        out.append("the code (source hash)")
    if recorded.get("packages") not in (None, now["packages"]):
        out.append(first_difference(recorded["packages"], now["packages"], "package versions"))
    return out


__all__ = ["PACKAGES", "changes_since", "environment", "first_difference", "git_sha",
           "package_versions"]
