"""KUKA KRL (.src): a module the controller loads as written (the krl.g4 grammar's structure).

``&ACCESS`` lines, then ``DEF name( )`` on the first statement line (no comment may come before it),
the declaration ``EXT BAS``, the header as ; comments, initialisation (BAS #INITMOV, tool, base),
a check that the tool is not still the flange, ``PTP XHOME`` (the controller's own home, also the
BCO run), a PTP to the first point (a POS with the Status and Turn of the reach check's solution when a
robot is given, so that the controller takes that configuration), LIN moves with $VEL.CP, the CAM
file's events (HALT with a
comment, WAIT SEC, tool selection), ``PTP XHOME``, ``END``.  Over ``MAX_LINES`` lines the moves go
into numbered part modules ``name_001.src`` ... that the main module calls in order.

``base`` mode (default) keeps the path in workpiece coordinates and sets $BASE = $ROBROOT:W, the way
KUKA programs are meant to be re-used on a moved part; ``transformed`` writes positions in B
($BASE = $ROBROOT).
"""
from __future__ import annotations

import re

from ...robots.configuration import kuka_status_turn
from ..orientation import kuka_abc_deg
from ..safety import numbers
from . import common

NAME, EXTENSION = "KUKA KRL", ".src"
MACHINES = ("robot",)
CONTROLLERS = ("kuka",)  # the robots whose controller runs this program (robots.model.CONTROLLERS)
MODES = ("base", "transformed")
MAX_NAME = 24  # KRL names: at most 24 characters
MAX_LINES = 2500  # lines per module, as RoboDK's KUKA posts split programs
MAX_SPEED_MM_S = 2000.0  # $VEL.CP limit of KR C4 ($VEL_MA.CP, 2 m/s on most robots)
COMMENT_WIDTH = 80
PTP_PERCENT = 20
# the keywords of the krl.g4 grammar, and the names this program uses
RESERVED = set("""AND ANIN ANOUT B_AND B_NOT B_OR B_EXOR BOOL BRAKE C_DIS C_ORI C_PTP C_VEL CASE CAST_FROM CAST_TO
    CHAR CIRC_REL CIRC CONST CONTINUE DELAY DECL DEF DEFAULT DEFDAT DEFFCT DO ELSE END ENDDAT ENDFCT ENDFOR ENDIF
    ENDLOOP ENDSWITCH ENDWHILE ENUM EXIT EXT EXTFCT FALSE FOR GLOBAL GOTO HALT IF IMPORT INTERRUPT INT IS LIN_REL LIN
    LOOP MAXIMUM MINIMUM NOT OR PRIO PTP_REL PTP PUBLIC REAL REPEAT RETURN SEC SIGNAL STRUC SWITCH THEN TO TRIGGER
    TRUE UNTIL WAIT WHEN WHILE EXOR BAS XHOME TOOL_DATA""".split())
ACCESS = ["&ACCESS RVP", "&REL 1"]


def frames_text(rotation, position) -> list[str]:
    """KRL FRAME/POS aggregates {X, Y, Z, A, B, C} (mm, degrees) for stacks of rotations and positions."""
    values = numbers(position, 4), numbers(kuka_abc_deg(rotation), 4)
    xyz = [values[0][i:i + 3] for i in range(0, len(values[0]), 3)]
    abc = [values[1][i:i + 3] for i in range(0, len(values[1]), 3)]
    return ["{" + ", ".join(f"{k} {v}" for k, v in zip("XYZABC", p + a)) + "}" for p, a in zip(xyz, abc)]


def frame(T) -> str:
    return frames_text(T[None, :3, :3], T[None, :3, 3])[0]


def comment(text: str) -> str:
    """A KRL comment line: ``;`` and the text (one line: common.comment_text), never a fold marker
    (``;FOLD`` / ``;ENDFOLD`` make the KUKA editor fold away the lines between them)."""
    text = common.comment_text(text)
    return ";" + ("- " + text if _FOLD.match(text) else text)


_FOLD = re.compile(r"\s*(END)?FOLD", re.IGNORECASE)


def _event_lines(event) -> list[str]:
    act = common.action(event)
    lines = [comment(act.message)]
    if act.dwell_s is not None:
        lines.append(f"WAIT SEC {numbers([act.dwell_s], 3)[0]}")
    if act.stop:
        lines.append("HALT")
    if act.tool is not None:
        lines.append(f"BAS(#TOOL, {act.tool})")
    return lines


def status_turn(job: common.ExportJob) -> tuple[int, int] | None:
    """Status and Turn of the first target in the reach check's solution (None without one)."""
    if job.solved is None:
        return None
    status, turn = kuka_status_turn(job.options.robot, job.solved.first_joints)
    return int(status), int(turn)


def _moves(path, first_status_turn):
    """The body, one group of lines per target."""
    targets = frames_text(path.rotation, path.position)
    if first_status_turn is not None:
        targets[0] = targets[0][:-1] + ", S {}, T {}}}".format(*first_status_turn)
    speed = [None]

    def move(i, stops):
        if i == 0:
            return [f"PTP {targets[0]}"]
        lines = []
        if path.feed[i] != speed[0]:
            speed[0] = path.feed[i]
            lines.append(f"$VEL.CP = {numbers([speed[0] / 60000.0], 6)[0]}")
        return lines + [f"LIN {targets[i]}" + ("" if stops(i) else " C_DIS")]

    return common.move_groups(path, _event_lines, comment, move)


def _module(name: str, head: list[str], body: list[str]) -> str:
    return "\n".join(ACCESS + [f"DEF {name}( )", "EXT BAS (BAS_COMMAND :IN, REAL :IN)", *head, *body, "END"]) + "\n"


def render(job: common.ExportJob):
    """The main module (and its parts, when over the line limit)."""
    name = common.program_name(job, MAX_NAME - 4, must_match_file=True, reserved=RESERVED)
    base_mode = job.options.krl_mode == "base"
    path = common.robot_path(job, in_base_frame=not base_mode, max_speed_mm_s=MAX_SPEED_MM_S)
    tools = sorted({int(e.number) for e in path.events if e.kind == "tool_change"}) or [1]
    first_tool = common.first_tool(path)
    where = (f"positions: workpiece frame X, relative to $BASE = $ROBROOT:{common.placement_name(job)}" if base_mode
             else "positions: robot base frame B ($BASE = $ROBROOT)")
    first_status_turn = status_turn(job)
    if first_status_turn is not None:
        s, t = first_status_turn
        configuration = [f"configuration: the PTP to the first point carries Status S {s} ('B{s:03b}') and Turn T {t} "
                         f"('B{t:06b}') of the reach check's solution, so the robot takes that configuration; the LIN "
                         "moves keep it"]
    else:
        configuration = []
    notes = ["units: mm, $VEL.CP in m/s, $APO.CDIS in mm",
             "angles: A, B, C in degrees, Z-Y'-X'' (A about Z, then B about the new Y, then C about the new X)",
             where, *configuration, *common.robot_notes(job, "m/s ($VEL.CP)"),
             f"PLACEHOLDERS to fill on the controller: TOOL_DATA[{'], TOOL_DATA['.join(map(str, tools))}] = the "
             "spindle's TCP with that tool, Z along the tool into the part (the program halts while it is unset); "
             "XHOME = a safe home the robot reaches from anywhere"]
    head = [comment(h) for h in common.wrapped(common.header_lines(job, NAME, notes), COMMENT_WIDTH)]
    setup = ["BAS(#INITMOV, 0)", f"BAS(#TOOL, {first_tool})",
             f"$BASE = $ROBROOT:{frame(job.transform)}" if base_mode else "$BASE = $ROBROOT",
             f"IF (TOOL_DATA[{first_tool}].X == 0) AND (TOOL_DATA[{first_tool}].Y == 0) AND "
             f"(TOOL_DATA[{first_tool}].Z == 0) THEN",
             f";TOOL_DATA[{first_tool}] is still the flange: set the spindle's TCP, then restart", "HALT", "ENDIF",
             f"$APO.CDIS = {numbers([common.BLEND_MM], 3)[0]}", f"BAS(#VEL_PTP, {PTP_PERCENT})", "PTP XHOME"]
    limit = (job.options.max_lines or MAX_LINES) - 10

    def part(index, body):
        part_name = common.part_name(name, index)
        note = f";WorkCal part {index} of program {name}, result sha256 {common.fingerprint(job)}"
        return common.part_path(job, index), [_module(part_name, [note], body)]

    def main(count):
        calls = [f"{common.part_name(name, i)}( )" for i in range(1, count + 1)]
        return _module(name, head, setup + calls + ["PTP XHOME"])

    yield from common.program_files(job, _moves(path, first_status_turn), limit, lambda body: _module(
        name, head, setup + body + ["PTP XHOME"]), part, main)
