"""Universal Robots URScript (.script): one program the controller's script interface runs as written.

``def name():`` in the first column is the first line and ``end`` the last; every line between is
indented (the header too, as # comments).  The program declares the calibration as a pose
(``workcal_base = W``) and one TCP per CAM tool (placeholders, checked before moving), moves with
movej to the first point (to the joint values of the reach check's solution when a robot is given, so
that the robot takes that configuration) and then movel to ``pose_trans(workcal_base, target)`` in metres and
radians, blending each corner by at most 0.4 of its shorter neighbouring segment, and writes the CAM
file's events as blocking popups (stops, spindle, coolant, tool change with set_tcp) and sleep
(dwell).
"""
from __future__ import annotations

import numpy as np

from ..orientation import rotation_vector_rad
from ..safety import numbers
from . import common

NAME, EXTENSION = "Universal Robots URScript", ".script"
MACHINES = ("robot",)
CONTROLLERS = ("ur",)  # the robots whose controller runs this program (robots.model.CONTROLLERS)
ACCELERATION_M_S2 = 1.2  # URScript's own default for movel
JOINT_ACCELERATION, JOINT_SPEED = 1.4, 1.05  # movej defaults, rad/s^2 and rad/s
# Joint values of movej in radians to this many decimals: 1e-10 rad is 1e-7 mm at the flange of a
# 1.3 m arm, so the joints reach the pose they were solved for to well under a micrometre.
JOINT_DECIMALS = 10
MAX_SPEED_MM_S = 1500.0  # tool speed limit of the default safety configuration
BLEND_SHARE = 0.4  # a blend radius covers at most this share of the shorter neighbouring segment
COMMENT_WIDTH = 76
MAX_NAME = 63
# URScript's keywords (Script Manual) and the functions and variables this program uses: a program named
# sleep would call itself
RESERVED = {w.upper() for w in """def end if elif else while return halt pause break continue sec thread run join kill
    global local True False None and or xor not enter_critical exit_critical movej movel popup sleep set_tcp
    pose_trans norm workcal_base""".split()}


def poses_text(rotation, position) -> list[str]:
    """p[x, y, z, rx, ry, rz]: metres and a rotation vector in radians, for stacks."""
    xyz, rv = numbers(np.asarray(position) / 1000.0, 7), numbers(rotation_vector_rad(rotation), 7)
    return [f"p[{', '.join(xyz[3 * i:3 * i + 3] + rv[3 * i:3 * i + 3])}]" for i in range(len(xyz) // 3)]


def tcp_name(number: int) -> str:
    return f"workcal_tcp_{number}"


def _string(text: str) -> str:
    """A URScript string of one line (common.comment_text) with no '"' nor '\\' (its quote and escape)."""
    return '"' + common.comment_text(text).replace('"', "'").replace("\\", "/") + '"'


def _event_lines(event) -> list[str]:
    act = common.action(event)
    lines = [f"  # {act.message}"]
    if act.dwell_s is not None:
        lines.append(f"  sleep({numbers([act.dwell_s], 3)[0]})")
    if act.stop:
        lines.append(f"  popup({_string('WorkCal: ' + act.message)}, \"WorkCal\", False, False, blocking=True)")
    if act.tool is not None:
        lines.append(f"  set_tcp({tcp_name(act.tool)})")
    return lines


def blend_radii_m(position: np.ndarray, stops) -> np.ndarray:
    """Blend radius per target (m): BLEND_MM, at most BLEND_SHARE of either neighbouring segment; 0 at
    the last target and where the robot must stop (``stops``: targets followed by an event)."""
    segment = np.linalg.norm(np.diff(position, axis=0), axis=1)
    before = np.concatenate([[0.0], segment])
    after = np.concatenate([segment, [0.0]])
    radius = np.minimum(common.BLEND_MM, BLEND_SHARE * np.minimum(before, after)) / 1000.0
    radius[list(stops)] = 0.0
    return radius


def render(job: common.ExportJob):
    path = common.robot_path(job, in_base_frame=False, max_speed_mm_s=MAX_SPEED_MM_S)
    tools = sorted({int(e.number) for e in path.events if e.kind == "tool_change"} | {1})
    name = common.program_name(job, MAX_NAME, reserved=RESERVED | {tcp_name(t).upper() for t in tools})
    first_tool = common.first_tool(path)
    events = common.events_by_move(path.events, len(path))
    notes = ["units: METRES and RADIANS (URScript), speeds v in m/s, acceleration a in m/s^2",
             "angles: rotation vector rx, ry, rz (axis times angle, radians)",
             f"positions: workpiece frame X; each target is pose_trans(workcal_base, target), workcal_base = "
             f"{common.placement_name(job)} in the robot base frame",
             f"blending: corners rounded by at most {common.BLEND_MM} mm (r in m), never past "
             f"{BLEND_SHARE:g} of a segment; none where the robot stops",
             *common.robot_notes(job, "m/s"),
             "program size: not split (URScript sets no line limit WorkCal knows of)",
             *(["first move: movej to the joint values (radians) of the reach check's solution at the first target, "
                "so the robot takes that configuration; they place the TCP set below at the first target"]
               if job.solved is not None else []),
             f"to run: send the file as it is to the controller's primary/secondary interface (port 30001/30002), "
             f"or in PolyScope insert it with a Script node (File) followed by a Script line {name}()",
             f"PLACEHOLDERS to fill: {', '.join(tcp_name(t) for t in tools)} = the spindle's TCP with that tool "
             "(metres, rotation vector), Z along the tool into the part (the program halts while it is zero)"]
    lines = [f"def {name}():"]
    lines += [f"  # {h}" for h in common.wrapped(common.header_lines(job, NAME, notes), COMMENT_WIDTH)]
    lines += [f"  workcal_base = {poses_text(job.transform[None, :3, :3], job.transform[None, :3, 3])[0]}"]
    lines += [f"  {tcp_name(t)} = p[0, 0, 0, 0, 0, 0]" for t in tools]
    first = tcp_name(first_tool)
    lines += [f"  if norm({first}) == 0:",
              f"    popup(\"WorkCal: set {first} to the spindle TCP, then restart\", \"WorkCal\", False, True, "
              "blocking=True)", "    halt", "  end", f"  set_tcp({first})"]
    targets = poses_text(path.rotation, path.position)
    first_joints = None if job.solved is None else numbers(np.radians(job.solved.first_joints), JOINT_DECIMALS)
    radii = numbers(blend_radii_m(path.position, [i - 1 for i in events if 0 < i <= len(path)] + [len(path) - 1]), 5)
    speeds = numbers(path.feed / 60000.0, 6)

    def move(i, stops):
        if i == 0 and first_joints is not None:
            return [f"  movej([{', '.join(first_joints)}], a={JOINT_ACCELERATION}, v={JOINT_SPEED})"]
        if i == 0:
            return [f"  movej(pose_trans(workcal_base, {targets[0]}), a={JOINT_ACCELERATION}, v={JOINT_SPEED})"]
        return [f"  movel(pose_trans(workcal_base, {targets[i]}), a={ACCELERATION_M_S2}, v={speeds[i]}, r={radii[i]})"]

    for group in common.move_groups(path, _event_lines, lambda c: f"  # {c}", move):
        lines += group
    return [(job.out, ["\n".join(lines + ["end"]) + "\n"])]
