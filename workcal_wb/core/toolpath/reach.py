"""A robot program checked against the robot that runs it, before a byte is written.

With a robot (``ExportOptions.robot``) and its tool (``ExportOptions.tool``, the TCP in the flange frame),
the poses the program commands (``common.robot_path`` in the robot base frame B, which W's B is: the
controller's base frame) are checked with ``robots.reach.check_reach``: a joint move to the first target,
linear moves after it, as every robot exporter writes them.  A program the robot cannot follow is refused
(``ReachRefused``: the first move it fails at, its source line, why, and where to put the part instead),
unless forced: then it is written with a FORCED banner saying why.  Without a robot the header says so.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..errors import InputError
from ..robots.model import Robot
from ..robots.placement import MARGIN_DEG, suggest_placement
from ..robots.reach import (ELBOW_NEAR_DEG, JOINT_MOVE, LINEAR_MOVE, SAMPLE_STEP_DEG, SAMPLE_STEP_MM,
                            SHOULDER_NEAR_MM, SHOULDER_SINGULARITY, WRIST_NEAR_DEG, WRIST_SINGULARITY,
                            ReachReport, check_reach, configuration_words, joint_name)
from .orientation import kuka_abc_deg
from .safety import ExportOptions, Placement, ReachRefused

NOT_CHECKED = "reach not checked (no robot given)"
# How the header and the messages name each controller's maker.
MAKERS = {"kuka": "KUKA", "abb": "ABB", "fanuc": "FANUC", "ur": "Universal Robots"}


def check_controller(robot: Robot | None, module) -> None:
    """Refuse a robot whose controller does not run the format's programs (InputError)."""
    if robot is None or robot.controller in module.CONTROLLERS:
        return
    if not module.CONTROLLERS:
        raise InputError(f"robot {robot.id}: {module.NAME} is written for machine tools; the reach of a robot is "
                         "checked for robot programs (KRL, RAPID, URScript, Fanuc LS, CSV)")
    raise InputError(f"robot {robot.id} ({robot.name}) is a {MAKERS[robot.controller]} robot: it does not run "
                     f"{module.NAME} programs (KUKA robots run KRL, ABB robots RAPID, FANUC robots Fanuc LS, "
                     "Universal Robots URScript)")


def tool_text(tool: np.ndarray) -> str:
    """The tool as KUKA writes a frame: X, Y, Z in mm and A, B, C in degrees (R = Rz(A) Ry(B) Rx(C))."""
    x, y, z = tool[:3, 3]
    a, b, c = kuka_abc_deg(tool)
    return f"X {x:.3f} Y {y:.3f} Z {z:.3f} mm, A {a:.3f} B {b:.3f} C {c:.3f} deg"


def checked_reach(toolpath, calibration, checked: Placement, options: ExportOptions) -> Placement:
    """``checked`` with the reach of ``options.robot`` added to its notes (or "not checked"); refuses
    (ReachRefused) a program the robot cannot follow unless ``options.force``, which adds the reason to
    the FORCED banner instead."""
    from .exporters import common

    robot = options.robot
    if robot is None:
        return replace(checked, notes=checked.notes + (NOT_CHECKED,))
    job = common.ExportJob(toolpath, calibration, checked.transform, checked.forced, None, options, "robot")
    path = common.robot_path(job, in_base_frame=True, max_speed_mm_s=np.inf)
    kinds = np.full(len(path), LINEAR_MOVE, dtype=np.int8)
    kinds[0] = JOINT_MOVE
    tool = np.asarray(options.tool, dtype=float)
    poses = np.zeros((len(path), 4, 4))
    poses[:, :3, :3], poses[:, :3, 3], poses[:, 3, 3] = path.rotation, path.position, 1.0
    report = check_reach(robot, poses, tool, kinds, path.line)
    notes = checked.notes + tuple(reach_notes(robot, tool, report))
    if report.reachable:
        return replace(checked, notes=notes, reach=report)
    suggestion = suggest_placement(robot, poses, tool, kinds, path.line)
    where = (f"Where the robot follows it with every joint {MARGIN_DEG:g} deg or more inside its limits: "
             f"{suggestion.describe()}, then calibrate again" if suggestion is not None else
             "No placement of the part on the platform was found where the robot follows it")
    failure = f"{robot.name} ({robot.id}) with the TCP {tool_text(tool)} cannot follow this program: {report.reason}"
    if not options.force:
        raise ReachRefused(f"{toolpath.source}: {failure}. {where}; nothing was written", report, suggestion)
    banner = (f"FORCED EXPORT: the reach check failed: {failure}.", f"{where}.",
              "Do not run this program before checking it in simulation, or by hand at low speed.")
    return replace(checked, forced=True, notes=notes, banner=checked.banner + banner, reach=report)


def reach_notes(robot: Robot, tool: np.ndarray, report: ReachReport) -> list[str]:
    """The header's lines on the reach check."""
    state = ("every robot target, and the linear moves between them every "
             f"{SAMPLE_STEP_MM:g} mm and {SAMPLE_STEP_DEG:g} deg, reachable in one configuration"
             if report.reachable else f"FAILED: {report.reason}")
    lines = [f"reach: checked for {robot.name} ({robot.id}) with the TCP {tool_text(tool)} in the flange frame "
             f"(one tool for every CAM tool): {state}"]
    if report.first_joints is not None and report.reachable:
        joints = ", ".join(f"{joint_name(robot, j)} {v:.3f}" for j, v in enumerate(report.first_joints))
        lines.append(f"reach: first target in configuration "
                     f"{configuration_words(robot, report.first_branch, report.first_joints)}, joints {joints} deg")
    if report.margin is not None:
        upto = "" if report.reachable else " (up to the failure)"
        m, w, e, s = report.margin, report.wrist, report.elbow, report.shoulder
        lines += [f"reach: smallest joint-limit margin{upto} {m.value:.1f} deg ({joint_name(robot, m.joint)} at "
                  f"{m.where.text()})",
                  f"reach: closest to the singularities{upto}: wrist {w.value:.1f} deg (joint 5 from 0 or 180 deg, at "
                  f"{w.where.text()}), elbow {e.value:.1f} deg (from stretched or folded, at {e.where.text()}), "
                  f"shoulder {s.value:.0f} mm (wrist point from axis 1, at {s.where.text()}); the header warns under "
                  f"{WRIST_NEAR_DEG:g} deg, {ELBOW_NEAR_DEG:g} deg and {SHOULDER_NEAR_MM:g} mm"]
        for code in report.near:
            what = {WRIST_SINGULARITY: "wrist", SHOULDER_SINGULARITY: "shoulder"}.get(code, "elbow")
            lines.append(f"reach: WARNING: the path comes close to the {what} singularity: the robot may slow down "
                         "there or stop with a singularity error; check it in simulation")
    return lines
