"""FreeCAD Path/CAM toolpaths in, calibrated Path objects and Robot trajectories out.

Reading is duck-typed on what FreeCAD 0.20 (``Path``, ``PathScripts``) and 1.x (``CAM``, ``Path.Main``)
share: a Job has ``Operations.Group``; an operation or ``Path::Feature`` has ``.Path.Commands``.  So no
version switch is needed here; only creating Jobs (tests, GUI) has to pick ``PathScripts.PathJob`` or
``Path.Main.Job``.  FreeCAD stores feeds in mm/s: they are converted to the core's mm/min both ways.
"""
from __future__ import annotations

import Path

from workcal_wb.core.errors import InputError, MissingDependency
from workcal_wb.core.result import CalibrationResult
from workcal_wb.core.toolpath import (DEFAULT_CHORD_TOL_MM, Envelope, ExportOptions, RotaryTable, Toolpath, parse_gcode,
                                      transformed)
from workcal_wb.core.toolpath.exporters.common import DEFAULT_RAPID_FEED_MM_MIN, ExportJob, robot_path
from workcal_wb.core.toolpath.gcode import AXES, MOTION_CODE, OFFSET_AXIS, PLANE_OF_AXIS, PLANES
from workcal_wb.core.toolpath.model import ARC_CCW, ARC_CW, KINDS
from workcal_wb.core.toolpath.safety import checked_placement, forced_banner
from workcal_wb.fc.placements import placement

SECONDS_PER_MINUTE = 60.0


def is_job(obj) -> bool:
    return hasattr(obj, "Operations") and hasattr(obj.Operations, "Group")


def _paths(obj) -> list:
    """The objects whose ``Path`` make up ``obj``: a Job's active operations in order, or obj itself."""
    if is_job(obj):
        ops = [op for op in obj.Operations.Group if hasattr(op, "Path") and getattr(op, "Active", True)]
        if not ops:
            raise InputError(f"Job {obj.Label!r}: no active operation with a path")
        return ops
    if hasattr(obj, "Path") and hasattr(obj.Path, "Commands"):
        return [obj]
    raise InputError(f"{obj.Label!r} is neither a Path/CAM Job nor an operation or Path object")


def _gcode_line(command) -> str:
    """One command as G-code in mm and mm/min (fixed-point: the reader takes no exponents).

    A/B words are read as WorkCal's tool-axis angles (as the G-code exporter writes them); C is refused."""
    if command.Name.startswith("("):
        return command.Name
    words = [f"{k}{v * SECONDS_PER_MINUTE if k == 'F' else v:.9f}" for k, v in command.Parameters.items()]
    return " ".join([command.Name] + words)


def read_toolpath(obj) -> Toolpath:
    """The toolpath of a Job (all active operations, modal state carried across) or of one Path object.

    Positions are in the Job's frame, i.e. the workpiece frame X; "line N" in errors is command N."""
    source = f"{obj.TypeId} {obj.Label!r}"
    lines = []
    for op in _paths(obj):
        lines += [_gcode_line(c) for c in op.Path.Commands]
    return parse_gcode("\n".join(lines), source=source)


def _commands(path: Toolpath) -> list:
    """Path commands of a toolpath whose arcs lie in a machine plane: positions only (see make_path_object)."""
    commands = []
    starts, arc = path.starts(), -1
    for i in range(len(path)):
        commands += [Path.Command(f"({c})") for c in path.comments.get(i, "").split("\n") if c]
        kind = KINDS[path.kind[i]]
        params = dict(zip(AXES, map(float, path.end[i])))
        if kind in (ARC_CW, ARC_CCW):
            arc += 1
            normal, centre = path.arc_normal[arc], path.arc_centre[arc]
            axis = int(abs(normal).argmax())
            if normal[axis] < 0:
                kind = ARC_CW if kind == ARC_CCW else ARC_CCW
            plane = PLANE_OF_AXIS[axis]
            commands.append(Path.Command(f"G{plane}"))
            params.update({k: float(centre[OFFSET_AXIS[k]] - starts[i][OFFSET_AXIS[k]]) for k in PLANES[plane][1]})
        if kind != "rapid":
            params["F"] = float(path.feed[i]) / SECONDS_PER_MINUTE
        commands.append(Path.Command(MOTION_CODE[kind], params))
    return commands


def make_path_object(doc, toolpath: Toolpath, calibration: CalibrationResult, *, force: bool = False,
                     envelope: Envelope | None = None, table: RotaryTable | None = None,
                     chord_tol_mm: float = DEFAULT_CHORD_TOL_MM, name: str = "WorkCalPath"):
    """A ``Path::Feature`` holding ``toolpath`` moved into B, after the same checks as a file export.

    Positions only: FreeCAD's Path treats A/B words as rotary axes and would draw the path displaced,
    so the tool axis (in every exported program) is not written into the Path object."""
    options = ExportOptions(force=force, envelope=envelope, table=table, chord_tol_mm=chord_tol_mm,
                            calibration_source=f"calibration for {name}")
    T, forced = checked_placement(toolpath, calibration, options)
    moved = transformed(toolpath, T, chord_tol_mm)
    header = (forced_banner(calibration) if forced else []) + moved.header
    commands = [Path.Command(f"({c})") for c in header] + _commands(moved)
    commands += [Path.Command(f"({c})") for c in moved.footer]
    obj = doc.addObject("Path::Feature", name)
    obj.Path = Path.Path(commands)
    if forced:
        obj.Label = f"{name} (FORCED)"
    return obj


def robot_available() -> bool:
    try:
        import Robot  # noqa: F401
    except ImportError:
        return False
    return True


def make_robot_trajectory(doc, toolpath: Toolpath, calibration: CalibrationResult, *, force: bool = False,
                          envelope: Envelope | None = None, table: RotaryTable | None = None,
                          chord_tol_mm: float = DEFAULT_CHORD_TOL_MM,
                          rapid_feed_mm_min: float = DEFAULT_RAPID_FEED_MM_MIN, name: str = "WorkCalTrajectory"):
    """A Robot ``TrajectoryObject`` of LIN waypoints in B (velocities in mm/s), tool orientation as the exporters.

    Waypoints are not continuous: FreeCAD blends continuous ones with a fixed 3 mm radius, which KDL
    rejects on chords shorter than that (and FreeCAD 0.20 aborts on the error)."""
    try:
        import Robot
    except ImportError as exc:
        raise MissingDependency("FreeCAD's Robot workbench is not available in this FreeCAD; "
                                "export KRL or CSV instead") from exc
    options = ExportOptions(force=force, envelope=envelope, table=table, chord_tol_mm=chord_tol_mm,
                            rapid_feed_mm_min=rapid_feed_mm_min, calibration_source=f"calibration for {name}")
    T, forced = checked_placement(toolpath, calibration, options)
    path = robot_path(ExportJob(toolpath, calibration, T, forced, None, options, "robot"), in_base_frame=True,
                      max_speed_mm_s=float("inf"))
    waypoints = [Robot.Waypoint(placement(path.matrix(i)), type="LIN", name=f"P{i + 1}",
                                vel=float(path.feed[i]) / SECONDS_PER_MINUTE, cont=False) for i in range(len(path))]
    obj = doc.addObject("Robot::TrajectoryObject", name)
    obj.Trajectory = Robot.Trajectory(waypoints)
    if forced:
        obj.Label = f"{name} (FORCED)"
    return obj
