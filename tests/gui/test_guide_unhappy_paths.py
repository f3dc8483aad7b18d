"""The guide when things go wrong: files read in the wrong unit, a step that failed, a model chosen twice,
reasons worded for people, and the guide's own controls in sight on a small screen; the report in its
own tab in front, and the scan drawn shaded.

Each test drives the guide's pages as a designer does and reads back what the running FreeCAD shows
(widget texts, marks, geometry) and what the document holds; a screenshot of each state is taken.
"""
import re

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

# A laptop screen, the smallest FreeCAD is commonly used on (px).
SMALL_SCREEN = (1366, 768)
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


@pytest.fixture
def failed_calibration(doc, tmp_path, monkeypatch):
    """A calibration in the guide's document that failed: its regions came out empty and a check failed by
    a share with float noise.  The match itself is replaced by that result (the guide's handling of a
    failure is under test, not the matcher)."""
    import Part

    from workcal_wb.core.result import NOT_FOUND, CalibrationResult, Reason
    from workcal_wb.fc import calibration_object as co
    from workcal_wb.fc import inputs as fc_inputs
    from workcal_wb.fc.scan import make_scan
    from workcal_wb.fc.setup import set_setup
    from workcal_wb.core.geometry import Cloud

    workpiece = doc.addObject("Part::Feature", "Block")
    workpiece.Shape = Part.makeBox(60, 40, 20)
    reference = doc.addObject("Part::Feature", "Cube")
    reference.Shape = Part.makeBox(30, 30, 30, FreeCAD.Vector(200, 0, 0))
    points = np.random.default_rng(0).uniform(0, 60, size=(2000, 3)) + [0, 0, 500]
    set_setup(doc, scan=make_scan(doc, Cloud(points, name="scan"), "Scan"), workpiece=workpiece, reference=reference)
    doc.recompute()
    W = np.eye(4)  # a pose with numbers as long as a real cell's
    rotation = FreeCAD.Rotation(FreeCAD.Vector(0.118, -0.862, -0.493), 87.123).toMatrix()
    W[:3, :3] = np.array(rotation.A).reshape(4, 4)[:3, :3]
    W[:3, 3] = (-1870.486, 205.048, -1170.651)
    failed = CalibrationResult(
        status="failed", W=W, reasons=[Reason(NOT_FOUND, "workpiece match: the scan shows too little of "
                                                                 "the workpiece model (use --regions auto)")],
        quality_gates=[{"name": "workpiece inliers", "value": 70.96000000000001, "limit": 80.0, "passed": False,
                        "unit": "%"}],
        regions={"workpiece": np.zeros(0, dtype=np.int64), "reference": np.zeros(0, dtype=np.int64)})
    monkeypatch.setattr(fc_inputs, "run", lambda inputs, progress=None: failed)
    calibration = co.make_calibration(doc, regions="Auto", resamples=1)
    assert calibration.Status == "failed"
    return calibration


def test_a_failed_calibration_is_crossed_out_in_the_step_list_not_ticked(doc, failed_calibration, guide_of, pump,
                                                                         shoot_window, page_fits):
    panel = guide_of("result")
    pump(0.1)
    states = panel.states()
    assert states["calibrate"][0] == "failed" and "FAILED" in states["calibrate"][1]
    assert states["result"][0] == "failed"
    assert states["regions"][0] == "failed" and "0 points" in states["regions"][1]  # empty regions: no tick
    for name in ("regions", "calibrate", "result"):
        mark = panel.rows[name].mark.text()
        assert "\u2717" in mark and "#c62828" in mark and "\u2713" not in mark, (name, mark)
    assert "\u2713" in panel.rows["scan"].mark.text() and "\u2713" in panel.rows["models"].mark.text()
    page_fits(panel.form)
    shoot_window("failed_calibration_crossed")


def test_reasons_in_the_guide_have_round_numbers_and_no_command_line_flags(doc, failed_calibration, guide_of, pump):
    from workcal_wb.gui.task_panels import common

    panel = guide_of("result")
    pump(0.1)
    shown = [panel.steps["result"].reasons.text(), panel.rows["result"].state.text(),
             panel.rows["calibrate"].state.text()]
    shown += [panel.steps["result"].checks.item(r, c).text() for r in range(panel.steps["result"].checks.rowCount())
              for c in range(3)]
    for text in shown:
        assert "--" not in text and "70.96000000000001" not in text, text
    assert "the scan shows too little of the workpiece model" in panel.steps["result"].reasons.text()
    for name in panel.steps:  # every text and tooltip of every page: no command-line flag
        panel.go(name)
        for widget in panel.form.findChildren(QtWidgets.QWidget):
            texts = [widget.toolTip()] + [widget.text()] if hasattr(widget, "text") and callable(widget.text) \
                else [widget.toolTip()]
            for text in texts:
                assert not re.search(r"(?<![\w-])--[a-z]", str(text)), (name, widget.objectName(), text)
    # The force question: the calibration's reason in it, rounded, without the command line's flag.
    asked = []
    monkey = common.confirm_force
    try:
        common.confirm_force = lambda reason, reach=False: asked.append(reason) or False
        panel.steps["toolpath"].use_file(str(write_gcode(doc)))
        panel.steps["toolpath"].show_in_robot_frame()
    finally:
        common.confirm_force = monkey
    assert asked, "no force question was asked"
    assert "70.96 %" in asked[0] and "70.96000000000001" not in asked[0] and "--" not in asked[0], asked[0]


def write_gcode(doc):
    import os
    import tempfile

    path = os.path.join(tempfile.mkdtemp(), "path.nc")
    with open(path, "w") as stream:
        stream.write("G21 G90\nG0 X0 Y0 Z10\nG1 Z0 F500\nG1 X20 Y10\nG1 X30 Y0\nG0 Z10\n")
    return path


def test_a_model_loaded_for_both_roles_is_refused_naming_both(doc, tmp_path, guide_of, pump, shoot_window,
                                                               page_fits):
    import Part

    step_file = tmp_path / "bracket.step"
    Part.makeBox(60, 40, 20).exportStep(str(step_file))
    panel = guide_of("models")
    page = panel.steps["models"]
    workpiece = page.load_file("workpiece", str(step_file))
    assert get_setup(doc)["workpiece"] is workpiece and not page.problem.isVisible()
    objects_before = [o.Name for o in doc.Objects]
    # The same file again, as the reference model: refused before it is read, the document unchanged.
    assert page.load_file("reference", str(step_file)) is None
    pump(0.1)
    text = page.problem.text()
    assert page.problem.isVisible() and "bracket.step" in text and "workpiece model" in text and \
        "reference model" in text, text
    assert get_setup(doc)["reference"] is None and [o.Name for o in doc.Objects] == objects_before
    assert "Traceback" not in text
    page_fits(panel.form)
    shoot_window("same_file_for_both_models")
    # The same shape under another name (a copy of the workpiece) chosen as the reference: refused naming both.
    copy = doc.addObject("Part::Feature", "BracketCopy")
    copy.Shape = workpiece.Shape.copy()
    copy.Label = "Bracket copy"
    doc.recompute()
    pump(0.1)
    choose_in(page.combos["reference"], "Bracket copy")
    pump(0.1)
    text = page.problem.text()
    assert "'Bracket copy'" in text and "'bracket.step'" in text and "same shape" in text, text
    assert get_setup(doc)["reference"] is None
    shoot_window("same_shape_for_both_models")
    # A model of its own for the reference: accepted, the message gone.
    other = doc.addObject("Part::Feature", "Cube")
    other.Shape = Part.makeBox(30, 30, 30, FreeCAD.Vector(200, 0, 0))
    doc.recompute()
    pump(0.1)
    choose_in(page.combos["reference"], "Cube")
    pump(0.1)
    assert get_setup(doc)["reference"] is other and not page.problem.isVisible()


# --- a small screen: 1366 x 768, FreeCAD's default panel width --------------------------------------

def task_view():
    """FreeCAD's task view: the scroll area that holds the open guide."""
    from workcal_wb.gui.task_panels.guide import GuidePanel

    from workcal_wb.gui.task_panels.common import scroll_area_around

    area = scroll_area_around(GuidePanel.current.form)
    assert area is not None, "the guide is not in a task view"
    return area


def in_sight(widget) -> bool:
    """Whether the whole of ``widget`` lies within the visible part of the task view."""
    from workcal_wb.gui.task_panels import QtCore

    viewport = task_view().viewport()
    corner = widget.mapTo(viewport, QtCore.QPoint(0, 0))
    shown = QtCore.QRect(corner, widget.size())
    return widget.isVisible() and viewport.rect().contains(shown)


@pytest.fixture
def small_screen(settle):
    """The main window as it fills a 1366 x 768 screen, maximised (as wide as the run's screen allows: the
    task panel's width is the dock's own, whatever the window's)."""
    from workcal_wb.gui.task_panels import QtCore, QtGui

    window = FreeCADGui.getMainWindow()
    before = window.geometry()
    screen = QtGui.QGuiApplication.primaryScreen().availableGeometry()
    if screen.height() < SMALL_SCREEN[1] - 40:
        pytest.skip(f"the screen ({screen.width()} x {screen.height()}) is smaller than the one tested")
    window.setGeometry(QtCore.QRect(screen.x(), screen.y(), min(SMALL_SCREEN[0], screen.width()),
                                    min(SMALL_SCREEN[1], screen.height())))
    settle()
    yield window
    window.setGeometry(before)


def test_the_guide_opens_without_a_document_and_makes_one(workbench, pump, shoot_window):
    from workcal_wb.gui.task_panels.guide import GuidePanel

    for name in list(FreeCAD.listDocuments()):
        FreeCAD.closeDocument(name)
    pump(0.2)
    assert FreeCAD.ActiveDocument is None
    from workcal_wb.gui.commands.guide import COMMANDS

    assert COMMANDS["WorkCal_Guide"].IsActive()  # the toolbar button is not greyed out
    try:
        FreeCADGui.runCommand("WorkCal_Guide")
        pump(0.3)
        panel = GuidePanel.current
        assert FreeCAD.ActiveDocument is not None and panel is not None and panel.alive()
        assert panel.doc is FreeCAD.ActiveDocument and panel.shown == "scan"
        shoot_window("guide_without_a_document")
    finally:
        if FreeCADGui.Control.activeDialog():
            FreeCADGui.Control.closeDialog()
        for name in list(FreeCAD.listDocuments()):
            FreeCAD.closeDocument(name)
        pump(0.1)


def test_on_a_small_screen_the_next_button_stays_in_sight_on_every_page(doc, failed_calibration, small_screen,
                                                                        guide_of, pump, settle, shoot_window,
                                                                        page_fits):
    panel = guide_of("scan")
    for name in panel.steps:
        panel.go(name)
        settle()
        bar = task_view().verticalScrollBar()
        bar.setValue(bar.maximum())  # the task view scrolled to its end
        pump(0.1)
        next_visible = panel.next_button.isVisible()
        if next_visible:
            assert in_sight(panel.next_button), f"{name}: the Next button is out of sight"
        task_view().verticalScrollBar().setValue(0)  # and back to its top
        pump(0.1)
        if next_visible:
            assert in_sight(panel.next_button), f"{name}: the Next button is out of sight at the top"
        page_fits(panel.form)
        assert not panel.scroll.horizontalScrollBar().isVisible(), f"{name}: the page scrolls sideways"
        shoot_window(f"small_screen_{name}")
    # The result: W in one line per quantity, the checks table whole (it does not scroll inside the panel).
    panel.go("result")
    settle()
    page = panel.steps["result"]
    line = page.position.fontMetrics().lineSpacing()
    for widget in (page.position, page.euler, page.omega):
        assert widget.height() < 1.8 * line, (widget.objectName(), widget.text(), widget.height(), line)
    assert page.rotation.height() < 2.8 * line
    table = page.checks
    assert not table.verticalScrollBar().isVisible() and not table.horizontalScrollBar().isVisible()
    rows = sum(table.rowHeight(r) for r in range(table.rowCount()))
    assert table.viewport().height() >= rows
    panel.scroll.ensureWidgetVisible(page.checks)
    pump(0.1)
    assert in_sight(panel.next_button)
    shoot_window("small_screen_result_W_and_checks")


def test_the_report_opens_in_a_tab_named_after_the_calibration_in_front(doc, tmp_path, pump, output_dir):
    from workcal_wb.gui.commands.report import open_report, report_title
    from workcal_wb.gui.task_panels.common import main_window

    calibration = doc.addObject("App::FeaturePython", "Calibration001")
    calibration.Label = "Left fixture"
    html = tmp_path / "report.html"
    html.write_text("<html><body><h1>WorkCal report</h1><p>W is known.</p></body></html>", encoding="utf-8")
    title = report_title(calibration)
    assert title == "Report: Left fixture"
    where = open_report(str(html), title)
    pump(0.5)
    if where != "freecad":
        pytest.skip("this FreeCAD has no web view: the report went to the system browser")
    area = main_window().findChild(QtWidgets.QMdiArea)
    active = area.activeSubWindow()
    assert active is not None and active.windowTitle().startswith(title), [
        w.windowTitle() for w in area.subWindowList()]
    assert main_window().grab().save(str(output_dir / "report_in_front.png"))  # the web view, not a 3D view
    # Opened again (after another window came to the front): the same one tab, in front again.
    area.setActiveSubWindow(area.subWindowList()[0])
    open_report(str(html), title)
    pump(0.5)
    area = main_window().findChild(QtWidgets.QMdiArea)
    tabs = [w for w in area.subWindowList() if w.windowTitle().startswith(title)]
    assert len(tabs) == 1 and area.activeSubWindow() is tabs[0]


def test_the_scan_is_drawn_shaded_by_its_surfaces_not_flat_grey(doc, tmp_path, guide_of, pump, settle, shoot_window):
    from workcal_wb.cli.simulate import write_simulation
    from workcal_wb.gui import scan_shading

    write_simulation(tmp_path, "car", seed=0)
    panel = guide_of("scan")
    panel.steps["scan"].import_files([str(tmp_path / "scan.ply")], units="mm")
    pump(0.3)
    settle()
    scan = get_setup(doc)["scan"]
    assert scan_shading.wait(scan, 60), "the scan was not shaded within a minute"
    colours = scan_shading.shown_colours(scan)  # read back from the scene graph
    assert colours is not None and len(colours) == scan.PointCount
    brightness = colours.mean(axis=1)
    assert brightness.std() > 0.05 and brightness.max() - brightness.min() > 0.3  # lit, not one grey
    assert scan_shading.shown(scan)
    scan.ViewObject.Visibility = False
    pump(0.1)
    assert not scan_shading.shown(scan)  # hidden with the scan
    scan.ViewObject.Visibility = True
    pump(0.1)
    assert scan_shading.shown(scan)
    shoot_window("scan_shaded")


def test_a_document_closed_under_its_guide_closes_the_guide_without_an_error(doc, guide_of, pump, report):
    """Closing the document while its guide is open: FreeCAD has deleted the GUI document by then, so the
    guide closes without looking for its 3D view (which raised "Unknown document" into the Report view)."""
    from workcal_wb.gui.task_panels.guide import GuidePanel

    panel = guide_of("regions")
    assert GuidePanel.current is panel and FreeCADGui.Control.activeDialog()
    FreeCAD.closeDocument(doc.Name)
    pump(0.2)
    logged = report.since()
    assert "Traceback" not in logged and "Unknown document" not in logged, logged
    assert GuidePanel.current is None and not panel.alive() and not FreeCADGui.Control.activeDialog()


def test_a_guide_whose_dialog_freecad_closed_leaves_the_next_guide_open_when_its_document_closes(
        doc, guide_of, pump, report):
    """FreeCAD may close a guide's dialog itself (another command's panel, a test's clean-up): the guide
    still watches its document, and when that closes it must not close the dialog open then, which
    belongs to another document's guide."""
    from workcal_wb.gui.commands.guide import open_guide
    from workcal_wb.gui.task_panels.guide import GuidePanel

    first = guide_of("scan")
    FreeCADGui.Control.closeDialog()
    pump(0.1)
    other = FreeCAD.newDocument("OtherGuideDocument")
    try:
        second = open_guide(other, "scan")
        assert GuidePanel.current is second and second.alive()
        FreeCAD.closeDocument(doc.Name)
        pump(0.2)
        assert second.alive() and FreeCADGui.Control.activeDialog() and GuidePanel.current is second
        assert not first.alive()
        logged = report.since()
        assert "Traceback" not in logged and "Unknown document" not in logged, logged
    finally:
        if FreeCADGui.Control.activeDialog():
            FreeCADGui.Control.closeDialog()
        FreeCAD.closeDocument(other.Name)
        pump(0.1)


def task_panels() -> int:
    """How many panels FreeCAD's task views hold their task boxes in.  Counted over the application's
    widgets, not from the main window: its Python wrapper would keep a wrapper of each widget found."""
    names = {"Gui::TaskView::TaskPanel", "QSint::ActionPanel"}
    return sum(w.metaObject().className() in names for w in QtWidgets.QApplication.allWidgets())


def test_freecads_task_panel_outlives_the_guides_python_objects(pump):
    """The guide fits its form to FreeCAD's task view; once the guide is closed, its document too, and Python
    has collected what the guide held, FreeCAD's own panel in the task view is still there (a wrapper
    Python made for it as the task view's widget went with the guide and deleted it, and FreeCAD 1.0
    crashed on its next layout pass), and a dialog still opens there."""
    import gc
    import weakref

    from workcal_wb.gui.commands.guide import open_guide

    before = task_panels()
    assert before >= 1
    for step in ("scan", "result"):
        other = FreeCAD.newDocument("GuideCollected")
        panel = open_guide(other, step)
        pump(0.3)
        assert panel.fitter.area is not None  # fitted to the task view
        FreeCADGui.Control.closeDialog()
        FreeCAD.closeDocument(other.Name)
        pump(0.2)
        guide = weakref.ref(panel)
        del panel
        gc.collect()
        pump(0.2)
        assert guide() is None  # collected, with what it held
        assert task_panels() == before
    other = FreeCAD.newDocument("GuideAfter")
    try:
        panel = open_guide(other, "scan")
        pump(0.3)  # FreeCAD lays its task view out again 100 ms after a dialog opens
        assert panel.alive() and FreeCADGui.Control.activeDialog()
    finally:
        if FreeCADGui.Control.activeDialog():
            FreeCADGui.Control.closeDialog()
        FreeCAD.closeDocument(other.Name)
        pump(0.2)
