"""G-code (.nc) in the robot/machine base frame B: arcs kept where W keeps their plane, A/B when the tool tilts."""
from __future__ import annotations

from ..gcode import IGNORED_G, format_gcode
from ..orientation import is_vertical
from ..transform import transformed
from . import common

NAME, EXTENSION = "G-code", ".nc"


def render(job: common.ExportJob) -> str:
    path = transformed(job.toolpath, job.transform, job.chord_tol_mm)
    ignored = " ".join(f"G{g:g}" for g in sorted(IGNORED_G))
    notes = ["units: mm G21, feed F in mm/min, absolute positions G90, arc centres I J K incremental",
             "positions: tool tip in the robot/machine base frame B",
             f"arcs: kept where their plane stays XY, ZX or YZ, otherwise chords within {job.chord_tol_mm} mm",
             f"not carried over: M S T H D words and {ignored}"]
    if not all(is_vertical(m.tool_axis) for m in path.moves):
        notes.append("5-axis: A about X, B about Y in degrees, tool axis from tip to spindle = Ry B * Rx A * +Z; "
                     "XYZ is the tool tip, so the controller needs tool-centre-point control")
    return format_gcode(path, common.header_lines(job, NAME, notes))
