"""Name -> object registries, filled where the objects are defined.

>>> reg = Registry("estimator")
>>> @reg.register("mc")
... class MC:
...     pass
>>> reg.get("mc") is MC
True
>>> reg.get("nope")
Traceback (most recent call last):
...
ValueError: unknown estimator 'nope'; known: mc
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping
from typing import Any, TypeVar

T = TypeVar("T")


class Registry(Mapping[str, Any]):
    """A read-only mapping of names to objects with a ``register`` decorator.

    Parameters
    ----------
    kind : str
        What the registry holds (used in error messages), e.g. ``"estimator"``.
    """

    def __init__(self, kind: str) -> None:
        self.kind = kind
        self._items: dict[str, Any] = {}

    def register(self, name: str) -> Callable[[T], T]:
        """Decorator registering the decorated object under ``name``; duplicates raise."""

        def deco(obj: T) -> T:
            if name in self._items:
                raise ValueError(f"duplicate {self.kind} name {name!r}: already registered")
            self._items[name] = obj
            return obj

        return deco

    def get(self, name: str) -> Any:  # type: ignore[override]
        """Return the object registered as ``name``; an unknown name lists the known ones."""
        try:
            return self._items[name]
        except KeyError:
            known = ", ".join(sorted(self._items)) or "(none)"
            raise ValueError(f"unknown {self.kind} {name!r}; known: {known}") from None

    def __getitem__(self, name: str) -> Any:
        return self.get(name)

    def __iter__(self) -> Iterator[str]:
        return iter(self._items)

    def __len__(self) -> int:
        return len(self._items)

    def __repr__(self) -> str:
        return f"Registry({self.kind!r}, {sorted(self._items)})"
