"""The guide when things go wrong: files read in the wrong unit, a step that failed, a model chosen twice,
reasons worded for people, and the guide's own controls in sight on a small screen.

Each test drives the guide's pages as a designer does and reads back what the running FreeCAD shows
(widget texts, marks, geometry) and what the document holds; a screenshot of each state is taken.
"""
import numpy as np
import pytest

FreeCAD = pytest.importorskip("FreeCAD")
if not FreeCAD.GuiUp:
    pytest.skip("needs the FreeCAD GUI (run tests/gui/run_gui_tests.py under xvfb-run freecad)",
                allow_module_level=True)

import FreeCADGui  # noqa: E402

from workcal_wb.fc import scan as fc_scan  # noqa: E402
from workcal_wb.fc.setup import get_setup  # noqa: E402
from workcal_wb.gui.task_panels import QtWidgets  # noqa: E402

# A box a third of a metre across, its numbers written in metres: read as mm it is well under 1 mm.
BOX_SIZE_M = 0.32


def box_in_metres(path, count=3000, seed=0, corner=(0.4, 0.1, 1.0)):
    """Points on the faces of a box BOX_SIZE_M across, written as plain 'x y z' lines in metres."""
    rng = np.random.default_rng(seed)
    points = rng.uniform(0.0, BOX_SIZE_M, size=(count, 3))
    face = rng.integers(0, 6, size=count)
    points[np.arange(count), face % 3] = np.where(face < 3, 0.0, BOX_SIZE_M)
    np.savetxt(path, points + np.asarray(corner), fmt="%.6f")
    return path


def extent(points) -> float:
    points = np.asarray(points, dtype=float)
    return float(np.linalg.norm(points.max(axis=0) - points.min(axis=0)))


def choose_in(combo, text) -> None:
    """Choose ``text`` in ``combo`` as a user does (the activated signal, not just the index)."""
    index = combo.findText(text)
    assert index >= 0, f"{text!r} is not offered in {[combo.itemText(i) for i in range(combo.count())]}"
    combo.setCurrentIndex(index)
    combo.activated.emit(index)


@pytest.fixture
def guide_of(doc):
    """``guide_of(step)``: the guide of the test's document open at ``step``."""
    from workcal_wb.gui.commands.guide import open_guide

    return lambda step=None: open_guide(doc, step)


def test_a_scan_read_in_the_wrong_unit_is_flagged_on_its_page_and_fixed_in_one_click(
        doc, tmp_path, guide_of, pump, shoot_window, page_fits):
    path = box_in_metres(tmp_path / "box_in_metres.xyz")
    panel = guide_of("scan")
    page = panel.steps["scan"]
    page.import_files([str(path)], units="mm")
    pump(0.1)
    scan = get_setup(doc)["scan"]
    assert scan.Units == "mm" and page.units.currentText() == "mm"  # the unit it was read in, on its step
    assert page.unit_warning.isVisible()
    text = page.unit_warning.text()
    assert "box_in_metres.xyz" in text and "mm across when read as mm" in text and "read it with unit m" in text
    assert page.unit_fix.isVisible() and page.unit_fix.text() == "Read it in m"
    page_fits(panel.form)
    shoot_window("scan_in_metres_read_as_mm")
    size_as_mm = extent(fc_scan.scan_cloud(scan).points)

    page.unit_fix.click()
    pump(0.1)
    assert scan.Units == "m" and page.units.currentText() == "m"
    assert extent(fc_scan.scan_cloud(scan).points) == pytest.approx(1000 * size_as_mm, rel=1e-5)
    assert not page.unit_warning.isVisible() and not page.unit_fix.isVisible()
    assert doc.UndoNames[0] == "Scan unit"
    shoot_window("scan_read_again_in_m")

    doc.undo()
    pump(0.1)
    assert scan.Units == "mm" and page.units.currentText() == "mm" and page.unit_warning.isVisible()
    choose_in(page.units, "cm")  # any unit, chosen on the page
    pump(0.1)
    assert scan.Units == "cm" and extent(fc_scan.scan_cloud(scan).points) == pytest.approx(10 * size_as_mm, rel=1e-5)
    assert not page.unit_warning.isVisible()  # a few mm across: small, but a size a part can have
    macro_lines = FreeCADGui.getMainWindow().findChild(QtWidgets.QPlainTextEdit, "Python console")
    if macro_lines is not None:
        assert "workcal_wb.fc.scan.change_units" in macro_lines.toPlainText()


def test_a_model_read_in_the_wrong_unit_is_flagged_for_its_role_and_fixed_in_one_click(
        doc, tmp_path, guide_of, pump, shoot_window, page_fits):
    path = box_in_metres(tmp_path / "block_in_metres.xyz", seed=1)
    panel = guide_of("models")
    page = panel.steps["models"]
    obj = page.load_file("reference", str(path), units="mm")
    pump(0.1)
    assert get_setup(doc)["reference"] is obj and obj.Units == "mm"
    assert page.unit_choosers["reference"].combo.currentText() == "mm"
    warning = page.unit_choosers["reference"].warning
    assert warning.isVisible() and "block_in_metres.xyz" in warning.text() and "read it with unit m" in warning.text()
    assert not page.unit_choosers["workpiece"].isVisible()  # nothing chosen there: nothing to say
    page_fits(panel.form)
    shoot_window("model_in_metres_read_as_mm")
    page.unit_choosers["reference"].fix.click()
    pump(0.1)
    assert obj.Units == "m" and page.unit_choosers["reference"].combo.currentText() == "m"
    assert extent([tuple(p) for p in obj.Points.Points]) == pytest.approx(1000 * BOX_SIZE_M * 3 ** 0.5, rel=0.05)
    assert not warning.isVisible()
    assert doc.UndoNames[0] == "Model unit"
    shoot_window("model_read_again_in_m")
    doc.undo()
    pump(0.1)
    assert obj.Units == "mm" and warning.isVisible()
