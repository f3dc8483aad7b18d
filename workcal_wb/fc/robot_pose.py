"""The robot drawn at the worst pose of a program checked against it, beside the part it machines.

After a robot program is checked against its robot (``fc.toolpath.export_program`` with ``robot``),
``show_robot_at_worst_pose`` draws that robot as a stick figure of cylinders and spheres through its
joints (``core.robots.links``) at the pose to look at (``core.robots.reach.worst_pose``): where a
program it follows comes nearest a joint limit, or where a program it cannot follow fails.  The shape is
in the robot base frame B, the document frame the reference model is in, so the robot stands where it
stands in the cell, its flange (and tool) on the calibrated toolpath.

One object per calibration: showing it again replaces it, in one undo step.  Its shape is made once:
it shows the check it was made from, not a later one.
"""
from __future__ import annotations

import numpy as np

import FreeCAD
import Part

from workcal_wb.core.errors import InputError
from workcal_wb.core.robots import forward
from workcal_wb.core.robots.links import arm_points
from workcal_wb.core.robots.reach import worst_pose
from workcal_wb.core.toolpath import ExportOptions, ReachRefused
from workcal_wb.core.toolpath.orientation import kuka_abc_deg
from workcal_wb.fc.proxies import Feature, add_properties, objects_of
from workcal_wb.fc.undo import transaction

translate = FreeCAD.Qt.translate
QT_TRANSLATE_NOOP = FreeCAD.Qt.QT_TRANSLATE_NOOP

TYPE = "WorkCal::RobotPose"
# The links' radius as a share of the arm's length (the sum of its links): about as thick as real arms
# look beside their reach (some 60 mm on a KR 16, 30 mm on a UR5e), thin enough to see the part through.
LINK_RADIUS_SHARE = 0.025
# The joints' spheres, the base plate and the tool, in link radii: the joints stand out of the links, the
# plate shows where the robot is bolted down, the tool is thinner than the arm that carries it.
JOINT_RADII, BASE_RADII, BASE_HEIGHT_RADII, TOOL_RADII, TCP_RADII = 1.3, 2.5, 0.6, 0.35, 0.6
# Links shorter than this (mm) are not drawn: a zero offset of the model (b = 0, a TCP at the flange).
SHORTEST_LINK_MM = 1e-6

PROPERTIES = [
    ("App::PropertyLink", "Calibration", "Robot pose",
     QT_TRANSLATE_NOOP("App::Property", "The calibration whose program the robot was checked against")),
    ("App::PropertyString", "Robot", "Robot pose", QT_TRANSLATE_NOOP("App::Property", "The robot's id and name")),
    ("App::PropertyFloatList", "Joints", "Robot pose",
     QT_TRANSLATE_NOOP("App::Property", "The joint values shown, the controller's, in degrees")),
    ("App::PropertyFloatList", "Tool", "Robot pose",
     QT_TRANSLATE_NOOP("App::Property", "The TCP in the flange frame: X, Y, Z in mm, A, B, C in degrees")),
    ("App::PropertyString", "Pose", "Robot pose",
     QT_TRANSLATE_NOOP("App::Property", "Where along the program the pose is, and why it is the one shown")),
]


class RobotPoseFeature(Feature):
    """Proxy of the robot drawn at a pose (``Part::FeaturePython``): the shape is made when the object is,
    from the check it shows."""

    TYPE = TYPE

    def setup(self, obj) -> None:
        add_properties(obj, PROPERTIES, read_only=("Calibration", "Robot", "Joints", "Tool", "Pose"))


def robot_shape(robot, joints_deg, tool=None) -> "Part.Shape":
    """``robot`` at ``joints_deg`` (the controller's, degrees) as a compound of solids in its controller's
    base frame (mm): a cylinder along each link, a sphere at each joint, a plate at its base and, with a
    ``tool`` (4x4 TCP in the flange frame) that is not the flange, the tool out to its TCP."""
    arm = arm_points(robot, np.asarray(joints_deg, dtype=float))
    radius = LINK_RADIUS_SHARE * float(arm.lengths().sum())
    points = [FreeCAD.Vector(*map(float, p)) for p in arm.points]
    solids = []
    axis1 = FreeCAD.Vector(*map(float, robot.base_transform[:3, :3].T @ np.array([0.0, 0.0, 1.0])))
    solids.append(Part.makeCylinder(BASE_RADII * radius, BASE_HEIGHT_RADII * radius, points[0], axis1))
    for start, end in zip(points[:-1], points[1:]):
        if (end - start).Length > SHORTEST_LINK_MM:
            solids.append(Part.makeCylinder(radius, (end - start).Length, start, end - start))
    for point in points[1:]:
        solids.append(Part.makeSphere(JOINT_RADII * radius, point))
    if tool is not None:
        tcp = FreeCAD.Vector(*map(float, (forward(robot, joints_deg) @ np.asarray(tool, dtype=float))[:3, 3]))
        if (tcp - points[-1]).Length > SHORTEST_LINK_MM:
            solids.append(Part.makeCylinder(TOOL_RADII * radius, (tcp - points[-1]).Length, points[-1],
                                            tcp - points[-1]))
            solids.append(Part.makeSphere(TCP_RADII * radius, tcp))
    return Part.makeCompound(solids)


def program_reach(calibration, fmt: str | None = None, source=None, *, force: bool = False, **options) -> tuple:
    """(robot, tool 4x4, ReachReport): the document's toolpath (or ``source``) through ``calibration``'s W,
    checked against ``options``' robot as ``export_program`` checks it, nothing written.  ``fmt`` only
    says which language the robot must run (default CSV, which every robot's poses can be written in);
    the check is the same for each.  Refuses as the export would, except that a program the robot
    cannot follow is reported (its report says where it fails) rather than refused."""
    from workcal_wb.core.toolpath.exporters import checked_export
    from workcal_wb.fc.lookups import result_of
    from workcal_wb.fc.setup import toolpath_of
    from workcal_wb.fc.toolpath import held_to_workpiece, robot_options
    from workcal_wb.fc.toolpath_input import read_source

    settings = {**held_to_workpiece(calibration), **robot_options(**options)}
    if settings.get("robot") is None:
        raise InputError(translate("WorkCal", "No robot given: the robot is shown at the worst pose of a program "
                                              "checked against it (choose the robot that runs the program)"))
    source = source if source is not None else toolpath_of(calibration.Document)
    export_options = ExportOptions(force=force, calibration_source=f"calibration {calibration.Label!r}", **settings)
    try:
        checked = checked_export(read_source(source), result_of(calibration), fmt or "csv", export_options)
        report = checked.reach
    except ReachRefused as refused:
        report = refused.report
    return export_options.robot, export_options.tool, report


def find(calibration):
    """The robot shown for ``calibration``'s program, or None."""
    return next((o for o in objects_of(calibration.Document, TYPE) if o.Calibration is calibration), None)


def show_robot_at_worst_pose(calibration, fmt: str | None = None, source=None, *, force: bool = False, **options):
    """The robot of ``options`` (``robot``: a built-in id or a robot file's path; ``tool``: X, Y, Z, A, B,
    C or a 4x4, as ``export_program`` takes them) drawn at the worst pose of the program
    ``export_program(calibration, ..., fmt, source, force=force, **options)`` writes or refuses, in
    the robot base frame; it replaces the one shown before for ``calibration``, in one undo step.
    Refuses (InputError) when no robot is given or the robot follows none of the program."""
    robot, tool, report = program_reach(calibration, fmt, source, force=force, **options)
    pose = worst_pose(robot, report)
    if pose is None:
        raise InputError(translate("WorkCal", "{}: the robot reaches none of the program, so there is no pose to "
                                              "show: {}").format(robot.name, report.reason))
    shape = robot_shape(robot, pose.joints, tool)
    doc = calibration.Document
    label = translate("WorkCal", "Robot {} {}").format(robot.name, pose.text)
    with transaction(doc, translate("WorkCal", "Show the robot at its worst pose")):
        old = find(calibration)
        if old is not None:
            doc.removeObject(old.Name)
        obj = doc.addObject("Part::FeaturePython", "RobotPose")
        RobotPoseFeature(obj)
        obj.Calibration = calibration
        obj.Robot = f"{robot.id} ({robot.name})"
        obj.Joints = [float(v) for v in pose.joints]
        obj.Tool = [float(v) for v in (*tool[:3, 3], *kuka_abc_deg(tool))]
        obj.Pose = pose.text
        obj.Shape = shape
        obj.Label = label
        doc.recompute()
    FreeCAD.Console.PrintMessage(f"WorkCal: {label}: joints "
                                 + ", ".join(f"{v:.2f}" for v in pose.joints) + " deg\n")
    return obj
