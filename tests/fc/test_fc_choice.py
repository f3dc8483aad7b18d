"""Choosing a pose of an ambiguous calibration object under freecadcmd: one undo step, kept by undo/redo and
by saving and reopening, the models on the scan shown at the chosen pose, and accepting it allowed."""
import numpy as np
import pytest

FreeCAD = pytest.importorskip("FreeCAD")

from workcal_wb.core import frames  # noqa: E402
from workcal_wb.core.errors import InputError  # noqa: E402
from workcal_wb.core.geometry import Cloud  # noqa: E402
from workcal_wb.core.result import AMBIGUOUS, CHOSEN, UNDER_CONSTRAINED, Reason  # noqa: E402
from workcal_wb.core.simulate import shapes  # noqa: E402
from workcal_wb.core.simulate.scanner import Scanner  # noqa: E402
from workcal_wb.core.simulate.scene import build_scene  # noqa: E402
from workcal_wb.fc import calibration_object as co  # noqa: E402
from workcal_wb.fc import placed_model  # noqa: E402
from workcal_wb.fc.lookups import result_of  # noqa: E402
from workcal_wb.fc.models import add_model  # noqa: E402
from workcal_wb.fc.placements import matrix_of  # noqa: E402
from workcal_wb.fc.scan import make_scan  # noqa: E402


@pytest.fixture
def ambiguous(tmp_path):
    """A document with an ellipsoid calibrated: symmetric, so ambiguous, the models placed on the scan."""
    scene = build_scene(shapes.ellipsoid(), seed=1)
    scan = Scanner.aimed_at(scene).scan(scene)
    doc = FreeCAD.newDocument("WorkCalChoiceTest")
    doc.UndoMode = 1
    cal = co.make_calibration(doc, make_scan(doc, Cloud(scan.points, name="scan"), "Scan"),
                              add_model(doc, scene.workpiece_model(), "Ellipsoid"),
                              add_model(doc, scene.reference_model(), "Reference"), resamples=2, overlays=True)
    assert cal.Status == AMBIGUOUS
    name = doc.Name
    yield doc, cal
    if name in FreeCAD.listDocuments():
        FreeCAD.closeDocument(name)


def test_a_chosen_pose_is_one_undo_step_and_survives_reopening(ambiguous, tmp_path):
    doc, cal = ambiguous
    before = result_of(cal)
    poses = placed_model.candidate_poses(cal, "workpiece")
    assert len(poses) > 2
    undo_before = doc.UndoCount
    co.choose_pose(cal, 2, who="tester")
    assert doc.UndoCount == undo_before + 1 and cal.Status == CHOSEN
    chosen = result_of(cal)
    assert chosen.choice.who == "tester" and chosen.choice.index == 2 and chosen.choice.count == len(poses)
    assert chosen.choice.difference.startswith("turned 180 deg about the part's")
    np.testing.assert_allclose(chosen.U, poses[2], atol=1e-9)
    np.testing.assert_allclose(matrix_of(cal.W), frames.invert(chosen.V) @ poses[2], atol=1e-6)
    np.testing.assert_allclose(placed_model.candidate_poses(cal, "workpiece")[0], poses[0], atol=1e-12)
    on_scan = placed_model.find(cal, "workpiece", placed_model.ON_SCAN)
    assert on_scan.Candidate == 2  # the scan shows the chosen pose
    co.accept(cal)
    assert cal.Accepted

    doc.undo()  # the acceptance
    doc.undo()  # the choice
    assert cal.Status == AMBIGUOUS and result_of(cal).choice is None and on_scan.Candidate == 0
    np.testing.assert_allclose(matrix_of(cal.W), before.W, atol=1e-6)
    doc.redo()
    assert cal.Status == CHOSEN and result_of(cal).choice == chosen.choice

    path = str(tmp_path / "chosen.FCStd")
    doc.saveAs(path)
    name = cal.Name
    FreeCAD.closeDocument(doc.Name)
    doc = FreeCAD.openDocument(path)
    try:
        cal = doc.getObject(name)
        doc.recompute()
        assert cal.Status == CHOSEN and result_of(cal).choice == chosen.choice
        np.testing.assert_allclose(matrix_of(cal.W), chosen.W, atol=1e-6)
    finally:
        FreeCAD.closeDocument(doc.Name)


def test_only_an_ambiguous_calibration_offers_a_choice(ambiguous):
    doc, cal = ambiguous
    with pytest.raises(InputError, match="no pose 9"):
        co.choose_pose(cal, 9)
    co.choose_pose(cal, 1)
    with pytest.raises(InputError, match="ambiguous"):  # chosen already: calibrate again to choose anew
        co.choose_pose(cal, 2)


def test_a_calibration_whose_inputs_changed_is_recomputed_before_a_choice(ambiguous):
    doc, cal = ambiguous
    stored = cal.ResultJson
    cal.Tolerance = 2 * cal.Tolerance.Value  # not recomputed: the result is of the inputs before
    with pytest.raises(InputError, match="recompute first"):
        co.choose_pose(cal, 1)
    assert cal.Status == AMBIGUOUS and cal.ResultJson == stored


def test_an_ambiguous_calibration_without_a_tie_says_so(ambiguous):
    doc, cal = ambiguous
    result = result_of(cal)
    doubt = Reason(UNDER_CONSTRAINED, "a motion the matched surface does not fix")
    result.workpiece.reasons = result.workpiece.reasons + [doubt]
    co.store_result(cal, result, cal.InputsKey)
    with pytest.raises(InputError, match="no tie between poses to choose from: .*more than a tie"):
        co.choose_pose(cal, 1)
    assert cal.Status == AMBIGUOUS
