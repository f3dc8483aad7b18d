"""WorkCal_ImportScan: read scan files into WorkCal scan objects.

``import_scan_files(paths, units)`` is what the command does after its file dialog (tests and macros
call it directly).  The length unit of scan files is asked once and remembered (preference
"ScanUnits"); a PLY written by WorkCal declares its own unit.  Files are read in a worker thread with
a progress dialog; each file is one undo step and becomes the document's scan (WorkCal setup).
"""
from __future__ import annotations

import os

import FreeCAD

from workcal_wb.core.errors import Cancelled, InputError
from workcal_wb.core.units import MM_PER_UNIT
from workcal_wb.fc.undo import transaction
from workcal_wb.gui.task_panels.common import Command, message, warning
from workcal_wb.gui.view import look

QT_TRANSLATE_NOOP = FreeCAD.Qt.QT_TRANSLATE_NOOP
translate = FreeCAD.Qt.translate

UNIT_CHOICES = ("mm", "cm", "m", "in", "um")
LAST_DIR_KEY = "LastScanDir"


def file_filter() -> str:
    from workcal_wb.fc.scan import SCAN_EXTENSIONS

    patterns = " ".join("*" + ext for ext in SCAN_EXTENSIONS)
    return (translate("WorkCal", "Scans") + f" ({patterns});;" + translate("WorkCal", "All files") + " (*)")


def ask_units(ask_again: bool = False) -> str:
    """The unit of scan files: the remembered one, or asked now (once) and remembered."""
    from workcal_wb.fc import scan as fc_scan

    units = fc_scan.preferred_units()
    if units in MM_PER_UNIT and not ask_again:
        return units
    import FreeCADGui

    from workcal_wb.gui.task_panels import QtWidgets

    choice, ok = QtWidgets.QInputDialog.getItem(
        FreeCADGui.getMainWindow(), translate("WorkCal", "Scan units"),
        translate("WorkCal", "Length unit of the numbers in scan files\n(asked once; change it in the WorkCal "
                             "preferences, parameter ScanUnits):"),
        list(UNIT_CHOICES), 0, False)
    if not ok:
        raise Cancelled(translate("WorkCal", "import cancelled: no unit chosen"))
    fc_scan.set_preferred_units(choice)
    return choice


def import_scan_files(paths, units: str | None = None, doc=None, background: bool = True) -> list:
    """Import each file as a WorkCal scan; returns the new objects.

    ``units``: the files' length unit (default: the remembered one, asked once).  A file that cannot
    be read raises InputError naming it; files before it stay imported (each is its own undo step)."""
    from workcal_wb.fc import scan as fc_scan
    from workcal_wb.fc.setup import set_setup
    from workcal_wb.gui.progress import run_in_background

    paths = [str(p) for p in ([paths] if isinstance(paths, (str, os.PathLike)) else paths)]
    if not paths:
        raise InputError(translate("WorkCal", "no scan file given"))
    units = units or ask_units()
    if units not in MM_PER_UNIT:
        raise InputError(translate("WorkCal", "unknown length unit {!r}; use one of {}").format(
            units, ", ".join(MM_PER_UNIT)))
    doc = doc or FreeCAD.ActiveDocument or FreeCAD.newDocument("Scan")
    created = []
    for path in paths:
        name = os.path.basename(path)
        if os.path.splitext(path)[1].lower() in fc_scan.FREECAD_POINT_FORMATS or not background:
            cloud = fc_scan.read_scan_file(path, units)  # FreeCAD's reader touches documents: main thread
        else:
            cloud = run_in_background(lambda p=path: fc_scan.read_scan_file(p, units),
                                      translate("WorkCal", "Reading {}...").format(name),
                                      translate("WorkCal", "Import scan"))
        used = fc_scan.declared_units(path) or units
        with transaction(doc, translate("WorkCal", "Import scan")):
            obj = fc_scan.make_scan(doc, cloud, name, used, path)
            set_setup(doc, scan=obj)
            doc.recompute()
        for text in cloud.warnings:
            warning(text)
        message(translate("WorkCal", "imported {} ({} points, read as {})").format(name, len(cloud), used))
        created.append(obj)
    FreeCAD.ParamGet(fc_scan.PARAMS).SetString(LAST_DIR_KEY, os.path.dirname(os.path.abspath(paths[-1])))
    _show(doc, created)
    return created


def _show(doc, objects) -> None:
    if not FreeCAD.GuiUp or not objects:
        return
    import FreeCADGui

    gui_doc = FreeCADGui.getDocument(doc.Name)
    view = gui_doc.ActiveView if gui_doc is not None else None
    FreeCADGui.Selection.clearSelection()
    for obj in objects:
        FreeCADGui.Selection.addSelection(obj)
    if view is not None and hasattr(view, "fitAll"):
        look(view)


class ImportScanCommand(Command):
    NAME, TITLE = "WorkCal_ImportScan", "Import scan"
    MENU_TEXT = QT_TRANSLATE_NOOP("WorkCal_ImportScan", "Import scan...")
    TOOL_TIP = QT_TRANSLATE_NOOP("WorkCal_ImportScan", "Read a 3D scan of the mounted workpiece and the reference "
                                                       "object (PLY, PCD, XYZ, ASC, PTS, CSV, E57, STL, OBJ, OFF); it "
                                                       "becomes the document's scan")
    NEEDS_DOCUMENT = False

    def run(self):
        import FreeCADGui

        from workcal_wb.fc.scan import PARAMS
        from workcal_wb.gui.task_panels import QtWidgets

        start = FreeCAD.ParamGet(PARAMS).GetString(LAST_DIR_KEY, "") or os.path.expanduser("~")
        paths, _ = QtWidgets.QFileDialog.getOpenFileNames(
            FreeCADGui.getMainWindow(), translate("WorkCal", "Import scan"), start, file_filter())
        if paths:
            import_scan_files(paths)


COMMANDS = {"WorkCal_ImportScan": ImportScanCommand()}
