"""Plain data (TOML/JSON) → validated frozen dataclasses, with one-line errors naming the
dotted path.

The schema of a config table, a geometry file or an effect *is* its dataclass (the
annotations give the types, ``__post_init__`` the ranges and choices), so there is one source
of truth for Python, config files and data files. pydantic (v2, strict) checks data against
it: no string is taken as a number or a boolean or split into characters, no float is
truncated to an integer, no NaN/inf passes, and unknown keys are refused. The data is
validated in JSON mode (TOML arrays are JSON arrays, so a tuple field takes ``[a, b]``; strict
Python mode would refuse any list for a tuple). The runner checks every config table with
:func:`parse`; the library parses geometry files (``SpindleGeometry.from_dict``) and effects
(``spindle.effects.effect_from_dict``) the same way. Errors come back as ``ValueError`` with
one line::

    optimization.weights = '0.5,0.5' is not allowed: must be an array, e.g. [1.0, 2.0]

>>> from dataclasses import dataclass
>>> @dataclass(frozen=True)
... class T:
...     n: int = 1
...     flag: bool = False
>>> parse(T, {"n": 3}, "table")
T(n=3, flag=False)
>>> parse(T, {"flag": "no"}, "table")
Traceback (most recent call last):
...
ValueError: table.flag = 'no' is not allowed: must be true or false
"""

from __future__ import annotations

import dataclasses
import json
import keyword
import re
import tomllib
import types
import typing
from collections import abc
from collections.abc import Mapping
from functools import cache
from pathlib import Path
from typing import Any

from pydantic import ConfigDict, TypeAdapter, ValidationError, create_model

from surrogate_rbrdo.core.files import read_input
from surrogate_rbrdo.core.magnitudes import check_magnitudes

WHAT = {
    "int_type": "an integer", "int_from_float": "an integer", "int_parsing": "an integer",
    "float_type": "a number", "float_parsing": "a number", "bool_type": "true or false",
    "bool_parsing": "true or false", "string_type": "a string",
    "dataclass_type": "a table", "dict_type": "a table", "model_type": "a table",
    "mapping_type": "a table", "finite_number": "a finite number",
}
SCALARS = {str: "a string", float: "a number", int: "an integer", bool: "true or false"}


#: a message that starts with a path below the failing value: ``k_N_per_m = ...``
SUBPATH = re.compile(r"([A-Za-z_]\w*(?:\[\d+\])*(?:\.[A-Za-z_]\w*(?:\[\d+\])*)*) = ")


def load_toml(path: str | Path, what: str = "config file") -> dict[str, Any]:
    """Read a TOML file; a missing, unreadable or non-UTF-8 file or a syntax error names the
    file (:func:`~surrogate_rbrdo.core.files.read_input`, so the file's hash is tracked)."""
    data = read_input(path, what)
    try:
        return tomllib.loads(data.decode("utf-8-sig"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise ValueError(f"{what} {str(path)!r} is not valid TOML: {exc}") from None


def load_data(path: str | Path, what: str = "file") -> Any:
    """Read a ``.toml`` or ``.json`` data file (errors name ``what`` and the file)."""
    path = Path(path)
    if path.suffix not in (".toml", ".json"):
        raise ValueError(f"{what} {str(path)!r} is not allowed: the suffix must be .toml or "
                         ".json")
    if path.suffix == ".toml":
        return load_toml(path, what)
    data = read_input(path, what)
    try:
        return json.loads(data.decode("utf-8-sig"))
    except (ValueError, UnicodeDecodeError) as exc:
        raise ValueError(f"{what} {str(path)!r} is not valid JSON: {exc}") from None


def dotted(loc: tuple[Any, ...]) -> str:
    """``("a", "b", 0)`` → ``"a.b[0]"``."""
    out = ""
    for part in loc:
        out += f"[{part}]" if isinstance(part, int) else (f".{part}" if out else str(part))
    return out


def _short(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


@cache
def _adapter(cls: type) -> Any:
    config = ConfigDict(strict=True, extra="forbid", allow_inf_nan=False,
                        arbitrary_types_allowed=True)
    model = create_model(f"{cls.__name__}Table", __config__=config, value=(cls, ...))
    return TypeAdapter(model)


def _unwrap(tp: Any) -> Any:
    """``X | None`` → ``X``."""
    args = [a for a in typing.get_args(tp) if a is not type(None)]
    if typing.get_origin(tp) in (typing.Union, types.UnionType) and len(args) == 1:
        return args[0]
    return tp


def _members(tp: Any) -> dict[str, Any]:
    """The members of a union of two or more types (``X | Y``) by pydantic's tag, the name it
    puts into an error's location (``"tuple[float, ...]"``, ``"dict[str,float]"``)."""
    args = [a for a in typing.get_args(tp) if a is not type(None)]
    if typing.get_origin(tp) not in (typing.Union, types.UnionType) or len(args) < 2:
        return {}
    return {_tag(a.__name__ if isinstance(a, type) else str(a)): a for a in args}


def _tag(name: str) -> str:
    """A union member's name as pydantic writes it (``tuple[()]`` is ``tuple[]``)."""
    return name.replace(" ", "").replace("()", "")


def _is_tag(cls: Any, head: tuple[Any, ...], part: Any) -> bool:
    """Whether ``part`` of a location after ``head`` names a union member (not a key)."""
    return isinstance(part, str) and _tag(part) in _members(type_at(cls, head))


def type_at(cls: Any, loc: tuple[Any, ...]) -> Any:
    """The annotation reached from ``cls`` along ``loc`` (dataclass fields, mapping values,
    tuple items, union members by their tag); ``None`` when the path leaves the schema."""
    tp = cls
    for part in loc:
        tp = _unwrap(tp)
        origin, args = typing.get_origin(tp), typing.get_args(tp)
        member = _members(tp).get(_tag(part)) if isinstance(part, str) else None
        if member is not None:
            tp = member
        elif dataclasses.is_dataclass(tp) and isinstance(part, str):
            tp = typing.get_type_hints(tp).get(part)
        elif origin in (dict, Mapping, abc.Mapping) and len(args) == 2:
            tp = args[1]
        elif origin is tuple and isinstance(part, int):
            tp = args[0] if len(args) == 2 and args[1] is Ellipsis else (
                args[part] if part < len(args) else None)
        else:
            return None
        if tp is None:
            return None
    return _unwrap(tp)


def fields_at(cls: type, loc: tuple[Any, ...]) -> list[str] | None:
    """Field names of the dataclass reached from ``cls`` along ``loc`` (``None``: not one)."""
    tp = type_at(cls, loc)
    return [_key(f.name) for f in dataclasses.fields(tp)] if dataclasses.is_dataclass(tp) \
        else None


def _key(name: str) -> str:
    """A field's config key: ``from_`` (a Python keyword with ``_``) is written ``from``."""
    return name[:-1] if name.endswith("_") and keyword.iskeyword(name[:-1]) else name


def _length(cls: type, loc: tuple[Any, ...]) -> int | None:
    """The fixed length of the tuple at ``loc`` (``None``: not a fixed-length tuple)."""
    tp = type_at(cls, loc)
    args = typing.get_args(tp)
    if typing.get_origin(tp) is tuple and not (len(args) == 2 and args[1] is Ellipsis):
        return len(args)
    return None


def _array(cls: type, loc: tuple[Any, ...]) -> str:
    """What an array at ``loc`` holds, for messages."""
    tp = type_at(cls, loc)
    args = typing.get_args(tp)
    item = _unwrap(args[0]) if args else None
    n = _length(cls, loc)
    size = f"{n} " if n is not None else ""
    if item is str:
        return f'an array of {size}strings, e.g. ["a", "b"]'
    if dataclasses.is_dataclass(item) or typing.get_origin(item) in (dict, abc.Mapping):
        return f"an array of {size}tables"
    if typing.get_origin(item) is tuple:
        return "an array of arrays, e.g. [[1.0, 0.0], [0.0, 1.0]]"
    example = ", ".join(f"{k + 1}.0" for k in range(n if n is not None else 2))
    return f"an array of {size}numbers, e.g. [{example}]"


def _shown(cls: type, loc: tuple[Any, ...]) -> tuple[Any, ...]:
    """``loc`` without union-member tags (the path a user wrote)."""
    return tuple(p for i, p in enumerate(loc) if not _is_tag(cls, loc[:i], p))


def _mismatch(cls: type, err: Mapping[str, Any]) -> bool:
    """An error saying only that the value does not have one union member's shape."""
    loc = tuple(err["loc"][1:])
    return bool(loc) and err["type"].endswith("_type") and _is_tag(cls, loc[:-1], loc[-1])


def _either(cls: type, loc: tuple[Any, ...]) -> str:
    """What a union at ``loc`` allows: ``an array of numbers, ... or a table {a, b}``."""
    out = []
    for member in _members(type_at(cls, loc)).values():
        if dataclasses.is_dataclass(member):
            out.append(f"a table {{{', '.join(f.name for f in dataclasses.fields(member))}}}")
        elif typing.get_origin(member) in (dict, abc.Mapping):
            out.append("a table")
        elif typing.get_origin(member) is tuple:
            out.append(_array(member, ()))
        else:
            out.append(SCALARS.get(member, str(member)))
    return " or ".join(out)


def _message(cls: type, err: Mapping[str, Any], where: str, union: bool = False) -> str:
    loc = tuple(err["loc"][1:])          # drop the wrapper field
    if union:                            # the value has the shape of no member of a union
        path = ".".join(p for p in (where, dotted(_shown(cls, loc[:-1]))) if p)
        return (f"{path} = {_short(err.get('input'))} is not allowed: must be "
                f"{_either(cls, loc[:-1])}")
    shown = _shown(cls, loc)
    path = ".".join(p for p in (where, dotted(shown)) if p)
    kind = err["type"]
    if kind in ("unexpected_keyword_argument", "extra_forbidden"):
        allowed = fields_at(cls, loc[:-1])
        what = "table" if len(loc) == 1 and not where and isinstance(err.get("input"),
                                                                      Mapping) else "key"
        return f"unknown {what} {path}; allowed: {sorted(allowed or [])}"
    if kind in ("missing", "missing_argument") and loc and isinstance(loc[-1], int):
        parent = ".".join(p for p in (where, dotted(shown[:-1])) if p)
        return (f"{parent} = {_short(err.get('input'))} is not allowed: must be "
                f"{_array(cls, loc[:-1])}")
    if kind in ("missing", "missing_argument"):
        return f"{path} is missing: it is required"
    if kind == "value_error":
        msg = str(err["ctx"]["error"])
        last = str(shown[-1]) if shown else where.rsplit(".", 1)[-1]
        if msg.startswith(f"unknown key {last}.") and path:     # from a nested parse
            return f"unknown key {path}{msg[len('unknown key ') + len(last):]}"
        if msg.startswith(f"{last}."):
            msg = msg[len(last) + 1:]
        first = msg.split(" ", 1)[0].split("[", 1)[0].split(".", 1)[0]
        head = SUBPATH.match(msg)
        fields = fields_at(cls, loc) or []
        if head is not None and head.group(1) == last and path and first not in fields:
            return f"{path}{msg[len(last):]}"          # "law = ..." raised at law
        if first in fields or first.startswith("unknown") or head:
            return f"{path}.{msg}" if path and not first.startswith("unknown") else msg
        return f"{path}: {msg}" if path else msg
    what = _array(cls, loc) if kind in ("tuple_type", "list_type") else WHAT.get(kind)
    if what is None:
        ctx = err.get("ctx") or {}
        n = _length(cls, loc)
        if kind in ("too_short", "too_long") and n is not None:
            what = f"an array of {n} items"
        elif kind in ("too_short", "too_long") and "max_length" in ctx:
            what = f"an array of at most {ctx['max_length']} items"
        elif kind in ("too_short", "too_long"):
            what = f"an array of at least {ctx.get('min_length')} items"
        else:
            what = err["msg"][0].lower() + err["msg"][1:]
            what = what.removeprefix("input should be ")
    return f"{path} = {_short(err.get('input'))} is not allowed: must be {what}"


def _json_ready(value: Any) -> Any:
    """TOML data as JSON (dates become strings, which no numeric field takes)."""
    if isinstance(value, Mapping):
        return {str(k): _json_ready(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_json_ready(v) for v in value]
    if value is None or isinstance(value, (bool, int, float, str)):
        return value
    return str(value)


def parse(cls: type, data: Any, where: str = "") -> Any:
    """Validate ``data`` (TOML-like: tables, arrays, scalars) into the dataclass ``cls``.

    ``where`` is the dotted path of ``data`` in the config (prefixes every message). Every
    number is also checked against the unit its field's name carries
    (:func:`~surrogate_rbrdo.core.magnitudes.check_magnitudes`).
    """
    if not isinstance(data, Mapping):
        raise ValueError(f"{where or 'config'} = {_short(data)} is not allowed: must be a "
                         "table")
    text = json.dumps({"value": _json_ready(data)})
    try:
        value = _adapter(cls).validate_json(text).value
    except ValidationError as exc:
        errors = exc.errors()
        fits = [e for e in errors if not _mismatch(cls, e)]
        raise ValueError(_message(cls, (fits or errors)[0], where, union=not fits)) from None
    check_magnitudes(value, where)     # a finite but absurd value for its field's unit
    return value


def table_defaults(schema: type, tables: tuple[str, ...]) -> str:
    """``[table] field=value, ...`` of the ``tables`` of ``schema`` as they are when the table
    is left out (``None`` fields, whose default depends on other fields, are not shown), read
    from the schema itself.

    >>> @dataclasses.dataclass(frozen=True)
    ... class Limit:
    ...     delta_lim_um: float = 19.5
    >>> @dataclasses.dataclass(frozen=True)
    ... class Config:
    ...     limit: Limit = dataclasses.field(default_factory=Limit)
    >>> table_defaults(Config, ("limit",))
    '[limit] delta_lim_um=19.5'
    """
    out = []
    for f in dataclasses.fields(schema):
        if f.name not in tables or f.default_factory is dataclasses.MISSING:
            continue
        value = f.default_factory()
        if not dataclasses.is_dataclass(value):
            continue
        shown = ", ".join(f"{g.name}={getattr(value, g.name)!r}"
                          for g in dataclasses.fields(value)
                          if getattr(value, g.name) is not None)
        out.append(f"[{f.name}] {shown}")
    return "; ".join(out)


__all__ = ["dotted", "fields_at", "load_data", "load_toml", "parse", "table_defaults",
           "type_at"]
