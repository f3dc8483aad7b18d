"""Toolpaths in: FreeCAD Path/CAM Jobs, operations and Path objects, and G-code files, as core Toolpaths
in the workpiece frame X.

Reading is duck-typed on what FreeCAD 0.20 (``Path``, ``PathScripts``) and 1.x (``CAM``, ``Path.Main``)
share: a Job has ``Operations.Group``; an operation or ``Path::Feature`` has ``.Path.Commands``.  So no
version switch is needed here.  FreeCAD stores feeds in mm/s: they are converted to the core's mm/min.
A *source* is what the setup remembers as the document's toolpath (``fc.setup.toolpath_of``): a Job,
an operation or Path object, or a G-code file path.
"""
from __future__ import annotations

import os

import numpy as np

from workcal_wb.core.errors import InputError
from workcal_wb.core.toolpath import RAPID, Toolpath, linearised, parse_gcode, read_gcode
from workcal_wb.core.toolpath.exporters.common import comment_text
from workcal_wb.core.toolpath.gcode import gcode_comment

# FreeCAD's feeds are mm/s, the core's mm/min.
SECONDS_PER_MINUTE = 60.0


def is_job(obj) -> bool:
    return hasattr(obj, "Operations") and hasattr(obj.Operations, "Group")


def jobs(doc) -> list:
    """The document's Path/CAM Jobs."""
    return [o for o in doc.Objects if is_job(o)]


def source_label(source) -> str:
    return os.path.basename(os.fspath(source)) if isinstance(source, (str, os.PathLike)) else source.Label


def read_source(source) -> Toolpath:
    """A source (Job, Path object or G-code file path) as a Toolpath in the workpiece frame X."""
    if source is None:
        raise InputError("no toolpath chosen: choose a Path/CAM Job or a G-code file first")
    if isinstance(source, (str, os.PathLike)):
        return read_gcode(os.fspath(source))
    return read_toolpath(source)


def toolpath_points(source) -> np.ndarray:
    """The cutting points (X, mm) of a source: where the calibration's uncertainty matters."""
    tp = linearised(read_source(source))
    cutting = [m.end for m in tp.moves if m.kind != RAPID]
    points = np.array(cutting) if cutting else tp.points()
    if len(points) == 0:
        raise InputError(f"{source_label(source)}: the toolpath has no moves")
    return points


def _paths(obj) -> list:
    """The objects whose ``Path`` make up ``obj``: a Job's active operations in order, or obj itself."""
    if is_job(obj):
        ops = [op for op in obj.Operations.Group if hasattr(op, "Path") and getattr(op, "Active", True)]
        if not ops:
            raise InputError(f"Job {obj.Label!r}: no active operation with a path")
        return ops
    if hasattr(obj, "Path") and hasattr(obj.Path, "Commands"):
        return [obj]
    raise InputError(f"{obj.Label!r} is neither a Path/CAM Job nor an operation or Path object")


def _gcode_line(command) -> str:
    """One command as one line of G-code in mm and mm/min (fixed-point: the reader takes no exponents),
    a comment's text on one line (comment_text: FreeCAD keeps a comment command's name as given, line
    breaks and all; it parses any other name into a word and parameters).

    A/B words are read as WorkCal's tool-axis angles (as the G-code exporter writes them); C is refused."""
    if command.Name.startswith("("):
        return gcode_comment(comment_text(command.Name[1:-1] if command.Name.endswith(")") else command.Name[1:]))
    words = [f"{k}{v * SECONDS_PER_MINUTE if k == 'F' else v:.9f}" for k, v in command.Parameters.items()]
    return " ".join([command.Name] + words)


def read_toolpath(obj) -> Toolpath:
    """The toolpath of a Job (all active operations, modal state carried across) or of one Path object.

    Positions are in the Job's frame, i.e. the workpiece frame X; "line N" in errors is command N."""
    source = f"{obj.TypeId} {obj.Label!r}"
    lines = []
    for op in _paths(obj):
        lines += [_gcode_line(c) for c in op.Path.Commands]
    return parse_gcode("\n".join(lines), source=source)
