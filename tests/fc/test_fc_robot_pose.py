"""The robot drawn at the worst pose of a program checked against it (fc.robot_pose), under freecadcmd:
its flange where the kinematics put it, in the robot base frame, at the pose the check names; replaced
in one undo step; refused without a robot, the document then unchanged."""
import numpy as np
import pytest

FreeCAD = pytest.importorskip("FreeCAD")

from workcal_wb.core import frames  # noqa: E402
from workcal_wb.core.errors import InputError  # noqa: E402
from workcal_wb.core.result import CalibrationResult  # noqa: E402
from workcal_wb.core.robots import forward, joint_margins_deg, load_robot  # noqa: E402
from workcal_wb.core.robots.links import arm_points  # noqa: E402
from workcal_wb.core.robots.model import xyzabc_transform  # noqa: E402
from workcal_wb.fc import calibration_object as co  # noqa: E402
from workcal_wb.fc import proxies, robot_pose, setup  # noqa: E402
from workcal_wb.fc.placements import matrix_of  # noqa: E402

# Where a KR 16-2 machines the block (W = ^B X), and where the block lies so far that it goes out of reach on
# the first cut.
W_IN_REACH = frames.rigid(frames.rot_z(25.0), (900.0, -150.0, 250.0))
W_OUT_OF_REACH = frames.rigid(frames.rot_z(25.0), (1500.0, -150.0, 250.0))
TOOL = [0.0, 0.0, 150.0, 0.0, 0.0, 0.0]
# A rectangle on the top of the 200 x 150 x 50 mm block, in its frame X.
GCODE = ("G0 X20 Y20 Z80\nG1 Z50 F600\nG1 X180\nG1 Y130\nG1 X20\nG1 Y20\nG0 Z80\n")
# The shape is made of the link geometry in mm: the flange lands where the kinematics put it to rounding.
FLANGE_MM = 1e-6


@pytest.fixture
def doc(tmp_path):
    """A document with the block and its toolpath chosen, undo on."""
    document = FreeCAD.newDocument("WorkCalRobotPose")
    document.UndoMode = 1
    block = document.addObject("Part::Box", "Block")
    block.Length, block.Width, block.Height = 200, 150, 50
    document.recompute()
    gcode = tmp_path / "rectangle.nc"
    gcode.write_text(GCODE)
    setup.choose_toolpath(document, str(gcode))
    yield document
    FreeCAD.closeDocument(document.Name)


def calibration(doc, W):
    """An ok calibration of the block placed by W, as the Calibrate command leaves it."""
    obj = doc.addObject("Part::FeaturePython", "Calibration")
    co.CalibrationFeature(obj)
    obj.Workpiece = doc.getObject("Block")
    co.store_result(obj, CalibrationResult("ok", W, U=W, V=np.eye(4), quality_gates=[
        {"name": "rms_mm", "value": 0.1, "limit": 0.3, "passed": True, "unit": "mm"}]))
    obj.purgeTouched()
    doc.clearUndos()
    return obj


def cap_centres(shape) -> np.ndarray:
    """The centres of the flat circular faces of a shape's cylinders: where each link starts and ends."""
    return np.array([tuple(face.CenterOfMass) for face in shape.Faces if face.Surface.TypeId == "Part::GeomPlane"])


def sphere_centres(shape) -> np.ndarray:
    return np.array([tuple(face.Surface.Center) for face in shape.Faces if face.Surface.TypeId == "Part::GeomSphere"])


def test_the_robot_stands_in_the_robot_base_frame_with_its_flange_where_the_kinematics_put_it(doc):
    cal = calibration(doc, W_IN_REACH)
    robot = load_robot("kuka_kr16_2")
    obj = robot_pose.show_robot_at_worst_pose(cal, "krl", robot="kuka_kr16_2", tool=TOOL)
    assert proxies.type_of(obj) == robot_pose.TYPE and robot_pose.find(cal) is obj
    # In B: the object is not moved, its shape's coordinates are B's (the reference model's document frame).
    np.testing.assert_allclose(matrix_of(obj.Placement), np.eye(4), atol=1e-12)
    joints = np.array(obj.Joints)
    flange = forward(robot, joints)
    assert np.linalg.norm(cap_centres(obj.Shape) - flange[:3, 3], axis=1).min() < FLANGE_MM  # the last link ends there
    assert np.linalg.norm(sphere_centres(obj.Shape) - flange[:3, 3], axis=1).min() < FLANGE_MM
    # Every joint of the arm is drawn, its base plate at the foot of axis 1 on B's origin.
    for point in arm_points(robot, joints).points[1:]:
        assert np.linalg.norm(sphere_centres(obj.Shape) - point, axis=1).min() < FLANGE_MM
    assert np.linalg.norm(cap_centres(obj.Shape), axis=1).min() < FLANGE_MM
    # The tool out to the TCP, which is on the calibrated rectangle (the top of the block at z 50 in X).
    tcp = (flange @ xyzabc_transform(TOOL))[:3, 3]
    assert np.linalg.norm(sphere_centres(obj.Shape) - tcp, axis=1).min() < FLANGE_MM
    in_x = frames.apply(frames.invert(W_IN_REACH), tcp[None])[0]
    assert abs(in_x[2] - 50.0) < 1e-6 and 20 - 1e-6 <= in_x[0] <= 180 + 1e-6 and 20 - 1e-6 <= in_x[1] <= 130 + 1e-6
    # The pose is the one the check names: its smallest margin is the one in the label.
    margins = joint_margins_deg(robot, joints)
    joint = int(np.argmin(margins))
    assert obj.Label.startswith("Robot KUKA KR 16-2 ") and obj.Pose in obj.Label
    assert f"(A{joint + 1} {margins[joint]:.1f} deg from its limit)" in obj.Label
    assert obj.Robot == "kuka_kr16_2 (KUKA KR 16-2)" and list(obj.Tool) == pytest.approx(TOOL, abs=1e-9)


def test_showing_it_again_replaces_it_in_one_undo_step(doc):
    cal = calibration(doc, W_IN_REACH)
    first = robot_pose.show_robot_at_worst_pose(cal, "krl", robot="kuka_kr16_2", tool=TOOL)
    first_label = first.Label
    second = robot_pose.show_robot_at_worst_pose(cal, "krl", robot="kuka_kr16_2",
                                                 tool=[0.0, 0.0, 250.0, 0.0, 0.0, 0.0])
    shown = [o for o in doc.Objects if proxies.type_of(o) == robot_pose.TYPE]
    assert shown == [second] and doc.UndoNames[0] == "Show the robot at its worst pose"
    assert second.Tool[2] == 250.0
    doc.undo()
    shown = [o for o in doc.Objects if proxies.type_of(o) == robot_pose.TYPE]
    assert len(shown) == 1 and shown[0].Label == first_label and shown[0].Tool[2] == 150.0


def test_a_program_the_robot_cannot_follow_shows_where_it_fails(doc):
    cal = calibration(doc, W_OUT_OF_REACH)
    robot = load_robot("kuka_kr16_2")
    obj = robot_pose.show_robot_at_worst_pose(cal, "krl", robot="kuka_kr16_2", tool=TOOL)
    assert "just before going out of reach" in obj.Label, obj.Label
    # The last pose it follows: within its limits, its TCP on the way out of reach.
    assert (joint_margins_deg(robot, np.array(obj.Joints)) >= 0).all()


def test_without_a_robot_or_a_pose_it_reaches_nothing_is_shown(doc):
    cal = calibration(doc, W_IN_REACH)
    before = sorted(o.Name for o in doc.Objects)
    with pytest.raises(InputError, match="No robot given"):
        robot_pose.show_robot_at_worst_pose(cal, "krl")
    with pytest.raises(InputError, match="KUKA robot: it does not run"):
        robot_pose.show_robot_at_worst_pose(cal, "rapid", robot="kuka_kr16_2")
    assert sorted(o.Name for o in doc.Objects) == before
    far = calibration(doc, frames.rigid(None, (3000.0, 0.0, 0.0)))
    before = sorted(o.Name for o in doc.Objects)
    with pytest.raises(InputError, match="reaches none of the program.*out of the robot's reach"):
        robot_pose.show_robot_at_worst_pose(far, "krl", robot="kuka_kr16_2")
    assert sorted(o.Name for o in doc.Objects) == before
