"""WorkCal_ImportScan: read scan files into WorkCal scan objects.

``import_scan_files(paths, units)`` is what the command does after its file dialog (tests call it
directly).  The length unit of scan files is asked once and remembered (preference "ScanUnits"); a
PLY written by WorkCal declares its own unit.  Each file is read in a worker thread with a progress
dialog, then added by the recorded command ``workcal_wb.fc.scan.import_scan(...)`` (one undo step,
replayable in a macro), which makes it the document's scan.
"""
from __future__ import annotations

import os

import FreeCAD

from workcal_wb.core.errors import Cancelled, InputError
from workcal_wb.core.units import MM_PER_UNIT
from workcal_wb.gui import replay
from workcal_wb.gui.task_panels.common import Command

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
                             "preferences):"),
        list(UNIT_CHOICES), 0, False)
    if not ok:
        raise Cancelled(translate("WorkCal", "import cancelled: no unit chosen"))
    fc_scan.set_preferred_units(choice)
    return choice


def import_scan_files(paths, units: str | None = None, doc=None) -> list:
    """Import each file as a WorkCal scan; returns the new objects.

    ``units``: the files' length unit (default: the remembered one, asked once).  A file that cannot
    be read raises InputError naming it; files before it stay imported (each is its own undo step)."""
    import FreeCADGui

    from workcal_wb.fc import scan as fc_scan
    from workcal_wb.gui.progress import run_in_background

    paths = [str(p) for p in ([paths] if isinstance(paths, (str, os.PathLike)) else paths)]
    if not paths:
        raise InputError(translate("WorkCal", "no scan file given"))
    units = units or ask_units()
    if units not in MM_PER_UNIT:
        raise InputError(translate("WorkCal", "unknown length unit {!r}; use one of {}").format(
            units, ", ".join(MM_PER_UNIT)))
    if doc is None and FreeCAD.ActiveDocument is None:
        FreeCADGui.runCommand("Std_New")  # recorded by FreeCAD itself: App.newDocument(...)
    doc = doc or FreeCAD.ActiveDocument
    created = []
    for path in paths:  # read first (remembered): a file that cannot be read is refused before it is recorded
        if os.path.splitext(path)[1].lower() in fc_scan.FREECAD_POINT_FORMATS:  # FreeCAD's reader: main thread
            fc_scan.read_scan_file(path, units)
        else:
            run_in_background(lambda p=path: fc_scan.read_scan_file(p, units),
                              translate("WorkCal", "Reading {}...").format(os.path.basename(path)),
                              translate("WorkCal", "Import scan"))
        created.append(replay.run("workcal_wb.fc.scan.import_scan", doc, path, units, result="scan"))
    FreeCAD.ParamGet(fc_scan.PARAMS).SetString(LAST_DIR_KEY, os.path.dirname(os.path.abspath(paths[-1])))
    return created


def ask_for_scan_files() -> list:
    """The scan files chosen in a file dialog (opening where the last scan was read)."""
    import FreeCADGui

    from workcal_wb.fc.scan import PARAMS
    from workcal_wb.gui.task_panels import QtWidgets

    start = FreeCAD.ParamGet(PARAMS).GetString(LAST_DIR_KEY, "") or os.path.expanduser("~")
    paths, _ = QtWidgets.QFileDialog.getOpenFileNames(
        FreeCADGui.getMainWindow(), translate("WorkCal", "Import scan"), start, file_filter())
    return paths


class ImportScanCommand(Command):
    NAME, TITLE = "WorkCal_ImportScan", "Import scan"
    MENU_TEXT = QT_TRANSLATE_NOOP("WorkCal_ImportScan", "Import scan...")
    TOOL_TIP = QT_TRANSLATE_NOOP("WorkCal_ImportScan", "Read a 3D scan of the mounted workpiece and the reference "
                                                       "object (PLY, PCD, XYZ, ASC, PTS, CSV, E57, STL, OBJ, OFF); it "
                                                       "becomes the document's scan")
    NEEDS_DOCUMENT = False

    def run(self):
        from workcal_wb.gui.commands.guide import open_guide

        paths = ask_for_scan_files()
        if paths:
            import_scan_files(paths)
            open_guide(FreeCAD.ActiveDocument, "scan")


COMMANDS = {"WorkCal_ImportScan": ImportScanCommand()}
