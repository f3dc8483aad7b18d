"""Length units at file boundaries.  Inside WorkCal every length is a millimetre."""
from __future__ import annotations

from .errors import InputError

MM_PER_UNIT = {"mm": 1.0, "cm": 10.0, "m": 1000.0, "in": 25.4, "inch": 25.4, "um": 0.001}

# A workpiece, reference block or toolpath lies between these sizes; outside them the unit is suspect.
PLAUSIBLE_EXTENT_MM = (1.0, 20000.0)


def mm_per_unit(units: str) -> float:
    try:
        return MM_PER_UNIT[units.lower()]
    except (KeyError, AttributeError):
        raise InputError(f"unknown length unit {units!r}; use one of {', '.join(MM_PER_UNIT)}") from None


def extent_warning(extent_mm: float, name: str, units: str) -> str | None:
    """A warning when an object's size in mm says the file was read with the wrong unit."""
    low, high = PLAUSIBLE_EXTENT_MM
    if 0 < extent_mm < low:
        hint = "it is probably in metres: read it with units='m'" if extent_mm * 1000 >= low else "check its unit"
        return f"{name}: only {extent_mm:.4g} mm across when read as {units}; {hint}"
    if extent_mm > high:
        return f"{name}: {extent_mm / 1000:.4g} m across when read as {units}; check its unit (micrometres?)"
    return None
