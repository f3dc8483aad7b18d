"""CSV of tool poses in the robot base frame: position, quaternion and KUKA-style ABC, feed."""
from __future__ import annotations

from ..orientation import kuka_abc_deg, quaternion_wxyz
from ..safety import number
from . import common

NAME, EXTENSION = "CSV poses", ".csv"
COLUMNS = "index,kind,x_mm,y_mm,z_mm,qw,qx,qy,qz,a_deg,b_deg,c_deg,feed_mm_min,source_line"


def render(job: common.ExportJob) -> str:
    notes = ["units: mm, feed in mm/min; lines starting with # are comments",
             "angles: quaternion qw qx qy qz (unit) and A B C in degrees, Z-Y'-X'' (R = Rz(A) Ry(B) Rx(C))",
             "positions: robot base frame B; comments of the source path are not carried", *common.robot_notes(job)]
    lines = [f"# {h}" for h in common.header_lines(job, NAME, notes)] + [COLUMNS]
    for i, target in enumerate(common.poses(job, in_base_frame=True), start=1):
        values = ([number(v, 4) for v in target.matrix[:3, 3]] + [number(v, 8) for v in quaternion_wxyz(target.matrix)]
                  + [number(v, 4) for v in kuka_abc_deg(target.matrix)] + [number(target.feed_mm_min, 3)])
        kind = "rapid" if target.rapid else "linear"
        lines.append(",".join([str(i), kind, *values, "" if target.line is None else str(target.line)]))
    return "\n".join(lines) + "\n"
