"""The export step's robot at its worst pose, in the real FreeCAD window (Xvfb): after a check against a
robot the page says where the robot comes nearest a joint limit and offers to show it there; the button
draws the robot beside the part (a screenshot of the 3D view and of the window); the next export updates
it; a robot that reaches none of the program has no pose to show."""
import numpy as np
import pytest

FreeCAD = pytest.importorskip("FreeCAD")
if not FreeCAD.GuiUp:
    pytest.skip("needs the FreeCAD GUI (run tests/gui/run_gui_tests.py under xvfb-run freecad)",
                allow_module_level=True)

from workcal_wb.core import frames  # noqa: E402
from workcal_wb.core.result import CalibrationResult  # noqa: E402
from workcal_wb.core.robots import forward, load_robot  # noqa: E402
from workcal_wb.fc import calibration_object as co  # noqa: E402
from workcal_wb.fc import placed_model, proxies, robot_pose, setup, toolpath  # noqa: E402

# Where the calibration puts the block (W = ^B X): in front of a KR 16-2, on a platform.
W = frames.rigid(frames.rot_z(25.0), (900.0, -150.0, 250.0))
# A rectangle on the top of the 200 x 150 x 50 mm block, in its frame X.
GCODE = "G0 X20 Y20 Z80\nG1 Z50 F600\nG1 X180\nG1 Y130\nG1 X20\nG1 Y20\nG0 Z80\n"


@pytest.fixture
def cell(doc, tmp_path):
    """The block, the platform it stands on (the reference model, in B), an ok calibration of them (as the
    Calibrate command leaves it), the toolpath chosen and shown in the robot frame with the placed block."""
    block = doc.addObject("Part::Box", "Block")
    block.Length, block.Width, block.Height = 200, 150, 50
    platform = doc.addObject("Part::Box", "Platform")
    platform.Length, platform.Width, platform.Height = 700, 700, 30
    platform.Placement.Base = FreeCAD.Vector(650, -500, 220)
    doc.recompute()
    setup.set_setup(doc, workpiece=block, reference=platform)
    cal = doc.addObject("Part::FeaturePython", "Calibration")
    co.CalibrationFeature(cal)
    cal.Workpiece, cal.Reference = block, platform
    co.store_result(cal, CalibrationResult("ok", W, U=W, V=np.eye(4), quality_gates=[
        {"name": "rms_mm", "value": 0.1, "limit": 0.3, "passed": True, "unit": "mm"}]))
    cal.purgeTouched()
    gcode = tmp_path / "rectangle.nc"
    gcode.write_text(GCODE)
    setup.choose_toolpath(doc, str(gcode))
    toolpath.make_calibrated_path(cal)
    placed_model.show_in_robot_frame(cal)
    return {"cal": cal, "dir": tmp_path}


def python_console() -> str:
    """What FreeCAD's Python console shows: the lines the commands ran (and a macro being recorded holds)."""
    import FreeCADGui

    from workcal_wb.gui.task_panels import QtWidgets

    console = FreeCADGui.getMainWindow().findChild(QtWidgets.QPlainTextEdit, "Python console")
    assert console is not None, "no Python console in the main window"
    return console.toPlainText()


def robots_shown(doc) -> list:
    return [o for o in doc.Objects if proxies.type_of(o) == robot_pose.TYPE]


def test_the_robot_is_shown_at_its_worst_pose_beside_the_part(doc, cell, shoot, shoot_window, pump, settle,
                                                               page_fits):
    from workcal_wb.gui.commands.guide import open_guide

    panel = open_guide(doc, "export")
    page = panel.steps["export"]
    assert not page.show_robot_button.isVisible()  # nothing checked yet
    page.set_options(fmt="krl", robot="kuka_kr16_2", tool="0, 0, 150, 0, 0, 0", path=cell["dir"] / "part.src")
    assert page.export() is not None and (cell["dir"] / "part.src").exists()
    pump(0.2)
    assert page.worst.isVisible() and page.show_robot_button.isVisible()
    assert page.worst.text().startswith("KUKA KR 16-2 comes nearest a joint limit at line ")
    assert robots_shown(doc) == []  # shown on request only
    page.show_robot_button.click()
    settle()
    # Recorded as the other commands are: the fc call with the export's format, force and options.
    assert ("workcal_wb.fc.robot_pose.show_robot_at_worst_pose(App.ActiveDocument.getObject('Calibration'), "
            "'krl', force=False, machine='robot', robot='kuka_kr16_2', tool=[0.0, 0.0, 150.0, 0.0, 0.0, 0.0])"
            in python_console())
    shown = robots_shown(doc)
    assert len(shown) == 1 and shown[0].ViewObject.Visibility
    robot = shown[0]
    assert robot.Label == f"Robot KUKA KR 16-2 {page.checked['pose'].text}"
    assert page.worst.text() == f"KUKA KR 16-2 comes nearest a joint limit {page.checked['pose'].text}."
    # The flange where the kinematics put it, the TCP on the top of the placed block.
    tcp = (forward(load_robot("kuka_kr16_2"), np.array(robot.Joints)) @ frames.rigid(None, (0, 0, 150)))[:3, 3]
    in_x = frames.apply(frames.invert(W), tcp[None])[0]
    assert abs(in_x[2] - 50.0) < 1e-6
    # The 3D view shows the robot with the toolpath and the placed block, all in view.
    placed = placed_model.find(cell["cal"])
    assert placed.ViewObject.Visibility and robot in panel.steps["export"].scene().show
    page_fits(panel.form)
    shoot("robot_at_worst_pose", fit=False)
    shoot_window("robot_at_worst_pose_window")
    # The next export updates the robot shown: another TCP, another pose, still one robot.
    page.set_options(tool="0, 0, 250, 0, 0, 0")
    assert page.export() is not None
    pump(0.2)
    shown = robots_shown(doc)
    assert len(shown) == 1 and shown[0].Tool[2] == 250.0 and shown[0].Label == \
        f"Robot KUKA KR 16-2 {page.checked['pose'].text}"


def test_a_robot_that_reaches_none_of_the_program_has_no_pose_to_show(doc, cell, pump):
    from workcal_wb.gui.commands.guide import open_guide

    page = open_guide(doc, "export").steps["export"]
    page.set_options(fmt="krl", robot="kuka_kr6_r700_sixx", tool="0, 0, 150, 0, 0, 0",
                     path=cell["dir"] / "part.src")
    asked = []
    assert page.export(confirm=lambda reason: asked.append(reason) or False) is None
    pump(0.1)
    assert asked and "cannot follow this program" in asked[0]
    assert page.worst.text() == "KUKA KR 6 R700 sixx reaches none of the program: there is no pose to show."
    assert not page.show_robot_button.isVisible() and robots_shown(doc) == []
