"""ABB RAPID (.mod): a module that loads beside the controller's own main module.

``MODULE MOD_name`` with the header as ! comments, the data it uses declared in it (a tooldata per
CAM tool, the work object whose uframe is W, zone and speeds), and ``PROC name()`` (never ``main``,
which the controller's own module has): a check that the tool is not still the flange, ConfJ/ConfL
off (on, with every robtarget's confdata from the reach check's solution, when a robot is given), a
MoveJ to the first point, MoveL to robtargets in workpiece coordinates, the CAM file's events
(TPWrite and Stop, WaitTime, the next tool).  Over ``MAX_LINES`` lines the moves go into part modules
``name_001.mod`` (``PROC name_001``) that ``name`` calls in order.
"""
from __future__ import annotations

import numpy as np

from ...robots.configuration import abb_confdata
from ..orientation import quaternion_wxyz
from ..safety import numbers
from . import common

NAME, EXTENSION = "ABB RAPID", ".mod"
MACHINES = ("robot",)
CONTROLLERS = ("abb",)  # the robots whose controller runs this program (robots.model.CONTROLLERS)
MAX_NAME = 24  # RAPID identifiers: at most 32 characters, "MOD_" + name + "_001"
MAX_LINES = 5000  # lines per module, as RoboDK's ABB post splits programs
MAX_SPEED_MM_S = 7000.0  # speeddata v_tcp limit
MAX_STRING = 80  # RAPID strings (TPWrite)
COMMENT_WIDTH = 78
WOBJ, ZONE = "wobjWorkCal", "zWorkCal"
_NO_EXTERNAL_AXES = "[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]"
# RAPID's reserved words (ABB technical reference manual), and main: the controller's own main module has it
RESERVED = set("""ALIAS AND BACKWARD CASE CONNECT CONST DEFAULT DIV DO ELSE ELSEIF ENDFOR ENDFUNC ENDIF ENDMODULE
    ENDPROC ENDRECORD ENDTEST ENDTRAP ENDWHILE ERROR EXIT FALSE FOR FROM FUNC GOTO IF INOUT LOCAL MOD MODULE NOSTEPIN
    NOT NOVIEW OR PERS PROC RAISE READONLY RECORD RETRY RETURN STEP SYSMODULE TEST THEN TO TRAP TRUE TRYNEXT UNDO VAR
    VIEWONLY WHILE WITH XOR MAIN""".split())
# RAPID's predefined data (a routine may not share a data object's name): zones, speeds, the default
# tool, work object and load.
PREDEFINED = set("""FINE Z0 Z1 Z5 Z10 Z15 Z20 Z30 Z40 Z50 Z60 Z80 Z100 Z150 Z200 V5 V10 V20 V30 V40 V50 V60 V80 V100
    V150 V200 V300 V400 V500 V600 V800 V1000 V1500 V2000 V2500 V3000 V4000 V5000 V6000 V7000 VMAX TOOL0 WOBJ0
    LOAD0""".split())


def tool_name(number: int) -> str:
    return f"tWorkCal{number}"


def poses_text(rotation, position) -> list[str]:
    """[[x, y, z], [q1, q2, q3, q4]] in mm and a unit quaternion (w, x, y, z), for stacks."""
    xyz, q = numbers(position, 4), numbers(quaternion_wxyz(rotation), 7)
    return [f"[[{','.join(xyz[3 * i:3 * i + 3])}],[{','.join(q[4 * i:4 * i + 4])}]]" for i in range(len(xyz) // 3)]


def _string(text: str) -> str:
    """A RAPID string of one line (common.comment_text) with no '"' nor '\\' (its quote and escape)."""
    return '"' + common.comment_text(text).replace('"', "'").replace("\\", "/")[:MAX_STRING] + '"'


def confdata_text(job: common.ExportJob, count: int) -> list[str]:
    """Every target's confdata [cf1,cf4,cf6,cfx]: from the reach check's solution, else 0,0,0,0 (which
    ConfJ\\Off and ConfL\\Off let the controller ignore)."""
    if job.solved is None:
        return ["[0,0,0,0]"] * count
    values = abb_confdata(job.options.robot, job.solved.joints)
    return ["[" + ",".join(map(str, row)) + "]" for row in np.asarray(values).tolist()]


def _moves(path, speed_names: dict, first_tool: int, confdata: list):
    """The body, one group of lines per target."""
    targets = poses_text(path.rotation, path.position)
    tools = common.tools_by_move(path, first_tool)

    def move(i, stops):
        kind, zone = ("MoveJ", "fine") if i == 0 else ("MoveL", "fine" if stops(i) else ZONE)
        return [f"    {kind} [{targets[i][1:-1]},{confdata[i]},{_NO_EXTERNAL_AXES}], {speed_names[path.feed[i]]}, "
                f"{zone}, {tool_name(tools[i])}\\WObj:={WOBJ};"]

    return common.move_groups(path, _event_lines, lambda c: f"    ! {c}", move)


def _event_lines(event) -> list[str]:
    act = common.action(event)
    lines = [f"    ! {act.message}"]
    if act.dwell_s is not None:
        lines.append(f"    WaitTime {numbers([act.dwell_s], 3)[0]};")
    if act.stop:
        lines += [f"    TPWrite {_string('WorkCal: ' + act.message)};", "    Stop;"]
    return lines


def _module(name: str, head: list[str], data: list[str], body: list[str]) -> str:
    return "\n".join([f"MODULE MOD_{name}", *head, *data, f"  PROC {name}()", *body, "  ENDPROC", "ENDMODULE"]) + "\n"


def render(job: common.ExportJob):
    """The main module (and its part modules, when over the line limit)."""
    path = common.robot_path(job, in_base_frame=False, max_speed_mm_s=MAX_SPEED_MM_S)
    tools = sorted({int(e.number) for e in path.events if e.kind == "tool_change"} | {1})
    first_tool = common.first_tool(path)
    speed_names = {f: f"vWorkCal{i}" for i, f in enumerate(dict.fromkeys(path.feed.tolist()), start=1)}
    confdata = confdata_text(job, len(path))
    monitored = job.solved is not None
    monitoring = "On" if monitored else "Off"  # configuration monitoring of MoveJ and MoveL
    configuration = ("configuration: ConfJ\\On and ConfL\\On, every robtarget's confdata [cf1,cf4,cf6,cfx] from "
                     "the reach check's solution (the robot stops rather than reach a target in another configuration)"
                     if monitored else "configuration: ConfJ\\Off and ConfL\\Off, robtargets carry cf 0,0,0,0 (the "
                     "robot keeps the configuration it starts in)")
    declared = {WOBJ, ZONE, *speed_names.values(), *map(tool_name, tools)}
    name = common.program_name(job, MAX_NAME, reserved=RESERVED | PREDEFINED | {d.upper() for d in declared})
    notes = ["units: mm, speeds (speeddata v_tcp) in mm/s",
             "angles: orientation quaternions q1..q4 = w, x, y, z (ABB order, unit length)",
             f"positions: workpiece frame X, in work object {WOBJ}: uframe = {common.placement_name(job)}, "
             "oframe identity",
             configuration, *common.robot_notes(job, "mm/s (speeddata)"),
             f"PLACEHOLDERS to fill: {', '.join(tool_name(t) for t in tools)} = the spindle's TCP and load with "
             "that tool, Z along the tool into the part (the program stops while the TCP is at the flange)"]
    head = [f"  ! {h}" for h in common.wrapped(common.header_lines(job, NAME, notes), COMMENT_WIDTH)]
    blend = numbers([common.BLEND_MM], 3)[0]
    data = [f"  PERS tooldata {tool_name(t)} := [TRUE,[[0,0,0],[1,0,0,0]],[1,[0,0,1],[1,0,0,0],0,0,0]];"
            for t in tools]
    data += [f"  PERS wobjdata {WOBJ} := [FALSE,TRUE,\"\",{poses_text(job.transform[None, :3, :3], job.transform[None, :3, 3])[0]},"
             "[[0,0,0],[1,0,0,0]]];",
             f"  CONST zonedata {ZONE} := [FALSE,{blend},{blend},{blend},0.01,{blend},0.01];",
             *[f"  CONST speeddata {v} := [{numbers([f / 60.0], 3)[0]},500,5000,1000];" for f, v in speed_names.items()]]
    t = tool_name(first_tool)
    setup = [f"    IF {t}.tframe.trans.x = 0 AND {t}.tframe.trans.y = 0 AND {t}.tframe.trans.z = 0 THEN",
             f"      TPWrite {_string(f'WorkCal: set {t} to the spindle TCP, then restart')};", "      EXIT;",
             "    ENDIF", f"    ConfJ\\{monitoring};", f"    ConfL\\{monitoring};"]
    limit = (job.options.max_lines or MAX_LINES) - 10

    def part(index, body):
        part_name = common.part_name(name, index)
        note = [f"  ! WorkCal part {index} of program {name}, result sha256 {common.fingerprint(job)}"]
        return common.part_path(job, index), [_module(part_name, note, [], body)]

    def main(count):
        return _module(name, head, data, setup + [f"    {common.part_name(name, i)};" for i in range(1, count + 1)])

    yield from common.program_files(job, _moves(path, speed_names, first_tool, confdata), limit,
                                    lambda body: _module(name, head, data, setup + body), part, main)
