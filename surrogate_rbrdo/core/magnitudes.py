"""Plausible magnitudes of config values, from the unit in the field's name.

A field's unit is in its name (``speed_rpm``, ``span_mm``, ``duration_s``,
``sensitivity_V_per_m``; the project's rule), so one table says how large a value of each
unit can physically be in a spindle study (stiffness and damping, ``_N_per_m``, are not
bounded: a very large or infinite value is how a rigid link is modelled), and
:func:`check_magnitudes` refuses a finite but
absurd value (``speed_rpm = 1e300``) in any table of any kind, naming the field, its value
and what is allowed, before any work starts. The bounds are generous (they refuse nonsense,
not unusual designs); each states its reason. Unitless relative scatters (``*_sd``,
``*_cov``) are at most 1 (100 %).

>>> from dataclasses import dataclass
>>> @dataclass(frozen=True)
... class Campaign:
...     speeds_rpm: tuple[float, ...] = (6000.0,)
...     duration_s: float = 1.0
>>> try:
...     check_magnitudes(Campaign(speeds_rpm=(6000.0, 1e300)), "rig.campaign")
... except ValueError as exc:
...     print(str(exc)[:90])
rig.campaign.speeds_rpm[1] = 1e+300 is not allowed: must be at most 1e+06 rpm in magnitude
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Mapping
from typing import Any

from surrogate_rbrdo.core.validate import check_positive

#: (name suffix, largest magnitude, unit as shown, why), the longest suffixes first
UNIT_LIMITS: tuple[tuple[str, float, str, str], ...] = (
    ("_mm2_s", 1e5, "mm²/s", "ISO VG 3200, the most viscous lubricant grade, is 3 200 mm²/s"),
    ("_mm_s", 4e3, "mm/s", "G 4000 is the coarsest balance grade of ISO 21940-11"),
    ("_mm_min", 1e8, "mm/min", "n·dm of the fastest rolling bearings is below 4e6"),
    ("_V_per_ms2", 10.0, "V/(m/s²)", "accelerometers give at most ~1 V/(m/s²)"),
    ("_V_per_N", 10.0, "V/N", "impact hammers give at most ~0.1 V/N"),
    ("_V_per_m", 1e6, "V/m", "eddy-current probes give ~8 000 V/m"),
    ("_per_s", 1e9, "1/s", "a rate above 1 GHz"),
    ("_ms2", 1e6, "m/s²", "10⁵ g"),
    ("_rpm", 1e6, "rpm", "the fastest spindles, dental air turbines, run below 500 000 rpm"),
    ("_hz", 1e9, "Hz", "1 GHz: above any sensor bandwidth, sampling or counter clock used"),
    ("_mm", 1e4, "mm", "10 m: longer than any spindle"),
    ("_um", 1e4, "µm", "10 mm: beyond any spindle's clearances"),
    ("_ms", 1e6, "ms", "1 000 s"),
    ("_s", 1e6, "s", "12 days: longer than any record, ramp, run-up or endurance run"),
    ("_h", 1e6, "h", "over a century of operation"),
    ("_m", 10.0, "m", "longer than any spindle"),
    ("_pa", 1e12, "Pa", "1 TPa: above the modulus of the stiffest material, diamond"),
    ("_N", 1e7, "N", "10 MN: beyond any spindle's loads"),
    ("_V", 1e4, "V", "beyond any transducer or acquisition voltage"),
    ("_W", 1e7, "W", "10 MW: beyond any spindle motor"),
    ("_deg", 360.0, "deg", "one turn"),
    ("_sd", 1.0, "", "a relative standard deviation above 100 %"),
    ("_cov", 1.0, "", "a coefficient of variation above 100 %"),
)


def unit_limit(name: str) -> tuple[float, str, str] | None:
    """The limit, unit and reason a field name's suffix gives (``None``: no unit, or a
    compound unit ``_per_`` that the table does not list).

    >>> unit_limit("balance_grade_mm_s")[:2], unit_limit("preload_N")[:2], unit_limit("n_doe")
    ((4000.0, 'mm/s'), (10000000.0, 'N'), None)
    """
    for suffix, limit, unit, why in UNIT_LIMITS:
        # a compound unit (``_per_``) not listed gives no check
        if name.endswith(suffix) and ("_per_" in suffix or "_per_" not in name):
            return limit, unit, why
    return None


#: the smallest displacement limit δ_lim worth stating (µm): 1 nm, below the resolution of
#: any displacement probe used on a spindle (eddy-current probes resolve ~0.01-0.1 µm,
#: capacitive ones ~1 nm); below it P_f is that of the probe's noise, not of the spindle
MIN_DISPLACEMENT_LIMIT_UM = 1e-3


def check_displacement_limit(name: str, value_um: float) -> None:
    """Refuse a displacement limit (µm) that is not a finite number of at least
    :data:`MIN_DISPLACEMENT_LIMIT_UM`.

    >>> check_displacement_limit("delta_lim_um", 1e-9)
    Traceback (most recent call last):
    ...
    ValueError: delta_lim_um = 1e-09 is not allowed: must be at least 0.001 µm (1 nm, below \
the resolution of any displacement probe on a spindle)
    """
    check_positive(name, value_um)
    if value_um < MIN_DISPLACEMENT_LIMIT_UM:
        raise ValueError(f"{name} = {value_um:g} is not allowed: must be at least "
                         f"{MIN_DISPLACEMENT_LIMIT_UM:g} µm (1 nm, below the resolution of any "
                         "displacement probe on a spindle)")


def _cores() -> int:
    """The cores this process may use."""
    if hasattr(os, "sched_getaffinity"):
        return len(os.sched_getaffinity(0))
    return os.cpu_count() or 1


def max_workers() -> int:
    """The most worker processes a config may ask for (``n_jobs``): 4 x the cores this
    process may use (at least 8). The work is CPU-bound (BLAS pinned to one thread), so
    processes beyond the cores only add memory and start-up time; a little
    oversubscription is harmless and keeps a config portable between machines.

    >>> max_workers() >= 8
    True
    """
    return max(8, 4 * _cores())


def _check_workers(path: str, value: Any) -> None:
    top = max_workers()
    if isinstance(value, int) and not isinstance(value, bool) and value > top:
        raise ValueError(f"{path} = {value} is not allowed: must be at most {top} worker "
                         f"processes (4 x the {_cores()} cores here, at least 8): more "
                         "processes than cores only add memory and start-up time")


def _numbers(value: Any, path: str):
    """(path, number) of a number or of the numbers in nested tuples/lists."""
    if isinstance(value, bool):
        return
    if isinstance(value, (int, float)):
        yield path, value
    elif isinstance(value, (tuple, list)):
        for i, v in enumerate(value):
            yield from _numbers(v, f"{path}[{i}]")


def check_magnitudes(obj: Any, where: str = "", limit: tuple[float, str, str] | None = None
                     ) -> None:
    """Refuse a number whose magnitude exceeds its unit's :data:`UNIT_LIMITS` anywhere in a
    parsed config table ``obj`` (dataclasses, mappings and arrays of them; ``limit``: the
    unit of ``obj`` itself); ``where`` is its dotted path."""
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        for f in dataclasses.fields(obj):
            key = f.name[:-1] if f.name.endswith("_") else f.name
            if key == "n_jobs":
                _check_workers(f"{where}.{key}" if where else key, getattr(obj, f.name))
            check_magnitudes(getattr(obj, f.name), f"{where}.{key}" if where else key,
                             unit_limit(key))
    elif isinstance(obj, Mapping):
        for k, v in obj.items():
            check_magnitudes(v, f"{where}.{k}" if where else str(k), unit_limit(str(k)))
    elif isinstance(obj, (tuple, list)) and any(
            dataclasses.is_dataclass(v) or isinstance(v, Mapping) for v in obj):
        for i, v in enumerate(obj):
            check_magnitudes(v, f"{where}[{i}]", limit)
    elif limit is not None:
        top, unit, why = limit
        for path, v in _numbers(obj, where):
            if abs(v) > top:
                raise ValueError(f"{path} = {v!r} is not allowed: must be at most {top:g}"
                                 f"{' ' + unit if unit else ''} in magnitude ({why})")


__all__ = ["MIN_DISPLACEMENT_LIMIT_UM", "UNIT_LIMITS", "check_displacement_limit",
           "check_magnitudes", "max_workers", "unit_limit"]
