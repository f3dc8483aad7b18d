"""Universal Robots URScript (.script): movel to poses in the robot base frame, in metres and radians."""
from __future__ import annotations

from ..orientation import rotation_vector_rad
from ..safety import number
from . import common

NAME, EXTENSION = "Universal Robots URScript", ".script"
ACCELERATION_M_S2 = 1.2  # URScript's own default for movel


def pose(T) -> str:
    """p[x, y, z, rx, ry, rz]: metres and a rotation vector in radians."""
    values = [number(v / 1000.0, 7) for v in T[:3, 3]] + [number(v, 7) for v in rotation_vector_rad(T)]
    return f"p[{', '.join(values)}]"


def render(job: common.ExportJob) -> str:
    name = common.program_name(job, max_len=64)
    notes = ["units: METRES and RADIANS (URScript), speeds v in m/s, acceleration a in m/s^2",
             "angles: rotation vector rx, ry, rz (axis times angle, radians)",
             "positions: robot base frame B (the UR base frame)",
             "tool: the active TCP (installation) must be the spindle's, its Z along the tool into the part",
             "blending: none (r=0), every target is reached exactly", *common.robot_notes(job)]
    lines = [f"# {h}" for h in common.header_lines(job, NAME, notes)] + [f"def {name}():"]
    for target in common.poses(job, in_base_frame=True):
        lines += [f"  # {c}" for c in target.comment.split("\n") if c]
        lines.append(f"  movel({pose(target.matrix)}, a={ACCELERATION_M_S2}, "
                     f"v={number(target.feed_mm_min / 60000.0, 6)}, r=0)")
    return "\n".join(lines + ["end"]) + "\n"
