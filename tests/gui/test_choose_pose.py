"""An ambiguous calibration in the guide: its poses drawn in the view (the workpiece frame's axes and the
toolpath, each pose in its own colour), each pose's difference from the best named on the page, one of
them chosen, and the choice read back from the document object, its result file and the exported program.
"""
import json
import os

import numpy as np
import pytest

FreeCAD = pytest.importorskip("FreeCAD")
if not FreeCAD.GuiUp:
    pytest.skip("needs the FreeCAD GUI (run tests/gui/run_gui_tests.py under xvfb-run freecad)",
                allow_module_level=True)

import FreeCADGui  # noqa: E402

from workcal_wb.core import choice, frames  # noqa: E402
from workcal_wb.core.geometry import Cloud  # noqa: E402
from workcal_wb.core.result import AMBIGUOUS, CHOSEN, CalibrationResult  # noqa: E402
from workcal_wb.core.simulate import shapes  # noqa: E402
from workcal_wb.core.simulate.scanner import Scanner  # noqa: E402
from workcal_wb.core.simulate.scene import build_scene  # noqa: E402
from workcal_wb.core.simulate.toolpath_sample import sample_toolpath  # noqa: E402
from workcal_wb.core.toolpath import format_gcode  # noqa: E402
from workcal_wb.fc import placed_model  # noqa: E402
from workcal_wb.fc.lookups import result_of  # noqa: E402
from workcal_wb.fc.models import add_model  # noqa: E402
from workcal_wb.fc.placements import matrix_of  # noqa: E402
from workcal_wb.gui import candidate_display  # noqa: E402


@pytest.fixture
def ambiguous_guide(doc, tmp_path):
    """The guide at the result of a symmetric workpiece (an ellipsoid) calibrated with a toolpath chosen."""
    from workcal_wb.fc.scan import make_scan
    from workcal_wb.fc.setup import choose_toolpath, set_setup
    from workcal_wb.gui.commands.guide import open_guide

    scene = build_scene(shapes.ellipsoid(), seed=1)
    scan = Scanner.aimed_at(scene).scan(scene)
    set_setup(doc, scan=make_scan(doc, Cloud(scan.points, name="ellipsoid scan"), "Scan"),
              workpiece=add_model(doc, scene.workpiece_model(), "Ellipsoid"),
              reference=add_model(doc, scene.reference_model(), "Reference"))
    gcode = tmp_path / "finishing.nc"
    gcode.write_text(format_gcode(sample_toolpath(scene)))
    choose_toolpath(doc, str(gcode))
    doc.recompute()
    guide = open_guide(doc, "calibrate")
    page = guide.steps["calibrate"]
    page.set_options(regions="Auto", seed=0, resamples=2)
    assert page.start() and page.wait(180) == "done", page.last_error
    yield guide
    guide.close()


def test_the_poses_are_drawn_named_and_one_is_chosen(doc, ambiguous_guide, pump, shoot_window, page_fits, tmp_path):
    from workcal_wb.gui.actions import export_program

    guide = ambiguous_guide
    page = guide.steps["result"]
    cal = guide.calibration()
    assert guide.shown == "result" and cal.Status == AMBIGUOUS
    assert not page.accept_button.isEnabled() and page.choose_button.isVisible()
    poses = placed_model.candidate_poses(cal, "workpiece")
    view = FreeCADGui.ActiveDocument.ActiveView
    drawn = candidate_display.drawn(view)
    assert sorted(drawn) == list(range(len(poses))) and len(poses) >= 3
    assert len({entry["colour"] for entry in drawn.values()}) == len(poses)  # a colour of its own each
    assert drawn[0]["width"] == candidate_display.SHOWN_WIDTH and drawn[1]["width"] == candidate_display.OTHER_WIDTH
    size = cal.FrameSize.Value
    for index, entry in drawn.items():  # the frame's axes at each pose, the toolpath run there
        np.testing.assert_allclose(entry["axes"][:, 0], [poses[index][:3, 3]] * 3, atol=1e-3)
        np.testing.assert_allclose(entry["axes"][0, 1], poses[index][:3, 3] + size * poses[index][:3, 0], atol=1e-3)
        assert entry["toolpath"] is not None and len(entry["toolpath"]) > 100
    assert page.difference.text() == "Pose 1: the pose the calibration found best."
    page_fits(guide.form)
    shoot_window("choose_pose_1")

    page.next_pose.click()
    pump(0.1)
    assert page.pose_label.text().startswith("Showing pose 2 of")
    text = page.difference.text()
    assert text.startswith("Pose 2: turned 180 deg about the part's ") and "from the best" in text
    assert candidate_display.hex_colour(1) in page.difference.styleSheet()
    drawn = candidate_display.drawn(view)
    assert drawn[1]["width"] == candidate_display.SHOWN_WIDTH and drawn[0]["width"] == candidate_display.OTHER_WIDTH
    assert frames.rotation_between_deg(poses[1], poses[0]) > 90
    shoot_window("choose_pose_2")

    page.choose_button.click()
    pump(0.1)
    assert cal.Status == CHOSEN and page.verdict.text().startswith("OK (CHOSEN)")
    record = result_of(cal).choice
    assert (record.index, record.count, record.who) == (1, len(poses), choice.user_name())
    assert record.difference in text
    assert page.accept_button.isEnabled() and not page.choose_button.isVisible()
    assert page.chosen.isVisible() and page.chosen.text().startswith(f"Chosen by {record.who} on ")
    np.testing.assert_allclose(matrix_of(cal.W), frames.invert(result_of(cal).V) @ poses[1], atol=1e-6)
    assert placed_model.find(cal, "workpiece", placed_model.ON_SCAN).Candidate == 1
    stored = json.loads(cal.ResultJson)
    assert stored["status"] == "ok (chosen)" and stored["choice"]["index"] == 1
    path = tmp_path / "result.json"
    result_of(cal).to_json(path)
    assert CalibrationResult.from_json(path).choice == record
    page_fits(guide.form)
    shoot_window("choose_pose_chosen")

    program = tmp_path / "part.src"
    export_program(cal, str(program), "krl")
    header = " ".join(line.lstrip("; ").strip() for line in program.read_text().splitlines() if line.startswith(";"))
    assert f"pose chosen by the user {record.who} on {record.when} among {len(poses)} candidate poses" in header
    assert "calibration status ok (chosen)" in header and "FORCED" not in header

    doc.undo()  # the choice (the export changed nothing in the document)
    pump(0.2)
    assert cal.Status == AMBIGUOUS and page.choose_button.isVisible() and not page.accept_button.isEnabled()
    doc.redo()
    pump(0.2)
    assert cal.Status == CHOSEN and result_of(cal).choice == record
    assert os.path.getsize(program) > 0


def test_a_deleted_model_hides_the_poses_without_a_traceback(doc, ambiguous_guide, pump):
    guide = ambiguous_guide
    page = guide.steps["result"]
    cal = guide.calibration()
    _, result = page.result()
    doc.removeObject(cal.Workpiece.Name)  # its result stays until recomputed; the panel refreshes on a timer
    page._shown_key = None  # as a refresh after any change to the result would
    assert page.shown_poses(cal, result, "workpiece") == []
    page._fill_poses(cal, result)
    assert not page.poses.isVisible()
    guide.go("result")
    pump(0.2)
