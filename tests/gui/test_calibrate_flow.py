"""End to end in the FreeCAD GUI (Xvfb): simulated scene -> calibrate through the task panel -> reopen ->
deviation map -> calibrated toolpath -> robot program -> report; screenshots of each step.

The tests share one document and run in file order (each step needs the previous one); a failed step
makes the later ones skip instead of failing for the wrong reason.
"""
import csv
import os
import time

import numpy as np
import pytest

FreeCAD = pytest.importorskip("FreeCAD")
if not FreeCAD.GuiUp:
    pytest.skip("needs the FreeCAD GUI (run tests/gui/run_gui_tests.py under xvfb-run freecad)",
                allow_module_level=True)

import FreeCADGui  # noqa: E402

from workcal_wb.core import frames  # noqa: E402
from workcal_wb.core.geometry import Cloud  # noqa: E402
from workcal_wb.core.simulate.scanner import Scanner  # noqa: E402
from workcal_wb.core.simulate.scene import build_scene  # noqa: E402
from workcal_wb.core.simulate.toolpath_sample import sample_toolpath  # noqa: E402
from workcal_wb.fc import calibration_object as co  # noqa: E402
from workcal_wb.fc import lookups  # noqa: E402
from workcal_wb.fc import placed_model  # noqa: E402
from workcal_wb.fc.models import add_model  # noqa: E402
from workcal_wb.fc.placements import matrix_of  # noqa: E402
from workcal_wb.gui.task_panels import QtCore, QtWidgets  # noqa: E402
from workcal_wb.gui.task_panels import common  # noqa: E402
from workcal_wb.gui.view import without_animation  # noqa: E402

ROT_TOL_DEG, TRANS_TOL_MM = 0.05, 0.1
SEED = 0  # calibration seed (the default)
SHOT_SIZE = (1000, 750)


@pytest.fixture(scope="module")
def flow(tmp_path_factory, request):
    """State shared by the steps: scene, truth, the document and what each step made."""
    scene = build_scene("car", seed=0, clay_change=["lump"])
    scan = Scanner.aimed_at(scene).scan(scene)
    common.INTERACTIVE = False  # no modal message boxes in tests
    state = {"scene": scene, "scan": scan, "dir": tmp_path_factory.mktemp("calibrate_flow"),
             "failures_at_start": request.session.testsfailed}
    yield state
    common.INTERACTIVE = True
    if FreeCADGui.Control.activeDialog():
        FreeCADGui.Control.closeDialog()
    doc = state.get("doc")
    if doc is not None:
        try:
            FreeCAD.closeDocument(doc.Name)
        except Exception:
            pass


@pytest.fixture
def step(flow, request):
    """The shared state; skips when an earlier step of this flow failed."""
    if request.session.testsfailed > flow["failures_at_start"]:
        pytest.skip("an earlier step of the calibrate flow failed")
    return flow


def pump(seconds=0.05):
    common.process_events(seconds)



# Looking from the scanner: along +z of S with -y of S up (camera looks along its own -z).
FROM_SCANNER = FreeCAD.Rotation(FreeCAD.Vector(1, 0, 0), 180)


def screenshot(output_dir, name, only=None, orientation=None):
    """Save the 3D view; ``only``: show just these objects (fitted), the others are hidden meanwhile."""
    view = FreeCADGui.ActiveDocument.ActiveView
    hidden = []
    if only:
        for obj in FreeCADGui.ActiveDocument.Document.Objects:
            vobj = getattr(obj, "ViewObject", None)
            if vobj is not None and obj not in only and vobj.Visibility:
                vobj.Visibility = False
                hidden.append(vobj)
        for obj in only:
            obj.ViewObject.Visibility = True
    with without_animation(view):
        if orientation is not None:
            view.setCameraOrientation(orientation)
        else:
            view.viewIsometric()
        view.fitAll()
    pump(0.1)
    path = os.path.join(str(output_dir), name)
    try:
        view.saveImage(path, SHOT_SIZE[0], SHOT_SIZE[1], "White")
    finally:
        for vobj in hidden:
            vobj.Visibility = True
    assert os.path.getsize(path) > 5000
    return path


def object_names(doc):
    return sorted(o.Name for o in doc.Objects)


def wait_for(predicate, timeout_s=60.0):
    end = time.monotonic() + timeout_s
    while not predicate() and time.monotonic() < end:
        pump(0.05)
    return predicate()


def assert_pose(T, truth):
    assert frames.rotation_between_deg(T, truth) < ROT_TOL_DEG
    assert np.linalg.norm(T[:3, 3] - truth[:3, 3]) < TRANS_TOL_MM


def test_01_import_simulated_scene(step, workbench, output_dir):
    from workcal_wb.fc.scan import make_scan
    from workcal_wb.fc.setup import set_setup

    flow = step
    doc = FreeCAD.newDocument("WorkCalFlow")
    flow["doc"] = doc
    scene, scan = flow["scene"], flow["scan"]
    flow["scan_obj"] = make_scan(doc, Cloud(scan.points, name="scene scan"), "Scan", "mm", "simulated scan")
    flow["workpiece"] = add_model(doc, scene.workpiece_model(), "Workpiece")
    flow["reference"] = add_model(doc, scene.reference_model(), "Reference")
    set_setup(doc, scan=flow["scan_obj"], workpiece=flow["workpiece"], reference=flow["reference"])
    doc.recompute()
    assert flow["scan_obj"].Points.CountPoints == len(scan.points)
    screenshot(output_dir, "01_imported.png")


def open_calibrate_step(doc):
    from workcal_wb.gui.commands.guide import open_guide

    guide = open_guide(doc, "calibrate")
    return guide, guide.steps["calibrate"]


def test_02_cancel_midway_leaves_the_document_unchanged(step, output_dir):
    flow = step
    doc = flow["doc"]
    before, undo_before = object_names(doc), doc.UndoCount
    guide, page = open_calibrate_step(doc)
    page.set_options(seed=SEED, regions="Auto")
    assert page.start()
    assert wait_for(lambda: page.progress_bar.value() > 0 or not page.busy(), 30)  # under way
    assert page.busy() and page.cancel_button.isVisible()
    page.cancel_button.click()  # what the user does: the worker is asked to stop
    assert page.wait(60) == "cancelled"
    assert object_names(doc) == before and doc.UndoCount == undo_before
    assert "unchanged" in page.message.text() and FreeCADGui.Control.activeDialog()  # the guide stays
    assert guide.states()["calibrate"][0] == "todo"
    screenshot(output_dir, "02_after_cancel.png")
    guide.close()


def test_03_bad_input_reports_and_changes_nothing(step, report):
    flow = step
    doc = flow["doc"]
    before = object_names(doc)
    guide, page = open_calibrate_step(doc)
    assert not page.picked_regions.isEnabled()  # nothing picked on the scan yet
    page.set_options(regions="Picked")  # as a script could: refused with the reason
    assert not page.start()
    assert page.state_name == "failed" and "no workpiece and no reference region" in page.last_error
    assert "region" in page.message.text()
    assert "no workpiece and no reference region" in report.since()  # the message reached the Report view
    assert FreeCADGui.Control.activeDialog()  # the user can fix the input
    guide.close()
    pump()
    assert not FreeCADGui.Control.activeDialog()
    assert object_names(doc) == before


def test_04_calibrate_through_the_guide(step, output_dir, page_fits):
    flow = step
    doc, scene = flow["doc"], flow["scene"]
    before, undo_before = object_names(doc), doc.UndoCount
    guide, page = open_calibrate_step(doc)
    page_fits(guide.form)
    page.set_options(method="robust", tolerance_mm=0.3, regions="Auto", seed=SEED)
    ticks = []  # while the worker thread runs (adding the result afterwards is main-thread work)
    timer = QtCore.QTimer()
    timer.timeout.connect(lambda: page.runner is not None and page.runner.running and ticks.append(time.monotonic()))
    timer.start(20)
    progress_seen = []
    page.start_button.click()  # starts the worker; the guide stays open
    assert page.busy()
    while page.busy():
        pump(0.05)
        bar = page.status
        if bar is not None and bar.bar is not None:
            progress_seen.append(bar.bar.value())
    timer.stop()
    assert page.state_name == "done", page.last_error
    # The window stayed responsive: the timer kept firing while the worker ran.
    gaps = np.diff(ticks)
    assert len(ticks) > 20 and gaps.max() < 1.0, f"event loop blocked for {gaps.max():.2f} s"
    assert max(progress_seen) > 0  # the status-bar progress bar moved
    assert guide.shown == "result"  # the result stays open
    cal = guide.calibration()
    assert lookups.is_calibration(cal) and cal.Status == "ok", cal.Reasons
    assert_pose(matrix_of(cal.W), scene.W)
    assert_pose(matrix_of(cal.U), flow["scan"].U)
    assert_pose(matrix_of(cal.V), flow["scan"].V)
    # One undo step adds the calibration and both models on the scan; undo removes them, redo brings them back.
    assert doc.UndoCount == undo_before + 1
    added = sorted(set(object_names(doc)) - set(before))
    assert cal.Name in added and len(added) == 3
    doc.undo()
    assert object_names(doc) == before
    doc.redo()
    assert object_names(doc) == sorted(before + added)
    cal = doc.getObject(cal.Name)
    guide.close()
    assert not FreeCADGui.Control.activeDialog()
    assert cal.ViewObject.Proxy.getIcon().endswith("WorkCal_Calibration.svg")
    assert not cal.ViewObject.Visibility  # the result step showed the scan frame, where B's triads are far away
    cal.ViewObject.Visibility = True
    vp = cal.ViewObject.Proxy
    assert vp.switch.whichChild.getValue() == 0 and vp.labels.getNumChildren() == 5  # colour, font + B, S, X
    assert len(cal.ViewObject.LineColorArray) == 9  # red, green, blue axes
    # The right-click menu (built with Qt6-safe calls) offers the placed model and the deviation map, as
    # recorded commands; asking for the placed model again does not add a second one.
    menu = QtWidgets.QMenu()
    vp.setupContextMenu(cal.ViewObject, menu)
    actions = {a.text(): a for a in menu.actions()}
    assert set(actions) >= {"Show the workpiece model in the robot frame", "Deviation map"}
    for _ in range(2):
        actions["Show the workpiece model in the robot frame"].trigger()
        pump()
    in_b = [o for o in placed_model.objects_of(doc, placed_model.TYPE) if o.Frame == placed_model.IN_ROBOT_FRAME]
    assert len(in_b) == 1
    # The placed model is drawn (a Python feature with no display mode would not be) and sits where
    # the workpiece stands beside the reference in B.
    [placed] = in_b
    assert placed.ViewObject.Visibility and placed.ViewObject.DisplayMode in placed.ViewObject.listDisplayModes()
    shown = np.array([tuple(v) for v in placed.Mesh.Topology[0]])
    np.testing.assert_allclose(shown, frames.apply(scene.W, scene.workpiece_model().points), atol=0.5)
    flow["cal"] = cal
    screenshot(output_dir, "04_calibrated.png")
    screenshot(output_dir, "04_placed_model_on_reference.png", only=[placed, flow["reference"], cal])


def property_names_cut_off(obj) -> list:
    """The names of WorkCal's properties of ``obj`` that the property editor (FreeCAD's default panel
    width) cannot show whole: a name wider than its cell is elided."""
    window = FreeCADGui.getMainWindow()
    FreeCADGui.Selection.clearSelection()
    FreeCADGui.Selection.addSelection(obj)
    pump(0.3)
    editors = [t for t in window.findChildren(QtWidgets.QTreeView)
               if t.isVisible() and t.model() is not None and t.model().columnCount() == 2
               and str(t.model().headerData(0, QtCore.Qt.Horizontal)) == "Property"]
    assert editors, "no property editor in the main window"
    tree, ours = editors[0], set(obj.PropertiesList) - set(FreeCAD.ActiveDocument.addObject(
        obj.TypeId.replace("Python", ""), "Plain").PropertiesList)
    FreeCAD.ActiveDocument.removeObject("Plain")
    model = tree.model()
    cut = []
    for group in (model.index(row, 0) for row in range(model.rowCount())):
        tree.expand(group)
        for row in range(model.rowCount(group)):
            index = model.index(row, 0, group)
            text = str(index.data())
            if text.replace(" ", "") not in ours:
                continue
            needed = tree.fontMetrics().boundingRect(text).width() + 6  # the cell's margins
            if needed > tree.visualRect(index).width():
                cut.append(f"{text}: {needed} px in {tree.visualRect(index).width()} px")
    FreeCADGui.Selection.clearSelection()
    return cut


def test_04b_result_properties_read_whole(step):
    """The property editor shows every name of WorkCal's properties whole at FreeCAD's default panel
    width (names such as "WorkpieceWithinTolerance" used to be cut off)."""
    from workcal_wb.fc.deviation_map import make_deviation_map
    from workcal_wb.gui.task_panels import QtWidgets as widgets

    combo = [d for d in FreeCADGui.getMainWindow().findChildren(widgets.QDockWidget) if d.objectName() == "Combo View"]
    tabs = combo[0].findChild(widgets.QTabWidget) if combo else None
    if tabs is not None:
        tabs.setCurrentIndex(0)  # the Model tab, with the property editor
    cal = step["cal"]
    dev = make_deviation_map(cal)
    try:
        objects = [cal, dev, placed_model.find(cal, "workpiece", placed_model.ON_SCAN), cal.Scan]
        cut = [f"{o.Label}: {c}" for o in objects for c in property_names_cut_off(o)]
    finally:
        step["doc"].removeObject(dev.Name)
    assert not cut, cut


def test_05_save_close_reopen(step, output_dir):
    flow = step
    doc, cal = flow["doc"], flow["cal"]
    stored, name = cal.ResultJson, cal.Name
    W = matrix_of(cal.W)
    path = os.path.join(str(output_dir), "calibrated.FCStd")
    doc.saveAs(path)
    FreeCAD.closeDocument(doc.Name)
    pump()
    doc = FreeCAD.openDocument(path)
    pump()
    flow["doc"] = doc
    cal = doc.getObject(name)
    assert lookups.is_calibration(cal) and cal.ResultJson == stored and cal.Status == "ok"
    np.testing.assert_allclose(matrix_of(cal.Placement), W, atol=1e-9)
    from workcal_wb.gui.view_providers.calibration import ViewProviderCalibration

    assert isinstance(cal.ViewObject.Proxy, ViewProviderCalibration)
    for obj in placed_model.objects_of(doc, placed_model.TYPE):  # drawn again after reopening
        assert obj.ViewObject.Proxy.__class__.__name__ == "ViewProviderPlacedModel"
    assert "Touched" not in cal.State
    flow["cal"] = cal
    flow["scan_obj"], flow["workpiece"], flow["reference"] = cal.Scan, cal.Workpiece, cal.Reference
    assert cal.Scan is not None and cal.Workpiece is not None
    screenshot(output_dir, "05_reopened.png")


def test_06_deviation_map_shows_the_lump(step, output_dir):
    from workcal_wb.gui.commands.report import deviation_map

    flow = step
    doc, cal = flow["doc"], flow["cal"]
    undo_before = doc.UndoCount
    dev = deviation_map(cal)
    assert doc.UndoCount == undo_before + 1 and not cal.Scan.ViewObject.Visibility
    d = np.array(dev.Deviations)
    assert np.nanmax(d) > 1.0 and dev.Max.Value > 1.0  # the clay lump stands out
    assert dev.Within > 50
    assert dev.ViewObject.DisplayMode == "Color"
    vp = dev.ViewObject.Proxy
    assert vp.switch.whichChild.getValue() == 0 and vp.legend.getNumChildren() > 0  # colour bar shown
    flow["dev"] = dev
    screenshot(output_dir, "06_deviation_map.png", only=[dev], orientation=FROM_SCANNER)
    dev.ViewObject.Visibility = False
    assert vp.switch.whichChild.getValue() == -1  # the legend goes with the map
    dev.ViewObject.Visibility = True


def _gcode_file(flow):
    from workcal_wb.core.toolpath import format_gcode

    path = os.path.join(str(flow["dir"]), "finishing.nc")
    toolpath = sample_toolpath(flow["scene"])
    with open(path, "w", encoding="utf-8") as fh:
        fh.write(format_gcode(toolpath))
    return path, toolpath


def test_07_transform_and_export_toolpath(step, output_dir):
    from workcal_wb.core.toolpath import linearised, read_gcode
    from workcal_wb.fc.toolpath_input import read_toolpath
    from workcal_wb.gui.actions import choose_toolpath, export_program, transform_toolpath

    flow = step
    doc, cal, scene = flow["doc"], flow["cal"], flow["scene"]
    gcode, _ = _gcode_file(flow)
    toolpath = read_gcode(gcode)
    W = matrix_of(cal.W)
    choose_toolpath(doc, gcode)  # chosen once for the document
    undo_before = doc.UndoCount
    path_obj = transform_toolpath(cal)
    assert doc.UndoCount == undo_before + 1
    moved = read_toolpath(path_obj)
    np.testing.assert_allclose(moved.points(), frames.apply(W, linearised(toolpath).points()), atol=1e-5)
    # Against the truth, the calibrated path lies within the tolerance of where it should be.
    error = np.linalg.norm(moved.points() - frames.apply(scene.W, linearised(toolpath).points()), axis=1)
    assert error.max() < 0.1
    in_b = [o for o in placed_model.objects_of(doc, placed_model.TYPE) if o.Frame == placed_model.IN_ROBOT_FRAME]
    screenshot(output_dir, "07_toolpath_in_B.png", only=[path_obj, flow["reference"]] + in_b)

    for fmt, ext in (("krl", ".src"), ("csv", ".csv"), ("rapid", ".mod"), ("urscript", ".script"),
                     ("fanuc", ".ls"), ("gcode", ".nc")):
        out = os.path.join(str(output_dir), f"program{ext}")
        # the sample scene tilts the part a few degrees: G-code for a 5-axis machine (3-axis is refused)
        export_program(cal, out, fmt, **({"machine": "5axis-tcp"} if fmt == "gcode" else {}))
        assert os.path.getsize(out) > 100
    with open(os.path.join(str(output_dir), "program.csv"), encoding="utf-8") as fh:
        rows = [r for r in csv.reader(line for line in fh if not line.startswith("#"))]
    header, rows = rows[0], rows[1:]
    xyz = np.array([[float(r[header.index(k)]) for k in ("x_mm", "y_mm", "z_mm")] for r in rows])
    np.testing.assert_allclose(xyz, frames.apply(W, linearised(toolpath).points()), atol=1e-3)
    exported = read_gcode(os.path.join(str(output_dir), "program.nc"))
    np.testing.assert_allclose(exported.points(), frames.apply(W, linearised(toolpath).points()), atol=1e-3)


def test_08_failed_calibration_needs_force(step):
    from workcal_wb.core.result import CalibrationResult
    from workcal_wb.core.toolpath import CalibrationNotOk
    from workcal_wb.gui.actions import export_program, transform_toolpath

    flow = step
    doc, cal = flow["doc"], flow["cal"]
    good = lookups.result_of(cal)
    bad = CalibrationResult.from_dict({**good.to_dict(), "status": "failed", "reasons": ["test: gates failed"]})
    failed = co.make_calibration(doc, cal.Scan, cal.Workpiece, cal.Reference, resamples=1, name="FailedCalibration")
    co.store_result(failed, bad, failed.InputsKey)
    assert failed.Status == "failed"
    before = object_names(doc)
    with pytest.raises(CalibrationNotOk):
        transform_toolpath(failed)
    assert object_names(doc) == before
    assert common.with_force(lambda force: transform_toolpath(failed, force=force),
                             confirm=lambda reason: False) is None
    assert object_names(doc) == before
    forced = common.with_force(lambda force: transform_toolpath(failed, force=force),
                               confirm=lambda reason: "failed" in reason)
    assert "FORCED" in forced.Label and forced.Forced
    out = os.path.join(str(flow["dir"]), "refused.src")
    with pytest.raises(CalibrationNotOk):
        export_program(failed, out)
    assert not os.path.exists(out)
    job = common.with_force(lambda force: export_program(failed, out, force=force), confirm=lambda r: True)
    assert job.forced and "FORCED" in open(out, encoding="utf-8").read()
    doc.removeObject(forced.Name)
    for obj in placed_model.objects_of(doc, placed_model.TYPE):
        if obj.Calibration is failed:
            doc.removeObject(obj.Name)
    doc.removeObject(failed.Name)


def test_09_report_written(step, output_dir):
    from workcal_wb.gui.commands.report import write_report

    flow = step
    paths = write_report(flow["cal"], os.path.join(str(output_dir), "report"))
    html = open(paths["html"], encoding="utf-8").read()
    assert "<html" in html.lower() and "OK" in html
    assert os.path.exists(paths["json"])


def test_10_commands_registered_and_guarded(step, output_dir):
    flow = step
    doc = flow["doc"]
    commands = FreeCADGui.listCommands()
    for name in ("WorkCal_Calibrate", "WorkCal_DeviationMap", "WorkCal_TransformToolpath", "WorkCal_ExportToolpath",
                 "WorkCal_Report", "WorkCal_Studies", "WorkCal_Preferences"):
        assert name in commands, name
    # A command that fails reports and returns instead of raising into FreeCAD.
    FreeCADGui.Selection.clearSelection()
    empty = FreeCAD.newDocument("WorkCalEmpty")
    try:
        FreeCADGui.runCommand("WorkCal_DeviationMap")  # no calibration: a message, no exception
        pump()
        assert object_names(empty) == []
    finally:
        FreeCAD.closeDocument(empty.Name)
        FreeCAD.setActiveDocument(doc.Name)
        FreeCADGui.ActiveDocument = FreeCADGui.getDocument(doc.Name)
    # The real command on the selected calibration: a second deviation map.
    FreeCADGui.Selection.addSelection(flow["cal"])
    count = len([o for o in doc.Objects if o.TypeId == "Points::FeaturePython"])
    FreeCADGui.runCommand("WorkCal_DeviationMap")
    pump()
    assert len([o for o in doc.Objects if o.TypeId == "Points::FeaturePython"]) == count + 1


def test_11_preferences_page(step, report, output_dir, choose_folder):
    from workcal_wb.fc import prefs
    from workcal_wb.fc.inputs import options_from
    from workcal_wb.gui.commands.preferences import PreferencePage

    # The page is in FreeCAD's (modal) preferences dialog: look for it from a timer, then close the dialog.
    seen = []

    def inspect_and_close():
        for dialog in QtWidgets.QApplication.topLevelWidgets():
            if isinstance(dialog, QtWidgets.QDialog) and dialog.isVisible():
                page = dialog.findChild(QtWidgets.QWidget, "WorkCalPreferences")
                seen.append(page is not None and page.findChild(QtWidgets.QDoubleSpinBox, "tolerance") is not None)
                dialog.grab().save(os.path.join(str(output_dir), "11_preferences.png"))
                dialog.reject()

    QtCore.QTimer.singleShot(1500, inspect_and_close)
    FreeCADGui.runCommand("WorkCal_Preferences")  # returns when the dialog is closed
    pump(0.1)
    assert seen and seen[0], "the WorkCal page was not in the preferences dialog"
    assert "Cannot find icon" not in report.since()  # the page's icon (preferences-workcal) is there
    page = PreferencePage()
    page.loadSettings()
    # "0" says what it means, and the report folder has a Browse button.
    assert page.form.deviationRange.value() == 0 and page.form.deviationRange.text().startswith("automatic")
    assert page.form.reportDir.placeholderText() and page.form.reportDirBrowse.text() == "Browse..."
    assert choose_folder(page.form.reportDirBrowse, output_dir)
    assert os.path.samefile(page.form.reportDir.text(), str(output_dir))

    saved = prefs.all_values()
    try:
        page = PreferencePage()
        page.loadSettings()
        page.form.tolerance.setValue(0.25)
        page.form.method.setCurrentIndex(page.form.method.findText("hausdorff"))
        page.form.exportFormat.setCurrentIndex(page.form.exportFormat.findData("csv"))
        page.saveSettings()
        assert prefs.get("ToleranceMm") == pytest.approx(0.25)
        assert prefs.get("Method") == "hausdorff" and prefs.get("ExportFormat") == "csv"
        assert options_from().method == "hausdorff"  # what a new calibration starts with
    finally:
        for name, value in saved.items():
            prefs.set(name, value)


def test_12_double_click_opens_the_result_and_redo_reruns(step):
    from workcal_wb.gui.task_panels.guide import GuidePanel

    flow = step
    doc, cal, scene = flow["doc"], flow["cal"], flow["scene"]
    undo_before, before = doc.UndoCount, object_names(doc)
    assert cal.ViewObject.Proxy.doubleClicked(cal.ViewObject)
    guide = GuidePanel.current
    assert guide is not None and FreeCADGui.Control.activeDialog() and guide.shown == "result"
    assert guide.calibration() is cal
    guide.steps["result"].redo_button.click()
    page = guide.steps["calibrate"]
    assert guide.shown == "calibrate" and page.tolerance.value() == pytest.approx(cal.Tolerance.Value)
    assert page.start_button.text() == "Calibrate again"
    page.set_options(tolerance_mm=0.4)
    assert page.start()
    assert page.wait(120) == "done", page.last_error
    assert object_names(doc) == before and doc.UndoCount == undo_before + 1  # the same object, one undo step
    assert cal.Tolerance.Value == pytest.approx(0.4) and lookups.result_of(cal).tolerance_mm == pytest.approx(0.4)
    assert cal.Status == "ok" and guide.shown == "result"
    assert_pose(matrix_of(cal.W), scene.W)
    doc.undo()
    assert cal.Tolerance.Value == pytest.approx(0.3)
    guide.close()


def test_14_study_plot_in_a_dialog(step, output_dir):
    from workcal_wb.gui.commands.report import start_study

    runner = start_study("repeatability", os.path.join(str(output_dir), "study"), n=1)
    assert wait_for(lambda: runner.state != "running" and getattr(runner, "window", None) is not None
                    or runner.state in ("failed", "cancelled"), 120)
    assert runner.state == "done", runner.error
    window = runner.window
    assert window.dialog.isVisible() and not window.pixmap.isNull()
    window.dialog.grab().save(os.path.join(str(output_dir), "14_study_dialog.png"))
    window.dialog.close()


def test_15_an_ambiguous_result_shows_its_poses_and_what_would_tell_them_apart(doc, shoot_window, page_fits):
    """A symmetric workpiece (an ellipsoid): the result says AMBIGUOUS in orange, cannot be accepted, and the
    poses the match found can be stepped through in the view with the sentence on the tie."""
    from workcal_wb.core.simulate import shapes
    from workcal_wb.fc.scan import make_scan
    from workcal_wb.fc.setup import set_setup
    from workcal_wb.gui.commands.guide import open_guide

    scene = build_scene(shapes.ellipsoid(), seed=1)
    scan = Scanner.aimed_at(scene).scan(scene)
    set_setup(doc, scan=make_scan(doc, Cloud(scan.points, name="ellipsoid scan"), "Scan"),
              workpiece=add_model(doc, scene.workpiece_model(), "Ellipsoid"),
              reference=add_model(doc, scene.reference_model(), "Reference"))
    doc.recompute()
    guide = open_guide(doc, "calibrate")
    page = guide.steps["calibrate"]
    page.set_options(regions="Auto", seed=SEED, resamples=2)
    assert page.start() and page.wait(180) == "done", page.last_error
    result = guide.steps["result"]
    cal = guide.calibration()
    assert guide.shown == "result" and cal.Status == "ambiguous"
    assert result.verdict.text().startswith("AMBIGUOUS") and "#d06000" in result.verdict.styleSheet()
    assert not result.accept_button.isEnabled()
    assert guide.states()["result"][0] == "attention"
    assert result.poses.isVisible() and result.pose_label.text().startswith("Showing pose 1 of")
    assert "symmetric" in result.tie.text()
    page_fits(guide.form)
    shoot_window("15_ambiguous_pose_1")
    placed = placed_model.find(cal, "workpiece", placed_model.ON_SCAN)
    first = matrix_of(placed.Placement)
    result.next_pose.click()
    pump(0.1)
    poses = placed_model.candidate_poses(cal, "workpiece")
    assert placed.Candidate == 1 and result.pose_label.text().startswith("Showing pose 2 of")
    np.testing.assert_allclose(matrix_of(placed.Placement), poses[1] @ matrix_of(cal.Workpiece.Placement), atol=1e-6)
    assert frames.rotation_between_deg(matrix_of(placed.Placement), first) > 90  # a clearly different pose
    shoot_window("15_ambiguous_pose_2")
    result.previous_pose.click()
    assert placed.Candidate == 0
    np.testing.assert_allclose(matrix_of(placed.Placement), first, atol=1e-9)
    guide.close()


def test_16_a_loose_reference_box_shows_the_points_off_its_model_in_red(doc, view_driver, settle, shoot,
                                                                         shoot_window, page_fits):
    """The user's case: a box dragged a little loosely around the reference block takes a band of the
    platform beside it (a mat, raised past the platform's band the calibration leaves out itself).  The
    calibration fails on the share of the region its model explains, the 3D view draws the points its
    model leaves unexplained in red and larger over the region (as the result lists them), and the
    calibrate and result pages say how many, where and what to do."""
    from loose_regions import platform_band_beside_the_block
    from workcal_wb.fc import regions as fc_regions
    from workcal_wb.fc.scan import get_regions, make_scan, scan_cloud
    from workcal_wb.fc.setup import set_setup
    from workcal_wb.gui import region_display
    from workcal_wb.gui.commands.guide import open_guide
    from workcal_wb.gui.commands.regions import open_pick_panel
    from workcal_wb.gui.picking import project
    from workcal_wb.gui.view import FROM_SCANNER, look

    scene = platform_band_beside_the_block()
    scan = make_scan(doc, scene.cloud, "Scan")
    set_setup(doc, scan=scan, workpiece=add_model(doc, scene.workpiece_model, "Workpiece"),
              reference=add_model(doc, scene.reference_model, "Reference"))
    fc_regions.set_regions(scan, workpiece=scene.regions["workpiece"])
    doc.recompute()
    # The box, dragged in the view from the scanner around the block and the mat, a few pixels loose.
    view = FreeCADGui.ActiveDocument.ActiveView
    look(view, FROM_SCANNER)
    panel = open_pick_panel(scan, "box", role="reference")
    settle()
    points = scan_cloud(scan).points
    xy, valid = project(view, points[np.union1d(scene.block, scene.mat)])
    low, high = xy[valid].min(axis=0) - 4, xy[valid].max(axis=0) + 4
    view_driver.drag((int(low[0]), int(low[1])), (int(high[0]), int(high[1])))
    assert panel.last_polygon is not None, "the box did not reach the tool"
    panel.accept()
    pump(0.2)
    picked = get_regions(scan)["reference"]
    assert np.isin(scene.mat, picked).mean() > 0.9 and np.isin(scene.block, picked).mean() > 0.9

    guide = open_guide(doc, "calibrate")
    page = guide.steps["calibrate"]
    page.set_options(regions="Picked", seed=SEED, resamples=2)
    assert page.start() and page.wait(180) == "done", page.last_error
    cal = guide.calibration()
    assert cal.Status == "failed" and any(r.startswith("reference region explained by its model") for r in cal.Reasons)
    result = lookups.result_of(cal)
    off, note = result.regions["reference_off_model"], result.off_model("reference")
    assert np.isin(scene.mat, off).mean() > 0.9
    # The overlay on the scan draws exactly the result's off-model points, larger than the regions'.
    assert wait_for(lambda: "reference_off_model" in region_display.shown_points(scan), 10)
    shown = region_display.shown_points(scan)
    np.testing.assert_allclose(shown["reference_off_model"], points[off], atol=1e-3)
    assert "workpiece_off_model" not in shown and len(result.regions["workpiece_off_model"]) == 0
    sizes = region_display.shown_sizes(scan)
    assert sizes[region_display.OFF_MODEL_PART + "reference"] > scan.ViewObject.PointSize + \
        region_display.EXTRA_POINT_SIZE
    # The result page (where the guide went) and the calibrate page say how many, where and what to do.
    assert guide.shown == "result"
    words = guide.steps["result"].off_model
    assert words.isVisible() and f"holds {len(off)} points its model does not explain" in words.text()
    guide.go("calibrate")
    pump(0.1)
    text = page.off_model.text()
    assert page.off_model.isVisible() and page.correct_regions.isVisible()
    assert f"The reference object region holds {len(off)} points its model does not explain (red in the 3D view)" \
        in text
    assert note["where"] in text and f"What to do: {note['change']}." in text and "Regions step" in text
    assert "--" not in text and "Traceback" not in text
    page_fits(guide.form)
    shoot("16_off_model_points_in_red")
    shoot_window("16_calibrate_step_says_what_to_do")
    page.correct_regions.click()
    assert guide.shown == "regions"
    guide.close()
