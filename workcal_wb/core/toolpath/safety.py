"""What keeps a bad program off a controller: finite numbers, a work envelope, the calibration's gates.

Every check runs before a single byte is written; together with atomic writing this means a refused
export leaves no file behind and an older file untouched.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .. import frames
from ..errors import InputError, WorkCalError
from ..result import OK, CalibrationResult
from .model import RotaryTable
from .transform import DEFAULT_CHORD_TOL_MM, path_points, placement


class ExportRefused(WorkCalError):
    """The inputs were readable but exporting them would be unsafe (failed gates, envelope, NaN)."""


def number(value: float, decimals: int) -> str:
    """Fixed-point text of a finite number; every number an exporter writes goes through here."""
    if not math.isfinite(value):
        raise ExportRefused(f"refusing to write a non-finite number ({value})")
    text = f"{value:.{decimals}f}"
    return text.lstrip("-") if float(text) == 0 else text  # "0.000", never "-0.000"


@dataclass
class Envelope:
    """Axis-aligned box in the robot base frame B (mm) that every written position must lie in."""

    lower: np.ndarray
    upper: np.ndarray

    @classmethod
    def parse(cls, text: str) -> "Envelope":
        """From "xmin,ymin,zmin,xmax,ymax,zmax" (mm)."""
        try:
            values = [float(v) for v in text.split(",")]
        except ValueError:
            values = []
        if len(values) != 6 or not all(map(math.isfinite, values)):
            raise InputError(f"work envelope {text!r}: expected six numbers xmin,ymin,zmin,xmax,ymax,zmax in mm")
        lower, upper = np.array(values[:3]), np.array(values[3:])
        if np.any(lower >= upper):
            raise InputError(f"work envelope {text!r}: each minimum must be below its maximum")
        return cls(lower, upper)

    def describe(self) -> str:
        return ", ".join(f"{a} [{lo:g}, {hi:g}]" for a, lo, hi in zip("xyz", self.lower, self.upper))


def _where(toolpath, index: int) -> str:
    line = toolpath.moves[index].line
    return f"move {index + 1}" + (f" (line {line})" if line is not None else "")


def check_moves(toolpath) -> None:
    """Refuse non-finite feeds and tool axes (positions are checked in B by ``check_positions``)."""
    for i, move in enumerate(toolpath.moves):
        values = list(move.tool_axis) + ([] if move.feed is None else [move.feed])
        if not all(map(math.isfinite, values)):
            raise ExportRefused(f"{toolpath.source}: {_where(toolpath, i)} has a non-finite feed or tool axis; "
                                "nothing was written")


def check_positions(points_B: np.ndarray, owners, toolpath, envelope: Envelope | None) -> None:
    """Refuse the first non-finite or out-of-envelope point; ``owners[k]`` is the move of point k."""
    finite = np.all(np.isfinite(points_B), axis=1)
    inside = finite if envelope is None else finite & np.all(
        (points_B >= envelope.lower) & (points_B <= envelope.upper), axis=1)
    bad = np.flatnonzero(~inside)
    if bad.size == 0:
        return
    k = int(bad[0])
    where = _where(toolpath, int(owners[k]))
    if not finite[k]:
        raise ExportRefused(f"{toolpath.source}: {where} has a non-finite position; nothing was written")
    x, y, z = points_B[k]
    raise ExportRefused(f"{toolpath.source}: {where} reaches ({x:.3f}, {y:.3f}, {z:.3f}) mm in the robot base "
                        f"frame, outside the work envelope {envelope.describe()}; nothing was written")


def value_text(value) -> str:
    """A value for a comment: as it is, but "n/a" for NaN/inf (no non-finite number reaches a file)."""
    return "n/a" if isinstance(value, float) and not math.isfinite(value) else str(value)


def gate_text(gate: dict) -> str:
    """One quality gate in words: "gate rms_mm = 0.8 mm, limit 0.3"."""
    unit = f" {gate['unit']}" if gate.get("unit") else ""
    value, limit = value_text(gate.get("value")), value_text(gate.get("limit"))
    return f"gate {gate.get('name', '?')} = {value}{unit}, limit {limit}"


def failed_checks(calibration: CalibrationResult) -> list[str]:
    """The failed quality gates (or, without gates, the reasons) in words."""
    words = [gate_text(g) for g in calibration.quality_gates if not g.get("passed", False)]
    return words or list(calibration.reasons) or ["no reason recorded"]


def check_calibration(calibration: CalibrationResult, force: bool, source: str = "calibration") -> bool:
    """True when the export goes ahead only because it was forced; refuses a non-"ok" result otherwise."""
    if calibration.W is None:
        raise InputError(f"{source}: calibration has no transform W (status {calibration.status!r}); nothing to export")
    if calibration.status == OK:
        return False
    if not force:
        raise ExportRefused(
            f"{source}: calibration status is {calibration.status!r} ({'; '.join(failed_checks(calibration))}); "
            "refusing to export. Fix the calibration, or force the export (--force) "
            "and the file says FORCED at its top")
    return True


def forced_banner(calibration: CalibrationResult) -> list[str]:
    """The lines a forced export starts with."""
    return [
        f"FORCED EXPORT: the calibration did NOT pass its quality gates, status {calibration.status!r}.",
        "Failed: " + "; ".join(failed_checks(calibration)),
        "Do not run this program before checking the workpiece position by hand.",
    ]


def checked_placement(toolpath, calibration: CalibrationResult, *, force: bool = False,
                      envelope: Envelope | None = None, table: RotaryTable | None = None,
                      chord_tol_mm: float = DEFAULT_CHORD_TOL_MM,
                      source: str = "calibration") -> tuple[np.ndarray, bool]:
    """Every check an export needs, in one place: (X -> B transform to use, whether forced).

    Positions are checked in B along the whole path (arcs sampled within the chordal tolerance), so a
    program written in workpiece coordinates is held to the same envelope as one written in B."""
    if not (math.isfinite(chord_tol_mm) and chord_tol_mm > 0):
        raise InputError(f"chordal tolerance must be a positive number of mm, not {chord_tol_mm}")
    if not toolpath.moves:
        raise InputError(f"{toolpath.source}: no moves to export")
    forced = check_calibration(calibration, force, source)
    T = placement(calibration.W, table)
    check_moves(toolpath)
    points, owners = path_points(toolpath, chord_tol_mm)
    check_positions(frames.apply(T, points), owners, toolpath, envelope)
    return T, forced
