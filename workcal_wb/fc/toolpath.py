"""Toolpaths out: the calibrated toolpath, robot programs and Robot trajectories (reading them in, from
Path/CAM Jobs and G-code files, is toolpath_input.py's).

A *source* is what the setup remembers as the document's toolpath (``fc.setup.toolpath_of``): a Job,
an operation or Path object, or a G-code file path.  ``make_calibrated_path`` shows it carried into
the robot base frame B by a calibration's W (a ``Path::FeaturePython`` that follows the calibration),
``export_program`` writes it as a robot or CNC program: both go through the same safety checks.
Creating Jobs (tests, GUI) has to pick ``PathScripts.PathJob`` (FreeCAD 0.20) or ``Path.Main.Job`` (1.x).
FreeCAD stores feeds in mm/s: they are converted from the core's mm/min.
"""
from __future__ import annotations

import os

import numpy as np

import FreeCAD
import Path

from workcal_wb.core.errors import MissingDependency
from workcal_wb.core.result import CalibrationResult
from workcal_wb.core.toolpath import (DEFAULT_CHORD_TOL_MM, FORMATS, Envelope, ExportOptions, RotaryTable, Toolpath,
                                      export, format_for, transformed)
from workcal_wb.core.toolpath.exporters.common import DEFAULT_RAPID_FEED_MM_MIN, ExportJob, comment_text, robot_path
from workcal_wb.core.toolpath.gcode import AXES, MOTION_CODE, OFFSET_AXIS, PLANE_OF_AXIS, PLANES, gcode_comment
from workcal_wb.core.toolpath.model import ARC_CCW, ARC_CW, KINDS
from workcal_wb.core.toolpath.safety import DEFAULT_PATH_REACH_MM, checked_placement, forced_banner
from workcal_wb.fc import prefs
from workcal_wb.fc.lookups import result_of
from workcal_wb.fc.models import model_cloud
from workcal_wb.fc.placements import placement
from workcal_wb.fc.proxies import Feature, add_properties, objects_of, type_of
from workcal_wb.fc.setup import toolpath_of
from workcal_wb.fc.toolpath_input import SECONDS_PER_MINUTE, is_job, jobs, read_source, source_label
from workcal_wb.fc.undo import transaction

translate = FreeCAD.Qt.translate
QT_TRANSLATE_NOOP = FreeCAD.Qt.QT_TRANSLATE_NOOP

MOTION = ("G0", "G1", "G2", "G3", "G00", "G01", "G02", "G03")
TYPE = "WorkCal::CalibratedPath"


def toolpath_sources(doc) -> list:
    """What can be a document's toolpath: Jobs first, then operations and other Path objects with moves
    (WorkCal's calibrated toolpaths, already in B, and tool controllers excluded)."""
    paths = [o for o in doc.Objects if not is_job(o) and hasattr(o, "Path") and hasattr(o.Path, "Commands")
             and type_of(o) != TYPE
             and not hasattr(o, "SpindleSpeed")  # tool controllers hold a tool change, not a path
             and any(c.Name in MOTION for c in o.Path.Commands)]
    return jobs(doc) + paths


def _commands(path: Toolpath) -> list:
    """Path commands of a toolpath whose arcs lie in a machine plane: positions only (see make_path_object)."""
    commands = []
    starts, arc = path.starts(), -1
    for i in range(len(path)):
        commands += [_comment_command(c) for c in path.comments.get(i, "").split("\n") if c]
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


def calibrated_path(toolpath: Toolpath, calibration: CalibrationResult, *, force: bool = False,
                    envelope: Envelope | None = None, table: RotaryTable | None = None,
                    chord_tol_mm: float = DEFAULT_CHORD_TOL_MM, source: str = "calibration",
                    workpiece_model=None, path_reach_mm: float = DEFAULT_PATH_REACH_MM) -> tuple:
    """(``Path.Path`` of ``toolpath`` moved into B, whether forced), after the same checks as a file export
    (the path held to ``workpiece_model``, X-A, when given).

    Positions only: FreeCAD's Path treats A/B words as rotary axes and would draw the path displaced,
    so the tool axis (in every exported program) is not written into the Path object."""
    options = ExportOptions(force=force, envelope=envelope, table=table, chord_tol_mm=chord_tol_mm,
                            calibration_source=source, workpiece_model=workpiece_model, path_reach_mm=path_reach_mm)
    checked = checked_placement(toolpath, calibration, options)
    forced = checked.forced
    moved = transformed(toolpath, checked.transform, chord_tol_mm)
    header = (forced_banner(calibration) if forced else []) + moved.header + list(checked.notes)
    commands = [_comment_command(c) for c in header] + _commands(moved)
    commands += [_comment_command(c) for c in moved.footer]
    return Path.Path(commands), forced


def _comment_command(text: str):
    """A Path comment command holding ``text`` on one line, as a G-code comment (common.comment_text)."""
    return Path.Command(gcode_comment(comment_text(text)))


PATH_PROPERTIES = [
    ("App::PropertyLink", "Calibration", "Calibrated toolpath",
     QT_TRANSLATE_NOOP("App::Property", "The calibration whose W carries the toolpath into the robot base frame")),
    ("App::PropertyLink", "Source", "Calibrated toolpath",
     QT_TRANSLATE_NOOP("App::Property", "The toolpath in the workpiece frame: a Path/CAM Job or operation")),
    ("App::PropertyFile", "SourceFile", "Calibrated toolpath",
     QT_TRANSLATE_NOOP("App::Property", "The toolpath as a G-code file (when Source is empty)")),
    ("App::PropertyBool", "Forced", "Calibrated toolpath",
     QT_TRANSLATE_NOOP("App::Property", "Made from a calibration that did not pass its checks, because the user "
                                        "said so")),
]


class CalibratedPathFeature(Feature):
    """Proxy of the calibrated toolpath (``Path::FeaturePython``): recomputed whenever the calibration
    or the toolpath changes, refused (an error on the object) when the calibration is no longer fit."""

    TYPE = TYPE

    def setup(self, obj) -> None:
        add_properties(obj, PATH_PROPERTIES, read_only=("Calibration", "Forced"))

    def execute(self, obj):
        source = obj.Source if obj.Source is not None else (obj.SourceFile or None)
        path, _ = calibrated_path(read_source(source), result_of(obj.Calibration), force=obj.Forced,
                                  source=f"calibration {obj.Calibration.Label!r}",
                                  **held_to_workpiece(obj.Calibration))
        obj.Path = path


def check_calibrated_path(calibration, source=None, *, force: bool = False) -> bool:
    """Every refusal ``make_calibrated_path`` would raise, without touching the document (the GUI checks
    before it records the command); returns whether it would be forced."""
    source = source if source is not None else toolpath_of(calibration.Document)
    _, forced = calibrated_path(read_source(source), result_of(calibration), force=force,
                                source=f"calibration {calibration.Label!r}", **held_to_workpiece(calibration))
    return forced


def held_to_workpiece(calibration) -> dict:
    """The export options that hold a toolpath to the workpiece model X-A ``calibration`` matched: the
    model (a Cloud) and how far from it the cutting moves may run (the preference)."""
    return {"workpiece_model": model_cloud(calibration.Workpiece, role="workpiece"),
            "path_reach_mm": prefs.get("PathReachMm")}


def make_calibrated_path(calibration, source=None, *, force: bool = False):
    """The document's toolpath (or ``source``) carried into the robot base frame by ``calibration``'s
    W, as a new object in one undo step.  Refuses (CalibrationNotOk) a calibration that is not "ok"
    unless ``force`` (the label then says FORCED), and (ExportRefused, InputError) whatever a program
    export would refuse; the document is then unchanged."""
    doc = calibration.Document
    source = source if source is not None else toolpath_of(doc)
    result = result_of(calibration)
    forced = check_calibrated_path(calibration, source, force=force)  # refuse before touching the document
    with transaction(doc, translate("WorkCal", "Calibrated toolpath")):
        obj = doc.addObject("Path::FeaturePython", "CalibratedToolpath")
        CalibratedPathFeature(obj)
        obj.Calibration = calibration
        is_file = isinstance(source, (str, os.PathLike))
        obj.Source = None if is_file else source
        obj.SourceFile = os.fspath(source) if is_file else ""
        obj.Forced = forced
        obj.Label = translate("WorkCal", "Toolpath in the robot frame ({})").format(source_label(source)) + (
            " (FORCED)" if forced else "")
        doc.recompute()
    FreeCAD.Console.PrintMessage(f"WorkCal: {obj.Label}: {len(read_source(source))} moves carried into the robot "
                                 f"base frame with {calibration.Label} ({result.status})\n")
    return obj


def calibrated_paths(calibration) -> list:
    """The calibrated toolpaths made from ``calibration``."""
    return [o for o in objects_of(calibration.Document, TYPE) if o.Calibration is calibration]


def check_export(calibration, path, fmt: str | None = None, source=None, *, force: bool = False, **options) -> None:
    """Every refusal ``export_program`` would raise (CalibrationNotOk, ToolTilted, ReachRefused,
    ExportRefused, InputError), without writing anything (the GUI checks before it records the export)."""
    from workcal_wb.core.toolpath.exporters import checked_export

    source = source if source is not None else toolpath_of(calibration.Document)
    fmt = fmt or format_for(path)
    options = {**held_to_workpiece(calibration), **robot_options(**options)}
    options = ExportOptions(force=force, calibration_source=f"calibration {calibration.Label!r}", **options)
    checked_export(read_source(source), result_of(calibration), fmt, options)


def robot_options(robot=None, tool=None, **options) -> dict:
    """Export options with ``robot`` given as a built-in id or a robot file's path (as a macro records it)
    loaded, and ``tool`` given as X, Y, Z, A, B, C (mm, degrees, R = Rz(A) Ry(B) Rx(C)) made a 4x4."""
    from workcal_wb.core.robots import load_robot
    from workcal_wb.core.robots.model import xyzabc_transform

    if isinstance(robot, (str, os.PathLike)):
        robot = load_robot(os.fspath(robot))
    if tool is not None and np.asarray(tool).shape == (6,):
        tool = xyzabc_transform(tool)
    return {**options, **({} if robot is None else {"robot": robot}), **({} if tool is None else {"tool": tool})}


def export_program(calibration, path, fmt: str | None = None, source=None, *, force: bool = False, **options):
    """Write the document's toolpath (or ``source``) through ``calibration``'s W as a robot or CNC
    program; returns the core's export job.  ``fmt``: krl, rapid, urscript, fanuc, gcode or csv
    (default: from the file extension); ``options`` go to core.toolpath.export (machine,
    vertical_tol_deg, rotary, envelope, krl_mode, rapid_feed_mm_min, chord_tol_mm, robot (a built-in
    robot's id, a robot file's path or a core.robots.Robot), tool (the TCP in its flange frame: X, Y, Z,
    A, B, C in mm and degrees, or a 4x4), ...).  Nothing is written when the export is refused
    (CalibrationNotOk or ReachRefused unless ``force``, ToolTilted, ExportRefused)."""
    source = source if source is not None else toolpath_of(calibration.Document)
    result = result_of(calibration)
    toolpath = read_source(source)
    fmt = fmt or format_for(path)
    options = {**held_to_workpiece(calibration), **robot_options(**options)}
    job = export(toolpath, result, fmt, path, force=force, calibration_source=f"calibration {calibration.Label!r}",
                 **options)
    text = (f"WorkCal: wrote {path}: {FORMATS[fmt].NAME} for {job.machine}, {len(toolpath)} moves from "
            f"{source_label(source)}, calibration {result.status}")
    if job.forced:
        FreeCAD.Console.PrintWarning(text + " (FORCED)\n")
    else:
        FreeCAD.Console.PrintMessage(text + "\n")
    return job


def robot_available() -> bool:
    try:
        import Robot  # noqa: F401
    except ImportError:
        return False
    return True


def make_robot_trajectory(doc, toolpath: Toolpath, calibration: CalibrationResult, *, force: bool = False,
                          envelope: Envelope | None = None, table: RotaryTable | None = None,
                          chord_tol_mm: float = DEFAULT_CHORD_TOL_MM,
                          rapid_feed_mm_min: float = DEFAULT_RAPID_FEED_MM_MIN, name: str = "WorkCalTrajectory",
                          workpiece_model=None):
    """A Robot ``TrajectoryObject`` of LIN waypoints in B (velocities in mm/s), tool orientation as the exporters.

    Waypoints are not continuous: FreeCAD blends continuous ones with a fixed 3 mm radius, which KDL
    rejects on chords shorter than that (and FreeCAD 0.20 aborts on the error)."""
    try:
        import Robot
    except ImportError as exc:
        raise MissingDependency("FreeCAD's Robot workbench is not available in this FreeCAD; "
                                "export KRL or CSV instead") from exc
    options = ExportOptions(force=force, envelope=envelope, table=table, chord_tol_mm=chord_tol_mm,
                            rapid_feed_mm_min=rapid_feed_mm_min, calibration_source=f"calibration for {name}",
                            workpiece_model=workpiece_model)
    checked = checked_placement(toolpath, calibration, options)
    forced = checked.forced
    path = robot_path(ExportJob(toolpath, calibration, checked.transform, forced, None, options, "robot"),
                      in_base_frame=True,
                      max_speed_mm_s=float("inf"))
    waypoints = [Robot.Waypoint(placement(path.matrix(i)), type="LIN", name=f"P{i + 1}",
                                vel=float(path.feed[i]) / SECONDS_PER_MINUTE, cont=False) for i in range(len(path))]
    obj = doc.addObject("Robot::TrajectoryObject", name)
    obj.Trajectory = Robot.Trajectory(waypoints)
    if forced:
        obj.Label = f"{name} (FORCED)"
    return obj
