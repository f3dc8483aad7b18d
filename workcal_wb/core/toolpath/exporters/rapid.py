"""ABB RAPID (.mod): MoveL to robtargets in workpiece coordinates, through a wobjdata whose uframe is W."""
from __future__ import annotations

from ..orientation import quaternion_wxyz
from ..safety import number
from . import common

NAME, EXTENSION = "ABB RAPID", ".mod"
WOBJ, ZONE, TOOL = "wobjWorkCal", "zWorkCal", "tSpindle"
_NO_EXTERNAL_AXES = "[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]"


def pose(T) -> str:
    """[[x, y, z], [q1, q2, q3, q4]] in mm and a unit quaternion (w, x, y, z)."""
    return (f"[[{','.join(number(v, 4) for v in T[:3, 3])}],"
            f"[{','.join(number(v, 7) for v in quaternion_wxyz(T))}]]")


def render(job: common.ExportJob) -> str:
    name = common.program_name(job, max_len=32)
    notes = ["units: mm, speeds (speeddata v_tcp) in mm/s",
             "angles: orientation quaternions q1..q4 = w, x, y, z (ABB order, unit length)",
             f"positions: workpiece frame X, in work object {WOBJ}: "
             f"uframe = {common.placement_name(job)}, oframe identity",
             f"tool: {TOOL} must be declared on the controller: the spindle's TCP, its Z along the tool into the part",
             "configuration: ConfL\\Off, robtargets carry cf 0,0,0,0", *common.robot_notes(job)]
    speeds: dict[float, str] = {}
    moves = []
    targets = common.poses(job, in_base_frame=False)
    for i, target in enumerate(targets):
        speed = speeds.setdefault(target.feed_mm_min, f"vWorkCal{len(speeds) + 1}")
        zone = "fine" if i == len(targets) - 1 else ZONE
        moves += [f"    ! {c}" for c in target.comment.split("\n") if c]
        moves.append(f"    MoveL [{pose(target.matrix)[1:-1]},[0,0,0,0],{_NO_EXTERNAL_AXES}], "
                     f"{speed}, {zone}, {TOOL}\\WObj:={WOBJ};")
    blend = number(common.BLEND_MM, 3)
    lines = [f"MODULE {name}", *[f"  ! {h}" for h in common.header_lines(job, NAME, notes)],
             f"  PERS wobjdata {WOBJ} := [FALSE,TRUE,\"\",{pose(job.transform)},[[0,0,0],[1,0,0,0]]];",
             f"  CONST zonedata {ZONE} := [FALSE,{blend},{blend},{blend},0.01,{blend},0.01];",
             *[f"  CONST speeddata {v} := [{number(f / 60.0, 3)},500,5000,1000];" for f, v in speeds.items()],
             "  PROC main()", "    ConfL\\Off;", *moves, "  ENDPROC", "ENDMODULE"]
    return "\n".join(lines) + "\n"
