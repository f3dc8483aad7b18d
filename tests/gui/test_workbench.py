"""Smoke test of the installed workbench in a running FreeCAD: it loads, activates, shows every command
with its icon, and the window can be captured.  A typo in InitGui.py, a command module that does not
import or a bad icon path makes one of these fail."""
import os
import re

import numpy as np
import pytest

FreeCAD = pytest.importorskip("FreeCAD")
import FreeCADGui  # noqa: E402

import workcal_wb  # noqa: E402
from workcal_wb.gui import commands  # noqa: E402
from workcal_wb.gui.task_panels import QtCore, QtGui, QtWidgets  # noqa: E402
from workcal_wb.gui.view import without_animation  # noqa: E402


def tree_icons() -> list:
    """The icon of every view provider in the registry, and the preference page's."""
    import importlib

    from workcal_wb.gui.view_providers import REGISTRY

    icons = [getattr(importlib.import_module(module), cls).ICON
             for module, cls in (target.split(":") for target in REGISTRY.values())]
    return icons + ["preferences-workcal"]


def names(entries):
    return [e for e in entries if e != commands.SEPARATOR]


def workcal_toolbar():
    bars = [b for b in FreeCADGui.getMainWindow().findChildren(QtWidgets.QToolBar) if b.objectName() == "WorkCal"]
    assert len(bars) == 1, "exactly one WorkCal toolbar"
    return bars[0]


def valid(qobject) -> bool:
    try:
        qobject.objectName()
    except RuntimeError:  # a menu of an earlier workbench activation, deleted since
        return False
    return True


def workcal_menu():
    QtCore.QCoreApplication.sendPostedEvents(None, QtCore.QEvent.DeferredDelete)
    bar = FreeCADGui.getMainWindow().menuBar()
    menus = [m for m in bar.findChildren(QtWidgets.QMenu)
             if valid(m) and m.title().replace("&", "") == "WorkCal" and m.menuAction() in bar.actions()]
    assert len(menus) == 1, "exactly one WorkCal menu"
    return menus[0]


def test_workbench_is_registered_and_activates(workbench, pump):
    assert "WorkCalWorkbench" in FreeCADGui.listWorkbenches()
    assert FreeCADGui.activateWorkbench("PointsWorkbench")
    pump(0.1)
    assert FreeCADGui.activateWorkbench("WorkCalWorkbench")
    pump(0.1)
    assert FreeCADGui.activeWorkbench().name() == "WorkCalWorkbench"
    wb = FreeCADGui.listWorkbenches()["WorkCalWorkbench"]
    # FreeCAD replaces the icon by the one package.xml names (as <addon>/./resources/...).
    assert os.path.isfile(wb.Icon) and os.path.samefile(wb.Icon, workcal_wb.icon("WorkCal"))


def test_every_module_defines_commands_and_all_are_registered(workbench):
    registered = set(FreeCADGui.listCommands())
    all_commands = commands.commands()
    assert len(all_commands) >= 6
    for name in all_commands:
        assert re.fullmatch(r"WorkCal_[A-Za-z]+", name)
        assert name in registered, f"{name} not registered with FreeCAD"
    assert names(commands.TOOLBAR) and names(commands.MENU)
    assert set(names(commands.MENU)) == set(all_commands)


def test_toolbar_shows_every_command_in_order(workbench):
    actions = [a for a in workcal_toolbar().actions()]
    shown = [a.objectName() for a in actions if not a.isSeparator()]
    assert shown == names(commands.TOOLBAR)
    menu_only = {name for module in commands.modules() if hasattr(module, "TOOLBAR")
                 for name in module.COMMANDS if name not in module.TOOLBAR}  # e.g. Preferences
    assert set(shown) == set(commands.commands()) - menu_only, "every command is on the toolbar"
    assert {"WorkCal_ImportScan", "WorkCal_ChooseModels", "WorkCal_PickBox", "WorkCal_PickLasso",
            "WorkCal_AutoRegions", "WorkCal_ClearRegions"} <= set(shown)
    for action in actions:
        if not action.isSeparator():
            assert not action.icon().isNull(), f"{action.objectName()} has no icon on the toolbar"
            assert action.text()


def test_menu_shows_every_command_in_order(workbench):
    actions = workcal_menu().actions()
    shown = [a.objectName() for a in actions if not a.isSeparator()]
    assert shown == names(commands.MENU)
    assert sum(a.isSeparator() for a in actions) == commands.MENU.count(commands.SEPARATOR)


def test_every_icon_file_exists_and_renders(workbench):
    paths = [workcal_wb.icon("WorkCal")] + [workcal_wb.icon(n) for n in tree_icons()]
    for name, command in commands.commands().items():
        resources = command.GetResources()
        assert resources["Pixmap"] == workcal_wb.icon(name), "icon named after its command"
        assert resources["MenuText"] and resources["ToolTip"]
        paths.append(resources["Pixmap"])
    for path in paths:
        assert os.path.isfile(path), f"missing icon {path}"
        image = QtGui.QIcon(path).pixmap(64, 64).toImage()
        assert not image.isNull() and image.width() >= 64, f"{path} does not render"
        colours = {image.pixel(x, y) for x in range(0, 64, 4) for y in range(0, 64, 4)}
        assert len(colours) > 3, f"{path} renders blank"


LOAD_FAILURES = [
    r"Cannot find icon: .*WorkCal",  # a bad icon path
    r"occurred in .*(WorkCal|workcal)",  # FreeCAD 0.20: 'During initialization the error ... occurred in <InitGui>'
    r"No module named '?workcal",
    r"File \".*workcal_wb.*\", line",  # a traceback through WorkCal code
]


def test_no_workcal_errors_were_reported_while_loading(load_log):
    """Start-up and the first activation printed nothing that says WorkCal failed to load."""
    text = load_log
    for pattern in LOAD_FAILURES:
        found = re.search(pattern, text)
        assert found is None, f"load problem in the Report view: {found and found.group(0)}"


def test_freecad_sees_the_activity_the_commands_report(doc):
    """FreeCAD reads IsActive() itself: a non-bool such as 1 counts as inactive (greyed out)."""
    for name, command in commands.commands().items():
        active = command.IsActive()
        assert isinstance(active, bool), f"{name}.IsActive must return a bool"
        assert FreeCADGui.Command.get(name).isActive() == active, name
    for name in ("WorkCal_ImportScan", "WorkCal_ChooseModels", "WorkCal_PickBox", "WorkCal_PickLasso"):
        assert FreeCADGui.Command.get(name).isActive(), f"{name} inactive with a document open"


def test_screenshots_of_the_main_window_and_the_3d_view(doc, shoot, output_dir, pump):
    from workcal_wb.core.geometry import Cloud
    from workcal_wb.fc.scan import make_scan, set_regions

    rng = np.random.default_rng(0)
    u, v = rng.uniform(-1, 1, (2, 20000))
    points = np.column_stack([100 * u, 60 * v, 20 * np.cos(2 * u) * np.cos(2 * v)])
    obj = make_scan(doc, Cloud(points), name="smoke scan")
    set_regions(obj, workpiece=np.flatnonzero(u < -0.3), reference=np.flatnonzero(u > 0.6))
    doc.recompute()
    view = FreeCADGui.ActiveDocument.ActiveView
    with without_animation(view):  # FreeCAD 1.x would still be turning when the picture is taken
        view.viewIsometric()
    isometric = tuple(view.getViewDirection())
    view_path = shoot("view3d", fit=True)
    pump(0.5)
    assert np.allclose(tuple(view.getViewDirection()), isometric, atol=1e-6), "the view kept turning"
    assert np.allclose(np.abs(isometric), 3 ** -0.5, atol=1e-3), "not an isometric view"
    window = FreeCADGui.getMainWindow()
    # After a task dialog closes, the tree is in front again (FreeCAD 1.x left the Tasks tab in front).
    from workcal_wb.gui.commands.guide import open_guide

    def front_tab():
        """The tab in front of the Model/Tasks pair: the combo view's (0.20) or the tabbed docks' (1.x)."""
        texts = lambda bar: [bar.tabText(i).replace("&", "") for i in range(bar.count())]  # noqa: E731
        [bar] = [b for b in window.findChildren(QtWidgets.QTabBar) if b.isVisible() and {"Model", "Tasks"} <= set(texts(b))]
        return texts(bar)[bar.currentIndex()]

    open_guide(doc)
    pump(0.2)
    assert FreeCADGui.Control.activeDialog() and front_tab() == "Tasks"
    [close] = [b for box in window.findChildren(QtWidgets.QDialogButtonBox) if box.isVisible()
               for b in [box.button(QtWidgets.QDialogButtonBox.Close)] if b is not None]
    close.click()  # as the user closes it
    pump(0.3)
    assert not FreeCADGui.Control.activeDialog() and obj.ViewObject.Visibility  # a scan to choose stays in sight
    assert front_tab() == "Model"
    pump(0.2)
    window_path = output_dir / "main_window.png"
    assert window.grab().save(str(window_path))
    for path, least in ((view_path, 3), (window_path, 10)):  # the points are drawn in flat colours
        image = QtGui.QImage(str(path))
        assert not image.isNull() and image.width() > 500
        sampled = {image.pixel(x, y) for x in range(0, image.width(), 7) for y in range(0, image.height(), 7)}
        assert len(sampled) > least, f"{path} is blank"
    # The 3D view shows the scan and both region colours (orange workpiece, blue reference).
    image = QtGui.QImage(str(view_path))
    colours = [QtGui.QColor(image.pixel(x, y)) for x in range(0, image.width(), 2) for y in range(0, image.height(), 2)]
    assert any(c.red() > 200 and 80 < c.green() < 150 and c.blue() < 60 for c in colours), "no orange region"
    assert any(c.red() < 60 and 100 < c.green() < 180 and c.blue() > 200 for c in colours), "no blue region"
