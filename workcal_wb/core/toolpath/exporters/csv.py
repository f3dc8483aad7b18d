"""CSV of tool poses in the robot base frame: position, quaternion and KUKA-style ABC, feed."""
from __future__ import annotations

import numpy as np

from ..orientation import kuka_abc_deg, quaternion_wxyz
from ..safety import numbers
from . import common

NAME, EXTENSION = "CSV poses", ".csv"
MACHINES = ("robot",)
CONTROLLERS = ("kuka", "abb", "fanuc", "ur")  # poses any robot's reach can be checked for
COLUMNS = "index,kind,x_mm,y_mm,z_mm,qw,qx,qy,qz,a_deg,b_deg,c_deg,feed_mm_min,source_line"


def render(job: common.ExportJob):
    path = common.robot_path(job, in_base_frame=True, max_speed_mm_s=np.inf)
    notes = ["units: mm, feed in mm/min; lines starting with # are comments",
             "angles: quaternion qw qx qy qz (unit) and A B C in degrees, Z-Y'-X'' (R = Rz(A) Ry(B) Rx(C))",
             "positions: robot base frame B; comments and events of the source path are not carried",
             *common.robot_notes(job, "mm/min")]
    lines = [f"# {common.comment_text(h)}" for h in common.header_lines(job, NAME, notes)] + [COLUMNS]
    xyz = np.array(numbers(path.position, 4)).reshape(-1, 3)
    q = np.array(numbers(quaternion_wxyz(path.rotation), 8)).reshape(-1, 4)
    abc = np.array(numbers(kuka_abc_deg(path.rotation), 4)).reshape(-1, 3)
    feed = numbers(path.feed, 3)
    for i in range(len(path)):
        kind = "rapid" if path.rapid[i] else "linear"
        line = str(path.line[i]) if path.line[i] else ""
        lines.append(",".join([str(i + 1), kind, *xyz[i], *q[i], *abc[i], feed[i], line]))
    return [(job.out, ["\n".join(lines) + "\n"])]
