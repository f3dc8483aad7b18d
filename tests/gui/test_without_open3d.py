"""On a FreeCAD whose Python has no open3d the workbench still loads, activates and shows every command;
a command that needs open3d says what to install (python3-open3d), changes nothing and FreeCAD runs on.

open3d is made unimportable for each test here (``sys.modules["open3d"] = None``: Python then refuses
``import open3d`` as if it were not installed) and restored afterwards.
"""
import importlib
import pkgutil
import sys
import time

import pytest

FreeCAD = pytest.importorskip("FreeCAD")
if not FreeCAD.GuiUp:
    pytest.skip("needs the FreeCAD GUI (run tests/gui/run_gui_tests.py under xvfb-run freecad)",
                allow_module_level=True)

import FreeCADGui  # noqa: E402

from workcal_wb.core.errors import MissingDependency  # noqa: E402
from workcal_wb.core.geometry import Cloud  # noqa: E402
from workcal_wb.gui import commands  # noqa: E402
from workcal_wb.gui.task_panels import QtCore, QtWidgets, common  # noqa: E402

INSTALL = "python3-open3d"  # what the message tells the user to install
PACKAGES = ("workcal_wb.core", "workcal_wb.fc", "workcal_wb.gui")


@pytest.fixture
def without_open3d(monkeypatch):
    monkeypatch.setitem(sys.modules, "open3d", None)
    with pytest.raises(ImportError):
        import open3d  # noqa: F401


@pytest.fixture(scope="module")
def scene():
    """A small simulated scene: every fourth point of its scan and the two models as points (Points
    objects): their normals need open3d (a meshed model does not: its faces give them)."""
    from workcal_wb.core.simulate.scanner import Scanner
    from workcal_wb.core.simulate.scene import build_scene

    world = build_scene("car", seed=0)
    scan = Scanner.aimed_at(world).scan(world)
    workpiece, reference = (Cloud(model.points, name=model.name)
                            for model in (world.workpiece_model(), world.reference_model()))
    return Cloud(scan.points[::4], name="scene scan"), workpiece, reference


@pytest.fixture
def setup_doc(doc, scene):
    """``doc`` holding the scene's scan and models, chosen as its WorkCal setup."""
    from workcal_wb.fc.models import add_model
    from workcal_wb.fc.scan import make_scan
    from workcal_wb.fc.setup import set_setup

    scan, workpiece, reference = scene
    set_setup(doc, scan=make_scan(doc, scan, "Scan"), workpiece=add_model(doc, workpiece, "Workpiece"),
              reference=add_model(doc, reference, "Reference"))
    doc.recompute()
    return doc


def state(doc):
    """What a command must leave as it was: objects, undo steps and the scan's regions."""
    from workcal_wb.fc import scan as fc_scan
    from workcal_wb.fc.setup import get_setup

    return [o.Name for o in doc.Objects], doc.UndoCount, fc_scan.has_regions(get_setup(doc)["scan"])


def workcal_modules() -> dict:
    return {name: module for name, module in sys.modules.items() if name.split(".")[0] == "workcal_wb"}


def test_every_module_imports_without_open3d(without_open3d, monkeypatch):
    """WorkCal's modules are imported again while open3d is missing: none needs it to load, and the
    workbench module registers a workbench whose commands are all there.  FreeCAD's registration
    calls are stubbed meanwhile (the session keeps one of each) and the loaded modules come back."""
    loaded = workcal_modules()
    expected = list(commands.commands())
    workbenches = []
    monkeypatch.setattr(FreeCAD, "addImportType", lambda *args: None)
    monkeypatch.setattr(FreeCADGui, "addWorkbench", workbenches.append)
    monkeypatch.setattr(FreeCADGui, "addPreferencePage", lambda *args: None)
    for name in loaded:
        del sys.modules[name]
    try:
        importlib.import_module("workcal_wb.gui.workbench")
        fresh = importlib.import_module("workcal_wb.gui.commands")
        assert list(fresh.commands()) == expected
        for command in fresh.commands().values():
            assert command.GetResources()["MenuText"] and isinstance(command.IsActive(), bool)
        for package in PACKAGES:
            path = importlib.import_module(package).__path__
            for found in pkgutil.walk_packages(path, package + "."):
                importlib.import_module(found.name)
    finally:
        for name in workcal_modules():
            del sys.modules[name]
        sys.modules.update(loaded)
    assert [type(wb).__name__ for wb in workbenches] == ["WorkCalWorkbench"]


def test_workbench_activates_with_every_command(without_open3d, workbench, pump):
    assert FreeCADGui.activateWorkbench("PointsWorkbench")
    pump(0.1)
    assert FreeCADGui.activateWorkbench("WorkCalWorkbench")
    pump(0.1)
    assert FreeCADGui.activeWorkbench().name() == "WorkCalWorkbench"
    registered = set(FreeCADGui.listCommands())
    assert set(commands.commands()) <= registered


def test_calibrate_entry_point_says_what_to_install(without_open3d, setup_doc):
    from workcal_wb.fc.calibration_object import make_calibration

    before = state(setup_doc)
    with pytest.raises(MissingDependency, match=INSTALL):
        make_calibration(setup_doc, regions="Auto")
    assert state(setup_doc) == before


def test_calibrate_command_shows_it_in_the_guide_and_report_view(without_open3d, setup_doc, report):
    from workcal_wb.gui.task_panels.guide import GuidePanel

    before = state(setup_doc)
    FreeCADGui.runCommand("WorkCal_Calibrate")
    guide = GuidePanel.current
    assert guide is not None and guide.doc.Name == setup_doc.Name and FreeCADGui.Control.activeDialog()
    assert guide.shown == "calibrate"
    page = guide.steps["calibrate"]
    page.set_options(regions="Auto", seed=0)
    assert page.start()
    assert page.wait(60) == "failed"
    assert INSTALL in page.last_error and INSTALL in page.message.text()
    text = report.since()
    assert INSTALL in text and "Traceback" not in text
    assert FreeCADGui.Control.activeDialog() and guide.shown == "calibrate"  # open, so the user reads why
    assert guide.reject()
    assert not FreeCADGui.Control.activeDialog()
    assert state(setup_doc) == before


def test_auto_regions_command_shows_it_in_a_message_box(without_open3d, setup_doc, report, monkeypatch, pump):
    """Interactively the message also comes in a box (closed here from a timer once it shows)."""
    monkeypatch.setattr(common, "INTERACTIVE", True)
    before = state(setup_doc)
    boxes = []
    deadline = time.monotonic() + 60

    def read_and_close_the_box():
        box = QtWidgets.QApplication.activeModalWidget()
        if isinstance(box, QtWidgets.QMessageBox):
            boxes.append((box.windowTitle(), box.text()))
            box.accept()
        elif time.monotonic() < deadline:
            QtCore.QTimer.singleShot(50, read_and_close_the_box)

    QtCore.QTimer.singleShot(50, read_and_close_the_box)
    FreeCADGui.runCommand("WorkCal_AutoRegions")  # returns once the box is closed
    pump(0.1)
    assert len(boxes) == 1, "no message box"
    title, text = boxes[0]
    assert title == "Find regions automatically" and INSTALL in text
    logged = report.since()
    assert INSTALL in logged and "Traceback" not in logged
    assert state(setup_doc) == before
    assert FreeCADGui.getMainWindow().isVisible() and FreeCAD.ActiveDocument.Name == setup_doc.Name
