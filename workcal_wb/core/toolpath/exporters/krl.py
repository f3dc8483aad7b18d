"""KUKA KRL (.src): LIN moves, with the calibration either in $BASE or already applied to the points.

``base`` mode (default) keeps the path in workpiece coordinates and sets $BASE = W, the way KUKA
programs are meant to be re-used on a moved part; ``transformed`` writes positions in B.
"""
from __future__ import annotations

from ..orientation import kuka_abc_deg
from ..safety import number
from . import common

NAME, EXTENSION = "KUKA KRL", ".src"
MODES = ("base", "transformed")
TOOL_NUMBER = 1


def frame(T) -> str:
    """A KRL FRAME/POS aggregate {X, Y, Z, A, B, C} (mm, degrees)."""
    values = list(T[:3, 3]) + list(kuka_abc_deg(T))
    return "{" + ", ".join(f"{k} {number(v, 4)}" for k, v in zip("XYZABC", values)) + "}"


def render(job: common.ExportJob) -> str:
    name = common.program_name(job, max_len=24, must_match_file=True)
    base_mode = job.krl_mode == "base"
    where = (f"positions: workpiece frame X, relative to $BASE = {common.placement_name(job)}" if base_mode else
             "positions: robot base frame B, taken as KUKA WORLD ($BASE = $NULLFRAME, $ROBROOT at WORLD)")
    notes = ["units: mm, $VEL.CP in m/s, $APO.CDIS in mm",
             "angles: A, B, C in degrees, Z-Y'-X'' (A about Z, then B about the new Y, then C about the new X)",
             where, f"tool: TOOL_DATA[{TOOL_NUMBER}] must be the spindle's TCP, its Z along the tool into the part",
             *common.robot_notes(job)]
    lines = [";" + h for h in common.header_lines(job, NAME, notes)]
    lines += [f"DEF {name}()", "  BAS(#INITMOV, 0)",
              f"  $BASE = {frame(job.transform)}" if base_mode else "  $BASE = $NULLFRAME",
              f"  $TOOL = TOOL_DATA[{TOOL_NUMBER}]", f"  $APO.CDIS = {number(common.BLEND_MM, 3)}"]
    speed = None
    for pose in common.poses(job, in_base_frame=not base_mode):
        lines += [f"  ;{c}" for c in pose.comment.split("\n") if c]
        if pose.feed_mm_min != speed:
            speed = pose.feed_mm_min
            lines.append(f"  $VEL.CP = {number(speed / 60000.0, 6)}")
        lines.append(f"  LIN {frame(pose.matrix)} C_DIS")
    return "\n".join(lines + ["END"]) + "\n"
