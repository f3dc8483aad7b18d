"""Scan regions: pick them (box, lasso), find them automatically, clear them.

The scan a command works on: the selected WorkCal scan, else the document's setup scan, else a
selected point cloud or mesh, else the only WorkCal scan in the document.  ``open_pick_panel``,
``auto_regions`` and ``clear_regions`` are the commands without their dialogs; every document change
is a recorded ``workcal_wb.fc.regions`` call (replayable in a macro).
"""
from __future__ import annotations

import FreeCAD

from workcal_wb.core.errors import InputError, WorkCalError
from workcal_wb.gui import replay
from workcal_wb.gui.task_panels.common import Command, active_document, refuse_second_panel, selected_objects

QT_TRANSLATE_NOOP = FreeCAD.Qt.QT_TRANSLATE_NOOP
translate = FreeCAD.Qt.translate


def target_scan(doc=None):
    """The scan the user means (see the module doc); InputError when there is none."""
    from workcal_wb.fc import lookups
    from workcal_wb.fc.setup import get_setup

    doc = doc or active_document()
    selected = [o for o in selected_objects() if o.Document is doc]
    for obj in selected:
        if lookups.is_scan(obj):
            return obj
    chosen = get_setup(doc)["scan"]
    if chosen is not None:
        return chosen
    for obj in selected:
        if lookups.can_be_scan(obj):
            return obj
    scans = [o for o in doc.Objects if lookups.is_scan(o)]
    if len(scans) == 1:
        return scans[0]
    if scans:
        raise InputError(translate("WorkCal", "{} scans in {}: select the one to use").format(len(scans), doc.Label))
    raise InputError(translate("WorkCal", "no scan in {}: import one first (WorkCal > Import scan) or select a "
                                          "point cloud or mesh").format(doc.Label))


# --- picking -------------------------------------------------------------------------------------

def open_pick_panel(scan=None, shape: str = "box", role: str = "workpiece", on_close=None):
    """Open the picking task panel on ``scan`` (or switch the open one to ``shape``); returns the panel.
    ``on_close()`` runs after the panel closed (later, from the event loop)."""
    import FreeCADGui

    from workcal_wb.gui.picking import PickPanel
    from workcal_wb.gui.task_panels import QtCore

    current = _open_pick_panel()
    if current is not None:
        current.set_shape(shape)
        return current
    refuse_second_panel()
    scan = scan or target_scan()
    gui_doc = FreeCADGui.getDocument(scan.Document.Name)
    view = gui_doc.ActiveView if gui_doc is not None else None
    if view is None or not hasattr(view, "addEventCallbackPivy"):
        raise WorkCalError(translate("WorkCal", "picking needs the 3D view of {}: activate it first").format(
            scan.Document.Label))
    later = (lambda: QtCore.QTimer.singleShot(0, on_close)) if on_close is not None else None
    panel = PickPanel(scan, view, shape, role, on_close=later)
    _PANELS.append(panel)
    FreeCADGui.Control.showDialog(panel)
    return panel


_PANELS = []  # the pick panel shown (task dialogs keep no Python-visible reference to it)


def _open_pick_panel():
    import FreeCADGui

    live = [p for p in _PANELS if p.tool.active]
    _PANELS[:] = live
    if live and FreeCADGui.Control.activeDialog():
        return live[-1]
    return None


class PickCommand(Command):
    SHAPE, NAME, TITLE = "box", "WorkCal_PickBox", "Pick region"
    MENU_TEXT = QT_TRANSLATE_NOOP("WorkCal_PickBox", "Pick region (box)")
    TOOL_TIP = QT_TRANSLATE_NOOP("WorkCal_PickBox", "Pick the workpiece or the reference region of the scan by "
                                                    "dragging boxes in the 3D view (Shift adds, Ctrl subtracts)")

    def IsActive(self):
        return super().IsActive() and bool(FreeCAD.GuiUp)

    def run(self):
        open_pick_panel(shape=self.SHAPE)


class PickLassoCommand(PickCommand):
    SHAPE, NAME = "lasso", "WorkCal_PickLasso"
    MENU_TEXT = QT_TRANSLATE_NOOP("WorkCal_PickLasso", "Pick region (lasso)")
    TOOL_TIP = QT_TRANSLATE_NOOP("WorkCal_PickLasso", "Pick the workpiece or the reference region of the scan by "
                                                      "drawing polygons in the 3D view; right-click or Enter closes")


# --- automatic regions ---------------------------------------------------------------------------

def auto_regions(scan=None, workpiece=None, reference=None) -> dict:
    """Find the workpiece and reference regions with the models of the setup (in a worker thread, with
    a progress dialog) and store them (recorded ``fc.regions.auto_regions``, one undo step); returns
    what was found.  InputError says what is missing or which object was not found; the document is
    then unchanged."""
    from workcal_wb.fc import regions as fc_regions
    from workcal_wb.gui.progress import run_in_background

    scan = scan or target_scan()
    clouds = fc_regions.regions_inputs(scan, workpiece, reference)
    run_in_background(lambda: fc_regions.find_regions(clouds, blas_threads=None),
                      translate("WorkCal", "Finding the workpiece and the reference in {}...").format(scan.Label),
                      translate("WorkCal", "Automatic regions"))
    found = replay.run("workcal_wb.fc.regions.auto_regions", scan, workpiece, reference, result="regions")
    _update_display(scan)
    return found


def clear_regions(scan=None) -> bool:
    """Remove both regions of the scan (recorded, one undo step); False (and a warning) when there were none."""
    scan = scan or target_scan()
    cleared = replay.run("workcal_wb.fc.regions.clear_regions", scan, result="cleared")
    _update_display(scan)
    return cleared


def _update_display(scan) -> None:
    """The region colours at once (the view provider's own update waits for the event loop)."""
    from workcal_wb.gui import region_display

    region_display.update(scan)


class AutoRegionsCommand(Command):
    NAME, TITLE = "WorkCal_AutoRegions", "Find regions automatically"
    MENU_TEXT = QT_TRANSLATE_NOOP("WorkCal_AutoRegions", "Find regions automatically")
    TOOL_TIP = QT_TRANSLATE_NOOP("WorkCal_AutoRegions", "Find the workpiece and the reference object in the scan with "
                                                        "their models (removes the platform, splits the objects and "
                                                        "matches them); correct the result with the pick tools")

    def run(self):
        auto_regions()


class ClearRegionsCommand(Command):
    NAME, TITLE = "WorkCal_ClearRegions", "Clear regions"
    MENU_TEXT = QT_TRANSLATE_NOOP("WorkCal_ClearRegions", "Clear regions")
    TOOL_TIP = QT_TRANSLATE_NOOP("WorkCal_ClearRegions", "Remove the workpiece and reference regions of the scan")

    def run(self):
        clear_regions()


COMMANDS = {
    "WorkCal_PickBox": PickCommand(),
    "WorkCal_PickLasso": PickLassoCommand(),
    "WorkCal_AutoRegions": AutoRegionsCommand(),
    "WorkCal_ClearRegions": ClearRegionsCommand(),
}
