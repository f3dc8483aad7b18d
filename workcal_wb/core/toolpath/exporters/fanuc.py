"""Fanuc TP source (.ls), as the controller (or Roboguide's MakeTP) reads it.

``/PROG``, ``/ATTR`` with the entries a controller writes, ``/MN`` with lines ``  12:L P[12] ...``
(line number, colon, motion type; other instructions after two spaces), remarks of at most
``REMARK_WIDTH`` characters, ``UFRAME_NUM=0`` (positions in the world frame = the robot base frame B)
and ``UTOOL_NUM`` per CAM tool, a joint move to the first point, linear moves, the CAM file's events
(remark, MESSAGE and PAUSE; WAIT for a dwell; UTOOL_NUM for a new tool), ``/POS`` (each position's
CONFIG from the reach check's solution when a robot is given, else ``--fanuc-config``) and ``/END``.  Over
``MAX_LINES`` lines the moves go into programs ``NAME_001.ls`` ... that ``NAME`` calls in order.
"""
from __future__ import annotations

from ...robots.configuration import fanuc_config
from ..orientation import fanuc_wpr_deg
from ..safety import numbers
from . import common

NAME, EXTENSION = "Fanuc LS", ".ls"
MACHINES = ("robot",)
CONTROLLERS = ("fanuc",)  # the robots whose controller runs this program (robots.model.CONTROLLERS)
MAX_NAME = 32  # program names: at most 36 characters, "_001" for parts
MAX_LINES = 9999  # /MN lines per program, as controllers and RoboDK's Fanuc post cap them
MAX_SPEED_MM_S = 2000.0  # linear speed limit (12000 cm/min)
REMARK_WIDTH = 29  # the teach pendant shows about 30 characters of a remark
MESSAGE_WIDTH = 24
JOINT_SPEED = "20%"
DATE = "DATE 26-01-01  TIME 00:00:00"  # fixed, so an export repeats to the byte


def positions_text(rotation, position, tools, configs) -> list[str]:
    """The /POS entries P[1..N] in order, ``configs`` one per position."""
    xyz, wpr = numbers(position, 3), numbers(fanuc_wpr_deg(rotation), 4)
    out = []
    for i, (tool, config) in enumerate(zip(tools, configs)):
        x, y, z = xyz[3 * i:3 * i + 3]
        w, p, r = wpr[3 * i:3 * i + 3]
        out += [f"P[{i + 1}]{{", "   GP1:", f"\tUF : 0, UT : {tool},\t\tCONFIG : '{config}',",
                f"\tX = {x} mm,\tY = {y} mm,\tZ = {z} mm,", f"\tW = {w} deg,\tP = {p} deg,\tR = {r} deg", "};"]
    return out


def remarks(text: str) -> list[str]:
    """Remark instructions of at most REMARK_WIDTH characters; ';' ends a TP line, so none inside."""
    return [f"! {piece} ;" for piece in common.wrapped([common.comment_text(text).replace(";", ",")], REMARK_WIDTH)]


def _event_lines(event) -> list[str]:
    act = common.action(event)
    lines = remarks(act.message)
    if act.dwell_s is not None:
        lines.append(f"WAIT {numbers([act.dwell_s], 2)[0]}(sec) ;")
    if act.tool is not None:
        lines.append(f"UTOOL_NUM={act.tool} ;")
    if act.stop:
        message = act.message.replace(";", ",").replace("[", "(").replace("]", ")")  # one line already (action)
        lines += [f"MESSAGE[{message[:MESSAGE_WIDTH]}] ;", "PAUSE ;"]
    return lines


def _program(name: str, comment: str, body: list, targets: list) -> str:
    """One TP program: body items are instruction strings or (motion letter, instruction)."""
    main = []
    for n, item in enumerate(body, start=1):
        main.append(f"{n:4d}:{item[0]} {item[1]}" if isinstance(item, tuple) else f"{n:4d}:  {item}")
    attributes = ["OWNER\t\t= MNEDITOR;", f"COMMENT\t\t= \"{comment}\";", "PROG_SIZE\t= 0;", f"CREATE\t\t= {DATE};",
                  f"MODIFIED\t= {DATE};", "FILE_NAME\t= ;", "VERSION\t\t= 0;", f"LINE_COUNT\t= {len(body)};",
                  "MEMORY_SIZE\t= 0;", "PROTECT\t\t= READ_WRITE;", "TCD:  STACK_SIZE\t= 0,",
                  "      TASK_PRIORITY\t= 50,", "      TIME_SLICE\t= 0,", "      BUSY_LAMP_OFF\t= 0,",
                  "      ABORT_REQUEST\t= 0,", "      PAUSE_REQUEST\t= 0;", "DEFAULT_GROUP\t= 1,*,*,*,*;",
                  "CONTROL_CODE\t= 00000000 00000000;"]
    return "\n".join([f"/PROG  {name}", "/ATTR", *attributes, "/MN", *main, "/POS", *targets, "/END"]) + "\n"


def render(job: common.ExportJob):
    """The main program (and its parts, when over the line limit)."""
    name = common.program_name(job, MAX_NAME, must_match_file=True).upper()
    path = common.robot_path(job, in_base_frame=True, max_speed_mm_s=MAX_SPEED_MM_S)
    if job.solved is None:
        configs = [job.options.fanuc_config] * len(path)
        configuration = (f"configuration: CONFIG '{job.options.fanuc_config}' on every position (no robot given to "
                         "solve it: set the robot's configuration at the workpiece with --fanuc-config)")
    else:
        configs = list(fanuc_config(job.options.robot, job.solved.joints))
        configuration = ("configuration: each position's CONFIG (flip, elbow, base side, turns of J1 J4 J6) from the "
                         "reach check's solution")
    first_tool = common.first_tool(path)
    tools = sorted({int(e.number) for e in path.events if e.kind == "tool_change"} | {first_tool})
    notes = ["units: mm, speeds in cm/min (whole numbers: the controller's resolution)",
             "angles: W, P, R in degrees, fixed axes X then Y then Z (R = Rz(R) Ry(P) Rx(W))",
             "positions: robot base frame B as the world frame (UFRAME 0)",
             configuration,
             "termination: CNT0, FINE where the robot stops", *common.robot_notes(job, "cm/min"),
             f"PLACEHOLDERS to fill: UTOOL {', '.join(map(str, tools))} = the spindle's TCP with that tool, "
             "Z along the tool into the part"]
    head = []
    for h in common.header_lines(job, NAME, notes):
        head += remarks(h)
    head += ["UFRAME_NUM=0 ;", f"UTOOL_NUM={first_tool} ;"]
    tool_of = common.tools_by_move(path, first_tool)

    def move(i, stops):
        if i == 0:
            return [(i, ("J", f"P[{{}}] {JOINT_SPEED} FINE ;"))]
        speed = max(1, round(path.feed[i] / 10.0))
        return [(i, ("L", f"P[{{}}] {speed}cm/min {'FINE' if stops(i) else 'CNT0'} ;"))]

    groups = common.move_groups(path, _event_lines, lambda c: "\n".join(remarks(c)), move)
    limit = (job.options.max_lines or MAX_LINES) - 5
    comment = "FORCED" if job.forced else "WorkCal"
    parts = list(common.packed(_split_remarks(groups), limit))
    if len(parts) == 1 and len(head) + len(parts[0]) <= (job.options.max_lines or MAX_LINES):
        yield job.out, [_program(name, comment, head + _positions_of(parts[0])[0],
                                 positions_text(*_targets(path, tool_of, configs, _positions_of(parts[0])[1])))]
        return
    for index, part in enumerate(parts, start=1):
        part_name = common.part_name(name, index)
        body, moves = _positions_of(part)
        note = remarks(f"WorkCal part {index} of {name}, result sha256 {common.fingerprint(job)}")
        yield (common.part_path(job, index),
               [_program(part_name, comment, note + body, positions_text(*_targets(path, tool_of, configs, moves)))])
    calls = [f"CALL {common.part_name(name, i)} ;" for i in range(1, len(parts) + 1)]
    yield job.out, [_program(name, comment, head + calls, [])]


def _split_remarks(groups):
    """Line groups with each remark of a comment on its own /MN line."""
    for lines in groups:
        yield [piece for item in lines for piece in (item.split("\n") if isinstance(item, str) else [item])]


def _positions_of(part: list) -> tuple[list, list]:
    """A part's body with P[] numbered from 1, and the move index of each P[]."""
    body, moves = [], []
    for item in part:
        if isinstance(item, tuple):
            i, (letter, text) = item
            moves.append(i)
            body.append((letter, text.format(len(moves))))
        else:
            body.append(item)
    return body, moves


def _targets(path, tool_of: list, configs: list, moves: list):
    return path.rotation[moves], path.position[moves], [tool_of[i] for i in moves], [configs[i] for i in moves]
