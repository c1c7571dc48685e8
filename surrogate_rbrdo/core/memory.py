"""Memory a configuration would need, checked before any work.

Options dataclasses whose sizes make arrays may say what they need with a method
``memory_bytes() -> {field: bytes}``: the peak bytes of the arrays each size field makes (the
largest term names the field to blame). A term sized by a product of fields is keyed
``"a*b"`` and blamed on all of them (``optimization.pop_size × n_gen = 100 × 200``).
:func:`check_memory` refuses a need larger than the memory available now, naming the field,
its value and the need; the runner calls it for every
config table that has ``memory_bytes`` (``runner.execute.prepare``), so a size that would not
fit is refused before a run folder exists, not after hours of work.

>>> from dataclasses import dataclass
>>> @dataclass(frozen=True)
... class Grid:
...     n: int = 10
...     def memory_bytes(self):
...         return {"n": 8.0 * self.n ** 2}
>>> check_memory(memory_needs(Grid(10), "grid"))
>>> check_memory(memory_needs(Grid(10 ** 9), "grid"))   # doctest: +ELLIPSIS
Traceback (most recent call last):
...
ValueError: grid.n = 1000000000 is not allowed: the arrays it sizes need ~8e+09 GB of memory...
>>> @dataclass(frozen=True)
... class Archive:
...     pop_size: int = 10
...     n_gen: int = 10
...     def memory_bytes(self):
...         return {"pop_size*n_gen": 128.0 * self.pop_size * self.n_gen}
>>> check_memory(memory_needs(Archive(10 ** 8, 10 ** 8), "opt"))   # doctest: +ELLIPSIS
Traceback (most recent call last):
...
ValueError: opt.pop_size × n_gen = 100000000 × 100000000 is not allowed: the arrays they size...
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any


def available_memory() -> int:
    """Bytes of memory available now (``MemAvailable``; else the physical memory)."""
    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemAvailable:"):
                return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")


class _Product:
    """The values of a product of size fields, shown ``a × b``."""

    def __init__(self, values: tuple[Any, ...]) -> None:
        self.values = values

    def __repr__(self) -> str:
        return " × ".join(repr(v) for v in self.values)


def memory_needs(options: Any, where: str, **context: Any) -> dict[str, tuple[Any, float]]:
    """``{"<where>.<field>": (value, bytes)}`` from ``options.memory_bytes(**context)`` (empty
    if it has none); a key ``"a*b"`` becomes ``"<where>.a × b"`` with the value ``a × b``.
    ``context``: what the caller knows and the options do not (e.g. the number of designs)."""
    method = getattr(options, "memory_bytes", None)
    if method is None:
        return {}
    out = {}
    for k, b in method(**context).items():
        names = tuple(k.split("*"))
        label = " × ".join(names)
        value = getattr(options, k, None) if len(names) == 1 else \
            _Product(tuple(getattr(options, n, None) for n in names))
        out[f"{where}.{label}" if where else label] = (value, float(b))
    return out


def table_needs(config: Any, where: str = "") -> list[dict[str, tuple[Any, float]]]:
    """The memory needs of every dataclass in ``config`` (itself and nested fields), one dict
    per dataclass that has ``memory_bytes``."""
    out = []
    if dataclasses.is_dataclass(config) and not isinstance(config, type):
        need = memory_needs(config, where)
        if need:
            out.append(need)
        for f in dataclasses.fields(config):
            sub = f"{where}.{f.name}" if where else f.name
            out += table_needs(getattr(config, f.name), sub)
    return out


def check_memory(needs: Mapping[str, tuple[Any, float]], *, have: float | None = None) -> None:
    """Refuse ``needs`` (``{field: (value, bytes)}``, arrays alive at once) if their sum
    exceeds the memory available now; the message names the field needing most."""
    if not needs:
        return
    total = sum(b for _, b in needs.values())
    have = available_memory() if have is None else have
    if total > have:
        field, (value, nbytes) = max(needs.items(), key=lambda kv: kv[1][1])
        share = "" if nbytes >= 0.999 * total else f" (of ~{total / 1e9:.3g} GB in all)"
        it = "they size" if isinstance(value, _Product) else "it sizes"
        raise ValueError(f"{field} = {value!r} is not allowed: the arrays {it} need "
                         f"~{nbytes / 1e9:.3g} GB of memory{share}, more than the "
                         f"{have / 1e9:.3g} GB available")


def require_memory(field: str, value: Any, nbytes: float, detail: str) -> None:
    """Refuse ``field = value`` if the arrays it sizes (``nbytes``, described by ``detail``)
    exceed the memory available now (one field; :func:`check_memory` for several).

    >>> require_memory("n", 10, 80.0, "the grid")
    >>> require_memory("n", 10 ** 12, 8e24, "the grid")   # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    ValueError: n = 1000000000000 is not allowed: the grid need ~8e+15 GB of memory, more than...
    """
    have = available_memory()
    if nbytes > have:
        raise ValueError(f"{field} = {value!r} is not allowed: {detail} need ~{nbytes / 1e9:.3g} "
                         f"GB of memory, more than the {have / 1e9:.3g} GB available")


__all__ = ["available_memory", "check_memory", "memory_needs", "require_memory", "table_needs"]
