"""Fanuc TP source (.ls): linear moves to P[] positions in the world frame (UF 0), WPR fixed X-Y-Z."""
from __future__ import annotations

from ..orientation import fanuc_wpr_deg
from ..safety import number
from . import common

NAME, EXTENSION = "Fanuc LS", ".ls"
USER_TOOL = 1
CONFIG = "N U T, 0, 0, 0"


def position(index: int, T) -> list[str]:
    x, y, z = (number(v, 3) for v in T[:3, 3])
    w, p, r = (number(v, 4) for v in fanuc_wpr_deg(T))
    return [f"P[{index}]{{", "   GP1:", f"\tUF : 0, UT : {USER_TOOL},\t\tCONFIG : '{CONFIG}',",
            f"\tX = {x} mm,\tY = {y} mm,\tZ = {z} mm,", f"\tW = {w} deg,\tP = {p} deg,\tR = {r} deg", "};"]


def _remark(text: str) -> str:
    """A TP remark line; ';' ends a TP line, so it cannot appear inside one."""
    return "!" + text.replace(";", ",") + " ;"


def render(job: common.ExportJob) -> str:
    name = common.program_name(job, max_len=36, must_match_file=True).upper()
    notes = ["units: mm, speeds in cm/min (whole numbers: the controller's resolution)",
             "angles: W, P, R in degrees, fixed axes X then Y then Z (R = Rz(R) Ry(P) Rx(W))",
             "positions: robot base frame B as the world frame (UFRAME 0)",
             f"tool: UTOOL {USER_TOOL} must be the spindle's TCP, its Z along the tool into the part",
             f"configuration: CONFIG '{CONFIG}' on every position; check the wrist configuration",
             "termination: CNT0, FINE at the last position", *common.robot_notes(job)]
    body = [_remark(h) for h in common.header_lines(job, NAME, notes)]
    body += ["UFRAME_NUM=0 ;", f"UTOOL_NUM={USER_TOOL} ;"]
    positions = []
    targets = common.poses(job, in_base_frame=True)
    for i, target in enumerate(targets, start=1):
        body += [_remark(c) for c in target.comment.split("\n") if c]
        speed = max(1, round(target.feed_mm_min / 10.0))
        body.append(f"L P[{i}] {speed}cm/min {'FINE' if i == len(targets) else 'CNT0'} ;")
        positions += position(i, target.matrix)
    attributes = ["OWNER\t\t= MNEDITOR;", f"COMMENT\t\t= \"{'FORCED' if job.forced else 'WorkCal'}\";",
                  "PROG_SIZE\t= 0;", "FILE_NAME\t= ;", "VERSION\t\t= 0;", f"LINE_COUNT\t= {len(body)};",
                  "MEMORY_SIZE\t= 0;", "PROTECT\t\t= READ_WRITE;", "DEFAULT_GROUP\t= 1,*,*,*,*;"]
    lines = [f"/PROG  {name}", "/ATTR", *attributes, "/MN",
             *[f"{i:4d}:  {text}" for i, text in enumerate(body, start=1)], "/POS", *positions, "/END"]
    return "\n".join(lines) + "\n"
