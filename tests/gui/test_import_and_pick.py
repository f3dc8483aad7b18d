"""Import a simulated scene scan, pick regions with synthetic mouse events in the real 3D view, find them
automatically, save/reopen; and bad input: a message in the Report view, the document unchanged.

Expected selections are computed independently of WorkCal's projection: every point is projected with
FreeCAD's own ``getPointOnScreen`` and tested against the box/lasso the tool actually received; points
within ``EDGE_PX`` of the outline (integer pixel rounding) are not judged.
"""
import os

import numpy as np
import pytest

FreeCAD = pytest.importorskip("FreeCAD")
import FreeCADGui  # noqa: E402
import Mesh  # noqa: E402

from workcal_wb.core.errors import InputError  # noqa: E402
from workcal_wb.core.geometry import Cloud  # noqa: E402
from workcal_wb.core.simulate.scanner import Scanner  # noqa: E402
from workcal_wb.core.simulate.scene import build_scene  # noqa: E402
from workcal_wb.core.writers import write_ply, write_xyz  # noqa: E402
from workcal_wb.fc import lookups  # noqa: E402
from workcal_wb.fc import scan as fc_scan  # noqa: E402
from workcal_wb.fc.models import add_model  # noqa: E402
from workcal_wb.fc import setup as fc_setup  # noqa: E402
from workcal_wb.gui import actions, region_display  # noqa: E402
from workcal_wb.gui.commands import regions  # noqa: E402
from workcal_wb.gui.task_panels import QtCore, QtWidgets  # noqa: E402
from workcal_wb.gui.view import look  # noqa: E402

EDGE_PX = 1.5


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    """The simulated car scene, its scan written as PLY, and the truth per point."""
    world = build_scene("car", seed=0)
    result = Scanner.aimed_at(world).scan(world)
    folder = tmp_path_factory.mktemp("scene")
    path = folder / "car_scene.ply"
    write_ply(path, result.cloud(name="car scene"))
    return {"scene": world, "result": result, "ply": path, "dir": folder,
            "workpiece": result.mask("workpiece"), "reference": result.mask("reference")}


@pytest.fixture
def scan_units():
    """The ScanUnits preference, restored after the test."""
    group = FreeCAD.ParamGet(fc_scan.PARAMS)
    before = group.GetString("ScanUnits", "")
    yield group
    if before:
        group.SetString("ScanUnits", before)
    else:
        group.RemString("ScanUnits")


@pytest.fixture
def imported(doc, scene, scan_units, pump):
    """The scene scan imported through the command's entry point, seen from the scanner."""
    scan_units.SetString("ScanUnits", "mm")
    (obj,) = actions.import_scan_files([str(scene["ply"])])
    look_from_scanner()
    pump(0.1)
    return obj


def oblique_view(*objects, angle=150):
    """``objects`` only, seen from beside the scanner (30 degrees off its axis), for screenshots with depth."""
    QtWidgets.QApplication.processEvents()
    FreeCADGui.Selection.clearSelection()
    view = FreeCADGui.ActiveDocument.ActiveView
    for obj in objects[0].Document.Objects:
        if getattr(obj, "ViewObject", None) is not None:
            obj.ViewObject.Visibility = obj in objects
    look(view, FreeCAD.Rotation(FreeCAD.Vector(1, 0, 0), angle))


def look_from_scanner():
    """Look along +Z of S (the scanner's viewing direction), the whole scan in view."""
    look(FreeCADGui.ActiveDocument.ActiveView, FreeCAD.Rotation(FreeCAD.Vector(1, 0, 0), 180))


@pytest.fixture
def open_pick_panel(settle):
    """Opens the pick panel and returns it once the 3D view has its final size (FreeCAD 1.x narrows
    the view after the panel opens, which moves every point on the screen).  "Visible points only" is
    off unless asked for: these tests check the projection of every point."""

    def open_panel(obj, visible_only=False, **options):
        panel = regions.open_pick_panel(obj, **options)
        panel.visible_box.setChecked(visible_only)
        settle()
        return panel

    yield open_panel
    from workcal_wb.fc import prefs

    prefs.set("PickVisibleOnly", 1)  # the default, whatever a test clicked



def screen_xy(points) -> np.ndarray:
    """Every point projected with FreeCAD's own getPointOnScreen (Coin pixels) as the view is now."""
    view = FreeCADGui.ActiveDocument.ActiveView
    return np.array([view.getPointOnScreen(FreeCAD.Vector(*p)) for p in np.asarray(points).tolist()], dtype=float)


def edge_distance(xy, polygon) -> np.ndarray:
    """Distance of each position to the closed outline."""
    polygon = np.asarray(polygon, dtype=float)
    a, b = polygon, np.roll(polygon, -1, axis=0)
    best = np.full(len(xy), np.inf)
    for p, q in zip(a, b):
        d = q - p
        t = np.clip(((xy - p) @ d) / max(d @ d, 1e-12), 0, 1)
        best = np.minimum(best, np.linalg.norm(xy - (p + t[:, None] * d), axis=1))
    return best


def inside(xy, polygon) -> np.ndarray:
    from matplotlib.path import Path

    return Path(np.asarray(polygon, dtype=float)).contains_points(xy)


def assert_selection(picked, xy, polygon):
    """``picked`` (indices) holds every point inside ``polygon`` and none outside, edges excepted."""
    expected = inside(xy, polygon)
    judged = edge_distance(xy, polygon) > EDGE_PX
    got = np.zeros(len(xy), bool)
    got[picked] = True
    wrong = np.flatnonzero(judged & (got != expected))
    assert len(wrong) == 0, f"{len(wrong)} points picked wrongly, e.g. {wrong[:5]} at {xy[wrong[:5]]}"
    assert expected[judged].sum() > 100


def workpiece_box(xy, mask, low=30, high=70):
    """A box (Coin pixels) over the middle of the workpiece as the camera sees it."""
    x0, y0 = np.percentile(xy[mask], low, axis=0)
    x1, y1 = np.percentile(xy[mask], high, axis=0)
    return (int(x0), int(y0)), (int(x1), int(y1))


def regions_now(obj):
    found = fc_scan.get_regions(obj)
    return {r: (set() if found[r] is None else set(found[r].tolist())) for r in ("workpiece", "reference")}


def shown_matches_regions(obj):
    """The highlight in the scene graph shows exactly the region points (in kernel coordinates)."""
    shown = region_display.shown_points(obj)
    points = fc_scan.scan_cloud(obj).points
    for role, idx in fc_scan.get_regions(obj).items():
        if role == "source":
            continue
        if idx is None:
            assert role not in shown
        else:
            np.testing.assert_allclose(shown[role], points[idx], atol=1e-3)


def doc_state(doc):
    return ([o.Name for o in doc.Objects], doc.UndoCount, fc_setup.get_setup(doc))


# --- import -----------------------------------------------------------------------------------

def test_import_scan_makes_one_undoable_scan_object(doc, scene, scan_units, shoot, report):
    scan_units.SetString("ScanUnits", "m")  # ignored: this PLY declares its unit (mm)
    (obj,) = actions.import_scan_files([str(scene["ply"])])
    points = scene["result"].points
    assert lookups.is_scan(obj) and obj.Label == "car_scene.ply" and obj.Units == "mm"
    assert obj.Points.CountPoints == len(points) == obj.PointCount
    np.testing.assert_allclose(fc_scan.scan_cloud(obj).points, points, atol=2e-4)
    assert obj.ViewObject.Proxy.__class__.__name__ == "ViewProviderScan"
    assert fc_setup.get_setup(doc)["scan"] is obj
    assert "imported car_scene.ply" in report.since()
    assert doc.UndoNames[0] == "Import scan"
    look_from_scanner()
    shoot("01_imported")
    name = obj.Name
    doc.undo()
    assert doc.getObject(name) is None and fc_setup.get_setup(doc)["scan"] is None
    doc.redo()
    assert lookups.is_scan(doc.getObject(name)) and fc_setup.get_setup(doc)["scan"] is doc.getObject(name)


def test_units_are_asked_once_and_remembered(doc, scene, scan_units, pump):
    scan_units.RemString("ScanUnits")
    path = scene["dir"] / "in_metres.xyz"
    write_xyz(path, Cloud(np.array([[0.0, 0.0, 1.0], [0.1, 0.2, 1.3], [0.05, -0.1, 1.2]]) * 1000.0), units="m")
    answered = []

    def answer():
        dialog = QtWidgets.QApplication.activeModalWidget()
        if isinstance(dialog, QtWidgets.QInputDialog):
            dialog.setTextValue("m")
            answered.append(dialog.labelText())
            dialog.accept()
        elif dialog is not None:
            dialog.reject()
        else:
            QtCore.QTimer.singleShot(50, answer)

    QtCore.QTimer.singleShot(50, answer)
    (obj,) = actions.import_scan_files([str(path)])
    assert answered and "unit" in answered[0]
    assert scan_units.GetString("ScanUnits", "") == "m" and obj.Units == "m"
    np.testing.assert_allclose(fc_scan.scan_cloud(obj).points[1], [100, 200, 1300], atol=1e-3)
    # Asked once: the next import uses the remembered unit without a dialog (a dialog would block here,
    # so a guard timer rejects any and the import would then be cancelled).
    guard = QtCore.QTimer()
    guard.timeout.connect(lambda: QtWidgets.QApplication.activeModalWidget() and
                          QtWidgets.QApplication.activeModalWidget().reject())
    guard.start(200)
    try:
        (again,) = actions.import_scan_files([str(path)])
    finally:
        guard.stop()
    assert again.Units == "m"


# --- picking ----------------------------------------------------------------------------------

def test_box_pick_selects_the_points_in_the_box(open_pick_panel, imported, scene, view_driver, shoot, pump,
                                                assert_ok_cancel, page_fits):
    panel = open_pick_panel(imported, shape="box")
    assert_ok_cancel(panel)
    page_fits(panel.form)
    xy = screen_xy(fc_scan.scan_cloud(imported).points)
    start, end = workpiece_box(xy, scene["workpiece"])
    assert FreeCADGui.Control.activeDialog() and panel.tool.active
    camera_before = FreeCADGui.ActiveDocument.ActiveView.getCameraNode().orientation.getValue().getValue()
    FreeCADGui.Selection.clearSelection()
    view_driver.drag(start, end)
    assert panel.last_polygon is not None, "the box did not reach the tool"
    assert all(abs(a - b) <= 2 for a, b in zip(panel.last_polygon[0], start))
    assert all(abs(a - b) <= 2 for a, b in zip(panel.last_polygon[2], end))
    picked = fc_scan.get_regions(imported)["workpiece"]
    assert_selection(picked, xy, panel.last_polygon)
    truth = scene["workpiece"][picked]
    assert truth.mean() > 0.95, f"only {truth.mean():.0%} of the box is workpiece"
    assert FreeCADGui.ActiveDocument.ActiveView.getCameraNode().orientation.getValue().getValue() == camera_before
    assert FreeCADGui.Selection.getSelection() == [], "the clicks reached FreeCAD's selection"
    shown_matches_regions(imported)
    shoot("02_box_picked")
    panel.accept()
    assert not FreeCADGui.Control.activeDialog() and not panel.tool.active
    view_driver.click(*start)  # the tool is gone: FreeCAD selects the scan again
    assert FreeCADGui.Selection.getSelection() == [imported]


def test_visible_points_only_leaves_the_platform_behind_the_part(open_pick_panel, imported, scene, view_driver,
                                                                 shoot):
    """Seen from the far side of the platform, a box over the car covers the platform behind it too: with
    "Visible points only" the pick is the car's points, without it it takes the hidden platform as well."""
    picked = {}
    for visible_only in (False, True):
        oblique_view(imported, angle=210)
        panel = open_pick_panel(imported, shape="box", visible_only=visible_only)
        xy = screen_xy(fc_scan.scan_cloud(imported).points)
        start, end = workpiece_box(xy, scene["workpiece"], 20, 80)
        view_driver.drag(start, end)
        picked[visible_only] = fc_scan.get_regions(imported)["workpiece"]
        if visible_only:
            shoot("11_visible_points_only")
        panel.reject()
    through, visible = (scene["workpiece"][picked[v]].mean() for v in (False, True))
    assert through < 0.7, f"the view does not show the platform behind the car ({through:.0%} workpiece)"
    assert visible > 0.9, f"only {visible:.0%} of the visible pick is workpiece"
    assert np.isin(picked[True], picked[False]).all()


def lasso_corners(start, end):
    (x0, y0), (x1, y1) = start, end
    cx, cy, rx, ry = (x0 + x1) / 2, (y0 + y1) / 2, (x1 - x0) / 2, (y1 - y0) / 2
    angles = np.radians([90, 150, 200, 260, 330, 20])
    return [(int(cx + rx * np.cos(a)), int(cy + ry * np.sin(a))) for a in angles]


def test_lasso_pick_closed_by_right_click_and_by_enter(open_pick_panel, imported, scene, view_driver, shoot):
    panel = open_pick_panel(imported, shape="lasso")
    xy = screen_xy(fc_scan.scan_cloud(imported).points)
    start, end = workpiece_box(xy, scene["workpiece"], 15, 85)
    corners = lasso_corners(start, end)
    for corner in corners:
        view_driver.click(*corner)
    assert len(panel.tool.corners) == len(corners)
    view_driver.move(*corners[0])
    shoot("03_lasso_drawing")
    view_driver.click(*corners[0], button=QtCore.Qt.RightButton)
    assert panel.tool.corners == [] and len(panel.last_polygon) == len(corners)
    picked = fc_scan.get_regions(imported)["workpiece"]
    assert_selection(picked, xy, panel.last_polygon)
    assert scene["workpiece"][picked].mean() > 0.9
    shoot("04_lasso_picked")
    # The reference object with Enter closing the lasso; the workpiece region stays.
    xs, ys = workpiece_box(xy, scene["reference"], 20, 80)
    panel.set_role("reference")
    for corner in lasso_corners(xs, ys)[:5]:
        view_driver.click(*corner)
    view_driver.key(QtCore.Qt.Key_Return)
    found = fc_scan.get_regions(imported)
    assert_selection(found["reference"], xy, panel.last_polygon)
    assert scene["reference"][found["reference"]].mean() > 0.9
    np.testing.assert_array_equal(found["workpiece"], picked)
    shown_matches_regions(imported)
    shoot("05_lasso_reference")
    panel.accept()


def test_add_subtract_and_one_point_one_region(open_pick_panel, imported, scene, view_driver, shoot):
    panel = open_pick_panel(imported, shape="box")
    xy = screen_xy(fc_scan.scan_cloud(imported).points)
    (x0, y0), (x1, y1) = workpiece_box(xy, scene["workpiece"], 10, 90)
    xm = (x0 + x1) // 2
    view_driver.drag((x0, y0), (xm, y1))
    left = regions_now(imported)["workpiece"]
    view_driver.drag((xm, y0), (x1, y1), modifiers=QtCore.Qt.ShiftModifier)  # Shift: add
    right = set(np.flatnonzero(inside(xy, panel.last_polygon) & (edge_distance(xy, panel.last_polygon) > EDGE_PX)))
    both = regions_now(imported)["workpiece"]
    assert both >= left and both >= right and len(both) > len(left)
    shoot("06_added")
    yc = (y0 + y1) // 2
    view_driver.drag((x0, y0), (x1, yc), modifiers=QtCore.Qt.ControlModifier)  # Ctrl: subtract
    removed = inside(xy, panel.last_polygon) & (edge_distance(xy, panel.last_polygon) > EDGE_PX)
    after = regions_now(imported)["workpiece"]
    assert after <= both and not (after & set(np.flatnonzero(removed)))
    assert len(after) < len(both)
    shoot("07_subtracted")
    # Mode buttons instead of modifiers: the same box as reference takes the points from the workpiece.
    panel.set_role("reference")
    panel.set_mode("replace")
    view_driver.drag((x0, yc), (xm, y1))
    now = regions_now(imported)
    assert now["reference"] and not (now["reference"] & now["workpiece"])
    assert now["workpiece"] == after - now["reference"]
    shown_matches_regions(imported)
    shoot("08_reference_taken")
    panel.undo_pick()
    assert regions_now(imported)["workpiece"] == after and not regions_now(imported)["reference"]
    panel.accept()


def test_cancel_restores_and_ok_is_one_undo_step(open_pick_panel, imported, scene, view_driver):
    doc = imported.Document
    undo_before = doc.UndoCount
    panel = open_pick_panel(imported)
    xy = screen_xy(fc_scan.scan_cloud(imported).points)
    start, end = workpiece_box(xy, scene["workpiece"])
    view_driver.drag(start, end)
    view_driver.drag(start, (end[0], (start[1] + end[1]) // 2), modifiers=QtCore.Qt.ControlModifier)
    assert regions_now(imported)["workpiece"]
    panel.reject()
    assert regions_now(imported) == {"workpiece": set(), "reference": set()}
    assert doc.UndoCount == undo_before and region_display.shown_points(imported) == {}
    panel = open_pick_panel(imported)
    view_driver.drag(start, end)
    view_driver.drag(start, (end[0], (start[1] + end[1]) // 2), modifiers=QtCore.Qt.ShiftModifier)
    picked = regions_now(imported)["workpiece"]
    panel.accept()
    assert doc.UndoCount == undo_before + 1 and doc.UndoNames[0] == "Pick scan regions"
    doc.undo()
    assert regions_now(imported)["workpiece"] == set()
    doc.redo()
    assert regions_now(imported)["workpiece"] == picked


def test_regions_survive_save_and_reopen(open_pick_panel, imported, scene, view_driver, output_dir, shoot, pump):
    panel = open_pick_panel(imported)
    xy = screen_xy(fc_scan.scan_cloud(imported).points)
    start, end = workpiece_box(xy, scene["workpiece"])
    view_driver.drag(start, end)
    panel.set_role("reference")
    rs, re_ = workpiece_box(xy, scene["reference"])
    view_driver.drag(rs, re_)
    panel.accept()
    before = fc_scan.get_regions(imported)
    name, path = imported.Name, str(output_dir / "picked.FCStd")
    imported.Document.saveAs(path)
    FreeCAD.closeDocument(imported.Document.Name)
    pump(0.1)
    reopened = FreeCAD.openDocument(path)
    pump(0.2)  # the overlay is rebuilt once the event loop runs
    obj = reopened.getObject(name)
    after = fc_scan.get_regions(obj)
    for role in ("workpiece", "reference"):
        np.testing.assert_array_equal(after[role], before[role])
    assert after["source"] == "user" and fc_setup.get_setup(reopened)["scan"] is obj
    assert obj.ViewObject.Proxy.__class__.__name__ == "ViewProviderScan"
    shown_matches_regions(obj)
    oblique_view(obj)
    shoot("09_reopened")


# --- automatic regions and models --------------------------------------------------------------

def test_choose_models_and_automatic_regions(imported, scene, shoot, report, output_dir, pump, page_fits):
    from workcal_wb.gui.commands.guide import open_guide

    doc = imported.Document
    workpiece = add_model(doc, scene["scene"].workpiece_model(), "CarModel")
    reference = add_model(doc, scene["scene"].reference_model(), "ReferenceModel")
    doc.recompute()
    FreeCADGui.runCommand("WorkCal_ChooseModels")  # the guide, at its models step
    guide = open_guide(doc)
    assert guide.shown == "models" and fc_setup.get_setup(doc)["scan"] is imported  # the import made it the scan
    page = guide.steps["models"]
    assert [page.combos["workpiece"].itemText(i) for i in range(page.combos["workpiece"].count())] == \
        ["CarModel", "ReferenceModel"]  # models only: neither the scan nor WorkCal's own objects
    undo_before = doc.UndoCount
    page.select("workpiece", workpiece)
    page.select("reference", reference)
    assert fc_setup.get_setup(doc) == {"scan": imported, "workpiece": workpiece, "reference": reference}
    assert doc.UndoCount == undo_before + 2 and doc.UndoNames[0] == "Choose models"
    page_fits(guide.form)
    guide.close()

    def progress_shown():
        return any(w.objectName() == "WorkCalProgress" and w.isVisible()
                   for w in QtWidgets.QApplication.topLevelWidgets())

    seen = []  # while the regions are searched, the window keeps running and shows a progress dialog
    watcher = QtCore.QTimer()
    watcher.timeout.connect(lambda: seen.append(progress_shown()))
    watcher.start(100)
    try:
        found = regions.auto_regions()
    finally:
        watcher.stop()
    assert len(seen) >= 5 and any(seen), "no progress dialog while finding the regions"
    assert not progress_shown()
    got = fc_scan.get_regions(imported)
    assert got["source"] == "auto"
    for role in ("workpiece", "reference"):
        truth = scene[role]
        precision = truth[got[role]].mean()
        recall = np.isin(np.flatnonzero(truth), got[role]).mean()
        assert precision > 0.98 and recall > 0.95, (role, precision, recall)
        np.testing.assert_array_equal(np.sort(found[role]), got[role])
    assert "regions of car_scene.ply found" in report.since()
    shown_matches_regions(imported)
    oblique_view(imported)
    shoot("10_auto_regions")
    assert regions.clear_regions()
    assert fc_scan.get_regions(imported)["workpiece"] is None and region_display.shown_points(imported) == {}
    doc.undo()
    assert fc_scan.get_regions(imported)["source"] == "auto"


def test_models_from_files_are_chosen_and_undone(doc, tmp_path, scan_units):
    import Part

    from workcal_wb.gui.commands.guide import open_guide

    scan_units.SetString("ScanUnits", "mm")
    Part.makeBox(30, 20, 10).exportStep(str(tmp_path / "block.step"))
    names_before = [o.Name for o in doc.Objects]
    page = open_guide(doc, "models").steps["models"]
    obj = page.load_file("reference", tmp_path / "block.step")
    assert fc_setup.get_setup(doc)["reference"] is obj and obj.TypeId == "Part::Feature"
    assert page.combos["reference"].currentText() == "block.step"
    assert doc.UndoNames[:2] == ["Choose models", "Import model"]
    doc.undo()
    doc.undo()
    assert [o.Name for o in doc.Objects if o.Name != "WorkCalSetup"] == names_before
    assert fc_setup.get_setup(doc)["reference"] is None


# --- bad input: a message, the document unchanged -------------------------------------------------

def test_pick_without_a_scan_reports_and_changes_nothing(doc, report):
    doc.addObject("Part::Box", "Box")
    doc.recompute()
    state = doc_state(doc)
    FreeCADGui.Selection.addSelection(doc.Box)
    FreeCADGui.runCommand("WorkCal_PickBox")
    assert "no scan in" in report.since()
    assert not FreeCADGui.Control.activeDialog() and doc_state(doc) == state
    FreeCADGui.runCommand("WorkCal_ClearRegions")
    FreeCADGui.runCommand("WorkCal_AutoRegions")
    assert report.since().count("no scan in") == 3 and doc_state(doc) == state


def test_empty_scan_reports_and_changes_nothing(doc, report):
    empty = doc.addObject("Points::Feature", "EmptyCloud")
    doc.recompute()
    state = doc_state(doc)
    FreeCADGui.Selection.addSelection(empty)
    FreeCADGui.runCommand("WorkCal_PickLasso")
    assert "'EmptyCloud': contains no points" in report.since()
    assert not FreeCADGui.Control.activeDialog() and doc_state(doc) == state
    with pytest.raises(InputError, match="contains no points"):
        regions.open_pick_panel(empty)
    assert not FreeCADGui.Control.activeDialog()


def test_auto_regions_without_models_reports_and_changes_nothing(imported, report):
    doc = imported.Document
    state = doc_state(doc)
    FreeCADGui.runCommand("WorkCal_AutoRegions")
    assert "automatic regions need the workpiece model and the reference model" in report.since()
    assert doc_state(doc) == state and not fc_scan.has_regions(imported)


def test_auto_regions_with_the_wrong_model_names_it(imported, scene, report):
    doc = imported.Document
    ball = doc.addObject("Mesh::Feature", "Ball")
    ball.Mesh = Mesh.createSphere(60, 20)
    wrong = doc.addObject("Mesh::Feature", "NotTheReference")
    wrong.Mesh = Mesh.createCylinder(5, 400, True, 1.0, 24)
    doc.recompute()
    actions.choose_models(doc, workpiece=ball, reference=wrong)
    state = doc_state(doc)
    FreeCADGui.runCommand("WorkCal_AutoRegions")
    text = report.since()
    assert "NotTheReference" in text and "not found" in text
    assert doc_state(doc) == state and not fc_scan.has_regions(imported)


def test_non_shape_model_reports_and_changes_nothing(imported, report, pump):
    from workcal_wb.gui.commands.guide import open_guide

    doc = imported.Document
    sheet = doc.addObject("Spreadsheet::Sheet", "Notes")
    box = doc.addObject("Part::Box", "Block")
    doc.recompute()
    state = doc_state(doc)
    with pytest.raises(InputError, match=r"'Notes' \(Spreadsheet::Sheet\) is not a Part shape, mesh or point cloud"):
        actions.choose_models(doc, workpiece=sheet)
    assert doc_state(doc) == state
    guide = open_guide(doc, "models")
    page = guide.steps["models"]
    assert page.combos["workpiece"].findData("Notes") < 0, "a spreadsheet is not offered as a model"
    page.select("workpiece", box)
    report.mark()
    page.run_guarded("Choose models", lambda: page.select("reference", box))
    assert "cannot be both the workpiece and the reference model" in report.since()
    assert guide.alive() and fc_setup.get_setup(doc)["reference"] is None  # refused, the guide still open
    guide.close()


def test_bad_scan_file_reports_and_changes_nothing(doc, tmp_path, report, scan_units):
    from workcal_wb.gui.task_panels.common import guarded

    scan_units.SetString("ScanUnits", "mm")
    bad = tmp_path / "broken.ply"
    bad.write_bytes(b"ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nend_header\n1\n2\n")
    state = doc_state(doc)
    with pytest.raises(InputError, match="broken.ply"):
        actions.import_scan_files([str(bad)])
    guarded("Import scan")(actions.import_scan_files)([str(bad)])  # as the command runs it
    assert report.since().count("broken.ply") >= 1
    assert doc_state(doc) == state
    assert not any(isinstance(w, QtWidgets.QProgressDialog) and w.isVisible()
                   for w in QtWidgets.QApplication.topLevelWidgets())
    assert os.path.exists(bad)


def test_task_dialog_closed_from_outside_stops_the_tool_and_rolls_back(open_pick_panel, imported, scene, view_driver,
                                                                     pump):
    undo_before = imported.Document.UndoCount
    panel = open_pick_panel(imported)
    xy = screen_xy(fc_scan.scan_cloud(imported).points)
    start, end = workpiece_box(xy, scene["workpiece"])
    view_driver.drag(start, end)
    assert regions_now(imported)["workpiece"]
    FreeCADGui.Control.closeDialog()  # neither OK nor Cancel
    pump(0.1)
    view_driver.move(*start)  # the next event finds the panel gone
    assert not panel.tool.active
    assert regions_now(imported)["workpiece"] == set() and imported.Document.UndoCount == undo_before
    FreeCADGui.Selection.clearSelection()
    view_driver.click(*start)  # clicks reach FreeCAD again
    assert FreeCADGui.Selection.getSelection() == [imported]
