"""One module per target format, each with NAME, EXTENSION and ``render(job) -> str``; ``export`` runs them.

``export`` is the only way a program reaches the disk: checks first (calibration gates, finite numbers,
work envelope in B), then the text is rendered in memory and written atomically.
"""
from __future__ import annotations

from pathlib import Path

from ...atomic import atomic_write_text
from ...errors import InputError
from ...result import CalibrationResult
from ..model import RotaryTable, Toolpath
from ..safety import Envelope, checked_placement
from ..transform import DEFAULT_CHORD_TOL_MM
from . import common, csv, fanuc, gcode, krl, rapid, urscript

FORMATS = {"krl": krl, "rapid": rapid, "urscript": urscript, "fanuc": fanuc, "gcode": gcode, "csv": csv}


def format_for(path) -> str:
    """The format whose usual extension ``path`` has."""
    suffix = Path(path).suffix.lower()
    for name, module in FORMATS.items():
        if module.EXTENSION == suffix:
            return name
    known = ", ".join(f"{m.EXTENSION} ({n})" for n, m in FORMATS.items())
    raise InputError(f"{path}: cannot tell the output format from the extension; use one of {known} or name the format")


def export(toolpath: Toolpath, calibration: CalibrationResult, fmt: str, out, *, force: bool = False,
           envelope: Envelope | None = None, table: RotaryTable | None = None,
           chord_tol_mm: float = DEFAULT_CHORD_TOL_MM,
           krl_mode: str = "base", rapid_feed_mm_min: float = common.DEFAULT_RAPID_FEED_MM_MIN,
           calibration_source: str = "calibration") -> common.ExportJob:
    """Write ``toolpath`` (workpiece frame, mm) as ``fmt`` to ``out``; refuses (ExportRefused) before writing."""
    if fmt not in FORMATS:
        raise InputError(f"unknown output format {fmt!r}; use one of {', '.join(FORMATS)}")
    if krl_mode not in krl.MODES:
        raise InputError(f"unknown KRL mode {krl_mode!r}; use one of {', '.join(krl.MODES)}")
    if not rapid_feed_mm_min > 0:
        raise InputError(f"rapid feed must be a positive number of mm/min, not {rapid_feed_mm_min}")
    T, forced = checked_placement(toolpath, calibration, force=force, envelope=envelope, table=table,
                                  chord_tol_mm=chord_tol_mm, source=calibration_source)
    job = common.ExportJob(toolpath, calibration, T, forced, Path(out), chord_tol_mm, table, krl_mode,
                           rapid_feed_mm_min)
    atomic_write_text(job.out, FORMATS[fmt].render(job))
    return job
