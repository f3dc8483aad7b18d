"""Length units at file boundaries.  Inside WorkCal every length is a millimetre."""
from __future__ import annotations

import numpy as np

from .errors import InputError

MM_PER_UNIT = {"mm": 1.0, "cm": 10.0, "m": 1000.0, "in": 25.4, "inch": 25.4, "um": 0.001}

# A workpiece, reference block or toolpath lies between these sizes; outside them the unit is suspect.
PLAUSIBLE_EXTENT_MM = (1.0, 20000.0)
# The size of a cloud is that of its bulk (the box from the 1st to the 99th percentile); a point
# farther than this many bulk sizes from the bulk's centre is a stray point, not a sign of a unit.
STRAY_DISTANCE = 10.0
# The bulk of a cloud is measured on at most about this many of its points.
BULK_SAMPLE = 1_000_000


def mm_per_unit(units: str) -> float:
    try:
        return MM_PER_UNIT[units.lower()]
    except (KeyError, AttributeError):
        raise InputError(f"unknown length unit {units!r}; use one of {', '.join(MM_PER_UNIT)}") from None


# The units a file read in the wrong one is most likely in, tried in this order (metres before inches:
# scanners and CAD exports write metres far more often than inches).
LIKELY_UNITS = ("mm", "m", "in", "cm", "um")


def bulk_size(points: np.ndarray) -> float:
    """The diagonal of the box from the 1st to the 99th percentile of the points (mm): their size
    without a few stray points."""
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    if len(points) < 2:
        return 0.0
    sample = points[::-(-len(points) // BULK_SAMPLE)]  # every k-th point: the bulk of millions is that of a million
    low_corner, high_corner = np.percentile(sample, [1, 99], axis=0)
    return float(np.linalg.norm(high_corner - low_corner))


def likely_unit(size_mm: float, units: str) -> str | None:
    """The unit that gives a cloud ``size_mm`` across (read in ``units``) a plausible size, when ``units``
    does not; None when its size is plausible, or no unit makes it so."""
    low, high = PLAUSIBLE_EXTENT_MM
    if size_mm <= 0 or low <= size_mm <= high:
        return None
    numbers = size_mm / mm_per_unit(units)  # the size in the file's own numbers
    return next((u for u in LIKELY_UNITS if u != units.lower() and low <= numbers * MM_PER_UNIT[u] <= high), None)


def unit_warning(points: np.ndarray, name: str, units: str, unit_option: str = "unit") -> tuple[str, str | None]:
    """(warning, the unit to read it in instead) when the cloud's size in mm says the file was read in
    the wrong unit, else ("", None).  ``unit_option`` is how the caller's user sets the unit."""
    bulk = bulk_size(points)
    low, high = PLAUSIBLE_EXTENT_MM
    suggestion = likely_unit(bulk, units)
    if 0 < bulk < low:
        hint = (f"it is probably in metres: read it with {unit_option} m" if suggestion == "m" else
                f"read it with {unit_option} {suggestion}" if suggestion else f"check its unit ({unit_option})")
        return f"{name}: only {bulk:.4g} mm across when read as {units}; {hint}", suggestion
    if bulk > high:
        hint = (f"read it with {unit_option} {suggestion}" if suggestion else
                f"check its unit ({unit_option}; micrometres?)")
        return f"{name}: {bulk / 1000:.4g} m across when read as {units}; {hint}", suggestion
    return "", None


def extent_warnings(points: np.ndarray, name: str, units: str, unit_option: str = "unit") -> list[str]:
    """Warnings when a cloud's size in mm says the file was read with the wrong unit, or when a few
    points lie far from all the others (which says nothing about the unit).  ``unit_option`` is how
    the caller's user sets the unit ("--model-units" on the command line), for the hint."""
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    if len(points) < 2:
        return []
    sample = points[::-(-len(points) // BULK_SAMPLE)]
    bulk = bulk_size(points)
    warnings = []
    centre, distance = np.median(sample, axis=0), np.zeros(len(points))
    with np.errstate(over="ignore", invalid="ignore"):
        for k in range(3):  # a column at a time: no offset copy of millions of points
            offset = points[:, k] - centre[k]
            offset *= offset
            distance += offset
        distance = np.sqrt(distance, out=distance)
    stray = distance > STRAY_DISTANCE * max(bulk, 1e-9)
    if stray.any():
        warnings.append(f"{name}: {int(stray.sum())} of {len(points)} points lie far from all the others (up to "
                        f"{float(distance[stray].max()):.4g} mm away, the rest is {bulk:.4g} mm across): stray "
                        "points or a corrupt file?")
    text, _ = unit_warning(points, name, units, unit_option)
    if text:
        warnings.append(text)
    return warnings
